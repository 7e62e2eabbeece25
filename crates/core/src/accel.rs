//! The contract every CPU acceleration strategy implements.

use crate::geometry::Geometry;
use crate::hit::Hit;
use crate::ray::Ray;
use std::sync::Arc;

/// Counts of the work a query did. Implemented by [`RayCounters`] (counting) and
/// [`NoCounters`] (a zero-sized no-op, so counting is free when it is off: the choice is made
/// once per frame and monomorphised).
///
/// Counters are plain values owned by one work item (a tile) and summed when the work items
/// are reduced, so they are exact under any parallelism without atomics or thread-locals.
pub trait Counters: Default + Send {
    /// Whether this type counts at all.
    const ENABLED: bool;
    /// Adds `n` ray/primitive tests.
    fn add_tests(&mut self, n: u64);
    /// Adds `n` visits of acceleration-structure nodes or cells.
    fn add_visits(&mut self, n: u64);
    /// Adds another work item's counts.
    fn merge(&mut self, other: &Self);
    /// The counts, or `None` when this type does not count.
    fn counts(&self) -> Option<RayCounters>;
}

/// Exact counts of ray/primitive tests and node or cell visits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounters {
    /// Ray/primitive intersection tests.
    pub prim_tests: u64,
    /// Node (BVH) or cell (grid) visits.
    pub node_visits: u64,
}

impl Counters for RayCounters {
    const ENABLED: bool = true;
    #[inline]
    fn add_tests(&mut self, n: u64) {
        self.prim_tests += n;
    }
    #[inline]
    fn add_visits(&mut self, n: u64) {
        self.node_visits += n;
    }
    fn merge(&mut self, other: &Self) {
        self.prim_tests += other.prim_tests;
        self.node_visits += other.node_visits;
    }
    fn counts(&self) -> Option<RayCounters> {
        Some(*self)
    }
}

/// Counters that count nothing and cost nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NoCounters;

impl Counters for NoCounters {
    const ENABLED: bool = false;
    #[inline(always)]
    fn add_tests(&mut self, _: u64) {}
    #[inline(always)]
    fn add_visits(&mut self, _: u64) {}
    fn merge(&mut self, _: &Self) {}
    fn counts(&self) -> Option<RayCounters> {
        None
    }
}

/// Relative slack of early-exit comparisons: a node or cell is skipped only when its entry
/// distance exceeds [`cull_bound`]`(best_t)`, slightly more than the best `t`.
///
/// Rule 3 of the contract compares a box's entry distance with a primitive's `t`, two
/// numbers computed by different routines, each with its own rounding. A primitive hit at
/// `t` lies inside its box, so the box's true entry is at most the true `t`; but the
/// computed entry can exceed the computed `t` by a few ulps (the slab test rounds twice, the
/// triangle test a handful of times). Without slack, two coincident triangles in different
/// leaves (equal `t`, the tie going to the smaller id) could see the smaller id's leaf
/// skipped. `2^-16` relative dwarfs those few ulps (`~2^-21`) and costs no measurable
/// extra visits.
pub const CULL_SLACK: f32 = 1.0 / 65_536.0;

/// The largest entry distance at which a node or cell must still be visited when the best
/// hit so far is at `best_t` (see [`CULL_SLACK`]).
#[inline]
#[must_use]
pub fn cull_bound(best_t: f32) -> f32 {
    best_t + best_t.abs() * CULL_SLACK
}

/// A closest-hit traversal stack of `(node, entry distance)` pairs over storage the caller
/// owns (so that a batch can reuse one allocation), which pops only the entries that pass
/// the strict early exit of rule 3: entries entered beyond the current limit are dropped.
#[derive(Debug)]
pub struct NodeStack<'a> {
    entries: &'a mut [(u32, f32)],
    len: usize,
}

impl<'a> NodeStack<'a> {
    /// An empty stack over `storage` (its capacity).
    #[inline]
    pub fn new(storage: &'a mut [(u32, f32)]) -> Self {
        Self {
            entries: storage,
            len: 0,
        }
    }

    /// Pushes `node`, entered at `entry`.
    ///
    /// # Panics
    /// When the storage is full (a traversal deeper than it was sized for).
    #[inline]
    pub fn push(&mut self, node: u32, entry: f32) {
        self.entries[self.len] = (node, entry);
        self.len += 1;
    }

    /// The most recently pushed entry whose entry distance is at most `limit`
    /// ([`cull_bound`] of the best hit so far), dropping those above it.
    #[inline]
    pub fn pop_within(&mut self, limit: f32) -> Option<(u32, f32)> {
        while self.len > 0 {
            self.len -= 1;
            let e = self.entries[self.len];
            // Strict: skip only entries *beyond* the limit (an equal one may hold a tie).
            if e.1 > limit {
                continue;
            }
            return Some(e);
        }
        None
    }
}

/// Size and shape of a built acceleration structure, for `raybench info` and reports.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AccelStats {
    /// Bytes held by the structure itself (not counting the shared geometry).
    pub memory_bytes: usize,
    /// Named counts, such as `("nodes", 1234)`, `("leaves", 600)`, `("cells", 4096)`.
    pub counts: Vec<(&'static str, u64)>,
}

