//! `raybench report`: renders a matrix of scenes, workloads and backends, times them, checks
//! that the images agree, runs the scaling experiments, and writes `REPORT.md`, charts,
//! images, `REPORT.html` (the same report as a page with an image viewer) and `results.json`
//! into one folder. `raybench merge` joins the results of
//! shards (parts of the matrix run on several machines or at several times).

pub mod baseline;
pub mod charts;
mod experiments;
mod html;
pub mod images;
pub mod machine;
mod markdown;
pub mod results;
mod verdict;

use crate::measure::{Measured, measure};
use crate::progress::Progress;
use crate::{BACKENDS, Backend, Roles, backend};
use anyhow::{Context, Result, bail};
use experiments::{Experiment, Planned};
use raybench_core::{Mode, RaySet, RenderSettings, Renderer, Scene};
use results::{Results, Shard, Skipped, Timing};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// What to run and where to write it.
#[derive(Clone, Debug)]
pub struct Options {
    /// The small matrix (under 5 minutes on 2 cores; without `backends`, the GPU backends are
    /// left out on a software adapter).
    pub quick: bool,
    /// Scenes (default: the built-in scenes of the chosen matrix, by their `[benchmark]`
    /// tables).
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
    /// Which scaling experiments (default: all of [`experiments()`]).
    pub experiments: Option<Vec<String>>,
    /// The ray sets of the ray-casting workloads (default: every set, [`RaySet::ALL`]).
    pub ray_sets: Option<Vec<RaySet>>,
    /// Ambient-occlusion rays per primary hit of the `ao` workloads.
    pub ao_rays: u32,
    /// A ray file (`docs/rays-format.md`) every scene of the matrix also traces, as the
    /// ray-casting workload `cast-file` (alone unless `ray_sets` names sets too).
    pub rays_file: Option<PathBuf>,
    /// Assets folder.
    pub assets: PathBuf,
    /// Worker threads.
    pub threads: usize,
    /// The command line, for the record.
    pub command: String,
    /// An earlier report (folder or `results.json`) to compare with ([`baseline`]).
    pub baseline: Option<PathBuf>,
}

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
    /// Traces the rays of the run's ray file ([`Options::rays_file`]) instead of `rays`.
    replay: bool,
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
            ..RenderSettings::default()
        }
    }

    fn key(&self) -> String {
        format!("{}-{}", self.mode.name(), self.ray_set())
    }

    /// The name of its rays in `results.json`: the ray set's, or `file` for a replay.
    fn ray_set(&self) -> &'static str {
        if self.replay {
            "file"
        } else {
            self.rays.name()
        }
    }
}

/// The names of the scaling experiments, in the order they run (`--experiments`).
#[must_use]
pub fn experiments() -> Vec<&'static str> {
    experiments::SCALING.iter().map(|e| e.name()).collect()
}

