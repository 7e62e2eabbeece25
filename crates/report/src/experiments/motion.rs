//! Experiment `motion`: refit against rebuild over the frames of the moving scene whose
//! `[benchmark]` table names it (`bench-scenes/moving.toml`). For every chosen backend
//! that refits (its [`Renderer::update`] reports a `refit` phase), two renderers follow
//! the frames: one refitted from frame 0 on ([`UpdatePolicy::Refit`]), one rebuilt every
//! frame ([`UpdatePolicy::Rebuild`]). Per frame: the refit's and the rebuild's seconds (and
//! the two-level form's top-level rebuild), the trace time of camera rays through each
//! (median of the run's repetitions, ray casting at the report's size, or 128 in the quick
//! run) and each one's SAH cost over the flat primitives (backends that rebuild under both
//! policies are left out, with a line on stderr). The frames are
//! [`MotionFrame`]s of `results.json`, so `raybench merge` redraws the part.

use super::{Chart, Experiment, Planned, Plot, planned, skip};
use crate::charts::Series;
use crate::ctx::{Ctx, Workload};
use crate::fmt::{file_safe, section};
use crate::results::{MotionFrame, Results};
use anyhow::Result;
use raybench_core::{
    Mode, QualityParams, RaySet, Renderer, StructureQuality, Timings, UpdatePolicy,
};
use raybench_registry::Roles;
use raybench_registry::frames::advance;
use raybench_registry::measure::prepare;
use raybench_registry::progress::Progress;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// Experiment `motion`.
pub(super) struct Motion;

/// Its name.
const NAME: &str = "motion";

/// Frames of the full run and of the quick run.
const FRAMES: (u32, u32) = (32, 8);

/// Largest image side of the quick run (its frames must stay fast).
const QUICK_SIZE: u32 = 128;

/// The SAH cost over the flat primitives of a prepared renderer (`C_t = C_i = 1`, no EPO).
fn sah(r: &dyn Renderer) -> Option<f64> {
    let params = QualityParams {
        epo_samples: 0,
        ..QualityParams::default()
    };
    match r.flat_quality(&params) {
        Some(StructureQuality::Tree(q)) => Some(q.sah),
        _ => None,
    }
}

/// The sum of an update's phases named `names`.
fn phase(t: &Timings, names: &[&str]) -> Option<f64> {
    let v: Vec<f64> = names.iter().filter_map(|n| t.get(n)).collect();
    (!v.is_empty()).then(|| v.iter().sum())
}

/// Frames on either side of a frame whose times [`rebuild_pays`] takes the median of.
const SMOOTHING_RADIUS: usize = 2;

/// Each value replaced by the median of the values at most `radius` places away (fewer at
/// the ends): a lone outlier, one frame the machine interrupted, cannot move a running sum.
fn running_median(values: &[f64], radius: usize) -> Vec<f64> {
    (0..values.len())
        .map(|i| {
            let window = &values[i.saturating_sub(radius)..(i + radius + 1).min(values.len())];
            crate::stats::median(window).unwrap_or(0.0)
        })
        .collect()
}

/// When rebuilding pays, from per-frame `(refit + top, rebuild + top, trace refitted, trace
/// rebuilt)` seconds of frames 1, 2, ...: the first frame (1-based index into the list) at
/// which refitting every frame has cost more in total than rebuilding every frame, and the
/// first frame at which the refitted tree's extra trace time, summed since frame 0, exceeds
/// that frame's rebuild (one rebuild there would have paid for itself already). Each frame
/// is timed once, so each series is first replaced by its running median over
/// 2 x [`SMOOTHING_RADIUS`] + 1 frames: a single slow frame (an interruption) does not move
/// a break-even, while a trend (the refitted tree decaying) does.
#[must_use]
pub(super) fn rebuild_pays(frames: &[(f64, f64, f64, f64)]) -> (Option<usize>, Option<usize>) {
    let column = |f: fn(&(f64, f64, f64, f64)) -> f64| {
        running_median(&frames.iter().map(f).collect::<Vec<_>>(), SMOOTHING_RADIUS)
    };
    let smoothed: Vec<(f64, f64, f64, f64)> = {
        let (a, b, c, d) = (
            column(|f| f.0),
            column(|f| f.1),
            column(|f| f.2),
            column(|f| f.3),
        );
        (0..frames.len())
            .map(|i| (a[i], b[i], c[i], d[i]))
            .collect()
    };
    let (mut refit_total, mut rebuild_total, mut extra) = (0.0, 0.0, 0.0);
    let (mut always, mut once) = (None, None);
    for (i, &(refit, rebuild, traced_refit, traced_rebuilt)) in smoothed.iter().enumerate() {
        refit_total += refit + traced_refit;
        rebuild_total += rebuild + traced_rebuilt;
        extra += traced_refit - traced_rebuilt;
        if always.is_none() && refit_total > rebuild_total {
            always = Some(i + 1);
        }
        if once.is_none() && extra > rebuild {
            once = Some(i + 1);
        }
    }
    (always, once)
}

