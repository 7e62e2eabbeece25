//! Experiment `presets`: every builder preset of the chosen backends
//! ([`raybench_registry::presets::PRESETS`]) on the scene whose `[benchmark]` table names it (the bunny;
//! a built-in scene names each experiment once) and, in the full run, a generated triangle
//! soup: build time (median of the run's repetitions)
//! against the trace time of camera rays and of incoherent rays, the structure's memory,
//! and the time to an image, `build + k x frame` for k = 1, 16 and 256 frames, with the
//! frame count at which a slower-building, faster-tracing preset pays for its build.
//!
//! Its points are [`ScalingPoint`]s of series `SCENE RAYS` (`bunny primary`,
//! `bunny incoherent`), backend `BACKEND:PRESET`, `x` the ray count, `seconds` the median
//! trace time, with `build_seconds` and `memory_bytes`.

use super::{Chart, Experiment, Planned, Plot, planned, skip};
use crate::charts::Series;
use crate::ctx::{Ctx, Workload, memory_bytes};
use crate::fmt::file_safe;
use crate::fmt::{bytes, opt, section};
use crate::results::{Quality, Results, ScalingPoint};
use anyhow::Result;
use raybench_core::{Hit, Mode, QualityParams, Ray, RaySet};
use raybench_registry::measure::{explicit_rays, median, prepare, primary_rays};
use raybench_registry::presets::{PRESETS, Preset};
use raybench_registry::progress::Progress;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::sync::Arc;

/// Experiment `presets`.
pub(super) struct Presets;

/// Its name.
const NAME: &str = "presets";

/// The frame counts of the time-to-image comparison.
pub(super) const FRAMES: [f64; 3] = [1.0, 16.0, 256.0];

/// The generated mesh the full run adds to the built-in scenes: a triangle soup, where
/// tree quality matters most (the peer benchmark's `soup`).
const GENERATED: &str = "soup:100000";

impl Presets {
    /// The scene specs it runs: the built-in scenes naming it, then (full run) [`GENERATED`].
    fn scenes(ctx: &Ctx) -> Vec<String> {
        let mut specs: Vec<String> = raybench_scene::BUILTIN_SCENES
            .iter()
            .filter(|b| b.benchmark.experiments.contains(&NAME))
            .map(|b| b.name.to_string())
            .collect();
        if !ctx.opts.quick && !specs.is_empty() {
            specs.push(GENERATED.into());
        }
        specs
    }

    /// The presets it runs: those named with `--backends`, and every preset of a chosen
    /// backend.
    fn presets(ctx: &Ctx) -> Vec<&'static Preset> {
        PRESETS
            .iter()
            .filter(|p| {
                ctx.chosen
                    .iter()
                    .any(|b| b.name == p.entry.name || b.name == p.backend)
            })
            .collect()
    }
}

/// The frame count after which preset `slow` (slower build, faster trace) is faster to an
/// image than preset `fast`, from their `(build, trace per frame)` seconds: the `k` where
/// `build_slow + k trace_slow = build_fast + k trace_fast`; `None` when `slow` never
/// catches up (it does not trace faster).
#[must_use]
pub(super) fn break_even(fast: (f64, f64), slow: (f64, f64)) -> Option<f64> {
    let gain = fast.1 - slow.1;
    (gain > 0.0).then(|| ((slow.0 - fast.0) / gain).max(0.0))
}

/// One preset's figures on one scene: `(preset, build s, primary trace s, the trace
/// median's interval where recorded)`.
type Measured = (String, f64, f64, Option<[f64; 2]>);

/// The presets of experiment `presets` on scene `scene` with their build and camera-ray
/// trace seconds, grouped by backend (the part before `:`), in the order they ran.
fn by_backend(results: &Results, scene: &str) -> BTreeMap<String, Vec<Measured>> {
    let series = format!("{scene} {}", RaySet::Primary.name());
    let mut out: BTreeMap<String, Vec<Measured>> = BTreeMap::new();
    for p in results
        .scaling
        .iter()
        .filter(|p| p.experiment == NAME && p.series == series)
    {
        let backend = p.backend.split(':').next().unwrap_or_default();
        if let Some(build) = p.build_seconds {
            out.entry(backend.into()).or_default().push((
                p.backend.clone(),
                build,
                p.seconds,
                p.timing.as_ref().and_then(|t| t.interval),
            ));
        }
    }
    out
}

