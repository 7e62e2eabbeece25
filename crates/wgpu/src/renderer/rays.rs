//! Explicit rays on the device: closest and any hits of a ray batch in chunks that fit a
//! dispatch and the output buffer, with the `upload`, `gpu` and `readback` phases.

use super::{Batches, WgpuRenderer, buffer, gpu};
use crate::data::{OCCLUDE_ENTRY, entry_point};
use crate::plan;
use crate::records::{GpuOut, GpuRay, Params};
use raybench_core::{
    Hit, Mode, NO_HIT, PrimHit, Ray, RayCounters, RenderError, RenderSettings, Timings, limits,
};
use std::time::Instant;

/// An answer per ray of an explicit batch, the work counters when counted, and the
/// `upload`, `gpu` and `readback` phases.
pub type Phased<T> = (Vec<T>, Option<RayCounters>, Timings);

impl WgpuRenderer {
    /// The adapter's name, type and driver, when one can be had.
    #[must_use]
    pub fn adapter(&self) -> Option<String> {
        gpu(&self.request).ok().map(|g| g.describe())
    }

    /// Any hit through the any-hit kernel (`occlude_kernel`: the traversal stops at the
    /// first hit), with `upload`, `gpu` and `readback` phases.
    ///
    /// # Errors
    /// As [`Renderer::trace_rays`].
    pub fn occlude_rays_phased(
        &self,
        rays: &[Ray],
        count: bool,
    ) -> Result<Phased<bool>, RenderError> {
        let mut blocked = Vec::with_capacity(rays.len());
        let (counters, timings) = self.explicit_rays(rays, count, OCCLUDE_ENTRY, |o, _| {
            blocked.push(o.id != NO_HIT)
        })?;
        Ok((blocked, counters, timings))
    }

    /// Closest hits of `rays` through the closest-hit kernel, with `upload`, `gpu` and
    /// `readback` phases.
    ///
    /// # Errors
    /// As [`Renderer::trace_rays`].
    pub fn trace_rays_phased(
        &self,
        rays: &[Ray],
        count: bool,
    ) -> Result<Phased<Option<Hit>>, RenderError> {
        let p = self.prepared.as_ref().ok_or(RenderError::NotPrepared)?;
        let entry = entry_point(None).map_err(RenderError::Unsupported)?;
        let g = &p.scene.geometry;
        let mut hits = Vec::with_capacity(rays.len());
        let (counters, timings) = self.explicit_rays(rays, count, entry, |o, ray| {
            hits.push(g.complete_global(
                ray,
                (o.id != NO_HIT).then_some((
                    o.id,
                    PrimHit {
                        t: o.v[0],
                        sub: o.sub,
                        u: o.v[1],
                        v: o.v[2],
                    },
                )),
            ));
        })?;
        Ok((hits, counters, timings))
    }

    /// Runs kernel `entry` on explicit `rays` in chunks that fit a dispatch and the output
    /// buffer, handing each ray's output record to `each` in order; returns the counters and
    /// the `upload`, `gpu`, `readback` and `render` phases.
    fn explicit_rays(
        &self,
        rays: &[Ray],
        count: bool,
        entry: &'static str,
        mut each: impl FnMut(&GpuOut, &Ray),
    ) -> Result<(Option<RayCounters>, Timings), RenderError> {
        let p = self.prepared.as_ref().ok_or(RenderError::NotPrepared)?;
        if rays.len() as u64 > limits::MAX_EXPLICIT_RAYS {
            return Err(RenderError::InvalidSettings(format!(
                "{} rays exceed the limit of {}",
                rays.len(),
                limits::MAX_EXPLICIT_RAYS
            )));
        }
        let _frame = p.frame_lock.lock().unwrap_or_else(|e| e.into_inner());
        let start = Instant::now();
        let gpu = &p.gpu;
        let pipeline = p
            .kernels
            .pipeline(gpu, entry, count, self.layout, p.features)?;
        let out_size = std::mem::size_of::<GpuOut>() as u64;
        let per_dispatch = u64::from(gpu.limits.max_compute_workgroups_per_dimension) * 64;
        let chunk = (Self::binding_limit(gpu) / out_size)
            .min(per_dispatch)
            .min(plan::budget(Mode::Cast))
            .max(1) as usize;

        let upload_start = Instant::now();
        let base = p.data.params(&p.scene, &RenderSettings::default())?;
        let chunks: Vec<&[Ray]> = rays.chunks(chunk).collect();
        let params: Vec<Params> = chunks
            .iter()
            .map(|c| Params {
                ray_count: c.len() as u32,
                ..base
            })
            .collect();
        let (params_buf, stride) = p.upload_params(&params);
        let max_len = chunks.first().map_or(0, |c| c.len()) as u64;
        let rays_buf = buffer(
            gpu,
            "rays",
            max_len * 32,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        let out = buffer(
            gpu,
            "hits",
            max_len * out_size,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let counters = p.counters_buffer();
        let f = Batches::new(
            p,
            &pipeline,
            &params_buf,
            stride,
            &rays_buf,
            &out,
            &counters,
        );
        let mut upload = upload_start.elapsed().as_secs_f64();

        let (mut gpu_seconds, mut readback) = (0.0, 0.0);
        for (slot, c) in chunks.iter().enumerate() {
            let up = Instant::now();
            let packed: Vec<GpuRay> = c
                .iter()
                .map(|r| GpuRay {
                    o: [r.origin.x, r.origin.y, r.origin.z, r.t_min],
                    d: [r.dir.x, r.dir.y, r.dir.z, r.t_max],
                })
                .collect();
            gpu.queue
                .write_buffer(&rays_buf, 0, bytemuck::cast_slice(&packed));
            upload += up.elapsed().as_secs_f64();
            let workgroups = (c.len() as u32).div_ceil(64);
            gpu_seconds += f.run(&[(slot as u64, workgroups)])?;
            let read_start = Instant::now();
            f.fetch(&out, c.len() as u64 * out_size, |bytes| {
                let outs: &[GpuOut] = bytemuck::cast_slice(bytes);
                for (o, ray) in outs.iter().zip(c.iter()) {
                    each(o, ray);
                }
            })?;
            readback += read_start.elapsed().as_secs_f64();
        }
        let (_, counted) = p.read_counters(&f, count)?;
        let mut timings = Timings::default();
        timings.push("upload", upload);
        timings.push("gpu", gpu_seconds);
        timings.push("readback", readback);
        timings.push("render", start.elapsed().as_secs_f64());
        Ok((counted, timings))
    }
}
