//! Bicubic Bezier patches intersected directly (no triangles): subdivision with the
//! control points' bounding boxes isolates candidate regions, Newton iteration on
//! `(u, v, t)` finds the hit inside each.
//!
//! A patch is `S(u, v) = sum_ij B_i(u) B_j(v) P[4 j + i]` over the cubic Bernstein
//! polynomials `B_i`, `(u, v)` in `[0, 1]^2`. Its control points' box contains it (convex
//! hull property), and so does every sub-patch's.
//!
//! **Rules** (tested below and in `tests/tests/bezier.rs`):
//! - *Regions.* Construction subdivides the patch into a fixed quadtree of
//!   [`REGION_DEPTH`] levels (`8 x 8` leaf regions) and stores each node's control-point box,
//!   padded by `1e-5` of the patch's extent (which covers the f64 -> f32 rounding of the
//!   sub-patch control points and Newton's tolerance). The ray walks the tree nearest box
//!   first (the workspace's slab test), skipping boxes that start beyond the best hit.
//! - *Newton.* In a leaf region Newton's method solves `S(u, v) - (o + t d) = 0` (a 3x3
//!   system per step, Cramer's rule, in f64) from the region's centre and the box's entry
//!   `t`. Converged: `|F| < 1e-7` of the patch extent ([`BezierPatch::tolerance`]) within
//!   [`MAX_NEWTON_ITERATIONS`] steps, with `(u, v)` inside `[0, 1]^2` up to a margin of
//!   `1e-6` (the reported parameters are clamped to `[0, 1]`). A converged point outside
//!   the region is a true surface point too and is kept (accepting only points inside the
//!   region left 7 holes at seams in 256^2 teapot pixels). An iterate that leaves the
//!   region by more than its width is a miss of this region (a hit elsewhere lies in a
//!   region whose box the ray also enters; half a width left one hole at the spout).
//! - *Fallback.* A singular Jacobian (`|det| <= 1e-12 |S_u| |S_v| |d|`, as at the teapot's
//!   collapsed edges) or no convergence within the iteration limit subdivides the region
//!   on the fly (de Casteljau restriction, boxes of the sub-control points, nearest first)
//!   for up to [`FALLBACK_DEPTH`] more levels and runs Newton again in each; at the last
//!   level the region's bilinear approximation (its four corners) gives the hit, polished by
//!   Newton when that converges inside the region.
//! - *Determinism.* The search ignores `ray.t_max` (it finds the closest hit in
//!   `[t_min, inf)` and then compares it with `t_max`), so the result does not depend on
//!   which other primitives a backend tested first: every backend gets bit-identical hits.
//! - *Normals* are `S_u x S_v` (normalised; this orientation always, the renderer shades
//!   both sides). Where it vanishes (a collapsed edge, e.g. the teapot's lid and bottom
//!   centres) it is taken at the point moved `1e-3` of the way toward the patch centre,
//!   which approaches the limit normal.
//! - *Secondary rays* start off the surface by the renderer's Waechter-Binder offset
//!   (hundreds of ulps of the coordinates); the tolerance is two orders of magnitude below
//!   it, so the ray's own surface solves to `t < 0` and is not hit again.

use crate::aabb::{Aabb, SlabRay};
use crate::bilinear::BilinearPatch;
use crate::error::SceneError;
use crate::hit::PrimHit;
use crate::limits::MAX_COORDINATE;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::stack::NodeStack;
use glam::{DVec3, Vec3, Vec3A};

/// Levels of the precomputed region tree below the whole patch (`2^3 x 2^3` leaf regions).
pub const REGION_DEPTH: u32 = 3;
/// Newton steps before a region counts as failed (and falls back to subdivision).
pub const MAX_NEWTON_ITERATIONS: u32 = 12;
/// Further subdivision levels below a leaf region after Newton failed there.
pub const FALLBACK_DEPTH: u32 = 4;

/// Relative tolerance of Newton's `|F|` test (times the patch extent).
const TOLERANCE: f64 = 1e-7;
/// Padding of region boxes, relative to the patch extent.
const PAD: f32 = 1e-5;
/// How far outside its region (in parameter space) an accepted hit may lie.
pub const UV_MARGIN: f64 = 1e-6;

