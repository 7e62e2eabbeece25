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
//! [`Bvh::reinserted`] goes the other way first: the top of a finished tree (the binned
//! builder's) is handed to obvhs's reinsertion optimiser, the subtrees below it as leaves,
//! and the new top copied back around those subtrees, which move as whole blocks.

use crate::build::MAX_DEPTH;
use crate::{Bvh, BvhParams, Node};
use glam::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::node::Bvh2Node;
use raybench_geometry::{Aabb, Geometry};
use rayon::prelude::*;
use std::ops::Range;
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
    /// each later one over fewer). The same tree on any thread count.
    ///
    /// obvhs gets only the top of the tree, the nodes among which the passes pick their
    /// candidates and as many again below them; each subtree under that top goes over as
    /// one leaf and comes back whole, its nodes, boxes and primitives copied as they were,
    /// and only the nodes above them get new boxes, the unions of their children's (exact,
    /// as a refit's). So the hand-over costs the top's size, not the tree's; subtrees that
    /// would reach below the traversal's depth limit become leaves there. The leaves keep
    /// their primitives, so the hits stay bit-identical to the naive backend's.
    ///
    /// The passes' tree is kept only where it lowers the tree's surface-area cost
    /// ([`Bvh::sah_cost`]) by more than the fraction `min_gain` of it; otherwise this tree
    /// comes back as it was, without the copy (on regular meshes the passes move nothing:
    /// the hand-over and the passes are then all they cost). A tree whose root box has no
    /// finite area is never reinserted.
    #[must_use]
    pub fn reinserted(self, passes: &[f32], min_gain: f64) -> Self {
        let n = self.nodes.len();
        if n < 3 || passes.is_empty() {
            return self;
        }
        // A pass over a fraction `f` of `n` nodes moves up to `floor(f n)` of them (at least
        // one), taking as candidates the largest of the first `2 (floor(f n) + 1)`.
        let moves: Vec<usize> = passes
            .iter()
            .map(|&f| ((n as f32 * f) as usize).max(1))
            .collect();
        let pool = 2 * (moves.iter().max().copied().unwrap_or(1) + 1);
        let (mut tree, blocks) = self.to_obvhs(pool.saturating_mul(TOP_MARGIN));
        // The same moves over the smaller tree (half a node above each, against rounding).
        let handed = tree.nodes.len() as f32;
        let fractions = moves.iter().map(|&m| (m as f32 + 0.5) / handed).collect();
        let before = interior_area(&tree);
        obvhs::bvh2::reinsertion::ReinsertionOptimizer::default().run(
            &mut tree,
            1.0,
            Some(fractions),
        );
        // Only the top's interior nodes changed: the subtrees below are the same, unless the
        // new top hangs one below the depth limit, where it is cut into leaves (rare, and
        // not counted here).
        let gain = f64::from(self.params.traversal_cost) * (before - interior_area(&tree));
        if gain > 0.0 && gain > min_gain * self.weighted_cost() {
            self.with_top(&tree, &blocks)
        } else {
            self
        }
    }

    /// [`Bvh::sah_cost`] times the root's surface area: every interior node's area times
    /// the traversal cost, every leaf's times its primitive count. Summed in chunks of a
    /// fixed size, so the same on any thread count.
    fn weighted_cost(&self) -> f64 {
        let c_t = f64::from(self.params.traversal_cost);
        let partial: Vec<f64> = self
            .nodes
            .par_chunks(COPY_CHUNK)
            .map(|chunk| {
                chunk
                    .iter()
                    .map(|n| {
                        let weight = if n.is_leaf() { f64::from(n.count) } else { c_t };
                        weight * f64::from(n.aabb().surface_area())
                    })
                    .sum()
            })
            .collect();
        partial.iter().sum()
    }

    /// The top `top` nodes of this tree, numbered breadth first, in obvhs's layout
    /// (siblings side by side), and for each of its leaves the subtree of this tree it
    /// stands for (its root node): the children of the top's nodes that are not in the
    /// top themselves become leaves whole, as do the top's own leaves. A leaf's
    /// `first_index` is its subtree's place in the returned list. With `top` at least the
    /// node count the whole tree goes over.
    ///
    /// Breadth first because a reinsertion pass over a fraction `f` of the nodes takes its
    /// candidates from the first `2 f` of the array (sorted by area), which must therefore
    /// be the top of the tree (numbered depth first, passes starting at a fifth of Sponza's
    /// nodes saved at most a third of what one such pass saves now); and because then the
    /// first `top` nodes are numbered as they would be in the whole tree.
    fn to_obvhs(&self, top: usize) -> (Bvh2, Vec<u32>) {
        let node = |n: &Node, prim_count: u32, first_index: u32| Bvh2Node {
            aabb: obvhs::aabb::Aabb {
                min: Vec3A::from(n.min),
                max: Vec3A::from(n.max),
            },
            prim_count,
            first_index,
            ..Bvh2Node::default()
        };
        let mut nodes = vec![
            Bvh2Node::default();
            self.nodes
                .len()
                .min(top.saturating_mul(2).saturating_add(1))
        ];
        let mut blocks = Vec::new();
        // (raybench node, obvhs node), breadth first.
        let mut queue = std::collections::VecDeque::from([(0usize, 0usize)]);
        let mut next = 1;
        while let Some((ours, theirs)) = queue.pop_front() {
            let n = &self.nodes[ours];
            if n.is_leaf() || theirs >= top {
                nodes[theirs] = node(n, 1, blocks.len() as u32);
                blocks.push(ours as u32);
                continue;
            }
            nodes[theirs] = node(n, 0, next as u32);
            queue.push_back((ours + 1, next));
            queue.push_back((n.first_or_right as usize, next + 1));
            next += 2;
        }
        nodes.truncate(next);
        let tree = Bvh2 {
            nodes,
            primitive_indices: (0..blocks.len() as u32).collect(),
            ..Bvh2::default()
        };
        (tree, blocks)
    }

    /// This tree with `tree`'s topology above the subtrees `blocks` (which its leaves
    /// stand for: see [`Bvh::to_obvhs`]), in depth-first order, left subtree first. A
    /// subtree's nodes and primitives are contiguous in the depth-first layout and are
    /// copied as one block, its indices shifted; one that would reach below the
    /// traversal's depth limit is copied node by node down to it, where its subtrees
    /// become leaves holding all their primitives. The nodes above the blocks get the
    /// unions of their children's boxes.
    ///
    /// The new arrays are planned first, on one thread, over the top and the blocks' extents
    /// (found in parallel, each block walking only its own nodes; a block copied node by
    /// node walks each of its subtrees down to the limit again, a case the binned trees
    /// rarely reach); then every block is copied into the range the plan gives it, in
    /// parallel. The result does not depend on the thread count.
    fn with_top(self, tree: &Bvh2, blocks: &[u32]) -> Self {
        let old = &self.nodes;
        let extents: Vec<Subtree> = blocks
            .par_iter()
            .map_init(Vec::new, |pending, &root| {
                Subtree::of(old, root as usize, pending)
            })
            .collect();
        // The new node array as pieces in order, and the ranges of the old primitive ids
        // that make up the new one.
        let mut pieces: Vec<Piece> = Vec::new();
        let mut prim_ranges: Vec<Range<usize>> = Vec::new();
        let (mut node_count, mut prim_count) = (0usize, 0usize);
        // Interior nodes made here (indices into the new array), whose boxes are set once
        // their children's are.
        let mut made = Vec::new();
        // Depth first: (obvhs node or, with `OURS`, a node of this tree; the piece of the
        // node to patch with this node's index as its second child; depth).
        const OURS: usize = 1 << (usize::BITS - 1);
        let mut stack: Vec<(usize, Option<usize>, usize)> = vec![(0, None, 1)];
        let mut scratch = Vec::new();
        while let Some((at, patch, depth)) = stack.pop() {
            if let Some(p) = patch {
                let Piece::One(parent) = &mut pieces[p] else {
                    unreachable!("a node with a second child is a piece of its own")
                };
                parent.first_or_right = node_count as u32;
            }
            let (ours, subtree) = if at & OURS != 0 {
                let ours = at & !OURS;
                (ours, Subtree::of(old, ours, &mut scratch))
            } else {
                let node = &tree.nodes[at];
                if node.is_leaf() {
                    let block = node.first_index as usize;
                    (blocks[block] as usize, extents[block].clone())
                } else if depth >= MAX_DEPTH {
                    // One leaf for all the subtrees below.
                    let (first, mut bounds) = (prim_count, Aabb::EMPTY);
                    let mut below = vec![at];
                    while let Some(b) = below.pop() {
                        let b = &tree.nodes[b];
                        if b.is_leaf() {
                            let block = b.first_index as usize;
                            let prims = extents[block].prims.clone();
                            prim_count += prims.len();
                            prim_ranges.push(prims);
                            bounds = bounds.union(old[blocks[block] as usize].aabb());
                        } else {
                            below.extend([b.first_index as usize + 1, b.first_index as usize]);
                        }
                    }
                    pieces.push(Piece::One(Node {
                        min: bounds.min,
                        first_or_right: first as u32,
                        max: bounds.max,
                        count: (prim_count - first) as u32,
                    }));
                    node_count += 1;
                    continue;
                } else {
                    made.push(node_count);
                    let first = node.first_index as usize;
                    stack.push((first + 1, Some(pieces.len()), depth + 1));
                    stack.push((first, None, depth + 1));
                    pieces.push(Piece::One(Node::default()));
                    node_count += 1;
                    continue;
                }
            };
            let Subtree {
                nodes: span,
                prims,
                levels,
            } = subtree;
            if depth + levels - 1 <= MAX_DEPTH {
                pieces.push(Piece::Whole {
                    node_shift: node_count as i64 - span.start as i64,
                    prim_shift: prim_count as i64 - prims.start as i64,
                    nodes: span.clone(),
                });
                node_count += span.len();
                prim_count += prims.len();
                prim_ranges.push(prims);
            } else if depth >= MAX_DEPTH {
                pieces.push(Piece::One(Node {
                    first_or_right: prim_count as u32,
                    count: prims.len() as u32,
                    ..old[ours]
                }));
                node_count += 1;
                prim_count += prims.len();
                prim_ranges.push(prims);
            } else {
                let right = old[ours].first_or_right as usize;
                stack.push((right | OURS, Some(pieces.len()), depth + 1));
                stack.push(((ours + 1) | OURS, None, depth + 1));
                pieces.push(Piece::One(Node {
                    first_or_right: 0,
                    ..old[ours]
                }));
                node_count += 1;
            }
        }
        let mut nodes = Vec::with_capacity(node_count);
        nodes.par_extend(rayon::iter::repeat_n(Node::default(), node_count));
        split_by(&mut nodes, pieces.iter().map(Piece::len))
            .into_par_iter()
            .zip(&pieces)
            .for_each(|(dst, piece)| match piece {
                Piece::One(node) => dst[0] = *node,
                Piece::Whole {
                    nodes: span,
                    node_shift,
                    prim_shift,
                } => {
                    let shift = |n: &Node| {
                        let by = if n.is_leaf() { prim_shift } else { node_shift };
                        Node {
                            first_or_right: (i64::from(n.first_or_right) + by) as u32,
                            ..*n
                        }
                    };
                    dst.par_chunks_mut(COPY_CHUNK)
                        .zip(old[span.clone()].par_chunks(COPY_CHUNK))
                        .for_each(|(d, s)| {
                            for (d, s) in d.iter_mut().zip(s) {
                                *d = shift(s);
                            }
                        });
                }
            });
        let mut prim_ids = Vec::with_capacity(prim_count);
        prim_ids.par_extend(rayon::iter::repeat_n(0, prim_count));
        split_by(&mut prim_ids, prim_ranges.iter().map(Range::len))
            .into_par_iter()
            .zip(&prim_ranges)
            .for_each(|(dst, src)| {
                dst.par_chunks_mut(COPY_CHUNK)
                    .zip(self.prim_ids[src.clone()].par_chunks(COPY_CHUNK))
                    .for_each(|(d, s)| d.copy_from_slice(s));
            });
        for &i in made.iter().rev() {
            let b = nodes[i + 1]
                .aabb()
                .union(nodes[nodes[i].first_or_right as usize].aabb());
            nodes[i].min = b.min;
            nodes[i].max = b.max;
        }
        Self {
            nodes,
            prim_ids,
            ..self
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

/// How many more nodes than the reinsertion passes' candidate pool [`Bvh::reinserted`]
/// hands to obvhs (the pool is the first `2 (m + 1)` nodes for a pass that moves `m`): the
/// nodes below the pool are where the passes can move a candidate to.
const TOP_MARGIN: usize = 2;

/// The surface areas of `tree`'s interior nodes, summed.
fn interior_area(tree: &Bvh2) -> f64 {
    tree.nodes
        .iter()
        .filter(|n| !n.is_leaf())
        .map(|n| 2.0 * f64::from(n.aabb.half_area()))
        .sum()
}

/// Elements per parallel task when [`Bvh::with_top`] copies a large block or
/// [`Bvh::weighted_cost`] sums a tree's areas.
const COPY_CHUNK: usize = 1 << 14;

/// A subtree of a depth-first node array.
#[derive(Clone, Debug, PartialEq)]
struct Subtree {
    /// Its nodes (contiguous: the root, then the left subtree, then the right).
    nodes: Range<usize>,
    /// The primitive ids its leaves cover (contiguous too).
    prims: Range<usize>,
    /// Its levels: 1 for a leaf.
    levels: usize,
}

impl Subtree {
    /// The subtree under `root` of the depth-first `nodes`, found by walking its nodes in
    /// array order: after a leaf comes the second child of the nearest node above it whose
    /// second child is still to come, and after the last leaf the subtree ends. `pending`
    /// is scratch space (the depths of the second children still to come, the nearest
    /// last), empty again on return.
    fn of(nodes: &[Node], root: usize, pending: &mut Vec<usize>) -> Self {
        debug_assert!(pending.is_empty());
        let (mut i, mut depth, mut levels) = (root, 1, 1);
        let mut first_prim = None;
        loop {
            levels = levels.max(depth);
            let n = &nodes[i];
            if n.is_leaf() {
                let first = *first_prim.get_or_insert(n.first_or_right as usize);
                match pending.pop() {
                    Some(d) => depth = d,
                    None => {
                        return Self {
                            nodes: root..i + 1,
                            prims: first..(n.first_or_right + n.count) as usize,
                            levels,
                        };
                    }
                }
            } else {
                depth += 1;
                pending.push(depth);
            }
            i += 1;
        }
    }
}

/// A piece of the node array [`Bvh::with_top`] writes.
enum Piece {
    /// One node, as it is.
    One(Node),
    /// A subtree copied whole: the old `nodes`, second-child indices shifted by
    /// `node_shift` and leaves' first primitives by `prim_shift`.
    Whole {
        nodes: Range<usize>,
        node_shift: i64,
        prim_shift: i64,
    },
}

impl Piece {
    /// Nodes it writes.
    fn len(&self) -> usize {
        match self {
            Self::One(_) => 1,
            Self::Whole { nodes, .. } => nodes.len(),
        }
    }
}

/// `v` cut into consecutive slices of the lengths `lens` (which add up to at most its
/// length).
fn split_by<T>(v: &mut [T], lens: impl Iterator<Item = usize>) -> Vec<&mut [T]> {
    let mut rest = v;
    lens.map(|len| {
        let (head, tail) = std::mem::take(&mut rest).split_at_mut(len);
        rest = tail;
        head
    })
    .collect()
}

#[cfg(test)]
mod tests {
    use super::Subtree;
    use crate::build::MAX_DEPTH;
    use crate::{Bvh, Node};
    use obvhs::BvhBuildParams;
    use obvhs::bvh2::Bvh2;
    use obvhs::bvh2::node::Bvh2Node;
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
        let rays = (0..500u32).map(|k| {
            let o = Vec3::new(-3.0, 0.1 + 0.023 * k as f32, 0.05 + 0.021 * k as f32);
            Ray::new(o, Vec3::new(1.0, 0.01 * (k % 7) as f32, 0.002))
        });
        let hits = assert_same_hits_on(t, reference, rays);
        assert!(hits > 150, "only {hits} of 500 rays hit");
    }

    /// Asserts that `t` gives `reference`'s closest hits (id and `t`) and any hits on
    /// `rays`; returns how many hit.
    fn assert_same_hits_on(t: &Bvh, reference: &Bvh, rays: impl Iterator<Item = Ray>) -> usize {
        let (mut c, mut hits) = (RayCounters::default(), 0);
        for ray in rays {
            let (a, b) = (t.intersect(&ray, &mut c), reference.intersect(&ray, &mut c));
            assert_eq!(
                a.map(|h| (h.prim, h.t.to_bits())),
                b.map(|h| (h.prim, h.t.to_bits()))
            );
            assert_eq!(t.occluded(&ray, &mut c), b.is_some());
            hits += usize::from(b.is_some());
        }
        hits
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
        let reinserted = binned.clone().reinserted(&[1.0, 0.5], 0.0);
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
        let (tree, blocks) = t.to_obvhs(usize::MAX);
        assert_eq!(tree.nodes.len(), t.nodes().len());
        assert_eq!(
            blocks.len(),
            t.nodes().iter().filter(|n| n.is_leaf()).count()
        );
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
        let back = t.clone().with_top(&tree, &blocks);
        assert_eq!(back.nodes(), t.nodes());
        assert_eq!(back.prim_ids(), t.prim_ids());
        // Only the top: the same first nodes, the rest as whole subtrees, and the same
        // tree back.
        let (top, blocks) = t.to_obvhs(40);
        assert!(
            top.nodes.len() <= 81 && blocks.len() > 20,
            "{}",
            top.nodes.len()
        );
        for (a, b) in top.nodes.iter().zip(&tree.nodes).take(40) {
            assert_eq!((a.aabb, a.is_leaf()), (b.aabb, b.is_leaf()));
        }
        let back = t.clone().with_top(&top, &blocks);
        assert_eq!(back.nodes(), t.nodes());
        assert_eq!(back.prim_ids(), t.prim_ids());
    }

    /// A top deeper than the depth limit: the subtrees that would reach below it are
    /// copied node by node down to it, and what lies below becomes leaves, so the tree
    /// keeps every primitive once and gives the same hits.
    #[test]
    fn subtrees_hung_below_the_depth_limit_are_cut_there() {
        let g = soup();
        let t = Bvh::build_with(Arc::clone(&g), crate::BvhParams::fast());
        let (_, blocks) = t.to_obvhs(64);
        assert!(blocks.len() > MAX_DEPTH + 2, "{} subtrees", blocks.len());
        // A chain: interior node 2 k holds subtree k and the interior node 2 k + 2, so
        // subtree k hangs at depth k + 2; the last interior node holds the last two.
        let leaf = |k: usize| Bvh2Node {
            prim_count: 1,
            first_index: k as u32,
            ..Bvh2Node::default()
        };
        let inner = |first: usize| Bvh2Node {
            first_index: first as u32,
            ..Bvh2Node::default()
        };
        let k = blocks.len();
        let mut nodes = vec![inner(1)];
        for i in 0..k - 1 {
            nodes.push(leaf(i));
            nodes.push(if i + 2 < k {
                inner(nodes.len() + 1)
            } else {
                leaf(k - 1)
            });
        }
        let chain = Bvh2 {
            nodes,
            ..Bvh2::default()
        };
        let cut = t.clone().with_top(&chain, &blocks);
        cut.validate().unwrap();
        assert_eq!(cut.depth(), MAX_DEPTH);
        assert_same_hits(&cut, &t);
    }

    /// A pass that moves fewer nodes than the tree holds hands obvhs only the top, and the
    /// tree it gives back is valid, cheaper, exactly boxed and traced alike.
    #[test]
    fn a_tree_larger_than_its_top_is_reinserted_in_blocks() {
        let g = Arc::new(Geometry::new(
            raybench_scene::generators::soup(20_000, 1)
                .triangles()
                .map(Shape::Triangle)
                .collect(),
        ));
        let binned = Bvh::build_with(Arc::clone(&g), crate::BvhParams::fast());
        let moves = (binned.nodes().len() as f32 * 0.1) as usize;
        let (top, _) = binned.to_obvhs(2 * (moves + 1) * super::TOP_MARGIN);
        assert!(
            top.nodes.len() < binned.nodes().len() * 3 / 4,
            "{} of {} nodes handed over",
            top.nodes.len(),
            binned.nodes().len()
        );
        let reinserted = binned.clone().reinserted(&[0.1], 0.0);
        reinserted.validate().unwrap();
        // The blocks are copied in parallel: the same tree on one thread and on four.
        for threads in [1, 4] {
            let t = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| binned.clone().reinserted(&[0.1], 0.0));
            assert_eq!(t.nodes(), reinserted.nodes(), "{threads} threads");
            assert_eq!(t.prim_ids(), reinserted.prim_ids(), "{threads} threads");
        }
        // Kept only when it gains more than asked for.
        let gain = 1.0 - reinserted.sah_cost() / binned.sah_cost();
        let kept = binned.clone().reinserted(&[0.1], 0.5 * gain);
        assert_eq!(kept.nodes(), reinserted.nodes());
        assert_eq!(kept.prim_ids(), reinserted.prim_ids());
        let dropped = binned.clone().reinserted(&[0.1], 1.5 * gain);
        assert_eq!(dropped.nodes(), binned.nodes());
        assert_eq!(dropped.prim_ids(), binned.prim_ids());
        assert!(reinserted.depth() <= MAX_DEPTH);
        assert!(
            reinserted.sah_cost() < binned.sah_cost(),
            "SAH {} -> {}",
            binned.sah_cost(),
            reinserted.sah_cost()
        );
        let mut refitted = reinserted.clone();
        refitted.refit_boxes();
        assert_eq!(refitted.nodes(), reinserted.nodes(), "boxes not exact");
        let mut ids = reinserted.prim_ids().to_vec();
        ids.sort_unstable();
        assert_eq!(ids, (0..g.len() as u32).collect::<Vec<_>>());
        // Rays from all sides through the soup's unit cube.
        let rays = (0..2000u32).map(|k| {
            let t = k as f32 * 0.618;
            let o = Vec3::new(t.sin(), t.cos(), (t * 1.3).sin()) * 30.0;
            Ray::new(o, Vec3::new(t.cos(), (2.0 * t).sin(), t.sin()) * 0.8 - o)
        });
        let hits = assert_same_hits_on(&reinserted, &binned, rays);
        assert!(hits > 1000, "only {hits} of 2000 rays hit");
    }

    /// The gain is weighed as `Bvh::sah_cost` weighs a tree, traversal cost included: with
    /// `C_t` = 2 a threshold a little under the gain keeps the tree, one above drops it.
    #[test]
    fn the_gain_is_weighed_as_the_sah_weighs_it() {
        let params = crate::BvhParams {
            traversal_cost: 2.0,
            ..crate::BvhParams::fast()
        };
        let g = Arc::new(Geometry::new(
            raybench_scene::generators::soup(20_000, 1)
                .triangles()
                .map(Shape::Triangle)
                .collect(),
        ));
        let binned = Bvh::build_with(g, params);
        let root = f64::from(binned.nodes()[0].aabb().surface_area());
        let sah = binned.weighted_cost() / root;
        assert!(
            (sah - binned.sah_cost()).abs() < 1e-6 * sah,
            "{sah} against {}",
            binned.sah_cost()
        );
        let reinserted = binned.clone().reinserted(&[1.0], 0.0);
        let gain = 1.0 - reinserted.sah_cost() / binned.sah_cost();
        assert!(gain > 0.0, "nothing was reinserted");
        let kept = binned.clone().reinserted(&[1.0], 0.8 * gain);
        assert_eq!(kept.nodes(), reinserted.nodes());
        let dropped = binned.clone().reinserted(&[1.0], 1.25 * gain);
        assert_eq!(dropped.nodes(), binned.nodes());
    }

    #[test]
    fn a_subtree_is_found_by_walking_its_nodes() {
        fn reference(nodes: &[Node], i: usize) -> Subtree {
            let n = &nodes[i];
            if n.is_leaf() {
                let first = n.first_or_right as usize;
                return Subtree {
                    nodes: i..i + 1,
                    prims: first..first + n.count as usize,
                    levels: 1,
                };
            }
            let (l, r) = (
                reference(nodes, i + 1),
                reference(nodes, n.first_or_right as usize),
            );
            assert_eq!((l.nodes.end, l.prims.end), (r.nodes.start, r.prims.start));
            Subtree {
                nodes: i..r.nodes.end,
                prims: l.prims.start..r.prims.end,
                levels: 1 + l.levels.max(r.levels),
            }
        }
        let t = Bvh::build_with(soup(), crate::BvhParams::fast());
        assert!(t.depth() > 6);
        for i in 0..t.nodes().len() {
            assert_eq!(
                Subtree::of(t.nodes(), i, &mut Vec::new()),
                reference(t.nodes(), i),
                "node {i}"
            );
        }
        assert_eq!(Subtree::of(t.nodes(), 0, &mut Vec::new()).levels, t.depth());
    }

    #[test]
    fn a_lone_leaf_is_left_alone() {
        let tri = Shape::Triangle(Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y));
        let t = Bvh::build(Arc::new(Geometry::new(vec![tri; 3])));
        assert_eq!(t.nodes().len(), 1);
        assert_eq!(t.clone().reinserted(&[1.0], 0.0).nodes(), t.nodes());
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