impl Motion {
    /// The moving scene it runs, and its frame count and image side.
    fn plan_of(ctx: &Ctx) -> Option<(&'static str, u32, u32)> {
        let scene = raybench_scene::for_experiment(NAME)?;
        Some(if ctx.opts.quick {
            (scene.name, FRAMES.1, ctx.size.min(QUICK_SIZE))
        } else {
            (scene.name, FRAMES.0, ctx.size)
        })
    }

    /// The chosen backends it tries: exact, not brute force (naive rebuilds nothing and
    /// tests every primitive), not pinned variants of another.
    fn backends(ctx: &Ctx) -> Vec<&'static raybench_registry::Backend> {
        ctx.chosen
            .iter()
            .copied()
            .filter(|b| b.is(Roles::EXACT) && !b.is(Roles::BRUTE_FORCE) && !b.is(Roles::PINNED))
            .collect()
    }
}

/// The first paragraph of its section of `REPORT.md`.
const INTRO: &str = "\
    The frames of a moving scene, followed by two structures of each backend that \
    refits: one built at frame 0 and refitted every frame (boxes recomputed bottom \
    up, the tree's topology kept; a two-level form refits its flat part and the \
    meshes that deform, and rebuilds its top level over the instances: `top`), and \
    one rebuilt every frame (its flat part, the deformed meshes and the top level). \
    Per frame: the update's seconds, the median trace time of the camera rays (ray \
    casting) through each, and each one's SAH cost over the flat primitives (where \
    the twisting mesh is). Both give the same ids and `t` on every frame (checked \
    here, and against naive by `tests/tests/motion.rs`). One run on a shared \
    machine: trace times within a few per cent of each other are noise. Each frame \
    is timed once, so the break-evens below use each series' running median over \
    five frames: one slow frame (an interruption) moves neither, a trend does.";

