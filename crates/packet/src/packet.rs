//! Coherent packets through the BVH8: `K` vectors of `W` rays (64 rays with AVX2) share
//! one traversal of the same wide tree the single rays walk.
//!
//! At each node, one interval-arithmetic slab test of the whole packet against all eight
//! children at once (the packet's frustum: the ranges of its origins and inverse
//! directions) rejects the children no ray can enter, and accepts for every lane the
//! children every ray enters (the same intervals, bounded the other way); only the children
//! in between get the per-lane SIMD slab tests, which give each the mask of lanes entering
//! it. Children are visited nearest first by the frustum's entry bound, each lane clips to
//! its own best `t`, and leaves test one triangle against all active lanes at once (or,
//! when few lanes are left, each lane against a block of four triangles). A packet whose
//! active lanes drop to [`SPLIT_LANES`] at an interior node finishes that subtree ray by
//! ray.
//!
//! A packet needs one octant (the same direction signs in every lane, so each axis has one
//! near plane) and finite rays; batches are cut into packets and any packet that is not
//! coherent in that sense takes the single-ray path lane by lane.

use crate::layout::{EMPTY_CHILD, LEAF_BIT, Layout, LeafRef, WIDE, WideNode, core_triangle};
use crate::simd::{Lanes, lanes_below, ray_rows};
use crate::single::{
    self, BitIter, FAR_SCALE, HitValues, STACK, Stack, block_closest, scalar_lanes,
};
use crate::tri::{RayLanes, SplatRay, TriLanes, rays_vs_triangle};
use raybench_geometry::{CULL_SLACK, Counters, Geometry, PrimHit, Ray, cull_bound, keep_closer};

/// Lanes at or below this count leave the packet at an interior node and finish its
/// subtree one ray at a time (the hybrid of Benthin, Boulos, Lacewell and Wald, "Combining
/// Single and Packet Ray Tracing for Arbitrary Ray Distributions on the Intel MIC
/// Architecture", 2012): a packet that has spread over many small nodes would otherwise
/// test every node against lanes that mostly miss it.
const SPLIT_LANES: u32 = 2;

/// The whole packet as intervals, splatted over the eight children of a node: per axis the
/// range of origins and of inverse directions, and the smallest `t_min`. One
/// interval-arithmetic slab test with these bounds every lane's box test (the interval
/// culling of Boulos et al., "Adaptive Ray Packet Reordering", 2008, and of Wald's packet
/// tracers): a child it rejects is entered by no lane.
///
/// It is conservative without widening: IEEE rounding is monotonic, so the corner products
/// of the intervals, computed with the lanes' own operations, bound every lane's computed
/// distance. A NaN corner (`0 * inf`) leaves the axis unconstrained, as a NaN does in the
/// lanes.
struct Frustum<S: Lanes> {
    origin: [(S::V, S::V); 3],
    inv: [(S::V, S::V); 3],
    negative: [bool; 3],
    t_min: S::V,
    /// The largest `t_min` of the packet.
    t_min_hi: S::V,
}

impl<S: Lanes> Frustum<S> {
    /// The frustum of a packet from its box-test lanes ([`split`]; padding lanes repeat a
    /// ray of the packet, so they change no bound). The ranges are reduced vector by
    /// vector, then across one vector's lanes: packets hold finite origins and non-NaN
    /// inverse directions, and no ray's `t_min` is NaN (`Ray::with_interval` makes an
    /// invalid ray's interval empty), so plain comparisons give the exact minimum and maximum (the
    /// per-ray `f32::min` loop this replaces spent a third of a primary any-hit packet's
    /// time on its NaN checks).
    #[inline(always)]
    fn new<L: Lanes, const K: usize>(chunks: &Chunks<L, K>, negative: [bool; 3]) -> Self {
        let mut origin = [(S::splat(0.0), S::splat(0.0)); 3];
        let mut inv = [(S::splat(0.0), S::splat(0.0)); 3];
        for axis in 0..3 {
            let (mut o_lo, mut o_hi) = (chunks[0].0.origin[axis], chunks[0].0.origin[axis]);
            let (mut i_lo, mut i_hi) = (chunks[0].0.inv[axis], chunks[0].0.inv[axis]);
            for chunk in &chunks[1..] {
                o_lo = L::min(o_lo, chunk.0.origin[axis]);
                o_hi = L::max(o_hi, chunk.0.origin[axis]);
                i_lo = L::min(i_lo, chunk.0.inv[axis]);
                i_hi = L::max(i_hi, chunk.0.inv[axis]);
            }
            origin[axis] = (S::splat(lowest::<L>(o_lo)), S::splat(highest::<L>(o_hi)));
            inv[axis] = (S::splat(lowest::<L>(i_lo)), S::splat(highest::<L>(i_hi)));
        }
        let (mut t_min, mut t_min_hi) = (chunks[0].0.t_min, chunks[0].0.t_min);
        for chunk in &chunks[1..] {
            t_min = L::min(t_min, chunk.0.t_min);
            t_min_hi = L::max(t_min_hi, chunk.0.t_min);
        }
        Self {
            origin,
            inv,
            negative,
            t_min: S::splat(lowest::<L>(t_min)),
            t_min_hi: S::splat(highest::<L>(t_min_hi)),
        }
    }