/// Nodes of the region tree: `(4^(D+1) - 1) / 3`.
const NODES: usize = ((1 << (2 * (REGION_DEPTH + 1))) - 1) / 3;

/// A bicubic Bezier patch, placed in the world, with its precomputed region boxes.
#[derive(Clone, Debug, PartialEq)]
pub struct BezierPatch {
    /// Control points, `points[4 j + i]` weighted by `B_i(u) B_j(v)`.
    points: [Vec3; 16],
    /// The same in f64, for evaluation.
    p64: [DVec3; 16],
    /// Absolute Newton tolerance.
    tol: f64,
    /// Absolute padding of region boxes.
    pad: f32,
    /// Region boxes, level by level (level `l`: `2^l x 2^l` regions, row-major in `v`).
    boxes: Vec<[Vec3A; 2]>,
}

/// Counts of what the intersection did, for measurements (see
/// [`BezierPatch::intersect_counted`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BezierStats {
    /// Newton solves started.
    pub newton_runs: u64,
    /// Newton steps taken.
    pub iterations: u64,
    /// Solves that converged inside their region (with `t >= t_min`).
    pub converged: u64,
    /// Regions that fell back to further subdivision (singular Jacobian or no convergence).
    pub fallbacks: u64,
    /// Hits taken from a bilinear approximation at the last fallback level.
    pub bilinear: u64,
    /// Calls that returned a hit.
    pub hits: u64,
}

/// A parameter rectangle `[u0, u1] x [v0, v1]`.
#[derive(Clone, Copy, Debug)]
struct Region {
    u0: f64,
    u1: f64,
    v0: f64,
    v1: f64,
}

impl Region {
    /// Region `(iu, iv)` of the `2^level x 2^level` grid over the patch.
    fn cell(level: u32, iu: u32, iv: u32) -> Self {
        let s = 1.0 / f64::from(1u32 << level);
        Self {
            u0: f64::from(iu) * s,
            u1: f64::from(iu + 1) * s,
            v0: f64::from(iv) * s,
            v1: f64::from(iv + 1) * s,
        }
    }

    fn quarter(self, k: usize) -> Self {
        let um = 0.5 * (self.u0 + self.u1);
        let vm = 0.5 * (self.v0 + self.v1);
        let (u0, u1) = if k & 1 == 0 {
            (self.u0, um)
        } else {
            (um, self.u1)
        };
        let (v0, v1) = if k & 2 == 0 {
            (self.v0, vm)
        } else {
            (vm, self.v1)
        };
        Self { u0, u1, v0, v1 }
    }

    fn contains(self, u: f64, v: f64, margin: f64) -> bool {
        let mu = margin * (self.u1 - self.u0);
        let mv = margin * (self.v1 - self.v0);
        u >= self.u0 - mu && u <= self.u1 + mu && v >= self.v0 - mv && v <= self.v1 + mv
    }
}

/// The whole patch's parameter square.
const UNIT: Region = Region {
    u0: 0.0,
    u1: 1.0,
    v0: 0.0,
    v1: 1.0,
};

/// How one Newton solve ended.
enum Newton {
    /// `|F|` below the tolerance at `(u, v, t)`.
    Converged(f64, f64, f64),
    /// The iterate left the region: no hit here.
    Left,
    /// Singular Jacobian or the iteration limit.
    Failed,
}

/// The cubic Bernstein polynomials and their derivatives at `x`.
#[inline]
fn bernstein(x: f64) -> ([f64; 4], [f64; 4]) {
    let y = 1.0 - x;
    (
        [y * y * y, 3.0 * x * y * y, 3.0 * x * x * y, x * x * x],
        [
            -3.0 * y * y,
            3.0 * y * y - 6.0 * x * y,
            6.0 * x * y - 3.0 * x * x,
            3.0 * x * x,
        ],
    )
}

