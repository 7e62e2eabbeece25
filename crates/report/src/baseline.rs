//! Before and after: a report's runs set beside an earlier `results.json`
//! (`raybench compare-results OLD NEW`, `raybench report --baseline DIR`), the way a change
//! is judged. Per workload (scene, mode, ray set, size, samples, backend) the speed ratio
//! relative to the workload's common mode, with its confidence interval, and a change only
//! where that interval excludes parity and the change exceeds the larger of
//! [`crate::stats::MIN_EFFECT`] and the comparison's run-to-run floor ([`compare`]); where
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
    /// The workload's common mode: the median of [`Change::ratio`] over its backends (where
    /// three or more have repetitions enough on both sides and no interference), the
    /// machine's drift between the runs together with any change common to every backend;
    /// `null` where the workload has fewer backends.
    pub common: Option<f64>,
    /// [`Change::ratio`] over [`Change::common`] (the ratio itself without a common mode):
    /// what the verdict judges.
    pub relative: f64,
    /// The confidence interval of [`Change::relative`] (`null` when either run has a single
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
    /// Geometric mean of the workloads' common modes ([`Change::common`]; `null` where no
    /// workload has one).
    pub geomean_common: Option<f64>,
    /// The smallest change claimed, as a fraction: [`stats::MIN_EFFECT`], or the run-to-run
    /// floor ([`FLOOR_SIGMAS`] robust standard deviations of the relative ratios) where it
    /// is larger.
    pub min_effect: f64,
}

/// Robust standard deviations of the relative ratios' logarithms (over the comparison's
/// judged workloads) that a change must also exceed: the run-to-run floor. Two runs of one
/// binary minutes apart differ by more than their own intervals say (memory layout, the
/// host's other guests): on a 2-vCPU guest the relative ratios of two quiet runs had a
/// median absolute log of 0.9 % and a tail to 17 %.
pub const FLOOR_SIGMAS: f64 = 5.0;

/// Judged workloads a comparison needs to estimate its run-to-run floor; with fewer the
/// floor is [`stats::MIN_EFFECT`].
pub const FLOOR_WORKLOADS: usize = 20;

/// Backends a workload needs in both runs for its common mode: with two, one backend's
/// change would move the median halfway and show in both.
pub const COMMON_MODE_BACKENDS: usize = 3;

/// The geometric mean of `values` (`None` for none).
fn geomean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let logs: Vec<f64> = values.filter(|v| *v > 0.0).map(f64::ln).collect();
    (!logs.is_empty()).then(|| (logs.iter().sum::<f64>() / logs.len() as f64).exp())
}

/// Whether `r`'s median rests on repetitions another process interfered with (at least half
/// of those kept were contended: the machine was busy throughout): its time measures the machine's
/// load as much as the backend, so no change is claimed from it.
fn interfered(r: &Run) -> bool {
    r.seconds
        .as_ref()
        .is_some_and(|t| 2 * t.contended as usize >= t.samples.len().max(1))
}

