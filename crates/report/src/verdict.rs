//! The verdict that opens `REPORT.md`: what the run concluded, drawn from [`Results`] alone
//! (so a merge of shards concludes over all of them): the fastest backend per scene and ray
//! set with its speed-up over the baseline structure and the oracle, which backends matched
//! the reference bit for bit, what was skipped and why, which timings were noisy, and how
//! the scaling slopes compare with the theory the report states.

use crate::fmt::noisy_mark;
use crate::results::{Fit, Results, Run};
use raybench_registry::Roles;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// How many noisy timings the verdict names before it only counts the rest.
const NOISY_NAMED: usize = 12;

/// Writes the verdict section.
pub(super) fn write(results: &Results, s: &mut String) {
    let _ = writeln!(s, "## Verdict\n");
    if results.runs.is_empty() && results.scaling.is_empty() {
        let _ = writeln!(s, "Nothing ran: see Skipped below.\n");
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

/// The fastest valid backend per scene and workload kind, and its speed-ups.
fn fastest(results: &Results, s: &mut String) {
    let (kinds, scenes) = kinds_and_scenes(&results.runs);
    if kinds.is_empty() {
        return;
    }
    let baseline = raybench_registry::name_with(Roles::BASELINE);
    let oracle = raybench_registry::name_with(Roles::ORACLE);
    let _ = writeln!(
        s,
        "**Fastest backend** per scene and workload (Mrays/s over every ray traced; only \
         backends whose result passed the equality check count), with its speed-up over \
         `{baseline}` (the baseline structure) and `{oracle}` (the oracle, where it fitted \
         its time budget). † marks a noisy time.\n"
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
                let speed = |name: &str| {
                    runs.iter()
                        .find(|r| r.backend == name && valid(r))
                        .and_then(|r| r.mrays_per_s)
                };
                let Some(best) = runs.iter().filter(|r| valid(r)).max_by(|a, b| {
                    a.mrays_per_s
                        .unwrap_or(0.0)
                        .total_cmp(&b.mrays_per_s.unwrap_or(0.0))
                }) else {
                    return if runs.is_empty() {
                        String::new()
                    } else {
                        "none passed".into()
                    };
                };
                let v = best.mrays_per_s.unwrap_or(0.0);
                let over = |name: &str| {
                    let other = (name != best.backend).then(|| speed(name)).flatten();
                    other.filter(|b| *b > 0.0).map(|b| {
                        let x = v / b;
                        if x >= 10.0 {
                            format!("{x:.0}x {name}")
                        } else {
                            format!("{x:.2}x {name}")
                        }
                    })
                };
                let ups: Vec<String> = [over(baseline), over(oracle)]
                    .into_iter()
                    .flatten()
                    .collect();
                format!(
                    "`{}` {v:.2}{}{}",
                    best.backend,
                    best.seconds.as_ref().map_or("", noisy_mark),
                    if ups.is_empty() {
                        String::new()
                    } else {
                        format!(" ({})", ups.join(", "))
                    }
                )
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
    if lines.is_empty() {
        let _ = writeln!(
            s,
            "**Skipped**: nothing; every scene, workload and backend ran.\n"
        );
    } else {
        let _ = writeln!(s, "**Skipped or refused**:\n\n{}\n", lines.join("\n"));
    }
}

/// The noisy timings, named (the tables mark them in place).
fn noisy(results: &Results, s: &mut String) {
    let timed: Vec<&Run> = results
        .runs
        .iter()
        .filter(|r| r.seconds.is_some())
        .collect();
    let mut noisy: Vec<(&Run, f64)> = timed
        .iter()
        .filter_map(|r| {
            let t = r.seconds.as_ref()?;
            t.noisy().then(|| (*r, t.spread()))
        })
        .collect();
    noisy.sort_by(|a, b| b.1.total_cmp(&a.1));
    let points = results.scaling.len();
    if noisy.is_empty() {
        let _ = writeln!(
            s,
            "**Noise**: every one of the {} timed runs spread by at most {:.0}% between its \
             fastest and slowest repetition.\n",
            timed.len(),
            crate::results::NOISY_SPREAD * 100.0
        );
        return;
    }
    let named: Vec<String> = noisy
        .iter()
        .take(NOISY_NAMED)
        .map(|(r, spread)| {
            format!(
                "{} {}-{} `{}` ({:.0}%)",
                r.scene,
                r.mode,
                r.ray_set,
                r.backend,
                spread * 100.0
            )
        })
        .collect();
    let more = noisy.len().saturating_sub(NOISY_NAMED);
    let _ = writeln!(
        s,
        "**Noise**: {} of the {} timed runs spread by more than {:.0}% between their fastest \
         and slowest repetition (marked † in the tables{}): {}{}.\n",
        noisy.len(),
        timed.len(),
        crate::results::NOISY_SPREAD * 100.0,
        if points > 0 {
            format!("; the scaling experiments' {points} points are single medians, not judged")
        } else {
            String::new()
        },
        named.join(", "),
        if more > 0 {
            format!(", and {more} more")
        } else {
            String::new()
        }
    );
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
