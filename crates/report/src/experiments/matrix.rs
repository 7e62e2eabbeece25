//! The main matrix: every chosen backend on every workload of every scene, timed and
//! compared with the reference backend of its scene; its throughput charts, summary, GPU
//! phases and per-scene tables.

use super::{Chart, Experiment, Planned, Plot};
use crate::charts::{Bar, Bars};
use crate::ctx::{Ctx, Measurement, PEER_MAX_FLIP, PEER_MIN_ID_MATCH, Views, Workload, skip};
use crate::fmt::file_safe;
use crate::fmt::{backends_in, bytes, label_in, noisy_mark, opt, repetitions, secs, section};
use crate::images::{self, Rgb8};
use crate::results::{
    CameraRun, Distribution, Equality, Images, Quality, RayCosts, Results, Run, Trace,
};
use anyhow::Result;
use raybench_core::integrator::HEADLIGHT_NOTE;
use raybench_core::ray_sets::DerivedParams;
use raybench_core::{Mode, NO_HIT, QualityParams, RaySet, Scene};
use raybench_registry::measure::{
    Measured, Prepared, RayBatch, counts_per_ray, explicit_rays, prepare, primary_rays,
};
use raybench_registry::progress::Progress;
use raybench_registry::{Backend, Roles, TimedRenderer, compare_hits};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::sync::Arc;

/// The start of the lines of `REPORT.md` that `REPORT.html` replaces with the image viewer
/// of one workload: followed by the workload's index in [`measured`] and ` -->`.
pub(crate) const VIEWER_BEGIN: &str = "<!-- raybench-viewer ";
/// The end of those lines.
pub(crate) const VIEWER_END: &str = "<!-- /raybench-viewer -->";

/// One workload of one scene in the results: the runs of every backend on it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct WorkloadKey {
    pub scene: String,
    pub mode: String,
    pub set: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
}

impl WorkloadKey {
    /// Its runs, the reference's first (in the order they were measured).
    pub fn runs<'r>(&self, results: &'r Results) -> Vec<&'r Run> {
        results.runs.iter().filter(|r| self.holds(r)).collect()
    }

    fn holds(&self, r: &Run) -> bool {
        r.scene == self.scene
            && r.mode == self.mode
            && r.ray_set == self.set
            && r.width == self.width
            && r.height == self.height
            && r.spp == self.spp
    }
}

/// The matrix's workloads in `results`, in order of first appearance (the order of the
/// report's per-scene tables).
pub(crate) fn measured(results: &Results) -> Vec<WorkloadKey> {
    let mut keys: Vec<WorkloadKey> = Vec::new();
    for r in &results.runs {
        if !keys.iter().any(|k| k.holds(r)) {
            keys.push(WorkloadKey {
                scene: r.scene.clone(),
                mode: r.mode.clone(),
                set: r.ray_set.clone(),
                width: r.width,
                height: r.height,
                spp: r.spp,
            });
        }
    }
    keys
}

/// The main matrix of scenes, workloads and backends.
pub(super) struct Matrix;