/// Compares the timed runs of `after` with those of `before`.
///
/// Two runs are minutes apart, and a shared machine's speed drifts over minutes (on a
/// 2-vCPU guest, 5-25 % between two quiet runs of the same binary, by workload, with no
/// other process in sight): each workload's ratios are therefore judged relative to its
/// common mode, the median ratio over its backends, which were timed in the same rounds.
/// A change common to every backend cannot be told from the machine's drift: it shows in
/// the common mode, reported beside.
#[must_use]
pub fn compare(before: &Results, after: &Results) -> Comparison {
    let timed = |r: &&Run| r.status == "ok" && r.mrays_per_s.is_some();
    let mut out = Comparison::default();
    // (workload without the backend, change, before's and after's seconds per ray)
    let mut found: Vec<(String, Change, Vec<f64>, Vec<f64>)> = Vec::new();
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
        let unknown = before_t.len() < 2 || after_t.len() < 2;
        let verdict = if interfered(a) || interfered(b) {
            "machine interfered"
        } else if unknown {
            "noise unknown"
        } else {
            ""
        };
        let group = format!(
            "{} {}-{} {}x{} {}",
            a.scene, a.mode, a.ray_set, a.width, a.height, a.spp
        );
        found.push((
            group,
            Change {
                workload: key,
                before: vb,
                after: va,
                ratio: va / vb,
                common: None,
                relative: va / vb,
                interval: None,
                significant: false,
                verdict,
            },
            before_t,
            after_t,
        ));
    }
    for (group, change, before_t, after_t) in &found {
        let peers: Vec<f64> = found
            .iter()
            .filter(|(g, c, ..)| g == group && c.verdict.is_empty())
            .map(|(_, c, ..)| c.ratio)
            .collect();
        let common = (peers.len() >= COMMON_MODE_BACKENDS)
            .then(|| stats::median(&peers))
            .flatten();
        let drift = common.unwrap_or(1.0);
        // Speed is the inverse of time: before's time over after's is after's speed-up.
        let (_, interval) = stats::ratio_interval(before_t, after_t);
        let interval = interval.map(|i| stats::Interval {
            lo: i.lo / drift,
            hi: i.hi / drift,
            ..i
        });
        out.changes.push(Change {
            common,
            relative: change.ratio / drift,
            interval: interval.map(|i| [i.lo, i.hi]),
            ..change.clone()
        });
    }
    out.min_effect = run_to_run_floor(&out.changes).max(stats::MIN_EFFECT);
    for c in &mut out.changes {
        if !c.verdict.is_empty() {
            continue;
        }
        // Judged as a ratio of times, after over before: the inverse of the speed ratio.
        let times = c.interval.map(|[lo, hi]| stats::Interval {
            lo: 1.0 / hi,
            hi: 1.0 / lo,
            confidence: stats::CONFIDENCE,
        });
        c.verdict = stats::judge(1.0 / c.relative, times, out.min_effect).label();
        c.significant = matches!(c.verdict, "faster" | "slower");
    }
    for b in before.runs.iter().filter(timed) {
        let key = b.key();
        if !after.runs.iter().filter(timed).any(|a| a.key() == key) {
            out.only_before.push(key);
        }
    }
    out.geomean_ratio = geomean(out.changes.iter().map(|c| c.ratio));
    // One common mode per workload, not per backend.
    let mut commons: Vec<(&str, f64)> = Vec::new();
    for ((group, ..), c) in found.iter().zip(&out.changes) {
        if let Some(m) = c.common
            && !commons.iter().any(|(g, _)| *g == group)
        {
            commons.push((group, m));
        }
    }
    out.geomean_common = geomean(commons.iter().map(|(_, m)| *m));
    out
}

