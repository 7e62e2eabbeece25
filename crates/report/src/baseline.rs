//! Before and after: a report's runs set beside an earlier `results.json`
//! (`raybench compare-results OLD NEW`, `raybench report --baseline DIR`), the way a change
//! is judged. Per workload (scene, mode, ray set, size, samples, backend) the speed ratio,
//! and whether it exceeds the noise of both runs: the ranges of speeds their timed
//! repetitions span (rays over the slowest and over the fastest repetition) do not overlap.

use crate::results::{Results, Run};
use anyhow::{Context, Result};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One workload measured in both runs.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Change {
    /// What was measured ([`Run::key`]).
    pub workload: String,
    /// Mrays/s before (over the median time).
    pub before: f64,
    /// Mrays/s after.
    pub after: f64,
    /// `after / before`: above 1 is faster.
    pub ratio: f64,
    /// The repetitions' speed ranges do not overlap: the change exceeds both runs' noise.
    pub significant: bool,
    /// `faster`, `slower` or `within noise`.
    pub verdict: &'static str,
}

/// Two runs compared.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct Comparison {
    /// The workloads both measured, in the newer run's order.
    pub changes: Vec<Change>,
    /// Workloads only the earlier run measured.
    pub only_before: Vec<String>,
    /// Workloads only the newer run measured.
    pub only_after: Vec<String>,
    /// Geometric mean of the ratios (`null` without common workloads).
    pub geomean_ratio: Option<f64>,
}

/// The speeds (Mrays/s) a run's repetitions span: rays over the slowest and the fastest.
fn speed_range(r: &Run) -> Option<(f64, f64)> {
    let t = r.seconds.as_ref()?;
    let rays = r.rays? as f64;
    (t.min > 0.0 && t.max > 0.0).then(|| (rays / t.max / 1e6, rays / t.min / 1e6))
}

/// Compares the timed runs of `after` with those of `before`.
#[must_use]
pub fn compare(before: &Results, after: &Results) -> Comparison {
    let timed = |r: &&Run| r.status == "ok" && r.mrays_per_s.is_some();
    let mut out = Comparison::default();
    for a in after.runs.iter().filter(timed) {
        let key = a.key();
        let Some(b) = before.runs.iter().filter(timed).find(|b| b.key() == key) else {
            out.only_after.push(key);
            continue;
        };
        let (Some(vb), Some(va)) = (b.mrays_per_s, a.mrays_per_s) else {
            continue;
        };
        if vb <= 0.0 {
            continue;
        }
        let ratio = va / vb;
        let significant = match (speed_range(b), speed_range(a)) {
            (Some((b_lo, b_hi)), Some((a_lo, a_hi))) => a_lo > b_hi || a_hi < b_lo,
            _ => false,
        };
        let verdict = match (significant, ratio > 1.0) {
            (false, _) => "within noise",
            (true, true) => "faster",
            (true, false) => "slower",
        };
        out.changes.push(Change {
            workload: key,
            before: vb,
            after: va,
            ratio,
            significant,
            verdict,
        });
    }
    for b in before.runs.iter().filter(timed) {
        let key = b.key();
        if !after.runs.iter().filter(timed).any(|a| a.key() == key) {
            out.only_before.push(key);
        }
    }
    let logs: Vec<f64> = out
        .changes
        .iter()
        .filter(|c| c.ratio > 0.0)
        .map(|c| c.ratio.ln())
        .collect();
    out.geomean_ratio =
        (!logs.is_empty()).then(|| (logs.iter().sum::<f64>() / logs.len() as f64).exp());
    out
}