/// The blossom of a cubic Bezier curve at `(a, b, c)` (de Casteljau with one parameter
/// per level): the restriction to `[a, b]` has control points `f(a,a,a), f(a,a,b),
/// f(a,b,b), f(b,b,b)`.
fn blossom(c: [DVec3; 4], t: [f64; 3]) -> DVec3 {
    let l1 = [
        c[0].lerp(c[1], t[0]),
        c[1].lerp(c[2], t[0]),
        c[2].lerp(c[3], t[0]),
    ];
    let l2 = [l1[0].lerp(l1[1], t[1]), l1[1].lerp(l1[2], t[1])];
    l2[0].lerp(l2[1], t[2])
}

/// Control points of a cubic restricted to `[a, b]`.
fn restrict_curve(c: [DVec3; 4], a: f64, b: f64) -> [DVec3; 4] {
    [
        blossom(c, [a, a, a]),
        blossom(c, [a, a, b]),
        blossom(c, [a, b, b]),
        blossom(c, [b, b, b]),
    ]
}

/// Control points of the sub-patch over `r` (rows in `u`, then columns in `v`).
fn restrict(p: &[DVec3; 16], r: Region) -> [DVec3; 16] {
    let mut rows = [DVec3::ZERO; 16];
    for j in 0..4 {
        let c = restrict_curve(
            [p[4 * j], p[4 * j + 1], p[4 * j + 2], p[4 * j + 3]],
            r.u0,
            r.u1,
        );
        rows[4 * j..4 * j + 4].copy_from_slice(&c);
    }
    let mut out = [DVec3::ZERO; 16];
    for i in 0..4 {
        let c = restrict_curve(
            [rows[i], rows[4 + i], rows[8 + i], rows[12 + i]],
            r.v0,
            r.v1,
        );
        for (j, q) in c.into_iter().enumerate() {
            out[4 * j + i] = q;
        }
    }
    out
}

/// The box of f64 control points, padded by `pad`.
fn control_box(p: &[DVec3; 16], pad: f32) -> [Vec3A; 2] {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for q in p {
        lo = lo.min(*q);
        hi = hi.max(*q);
    }
    [
        Vec3A::from(lo.as_vec3()) - Vec3A::splat(pad),
        Vec3A::from(hi.as_vec3()) + Vec3A::splat(pad),
    ]
}

impl BezierPatch {
    /// A patch from its 16 control points (`points[4 j + i]` weighted by `B_i(u) B_j(v)`:
    /// four rows along `u`).
    ///
    /// # Errors
    /// [`SceneError::NonFinite`] for a NaN or infinite point, [`SceneError::TooLarge`]
    /// beyond [`MAX_COORDINATE`], [`SceneError::Invalid`] for a patch of zero area (all
    /// control points coincident or collinear). Patches with one collapsed edge are fine.
    pub fn new(points: [Vec3; 16]) -> Result<Self, SceneError> {
        if let Some(k) = points.iter().position(|p| !p.is_finite()) {
            return Err(SceneError::NonFinite(format!("control point {}", k + 1)));
        }
        if points
            .iter()
            .any(|p| p.abs().max_element() > MAX_COORDINATE)
        {
            return Err(SceneError::TooLarge(format!(
                "a control point exceeds the coordinate limit of {MAX_COORDINATE:e}"
            )));
        }
        let p64 = points.map(|p| p.as_dvec3());
        let bounds = Aabb::from_points(points);
        let extent = f64::from(bounds.extent().max_element());
        // Zero area: every point within 1e-6 of the extent of the line through the first
        // point and the point farthest from it (or all points coincident).
        let far = p64
            .iter()
            .copied()
            .max_by(|a, b| a.distance(p64[0]).total_cmp(&b.distance(p64[0])))
            .unwrap_or(p64[0]);
        let axis = (far - p64[0]).normalize_or_zero();
        let off_line = p64
            .iter()
            .map(|&q| {
                let w = q - p64[0];
                (w - axis * w.dot(axis)).length()
            })
            .fold(0.0, f64::max);
        if extent == 0.0 || off_line <= 1e-6 * extent {
            return Err(SceneError::Invalid(
                "degenerate Bezier patch: its control points are coincident or collinear \
                 (zero area)"
                    .into(),
            ));
        }
        let pad = PAD * extent as f32;
        let mut boxes = Vec::with_capacity(NODES);
        for level in 0..=REGION_DEPTH {
            let n = 1u32 << level;
            for iv in 0..n {
                for iu in 0..n {
                    let r = Region::cell(level, iu, iv);
                    boxes.push(control_box(&restrict(&p64, r), pad));
                }
            }
        }
        Ok(Self {
            points,
            p64,
            tol: TOLERANCE * extent,
            pad,
            boxes,
        })
    }

