//! Single rays through the BVH8: one SIMD slab test checks a node's eight children, the
//! children hit are visited nearest first, and a leaf tests its blocks of four triangles
//! one SIMD test each.

use crate::layout::{BLOCK, EMPTY_CHILD, LEAF_BIT, Layout, LeafRef, TriBlock, WIDE, core_triangle};
use crate::simd::{Lanes, prefetch};
use crate::tri::{SplatRay, TriLanes, ray_vs_block};
use raybench_geometry::{
    Counters, Geometry, NodeStack, PrimHit, Ray, Shape, cull_bound, keep_closer,
};

/// `1 + 2 gamma(3)`: the far-distance scale of the conservative slab test (the core's).
pub(crate) use raybench_geometry::FAR_SCALE;

/// A ray prepared for wide slab tests: for each axis, which of a node's `min`/`max` arrays
/// holds the near plane (by the sign of the inverse direction, as `raybench_geometry::SlabRay`).
pub(crate) struct WideRay<L: Lanes> {
    origin: [L::V; 3],
    inv: [L::V; 3],
    near_is_min: [bool; 3],
    t_min: L::V,
}

impl<L: Lanes> WideRay<L> {
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        let o = ray.origin;
        let inv = ray.inv_dir;
        Self {
            origin: [L::splat(o.x), L::splat(o.y), L::splat(o.z)],
            inv: [L::splat(inv.x), L::splat(inv.y), L::splat(inv.z)],
            near_is_min: [inv.x >= 0.0, inv.y >= 0.0, inv.z >= 0.0],
            t_min: L::splat(ray.t_min),
        }
    }

    /// Entry distances of children `first..first + W` of `node`, and the mask of those
    /// entered at or before `limit` (conservatively: see `raybench_geometry::Aabb::intersect`).
    #[inline(always)]
    pub fn entries(
        &self,
        min: &[[f32; WIDE]; 3],
        max: &[[f32; WIDE]; 3],
        first: usize,
        limit: L::V,
    ) -> (L::V, u32) {
        let mut t0 = self.t_min;
        let mut t1 = limit;
        let scale = L::splat(FAR_SCALE);
        for axis in 0..3 {
            let (near, far) = if self.near_is_min[axis] {
                (&min[axis], &max[axis])
            } else {
                (&max[axis], &min[axis])
            };
            let tn = L::mul(
                L::sub(L::load(&near[first..]), self.origin[axis]),
                self.inv[axis],
            );
            let tf = L::mul(
                L::sub(L::load(&far[first..]), self.origin[axis]),
                self.inv[axis],
            );
            // NaN (0 * inf) first: the x86 min/max then return the accumulated bound.
            t0 = L::max(tn, t0);
            t1 = L::min(L::mul(tf, scale), t1);
        }
        (t0, L::bits(L::le(t0, t1)))
    }
}

/// Tests the leaf `leaf` against `ray`, keeping the closest hit in `best`.
#[inline(always)]
pub(crate) fn leaf_closest<L: Lanes, C: Counters>(
    layout: &Layout,
    g: &Geometry,
    leaf: LeafRef,
    ray: &Ray,
    splat: &SplatRay<L>,
    best: &mut Option<(u32, PrimHit)>,
    counters: &mut C,
) {
    for block in &layout.blocks[leaf.first..leaf.first + leaf.blocks] {
        if C::ENABLED {
            counters.add_tests(u64::from(block.occupied().count_ones()));
        }
        block_closest(g, block, leaf.mixed, ray, splat, best);
    }
}

/// Tests the triangles of `block` against `ray` (and, when `mixed`, its other primitives
/// with the core's routine), keeping the closest hit in `best`.
#[inline(always)]
pub(crate) fn block_closest<L: Lanes>(
    g: &Geometry,
    block: &TriBlock,
    mixed: bool,
    ray: &Ray,
    splat: &SplatRay<L>,
    best: &mut Option<(u32, PrimHit)>,
) {
    let t_max = best.map_or(ray.t_max, |(_, h)| h.t);
    // Unused lanes hold NaN coordinates, which neither hit nor need the scalar routine:
    // the ids are read only for hits.
    let r = ray_vs_block(block, splat, t_max, ALL_LANES);
    take_hits(block, ray, &r, best);
    for lane in BitIter(r.zero) {
        g.test_closest(block.id[lane], ray, best);
    }
    if mixed {
        for lane in BitIter(scalar_lanes(g, block)) {
            g.test_closest(block.id[lane], ray, best);
        }
    }
}