impl Experiment for Motion {
    fn name(&self) -> &'static str {
        NAME
    }

    fn plan(&self, ctx: &Ctx, unit: &str, results: &mut Results) -> Result<Option<Planned>> {
        let steps = match (Self::plan_of(ctx), Self::backends(ctx).len()) {
            (None, _) => {
                Err("no built-in scene names experiment `motion` in its [benchmark] table".into())
            }
            (Some(_), 0) => Err("no chosen backend is an exact, accelerated one".into()),
            (Some((_, frames, _)), backends) => Ok(backends * frames as usize),
        };
        Ok(planned(results, unit, steps))
    }

    fn run(&self, ctx: &Ctx, _: Planned, progress: &Progress, results: &mut Results) -> Result<()> {
        let Some((spec, frames, size)) = Self::plan_of(ctx) else {
            return Ok(());
        };
        let backends = Self::backends(ctx);
        progress.begin(format!("motion: load {spec}"));
        let scene = match ctx.load(spec)? {
            Ok(scene) => scene,
            Err(why) => {
                skip(results, "experiment", NAME, "skipped", why);
                progress.remove(backends.len() * frames as usize);
                return Ok(());
            }
        };
        let w = Workload {
            mode: Mode::Cast,
            rays: RaySet::Primary,
            width: size,
            height: size,
            spp: 1,
            replay: false,
        };
        let mut skipped: Vec<String> = Vec::new();
        for b in backends {
            let name = b.name;
            progress.begin(format!("motion {name}: build"));
            // Whether it refits: a backend that rebuilds under both policies has nothing
            // to compare, and is left out.
            let refits = match prepare(b, &scene) {
                Ok(mut probe) => advance(probe.renderer.as_mut(), &scene, 1, UpdatePolicy::Refit)
                    .map_err(anyhow::Error::msg)?
                    .1
                    .get("refit")
                    .is_some(),
                Err(why) => {
                    skipped.push(format!("{name}: {why}"));
                    progress.remove(frames as usize);
                    continue;
                }
            };
            if !refits {
                eprintln!("motion: {name} cannot refit (it rebuilds every frame): left out");
                progress.remove(frames as usize);
                continue;
            }
            let (mut refitted, mut rebuilt) = match (prepare(b, &scene), prepare(b, &scene)) {
                (Ok(a), Ok(c)) => (a, c),
                (Err(why), _) | (_, Err(why)) => {
                    skipped.push(format!("{name}: {why}"));
                    progress.remove(frames as usize);
                    continue;
                }
            };
            let mut rows = Vec::new();
            for f in 0..frames {
                let (refit, top, rebuild) = if f == 0 {
                    (None, None, refitted.build)
                } else {
                    progress.begin(format!("motion {name}: frame {f}: update"));
                    let (_, a) =
                        advance(refitted.renderer.as_mut(), &scene, f, UpdatePolicy::Refit)
                            .map_err(anyhow::Error::msg)?;
                    let (_, c) =
                        advance(rebuilt.renderer.as_mut(), &scene, f, UpdatePolicy::Rebuild)
                            .map_err(anyhow::Error::msg)?;
                    anyhow::ensure!(
                        a.get("refit").is_some(),
                        "motion: {name} refitted frame 1 but not frame {f}"
                    );
                    (
                        phase(&a, &["refit"]),
                        a.get("top"),
                        phase(&c, &["build", "top"]).unwrap_or(0.0),
                    )
                };
                progress.begin(format!("motion {name}: frame {f}: trace"));
                // In the same rounds, so that load drift reaches both alike.
                let mut both = ctx.measure_all(
                    &[refitted.renderer.as_ref(), rebuilt.renderer.as_ref()],
                    &w.settings(),
                    &[(None, None)],
                )?;
                let m_rebuilt = both.pop().expect("two measured").0;
                let m_refit = both.pop().expect("two measured").0;
                anyhow::ensure!(
                    m_refit.warm.ids == m_rebuilt.warm.ids
                        && m_refit
                            .warm
                            .t
                            .iter()
                            .zip(&m_rebuilt.warm.t)
                            .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "motion: {name} frame {f}: the refitted and the rebuilt structure disagree"
                );
                rows.push(MotionFrame {
                    shard: 0,
                    scene: spec.into(),
                    backend: name.into(),
                    frame: f,
                    size,
                    refit_seconds: refit,
                    rebuild_seconds: rebuild,
                    top_seconds: top,
                    trace_refitted_seconds: m_refit.timing.median,
                    trace_rebuilt_seconds: m_rebuilt.timing.median,
                    sah_refitted: sah(refitted.renderer.as_ref()),
                    sah_rebuilt: sah(rebuilt.renderer.as_ref()),
                });
                progress.step(&format!("motion {name}: frame {f}"));
            }
            results.motion.extend(rows);
        }
        if !skipped.is_empty() {
            let status = if !results.motion.iter().any(|m| m.scene == spec) {
                "skipped"
            } else {
                "partial"
            };
            skip(results, "experiment", NAME, status, skipped.join("; "));
        }
        Ok(())
    }

    fn charts(&self, results: &Results) -> Vec<Chart> {
        let mut out = Vec::new();
        for ((scene, backend), rows) in by_backend(results) {
            let series = |label: &str, y: &dyn Fn(&MotionFrame) -> Option<f64>| Series {
                label: label.into(),
                points: rows
                    .iter()
                    .filter_map(|r| y(r).map(|v| (f64::from(r.frame), v)))
                    .collect(),
                fit: None,
            };
            let stem = format!("motion-{}-{}", file_safe(&scene), file_safe(&backend));
            out.push(Chart {
                title: format!("Refit against rebuild per frame ({scene}, {backend})"),
                stem: format!("{stem}-time"),
                x_label: "frame".into(),
                y_label: "seconds".into(),
                plot: Plot::Lines(vec![
                    series("refit", &|r| {
                        r.refit_seconds.map(|s| s + r.top_seconds.unwrap_or(0.0))
                    }),
                    series("rebuild", &|r| (r.frame > 0).then_some(r.rebuild_seconds)),
                    series("trace, refitted", &|r| Some(r.trace_refitted_seconds)),
                    series("trace, rebuilt", &|r| Some(r.trace_rebuilt_seconds)),
                ]),
            });
            out.push(Chart {
                title: format!("SAH cost per frame, refitted and rebuilt ({scene}, {backend})"),
                stem: format!("{stem}-sah"),
                x_label: "frame".into(),
                y_label: "SAH cost (C_t = C_i = 1)".into(),
                plot: Plot::Lines(vec![
                    series("refitted", &|r| r.sah_refitted),
                    series("rebuilt", &|r| r.sah_rebuilt),
                ]),
            });
        }
        out
    }

    fn write(&self, results: &Results, s: &mut String) {
        let groups = by_backend(results);
        if groups.is_empty() {
            return;
        }
        section(s, "Moving scenes: refit against rebuild", INTRO);
        for ((scene, backend), rows) in &groups {
            let size = rows.first().map_or(0, |r| r.size);
            let _ = writeln!(s, "### {scene}, {backend} ({size} x {size})\n");
            let _ = writeln!(
                s,
                "| frame | refit ms | top ms | rebuild ms | trace refitted ms | trace rebuilt ms \
                 | SAH refitted | SAH rebuilt |"
            );
            let _ = writeln!(s, "|---:|---:|---:|---:|---:|---:|---:|---:|");
            let ms = |v: Option<f64>| v.map_or("-".into(), |v| format!("{:.3}", v * 1e3));
            let sah = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.2}"));
            for r in rows {
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} | {} | {} | {} | {} |",
                    r.frame,
                    ms(r.refit_seconds),
                    ms(r.top_seconds),
                    ms(Some(r.rebuild_seconds)),
                    ms(Some(r.trace_refitted_seconds)),
                    ms(Some(r.trace_rebuilt_seconds)),
                    sah(r.sah_refitted),
                    sah(r.sah_rebuilt)
                );
            }
            let later: Vec<(f64, f64, f64, f64)> = rows
                .iter()
                .filter(|r| r.frame > 0)
                .map(|r| {
                    (
                        r.refit_seconds.unwrap_or(0.0) + r.top_seconds.unwrap_or(0.0),
                        r.rebuild_seconds,
                        r.trace_refitted_seconds,
                        r.trace_rebuilt_seconds,
                    )
                })
                .collect();
            let last = rows.last().map_or(0, |r| r.frame);
            let (always, once) = rebuild_pays(&later);
            let decay = rows
                .last()
                .and_then(|r| Some(r.sah_refitted? / r.sah_rebuilt?))
                .map_or(String::new(), |x| {
                    format!(
                        " By frame {last} the refitted tree's SAH cost is {x:.2} times the \
                         rebuilt one's."
                    )
                });
            let always = match always {
                Some(f) => format!(
                    "From frame {f} on, rebuilding every frame would have cost less in total \
                     (updates and traces) than refitting every frame."
                ),
                None => format!(
                    "Refitting every frame costs less in total (updates and traces) than \
                     rebuilding every frame through frame {last}."
                ),
            };
            let once = match once {
                Some(f) => format!(
                    " One rebuild pays for itself at frame {f}: the refitted tree's extra \
                     trace time since frame 0 then exceeds a rebuild's."
                ),
                None => format!(
                    " The refitted tree's extra trace time, summed over frames 1 to {last}, \
                     stays below one rebuild: within these frames a rebuild does not pay."
                ),
            };
            let _ = writeln!(s, "\n{always}{once}{decay}\n");
        }
    }
}

