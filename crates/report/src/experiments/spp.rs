//! Experiment `spp`: path-tracing time against the samples per pixel K, 64 x 64, on the
//! built-in scene whose `[benchmark]` table names it (the Cornell box).

use super::{Ctx, Point, Scaling, scene_points, square};
use raybench_core::Mode;

/// Experiment `spp`.
pub(super) struct Spp;

impl Scaling for Spp {
    type State = ();

    fn name(&self) -> &'static str {
        "spp"
    }

    fn x_label(&self) -> &'static str {
        "samples per pixel (K)"
    }

    fn axis(&self) -> Option<&'static str> {
        Some("the samples per pixel K (Cornell box, path tracing, 64 x 64)")
    }

    fn points(&self, ctx: &Ctx) -> Result<Vec<Point>, String> {
        let ks: &[u32] = if ctx.opts.quick {
            &[1, 2, 4, 8, 16]
        } else {
            &[1, 2, 4, 8, 16, 32, 64]
        };
        scene_points(self.name(), ks, |k| {
            (f64::from(k), square(64, k, Mode::Path))
        })
    }
}