/// Every lane of a block.
const ALL_LANES: u32 = (1 << BLOCK) - 1;

/// The lanes of `block` whose primitives are not triangles (the core's scalar routine tests
/// them).
#[inline(always)]
pub(crate) fn scalar_lanes(g: &Geometry, block: &TriBlock) -> u32 {
    let mut m = 0;
    for lane in BitIter(block.occupied()) {
        if !matches!(g.shape(block.id[lane]), Shape::Triangle(_)) {
            m |= 1 << lane;
        }
    }
    m
}

/// Merges the hit lanes of a block test of `ray` into `best` by the tie rule (those whose
/// triangle's box the ray enters: see [`boxed`]).
#[inline(always)]
pub(crate) fn take_hits<L: Lanes>(
    block: &TriBlock,
    ray: &Ray,
    r: &TriLanes<L>,
    best: &mut Option<(u32, PrimHit)>,
) {
    if r.hit == 0 {
        return;
    }
    let hits = HitValues::new(r);
    for lane in BitIter(boxed(block, ray, &hits.t, r.hit)) {
        keep_closer(best, block.id[lane], hits.get(lane));
    }
}

/// The lanes of `hit` (a block test of `ray` with distances `t`) whose triangle's box the
/// ray enters by its hit, by the core's own check ([`Triangle::box_entered_by`]): a lane
/// the edge functions accept beside its triangle is no hit, as in the scalar routine.
/// Hits are few, so the check runs lane by lane.
///
/// [`Triangle::box_entered_by`]: raybench_geometry::Triangle::box_entered_by
#[inline(always)]
pub(crate) fn boxed(block: &TriBlock, ray: &Ray, t: &[f32; 16], hit: u32) -> u32 {
    let mut kept = 0;
    for lane in BitIter(hit) {
        if core_triangle(&block.triangle(lane)).box_entered_by(ray, t[lane]) {
            kept |= 1 << lane;
        }
    }
    kept
}

/// The lanes of a triangle test as the scalar routine's `PrimHit`s: `t`, and `u = V / det`,
/// `v = W / det` divided once for all lanes (IEEE division, lane by lane the scalar
/// quotient; dividing per hit lane stored the three vectors again for every lane).
pub(crate) struct HitValues {
    t: [f32; 16],
    u: [f32; 16],
    v: [f32; 16],
}

impl HitValues {
    /// The values of every lane of `r` (those of lanes that did not hit are meaningless).
    #[inline(always)]
    pub fn new<L: Lanes>(r: &TriLanes<L>) -> Self {
        let mut out = Self {
            t: [0.0; 16],
            u: [0.0; 16],
            v: [0.0; 16],
        };
        L::store(r.t, &mut out.t);
        L::store(L::div(r.v, r.det), &mut out.u);
        L::store(L::div(r.w, r.det), &mut out.v);
        out
    }

    /// The hit of lane `lane`.
    #[inline(always)]
    pub fn get(&self, lane: usize) -> PrimHit {
        PrimHit {
            t: self.t[lane],
            sub: 0,
            u: self.u[lane],
            v: self.v[lane],
        }
    }
}

/// Whether the leaf `leaf` blocks `ray`.
#[inline(always)]
pub(crate) fn leaf_occluded<L: Lanes>(
    layout: &Layout,
    g: &Geometry,
    leaf: LeafRef,
    ray: &Ray,
    splat: &SplatRay<L>,
) -> bool {
    // Loops, not `Iterator::any`: its closure was compiled as a function of its own,
    // without the caller's target features (plain SSE code in the AVX2 kernel).
    for block in &layout.blocks[leaf.first..leaf.first + leaf.blocks] {
        if block_occluded(g, block, leaf.mixed, ray, splat) {
            return true;
        }
    }
    false
}

