//! Experiment `pixels`: render time against the pixel count N^2 of the built-in scene whose
//! `[benchmark]` table names it (the bunny), camera rays.

use super::{Ctx, Point, Scaling, scene_for, square};
use raybench_core::Mode;

/// Experiment `pixels`.
pub(super) struct Pixels;

impl Scaling for Pixels {
    type State = ();

    fn name(&self) -> &'static str {
        "pixels"
    }

    fn x_label(&self) -> &'static str {
        "pixels N^2"
    }

    fn axis(&self) -> Option<&'static str> {
        Some("the pixel count N^2 (bunny)")
    }

    fn points(&self, ctx: &Ctx) -> Result<Vec<Point>, String> {
        let scene = scene_for(self.name())?;
        let sides: &[u32] = if ctx.opts.quick {
            &[64, 128, 256, 512]
        } else {
            &[64, 128, 256, 512, 1024]
        };
        Ok(sides
            .iter()
            .map(|&n| Point {
                series: scene.into(),
                x: f64::from(n * n),
                spec: scene.into(),
                workload: square(n, 1, Mode::Cast),
            })
            .collect())
    }
}
