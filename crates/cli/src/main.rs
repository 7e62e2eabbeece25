//! The `raybench` command. Stdout carries data (tables, JSON); progress, timings and
//! warnings go to stderr.

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};
use raybench::diff::{Metric, diff};
use raybench::measure::{
    Measured, Prepared, RayBatch, explicit_rays, measure, median, median_phases, prepare,
    prepare_for_mode, primary_rays, timed_seconds,
};
use raybench::progress::Progress;
use raybench::report::results::{GRID_COLUMNS, Quality, TREE_COLUMNS};
use raybench::{
    BACKENDS, NOT_BUILT, backend, brute_force_tests, chosen_backends, compare_hits, default_backend,
};
use raybench_core::limits::MAX_THREADS;
use raybench_core::ray_sets::{DEFAULT_AO_RAYS, DerivedParams};
use raybench_core::{
    CameraOverrides, LightSampling, Mode, QualityParams, RaySet, RenderSettings, Scene, Timings,
    UpdatePolicy, Vec3,
};
use raybench_scene::{BUILTIN_SCENES, assets_dir, generators::GENERATORS};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

/// `println!` that returns the write's `io::Result` instead of panicking, so that a reader
/// that closes the pipe early (`raybench compare-results A B --json | head`) ends the
/// command quietly ([`main`]) rather than with a panic.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)
    }};
}

/// `print!` likewise ([`outln`]).
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout().lock(), $($arg)*)
    }};
}

/// Renders scenes with interchangeable acceleration strategies and compares them.
#[derive(Parser)]
#[command(name = "raybench", version = raybench::VERSION, about, long_about = None)]
struct Cli {
    /// Folder holding the shared meshes (default: $RAYBENCH_ASSETS, else assets/ at the
    /// workspace root).
    #[arg(long, global = true, value_name = "DIR")]
    assets: Option<PathBuf>,
    /// Largest memory a scene may take, estimated from its declared sizes before loading
    /// (8G, 512M, or none; default: $RAYBENCH_MEMORY_LIMIT, else half the available
    /// memory).
    #[arg(long, global = true, value_name = "SIZE", value_parser = parse_memory_limit)]
    memory_limit: Option<MemoryLimit>,
    #[command(subcommand)]
    command: Command,
}

/// `--memory-limit`: bytes, or `None` for no limit.
#[derive(Clone, Copy)]
struct MemoryLimit(Option<u64>);

fn parse_memory_limit(s: &str) -> Result<MemoryLimit, String> {
    raybench_scene::parse_size(s).map(MemoryLimit)
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to an image (PNG, OpenEXR or PFM).
    Render(RenderCmd),
    /// Render a scene with several backends, time them and check that they agree.
    Compare(CompareCmd),
    /// List the built-in scenes and generators.
    Scenes,
    /// List the backends, their build presets (BACKEND:PRESET) and whether they are
    /// available here.
    Backends {
        /// One JSON array on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Show a scene's primitives and each backend's structure.
    Info(InfoCmd),
    /// Run the benchmark matrix and write a report (REPORT.md, charts, images,
    /// results.json).
    Report(ReportCmd),
    /// Join the results of report shards into one report.
    Merge(MergeCmd),
    /// Set a report's results beside an earlier one's: per workload the speed ratio and
    /// whether it exceeds the noise of both runs.
    CompareResults(CompareResultsCmd),
    /// Measure how far image B is from the reference A (PNG, EXR or PFM).
    Diff(DiffCmd),
    /// Ray files (docs/rays-format.md): write a ray set for other tools to replay.
    #[command(subcommand)]
    Rays(RaysCmd),
}

#[derive(Subcommand)]
enum RaysCmd {
    /// Write a ray set of a scene to a ray file (`--rays-file` replays it).
    Export(ExportCmd),
}

#[derive(Args)]
struct ExportCmd {
    /// Scene (as for render).
    scene: String,
    /// Ray set: primary (in the renderer's tile order), incoherent, shadow, ao or diffuse.
    #[arg(long, default_value = "primary", value_parser = parse_ray_set)]
    rays: RaySet,
    /// The ray file to write (replaced).
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
    /// Image width (primary rays; width x height incoherent rays).
    #[arg(long, default_value_t = 512)]
    width: u32,
    /// Image height.
    #[arg(long, default_value_t = 512)]
    height: u32,
    /// Seed of the derived sets' random numbers.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Ambient-occlusion rays per primary hit (--rays ao).
    #[arg(long, default_value_t = DEFAULT_AO_RAYS, value_name = "N")]
    ao_rays: u32,
    #[command(flatten)]
    camera: CameraArgs,
}

/// The rays a measurement traces: a ray set, or a ray file's rays.
#[derive(Args, Clone)]
struct RaysArgs {
    /// Ray set: `primary` renders frames; the others trace explicit rays: `incoherent`
    /// (width x height seeded random rays: origins in the scene's box, uniform directions),
    /// `shadow` (any hit: from each primary hit to each light and one sampled emitter
    /// point), `ao` (any hit: --ao-rays cosine rays per primary hit, a tenth of the scene's
    /// diagonal long), `diffuse` (one cosine bounce per primary hit).
    #[arg(long, default_value = "primary", value_parser = parse_ray_set)]
    rays: RaySet,
    /// Replay the rays of a ray file (`raybench rays export`, docs/rays-format.md) instead
    /// of a ray set: any hit or closest hit as the file's flag says.
    #[arg(long, value_name = "FILE", conflicts_with = "rays")]
    rays_file: Option<PathBuf>,
    /// Ambient-occlusion rays per primary hit (--rays ao).
    #[arg(long, default_value_t = DEFAULT_AO_RAYS, value_name = "N")]
    ao_rays: u32,
}

impl RaysArgs {
    /// The workload's name (`shadow`, or `file:NAME`) and its explicit rays (`None`:
    /// frames).
    fn batch(
        &self,
        scene: &Arc<Scene>,
        settings: &RenderSettings,
    ) -> Result<(String, Option<RayBatch>)> {
        if let Some(path) = &self.rays_file {
            let file = raybench::rays_file::read(path)?;
            let name = path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            );
            return Ok((format!("file:{name}"), Some(RayBatch::from_file(file))));
        }
        let params = DerivedParams {
            ao_rays: self.ao_rays,
            seed: settings.seed,
            ..DerivedParams::default()
        };
        let batch = explicit_rays(self.rays, scene, settings, &params)?;
        Ok((self.rays.name().to_owned(), batch))
    }

    /// Estimated tests of a brute-force backend ([`brute_force_tests`]; a file's rays as
    /// they are).
    fn work(
        &self,
        batch: Option<&RayBatch>,
        settings: &RenderSettings,
        prims: usize,
        frames: u32,
    ) -> f64 {
        match (&self.rays_file, batch) {
            (Some(_), Some(b)) => b.rays.len() as f64 * prims as f64 * f64::from(frames),
            _ => brute_force_tests(settings, self.rays, prims, frames),
        }
    }
}

