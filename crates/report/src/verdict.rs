//! The verdict that opens `REPORT.md`: what the run concluded, drawn from [`Results`] alone
//! (so a merge of shards concludes over all of them): the fastest backend per scene and ray
//! set with its speed-up over the baseline structure and the oracle, which backends matched
//! the reference bit for bit, what was skipped and why, which timings were noisy, and how
//! the scaling slopes compare with the theory the report states.

use crate::fmt::noisy_mark;
use crate::results::{Fit, NOISY_HALF_WIDTH, Noise, Results, Run, Timing};
use crate::stats::{self, Fastest};
use raybench_registry::Roles;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// How many noisy timings the verdict names before it only counts the rest.
const NOISY_NAMED: usize = 12;

/// Writes the verdict section.
pub(super) fn write(results: &Results, s: &mut String) {
    let _ = writeln!(s, "## Verdict\n");
    if results.runs.is_empty() && results.scaling.is_empty() {
        let _ = writeln!(s, "Nothing ran.\n");
        skipped(results, s);
        return;
    }
    fastest(results, s);
    identical(results, s);
    skipped(results, s);
    noisy(results, s);
    slopes(results, s);
}

/// The workload kinds `(mode, ray set)` and scenes of the runs, in order of appearance.
fn kinds_and_scenes(runs: &[Run]) -> (Vec<(String, String)>, Vec<String>) {
    let (mut kinds, mut scenes) = (Vec::new(), Vec::new());
    for r in runs {
        let k = (r.mode.clone(), r.ray_set.clone());
        if !kinds.contains(&k) {
            kinds.push(k);
        }
        if !scenes.contains(&r.scene) {
            scenes.push(r.scene.clone());
        }
    }
    (kinds, scenes)
}

/// Whether a run counts for the fastest: it ran and matched its reference (or is it).
fn valid(r: &Run) -> bool {
    r.status == "ok" && r.mrays_per_s.is_some() && r.equality.as_ref().is_none_or(|e| e.pass)
}

/// `x` as a speed-up factor: two decimals below 10, none above.
fn factor(x: f64) -> String {
    if x >= 10.0 {
        format!("{x:.0}")
    } else {
        format!("{x:.2}")
    }
}

/// How much faster `best` is than `other`, with the ratio's interval where both have
/// repetitions enough: `1.95x [1.90-2.01] bvh`.
fn speed_up(best: &Run, other: &Run, by_device: bool) -> String {
    // The runs of one workload were timed in the same rounds: compared round by round.
    let (ratio, interval) = stats::paired_ratio(
        &other.seconds_per_ray_by(by_device),
        &best.seconds_per_ray_by(by_device),
    );
    match interval {
        Some(i) => format!(
            "{}x [{}-{}] {}",
            factor(ratio),
            factor(i.lo),
            factor(i.hi),
            other.label()
        ),
        None => format!("{}x {}", factor(ratio), other.label()),
    }
}

