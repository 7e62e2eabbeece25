//! Building a grid: its resolution from the primitive count and the box's aspect, then the
//! cell lists in two passes (count, fill), each primitive inserted into the cells its padded
//! box overlaps, triangles skipping the cells their plane and edges certainly miss.

use crate::{Grid, GridParams, MAX_REFERENCES_PER_PRIMITIVE};
use raybench_geometry::{Aabb, Geometry, Shape, Triangle, Vec3};
use std::sync::Arc;

impl Grid {
    /// Builds the grid over the bounded primitives of `geometry`.
    ///
    /// # Panics
    /// When the primitive references exceed `u32::MAX` (about 4 billion).
    #[must_use]
    pub fn build_with(geometry: Arc<Geometry>, params: GridParams) -> Self {
        let prims = geometry.bounded().to_vec();
        let gb = geometry.bounds();
        Self::build_over(geometry, prims, gb, params)
    }

    /// Builds a grid over `prims` (bounded primitive ids of `geometry`) inside `region`;
    /// primitives reaching outside it are listed in its border cells.
    pub(crate) fn build_over(
        geometry: Arc<Geometry>,
        prims: Vec<u32>,
        gb: Aabb,
        params: GridParams,
    ) -> Self {
        let empty = Self {
            geometry: Arc::clone(&geometry),
            bounds: Aabb::EMPTY,
            res: [0; 3],
            cell: Vec3::ONE,
            inv_cell: Vec3::ONE,
            pad: Vec3::ZERO,
            offsets: vec![0],
            ids: Vec::new(),
            prims,
            params,
        };
        if gb.is_empty() || !gb.extent().is_finite() || empty.prims.is_empty() {
            return empty;
        }
        let m = empty.prims.len() as f32;
        // Pad the box so flat scenes have volume and border primitives sit inside.
        let scale = gb
            .extent()
            .max_element()
            .max(gb.min.abs().max_element())
            .max(gb.max.abs().max_element());
        let pad = Vec3::splat(
            (gb.extent().max_element() * (1.0 / 1024.0))
                .max(scale * 1e-6)
                .max(1e-30),
        );
        let bounds = Aabb::new(gb.min - pad, gb.max + pad);
        let e = bounds.extent();
        let volume = f64::from(e.x) * f64::from(e.y) * f64::from(e.z);
        let k = f64::from(params.lambda.max(1e-3)) * (f64::from(m) / volume).cbrt();
        let mut n = [0u32; 3];
        for a in 0..3 {
            n[a] = ((f64::from(e[a]) * k).round() as u32).clamp(1, 1 << 16);
        }
        // Cap the total, shrinking every axis by the same factor.
        let total = |n: &[u32; 3]| u64::from(n[0]) * u64::from(n[1]) * u64::from(n[2]);
        let max_cells = params.max_cells.max(1) as u64;
        if total(&n) > max_cells {
            let f = (max_cells as f64 / total(&n) as f64).cbrt();
            for v in &mut n {
                *v = ((f64::from(*v) * f).floor() as u32).max(1);
            }
        }
        let mut grid = Self { bounds, ..empty };
        grid.set_resolution(n);
        // Coarsen while the cell lists would be too long.
        let budget = MAX_REFERENCES_PER_PRIMITIVE * grid.prims.len() as u64;
        while grid.res.iter().any(|&r| r > 1)
            && grid.count_references() > budget + grid.cell_count() as u64
        {
            let res = grid.res.map(|r| (r / 2).max(1));
            grid.set_resolution(res);
        }
        grid.insert();
        grid
    }

    fn cell_count(&self) -> usize {
        self.res.iter().map(|&r| r as usize).product()
    }