    /// The control points.
    #[must_use]
    pub fn points(&self) -> &[Vec3; 16] {
        &self.points
    }

    /// The absolute tolerance of Newton's `|F|` test (`1e-7` of the patch extent).
    #[must_use]
    pub fn tolerance(&self) -> f64 {
        self.tol
    }

    /// The box of the control points (padded slightly), which contains the patch.
    #[inline]
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        Aabb::new(self.boxes[0][0].into(), self.boxes[0][1].into())
    }

    /// The precomputed region boxes, level by level (level `l`: `2^l x 2^l` regions,
    /// row-major in `v`; the root first), padded by [`BezierPatch::box_pad`]: what the GPU
    /// kernels walk.
    #[must_use]
    pub fn region_boxes(&self) -> &[[Vec3A; 2]] {
        &self.boxes
    }

    /// The absolute padding of the region boxes (and of the fallback's boxes).
    #[must_use]
    pub fn box_pad(&self) -> f32 {
        self.pad
    }

    /// Bytes held, the region boxes included.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>() + self.boxes.len() * std::mem::size_of::<[Vec3A; 2]>()
    }

    /// `S(u, v)`, `S_u` and `S_v` in f64.
    #[inline]
    fn eval(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        let (bu, du) = bernstein(u);
        let (bv, dv) = bernstein(v);
        let (mut s, mut su, mut sv) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
        for j in 0..4 {
            for i in 0..4 {
                let p = self.p64[4 * j + i];
                s += p * (bu[i] * bv[j]);
                su += p * (du[i] * bv[j]);
                sv += p * (bu[i] * dv[j]);
            }
        }
        (s, su, sv)
    }

    /// The surface point at `(u, v)`.
    #[must_use]
    pub fn point(&self, u: f32, v: f32) -> Vec3 {
        self.eval(f64::from(u), f64::from(v)).0.as_vec3()
    }

    /// The unit geometric normal `S_u x S_v` at `(u, v)`; at a collapsed edge (where it
    /// vanishes) the normal at the point moved `1e-3` of the way toward the centre.
    #[must_use]
    pub fn normal(&self, u: f32, v: f32) -> Vec3 {
        let (u, v) = (f64::from(u), f64::from(v));
        let (_, su, sv) = self.eval(u, v);
        let n = su.cross(sv);
        let scale = su.length_squared().max(sv.length_squared());
        let n = if n.length() > 1e-9 * scale {
            n
        } else {
            let (_, su, sv) = self.eval(u + (0.5 - u) * 1e-3, v + (0.5 - v) * 1e-3);
            su.cross(sv)
        };
        n.normalize_or_zero().as_vec3().normalize_or(Vec3::Y)
    }

    /// The closest hit inside `[ray.t_min, ray.t_max]`: sub-primitive 0, `(u, v)` the
    /// patch parameters.
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        self.intersect_counted(ray, &mut BezierStats::default())
    }

    /// [`BezierPatch::intersect`], counting Newton solves, steps and fallbacks into `stats`.
    pub fn intersect_counted(&self, ray: &Ray, stats: &mut BezierStats) -> Option<PrimHit> {
        if !ray.is_valid() {
            return None;
        }
        // The search ignores t_max (see the module rules): one answer per ray.
        let slab = SlabRay::new(ray);
        let o = ray.origin.as_dvec3();
        let d = ray.dir.as_dvec3();
        let mut best: Option<(f64, f64, f64)> = None;
        let bound = |best: &Option<(f64, f64, f64)>| best.map_or(f32::INFINITY, |b| b.2 as f32);
        // Nearest-first walk of the region tree with an explicit stack of (level, iu, iv,
        // entry); at most 3 siblings wait per level.
        let mut storage = [((0u32, 0u32, 0u32), 0.0f32); 16];
        let mut stack = NodeStack::new(&mut storage);
        stack.push(
            (0, 0, 0),
            slab.entry(self.boxes[0][0], self.boxes[0][1], f32::INFINITY)?,
        );
        while let Some(((level, iu, iv), entry)) = stack.pop_within(bound(&best)) {
            let n = 1u32 << level;
            let region = Region::cell(level, iu, iv);
            if level == REGION_DEPTH {
                self.solve_region(ray, o, d, region, entry, FALLBACK_DEPTH, &mut best, stats);
                continue;
            }
            // Children sorted far to near, so the nearest is popped first.
            let base = NODES_BEFORE[level as usize + 1];
            let mut kids: [(u32, u32, f32); 4] = [(0, 0, f32::INFINITY); 4];
            let mut count = 0;
            for k in 0..4u32 {
                let (cu, cv) = (2 * iu + (k & 1), 2 * iv + (k >> 1));
                let b = &self.boxes[base + (cv * 2 * n + cu) as usize];
                if let Some(t) = slab.entry(b[0], b[1], bound(&best)) {
                    kids[count] = (cu, cv, t);
                    count += 1;
                }
            }
            kids[..count].sort_unstable_by(|a, b| b.2.total_cmp(&a.2));
            for &(cu, cv, t) in &kids[..count] {
                stack.push((level + 1, cu, cv), t);
            }
        }
        let (u, v, t) = best?;
        let t = t as f32;
        if t < ray.t_min || t > ray.t_max {
            return None;
        }
        stats.hits += 1;
        Some(PrimHit {
            t,
            sub: 0,
            u: u.clamp(0.0, 1.0) as f32,
            v: v.clamp(0.0, 1.0) as f32,
        })
    }

    /// Newton in `region` from its centre and `entry`; on failure, subdivision for up to
    /// `depth` more levels, then the bilinear approximation. Keeps the closest hit in
    /// `best`.
    #[allow(clippy::too_many_arguments)]
    fn solve_region(
        &self,
        ray: &Ray,
        o: DVec3,
        d: DVec3,
        region: Region,
        entry: f32,
        depth: u32,
        best: &mut Option<(f64, f64, f64)>,
        stats: &mut BezierStats,
    ) {
        let u = 0.5 * (region.u0 + region.u1);
        let v = 0.5 * (region.v0 + region.v1);
        match self.newton(o, d, u, v, f64::from(entry), region, stats) {
            Newton::Converged(u, v, t) => self.keep(ray, u, v, t, best, stats),
            Newton::Left => {}
            Newton::Failed if depth == 0 => {
                // The region's corners as a bilinear patch, polished by Newton.
                let c = |u: f64, v: f64| self.eval(u, v).0.as_vec3();
                let patch = BilinearPatch {
                    q00: c(region.u0, region.v0),
                    q10: c(region.u1, region.v0),
                    q11: c(region.u1, region.v1),
                    q01: c(region.u0, region.v1),
                };
                let Some(h) = patch.intersect(&ray.clipped(f32::INFINITY)) else {
                    return;
                };
                let u = region.u0 + f64::from(h.u) * (region.u1 - region.u0);
                let v = region.v0 + f64::from(h.v) * (region.v1 - region.v0);
                match self.newton(o, d, u, v, f64::from(h.t), region, stats) {
                    Newton::Converged(u, v, t) => self.keep(ray, u, v, t, best, stats),
                    _ => {
                        stats.bilinear += 1;
                        self.keep(ray, u, v, f64::from(h.t), best, stats);
                    }
                }
            }
            Newton::Failed => {
                stats.fallbacks += 1;
                let slab = SlabRay::new(ray);
                let mut kids: [(Region, f32); 4] = [(region, 0.0); 4];
                let mut count = 0;
                for k in 0..4 {
                    let r = region.quarter(k);
                    let b = control_box(&restrict(&self.p64, r), self.pad);
                    let bound = best.map_or(f32::INFINITY, |b| b.2 as f32);
                    if let Some(t) = slab.entry(b[0], b[1], bound) {
                        kids[count] = (r, t);
                        count += 1;
                    }
                }
                kids[..count].sort_unstable_by(|a, b| a.1.total_cmp(&b.1));
                for &(r, t) in &kids[..count] {
                    if best.is_some_and(|b| t > b.2 as f32) {
                        break;
                    }
                    self.solve_region(ray, o, d, r, t, depth - 1, best, stats);
                }
            }
        }
    }

    /// Records a converged `(u, v, t)` when it lies in `[t_min, inf)` and is closer.
    fn keep(
        &self,
        ray: &Ray,
        u: f64,
        v: f64,
        t: f64,
        best: &mut Option<(f64, f64, f64)>,
        stats: &mut BezierStats,
    ) {
        if (t as f32) < ray.t_min || !t.is_finite() {
            return;
        }
        stats.converged += 1;
        if best.is_none_or(|b| t < b.2) {
            *best = Some((u, v, t));
        }
    }

    /// Newton's method on `F(u, v, t) = S(u, v) - o - t d` from `(u, v, t)`.
    #[allow(clippy::too_many_arguments)]
    fn newton(
        &self,
        o: DVec3,
        d: DVec3,
        mut u: f64,
        mut v: f64,
        mut t: f64,
        region: Region,
        stats: &mut BezierStats,
    ) -> Newton {
        stats.newton_runs += 1;
        let d_len = d.length();
        for _ in 0..MAX_NEWTON_ITERATIONS {
            let (s, su, sv) = self.eval(u, v);
            let f = s - o - d * t;
            if f.length() < self.tol {
                return if UNIT.contains(u, v, UV_MARGIN) {
                    Newton::Converged(u, v, t)
                } else {
                    Newton::Left
                };
            }
            stats.iterations += 1;
            // J = [S_u, S_v, -d]; J x = -F by Cramer's rule.
            let c = -d;
            let det = su.dot(sv.cross(c));
            if det.abs() <= 1e-12 * su.length() * sv.length() * d_len || !det.is_finite() {
                return Newton::Failed;
            }
            let r = -f;
            u += r.dot(sv.cross(c)) / det;
            v += su.dot(r.cross(c)) / det;
            t += su.dot(sv.cross(r)) / det;
            if !region.contains(u, v, 1.0) {
                return Newton::Left;
            }
        }
        Newton::Failed
    }

    /// `n x n` quads per patch, each split into two triangles, with vertices on the exact
    /// surface (`(u, v) = (i / n, j / n)`), wound like `S_u x S_v`: `(p00, p10, p11)` and
    /// `(p00, p11, p01)`.
    #[must_use]
    pub fn tessellate(&self, n: u32) -> TriangleMesh {
        let n = n.max(1);
        let step = 1.0 / f64::from(n);
        let mut positions = Vec::with_capacity(((n + 1) * (n + 1)) as usize);
        for j in 0..=n {
            for i in 0..=n {
                let (s, _, _) = self.eval(f64::from(i) * step, f64::from(j) * step);
                positions.push(s.as_vec3());
            }
        }
        let id = |i: u32, j: u32| j * (n + 1) + i;
        let mut indices = Vec::with_capacity((2 * n * n) as usize);
        for j in 0..n {
            for i in 0..n {
                let (p00, p10, p11, p01) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                indices.push([p00, p10, p11]);
                indices.push([p00, p11, p01]);
            }
        }
        TriangleMesh { positions, indices }
    }
}

