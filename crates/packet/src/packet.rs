//! Coherent packets through the BVH2: `K` vectors of `W` rays (8 or 16 rays with AVX2)
//! share one traversal. Each node's box is tested against every active lane in SIMD, the
//! packet descends while any lane enters, children are visited in the order the packet's
//! common direction signs give along the node's split axis, and each lane clips to its own
//! best `t`. Leaves test one triangle against all lanes at once.
//!
//! A packet needs one octant (the same direction signs in every lane, so each axis has one
//! near plane) and finite rays; batches are cut into packets and any packet that is not
//! coherent in that sense takes the single-ray BVH8 path lane by lane.

use crate::layout::{Layout, Leaf};
use crate::simd::Lanes;
use crate::single::{BitIter, FAR_SCALE, Stack, lanes_below, leaf_closest, prim_hit};
use crate::tri::{RayLanes, SplatRay, rays_vs_triangle};
use raybench_core::{Counters, Geometry, Hit, NodeStack, PrimHit, Ray, SlabRay, cull_bound};

/// Lanes at or below this count leave the packet at an interior node and finish its
/// subtree one ray at a time (the hybrid of Benthin, Boulos, Lacewell and Wald, "Combining
/// Single and Packet Ray Tracing for Arbitrary Ray Distributions on the Intel MIC
/// Architecture", 2012): a packet that has spread over many small nodes would otherwise
/// test every node against lanes that mostly miss it.
const SPLIT_LANES: u32 = 2;

/// The closest hit of one ray in the BVH2 subtree under `root`, merged into `best`: the
/// scalar slab test for boxes, the SIMD leaf test over triangles.
#[inline(always)]
fn subtree_closest<L: Lanes, C: Counters>(
    layout: &Layout,
    g: &Geometry,
    ray: &Ray,
    root: usize,
    best: &mut Option<(u32, PrimHit)>,
    stack: &mut Stack,
    counters: &mut C,
) {
    let nodes = layout.bvh.nodes();
    let slab = SlabRay::new(ray);
    let splat = SplatRay::<L::Single>::new(ray);
    let mut limit = cull_bound(best.map_or(ray.t_max, |(_, h)| h.t));
    let mut stack = NodeStack::new(stack);
    stack.push(root as u32, f32::NEG_INFINITY);
    while let Some((index, _)) = stack.pop_within(limit) {
        counters.add_visits(1);
        let node = &nodes[index as usize];
        if node.is_leaf() {
            let leaf = Leaf {
                first: node.first_or_right,
                count: node.count,
                all_triangles: layout.node_all_triangles[index as usize],
            };
            leaf_closest(layout, g, leaf, ray, &splat, best, counters);
            limit = cull_bound(best.map_or(ray.t_max, |(_, h)| h.t));
            continue;
        }
        let (l, r) = (index + 1, node.first_or_right);
        let (nl, nr) = (&nodes[l as usize], &nodes[r as usize]);
        let tl = slab.entry(nl.min.into(), nl.max.into(), limit);
        let tr = slab.entry(nr.min.into(), nr.max.into(), limit);
        match (tl, tr) {
            (Some(a), Some(b)) if a <= b => {
                stack.push(r, b);
                stack.push(l, a);
            }
            (Some(a), Some(b)) => {
                stack.push(l, a);
                stack.push(r, b);
            }
            (Some(a), None) => stack.push(l, a),
            (None, Some(b)) => stack.push(r, b),
            (None, None) => {}
        }
    }
}

/// The whole packet as intervals: per axis the range of origins and of inverse directions,
/// and the smallest `t_min`. One scalar interval-arithmetic slab test with these bounds
/// every lane's box test (Boulos et al., "Adaptive Ray Packet Reordering", 2008, and the
/// interval culling of Wald's packet tracers): when it says the box is missed, every lane
/// would have missed it, so the per-lane SIMD tests are skipped.
///
/// It is conservative without widening: IEEE rounding is monotonic, so the corner products
/// of the intervals, computed with the lanes' own operations, bound every lane's computed
/// distance; a NaN corner (`0 * inf`) leaves the axis unconstrained, as in the lanes.
#[derive(Clone, Copy, Debug)]
struct PacketInterval {
    origin: [(f32, f32); 3],
    inv: [(f32, f32); 3],
    t_min: f32,
}

