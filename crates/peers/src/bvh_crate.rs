//! svenstaro's `bvh` crate behind raybench's [`Accel`] (backend `bvh-crate`).

use bvh::aabb::{Aabb as CrateAabb, Bounded};
use bvh::bounding_hierarchy::{BHShape, BoundingHierarchy};
use bvh::bvh::{Bvh as CrateBvh, BvhNode};
use raybench_geometry::traverse::{self, AnyHit, Closest};
use raybench_geometry::{
    Aabb, Accel, AccelStats, Counters, Geometry, Hit, QualityParams, Ray, StructureQuality,
    TreeView, Vec3, ray_by_ray,
};
use std::sync::Arc;

/// A bounded primitive as the `bvh` crate's builder wants it: its box and a slot for its
/// node index. The crate only needs the box, so triangles and spheres alike go in.
#[derive(Clone, Copy, Debug)]
struct CrateShape {
    aabb: CrateAabb<f32, 3>,
    node: usize,
}

impl Bounded<f32, 3> for CrateShape {
    fn aabb(&self) -> CrateAabb<f32, 3> {
        self.aabb
    }
}

impl BHShape<f32, 3> for CrateShape {
    fn set_bh_node_index(&mut self, index: usize) {
        self.node = index;
    }

    fn bh_node_index(&self) -> usize {
        self.node
    }
}

/// Traversal stack entries: node index and the ray's entry distance into its box.
type Stack = Vec<(usize, f32)>;