/// The scenes of experiment `presets` in `results`, in the order they ran.
fn scenes_in(results: &Results) -> Vec<String> {
    let suffix = format!(" {}", RaySet::Primary.name());
    let mut scenes: Vec<String> = Vec::new();
    for p in results.scaling.iter().filter(|p| p.experiment == NAME) {
        if let Some(scene) = p.series.strip_suffix(&suffix)
            && !scenes.iter().any(|s| s == scene)
        {
            scenes.push(scene.to_string());
        }
    }
    scenes
}

/// `rays` each clipped at its closest hit in `hits` (a miss keeps its own end): the
/// segments whose leaf counts the fixed-kernel analysis reads. Empty when the counts do not
/// match (a backend that does not trace rays one by one answers none).
fn segments(rays: &[Ray], hits: &[Option<Hit>]) -> Arc<[Ray]> {
    if rays.len() != hits.len() {
        return Arc::from(Vec::new());
    }
    rays.iter()
        .zip(hits)
        .map(|(r, h)| Ray {
            t_max: h.map_or(r.t_max, |h| h.t.min(r.t_max)),
            ..*r
        })
        .collect()
}

/// Whether two medians' intervals overlap (both recorded): then neither trace is shown
/// faster, and a break-even computed from their difference would be noise.
fn overlap(a: Option<[f64; 2]>, b: Option<[f64; 2]>) -> bool {
    matches!((a, b), (Some([a0, a1]), Some([b0, b1])) if a0 <= b1 && b0 <= a1)
}

/// The preset of `list` fastest to an image after `k` frames.
fn fastest_at(list: &[Measured], k: f64) -> Option<&Measured> {
    list.iter()
        .min_by(|a, b| (a.1 + k * a.2).total_cmp(&(b.1 + k * b.2)))
}

/// The first paragraph of its section of `REPORT.md`.
const INTRO: &str = "\
    Every builder preset of the chosen backends (`BACKEND:PRESET`; `raybench \
    backends` lists them) on each scene: the build (median of the run's repetitions, \
    a fresh structure each, all threads), then one frame of camera rays (ray casting, \
    the report's image size) and as many incoherent rays, timed as in the matrix \
    (median). Memory: primitives plus structure (Embree's own BVH is not counted). \
    Time to an image is `build + k x frame` with the camera-ray frame; the \
    break-even is the frame count after which the backend's fastest-tracing preset \
    overtakes the one fastest to a first image, given only where the two presets' \
    trace medians have intervals that do not overlap (else no preset traces faster, \
    and the table says so). One run on a shared machine: a \
    difference of a few per cent between presets is within its noise (the \
    matrix's min-max spreads show how much).";

