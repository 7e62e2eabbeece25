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

/// `backend` as the report shows it among `runs`: with `(software adapter)` where one of
/// its runs ran on one ([`Run::label`]).
pub(crate) fn label_in(runs: &[&Run], backend: &str) -> String {
    runs.iter()
        .find(|r| r.backend == backend && r.software_device)
        .map_or_else(|| backend.to_string(), |r| r.label())
}

/// Seconds with three significant digits, in plain decimals (`0.0123`, `0.0000234`,
/// `1.23`), so that a short workload's time does not print as `0.0000`.
pub(crate) fn secs(v: f64) -> String {
    if !(v.is_finite() && v > 0.0) {
        return format!("{v}");
    }
    let decimals = (2 - v.log10().floor() as i32).clamp(0, 12) as usize;
    format!("{v:.decimals$}")
}

/// A timing's repetitions as the per-scene tables show them: `6`, with the runs per
/// repetition, the redone and the contended ones where there are any
/// (`9 (20 runs each, 2 redone, 1 contended)`).
pub(crate) fn repetitions(t: &crate::results::Timing) -> String {
    let mut notes = Vec::new();
    if t.per_sample > 1 {
        notes.push(format!("{} runs each", t.per_sample));
    }
    if t.redone > 0 {
        notes.push(format!("{} redone", t.redone));
    }
    if t.contended > 0 {
        notes.push(format!("{} contended", t.contended));
    }
    if notes.is_empty() {
        t.samples.len().to_string()
    } else {
        format!("{} ({})", t.samples.len(), notes.join(", "))
    }
}

/// `n` and the noun, plural unless `n` is 1: `1 workload`, `3 workloads`.
pub(crate) fn count(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
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

#[cfg(test)]
mod tests {
    #[test]
    fn seconds_keep_three_significant_digits() {
        assert_eq!(super::secs(0.012_345), "0.0123");
        assert_eq!(super::secs(0.000_023_4), "0.0000234");
        assert_eq!(super::secs(1.234_5), "1.23");
        assert_eq!(super::secs(123.4), "123");
        assert_eq!(super::secs(0.0), "0");
    }
}
