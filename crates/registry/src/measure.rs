//! Measuring one workload with one backend: the shared core of `compare`, `info` and
//! `report`.

use crate::TimedRenderer;
use crate::interference::{self, Interference};
use crate::{Backend, Roles};
use anyhow::{Result, anyhow, bail};
use raybench_core::ray_sets::{self, DerivedParams};
use raybench_core::{NO_HIT, Ray, RayCounters, RaySet, RenderSettings, Scene, Timings, limits};
use raybench_render::TILE_SIZE;
use std::sync::Arc;

/// Seed of the incoherent ray set (the same rays in every run and in the benches).
pub const INCOHERENT_SEED: u32 = 1;

/// The id [`measure`] records for an any-hit ray that is occluded (with `t` = 0); a ray
/// that is not gets [`NO_HIT`] and infinity, so that [`crate::compare_hits`] compares
/// any-hit answers on their boolean.
pub const OCCLUDED: u32 = 0;

/// Rays traced explicitly (not as frames), and the query they ask for.
#[derive(Clone, Debug)]
pub struct RayBatch {
    /// The rays.
    pub rays: Vec<Ray>,
    /// Any hit ([`TimedRenderer::occlude_rays_timed`]) rather than the closest hit
    /// ([`TimedRenderer::trace_rays_timed`]).
    pub any_hit: bool,
    /// Shadow rays of the set left out untraced because their light lies behind the surface
    /// they leave, which blocks it ([`ray_sets::Derived::facing_away`]); 0 for other sets.
    pub facing_away: u64,
}

impl RayBatch {
    /// The rays of a ray file (`docs/rays-format.md`), with its any-hit flag.
    #[must_use]
    pub fn from_file(file: crate::rays_file::RayFile) -> Self {
        Self {
            rays: file.rays,
            any_hit: file.any_hit,
            facing_away: 0,
        }
    }
}

/// The rays a ray set traces explicitly: `None` for primary rays (frames are rendered);
/// `width x height` seeded incoherent rays; or a set derived from the primary hits
/// ([`derived_rays`], traced once with the baseline backend).
///
/// # Errors
/// When the ray count exceeds [`limits::MAX_EXPLICIT_RAYS`], or the primary rays cannot be
/// traced.
pub fn explicit_rays(
    set: RaySet,
    scene: &Arc<Scene>,
    settings: &RenderSettings,
    params: &DerivedParams,
) -> Result<Option<RayBatch>> {
    let count = u64::from(settings.width) * u64::from(settings.height);
    let mut facing_away = 0;
    let rays = match set {
        RaySet::Primary => return Ok(None),
        RaySet::Incoherent if count > limits::MAX_EXPLICIT_RAYS => bail!(
            "{count} incoherent rays exceed the limit of {} (use a smaller --width x --height)",
            limits::MAX_EXPLICIT_RAYS
        ),
        RaySet::Incoherent => raybench_core::ray_sets::incoherent(
            scene.geometry.world_bounds(),
            count as usize,
            INCOHERENT_SEED,
        ),
        _ => {
            let baseline = crate::with_role(Roles::BASELINE)
                .ok_or_else(|| anyhow!("no baseline backend to trace the primary rays"))?;
            let derived = derived_rays(set, scene, settings, params, baseline)?;
            facing_away = derived.facing_away;
            derived.rays
        }
    };
    Ok(Some(RayBatch {
        rays,
        any_hit: set.any_hit(),
        facing_away,
    }))
}

/// Why a batch of rays of `set` on `scene` came out empty, for messages: the ray file
/// (`file`) holds none, the scene has no light to aim shadow rays at, or no primary ray
/// hits the scene (every derived set starts at the primary hits).
#[must_use]
pub fn no_rays(set: RaySet, scene: &Scene, file: Option<&std::path::Path>) -> String {
    match file {
        Some(file) => format!("no rays: the ray file {} holds none", file.display()),
        None if set == RaySet::Shadow && scene.lights.is_empty() && scene.emitters.is_empty() => {
            "no shadow rays: the scene has no light or emitter to aim them at".into()
        }
        None if set == RaySet::Shadow => "no shadow rays: no primary ray hits the scene, or \
                                          every light lies behind the surfaces they hit"
            .into(),
        None => format!("no {} rays: no primary ray hits the scene", set.name()),
    }
}