    /// Lower bounds of the lanes' entry distances into children `first..first + W` of
    /// `node`; the mask of the children some lane may enter at or before `limit` (the
    /// largest lane limit); and the mask of the children every lane enters at or before
    /// `limit_lo` (the smallest lane limit), which need no per-lane tests.
    ///
    /// The second mask bounds the other way round: the largest corner product of the near
    /// plane bounds every lane's entry from above, the smallest of the far plane its exit
    /// from below (the same monotonic rounding), so a child whose upper entry bound is at
    /// most its lower exit bound passes every lane's own slab test. A NaN corner leaves the
    /// lanes unbounded, so that child is not in it. (The per-lane tests of the children
    /// took about a fifth of a Sponza shadow packet's any-hit time.)
    #[inline(always)]
    fn entries(
        &self,
        node: &WideNode,
        first: usize,
        limit: S::V,
        limit_lo: S::V,
    ) -> (S::V, u32, u32) {
        let mut t0 = self.t_min;
        let mut t1 = limit;
        let mut t0_hi = self.t_min_hi;
        let mut t1_lo = limit_lo;
        // All lanes set (`t_min` is never NaN); cleared where a corner is NaN.
        let mut ordered_all = S::eq(t0_hi, t0_hi);
        let scale = S::splat(FAR_SCALE);
        for axis in 0..3 {
            let (lo, hi) = (
                S::load(&node.min[axis][first..]),
                S::load(&node.max[axis][first..]),
            );
            let (near, far) = if self.negative[axis] {
                (hi, lo)
            } else {
                (lo, hi)
            };
            let (o_lo, o_hi) = self.origin[axis];
            let (i_lo, i_hi) = self.inv[axis];
            let (n_lo, n_hi) = (S::sub(near, o_hi), S::sub(near, o_lo));
            let (f_lo, f_hi) = (S::sub(far, o_hi), S::sub(far, o_lo));
            let n = [
                S::mul(n_lo, i_lo),
                S::mul(n_lo, i_hi),
                S::mul(n_hi, i_lo),
                S::mul(n_hi, i_hi),
            ];
            let f = [
                S::mul(f_lo, i_lo),
                S::mul(f_lo, i_hi),
                S::mul(f_hi, i_lo),
                S::mul(f_hi, i_hi),
            ];
            let ordered = |c: &[S::V; 4]| {
                S::and(
                    S::and(S::eq(c[0], c[0]), S::eq(c[1], c[1])),
                    S::and(S::eq(c[2], c[2]), S::eq(c[3], c[3])),
                )
            };
            let near_lo = S::min(S::min(n[0], n[1]), S::min(n[2], n[3]));
            let far_hi = S::max(S::max(f[0], f[1]), S::max(f[2], f[3]));
            let near_hi = S::max(S::max(n[0], n[1]), S::max(n[2], n[3]));
            let far_lo = S::min(S::min(f[0], f[1]), S::min(f[2], f[3]));
            let (n_ok, f_ok) = (ordered(&n), ordered(&f));
            // Any NaN corner: the axis constrains nothing for that child (and a lane's
            // NaN is not bounded by the corners: no child is known to be entered by all).
            ordered_all = S::and(ordered_all, S::and(n_ok, f_ok));
            let near_lo = S::select(n_ok, near_lo, S::splat(f32::NEG_INFINITY));
            let far_hi = S::select(f_ok, far_hi, S::splat(f32::INFINITY));
            t0 = S::max(near_lo, t0);
            t1 = S::min(S::mul(far_hi, scale), t1);
            t0_hi = S::max(near_hi, t0_hi);
            t1_lo = S::min(S::mul(far_lo, scale), t1_lo);
        }
        let full = S::and(ordered_all, S::le(t0_hi, t1_lo));
        (t0, S::bits(S::le(t0, t1)), S::bits(full))
    }
}

/// The smallest lane of `v` (no lane is NaN).
#[inline(always)]
fn lowest<L: Lanes>(v: L::V) -> f32 {
    let mut a = [0.0f32; 16];
    L::store(v, &mut a);
    let mut m = a[0];
    for &x in &a[1..L::W] {
        if x < m {
            m = x;
        }
    }
    m
}

/// The largest lane of `v` (no lane is NaN).
#[inline(always)]
fn highest<L: Lanes>(v: L::V) -> f32 {
    let mut a = [0.0f32; 16];
    L::store(v, &mut a);
    let mut m = a[0];
    for &x in &a[1..L::W] {
        if x > m {
            m = x;
        }
    }
    m
}

/// Box-test lanes of one vector of a packet.
#[derive(Clone, Copy)]
struct SlabLanes<L: Lanes> {
    origin: [L::V; 3],
    inv: [L::V; 3],
    t_min: L::V,
}

