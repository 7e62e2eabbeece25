//! How a frame is split into dispatches: bands of rows that fit the output buffer, regions
//! of rows small enough for one dispatch, and sample ranges, so that no dispatch runs long
//! enough to trip a driver's watchdog (about two seconds on desktop drivers) and path
//! tracing accumulates progressively.

use raybench_core::Mode;

/// Pixels are traced in square blocks of this side, one 64-thread workgroup per block.
pub const BLOCK: u32 = 8;

/// Work budget of one dispatch, in pixel samples: about 4 million primary rays, or a
/// million Whitted or path-traced samples (a few rays each). On an H100 a dispatch then
/// takes milliseconds; on lavapipe (one CPU thread's speed) a few seconds.
#[must_use]
pub fn budget(mode: Mode) -> u64 {
    match mode {
        Mode::Cast | Mode::Mip | Mode::Composite => 1 << 22,
        Mode::Whitted | Mode::Path => 1 << 20,
    }
}

/// Samples one thread traces in one dispatch, at most. Besides keeping dispatches short,
/// this keeps each thread's loops short: Mesa's lavapipe (llvmpipe) stops a shader's loop
/// nest after 65,535 iterations in all (gallivm's `LP_MAX_TGSI_LOOP_ITERATIONS`), and a
/// thread looping over thousands of samples, each with its traversal loops, silently lost
/// samples (measured: 8 x 8 pixels at 1,000 path-traced samples traced 78% of the rays;
/// at 4,000, 28%).
pub const MAX_SAMPLES_PER_DISPATCH: u32 = 4;

/// Samples one thread traces in one dispatch on an adapter of `device_type`
/// ([`frame`]'s `max_samples`): [`MAX_SAMPLES_PER_DISPATCH`] on a GPU, one on a software
/// adapter. lavapipe's cap counts a loop's iterations over the whole invocation, and the
/// iterative primitives (the torus quartic's bracketing and Newton loops, CSG event walks,
/// SDF sphere tracing) spend hundreds per ray: path tracing the built-in `quadrics` at 128 x
/// 128, 4 samples in one dispatch and 4 bounces traced 292,253 rays against naive's 294,546
/// and 536 pixels differed (paths bouncing inside the torus' hole); one sample per dispatch
/// traced 294,543, 4 pixels differing (f32 against the CPU's f64 torus). What remains
/// is a single sample whose loops pass the cap (a path through trees far larger than the
/// built-in scenes'), which lavapipe still cuts short; GPUs have no such cap.
#[must_use]
pub fn max_samples(device_type: wgpu::DeviceType) -> u32 {
    if device_type == wgpu::DeviceType::Cpu {
        1
    } else {
        MAX_SAMPLES_PER_DISPATCH
    }
}

/// One dispatch: rows `[y0, y0 + rows)` and samples `[s0, s1)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Dispatch {
    /// First row.
    pub y0: u32,
    /// Rows.
    pub rows: u32,
    /// First sample.
    pub s0: u32,
    /// One past the last sample.
    pub s1: u32,
    /// Workgroups to launch.
    pub workgroups: u32,
}

/// Rows `[y0, y0 + rows)` held by the output buffer at once, and their dispatches.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Band {
    /// First row.
    pub y0: u32,
    /// Rows.
    pub rows: u32,
    /// Dispatches, region by region, samples in order within a region.
    pub dispatches: Vec<Dispatch>,
}