#[derive(Args)]
struct DiffCmd {
    /// The reference image (.png, .exr or .pfm).
    a: PathBuf,
    /// The image compared with it.
    b: PathBuf,
    /// Write the error map (error.png) and the FLIP map (flip.png) into this folder.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    #[command(flatten)]
    exposure: Exposure,
    /// Exit with status 2 when the metric of --metric exceeds this value (errors exit
    /// with 1).
    #[arg(long, value_name = "X")]
    fail_above: Option<f64>,
    /// The metric --fail-above tests: flip, mae, max, mse or relmse.
    #[arg(long, default_value = "flip", value_parser = parse_metric)]
    metric: Metric,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
}

/// `--exposure EV` of `render` and `diff`.
#[derive(Args)]
struct Exposure {
    /// Exposure in stops: colour is scaled by 2^EV (render: what is written, in every
    /// format, 0 writing the radiance itself; diff: both images before PSNR and FLIP,
    /// which compare them as displayed).
    #[arg(
        long = "exposure",
        default_value_t = 0.0,
        value_name = "EV",
        allow_hyphen_values = true
    )]
    ev: f32,
}

impl Exposure {
    /// The exposure, checked to lie within [-64, 64] stops.
    fn checked(&self) -> Result<f32> {
        if !self.ev.is_finite() || self.ev.abs() > 64.0 {
            bail!("--exposure {} is outside [-64, 64] stops", self.ev);
        }
        Ok(self.ev)
    }
}

fn parse_metric(s: &str) -> Result<Metric, String> {
    Metric::from_name(s).ok_or_else(|| {
        let names: Vec<_> = Metric::ALL.iter().map(|(_, n)| *n).collect();
        format!("unknown metric '{s}' (known: {})", names.join(", "))
    })
}

#[derive(Args)]
struct ReportCmd {
    /// The small matrix: under 5 minutes on a 2-core machine (what the README's main
    /// command runs). Without --backends it leaves the GPU backends out when their adapter
    /// is a software one (lavapipe), saying so.
    #[arg(long)]
    quick: bool,
    /// Comma-separated scenes (default: the built-in list; see the README).
    #[arg(long, value_delimiter = ',')]
    scenes: Option<Vec<String>>,
    /// Comma-separated backends, or build presets as BACKEND:PRESET (default: every backend
    /// but the pinned variants).
    #[arg(long, value_delimiter = ',')]
    backends: Option<Vec<String>>,
    /// Comma-separated modes (cast, whitted, path, mip, composite; default: all).
    #[arg(long, value_delimiter = ',', value_parser = parse_mode)]
    modes: Option<Vec<Mode>>,
    /// Output folder (created; files in it are replaced).
    #[arg(long, default_value = "target/raybench-report", value_name = "DIR")]
    out: PathBuf,
    /// Run part I of N of the matrix (1-based), split by scene: `--shard 2/4`.
    #[arg(long, value_parser = parse_shard, default_value = "1/1", value_name = "I/N")]
    shard: (u32, u32),
    /// Image side of the main matrix (default 256 with --quick, else 512).
    #[arg(long)]
    size: Option<u32>,
    /// Timed repetitions after the warm-up (default 3 with --quick, else 5).
    #[arg(long)]
    repeat: Option<u32>,
    /// Leave out the scaling experiments.
    #[arg(long)]
    no_scaling: bool,
    /// Run only these scaling experiments (primitives, pixels, spp, heightfield, bezier,
    /// presets, instancing, motion).
    #[arg(long, value_delimiter = ',', value_name = "A,B")]
    experiments: Option<Vec<String>>,
    /// Worker threads (default: all cores; at most 1024).
    #[arg(long)]
    threads: Option<usize>,
    /// An earlier report (its folder or its results.json) to set this run beside: REPORT.md
    /// gains a "Before and after" section (as `compare-results` prints).
    #[arg(long, value_name = "DIR")]
    baseline: Option<PathBuf>,
    /// Comma-separated ray sets of the ray-casting workloads (primary, incoherent, shadow,
    /// ao, diffuse; default: all).
    #[arg(long, value_delimiter = ',', value_parser = parse_ray_set, value_name = "SET,...")]
    rays: Option<Vec<RaySet>>,
    /// Ambient-occlusion rays per primary hit of the `ao` workloads.
    #[arg(long, default_value_t = DEFAULT_AO_RAYS, value_name = "N")]
    ao_rays: u32,
    /// Replay a ray file (`raybench rays export`, docs/rays-format.md) on every scene as
    /// the workload `cast-file` (the only ray-casting workload unless --rays names sets).
    #[arg(long, value_name = "FILE")]
    rays_file: Option<PathBuf>,
}

fn parse_shard(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("'{s}' is not I/N with 1 <= I <= N (for example 2/4)");
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let (i, n): (u32, u32) = (
        i.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if i == 0 || n == 0 || i > n {
        return Err(bad());
    }
    Ok((i, n))
}

#[derive(Args)]
struct MergeCmd {
    /// Report folders (each with a results.json).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Output folder of the merged report.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

#[derive(Args)]
struct CompareResultsCmd {
    /// The earlier run: a report folder or its results.json.
    before: PathBuf,
    /// The newer run.
    after: PathBuf,
    /// Print the comparison as JSON instead of markdown.
    #[arg(long)]
    json: bool,
}

#[derive(Args, Clone)]
struct FrameArgs {
    /// Integrator.
    #[arg(long, default_value = "cast", value_parser = parse_mode)]
    mode: Mode,
    /// Image width in pixels.
    #[arg(long, default_value_t = 512)]
    width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 512)]
    height: u32,
    /// Samples per pixel.
    #[arg(long, default_value_t = 1)]
    spp: u32,
    /// Seed of the random numbers.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Maximum number of bounces (whitted, path).
    #[arg(long, default_value_t = 5)]
    max_depth: u32,
    /// How `path` mode reaches emitters: `mis` (next-event estimation and BSDF sampling
    /// combined) or `bsdf` (BSDF sampling only, to compare).
    #[arg(long, default_value = "mis", value_parser = parse_light_sampling)]
    light_sampling: LightSampling,
    /// Worker threads (default: all cores; at most 1024).
    #[arg(long)]
    threads: Option<usize>,
}

impl FrameArgs {
    fn settings(&self, count: bool) -> RenderSettings {
        RenderSettings {
            width: self.width,
            height: self.height,
            spp: self.spp,
            mode: self.mode,
            seed: self.seed,
            max_depth: self.max_depth,
            count,
            light_sampling: self.light_sampling,
            // --camera selects the scene's camera when loading (overrides apply to it).
            camera: None,
        }
    }
}