/// The experiment's frames by (scene, backend), in frame order.
fn by_backend(results: &Results) -> BTreeMap<(String, String), Vec<MotionFrame>> {
    let mut out: BTreeMap<(String, String), Vec<MotionFrame>> = BTreeMap::new();
    for r in &results.motion {
        out.entry((r.scene.clone(), r.backend.clone()))
            .or_default()
            .push(r.clone());
    }
    for rows in out.values_mut() {
        rows.sort_by_key(|r| r.frame);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn when_a_rebuild_pays() {
        // Refit 1 ms, rebuild 10 ms; the refitted tree traces 2 ms slower per frame: its
        // extra trace time (2, 4, ... ms) passes one rebuild at the sixth frame, while
        // refitting every frame (23 ms a frame) stays cheaper than rebuilding (30 ms).
        let frames: Vec<(f64, f64, f64, f64)> =
            (0..12).map(|_| (0.001, 0.010, 0.022, 0.020)).collect();
        assert_eq!(rebuild_pays(&frames), (None, Some(6)));
        // A tree that decays fast: 15 ms slower per frame; rebuilding every frame is
        // cheaper from the first frame, and one rebuild pays at once.
        let fast: Vec<(f64, f64, f64, f64)> =
            (0..4).map(|_| (0.001, 0.010, 0.035, 0.020)).collect();
        assert_eq!(rebuild_pays(&fast), (Some(1), Some(1)));
        assert_eq!(rebuild_pays(&[]), (None, None));
    }

    /// One frame the machine interrupted (its refitted trace 30 ms slower) does not make a
    /// rebuild pay at that frame; a lasting slowdown still does.
    #[test]
    fn a_lone_slow_frame_is_no_break_even() {
        let mut frames: Vec<(f64, f64, f64, f64)> =
            (0..12).map(|_| (0.001, 0.010, 0.0205, 0.020)).collect();
        frames[4].2 += 0.030;
        assert_eq!(rebuild_pays(&frames), (None, None));
        // Slower from that frame on: a trend, so a rebuild pays there (frame 5).
        for f in &mut frames[4..] {
            f.2 += 0.030;
        }
        assert_eq!(rebuild_pays(&frames).1, Some(5));
        assert_eq!(running_median(&[1.0, 9.0, 1.0, 1.0, 1.0], 2), vec![1.0; 5]);
    }
}