/// Whether a primitive of `block` blocks `ray` (its triangles in one SIMD test, the lanes
/// that test cannot decide and, when `mixed`, its other primitives with the core's routine).
#[inline(always)]
pub(crate) fn block_occluded<L: Lanes>(
    g: &Geometry,
    block: &TriBlock,
    mixed: bool,
    ray: &Ray,
    splat: &SplatRay<L>,
) -> bool {
    let r = ray_vs_block(block, splat, ray.t_max, ALL_LANES);
    if r.hit != 0 {
        let mut t = [0.0; 16];
        L::store(r.t, &mut t);
        if boxed(block, ray, &t, r.hit) != 0 {
            return true;
        }
    }
    let mut scalar = r.zero;
    if mixed {
        scalar |= scalar_lanes(g, block);
    }
    for lane in BitIter(scalar) {
        if g.shape(block.id[lane]).intersect(ray).is_some() {
            return true;
        }
    }
    false
}

/// Primitives in a leaf, for counting tests.
#[inline(always)]
pub(crate) fn leaf_prims(layout: &Layout, leaf: LeafRef) -> u64 {
    layout.blocks[leaf.first..leaf.first + leaf.blocks]
        .iter()
        .map(|b| u64::from(b.occupied().count_ones()))
        .sum()
}

/// Indices of the set bits, lowest first.
pub(crate) struct BitIter<T>(pub T);

/// [`BitIter`] over one integer type.
macro_rules! bit_iter {
    ($t:ty) => {
        impl Iterator for BitIter<$t> {
            type Item = usize;
            #[inline(always)]
            fn next(&mut self) -> Option<usize> {
                if self.0 == 0 {
                    return None;
                }
                let i = self.0.trailing_zeros() as usize;
                self.0 &= self.0 - 1;
                Some(i)
            }
        }
    };
}
bit_iter!(u32);
bit_iter!(u64);

/// Traversal stack capacity: the BVH2 depth bound (60) times seven siblings, plus slack.
pub(crate) const STACK: usize = 7 * 64 + 8;

/// A traversal stack, allocated once per batch (initialising it per ray cost 10% of an
/// incoherent ray).
pub(crate) type Stack = [(u32, f32); STACK];

/// The nearest child of wide node `index` that `ray` enters at or before `limit` (none when
/// it enters none), to be visited next; the other children entered are pushed onto `stack`
/// far to near (so that the nearest of them is popped first). Each is prefetched. One or
/// two children entered, most visits, take neither a loop nor a sort.
///
/// Returning the nearest child instead of pushing it keeps the step from a node to the next
/// out of the stack's memory, as Embree's single-ray traversal does: with one child entered,
/// the most frequent case, the stack is not touched. Any-hit rays do the same with the
/// child in the highest slot ([`descend_any`]).
#[inline(always)]
pub(crate) fn descend<L: Lanes>(
    layout: &Layout,
    wray: &WideRay<L>,
    index: u32,
    limit: f32,
    stack: &mut NodeStack<'_>,
) -> Option<u32> {
    let node = &layout.wide[index as usize];
    let mut t = [0.0f32; 16];
    let mut bits = 0;
    let mut first = 0;
    while first < WIDE {
        let (t0, b) = wray.entries(&node.min, &node.max, first, L::splat(limit));
        L::store(t0, &mut t[first..]);
        bits |= b << first;
        first += L::W;
    }
    if bits == 0 {
        return None;
    }
    // One or two children entered (most visits) take no loop and no sort; the nearer of
    // two is chosen without a branch on the distances, which no predictor can learn.
    let a = bits.trailing_zeros() as usize;
    let rest = bits & (bits - 1);
    if rest == 0 {
        let child = node.child[a];
        if child == EMPTY_CHILD {
            return None;
        }
        prefetch_child(layout, child);
        return Some(child);
    }
    if rest & (rest - 1) == 0 {
        let b = rest.trailing_zeros() as usize;
        let pair = [(node.child[a], t[a]), (node.child[b], t[b])];
        if pair[0].0 != EMPTY_CHILD && pair[1].0 != EMPTY_CHILD {
            // Between equal entries the lower slot is nearer (as in the packet traversal).
            let b_nearer = usize::from(pair[1].1 < pair[0].1);
            let (near, far) = (pair[b_nearer], pair[1 - b_nearer]);
            prefetch_child(layout, far.0);
            stack.push(far.0, far.1);
            prefetch_child(layout, near.0);
            return Some(near.0);
        }
    }
    let mut found = [(0u32, 0.0f32); WIDE];
    let mut n = 0;
    for lane in BitIter(bits) {
        let child = node.child[lane];
        if child == EMPTY_CHILD {
            continue;
        }
        // Insertion sort, descending by entry; between equal entries the lower slot is
        // nearer.
        let mut j = n;
        while j > 0 && found[j - 1].1 <= t[lane] {
            found[j] = found[j - 1];
            j -= 1;
        }
        found[j] = (child, t[lane]);
        n += 1;
    }
    let (&(nearest, _), farther) = found[..n].split_last()?;
    for &(child, entry) in farther {
        prefetch_child(layout, child);
        stack.push(child, entry);
    }
    prefetch_child(layout, nearest);
    Some(nearest)
}