/// The built-in scenes of the quick matrix (`--quick`) or the full one, in listing order
/// (each scene's `[benchmark]` table says which).
#[must_use]
pub fn matrix_scenes(quick: bool) -> Vec<&'static str> {
    raybench_scene::matrix(quick).map(|b| b.name).collect()
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
    let mut chosen: Vec<&'static Backend> = match &opts.backends {
        Some(names) => names
            .iter()
            .map(|n| backend(n.trim()))
            .collect::<Result<_, _>>()
            .map_err(anyhow::Error::msg)?,
        None => BACKENDS.iter().filter(|b| !b.is(Roles::PINNED)).collect(),
    };
    // A quick run of every backend leaves the GPU backends out when their adapter is a
    // software one (lavapipe: about one CPU thread's speed, and every kind's kernels to
    // compile): on two cores they would take most of the run. Named, they run.
    let mut software = Vec::new();
    if opts.quick
        && opts.backends.is_none()
        && let Some(adapter) = crate::software_device()
    {
        chosen.retain(|b| {
            let device = b.is(Roles::DEVICE);
            if device {
                software.push((b.name, adapter.clone()));
            }
            !device
        });
    }
    if chosen.is_empty() {
        bail!("no backend to run");
    }
    if let Some(unknown) = opts
        .experiments
        .iter()
        .flatten()
        .find(|c| !experiments().contains(&c.as_str()))
        .filter(|_| opts.scaling)
    {
        bail!(
            "unknown experiment '{unknown}' (known: {})",
            experiments().join(", ")
        );
    }
    // Read the baseline first: a bad path should fail before the measuring, not after.
    let before = opts
        .baseline
        .as_deref()
        .map(|p| baseline::read(p).map(|r| (r, p.display().to_string())))
        .transpose()?;
    let max_ao = raybench_core::ray_sets::MAX_AO_RAYS;
    if !(1..=max_ao).contains(&opts.ao_rays) {
        bail!("--ao-rays {} must be in 1..={max_ao}", opts.ao_rays);
    }
    let modes = opts.modes.clone().unwrap_or_else(|| Mode::ALL.to_vec());
    // The ray file too, before any measuring.
    let replay = opts
        .rays_file
        .as_deref()
        .map(|p| crate::rays_file::read(p).map(crate::measure::RayBatch::from_file))
        .transpose()?;
    let ctx = Ctx {
        opts,
        replay,
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
    // The units of every experiment that runs: the matrix's scenes, then one per scaling
    // experiment. Whole units per shard, so that every backend of a scene runs on the same
    // machine.
    let units: Vec<(&dyn Experiment, String)> = experiments::ALL
        .iter()
        .filter(|e| {
            !e.scaling()
                || (opts.scaling
                    && opts
                        .experiments
                        .as_ref()
                        .is_none_or(|chosen| chosen.iter().any(|c| c == e.name())))
        })
        .flat_map(|e| e.units(&ctx).into_iter().map(move |u| (*e, u)))
        .collect();
    let mine: Vec<(&dyn Experiment, String)> = units
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

    for (name, adapter) in software {
        skip(
            &mut results,
            "backend",
            name,
            "skipped",
            format!(
                "a quick run leaves the GPU backends out on a software adapter ({adapter}); \
                 name them in --backends to include them"
            ),
        );
    }

    // Plan every unit first (loading the matrix's scenes), so that the progress bar knows
    // the whole run.
    let mut plan: Vec<(&dyn Experiment, Planned)> = Vec::new();
    for (e, unit) in mine {
        if let Some(p) = e.plan(&ctx, &unit, &mut results)? {
            plan.push((e, p));
        }
    }
    let progress = Progress::new(plan.iter().map(|(_, p)| p.steps).sum());
    for (e, p) in plan {
        e.run(&ctx, p, &progress, &mut results)?;
    }
    results.shards[0].wall_seconds = wall.elapsed().as_secs_f64();
    results.fit();
    let appendix = before.as_ref().map(|(before, name)| {
        baseline::markdown(
            &baseline::compare(before, &results),
            name,
            &opts.out.display().to_string(),
        )
    });
    if let Some(section) = &appendix {
        use std::io::Write as _;
        write!(std::io::stdout().lock(), "{section}")?;
    }
    write(&results, &opts.out, appendix.as_deref())?;
    Ok(results)
}

/// Writes `results.json`, the charts, `REPORT.md` and `REPORT.html` into `out`;
/// `appendix` (Markdown: the comparison with a baseline) ends both reports.
///
/// # Errors
/// When a file cannot be written.
pub fn write(results: &Results, out: &Path, appendix: Option<&str>) -> Result<()> {
    std::fs::create_dir_all(out.join("charts"))?;
    // Compact: a full report's results run to hundreds of kilobytes, read by tools (`jq`
    // formats them for people).
    let json = serde_json::to_string(results)?;
    // Every file through a temporary name: an interrupted run leaves the previous report's
    // files whole, never a truncated one.
    write_text(&out.join("results.json"), &(json + "\n"))?;
    let charts = markdown::charts(results, &out.join("charts"));
    let mut text = markdown::report(results, &charts);
    if let Some(appendix) = appendix {
        text = text + "\n" + appendix;
    }
    write_text(&out.join("REPORT.md"), &text)?;
    write_text(&out.join("REPORT.html"), &html::page(results, &text, out))?;
    eprintln!(
        "report written to {} and {}",
        out.join("REPORT.md").display(),
        out.join("REPORT.html").display()
    );
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
    write(&merged, out, None)?;
    Ok(merged)
}

/// The cameras a workload is measured from, each with its explicit rays (`None` for a
/// rendered frame): indices into the scene's cameras, `None` for the scene's camera.
type Views = [(Option<u32>, Option<crate::measure::RayBatch>)];

/// A loaded scene, or why it is skipped.
type Loaded = Result<Arc<Scene>, String>;