impl Experiment for Matrix {
    fn name(&self) -> &'static str {
        "matrix"
    }

    fn scaling(&self) -> bool {
        false
    }

    /// The scenes named by `--scenes`, else the built-in scenes of the chosen matrix; then
    /// the empty scene ([`super::empty_scene::UNIT`]) where camera rays are cast.
    fn units(&self, ctx: &Ctx) -> Vec<String> {
        let mut units: Vec<String> = match &ctx.opts.scenes {
            Some(s) => s.iter().map(|s| s.trim().to_string()).collect(),
            None => crate::ctx::matrix_scenes(ctx.opts.quick)
                .into_iter()
                .map(String::from)
                .collect(),
        };
        if super::empty_scene::wanted(ctx) {
            units.push(super::empty_scene::UNIT.into());
        }
        units
    }

    fn plan(&self, ctx: &Ctx, unit: &str, results: &mut Results) -> Result<Option<Planned>> {
        if unit == super::empty_scene::UNIT {
            return Ok(Some(Planned {
                steps: ctx.chosen.len(),
                scene: None,
            }));
        }
        Ok(match ctx.load(unit)? {
            Ok(scene) => Some(Planned {
                steps: workloads(ctx, &scene).0.len() * ctx.chosen.len(),
                scene: Some(scene),
            }),
            Err(reason) => {
                skip(results, "scene", unit, "skipped", reason);
                None
            }
        })
    }

    fn run(&self, ctx: &Ctx, unit: Planned, progress: &Progress, out: &mut Results) -> Result<()> {
        if let Some(scene) = &unit.scene {
            let (runs, empty) = run_scene(ctx, scene, progress)?;
            out.runs.extend(runs);
            for (workload, why) in empty {
                skip(
                    out,
                    "workload",
                    &format!("{} {workload}", scene.name),
                    "skipped",
                    why,
                );
            }
        } else {
            super::empty_scene::run(ctx, progress, out)?;
        }
        Ok(())
    }

    /// Throughput per scene, one chart per workload kind.
    fn charts(&self, results: &Results) -> Vec<Chart> {
        let mut out = Vec::new();
        let mut kinds: Vec<(String, String)> = Vec::new();
        for r in &results.runs {
            let k = (r.mode.clone(), r.ray_set.clone());
            if !kinds.contains(&k) {
                kinds.push(k);
            }
        }
        for (mode, set) in &kinds {
            let runs: Vec<&Run> = results
                .runs
                .iter()
                .filter(|r| &r.mode == mode && &r.ray_set == set)
                .collect();
            let mut scenes: Vec<String> = Vec::new();
            for r in &runs {
                if !scenes.contains(&r.scene) {
                    scenes.push(r.scene.clone());
                }
            }
            // Every backend with a run, a bar per scene: its throughput, or a marked stub
            // where it did not run (unsupported there, unavailable on this machine, or a
            // brute-force backend left out of a scene over its time budget, which has no
            // run).
            let series: Vec<Bars> = backends_in(&runs)
                .into_iter()
                .map(|b| {
                    let brute = raybench_registry::roles_of(&b)
                        .is_some_and(|r| r.contains(Roles::BRUTE_FORCE));
                    let values = scenes
                        .iter()
                        .map(
                            |s| match runs.iter().find(|r| &r.scene == s && r.backend == b) {
                                Some(r) if r.status != "ok" => Bar::Unsupported(format!(
                                    "{}: {}",
                                    r.status,
                                    r.reason.as_deref().unwrap_or("no reason given")
                                )),
                                Some(r) => throughput_bar(r),
                                None if brute => Bar::Unsupported(
                                    "left out: a brute-force backend over its time budget \
                                     on this scene"
                                        .into(),
                                ),
                                None => Bar::Absent,
                            },
                        )
                        .collect();
                    Bars {
                        label: label_in(&runs, &b),
                        values,
                    }
                })
                .collect();
            out.push(Chart {
                title: format!("Throughput, {mode} ({set} rays)"),
                stem: format!("throughput-{mode}-{set}"),
                x_label: "scene".into(),
                y_label: "rays per second (millions)".into(),
                plot: Plot::Categories(scenes, series),
            });
        }
        out.extend(super::quality::charts(results));
        out
    }

    /// The summary (ray casting, camera rays), the ratios to the yardstick peers, the GPU
    /// phases and the per-scene tables.
    fn write(&self, results: &Results, s: &mut String) {
        // Summary table: Mrays/s of every backend on every scene, camera rays, ray casting.
        let summary: Vec<&Run> = results
            .runs
            .iter()
            .filter(|r| r.mode == "cast" && r.ray_set == "primary")
            .collect();
        if !summary.is_empty() {
            let backends = backends_in(&summary);
            let mut scenes: Vec<&str> = Vec::new();
            for r in &summary {
                if !scenes.contains(&r.scene.as_str()) {
                    scenes.push(&r.scene);
                }
            }
            let _ = writeln!(s, "## Summary: ray casting, camera rays, Mrays/s\n");
            if summary.iter().any(|r| r.trace.is_some()) {
                let _ = writeln!(
                    s,
                    "Each cell: the camera rays traced as a batch made beforehand (the trace \
                     throughput) / the whole frame (ray generation, tracing, shading, the \
                     image); the verdict and the ratios below judge the first.\n"
                );
            }
            let labels: Vec<String> = backends.iter().map(|b| label_in(&summary, b)).collect();
            let _ = writeln!(
                s,
                "| scene | primitives | camera rays that hit | {} |",
                labels.join(" | ")
            );
            let _ = writeln!(s, "|---|---:|---:|{}", "---:|".repeat(backends.len()));
            for sc in &scenes {
                let prims = summary
                    .iter()
                    .find(|r| r.scene == *sc)
                    .map_or(0, |r| r.primitives);
                // The reference's answer (the first run of the scene), which the exact
                // backends share.
                let hits = summary
                    .iter()
                    .find(|r| r.scene == *sc)
                    .and_then(|r| r.hit_fraction)
                    .map_or_else(|| "-".into(), |f| format!("{:.1}%", f * 100.0));
                let cells: Vec<String> = backends
                    .iter()
                    .map(|b| {
                        summary
                            .iter()
                            .find(|r| r.scene == *sc && &r.backend == b)
                            .map_or("-".into(), |r| {
                                let fail = r.equality.as_ref().is_some_and(|e| !e.pass);
                                let noise = r.seconds.as_ref().map_or("", noisy_mark);
                                let differs = if fail { " (differs)" } else { "" };
                                match (r.mrays_per_s, &r.trace) {
                                    (Some(v), Some(t)) => format!(
                                        "{:.2}{} / {v:.2}{noise}{differs}",
                                        t.mrays_per_s,
                                        noisy_mark(&t.seconds)
                                    ),
                                    (Some(v), None) => format!("{v:.2}{noise}{differs}"),
                                    (None, _) => r.status.clone(),
                                }
                            })
                    })
                    .collect();
                let _ = writeln!(s, "| {sc} | {prims} | {hits} | {} |", cells.join(" | "));
            }
            let _ = writeln!(s);
            // Ratios to the yardstick peers (Embree's single rays and packets) where they ran
            // (read from the registry, built or not: a merge may hold runs of either); none
            // for a yardstick without a figure (unavailable everywhere: every ratio is `-`).
            for base_name in backends.iter().filter(|b| {
                raybench_registry::roles_of(b).is_some_and(|r| r.contains(Roles::YARDSTICK))
                    && summary
                        .iter()
                        .any(|r| &r.backend == *b && r.mrays_per_s.is_some())
            }) {
                let _ = writeln!(
                    s,
                    "Throughput relative to the yardstick peer `{base_name}` on the same rays, same \
                 run:\n"
                );
                let _ = writeln!(s, "| scene | {} |", labels.join(" | "));
                let _ = writeln!(s, "|---|{}", "---:|".repeat(backends.len()));
                for sc in &scenes {
                    // Trace against trace where both have one, else frame against frame.
                    let figure = |r: &Run, traced: bool| {
                        if traced {
                            r.trace.as_ref().map(|t| t.mrays_per_s)
                        } else {
                            r.mrays_per_s
                        }
                    };
                    let base_run = summary
                        .iter()
                        .find(|r| r.scene == *sc && &r.backend == base_name);
                    let cells: Vec<String> = backends
                        .iter()
                        .map(|b| {
                            let run = summary.iter().find(|r| r.scene == *sc && &r.backend == b);
                            let traced = run.is_some_and(|r| r.trace.is_some())
                                && base_run.is_some_and(|r| r.trace.is_some());
                            let base = base_run.and_then(|r| figure(r, traced));
                            let v = run.and_then(|r| figure(r, traced));
                            opt(v.zip(base).map(|(v, e)| v / e), |x| format!("{x:.2}"))
                        })
                        .collect();
                    let _ = writeln!(s, "| {sc} | {} |", cells.join(" | "));
                }
                let _ = writeln!(s);
            }
        }

        super::empty_scene::write(results, s);
        super::quality::write(results, s);

        // Phases of backends on another device (the GPU).
        let phased: Vec<&Run> = results
            .runs
            .iter()
            .filter(|r| !r.phases.is_empty())
            .collect();
        if !phased.is_empty() {
            section(
                s,
                "GPU phases",
                "Seconds per phase on the GPU backend (median of the timed repetitions): the \
             BVH built on the CPU and the scene uploaded once per scene; the warm-up call \
             (untimed: it compiles the kernels the timed calls use); then per frame the \
             parameters uploaded, the kernels' execution on the GPU (timestamp queries when \
             the adapter has them, else wall time around submit and wait), the image read \
             back, and the whole call. Mrays/s (wall) is over the whole call, as for every \
             backend, and ranks it in the verdict; Mrays/s (device) over the kernels' \
             execution ranks it with `--device-time`. A backend on a software adapter (a CPU \
             emulating a GPU) is marked so wherever its figures appear: they are no GPU's.",
            );
            let cols = [
                "prepare.build",
                "prepare.upload",
                "warm-up",
                "upload",
                "gpu",
                "readback",
                "render",
            ];
            let _ = writeln!(
                s,
                "| scene | workload | backend | {} | Mrays/s (wall) | Mrays/s (device) |",
                cols.join(" | ")
            );
            let _ = writeln!(s, "|---|---|---|{}---:|---:|", "---:|".repeat(cols.len()));
            for r in phased {
                let cells: Vec<String> = cols
                    .iter()
                    .map(|c| opt(r.phases.get(*c).copied(), |v| format!("{v:.4}")))
                    .collect();
                let device = r
                    .device_seconds
                    .as_ref()
                    .zip(r.rays)
                    .map(|(t, rays)| rays as f64 / t.median.max(1e-12) / 1e6);
                let _ = writeln!(
                    s,
                    "| {} | {} {} {}x{} spp {} | {} | {} | {} | {} |",
                    r.scene,
                    r.mode,
                    r.ray_set,
                    r.width,
                    r.height,
                    r.spp,
                    r.label(),
                    cells.join(" | "),
                    opt(r.mrays_per_s, |v| format!("{v:.2}")),
                    opt(device, |v| format!("{v:.2}"))
                );
            }
            let _ = writeln!(s);
        }

        // Per scene and workload.
        let _ = writeln!(s, "## Scenes\n");
        let mut last_scene = String::new();
        for (index, key) in measured(results).iter().enumerate() {
            let WorkloadKey {
                scene,
                mode,
                set,
                width: w,
                height: h,
                spp,
            } = key;
            let runs = key.runs(results);
            if *scene != last_scene {
                let prims = runs.first().map_or(0, |r| r.primitives);
                let _ = writeln!(s, "### {scene} ({prims} primitives)\n");
                last_scene.clone_from(scene);
            }
            let what = match set.as_str() {
                "primary" => format!("{w} x {h}, {spp} spp"),
                "incoherent" => format!("{} random rays", u64::from(*w) * u64::from(*h)),
                "file" => format!(
                    "{} rays replayed from the run's ray file (`--rays-file`)",
                    runs.iter().find_map(|r| r.rays).unwrap_or(0)
                ),
                _ => format!(
                    "{} {} rays from the primary hits of {w} x {h} pixels",
                    runs.iter().find_map(|r| r.rays).unwrap_or(0),
                    if RaySet::from_name(set).is_some_and(RaySet::any_hit) {
                        "any-hit"
                    } else {
                        "closest-hit"
                    }
                ),
            };
            let reference = runs.first().map_or("-", |r| r.reference.as_str());
            let lit = if runs.iter().any(|r| r.headlight) {
                format!("; lit by a headlight: `{scene}` {HEADLIGHT_NOTE}")
            } else {
                String::new()
            };
            let hits = runs
                .first()
                .and_then(|r| hits_note(r))
                .map_or_else(String::new, |h| format!("; {h}"));
            let _ = writeln!(
                s,
                "**{mode}, {set} rays** ({what}{hits}; reference `{reference}`{lit})\n"
            );
            let _ = writeln!(
                s,
                "| backend | build s | memory | render s [interval] | min s | repetitions | Mrays/s | tests/ray | visits/ray | id match | hit diff | ties | max abs dt | PSNR dB | FLIP | pass |"
            );
            let _ = writeln!(
                s,
                "|---|---:|---:|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"
            );
            for r in &runs {
                if r.status != "ok" {
                    let _ = writeln!(
                        s,
                        "| {} | {}: {} ||||||||||||||",
                        r.label(),
                        r.status,
                        r.reason.as_deref().unwrap_or("")
                    );
                    continue;
                }
                let e = r.equality.as_ref();
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                    r.label(),
                    opt(r.build_seconds, |v| format!("{v:.3}")),
                    r.memory_bytes.map_or("-".into(), bytes),
                    r.seconds.as_ref().map_or("-".into(), |t| format!(
                        "{} {}{}",
                        secs(t.median),
                        t.interval.map_or("[?]".into(), |[lo, hi]| format!(
                            "[{}-{}]",
                            secs(lo),
                            secs(hi)
                        )),
                        noisy_mark(t)
                    )),
                    r.seconds.as_ref().map_or("-".into(), |t| secs(t.min)),
                    r.seconds.as_ref().map_or("-".into(), repetitions),
                    opt(r.mrays_per_s, |v| format!("{v:.3}")),
                    opt(r.tests_per_ray, |v| format!("{v:.1}")),
                    opt(r.visits_per_ray, |v| format!("{v:.1}")),
                    e.map_or("-".into(), |e| format!("{:.4}%", e.id_match * 100.0)),
                    e.map_or("-".into(), |e| e.hit_mismatch.to_string()),
                    e.map_or("-".into(), |e| e.tie_mismatch.to_string()),
                    e.map_or("-".into(), |e| format!("{:.1e}", e.max_abs_dt)),
                    e.map_or("-".into(), |e| {
                        match (e.psnr_db, e.identical || e.flip_mean.is_some()) {
                            (Some(p), _) => format!("{p:.1}"),
                            (None, true) if e.flip_mean.is_some() => "inf".into(),
                            _ => "-".into(),
                        }
                    }),
                    e.and_then(|e| e.flip_mean)
                        .map_or("-".into(), |f| format!("{f:.4}")),
                    e.map_or("-", |e| if e.pass { "yes" } else { "**no**" }),
                );
            }
            let _ = writeln!(s);
            write_trace(&runs, s);
            write_ray_costs(&runs, s);
            write_cameras(&runs, s);
            let mut pictures = Vec::new();
            for r in &runs {
                if let Some(c) = &r.images.color {
                    pictures.push(format!("[{} image]({c})", r.backend));
                }
                if let Some(d) = &r.images.ids_diff {
                    pictures.push(format!("[{} id differences]({d})", r.backend));
                }
                if let Some(f) = &r.images.flip {
                    pictures.push(format!("[{} FLIP map]({f})", r.backend));
                }
                if let Some(v) = &r.images.visits {
                    pictures.push(format!("[{} visits heat map]({v})", r.backend));
                }
            }
            // REPORT.html replaces what lies between the markers with its image viewer.
            let reference_image = runs.first().and_then(|r| r.images.color.as_ref());
            if reference_image.is_some() {
                let _ = writeln!(s, "{VIEWER_BEGIN}{index} -->\n");
            }
            if let Some(reference_image) = reference_image {
                let _ = writeln!(
                    s,
                    "<img src=\"{reference_image}\" width=\"192\" alt=\"{scene} {mode}\">\n"
                );
            }
            if !pictures.is_empty() {
                let _ = writeln!(s, "Images: {}\n", pictures.join(", "));
            }
            if reference_image.is_some() {
                let _ = writeln!(s, "{VIEWER_END}\n");
            }
        }
    }
}