/// The node to visit next: `next` when the last step chose one (see [`descend`]), else the
/// top of `stack` within `limit`; none when the walk is over.
#[inline(always)]
pub(crate) fn next_node(
    next: &mut Option<u32>,
    stack: &mut NodeStack<'_>,
    limit: f32,
) -> Option<u32> {
    if next.is_some() {
        return next.take();
    }
    let (index, _) = stack.pop_within(limit)?;
    Some(index)
}

/// Prefetches the memory of the child reference `child` (a wide node or a leaf's blocks).
#[inline(always)]
pub(crate) fn prefetch_child(layout: &Layout, child: u32) {
    if child & LEAF_BIT == 0 {
        prefetch(&layout.wide[child as usize]);
    } else {
        let leaf = LeafRef::decode(child);
        prefetch(&layout.blocks[leaf.first]);
        if leaf.blocks > 1 {
            prefetch(&layout.blocks[leaf.first + 1]);
        }
    }
}

/// The closest hit of one ray in the subtree under the child reference `root` (the BVH
/// part; `best` arrives holding the hit found so far, such as the planes').
#[inline(always)]
pub(crate) fn closest<L: Lanes, C: Counters>(
    layout: &Layout,
    g: &Geometry,
    ray: &Ray,
    root: u32,
    mut best: Option<(u32, PrimHit)>,
    stack: &mut Stack,
    counters: &mut C,
) -> Option<(u32, PrimHit)> {
    if layout.wide.is_empty() {
        return best;
    }
    let wray = WideRay::<L::Single>::new(ray);
    let splat = SplatRay::<L::Narrow>::new(ray);
    let bound = |best: &Option<(u32, PrimHit)>| cull_bound(best.map_or(ray.t_max, |(_, h)| h.t));
    let mut limit = bound(&best);
    let mut stack = NodeStack::new(stack);
    let mut next = Some(root);
    while let Some(index) = next_node(&mut next, &mut stack, limit) {
        counters.add_visits(1);
        if index & LEAF_BIT != 0 {
            leaf_closest(
                layout,
                g,
                LeafRef::decode(index),
                ray,
                &splat,
                &mut best,
                counters,
            );
            limit = bound(&best);
            continue;
        }
        next = descend(layout, &wray, index, limit, &mut stack);
    }
    best
}

/// The child of wide node `index` in the highest slot that `ray` enters at or before
/// `t_max` (none when it enters none), to be visited next; the other children entered are
/// pushed onto `stack` in slot order, so that the next highest is popped first. Each is
/// prefetched. The highest slot holds the child likeliest to block the ray per unit of
/// cost (the layout's slot order); as in [`descend`], the step to it keeps out of the
/// stack's memory.
#[inline(always)]
pub(crate) fn descend_any<L: Lanes>(
    layout: &Layout,
    wray: &WideRay<L>,
    index: u32,
    t_max: L::V,
    stack: &mut NodeStack<'_>,
) -> Option<u32> {
    let node = &layout.wide[index as usize];
    let mut next = None;
    let mut first = 0;
    while first < WIDE {
        let (_, bits) = wray.entries(&node.min, &node.max, first, t_max);
        for lane in BitIter(bits) {
            let child = node.child[first + lane];
            if child != EMPTY_CHILD {
                prefetch_child(layout, child);
                if let Some(lower) = next.replace(child) {
                    stack.push(lower, f32::NEG_INFINITY);
                }
            }
        }
        first += L::W;
    }
    next
}

