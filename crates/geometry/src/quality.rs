//! Structure quality: the one definition of the figures that describe a built acceleration
//! structure independently of how fast it is traced (`raybench info`, the report's
//! "Structure quality" section).
//!
//! A tree-shaped structure of any arity (raybench's BVH2, obvhs's CWBVH8, the packet
//! backend's BVH8, the `bvh` crate's tree) describes itself as a [`TreeView`]: nodes with a
//! box, interior nodes with children, leaves with the primitive ids they test. From the view
//! come:
//!
//! - the **SAH cost** ([`TreeView::sah_cost`]): `(C_t * sum over interior nodes of A(n) +
//!   C_i * sum over leaves of A(n) * |prims(n)|) / A(root)`, the expected work of a ray that
//!   hits the root box (MacDonald and Booth 1990), with the constants of [`CostConstants`]
//!   (the report and `info` use [`CostConstants::UNIT`]: `C_t = 1`, `C_i = 1`);
//! - the **EPO**, end-point overlap (Aila, Karras and Laine, "On Quality Metrics of Bounding
//!   Volume Hierarchies", HPG 2013; [`TreeView::epo`]): the cost, in the same constants, of
//!   the nodes whose box contains a point on a primitive's surface although their subtree
//!   does not hold that primitive, averaged over the scene's surface area: `sum over nodes n
//!   of C(n) * A((S \ Q(n)) ∩ box(n)) / A(S)`, `S` the surfaces, `Q(n)` those in `n`'s
//!   subtree, `C(n)` = `C_t` for an interior node and `C_i * |prims(n)|` for a leaf. It is
//!   estimated from points sampled uniformly by area, with its standard error;
//! - leaf and interior node counts, the leaf-size histogram ([`SizeHistogram`]), the depth
//!   (maximum and mean over leaves, the root at depth 1), bytes per primitive;
//! - given rays, the **leaf counts** ([`TreeView::leaf_counts`]): per ray, the leaves whose
//!   box its segment up to its closest hit enters, which every exact closest-hit traversal
//!   must open, with their mean and standard deviation (the spread is the leaf-count
//!   variability of Aila, Karras and Laine 2013).
//!
//! Grids describe themselves by their cell lists' lengths ([`GridQuality::from_lists`]).

use crate::aabb::Aabb;
use crate::geometry::{Geometry, Shape};
use crate::ray::Ray;
use crate::sampling::{pcg3d, to_unit_f32};
use std::sync::Arc;

/// EPO samples drawn by default ([`QualityParams::default`]): a standard error of a few per
/// cent of the estimate on the built-in scenes, in milliseconds.
pub const DEFAULT_EPO_SAMPLES: u32 = 4096;

/// The most EPO samples a run may ask for: 256 times the default, seconds on a large scene
/// (the standard error falls only as the square root of the count).
pub const MAX_EPO_SAMPLES: u32 = 1 << 20;

/// The cost constants of the SAH cost and the EPO.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostConstants {
    /// `C_t`: the cost of visiting an interior node (testing a ray against its box or its
    /// children's boxes).
    pub traversal: f64,
    /// `C_i`: the cost of testing one primitive.
    pub intersection: f64,
}

impl CostConstants {
    /// `C_t = 1`, `C_i = 1`: the constants `raybench info` and the report state, and those of
    /// `raybench-bvh`'s default build (`Bvh::sah_cost` is [`TreeView::sah_cost`] with the
    /// build's `C_t` and `C_i = 1`).
    pub const UNIT: Self = Self {
        traversal: 1.0,
        intersection: 1.0,
    };
}

/// What to measure and how: the cost constants, the number of EPO samples and their seed,
/// and the rays of the leaf counts.
#[derive(Clone, Debug, PartialEq)]
pub struct QualityParams {
    /// The SAH and EPO constants.
    pub costs: CostConstants,
    /// Points sampled for the EPO (0: no estimate).
    pub epo_samples: u32,
    /// Seed of the sampled points.
    pub seed: u32,
    /// Rays whose segments give the leaf counts ([`TreeView::leaf_counts`]), each clipped at
    /// its closest hit (`t_max`; a miss keeps its own); empty (the default): not measured.
    pub rays: Arc<[Ray]>,
}