/// A node of the crate's tree as the walks read it.
enum Node<'a> {
    /// A leaf: the raybench id of its one primitive.
    Leaf(u32),
    /// An interior node: its left and right children's indices, each with the box the node
    /// stores for it.
    Interior([(usize, &'a CrateAabb<f32, 3>); 2]),
}

/// svenstaro's `bvh` crate (0.13): its binned-SAH tree (one primitive per leaf, built in
/// parallel with rayon) over the scene's bounded primitives, traced by a stack traversal of
/// the tree that tests primitives with raybench's own routine
/// ([`Geometry::test_closest`]). Unbounded primitives (planes) are tested by every ray
/// beside the tree, as in every raybench backend.
///
/// The crate has no closest-hit query of its own: `traverse` and `traverse_iterator` return
/// every shape whose box the ray touches, and the distance-ordered iterators keep a heap
/// and never stop early. So this peer walks the crate's own tree (`Bvh::nodes`, whose
/// interior nodes hold both children's boxes): child boxes tested with the crate's
/// `Ray::intersection_slice_for_aabb`, nearer child first, a child skipped when its entry
/// lies beyond the best hit so far, leaves tested with raybench's primitive routine and the
/// closest kept under raybench's tie rule. This is the "bvh crate tree, own stack
/// traversal" row of `../shared/PEERS.md`.
///
/// Not bound by the equivalence contract: the crate's slab test is not conservative (a ray
/// lying in the plane of a box face misses the box) and the early exit has no slack, so
/// a few rays in ten thousand may find another primitive than naive does.
pub struct BvhCrateAccel {
    bvh: CrateBvh<f32, 3>,
    /// The shared primitives; leaf `shape_index` `i` holds `geometry.bounded()[i]`.
    geometry: Arc<Geometry>,
    /// Whether every primitive is bounded, so that `shape_index` is the primitive id (no
    /// lookup, and no cache miss on it, per leaf).
    all_bounded: bool,
}

impl BvhCrateAccel {
    /// The crate's tree over the bounded primitives of `geometry`.
    fn build_tree(geometry: Arc<Geometry>) -> Self {
        let mut shapes: Vec<CrateShape> = geometry
            .bounded()
            .iter()
            .map(|&id| {
                let b = geometry
                    .shape(id)
                    .bounds()
                    .expect("bounded primitives have boxes");
                CrateShape {
                    aabb: CrateAabb::with_bounds(b.min.to_array().into(), b.max.to_array().into()),
                    node: 0,
                }
            })
            .collect();
        let bvh = CrateBvh::build_par(&mut shapes);
        let all_bounded = geometry.bounded().len() == geometry.len();
        Self {
            bvh,
            geometry,
            all_bounded,
        }
    }

    /// The crate's tree as the quality metrics see it: its nodes, each with the box its
    /// parent stores for it (the crate keeps no box for the root: its box is the scene's
    /// bounded primitives' box), and one primitive per leaf.
    #[must_use]
    pub fn tree_view(&self) -> TreeView {
        let mut view = TreeView::new();
        if !self.bvh.nodes.is_empty() {
            self.view_node(0, self.geometry.bounds(), &mut view);
        }
        view
    }

    /// Adds node `index` (with box `bounds`) and its subtree to `view`.
    fn view_node(&self, index: usize, bounds: Aabb, view: &mut TreeView) -> u32 {
        let to_aabb = |b: &CrateAabb<f32, 3>| {
            Aabb::new(
                Vec3::new(b.min[0], b.min[1], b.min[2]),
                Vec3::new(b.max[0], b.max[1], b.max[2]),
            )
        };
        match self.node(index) {
            Node::Leaf(id) => view.leaf(bounds, &[id]),
            Node::Interior(children) => {
                let [l, r] = children.map(|(child, b)| self.view_node(child, to_aabb(b), view));
                view.interior(bounds, &[l, r])
            }
        }
    }

    /// Node `index` of the crate's tree as the walks read it.
    #[inline]
    fn node(&self, index: usize) -> Node<'_> {
        match &self.bvh.nodes[index] {
            BvhNode::Leaf { shape_index, .. } => Node::Leaf(self.id(*shape_index)),
            BvhNode::Node {
                child_l_index,
                child_l_aabb,
                child_r_index,
                child_r_aabb,
                ..
            } => Node::Interior([
                (*child_l_index, child_l_aabb),
                (*child_r_index, child_r_aabb),
            ]),
        }
    }

    /// The raybench id of the primitive in the leaf with `shape_index`.
    #[inline]
    fn id(&self, shape_index: usize) -> u32 {
        if self.all_bounded {
            shape_index as u32
        } else {
            self.geometry.bounded()[shape_index]
        }
    }

    /// The crate's ray with raybench's direction (not normalised, so `t` agrees) and inverse.
    fn crate_ray(ray: &Ray) -> bvh::ray::Ray<f32, 3> {
        bvh::ray::Ray {
            origin: ray.origin.to_array().into(),
            direction: ray.dir.to_array().into(),
            inv_direction: ray.inv_dir.to_array().into(),
        }
    }

    /// The closest-hit walk: the crate's tree, nearer child first.
    fn walk_closest<C: Counters>(&self, q: &mut Closest<'_, C>, stack: &mut Stack) {
        let nodes = &self.bvh.nodes;
        if nodes.is_empty() {
            return;
        }
        let ray = q.ray();
        let cray = Self::crate_ray(ray);
        let mut best_t = q.best_t();
        stack.clear();
        // The crate keeps no box for the root: its children's boxes are tested on the way.
        stack.push((0, ray.t_min));
        while let Some((index, entry)) = stack.pop() {
            if entry > best_t {
                continue;
            }
            q.add_visits(1);
            match self.node(index) {
                Node::Leaf(id) => {
                    q.test(id);
                    best_t = q.best_t();
                }
                Node::Interior([(l, l_box), (r, r_box)]) => {
                    let entry_of = |b: &CrateAabb<f32, 3>| {
                        cray.intersection_slice_for_aabb(b)
                            .map(|(t0, _)| t0)
                            .filter(|&t0| t0 <= best_t)
                    };
                    match (entry_of(l_box), entry_of(r_box)) {
                        (Some(tl), Some(tr)) => {
                            if tl <= tr {
                                stack.push((r, tr));
                                stack.push((l, tl));
                            } else {
                                stack.push((l, tl));
                                stack.push((r, tr));
                            }
                        }
                        (Some(tl), None) => stack.push((l, tl)),
                        (None, Some(tr)) => stack.push((r, tr)),
                        (None, None) => {}
                    }
                }
            }
        }
    }

    /// The any-hit walk, stopping at the first hit.
    fn walk_any<C: Counters>(&self, q: &mut AnyHit<'_, C>, stack: &mut Stack) -> bool {
        let nodes = &self.bvh.nodes;
        if nodes.is_empty() {
            return false;
        }
        let ray = q.ray();
        let cray = Self::crate_ray(ray);
        stack.clear();
        stack.push((0, ray.t_min));
        while let Some((index, _)) = stack.pop() {
            q.add_visits(1);
            match self.node(index) {
                Node::Leaf(id) => {
                    if q.test(id) {
                        return true;
                    }
                }
                Node::Interior([left, right]) => {
                    for (child, aabb) in [right, left] {
                        if cray
                            .intersection_slice_for_aabb(aabb)
                            .is_some_and(|(t0, _)| t0 <= ray.t_max)
                        {
                            stack.push((child, 0.0));
                        }
                    }
                }
            }
        }
        false
    }

    fn intersect_with<C: Counters>(
        &self,
        ray: &Ray,
        stack: &mut Stack,
        counters: &mut C,
    ) -> Option<Hit> {
        traverse::closest(&self.geometry, ray, counters, |q| {
            self.walk_closest(q, stack);
        })
    }

    fn occluded_with<C: Counters>(&self, ray: &Ray, stack: &mut Stack, counters: &mut C) -> bool {
        traverse::occluded(&self.geometry, ray, counters, |q| self.walk_any(q, stack))
    }
}

/// Initial capacity of a traversal stack (it grows if a tree is deeper).
const STACK_CAPACITY: usize = 64;

impl Accel for BvhCrateAccel {
    fn build(geometry: Arc<Geometry>) -> Self {
        Self::build_tree(geometry)
    }

    fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        self.intersect_with(ray, &mut Vec::with_capacity(STACK_CAPACITY), counters)
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        self.occluded_with(ray, &mut Vec::with_capacity(STACK_CAPACITY), counters)
    }

    /// Single rays one after the other, sharing one traversal stack.
    fn intersect_batch<C: Counters>(
        &self,
        rays: &[Ray],
        hits: &mut [Option<Hit>],
        counters: &mut C,
    ) {
        let mut stack = Vec::with_capacity(STACK_CAPACITY);
        ray_by_ray(rays, hits, |ray| {
            self.intersect_with(ray, &mut stack, counters)
        });
    }

    /// Single rays one after the other, sharing one traversal stack.
    fn occluded_batch<C: Counters>(&self, rays: &[Ray], occluded: &mut [bool], counters: &mut C) {
        let mut stack = Vec::with_capacity(STACK_CAPACITY);
        ray_by_ray(rays, occluded, |ray| {
            self.occluded_with(ray, &mut stack, counters)
        });
    }

    fn stats(&self) -> AccelStats {
        let nodes = &self.bvh.nodes;
        let leaves = nodes
            .iter()
            .filter(|n| matches!(n, BvhNode::Leaf { .. }))
            .count();
        AccelStats {
            memory_bytes: std::mem::size_of_val(nodes.as_slice()),
            counts: vec![("nodes", nodes.len() as u64), ("leaves", leaves as u64)],
        }
    }

    fn quality(&self, params: &QualityParams) -> Option<StructureQuality> {
        let q = self
            .tree_view()
            .quality(&self.geometry, params, self.stats().memory_bytes);
        Some(StructureQuality::Tree(q))
    }
}