impl PacketInterval {
    fn new(rays: &[Ray]) -> Self {
        let mut s = Self {
            origin: [(f32::INFINITY, f32::NEG_INFINITY); 3],
            inv: [(f32::INFINITY, f32::NEG_INFINITY); 3],
            t_min: f32::INFINITY,
        };
        for r in rays {
            for axis in 0..3 {
                let (o, i) = (r.origin[axis], r.inv_dir[axis]);
                s.origin[axis] = (s.origin[axis].0.min(o), s.origin[axis].1.max(o));
                s.inv[axis] = (s.inv[axis].0.min(i), s.inv[axis].1.max(i));
            }
            s.t_min = s.t_min.min(r.t_min);
        }
        s
    }

    /// False only when no ray of the packet can enter `node` at or before `limit` (the
    /// largest lane limit).
    #[inline(always)]
    fn may_enter(&self, node: &raybench_bvh::Node, negative: &[bool; 3], limit: f32) -> bool {
        let mut t0 = self.t_min;
        let mut t1 = limit;
        for (axis, &neg) in negative.iter().enumerate() {
            let (near, far) = if neg {
                (node.max[axis], node.min[axis])
            } else {
                (node.min[axis], node.max[axis])
            };
            let (o_lo, o_hi) = self.origin[axis];
            let (i_lo, i_hi) = self.inv[axis];
            let corners = |plane: f32| {
                let (d_lo, d_hi) = (plane - o_hi, plane - o_lo);
                [d_lo * i_lo, d_lo * i_hi, d_hi * i_lo, d_hi * i_hi]
            };
            let n = corners(near);
            let f = corners(far);
            if n.iter().chain(&f).any(|x| x.is_nan()) {
                continue;
            }
            t0 = t0.max(n.into_iter().fold(f32::INFINITY, f32::min));
            t1 = t1.min(f.into_iter().fold(f32::NEG_INFINITY, f32::max) * FAR_SCALE);
        }
        t0 <= t1
    }
}

/// Box-test lanes of one vector of a packet.
#[derive(Clone, Copy)]
struct SlabLanes<L: Lanes> {
    origin: [L::V; 3],
    inv: [L::V; 3],
    t_min: L::V,
}

impl<L: Lanes> SlabLanes<L> {
    /// The lanes that enter `node` no later than their lane of `limit`: the core's
    /// conservative slab test, with the near plane of each axis given by the packet's
    /// common direction signs.
    #[inline(always)]
    fn enters(&self, node: &raybench_bvh::Node, negative: &[bool; 3], limit: L::V) -> u32 {
        let mut t0 = self.t_min;
        let mut t1 = limit;
        for (axis, &neg) in negative.iter().enumerate() {
            let (near, far) = if neg {
                (node.max[axis], node.min[axis])
            } else {
                (node.min[axis], node.max[axis])
            };
            let tn = L::mul(L::sub(L::splat(near), self.origin[axis]), self.inv[axis]);
            let tf = L::mul(L::sub(L::splat(far), self.origin[axis]), self.inv[axis]);
            // NaN (0 * inf) first: the x86 min/max then return the accumulated bound.
            t0 = L::max(tn, t0);
            t1 = L::min(L::mul(tf, L::splat(FAR_SCALE)), t1);
        }
        L::bits(L::le(t0, t1))
    }
}