impl Default for QualityParams {
    fn default() -> Self {
        Self {
            costs: CostConstants::UNIT,
            epo_samples: DEFAULT_EPO_SAMPLES,
            seed: 0,
            rays: Arc::from(Vec::new()),
        }
    }
}

/// Leaves entered per ray ([`TreeView::leaf_counts`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LeafCounts {
    /// Rays counted.
    pub rays: u64,
    /// Mean leaves per ray.
    pub mean: f64,
    /// Their standard deviation over the rays (population): the leaf-count variability.
    pub std_dev: f64,
    /// The most leaves one ray entered.
    pub max: u32,
}

/// Labels of the buckets of a [`SizeHistogram`].
pub const SIZE_BUCKETS: [&str; 7] = ["1", "2", "3", "4", "5-8", "9-16", ">16"];

/// A histogram of sizes (primitives per leaf, references per grid cell) in the buckets of
/// [`SIZE_BUCKETS`]: 1, 2, 3, 4, 5-8, 9-16, more than 16. Size 0 is not counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SizeHistogram(pub [u64; 7]);

impl SizeHistogram {
    /// The bucket of `size` (at least 1).
    #[must_use]
    pub fn bucket(size: u64) -> usize {
        match size {
            0..=4 => size.max(1) as usize - 1,
            5..=8 => 4,
            9..=16 => 5,
            _ => 6,
        }
    }

    /// Counts one item of `size` (nothing for 0).
    pub fn add(&mut self, size: u64) {
        if size > 0 {
            self.0[Self::bucket(size)] += 1;
        }
    }

    /// `1:n 2:n ... >16:n`, empty buckets left out.
    #[must_use]
    pub fn describe(&self) -> String {
        let parts: Vec<String> = SIZE_BUCKETS
            .iter()
            .zip(self.0)
            .filter(|(_, n)| *n > 0)
            .map(|(label, n)| format!("{label}:{n}"))
            .collect();
        if parts.is_empty() {
            "-".into()
        } else {
            parts.join(" ")
        }
    }
}

/// An estimate of the EPO ([`TreeView::epo`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Epo {
    /// The estimate: the mean over the samples.
    pub mean: f64,
    /// Its standard error (sample standard deviation over the square root of the count).
    pub std_error: f64,
    /// Points sampled.
    pub samples: u32,
    /// Bounded primitives left out of the sampling: those whose [`Shape::area`] is not
    /// known (height fields, CSG trees, Bezier patches, SDF models), whose surface cannot be
    /// sampled by area here. Their area is unknown, so it is their count that is stated.
    pub excluded_primitives: u64,
}

/// The quality of a tree-shaped structure ([`TreeView::quality`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TreeQuality {
    /// The constants of `sah` and `epo`.
    pub costs: CostConstants,
    /// The SAH cost ([`TreeView::sah_cost`]).
    pub sah: f64,
    /// The EPO estimate ([`TreeView::epo`]).
    pub epo: Epo,
    /// Interior nodes (the root included unless it is a leaf).
    pub interior_nodes: u64,
    /// Leaves.
    pub leaves: u64,
    /// Primitives per leaf.
    pub leaf_sizes: SizeHistogram,
    /// Nodes on the longest path from the root to a leaf (a lone leaf: 1; empty: 0).
    pub max_depth: u32,
    /// Mean depth of the leaves, counted like `max_depth`.
    pub mean_leaf_depth: f64,
    /// Primitive references over all leaves.
    pub references: u64,
    /// The structure's bytes (its `AccelStats::memory_bytes`) over the scene's bounded
    /// primitives (0 when there are none).
    pub bytes_per_primitive: f64,
    /// Leaves entered per ray over [`QualityParams::rays`]; `None` without rays.
    pub leaf_counts: Option<LeafCounts>,
}

/// The quality of a grid ([`GridQuality::from_lists`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridQuality {
    /// Cells whose lists a ray tests (a two-level grid: its top cells without a sub-grid and
    /// every sub-grid's cells).
    pub cells: u64,
    /// Cells with a non-empty list.
    pub non_empty_cells: u64,
    /// Primitive references over all lists.
    pub references: u64,
    /// Bounded primitives of the scene.
    pub primitives: u64,
    /// The longest list.
    pub max_list: u64,
    /// Lengths of the non-empty lists.
    pub list_lengths: SizeHistogram,
    /// The structure's bytes over the bounded primitives (0 when there are none).
    pub bytes_per_primitive: f64,
}

