//! `raybench report`: renders a matrix of scenes, workloads and backends, times them, checks
//! that the images agree, runs the scaling experiments, and writes `REPORT.md`, charts,
//! images and `results.json` into one folder. `raybench merge` joins the results of
//! shards (parts of the matrix run on several machines or at several times).

pub mod charts;
pub mod images;
pub mod machine;
mod markdown;
pub mod results;

use crate::measure::{Measured, explicit_rays, measure, prepare};
use crate::progress::Progress;
use crate::{BACKENDS, Backend, backend, compare_hits};
use anyhow::{Context, Result, bail};
use images::Rgb8;
use raybench_core::{Mode, NO_HIT, RaySet, RenderSettings, Renderer, Scene};
use results::{
    Equality, ImageDifference, Images, Results, Run, ScalingPoint, Shard, Skipped, Timing,
};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// What to run and where to write it.
#[derive(Clone, Debug)]
pub struct Options {
    /// The small matrix (under 5 minutes on 2 cores).
    pub quick: bool,
    /// Scenes (default: the built-in list of the chosen size).
    pub scenes: Option<Vec<String>>,
    /// Backends (default: every backend but the variants).
    pub backends: Option<Vec<String>>,
    /// Modes (default: all; `mip` and `composite` run only on scenes with volumes).
    pub modes: Option<Vec<Mode>>,
    /// Output folder.
    pub out: PathBuf,
    /// This run's shard `(i, n)`, 1-based.
    pub shard: (u32, u32),
    /// Image side for the main matrix (default 256 quick, 512 full).
    pub size: Option<u32>,
    /// Timed repetitions after the warm-up (default 3 quick, 5 full).
    pub repeat: Option<u32>,
    /// Run the scaling experiments.
    pub scaling: bool,
    /// Which scaling experiments (default: all of [`EXPERIMENTS`]).
    pub experiments: Option<Vec<String>>,
    /// Assets folder.
    pub assets: PathBuf,
    /// Worker threads.
    pub threads: usize,
    /// The command line, for the record.
    pub command: String,
}

/// The built-in scenes of the quick matrix.
pub const QUICK_SCENES: &[&str] = &[
    "spheres",
    "whitted",
    "cornell-box",
    "bunny",
    "sponza",
    "heightfield",
    "phantom",
    "csg",
    "quadrics",
    "teapot-bezier",
    "sdf",
];
/// The built-in scenes of the full matrix.
pub const FULL_SCENES: &[&str] = &[
    "spheres",
    "whitted",
    "cornell-box",
    "bunny-lowres",
    "bunny",
    "sponza",
    "suzanne",
    "teapot",
    "teapot-stadium",
    "heightfield",
    "phantom",
    "csg",
    "quadrics",
    "teapot-bezier",
    "sdf",
];

/// Naive's estimated ray/primitive tests per workload above which it is left out (it is
/// then not the reference: `bvh` is, itself checked against naive by the tests).
const NAIVE_BUDGET_QUICK: f64 = 2.0e9;
const NAIVE_BUDGET_FULL: f64 = 2.0e10;

/// The tolerance a backend outside the equivalence contract must meet: at least this
/// fraction of identical ids ...
pub const PEER_MIN_ID_MATCH: f64 = 0.999;
/// ... and at most this mean FLIP error.
pub const PEER_MAX_FLIP: f64 = 0.05;

/// One render setting of a scene.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Workload {
    mode: Mode,
    rays: RaySet,
    width: u32,
    height: u32,
    spp: u32,
}

impl Workload {
    fn settings(&self) -> RenderSettings {
        RenderSettings {
            width: self.width,
            height: self.height,
            spp: self.spp,
            mode: self.mode,
            seed: 0,
            max_depth: 5,
            count: false,
        }
    }

    fn key(&self) -> String {
        format!("{}-{}", self.mode.name(), self.rays.name())
    }
}

