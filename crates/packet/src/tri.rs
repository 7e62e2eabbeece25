//! The watertight ray/triangle test of `raybench_geometry::Triangle::intersect`, lane by lane.
//!
//! Both kernels perform, in every lane, exactly the IEEE operations of the scalar routine
//! in the same order (translate, permute, shear, the three 2D edge functions, `det = (U +
//! V) + W`, `T = (U az + V bz) + W cz`, `t = T / det`), so a lane's `t` and barycentrics
//! are bit-identical to the scalar result. The scalar routine recomputes the edge
//! functions in f64 when one is exactly 0; lanes where that happens are reported in
//! `zero` and the caller hands them to the scalar routine itself.

use crate::layout::{BLOCK, TriBlock};
use crate::simd::{Lanes, ray_rows};

/// Per-lane results of a triangle test.
#[derive(Clone, Copy)]
pub(crate) struct TriLanes<L: Lanes> {
    /// Lanes with a hit in `[t_min, t_max]`.
    pub hit: u32,
    /// Lanes the scalar routine must decide (an edge function is exactly 0).
    pub zero: u32,
    /// Ray parameter `T / det`.
    pub t: L::V,
    /// Edge function `V` (the barycentric `u` is `V / det`).
    pub v: L::V,
    /// Edge function `W` (the barycentric `v` is `W / det`).
    pub w: L::V,
    /// Determinant `(U + V) + W`.
    pub det: L::V,
}

/// One ray, splatted across the lanes, for testing `W` triangles at once. The axes are
/// stored already permuted (`origin[i]` is the origin's coordinate on axis `k[i]`), so a
/// block's coordinates are loaded from memory in the ray's order: indexing an array of
/// registers by a run-time axis made the compiler store the three differences to the stack
/// and load them back, on every vertex.
#[derive(Clone, Copy)]
pub(crate) struct SplatRay<L: Lanes> {
    /// The origin's coordinates on axes `k[0]`, `k[1]`, `k[2]`.
    pub origin: [L::V; 3],
    pub shear: [L::V; 3],
    /// The permutation `kx, ky, kz`.
    pub k: [usize; 3],
    pub t_min: L::V,
}

impl<L: Lanes> SplatRay<L> {
    #[inline(always)]
    pub fn new(ray: &raybench_geometry::Ray) -> Self {
        let k = [
            usize::from(ray.kx) % 3,
            usize::from(ray.ky) % 3,
            usize::from(ray.kz) % 3,
        ];
        let o = ray.origin.to_array();
        Self {
            origin: [L::splat(o[k[0]]), L::splat(o[k[1]]), L::splat(o[k[2]])],
            shear: [
                L::splat(ray.shear.x),
                L::splat(ray.shear.y),
                L::splat(ray.shear.z),
            ],
            k,
            t_min: L::splat(ray.t_min),
        }
    }
}

/// `W` rays in structure-of-arrays form, for testing one triangle against all of them.
/// The axis permutation may differ per lane: it is applied with selects, which move
/// values without changing them.
#[derive(Clone, Copy)]
pub(crate) struct RayLanes<L: Lanes> {
    pub origin: [L::V; 3],
    pub shear: [L::V; 3],
    /// `is[k][a]`: bits of the lanes whose permuted axis `k` (x, y, z) is axis `a` (for
    /// `a` = 0, 1); read only when the permutation is not `uniform`. (Bits, not masks: a
    /// packet writes `K` of these at its first leaf, and masks add six vectors to each.)
    pub is: [[u32; 2]; 3],
    /// The permutation when every lane has the same one (primary rays almost always do):
    /// then it is applied by indexing, without selects.
    pub uniform: Option<[usize; 3]>,
    pub t_min: L::V,
}

impl<L: Lanes> RayLanes<L> {
    /// Lanes `rays[0..W]`; missing rays are padded with the last one.
    #[inline(always)]
    pub fn new(rays: &[raybench_geometry::Ray]) -> Self {
        let (head, tail) = ray_rows::<L>(rays);
        // Columns of floats 0..8 (origin, dir, inv_dir.x, .y) and 6..14 (inv_dir, t_min,
        // t_max, shear).
        let (a, b) = (L::columns8(&head), L::columns8(&tail));
        let perm = |r: &raybench_geometry::Ray| [r.kx, r.ky, r.kz];
        let first = perm(&rays[0]);
        let lanes = &rays[..rays.len().min(L::W)];
        let (is, uniform) = if lanes.iter().all(|r| perm(r) == first) {
            // One permutation (primary rays almost always): no per-lane bits.
            ([[0; 2]; 3], Some(first.map(|a| usize::from(a) % 3)))
        } else {
            let mut is = [[0u32; 2]; 3];
            for lane in 0..L::W {
                let r = &rays[lane.min(rays.len() - 1)];
                for (slot, kk) in perm(r).into_iter().enumerate() {
                    for (a, bits) in is[slot].iter_mut().enumerate() {
                        if usize::from(kk) == a {
                            *bits |= 1 << lane;
                        }
                    }
                }
            }
            (is, None)
        };
        Self {
            origin: [a[0], a[1], a[2]],
            shear: [b[5], b[6], b[7]],
            is,
            uniform,
            t_min: b[3],
        }
    }