/// Whether anything in the subtree under the child reference `root` blocks `ray`.
#[inline(always)]
pub(crate) fn occluded<L: Lanes, C: Counters>(
    layout: &Layout,
    g: &Geometry,
    ray: &Ray,
    root: u32,
    stack: &mut Stack,
    counters: &mut C,
) -> bool {
    if layout.wide.is_empty() {
        return false;
    }
    let wray = WideRay::<L::Single>::new(ray);
    let splat = SplatRay::<L::Narrow>::new(ray);
    let t_max = <L::Single as Lanes>::splat(ray.t_max);
    let mut stack = NodeStack::new(stack);
    let mut next = Some(root);
    while let Some(index) = next_node(&mut next, &mut stack, f32::INFINITY) {
        let step = leaf_or_descend::<L, C>(
            layout, g, ray, &wray, &splat, t_max, index, &mut stack, counters,
        );
        match step {
            AnyStep::Blocked => return true,
            AnyStep::Next(child) => next = child,
        }
    }
    false
}

/// What one step of an any-hit traversal found.
pub(crate) enum AnyStep {
    /// The leaf blocks the ray.
    Blocked,
    /// The node to visit next without the stack ([`descend_any`]; none after a leaf that
    /// does not block, or a node whose children the ray misses).
    Next(Option<u32>),
}