/// A unit of the matrix; shards split the list of units.
#[derive(Clone, Debug, PartialEq)]
enum Unit {
    Scene(String),
    Scaling(&'static str),
}

/// A unit of this shard, ready to run: a loaded scene or an experiment.
enum Planned {
    Scene(Arc<Scene>),
    Scaling(&'static str),
}

/// The scaling experiments. `heightfield` is the direct height field against the same
/// terrain tessellated into triangles, both in the BVH, for growing grids; `bezier` is the
/// Bezier teapot intersected directly against its tessellations into `2 N^2` triangles per
/// patch, with their image difference from the direct rendering.
pub const EXPERIMENTS: [&str; 5] = ["primitives", "pixels", "spp", "heightfield", "bezier"];

/// The scene of the `bezier` experiment.
const BEZIER_SCENE: &str = "teapot-bezier";

/// The one backend of the `heightfield` and `bezier` experiments (the comparison:
/// the tessellated mesh in the BVH).
const HEIGHTFIELD_BACKEND: &str = "bvh";

/// Backends that run an experiment's points.
fn experiment_backends(experiment: &str, chosen: &[&'static Backend]) -> Vec<&'static Backend> {
    if matches!(experiment, "heightfield" | "bezier") {
        BACKENDS
            .iter()
            .filter(|b| b.name == HEIGHTFIELD_BACKEND)
            .collect()
    } else {
        chosen.to_vec()
    }
}

/// Runs the report and writes it; returns the results.
///
/// # Errors
/// Bad options, an unwritable output folder, or a scene that fails to load for another
/// reason than a missing asset (those are reported and skipped, except under `CI=true`).
pub fn run(opts: &Options) -> Result<Results> {
    let (shard, shards) = opts.shard;
    if shards == 0 || shard == 0 || shard > shards {
        bail!("--shard must be I/N with 1 <= I <= N (got {shard}/{shards})");
    }
    let size = opts.size.unwrap_or(if opts.quick { 256 } else { 512 });
    if !(16..=4096).contains(&size) {
        bail!("--size must be in 16..=4096");
    }
    let repeat = opts.repeat.unwrap_or(if opts.quick { 3 } else { 5 });
    if !(1..=100).contains(&repeat) {
        bail!("--repeat must be in 1..=100");
    }
    let chosen: Vec<&'static Backend> = match &opts.backends {
        Some(names) => names
            .iter()
            .map(|n| backend(n.trim()))
            .collect::<Result<_, _>>()
            .map_err(anyhow::Error::msg)?,
        None => BACKENDS.iter().filter(|b| !b.variant).collect(),
    };
    if chosen.is_empty() {
        bail!("no backend to run");
    }
    let modes = opts.modes.clone().unwrap_or_else(|| Mode::ALL.to_vec());
    let scene_names: Vec<String> = match &opts.scenes {
        Some(s) => s.iter().map(|s| s.trim().to_string()).collect(),
        None => (if opts.quick {
            QUICK_SCENES
        } else {
            FULL_SCENES
        })
        .iter()
        .map(|s| (*s).to_string())
        .collect(),
    };
    let mut units: Vec<Unit> = scene_names.into_iter().map(Unit::Scene).collect();
    if opts.scaling {
        for e in &EXPERIMENTS {
            if opts
                .experiments
                .as_ref()
                .is_none_or(|chosen| chosen.iter().any(|c| c == e))
            {
                units.push(Unit::Scaling(e));
            }
        }
        if let Some(unknown) = opts
            .experiments
            .iter()
            .flatten()
            .find(|c| !EXPERIMENTS.contains(&c.as_str()))
        {
            bail!(
                "unknown experiment '{unknown}' (known: {})",
                EXPERIMENTS.join(", ")
            );
        }
    }
    // Whole units per shard, so that every backend of a scene runs on the same machine.
    let mine: Vec<Unit> = units
        .into_iter()
        .enumerate()
        .filter(|(i, _)| (*i as u32 % shards) + 1 == shard)
        .map(|(_, u)| u)
        .collect();

    std::fs::create_dir_all(opts.out.join("images"))
        .with_context(|| format!("cannot create {}", opts.out.display()))?;
    std::fs::create_dir_all(opts.out.join("charts"))?;
    let started = machine::now_utc();
    let wall = Instant::now();
    let mut results = Results {
        schema: results::SCHEMA.into(),
        raybench_version: env!("CARGO_PKG_VERSION").into(),
        shards: vec![Shard {
            index: shard,
            count: shards,
            machine: machine::describe(opts.threads),
            started,
            wall_seconds: 0.0,
            command: opts.command.clone(),
            quick: opts.quick,
        }],
        ..Results::default()
    };

    let ctx = Ctx {
        opts,
        chosen: &chosen,
        modes: &modes,
        size,
        repeat,
        budget: if opts.quick {
            NAIVE_BUDGET_QUICK
        } else {
            NAIVE_BUDGET_FULL
        },
    };
    // Load the scenes first, so that the progress bar knows the whole matrix.
    let mut plan: Vec<(Planned, usize)> = Vec::new();
    for unit in mine {
        match unit {
            Unit::Scene(name) => match ctx.load(&name)? {
                Ok(scene) => {
                    let n = ctx.workloads(&scene).len() * chosen.len();
                    plan.push((Planned::Scene(scene), n));
                }
                Err(reason) => skip(&mut results, "scene", &name, "skipped", reason),
            },
            Unit::Scaling(e) => {
                let n = ctx.scaling_plan(e).len() * experiment_backends(e, &chosen).len();
                plan.push((Planned::Scaling(e), n));
            }
        }
    }
    let progress = Progress::new(plan.iter().map(|p| p.1).sum());
    for (unit, _) in plan {
        match unit {
            Planned::Scene(scene) => {
                results.runs.extend(ctx.run_scene(&scene, &progress)?);
            }
            Planned::Scaling(e) => {
                let (points, skipped) = ctx.run_scaling(e, &progress)?;
                if !skipped.is_empty() {
                    let status = if points.is_empty() {
                        "skipped"
                    } else {
                        "partial"
                    };
                    // Each reason once (the loader's error names the scene and the file;
                    // the tessellations of the Bezier teapot share one).
                    let mut reasons: Vec<&str> = Vec::new();
                    for (_, why) in &skipped {
                        if !reasons.contains(&why.as_str()) {
                            reasons.push(why);
                        }
                    }
                    let reason = reasons.join("; ");
                    skip(&mut results, "experiment", e, status, reason);
                }
                results.scaling.extend(points);
            }
        }
    }
    results.shards[0].wall_seconds = wall.elapsed().as_secs_f64();
    results.fit();
    write(&results, &opts.out)?;
    Ok(results)
}

/// Writes `results.json`, the charts and `REPORT.md` into `out`.
///
/// # Errors
/// When a file cannot be written.
pub fn write(results: &Results, out: &Path) -> Result<()> {
    std::fs::create_dir_all(out.join("charts"))?;
    let json = serde_json::to_string_pretty(results)?;
    // Every file through a temporary name: an interrupted run leaves the previous report's
    // files whole, never a truncated one.
    write_text(&out.join("results.json"), &(json + "\n"))?;
    let charts = markdown::charts(results, &out.join("charts"));
    write_text(&out.join("REPORT.md"), &markdown::report(results, &charts))?;
    eprintln!("report written to {}", out.join("REPORT.md").display());
    Ok(())
}

/// Writes `text` to `path` through [`raybench_render::write_atomically`].
fn write_text(path: &Path, text: &str) -> Result<()> {
    raybench_render::write_atomically(path, |tmp| {
        std::fs::write(tmp, text).with_context(|| format!("cannot write {}", path.display()))
    })
}

/// Joins the `results.json` of several report folders into one report in `out` (images are
/// copied; charts and `REPORT.md` are drawn anew).
///
/// # Errors
/// A folder without a readable `results.json`, two folders holding the same shard or the
/// same measurement, or an unwritable `out`.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<Results> {
    if dirs.is_empty() {
        bail!("merge needs at least one report folder");
    }
    let mut merged = Results {
        schema: results::SCHEMA.into(),
        raybench_version: env!("CARGO_PKG_VERSION").into(),
        ..Results::default()
    };
    // Every input first: a shard given twice (the same folder twice, a copy of it, or a
    // merged report with one of its parts) would double its rows.
    let mut inputs: Vec<(&PathBuf, Results)> = Vec::new();
    for dir in dirs {
        let r = Results::read(&dir.join("results.json"))?;
        for (first, earlier) in &inputs {
            if let Some(why) = earlier.overlap(&r) {
                bail!(
                    "{} and {} hold the same shard ({why}); give each shard once",
                    first.display(),
                    dir.display()
                );
            }
        }
        inputs.push((dir, r));
    }
    std::fs::create_dir_all(out.join("images"))
        .with_context(|| format!("cannot create {}", out.display()))?;
    for (dir, r) in inputs {
        for run in &r.runs {
            for name in [&run.images.color, &run.images.ids_diff, &run.images.flip]
                .into_iter()
                .flatten()
            {
                let (from, to) = (dir.join(name), out.join(name));
                if from != to {
                    std::fs::copy(&from, &to)
                        .with_context(|| format!("cannot copy {}", from.display()))?;
                }
            }
        }
        merged.absorb(r);
    }
    write(&merged, out)?;
    Ok(merged)
}

/// A scene spec that could not be loaded, and why.
type SkippedScene = (String, String);

/// A loaded scene, or why it is skipped.
type Loaded = Result<Arc<Scene>, String>;

/// The outcome of loading `spec`: the scene; why it is skipped (a missing asset); or, for
/// any other failure and for a missing asset under `CI=true` (where every asset is
/// installed), an error.
fn skip_missing_asset(
    spec: &str,
    loaded: Result<Scene, raybench_scene::LoadError>,
) -> Result<Loaded> {
    match loaded {
        Ok(s) => Ok(Ok(Arc::new(s))),
        Err(e) if e.is_missing_asset() && std::env::var("CI").as_deref() != Ok("true") => {
            Ok(Err(e.to_string()))
        }
        Err(e) => Err(anyhow::Error::new(e).context(format!("cannot load scene {spec}"))),
    }
}

/// Records a skipped scene or experiment in `results` and says so once on stderr.
fn skip(results: &mut Results, kind: &str, name: &str, status: &str, reason: String) {
    eprintln!("skipped {kind} {name}: {reason}");
    results.skipped.push(Skipped {
        shard: 0,
        kind: kind.into(),
        name: name.into(),
        status: status.into(),
        reason,
    });
}

struct Ctx<'a> {
    opts: &'a Options,
    chosen: &'a [&'static Backend],
    modes: &'a [Mode],
    size: u32,
    repeat: u32,
    budget: f64,
}

