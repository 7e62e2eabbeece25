//! Experiment `instancing`: a scene with instances against the same scene flattened
//! (`raybench_scene::flatten_within_budget`: every instanced primitive carried to world
//! space and stored flat), with a few representative backends read from the registry's
//! roles (the baseline, the SIMD representative, the yardstick where it is built): primitives
//! stored, memory (primitives plus structure) in all and per primitive, build time, and the
//! throughput of camera rays at the report's image size. The quick run measures the small
//! built-in scene whose `[benchmark]` table names the experiment; the full run adds
//! [`LARGE`], tens of millions of triangles made from the shared meshes, flattened only
//! where the memory budget allows (skipped with the estimate otherwise).
//!
//! Its points are [`ScalingPoint`]s of series `SCENE instanced` and `SCENE flattened`, `x`
//! the flattened scene's primitive count (the same for both), `seconds` the median trace
//! time, with `build_seconds`, `memory_bytes` and `stored_primitives`; a form that could not
//! run is a skip record whose reason starts `SCENE flattened: `.

use super::{Chart, Experiment, Planned, Plot, planned, scene_for, skip};
use crate::charts::{Bar, Bars};
use crate::ctx::{Ctx, memory_bytes};
use crate::fmt::{bytes, section};
use crate::results::{Results, ScalingPoint};
use anyhow::Result;
use raybench_core::{Mode, Scene};
use raybench_registry::measure::prepare;
use raybench_registry::progress::Progress;
use raybench_registry::{Backend, Roles};
use std::fmt::Write as _;
use std::sync::Arc;

/// Experiment `instancing`.
pub(super) struct Instancing;

/// Its name.
const NAME: &str = "instancing";

/// The large instanced scene of the full run (`bench-scenes/bunny-field.toml`: 12.6
/// million triangles of the shared meshes, 142 thousand stored).
pub(super) const LARGE: &str = "bunny-field";

/// The two forms measured, in order.
const FORMS: [&str; 2] = ["instanced", "flattened"];

/// The roles whose first chosen backend runs it (pinned variants left out).
const ROLES: [Roles; 3] = [Roles::BASELINE, Roles::SIMD, Roles::YARDSTICK];

impl Instancing {
    /// The scenes it measures: the small one, then (full run) [`LARGE`].
    fn scenes(ctx: &Ctx) -> Result<Vec<String>, String> {
        let mut scenes = vec![scene_for(NAME)?.to_string()];
        if !ctx.opts.quick {
            scenes.push(LARGE.into());
        }
        Ok(scenes)
    }

    /// The backends it runs: of the chosen ones, the first with each of [`ROLES`].
    fn backends(ctx: &Ctx) -> Vec<&'static Backend> {
        let mut out: Vec<&'static Backend> = Vec::new();
        for role in ROLES {
            if let Some(b) = ctx
                .chosen
                .iter()
                .find(|b| b.is(role) && !b.is(Roles::PINNED))
                && !out.iter().any(|o| o.name == b.name)
            {
                out.push(b);
            }
        }
        out
    }

    /// Measures every backend on one form of a scene, adding a point each; returns why
    /// backends could not run.
    fn measure_form(
        ctx: &Ctx,
        scene: &Arc<Scene>,
        series: &str,
        x: f64,
        progress: &Progress,
        results: &mut Results,
    ) -> Result<Vec<String>> {
        let g = &scene.geometry;
        let stored = g.len() as u64 + g.meshes().iter().map(|m| m.len() as u64).sum::<u64>();
        let w = super::square(ctx.size, 1, Mode::Cast);
        let mut why = Vec::new();
        for b in Self::backends(ctx) {
            progress.begin(format!("{NAME} {series} {}: build", b.name));
            let p = match prepare(b, scene) {
                Ok(p) => p,
                Err(e) => {
                    why.push(format!("{series}, {}: {e}", b.name));
                    progress.step(&format!("{NAME} {series} {}: unavailable", b.name));
                    continue;
                }
            };
            let memory = memory_bytes(scene, p.renderer.as_ref());
            progress.begin(format!("{NAME} {series} {}: trace", b.name));
            let m = ctx.measure(p.renderer.as_ref(), &w, None)?;
            results.scaling.push(ScalingPoint {
                hit_fraction: None,
                build_seconds: Some(p.build),
                memory_bytes: Some(memory),
                stored_primitives: Some(stored),
                ..m.point(p.renderer.as_ref(), NAME, series.into(), b.name, x)
            });
            progress.step(&format!(
                "{NAME} {series} {}: build {:.3} s, trace {:.4} s",
                b.name, p.build, m.timing.median
            ));
        }
        Ok(why)
    }
}