/// Splits a `width x height` frame of `spp` samples into bands of at most `band_pixels`
/// pixels and dispatches of at most `budget` pixel samples (at least one 8-row strip and
/// one sample), `max_samples` samples per pixel ([`max_samples`]) and `max_workgroups`
/// workgroups.
#[must_use]
pub fn frame(
    width: u32,
    height: u32,
    spp: u32,
    budget: u64,
    band_pixels: u64,
    max_samples: u32,
    max_workgroups: u32,
) -> Vec<Band> {
    let width = width.max(1);
    let blocks_per_row = width.div_ceil(BLOCK);
    let strip = u64::from(width) * u64::from(BLOCK);
    let strips = |limit: u64| (limit / strip).clamp(1, u64::from(u32::MAX / BLOCK)) as u32;
    let band_rows = strips(band_pixels) * BLOCK;
    let region_rows = strips(budget)
        .min((max_workgroups / blocks_per_row).max(1))
        .min(band_rows / BLOCK)
        * BLOCK;
    let mut bands = Vec::new();
    for band_y0 in (0..height).step_by(band_rows as usize) {
        let band_end = (band_y0 + band_rows).min(height);
        let mut dispatches = Vec::new();
        for y0 in (band_y0..band_end).step_by(region_rows as usize) {
            let rows = region_rows.min(band_end - y0);
            let pixels = u64::from(rows) * u64::from(width);
            let per = (budget / pixels).clamp(1, u64::from(spp.min(max_samples).max(1))) as u32;
            for s0 in (0..spp).step_by(per as usize) {
                dispatches.push(Dispatch {
                    y0,
                    rows,
                    s0,
                    s1: (s0 + per).min(spp),
                    workgroups: blocks_per_row * rows.div_ceil(BLOCK),
                });
            }
        }
        bands.push(Band {
            y0: band_y0,
            rows: band_end - band_y0,
            dispatches,
        });
    }
    bands
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every (pixel row, sample) pair is covered exactly once, within the limits.
    fn check(width: u32, height: u32, spp: u32, budget: u64, band: u64, wg: u32) {
        let bands = frame(
            width,
            height,
            spp,
            budget,
            band,
            MAX_SAMPLES_PER_DISPATCH,
            wg,
        );
        let mut cover = vec![0u32; (height * spp) as usize];
        let mut next_band = 0;
        for b in &bands {
            assert_eq!(b.y0, next_band);
            next_band = b.y0 + b.rows;
            assert!(u64::from(b.rows) * u64::from(width) <= band.max(u64::from(width * BLOCK)));
            for d in &b.dispatches {
                assert!(d.y0 >= b.y0 && d.y0 + d.rows <= b.y0 + b.rows);
                assert!(d.workgroups <= wg.max(width.div_ceil(BLOCK)));
                assert!(d.s0 < d.s1 && d.s1 <= spp);
                let work = u64::from(d.rows) * u64::from(width) * u64::from(d.s1 - d.s0);
                assert!(work <= budget || (d.rows <= BLOCK && d.s1 - d.s0 == 1));
                for y in d.y0..d.y0 + d.rows {
                    for s in d.s0..d.s1 {
                        cover[(y * spp + s) as usize] += 1;
                    }
                }
            }
        }
        assert_eq!(next_band, height);
        assert!(cover.iter().all(|&c| c == 1));
    }

    #[test]
    fn plans_cover_every_pixel_sample_once() {
        check(512, 512, 1, budget(Mode::Cast), 1 << 24, 65_535);
        check(1024, 1024, 64, budget(Mode::Path), 1 << 24, 65_535);
        check(37, 21, 5, 100, 1 << 24, 65_535);
        check(37, 21, 5, 100, 300, 65_535);
        check(1, 1, 1, 1, 1, 1);
        check(16_384, 40, 3, 1 << 20, 1 << 16, 100);
        check(100, 9, 7, 1 << 30, 1 << 30, 65_535);
    }

    #[test]
    fn small_frames_are_one_dispatch() {
        let bands = frame(128, 128, 4, budget(Mode::Path), 1 << 24, 4, 65_535);
        assert_eq!(bands.len(), 1);
        assert_eq!(bands[0].dispatches.len(), 1);
        assert_eq!(bands[0].dispatches[0].workgroups, 16 * 16);
    }

    #[test]
    fn software_adapters_trace_one_sample_per_dispatch() {
        assert_eq!(max_samples(wgpu::DeviceType::Cpu), 1);
        assert_eq!(
            max_samples(wgpu::DeviceType::DiscreteGpu),
            MAX_SAMPLES_PER_DISPATCH
        );
        let bands = frame(128, 128, 4, budget(Mode::Path), 1 << 24, 1, 65_535);
        let samples: Vec<_> = bands[0].dispatches.iter().map(|d| (d.s0, d.s1)).collect();
        assert_eq!(samples, [(0, 1), (1, 2), (2, 3), (3, 4)]);
    }
}