impl GridQuality {
    /// The figures of a grid whose cells' lists have the lengths `lists`, over `primitives`
    /// bounded primitives, holding `memory_bytes`.
    #[must_use]
    pub fn from_lists(
        lists: impl IntoIterator<Item = u64>,
        primitives: u64,
        memory_bytes: usize,
    ) -> Self {
        let mut q = Self {
            cells: 0,
            non_empty_cells: 0,
            references: 0,
            primitives,
            max_list: 0,
            list_lengths: SizeHistogram::default(),
            bytes_per_primitive: per_primitive(memory_bytes, primitives),
        };
        for n in lists {
            q.cells += 1;
            q.non_empty_cells += u64::from(n > 0);
            q.references += n;
            q.max_list = q.max_list.max(n);
            q.list_lengths.add(n);
        }
        q
    }

    /// The fraction of cells that are not empty (0 without cells).
    #[must_use]
    pub fn fill(&self) -> f64 {
        ratio(self.non_empty_cells, self.cells)
    }

    /// References per bounded primitive (0 without primitives).
    #[must_use]
    pub fn references_per_primitive(&self) -> f64 {
        ratio(self.references, self.primitives)
    }

    /// The mean length of the non-empty lists (0 when all are empty).
    #[must_use]
    pub fn mean_list(&self) -> f64 {
        ratio(self.references, self.non_empty_cells)
    }
}

/// The quality of a built structure, as [`crate::Accel::quality`] reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StructureQuality {
    /// A tree of boxes.
    Tree(TreeQuality),
    /// A uniform or two-level grid.
    Grid(GridQuality),
    /// A structure that exists but cannot be read (Embree's BVH lives inside the library,
    /// behind an API without node access); the reason.
    NotReadable(&'static str),
}

/// `a / b`, 0 when `b` is 0.
fn ratio(a: u64, b: u64) -> f64 {
    if b == 0 { 0.0 } else { a as f64 / b as f64 }
}

/// Bytes per primitive, 0 without primitives.
fn per_primitive(bytes: usize, primitives: u64) -> f64 {
    ratio(bytes as u64, primitives)
}

/// One node of a [`TreeView`].
#[derive(Clone, Copy, Debug)]
struct ViewNode {
    bounds: Aabb,
    /// `items[first..first + count]`: children (interior) or primitive ids (leaf).
    first: u32,
    count: u32,
    leaf: bool,
}

/// A neutral view of a tree-shaped structure: boxes, children of any arity, leaves with the
/// primitive ids they test. Built bottom up: [`TreeView::leaf`] and [`TreeView::interior`]
/// return the new node's index, children are added before their parent, and the last node
/// added is the root.
#[derive(Clone, Debug, Default)]
pub struct TreeView {
    nodes: Vec<ViewNode>,
    items: Vec<u32>,
}

impl TreeView {
    /// An empty view (the tree of a scene without bounded primitives).
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a leaf with box `bounds` testing the primitives `prims`; returns its index.
    pub fn leaf(&mut self, bounds: Aabb, prims: &[u32]) -> u32 {
        self.push(bounds, prims, true)
    }

    /// Adds an interior node with box `bounds` over the nodes `children` (added before);
    /// returns its index.
    ///
    /// # Panics
    /// When a child has not been added yet.
    pub fn interior(&mut self, bounds: Aabb, children: &[u32]) -> u32 {
        let next = self.nodes.len() as u32;
        assert!(children.iter().all(|&c| c < next), "children come first");
        self.push(bounds, children, false)
    }

    fn push(&mut self, bounds: Aabb, items: &[u32], leaf: bool) -> u32 {
        let index = self.nodes.len() as u32;
        self.nodes.push(ViewNode {
            bounds,
            first: self.items.len() as u32,
            count: items.len() as u32,
            leaf,
        });
        self.items.extend_from_slice(items);
        index
    }

    /// Number of nodes (leaves included).
    #[must_use]
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True when the view has no node.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The root: the last node added.
    fn root(&self) -> Option<usize> {
        self.nodes.len().checked_sub(1)
    }

    fn items_of(&self, n: &ViewNode) -> &[u32] {
        &self.items[n.first as usize..(n.first + n.count) as usize]
    }