/// Which of the scene's cameras renders, and adjustments to it.
#[derive(Args, Clone, Default)]
struct CameraArgs {
    /// The scene's camera to render, by name or 0-based index (`raybench info` lists
    /// them; default: the first).
    #[arg(long, value_name = "NAME|INDEX")]
    camera: Option<String>,
    /// Replace the camera's position: `x,y,z`.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    look_from: Option<Vec3>,
    /// Replace the point the camera looks at: `x,y,z`.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    look_at: Option<Vec3>,
    /// Replace the camera's up direction: `x,y,z`.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    up: Option<Vec3>,
    /// Replace the vertical field of view, in degrees (as the scene format's `fov`).
    #[arg(long, value_name = "DEGREES")]
    fov: Option<f32>,
}

impl CameraArgs {
    /// Picks and adjusts the scene's camera.
    fn apply(&self, scene: &mut Scene) -> Result<()> {
        let overrides = CameraOverrides {
            position: self.look_from,
            look_at: self.look_at,
            up: self.up,
            vfov_degrees: self.fov,
        };
        scene
            .select_camera(self.camera.as_deref(), &overrides)
            .map_err(anyhow::Error::msg)
    }
}

/// `x,y,z` as three finite numbers.
fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let bad = || format!("'{s}' is not three numbers x,y,z (for example 0,1.5,-4)");
    let [x, y, z] = parts.as_slice() else {
        return Err(bad());
    };
    let v = Vec3::new(
        x.parse().map_err(|_| bad())?,
        y.parse().map_err(|_| bad())?,
        z.parse().map_err(|_| bad())?,
    );
    if !v.is_finite() {
        return Err(format!("'{s}' has a component that is not finite"));
    }
    Ok(v)
}

fn parse_light_sampling(s: &str) -> Result<LightSampling, String> {
    LightSampling::from_name(s)
        .ok_or_else(|| format!("unknown light sampling '{s}' (known: mis, bsdf)"))
}

fn parse_mode(s: &str) -> Result<Mode, String> {
    Mode::from_name(s).ok_or_else(|| {
        let names: Vec<_> = Mode::ALL.iter().map(|m| m.name()).collect();
        format!("unknown mode '{s}' (known: {})", names.join(", "))
    })
}

#[derive(Args)]
struct RenderCmd {
    /// Scene: a file (.toml, .obj, .gltf, .glb, .ply), a built-in name or a generator (soup:1000).
    scene: String,
    /// Backend, or a build preset as BACKEND:PRESET (default: the fastest available).
    #[arg(long)]
    backend: Option<String>,
    #[command(flatten)]
    frame: FrameArgs,
    #[command(flatten)]
    camera: CameraArgs,
    /// Output image (default: SCENE.png): `.png` is 8-bit sRGB clamped to [0, 1]; `.exr`
    /// (OpenEXR, 32-bit float) and `.pfm` hold the unclamped linear radiance.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    #[command(flatten)]
    exposure: Exposure,
    /// Flatten the scene's instances first: every instanced primitive carried to world
    /// space and stored flat, ids unchanged (to compare a two-level structure with one over
    /// the flattened scene; refused over the memory budget).
    #[arg(long)]
    flatten: bool,
    /// Also write a false-colour image of primitive ids.
    #[arg(long, value_name = "FILE.png")]
    ids: Option<PathBuf>,
    /// Renders frames 0..N-1 of a moving scene (instance `keys` and `motion`, object
    /// `deform`), each image named after --out (and --ids) with the frame number:
    /// moving.png becomes moving-0000.png, moving-0001.png, ... A scene that does not move
    /// refuses N > 1 (its frames would be the same image).
    #[arg(long, default_value_t = 1, value_name = "N")]
    frames: u32,
    /// How the structure follows the frames: `refit` (boxes recomputed bottom up, the
    /// tree's topology kept; a two-level form rebuilds its top level) or `rebuild`.
    /// Backends that cannot refit rebuild.
    #[arg(long, default_value = "refit", value_parser = parse_update)]
    update: UpdatePolicy,
}

fn parse_update(s: &str) -> Result<UpdatePolicy, String> {
    UpdatePolicy::from_name(s)
        .ok_or_else(|| format!("unknown update policy '{s}' (known: refit, rebuild)"))
}

#[derive(Args)]
struct CompareCmd {
    /// Scene (as for render).
    scene: String,
    /// Comma-separated backends or BACKEND:PRESET build presets, the first being the
    /// reference (default: every available backend, naive first when it finishes in
    /// reasonable time).
    #[arg(long, value_delimiter = ',')]
    backends: Option<Vec<String>>,
    #[command(flatten)]
    frame: FrameArgs,
    #[command(flatten)]
    camera: CameraArgs,
    #[command(flatten)]
    rays: RaysArgs,
    /// Timed repetitions after one warm-up; the median is reported.
    #[arg(long, default_value_t = 3)]
    repeat: u32,
    /// Print exactly one JSON array on stdout.
    #[arg(long)]
    json: bool,
    /// Flatten the scene's instances first: every instanced primitive carried to world
    /// space and stored flat, ids unchanged (to compare a two-level structure with one over
    /// the flattened scene; refused over the memory budget).
    #[arg(long)]
    flatten: bool,
}

fn parse_ray_set(s: &str) -> Result<RaySet, String> {
    RaySet::from_name(s).ok_or_else(|| {
        let names: Vec<_> = RaySet::ALL.iter().map(|r| r.name()).collect();
        format!("unknown ray set '{s}' (known: {})", names.join(", "))
    })
}

#[derive(Args)]
struct InfoCmd {
    /// Scene (as for render).
    scene: String,
    /// Comma-separated backends or BACKEND:PRESET build presets (default: all available).
    #[arg(long, value_delimiter = ',')]
    backends: Option<Vec<String>>,
    /// The probe's rays, whose work per ray is shown.
    #[command(flatten)]
    rays: RaysArgs,
    /// Width of the probe image (or width x height incoherent rays).
    #[arg(long, default_value_t = 128)]
    width: u32,
    /// Height of the probe image.
    #[arg(long, default_value_t = 128)]
    height: u32,
    /// Integrator of the probe (primary rays only).
    #[arg(long, default_value = "cast", value_parser = parse_mode)]
    mode: Mode,
    /// Samples per pixel of the probe.
    #[arg(long, default_value_t = 1)]
    spp: u32,
    /// Maximum bounces of the probe.
    #[arg(long, default_value_t = 5)]
    max_depth: u32,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Points sampled for each structure's EPO (end-point overlap).
    #[arg(long, default_value_t = raybench_core::quality::DEFAULT_EPO_SAMPLES)]
    epo_samples: u32,
    /// Flatten the scene's instances first: every instanced primitive carried to world
    /// space and stored flat, ids unchanged (to compare a two-level structure with one over
    /// the flattened scene; refused over the memory budget).
    #[arg(long)]
    flatten: bool,
    #[command(flatten)]
    camera: CameraArgs,
}