impl Experiment for Presets {
    fn name(&self) -> &'static str {
        NAME
    }

    fn plan(&self, ctx: &Ctx, unit: &str, results: &mut Results) -> Result<Option<Planned>> {
        let (scenes, presets) = (Self::scenes(ctx), Self::presets(ctx));
        let steps = if scenes.is_empty() {
            Err("no built-in scene names experiment `presets` in its [benchmark] table".into())
        } else if presets.is_empty() {
            Err("no chosen backend has build presets".into())
        } else {
            Ok(scenes.len() * presets.len())
        };
        Ok(planned(results, unit, steps))
    }

    fn run(&self, ctx: &Ctx, _: Planned, progress: &Progress, results: &mut Results) -> Result<()> {
        let presets = Self::presets(ctx);
        let scenes = Self::scenes(ctx);
        let mut skipped: Vec<String> = Vec::new();
        let mut ran = false;
        for spec in &scenes {
            progress.begin(format!("presets: load {spec}"));
            let scene = match ctx.load(spec)? {
                Ok(scene) => scene,
                Err(why) => {
                    skipped.push(why);
                    progress.remove(presets.len());
                    continue;
                }
            };
            let primary = super::square(ctx.size, 1, Mode::Cast);
            let incoherent = Workload {
                rays: RaySet::Incoherent,
                ..primary
            };
            let rays = explicit_rays(
                RaySet::Incoherent,
                &scene,
                &incoherent.settings(),
                &raybench_core::ray_sets::DerivedParams::default(),
            )?;
            let camera = primary_rays(&scene, &primary.settings())?;
            for p in &presets {
                let name = p.entry.name;
                progress.begin(format!("presets {spec} {name}: build"));
                // The run's repetitions of the build, each a fresh renderer; the last one
                // traces.
                let mut builds = Vec::new();
                let mut prepared = None;
                for _ in 0..ctx.repeat {
                    match prepare(&p.entry, &scene) {
                        Ok(r) => {
                            builds.push(r.build);
                            prepared = Some(r.renderer);
                        }
                        Err(why) => {
                            skipped.push(format!("{name}: {why}"));
                            break;
                        }
                    }
                }
                let Some(r) = prepared.filter(|_| builds.len() == ctx.repeat as usize) else {
                    progress.step(&format!("presets {spec} {name}: unavailable"));
                    continue;
                };
                let build = median(builds);
                let memory = memory_bytes(&scene, r.as_ref());
                progress.begin(format!("presets {spec} {name}: trace"));
                for (w, explicit) in [(primary, None), (incoherent, rays.as_ref())] {
                    let m = ctx.measure(r.as_ref(), &w, explicit)?;
                    // The tree's figures for the analysis with the kernel held fixed
                    // (`fixed_kernel.rs`), its leaf counts over these rays clipped at the
                    // hits this (exact) backend finds for them (untimed).
                    let traced = explicit.map_or(&camera, |b| &b.rays);
                    let hits = r.trace_rays(traced, false).map(|h| h.0).unwrap_or_default();
                    let quality = r
                        .quality(&QualityParams {
                            rays: segments(traced, &hits),
                            ..QualityParams::default()
                        })
                        .as_ref()
                        .map(Quality::from);
                    let series = format!("{spec} {}", w.rays.name());
                    let x = f64::from(ctx.size) * f64::from(ctx.size);
                    results.scaling.push(ScalingPoint {
                        hit_fraction: None,
                        build_seconds: Some(build),
                        memory_bytes: Some(memory),
                        quality,
                        ..m.point(r.as_ref(), NAME, series, name, x)
                    });
                }
                ran = true;
                progress.step(&format!("presets {spec} {name}: build {build:.4} s"));
            }
        }
        if !skipped.is_empty() {
            skipped.dedup();
            let status = if ran { "partial" } else { "skipped" };
            skip(
                results,
                "experiment",
                self.name(),
                status,
                skipped.join("; "),
            );
        }
        Ok(())
    }

    fn charts(&self, results: &Results) -> Vec<Chart> {
        let mut out = Vec::new();
        for scene in scenes_in(results) {
            for set in [RaySet::Primary, RaySet::Incoherent] {
                let series_name = format!("{scene} {}", set.name());
                let series: Vec<Series> = results
                    .scaling
                    .iter()
                    .filter(|p| p.experiment == self.name() && p.series == series_name)
                    .filter_map(|p| {
                        p.build_seconds.map(|b| Series {
                            label: p.backend.clone(),
                            points: vec![(b, p.seconds)],
                            fit: None,
                        })
                    })
                    .collect();
                if !series.is_empty() {
                    out.push(Chart {
                        title: format!(
                            "Build time against trace time, {} rays ({scene})",
                            set.name()
                        ),
                        stem: format!("presets-{}-{}", file_safe(&scene), set.name()),
                        x_label: "build time (s)".into(),
                        y_label: format!("trace time (s), {} rays", set.name()),
                        plot: Plot::Scatter(series),
                    });
                }
            }
            let series: Vec<Series> = by_backend(results, &scene)
                .into_values()
                .flatten()
                .map(|(name, build, trace, _)| Series {
                    label: name,
                    points: FRAMES.iter().map(|&k| (k, build + k * trace)).collect(),
                    fit: None,
                })
                .collect();
            if !series.is_empty() {
                out.push(Chart {
                    title: format!("Time to an image: build + k frames ({scene})"),
                    stem: format!("presets-{}-time-to-image", file_safe(&scene)),
                    x_label: "frames rendered (k)".into(),
                    y_label: "build + k frames (s)".into(),
                    plot: Plot::LogLog(series),
                });
            }
        }
        out.extend(super::fixed_kernel::charts(results));
        out
    }

    fn write(&self, results: &Results, s: &mut String) {
        let scenes = scenes_in(results);
        if scenes.is_empty() {
            return;
        }
        section(s, "Build presets: build time against trace time", INTRO);
        let _ = writeln!(
            s,
            "| scene | preset | build s | primary s | incoherent s | memory | tests/ray |"
        );
        let _ = writeln!(s, "|---|---|---:|---:|---:|---:|---:|");
        for scene in &scenes {
            let primary = format!("{scene} {}", RaySet::Primary.name());
            let incoherent = format!("{scene} {}", RaySet::Incoherent.name());
            for p in results
                .scaling
                .iter()
                .filter(|p| p.experiment == self.name() && p.series == primary)
            {
                let inc = results.scaling.iter().find(|q| {
                    q.experiment == p.experiment && q.series == incoherent && q.backend == p.backend
                });
                let _ = writeln!(
                    s,
                    "| {scene} | {} | {} | {:.4} | {} | {} | {} |",
                    p.backend,
                    opt(p.build_seconds, |v| format!("{v:.4}")),
                    p.seconds,
                    opt(inc.map(|q| q.seconds), |v| format!("{v:.4}")),
                    p.memory_bytes.map_or("-".into(), bytes),
                    opt(p.tests_per_ray, |v| format!("{v:.1}"))
                );
            }
        }
        let _ = writeln!(s);
        let _ = writeln!(
            s,
            "Fastest preset to an image after k frames (camera rays), per backend, and the \
             break-even frame count of its fastest-tracing preset:\n"
        );
        let _ = writeln!(
            s,
            "| scene | backend | k = 1 | k = 16 | k = 256 | fastest trace | break-even frames |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---:|");
        for scene in &scenes {
            for (backend, list) in by_backend(results, scene) {
                let at = |k: f64| fastest_at(&list, k).map_or("-".into(), |m| m.0.clone());
                let first = fastest_at(&list, 1.0);
                let best = list.iter().min_by(|a, b| a.2.total_cmp(&b.2));
                let even = match (first, best) {
                    (Some(f), Some(b)) if f.0 == b.0 => "none: it is also fastest to trace".into(),
                    (Some(f), Some(b)) if overlap(f.3, b.3) => {
                        "none: their trace times' intervals overlap (no trace is faster)".into()
                    }
                    (Some(f), Some(b)) => {
                        break_even((f.1, f.2), (b.1, b.2)).map_or("-".into(), |k| format!("{k:.1}"))
                    }
                    _ => "-".into(),
                };
                let _ = writeln!(
                    s,
                    "| {scene} | {backend} | {} | {} | {} | {} | {even} |",
                    at(FRAMES[0]),
                    at(FRAMES[1]),
                    at(FRAMES[2]),
                    best.map_or("-".into(), |m| m.0.clone()),
                );
            }
        }
        let _ = writeln!(s);
        super::fixed_kernel::write(results, s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overlapping_intervals_are_no_difference() {
        assert!(overlap(Some([1.0, 2.0]), Some([2.0, 3.0])));
        assert!(overlap(Some([1.0, 4.0]), Some([2.0, 3.0])));
        assert!(!overlap(Some([1.0, 1.9]), Some([2.0, 3.0])));
        assert!(!overlap(None, Some([2.0, 3.0])));
    }

    #[test]
    fn break_even_is_where_the_lines_cross() {
        // 10 ms build + 4 ms/frame against 50 ms + 2 ms/frame: equal after 20 frames.
        assert_eq!(break_even((0.010, 0.004), (0.050, 0.002)), Some(20.0));
        // A slower tracer never pays off.
        assert_eq!(break_even((0.010, 0.002), (0.050, 0.004)), None);
        // Faster in both: from the first frame.
        assert_eq!(break_even((0.050, 0.004), (0.010, 0.002)), Some(0.0));
    }

    #[test]
    fn the_fastest_preset_depends_on_the_frames() {
        let list = vec![
            ("a:fast".to_string(), 0.010, 0.004, None),
            ("a:quality".to_string(), 0.050, 0.002, None),
        ];
        assert_eq!(fastest_at(&list, 1.0).unwrap().0, "a:fast");
        assert_eq!(fastest_at(&list, 16.0).unwrap().0, "a:fast");
        assert_eq!(fastest_at(&list, 256.0).unwrap().0, "a:quality");
    }
}