impl<L: Lanes> SlabLanes<L> {
    /// The lanes that enter child `slot` of `node` no later than their lane of `limit`: the core's
    /// conservative slab test, with the near plane of each axis given by the packet's
    /// common direction signs.
    #[inline(always)]
    fn enters(&self, node: &WideNode, slot: usize, negative: &[bool; 3], limit: L::V) -> u32 {
        let min = std::array::from_fn(|axis| node.min[axis][slot]);
        let max = std::array::from_fn(|axis| node.max[axis][slot]);
        self.enters_box(min, max, negative, limit)
    }

    /// The lanes that enter the box `[min, max]` no later than their lane of `limit`, as
    /// [`SlabLanes::enters`] tests a child (per lane, the decision of the core's
    /// `SlabRay::entry`: a NaN axis leaves the bound, and the maximum and minimum are
    /// exact in any order).
    #[inline(always)]
    fn enters_box(&self, min: [f32; 3], max: [f32; 3], negative: &[bool; 3], limit: L::V) -> u32 {
        let mut t0 = self.t_min;
        let mut t1 = limit;
        for (axis, &neg) in negative.iter().enumerate() {
            let (lo, hi) = (min[axis], max[axis]);
            let (near, far) = if neg { (hi, lo) } else { (lo, hi) };
            let tn = L::mul(L::sub(L::splat(near), self.origin[axis]), self.inv[axis]);
            let tf = L::mul(L::sub(L::splat(far), self.origin[axis]), self.inv[axis]);
            // NaN (0 * inf) first: the x86 min/max then return the accumulated bound.
            t0 = L::max(tn, t0);
            t1 = L::min(L::mul(tf, L::splat(FAR_SCALE)), t1);
        }
        L::bits(L::le(t0, t1))
    }
}

/// A packet's vectors for box tests: slab-test lanes, `t_max` and the mask of lanes
/// holding a ray ([`split`]).
type Chunks<L, const K: usize> = [(SlabLanes<L>, <L as Lanes>::V, u32); K];

/// The `K` vectors of a packet of at most `K * W` rays for box tests: slab-test lanes,
/// `t_max` and the mask of lanes holding a ray. Missing rays repeat the last one.
#[inline(always)]
fn split<L: Lanes, const K: usize>(rays: &[Ray]) -> Chunks<L, K> {
    let n = rays.len();
    let mut out = [(
        SlabLanes {
            origin: [L::splat(0.0); 3],
            inv: [L::splat(0.0); 3],
            t_min: L::splat(0.0),
        },
        L::splat(0.0),
        0,
    ); K];
    for (k, chunk) in out.iter_mut().enumerate() {
        let lo = (k * L::W).min(n - 1);
        let part = &rays[lo..n.min(lo + L::W).max(lo + 1)];
        let (head, tail) = ray_rows::<L>(part);
        // Columns of floats 0..8 (origin, dir, inv_dir.x, .y) and 6..14 (inv_dir, t_min,
        // t_max, shear).
        let (a, b) = (L::columns8(&head), L::columns8(&tail));
        *chunk = (
            SlabLanes {
                origin: [a[0], a[1], a[2]],
                inv: [a[6], a[7], b[2]],
                t_min: b[3],
            },
            b[4],
            if k * L::W < n {
                lanes_below::<L>(n - k * L::W)
            } else {
                0
            },
        );
    }
    out
}

/// The `K` vectors of a packet for triangle tests (made only when the packet reaches a
/// leaf: rays that end before any leaf never need them).
#[inline(always)]
fn triangle_lanes<L: Lanes, const K: usize>(rays: &[Ray]) -> [RayLanes<L>; K] {
    let n = rays.len();
    let mut out = [RayLanes::new(&rays[..n.min(L::W)]); K];
    for (k, lanes) in out.iter_mut().enumerate().skip(1) {
        let lo = (k * L::W).min(n - 1);
        *lanes = RayLanes::new(&rays[lo..n.min(lo + L::W).max(lo + 1)]);
    }
    out
}

/// The lanes set in `masks`, the packet's rays that enter a node, counted as node visits.
#[inline]
fn visit<C: Counters>(masks: &[u32], counters: &mut C) -> u32 {
    let active: u32 = masks.iter().map(|m| m.count_ones()).sum();
    counters.add_visits(u64::from(active));
    active
}

/// The common octant of `rays` (bit `a` set when the inverse direction along axis `a` is
/// negative, as `raybench_geometry::SlabRay` decides), or `None` when the rays are not one
/// coherent packet (mixed signs, or a non-finite origin or direction).
pub(crate) fn octant(rays: &[Ray]) -> Option<u8> {
    let sign = |r: &Ray| {
        let s = r.inv_dir;
        // Only rays with finite directions form packets, so the inverse is never NaN and
        // `< 0` is `SlabRay`'s `!(>= 0)`.
        u8::from(s.x < 0.0) | u8::from(s.y < 0.0) << 1 | u8::from(s.z < 0.0) << 2
    };
    let first = sign(rays.first()?);
    rays.iter()
        .all(|r| r.origin.is_finite() && r.dir.is_finite() && sign(r) == first)
        .then_some(first)
}