/// Index of the first node of each level of the region tree.
const NODES_BEFORE: [usize; REGION_DEPTH as usize + 2] = {
    let mut out = [0; REGION_DEPTH as usize + 2];
    let mut l = 1;
    while l < out.len() {
        out[l] = out[l - 1] + (1 << (2 * (l - 1)));
        l += 1;
    }
    out
};

#[cfg(test)]
mod tests {
    use super::*;

    /// The patch with control points on a regular grid in the plane `z = h`, spanning
    /// `[0, 3]^2` (so `S(u, v) = (3u, 3v, h)`).
    fn flat(h: f32) -> BezierPatch {
        let mut p = [Vec3::ZERO; 16];
        for j in 0..4 {
            for i in 0..4 {
                p[4 * j + i] = Vec3::new(i as f32, j as f32, h);
            }
        }
        BezierPatch::new(p).unwrap()
    }

    #[test]
    fn node_offsets() {
        assert_eq!(NODES_BEFORE, [0, 1, 5, 21, 85]);
        assert_eq!(NODES, 85);
        assert_eq!(flat(0.0).boxes.len(), NODES);
    }

    #[test]
    fn flat_patch_hit_matches_plane() {
        let p = flat(1.0);
        let ray = Ray::new(
            Vec3::new(0.9, 2.1, 5.0),
            Vec3::new(0.1, -0.2, -1.0).normalize(),
        );
        let h = p.intersect(&ray).unwrap();
        let t_exact = 4.0 / ray.dir.z.abs();
        assert!((h.t - t_exact).abs() < 1e-5, "{} vs {t_exact}", h.t);
        let hit = ray.at(h.t);
        assert!((h.u - hit.x / 3.0).abs() < 1e-5 && (h.v - hit.y / 3.0).abs() < 1e-5);
        assert!((p.normal(h.u, h.v) - Vec3::Z).length() < 1e-6);
        // Outside the square: miss; beyond t_max: miss.
        assert!(
            p.intersect(&Ray::new(Vec3::new(3.5, 1.0, 5.0), -Vec3::Z))
                .is_none()
        );
        let short = Ray::with_interval(Vec3::new(1.0, 1.0, 5.0), -Vec3::Z, 0.0, 3.9);
        assert!(p.intersect(&short).is_none());
    }