/// The `K` vectors of a packet of at most `K * W` rays: triangle-test lanes, slab-test
/// lanes, `t_max` and the mask of lanes holding a ray. Missing rays repeat the last one.
#[inline(always)]
#[allow(clippy::type_complexity)]
fn split<L: Lanes, const K: usize>(rays: &[Ray]) -> [(RayLanes<L>, SlabLanes<L>, L::V, u32); K] {
    let n = rays.len();
    let mut buf = [[0.0f32; 16]; 7];
    let mut out = [(
        RayLanes::new(&rays[..1]),
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
        for lane in 0..L::W {
            let r = &part[lane.min(part.len() - 1)];
            let vals = [
                r.origin.x,
                r.origin.y,
                r.origin.z,
                r.inv_dir.x,
                r.inv_dir.y,
                r.inv_dir.z,
                r.t_max,
            ];
            for (b, v) in buf.iter_mut().zip(vals) {
                b[lane] = v;
            }
        }
        let lanes = RayLanes::new(part);
        *chunk = (
            lanes,
            SlabLanes {
                origin: [L::load(&buf[0]), L::load(&buf[1]), L::load(&buf[2])],
                inv: [L::load(&buf[3]), L::load(&buf[4]), L::load(&buf[5])],
                t_min: lanes.t_min,
            },
            L::load(&buf[6]),
            if k * L::W < n {
                lanes_below::<L>(n - k * L::W)
            } else {
                0
            },
        );
    }
    out
}

/// The common octant of `rays` (bit `a` set when the inverse direction along axis `a` is
/// negative, as `raybench_core::SlabRay` decides), or `None` when the rays are not one
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

/// Closest hits of a coherent packet of at most `K * W` rays with octant `oct`: `best[i]`
/// arrives holding ray `i`'s hit with the unbounded primitives and leaves with its closest
/// hit.
#[inline(always)]
// The kernel's inputs are separate borrows on purpose: bundling them would only move the
// same eight names into a struct built for one call.
#[allow(clippy::too_many_arguments)]
pub(crate) fn closest<L: Lanes, const K: usize, C: Counters>(
    layout: &Layout,
    g: &Geometry,
    rays: &[Ray],
    oct: u8,
    best: &mut [Option<(u32, PrimHit)>],
    interval_cull: bool,
    scratch: &mut Stack,
    counters: &mut C,
) {
    let nodes = layout.bvh.nodes();
    if nodes.is_empty() {
        return;
    }
    let n = rays.len();
    // Per-lane state in plain arrays (`16` covers K * W for every instruction set).
    let mut t_best = [0.0f32; 32];
    let mut limit = [0.0f32; 32];
    for i in 0..n {
        t_best[i] = best[i].map_or(rays[i].t_max, |(_, h)| h.t);
        limit[i] = cull_bound(t_best[i]);
    }
    let chunks = split::<L, K>(rays);
    let negative = [oct & 1 != 0, oct & 2 != 0, oct & 4 != 0];
    let interval = interval_cull.then(|| PacketInterval::new(rays));

    let mut stack = [0u32; 2 * 64 + 4];
    let mut sp = 1;
    while sp > 0 {
        sp -= 1;
        let index = stack[sp] as usize;
        let node = &nodes[index];
        if let Some(iv) = &interval {
            let packet_limit = limit[..n].iter().fold(f32::NEG_INFINITY, |a, &b| a.max(b));
            if !iv.may_enter(node, &negative, packet_limit) {
                continue;
            }
        }
        // Lanes entering the node before their own limit.
        let mut masks = [0u32; K];
        for (k, (_, slab, _, valid)) in chunks.iter().enumerate() {
            if *valid == 0 {
                continue;
            }
            masks[k] = slab.enters(node, &negative, L::load(&limit[k * L::W..])) & valid;
        }
        let active: u32 = masks.iter().map(|m| m.count_ones()).sum();
        if active == 0 {
            continue;
        }
        counters.add_visits(u64::from(active));
        if !node.is_leaf() && active <= SPLIT_LANES {
            // The packet has diverged: its last lanes finish this subtree one by one.
            for (k, m) in masks.iter().enumerate() {
                for lane in BitIter(*m) {
                    let i = k * L::W + lane;
                    subtree_closest::<L, C>(
                        layout,
                        g,
                        &rays[i],
                        index,
                        &mut best[i],
                        scratch,
                        counters,
                    );
                    t_best[i] = best[i].map_or(rays[i].t_max, |(_, h)| h.t);
                    limit[i] = cull_bound(t_best[i]);
                }
            }
            continue;
        }
        if !node.is_leaf() {
            let order = layout.order[index];
            let axis = usize::from(order & 3);
            // The child whose centre comes first along the axis, in the packet's direction.
            let second_first = (order & 4 != 0) != negative[axis];
            let (l, r) = (index as u32 + 1, node.first_or_right);
            let (near, far) = if second_first { (r, l) } else { (l, r) };
            stack[sp] = far;
            stack[sp + 1] = near;
            sp += 2;
            continue;
        }
        let (first, count) = (node.first_or_right as usize, node.count as usize);
        let all_triangles = layout.node_all_triangles[index];
        // Few lanes left in a leaf (the packet has diverged): one SIMD test of up to `W`
        // triangles per lane is cheaper than one SIMD test of the lanes per triangle.
        let vectors = masks.iter().filter(|&&m| m != 0).count();
        if all_triangles
            && (active as usize) * count.div_ceil(<L::Single as Lanes>::W) < vectors * count
        {
            let leaf = Leaf {
                first: first as u32,
                count: count as u32,
                all_triangles,
            };
            for (k, m) in masks.iter().enumerate() {
                for lane in BitIter(*m) {
                    let i = k * L::W + lane;
                    let splat = SplatRay::<L::Single>::new(&rays[i]);
                    leaf_closest(layout, g, leaf, &rays[i], &splat, &mut best[i], counters);
                    t_best[i] = best[i].map_or(rays[i].t_max, |(_, h)| h.t);
                    limit[i] = cull_bound(t_best[i]);
                }
            }
            continue;
        }
        counters.add_tests(u64::from(active) * count as u64);
        for pos in first..first + count {
            let id = layout.ids[pos];
            for (k, (lanes, _, _, _)) in chunks.iter().enumerate() {
                if masks[k] == 0 {
                    continue;
                }
                let base = k * L::W;
                if !all_triangles && !layout.is_triangle[pos] {
                    for lane in BitIter(masks[k]) {
                        let i = base + lane;
                        g.test_closest(id, &rays[i], &mut best[i]);
                    }
                    continue;
                }
                let r = rays_vs_triangle(layout, lanes, pos, L::load(&t_best[base..]), masks[k]);
                if r.hit != 0 {
                    let mut t = [0.0f32; 16];
                    L::store(r.t, &mut t);
                    for lane in BitIter(r.hit) {
                        let i = base + lane;
                        let better =
                            best[i].is_none_or(|(bid, bh)| Hit::closer(t[lane], id, bh.t, bid));
                        if better {
                            best[i] = Some((id, prim_hit::<L>(&r, lane, t[lane])));
                        }
                    }
                }
                for lane in BitIter(r.zero) {
                    let i = base + lane;
                    g.test_closest(id, &rays[i], &mut best[i]);
                }
                for lane in BitIter(r.hit | r.zero) {
                    let i = base + lane;
                    t_best[i] = best[i].map_or(rays[i].t_max, |(_, h)| h.t);
                    limit[i] = cull_bound(t_best[i]);
                }
            }
        }
        if !all_triangles {
            for (k, m) in masks.iter().enumerate() {
                for lane in BitIter(*m) {
                    let i = k * L::W + lane;
                    t_best[i] = best[i].map_or(rays[i].t_max, |(_, h)| h.t);
                    limit[i] = cull_bound(t_best[i]);
                }
            }
        }
    }
}

/// Any-hit results of a coherent packet: `blocked[i]` arrives true for rays already
/// blocked (by an unbounded primitive) and leaves true for every blocked ray.
#[inline(always)]
pub(crate) fn occluded<L: Lanes, const K: usize, C: Counters>(
    layout: &Layout,
    g: &Geometry,
    rays: &[Ray],
    oct: u8,
    blocked: &mut [bool],
    counters: &mut C,
) {
    let nodes = layout.bvh.nodes();
    if nodes.is_empty() {
        return;
    }
    let mut open = [0u32; K];
    for (i, b) in blocked.iter().enumerate() {
        if !*b {
            open[i / L::W] |= 1 << (i % L::W);
        }
    }
    let chunks = split::<L, K>(rays);
    let negative = [oct & 1 != 0, oct & 2 != 0, oct & 4 != 0];
    let mut stack = [0u32; 2 * 64 + 4];
    let mut sp = 1;
    while sp > 0 && open.iter().any(|&m| m != 0) {
        sp -= 1;
        let index = stack[sp] as usize;
        let node = &nodes[index];
        let mut masks = [0u32; K];
        for (k, (_, slab, t_max, _)) in chunks.iter().enumerate() {
            if open[k] == 0 {
                continue;
            }
            masks[k] = slab.enters(node, &negative, *t_max) & open[k];
        }
        let active: u32 = masks.iter().map(|m| m.count_ones()).sum();
        if active == 0 {
            continue;
        }
        counters.add_visits(u64::from(active));
        if !node.is_leaf() {
            stack[sp] = node.first_or_right;
            stack[sp + 1] = index as u32 + 1;
            sp += 2;
            continue;
        }
        let (first, count) = (node.first_or_right as usize, node.count as usize);
        counters.add_tests(u64::from(active) * count as u64);
        for pos in first..first + count {
            let id = layout.ids[pos];
            for (k, (lanes, _, t_max, _)) in chunks.iter().enumerate() {
                let m = masks[k] & open[k];
                if m == 0 {
                    continue;
                }
                let mut hit = 0;
                let mut scalar = m;
                if layout.is_triangle[pos] {
                    let r = rays_vs_triangle(layout, lanes, pos, *t_max, m);
                    hit = r.hit;
                    scalar = r.zero;
                }
                for lane in BitIter(scalar) {
                    if g.shape(id).intersect(&rays[k * L::W + lane]).is_some() {
                        hit |= 1 << lane;
                    }
                }
                for lane in BitIter(hit) {
                    blocked[k * L::W + lane] = true;
                }
                open[k] &= !hit;
            }
        }
    }
}