/// The points of `scene`'s form `form`, in the order they ran.
fn points<'r>(results: &'r Results, scene: &str, form: &str) -> Vec<&'r ScalingPoint> {
    let series = format!("{scene} {form}");
    results
        .scaling
        .iter()
        .filter(|p| p.experiment == NAME && p.series == series)
        .collect()
}

/// The scenes in `results`, in the order they ran.
fn scenes_in(results: &Results) -> Vec<String> {
    let mut scenes: Vec<String> = Vec::new();
    for p in results.scaling.iter().filter(|p| p.experiment == NAME) {
        let scene = FORMS
            .iter()
            .find_map(|f| p.series.strip_suffix(&format!(" {f}")))
            .unwrap_or(&p.series);
        if !scenes.iter().any(|s| s == scene) {
            scenes.push(scene.to_string());
        }
    }
    scenes
}

/// Why `scene`'s form `form` did not run, from the skip records.
fn skipped_form(results: &Results, scene: &str, form: &str) -> Option<String> {
    let prefix = format!("{scene} {form}: ");
    results
        .skipped
        .iter()
        .filter(|k| k.kind == "experiment" && k.name == NAME)
        .find_map(|k| k.reason.strip_prefix(&prefix).map(str::to_string))
}

/// Millions of rays per second of a point.
fn mrays(p: &ScalingPoint) -> f64 {
    p.rays as f64 / p.seconds.max(1e-12) / 1e6
}

/// The first paragraph of its section of `REPORT.md`.
const INTRO: &str = "\
    Each scene as loaded, its instances placing meshes stored once under a two-level \
    structure (a tree over the instances, one structure per distinct mesh), against \
    the same scene flattened: every instanced primitive carried to world space and \
    stored flat under one structure. Both have the same primitives under the same \
    ids (flattening rounds differently, so a few hits may differ in their last \
    bits). Memory: primitives plus structure (Embree's own BVH is not counted); per \
    instanced primitive it is divided by the flattened count, per stored primitive \
    by the primitives actually stored. Build: one build, all threads; trace: camera \
    rays at the report's image size, ray casting, median of the run's repetitions. \
    The flattened form runs only where the memory budget allows it.";