    /// The node's own cost: `C_t` for an interior node, `C_i` times its primitives for a
    /// leaf.
    fn node_cost(n: &ViewNode, c: CostConstants) -> f64 {
        if n.leaf {
            c.intersection * f64::from(n.count)
        } else {
            c.traversal
        }
    }

    /// The SAH cost with constants `c` (see the module's documentation): every node's own
    /// cost weighted by its box's surface area over the root's. 0 when the view is empty
    /// or the root's box has no (or an infinite) area.
    #[must_use]
    pub fn sah_cost(&self, c: CostConstants) -> f64 {
        let Some(root) = self.root() else {
            return 0.0;
        };
        let root_area = f64::from(self.nodes[root].bounds.surface_area());
        if root_area <= 0.0 || !root_area.is_finite() {
            return 0.0;
        }
        let sum: f64 = self
            .nodes
            .iter()
            .map(|n| Self::node_cost(n, c) * f64::from(n.bounds.surface_area()))
            .sum();
        sum / root_area
    }

    /// Nodes in depth-first order from the root, each with its depth (root 1) and the
    /// position one past its subtree's last node in that order.
    fn depth_first(&self) -> Vec<(u32, u32, u32)> {
        let Some(root) = self.root() else {
            return Vec::new();
        };
        // (node, depth) in pre-order; subtree ends filled in afterwards from the depths.
        let mut order: Vec<(u32, u32, u32)> = Vec::with_capacity(self.nodes.len());
        let mut stack = vec![(root as u32, 1u32)];
        while let Some((n, d)) = stack.pop() {
            order.push((n, d, 0));
            let node = &self.nodes[n as usize];
            if !node.leaf {
                for &child in self.items_of(node).iter().rev() {
                    stack.push((child, d + 1));
                }
            }
        }
        // A subtree ends at the next position whose depth is not deeper.
        let mut open: Vec<usize> = Vec::new();
        for i in 0..order.len() {
            while let Some(&top) = open.last() {
                if order[top].1 >= order[i].1 {
                    order[top].2 = i as u32;
                    open.pop();
                } else {
                    break;
                }
            }
            open.push(i);
        }
        let end = order.len() as u32;
        for i in open {
            order[i].2 = end;
        }
        order
    }

    /// Checks that every bounded primitive of `geometry` is in exactly one leaf, that leaves
    /// hold only bounded primitives inside their box, and that every node is reached once
    /// from the root.
    ///
    /// # Errors
    /// A description of the first violation.
    pub fn check_leaves(&self, geometry: &Geometry) -> Result<(), String> {
        let order = self.depth_first();
        if order.len() != self.nodes.len() {
            return Err(format!(
                "{} of {} nodes reached from the root",
                order.len(),
                self.nodes.len()
            ));
        }
        let mut seen = vec![0u32; geometry.len()];
        for &(n, _, _) in &order {
            let node = &self.nodes[n as usize];
            if !node.leaf {
                continue;
            }
            for &id in self.items_of(node) {
                let b = geometry
                    .shapes()
                    .get(id as usize)
                    .and_then(Shape::bounds)
                    .ok_or_else(|| format!("leaf {n} holds unbounded or unknown primitive {id}"))?;
                if !node.bounds.contains(&b) {
                    return Err(format!("leaf {n} does not contain primitive {id}"));
                }
                seen[id as usize] += 1;
            }
        }
        for &id in geometry.bounded() {
            if seen[id as usize] != 1 {
                return Err(format!("primitive {id} is in {} leaves", seen[id as usize]));
            }
        }
        Ok(())
    }