/// The verdict's cell for one scene and workload kind: the fastest valid backend where its
/// interval separates it from every other, else the backends that tie with it.
/// With `by_device`, a backend on another device is timed by its device time.
fn fastest_cell(runs: &[&Run], baseline: &str, oracle: &str, by_device: bool) -> String {
    let valid: Vec<&Run> = runs.iter().copied().filter(|r| valid(r)).collect();
    let times: Vec<Vec<f64>> = valid
        .iter()
        .map(|r| r.seconds_per_ray_by(by_device))
        .collect();
    let refs: Vec<&[f64]> = times.iter().map(Vec::as_slice).collect();
    let Some(verdict) = stats::fastest(&refs) else {
        return if runs.is_empty() {
            String::new()
        } else {
            "none passed".into()
        };
    };
    let (best, prefix) = match &verdict {
        Fastest::Clear(i) => (valid[*i], String::new()),
        Fastest::Unknown(i) => (valid[*i], String::new()),
        Fastest::Tie(tied) => (
            valid[tied[0]],
            format!(
                "tie: {} within noise; ",
                tied.iter()
                    .map(|&i| format!("`{}`", valid[i].label()))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ),
    };
    let v = stats::median(&best.seconds_per_ray_by(by_device)).map_or(0.0, |t| 1e-6 / t);
    let ups: Vec<String> = [baseline, oracle]
        .iter()
        .filter(|name| **name != best.backend)
        .filter_map(|name| valid.iter().find(|r| r.backend == *name))
        .filter(|r| r.mrays_per_s.is_some_and(|m| m > 0.0))
        .map(|r| speed_up(best, r, by_device))
        .collect();
    format!(
        "{prefix}`{}` {v:.2}{}{}",
        best.label(),
        match verdict {
            Fastest::Unknown(_) => " ? (noise unknown)",
            _ => best.seconds.as_ref().map_or("", noisy_mark),
        },
        if ups.is_empty() {
            String::new()
        } else {
            format!(" ({})", ups.join(", "))
        }
    )
}

/// The fastest valid backend per scene and workload kind, or the tie, and its speed-ups.
fn fastest(results: &Results, s: &mut String) {
    let (kinds, scenes) = kinds_and_scenes(&results.runs);
    if kinds.is_empty() {
        return;
    }
    let baseline = raybench_registry::name_with(Roles::BASELINE);
    let oracle = raybench_registry::name_with(Roles::ORACLE);
    let by_device = results.shards.iter().any(|s| s.ranked_by_device);
    let _ = writeln!(
        s,
        "**Fastest backend** per scene and workload (Mrays/s over every ray traced, by the \
         wall-clock time of the whole call{}; only \
         backends whose result passed the equality check count), with its speed-up over \
         `{baseline}` (the baseline structure) and `{oracle}` (the oracle, where it fitted \
         its time budget) and the {:.0}% interval of each speed-up. A backend is named \
         fastest only where the interval of its lead over every other excludes parity and the \
         lead is at least {:.0}%; otherwise the cell names the backends that **tie** within the noise. † marks a \
         noisy time, ? a single repetition (noise unknown).\n",
        if by_device {
            ", a backend on another device by its device time (`--device-time`)"
        } else {
            ", a GPU's too"
        },
        stats::CONFIDENCE * 100.0,
        stats::MIN_EFFECT * 100.0
    );
    let _ = writeln!(
        s,
        "| scene | {} |",
        kinds
            .iter()
            .map(|(m, r)| format!("{m}, {r}"))
            .collect::<Vec<_>>()
            .join(" | ")
    );
    let _ = writeln!(s, "|---|{}", "---|".repeat(kinds.len()));
    for scene in &scenes {
        let cells: Vec<String> = kinds
            .iter()
            .map(|(mode, set)| {
                let runs: Vec<&Run> = results
                    .runs
                    .iter()
                    .filter(|r| &r.scene == scene && &r.mode == mode && &r.ray_set == set)
                    .collect();
                fastest_cell(&runs, baseline, oracle, by_device)
            })
            .collect();
        let _ = writeln!(s, "| {scene} | {} |", cells.join(" | "));
    }
    let _ = writeln!(s);
}

/// Per backend: how many of its runs were bit-identical to the reference, and which failed.
fn identical(results: &Results, s: &mut String) {
    // (runs compared, identical, passed, failures)
    let mut per: BTreeMap<&str, (usize, usize, usize, Vec<String>, bool)> = BTreeMap::new();
    for r in results.runs.iter().filter(|r| r.status == "ok") {
        let Some(e) = &r.equality else { continue };
        if r.backend == r.reference {
            continue;
        }
        let entry = per
            .entry(&r.backend)
            .or_insert((0, 0, 0, Vec::new(), r.exact));
        entry.0 += 1;
        entry.1 += usize::from(e.identical);
        entry.2 += usize::from(e.pass);
        if !e.pass {
            entry
                .3
                .push(format!("{} {}-{}", r.scene, r.mode, r.ray_set));
        }
    }
    if per.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "**Agreement** with each scene's reference backend (bit-identical ids, `t` and colours; \
         backends outside the equivalence contract pass within the tolerance stated below):\n"
    );
    for (backend, (n, same, pass, failed, exact)) in &per {
        let what = if *exact {
            "exact (bound by the contract)"
        } else {
            "outside the contract"
        };
        let mut line = format!(
            "- `{backend}`, {what}: bit-identical in {same} of {n} workloads, passed {pass} of {n}"
        );
        if !failed.is_empty() {
            let _ = write!(line, "; **failed**: {}", failed.join(", "));
        }
        let _ = writeln!(s, "{line}.");
    }
    let _ = writeln!(s);
}

