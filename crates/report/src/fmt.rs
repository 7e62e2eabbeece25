//! Formatting helpers shared by the experiments and the report writers: a leaf module,
//! it imports nothing of the crate but the results' types.

use crate::results::{Noise, Run, Timing};
use std::fmt::Write as _;

/// Starts a section of `REPORT.md`: the heading `## title`, then `intro` as its first
/// paragraph.
pub(crate) fn section(s: &mut String, title: &str, intro: &str) {
    let _ = writeln!(s, "## {title}\n\n{intro}\n");
}

/// A name usable in a file name (generator specs contain `:`).
pub(crate) fn file_safe(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The mark of a timing's noise in a table: ` †` where the median's interval is wider than
/// [`crate::results::NOISY_HALF_WIDTH`], ` ?` where a single repetition leaves the noise
/// unknown, empty otherwise.
pub(crate) fn noisy_mark(t: &Timing) -> &'static str {
    match t.noise() {
        Noise::Wide(_) => " †",
        Noise::Unknown => " ?",
        Noise::Narrow(_) => "",
    }
}

/// The backends of `runs`, in order of first appearance.
pub(crate) fn backends_in(runs: &[&Run]) -> Vec<String> {
    let mut seen = Vec::new();
    for r in runs {
        if !seen.contains(&r.backend) {
            seen.push(r.backend.clone());
        }
    }
    seen
}

/// A value formatted by `f`, or `-`.
pub(crate) fn opt(v: Option<f64>, f: impl Fn(f64) -> String) -> String {
    v.map_or_else(|| "-".into(), f)
}

/// A byte count in B, KiB or MiB.
pub(crate) fn bytes(b: u64) -> String {
    if b >= 1 << 20 {
        format!("{:.1} MiB", b as f64 / f64::from(1 << 20))
    } else if b >= 1 << 10 {
        format!("{:.1} KiB", b as f64 / 1024.0)
    } else {
        format!("{b} B")
    }
}
