//! # raybench-grid
//!
//! The lecture's "ray marching": a uniform grid over the scene's box, walked cell by cell
//! with the 3D-DDA of Amanatides and Woo ("A Fast Voxel Traversal Algorithm for Ray
//! Tracing", Eurographics 1987); only the primitives listed in the cells the ray crosses
//! are tested.
//!
//! - **Resolution** ([`GridParams`]): about `lambda * M^(1/3)` cells per axis, scaled to the
//!   box's aspect (`n_i = lambda * e_i * cbrt(M / V)`, so about `lambda^3 M` cells), total
//!   capped at `max_cells`, and coarsened while the cell lists would exceed
//!   [`MAX_REFERENCES_PER_PRIMITIVE`] entries per primitive (primitives that span many cells,
//!   such as long thin triangles, would otherwise make the lists quadratic).
//! - **Storage**: one flat array of primitive ids and one of per-cell offsets (compressed
//!   rows), no `Vec` per cell.
//! - **Insertion**: each primitive goes into every cell its box, padded by `PAD` (the
//!   larger of 1/4096 of a cell and 2^-16 of the grid's size, [`pad_of_size`]; 2^-12 for
//!   the meshes instances place), overlaps. The padding makes insertion conservative
//!   against the DDA's rounding: a ray that passes through a cell corner visits three of
//!   the four cells around it, and any primitive near that corner is also listed in the
//!   visited ones; and the DDA's positions, off by a few ulps of the ray origin's distance
//!   to the grid, stay within the padding for rays starting less than [`FAR_ORIGIN`] grid
//!   sizes away ([`INSTANCE_FAR_ORIGIN`] for instanced meshes). Rays starting farther away
//!   (a camera 10 km from a 1 mm scene) cannot be located in the grid to f32 precision:
//!   they skip the grid and stay exact: a ray that misses the box of the bounded
//!   primitives (the slab test the tree backends trust at any distance) tests only the
//!   unbounded ones, any other every primitive
//!   (`raybench_geometry::Geometry::closest_unplaced`).
//! - **Traversal**: enter from outside (conservative slab test) or start inside; one
//!   comparison per axis per step; zero direction components never step; crossing
//!   distances recomputed from cell boundaries (no drift). The walk stops only when the
//!   best hit lies before the current cell's exit (with the contract's slack), since a
//!   primitive spanning several cells may be hit beyond the cell where it was first met.
//! - **Mailboxing**: a per-ray ring of the last [`MAILBOX`] primitive ids tested, so a
//!   primitive spanning consecutive cells is tested once; it lives on the stack of the
//!   query, so it is safe under rayon. The test counter shows the saving.
//! - Unbounded primitives (planes) are tested beside the grid; any-hit queries stop at the
//!   first hit.

use raybench_geometry::{Aabb, Geometry, Vec3};
use std::sync::Arc;

mod build;
mod params;
mod traverse;
mod two_level;

pub use build::triangle_may_touch_box;
pub use params::GridParams;
pub use two_level::{TwoLevelGrid, TwoLevelParams};

/// Size of the per-ray mailbox (recently tested primitive ids).
pub const MAILBOX: usize = 8;

/// Rays whose origin lies farther than this many grid sizes from the grid's centre skip
/// the DDA for the exact fallback (see the crate documentation): the default
/// [`GridParams::far_origin`]. The DDA's positions are off by up to about 16 ulps of the
/// origin's distance to the grid, so the insertion padding's floor is `far_origin * 16 *
/// 2^-23` of the grid's size ([`pad_of_size`]): `2^-16` here.
pub const FAR_ORIGIN: f32 = 8.0;

/// [`GridParams::far_origin`] of a grid over a mesh that instances place
/// (`Accel::for_instances`): an instance's rays start in its mesh's space as many of the
/// mesh's sizes away as the camera is (7 to 30 on `bunny-field`). Its padding floor,
/// `2^-12` of the grid's size (a sixty-fourth of a cell at 64 cells per axis), would cost a
/// scene's grid up to 11 % more tests per ray (dabrovic-sponza), so only those meshes pay it.
pub const INSTANCE_FAR_ORIGIN: f32 = 128.0;

/// The insertion padding's floor relative to the grid's size for rays from up to
/// `far_origin` grid sizes away (see [`FAR_ORIGIN`]).
#[must_use]
pub fn pad_of_size(far_origin: f32) -> f32 {
    far_origin * 16.0 / 8_388_608.0
}

/// The cell lists are kept below this many entries per primitive (plus one per cell) by
/// coarsening the grid.
pub const MAX_REFERENCES_PER_PRIMITIVE: u64 = 16;
/// The uniform grid.
#[derive(Clone, Debug)]
pub struct Grid {
    geometry: Arc<Geometry>,
    /// The grid's box (the bounded primitives' box, padded).
    bounds: Aabb,
    /// Cells per axis (each at least 1; all 0 when empty).
    res: [u32; 3],
    /// Cell size per axis.
    cell: Vec3,
    /// `1 / cell`.
    inv_cell: Vec3,
    /// Insertion padding (per axis).
    pad: Vec3,
    /// `offsets[c]..offsets[c + 1]` indexes `ids` for cell `c = (z * ny + y) * nx + x`.
    offsets: Vec<u32>,
    /// Primitive ids, cell after cell.
    ids: Vec<u32>,
    /// The primitives this grid holds (all bounded ones, or a dense cell's for a sub-grid).
    prims: Vec<u32>,
    params: GridParams,
}
impl Grid {
    pub(crate) fn cell_index(&self, c: [u32; 3]) -> usize {
        (c[2] as usize * self.res[1] as usize + c[1] as usize) * self.res[0] as usize
            + c[0] as usize
    }

    /// Cells per axis.
    #[must_use]
    pub fn resolution(&self) -> [u32; 3] {
        self.res
    }

    /// The primitive ids listed in cell `(x, y, z)`.
    #[must_use]
    pub fn cell_ids(&self, c: [u32; 3]) -> &[u32] {
        let i = self.cell_index(c);
        &self.ids[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    /// The parameters it was built with.
    #[must_use]
    pub fn params(&self) -> &GridParams {
        &self.params
    }

    /// The grid's box (the bounded primitives' box, padded by 1/1024 of its size).
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The size of one cell.
    #[must_use]
    pub fn cell_size(&self) -> Vec3 {
        self.cell
    }
}

#[cfg(test)]
mod tests;