    /// The EPO with constants `c`, estimated from `samples` points drawn uniformly by area on
    /// the surfaces of `geometry`'s bounded primitives whose area is known (triangles and
    /// spheres: [`Shape::area`], [`Shape::uniform_point`]; the others are left out and
    /// counted in [`Epo::excluded_primitives`]), seeded by `seed` with the counter-based
    /// hash of [`crate::sampling`]: the same figure on every run and thread count.
    ///
    /// For each point on primitive `q`, every node whose box contains the point (boundaries
    /// included) and whose subtree does not hold `q` adds its own cost; a primitive held by
    /// several leaves is held by every subtree that holds one of them.
    #[must_use]
    pub fn epo(&self, geometry: &Geometry, c: CostConstants, samples: u32, seed: u32) -> Epo {
        let mut epo = Epo::default();
        // The sampled primitives and their areas' running sums.
        let mut sampled: Vec<u32> = Vec::new();
        let mut cdf: Vec<f64> = Vec::new();
        let mut total = 0.0f64;
        for &id in geometry.bounded() {
            let Some(area) = geometry.shape(id).area() else {
                epo.excluded_primitives += 1;
                continue;
            };
            if area > 0.0 && area.is_finite() {
                total += area;
                sampled.push(id);
                cdf.push(total);
            }
        }
        let Some(root) = self.root() else {
            return epo;
        };
        if sampled.is_empty() || samples == 0 {
            return epo;
        }
        // Depth-first intervals: a subtree holds q when one of q's leaves lies in it.
        let order = self.depth_first();
        let mut position = vec![0u32; self.nodes.len()];
        let mut end = vec![0u32; self.nodes.len()];
        for (i, &(n, _, e)) in order.iter().enumerate() {
            position[n as usize] = i as u32;
            end[n as usize] = e;
        }
        // The leaf positions of every primitive, sorted (compressed rows by primitive id).
        let mut offsets = vec![0u32; geometry.len() + 1];
        for &(n, _, _) in &order {
            let node = &self.nodes[n as usize];
            if node.leaf {
                for &id in self.items_of(node) {
                    if let Some(o) = offsets.get_mut(id as usize + 1) {
                        *o += 1;
                    }
                }
            }
        }
        for i in 1..offsets.len() {
            offsets[i] += offsets[i - 1];
        }
        let mut fill = offsets.clone();
        let mut leaf_at = vec![0u32; offsets[geometry.len()] as usize];
        for (i, &(n, _, _)) in order.iter().enumerate() {
            let node = &self.nodes[n as usize];
            if node.leaf {
                for &id in self.items_of(node) {
                    if let Some(f) = fill.get_mut(id as usize) {
                        leaf_at[*f as usize] = i as u32;
                        *f += 1;
                    }
                }
            }
        }

        let (mut sum, mut sum_sq) = (0.0f64, 0.0f64);
        let mut stack: Vec<u32> = Vec::new();
        for i in 0..samples {
            let [a, b, _] = pcg3d([i, seed, 0x4550_4f31]);
            let [u, v, _] = pcg3d([i, seed, 0x4550_4f32]);
            // 53 random bits pick the primitive by area.
            let pick = ((u64::from(a) << 21) | u64::from(b >> 11)) as f64
                * (1.0 / 9_007_199_254_740_992.0);
            let k = cdf
                .partition_point(|&s| s <= pick * total)
                .min(sampled.len() - 1);
            let q = sampled[k];
            // Every sampled kind has an area, hence points.
            let Some(p) = geometry
                .shape(q)
                .uniform_point(to_unit_f32(u), to_unit_f32(v))
            else {
                continue;
            };
            let leaves = &leaf_at[offsets[q as usize] as usize..offsets[q as usize + 1] as usize];
            let mut cost = 0.0f64;
            stack.clear();
            stack.push(root as u32);
            while let Some(n) = stack.pop() {
                let node = &self.nodes[n as usize];
                let bb = node.bounds;
                if !(p.cmpge(bb.min).all() && p.cmple(bb.max).all()) {
                    continue;
                }
                let (lo, hi) = (position[n as usize], end[n as usize]);
                let holds = leaves.iter().any(|&l| l >= lo && l < hi);
                if !holds {
                    cost += Self::node_cost(node, c);
                }
                if !node.leaf {
                    stack.extend_from_slice(self.items_of(node));
                }
            }
            sum += cost;
            sum_sq += cost * cost;
        }
        let n = f64::from(samples);
        epo.samples = samples;
        epo.mean = sum / n;
        epo.std_error = if samples > 1 {
            ((sum_sq - sum * sum / n).max(0.0) / (n - 1.0) / n).sqrt()
        } else {
            0.0
        };
        epo
    }