/// The rays of the derived set `set` (`shadow`, `ao`, `diffuse`): the [`primary_rays`]
/// traced with `tracer` (any exact backend gives the same hits, so the same set), then
/// [`ray_sets::derived_set`] with seed `params.seed`.
///
/// # Errors
/// Too many primary or derived rays, a backend that cannot run or trace, bad parameters.
pub fn derived_rays(
    set: RaySet,
    scene: &Arc<Scene>,
    settings: &RenderSettings,
    params: &DerivedParams,
    tracer: &Backend,
) -> Result<ray_sets::Derived> {
    let primary = primary_rays(scene, settings)?;
    let p = prepare(tracer, scene).map_err(|reason| {
        anyhow!(
            "cannot trace the primary rays of the {} set with {}: {reason}",
            set.name(),
            tracer.name
        )
    })?;
    let (hits, _) = p.renderer.trace_rays(&primary, false)?;
    Ok(ray_sets::derived_set(set, scene, &primary, &hits, params)?)
}

/// The camera's `width x height` primary rays ([`settings`'s camera](Scene::view)) in the
/// order the integrators trace them: [`ray_sets::primary_tiled`] with [`TILE_SIZE`] tiles.
///
/// # Errors
/// More than [`limits::MAX_EXPLICIT_RAYS`] rays, or a camera the scene does not have.
pub fn primary_rays(scene: &Scene, settings: &RenderSettings) -> Result<Vec<Ray>> {
    let count = u64::from(settings.width) * u64::from(settings.height);
    if count > limits::MAX_EXPLICIT_RAYS {
        bail!(
            "{count} primary rays exceed the limit of {} (use a smaller --width x --height)",
            limits::MAX_EXPLICIT_RAYS
        );
    }
    let camera = scene.view(settings)?;
    Ok(ray_sets::primary_tiled(
        camera,
        settings.width,
        settings.height,
        TILE_SIZE,
    ))
}

/// One measured workload: per-ray ids and `t`, rays traced, counters, seconds.
#[derive(Clone)]
pub struct Measured {
    /// Primitive id per ray or pixel ([`NO_HIT`] for misses); for any-hit rays
    /// [`OCCLUDED`] or [`NO_HIT`].
    pub ids: Vec<u32>,
    /// `t` per ray or pixel (infinity for misses; 0 for occluded any-hit rays).
    pub t: Vec<f32>,
    /// Rays traced.
    pub rays: u64,
    /// Work counters, when counted.
    pub counters: Option<RayCounters>,
    /// Seconds of rendering or tracing: the GPU's execution time for a backend that reports
    /// one (phase `gpu`), else the whole call (phase `render`).
    pub seconds: f64,
    /// The backend's timing phases (`render`; a GPU backend adds `upload`, `gpu`,
    /// `readback`).
    pub phases: Timings,
    /// The frame's linear colours (primary rays only).
    pub color: Option<Vec<raybench_core::Vec3>>,
    /// What the scheduler says of the call: how long the threads waited for a CPU
    /// ([`crate::interference`]); `None` where the kernel does not tell.
    pub interference: Option<Interference>,
}

/// Renders a frame (primary rays) or traces the given rays once: closest hits, or any
/// hits for an any-hit batch.
///
/// # Errors
/// When rendering or tracing fails.
pub fn measure(
    r: &dyn TimedRenderer,
    settings: &RenderSettings,
    rays: Option<&RayBatch>,
    count: bool,
) -> Result<Measured> {
    let settings = RenderSettings { count, ..*settings };
    let Some(batch) = rays else {
        let (f, interference) = interference::during(|| r.render(&settings));
        let f = f?;
        return Ok(Measured {
            seconds: timed_seconds(&f.timings),
            phases: f.timings,
            rays: f.stats.rays,
            counters: f.stats.counters,
            ids: f.ids,
            t: f.t,
            color: Some(f.color),
            interference,
        });
    };
    let (result, interference) = interference::during(|| traced(r, batch, count));
    Ok(Measured {
        interference,
        ..result?
    })
}

/// `batch` traced once (without the scheduler's account).
fn traced(r: &dyn TimedRenderer, batch: &RayBatch, count: bool) -> Result<Measured> {
    let (ids, t, counters, phases) = if batch.any_hit {
        let (occluded, counters, phases) = r.occlude_rays_timed(&batch.rays, count)?;
        let ids = occluded
            .iter()
            .map(|&o| if o { OCCLUDED } else { NO_HIT })
            .collect();
        let t = occluded
            .iter()
            .map(|&o| if o { 0.0 } else { f32::INFINITY })
            .collect();
        (ids, t, counters, phases)
    } else {
        let (hits, counters, phases) = r.trace_rays_timed(&batch.rays, count)?;
        let ids = hits.iter().map(|h| h.map_or(NO_HIT, |h| h.prim)).collect();
        let t = hits
            .iter()
            .map(|h| h.map_or(f32::INFINITY, |h| h.t))
            .collect();
        (ids, t, counters, phases)
    };
    Ok(Measured {
        seconds: timed_seconds(&phases),
        phases,
        ids,
        t,
        rays: batch.rays.len() as u64,
        counters,
        color: None,
        interference: None,
    })
}