/// A packet traversal stack entry: a child reference, the frustum's entry bound, and the
/// lanes (per vector) that entered it.
pub(crate) type Entry<const K: usize> = (u32, f32, [u32; K]);

/// A packet traversal stack (allocated once per batch).
pub(crate) type PacketStack<const K: usize> = [Entry<K>; STACK];

/// Most rays in a packet (`K * W` for every instruction set).
pub(crate) const MAX_PACKET: usize = 64;

/// Per-lane state of a closest-hit packet.
struct Lanestate {
    t_best: [f32; MAX_PACKET],
    limit: [f32; MAX_PACKET],
}

impl Lanestate {
    #[inline(always)]
    fn update(&mut self, i: usize, ray: &Ray, best: &Option<(u32, PrimHit)>) {
        self.t_best[i] = best.map_or(ray.t_max, |(_, h)| h.t);
        self.limit[i] = cull_bound(self.t_best[i]);
    }

    /// [`Self::update`] of the hit lanes of a triangle test of the vector at `base`, in
    /// vectors: a lane hits only at or before its best `t`, and a tie keeps the same `t`,
    /// so each hit lane's best `t` is now its `t` (and its limit `cull_bound` of it, the
    /// same operations: `|t|` as `max(t, 0 - t)`, which gives `+0` for `-0`).
    #[inline(always)]
    fn take_hits<L: Lanes>(&mut self, base: usize, r: &TriLanes<L>) {
        let hit = L::mask(r.hit);
        let t_best = L::select(hit, r.t, L::load(&self.t_best[base..]));
        L::store(t_best, &mut self.t_best[base..]);
        let limit = L::select(hit, cull_bounds::<L>(r.t), L::load(&self.limit[base..]));
        L::store(limit, &mut self.limit[base..]);
    }
}

/// [`cull_bound`] of every lane of `t`, with the same operations (`|t|` as `max(t, 0 - t)`,
/// which gives `+0` for `-0`).
#[inline(always)]
fn cull_bounds<L: Lanes>(t: L::V) -> L::V {
    let abs = L::max(t, L::sub(L::splat(0.0), t));
    L::add(t, L::mul(abs, L::splat(CULL_SLACK)))
}

/// `r` keeping only the hit lanes whose ray enters the box of the triangle `tri` (nine
/// coordinates) by its hit: the core's `Triangle::box_entered_by` in lanes (the box as the
/// core computes it, each lane's slab test as [`SlabLanes::enters`] makes it, up to
/// [`cull_bound`] of the lane's `t`), so that a lane the edge functions accept beside its
/// triangle is no hit, as in the scalar routine.
#[inline(always)]
fn boxed<L: Lanes>(
    tri: &[f32; 9],
    slab: &SlabLanes<L>,
    negative: &[bool; 3],
    r: TriLanes<L>,
) -> TriLanes<L> {
    if r.hit == 0 {
        return r;
    }
    let b = core_triangle(tri).bounds();
    let entered = slab.enters_box(
        b.min.to_array(),
        b.max.to_array(),
        negative,
        cull_bounds::<L>(r.t),
    );
    TriLanes {
        hit: r.hit & entered,
        ..r
    }
}