/// A CPU acceleration strategy: decides *which* primitives a ray is tested against. The
/// tests themselves are the core's ([`Geometry::test_closest`], [`crate::Shape::intersect`]).
///
/// # Equivalence contract
///
/// Every raybench CPU backend obeys these four rules, and with them returns bit-identical
/// primitive ids and `t` to the naive backend for every ray:
///
/// 1. **Tie rule.** The closest hit is the one with the smallest `t`; equal `t` goes to the
///    smaller primitive id ([`Hit::closer`]).
/// 2. **Conservative culling.** A box or cell test may accept a ray that misses, never reject
///    one that hits (robust slab test, [`crate::Aabb::intersect`]; pad where needed).
/// 3. **Strict early exits.** Skip a node only when its entry `t` is *greater* than the best
///    `t` so far (equal must still be visited, for the tie rule), with the small relative
///    slack of [`cull_bound`] that absorbs the rounding of two different routines; a grid
///    stops only when the best `t` is *less* than the current cell's exit.
/// 4. **Original rays.** Primitive tests always receive the original ray (its `t_max` may be
///    lowered to the best `t` so far, which changes no computed `t`), never one clipped to
///    a node or cell or with a moved origin.
///
/// Unbounded primitives ([`Geometry::unbounded`]) are kept beside the structure and tested
/// by every ray. Any-hit queries ([`Accel::occluded`]) may stop at the first hit in any
/// order; only their boolean result is defined.
pub trait Accel: Send + Sync + Sized + 'static {
    /// Builds the structure over `geometry` with default parameters. Building is separate
    /// from tracing: one build serves any number of frames.
    fn build(geometry: Arc<Geometry>) -> Self;

    /// The geometry this structure was built over.
    fn geometry(&self) -> &Geometry;

    /// The closest hit of `ray` in `[ray.t_min, ray.t_max]`.
    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit>;

    /// Whether anything is hit in `[ray.t_min, ray.t_max]` (shadow rays).
    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool;

    /// Closest hits of a batch of rays: `hits[i]` for `rays[i]`. The integrators trace whole
    /// tiles through this entry point; packet backends override it.
    ///
    /// # Panics
    /// When the slices differ in length.
    fn intersect_batch<C: Counters>(
        &self,
        rays: &[Ray],
        hits: &mut [Option<Hit>],
        counters: &mut C,
    ) {
        assert_eq!(rays.len(), hits.len());
        for (ray, hit) in rays.iter().zip(hits) {
            *hit = self.intersect(ray, counters);
        }
    }

    /// Any-hit results of a batch of rays: `occluded[i]` for `rays[i]`.
    ///
    /// # Panics
    /// When the slices differ in length.
    fn occluded_batch<C: Counters>(&self, rays: &[Ray], occluded: &mut [bool], counters: &mut C) {
        assert_eq!(rays.len(), occluded.len());
        for (ray, o) in rays.iter().zip(occluded) {
            *o = self.occluded(ray, counters);
        }
    }

    /// Size and node or cell counts of the structure.
    fn stats(&self) -> AccelStats;
}

/// The batch entry points of an [`Accel`] behind a trait object, for harnesses that pick a
/// structure by name ([`crate::Renderer::batch_tracer`]) and time batches of rays without
/// rendering frames (`tests/benches/peers.rs`). Implemented for every [`Accel`]: one virtual
/// call per batch, the per-ray path inside it is the structure's generic one.
pub trait BatchTracer: Send + Sync {
    /// [`Accel::intersect_batch`], not counting.
    fn trace_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]);

    /// [`Accel::occluded_batch`], not counting.
    fn occlude_batch(&self, rays: &[Ray], occluded: &mut [bool]);

    /// [`Accel::intersect_batch`], adding its work to `counters`.
    fn trace_batch_counted(
        &self,
        rays: &[Ray],
        hits: &mut [Option<Hit>],
        counters: &mut RayCounters,
    );

    /// [`Accel::occluded_batch`], adding its work to `counters`.
    fn occlude_batch_counted(
        &self,
        rays: &[Ray],
        occluded: &mut [bool],
        counters: &mut RayCounters,
    );
}

impl<A: Accel> BatchTracer for A {
    fn trace_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        self.intersect_batch(rays, hits, &mut NoCounters);
    }

    fn occlude_batch(&self, rays: &[Ray], occluded: &mut [bool]) {
        self.occluded_batch(rays, occluded, &mut NoCounters);
    }

    fn trace_batch_counted(
        &self,
        rays: &[Ray],
        hits: &mut [Option<Hit>],
        counters: &mut RayCounters,
    ) {
        self.intersect_batch(rays, hits, counters);
    }

    fn occlude_batch_counted(
        &self,
        rays: &[Ray],
        occluded: &mut [bool],
        counters: &mut RayCounters,
    ) {
        self.occluded_batch(rays, occluded, counters);
    }
}
