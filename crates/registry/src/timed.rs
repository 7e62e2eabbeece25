//! The harness's side of a renderer: ray batches with the timing of their phases, and the
//! device a backend runs on. Core's [`Renderer`] is what an integrator needs and holds no
//! clock; this trait adds what `raybench report`, `backends` and the benches measure.

use raybench_core::{Accel, Hit, Ray, RayCounters, RenderError, Renderer, Timings};
use raybench_render::CpuRenderer;
use raybench_wgpu::WgpuRenderer;
use std::time::Instant;

/// What [`TimedRenderer::trace_rays_timed`] returns: a closest hit per ray, the work
/// counters when counted, and the timing phases.
pub type TracedRays = (Vec<Option<Hit>>, Option<RayCounters>, Timings);

/// What [`TimedRenderer::occlude_rays_timed`] returns: per ray whether anything lies in its
/// interval, the work counters when counted, and the timing phases.
pub type OccludedRays = (Vec<bool>, Option<RayCounters>, Timings);

/// A [`Renderer`] as the harness times it. Every registered backend is one
/// ([`crate::Backend::make`]); a `Box<dyn TimedRenderer>` is used wherever a
/// `&dyn Renderer` is wanted.
pub trait TimedRenderer: Renderer {
    /// The device the backend runs on, when it is not this machine's CPU (a GPU adapter's
    /// name, type and driver), for `raybench backends` and the report's machine section.
    fn device(&self) -> Option<String> {
        None
    }

    /// [`Renderer::trace_rays`] with the timing of its phases, named as a frame's
    /// [`raybench_core::Frame::timings`] are. The default times the whole call as `render`;
    /// a backend on another device splits it into `upload`, `gpu` (execution) and
    /// `readback`.
    ///
    /// # Errors
    /// As [`Renderer::trace_rays`].
    fn trace_rays_timed(&self, rays: &[Ray], count: bool) -> Result<TracedRays, RenderError> {
        timed(|| self.trace_rays(rays, count))
    }

    /// [`Renderer::occlude_rays`] with the timing of its phases, as
    /// [`TimedRenderer::trace_rays_timed`].
    ///
    /// # Errors
    /// As [`Renderer::trace_rays`].
    fn occlude_rays_timed(&self, rays: &[Ray], count: bool) -> Result<OccludedRays, RenderError> {
        timed(|| self.occlude_rays(rays, count))
    }
}

/// Runs `call` and records its wall-clock time as the `render` phase.
fn timed<T>(
    call: impl FnOnce() -> Result<(Vec<T>, Option<RayCounters>), RenderError>,
) -> Result<(Vec<T>, Option<RayCounters>, Timings), RenderError> {
    let start = Instant::now();
    let (answers, counters) = call()?;
    let mut timings = Timings::default();
    timings.push("render", start.elapsed().as_secs_f64());
    Ok((answers, counters, timings))
}

/// The CPU backends: timed by the wall clock around the whole call, on this machine's CPU.
impl<A: Accel> TimedRenderer for CpuRenderer<A> {}

/// The GPU backends: the adapter's description, and batches split into `upload`, `gpu`
/// (timestamp queries where the adapter has them) and `readback`.
impl TimedRenderer for WgpuRenderer {
    fn device(&self) -> Option<String> {
        self.adapter()
    }

    fn trace_rays_timed(&self, rays: &[Ray], count: bool) -> Result<TracedRays, RenderError> {
        self.trace_rays_phased(rays, count)
    }

    fn occlude_rays_timed(&self, rays: &[Ray], count: bool) -> Result<OccludedRays, RenderError> {
        self.occlude_rays_phased(rays, count)
    }
}
