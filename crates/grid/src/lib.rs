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
//!   larger of 1/4096 of a cell and 2^-16 of the grid's size), overlaps. The padding makes
//!   insertion conservative against the DDA's rounding: a ray that passes through a cell
//!   corner visits three of the four cells around it, and any primitive near that corner
//!   is also listed in the visited ones; and the DDA's positions, off by a few ulps of the
//!   ray origin's distance to the grid, stay within the padding for rays starting less
//!   than [`FAR_ORIGIN`] grid sizes away. Rays starting farther away (a camera 10 km from
//!   a 1 mm scene) cannot be located in the grid to f32 precision: they test every bounded
//!   primitive instead, which keeps the result exact.
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

use glam::Vec3A;
use raybench_core::{
    Aabb, Accel, AccelStats, Counters, Geometry, Hit, PrimHit, Ray, Shape, SlabRay, Vec3,
    cull_bound,
};
use std::sync::Arc;

mod two_level;
pub use two_level::{TwoLevelGrid, TwoLevelParams};

/// Size of the per-ray mailbox (recently tested primitive ids).
pub const MAILBOX: usize = 8;

/// Rays whose origin lies farther than this many grid sizes from the grid's centre skip
/// the DDA and test every bounded primitive (see the crate documentation).
pub const FAR_ORIGIN: f32 = 8.0;