    #[test]
    fn restriction_reproduces_the_surface() {
        let p = flat(0.0);
        let r = Region {
            u0: 0.25,
            u1: 0.5,
            v0: 0.5,
            v1: 1.0,
        };
        let q = restrict(&p.p64, r);
        // Corner points of the sub-patch equal the surface there.
        assert!((q[0] - p.eval(0.25, 0.5).0).length() < 1e-12);
        assert!((q[15] - p.eval(0.5, 1.0).0).length() < 1e-12);
    }

    #[test]
    fn degenerate_patches_are_refused() {
        let same = [Vec3::ONE; 16];
        assert!(BezierPatch::new(same).is_err());
        let line: [Vec3; 16] = std::array::from_fn(|k| Vec3::new(k as f32, 2.0 * k as f32, 0.0));
        let e = BezierPatch::new(line).unwrap_err().to_string();
        assert!(e.contains("zero area"), "{e}");
        let mut nan = [Vec3::ZERO; 16];
        nan[3] = Vec3::NAN;
        assert!(matches!(
            BezierPatch::new(nan),
            Err(SceneError::NonFinite(m)) if m == "control point 4"
        ));
    }

    #[test]
    fn collapsed_edge_has_a_finite_normal() {
        // A cone-like patch: row 0 collapsed to the apex (0, 0, 1); rows move outward and
        // down. The normal at the apex is the cone's axis direction.
        let mut p = [Vec3::ZERO; 16];
        for j in 0..4 {
            for i in 0..4 {
                let a = i as f32 / 3.0 * std::f32::consts::FRAC_PI_2;
                let r = j as f32 / 3.0;
                p[4 * j + i] = Vec3::new(r * a.cos(), r * a.sin(), 1.0 - 0.1 * r);
            }
        }
        let patch = BezierPatch::new(p).unwrap();
        let n = patch.normal(0.5, 0.0);
        assert!(n.is_finite() && n.z.abs() > 0.95, "{n}");
        // A ray straight down on the apex hits it.
        let ray = Ray::new(Vec3::new(1e-4, 1e-4, 3.0), -Vec3::Z);
        let h = patch.intersect(&ray).unwrap();
        assert!((h.t - 2.0).abs() < 1e-3, "{}", h.t);
    }

    #[test]
    fn tessellation_vertices_lie_on_the_surface() {
        let p = flat(2.0);
        let m = p.tessellate(4);
        assert_eq!(m.indices.len(), 32);
        assert_eq!(m.positions.len(), 25);
        assert_eq!(m.positions[6], Vec3::new(0.75, 0.75, 2.0));
        // Winding like S_u x S_v (+z here).
        let t = m.triangles().next().unwrap();
        assert!(t.normal().z > 0.99);
    }
}