/// A run's throughput bar: Mrays/s over the median time, with the interval the median's
/// interval gives where it has one.
fn throughput_bar(r: &Run) -> Bar {
    let Some(v) = r.mrays_per_s else {
        return Bar::Absent;
    };
    match (r.seconds.as_ref().and_then(|t| t.interval), r.rays) {
        (Some([lo, hi]), Some(rays)) if lo > 0.0 => Bar::Interval {
            value: v,
            lo: rays as f64 / hi / 1e6,
            hi: rays as f64 / lo / 1e6,
        },
        _ => Bar::Value(v),
    }
}

/// The workloads of a scene: ray casting with every ray set of `--rays` (camera,
/// incoherent, shadow, ambient-occlusion and diffuse rays; `cast-shadow` and so on)
/// everywhere; Whitted and path tracing where the built-in scene's `[benchmark]` table asks
/// for them (lights to shadow and mirrors to follow; scenes built for path tracing), or on
/// every scene when `--modes` names them; the volume modes where there are volumes.
///
/// Also returns the modes asked for that do not run on this scene, with the reason (so the
/// report lists them under Skipped rather than claiming every workload ran).
fn workloads(ctx: &Ctx, scene: &Scene) -> (Vec<Workload>, Vec<NoRays>) {
    let s = ctx.size;
    let mut w = Vec::new();
    let cast = |rays| Workload {
        mode: Mode::Cast,
        rays,
        width: s,
        height: s,
        spp: 1,
        replay: false,
    };
    if ctx.modes.contains(&Mode::Cast) {
        // A ray file alone, unless sets are named too.
        let default: &[RaySet] = if ctx.replay.is_some() {
            &[]
        } else {
            &RaySet::ALL
        };
        let sets = ctx.opts.ray_sets.as_deref().unwrap_or(default);
        // In the order of `RaySet::ALL`, whatever the order asked.
        for set in RaySet::ALL.into_iter().filter(|s| sets.contains(s)) {
            w.push(cast(set));
        }
        if ctx.replay.is_some() {
            // Its own rays: `rays` only names the kind for the brute-force estimate.
            w.push(Workload {
                replay: true,
                ..cast(RaySet::Incoherent)
            });
        }
    }
    // Whitted and path tracing: named by --modes, on every scene; by default, where a
    // built-in scene's table asks for them (a scene file or generator has no such table).
    let named = ctx.opts.modes.is_some();
    let table = raybench_scene::builtin(&scene.name).map(|b| b.benchmark.modes);
    let mut not_run = Vec::new();
    let mut asks = |mode: Mode| {
        if !ctx.modes.contains(&mode) {
            return false;
        }
        match table {
            _ if named => true,
            Some(modes) => modes.contains(&mode.name()),
            None => {
                not_run.push((
                    mode.name().to_string(),
                    format!(
                        "a scene file or generator runs {} only when --modes names it",
                        mode.name()
                    ),
                ));
                false
            }
        }
    };
    let (whitted, path) = (asks(Mode::Whitted), asks(Mode::Path));
    if whitted {
        w.push(Workload {
            mode: Mode::Whitted,
            ..cast(RaySet::Primary)
        });
    }
    // The volume modes where there are volumes (their integration is the core's, the
    // same for every backend; the backend traces the surfaces that cut it).
    for mode in [Mode::Mip, Mode::Composite] {
        if !ctx.modes.contains(&mode) {
            continue;
        }
        if !scene.volumes.is_empty() {
            w.push(Workload {
                mode,
                ..cast(RaySet::Primary)
            });
        } else if named {
            not_run.push((
                mode.name().to_string(),
                format!("{} shows volumes, and the scene has none", mode.name()),
            ));
        }
    }
    if path {
        let (side, spp) = if ctx.opts.quick {
            (s / 2, 16)
        } else {
            (s / 2, 64)
        };
        w.push(Workload {
            mode: Mode::Path,
            rays: RaySet::Primary,
            width: side,
            height: side,
            spp,
            replay: false,
        });
    }
    (w, not_run)
}

