//! [`Bvh`] with obvhs's PLOC topology: obvhs builds its binary tree (PLOC, reinsertion and
//! leaf collapse at one of its presets), and the tree is copied into the workspace's
//! depth-first layout with boxes recomputed from raybench's own primitive boxes.
//!
//! The result is traversed by [`Bvh`]'s kernel like any tree its binned SAH builder makes, so
//! the builders can be compared with the traversal held fixed (Aila, Karras and Laine, "On
//! Quality Metrics of Bounding Volume Hierarchies", HPG 2013, varied the builder under one
//! kernel). Only obvhs's topology is used: its boxes (and any rounding in them) are not, so
//! the hits are bit-identical to the naive backend's as for every [`Bvh`].
//!
//! [`Bvh::reinserted`] goes the other way first: a finished tree (the binned builder's) is
//! handed to obvhs's reinsertion optimiser and its new topology copied back the same way.

use crate::build::MAX_DEPTH;
use crate::{Bvh, BvhParams, Node};
use glam::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::node::Bvh2Node;
use raybench_geometry::{Aabb, Geometry};
use std::sync::Arc;
use std::time::Duration;

impl Bvh {
    /// Builds with obvhs's PLOC builder at `params` (its presets: `fastest_build()` ..
    /// `very_slow_build()`), the tree copied into the depth-first layout and refitted
    /// exactly. Subtrees that would lie deeper than the traversal's depth limit are made
    /// leaves holding all their primitives (PLOC does not bound the depth; the binned
    /// builder does), so every ray still finds its exact hit. [`Bvh::params`] reports
    /// [`BvhParams::medium`] with obvhs's leaf size limit.
    #[must_use]
    pub fn build_ploc(geometry: Arc<Geometry>, params: BvhBuildParams) -> Self {
        let bounded = geometry.bounded();
        let boxes: Vec<obvhs::aabb::Aabb> = bounded
            .iter()
            .map(|&id| {
                let b = geometry.shape(id).bounds().unwrap_or(Aabb::EMPTY);
                obvhs::aabb::Aabb {
                    min: Vec3A::from(b.min),
                    max: Vec3A::from(b.max),
                }
            })
            .collect();
        let mut bvh = Self {
            geometry: Arc::clone(&geometry),
            nodes: Vec::new(),
            prim_ids: Vec::with_capacity(bounded.len()),
            params: BvhParams {
                max_leaf_size: params.max_prims_per_leaf.max(1) as usize,
                ..BvhParams::medium()
            },
        };
        if boxes.is_empty() {
            return bvh;
        }
        let tree = obvhs::bvh2::builder::build_bvh2(&boxes, params, &mut Duration::default());
        bvh.copy_topology(&tree, |i| bounded[i as usize]);
        bvh
    }

    /// This tree after obvhs's reinsertion optimiser (Meister and Bittner, "Parallel
    /// Reinsertion for Bounding Volume Hierarchy Optimization", 2018): one pass per entry
    /// of `passes`, each over that fraction of the nodes (the largest of the upper
    /// levels), moves subtrees to where they lower the tree's surface-area cost most
    /// (obvhs's own builds run sixteen passes, the first over 2 % to 5 % of the nodes,
    /// each later one over fewer). The leaves keep their primitives; the tree is copied back into the depth-first layout and refitted
    /// exactly, so the hits stay bit-identical to the naive backend's. The same tree on
    /// any thread count.
    #[must_use]
    pub fn reinserted(mut self, passes: &[f32]) -> Self {
        if self.nodes.len() < 3 || passes.is_empty() {
            return self;
        }
        let mut tree = self.to_obvhs();
        obvhs::bvh2::reinsertion::ReinsertionOptimizer::default().run(
            &mut tree,
            1.0,
            Some(passes.to_vec()),
        );
        let prim_ids = std::mem::take(&mut self.prim_ids);
        self.prim_ids.reserve(prim_ids.len());
        self.nodes.clear();
        self.copy_topology(&tree, |i| prim_ids[i as usize]);
        self
    }