/// [`FLOOR_SIGMAS`] robust standard deviations (1.4826 times the median absolute value) of
/// the logarithms of the judged changes' relative ratios, as a fraction; 0 with fewer than
/// [`FLOOR_WORKLOADS`] of them.
fn run_to_run_floor(changes: &[Change]) -> f64 {
    let logs: Vec<f64> = changes
        .iter()
        .filter(|c| c.verdict.is_empty() && c.relative > 0.0)
        .map(|c| c.relative.ln().abs())
        .collect();
    if logs.len() < FLOOR_WORKLOADS {
        return 0.0;
    }
    let mad = stats::median(&logs).unwrap_or(0.0);
    (FLOOR_SIGMAS * 1.4826 * mad).exp() - 1.0
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
        "`{after}` against `{before}`: {} in both, {faster} faster and {slower} slower \
         (the {:.0}% interval of the speed ratio excludes 1 and the change is at least {:.1}%: \
         the larger of {:.0}% and the run-to-run floor, {FLOOR_SIGMAS} robust standard \
         deviations of the relative ratios over this comparison's workloads, what two runs \
         of one binary differ by beyond their own intervals), \
         {unknown} with a single repetition on either side (noise unknown, no change claimed), \
         {interfered} where another process took the CPU through most repetitions of either \
         side (machine interfered, no change claimed), the rest within noise; geometric mean of the speed ratios {}. Workloads only before: \
         {}; only after: {}.\n\n\
         Each ratio is judged relative to its workload's common mode (**all**: the median \
         ratio over the workload's backends, where {COMMON_MODE_BACKENDS} or more have one), \
         which takes out the machine's drift between the two runs (a shared machine's speed \
         moves by several percent over minutes) and with it any change common to every \
         backend, which cannot be told from that drift; geometric mean of the common modes \
         {}.\n",
        crate::fmt::count(c.changes.len(), "workload"),
        stats::CONFIDENCE * 100.0,
        c.min_effect * 100.0,
        stats::MIN_EFFECT * 100.0,
        c.geomean_ratio
            .map_or_else(|| "-".into(), |g| format!("{g:.3}")),
        c.only_before.len(),
        c.only_after.len(),
        c.geomean_common
            .map_or_else(|| "-".into(), |g| format!("{g:.3}")),
    );
    if c.changes.is_empty() {
        return s;
    }
    let _ = writeln!(
        s,
        "| workload | before Mrays/s | after Mrays/s | after / before | all | relative | interval | verdict |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---|---|");
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
            "| {} | {:.3} | {:.3} | {:.3} | {} | {:.3} | {interval} | {verdict} |",
            x.workload,
            x.before,
            x.after,
            x.ratio,
            x.common.map_or_else(|| "-".into(), |m| format!("{m:.3}")),
            x.relative
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
        let relative = c.changes[0].relative;
        assert!(lo > 1.0 && lo <= relative && relative <= hi);
        // Three backends judged: their common mode is b's (unchanged).
        let common = c.changes[0].common.unwrap();
        assert!(
            (common - 1.0 / 1.005).abs() < 1e-9
                && (relative - c.changes[0].ratio / common).abs() < 1e-12
        );
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

    /// The machine 10 % slower in the second run for every backend alike: no change is
    /// claimed, the drift shows as the common mode; one backend 30 % slower on top of it is
    /// slower. With two backends there is no common mode, and the drift counts.
    #[test]
    fn the_machine_s_drift_is_the_common_mode() {
        let steady = |scale: f64| {
            [1.0, 1.01, 0.99, 1.0, 1.02, 0.98]
                .iter()
                .map(|x| x * scale)
                .collect::<Vec<_>>()
        };
        let before = results(["a", "b", "c", "d"].map(|n| run(n, steady(1.0))).to_vec());
        let after = results(vec![
            run("a", steady(1.1)),
            run("b", steady(1.1)),
            run("c", steady(1.1)),
            run("d", steady(1.1 * 1.3)),
        ]);
        let c = compare(&before, &after);
        let verdicts: Vec<&str> = c.changes.iter().map(|x| x.verdict).collect();
        assert_eq!(
            verdicts,
            ["within noise", "within noise", "within noise", "slower"]
        );
        assert!((c.geomean_common.unwrap() - 1.0 / 1.1).abs() < 1e-9);
        let md = markdown(&c, "old", "new");
        assert!(
            md.contains("geometric mean of the common modes 0.909"),
            "{md}"
        );
        // Over twenty workloads the floor is measured: scattered by about 1 %, it stays at
        // the minimum effect, and a 30 % change stands out of it.
        let jitter = |i: usize| 1.0 + 0.01 * ((i * 7 % 5) as f64 - 2.0) / 2.0;
        let names: Vec<String> = (0..24).map(|i| format!("b{i}")).collect();
        let before24 = results(names.iter().map(|n| run(n, steady(1.0))).collect());
        let after24 = results(
            names
                .iter()
                .enumerate()
                .map(|(i, n)| run(n, steady(jitter(i) * if i == 5 { 1.3 } else { 1.0 })))
                .collect(),
        );
        let c = compare(&before24, &after24);
        assert!(
            c.min_effect >= stats::MIN_EFFECT && c.min_effect < 0.1,
            "{}",
            c.min_effect
        );
        let claimed: Vec<&str> = c
            .changes
            .iter()
            .filter(|x| x.significant)
            .map(|x| x.verdict)
            .collect();
        assert_eq!(claimed, ["slower"]);
        // Two backends: judged as they are.
        let two = |r: &Results| results(r.runs[..2].to_vec());
        let c = compare(&two(&before), &two(&after));
        assert!(
            c.changes
                .iter()
                .all(|x| x.common.is_none() && x.verdict == "slower")
        );
    }
}