    /// Sets the resolution, with the cell size and padding that go with it.
    fn set_resolution(&mut self, res: [u32; 3]) {
        let e = self.bounds.extent();
        self.res = res;
        self.cell = e / Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32);
        self.inv_cell = self.cell.recip();
        self.pad = (self.cell * (1.0 / 4096.0)).max(Vec3::splat(
            e.max_element() * crate::pad_of_size(self.params.far_origin),
        ));
    }

    /// The number of cell-list entries the current resolution needs.
    fn count_references(&self) -> u64 {
        self.prims
            .iter()
            .map(|&id| {
                let b = self.geometry.shape(id).bounds().unwrap_or(Aabb::EMPTY);
                let (lo, hi) = self.cell_range(b);
                (0..3)
                    .map(|a| u64::from(hi[a] - lo[a] + 1))
                    .product::<u64>()
            })
            .sum()
    }

    /// Calls `f` with the index of every cell primitive `id` goes into: every cell of its
    /// box's range `[lo, hi]`, except that a triangle spanning several cells skips those its
    /// plane or edges certainly miss ([`triangle_may_touch_box`], with the cells padded like
    /// the insertion, so the listing stays conservative).
    fn cells_of(&self, id: u32, lo: [u32; 3], hi: [u32; 3], mut f: impl FnMut(usize)) {
        let triangle = match self.geometry.shape(id) {
            Shape::Triangle(t) if lo != hi && self.params.clip_triangles => Some(t),
            _ => None,
        };
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    if let Some(t) = triangle {
                        let min =
                            self.bounds.min + self.cell * Vec3::new(x as f32, y as f32, z as f32);
                        let pad =
                            self.pad + min.abs().max((min + self.cell).abs()) * (1.0 / 1_048_576.0);
                        let half = self.cell * 0.5 + pad;
                        if !triangle_may_touch_box(t, min + self.cell * 0.5, half) {
                            continue;
                        }
                    }
                    f(self.cell_index([x, y, z]));
                }
            }
        }
    }

    /// The cell range `[lo, hi]` (inclusive) a padded box overlaps.
    fn cell_range(&self, b: Aabb) -> ([u32; 3], [u32; 3]) {
        let pad = self.pad + b.min.abs().max(b.max.abs()) * (1.0 / 1_048_576.0);
        let lo = ((b.min - pad - self.bounds.min) * self.inv_cell).floor();
        let hi = ((b.max + pad - self.bounds.min) * self.inv_cell).floor();
        let clamp = |v: f32, a: usize| {
            if v.is_nan() {
                0
            } else {
                v.clamp(0.0, (self.res[a] - 1) as f32) as u32
            }
        };
        (
            [clamp(lo.x, 0), clamp(lo.y, 1), clamp(lo.z, 2)],
            [clamp(hi.x, 0), clamp(hi.y, 1), clamp(hi.z, 2)],
        )
    }

    /// Two passes over the primitives: count per cell, prefix sums, fill.
    fn insert(&mut self) {
        let cells = self.res.iter().map(|&r| r as usize).product::<usize>();
        let mut counts = vec![0u32; cells + 1];
        let ranges: Vec<(u32, [u32; 3], [u32; 3])> = self
            .prims
            .iter()
            .map(|&id| {
                let b = self.geometry.shape(id).bounds().unwrap_or(Aabb::EMPTY);
                let (lo, hi) = self.cell_range(b);
                (id, lo, hi)
            })
            .collect();
        for (id, lo, hi) in &ranges {
            self.cells_of(*id, *lo, *hi, |c| counts[c] += 1);
        }
        let mut offsets = vec![0u32; cells + 1];
        let mut sum = 0u64;
        for c in 0..cells {
            offsets[c] = u32::try_from(sum).expect("too many primitive references");
            sum += u64::from(counts[c]);
        }
        offsets[cells] = u32::try_from(sum).expect("too many primitive references");
        let mut fill = offsets.clone();
        let mut ids = vec![0u32; sum as usize];
        for (id, lo, hi) in &ranges {
            self.cells_of(*id, *lo, *hi, |c| {
                ids[fill[c] as usize] = *id;
                fill[c] += 1;
            });
        }
        self.offsets = offsets;
        self.ids = ids;
    }
}

/// Separating-axis test of a triangle against the box `center +- half` (Akenine-Moeller,
/// "Fast 3D Triangle-Box Overlap Testing", 2001): the box's axes are implied by the
/// caller's cell range; this tests the triangle's normal and the nine edge-axis cross
/// products. Conservative: an axis separates only when the gap exceeds a tolerance of
/// `2^-12` of the projected magnitudes, far above the rounding of these few products, so
/// a touching triangle is never dropped (a rejected cell costs nothing but speed if wrong
/// the other way).
#[must_use]
pub fn triangle_may_touch_box(t: &Triangle, center: Vec3, half: Vec3) -> bool {
    let v = [t.v[0] - center, t.v[1] - center, t.v[2] - center];
    let e = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    let separated = |axis: Vec3| {
        let p = [axis.dot(v[0]), axis.dot(v[1]), axis.dot(v[2])];
        let r = half.dot(axis.abs());
        let magnitude = r + p[0].abs() + p[1].abs() + p[2].abs();
        let tolerance = magnitude * (1.0 / 4096.0);
        let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        lo > r + tolerance || hi < -r - tolerance
    };
    for edge in e {
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            let a = edge.cross(axis);
            if a != Vec3::ZERO && separated(a) {
                return false;
            }
        }
    }
    let n = e[0].cross(e[1]);
    !(n != Vec3::ZERO && separated(n))
}