/// Closest hits of a coherent packet of at most `K * W` rays with octant `oct`: `best[i]`
/// arrives holding ray `i`'s hit with the unbounded primitives and leaves with its closest
/// hit.
#[inline(always)]
// The kernel's inputs are separate borrows on purpose: bundling them would only move the
// same names into a struct built for one call.
#[allow(clippy::too_many_arguments)]
pub(crate) fn closest<L: Lanes, const K: usize, C: Counters>(
    layout: &Layout,
    g: &Geometry,
    rays: &[Ray],
    oct: u8,
    best: &mut [Option<(u32, PrimHit)>],
    stack: &mut PacketStack<K>,
    scratch: &mut Stack,
    counters: &mut C,
) {
    const { assert!(K * L::W <= MAX_PACKET) };
    if layout.wide.is_empty() {
        return;
    }
    let n = rays.len();
    let mut st = Lanestate {
        t_best: [0.0; MAX_PACKET],
        limit: [0.0; MAX_PACKET],
    };
    for i in 0..n {
        st.update(i, &rays[i], &best[i]);
    }
    let chunks = split::<L, K>(rays);
    let negative = [oct & 1 != 0, oct & 2 != 0, oct & 4 != 0];
    let frustum = Frustum::<L::Single>::new(&chunks, negative);
    stack[0] = (0, f32::NEG_INFINITY, std::array::from_fn(|k| chunks[k].2));
    let mut tri_lanes: Option<[RayLanes<L>; K]> = None;
    let mut sp = 1;
    while sp > 0 {
        sp -= 1;
        let (index, entry, pushed) = stack[sp];
        // Lanes still interested: entered the child, and not yet clipped before it.
        let mut masks = [0u32; K];
        let entry_v = L::splat(entry);
        for k in 0..K {
            if pushed[k] != 0 {
                masks[k] = pushed[k] & L::bits(L::le(entry_v, L::load(&st.limit[k * L::W..])));
            }
        }
        let active = visit(&masks, counters);
        if active == 0 {
            continue;
        }
        if index & LEAF_BIT != 0 {
            let lanes = tri_lanes.get_or_insert_with(|| triangle_lanes::<L, K>(rays));
            packet_leaf::<L, K, C>(
                layout,
                g,
                rays,
                lanes,
                (&chunks, &negative),
                LeafRef::decode(index),
                &masks,
                best,
                &mut st,
                counters,
            );
            continue;
        }
        if active <= SPLIT_LANES {
            // The packet has diverged: its last lanes finish this subtree one by one.
            for (k, m) in masks.iter().enumerate() {
                for lane in BitIter(*m) {
                    let i = k * L::W + lane;
                    best[i] = single::closest::<L, C>(
                        layout, g, &rays[i], index, best[i], scratch, counters,
                    );
                    st.update(i, &rays[i], &best[i]);
                }
            }
            continue;
        }
        let node = &layout.wide[index as usize];
        // The largest and the smallest limit of the active lanes (limits are never NaN).
        let mut limits = [L::splat(0.0); K];
        let mut widest = L::splat(f32::NEG_INFINITY);
        let mut narrowest = L::splat(f32::INFINITY);
        for (k, limit) in limits.iter_mut().enumerate() {
            *limit = L::load(&st.limit[k * L::W..]);
            if masks[k] != 0 {
                let lanes = L::mask(masks[k]);
                widest = L::max(
                    widest,
                    L::select(lanes, *limit, L::splat(f32::NEG_INFINITY)),
                );
                narrowest = L::min(narrowest, L::select(lanes, *limit, L::splat(f32::INFINITY)));
            }
        }
        let packet_limit = <L::Single as Lanes>::splat(highest::<L>(widest));
        let packet_limit_lo = <L::Single as Lanes>::splat(lowest::<L>(narrowest));
        // Children hit by some lane, sorted far to near by the frustum's entry bound.
        let mut found: [Entry<K>; WIDE] = [(0, 0.0, [0; K]); WIDE];
        let mut count = 0;
        let mut first = 0;
        while first < WIDE {
            let (t0, bits, full) = frustum.entries(node, first, packet_limit, packet_limit_lo);
            if bits != 0 {
                let mut t = [0.0f32; 16];
                <L::Single as Lanes>::store(t0, &mut t);
                for slot in BitIter(bits) {
                    let child = node.child[first + slot];
                    if child == EMPTY_CHILD {
                        continue;
                    }
                    let lanes = if full & (1 << slot) != 0 {
                        Some(masks)
                    } else {
                        child_lanes(&chunks, node, first + slot, &negative, &masks, &limits)
                    };
                    let Some(lanes) = lanes else {
                        continue;
                    };
                    let e = t[slot];
                    // Equal entries (lanes starting inside both boxes) leave the lower slot
                    // to be popped first: the layout's any-hit order, backwards, had 11 %
                    // fewer triangle tests per shadow ray on Sponza than forwards.
                    let mut j = count;
                    while j > 0 && found[j - 1].1 <= e {
                        found[j] = found[j - 1];
                        j -= 1;
                    }
                    found[j] = (child, e, lanes);
                    count += 1;
                }
            }
            first += <L::Single as Lanes>::W;
        }
        for &(child, _, _) in &found[..count] {
            single::prefetch_child(layout, child);
        }
        stack[sp..sp + count].copy_from_slice(&found[..count]);
        sp += count;
    }
}

/// The lanes of each vector (among `masks`) that enter child `slot` of `node` no later than
/// their lane of `limits`, or `None` when no lane does.
#[inline(always)]
fn child_lanes<L: Lanes, const K: usize>(
    chunks: &Chunks<L, K>,
    node: &WideNode,
    slot: usize,
    negative: &[bool; 3],
    masks: &[u32; K],
    limits: &[L::V; K],
) -> Option<[u32; K]> {
    let mut lanes = [0u32; K];
    let mut any = 0;
    for k in 0..K {
        if masks[k] != 0 {
            lanes[k] = chunks[k].0.enters(node, slot, negative, limits[k]) & masks[k];
            any |= lanes[k];
        }
    }
    (any != 0).then_some(lanes)
}