    /// The leaves whose box the segment of `ray` (`t_min` to `t_max`) enters: every exact
    /// closest-hit traversal opens at least these when `t_max` is the ray's closest hit, since
    /// a box entered before the hit may hold a closer one until its primitives are tested.
    #[must_use]
    pub fn leaves_entered(&self, ray: &Ray) -> u32 {
        let Some(root) = self.root() else {
            return 0;
        };
        let mut count = 0;
        let mut stack = vec![root as u32];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            if node.bounds.intersect(ray, ray.t_max).is_none() {
                continue;
            }
            if node.leaf {
                count += 1;
            } else {
                stack.extend_from_slice(self.items_of(node));
            }
        }
        count
    }

    /// [`TreeView::leaves_entered`] over `rays`: mean, standard deviation and maximum;
    /// `None` without rays.
    #[must_use]
    pub fn leaf_counts(&self, rays: &[Ray]) -> Option<LeafCounts> {
        if rays.is_empty() {
            return None;
        }
        let counts: Vec<u32> = rays.iter().map(|r| self.leaves_entered(r)).collect();
        let n = counts.len() as f64;
        let mean = counts.iter().map(|&c| f64::from(c)).sum::<f64>() / n;
        let var = counts
            .iter()
            .map(|&c| (f64::from(c) - mean).powi(2))
            .sum::<f64>()
            / n;
        Some(LeafCounts {
            rays: counts.len() as u64,
            mean,
            std_dev: var.sqrt(),
            max: counts.iter().copied().max().unwrap_or(0),
        })
    }

    /// Every figure of [`TreeQuality`], for a structure of `memory_bytes` bytes built over
    /// `geometry`.
    #[must_use]
    pub fn quality(
        &self,
        geometry: &Geometry,
        params: &QualityParams,
        memory_bytes: usize,
    ) -> TreeQuality {
        let mut q = TreeQuality {
            costs: params.costs,
            sah: self.sah_cost(params.costs),
            epo: self.epo(geometry, params.costs, params.epo_samples, params.seed),
            interior_nodes: 0,
            leaves: 0,
            leaf_sizes: SizeHistogram::default(),
            max_depth: 0,
            mean_leaf_depth: 0.0,
            references: 0,
            bytes_per_primitive: per_primitive(memory_bytes, geometry.bounded().len() as u64),
            leaf_counts: self.leaf_counts(&params.rays),
        };
        let mut depth_sum = 0u64;
        for (n, depth, _) in self.depth_first() {
            let node = &self.nodes[n as usize];
            q.max_depth = q.max_depth.max(depth);
            if node.leaf {
                q.leaves += 1;
                q.references += u64::from(node.count);
                q.leaf_sizes.add(u64::from(node.count));
                depth_sum += u64::from(depth);
            } else {
                q.interior_nodes += 1;
            }
        }
        q.mean_leaf_depth = ratio(depth_sum, q.leaves);
        q
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn tri(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Shape {
        Shape::Triangle(crate::Triangle::new(a.into(), b.into(), c.into()))
    }

    fn bounds(g: &Geometry, ids: &[u32]) -> Aabb {
        ids.iter()
            .filter_map(|&i| g.shape(i).bounds())
            .fold(Aabb::EMPTY, Aabb::union)
    }

    /// Two unit right triangles in the plane z = 0, at x in [0, 1] and [3, 4].
    fn two_apart() -> Geometry {
        Geometry::new(vec![
            tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            tri([3.0, 0.0, 0.0], [4.0, 0.0, 0.0], [3.0, 1.0, 0.0]),
        ])
    }

    fn binary(g: &Geometry, left: &[u32], right: &[u32]) -> TreeView {
        let mut t = TreeView::new();
        let l = t.leaf(bounds(g, left), left);
        let r = t.leaf(bounds(g, right), right);
        let all: Vec<u32> = left.iter().chain(right).copied().collect();
        t.interior(bounds(g, &all), &[l, r]);
        t
    }

    #[test]
    fn leaves_entered_stop_at_the_segment_end() {
        let g = two_apart();
        let t = binary(&g, &[0], &[1]);
        // Along x at y = z = 0.25... in the plane z = 0: both leaves' (flat) boxes lie on the
        // ray's line; a ray through z = 0 enters them.
        let along = |t_max: f32| {
            let mut r = Ray::new(Vec3::new(-1.0, 0.25, 0.0), Vec3::X);
            r.t_max = t_max;
            r
        };
        assert_eq!(t.leaves_entered(&along(f32::INFINITY)), 2);
        // Ending at x = 2 (t = 3): only the first leaf's box is entered.
        assert_eq!(t.leaves_entered(&along(3.0)), 1);
        // Ending before x = 0: none.
        assert_eq!(t.leaves_entered(&along(0.5)), 0);
        let c = t
            .leaf_counts(&[along(f32::INFINITY), along(3.0), along(0.5)])
            .unwrap();
        assert_eq!((c.rays, c.max), (3, 2));
        assert!((c.mean - 1.0).abs() < 1e-12);
        // Counts 2, 1, 0 around 1: variance 2/3.
        assert!((c.std_dev - (2.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert_eq!(t.leaf_counts(&[]), None);
        assert_eq!(TreeView::new().leaves_entered(&along(1.0)), 0);
    }

    #[test]
    fn sah_of_two_disjoint_leaves() {
        let g = two_apart();
        let t = binary(&g, &[0], &[1]);
        t.check_leaves(&g).unwrap();
        // Boxes 1 x 1 x 0 (area 2) in a root 4 x 1 x 0 (area 8): 1 + 2 * 2 / 8.
        assert_eq!(t.sah_cost(CostConstants::UNIT), 1.5);
        let c = CostConstants {
            traversal: 2.0,
            intersection: 3.0,
        };
        assert_eq!(t.sah_cost(c), 2.0 + 3.0 * 4.0 / 8.0);
        // A lone leaf of both: C_i * 2.
        let mut one = TreeView::new();
        one.leaf(bounds(&g, &[0, 1]), &[0, 1]);
        assert_eq!(one.sah_cost(CostConstants::UNIT), 2.0);
        assert_eq!(TreeView::new().sah_cost(CostConstants::UNIT), 0.0);
    }

    #[test]
    fn epo_of_disjoint_leaves_is_zero() {
        let g = two_apart();
        let e = binary(&g, &[0], &[1]).epo(&g, CostConstants::UNIT, 1000, 7);
        assert_eq!(e.mean, 0.0);
        assert_eq!(e.std_error, 0.0);
        assert_eq!(e.samples, 1000);
        assert_eq!(e.excluded_primitives, 0);
    }

    #[test]
    fn epo_of_nested_boxes_is_known() {
        // A big triangle whose leaf box holds a small one. Every point of the small
        // triangle (area 1/2) lies in the big one's leaf box: cost C_i * 1. The big
        // triangle (0,0),(4,0),(0,4) (area 8) covers the small one's box [0, 1]^2 whole
        // (x + y <= 2 there): those points (area 1) pay the small leaf, C_i * 1.
        // EPO = (1/2 * 1 + 1 * 1) / (8 + 1/2).
        let g = Geometry::new(vec![
            tri([0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [0.0, 4.0, 0.0]),
            tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ]);
        let t = binary(&g, &[0], &[1]);
        let e = t.epo(&g, CostConstants::UNIT, 200_000, 3);
        let expected = 1.5 / 8.5;
        assert!(
            (e.mean - expected).abs() < 4.0 * e.std_error,
            "{} +- {} vs {expected}",
            e.mean,
            e.std_error
        );
        assert!(e.std_error > 0.0 && e.std_error < 0.002, "{}", e.std_error);
        // Deterministic, and the seed matters.
        assert_eq!(e, t.epo(&g, CostConstants::UNIT, 200_000, 3));
        assert_ne!(e.mean, t.epo(&g, CostConstants::UNIT, 200_000, 4).mean);
        // C_i scales it.
        let c = CostConstants {
            traversal: 1.0,
            intersection: 2.0,
        };
        assert!((t.epo(&g, c, 200_000, 3).mean - 2.0 * e.mean).abs() < 1e-12);
    }

    #[test]
    fn epo_counts_interior_nodes_with_traversal_cost() {
        // Two subtrees with overlapping boxes: the first over triangles 0 and 1 (x in
        // [0, 2]), the second over 2 and 3 (x in [1, 3]), all in z = 0 and y in [0, 1].
        // Points of 2 in x < 2 lie in the first subtree's box (C_t) and maybe its leaves.
        let g = Geometry::new(vec![
            tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            tri([1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.0, 1.0, 0.0]),
            tri([1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 1.0, 0.0]),
            tri([2.0, 0.0, 0.0], [3.0, 0.0, 0.0], [3.0, 1.0, 0.0]),
        ]);
        let mut t = TreeView::new();
        let l: Vec<u32> = (0..4).map(|i| t.leaf(bounds(&g, &[i]), &[i])).collect();
        let a = t.interior(bounds(&g, &[0, 1]), &[l[0], l[1]]);
        let b = t.interior(bounds(&g, &[2, 3]), &[l[2], l[3]]);
        t.interior(bounds(&g, &[0, 1, 2, 3]), &[a, b]);
        t.check_leaves(&g).unwrap();
        // Exactly: each triangle has area 1/2, total 2. Triangle 1 (x in [1,2]) lies in
        // b's box [1,3] (C_t = 1) and in leaf 2's box [1,2]x[0,1] (1): cost 2 everywhere.
        // Triangle 2 likewise in a's box [0,2] and leaf 1's box [1,2]x[0,1]: cost 2.
        // Triangle 0 (x in [0,1]) touches b's box and leaf 2's only on the line x = 1
        // (area 0); triangle 3 touches a and leaf 1 on x = 2 only. EPO = (2 * 1/2 + 2 *
        // 1/2) / 2 = 1.
        let e = t.epo(&g, CostConstants::UNIT, DEFAULT_EPO_SAMPLES, 0);
        assert!((e.mean - 1.0).abs() < 4.0 * e.std_error.max(1e-3), "{e:?}");
        let q = t.quality(&g, &QualityParams::default(), 4 * 32);
        assert_eq!((q.leaves, q.interior_nodes, q.references), (4, 3, 4));
        assert_eq!(q.max_depth, 3);
        assert_eq!(q.mean_leaf_depth, 3.0);
        assert_eq!(q.leaf_sizes.0, [4, 0, 0, 0, 0, 0, 0]);
        assert_eq!(q.bytes_per_primitive, 32.0);
        assert_eq!(q.epo, e);
    }

    #[test]
    fn excluded_kinds_are_counted_and_spheres_sampled() {
        let g = Geometry::new(vec![
            Shape::Sphere(crate::Sphere::new(Vec3::ZERO, 1.0)),
            Shape::Sphere(crate::Sphere::new(Vec3::new(5.0, 0.0, 0.0), 1.0)),
            Shape::Plane(crate::Plane::new(Vec3::ZERO, Vec3::Y)),
        ]);
        let t = binary(&g, &[0], &[1]);
        t.check_leaves(&g).unwrap();
        let e = t.epo(&g, CostConstants::UNIT, 500, 0);
        assert_eq!((e.mean, e.excluded_primitives), (0.0, 0));
        // One leaf holding both spheres: no overlap by definition.
        let mut one = TreeView::new();
        one.leaf(bounds(&g, &[0, 1]), &[0, 1]);
        assert_eq!(one.epo(&g, CostConstants::UNIT, 100, 0).mean, 0.0);
    }

    #[test]
    fn check_leaves_finds_lost_and_doubled_primitives() {
        let g = two_apart();
        let mut lost = TreeView::new();
        lost.leaf(bounds(&g, &[0]), &[0]);
        assert!(lost.check_leaves(&g).is_err());
        let doubled = binary(&g, &[0, 1], &[1]);
        assert!(doubled.check_leaves(&g).is_err());
        let mut small = TreeView::new();
        small.leaf(bounds(&g, &[0]), &[0, 1]);
        assert!(small.check_leaves(&g).is_err());
    }

    #[test]
    fn histograms_and_grids() {
        let mut h = SizeHistogram::default();
        for n in [0, 1, 2, 3, 4, 5, 8, 9, 16, 17, 1000] {
            h.add(n);
        }
        assert_eq!(h.0, [1, 1, 1, 1, 2, 2, 2]);
        assert_eq!(h.describe(), "1:1 2:1 3:1 4:1 5-8:2 9-16:2 >16:2");
        assert_eq!(SizeHistogram::default().describe(), "-");
        let q = GridQuality::from_lists([0, 3, 0, 1, 20], 8, 64);
        assert_eq!((q.cells, q.non_empty_cells, q.references), (5, 3, 24));
        assert_eq!((q.max_list, q.fill()), (20, 0.6));
        assert_eq!(q.references_per_primitive(), 3.0);
        assert_eq!(q.mean_list(), 8.0);
        assert_eq!(q.bytes_per_primitive, 8.0);
        assert_eq!(q.list_lengths.0, [1, 0, 1, 0, 0, 0, 1]);
        let empty = GridQuality::from_lists([], 0, 0);
        assert_eq!((empty.fill(), empty.mean_list()), (0.0, 0.0));
    }
}
