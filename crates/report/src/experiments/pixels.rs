//! Experiment `pixels`: render time against the pixel count N^2 of the built-in scene whose
//! `[benchmark]` table names it (the bunny), camera rays.

use super::{About, SceneSweep, square};
use raybench_core::Mode;

/// Experiment `pixels`.
pub(super) const PIXELS: SceneSweep = SceneSweep {
    about: About {
        name: "pixels",
        x_label: "pixels per image (N²)",
        axis: Some("the pixel count N^2 (bunny)"),
    },
    quick: &[64, 128, 256, 512],
    full: &[64, 128, 256, 512, 1024],
    at: |n| (f64::from(n * n), square(n, 1, Mode::Cast)),
};