impl Experiment for Instancing {
    fn name(&self) -> &'static str {
        NAME
    }

    fn plan(&self, ctx: &Ctx, unit: &str, results: &mut Results) -> Result<Option<Planned>> {
        let steps = Self::scenes(ctx).and_then(|scenes| match Self::backends(ctx).len() {
            0 => Err(
                "no chosen backend is the baseline, the SIMD representative or the yardstick"
                    .into(),
            ),
            backends => Ok(scenes.len() * FORMS.len() * backends),
        });
        Ok(planned(results, unit, steps))
    }

    fn run(&self, ctx: &Ctx, _: Planned, progress: &Progress, results: &mut Results) -> Result<()> {
        let n = Self::backends(ctx).len();
        let mut reasons: Vec<String> = Vec::new();
        let mut ran = false;
        for spec in Self::scenes(ctx).unwrap_or_default() {
            progress.begin(format!("{NAME}: load {spec}"));
            let scene = match ctx.load(&spec)? {
                Ok(s) => s,
                Err(why) => {
                    reasons.push(format!("{spec} {}: {why}", FORMS[0]));
                    reasons.push(format!("{spec} {}: {why}", FORMS[1]));
                    progress.remove(FORMS.len() * n);
                    continue;
                }
            };
            let x = scene.geometry.total_len() as f64;
            let series = format!("{spec} {}", FORMS[0]);
            let before = results.scaling.len();
            reasons.extend(Self::measure_form(
                ctx, &scene, &series, x, progress, results,
            )?);
            progress.begin(format!("{NAME}: flatten {spec}"));
            let flat = raybench_scene::flatten_within_budget(&scene);
            let estimate = raybench_scene::flattened_bytes_estimate(&scene);
            drop(scene);
            let series = format!("{spec} {}", FORMS[1]);
            match flat {
                Ok(flat) => {
                    let flat = Arc::new(flat);
                    reasons.extend(Self::measure_form(
                        ctx, &flat, &series, x, progress, results,
                    )?);
                }
                Err(e) => {
                    let why = if e.is_over_budget() {
                        format!(
                            "skipped: would need {} ({e})",
                            raybench_scene::human_bytes(estimate)
                        )
                    } else {
                        format!("skipped: {e}")
                    };
                    reasons.push(format!("{series}: {why}"));
                    progress.remove(n);
                }
            }
            ran |= results.scaling.len() > before;
        }
        for reason in reasons {
            let status = if ran { "partial" } else { "skipped" };
            skip(results, "experiment", NAME, status, reason);
        }
        Ok(())
    }

    /// One chart: camera-ray throughput of each backend, instanced and flattened, per scene;
    /// a form that did not run is a hatched stub with its reason.
    fn charts(&self, results: &Results) -> Vec<Chart> {
        let scenes = scenes_in(results);
        if scenes.is_empty() {
            return Vec::new();
        }
        let mut names = Vec::new();
        let mut cells = Vec::new();
        for scene in &scenes {
            for form in FORMS {
                names.push(format!("{scene} {form}"));
                cells.push((scene.as_str(), form));
            }
        }
        let mut backends: Vec<String> = Vec::new();
        for p in results.scaling.iter().filter(|p| p.experiment == NAME) {
            if !backends.contains(&p.backend) {
                backends.push(p.backend.clone());
            }
        }
        let bars = backends
            .iter()
            .map(|b| Bars {
                label: b.clone(),
                values: cells
                    .iter()
                    .map(|&(scene, form)| {
                        match points(results, scene, form)
                            .into_iter()
                            .find(|p| &p.backend == b)
                        {
                            Some(p) => Bar::Value(mrays(p)),
                            None => skipped_form(results, scene, form)
                                .map_or(Bar::Absent, Bar::Unsupported),
                        }
                    })
                    .collect(),
            })
            .collect();
        vec![Chart {
            title: "Camera-ray throughput, instanced against flattened".into(),
            stem: "instancing-throughput".into(),
            x_label: String::new(),
            y_label: "million rays per second".into(),
            plot: Plot::Categories(names, bars),
        }]
    }

    fn write(&self, results: &Results, s: &mut String) {
        let scenes = scenes_in(results);
        if scenes.is_empty() {
            return;
        }
        section(s, "Instancing: instanced against flattened", INTRO);
        let _ = writeln!(
            s,
            "| scene | form | backend | stored | instanced | memory | B/instanced prim | \
             B/stored prim | build s | trace s | Mrays/s |"
        );
        let _ = writeln!(s, "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|");
        let mut notes = Vec::new();
        for scene in &scenes {
            for form in FORMS {
                for p in points(results, scene, form) {
                    let per = |n: f64| {
                        p.memory_bytes
                            .map_or("-".into(), |m| format!("{:.1}", m as f64 / n.max(1.0)))
                    };
                    let stored = p.stored_primitives.unwrap_or(0);
                    let _ = writeln!(
                        s,
                        "| {scene} | {form} | {} | {stored} | {} | {} | {} | {} | {} | {:.4} | \
                         {:.2} |",
                        p.backend,
                        p.x,
                        p.memory_bytes.map_or("-".into(), bytes),
                        per(p.x),
                        per(stored as f64),
                        p.build_seconds.map_or("-".into(), |b| format!("{b:.3}")),
                        p.seconds,
                        mrays(p)
                    );
                }
                if let Some(why) = skipped_form(results, scene, form) {
                    notes.push(format!("- {scene}, {form}: {why}"));
                }
            }
        }
        let _ = writeln!(s);
        // Per backend and scene: what flattening costs and gains.
        let mut ratios = Vec::new();
        for scene in &scenes {
            for p in points(results, scene, FORMS[0]) {
                let Some(q) = points(results, scene, FORMS[1])
                    .into_iter()
                    .find(|q| q.backend == p.backend)
                else {
                    continue;
                };
                let memory = match (p.memory_bytes, q.memory_bytes) {
                    (Some(a), Some(b)) if a > 0 => {
                        format!("{:.1}x the memory", b as f64 / a as f64)
                    }
                    _ => "memory unknown".into(),
                };
                let build = match (p.build_seconds, q.build_seconds) {
                    (Some(a), Some(b)) if a > 0.0 => format!("{:.1}x the build time", b / a),
                    _ => "build time unknown".into(),
                };
                ratios.push(format!(
                    "- {scene}, {}: flattened takes {memory} and {build}, and traces at {:.2}x \
                     the instanced throughput.",
                    p.backend,
                    mrays(q) / mrays(p).max(1e-12)
                ));
            }
        }
        if !ratios.is_empty() {
            let _ = writeln!(s, "Flattened against instanced:\n");
            for r in ratios {
                let _ = writeln!(s, "{r}");
            }
            let _ = writeln!(s);
        }
        if !notes.is_empty() {
            let _ = writeln!(s, "Not measured:\n");
            for n in notes {
                let _ = writeln!(s, "{n}");
            }
            let _ = writeln!(s);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The large scene is a built-in scene with instances in the full matrix, and the small
    /// one names the experiment.
    #[test]
    fn its_scenes_exist() {
        let large = raybench_scene::builtin(LARGE).expect("the large scene is built in");
        assert_eq!(large.benchmark.matrix, raybench_scene::Matrix::Full);
        assert!(large.benchmark.heavy);
        assert!(scene_for(NAME).is_ok());
    }

    /// The write-up and the chart come from the results alone: a skipped flattened form is
    /// a stub with its reason, and the ratios are computed where both forms ran.
    #[test]
    fn it_writes_from_the_results() {
        let mut r = Results::default();
        let point =
            |series: &str, backend: &str, stored: u64, memory: u64, seconds: f64| ScalingPoint {
                hit_fraction: None,
                shard: 0,
                experiment: NAME.into(),
                series: series.into(),
                backend: backend.into(),
                x: 1000.0,
                seconds,
                timing: None,
                rays: 4096,
                tests_per_ray: None,
                load_seconds: None,
                build_seconds: Some(0.5),
                memory_bytes: Some(memory),
                difference: None,
                stored_primitives: Some(stored),
                visits_per_ray: None,
                quality: None,
            };
        r.scaling
            .push(point("small instanced", "b", 100, 10_000, 0.002));
        r.scaling
            .push(point("small flattened", "b", 1000, 60_000, 0.001));
        r.scaling
            .push(point("big instanced", "b", 100, 10_000, 0.004));
        skip(
            &mut r,
            "experiment",
            NAME,
            "partial",
            "big flattened: skipped: would need 9.0 GiB (over budget)".into(),
        );
        let mut s = String::new();
        Instancing.write(&r, &mut s);
        assert!(
            s.contains("| small | flattened | b | 1000 | 1000 | "),
            "{s}"
        );
        assert!(s.contains("| 60.0 | 60.0 |"), "bytes per primitive: {s}");
        assert!(
            s.contains("small, b: flattened takes 6.0x the memory and 1.0x the build time, and traces at 2.00x"),
            "{s}"
        );
        assert!(
            s.contains("- big, flattened: skipped: would need 9.0 GiB"),
            "{s}"
        );
        let charts = Instancing.charts(&r);
        assert_eq!(charts.len(), 1);
        let Plot::Categories(names, bars) = &charts[0].plot else {
            panic!("not a bar chart");
        };
        assert_eq!(names.len(), 4);
        assert_eq!(
            bars[0].values[3],
            Bar::Unsupported("skipped: would need 9.0 GiB (over budget)".into())
        );
    }
}