/// Tests the leaf `leaf` against the lanes `masks` of a packet.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn packet_leaf<L: Lanes, const K: usize, C: Counters>(
    layout: &Layout,
    g: &Geometry,
    rays: &[Ray],
    tri_lanes: &[RayLanes<L>; K],
    (chunks, negative): (&Chunks<L, K>, &[bool; 3]),
    leaf: LeafRef,
    masks: &[u32; K],
    best: &mut [Option<(u32, PrimHit)>],
    st: &mut Lanestate,
    counters: &mut C,
) {
    let active: u32 = masks.iter().map(|m| m.count_ones()).sum();
    let vectors = masks.iter().filter(|&&m| m != 0).count() as u32;
    for block in &layout.blocks[leaf.first..leaf.first + leaf.blocks] {
        let occupied = block.occupied();
        let tris = occupied.count_ones();
        if C::ENABLED {
            counters.add_tests(u64::from(active * tris));
        }
        // Few lanes left (the packet has diverged): one SIMD test of the block per lane is
        // cheaper than one SIMD test of the lanes per triangle.
        if active < vectors * tris {
            for (k, m) in masks.iter().enumerate() {
                for lane in BitIter(*m) {
                    let i = k * L::W + lane;
                    let splat = SplatRay::<L::Narrow>::new(&rays[i]);
                    block_closest(g, block, leaf.mixed, &rays[i], &splat, &mut best[i]);
                    st.update(i, &rays[i], &best[i]);
                }
            }
            continue;
        }
        let scalar = if leaf.mixed {
            scalar_lanes(g, block)
        } else {
            0
        };
        for j in BitIter(occupied) {
            let id = block.id[j];
            if scalar & (1 << j) != 0 {
                for (k, m) in masks.iter().enumerate() {
                    for lane in BitIter(*m) {
                        let i = k * L::W + lane;
                        g.test_closest(id, &rays[i], &mut best[i]);
                        st.update(i, &rays[i], &best[i]);
                    }
                }
                continue;
            }
            let tri = block.triangle(j);
            for (k, lanes) in tri_lanes.iter().enumerate() {
                if masks[k] == 0 {
                    continue;
                }
                let base = k * L::W;
                let r = rays_vs_triangle(&tri, lanes, L::load(&st.t_best[base..]), masks[k]);
                let r = boxed(&tri, &chunks[k].0, negative, r);
                if r.hit != 0 {
                    let hits = HitValues::new(&r);
                    for lane in BitIter(r.hit) {
                        keep_closer(&mut best[base + lane], id, hits.get(lane));
                    }
                    st.take_hits(base, &r);
                }
                for lane in BitIter(r.zero) {
                    g.test_closest(id, &rays[base + lane], &mut best[base + lane]);
                    st.update(base + lane, &rays[base + lane], &best[base + lane]);
                }
            }
        }
    }
}

/// An any-hit packet traversal stack entry: a child reference and the packet's lanes that
/// entered it, lane `lane` of vector `k` at bit `k * W + lane`. One `u64` holds the whole
/// packet (`K * W <= 64`), so that a stack entry, the open lanes and a node's live lanes
/// are one integer each (per-vector masks cost an array operation at every step).
pub(crate) type AnyEntry = (u32, u64);

/// An any-hit packet traversal stack, allocated once per batch.
pub(crate) type AnyStack = [AnyEntry; STACK];

/// The lane set of per-vector masks `masks` (the inverse of [`vector_lanes`]).
#[inline(always)]
fn packed<L: Lanes, const K: usize>(masks: &[u32; K]) -> u64 {
    let mut lanes = 0;
    for (k, &m) in masks.iter().enumerate() {
        lanes |= u64::from(m) << (k * L::W);
    }
    lanes
}

/// Vector `k`'s lanes of the lane set `lanes`.
#[inline(always)]
fn vector_lanes<L: Lanes>(lanes: u64, k: usize) -> u32 {
    ((lanes >> (k * L::W)) & ((1 << L::W) - 1)) as u32
}