/// What did not run: skipped scenes and experiments, and backends that could not render a
/// scene, grouped by reason.
fn skipped(results: &Results, s: &mut String) {
    let mut lines = Vec::new();
    for k in &results.skipped {
        lines.push(format!(
            "- {} `{}` ({}): {}",
            k.kind, k.name, k.status, k.reason
        ));
    }
    // (backend, status, reason) -> scenes
    let mut refused: BTreeMap<(String, String, String), Vec<String>> = BTreeMap::new();
    for r in results.runs.iter().filter(|r| r.status != "ok") {
        let scenes = refused
            .entry((
                r.backend.clone(),
                r.status.clone(),
                r.reason.clone().unwrap_or_default(),
            ))
            .or_default();
        let what = format!("{} {}-{}", r.scene, r.mode, r.ray_set);
        if !scenes.contains(&what) {
            scenes.push(what);
        }
    }
    for ((backend, status, reason), what) in &refused {
        lines.push(format!(
            "- `{backend}` {status} on {}: {reason}",
            what.join(", ")
        ));
    }
    if lines.is_empty() && results.runs.is_empty() && results.scaling.is_empty() {
        let _ = writeln!(s, "**Skipped**: nothing was planned.\n");
    } else if lines.is_empty() {
        let _ = writeln!(
            s,
            "**Skipped**: nothing; every scene, workload and backend ran.\n"
        );
    } else {
        let _ = writeln!(s, "**Skipped or refused**:\n\n{}\n", lines.join("\n"));
    }
}

/// The noise of the timings: how many have a wide interval (named, widest first), how many
/// a single repetition, and how many repetitions the machine interfered with.
fn noisy(results: &Results, s: &mut String) {
    let timed: Vec<(&Run, &Timing)> = results
        .runs
        .iter()
        .filter_map(|r| Some((r, r.seconds.as_ref()?)))
        .collect();
    let mut wide: Vec<(&Run, f64)> = Vec::new();
    let mut unknown = 0;
    for (r, t) in &timed {
        match t.noise() {
            Noise::Wide(half) => wide.push((r, half)),
            Noise::Unknown => unknown += 1,
            Noise::Narrow(_) => {}
        }
    }
    wide.sort_by(|a, b| b.1.total_cmp(&a.1));
    let redone: u32 = timed.iter().map(|(_, t)| t.redone).sum();
    let contended: u32 = timed.iter().map(|(_, t)| t.contended).sum();
    let kept: usize = timed.iter().map(|(_, t)| t.samples.len()).sum();
    let mut parts = vec![format!(
        "{} timed runs, {kept} timed repetitions",
        timed.len()
    )];
    if wide.is_empty() {
        parts.push(format!(
            "no median's {:.0}% interval is wider than ±{:.0}%",
            stats::CONFIDENCE * 100.0,
            NOISY_HALF_WIDTH * 100.0
        ));
    } else {
        let named: Vec<String> = wide
            .iter()
            .take(NOISY_NAMED)
            .map(|(r, half)| {
                format!(
                    "{} {}-{} `{}` (±{:.0}%)",
                    r.scene,
                    r.mode,
                    r.ray_set,
                    r.backend,
                    half * 100.0
                )
            })
            .collect();
        let more = wide.len().saturating_sub(NOISY_NAMED);
        parts.push(format!(
            "{} with a median's interval wider than ±{:.0}% (marked †): {}{}",
            wide.len(),
            NOISY_HALF_WIDTH * 100.0,
            named.join(", "),
            if more > 0 {
                format!(", and {more} more")
            } else {
                String::new()
            }
        ));
    }
    if unknown > 0 {
        parts.push(format!(
            "{unknown} with a single repetition, whose noise is unknown (marked ?)"
        ));
    }
    parts.push(format!(
        "{redone} repetitions redone because the machine interfered (their threads waited \
         for a CPU more than {:.0}% of the time and more than {:.0} ms), {contended} kept \
         contended (the redo budget spent, or the machine busy throughout: {} contended in a \
         row stop the redoing)",
        raybench_registry::interference::CONTENDED_WAIT_SHARE * 100.0,
        raybench_registry::interference::CONTENDED_WAIT_SECONDS * 1e3,
        crate::rounds::PERSISTENT
    ));
    let points = &results.scaling;
    if !points.is_empty() {
        let wide = points
            .iter()
            .filter(|p| matches!(p.timing.as_ref().map(Timing::noise), Some(Noise::Wide(_))))
            .count();
        let without = points.iter().filter(|p| p.timing.is_none()).count();
        parts.push(format!(
            "of the scaling experiments' {} points, {wide} have a median's interval wider \
             than ±{:.0}%{}",
            points.len(),
            NOISY_HALF_WIDTH * 100.0,
            if without > 0 {
                format!(" ({without} without repetitions recorded: older files)")
            } else {
                String::new()
            }
        ));
    }
    let _ = writeln!(s, "**Noise**: {}.\n", parts.join("; "));
}

