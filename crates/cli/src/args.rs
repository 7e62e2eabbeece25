//! The arguments and helpers several subcommands share: frame and camera options, ray
//! sets, value parsers, the worker pool and scene loading.

use anyhow::{Context, Result, bail};
use clap::Args;
use raybench_core::limits::MAX_THREADS;
use raybench_core::ray_sets::{DEFAULT_AO_RAYS, DerivedParams};
use raybench_core::{
    CameraOverrides, LightSampling, Mode, RaySet, RenderSettings, Scene, Timings, Vec3,
};
use raybench_registry::brute_force_tests;
use raybench_registry::measure::{RayBatch, explicit_rays, no_rays};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The rays a measurement traces: a ray set, or a ray file's rays.
#[derive(Args, Clone)]
pub(crate) struct RaysArgs {
    /// Ray set: `primary` renders frames; the others trace explicit rays: `incoherent`
    /// (width x height seeded random rays: origins in the scene's box, uniform directions),
    /// `shadow` (any hit: from each primary hit to each light and one sampled emitter
    /// point), `ao` (any hit: --ao-rays cosine rays per primary hit, a tenth of the scene's
    /// diagonal long), `diffuse` (one cosine bounce per primary hit).
    #[arg(long, default_value = "primary", value_parser = parse_ray_set)]
    pub(crate) rays: RaySet,
    /// Replay the rays of a ray file (`raybench rays export`, docs/rays-format.md) instead
    /// of a ray set: any hit or closest hit as the file's flag says.
    #[arg(long, value_name = "FILE", conflicts_with = "rays")]
    pub(crate) rays_file: Option<PathBuf>,
    /// Ambient-occlusion rays per primary hit (--rays ao).
    #[arg(long, default_value_t = DEFAULT_AO_RAYS, value_name = "N")]
    pub(crate) ao_rays: u32,
}

impl RaysArgs {
    /// The workload's name (`shadow`, or `file:NAME`) and its explicit rays (`None`:
    /// frames); an empty batch (a ray file of no rays, shadow rays without lights) is an
    /// error saying why.
    pub(crate) fn batch(
        &self,
        scene: &Arc<Scene>,
        settings: &RenderSettings,
    ) -> Result<(String, Option<RayBatch>)> {
        if let Some(path) = &self.rays_file {
            let file = raybench_registry::rays_file::read(path)?;
            let name = path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            );
            let batch = RayBatch::from_file(file);
            if batch.rays.is_empty() {
                bail!("{}", no_rays(self.rays, scene, Some(path)));
            }
            return Ok((format!("file:{name}"), Some(batch)));
        }
        let params = DerivedParams {
            ao_rays: self.ao_rays,
            seed: settings.seed,
            ..DerivedParams::default()
        };
        let batch = explicit_rays(self.rays, scene, settings, &params)?;
        // Nothing to time or compare: a table of zero rays would rank backends by noise.
        if batch.as_ref().is_some_and(|b| b.rays.is_empty()) {
            bail!("{}: {}", scene.name, no_rays(self.rays, scene, None));
        }
        Ok((self.rays.name().to_owned(), batch))
    }

    /// Estimated tests of a brute-force backend ([`brute_force_tests`]; a file's rays as
    /// they are).
    pub(crate) fn work(
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

#[derive(Args, Clone)]
pub(crate) struct FrameArgs {
    /// Integrator: cast (ray casting), whitted (Whitted ray tracing), path (Monte Carlo
    /// path tracing), mip or composite (voxel volumes: maximum intensity, compositing).
    #[arg(long, default_value = "cast", value_parser = parse_mode)]
    pub(crate) mode: Mode,
    /// Image width in pixels.
    #[arg(long, default_value_t = 512)]
    pub(crate) width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 512)]
    pub(crate) height: u32,
    /// Samples per pixel.
    #[arg(long, default_value_t = 1)]
    pub(crate) spp: u32,
    /// Seed of the random numbers.
    #[arg(long, default_value_t = 0)]
    pub(crate) seed: u32,
    /// Maximum number of bounces (whitted, path).
    #[arg(long, default_value_t = 5)]
    pub(crate) max_depth: u32,
    /// How `path` mode reaches emitters: `mis` (next-event estimation and BSDF sampling
    /// combined) or `bsdf` (BSDF sampling only, to compare).
    #[arg(long, default_value = "mis", value_parser = parse_light_sampling)]
    pub(crate) light_sampling: LightSampling,
    /// Worker threads (default: all cores; at most 1024).
    #[arg(long)]
    pub(crate) threads: Option<usize>,
}