/// Any-hit results of a coherent packet: `blocked[i]` arrives true for rays already
/// blocked (by an unbounded primitive) and leaves true for every blocked ray. A lane leaves
/// the packet as soon as it is blocked, and the packet stops when none is left. Children
/// are pushed in slot order, so the highest slot (the layout's any-hit order) goes first. As in
/// [`closest`], a packet down to [`SPLIT_LANES`] lanes at an interior node finishes that
/// subtree ray by ray, and a leaf block meets few lanes one lane at a time.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn occluded<L: Lanes, const K: usize, C: Counters>(
    layout: &Layout,
    g: &Geometry,
    rays: &[Ray],
    oct: u8,
    blocked: &mut [bool],
    stack: &mut AnyStack,
    scratch: &mut Stack,
    counters: &mut C,
) {
    const { assert!(K * L::W <= 64) };
    if layout.wide.is_empty() {
        return;
    }
    let mut open = 0u64;
    for (i, b) in blocked.iter().enumerate() {
        if !*b {
            open |= 1 << i;
        }
    }
    let chunks = split::<L, K>(rays);
    let mut t_max = [L::splat(0.0); K];
    for (t, chunk) in t_max.iter_mut().zip(&chunks) {
        *t = chunk.1;
    }
    let mut tri_lanes: Option<[RayLanes<L>; K]> = None;
    let negative = [oct & 1 != 0, oct & 2 != 0, oct & 4 != 0];
    let frustum = Frustum::<L::Single>::new(&chunks, negative);
    // The largest and the smallest `t_max` of the packet.
    let (lo, hi) = rays
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), r| {
            (lo.min(r.t_max), hi.max(r.t_max))
        });
    let packet_limit = <L::Single as Lanes>::splat(hi);
    let packet_limit_lo = <L::Single as Lanes>::splat(lo);
    stack[0] = (0, open);
    let mut sp = 1;
    while sp > 0 && open != 0 {
        sp -= 1;
        let (index, pushed) = stack[sp];
        let live = pushed & open;
        if live == 0 {
            continue;
        }
        let active = live.count_ones();
        counters.add_visits(u64::from(active));
        if index & LEAF_BIT != 0 {
            let tri_lanes = tri_lanes.get_or_insert_with(|| triangle_lanes::<L, K>(rays));
            packet_leaf_any::<L, K, C>(
                layout,
                g,
                rays,
                tri_lanes,
                (&chunks, &negative),
                LeafRef::decode(index),
                live,
                &mut open,
                blocked,
                counters,
            );
            continue;
        }
        if active <= SPLIT_LANES {
            // The packet has diverged: its last lanes finish this subtree one by one.
            for i in BitIter(live) {
                if single::occluded::<L, C>(layout, g, &rays[i], index, scratch, counters) {
                    blocked[i] = true;
                    open &= !(1 << i);
                }
            }
            continue;
        }
        let node = &layout.wide[index as usize];
        let masks: [u32; K] = std::array::from_fn(|k| vector_lanes::<L>(live, k));
        let mut first = 0;
        while first < WIDE {
            let (_, bits, full) = frustum.entries(node, first, packet_limit, packet_limit_lo);
            for slot in BitIter(bits) {
                let child = node.child[first + slot];
                if child == EMPTY_CHILD {
                    continue;
                }
                let lanes = if full & (1 << slot) != 0 {
                    live
                } else {
                    child_lanes(&chunks, node, first + slot, &negative, &masks, &t_max)
                        .map_or(0, |lanes| packed::<L, K>(&lanes))
                };
                if lanes != 0 {
                    single::prefetch_child(layout, child);
                    stack[sp] = (child, lanes);
                    sp += 1;
                }
            }
            first += <L::Single as Lanes>::W;
        }
    }
}