/// The cell lists are kept below this many entries per primitive (plus one per cell) by
/// coarsening the grid.
pub const MAX_REFERENCES_PER_PRIMITIVE: u64 = 16;

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
        self.pad =
            (self.cell * (1.0 / 4096.0)).max(Vec3::splat(e.max_element() * (1.0 / 65_536.0)));
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

    pub(crate) fn cell_index(&self, c: [u32; 3]) -> usize {
        (c[2] as usize * self.res[1] as usize + c[1] as usize) * self.res[0] as usize
            + c[0] as usize
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

    /// Whether the DDA can locate `ray` in the grid precisely enough (its origin within
    /// [`FAR_ORIGIN`] grid sizes of the centre, and finite).
    #[inline]
    pub(crate) fn dda_is_exact_for(&self, ray: &Ray) -> bool {
        if self.ids.is_empty() {
            // Nothing to walk; unless primitives exist that the grid could not hold.
            return self.prims.is_empty();
        }
        if !ray.is_valid() {
            // NaN or zero directions would never step: test everything, as naive does.
            return false;
        }
        let reach = (ray.origin - self.bounds.center()).abs().max_element();
        reach <= FAR_ORIGIN * self.bounds.extent().max_element()
    }

    /// The cells `ray` visits, in order (for tests and teaching).
    #[must_use]
    pub fn cells_visited(&self, ray: &Ray) -> Vec<[u32; 3]> {
        let mut out = Vec::new();
        self.dda(ray, |c, _| {
            out.push(c);
            true
        });
        out
    }

    /// Walks the cells `ray` crosses in order, calling `visit(cell_ids, exit_t)` for each;
    /// `visit` returns `false` to stop. Cells are visited from the ray's entry into the
    /// grid until it leaves the grid or passes `ray.t_max`. Returns the cells visited.
    #[inline]
    pub(crate) fn walk(&self, ray: &Ray, mut visit: impl FnMut(&[u32], f32) -> bool) -> u64 {
        self.dda(ray, |c, exit| {
            let i = self.cell_index(c);
            visit(
                &self.ids[self.offsets[i] as usize..self.offsets[i + 1] as usize],
                exit,
            )
        })
    }

    /// The 3D-DDA itself: calls `visit(cell, exit_t)` for each cell crossed.
    #[inline]
    pub(crate) fn dda(&self, ray: &Ray, mut visit: impl FnMut([u32; 3], f32) -> bool) -> u64 {
        if self.ids.is_empty() {
            return 0;
        }
        let slab = SlabRay::new(ray);
        let Some(t_enter) = slab.entry(self.bounds.min.into(), self.bounds.max.into(), ray.t_max)
        else {
            return 0;
        };
        let o = Vec3A::from(ray.origin);
        let d = Vec3A::from(ray.dir);
        let gmin = Vec3A::from(self.bounds.min);
        let cell = Vec3A::from(self.cell);
        let p = o + d * t_enter;
        let start = ((p - gmin) * Vec3A::from(self.inv_cell)).floor();
        let mut c = [0i64; 3];
        let mut step = [0i64; 3];
        let mut t_next = [f32::INFINITY; 3];
        let inv = ray.inv_dir;
        for a in 0..3 {
            let max = i64::from(self.res[a]) - 1;
            c[a] = if start[a].is_nan() {
                0
            } else {
                (start[a] as i64).clamp(0, max)
            };
            if d[a] > 0.0 {
                step[a] = 1;
            } else if d[a] < 0.0 {
                step[a] = -1;
            }
        }
        // Distance at which the ray leaves cell `c` across axis `a`'s boundary.
        let boundary_t = |c: &[i64; 3], a: usize| -> f32 {
            match step[a] {
                1 => (gmin[a] + (c[a] + 1) as f32 * cell[a] - o[a]) * inv[a],
                -1 => (gmin[a] + c[a] as f32 * cell[a] - o[a]) * inv[a],
                _ => f32::INFINITY,
            }
        };
        for (a, t) in t_next.iter_mut().enumerate() {
            *t = boundary_t(&c, a);
        }
        let mut visits = 0u64;
        loop {
            visits += 1;
            let exit = t_next[0].min(t_next[1]).min(t_next[2]);
            // `exit` is never NaN: only axes with a non-zero direction step.
            if !visit([c[0] as u32, c[1] as u32, c[2] as u32], exit) || exit > ray.t_max {
                return visits;
            }
            // One comparison per axis: step along the axis whose boundary comes first.
            let a = if t_next[0] <= t_next[1] && t_next[0] <= t_next[2] {
                0
            } else if t_next[1] <= t_next[2] {
                1
            } else {
                2
            };
            c[a] += step[a];
            if c[a] < 0 || c[a] >= i64::from(self.res[a]) {
                return visits;
            }
            t_next[a] = boundary_t(&c, a);
        }
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
pub fn triangle_may_touch_box(t: &raybench_core::Triangle, center: Vec3, half: Vec3) -> bool {
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

/// A ring of recently tested primitive ids (mailboxing without shared state).
pub(crate) struct Mailbox {
    ids: [u32; MAILBOX],
    next: usize,
}

impl Mailbox {
    pub(crate) fn new() -> Self {
        Self {
            ids: [u32::MAX; MAILBOX],
            next: 0,
        }
    }

    /// True when `id` was tested recently; otherwise remembers it and returns false.
    #[inline]
    pub(crate) fn seen(&mut self, id: u32) -> bool {
        if self.ids.contains(&id) {
            return true;
        }
        self.ids[self.next] = id;
        self.next = (self.next + 1) % MAILBOX;
        false
    }
}

impl Accel for Grid {
    fn build(geometry: Arc<Geometry>) -> Self {
        Self::build_with(geometry, GridParams::default())
    }

    fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        let g = &*self.geometry;
        let mut best: Option<(u32, PrimHit)> = None;
        if !self.dda_is_exact_for(ray) {
            return g.closest_brute_force(ray, counters);
        }
        let mut tests = g.closest_unbounded(ray, &mut best);
        let mut mailbox = Mailbox::new();
        let visits = self.walk(ray, |ids, exit| {
            for &id in ids {
                if !mailbox.seen(id) {
                    tests += 1;
                    g.test_closest(id, ray, &mut best);
                }
            }
            // Stop only when the best hit lies before this cell's exit (with slack).
            best.is_none_or(|(_, h)| cull_bound(h.t) >= exit)
        });
        counters.add_tests(tests);
        counters.add_visits(visits);
        g.complete(ray, best)
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        let g = &*self.geometry;
        if !self.dda_is_exact_for(ray) {
            return g.occluded_brute_force(ray, counters);
        }
        let (plane_hit, mut tests) = g.occluded_unbounded(ray);
        if plane_hit {
            counters.add_tests(tests);
            return true;
        }
        let mut hit = false;
        let mut mailbox = Mailbox::new();
        let visits = self.walk(ray, |ids, _| {
            for &id in ids {
                if !mailbox.seen(id) {
                    tests += 1;
                    if g.shape(id).intersect(ray).is_some() {
                        hit = true;
                        return false;
                    }
                }
            }
            true
        });
        counters.add_tests(tests);
        counters.add_visits(visits);
        hit
    }

    fn stats(&self) -> AccelStats {
        let cells = self.offsets.len().saturating_sub(1);
        let non_empty = self.offsets.windows(2).filter(|w| w[1] > w[0]).count();
        AccelStats {
            memory_bytes: std::mem::size_of_val(self.offsets.as_slice())
                + std::mem::size_of_val(self.ids.as_slice()),
            counts: vec![
                ("cells", cells as u64),
                ("non-empty cells", non_empty as u64),
                ("references", self.ids.len() as u64),
                ("nx", u64::from(self.res[0])),
                ("ny", u64::from(self.res[1])),
                ("nz", u64::from(self.res[2])),
            ],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_core::{Shape, Sphere, Triangle};
    use raybench_scene::generators;

    fn soup_grid(n: u32) -> Grid {
        let g = Arc::new(Geometry::new(
            generators::soup(n, 4)
                .triangles()
                .map(Shape::Triangle)
                .collect(),
        ));
        Grid::build_with(g, GridParams::default())
    }

    /// f64 slab interval of `ray` with box `[lo, hi]`.
    fn interval(ray: &Ray, lo: [f64; 3], hi: [f64; 3]) -> (f64, f64) {
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for a in 0..3 {
            let o = f64::from(ray.origin[a]);
            let d = f64::from(ray.dir[a]);
            if d == 0.0 {
                if o < lo[a] || o > hi[a] {
                    return (1.0, 0.0);
                }
                continue;
            }
            let (mut n, mut f) = ((lo[a] - o) / d, (hi[a] - o) / d);
            if n > f {
                std::mem::swap(&mut n, &mut f);
            }
            t0 = t0.max(n);
            t1 = t1.min(f);
        }
        (t0, t1)
    }

    #[test]
    fn dda_visits_every_cell_the_ray_really_crosses() {
        let grid = soup_grid(3000);
        let res = grid.resolution();
        let rays = raybench_core::rays::incoherent(grid.bounds(), 300, 9);
        let (min, cell) = (grid.bounds().min, grid.cell_size());
        for ray in &rays {
            let visited: std::collections::HashSet<[u32; 3]> =
                grid.cells_visited(ray).into_iter().collect();
            for z in 0..res[2] {
                for y in 0..res[1] {
                    for x in 0..res[0] {
                        let lo = [0, 1, 2].map(|a| {
                            f64::from(min[a]) + f64::from([x, y, z][a]) * f64::from(cell[a])
                        });
                        let hi = [0, 1, 2].map(|a| lo[a] + f64::from(cell[a]));
                        let (t0, t1) = interval(ray, lo, hi);
                        // Crossed by more than a sliver: must be visited.
                        if t1 - t0 > 1e-4 * f64::from(cell.min_element()) {
                            assert!(
                                visited.contains(&[x, y, z]),
                                "ray {ray:?} skipped cell {x} {y} {z}"
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn resolution_follows_the_primitive_count_and_cap() {
        let small = soup_grid(100);
        let large = soup_grid(20_000);
        let cells = |g: &Grid| {
            g.resolution()
                .iter()
                .map(|&r| u64::from(r))
                .product::<u64>()
        };
        assert!(cells(&large) > 50 * cells(&small));
        // lambda * M cells, roughly.
        let ratio = cells(&large) as f64 / (2.0 * 20_000.0);
        assert!((0.5..2.0).contains(&ratio), "{ratio}");
        let g = Arc::new(Geometry::new(
            generators::soup(20_000, 4)
                .triangles()
                .map(Shape::Triangle)
                .collect(),
        ));
        let capped = Grid::build_with(
            g,
            GridParams {
                lambda: 8.0,
                max_cells: 1000,
                clip_triangles: true,
            },
        );
        assert!(cells(&capped) <= 1000);
    }

    #[test]
    fn mailboxing_tests_each_primitive_once_along_a_ray() {
        // One long thin triangle spanning every cell along x.
        let mut shapes = vec![Shape::Triangle(Triangle::new(
            Vec3::new(-10.0, 0.0, 0.0),
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(10.0, 0.1, 0.0),
        ))];
        shapes.extend((0..500).map(|i| {
            Shape::Sphere(Sphere::new(
                Vec3::new(-9.0 + i as f32 * 0.036, 5.0, 5.0),
                0.01,
            ))
        }));
        let grid = Grid::build_with(Arc::new(Geometry::new(shapes)), GridParams::default());
        // Along the triangle's plane, just above it: crosses every cell it lists.
        let ray = Ray::new(Vec3::new(-11.0, 0.05, 0.0), Vec3::X);
        let mut c = raybench_core::RayCounters::default();
        let _ = grid.intersect(&ray, &mut c);
        assert!(c.node_visits > 5, "{} cells", c.node_visits);
        assert_eq!(
            c.prim_tests, 1,
            "tested once despite spanning {} cells",
            c.node_visits
        );
    }

    #[test]
    fn primitives_spanning_everything_do_not_make_lists_quadratic() {
        // 3,000 triangles each crossing the whole box: at two cells per primitive the lists
        // would hold 3,000 x 6,000 entries; coarsening keeps them near 16 per primitive.
        let shapes: Vec<Shape> = (0..3000)
            .map(|i| {
                let a = i as f32 * 0.001;
                Shape::Triangle(Triangle::new(
                    Vec3::new(-1.0, -1.0, -1.0 + a),
                    Vec3::new(1.0, 1.0, 1.0 - a),
                    Vec3::new(1.0, -1.0, a),
                ))
            })
            .collect();
        let grid = Grid::build_with(Arc::new(Geometry::new(shapes)), GridParams::default());
        let refs = grid.ids.len() as u64;
        let cells = grid.offsets.len() as u64 - 1;
        assert!(
            refs <= MAX_REFERENCES_PER_PRIMITIVE * 3000 + cells,
            "{refs} references"
        );
        let hit = grid.intersect(
            &Ray::new(Vec3::new(0.2, 0.1, -5.0), Vec3::Z),
            &mut raybench_core::NoCounters,
        );
        assert!(hit.is_some());
    }

    #[test]
    fn triangle_box_test_keeps_touching_and_drops_missing_cells() {
        let (c, h) = (Vec3::ZERO, Vec3::splat(0.5));
        let t = |a: [f32; 3], b: [f32; 3], d: [f32; 3]| Triangle::new(a.into(), b.into(), d.into());
        // Through the centre.
        assert!(triangle_may_touch_box(
            &t([-2.0, -2.0, 0.0], [2.0, -2.0, 0.0], [0.0, 2.0, 0.0]),
            c,
            h
        ));
        // Its plane touches the box exactly at the corner (0.5, 0.5, 0.5): x + y + z = 1.5.
        assert!(triangle_may_touch_box(
            &t([1.5, 0.0, 0.0], [0.0, 1.5, 0.0], [0.0, 0.0, 1.5]),
            c,
            h
        ));
        // An edge exactly along a box edge.
        assert!(triangle_may_touch_box(
            &t([0.5, 0.5, -3.0], [0.5, 0.5, 3.0], [3.0, 3.0, 0.0]),
            c,
            h
        ));
        // A large triangle whose bounding box covers the cell but whose plane passes by.
        assert!(!triangle_may_touch_box(
            &t([2.0, -5.0, -5.0], [-5.0, 2.0, -5.0], [-5.0, -5.0, 2.0]),
            c,
            h
        ));
        // A sliver beside the box: an edge/axis cross product separates it.
        assert!(!triangle_may_touch_box(
            &t([0.6, 0.6, -3.0], [0.7, 0.7, 3.0], [3.0, 3.0, 0.0]),
            c,
            h
        ));
    }

    #[test]
    fn zero_and_nan_directions_terminate_and_miss() {
        let grid = soup_grid(500);
        for dir in [Vec3::ZERO, Vec3::splat(f32::NAN)] {
            let r = Ray::new(Vec3::ZERO, dir);
            assert!(grid.intersect(&r, &mut raybench_core::NoCounters).is_none());
            assert!(!grid.occluded(&r, &mut raybench_core::NoCounters));
        }
    }

    #[test]
    fn empty_and_flat_grids() {
        let g = Grid::build_with(Arc::new(Geometry::default()), GridParams::default());
        assert!(
            g.intersect(
                &Ray::new(Vec3::ZERO, Vec3::X),
                &mut raybench_core::NoCounters
            )
            .is_none()
        );
        let flat = Arc::new(Geometry::new(
            generators::terrain(1)
                .triangles()
                .map(|t| {
                    Shape::Triangle(Triangle::new(
                        Vec3::new(t.v[0].x, 0.0, t.v[0].z),
                        Vec3::new(t.v[1].x, 0.0, t.v[1].z),
                        Vec3::new(t.v[2].x, 0.0, t.v[2].z),
                    ))
                })
                .collect(),
        ));
        let g = Grid::build_with(flat, GridParams::default());
        let hit = g.intersect(
            &Ray::new(Vec3::new(0.1, 1.0, 0.2), -Vec3::Y),
            &mut raybench_core::NoCounters,
        );
        assert_eq!(hit.map(|h| h.t), Some(1.0));
    }
}