/// A backend's measurements of one workload.
struct Measurement {
    warm: Measured,
    timing: Timing,
    /// Medians of the timed repetitions' phases.
    phases: raybench_core::Timings,
}

impl Ctx<'_> {
    /// The scene `name`, or (inner `Err`) why it is skipped: a missing asset, except under
    /// `CI=true`, where that is an error too.
    fn load(&self, name: &str) -> Result<Loaded> {
        skip_missing_asset(name, raybench_scene::load(name, &self.opts.assets))
    }

    /// [`Self::load`], and `teapot-bezier:tessellate=N` (experiment `bezier`): the built-in
    /// scene with its patches tessellated into `N x N` quads each.
    fn load_scaling(&self, spec: &str) -> Result<Loaded> {
        let Some(n) = spec
            .strip_prefix(BEZIER_SCENE)
            .and_then(|r| r.strip_prefix(":tessellate="))
        else {
            return self.load(spec);
        };
        let source = raybench_scene::BUILTIN_SCENES
            .iter()
            .find(|s| s.name == BEZIER_SCENE)
            .map(|s| s.source)
            .unwrap_or_default()
            .replace(
                "kind = \"bezier\"",
                &format!("kind = \"bezier\"\ntessellate = {n}"),
            );
        skip_missing_asset(
            spec,
            raybench_scene::load_scene_str(&source, BEZIER_SCENE, None, &self.opts.assets),
        )
    }

    /// The workloads of a scene: ray casting (camera and incoherent rays) everywhere,
    /// Whitted where there are lights to shadow and mirrors to follow, path tracing on the
    /// scenes built for it.
    fn workloads(&self, scene: &Scene) -> Vec<Workload> {
        let s = self.size;
        let mut w = Vec::new();
        let cast = |rays| Workload {
            mode: Mode::Cast,
            rays,
            width: s,
            height: s,
            spp: 1,
        };
        if self.modes.contains(&Mode::Cast) {
            w.push(cast(RaySet::Primary));
            w.push(cast(RaySet::Incoherent));
        }
        let name = scene.name.as_str();
        if self.modes.contains(&Mode::Whitted)
            && [
                "spheres",
                "whitted",
                "cornell-box",
                "heightfield",
                "csg",
                "sdf",
                "quadrics",
            ]
            .contains(&name)
        {
            w.push(Workload {
                mode: Mode::Whitted,
                ..cast(RaySet::Primary)
            });
        }
        // The volume modes where there are volumes (their integration is the core's, the
        // same for every backend; the backend traces the surfaces that cut it).
        if !scene.volumes.is_empty() {
            for mode in [Mode::Mip, Mode::Composite] {
                if self.modes.contains(&mode) {
                    w.push(Workload {
                        mode,
                        ..cast(RaySet::Primary)
                    });
                }
            }
        }
        if self.modes.contains(&Mode::Path) && ["cornell-box", "whitted"].contains(&name) {
            let (side, spp) = if self.opts.quick {
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
            });
        }
        w
    }

    /// Whether naive stays within its budget on `w` over a scene of `prims` primitives.
    fn naive_fits(&self, w: &Workload, prims: usize) -> bool {
        crate::brute_force_tests(&w.settings(), w.rays, prims, self.repeat + 1) <= self.budget
    }

    /// Warm-up (counted, kept for the comparison) and timed repetitions.
    fn measure(
        &self,
        r: &dyn Renderer,
        w: &Workload,
        rays: Option<&[raybench_core::Ray]>,
    ) -> Result<Measurement> {
        let settings = w.settings();
        let warm = measure(r, &settings, rays, true)?;
        let mut samples = Vec::new();
        let mut phases = Vec::new();
        for _ in 0..self.repeat {
            let m = measure(r, &settings, rays, false)?;
            samples.push(m.seconds);
            phases.push(m.phases);
        }
        Ok(Measurement {
            warm,
            timing: Timing::of(samples),
            phases: crate::measure::median_phases(&phases),
        })
    }

    fn run_scene(&self, scene: &Arc<Scene>, progress: &Progress) -> Result<Vec<Run>> {
        let workloads = self.workloads(scene);
        let prims = scene.geometry.len();
        // The reference: naive where it fits every workload's budget, else bvh.
        let naive_ok = workloads.iter().all(|w| self.naive_fits(w, prims));
        let mut order: Vec<&'static Backend> = self
            .chosen
            .iter()
            .copied()
            .filter(|b| b.name != "naive" || naive_ok)
            .collect();
        let skipped_naive = self.chosen.iter().any(|b| b.name == "naive") && !naive_ok;
        let reference_name = if order.iter().any(|b| b.name == "naive") {
            "naive"
        } else if order.iter().any(|b| b.name == "bvh") {
            "bvh"
        } else {
            order[0].name
        };
        order.sort_by_key(|b| b.name != reference_name);
        if skipped_naive {
            eprintln!(
                "{}: naive left out (over its time budget); bvh is the reference",
                scene.name
            );
            progress.remove(workloads.len());
        }

        let explicit: Vec<Option<Vec<raybench_core::Ray>>> = workloads
            .iter()
            .map(|w| explicit_rays(w.rays, scene, &w.settings()))
            .collect::<Result<_>>()?;
        let mut reference: Vec<Option<(Measured, Option<Rgb8>)>> =
            workloads.iter().map(|_| None).collect();
        let mut runs = Vec::new();
        for b in order {
            progress.begin(format!("{} {}: build", scene.name, b.name));
            let prepared = prepare(b, scene);
            for (wi, w) in workloads.iter().enumerate() {
                let mut run = Run {
                    shard: 0,
                    scene: scene.name.clone(),
                    primitives: prims as u64,
                    mode: w.mode.name().into(),
                    ray_set: w.rays.name().into(),
                    width: w.width,
                    height: w.height,
                    spp: w.spp,
                    backend: b.name.into(),
                    exact: b.exact,
                    reference: reference_name.into(),
                    status: "ok".into(),
                    reason: None,
                    build_seconds: None,
                    memory_bytes: None,
                    structure: BTreeMap::new(),
                    seconds: None,
                    rays: None,
                    mrays_per_s: None,
                    tests_per_ray: None,
                    visits_per_ray: None,
                    equality: None,
                    images: Images::default(),
                    phases: BTreeMap::new(),
                };
                let checked = match &prepared {
                    Ok(p) => p.renderer.supports_mode(w.mode).map(|()| p),
                    Err(reason) => Err(reason.clone()),
                };
                let (r, build, prepare_phases) = match checked {
                    Ok(p) => (&p.renderer, p.build, &p.phases),
                    Err(reason) => {
                        let available = (b.make)().availability().is_ok();
                        run.status = if available {
                            "unsupported"
                        } else {
                            "unavailable"
                        }
                        .into();
                        progress.step(&format!("{} {} {}: {reason}", scene.name, w.key(), b.name));
                        run.reason = Some(reason);
                        runs.push(run);
                        continue;
                    }
                };
                progress.begin(format!("{} {} {}", scene.name, w.key(), b.name));
                let m = self.measure(r.as_ref(), w, explicit[wi].as_deref())?;
                run.build_seconds = Some(build);
                // Phases only for backends that have more than build and render (a GPU).
                if prepare_phases.0.len() > 1 || m.phases.0.len() > 1 {
                    run.phases = prepare_phases
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
                run.mrays_per_s = Some(m.warm.rays as f64 / m.timing.median.max(1e-12) / 1e6);
                if let Some(c) = m.warm.counters.filter(|_| r.counts_tests()) {
                    run.tests_per_ray = Some(c.prim_tests as f64 / rays as f64);
                    run.visits_per_ray =
                        (c.node_visits > 0).then(|| c.node_visits as f64 / rays as f64);
                }
                run.seconds = Some(m.timing);
                let image = m
                    .warm
                    .color
                    .as_ref()
                    .map(|c| Rgb8::from_linear(w.width, w.height, c));
                let stem = format!(
                    "{}-{}-{}",
                    file_safe(&scene.name),
                    w.key(),
                    file_safe(b.name)
                );
                match &reference[wi] {
                    None => {
                        if let Some(img) = &image {
                            let name = format!("images/{stem}.png");
                            img.save(&self.opts.out.join(&name))?;
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
                        reference[wi] = Some((m.warm, image));
                    }
                    Some((ref_m, ref_img)) => {
                        run.equality = Some(self.equality(
                            b,
                            ref_m,
                            ref_img.as_ref(),
                            &m.warm,
                            image.as_ref(),
                            w,
                            &stem,
                            &mut run.images,
                        )?);
                    }
                }
                progress.step(&format!(
                    "{} {} {}: {:.3} Mrays/s",
                    scene.name,
                    w.key(),
                    b.name,
                    run.mrays_per_s.unwrap_or(0.0)
                ));
                runs.push(run);
            }
        }
        Ok(runs)
    }

    #[allow(clippy::too_many_arguments)]
    fn equality(
        &self,
        b: &Backend,
        ref_m: &Measured,
        ref_img: Option<&Rgb8>,
        m: &Measured,
        img: Option<&Rgb8>,
        w: &Workload,
        stem: &str,
        files: &mut Images,
    ) -> Result<Equality> {
        let c = compare_hits(&ref_m.ids, &ref_m.t, &m.ids, &m.t);
        let same_color = match (&ref_m.color, &m.color) {
            (Some(a), Some(b)) => a
                .iter()
                .zip(b)
                .all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits)),
            _ => true,
        };
        let identical = c.is_exact() && same_color;
        let (mut psnr, mut flip) = (None, None);
        if let (Some(ri), Some(ti)) = (ref_img, img) {
            psnr = images::psnr(ri, ti);
            let (mean, map) = images::flip(ri, ti);
            flip = Some(mean);
            if !identical {
                let color = format!("images/{stem}.png");
                ti.save(&self.opts.out.join(&color))?;
                files.color = Some(color);
                let ids = format!("images/{stem}-ids-diff.png");
                images::ids_diff(w.width, w.height, &ref_m.ids, &m.ids, Some(ri))
                    .save(&self.opts.out.join(&ids))?;
                files.ids_diff = Some(ids);
                let fl = format!("images/{stem}-flip.png");
                map.save(&self.opts.out.join(&fl))?;
                files.flip = Some(fl);
            }
        }
        // Outside the contract, a different primitive at the same distance is a tie
        // between coincident surfaces (each library breaks ties its own way), not an error.
        let n = m.ids.len().max(1) as f64;
        let pass = if b.exact {
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

    /// The scenes and workloads of an experiment: `(series, x, scene spec, workload)`.
    fn scaling_plan(&self, experiment: &str) -> Vec<(String, f64, String, Workload)> {
        let small = |width: u32, spp: u32, mode: Mode| Workload {
            mode,
            rays: RaySet::Primary,
            width,
            height: width,
            spp,
        };
        let mut plan = Vec::new();
        match experiment {
            "primitives" => {
                for series in ["soup", "spheres"] {
                    for e in 1..=6 {
                        let m = 10u64.pow(e);
                        plan.push((
                            series.to_string(),
                            m as f64,
                            format!("{series}:{m}"),
                            small(64, 1, Mode::Cast),
                        ));
                    }
                }
            }
            "pixels" => {
                let sides: &[u32] = if self.opts.quick {
                    &[64, 128, 256, 512]
                } else {
                    &[64, 128, 256, 512, 1024]
                };
                for &n in sides {
                    plan.push((
                        "bunny".into(),
                        f64::from(n * n),
                        "bunny".into(),
                        small(n, 1, Mode::Cast),
                    ));
                }
            }
            "heightfield" => {
                let sides: &[u32] = if self.opts.quick {
                    &[256, 512, 1024]
                } else {
                    &[256, 512, 1024, 2048, 4096]
                };
                for &n in sides {
                    for (series, generator) in
                        [("direct", "heightfield"), ("tessellated", "terrain")]
                    {
                        plan.push((
                            series.into(),
                            f64::from(n) * f64::from(n),
                            format!("{generator}:{n}"),
                            small(256, 1, Mode::Cast),
                        ));
                    }
                }
            }
            "bezier" => {
                // The direct patches at x = their primitive count, then the tessellations
                // at x = their triangle count (spec `teapot-bezier` + `tessellate = N`).
                let w = small(256, 1, Mode::Cast);
                plan.push(("direct".into(), 32.0, BEZIER_SCENE.into(), w));
                let ns: &[u32] = if self.opts.quick {
                    &[1, 2, 4, 8, 16]
                } else {
                    &[1, 2, 4, 8, 16, 32]
                };
                for &n in ns {
                    plan.push((
                        "tessellated".into(),
                        f64::from(2 * n * n * 32),
                        format!("{BEZIER_SCENE}:tessellate={n}"),
                        w,
                    ));
                }
            }
            _ => {
                let ks: &[u32] = if self.opts.quick {
                    &[1, 2, 4, 8, 16]
                } else {
                    &[1, 2, 4, 8, 16, 32, 64]
                };
                for &k in ks {
                    plan.push((
                        "cornell-box".into(),
                        f64::from(k),
                        "cornell-box".into(),
                        small(64, k, Mode::Path),
                    ));
                }
            }
        }
        plan
    }

    /// The points of an experiment, and the scenes skipped (each once, with the reason).
    fn run_scaling(
        &self,
        experiment: &str,
        progress: &Progress,
    ) -> Result<(Vec<ScalingPoint>, Vec<SkippedScene>)> {
        let mut points = Vec::new();
        let mut skipped: Vec<SkippedScene> = Vec::new();
        let mut loaded: Option<(String, Arc<Scene>, f64)> = None;
        // Experiment `bezier`: the direct rendering the tessellations are compared with.
        let mut reference: Option<BezierReference> = None;
        let backends = experiment_backends(experiment, self.chosen);
        for (series, x, spec, w) in self.scaling_plan(experiment) {
            let (scene, load_seconds) = match &loaded {
                Some((s, scene, secs)) if *s == spec => (Arc::clone(scene), *secs),
                _ => {
                    // Free the previous scene first: the largest terrains take gigabytes.
                    loaded = None;
                    if skipped.iter().any(|(s, _)| *s == spec) {
                        progress.remove(backends.len());
                        continue;
                    }
                    let start = Instant::now();
                    progress.begin(format!("scaling {experiment}: load {spec}"));
                    match self.load_scaling(&spec)? {
                        Ok(scene) => {
                            let secs = start.elapsed().as_secs_f64();
                            loaded = Some((spec.clone(), Arc::clone(&scene), secs));
                            (scene, secs)
                        }
                        Err(reason) => {
                            skipped.push((spec, reason));
                            progress.remove(backends.len());
                            continue;
                        }
                    }
                }
            };
            let heightfield = experiment == "heightfield";
            let bezier = experiment == "bezier";
            for b in &backends {
                if b.name == "naive" && !self.naive_fits(&w, scene.geometry.len()) {
                    progress.remove(1);
                    continue;
                }
                progress.begin(format!("scaling {experiment} {spec} {}: build", b.name));
                let Ok(crate::measure::Prepared {
                    renderer: r, build, ..
                }) = prepare(b, &scene)
                else {
                    progress.step(&format!(
                        "scaling {experiment} {spec} {}: unavailable",
                        b.name
                    ));
                    continue;
                };
                if let Err(why) = r.supports_mode(w.mode) {
                    progress.step(&format!("scaling {experiment} {spec} {}: {why}", b.name));
                    continue;
                }
                progress.begin(format!("scaling {experiment} {spec} x={x} {}", b.name));
                let m = self.measure(r.as_ref(), &w, None)?;
                let rays = m.warm.rays.max(1);
                let difference = if bezier {
                    bezier_difference(&mut reference, &series, x, &w, &m.warm)
                } else {
                    None
                };
                points.push(ScalingPoint {
                    shard: 0,
                    experiment: experiment.into(),
                    series: series.clone(),
                    backend: b.name.into(),
                    x,
                    seconds: m.timing.median,
                    rays: m.warm.rays,
                    tests_per_ray: m
                        .warm
                        .counters
                        .filter(|_| r.counts_tests())
                        .map(|c| c.prim_tests as f64 / rays as f64),
                    load_seconds: heightfield.then_some(load_seconds),
                    build_seconds: heightfield.then_some(build),
                    memory_bytes: heightfield.then(|| {
                        (scene.geometry.memory_bytes()
                            + r.structure().map_or(0, |s| s.memory_bytes))
                            as u64
                    }),
                    difference,
                });
                progress.step(&format!(
                    "scaling {experiment} {spec} x={x} {}: {:.4} s",
                    b.name, m.timing.median
                ));
            }
        }
        Ok((points, skipped))
    }
}

/// Experiment `bezier`: keeps the direct rendering as the reference, and compares a
/// tessellated one with it (mean FLIP of the images; fractions of pixels whose patch differs,
/// hit or miss included, and of pixels both hit whose depth differs by more than 1%). The
/// tessellation of `x` triangles has `x / 32` triangles per patch, in patch order.
fn bezier_difference(
    reference: &mut Option<BezierReference>,
    series: &str,
    x: f64,
    w: &Workload,
    m: &Measured,
) -> Option<ImageDifference> {
    let image = |c: &[raybench_core::Vec3]| Rgb8::from_linear(w.width, w.height, c);
    let color = m.color.as_deref().unwrap_or_default();
    if series == "direct" {
        *reference = Some(BezierReference {
            ids: m.ids.clone(),
            t: m.t.clone(),
            image: image(color),
        });
        return None;
    }
    let r = reference.as_ref()?;
    let per_patch = (x / 32.0).round().max(1.0) as u32;
    let (mean_flip, _) = images::flip(&r.image, &image(color));
    let patch = |id: u32, per: u32| if id == NO_HIT { NO_HIT } else { id / per };
    let (mut patch_differs, mut depth_differs) = (0u64, 0u64);
    for i in 0..r.ids.len() {
        let (a, b) = (patch(r.ids[i], 1), patch(m.ids[i], per_patch));
        patch_differs += u64::from(a != b);
        depth_differs +=
            u64::from(a != NO_HIT && b != NO_HIT && (r.t[i] - m.t[i]).abs() > 0.01 * r.t[i]);
    }
    let n = r.ids.len().max(1) as f64;
    Some(ImageDifference {
        mean_flip,
        patch_mismatch: patch_differs as f64 / n,
        depth_mismatch: depth_differs as f64 / n,
    })
}

/// The direct rendering of experiment `bezier`: ids, depths and the image.
struct BezierReference {
    ids: Vec<u32>,
    t: Vec<f32>,
    image: Rgb8,
}

/// A name usable in a file name (generator specs contain `:`).
fn file_safe(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect()
}