/// The comparison as a markdown section (a heading, a summary line, a table).
#[must_use]
pub fn markdown(c: &Comparison, before: &str, after: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "## Before and after\n");
    let faster = c.changes.iter().filter(|x| x.verdict == "faster").count();
    let slower = c.changes.iter().filter(|x| x.verdict == "slower").count();
    let _ = writeln!(
        s,
        "`{after}` against `{before}`: {} workloads in both, {faster} faster and {slower} slower \
         beyond the noise of both runs (their repetitions' speed ranges do not overlap), the \
         rest within noise; geometric mean of the speed ratios {}. Workloads only before: {}; \
         only after: {}.\n",
        c.changes.len(),
        c.geomean_ratio
            .map_or_else(|| "-".into(), |g| format!("{g:.3}")),
        c.only_before.len(),
        c.only_after.len()
    );
    if c.changes.is_empty() {
        return s;
    }
    let _ = writeln!(
        s,
        "| workload | before Mrays/s | after Mrays/s | after / before | verdict |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---|");
    for x in &c.changes {
        let verdict = if x.significant {
            format!("**{}**", x.verdict)
        } else {
            x.verdict.to_string()
        };
        let _ = writeln!(
            s,
            "| {} | {:.3} | {:.3} | {:.3} | {verdict} |",
            x.workload, x.before, x.after, x.ratio
        );
    }
    let _ = writeln!(s);
    s
}

/// The `results.json` that `path` names: the file itself, or the one in a report folder.
#[must_use]
pub fn results_path(path: &Path) -> PathBuf {
    if path.is_dir() {
        path.join("results.json")
    } else {
        path.to_path_buf()
    }
}

/// Reads the results `path` names ([`results_path`]).
///
/// # Errors
/// When it cannot be read or is not a results file of this schema.
pub fn read(path: &Path) -> Result<Results> {
    let file = results_path(path);
    Results::read(&file).with_context(|| format!("baseline {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::Timing;

    fn run(backend: &str, samples: Vec<f64>) -> Run {
        let timing = Timing::of(samples);
        let rays = 1_000_000u64;
        serde_json::from_value(serde_json::json!({
            "shard": 0, "scene": "s", "primitives": 1, "mode": "cast", "ray_set": "primary",
            "width": 1000, "height": 1000, "spp": 1, "backend": backend, "exact": true,
            "reference": "oracle", "status": "ok", "reason": null, "build_seconds": 0.1,
            "memory_bytes": 1, "structure": {}, "seconds": timing, "rays": rays,
            "mrays_per_s": rays as f64 / timing.median / 1e6, "tests_per_ray": null,
            "visits_per_ray": null, "equality": null, "images": {}
        }))
        .unwrap()
    }

    fn results(runs: Vec<Run>) -> Results {
        Results {
            runs,
            ..Results::default()
        }
    }

    /// A change beyond both runs' spreads is faster or slower; one inside them is noise;
    /// workloads in one run only are listed.
    #[test]
    fn judges_changes_against_both_runs_noise() {
        let before = results(vec![
            run("a", vec![1.0, 1.05, 0.98]),
            run("b", vec![1.0, 1.02, 0.99]),
            run("c", vec![1.0, 1.01, 0.99]),
            run("gone", vec![1.0]),
        ]);
        let after = results(vec![
            run("a", vec![0.5, 0.52, 0.51]),
            run("b", vec![1.01, 0.97, 1.03]),
            run("c", vec![1.5, 1.4, 1.45]),
            run("new", vec![1.0]),
        ]);
        let c = compare(&before, &after);
        let verdicts: Vec<(&str, &str)> = c
            .changes
            .iter()
            .map(|x| (x.workload.rsplit(' ').next().unwrap(), x.verdict))
            .collect();
        assert_eq!(
            verdicts,
            [("a", "faster"), ("b", "within noise"), ("c", "slower")]
        );
        assert!((c.changes[0].ratio - 1.0 / 0.51).abs() < 1e-9);
        assert_eq!(c.only_before.len(), 1);
        assert_eq!(c.only_after.len(), 1);
        let g = c.geomean_ratio.unwrap();
        let expected = (c.changes.iter().map(|x| x.ratio.ln()).sum::<f64>() / 3.0).exp();
        assert!((g - expected).abs() < 1e-12);
        let md = markdown(&c, "old", "new");
        assert!(md.contains("1 faster and 1 slower"), "{md}");
        assert!(md.contains("| **faster** |"), "{md}");
    }
}