fn main() -> ExitCode {
    quiet_wayland_probe();
    let cli = Cli::parse();
    match run(cli) {
        Ok(code) => code,
        // The reader of standard output went away (`| head`): what it wanted was written.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Whether `e` comes from writing to a pipe whose reader has closed it.
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Gives the process a private, empty `XDG_RUNTIME_DIR` when it has none (or a relative
/// one): `raybench-runtime-UID` in the temporary folder, made once per user with mode 0700
/// and kept (so that nothing is left behind per run); not used if someone else owns it.
///
/// Mesa's Vulkan device-selection layer (`VK_LAYER_MESA_device_select`) asks Wayland for
/// the compositor's GPU whenever wgpu lists the adapters, and libwayland-client then prints
/// `error: XDG_RUNTIME_DIR is invalid or not set in the environment.`, twice per command,
/// on servers, in containers and over ssh, where the variable is unset. In an empty folder
/// the layer finds no compositor, as it would not have anyway, and nothing is printed; the
/// adapters and their order are unchanged. wgpu offers no switch for this: the layer reads
/// only the environment.
#[cfg(target_os = "linux")]
#[allow(unsafe_code)]
fn quiet_wayland_probe() {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt};
    let set = std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| Path::new(&d).is_absolute());
    if set {
        return;
    }
    // The process's user owns its /proc entry.
    let Ok(uid) = std::fs::metadata("/proc/self").map(|m| m.uid()) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("raybench-runtime-{uid}"));
    let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
    let private = std::fs::symlink_metadata(&dir)
        .is_ok_and(|m| m.is_dir() && m.uid() == uid && m.mode() & 0o777 == 0o700);
    if private {
        // SAFETY: this runs first in `main`, before any other thread exists, so no thread
        // can read the environment while it changes (the condition of `set_var`).
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
    }
}

/// Elsewhere there is no Wayland probe to quiet.
#[cfg(not(target_os = "linux"))]
fn quiet_wayland_probe() {}