/// Renders `scene` with every chosen backend on every workload, the reference first.
///
/// Also returns the workloads left out, with the reason ([`NoRays`]): modes asked for that
/// do not run on the scene, and workloads without rays (a derived set of a scene without
/// lights or whose camera sees nothing, an empty ray file).
fn run_scene(
    ctx: &Ctx,
    scene: &Arc<Scene>,
    progress: &Progress,
) -> Result<(Vec<Run>, Vec<NoRays>)> {
    let (mut workloads, modes_not_run) = workloads(ctx, scene);
    if scene.lights.is_empty() && workloads.iter().any(|w| w.mode == Mode::Whitted) {
        eprintln!("note: scene '{}' {HEADLIGHT_NOTE}", scene.name);
    }
    let prims = scene.geometry.total_len();
    // The reference: the oracle where it fits every workload's budget, else the
    // baseline. Brute-force backends run only within that budget.
    let naive_ok = workloads.iter().all(|w| ctx.naive_fits(w, prims));
    let mut order: Vec<&'static Backend> = ctx
        .chosen
        .iter()
        .copied()
        .filter(|b| !b.is(Roles::BRUTE_FORCE) || naive_ok)
        .collect();
    let left_out: Vec<&str> = ctx
        .chosen
        .iter()
        .filter(|b| b.is(Roles::BRUTE_FORCE) && !naive_ok)
        .map(|b| b.name)
        .collect();
    let reference_name = [Roles::ORACLE, Roles::BASELINE]
        .into_iter()
        .find_map(|role| order.iter().find(|b| b.is(role)))
        .or(order.first())
        .map_or("", |b| b.name);
    order.sort_by_key(|b| b.name != reference_name);
    for name in &left_out {
        eprintln!(
            "{}: {name} left out (over its time budget); {reference_name} is the reference",
            scene.name
        );
        progress.remove(workloads.len());
    }
    if order.is_empty() {
        return Ok((Vec::new(), modes_not_run));
    }

    let params = DerivedParams {
        ao_rays: ctx.opts.ao_rays,
        ..DerivedParams::default()
    };
    // Every camera of a scene that has several, for the workloads whose rays start at the
    // camera (the incoherent rays do not depend on it); the scene's camera otherwise.
    let views = |w: &Workload| -> Vec<Option<u32>> {
        if scene.cameras.len() > 1 && w.rays != RaySet::Incoherent && !w.replay {
            (0..scene.cameras.len() as u32).map(Some).collect()
        } else {
            vec![None]
        }
    };
    // The explicit rays of each workload and camera, generated once for every backend.
    let explicit: Vec<Box<Views>> = workloads
        .iter()
        .map(|w| {
            views(w)
                .into_iter()
                .map(|camera| {
                    let settings = raybench_core::RenderSettings {
                        camera,
                        ..w.settings()
                    };
                    let rays = match (&ctx.replay, w.replay) {
                        (Some(batch), true) => Some(batch.clone()),
                        _ => explicit_rays(w.rays, scene, &settings, &params)?,
                    };
                    Ok((camera, rays))
                })
                .collect::<Result<Box<Views>>>()
        })
        .collect::<Result<_>>()?;
    // A set derived from the primary hits can be empty (shadow rays without lights): there
    // is nothing to time.
    let no_rays = |views: &Views| {
        views
            .iter()
            .all(|(_, rays)| rays.as_ref().is_some_and(|b| b.rays.is_empty()))
    };
    let mut empty = modes_not_run;
    let kept: Vec<(Workload, Box<Views>)> = workloads
        .drain(..)
        .zip(explicit)
        .filter(|(w, views)| {
            if no_rays(views) {
                progress.remove(order.len());
                let file = w.replay.then_some(ctx.opts.rays_file.as_deref()).flatten();
                empty.push((
                    w.key(),
                    raybench_registry::measure::no_rays(w.rays, scene, file),
                ));
                false
            } else {
                true
            }
        })
        .collect();
    let (workloads, explicit): (Vec<Workload>, Vec<Box<Views>>) = kept.into_iter().unzip();
    // Every backend prepared first, so that each workload's repetitions can be taken in
    // rounds over all of them.
    let prepared: Vec<(&Backend, Result<Prepared, String>, Option<Quality>)> = order
        .iter()
        .map(|b| {
            progress.begin(format!("{} {}: build", scene.name, b.name));
            let p = prepare(b, scene);
            // Once per backend and scene: the EPO's samples are bounded (4096 points).
            let quality = p.as_ref().ok().and_then(|p| {
                p.renderer
                    .quality(&QualityParams::default())
                    .as_ref()
                    .map(Quality::from)
            });
            (*b, p, quality)
        })
        .collect();
    let coverage = raybench_scene::builtin(&scene.name)
        .is_some_and(|b| b.benchmark.purpose == raybench_scene::Purpose::Coverage);
    let mut runs = Vec::new();
    for (wi, w) in workloads.iter().enumerate() {
        let mut of_workload = Vec::with_capacity(prepared.len());
        let mut timed: Vec<(usize, &Prepared)> = Vec::new();
        for (b, p, _) in &prepared {
            let mut run = Run {
                shard: 0,
                scene: scene.name.clone(),
                primitives: prims as u64,
                mode: w.mode.name().into(),
                ray_set: w.ray_set().into(),
                width: w.width,
                height: w.height,
                spp: w.spp,
                backend: b.name.into(),
                exact: b.exact(),
                reference: reference_name.into(),
                status: "ok".into(),
                reason: None,
                build_seconds: None,
                memory_bytes: None,
                structure: BTreeMap::new(),
                seconds: None,
                device_seconds: None,
                device: None,
                software_device: false,
                headlight: w.mode == Mode::Whitted && scene.lights.is_empty(),
                coverage,
                rays: None,
                mrays_per_s: None,
                tests_per_ray: None,
                visits_per_ray: None,
                ray_costs: None,
                hit_fraction: None,
                facing_away: None,
                trace: None,
                equality: None,
                images: Images::default(),
                phases: BTreeMap::new(),
                cameras: Vec::new(),
                quality: None,
            };
            match p {
                Ok(p) => match p.renderer.supports_mode(w.mode) {
                    Ok(()) => timed.push((of_workload.len(), p)),
                    Err(reason) => not_run(&mut run, b, reason),
                },
                Err(reason) => not_run(&mut run, b, reason.clone()),
            }
            if let Some(reason) = &run.reason {
                progress.step(&format!("{} {} {}: {reason}", scene.name, w.key(), b.name));
            }
            of_workload.push(run);
        }
        progress.begin(format!(
            "{} {}: {} backends in rounds",
            scene.name,
            w.key(),
            timed.len()
        ));
        let renderers: Vec<&dyn TimedRenderer> =
            timed.iter().map(|(_, p)| p.renderer.as_ref()).collect();
        let measured = ctx.measure_all(&renderers, &w.settings(), &explicit[wi])?;
        // Ray casting's camera rays once more, made beforehand and traced as a batch: the
        // trace throughput, without the frame's ray generation, shading and image.
        let traced: Vec<Option<Measurement>> =
            if w.mode == Mode::Cast && w.rays == RaySet::Primary && !w.replay {
                progress.begin(format!(
                    "{} {}: the camera rays as a batch, {} backends in rounds",
                    scene.name,
                    w.key(),
                    renderers.len()
                ));
                let views = camera_batches(scene, &w.settings(), &explicit[wi])?;
                ctx.measure_all(&renderers, &w.settings(), &views)?
                    .into_iter()
                    .map(|(m, _)| Some(m))
                    .collect()
            } else {
                renderers.iter().map(|_| None).collect()
            };
        let mut reference: Option<Reference> = None;
        for (((i, p), (m, each)), trace) in timed.into_iter().zip(measured).zip(traced) {
            let (b, _, quality) = &prepared[i];
            let run = &mut of_workload[i];
            run.trace = trace.map(|t| Trace {
                rays: t.warm.rays,
                mrays_per_s: t.warm.rays as f64 / t.timing.median.max(1e-12) / 1e6,
                seconds: t.timing,
            });
            let r = &p.renderer;
            run.build_seconds = Some(p.build);
            run.quality.clone_from(quality);
            // Phases only for backends that have more than build and render (a GPU).
            if p.phases.0.len() > 1 || m.phases.0.len() > 1 {
                run.phases = p
                    .phases
                    .0
                    .iter()
                    .map(|(n, s)| (format!("prepare.{n}"), *s))
                    .chain(m.phases.0.iter().map(|(n, s)| (n.clone(), *s)))
                    .collect();
            }
            if let Some(s) = r.structure() {
                run.memory_bytes = Some(s.memory_bytes as u64);
                run.structure = s
                    .counts
                    .iter()
                    .map(|(k, v)| ((*k).to_string(), *v))
                    .collect();
            }
            let rays = m.warm.rays.max(1);
            run.rays = Some(m.warm.rays);
            run.hit_fraction = hit_fraction(&m.warm.ids);
            run.facing_away = explicit[wi]
                .iter()
                .filter_map(|(_, batch)| batch.as_ref())
                .map(|b| b.facing_away)
                .reduce(|a, b| a + b)
                .filter(|_| w.rays == RaySet::Shadow);
            run.mrays_per_s = Some(m.warm.rays as f64 / m.timing.median.max(1e-12) / 1e6);
            if let Some(c) = m.warm.counters.filter(|_| r.counts_tests()) {
                run.tests_per_ray = Some(c.prim_tests as f64 / rays as f64);
                run.visits_per_ray =
                    (c.node_visits > 0).then(|| c.node_visits as f64 / rays as f64);
            }
            // Each ray's own work, in an untimed pass after the timed ones.
            let stem = format!(
                "{}-{}-{}",
                file_safe(&scene.name),
                w.key(),
                file_safe(b.name)
            );
            if w.mode == Mode::Cast && run.visits_per_ray.is_some() && r.device().is_none() {
                progress.begin(format!(
                    "{} {} {}: each ray's own work",
                    scene.name,
                    w.key(),
                    b.name
                ));
                if let Some((costs, first)) = ray_costs(
                    scene,
                    &w.settings(),
                    &explicit[wi],
                    r.as_ref(),
                    m.warm.counters,
                )? {
                    run.ray_costs = Some(costs);
                    if w.rays == RaySet::Primary && !w.replay {
                        let name = format!("images/{stem}-visits.png");
                        images::visits_heat_map(w.width, w.height, &first)
                            .save(&ctx.opts.out.join(&name))?;
                        run.images.visits = Some(name);
                    }
                }
            }
            run.seconds = Some(m.timing);
            run.device_seconds = m.device;
            run.device = r.device();
            run.software_device = run.device.is_some()
                && raybench_registry::software_device().as_deref() == run.device.as_deref();
            // The images are the first camera's.
            let image = each[0]
                .warm
                .color
                .as_ref()
                .map(|c| Rgb8::from_linear(w.width, w.height, c));
            match &reference {
                None => {
                    if let Some(img) = &image {
                        let name = format!("images/{stem}.png");
                        img.save(&ctx.opts.out.join(&name))?;
                        run.images.color = Some(name);
                    }
                    run.equality = Some(Equality {
                        id_match: 1.0,
                        hit_mismatch: 0,
                        t_mismatch: 0,
                        tie_mismatch: 0,
                        max_abs_dt: 0.0,
                        identical: true,
                        psnr_db: None,
                        flip_mean: image.as_ref().map(|_| 0.0),
                        pass: true,
                    });
                    run.cameras = camera_runs(scene, &explicit[wi], &each, None);
                    reference = Some(Reference {
                        all: m.warm,
                        each: each.into_iter().map(|m| m.warm).collect(),
                        image,
                    });
                }
                Some(rf) => {
                    run.equality = Some(equality(
                        ctx,
                        b,
                        (&rf.all, &rf.each[0], rf.image.as_ref()),
                        (&m.warm, &each[0].warm, image.as_ref()),
                        w,
                        &stem,
                        &mut run.images,
                    )?);
                    run.cameras = camera_runs(scene, &explicit[wi], &each, Some(&rf.each));
                }
            }
            progress.step(&format!(
                "{} {} {}: {:.3} Mrays/s",
                scene.name,
                w.key(),
                b.name,
                run.mrays_per_s.unwrap_or(0.0)
            ));
        }
        runs.extend(of_workload);
    }
    Ok((runs, empty))
}