/// Tests the leaf `leaf` against the lanes `entered` of a packet that are still in `open`,
/// marking the lanes it blocks in `blocked` and closing them in `open`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn packet_leaf_any<L: Lanes, const K: usize, C: Counters>(
    layout: &Layout,
    g: &Geometry,
    rays: &[Ray],
    tri_lanes: &[RayLanes<L>; K],
    (chunks, negative): (&Chunks<L, K>, &[bool; 3]),
    leaf: LeafRef,
    entered: u64,
    open: &mut u64,
    blocked: &mut [bool],
    counters: &mut C,
) {
    for block in &layout.blocks[leaf.first..leaf.first + leaf.blocks] {
        let occupied = block.occupied();
        let tris = occupied.count_ones();
        let live = entered & *open;
        if live == 0 {
            return;
        }
        let active = live.count_ones();
        if C::ENABLED {
            counters.add_tests(u64::from(active * tris));
        }
        let vectors = (0..K).filter(|&k| vector_lanes::<L>(live, k) != 0).count() as u32;
        // Few lanes left: one SIMD test of the block per lane is cheaper than one SIMD
        // test of the lanes per triangle.
        if active < vectors * tris {
            for i in BitIter(live) {
                let splat = SplatRay::<L::Narrow>::new(&rays[i]);
                if single::block_occluded(g, block, leaf.mixed, &rays[i], &splat) {
                    blocked[i] = true;
                    *open &= !(1 << i);
                }
            }
            continue;
        }
        let scalar = if leaf.mixed {
            scalar_lanes(g, block)
        } else {
            0
        };
        for j in BitIter(occupied) {
            let tri = block.triangle(j);
            // The vectors' tests are independent: each reads its lanes from `live` and the
            // blocked lanes are closed after all (closing them in `open` vector by vector
            // chained every vector's test to the previous one's division).
            let live = entered & *open;
            let mut closed = 0u64;
            for (k, (lanes, (_, t_max, _))) in tri_lanes.iter().zip(chunks).enumerate() {
                let m = vector_lanes::<L>(live, k);
                if m == 0 {
                    continue;
                }
                let (mut hit, mut test) = (0, m);
                if scalar & (1 << j) == 0 {
                    let r = rays_vs_triangle(&tri, lanes, *t_max, m);
                    let r = boxed(&tri, &chunks[k].0, negative, r);
                    (hit, test) = (r.hit, r.zero);
                }
                if test != 0 {
                    let shape = g.shape(block.id[j]);
                    for lane in BitIter(test) {
                        if shape.intersect(&rays[k * L::W + lane]).is_some() {
                            hit |= 1 << lane;
                        }
                    }
                }
                for lane in BitIter(hit) {
                    blocked[k * L::W + lane] = true;
                }
                closed |= u64::from(hit) << (k * L::W);
            }
            *open &= !closed;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simd::Portable;
    use raybench_geometry::Vec3;

    /// A small deterministic generator (xorshift32) for the test's geometry.
    struct Xorshift(u32);

    impl Xorshift {
        fn next(&mut self) -> u32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 17;
            self.0 ^= self.0 << 5;
            self.0
        }

        /// A value of `-range..range` snapped to a grid of eighths, so that ray origins
        /// often lie exactly on box planes (`0 * inf` corners with axis-parallel rays).
        fn coord(&mut self, range: f32) -> f32 {
            let steps = (range * 8.0) as u32 * 2;
            (self.next() % (steps + 1)) as f32 / 8.0 - range
        }
    }

    /// Every lane enters each child the frustum says all lanes enter: for random packets
    /// in one octant (some with axis-parallel directions, some with origins on the boxes'
    /// planes) against random boxes, the per-lane slab test of such a child passes in every
    /// lane. The test also requires the shortcut to be taken, so it cannot pass vacuously.
    #[test]
    fn children_entered_by_every_lane_pass_every_lane_test() {
        const K: usize = 2;
        let mut rng = Xorshift(0x9e37_79b9);
        let (mut full_children, mut partial_children) = (0, 0);
        for packet in 0..4000 {
            let n = 1 + packet % (K * Portable::W);
            let base = Vec3::new(rng.coord(4.0), rng.coord(4.0), rng.coord(4.0));
            let mut sign = || {
                if rng.next().is_multiple_of(2) {
                    1.0
                } else {
                    -1.0
                }
            };
            let signs = Vec3::new(sign(), sign(), sign());
            let flat_axis = packet % 5;
            let rays: Vec<Ray> = (0..n)
                .map(|_| {
                    // A third of the packets share one origin.
                    let origin = if packet % 3 == 0 {
                        base
                    } else {
                        base + Vec3::new(rng.coord(0.5), rng.coord(0.5), rng.coord(0.5))
                    };
                    let mut dir = Vec3::new(
                        1.0 + (rng.next() % 100) as f32 / 100.0,
                        1.0 + (rng.next() % 100) as f32 / 100.0,
                        1.0 + (rng.next() % 100) as f32 / 100.0,
                    ) * signs;
                    if flat_axis < 3 {
                        dir[flat_axis] = 0.0 * signs[flat_axis];
                    }
                    let t_max = if packet % 2 == 0 {
                        f32::INFINITY
                    } else {
                        2.0 + (rng.next() % 400) as f32 / 100.0
                    };
                    Ray::with_interval(origin, dir, 0.0, t_max)
                })
                .collect();
            let Some(oct) = octant(&rays) else {
                continue;
            };
            let negative = [oct & 1 != 0, oct & 2 != 0, oct & 4 != 0];
            let chunks = split::<Portable, K>(&rays);
            let frustum = Frustum::<Portable>::new(&chunks, negative);
            let mut node = WideNode {
                min: [[0.0; WIDE]; 3],
                max: [[0.0; WIDE]; 3],
                child: [0; WIDE],
            };
            for slot in 0..WIDE {
                for axis in 0..3 {
                    let (a, b) = (rng.coord(6.0), rng.coord(6.0));
                    node.min[axis][slot] = a.min(b);
                    node.max[axis][slot] = a.max(b);
                }
                node.child[slot] = slot as u32;
            }
            let limit = rays.iter().fold(f32::NEG_INFINITY, |a, r| a.max(r.t_max));
            let limit_lo = rays.iter().fold(f32::INFINITY, |a, r| a.min(r.t_max));
            let masks: [u32; K] = std::array::from_fn(|k| chunks[k].2);
            let t_max: [_; K] = std::array::from_fn(|k| chunks[k].1);
            for first in (0..WIDE).step_by(Portable::W) {
                let (_, some, every) = frustum.entries(
                    &node,
                    first,
                    Portable::splat(limit),
                    Portable::splat(limit_lo),
                );
                assert_eq!(
                    every & !some,
                    0,
                    "a child entered by every lane but not by some"
                );
                for slot in 0..Portable::W {
                    let lanes =
                        child_lanes(&chunks, &node, first + slot, &negative, &masks, &t_max);
                    if every & (1 << slot) != 0 {
                        assert_eq!(
                            lanes,
                            Some(masks),
                            "packet {packet}, child {}",
                            first + slot
                        );
                        full_children += 1;
                    } else if lanes.is_some() {
                        partial_children += 1;
                    }
                }
            }
        }
        assert!(
            full_children > 1000 && partial_children > 1000,
            "{full_children} {partial_children}"
        );
    }
}
