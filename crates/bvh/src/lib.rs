//! # raybench-bvh
//!
//! Two bounding volume hierarchies behind raybench's [`Accel`](raybench_geometry::Accel)
//! contract:
//!
//! - [`Bvh`] (backend `bvh`): the textbook structure, written here. A binned SAH builder
//!   (Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies", 2007), parallel
//!   with rayon; a flattened depth-first layout of 32-byte nodes whose first child follows
//!   its parent; stack traversal, nearest child first, with strict early exits.
//!   [`Bvh::build_ploc`] fills the same layout with obvhs's PLOC topology, so builders can
//!   be compared under one traversal kernel; [`Bvh::reinserted`] runs obvhs's reinsertion
//!   optimiser over a finished tree.
//! - [`ObvhsAccel`] (backend `obvhs`): the `obvhs` crate's production layout (PLOC with
//!   reinsertion, compressed wide CWBVH8 nodes) with its own traversal.
//!
//! Both keep unbounded primitives (planes) in a side list tested by every ray, and both
//! test primitives only through the core's routines, so their hits are bit-identical to the
//! naive backend's.

mod build;
mod node;
mod obvhs_adapter;
mod params;
mod ploc;
mod presplit;
mod refit;
mod traverse;

pub use node::Node;
/// obvhs's build parameters and their presets (`fastest_build()` .. `very_slow_build()`),
/// for [`ObvhsAccel::build_with`].
pub use obvhs::BvhBuildParams as ObvhsBuildParams;
pub use obvhs_adapter::ObvhsAccel;
pub use params::BvhParams;

use raybench_geometry::{CostConstants, Geometry, TreeView};
use std::sync::Arc;

/// The workspace's own BVH2.
#[derive(Clone, Debug)]
pub struct Bvh {
    geometry: Arc<Geometry>,
    /// Depth-first nodes; node 0 is the root, an interior node's first child is the next
    /// node. Empty when there are no bounded primitives.
    nodes: Vec<Node>,
    /// Primitive ids in leaf order; a leaf covers `prim_ids[first..first + count]`.
    prim_ids: Vec<u32>,
    params: BvhParams,
}

impl Bvh {
    /// The nodes, depth-first.
    #[must_use]
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The primitive ids in leaf order.
    #[must_use]
    pub fn prim_ids(&self) -> &[u32] {
        &self.prim_ids
    }

    /// The parameters it was built with.
    #[must_use]
    pub fn params(&self) -> &BvhParams {
        &self.params
    }

    /// The geometry it was built over.
    #[must_use]
    pub fn geometry_arc(&self) -> &Arc<Geometry> {
        &self.geometry
    }

    /// Depth of the tree (a lone leaf has depth 1; 0 when empty).
    #[must_use]
    pub fn depth(&self) -> usize {
        fn rec(nodes: &[Node], i: usize) -> usize {
            let n = &nodes[i];
            if n.is_leaf() {
                1
            } else {
                1 + rec(nodes, i + 1).max(rec(nodes, n.first_or_right as usize))
            }
        }
        if self.nodes.is_empty() {
            0
        } else {
            rec(&self.nodes, 0)
        }
    }

    /// The tree's cost by the surface area heuristic, the figure the builder minimises
    /// greedily: the expected work of a ray that hits the root box, in primitive tests
    /// (`C_i` = 1). Every interior node adds `traversal_cost` (the `C_t` of the build
    /// parameters) times the probability that such a ray hits its box (its surface area over
    /// the root's), every leaf its primitive count times that probability.
    /// Lower is better; compare trees over the same primitives. 0 when the tree is empty or
    /// its root box has no (or an infinite) area. It is [`TreeView::sah_cost`] of
    /// [`Bvh::tree_view`]: with the default `C_t` of 1, the `SAH` of `raybench info`.
    #[must_use]
    pub fn sah_cost(&self) -> f64 {
        self.tree_view().sah_cost(CostConstants {
            traversal: f64::from(self.params.traversal_cost),
            intersection: 1.0,
        })
    }

    /// The tree as the quality metrics see it ([`raybench_geometry::quality`]): every node
    /// with its box, leaves with their primitive ids.
    #[must_use]
    pub fn tree_view(&self) -> TreeView {
        fn add(nodes: &[Node], ids: &[u32], i: usize, view: &mut TreeView) -> u32 {
            let n = &nodes[i];
            if n.is_leaf() {
                let first = n.first_or_right as usize;
                view.leaf(n.aabb(), &ids[first..first + n.count as usize])
            } else {
                let l = add(nodes, ids, i + 1, view);
                let r = add(nodes, ids, n.first_or_right as usize, view);
                view.interior(n.aabb(), &[l, r])
            }
        }
        let mut view = TreeView::new();
        if !self.nodes.is_empty() {
            add(&self.nodes, &self.prim_ids, 0, &mut view);
        }
        view
    }