/// How a backend's measurement compares with the reference's, writing the images of a
/// difference.
///
/// `reference` and `measured` are each `(every camera, the first camera, its image)`: the
/// figures are over every camera, the images and maps the first camera's.
fn equality(
    ctx: &Ctx,
    b: &Backend,
    reference: (&Measured, &Measured, Option<&Rgb8>),
    measured: (&Measured, &Measured, Option<&Rgb8>),
    w: &Workload,
    stem: &str,
    files: &mut Images,
) -> Result<Equality> {
    let (ref_m, ref_first, ref_img) = reference;
    let (m, first, img) = measured;
    let c = compare_hits(&ref_m.ids, &ref_m.t, &m.ids, &m.t);
    let identical = c.is_exact() && same_colors(ref_m, m);
    let (mut psnr, mut flip) = (None, None);
    if let (Some(ri), Some(ti)) = (ref_img, img) {
        psnr = images::psnr(ri, ti);
        let (mean, map) = images::flip(ri, ti);
        flip = Some(mean);
        if !identical {
            let color = format!("images/{stem}.png");
            ti.save(&ctx.opts.out.join(&color))?;
            files.color = Some(color);
            let ids = format!("images/{stem}-ids-diff.png");
            images::ids_diff(w.width, w.height, &ref_first.ids, &first.ids, Some(ri))
                .save(&ctx.opts.out.join(&ids))?;
            files.ids_diff = Some(ids);
            let fl = format!("images/{stem}-flip.png");
            map.save(&ctx.opts.out.join(&fl))?;
            files.flip = Some(fl);
        }
    }
    // Outside the contract, a different primitive at the same distance is a tie
    // between coincident surfaces (each library breaks ties its own way), not an error.
    let n = m.ids.len().max(1) as f64;
    let pass = if b.exact() {
        identical
    } else {
        c.id_match + c.tie_mismatch as f64 / n >= PEER_MIN_ID_MATCH
            && flip.is_none_or(|f| f <= PEER_MAX_FLIP)
    };
    Ok(Equality {
        id_match: c.id_match,
        hit_mismatch: c.hit_mismatch,
        t_mismatch: c.t_mismatch,
        tie_mismatch: c.tie_mismatch,
        max_abs_dt: c.max_abs_dt,
        identical,
        psnr_db: psnr,
        flip_mean: flip,
        pass,
    })
}

