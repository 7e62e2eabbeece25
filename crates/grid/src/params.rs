//! The grid's construction parameters.

/// Grid construction parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridParams {
    /// Cells per axis are about `lambda * M^(1/3)` for `M` primitives in a cubic box (about
    /// `lambda^3` cells per primitive).
    pub lambda: f32,
    /// Largest number of cells.
    pub max_cells: usize,
    /// Whether triangles spanning several cells skip the cells they certainly miss
    /// (separating-axis test). Measured (512x512 primary rays, 2 threads): Sponza 45.7
    /// instead of 52.7 tests per ray and 1.18x the throughput, the 100k-triangle soup 1.19x,
    /// the bunny 1.08x; builds take 5x to 9x longer (Sponza 47 ms instead of 5.5 ms).
    pub clip_triangles: bool,
    /// Rays whose origin lies farther than this many grid sizes from the grid's centre
    /// skip the grid for the exact fallback (the unbounded primitives alone when the ray
    /// misses the grid's primitives' box, otherwise every one); the insertion padding's floor
    /// grows with it (`far_origin * 16 * 2^-23` of the grid's size, [`crate::FAR_ORIGIN`]).
    /// [`crate::FAR_ORIGIN`] for a scene; [`crate::INSTANCE_FAR_ORIGIN`] for the meshes
    /// instances place (`Accel::for_instances`).
    pub far_origin: f32,
}

impl GridParams {
    /// The default: `lambda = 1.25` (about two cells per primitive), at most 2^24 cells
    /// (64 MiB of offsets).
    #[must_use]
    pub fn medium() -> Self {
        Self {
            lambda: 1.25,
            max_cells: 1 << 24,
            clip_triangles: true,
            far_origin: crate::FAR_ORIGIN,
        }
    }

    /// The default without the triangle/box test: the fastest build.
    #[must_use]
    pub fn fast_build() -> Self {
        Self {
            clip_triangles: false,
            ..Self::medium()
        }
    }

    /// Coarser and cheaper: `lambda = 0.8` (about half a cell per primitive).
    #[must_use]
    pub fn coarse() -> Self {
        Self {
            lambda: 0.8,
            ..Self::medium()
        }
    }

    /// Finer: `lambda = 2` (eight cells per primitive).
    #[must_use]
    pub fn fine() -> Self {
        Self {
            lambda: 2.0,
            ..Self::medium()
        }
    }
}

impl Default for GridParams {
    fn default() -> Self {
        Self::medium()
    }
}