/// One step of an any-hit traversal: tests the leaf `index`, or takes the children of the
/// wide node `index` ([`descend_any`]).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn leaf_or_descend<L: Lanes, C: Counters>(
    layout: &Layout,
    g: &Geometry,
    ray: &Ray,
    wray: &WideRay<L::Single>,
    splat: &SplatRay<L::Narrow>,
    t_max: <L::Single as Lanes>::V,
    index: u32,
    stack: &mut NodeStack<'_>,
    counters: &mut C,
) -> AnyStep {
    counters.add_visits(1);
    if index & LEAF_BIT != 0 {
        let leaf = LeafRef::decode(index);
        if C::ENABLED {
            counters.add_tests(leaf_prims(layout, leaf));
        }
        return if leaf_occluded(layout, g, leaf, ray, splat) {
            AnyStep::Blocked
        } else {
            AnyStep::Next(None)
        };
    }
    AnyStep::Next(descend_any(layout, wray, index, t_max, stack))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::WideNode;
    use crate::simd::Portable;
    use raybench_geometry::Vec3;

    /// Child `slot` is a box from x = NEAR[slot] to NEAR[slot] + 0.5 on the x axis, except
    /// slot 2, which lies off it; the children are (empty) wide nodes 1 to 8.
    const NEAR: [f32; WIDE] = [6.0, 2.0, 9.0, 4.0, 1.0, 8.0, 3.0, 7.0];

    fn row_of_boxes() -> Layout {
        let mut root = WideNode {
            min: [[0.0; WIDE]; 3],
            max: [[0.0; WIDE]; 3],
            child: [0; WIDE],
        };
        for (slot, &x) in NEAR.iter().enumerate() {
            let y = if slot == 2 { 5.0 } else { 0.0 };
            root.min[0][slot] = x;
            root.max[0][slot] = x + 0.5;
            root.min[1][slot] = y - 1.0;
            root.max[1][slot] = y + 1.0;
            root.min[2][slot] = -1.0;
            root.max[2][slot] = 1.0;
            root.child[slot] = slot as u32 + 1;
        }
        Layout {
            wide: vec![root; WIDE + 1],
            ..Layout::default()
        }
    }

    /// `descend` hands back the nearest child the ray enters and leaves the others on the
    /// stack to be popped near to far, without the children it misses or enters beyond
    /// the limit.
    #[test]
    fn descend_visits_the_nearest_child_next_and_stacks_the_others() {
        let near = NEAR;
        let layout = row_of_boxes();
        let ray = Ray::new(Vec3::ZERO, Vec3::new(1.0, 0.001, 0.002));
        let mut storage = [(0, 0.0); STACK];
        let mut stack = NodeStack::new(&mut storage);
        // Entered at about x: slot 5 (x = 8) lies beyond the limit.
        let next = descend(&layout, &WideRay::<Portable>::new(&ray), 0, 7.5, &mut stack);
        assert_eq!(next, Some(4 + 1));
        let mut popped = Vec::new();
        while let Some((child, entry)) = stack.pop_within(f32::INFINITY) {
            popped.push(child - 1);
            assert!((entry - near[child as usize - 1]).abs() < 0.01, "{entry}");
        }
        assert_eq!(popped, [1, 6, 3, 0, 7]);
        // A ray that enters nothing gets nothing.
        let away = Ray::new(Vec3::ZERO, Vec3::new(-1.0, 0.001, 0.002));
        let next = descend(
            &layout,
            &WideRay::<Portable>::new(&away),
            0,
            100.0,
            &mut stack,
        );
        assert_eq!(next, None);
        assert!(stack.pop_within(f32::INFINITY).is_none());
        // A ray starting inside slots 1, 3 and 6 enters them at its `t_min`: the lowest
        // slot is visited next, the others popped in slot order.
        let inside = Ray::new(Vec3::ZERO, Vec3::new(1.0, 0.001, 0.002));
        let mut wide = layout.wide[0];
        for slot in [1, 3, 6] {
            wide.min[0][slot] = -1.0;
        }
        let layout = Layout {
            wide: vec![wide; WIDE + 1],
            ..Layout::default()
        };
        let next = descend(
            &layout,
            &WideRay::<Portable>::new(&inside),
            0,
            0.5,
            &mut stack,
        );
        assert_eq!(next, Some(1 + 1));
        let mut popped = Vec::new();
        while let Some((child, _)) = stack.pop_within(f32::INFINITY) {
            popped.push(child - 1);
        }
        assert_eq!(popped, [3, 6]);
    }

    /// With one or two children entered (the paths without a sort), `descend` still visits
    /// the nearest next and stacks the other; between equal entries the lower slot is
    /// nearer.
    #[test]
    fn descend_orders_one_or_two_children_like_many() {
        let layout = row_of_boxes();
        let ray = Ray::new(Vec3::ZERO, Vec3::new(1.0, 0.001, 0.002));
        let wray = WideRay::<Portable>::new(&ray);
        let mut storage = [(0, 0.0); STACK];
        let mut stack = NodeStack::new(&mut storage);
        // Only slot 4 (x = 1) lies within 1.5.
        assert_eq!(descend(&layout, &wray, 0, 1.5, &mut stack), Some(4 + 1));
        assert!(stack.pop_within(f32::INFINITY).is_none());
        // Slots 4 (x = 1) and 1 (x = 2) lie within 2.5: the lower slot is the farther.
        assert_eq!(descend(&layout, &wray, 0, 2.5, &mut stack), Some(4 + 1));
        assert_eq!(stack.pop_within(f32::INFINITY).map(|e| e.0), Some(1 + 1));
        assert!(stack.pop_within(f32::INFINITY).is_none());
        // A ray starting inside slots 3 and 6 enters both at its `t_min`: slot 3 first.
        let mut wide = layout.wide[0];
        for slot in [3, 6] {
            wide.min[0][slot] = -1.0;
        }
        let tied = Layout {
            wide: vec![wide; WIDE + 1],
            ..Layout::default()
        };
        assert_eq!(descend(&tied, &wray, 0, 0.5, &mut stack), Some(3 + 1));
        assert_eq!(stack.pop_within(f32::INFINITY).map(|e| e.0), Some(6 + 1));
        assert!(stack.pop_within(f32::INFINITY).is_none());
    }

    /// `descend_any` hands back the child in the highest slot the ray enters and leaves the
    /// others on the stack to be popped from the highest slot down, without the children it
    /// misses or enters beyond `t_max`.
    #[test]
    fn descend_any_visits_the_highest_slot_next_and_stacks_the_others() {
        let layout = row_of_boxes();
        let ray = Ray::new(Vec3::ZERO, Vec3::new(1.0, 0.001, 0.002));
        let mut storage = [(0, 0.0); STACK];
        let mut stack = NodeStack::new(&mut storage);
        let wray = WideRay::<Portable>::new(&ray);
        // Slot 5 (x = 8) lies beyond t_max, slot 2 off the ray.
        let next = descend_any(&layout, &wray, 0, Portable::splat(7.5), &mut stack);
        assert_eq!(next, Some(7 + 1));
        let mut popped = Vec::new();
        while let Some((child, _)) = stack.pop_within(f32::INFINITY) {
            popped.push(child - 1);
        }
        assert_eq!(popped, [6, 4, 3, 1, 0]);
        let next = descend_any(&layout, &wray, 0, Portable::splat(0.5), &mut stack);
        assert_eq!(next, None);
        assert!(stack.pop_within(f32::INFINITY).is_none());
    }
}
