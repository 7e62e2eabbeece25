//! Experiment `spp`: path-tracing time against the samples per pixel K, 64 x 64, on the
//! built-in scene whose `[benchmark]` table names it (the Cornell box).

use super::{About, SceneSweep, square};
use raybench_core::Mode;

/// Experiment `spp`.
pub(super) const SPP: SceneSweep = SceneSweep {
    about: About {
        name: "spp",
        x_label: "samples per pixel (K)",
        axis: Some("the samples per pixel K (Cornell box, path tracing, 64 x 64)"),
    },
    quick: &[1, 2, 4, 8, 16],
    full: &[1, 2, 4, 8, 16, 32, 64],
    at: |k| (f64::from(k), square(64, k, Mode::Path)),
};
