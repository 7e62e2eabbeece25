//! Before and after: a report's runs set beside an earlier `results.json`
//! (`raybench compare-results OLD NEW`, `raybench report --baseline DIR`), the way a change
//! is judged. Per workload (scene, mode, ray set, size, samples, backend) the speed ratio
//! with its confidence interval, and a change only where that interval excludes parity and
//! the change is at least [`crate::stats::MIN_EFFECT`] ([`crate::stats::change`]); where
//! either run has a single repetition, the noise is unknown and no change is claimed.

use crate::results::{Results, Run};
use crate::stats;
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
    /// The confidence interval of [`Change::ratio`] (`null` when either run has a single
    /// repetition).
    pub interval: Option<[f64; 2]>,
    /// The change exceeds the noise of both runs and the minimum effect.
    pub significant: bool,
    /// `faster`, `slower`, `within noise`, `noise unknown` (a single repetition on either
    /// side) or `machine interfered` (either side's median rests on contended repetitions).
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

/// Whether `r`'s median rests on repetitions another process interfered with (at least half
/// of those kept were contended: the redo budget was spent): its time measures the machine's
/// load as much as the backend, so no change is claimed from it.
fn interfered(r: &Run) -> bool {
    r.seconds
        .as_ref()
        .is_some_and(|t| 2 * t.contended as usize >= t.samples.len().max(1))
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
        let (before_t, after_t) = (b.seconds_per_ray(), a.seconds_per_ray());
        // Speed is the inverse of time: before's time over after's is after's speed-up.
        let (_, interval) = stats::ratio_interval(&before_t, &after_t);
        let verdict = if interfered(a) || interfered(b) {
            "machine interfered"
        } else {
            match stats::change(&after_t, &before_t) {
                stats::Change::Faster => "faster",
                stats::Change::Slower => "slower",
                stats::Change::Same => "within noise",
                stats::Change::Unknown => "noise unknown",
            }
        };
        out.changes.push(Change {
            workload: key,
            before: vb,
            after: va,
            ratio: va / vb,
            interval: interval.map(|i| [i.lo, i.hi]),
            significant: matches!(verdict, "faster" | "slower"),
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
    let count = |v: &str| c.changes.iter().filter(|x| x.verdict == v).count();
    let (faster, slower, unknown) = (count("faster"), count("slower"), count("noise unknown"));
    let interfered = count("machine interfered");
    let _ = writeln!(
        s,
        "`{after}` against `{before}`: {} workloads in both, {faster} faster and {slower} slower \
         (the {:.0}% interval of the speed ratio excludes 1 and the change is at least {:.0}%), \
         {unknown} with a single repetition on either side (noise unknown, no change claimed), \
         {interfered} where another process took the CPU through most repetitions of either \
         side (machine interfered, no change claimed), the rest within noise; geometric mean of the speed ratios {}. Workloads only before: \
         {}; only after: {}.\n",
        c.changes.len(),
        stats::CONFIDENCE * 100.0,
        stats::MIN_EFFECT * 100.0,
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
        "| workload | before Mrays/s | after Mrays/s | after / before | interval | verdict |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---|---|");
    for x in &c.changes {
        let verdict = if x.significant {
            format!("**{}**", x.verdict)
        } else {
            x.verdict.to_string()
        };
        let interval = x
            .interval
            .map_or_else(|| "-".into(), |[lo, hi]| format!("{lo:.3}-{hi:.3}"));
        let _ = writeln!(
            s,
            "| {} | {:.3} | {:.3} | {:.3} | {interval} | {verdict} |",
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

    /// `r` with `n` of its repetitions kept contended.
    fn contended(mut r: Run, n: u32) -> Run {
        r.seconds.as_mut().unwrap().contended = n;
        r
    }

    fn results(runs: Vec<Run>) -> Results {
        Results {
            runs,
            ..Results::default()
        }
    }

    /// A change whose ratio interval excludes 1 by the minimum effect is faster or slower;
    /// one inside the noise is not; a single repetition is noise unknown; workloads in one
    /// run only are listed.
    #[test]
    fn judges_changes_against_both_runs_noise() {
        let before = results(vec![
            run("a", vec![1.0, 1.05, 0.98, 1.01, 0.99, 1.02]),
            run("b", vec![1.0, 1.02, 0.99, 1.01, 1.0, 0.98]),
            run("c", vec![1.0, 1.01, 0.99, 1.0, 1.02, 0.98]),
            run("one", vec![1.0]),
            run("busy", vec![1.0, 1.01, 0.99, 1.0, 1.02, 0.98]),
            run("gone", vec![1.0]),
        ]);
        let after = results(vec![
            run("a", vec![0.5, 0.52, 0.51, 0.5, 0.49, 0.51]),
            run("b", vec![1.01, 0.97, 1.03, 1.0, 0.99, 1.02]),
            run("c", vec![1.5, 1.4, 1.45, 1.48, 1.42, 1.46]),
            run("one", vec![0.5]),
            contended(run("busy", vec![2.0, 2.02, 1.98, 2.0, 2.04, 1.96]), 4),
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
            [
                ("a", "faster"),
                ("b", "within noise"),
                ("c", "slower"),
                ("one", "noise unknown"),
                ("busy", "machine interfered")
            ]
        );
        assert!((c.changes[0].ratio - 1.005 / 0.505).abs() < 1e-9);
        let [lo, hi] = c.changes[0].interval.unwrap();
        assert!(lo > 1.0 && lo <= c.changes[0].ratio && c.changes[0].ratio <= hi);
        assert_eq!(c.changes[3].interval, None);
        assert_eq!(c.only_before.len(), 1);
        assert_eq!(c.only_after.len(), 1);
        let g = c.geomean_ratio.unwrap();
        let expected = (c.changes.iter().map(|x| x.ratio.ln()).sum::<f64>() / 5.0).exp();
        assert!((g - expected).abs() < 1e-12);
        let md = markdown(&c, "old", "new");
        assert!(md.contains("1 faster and 1 slower"), "{md}");
        assert!(md.contains("1 with a single repetition"), "{md}");
        assert!(md.contains("1 where another process took the CPU"), "{md}");
        assert!(md.contains("| **faster** |"), "{md}");
    }
}