    /// The masks of `is`.
    #[inline(always)]
    fn masks(&self) -> [[L::M; 2]; 3] {
        let is = &self.is;
        [
            [L::mask(is[0][0]), L::mask(is[0][1])],
            [L::mask(is[1][0]), L::mask(is[1][1])],
            [L::mask(is[2][0]), L::mask(is[2][1])],
        ]
    }
}

/// Component `slot` (0 = kx, 1 = ky, 2 = kz) of `a` under each lane's permutation
/// ([`RayLanes::masks`]).
#[inline(always)]
fn pick<L: Lanes>(is: &[[L::M; 2]; 3], a: &[L::V; 3], slot: usize) -> L::V {
    let [is0, is1] = is[slot];
    L::select(is0, a[0], L::select(is1, a[1], a[2]))
}

/// The shared tail of both kernels: edge functions to hit lanes.
#[inline(always)]
fn finish<L: Lanes>(
    p: [[L::V; 2]; 3],
    z: [L::V; 3],
    t_min: L::V,
    t_max: L::V,
    valid: u32,
) -> TriLanes<L> {
    let [[ax, ay], [bx, by], [cx, cy]] = p;
    let u = L::sub(L::mul(cx, by), L::mul(cy, bx));
    let v = L::sub(L::mul(ax, cy), L::mul(ay, cx));
    let w = L::sub(L::mul(bx, ay), L::mul(by, ax));
    let zero = L::splat(0.0);
    let any_zero = L::or(L::or(L::eq(u, zero), L::eq(v, zero)), L::eq(w, zero));
    let neg = L::or(L::or(L::lt(u, zero), L::lt(v, zero)), L::lt(w, zero));
    let pos = L::or(L::or(L::gt(u, zero), L::gt(v, zero)), L::gt(w, zero));
    let det = L::add(L::add(u, v), w);
    let t_scaled = L::add(L::add(L::mul(u, z[0]), L::mul(v, z[1])), L::mul(w, z[2]));
    let t = L::div(t_scaled, det);
    // Accept where the scalar routine returns Some: inside (not both signs), det != 0,
    // t_min <= t <= t_max (false for NaN t).
    let inside = L::andnot(L::and(neg, pos), L::le(t_min, t));
    let accept = L::and(L::andnot(L::eq(det, zero), inside), L::le(t, t_max));
    let zero_bits = L::bits(any_zero) & valid;
    TriLanes {
        hit: L::bits(accept) & valid & !zero_bits,
        zero: zero_bits,
        t,
        v,
        w,
        det,
    }
}

/// Tests one ray against the four triangles of `block` (`L::W` must be 4); lanes outside
/// `valid` are ignored.
#[inline(always)]
pub(crate) fn ray_vs_block<L: Lanes>(
    block: &TriBlock,
    ray: &SplatRay<L>,
    t_max: f32,
    valid: u32,
) -> TriLanes<L> {
    debug_assert_eq!(L::W, BLOCK);
    // No closures in kernels: a closure is a function of its own, compiled without the
    // caller's target features, so its intrinsics would not be inlined.
    let mut p = [[L::splat(0.0); 2]; 3];
    let mut z = [L::splat(0.0); 3];
    let [kx, ky, kz] = ray.k;
    let [sx, sy, sz] = ray.shear;
    for vertex in 0..3 {
        let coord = &block.v[3 * vertex..3 * vertex + 3];
        let x = L::sub(L::load(&coord[kx]), ray.origin[0]);
        let y = L::sub(L::load(&coord[ky]), ray.origin[1]);
        let vz = L::sub(L::load(&coord[kz]), ray.origin[2]);
        p[vertex] = [L::sub(x, L::mul(sx, vz)), L::sub(y, L::mul(sy, vz))];
        z[vertex] = L::mul(sz, vz);
    }
    finish::<L>(p, z, ray.t_min, L::splat(t_max), valid)
}

/// Tests the `W` rays of `rays` (each clipped to its lane of `t_max`) against the triangle
/// `tri` (nine coordinates, [`TriBlock::triangle`]); lanes outside `valid` are ignored.
#[inline(always)]
pub(crate) fn rays_vs_triangle<L: Lanes>(
    tri: &[f32; 9],
    rays: &RayLanes<L>,
    t_max: L::V,
    valid: u32,
) -> TriLanes<L> {
    let mut p = [[L::splat(0.0); 2]; 3];
    let mut z = [L::splat(0.0); 3];
    let [sx, sy, sz] = rays.shear;
    let is = match rays.uniform {
        Some(_) => [[L::mask(0); 2]; 3],
        None => rays.masks(),
    };
    for vertex in 0..3 {
        let v = [
            L::sub(L::splat(tri[3 * vertex]), rays.origin[0]),
            L::sub(L::splat(tri[3 * vertex + 1]), rays.origin[1]),
            L::sub(L::splat(tri[3 * vertex + 2]), rays.origin[2]),
        ];
        let (x, y, vz) = match rays.uniform {
            Some([kx, ky, kz]) => (v[kx], v[ky], v[kz]),
            None => (
                pick::<L>(&is, &v, 0),
                pick::<L>(&is, &v, 1),
                pick::<L>(&is, &v, 2),
            ),
        };
        p[vertex] = [L::sub(x, L::mul(sx, vz)), L::sub(y, L::mul(sy, vz))];
        z[vertex] = L::mul(sz, vz);
    }
    finish::<L>(p, z, rays.t_min, t_max, valid)
}
