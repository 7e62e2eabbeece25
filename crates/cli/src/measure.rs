//! Measuring one workload with one backend: the shared core of `compare`, `info` and
//! `report`.

use crate::Backend;
use anyhow::{Result, bail};
use raybench_core::{
    NO_HIT, Ray, RayCounters, RaySet, RenderSettings, Renderer, Scene, Timings, limits,
};
use std::sync::Arc;

/// Seed of the incoherent ray set (the same rays in every run and in the benches).
pub const INCOHERENT_SEED: u32 = 1;

/// The rays a ray set traces explicitly: `None` for primary rays (frames are rendered),
/// `width x height` seeded incoherent rays otherwise.
///
/// # Errors
/// When the ray count exceeds [`limits::MAX_EXPLICIT_RAYS`].
pub fn explicit_rays(
    set: RaySet,
    scene: &Scene,
    settings: &RenderSettings,
) -> Result<Option<Vec<Ray>>> {
    let count = u64::from(settings.width) * u64::from(settings.height);
    match set {
        RaySet::Primary => Ok(None),
        RaySet::Incoherent if count > limits::MAX_EXPLICIT_RAYS => bail!(
            "{count} incoherent rays exceed the limit of {} (use a smaller --width x --height)",
            limits::MAX_EXPLICIT_RAYS
        ),
        RaySet::Incoherent => Ok(Some(raybench_core::ray_sets::incoherent(
            scene.geometry.bounds(),
            count as usize,
            INCOHERENT_SEED,
        ))),
    }
}

/// One measured workload: per-ray ids and `t`, rays traced, counters, seconds.
#[derive(Clone)]
pub struct Measured {
    /// Primitive id per ray or pixel ([`NO_HIT`] for misses).
    pub ids: Vec<u32>,
    /// `t` per ray or pixel (infinity for misses).
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
}

/// Renders a frame (primary rays) or traces the given rays (incoherent) once.
///
/// # Errors
/// When rendering or tracing fails.
pub fn measure(
    r: &dyn Renderer,
    settings: &RenderSettings,
    rays: Option<&[Ray]>,
    count: bool,
) -> Result<Measured> {
    let settings = RenderSettings { count, ..*settings };
    match rays {
        None => {
            let f = r.render(&settings)?;
            Ok(Measured {
                seconds: timed_seconds(&f.timings),
                phases: f.timings,
                rays: f.stats.rays,
                counters: f.stats.counters,
                ids: f.ids,
                t: f.t,
                color: Some(f.color),
            })
        }
        Some(rays) => {
            let (hits, counters, phases) = r.trace_rays_timed(rays, count)?;
            Ok(Measured {
                seconds: timed_seconds(&phases),
                phases,
                ids: hits.iter().map(|h| h.map_or(NO_HIT, |h| h.prim)).collect(),
                t: hits
                    .iter()
                    .map(|h| h.map_or(f32::INFINITY, |h| h.t))
                    .collect(),
                rays: rays.len() as u64,
                counters,
                color: None,
            })
        }
    }
}

/// The seconds a measurement reports: phase `gpu` (execution on the device) when the
/// backend has one, else `render` (the whole call).
#[must_use]
pub fn timed_seconds(phases: &Timings) -> f64 {
    phases
        .get("gpu")
        .or_else(|| phases.get("render"))
        .unwrap_or(0.0)
}

/// A renderer prepared for a scene.
pub struct Prepared {
    /// The renderer.
    pub renderer: Box<dyn Renderer>,
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