/// Marks `run` as not run: `unsupported` where `b` is available but cannot run it,
/// `unavailable` where `b` cannot run on this machine.
fn not_run(run: &mut Run, b: &Backend, reason: String) {
    let available = (b.make)().availability().is_ok();
    run.status = if available {
        "unsupported"
    } else {
        "unavailable"
    }
    .into();
    run.reason = Some(reason);
}

/// A workload left out: its key (`cast-shadow`, or a mode) and why.
type NoRays = (String, String);

/// The reference backend's measurement of one workload: over every camera, each camera's,
/// and the first camera's image.
struct Reference {
    all: Measured,
    each: Vec<Measured>,
    image: Option<Rgb8>,
}

/// Whether two measurements' colours are bit-identical (true without colours).
fn same_colors(a: &Measured, b: &Measured) -> bool {
    match (&a.color, &b.color) {
        (Some(a), Some(b)) => {
            a.len() == b.len()
                && a.iter()
                    .zip(b)
                    .all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits))
        }
        _ => true,
    }
}

/// Each camera's figures for a scene with several cameras (empty for one view), compared
/// with the reference's same camera (`None`: this is the reference).
fn camera_runs(
    scene: &Scene,
    views: &Views,
    each: &[crate::ctx::Measurement],
    reference: Option<&[Measured]>,
) -> Vec<CameraRun> {
    if views.len() < 2 {
        return Vec::new();
    }
    views
        .iter()
        .zip(each)
        .enumerate()
        .map(|(i, ((camera, _), m))| CameraRun {
            name: camera
                .and_then(|c| scene.cameras.get(c as usize))
                .map_or_else(|| "camera".into(), |c| c.name.clone()),
            seconds: m.timing.clone(),
            rays: m.warm.rays,
            mrays_per_s: m.warm.rays as f64 / m.timing.median.max(1e-12) / 1e6,
            identical: reference.map(|rf| {
                compare_hits(&rf[i].ids, &rf[i].t, &m.warm.ids, &m.warm.t).is_exact()
                    && same_colors(&rf[i], &m.warm)
            }),
        })
        .collect()
}

/// For a scene with several cameras, each camera's throughput per backend (the table above
/// is over all of them).
fn write_cameras(runs: &[&Run], s: &mut String) {
    let Some(names) = runs
        .iter()
        .find(|r| !r.cameras.is_empty())
        .map(|r| r.cameras.iter().map(|c| c.name.clone()).collect::<Vec<_>>())
    else {
        return;
    };
    let _ = writeln!(
        s,
        "Each of the scene's {} cameras (the figures above are over all of them: the time \
         to render every camera once, and their rays over it), Mrays/s:\n",
        names.len()
    );
    let _ = writeln!(
        s,
        "| backend | {} | identical per camera |",
        names
            .iter()
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>()
            .join(" | ")
    );
    let _ = writeln!(s, "|---|{}---|", "---:|".repeat(names.len()));
    for r in runs.iter().filter(|r| !r.cameras.is_empty()) {
        let speeds: Vec<String> = r
            .cameras
            .iter()
            .map(|c| format!("{:.3}{}", c.mrays_per_s, noisy_mark(&c.seconds)))
            .collect();
        let identical = if r.cameras.iter().all(|c| c.identical.is_none()) {
            "reference".to_string()
        } else {
            r.cameras
                .iter()
                .map(|c| match c.identical {
                    Some(true) => "yes",
                    Some(false) => "no",
                    None => "-",
                })
                .collect::<Vec<_>>()
                .join(", ")
        };
        let _ = writeln!(
            s,
            "| {} | {} | {identical} |",
            r.backend,
            speeds.join(" | ")
        );
    }
    let _ = writeln!(s);
}

/// The camera rays traced as a batch beside their frame ([`Run::trace`]): the trace
/// throughput, and what the frame's pipeline (ray generation, shading, the image) adds per
/// camera ray. Nothing for workloads without it.
fn write_trace(runs: &[&Run], s: &mut String) {
    let traced: Vec<(&Run, &Trace)> = runs
        .iter()
        .filter_map(|r| Some((*r, r.trace.as_ref()?)))
        .collect();
    if traced.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "The same camera rays made beforehand and traced as a batch (closest hits; no ray \
         generation, shading or image): the **trace** throughput, which the verdict judges, \
         beside the whole frame's, and what the frame adds per camera ray.\n"
    );
    let _ = writeln!(
        s,
        "| backend | trace s [interval] | repetitions | trace Mrays/s | frame Mrays/s | frame adds, ns per camera ray |"
    );
    let _ = writeln!(s, "|---|---|---|---:|---:|---:|");
    for (r, t) in traced {
        let interval = t.seconds.interval.map_or("[?]".into(), |[lo, hi]| {
            format!("[{}-{}]", secs(lo), secs(hi))
        });
        let added = r.seconds.as_ref().map_or("-".into(), |frame| {
            let rays = t.rays.max(1) as f64;
            format!("{:.1}", (frame.median - t.seconds.median) / rays * 1e9)
        });
        let _ = writeln!(
            s,
            "| {} | {} {interval}{} | {} | {:.3} | {} | {added} |",
            r.label(),
            secs(t.seconds.median),
            noisy_mark(&t.seconds),
            repetitions(&t.seconds),
            t.mrays_per_s,
            opt(r.mrays_per_s, |v| format!("{v:.3}")),
        );
    }
    let _ = writeln!(s);
}