    /// Checks the structure's invariants: every bounded primitive in exactly one leaf (with
    /// pre-splitting, in at least one, the leaves holding it spanning its box) and no
    /// unbounded one in any; every leaf non-empty and holding its primitives' boxes; every
    /// interior node with two children inside it; the depth-first layout (first child
    /// adjacent, every node reached exactly once).
    ///
    /// # Errors
    /// A description of the first violation.
    pub fn validate(&self) -> Result<(), String> {
        let g = &*self.geometry;
        if self.nodes.is_empty() {
            return if g.bounded().is_empty() && self.prim_ids.is_empty() {
                Ok(())
            } else {
                Err("no nodes but bounded primitives exist".into())
            };
        }
        // With pre-splitting a triangle may sit in several leaves, each holding a part of
        // it: the leaves' boxes together must then hold the triangle's.
        let cut = self.params.presplit > 0.0;
        let mut covered = vec![raybench_geometry::Aabb::EMPTY; if cut { g.len() } else { 0 }];
        let mut seen = vec![0u32; g.len()];
        let mut reached = vec![false; self.nodes.len()];
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let node = self
                .nodes
                .get(i)
                .ok_or_else(|| format!("child index {i} out of range"))?;
            if std::mem::replace(&mut reached[i], true) {
                return Err(format!("node {i} reached twice"));
            }
            let bounds = node.aabb();
            if node.is_leaf() {
                let (first, count) = (node.first_or_right as usize, node.count as usize);
                if count == 0 {
                    return Err(format!("leaf {i} is empty"));
                }
                let ids = self
                    .prim_ids
                    .get(first..first + count)
                    .ok_or_else(|| format!("leaf {i} range out of bounds"))?;
                for &id in ids {
                    let b = g
                        .shapes()
                        .get(id as usize)
                        .and_then(raybench_geometry::Shape::bounds)
                        .ok_or_else(|| {
                            format!("leaf {i} holds unbounded or unknown primitive {id}")
                        })?;
                    if cut {
                        covered[id as usize] = covered[id as usize].union(bounds);
                    } else if !bounds.contains(&b) {
                        return Err(format!("leaf {i} does not contain primitive {id}"));
                    }
                    seen[id as usize] += 1;
                }
            } else {
                let (l, r) = (i + 1, node.first_or_right as usize);
                if r <= l || r >= self.nodes.len() {
                    return Err(format!("interior node {i} has bad children {l}, {r}"));
                }
                for c in [l, r] {
                    if !bounds.contains(&self.nodes[c].aabb()) {
                        return Err(format!("child {c} sticks out of node {i}"));
                    }
                }
                stack.push(r);
                stack.push(l);
            }
        }
        if let Some(i) = reached.iter().position(|r| !r) {
            return Err(format!("node {i} is unreachable"));
        }
        for &id in g.bounded() {
            let n = seen[id as usize];
            if n == 0 || (n > 1 && !cut) {
                return Err(format!("primitive {id} is in {n} leaves"));
            }
            if cut {
                let b = g
                    .shape(id)
                    .bounds()
                    .unwrap_or(raybench_geometry::Aabb::EMPTY);
                if !covered[id as usize].contains(&b) {
                    return Err(format!("the leaves holding primitive {id} do not cover it"));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_geometry::{Accel, Shape, Sphere, Triangle, Vec3};
    use raybench_scene::generators;

    fn geometries() -> Vec<(&'static str, Arc<Geometry>)> {
        let mesh = |m: raybench_geometry::TriangleMesh| {
            Arc::new(Geometry::new(m.triangles().map(Shape::Triangle).collect()))
        };
        let spheres = generators::random_spheres(700, 3)
            .into_iter()
            .map(Shape::Sphere)
            .collect();
        let point = Triangle::new(Vec3::ONE, Vec3::ONE, Vec3::ONE);
        vec![
            ("soup", mesh(generators::soup(5000, 1))),
            ("icosphere", mesh(generators::icosphere(4))),
            ("terrain", mesh(generators::terrain(40))),
            ("spheres", Arc::new(Geometry::new(spheres))),
            (
                "one",
                Arc::new(Geometry::new(vec![Shape::Sphere(Sphere::new(
                    Vec3::ZERO,
                    1.0,
                ))])),
            ),
            (
                "same point",
                Arc::new(Geometry::new(vec![Shape::Triangle(point); 100])),
            ),
            ("empty", Arc::new(Geometry::default())),
        ]
    }

    #[test]
    fn every_preset_builds_valid_trees() {
        for (name, g) in geometries() {
            for params in [BvhParams::fast(), BvhParams::medium(), BvhParams::quality()] {
                let bvh = Bvh::build_with(Arc::clone(&g), params);
                bvh.validate()
                    .unwrap_or_else(|e| panic!("{name} {params:?}: {e}"));
                assert!(bvh.depth() <= build::MAX_DEPTH + 1);
                let leaves = bvh.nodes().iter().filter(|n| n.is_leaf()).count();
                if !g.is_empty() {
                    // A binary tree with every interior node full.
                    assert_eq!(bvh.nodes().len(), 2 * leaves - 1, "{name}");
                }
                let stats = bvh.stats();
                assert_eq!(
                    stats.memory_bytes,
                    32 * bvh.nodes().len() + 4 * bvh.prim_ids().len()
                );
            }
        }
    }

    #[test]
    fn leaves_of_one_when_max_leaf_size_is_one() {
        // The packet crate's wide collapse relies on it: every node splits down to single
        // primitives, coincident ones included.
        for (name, g) in geometries() {
            let params = BvhParams {
                max_leaf_size: 1,
                ..BvhParams::medium()
            };
            let bvh = Bvh::build_with(Arc::clone(&g), params);
            bvh.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(
                bvh.nodes()
                    .iter()
                    .filter(|n| n.is_leaf())
                    .all(|n| n.count == 1),
                "{name}"
            );
        }
    }

    #[test]
    fn same_tree_on_any_thread_count_and_parallel_threshold() {
        // Large enough for the parallel binning of the top nodes.
        let big = Arc::new(Geometry::new(
            generators::soup(150_000, 4)
                .triangles()
                .map(Shape::Triangle)
                .collect(),
        ));
        let mut all = geometries();
        all.push(("big soup", big));
        let build_on = |threads: usize, g: &Arc<Geometry>, params: BvhParams| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| Bvh::build_with(Arc::clone(g), params))
        };
        let cut = BvhParams {
            presplit: 0.5,
            ..BvhParams::medium()
        };
        for ((name, g), base) in all
            .iter()
            .flat_map(|g| [(g, BvhParams::medium()), (g, cut)])
        {
            let reference = build_on(1, g, base);
            reference.validate().unwrap();
            for (threads, parallel_threshold) in [(2, 4096), (2, 2), (3, 100), (1, usize::MAX)] {
                let params = BvhParams {
                    parallel_threshold,
                    ..base
                };
                let other = build_on(threads, g, params);
                assert_eq!(other.nodes(), reference.nodes(), "{name} {threads} threads");
                assert_eq!(
                    other.prim_ids(),
                    reference.prim_ids(),
                    "{name} {threads} threads"
                );
            }
        }
    }

    #[test]
    fn sah_cost_of_known_trees() {
        let one = Arc::new(Geometry::new(vec![Shape::Sphere(Sphere::new(
            Vec3::ZERO,
            1.0,
        ))]));
        // One leaf of one primitive, hit by every ray that hits the root.
        assert_eq!(Bvh::build_with(one, BvhParams::default()).sah_cost(), 1.0);
        assert_eq!(
            Bvh::build_with(Arc::new(Geometry::default()), BvhParams::default()).sah_cost(),
            0.0
        );
        // Two far-apart spheres: a root (C_t = 1) and two leaves each hit with probability
        // a / A, the leaves' boxes being cubes of side s (a sphere's box is padded by
        // 1/2048 of its radius) and the root's (10 + s) x s x s.
        let two = Arc::new(Geometry::new(vec![
            Shape::Sphere(Sphere::new(Vec3::ZERO, 0.5)),
            Shape::Sphere(Sphere::new(Vec3::new(10.0, 0.0, 0.0), 0.5)),
        ]));
        let bvh = Bvh::build_with(two, BvhParams::default());
        assert_eq!(bvh.nodes().len(), 3);
        let side = 1.0 + 1.0 / 2048.0;
        let root_area = 2.0 * (2.0 * (10.0 + side) * side + side * side);
        let expected = 1.0 + 2.0 * 6.0 * side * side / root_area;
        assert!(
            (bvh.sah_cost() - expected).abs() < 1e-5,
            "{}",
            bvh.sah_cost()
        );
    }

    #[test]
    fn tree_views_hold_every_primitive_once() {
        use raybench_geometry::{QualityParams, StructureQuality};
        for (name, g) in geometries() {
            let bvh = Bvh::build_with(Arc::clone(&g), BvhParams::medium());
            let view = bvh.tree_view();
            view.check_leaves(&g)
                .unwrap_or_else(|e| panic!("{name} bvh: {e}"));
            assert_eq!(view.len(), bvh.nodes().len(), "{name}");
            let Some(StructureQuality::Tree(q)) = bvh.quality(&QualityParams::default()) else {
                panic!("{name}: the BVH is a tree");
            };
            // C_t of the medium preset is 1: the figure `info` shows is `sah_cost`.
            assert_eq!(q.sah, bvh.sah_cost(), "{name}");
            assert_eq!(q.max_depth as usize, bvh.depth(), "{name}");
            let obvhs = ObvhsAccel::build(Arc::clone(&g));
            obvhs
                .tree_view()
                .check_leaves(&g)
                .unwrap_or_else(|e| panic!("{name} obvhs: {e}"));
            if !g.is_empty() {
                let Some(StructureQuality::Tree(o)) = obvhs.quality(&QualityParams::default())
                else {
                    panic!("{name}: the CWBVH is a tree");
                };
                assert!(o.sah.is_finite() && o.sah > 0.0, "{name}: {o:?}");
                assert!(o.epo.mean.is_finite() && o.epo.mean >= 0.0, "{name}: {o:?}");
            }
        }
    }

    #[test]
    fn validate_catches_broken_trees() {
        let g = Arc::new(Geometry::new(
            generators::soup(200, 2)
                .triangles()
                .map(Shape::Triangle)
                .collect(),
        ));
        let good = Bvh::build_with(g, BvhParams::default());
        good.validate().unwrap();

        let mut shrunk = good.clone();
        shrunk.nodes[0].max = shrunk.nodes[0].min;
        assert!(shrunk.validate().is_err(), "a child outside its parent");

        let mut lost = good.clone();
        let leaf = lost.nodes.iter().position(Node::is_leaf).unwrap();
        lost.nodes[leaf].count = 0;
        assert!(lost.validate().is_err(), "an empty leaf");

        let mut duplicated = good.clone();
        duplicated.prim_ids[1] = duplicated.prim_ids[0];
        assert!(duplicated.validate().is_err(), "a primitive in two leaves");
    }

    #[test]
    fn cut_triangles_keep_every_hit() {
        // Long thin triangles (a fan of slivers through a cylinder's axis, among small
        // well-shaped ones) are cut into parts that sit in several leaves; the hits stay
        // those of the uncut tree, bit for bit.
        let sphere = generators::icosphere(4);
        let small = sphere.triangles().map(Shape::Triangle);
        let slivers: Vec<Shape> = (0..50)
            .map(|i| {
                let a = i as f32 * 0.125;
                let (s, c) = a.sin_cos();
                Shape::Triangle(Triangle::new(
                    Vec3::new(c, -1.0, s),
                    Vec3::new(-c, 1.0, -s),
                    Vec3::new(-c * 0.99, 1.0, -s * 1.01),
                ))
            })
            .chain(small)
            .collect();
        let mut all = geometries();
        all.push(("slivers", Arc::new(Geometry::new(slivers))));
        for (name, g) in all {
            let plain = Bvh::build_with(Arc::clone(&g), BvhParams::medium());
            let params = BvhParams {
                presplit: 0.5,
                ..BvhParams::medium()
            };
            let cut = Bvh::build_with(Arc::clone(&g), params);
            cut.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
            if name == "slivers" {
                assert!(cut.prim_ids().len() > plain.prim_ids().len(), "nothing cut");
                assert!(cut.sah_cost() < plain.sah_cost(), "{name}: no better tree");
            }
            let rays = raybench_geometry::random_rays::incoherent(g.bounds(), 3000, 9);
            let mut c = raybench_geometry::RayCounters::default();
            let mut on_slivers = 0;
            for r in &rays {
                let hit = cut.intersect(r, &mut c);
                on_slivers += usize::from(hit.is_some_and(|h| h.prim < 50));
                assert_eq!(hit, plain.intersect(r, &mut c), "{name}");
                assert_eq!(cut.occluded(r, &mut c), plain.occluded(r, &mut c), "{name}");
            }
            if name == "slivers" {
                assert!(on_slivers > 30, "{on_slivers} hits on the slivers");
            }
        }
    }

    #[test]
    fn sah_beats_a_leaf_on_real_work() {
        // Incoherent rays test a handful of the 20,480 triangles: the tree really culls.
        let g = Arc::new(Geometry::new(
            generators::icosphere(5)
                .triangles()
                .map(Shape::Triangle)
                .collect(),
        ));
        let bvh = Bvh::build_with(g, BvhParams::default());
        let rays = raybench_geometry::random_rays::incoherent(bvh.geometry.bounds(), 2000, 5);
        let mut c = raybench_geometry::RayCounters::default();
        for r in &rays {
            let _ = bvh.intersect(r, &mut c);
        }
        let per_ray = c.prim_tests as f64 / rays.len() as f64;
        assert!(per_ray < 10.0, "{per_ray} tests per ray");
    }
}
