//! Experiment `pixels`: render time against the pixel count N^2 of the built-in scene whose
//! `[benchmark]` table names it (the bunny), camera rays.

use super::{Ctx, Point, Scaling, scene_points, square};
use raybench_core::Mode;

/// Experiment `pixels`.
pub(super) struct Pixels;

impl Scaling for Pixels {
    type State = ();

    fn name(&self) -> &'static str {
        "pixels"
    }

    fn x_label(&self) -> &'static str {
        "pixels per image (N²)"
    }

    fn axis(&self) -> Option<&'static str> {
        Some("the pixel count N^2 (bunny)")
    }

    fn points(&self, ctx: &Ctx) -> Result<Vec<Point>, String> {
        let sides: &[u32] = if ctx.opts.quick {
            &[64, 128, 256, 512]
        } else {
            &[64, 128, 256, 512, 1024]
        };
        scene_points(self.name(), sides, |n| {
            (f64::from(n * n), square(n, 1, Mode::Cast))
        })
    }
}