/// Each ray's own work on a ray-casting workload (every view's rays, each traced alone by
/// [`counts_per_ray`]) as percentiles, with the first view's node or cell visits per ray in
/// its order (for frames, pixels row by row: the heat map's). `None` where the renderer does
/// not count, or where the per-ray counts do not add up to `counted`, the counters of the
/// run's own counted pass (a packet traversal shares node visits between rays, so a ray
/// traced alone does other work than in its packet): the distribution is only ever the
/// run's own work split by ray.
///
/// # Errors
/// When the rays cannot be made or traced.
fn ray_costs(
    scene: &Scene,
    settings: &raybench_core::RenderSettings,
    views: &Views,
    r: &dyn TimedRenderer,
    counted: Option<raybench_core::RayCounters>,
) -> Result<Option<(RayCosts, Vec<u64>)>> {
    let Some(counted) = counted else {
        return Ok(None);
    };
    let mut all = Vec::new();
    let mut first = None;
    for (camera, batch) in views {
        let each = match batch {
            Some(batch) => counts_per_ray(r, &batch.rays, batch.any_hit)?,
            None => {
                // A frame's camera rays: the centre ray of each pixel, row by row.
                let settings = raybench_core::RenderSettings {
                    camera: *camera,
                    ..*settings
                };
                let view = scene.view(&settings)?;
                let rays = raybench_core::ray_sets::primary(view, settings.width, settings.height);
                counts_per_ray(r, &rays, false)?
            }
        };
        let Some(each) = each else {
            return Ok(None);
        };
        first.get_or_insert_with(|| each.iter().map(|c| c.node_visits).collect::<Vec<u64>>());
        all.extend(each);
    }
    let sum = |f: fn(&raybench_core::RayCounters) -> u64| all.iter().map(f).sum::<u64>();
    if sum(|c| c.prim_tests) != counted.prim_tests || sum(|c| c.node_visits) != counted.node_visits
    {
        return Ok(None);
    }
    let of = |f: fn(&raybench_core::RayCounters) -> u64| {
        Distribution::of(&all.iter().map(f).collect::<Vec<u64>>())
    };
    let (Some(tests), Some(visits)) = (of(|c| c.prim_tests), of(|c| c.node_visits)) else {
        return Ok(None);
    };
    let costs = RayCosts {
        rays: all.len() as u64,
        tests,
        visits,
    };
    Ok(Some((costs, first.unwrap_or_default())))
}

/// The table of each ray's own work ([`Run::ray_costs`]), for the runs that have it.
fn write_ray_costs(runs: &[&Run], s: &mut String) {
    let costs: Vec<(&Run, &RayCosts)> = runs
        .iter()
        .filter_map(|r| Some((*r, r.ray_costs.as_ref()?)))
        .collect();
    if costs.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "Each ray's own work, every ray traced alone in an untimed pass: the nearest-rank \
         percentiles of the primitive tests and of the node or cell visits per ray, over {} \
         rays (the means are the table's above).\n",
        costs[0].1.rays
    );
    let _ = writeln!(
        s,
        "| backend | tests p50 | tests p90 | tests p99 | tests max | visits p50 | visits p90 | visits p99 | visits max |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (r, c) in costs {
        let (t, v) = (&c.tests, &c.visits);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.label(),
            t.p50,
            t.p90,
            t.p99,
            t.max,
            v.p50,
            v.p90,
            v.p99,
            v.max
        );
    }
    let _ = writeln!(s);
}

/// Each view's camera rays (`primary_rays` of its camera, in the order the frame traces
/// them) as a closest-hit batch, for the trace throughput of ray casting's camera rays.
fn camera_batches(
    scene: &Arc<Scene>,
    settings: &raybench_core::RenderSettings,
    views: &Views,
) -> Result<Vec<(Option<u32>, Option<RayBatch>)>> {
    views
        .iter()
        .map(|(camera, _)| {
            let settings = raybench_core::RenderSettings {
                camera: *camera,
                ..*settings
            };
            Ok((
                *camera,
                Some(RayBatch {
                    rays: primary_rays(scene, &settings)?,
                    any_hit: false,
                    facing_away: 0,
                }),
            ))
        })
        .collect()
}

/// What share of a run's rays hit (the reference's answers, which every exact backend
/// shares): `62.5% of the camera rays hit`, `41.0% blocked, and 1,024 more blocked by their
/// own surface (the light behind it), not traced`; `None` when it was not recorded.
fn hits_note(r: &Run) -> Option<String> {
    let f = r.hit_fraction?;
    let any_hit = RaySet::from_name(&r.ray_set).is_some_and(RaySet::any_hit);
    let mut note = match r.ray_set.as_str() {
        "primary" => format!("{:.1}% of the camera rays hit", f * 100.0),
        _ if any_hit => format!("{:.1}% blocked", f * 100.0),
        _ => format!("{:.1}% hit", f * 100.0),
    };
    if let Some(n) = r.facing_away.filter(|&n| n > 0) {
        let _ = write!(
            note,
            ", and {} more blocked by their own surface (the light behind it), not traced",
            n
        );
    }
    Some(note)
}