/// Each ray's own work: every ray of `rays` traced alone (a batch of one, through
/// [`raybench_core::Renderer::trace_rays`], or [`raybench_core::Renderer::occlude_rays`] for
/// `any_hit`) with a fresh count, in the order of `rays`; `None` where the backend does not
/// count. Untimed, for per-ray cost distributions: never call it inside a timed pass.
///
/// A ray traced alone does the work it does in a batch wherever the structure's batch entry
/// point walks ray by ray; a packet traversal shares node visits between the rays of a
/// packet. A caller that reads these counts as a batch's work split by ray checks first that
/// they add up to the batch's counters. The rays are spread over the machine's threads in
/// contiguous chunks (each batch of one runs on its caller's thread), so the counts do not
/// depend on the thread count.
///
/// # Errors
/// When tracing fails (not prepared, or a backend that traces only whole frames).
pub fn counts_per_ray(
    r: &dyn TimedRenderer,
    rays: &[Ray],
    any_hit: bool,
) -> Result<Option<Vec<RayCounters>>> {
    let one = |ray: &Ray| -> Result<Option<RayCounters>> {
        let ray = std::slice::from_ref(ray);
        Ok(if any_hit {
            r.occlude_rays(ray, true)?.1
        } else {
            r.trace_rays(ray, true)?.1
        })
    };
    let threads = std::thread::available_parallelism().map_or(1, usize::from);
    let chunk = rays.len().div_ceil(threads).max(1);
    let parts: Vec<Result<Option<Vec<RayCounters>>>> = std::thread::scope(|scope| {
        let handles: Vec<_> = rays
            .chunks(chunk)
            .map(|part| scope.spawn(move || part.iter().map(one).collect()))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect()
    });
    let mut out = Vec::with_capacity(rays.len());
    for part in parts {
        match part? {
            Some(counts) => out.extend(counts),
            None => return Ok(None),
        }
    }
    Ok(Some(out))
}

/// The seconds a measurement reports: phase `render`, the wall-clock time of the whole call,
/// for every backend. A GPU's execution time alone (phase `gpu`) stays among the phases: a
/// user waits for the whole call, and on a software adapter the two differ most.
#[must_use]
pub fn timed_seconds(phases: &Timings) -> f64 {
    phases.get("render").unwrap_or(0.0)
}

/// The seconds a measurement's device spent executing (phase `gpu`), for a backend on
/// another device.
#[must_use]
pub fn device_seconds(phases: &Timings) -> Option<f64> {
    phases.get("gpu")
}

/// A renderer prepared for a scene.
pub struct Prepared {
    /// The renderer.
    pub renderer: Box<dyn TimedRenderer>,
    /// Seconds of preparation, all phases.
    pub build: f64,
    /// The phases (`build`; a GPU backend adds `upload`).
    pub phases: Timings,
}

/// A fresh renderer of `b`, prepared for `scene`, with its preparation time.
///
/// # Errors
/// Why the backend cannot run or cannot render the scene.
pub fn prepare(b: &Backend, scene: &Arc<Scene>) -> Result<Prepared, String> {
    let mut r = (b.make)();
    r.availability()?;
    r.supports(scene)?;
    let phases = r.prepare(scene).map_err(|e| e.to_string())?;
    let build = phases.0.iter().map(|(_, s)| s).sum();
    Ok(Prepared {
        renderer: r,
        build,
        phases,
    })
}

/// [`prepare`], and a check that the prepared renderer can render `mode` (a GPU may lack
/// one): what `compare` and `info` run before measuring.
///
/// # Errors
/// Why the backend cannot run, cannot render the scene, or lacks the mode.
pub fn prepare_for_mode(
    b: &Backend,
    scene: &Arc<Scene>,
    mode: raybench_core::Mode,
) -> Result<Prepared, String> {
    let p = prepare(b, scene)?;
    p.renderer.supports_mode(mode)?;
    Ok(p)
}

/// The median of each phase over several measurements, in the order of the first.
#[must_use]
pub fn median_phases(runs: &[Timings]) -> Timings {
    let mut out = Timings::default();
    if let Some(first) = runs.first() {
        for (name, _) in &first.0 {
            out.push(
                name.clone(),
                median(runs.iter().filter_map(|t| t.get(name)).collect()),
            );
        }
    }
    out
}

/// The median (mean of the middle two for an even count); 0 for none.
#[must_use]
pub fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if !n.is_multiple_of(2) {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}