/// The outcome of loading `spec`: the scene; why it is skipped (a missing asset, or a scene
/// over the memory budget); or, for any other failure and for a missing asset under
/// `CI=true` (where every asset is installed), an error.
fn skip_missing_asset(
    spec: &str,
    loaded: Result<Scene, raybench_scene::LoadError>,
) -> Result<Loaded> {
    match loaded {
        Ok(s) => Ok(Ok(Arc::new(s))),
        Err(e) if e.is_missing_asset() && std::env::var("CI").as_deref() != Ok("true") => {
            Ok(Err(e.to_string()))
        }
        // A scene over this machine's memory budget (the largest scaling points) is skipped
        // with the reason, CI or not: the rest of the run still means something.
        Err(e) if e.is_over_budget() => Ok(Err(e.to_string())),
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

/// What every experiment of one run shares: the options and what was made of them.
struct Ctx<'a> {
    opts: &'a Options,
    /// The rays of [`Options::rays_file`], read once.
    replay: Option<crate::measure::RayBatch>,
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

    /// Whether a brute-force backend stays within its budget on `w` over a scene of `prims`
    /// primitives.
    fn naive_fits(&self, w: &Workload, prims: usize) -> bool {
        let tests = match (&self.replay, w.replay) {
            (Some(batch), true) => {
                batch.rays.len() as f64 * prims as f64 * f64::from(self.repeat + 1)
            }
            _ => crate::brute_force_tests(&w.settings(), w.rays, prims, self.repeat + 1),
        };
        tests <= self.budget
    }

    /// Warm-up (counted, kept for the comparison) and timed repetitions.
    fn measure(
        &self,
        r: &dyn Renderer,
        w: &Workload,
        rays: Option<&crate::measure::RayBatch>,
    ) -> Result<Measurement> {
        self.measure_settings(r, &w.settings(), rays)
    }

    /// [`Ctx::measure`] with explicit settings (a camera chosen).
    fn measure_settings(
        &self,
        r: &dyn Renderer,
        settings: &RenderSettings,
        rays: Option<&crate::measure::RayBatch>,
    ) -> Result<Measurement> {
        let warm = measure(r, settings, rays, true)?;
        let mut samples = Vec::new();
        let mut phases = Vec::new();
        for _ in 0..self.repeat {
            let m = measure(r, settings, rays, false)?;
            samples.push(m.seconds);
            phases.push(m.phases);
        }
        Ok(Measurement {
            warm,
            timing: Timing::of(samples),
            phases: crate::measure::median_phases(&phases),
        })
    }

    /// [`Ctx::measure`] from each of `views` (indices into the scene's cameras; `None`: the
    /// scene's camera), with the rays of each view: the measurement of every view, and
    /// their sum ([`Measurement::sum`]).
    fn measure_views(
        &self,
        r: &dyn Renderer,
        w: &Workload,
        views: &Views,
    ) -> Result<(Measurement, Vec<Measurement>)> {
        let each: Vec<Measurement> = views
            .iter()
            .map(|(camera, rays)| {
                let settings = RenderSettings {
                    camera: *camera,
                    ..w.settings()
                };
                self.measure_settings(r, &settings, rays.as_ref())
            })
            .collect::<Result<_>>()?;
        Ok((Measurement::sum(&each), each))
    }
}

impl Measurement {
    /// Several cameras' measurements of one workload as one: the warm-ups' ids, `t` and
    /// colours concatenated in camera order, their rays and counters summed; the `i`-th
    /// timed repetition is the sum of every camera's `i`-th (so its median is the time to
    /// render every camera once), and each phase's median is summed likewise.
    fn sum(each: &[Measurement]) -> Measurement {
        if let [one] = each {
            return Measurement {
                warm: one.warm.clone(),
                timing: one.timing.clone(),
                phases: one.phases.clone(),
            };
        }
        let mut warm = Measured {
            ids: Vec::new(),
            t: Vec::new(),
            rays: 0,
            counters: None,
            seconds: 0.0,
            phases: raybench_core::Timings::default(),
            color: None,
        };
        let mut phases = raybench_core::Timings::default();
        let reps = each
            .iter()
            .map(|m| m.timing.samples.len())
            .min()
            .unwrap_or(0);
        let mut samples = vec![0.0; reps];
        for m in each {
            warm.ids.extend_from_slice(&m.warm.ids);
            warm.t.extend_from_slice(&m.warm.t);
            warm.rays += m.warm.rays;
            warm.seconds += m.warm.seconds;
            if let Some(c) = &m.warm.counters {
                use raybench_core::Counters as _;
                warm.counters
                    .get_or_insert_with(raybench_core::RayCounters::default)
                    .merge(c);
            }
            if let Some(c) = &m.warm.color {
                warm.color.get_or_insert_with(Vec::new).extend_from_slice(c);
            }
            for (i, s) in samples.iter_mut().enumerate() {
                *s += m.timing.samples[i];
            }
            for (name, secs) in &m.phases.0 {
                match phases.0.iter_mut().find(|(n, _)| n == name) {
                    Some((_, total)) => *total += secs,
                    None => phases.push(name.clone(), *secs),
                }
            }
        }
        Measurement {
            warm,
            timing: Timing::of(samples),
            phases,
        }
    }
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