fn run(cli: Cli) -> Result<ExitCode> {
    let assets = assets_dir(cli.assets.as_deref());
    if let Some(MemoryLimit(limit)) = cli.memory_limit {
        raybench_scene::set_memory_limit(limit);
    }
    match cli.command {
        Command::Render(cmd) => with_threads(cmd.frame.threads, || render(&cmd, &assets)),
        Command::Compare(cmd) => with_threads(cmd.frame.threads, || compare(&cmd, &assets)),
        Command::Scenes => scenes(&assets),
        Command::Backends { json } => backends(json),
        Command::Info(cmd) => with_threads(cmd.threads, || info(&cmd, &assets)),
        Command::Report(cmd) => with_threads(cmd.threads, || report(&cmd, &assets)),
        Command::Merge(cmd) => {
            raybench::report::merge(&cmd.dirs, &cmd.out)?;
            Ok(ExitCode::SUCCESS)
        }
        Command::CompareResults(cmd) => {
            use raybench::report::baseline;
            let before = baseline::read(&cmd.before)?;
            let after = baseline::read(&cmd.after)?;
            let c = baseline::compare(&before, &after);
            if cmd.json {
                outln!("{}", serde_json::to_string_pretty(&c)?)?;
            } else {
                out!(
                    "{}",
                    baseline::markdown(
                        &c,
                        &cmd.before.display().to_string(),
                        &cmd.after.display().to_string()
                    )
                )?;
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Diff(cmd) => diff_images(&cmd),
        Command::Rays(RaysCmd::Export(cmd)) => export_rays(&cmd, &assets),
    }
}

/// `raybench diff`: the measures on stdout, the maps on request, and status 2 when
/// `--fail-above` is exceeded (errors are 1).
fn diff_images(cmd: &DiffCmd) -> Result<ExitCode> {
    let exposure = cmd.exposure.checked()?;
    if let Some(x) = cmd.fail_above
        && !x.is_finite()
    {
        bail!("--fail-above {x} is not a finite number");
    }
    let maps = cmd
        .out
        .as_ref()
        .map(|d| (d.join("error.png"), d.join("flip.png")));
    if let Some((e, f)) = &maps {
        if let Some(dir) = &cmd.out {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create the folder {}", dir.display()))?;
        }
        raybench_render::check_png_path(e)?;
        raybench_render::check_png_path(f)?;
    }
    let a = raybench_render::read_linear(&cmd.a)?;
    let b = raybench_render::read_linear(&cmd.b)?;
    let (stats, error_map, flip_map) = diff(&a, &b, exposure)
        .map_err(|e| anyhow::anyhow!("{} and {}: {e}", cmd.a.display(), cmd.b.display()))?;
    if cmd.json {
        outln!("{}", serde_json::to_string(&stats)?)?;
    } else {
        outln!("size            {} x {}", stats.width, stats.height)?;
        outln!(
            "mean            {:.6} (A)  {:.6} (B)",
            stats.mean_a,
            stats.mean_b
        )?;
        outln!("mean abs error  {:.6}", stats.mean_abs_error)?;
        outln!("max abs error   {:.6}", stats.max_abs_error)?;
        outln!("MSE             {:.6e}", stats.mse)?;
        outln!("relative MSE    {:.6e}", stats.rel_mse)?;
        outln!(
            "PSNR            {}",
            stats
                .psnr
                .map_or("inf (identical as displayed)".into(), |p| format!(
                    "{p:.2} dB"
                ))
        )?;
        outln!("mean FLIP       {:.6}", stats.flip)?;
    }
    if let Some((e, f)) = &maps {
        error_map.save(e)?;
        flip_map.save(f)?;
        eprintln!("wrote {} and {}", e.display(), f.display());
    }
    if let Some(limit) = cmd.fail_above {
        let value = cmd.metric.of(&stats);
        if value > limit {
            let name = Metric::ALL
                .iter()
                .find(|(m, _)| *m == cmd.metric)
                .map_or("", |(_, n)| n);
            eprintln!("{name} {value:.6} is above {limit}");
            return Ok(ExitCode::from(2));
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn with_threads<T: Send>(
    threads: Option<usize>,
    f: impl FnOnce() -> Result<T> + Send,
) -> Result<T> {
    match threads {
        None => f(),
        Some(n) if !(1..=MAX_THREADS).contains(&n) => {
            bail!("--threads {n}: between 1 and {MAX_THREADS} worker threads are accepted")
        }
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .context("cannot start the thread pool")?
            .install(f),
    }
}

fn load_scene(spec: &str, assets: &Path, camera: &CameraArgs, flatten: bool) -> Result<Arc<Scene>> {
    let start = std::time::Instant::now();
    let mut scene = raybench_scene::load(spec, assets)?;
    if flatten {
        scene = raybench_scene::flatten_within_budget(&scene)?;
    }
    camera.apply(&mut scene)?;
    eprintln!(
        "loaded {} ({} primitives) in {:.3} s",
        scene.name,
        scene.geometry.total_len(),
        start.elapsed().as_secs_f64()
    );
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    Ok(Arc::new(scene))
}

/// Refuses a volume mode (`mip`, `composite`) on a scene without volumes: it would render
/// the surfaces' colours as if nothing were wrong.
fn check_mode_fits(scene: &Scene, mode: Mode) -> Result<()> {
    if matches!(mode, Mode::Mip | Mode::Composite) && scene.volumes.is_empty() {
        bail!(
            "--mode {} shows volumes, and scene '{}' has none (use cast, whitted or path)",
            mode.name(),
            scene.name
        );
    }
    Ok(())
}

/// Makes and prepares a renderer, or says why it cannot run this scene.
fn render(cmd: &RenderCmd, assets: &Path) -> Result<ExitCode> {
    let settings = cmd.frame.settings(false);
    settings.validate()?;
    let b = match &cmd.backend {
        Some(name) => backend(name).map_err(anyhow::Error::msg)?,
        None => default_backend(),
    };
    let out = cmd.out.clone().unwrap_or_else(|| {
        let stem = Path::new(&cmd.scene)
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("scene")
            .replace(':', "-");
        PathBuf::from(format!("{stem}.png"))
    });
    // Before loading and rendering: a long render must not be lost to a bad path.
    raybench_render::check_image_path(&out, &raybench_render::ImageFormat::ALL)?;
    let exposure = cmd.exposure.checked()?;
    if let Some(ids) = &cmd.ids {
        raybench_render::check_png_path(ids)?;
    }
    let scene = load_scene(&cmd.scene, assets, &cmd.camera, cmd.flatten)?;
    check_mode_fits(&scene, settings.mode)?;
    raybench::frames::check_frames(&scene, cmd.frames).map_err(anyhow::Error::msg)?;
    if !scene.volumes.is_empty() && !matches!(settings.mode, Mode::Mip | Mode::Composite) {
        eprintln!(
            "note: the scene's {} volume(s) show only with --mode mip or --mode composite",
            scene.volumes.len()
        );
    }
    if cmd.frames > 1 {
        return render_frames(cmd, b, &scene, &settings, &out, exposure);
    }
    let progress = Progress::new(1);
    progress.begin(format!("{}: build", b.name));
    let p = prepare(b, &scene).map_err(|e| anyhow::anyhow!("backend '{}': {e}", b.name))?;
    progress.begin(format!(
        "{}: render {} {}x{}, {} spp",
        b.name,
        settings.mode.name(),
        settings.width,
        settings.height,
        settings.spp
    ));
    let frame = p.renderer.render(&settings)?;
    progress.done();
    drop(progress);
    let secs = timed_seconds(&frame.timings);
    eprintln!(
        "{}: build {:.3} s, {} {:.3} s, {} rays, {:.2} Mrays/s",
        b.name,
        p.build,
        if frame.timings.get("gpu").is_some() {
            "GPU execution"
        } else {
            "render"
        },
        secs,
        frame.stats.rays,
        frame.stats.rays as f64 / secs.max(1e-12) / 1e6
    );
    if let Some(line) = phase_line(&p.phases, &frame.timings) {
        eprintln!("{}: {line}", b.name);
    }
    raybench_render::write_color(&frame, &out, exposure)?;
    eprintln!("wrote {}", out.display());
    if let Some(ids) = &cmd.ids {
        raybench_render::write_ids_png(&frame, ids)?;
        eprintln!("wrote {}", ids.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// `render --frames N`: frame 0 prepared, every later one updated by `--update`; per frame
/// the update's and the render's times, and the images numbered
/// ([`raybench::frames::numbered`]).
fn render_frames(
    cmd: &RenderCmd,
    b: &raybench::Backend,
    scene: &Arc<Scene>,
    settings: &RenderSettings,
    out: &Path,
    exposure: f32,
) -> Result<ExitCode> {
    use raybench::frames::{advance, describe, numbered};
    let progress = Progress::new(cmd.frames as usize);
    progress.begin(format!("{}: build", b.name));
    let mut p = prepare(b, scene).map_err(|e| anyhow::anyhow!("backend '{}': {e}", b.name))?;
    let (mut update, mut trace) = (0.0, 0.0);
    for f in 0..cmd.frames {
        let phases = if f == 0 {
            p.phases.clone()
        } else {
            progress.begin(format!("{}: frame {f}: {}", b.name, cmd.update.name()));
            let (_, phases) = advance(p.renderer.as_mut(), scene, f, cmd.update)
                .map_err(|e| anyhow::anyhow!("backend '{}': {e}", b.name))?;
            update += phases.0.iter().map(|(_, s)| s).sum::<f64>();
            phases
        };
        progress.begin(format!("{}: frame {f}: render", b.name));
        let frame = p.renderer.render(settings)?;
        let secs = timed_seconds(&frame.timings);
        trace += secs;
        progress.step(&format!("frame {f}"));
        eprintln!(
            "frame {f}: {}; render {:.3} ms, {:.2} Mrays/s",
            describe(&phases),
            secs * 1e3,
            frame.stats.rays as f64 / secs.max(1e-12) / 1e6
        );
        let path = numbered(out, f, cmd.frames);
        raybench_render::write_color(&frame, &path, exposure)?;
        if let Some(ids) = &cmd.ids {
            raybench_render::write_ids_png(&frame, &numbered(ids, f, cmd.frames))?;
        }
    }
    drop(progress);
    let n = f64::from(cmd.frames - 1);
    eprintln!(
        "{}: {} frames: build {:.3} ms, then update {:.3} ms per frame (mean, --update {}), \
         render {:.3} ms per frame (mean)",
        b.name,
        cmd.frames,
        p.build * 1e3,
        update / n * 1e3,
        cmd.update.name(),
        trace / f64::from(cmd.frames) * 1e3
    );
    eprintln!(
        "wrote {} .. {}",
        numbered(out, 0, cmd.frames).display(),
        numbered(out, cmd.frames - 1, cmd.frames).display()
    );
    Ok(ExitCode::SUCCESS)
}

/// One row of `raybench compare --json`; the key set is documented in the README.
#[derive(Serialize)]
struct CompareRow {
    backend: String,
    reference: bool,
    available: bool,
    reason: Option<String>,
    scene: String,
    mode: &'static str,
    ray_set: String,
    width: u32,
    height: u32,
    spp: u32,
    build_seconds: Option<f64>,
    render_seconds: Option<f64>,
    rays: Option<u64>,
    mrays_per_s: Option<f64>,
    tests_per_ray: Option<f64>,
    id_match: Option<f64>,
    hit_mismatch: Option<u64>,
    max_abs_dt: Option<f64>,
    /// Seconds per phase: `prepare.build`, `prepare.upload`, and the medians of the timed
    /// frames' phases (`render`; `upload`, `gpu`, `readback` on the GPU).
    phases: BTreeMap<String, f64>,
}

/// `prepare: build 0.060 s, upload 0.004 s; frame: upload ..., gpu ..., readback ...` for a
/// backend with phases beyond `build` and `render` (a GPU), else `None`.
fn phase_line(prepare: &Timings, frame: &Timings) -> Option<String> {
    let join = |t: &Timings| {
        t.0.iter()
            .map(|(n, s)| format!("{n} {s:.4} s"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    (prepare.0.len() > 1 || frame.0.len() > 1)
        .then(|| format!("prepare: {}; frame: {}", join(prepare), join(frame)))
}

fn compare(cmd: &CompareCmd, assets: &Path) -> Result<ExitCode> {
    let settings = cmd.frame.settings(false);
    settings.validate()?;
    if cmd.repeat == 0 || cmd.repeat > 10_000 {
        bail!("--repeat must be in 1..=10000");
    }
    let scene = load_scene(&cmd.scene, assets, &cmd.camera, cmd.flatten)?;
    check_mode_fits(&scene, settings.mode)?;
    let (ray_set, rays) = cmd.rays.batch(&scene, &settings)?;
    let work = cmd.rays.work(
        rays.as_ref(),
        &settings,
        scene.geometry.total_len(),
        cmd.repeat + 1,
    );
    let chosen = chosen_backends(cmd.backends.as_deref(), work).map_err(anyhow::Error::msg)?;
    if chosen.is_empty() {
        bail!("no backend to compare");
    }

    let mut rows = Vec::new();
    let mut reference: Option<Measured> = None;
    let mut disagree = false;
    let frames = cmd.repeat as usize + 1;
    let progress = Progress::new(chosen.len() * frames);
    for (i, b) in chosen.iter().enumerate() {
        let mut row = CompareRow {
            backend: b.name.into(),
            reference: i == 0,
            available: true,
            reason: None,
            scene: scene.name.clone(),
            mode: settings.mode.name(),
            ray_set: ray_set.clone(),
            width: settings.width,
            height: settings.height,
            spp: settings.spp,
            build_seconds: None,
            render_seconds: None,
            rays: None,
            mrays_per_s: None,
            tests_per_ray: None,
            id_match: None,
            hit_mismatch: None,
            max_abs_dt: None,
            phases: BTreeMap::new(),
        };
        progress.begin(format!("{}: build", b.name));
        let Prepared {
            renderer: r,
            build,
            phases: prepare_phases,
        } = match prepare_for_mode(b, &scene, settings.mode) {
            Ok(x) => x,
            Err(reason) => {
                progress.remove(frames);
                progress.note(&format!("skipping {}: {reason}", b.name));
                row.available = false;
                row.reason = Some(reason);
                rows.push(row);
                continue;
            }
        };
        progress.note(&format!(
            "{}: built in {build:.3} s, tracing {frames} times",
            b.name
        ));
        // The warm-up is counted and is what gets compared; timed runs count nothing.
        progress.begin(format!("{}: counted warm-up", b.name));
        let warm = measure(r.as_ref(), &settings, rays.as_ref(), true)?;
        progress.done();
        let mut times = Vec::new();
        let mut phases = Vec::new();
        for k in 1..=cmd.repeat {
            progress.begin(format!("{}: timed run {k}/{}", b.name, cmd.repeat));
            let m = measure(r.as_ref(), &settings, rays.as_ref(), false)?;
            progress.done();
            times.push(m.seconds);
            phases.push(m.phases);
        }
        let secs = median(times);
        let frame_phases = median_phases(&phases);
        if let Some(line) = phase_line(&prepare_phases, &frame_phases) {
            progress.note(&format!("{}: {line}", b.name));
        }
        row.phases = prepare_phases
            .0
            .iter()
            .map(|(n, s)| (format!("prepare.{n}"), *s))
            .chain(frame_phases.0.iter().map(|(n, s)| (n.clone(), *s)))
            .collect();
        row.build_seconds = Some(build);
        row.render_seconds = Some(secs);
        row.rays = Some(warm.rays);
        row.mrays_per_s = Some(warm.rays as f64 / secs.max(1e-12) / 1e6);
        row.tests_per_ray = warm
            .counters
            .filter(|_| r.counts_tests())
            .map(|c| c.prim_tests as f64 / warm.rays.max(1) as f64);
        match &reference {
            None => {
                row.reference = true;
                row.id_match = Some(1.0);
                row.hit_mismatch = Some(0);
                row.max_abs_dt = Some(0.0);
                reference = Some(warm);
            }
            Some(reference) => {
                let c = compare_hits(&reference.ids, &reference.t, &warm.ids, &warm.t);
                row.id_match = Some(c.id_match);
                row.hit_mismatch = Some(c.hit_mismatch);
                row.max_abs_dt = Some(c.max_abs_dt);
                if b.exact() && c.id_match < 1.0 {
                    disagree = true;
                }
            }
        }
        rows.push(row);
    }

    drop(progress);
    if cmd.json {
        outln!("{}", serde_json::to_string_pretty(&rows)?)?;
    } else {
        print_table(&rows)?;
    }
    if disagree {
        eprintln!("error: a raybench CPU backend disagrees with the reference");
        return Ok(ExitCode::from(3));
    }
    Ok(ExitCode::SUCCESS)
}

fn fmt_opt<T>(v: Option<T>, f: impl Fn(T) -> String) -> String {
    v.map_or_else(|| "-".into(), f)
}

fn print_table(rows: &[CompareRow]) -> std::io::Result<()> {
    outln!(
        "{:<16} {:>10} {:>10} {:>10} {:>12} {:>10} {:>9} {:>8} {:>10}",
        "backend",
        "build s",
        "render s",
        "Mrays/s",
        "tests/ray",
        "id match",
        "hit diff",
        "max|dt|",
        "speed-up"
    )?;
    let base = rows.iter().find_map(|r| r.render_seconds);
    for r in rows {
        if !r.available {
            outln!(
                "{:<16} unavailable: {}",
                r.backend,
                r.reason.as_deref().unwrap_or("")
            )?;
            continue;
        }
        outln!(
            "{:<16} {:>10} {:>10} {:>10} {:>12} {:>10} {:>9} {:>8} {:>10}",
            r.backend,
            fmt_opt(r.build_seconds, |v| format!("{v:.4}")),
            fmt_opt(r.render_seconds, |v| format!("{v:.4}")),
            fmt_opt(r.mrays_per_s, |v| format!("{v:.3}")),
            fmt_opt(r.tests_per_ray, |v| format!("{v:.1}")),
            fmt_opt(r.id_match, |v| format!("{:.4}%", v * 100.0)),
            fmt_opt(r.hit_mismatch, |v| v.to_string()),
            fmt_opt(r.max_abs_dt, |v| format!("{v:.1e}")),
            fmt_opt(r.render_seconds.zip(base), |(s, b)| format!(
                "{:.1}x",
                b / s.max(1e-12)
            )),
        )?;
    }
    Ok(())
}

/// `assets` as an absolute path without `.` or `..` (symbolic links resolved when it
/// exists), and whether it exists.
fn resolved_dir(assets: &Path) -> (PathBuf, bool) {
    if let Ok(p) = assets.canonicalize() {
        return (p, true);
    }
    let absolute = std::path::absolute(assets).unwrap_or_else(|_| assets.to_owned());
    let mut clean = PathBuf::new();
    for c in absolute.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                clean.pop();
            }
            c => clean.push(c),
        }
    }
    (clean, false)
}

fn scenes(assets: &Path) -> Result<ExitCode> {
    let (dir, exists) = resolved_dir(assets);
    outln!(
        "# built-in scenes (assets: {}{})",
        dir.display(),
        if exists {
            ""
        } else {
            ", which does not exist: set --assets or RAYBENCH_ASSETS"
        }
    )?;
    for b in BUILTIN_SCENES {
        let missing: Vec<_> = b
            .assets
            .iter()
            .filter(|a| !assets.join(a).is_file())
            .collect();
        let state = if missing.is_empty() {
            "ok"
        } else {
            "missing-assets"
        };
        outln!("{:<14} {:<15} {}", b.name, state, b.description)?;
    }
    outln!("# generators (NAME:ARG)")?;
    for g in GENERATORS {
        outln!(
            "{:<14} {:<15} {} (ARG = {}, at most {})",
            format!("{}:ARG", g.name),
            "ok",
            g.description,
            g.argument,
            g.max
        )?;
    }
    Ok(ExitCode::SUCCESS)
}

#[derive(Serialize)]
struct BackendRow {
    name: &'static str,
    /// For a build preset (`bvh:fast`): the backend it builds, and whether it is that
    /// backend's default.
    #[serde(skip_serializing_if = "Option::is_none")]
    preset_of: Option<&'static str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    default_preset: Option<bool>,
    available: bool,
    reason: Option<String>,
    exact: bool,
    /// Its roles in the registry (`exact`, `oracle`, `brute-force`, `pinned`, `peer`, ...).
    roles: Vec<&'static str>,
    description: &'static str,
    /// The device it runs on when that is not this CPU (the GPU adapter).
    device: Option<String>,
}

fn backends(json: bool) -> Result<ExitCode> {
    let row = |b: &'static raybench::Backend, preset: Option<(&'static str, bool)>| {
        let r = (b.make)();
        let avail = r.availability();
        BackendRow {
            name: b.name,
            preset_of: preset.map(|p| p.0),
            default_preset: preset.map(|p| p.1),
            available: avail.is_ok(),
            reason: avail.err(),
            exact: b.exact(),
            roles: b.roles.names(),
            description: b.description,
            device: r.device(),
        }
    };
    let built = BACKENDS.iter().map(|b| row(b, None));
    let presets = raybench::presets::PRESETS
        .iter()
        .map(|p| row(&p.entry, Some((p.backend, p.default))));
    let not_built = NOT_BUILT.iter().map(|n| BackendRow {
        name: n.name,
        preset_of: None,
        default_preset: None,
        available: false,
        reason: Some(n.reason()),
        exact: false,
        roles: Vec::new(),
        description: n.description,
        device: None,
    });
    let rows: Vec<BackendRow> = built.chain(not_built).chain(presets).collect();
    if json {
        outln!("{}", serde_json::to_string_pretty(&rows)?)?;
    } else {
        let width = rows
            .iter()
            .map(|r| r.name.len() + 2)
            .max()
            .unwrap_or(0)
            .max(16);
        let mut presets_begun = false;
        for r in rows {
            if r.preset_of.is_some() && !presets_begun {
                presets_begun = true;
                outln!(
                    "\nBuild presets (name them as BACKEND:PRESET wherever a backend is taken; \
                     * = the backend's default):"
                )?;
            }
            let name = match r.default_preset {
                Some(true) => format!("{}*", r.name),
                _ => r.name.to_string(),
            };
            let state = if r.available {
                "available".to_string()
            } else {
                format!("unavailable ({})", r.reason.unwrap_or_default())
            };
            outln!("{name:<width$} {:<12} {}", state, r.description)?;
            if let Some(d) = &r.device {
                outln!("{:<width$} {:<12} device: {d}", "", "")?;
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn report(cmd: &ReportCmd, assets: &Path) -> Result<ExitCode> {
    let opts = raybench::report::Options {
        quick: cmd.quick,
        scenes: cmd.scenes.clone(),
        backends: cmd.backends.clone(),
        modes: cmd.modes.clone(),
        out: cmd.out.clone(),
        shard: cmd.shard,
        size: cmd.size,
        repeat: cmd.repeat,
        scaling: !cmd.no_scaling,
        experiments: cmd.experiments.clone(),
        ray_sets: cmd.rays.clone(),
        ao_rays: cmd.ao_rays,
        rays_file: cmd.rays_file.clone(),
        assets: assets.to_path_buf(),
        threads: rayon::current_num_threads(),
        command: std::env::args().collect::<Vec<_>>().join(" "),
        baseline: cmd.baseline.clone(),
    };
    let results = raybench::report::run(&opts)?;
    let failed: Vec<String> = results
        .runs
        .iter()
        .filter(|r| r.exact && r.equality.as_ref().is_some_and(|e| !e.pass))
        .map(|r| format!("{} on {} ({}, {})", r.backend, r.scene, r.mode, r.ray_set))
        .collect();
    if !failed.is_empty() {
        eprintln!(
            "error: raybench CPU backends disagree with the reference: {}",
            failed.join("; ")
        );
        return Ok(ExitCode::from(3));
    }
    Ok(ExitCode::SUCCESS)
}

fn info(cmd: &InfoCmd, assets: &Path) -> Result<ExitCode> {
    let scene = load_scene(&cmd.scene, assets, &cmd.camera, cmd.flatten)?;
    check_mode_fits(&scene, cmd.mode)?;
    let g = &scene.geometry;
    outln!("scene       {}", scene.name)?;
    outln!("primitives  {}", g.total_len())?;
    if g.has_instances() {
        let stored: usize = g.meshes().iter().map(|m| m.len()).sum();
        outln!(
            "instances   {} of {} meshes ({} flat primitives and {stored} in the meshes \
             stored; the counts by kind below are the flat ones)",
            g.instances().len(),
            g.meshes().len(),
            g.len()
        )?;
    }
    for (kind, n) in g.count_by_kind() {
        outln!("  {:<9} {n}", kind.name())?;
    }
    outln!("volumes     {}", scene.volumes.len())?;
    outln!("objects     {}", scene.objects.len())?;
    outln!("materials   {}", scene.materials.len())?;
    outln!("lights      {}", scene.lights.len())?;
    outln!("cameras     {}", scene.cameras.len())?;
    for (i, c) in scene.cameras.iter().enumerate() {
        let cam = c.camera;
        outln!(
            "  {i:<3} {:<20} from [{}, {}, {}] at [{}, {}, {}] fov {}",
            format!("'{}'", c.name),
            cam.position.x,
            cam.position.y,
            cam.position.z,
            cam.look_at.x,
            cam.look_at.y,
            cam.look_at.z,
            cam.vfov_degrees
        )?;
    }
    let bb = g.world_bounds();
    if bb.is_empty() {
        outln!("bounds      (none: no bounded primitives)")?;
    } else {
        outln!(
            "bounds      [{}, {}, {}] .. [{}, {}, {}]",
            bb.min.x,
            bb.min.y,
            bb.min.z,
            bb.max.x,
            bb.max.y,
            bb.max.z
        )?;
    }
    let settings = RenderSettings {
        width: cmd.width,
        height: cmd.height,
        spp: cmd.spp,
        mode: cmd.mode,
        max_depth: cmd.max_depth,
        ..RenderSettings::default()
    };
    settings.validate()?;
    let (ray_set, probe) = cmd.rays.batch(&scene, &settings)?;
    outln!(
        "probe       {} rays{}, {}x{}, mode {}, {} spp, max depth {}",
        ray_set,
        probe.as_ref().map_or(String::new(), |b| format!(
            " ({} {} rays)",
            b.rays.len(),
            if b.any_hit { "any-hit" } else { "closest-hit" }
        )),
        cmd.width,
        cmd.height,
        cmd.mode.name(),
        cmd.spp,
        cmd.max_depth
    )?;
    let work = cmd.rays.work(probe.as_ref(), &settings, g.total_len(), 1);
    let chosen = chosen_backends(cmd.backends.as_deref(), work).map_err(anyhow::Error::msg)?;
    outln!(
        "{:<16} {:>10} {:>14} {:>9} {:>10} {:>10}  structure",
        "backend",
        "build s",
        "memory bytes",
        "rays/px",
        "tests/ray",
        "visits/ray"
    )?;
    let params = QualityParams {
        epo_samples: cmd.epo_samples,
        ..QualityParams::default()
    };
    let mut qualities = Vec::new();
    for b in chosen {
        match prepare_for_mode(b, &scene, settings.mode) {
            Err(reason) => outln!("{:<16} unavailable: {reason}", b.name)?,
            Ok(Prepared {
                renderer: r, build, ..
            }) => {
                qualities.push((b.name, r.quality(&params).as_ref().map(Quality::from)));
                let s = r.structure().unwrap_or_default();
                let counts: Vec<String> =
                    s.counts.iter().map(|(k, v)| format!("{k}={v}")).collect();
                let m = measure(r.as_ref(), &settings, probe.as_ref(), true)?;
                let per_ray = |v: u64| format!("{:.2}", v as f64 / m.rays.max(1) as f64);
                let pixels = f64::from(cmd.width) * f64::from(cmd.height);
                outln!(
                    "{:<16} {:>10.4} {:>14} {:>9.2} {:>10} {:>10}  {}",
                    b.name,
                    build,
                    s.memory_bytes,
                    m.rays as f64 / pixels,
                    m.counters.map_or("-".into(), |c| per_ray(c.prim_tests)),
                    m.counters.map_or("-".into(), |c| per_ray(c.node_visits)),
                    if counts.is_empty() {
                        "(none)".into()
                    } else {
                        counts.join(" ")
                    }
                )?;
            }
        }
    }
    print_quality(&qualities, &params)?;
    Ok(ExitCode::SUCCESS)
}

/// `raybench info`'s structure quality: one table for trees, one for grids, then the
/// structures that cannot be read and the backends without one.
fn print_quality(
    qualities: &[(&str, Option<Quality>)],
    params: &QualityParams,
) -> std::io::Result<()> {
    outln!(
        "quality     SAH cost and EPO with C_t = {}, C_i = {}; EPO from {} points sampled by area \
         on triangles and spheres, +- its standard error",
        params.costs.traversal,
        params.costs.intersection,
        params.epo_samples
    )?;
    let table = |headers: [&str; 7], rows: Vec<(&str, [String; 7])>| -> std::io::Result<()> {
        if rows.is_empty() {
            return Ok(());
        }
        outln!(
            "{:<16} {:>10} {:>16} {:>9} {:>9} {:>14} {:>10}  {}",
            "backend",
            headers[0],
            headers[1],
            headers[2],
            headers[3],
            headers[4],
            headers[5],
            headers[6]
        )?;
        for (name, c) in rows {
            outln!(
                "{name:<16} {:>10} {:>16} {:>9} {:>9} {:>14} {:>10}  {}",
                c[0],
                c[1],
                c[2],
                c[3],
                c[4],
                c[5],
                c[6]
            )?;
        }
        Ok(())
    };
    let rows = |f: fn(&Quality) -> Option<[String; 7]>| {
        qualities
            .iter()
            .filter_map(|(name, q)| Some((*name, f(q.as_ref()?)?)))
            .collect::<Vec<_>>()
    };
    table(TREE_COLUMNS, rows(Quality::tree_columns))?;
    table(GRID_COLUMNS, rows(Quality::grid_columns))?;
    for (name, q) in qualities {
        match q {
            Some(Quality::NotReadable { reason }) => {
                outln!("{name:<16} not readable: {reason}")?;
            }
            None => outln!("{name:<16} no structure")?,
            Some(_) => {}
        }
    }
    let excluded = qualities.iter().find_map(|(_, q)| match q {
        Some(Quality::Tree {
            epo_excluded_primitives,
            ..
        }) => Some(*epo_excluded_primitives),
        _ => None,
    });
    if let Some(n @ 1..) = excluded {
        outln!(
            "            EPO leaves out {n} bounded primitives that are neither triangles nor spheres"
        )?;
    }
    Ok(())
}

/// `raybench rays export`: the rays of a set written to a ray file.
fn export_rays(cmd: &ExportCmd, assets: &Path) -> Result<ExitCode> {
    let settings = RenderSettings {
        width: cmd.width,
        height: cmd.height,
        seed: cmd.seed,
        ..RenderSettings::default()
    };
    settings.validate()?;
    let scene = load_scene(&cmd.scene, assets, &cmd.camera, false)?;
    let params = DerivedParams {
        ao_rays: cmd.ao_rays,
        seed: cmd.seed,
        ..DerivedParams::default()
    };
    let rays = match explicit_rays(cmd.rays, &scene, &settings, &params)? {
        Some(batch) => batch.rays,
        None => primary_rays(&scene, &settings)?,
    };
    raybench::rays_file::write(&cmd.out, &rays, cmd.rays.any_hit())?;
    eprintln!(
        "wrote {} {} rays ({}) of {} to {}",
        rays.len(),
        cmd.rays.name(),
        if cmd.rays.any_hit() {
            "any hit"
        } else {
            "closest hit"
        },
        scene.name,
        cmd.out.display()
    );
    Ok(ExitCode::SUCCESS)
}
