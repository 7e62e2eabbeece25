//! The verdict that opens `REPORT.md`: what the run concluded, drawn from [`Results`] alone
//! (so a merge of shards concludes over all of them): the fastest backend per scene and ray
//! set with its speed-up over the baseline structure and the oracle, which backends matched
//! the reference bit for bit, what was skipped and why, which timings were noisy, and how
//! the scaling slopes compare with the theory the report states.

use crate::fmt::noisy_mark;
use crate::results::{
    AIC_MARGIN, CONSTANT_HITS_PP, Favoured, Fit, NOISY_HALF_WIDTH, Noise, Results, Run, Timing,
};
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
    factor_as(x, x)
}

/// `x` with the decimals [`factor`] gives `ratio`: the ends of a ratio's interval are
/// written as the ratio is, so that one straddling 10 reads `9.90x [9.60-10.20]`, not
/// `[9.60-10]`.
fn factor_as(x: f64, ratio: f64) -> String {
    if ratio >= 10.0 {
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
            factor_as(i.lo, ratio),
            factor_as(i.hi, ratio),
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
         wall-clock time of the whole call{}; camera rays by their trace as a batch made \
         beforehand, without the frame's ray generation, shading and image, where it was \
         measured; only \
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
    // Coverage scenes (small scenes that check modes and kinds) are timed, but their times
    // are a frame's fixed costs, not a structure's: no winner is named on them.
    let coverage = |scene: &String| {
        results
            .runs
            .iter()
            .filter(|r| &r.scene == scene)
            .all(|r| r.coverage)
    };
    let (left_out, scenes): (Vec<&String>, Vec<&String>) =
        scenes.iter().partition(|sc| coverage(sc));
    for scene in scenes {
        let cells: Vec<String> = kinds
            .iter()
            .map(|(mode, set)| {
                let runs: Vec<&Run> = results
                    .runs
                    .iter()
                    .filter(|r| &r.scene == scene && &r.mode == mode && &r.ray_set == set)
                    .collect();
                // Camera rays are judged on their batch trace where every backend that ran
                // has one (never a frame against a trace).
                let traced: Vec<std::borrow::Cow<Run>> = if runs
                    .iter()
                    .filter(|r| r.status == "ok")
                    .all(|r| r.trace.is_some())
                {
                    runs.iter().map(|r| r.traced()).collect()
                } else {
                    runs.iter()
                        .map(|r| std::borrow::Cow::Borrowed(*r))
                        .collect()
                };
                let runs: Vec<&Run> = traced.iter().map(AsRef::as_ref).collect();
                fastest_cell(&runs, baseline, oracle, by_device)
            })
            .collect();
        let _ = writeln!(s, "| {scene} | {} |", cells.join(" | "));
    }
    let _ = writeln!(s);
    if !left_out.is_empty() {
        let names: Vec<String> = left_out.iter().map(|sc| format!("`{sc}`")).collect();
        let _ = writeln!(
            s,
            "Coverage scenes, timed in the tables below but judged here on nothing: {} (small \
             scenes that check modes, primitive kinds and features; their times are mostly a \
             frame's fixed costs, not a structure's).\n",
            names.join(", ")
        );
    }
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
    if let Some(part) = cache_noise(results) {
        parts.push(part);
    }
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

/// What the last-level cache's walks before and after each shard say: that the cache was
/// shared with busy neighbours where a walk's median step took at least
/// [`CONTESTED_CACHE_RATIO`] times its fastest; `None` where no shard recorded them.
fn cache_noise(results: &Results) -> Option<String> {
    let walks: Vec<(u32, &str, &crate::results::CacheWalk)> = results
        .shards
        .iter()
        .filter_map(|sh| Some((sh.index, sh.cache.as_ref()?)))
        .flat_map(|(i, [before, after])| [(i, "before", before), (i, "after", after)])
        .collect();
    let worst = walks
        .iter()
        .max_by(|a, b| a.2.ratio().total_cmp(&b.2.ratio()))?;
    let (shard, when, walk) = worst;
    let ratio = walk.ratio();
    Some(if ratio >= CONTESTED_CACHE_RATIO {
        format!(
            "the last-level cache was shared with busy neighbours (a walk through {} of it \
             took {ratio:.2} times its fastest step at the median, {when} shard {shard}): \
             scenes whose structures fit in it ran slower by a share the repetitions do not \
             show, so trust their ratios more than their absolute times",
            walk.size()
        )
    } else {
        format!(
            "the last-level cache was quiet (a walk through {} of it within {ratio:.2} times \
             its fastest step at the median, before and after every shard that timed it)",
            walk.size()
        )
    })
}

/// A last-level cache walk whose median step takes at least this many times its fastest
/// marks the cache as shared with busy neighbours: 1.5 (quiet walks on a shared 2-vCPU
/// guest stayed near 1.1, contested ones reached 1.9 to 3.6).
const CONTESTED_CACHE_RATIO: f64 = 1.5;

/// What the theory the report states says of a scaling fit: the model it predicts, and
/// the range a measured slope may fall in where that is what is judged.
struct Theory {
    /// The claim, in words.
    claim: &'static str,
    /// Lowest and highest slope that agree with it: what is judged for a power law, and for
    /// a logarithm where the points are too few to compare the two models.
    range: (f64, f64),
    /// A logarithm (`y = a + b log M`), judged by which model the points favour
    /// ([`Fit::favoured`]) where they were compared; otherwise a power law of the range.
    logarithmic: bool,
}

/// Fixed per-frame costs (camera rays, shading, the threads' start) weigh most on the
/// smallest points of a scaling series.
const FIXED_COSTS: &str = "fixed per-frame and per-ray costs (camera rays, shading, starting the threads) weigh most \
     on the smallest points";

/// The theory for experiment `experiment` and backend `backend`, if the report states one.
fn theory(experiment: &str, backend: &str) -> Option<Theory> {
    let roles = raybench_registry::roles_of(backend).unwrap_or(Roles::NONE);
    let structure = matches!(experiment, "primitives" | "heightfield" | "bezier");
    if structure && roles.contains(Roles::BRUTE_FORCE) {
        (experiment == "primitives").then_some(Theory {
            claim: "linear in M (slope about 1)",
            range: (0.75, 1.25),
            logarithmic: false,
        })
    } else if structure && roles.contains(Roles::GRID) {
        Some(Theory {
            claim: "a power law near M^(1/3), the cells a ray crosses in a grid sized to M",
            range: (0.2, 0.5),
            logarithmic: false,
        })
    } else if structure {
        Some(Theory {
            claim: "logarithmic in M",
            // Without a model comparison: a slope near 0, short of a grid's 1/3.
            range: (-0.15, 0.25),
            logarithmic: true,
        })
    } else if matches!(experiment, "pixels" | "spp") {
        Some(Theory {
            claim: "linear in the number of samples (slope about 1)",
            range: (0.8, 1.2),
            logarithmic: false,
        })
    } else {
        None
    }
}

/// Why a fit of render time strays from its theory, read from the same series' fit of tests
/// per ray where there is one: work per ray that grows with it, or time that grows while
/// the work does not (memory, fixed costs).
fn diagnosis(results: &Results, f: &Fit, low: bool) -> String {
    let tests = results.slope(&f.experiment, &f.series, &f.backend, "tests_per_ray");
    match (tests, low) {
        (None, true) => format!("{FIXED_COSTS} (tests per ray not counted)"),
        (None, false) => "the rays' work or memory traffic grows faster than the theory's \
                          (tests per ray not counted, so which is not known)"
            .into(),
        (Some(t), true) => format!(
            "tests per ray scale as M^{t:.2}: {}",
            if t > f.slope + 0.1 {
                "the work grows while the time does not keep up, so fixed per-frame and \
                 per-ray costs hide it at the small points"
            } else {
                FIXED_COSTS
            }
        ),
        // The work explains the time where it grows at least three quarters as fast (and
        // grows at all): a flat or slower test count leaves the time per test to blame.
        (Some(t), false) if t > 0.05 && t >= 0.75 * f.slope => format!(
            "tests per ray grow too (M^{t:.2}): each ray does more work as M grows (the \
             scenes' depth complexity changes with M, or the structure is worse at large M)"
        ),
        (Some(t), false) => format!(
            "tests per ray scale as M^{t:.2}, slower than the time: the time per test grows, \
             so the structure or the primitives outgrow the caches"
        ),
    }
}

/// What the series' hit fraction says of a fit ([`Results::hit_fractions`]): whether it
/// stays constant (so the hit rate is not what moves the time) or changes with `x` (which
/// confounds the fit); `None` where fewer than two points recorded it.
fn hit_clause(results: &Results, f: &Fit) -> Option<(bool, String)> {
    let hits = results.hit_fractions(&f.experiment, &f.series);
    let (lo, hi) = hits.range()?;
    Some(if hits.constant()? {
        (
            true,
            format!(
                "the hit fraction stays within {:.1} percentage points over the series, so \
                 the hit rate is not the cause",
                hits.spread_pp()
            ),
        )
    } else {
        (
            false,
            format!(
                "the hit fraction moves between {:.1}% and {:.1}% over the series, which \
                 confounds the fit (a ray that hits costs more than one that misses)",
                lo * 100.0,
                hi * 100.0
            ),
        )
    })
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
    // Fits on series whose hit fraction stayed constant: judged, and agreeing.
    let (mut constant_agree, mut constant_judged) = (0, 0);
    let mut confounded = 0;
    let mut off = Vec::new();
    for f in &fits {
        let Some(t) = theory(&f.experiment, &f.backend) else {
            continue;
        };
        judged += 1;
        let in_range = (t.range.0..=t.range.1).contains(&f.slope);
        let verdict = match (t.logarithmic, f.favoured()) {
            (true, Some(Favoured::PowerLaw)) => Err(format!(
                "the points favour a power law (M^{:.2}) over a logarithm (Akaike criterion \
                 {:.1} lower)",
                f.slope,
                -f.delta_aic.unwrap_or(0.0)
            )),
            (true, Some(_)) => Ok(()),
            _ if in_range => Ok(()),
            _ => Err(format!(
                "slope {:.2}, outside {:.2} to {:.2}",
                f.slope, t.range.0, t.range.1
            )),
        };
        let hits = hit_clause(results, f);
        if let Some((true, _)) = hits {
            constant_judged += 1;
            constant_agree += usize::from(verdict.is_ok());
        }
        match verdict {
            Ok(()) => agree += 1,
            Err(what) => {
                let why = diagnosis(results, f, f.slope < t.range.0);
                let hits = hits.map_or(String::new(), |(constant, clause)| {
                    confounded += usize::from(!constant);
                    format!("; {clause}")
                });
                off.push(format!(
                    "- `{}` on {} `{}`: theory {}; {what}; likely: {why}{hits}.",
                    f.backend, f.experiment, f.series, t.claim
                ));
            }
        }
    }
    let _ = writeln!(
        s,
        "**Scaling against theory**: {agree} of {judged} fits of render time agree with the \
         theory (naive linear in the primitive count M; a tree logarithmic in it, judged by \
         whether the points favour a logarithm over a power law by the Akaike criterion on \
         relative residuals, by more than {AIC_MARGIN} either way, or with two points by a \
         slope of -0.15 to 0.25; a grid a power law of slope 0.2 to 0.5, about M^(1/3); every \
         backend linear in pixels and samples, slope 0.8 to 1.2).{}{}\n",
        if constant_judged > 0 || confounded > 0 {
            format!(
                " On the series whose hit fraction stays within {CONSTANT_HITS_PP} percentage \
                 point, {constant_agree} of {constant_judged} agree; {confounded} of the {} \
                 disagreements are on series whose hit fraction changes, which confounds them.",
                off.len()
            )
        } else {
            String::new()
        },
        if off.is_empty() {
            String::new()
        } else {
            format!(" These disagree:\n\n{}", off.join("\n"))
        }
    );
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::results::{Equality, Images, Skipped};

    /// The baseline and the oracle, as the registry names them.
    fn names() -> (&'static str, &'static str) {
        (
            raybench_registry::name_with(Roles::BASELINE),
            raybench_registry::name_with(Roles::ORACLE),
        )
    }

    /// A run of `backend` on `scene`, camera rays, 1,000 rays a repetition timed `samples`
    /// (ms), passing and identical.
    pub(crate) fn run(scene: &str, backend: &str, samples: &[f64]) -> Run {
        let timing =
            (!samples.is_empty()).then(|| Timing::of(samples.iter().map(|s| s * 1e-3).collect()));
        Run {
            shard: 0,
            scene: scene.into(),
            primitives: 1,
            mode: "cast".into(),
            ray_set: "primary".into(),
            width: 10,
            height: 100,
            spp: 1,
            backend: backend.into(),
            exact: true,
            reference: names().1.into(),
            status: "ok".into(),
            reason: None,
            build_seconds: None,
            memory_bytes: None,
            structure: BTreeMap::new(),
            mrays_per_s: timing.as_ref().map(|t| 1000.0 / t.median / 1e6),
            seconds: timing,
            device_seconds: None,
            device: None,
            software_device: false,
            headlight: false,
            rays: Some(1000),
            tests_per_ray: None,
            visits_per_ray: None,
            ray_costs: None,
            hit_fraction: None,
            facing_away: None,
            trace: None,
            coverage: false,
            equality: Some(Equality {
                id_match: 1.0,
                hit_mismatch: 0,
                t_mismatch: 0,
                tie_mismatch: 0,
                max_abs_dt: 0.0,
                identical: true,
                psnr_db: None,
                flip_mean: None,
                pass: true,
            }),
            images: Images::default(),
            phases: BTreeMap::new(),
            cameras: Vec::new(),
            quality: None,
        }
    }

    /// `r`, failing the equality check (outside the contract, 90 % of the ids).
    fn failed(mut r: Run) -> Run {
        r.exact = false;
        let e = r.equality.as_mut().unwrap();
        (e.id_match, e.identical, e.pass) = (0.9, false, false);
        r
    }

    /// `r`, not run, for `reason`.
    fn refused(mut r: Run, status: &str, reason: &str) -> Run {
        r.status = status.into();
        r.reason = Some(reason.into());
        (r.seconds, r.mrays_per_s, r.equality) = (None, None, None);
        r
    }

    fn cell(runs: &[Run]) -> String {
        let (baseline, oracle) = names();
        fastest_cell(&runs.iter().collect::<Vec<_>>(), baseline, oracle, false)
    }

    fn section(f: fn(&Results, &mut String), results: &Results) -> String {
        let mut s = String::new();
        f(results, &mut s);
        s
    }

    const QUIET: [f64; 6] = [1.0, 1.01, 0.99, 1.0, 1.02, 0.98];

    #[test]
    fn a_run_counts_when_it_ran_and_passed() {
        let ok = run("s", "a", &QUIET);
        assert!(valid(&ok));
        assert!(!valid(&failed(ok.clone())));
        assert!(!valid(&refused(ok.clone(), "unsupported", "no")));
        // Without an equality record (nothing to compare with) it counts.
        let mut alone = ok.clone();
        alone.equality = None;
        assert!(valid(&alone));
        let mut untimed = ok;
        untimed.mrays_per_s = None;
        assert!(!valid(&untimed));
    }

    #[test]
    fn factors_keep_two_decimals_below_ten() {
        assert_eq!(factor(1.0), "1.00");
        assert_eq!(factor(9.99), "9.99");
        assert_eq!(factor(9.996), "10.00");
        assert_eq!(factor(10.0), "10");
        assert_eq!(factor(12.5), "12");
        assert_eq!(factor(12.6), "13");
    }

    /// A coverage scene keeps its times in the tables but gets no row in the fastest-backend
    /// table; a performance scene does.
    #[test]
    fn no_winner_is_named_on_a_coverage_scene() {
        let small = |backend: &str, ms: f64| Run {
            coverage: true,
            ..run("tiny", backend, &QUIET.map(|t| t * ms))
        };
        let results = Results {
            runs: vec![
                small("a", 1.0),
                small("b", 3.0),
                run("big", "a", &QUIET),
                run("big", "b", &QUIET.map(|t| 3.0 * t)),
            ],
            ..Results::default()
        };
        let text = section(fastest, &results);
        assert!(text.contains("| big | `a`"), "{text}");
        assert!(!text.contains("| tiny |"), "{text}");
        assert!(
            text.contains(
                "Coverage scenes, timed in the tables below but judged here on nothing: `tiny`"
            ),
            "{text}"
        );
        // Without coverage scenes there is no such line.
        let only_big = Results {
            runs: results.runs[2..].to_vec(),
            ..Results::default()
        };
        assert!(!section(fastest, &only_big).contains("Coverage scenes"));
    }

    /// The ends of an interval take the ratio's decimals, either side of 10.
    #[test]
    fn a_speed_up_interval_reads_as_its_ratio() {
        let best = run("s", "best", &QUIET);
        let times = |ratios: [f64; 6]| -> Vec<f64> {
            QUIET.iter().zip(ratios).map(|(t, r)| t * r).collect()
        };
        // Ratios 9.6, 9.8, 9.9, 9.9, 10.0, 10.2: median 9.9, interval [9.6, 10.2].
        let below = run("s", "below", &times([9.6, 9.9, 10.2, 9.9, 10.0, 9.8]));
        assert_eq!(speed_up(&best, &below, false), "9.90x [9.60-10.20] below");
        // 9.6, 10.2, 10.3, 10.4, 10.5, 10.6: median 10.35, no decimals throughout.
        let above = run("s", "above", &times([9.6, 10.5, 10.2, 10.4, 10.6, 10.3]));
        assert_eq!(speed_up(&best, &above, false), "10x [10-11] above");
        // A single repetition: the ratio alone.
        let once = run("s", "once", &[4.0]);
        assert_eq!(speed_up(&best, &once, false), "4.00x once");
    }

    /// Clear leads, ties and unknown noise, each cell figured by hand: 1,000 rays a
    /// repetition, so Mrays/s = 1 / the median in ms.
    #[test]
    fn the_fastest_cell_names_a_backend_only_when_it_leads_clearly() {
        let (baseline, oracle) = names();
        // "fast" at 1.0 ms: 1.00 Mrays/s. The baseline at exactly 2x and the oracle at
        // exactly 12x every round: 2.00x [2.00-2.00] and 12x [12-12] (no decimals from 10).
        let fast = run("s", "fast", &QUIET);
        let double: Vec<f64> = QUIET.iter().map(|t| 2.0 * t).collect();
        let twelve: Vec<f64> = QUIET.iter().map(|t| 12.0 * t).collect();
        let clear = [
            run("s", oracle, &twelve),
            run("s", baseline, &double),
            fast.clone(),
        ];
        assert_eq!(
            cell(&clear),
            format!("`fast` 1.00 (2.00x [2.00-2.00] {baseline}, 12x [12-12] {oracle})")
        );
        // A faster run that failed its check is left out: the same cell.
        let mut with_failed = clear.to_vec();
        with_failed.push(failed(run("s", "wrong", &[0.1; 6])));
        assert_eq!(cell(&with_failed), cell(&clear));
        // "close" is slower in every round, by 1.0 to 2.0 % (ratios 1.010, 1.020, 1.010,
        // 1.010, 1.020, 1.010): the interval lies above 1 but the median ratio 1.01 is
        // below the 2 % minimum effect: a tie, "fast" (the lower median) first.
        let close = run("s", "close", &[1.01, 1.03, 1.0, 1.01, 1.04, 0.99]);
        let tie = cell(&[fast.clone(), close, run("s", baseline, &double)]);
        assert!(
            tie.starts_with("tie: `fast`, `close` within noise; `fast` 1.00 (2.00x"),
            "{tie}"
        );
        // A lead of 5 % whose rounds overlap (ratios 0.95 .. 1.15): a tie too.
        let overlapping = run("s", "overlap", &[1.15, 1.06, 0.94, 1.05, 1.07, 1.05]);
        let tie = cell(&[fast.clone(), overlapping]);
        assert!(
            tie.starts_with("tie: `fast`, `overlap` within noise"),
            "{tie}"
        );
        // A single repetition anywhere: named by its median, noise unknown.
        let unknown = cell(&[fast.clone(), run("s", "once", &[3.0])]);
        assert_eq!(unknown, "`fast` 1.00 ? (noise unknown)");
        // A noisy leader is marked: 1.0 .. 1.3 ms, median 1.05 ms (0.95 Mrays/s), half
        // width 0.2 / 1.05 = 19 %; the baseline is 3x every round.
        let noisy_samples = [1.0, 1.2, 0.9, 1.1, 1.0, 1.3];
        let noisy = run("s", "noisy", &noisy_samples);
        let triple: Vec<f64> = noisy_samples.iter().map(|t| 3.0 * t).collect();
        assert_eq!(
            cell(&[noisy, run("s", baseline, &triple)]),
            format!("`noisy` 0.95 † (3.00x [3.00-3.00] {baseline})")
        );
        // Nothing valid, or nothing at all.
        assert_eq!(cell(&[failed(fast.clone())]), "none passed");
        assert_eq!(cell(&[refused(fast, "unsupported", "no")]), "none passed");
        assert_eq!(cell(&[]), "");
    }

    #[test]
    fn agreement_lists_failures_per_backend() {
        let (_, oracle) = names();
        let mut results = Results {
            runs: vec![
                run("a", oracle, &QUIET),
                run("a", "same", &QUIET),
                failed(run("a", "peer", &QUIET)),
                run("b", "peer", &QUIET),
                refused(run("b", "gone", &QUIET), "unavailable", "not here"),
            ],
            ..Results::default()
        };
        results.runs[3].exact = false;
        let s = section(identical, &results);
        assert!(
            s.contains(
                "- `peer`, outside the contract: bit-identical in 1 of 2 workloads, passed 1 of 2; \
                 **failed**: a cast-primary.\n"
            ),
            "{s}"
        );
        assert!(
            s.contains(
                "- `same`, exact (bound by the contract): bit-identical in 1 of 1 workloads, \
                 passed 1 of 1.\n"
            ),
            "{s}"
        );
        // The reference and the runs that did not run are not compared.
        assert!(
            !s.contains(&format!("`{oracle}`,")) && !s.contains("`gone`"),
            "{s}"
        );
        // Only references: no section.
        results.runs.truncate(1);
        assert_eq!(section(identical, &results), "");
    }

    #[test]
    fn skipped_says_what_did_not_run_or_that_everything_did() {
        let empty = Results::default();
        assert_eq!(
            section(skipped, &empty),
            "**Skipped**: nothing was planned.\n\n"
        );
        let mut results = Results {
            runs: vec![run("a", "x", &QUIET)],
            ..Results::default()
        };
        assert_eq!(
            section(skipped, &results),
            "**Skipped**: nothing; every scene, workload and backend ran.\n\n"
        );
        results.skipped.push(Skipped {
            shard: 0,
            kind: "scene".into(),
            name: "big".into(),
            status: "skipped".into(),
            reason: "missing big.obj".into(),
        });
        for scene in ["a", "b"] {
            results.runs.push(refused(
                run(scene, "y", &QUIET),
                "unsupported",
                "no volumes",
            ));
        }
        assert_eq!(
            section(skipped, &results),
            "**Skipped or refused**:\n\n- scene `big` (skipped): missing big.obj\n\
             - `y` unsupported on a cast-primary, b cast-primary: no volumes\n\n"
        );
    }

    #[test]
    fn noise_names_the_wide_intervals_only() {
        let quiet = run("a", "quiet", &QUIET);
        // 0.96 .. 1.04 around 1.0 is ±4 %: not noisy.
        let edge = run("a", "edge", &[1.0, 0.96, 1.04, 1.0, 1.0, 1.0]);
        let mut results = Results {
            runs: vec![quiet, edge],
            ..Results::default()
        };
        let s = section(noisy, &results);
        assert!(
            s.starts_with(
                "**Noise**: 2 timed runs, 12 timed repetitions; no median's 95% interval is \
                 wider than ±5%; 0 repetitions redone"
            ),
            "{s}"
        );
        // Wider than 5 %: 0.9 .. 1.12 around 1.0 is ±11 %; a single repetition is unknown.
        results
            .runs
            .push(run("b", "wide", &[1.0, 0.9, 1.12, 1.0, 1.0, 1.0]));
        results.runs.push(run("b", "once", &[1.0]));
        results.runs[0].seconds.as_mut().unwrap().redone = 3;
        let s = section(noisy, &results);
        assert!(
            s.starts_with(
                "**Noise**: 4 timed runs, 19 timed repetitions; 1 with a median's interval \
                 wider than ±5% (marked †): b cast-primary `wide` (±11%); 1 with a single \
                 repetition, whose noise is unknown (marked ?); 3 repetitions redone"
            ),
            "{s}"
        );
        // The last-level cache's walks: quiet, then contested after shard 1.
        let walk = |median_ns| crate::results::CacheWalk {
            bytes: 8 << 20,
            samples: 100,
            fastest_ns: 20.0,
            median_ns,
            p90_ns: 100.0,
            slowest_ns: 100.0,
        };
        results.shards = vec![crate::results::Shard {
            index: 1,
            count: 1,
            machine: crate::results::Machine::default(),
            started: String::new(),
            wall_seconds: 1.0,
            command: String::new(),
            quick: false,
            load: None,
            ranked_by_device: false,
            others: None,
            cache: Some([walk(22.0), walk(24.0)]),
            pinned: false,
            repeat: String::new(),
            min_sample: 0.0,
            plan: None,
        }];
        let s = section(noisy, &results);
        assert!(
            s.contains(
                "; the last-level cache was quiet (a walk through 8.0 MiB of it within 1.20 \
                 times its fastest step at the median, before and after every shard that timed \
                 it)"
            ),
            "{s}"
        );
        results.shards[0].cache = Some([walk(22.0), walk(60.0)]);
        let s = section(noisy, &results);
        assert!(
            s.contains(
                "; the last-level cache was shared with busy neighbours (a walk through 8.0 \
                 MiB of it took 3.00 times its fastest step at the median, after shard 1)"
            ),
            "{s}"
        );
        // Past twelve, the rest are counted.
        results.runs = (0..14)
            .map(|i| run("c", &format!("w{i:02}"), &[1.0, 0.9, 1.12, 1.0, 1.0, 1.0]))
            .collect();
        let s = section(noisy, &results);
        assert!(s.contains("`w11` (±11%), and 2 more;"), "{s}");
        assert!(!s.contains("`w12`"), "{s}");
    }

    fn fit(experiment: &str, backend: &str, slope: f64) -> Fit {
        Fit {
            experiment: experiment.into(),
            series: "s".into(),
            backend: backend.into(),
            quantity: "seconds".into(),
            slope,
            intercept: None,
            points: 3,
            per_decade: None,
            delta_aic: None,
        }
    }

    /// A point of `primitives` with its hit fraction (read from JSON, so that fields added
    /// later with defaults need no change here).
    fn hit_point(series: &str, backend: &str, x: f64, hits: f64) -> crate::results::ScalingPoint {
        serde_json::from_value(serde_json::json!({
            "shard": 0,
            "experiment": "primitives",
            "series": series,
            "backend": backend,
            "x": x,
            "seconds": 1e-3,
            "rays": 4096,
            "hit_fraction": hits,
        }))
        .unwrap()
    }

    /// A disagreement says whether its series' hit fraction moved (confounding it) or
    /// stayed put (ruling the hit rate out), and the summary counts both.
    #[test]
    fn disagreements_say_whether_the_hit_fraction_moved() {
        let (baseline, _) = names();
        let power_law = |series: &str| Fit {
            series: series.into(),
            delta_aic: Some(-9.0),
            ..fit("primitives", baseline, 0.3)
        };
        let mut results = Results {
            fits: vec![
                power_law("soup"),
                power_law("icosphere"),
                Fit {
                    series: "spheres".into(),
                    delta_aic: Some(5.0),
                    ..fit("primitives", baseline, 0.1)
                },
                // No hit fractions recorded: no clause, counted in neither group.
                power_law("old"),
            ],
            ..Results::default()
        };
        for (series, hits) in [
            ("soup", [0.20, 0.41, 0.55]),
            ("icosphere", [0.300, 0.303, 0.304]),
            ("spheres", [0.500, 0.502, 0.501]),
        ] {
            for (i, h) in hits.into_iter().enumerate() {
                let x = 10f64.powi(i as i32 + 3);
                results.scaling.push(hit_point(series, baseline, x, h));
                // A later point of the same `x` is not read.
                results.scaling.push(hit_point(series, baseline, x, 0.99));
            }
        }
        let s = section(slopes, &results);
        assert!(s.contains("1 of 4 fits of render time agree"), "{s}");
        assert!(
            s.contains(
                "On the series whose hit fraction stays within 1 percentage point, 1 of 2 \
                 agree; 1 of the 3 disagreements are on series whose hit fraction changes, \
                 which confounds them. These disagree:"
            ),
            "{s}"
        );
        assert!(
            s.contains(
                "`soup`: theory logarithmic in M; the points favour a power law (M^0.30) over \
                 a logarithm (Akaike criterion 9.0 lower); likely: the rays' work or memory \
                 traffic grows faster than the theory's (tests per ray not counted, so which \
                 is not known); the hit fraction moves between 20.0% and 55.0% over the \
                 series, which confounds the fit"
            ),
            "{s}"
        );
        assert!(
            s.contains(
                "the hit fraction stays within 0.4 percentage points over the series, so the \
                 hit rate is not the cause."
            ),
            "{s}"
        );
        let old = s.lines().find(|l| l.contains("`old`")).unwrap();
        assert!(!old.contains("hit fraction"), "{old}");
    }

    #[test]
    fn slopes_are_judged_against_their_theory_ranges() {
        let (baseline, oracle) = names();
        let grid = raybench_registry::name_with(Roles::GRID);
        // The oracle is brute force: linear in M, 0.75 to 1.25 (ends included); a tree
        // without a model comparison by its slope, -0.15 to 0.25; a grid 0.2 to 0.5;
        // every backend linear in pixels, 0.8 to 1.2; the experiments without a theory are
        // not judged.
        let results = Results {
            fits: vec![
                fit("primitives", oracle, 1.25),
                fit("primitives", baseline, 0.25),
                fit("primitives", grid, 1.0 / 3.0),
                fit("pixels", baseline, 0.8),
                fit("presets", baseline, 3.0),
                Fit {
                    quantity: "tests_per_ray".into(),
                    ..fit("primitives", baseline, 9.0)
                },
            ],
            ..Results::default()
        };
        let s = section(slopes, &results);
        assert!(
            s.starts_with("**Scaling against theory**: 4 of 4 fits of render time agree"),
            "{s}"
        );
        assert!(s.ends_with("samples, slope 0.8 to 1.2).\n\n"), "{s}");
        // The grid's 1/3 is no tree's logarithm; the tree's 0.33 with the points favouring
        // a power law disagrees, diagnosed from its tests per ray.
        let results = Results {
            fits: vec![
                fit("primitives", oracle, 1.26),
                fit("primitives", baseline, -0.16),
                fit("spp", baseline, 1.0),
                Fit {
                    series: "soup".into(),
                    delta_aic: Some(-7.5),
                    ..fit("primitives", baseline, 0.33)
                },
                Fit {
                    series: "soup".into(),
                    quantity: "tests_per_ray".into(),
                    ..fit("primitives", baseline, 0.31)
                },
                Fit {
                    series: "flat".into(),
                    delta_aic: Some(1.0),
                    ..fit("primitives", baseline, 0.33)
                },
            ],
            ..Results::default()
        };
        let s = section(slopes, &results);
        assert!(s.contains("2 of 5 fits of render time agree"), "{s}");
        assert!(
            s.contains(&format!(
                "- `{oracle}` on primitives `s`: theory linear in M (slope about 1); slope \
                 1.26, outside 0.75 to 1.25; likely: the rays' work or memory traffic grows \
                 faster than the theory's (tests per ray not counted, so which is not known).\n"
            )),
            "{s}"
        );
        assert!(
            s.contains(&format!(
                "- `{baseline}` on primitives `s`: theory logarithmic in M; slope -0.16, \
                 outside -0.15 to 0.25; likely: {FIXED_COSTS} (tests per ray not counted)."
            )),
            "{s}"
        );
        assert!(
            s.contains(&format!(
                "- `{baseline}` on primitives `soup`: theory logarithmic in M; the points \
                 favour a power law (M^0.33) over a logarithm (Akaike criterion 7.5 lower); \
                 likely: tests per ray grow too (M^0.31)"
            )),
            "{s}"
        );
        // Points that do not tell the models apart agree with the logarithm.
        assert!(!s.contains("`flat`"), "{s}");
        // No fits of time: no paragraph.
        assert_eq!(section(slopes, &Results::default()), "");
    }

    #[test]
    fn the_verdict_of_nothing_says_so() {
        let s = section(write, &Results::default());
        assert_eq!(
            s,
            "## Verdict\n\nNothing ran.\n\n**Skipped**: nothing was planned.\n\n"
        );
    }
}