    /// This tree in obvhs's layout (siblings side by side), its leaves indexing the
    /// primitive-id array directly. The nodes are numbered breadth first: a reinsertion
    /// pass over a fraction `f` of the nodes takes its candidates from the first `2 f` of
    /// the array (sorted by area), which must therefore be the top of the tree (numbered
    /// depth first, passes starting at a fifth of Sponza's nodes saved at most a third of
    /// what one such pass saves now).
    fn to_obvhs(&self) -> Bvh2 {
        let node = |n: &Node, prim_count: u32, first_index: u32| Bvh2Node {
            aabb: obvhs::aabb::Aabb {
                min: Vec3A::from(n.min),
                max: Vec3A::from(n.max),
            },
            prim_count,
            first_index,
            ..Bvh2Node::default()
        };
        let mut nodes = vec![Bvh2Node::default(); self.nodes.len()];
        nodes[0] = node(&self.nodes[0], 0, 0);
        // (raybench node, obvhs node), breadth first.
        let mut queue = std::collections::VecDeque::from([(0usize, 0usize)]);
        let mut next = 1;
        while let Some((ours, theirs)) = queue.pop_front() {
            let n = &self.nodes[ours];
            if n.is_leaf() {
                nodes[theirs] = node(n, n.count, n.first_or_right);
                continue;
            }
            nodes[theirs] = node(n, 0, next as u32);
            queue.push_back((ours + 1, next));
            queue.push_back((n.first_or_right as usize, next + 1));
            next += 2;
        }
        Bvh2 {
            nodes,
            primitive_indices: (0..self.prim_ids.len() as u32).collect(),
            ..Bvh2::default()
        }
    }

    /// Replaces this tree's (empty) nodes and primitive ids with `tree`'s topology, in
    /// depth-first order, left subtree first; `id` maps `tree`'s primitive indices to
    /// primitive ids. Subtrees that would lie deeper than the traversal's depth limit
    /// become leaves holding all their primitives. The boxes are recomputed from the
    /// primitives' own.
    fn copy_topology(&mut self, tree: &Bvh2, id: impl Fn(u32) -> u32) {
        debug_assert!(self.nodes.is_empty() && self.prim_ids.is_empty());
        let ids = |first: u32, count: u32| {
            (first..first + count).map(|i| id(tree.primitive_indices[i as usize]))
        };
        // Depth first, left subtree before right: (obvhs node, node to patch with this
        // node's index as its second child, depth).
        let mut stack: Vec<(usize, Option<usize>, usize)> = vec![(0, None, 1)];
        while let Some((o, patch, depth)) = stack.pop() {
            let index = self.nodes.len();
            if let Some(p) = patch {
                self.nodes[p].first_or_right = index as u32;
            }
            let node = &tree.nodes[o];
            let first = self.prim_ids.len() as u32;
            if node.is_leaf() {
                self.prim_ids.extend(ids(node.first_index, node.prim_count));
            } else if depth >= MAX_DEPTH {
                let mut below = vec![o];
                while let Some(n) = below.pop() {
                    let n = &tree.nodes[n];
                    if n.is_leaf() {
                        self.prim_ids.extend(ids(n.first_index, n.prim_count));
                    } else {
                        below.extend([n.first_index as usize, n.first_index as usize + 1]);
                    }
                }
            } else {
                self.nodes.push(Node::default());
                stack.push((node.first_index as usize + 1, Some(index), depth + 1));
                stack.push((node.first_index as usize, None, depth + 1));
                continue;
            }
            self.nodes.push(Node {
                first_or_right: first,
                count: self.prim_ids.len() as u32 - first,
                ..Node::default()
            });
        }
        self.refit_boxes();
    }
}

#[cfg(test)]
mod tests {
    use crate::Bvh;
    use obvhs::BvhBuildParams;
    use raybench_geometry::{Accel, Geometry, Ray, RayCounters, Shape, Triangle, Vec3};
    use std::sync::Arc;

    /// A soup of small triangles on a 12 x 12 x 12 lattice.
    fn soup() -> Arc<Geometry> {
        let mut shapes = Vec::new();
        for i in 0..1728u32 {
            let p = Vec3::new((i % 12) as f32, ((i / 12) % 12) as f32, (i / 144) as f32);
            let q = p + Vec3::new(0.3 * (i % 5) as f32, 0.7, 0.1);
            shapes.push(Shape::Triangle(Triangle::new(p, q, p + Vec3::Z * 0.6)));
        }
        Arc::new(Geometry::new(shapes))
    }

    /// Asserts that `t` gives `reference`'s closest hits (id and `t`) and any hits on 500
    /// rays across the soup, of which 192 hit.
    fn assert_same_hits(t: &Bvh, reference: &Bvh) {
        let mut hits = 0;
        for k in 0..500u32 {
            let o = Vec3::new(-3.0, 0.1 + 0.023 * k as f32, 0.05 + 0.021 * k as f32);
            let ray = Ray::new(o, Vec3::new(1.0, 0.01 * (k % 7) as f32, 0.002));
            let mut c = RayCounters::default();
            let (a, b) = (t.intersect(&ray, &mut c), reference.intersect(&ray, &mut c));
            assert_eq!(
                a.map(|h| (h.prim, h.t.to_bits())),
                b.map(|h| (h.prim, h.t.to_bits()))
            );
            assert_eq!(t.occluded(&ray, &mut c), b.is_some());
            hits += usize::from(b.is_some());
        }
        assert!(hits > 150, "only {hits} of 500 rays hit");
    }