impl FrameArgs {
    pub(crate) fn settings(&self, count: bool) -> RenderSettings {
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
pub(crate) struct CameraArgs {
    /// The scene's camera to render, by name or 0-based index (`raybench info` lists
    /// them; default: the first).
    #[arg(long, value_name = "NAME|INDEX")]
    pub(crate) camera: Option<String>,
    /// Replace the camera's position: `x,y,z`.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub(crate) look_from: Option<Vec3>,
    /// Replace the point the camera looks at: `x,y,z`.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub(crate) look_at: Option<Vec3>,
    /// Replace the camera's up direction: `x,y,z`.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub(crate) up: Option<Vec3>,
    /// Replace the vertical field of view, in degrees (as the scene format's `fov`).
    #[arg(long, value_name = "DEGREES")]
    pub(crate) fov: Option<f32>,
}

impl CameraArgs {
    /// Picks and adjusts the scene's camera.
    pub(crate) fn apply(&self, scene: &mut Scene) -> Result<()> {
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
pub(crate) fn parse_vec3(s: &str) -> Result<Vec3, String> {
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

pub(crate) fn parse_light_sampling(s: &str) -> Result<LightSampling, String> {
    LightSampling::from_name(s)
        .ok_or_else(|| format!("unknown light sampling '{s}' (known: mis, bsdf)"))
}

pub(crate) fn parse_mode(s: &str) -> Result<Mode, String> {
    Mode::from_name(s).ok_or_else(|| {
        let names: Vec<_> = Mode::ALL.iter().map(|m| m.name()).collect();
        format!("unknown mode '{s}' (known: {})", names.join(", "))
    })
}

pub(crate) fn parse_ray_set(s: &str) -> Result<RaySet, String> {
    RaySet::from_name(s).ok_or_else(|| {
        let names: Vec<_> = RaySet::ALL.iter().map(|r| r.name()).collect();
        format!("unknown ray set '{s}' (known: {})", names.join(", "))
    })
}

pub(crate) fn with_threads<T: Send>(
    threads: Option<usize>,
    f: impl FnOnce() -> Result<T> + Send,
) -> Result<T> {
    with_pool(threads, false, f)
}

/// Runs `f` on a pool of `threads` workers (default: rayon's global pool, one per core);
/// with `pin`, worker `i` is bound to the `i`-th core this process may run on (modulo their
/// count), so that the scheduler does not move it between cores.
pub(crate) fn with_pool<T: Send>(
    threads: Option<usize>,
    pin: bool,
    f: impl FnOnce() -> Result<T> + Send,
) -> Result<T> {
    if let Some(n) = threads
        && !(1..=MAX_THREADS).contains(&n)
    {
        bail!("--threads {n}: between 1 and {MAX_THREADS} worker threads are accepted");
    }
    if threads.is_none() && !pin {
        return f();
    }
    let mut builder = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or_else(rayon::current_num_threads));
    if pin {
        let cores = core_affinity::get_core_ids()
            .filter(|c| !c.is_empty())
            .context("--pin: this system does not say which cores the process may use")?;
        builder = builder.start_handler(move |i| {
            // A refusal leaves the worker unpinned; the report records what was asked.
            let _ = core_affinity::set_for_current(cores[i % cores.len()]);
        });
    }
    builder
        .build()
        .context("cannot start the thread pool")?
        .install(f)
}

pub(crate) fn load_scene(
    spec: &str,
    assets: &Path,
    camera: &CameraArgs,
    flatten: bool,
) -> Result<Arc<Scene>> {
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
pub(crate) fn check_mode_fits(scene: &Scene, mode: Mode) -> Result<()> {
    if matches!(mode, Mode::Mip | Mode::Composite) && scene.volumes.is_empty() {
        bail!(
            "--mode {} shows volumes, and scene '{}' has none (use cast, whitted or path)",
            mode.name(),
            scene.name
        );
    }
    if mode == Mode::Whitted && scene.lights.is_empty() {
        eprintln!(
            "note: scene '{}' {}",
            scene.name,
            raybench_core::integrator::HEADLIGHT_NOTE
        );
    }
    Ok(())
}

pub(crate) fn fmt_opt<T>(v: Option<T>, f: impl Fn(T) -> String) -> String {
    v.map_or_else(|| "-".into(), f)
}

/// `--exposure EV` of `render` and `diff`.
#[derive(Args)]
pub(crate) struct Exposure {
    // `diff` replaces this help with its own (`main.rs`: both images are scaled before PSNR
    // and FLIP).
    /// Exposure in stops: the colour written, in every format, is scaled by 2^EV (0 writes
    /// the radiance itself).
    #[arg(
        long = "exposure",
        default_value_t = 0.0,
        value_name = "EV",
        allow_hyphen_values = true
    )]
    pub(crate) ev: f32,
}

impl Exposure {
    /// The exposure, checked to lie within [-64, 64] stops.
    pub(crate) fn checked(&self) -> Result<f32> {
        if !self.ev.is_finite() || self.ev.abs() > 64.0 {
            bail!("--exposure {} is outside [-64, 64] stops", self.ev);
        }
        Ok(self.ev)
    }
}

/// `prepare: build 0.060 s, upload 0.004 s; frame: upload ..., gpu ..., readback ...` for a
/// backend with phases beyond `build` and `render` (a GPU), else `None`.
pub(crate) fn phase_line(prepare: &Timings, frame: &Timings) -> Option<String> {
    let join = |t: &Timings| {
        t.0.iter()
            .map(|(n, s)| format!("{n} {s:.4} s"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    (prepare.0.len() > 1 || frame.0.len() > 1)
        .then(|| format!("prepare: {}; frame: {}", join(prepare), join(frame)))
}