/// The share of `ids` that are not [`NO_HIT`] (an any-hit set's [`OCCLUDED`] answers count
/// as hits: blocked); `None` for no rays.
///
/// [`OCCLUDED`]: raybench_registry::measure::OCCLUDED
fn hit_fraction(ids: &[u32]) -> Option<f64> {
    (!ids.is_empty())
        .then(|| ids.iter().filter(|&&id| id != NO_HIT).count() as f64 / ids.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ctx::Options;
    use crate::rounds::{Policy, Repeat};
    use raybench_core::{NO_HIT, Vec3};

    /// Options whose only use here is the output folder `out`.
    fn options(out: std::path::PathBuf) -> Options {
        Options {
            quick: true,
            scenes: None,
            backends: None,
            modes: None,
            out,
            shard: (1, 1),
            size: None,
            repeat: None,
            min_sample: None,
            scaling: false,
            experiments: None,
            ray_sets: None,
            ao_rays: 1,
            rays_file: None,
            assets: std::path::PathBuf::new(),
            threads: 1,
            command: String::new(),
            baseline: None,
            device_time: false,
            pin: false,
        }
    }

    /// A 2 x 2 frame: ids, `t` and colours.
    fn measured(ids: [u32; 4], t: [f32; 4], color: Option<[f32; 4]>) -> Measured {
        Measured {
            ids: ids.to_vec(),
            t: t.to_vec(),
            rays: 4,
            counters: None,
            seconds: 0.0,
            phases: raybench_core::Timings::default(),
            color: color.map(|c| c.iter().map(|&v| Vec3::splat(v)).collect()),
            interference: None,
        }
    }

    /// An exact backend (the baseline) and one outside the contract (a peer made up here).
    fn backends() -> (&'static Backend, Backend) {
        let exact = raybench_registry::with_role(Roles::BASELINE).unwrap();
        let peer = Backend {
            roles: Roles::PEER,
            ..*exact
        };
        (exact, peer)
    }

    /// `equality` of `m` against `reference` for backend `b`, a 2 x 2 camera workload, the
    /// images written to a fresh folder `name`: the figures and the files named.
    fn compare(b: &Backend, reference: &Measured, m: &Measured, name: &str) -> (Equality, Images) {
        let out = std::env::temp_dir().join(format!(
            "raybench-matrix-equality-{}-{name}",
            std::process::id()
        ));
        std::fs::create_dir_all(out.join("images")).unwrap();
        let opts = options(out.clone());
        let ctx = Ctx {
            opts: &opts,
            replay: None,
            chosen: &[],
            modes: &[],
            size: 2,
            repeat: 1,
            policy: Policy {
                repeat: Repeat::Fixed(1),
                min_sample: 0.0,
                budget: 0.0,
            },
            budget: 0.0,
        };
        let w = Workload {
            mode: Mode::Cast,
            rays: RaySet::Primary,
            width: 2,
            height: 2,
            spp: 1,
            replay: false,
        };
        let image = |m: &Measured| {
            m.color
                .as_ref()
                .map(|c| crate::images::Rgb8::from_linear(2, 2, c))
        };
        let (ri, ti) = (image(reference), image(m));
        let mut files = Images::default();
        let e = equality(
            &ctx,
            b,
            (reference, reference, ri.as_ref()),
            (m, m, ti.as_ref()),
            &w,
            "s",
            &mut files,
        )
        .unwrap();
        for f in [&files.color, &files.ids_diff, &files.flip]
            .into_iter()
            .flatten()
        {
            assert!(out.join(f).is_file(), "{f} named but not written");
        }
        let _ = std::fs::remove_dir_all(out);
        (e, files)
    }

    const IDS: [u32; 4] = [0, 1, NO_HIT, 2];
    const T: [f32; 4] = [1.0, 2.0, f32::INFINITY, 3.0];
    const GREY: [f32; 4] = [0.1, 0.2, 0.0, 0.3];

    #[test]
    fn same_colors_compares_every_bit_of_every_pixel() {
        let a = measured(IDS, T, Some(GREY));
        assert!(same_colors(&a, &a.clone()));
        // One channel of one pixel one bit away.
        let mut b = a.clone();
        let c = &mut b.color.as_mut().unwrap()[3];
        c.y = f32::from_bits(c.y.to_bits() + 1);
        assert!(!same_colors(&a, &b));
        // -0 and 0 compare equal as numbers, not as bits.
        let (zero, negative) = (
            measured(IDS, T, Some([0.0; 4])),
            measured(IDS, T, Some([0.0, 0.0, -0.0, 0.0])),
        );
        assert!(!same_colors(&zero, &negative));
        // A frame of another size differs.
        let mut short = a.clone();
        short.color.as_mut().unwrap().pop();
        assert!(!same_colors(&a, &short));
        // Without colours on either side (ray sets), there is nothing to differ.
        let rays = measured(IDS, T, None);
        assert!(same_colors(&rays, &rays) && same_colors(&a, &rays));
    }

    #[test]
    fn identical_results_pass_and_write_no_images() {
        let (exact, peer) = backends();
        let a = measured(IDS, T, Some(GREY));
        for b in [exact, &peer] {
            let (e, files) = compare(b, &a, &a.clone(), &format!("same-{}", b.exact()));
            assert!(e.identical && e.pass, "{e:?}");
            assert_eq!((e.id_match, e.psnr_db, e.flip_mean), (1.0, None, Some(0.0)));
            assert_eq!(files, Images::default());
        }
    }

    #[test]
    fn an_exact_backend_passes_only_bit_identical() {
        let (exact, _) = backends();
        let a = measured(IDS, T, Some(GREY));
        // The same ids and t, one colour off: not identical, so not passed, and the
        // difference's images are written.
        let mut colour = a.clone();
        colour.color.as_mut().unwrap()[0] = Vec3::splat(0.9);
        let (e, files) = compare(exact, &a, &colour, "colour");
        assert!(!e.identical && !e.pass, "{e:?}");
        assert!(e.psnr_db.is_some_and(f64::is_finite), "{e:?}");
        assert!(e.flip_mean.is_some_and(|f| f > 0.0), "{e:?}");
        assert_eq!(
            files,
            Images {
                color: Some("images/s.png".into()),
                ids_diff: Some("images/s-ids-diff.png".into()),
                flip: Some("images/s-flip.png".into()),
                visits: None,
            }
        );
        // One t a bit off, colours the same: not identical either.
        let mut t = a.clone();
        t.t[1] = f32::from_bits(t.t[1].to_bits() + 1);
        let (e, _) = compare(exact, &a, &t, "t");
        assert!(!e.identical && !e.pass && e.t_mismatch == 1, "{e:?}");
        // Without images (a ray set), ids and t alone decide.
        let rays = measured(IDS, T, None);
        let (e, files) = compare(exact, &rays, &rays.clone(), "rays");
        assert!(e.identical && e.pass && e.flip_mean.is_none(), "{e:?}");
        assert_eq!(files, Images::default());
    }

    /// A peer passes with at least 99.9 % of the ids (ties counted as matches) and a mean
    /// FLIP of at most 0.05; bit-identical or not does not matter.
    #[test]
    fn a_peer_passes_within_the_tolerance() {
        let (_, peer) = backends();
        // 1,000 rays without images: 999 the same is exactly the threshold, 998 is below;
        // a tie (another primitive at the same distance) counts as a match.
        let n = 1000;
        let rays = |ids: Vec<u32>, t: Vec<f32>| Measured {
            ids,
            t,
            rays: n as u64,
            ..measured(IDS, T, None)
        };
        let reference = rays((0..n).collect(), vec![1.0; n as usize]);
        let off_by = |k: u32, same_t: bool| {
            let mut ids: Vec<u32> = (0..n).collect();
            let mut t = vec![1.0; n as usize];
            for i in 0..k as usize {
                ids[i] = n + i as u32;
                if !same_t {
                    t[i] = 2.0;
                }
            }
            compare(
                &peer,
                &reference,
                &rays(ids, t),
                &format!("peer-{k}-{same_t}"),
            )
            .0
        };
        let one = off_by(1, false);
        assert!(one.pass && !one.identical, "{one:?}");
        let two = off_by(2, false);
        assert!(!two.pass, "{two:?}");
        let ties = off_by(5, true);
        assert_eq!(ties.tie_mismatch, 5);
        assert!(ties.pass, "{ties:?}");
        // On a frame: the ids all match, so the mean FLIP decides (an image half black,
        // half white against grey is far over 0.05; a colour one step off is under).
        let a = measured(IDS, T, Some([0.5; 4]));
        let mut far = a.clone();
        far.color = Some(vec![Vec3::ZERO, Vec3::ONE, Vec3::ZERO, Vec3::ONE]);
        let (e, _) = compare(&peer, &a, &far, "far");
        assert!(e.flip_mean.is_some_and(|f| f > 0.05) && !e.pass, "{e:?}");
        let mut near = a.clone();
        near.color = Some(vec![Vec3::splat(0.51); 4]);
        let (e, _) = compare(&peer, &a, &near, "near");
        assert!(e.flip_mean.is_some_and(|f| f <= 0.05), "{e:?}");
        assert!(e.pass && !e.identical, "{e:?}");
    }
}