    #[test]
    fn every_preset_gives_a_valid_tree_and_the_binned_trees_hits() {
        let g = soup();
        let reference = Bvh::build(Arc::clone(&g));
        for params in [
            BvhBuildParams::fastest_build(),
            BvhBuildParams::medium_build(),
            BvhBuildParams::very_slow_build(),
        ] {
            let t = Bvh::build_ploc(Arc::clone(&g), params);
            t.validate().unwrap();
            assert!(t.depth() <= crate::build::MAX_DEPTH);
            assert_same_hits(&t, &reference);
        }
    }

    #[test]
    fn reinsertion_keeps_the_hits_and_lowers_the_cost() {
        let g = soup();
        let binned = Bvh::build_with(Arc::clone(&g), crate::BvhParams::fast());
        let reinserted = binned.clone().reinserted(&[1.0, 0.5]);
        reinserted.validate().unwrap();
        assert!(reinserted.depth() <= crate::build::MAX_DEPTH);
        assert_ne!(reinserted.nodes(), binned.nodes(), "nothing was reinserted");
        assert!(
            reinserted.sah_cost() < binned.sah_cost(),
            "SAH {} -> {}",
            binned.sah_cost(),
            reinserted.sah_cost()
        );
        let mut ids = reinserted.prim_ids().to_vec();
        ids.sort_unstable();
        assert_eq!(ids, (0..g.len() as u32).collect::<Vec<_>>());
        assert_same_hits(&reinserted, &binned);
    }

    #[test]
    fn obvhs_gets_the_tree_breadth_first_and_gives_it_back_unchanged() {
        let t = Bvh::build_with(soup(), crate::BvhParams::fast());
        assert!(t.depth() > 6, "too shallow a tree to tell the orders apart");
        let tree = t.to_obvhs();
        assert_eq!(tree.nodes.len(), t.nodes().len());
        // Children are numbered after their parent, so one sweep sets every depth.
        assert!(
            tree.nodes
                .iter()
                .enumerate()
                .all(|(i, n)| n.is_leaf() || n.first_index as usize > i)
        );
        // Breadth first (a partial reinsertion pass takes its candidates from the front):
        // no node lies deeper than the one numbered after it.
        let mut depth = vec![0usize; tree.nodes.len()];
        for (i, n) in tree.nodes.iter().enumerate() {
            if !n.is_leaf() {
                let first = n.first_index as usize;
                depth[first] = depth[i] + 1;
                depth[first + 1] = depth[i] + 1;
            }
        }
        assert!(
            depth.windows(2).all(|d| d[0] <= d[1]),
            "not numbered breadth first"
        );
        let mut back = Bvh {
            nodes: Vec::new(),
            prim_ids: Vec::new(),
            ..t.clone()
        };
        back.copy_topology(&tree, |i| t.prim_ids()[i as usize]);
        assert_eq!(back.nodes(), t.nodes());
        assert_eq!(back.prim_ids(), t.prim_ids());
    }

    #[test]
    fn a_lone_leaf_is_left_alone() {
        let tri = Shape::Triangle(Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y));
        let t = Bvh::build(Arc::new(Geometry::new(vec![tri; 3])));
        assert_eq!(t.nodes().len(), 1);
        assert_eq!(t.clone().reinserted(&[1.0]).nodes(), t.nodes());
    }

    #[test]
    fn subtrees_below_the_depth_limit_become_leaves() {
        // Every triangle at the same place: PLOC's Morton codes all tie.
        let tri = Shape::Triangle(Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y));
        let g = Arc::new(Geometry::new(vec![tri; 5000]));
        let t = Bvh::build_ploc(g, BvhBuildParams::fastest_build());
        t.validate().unwrap();
        assert!(t.depth() <= crate::build::MAX_DEPTH);
        // The preset makes leaves of one primitive: a larger leaf is a collapsed subtree.
        assert!(
            t.nodes().iter().any(|n| n.count > 1),
            "the depth limit was not reached"
        );
    }

    #[test]
    fn an_empty_scene_has_no_nodes() {
        let t = Bvh::build_ploc(
            Arc::new(Geometry::new(Vec::new())),
            BvhBuildParams::medium_build(),
        );
        assert!(t.nodes().is_empty());
        t.validate().unwrap();
    }
}
