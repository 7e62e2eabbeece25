//! The contract every CPU acceleration strategy implements. The frames its queries share
//! live in [`crate::traverse`], the stack and the early-exit bound in `stack.rs`.

use crate::counters::{Counters, NoCounters, RayCounters};
use crate::geometry::Geometry;
use crate::hit::Hit;
use crate::quality::{QualityParams, StructureQuality};
use crate::ray::Ray;
use std::sync::Arc;

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
///    one that hits (robust slab test, [`crate::Aabb::intersect`]; pad where needed). A
///    triangle's hit is one whose box the ray enters by then
///    ([`crate::Triangle::box_entered_by`]), so the slab test of any box holding it
///    accepts the ray.
/// 3. **Strict early exits.** Skip a node only when its entry `t` is *greater* than the best
///    `t` so far (equal must still be visited, for the tie rule), with the small relative
///    slack of [`crate::cull_bound`] that absorbs the rounding of two different routines; a grid
///    stops only when the best `t` is *less* than the current cell's exit.
/// 4. **Original rays.** Primitive tests always receive the original ray (its `t_max` may be
///    lowered to the best `t` so far, which changes no computed `t`), never one clipped to
///    a node or cell or with a moved origin; an instance's primitives receive the
///    instance-space ray of the original ray ([`crate::Instance::local_ray`], the one
///    function every backend calls), likewise clipped only at the best `t`.
///
/// Ids number the flattened scene ([`Geometry`]): a structure built over a geometry with
/// instances organises its flat primitives only, unless it says it tests the instances
/// itself ([`Accel::TESTS_INSTANCES`]); [`crate::TwoLevel`] is the two-level form of any
/// structure that does not.
///
/// Unbounded primitives ([`Geometry::unbounded`]) are kept beside the structure and tested
/// by every ray. Any-hit queries ([`Accel::occluded`]) may stop at the first hit in any
/// order; only their boolean result is defined.
pub trait Accel: Send + Sync + Sized + 'static {
    /// True when the structure's queries cover every primitive of the flattened scene,
    /// instances included (naive, through [`Geometry::closest_every`]); false when it
    /// organises the flat primitives only and needs [`crate::TwoLevel`] on top for a
    /// geometry with instances (every structure but naive).
    const TESTS_INSTANCES: bool = false;

    /// Builds the structure over `geometry` with default parameters. Building is separate
    /// from tracing: one build serves any number of frames.
    fn build(geometry: Arc<Geometry>) -> Self;

    /// True when [`Accel::refit`] is implemented (a moving scene's frames can then be
    /// refitted instead of rebuilt).
    const REFITS: bool = false;

    /// Refits the structure to `geometry`, another frame of the geometry it was built over
    /// ([`crate::Motion::geometry_at`]: the same ids and topology, [`crate::same_topology`]):
    /// boxes recomputed bottom up over the new positions, the topology kept. A refitted
    /// structure obeys the equivalence contract like a built one (its boxes hold their
    /// primitives, so its culling stays conservative); only its quality may decay. Returns
    /// false, and leaves the structure as it was, when the structure cannot refit (the
    /// default) or the topology differs: the caller then rebuilds.
    fn refit(&mut self, _geometry: Arc<Geometry>) -> bool {
        false
    }

    /// The structure `self` (just built by the backend's build, over a mesh that
    /// instances place) made fit for instance-space rays, which start as many of the mesh's
    /// sizes away from it as the camera is: a structure that tests everything for rays from
    /// too far (the grids) widens that bound here. [`crate::TwoLevel`] calls it for each
    /// distinct mesh; the default keeps the structure as built.
    #[must_use]
    fn for_instances(self) -> Self {
        self
    }

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
        ray_by_ray(rays, hits, |ray| self.intersect(ray, counters));
    }

    /// Any-hit results of a batch of rays: `occluded[i]` for `rays[i]`.
    ///
    /// # Panics
    /// When the slices differ in length.
    fn occluded_batch<C: Counters>(&self, rays: &[Ray], occluded: &mut [bool], counters: &mut C) {
        ray_by_ray(rays, occluded, |ray| self.occluded(ray, counters));
    }

    /// Size and node or cell counts of the structure.
    fn stats(&self) -> AccelStats;

    /// The structure's quality figures ([`crate::quality`]): SAH cost, EPO, leaves and depth
    /// of a tree, cell and list statistics of a grid, or why it cannot be read. `None` for a
    /// strategy without a structure (naive). Samples points for the EPO: call it once per
    /// build, not per frame.
    fn quality(&self, _params: &QualityParams) -> Option<StructureQuality> {
        None
    }
}

/// Fills `out[i]` with `trace(&rays[i])`, ray after ray in order: the batch entry points of
/// a structure without a batch kernel ([`Accel::intersect_batch`]'s and
/// [`Accel::occluded_batch`]'s defaults, and backends that only share scratch space, such as
/// a traversal stack, between the rays of a batch).
///
/// # Panics
/// When the slices differ in length.
pub fn ray_by_ray<T>(rays: &[Ray], out: &mut [T], mut trace: impl FnMut(&Ray) -> T) {
    assert_eq!(rays.len(), out.len());
    for (ray, o) in rays.iter().zip(out) {
        *o = trace(ray);
    }
}

/// The batch entry points of an [`Accel`] behind a trait object, for harnesses that pick a
/// structure by name (`Renderer::batch_tracer` in `raybench-core`) and time batches of rays without
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