/// The slope a scaling fit should have by the theory the report states, with the range a
/// measured slope may fall in and the likely reasons when it falls outside.
struct Theory {
    /// The claim, in words.
    claim: &'static str,
    /// Lowest and highest slope that agree with it.
    range: (f64, f64),
    /// The likely reason for a slope below the range ...
    low: &'static str,
    /// ... and above it.
    high: &'static str,
}

/// Fixed per-frame costs (camera rays, shading, the threads' start) weigh most on the
/// smallest points of a scaling series.
const FIXED_COSTS: &str = "fixed per-frame and per-ray costs (camera rays, shading, starting the threads) weigh most \
     on the smallest points";

/// The theory for experiment `experiment` and backend `backend`, if the report states one.
fn theory(experiment: &str, backend: &str) -> Option<Theory> {
    let brute =
        raybench_registry::roles_of(backend).is_some_and(|r| r.contains(Roles::BRUTE_FORCE));
    match (experiment, brute) {
        ("primitives", true) => Some(Theory {
            claim: "linear in M (slope about 1)",
            range: (0.75, 1.25),
            low: FIXED_COSTS,
            high: "the primitives outgrow the caches at the largest M",
        }),
        ("primitives" | "heightfield" | "bezier", false) => Some(Theory {
            claim: "logarithmic in M (a slope near 0 on log-log axes)",
            range: (-0.15, 0.4),
            low: FIXED_COSTS,
            high: "the rays' work grows faster than log M: the structure outgrows the caches, \
                   or the generated scenes change their depth complexity or hit rate with M",
        }),
        ("pixels" | "spp", _) => Some(Theory {
            claim: "linear in the number of samples (slope about 1)",
            range: (0.8, 1.2),
            low: FIXED_COSTS,
            high: "larger frames leave the caches or the tiles balance worse over the threads",
        }),
        _ => None,
    }
}

/// The scaling fits of render time against the theory.
fn slopes(results: &Results, s: &mut String) {
    let fits: Vec<&Fit> = results
        .fits
        .iter()
        .filter(|f| f.quantity == "seconds")
        .collect();
    if fits.is_empty() {
        return;
    }
    let mut agree = 0;
    let mut judged = 0;
    let mut off = Vec::new();
    for f in &fits {
        let Some(t) = theory(&f.experiment, &f.backend) else {
            continue;
        };
        judged += 1;
        if (t.range.0..=t.range.1).contains(&f.slope) {
            agree += 1;
        } else {
            let why = if f.slope < t.range.0 { t.low } else { t.high };
            off.push(format!(
                "- `{}` on {} `{}`: slope {:.2}, theory {} ({:.2} to {:.2}); likely: {why}.",
                f.backend, f.experiment, f.series, f.slope, t.claim, t.range.0, t.range.1
            ));
        }
    }
    let _ = writeln!(
        s,
        "**Scaling against theory**: {agree} of {judged} fits of render time agree with the \
         slope the theory predicts (naive linear in the primitive count M, a tree logarithmic \
         in it, every backend linear in pixels and samples; the ranges allow for the few \
         points of each fit){}\n",
        if off.is_empty() {
            ".".to_string()
        } else {
            format!("; these disagree:\n\n{}", off.join("\n"))
        }
    );
}
