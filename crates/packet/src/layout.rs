//! The data the kernels read: a BVH8 collapsed from the `raybench-bvh` BVH2 by an SAH-optimal
//! dynamic program, its children's boxes as structure of arrays, and leaves stored as
//! contiguous blocks of four triangles.
//!
//! **The collapse** (the dynamic program of Ylitie, Karras and Laine, "Efficient Incoherent
//! Ray Traversal on GPUs Through Compressed Wide BVHs", HPG 2017, with a CPU cost model):
//! for every BVH2 node `n` and every `i` in `1..=8`, `cost[n][i]` is the cheapest SAH cost of
//! representing `n`'s subtree by at most `i` children of a wide node. One child is either a
//! leaf of all the subtree's primitives (`A(n) C_block ceil(P(n) / 4)`, allowed up to
//! [`MAX_LEAF_PRIMS`]) or a wide node (`A(n) C_node` plus the best distribution of its two
//! BVH2 children over eight slots); `i` children are the best split of the slots between the
//! two BVH2 children, or fewer. A greedy collapse (open the widest child until there are
//! eight) filled 43-47% of the slots on the PEERS.md meshes with leaves of one or two
//! triangles; this one decides leaves and node widths by cost.
//! The program runs bottom up over the BVH2's depth-first array, the two children of a large
//! subtree in parallel, and also counts the wide nodes and blocks each subtree will take. The
//! arrays are then allocated at their final size and written depth first; the slots of a
//! wide node over many primitives are written in parallel, each into the range its counts
//! mark out, so that every element is written in place once (copying parts into their
//! parents instead wrote a large mesh's layout three or four times). Both give the serial
//! result bit for bit, on any number of threads.
//!
//! **Slot order.** A wide node's occupied slots come first, ordered for any-hit queries,
//! which visit them from the highest slot down: by the probability that a ray entering the
//! child's box is blocked inside it, per unit of the child's expected cost in the
//! collapse's cost model (the shadow-ray traversal order of Ize and Hansen, "RTSAH
//! Traversal Order for Occlusion Rays", EG 2011). A primitive blocks a random line through
//! a box with the probability of its surface area over the box's (twice its area for a
//! triangle, seen from both sides), and the children of a node are taken as independent.
//! Closest-hit traversals sort the children by distance and need no order; the subtrees
//! are still written in the BVH2's depth-first order, so the memory layout does not depend
//! on it.
//!
//! **A leaf** is one or more [`TriBlock`]s: four triangles' nine coordinates each as four
//! lanes, then their primitive ids (160 bytes, Embree's `Triangle4` idea), so a leaf is one
//! run of cache lines and the ids needed to report a hit come with it. Lanes beyond the
//! leaf's primitives and lanes holding primitives that are not triangles have NaN
//! coordinates (never hit by the SIMD test); leaves with such primitives carry
//! [`MIXED_BIT`] and test them with the core's scalar routine.

use raybench_bvh::{Bvh, Node};
use raybench_geometry::{Aabb, Geometry, Shape, TreeView, Triangle, Vec3};
use rayon::prelude::*;

/// Children per wide node.
pub(crate) const WIDE: usize = 8;

/// Triangles per leaf block.
pub(crate) const BLOCK: usize = 4;

/// Marks a child reference as a leaf.
pub(crate) const LEAF_BIT: u32 = 1 << 31;

/// In a leaf reference: some primitive of the leaf is not a triangle.
pub(crate) const MIXED_BIT: u32 = 1 << 30;

/// In a leaf reference: the number of blocks minus one sits at this bit (three bits).
const BLOCKS_SHIFT: u32 = 27;

/// Largest number of blocks a leaf reference can name.
const MAX_REF_BLOCKS: usize = 8;

/// In a leaf reference: the mask of the first block's index.
const FIRST_MASK: u32 = (1 << BLOCKS_SHIFT) - 1;

/// An unused child slot (its box is empty, so no ray enters it).
pub(crate) const EMPTY_CHILD: u32 = u32::MAX;

/// Largest leaf the collapse makes by choice (two blocks). A BVH2 leaf with more primitives
/// (only the depth limit makes one) becomes a leaf as it is, or a small tree of leaves.
pub(crate) const MAX_LEAF_PRIMS: u32 = 8;

/// The collapse's cost of visiting a wide node (one SIMD test of eight boxes and the sort
/// of the children hit), relative to [`C_BLOCK`].
const C_NODE: f32 = 1.0;

/// The collapse's cost of testing one block of four triangles.
const C_BLOCK: f32 = 1.0;

/// A BVH8 node: the eight children's boxes in structure-of-arrays form, so that one SIMD
/// slab test checks all of them against one ray (Embree's and tinybvh's layout).
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug)]
pub(crate) struct WideNode {
    /// `min[axis][child]`.
    pub min: [[f32; WIDE]; 3],
    /// `max[axis][child]`.
    pub max: [[f32; WIDE]; 3],
    /// A wide node index, a leaf reference (`LEAF_BIT`, see [`LeafRef`]), or
    /// [`EMPTY_CHILD`]. Occupied slots come first, in ascending any-hit order (the module's
    /// "slot order").
    pub child: [u32; WIDE],
}

const _: () = assert!(std::mem::size_of::<WideNode>() == 224);

impl WideNode {
    const EMPTY: Self = Self {
        min: [[f32::INFINITY; WIDE]; 3],
        max: [[f32::NEG_INFINITY; WIDE]; 3],
        child: [EMPTY_CHILD; WIDE],
    };

    /// The node with slot `order[k]` moved to slot `k` (the slots past `order` empty).
    fn permuted(&self, order: &[usize]) -> Self {
        let mut node = Self::EMPTY;
        for (slot, &i) in order.iter().enumerate() {
            for axis in 0..3 {
                node.min[axis][slot] = self.min[axis][i];
                node.max[axis][slot] = self.max[axis][i];
            }
            node.child[slot] = self.child[i];
        }
        node
    }
}

/// Four triangles: `v[3 * vertex + axis][lane]`, then the primitive id of each lane
/// (`u32::MAX` for an unused lane).
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug)]
pub(crate) struct TriBlock {
    /// Vertex coordinates by vertex and axis, one lane per triangle; NaN in unused lanes and
    /// in lanes whose primitive is not a triangle.
    pub v: [[f32; BLOCK]; 9],
    /// Primitive ids; `u32::MAX` in unused lanes.
    pub id: [u32; BLOCK],
}

const _: () = assert!(std::mem::size_of::<TriBlock>() == 160);

impl TriBlock {
    const EMPTY: Self = Self {
        v: [[f32::NAN; BLOCK]; 9],
        id: [u32::MAX; BLOCK],
    };

    /// The mask of lanes holding a primitive.
    #[inline(always)]
    pub fn occupied(&self) -> u32 {
        let mut m = 0;
        for (lane, &id) in self.id.iter().enumerate() {
            m |= u32::from(id != u32::MAX) << lane;
        }
        m
    }

    /// The nine coordinates of lane `lane`'s triangle.
    #[inline(always)]
    pub fn triangle(&self, lane: usize) -> [f32; 9] {
        std::array::from_fn(|c| self.v[c][lane])
    }
}

/// The core's triangle of nine coordinates ([`TriBlock::triangle`]): the geometry's own
/// vertices, bit for bit.
#[inline(always)]
pub(crate) fn core_triangle(c: &[f32; 9]) -> Triangle {
    Triangle::new(
        Vec3::new(c[0], c[1], c[2]),
        Vec3::new(c[3], c[4], c[5]),
        Vec3::new(c[6], c[7], c[8]),
    )
}

/// A decoded leaf reference.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LeafRef {
    /// First block in [`Layout::blocks`].
    pub first: usize,
    /// Number of blocks (at least 1).
    pub blocks: usize,
    /// Whether some primitive of the leaf is not a triangle.
    pub mixed: bool,
}

impl LeafRef {
    /// Decodes a child reference with `LEAF_BIT` set.
    #[inline(always)]
    pub fn decode(child: u32) -> Self {
        Self {
            first: (child & FIRST_MASK) as usize,
            blocks: ((child >> BLOCKS_SHIFT) & 7) as usize + 1,
            mixed: child & MIXED_BIT != 0,
        }
    }

    fn encode(self) -> u32 {
        debug_assert!(self.blocks >= 1 && self.blocks <= MAX_REF_BLOCKS);
        LEAF_BIT
            | if self.mixed { MIXED_BIT } else { 0 }
            | ((self.blocks as u32 - 1) << BLOCKS_SHIFT)
            | self.first as u32
    }
}

/// Everything the kernels traverse.
#[derive(Debug, Default)]
pub(crate) struct Layout {
    /// The BVH8; node 0 is the root. Empty when there are no bounded primitives.
    pub wide: Vec<WideNode>,
    /// The leaves' triangle blocks.
    pub blocks: Vec<TriBlock>,
    /// Number of leaves.
    pub leaves: usize,
    /// Nodes of the BVH2 the tree was collapsed from.
    pub bvh2_nodes: usize,
    /// Occupied child slots over all wide nodes.
    pub slots: usize,
    /// Primitives over all leaves.
    pub leaf_prims: usize,
}

/// Per BVH2 node, what the dynamic program decided (16 bytes: one is kept for every node of
/// the BVH2, and on a 12.6M-triangle mesh that is 13.5 million of them).
#[derive(Clone, Copy)]
struct Plan {
    /// `choice[0]`: 1 when one slot holds a wide node, 0 when a leaf. `choice[i - 1]` for
    /// `i >= 2`: 0 when `i - 1` slots do as well, else the slots given to the first child.
    choice: [u8; WIDE],
    /// Slots given to the first child when the node becomes a wide node (eight in all).
    expand: u8,
    /// Number of primitives below.
    count: u32,
}

const _: () = assert!(std::mem::size_of::<Plan>() == 16);

/// `cost[i - 1]`: the cheapest SAH cost of a subtree with at most `i` slots. Only needed
/// until the parent is planned, so it is not kept in the [`Plan`].
type Cost = [f32; WIDE];

/// The wide nodes and blocks a part of the layout takes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Size {
    wide: u32,
    blocks: u32,
}

impl Size {
    fn add(self, other: Self) -> Self {
        Self {
            wide: self.wide + other.wide,
            blocks: self.blocks + other.blocks,
        }
    }
}

/// What the any-hit slot order knows of a written subtree: the probability that a random
/// line through its box is blocked inside it, and the expected cost of an any-hit query of
/// a line that enters the box, in the collapse's cost model ([`C_NODE`] per wide node,
/// [`C_BLOCK`] per block; Ize and Hansen's RTSAH): a child is visited when the line enters
/// its box (its share of the box's surface area) and no child visited before blocked it.
#[derive(Clone, Copy, Debug, Default)]
struct Occlusion {
    blocked: f32,
    cost: f32,
}

impl Occlusion {
    /// Of a node with box `bounds` whose slots have boxes `boxes` and occlusions `slots`,
    /// visited in the order `order` lists them backwards (see [`any_hit_order`]).
    fn of_node(bounds: Aabb, boxes: &[Aabb], slots: &[Occlusion], order: &[usize]) -> Self {
        let area = bounds.surface_area();
        let mut open = 1.0;
        let mut cost = C_NODE;
        for &i in order.iter().rev() {
            let share = line_share(boxes[i].surface_area(), area);
            cost += open * share * slots[i].cost;
            open *= 1.0 - slots[i].blocked * share;
        }
        Self {
            blocked: 1.0 - open,
            cost,
        }
    }

    /// The any-hit order key: blocked per unit of cost (0 where that is not a number).
    fn priority(&self) -> f32 {
        let p = self.blocked / self.cost;
        if p.is_finite() { p } else { 0.0 }
    }
}

/// The share of the lines through a box of surface area `outer` that also pass through a
/// convex body of surface area `inner` inside it (Cauchy-Crofton), at most 1; 1 for a box
/// without area.
fn line_share(inner: f32, outer: f32) -> f32 {
    if outer > 0.0 {
        (inner / outer).min(1.0)
    } else {
        1.0
    }
}

/// The any-hit order of slots with occlusions `slots`: `order[k]` is the slot to move to
/// slot `k`, in ascending priority (equal priorities keep their order), so that traversals
/// that visit the highest slot first visit the highest priority first.
fn any_hit_order(slots: &[Occlusion]) -> [usize; WIDE] {
    let mut order: [usize; WIDE] = std::array::from_fn(|i| i);
    order[..slots.len()].sort_by(|&a, &b| slots[a].priority().total_cmp(&slots[b].priority()));
    order
}

/// The surface of `shape` that blocks lines: a triangle's area twice (both sides), a
/// sphere's area, half the box's for the kinds whose area is not known.
fn blocking_surface(shape: &Shape) -> f32 {
    match (shape, shape.area()) {
        (Shape::Triangle(_), Some(a)) => 2.0 * a as f32,
        (_, Some(a)) => a as f32,
        (_, None) => 0.5 * shape.bounds().map_or(0.0, |b| b.surface_area()),
    }
}

impl Layout {
    /// Collapses `bvh` (built over `geometry`) into the BVH8 and lays out its leaves.
    pub fn new(bvh: &Bvh, geometry: &Geometry) -> Self {
        let nodes = bvh.nodes();
        let mut layout = Self {
            bvh2_nodes: nodes.len(),
            ..Self::default()
        };
        if nodes.is_empty() {
            return layout;
        }
        let plans = plan(nodes);
        let size = wide_size(nodes, &plans, 0);
        assert!(size.blocks <= FIRST_MASK + 1, "more than 2^27 leaf blocks");
        // Every element is written once more below; filling them here, in parallel, faults
        // the pages in on every thread.
        layout
            .wide
            .par_extend(rayon::iter::repeat_n(WideNode::EMPTY, size.wide as usize));
        layout
            .blocks
            .par_extend(rayon::iter::repeat_n(TriBlock::EMPTY, size.blocks as usize));
        let builder = Builder {
            nodes,
            plans: &plans,
            ids: bvh.prim_ids(),
            geometry,
        };
        let mut out = Out::new(&mut layout.wide, 0, &mut layout.blocks, 0);
        builder.wide_node(0, &mut out);
        out.assert_full();
        let counts = out.counts;
        layout.leaves = counts.leaves;
        layout.slots = counts.slots;
        layout.leaf_prims = counts.leaf_prims;
        layout
    }

    /// Percentage of the wide nodes' child slots that are occupied.
    pub fn fill_percent(&self) -> u64 {
        (100 * self.slots)
            .checked_div(WIDE * self.wide.len())
            .unwrap_or(0) as u64
    }

    /// Mean primitives per leaf, times 100.
    pub fn leaf_prims_x100(&self) -> u64 {
        (100 * self.leaf_prims)
            .checked_div(self.leaves)
            .unwrap_or(0) as u64
    }

    /// The BVH8 as the quality metrics see it: wide nodes as interior nodes, each occupied
    /// slot's box as its child's box, leaves with the primitive ids of their blocks. The
    /// root's box is the union of its children's.
    pub fn tree_view(&self) -> TreeView {
        let mut view = TreeView::new();
        if !self.wide.is_empty() {
            self.view_node(0, None, &mut view);
        }
        view
    }

    /// Adds wide node `index` (with box `bounds`, or its children's union) to `view`.
    fn view_node(&self, index: usize, bounds: Option<Aabb>, view: &mut TreeView) -> u32 {
        let node = &self.wide[index];
        let mut children = Vec::with_capacity(WIDE);
        let mut union = Aabb::EMPTY;
        for slot in 0..WIDE {
            let child = node.child[slot];
            if child == EMPTY_CHILD {
                continue;
            }
            let b = Aabb::new(
                std::array::from_fn::<f32, 3, _>(|axis| node.min[axis][slot]).into(),
                std::array::from_fn::<f32, 3, _>(|axis| node.max[axis][slot]).into(),
            );
            union = union.union(b);
            children.push(if child & LEAF_BIT != 0 {
                let leaf = LeafRef::decode(child);
                let ids: Vec<u32> = self.blocks[leaf.first..leaf.first + leaf.blocks]
                    .iter()
                    .flat_map(|block| block.id)
                    .filter(|&id| id != u32::MAX)
                    .collect();
                view.leaf(b, &ids)
            } else {
                self.view_node(child as usize, Some(b), view)
            });
        }
        view.interior(bounds.unwrap_or(union), &children)
    }

    /// Bytes held (not counting the shared geometry).
    pub fn memory_bytes(&self) -> usize {
        self.wide.len() * std::mem::size_of::<WideNode>()
            + self.blocks.len() * std::mem::size_of::<TriBlock>()
    }
}

/// Subtrees of at least this many BVH2 nodes are planned in parallel with their sibling, and
/// wide nodes over at least [`PARALLEL_PRIMS`] primitives lay out their children in
/// parallel. Neither depends on the thread count, and both give the serial result.
const PARALLEL_NODES: usize = 1 << 13;

/// See [`PARALLEL_NODES`].
const PARALLEL_PRIMS: u32 = 1 << 15;

/// The dynamic program, bottom up (a depth-first layout puts children after parents; the
/// two children's subtrees are independent and go in parallel while large).
fn plan(nodes: &[Node]) -> Vec<Plan> {
    let empty = Plan {
        choice: [0; WIDE],
        expand: 0,
        count: 0,
    };
    let mut plans = vec![empty; nodes.len()];
    plan_subtree(nodes, 0, &mut plans);
    plans
}

/// Plans the subtree of BVH2 node `root`, whose nodes are `root..root + plans.len()`;
/// returns its cost.
fn plan_subtree(nodes: &[Node], root: usize, plans: &mut [Plan]) -> Cost {
    let node = &nodes[root];
    if plans.len() < PARALLEL_NODES || node.is_leaf() {
        // Backwards over a depth-first array, every subtree is done before its parent, the
        // second child's before the first's: the children's costs are the top two of a stack.
        let mut costs: Vec<Cost> = Vec::with_capacity(64);
        for i in (0..plans.len()).rev() {
            let node = &nodes[root + i];
            let (plan, cost) = if node.is_leaf() {
                plan_leaf(node)
            } else {
                let right = node.first_or_right as usize - root;
                let count = plans[i + 1].count + plans[right].count;
                let (l, r) = (costs.pop(), costs.pop());
                plan_node(node, count, &l.expect("planned"), &r.expect("planned"))
            };
            plans[i] = plan;
            costs.push(cost);
        }
        debug_assert_eq!(costs.len(), 1);
        return costs[0];
    }
    let right = node.first_or_right as usize - root;
    let (head, rest) = plans.split_at_mut(1);
    let (l, r) = rest.split_at_mut(right - 1);
    let (lc, rc) = rayon::join(
        || plan_subtree(nodes, root + 1, l),
        || plan_subtree(nodes, root + right, r),
    );
    let (plan, cost) = plan_node(node, l[0].count + r[0].count, &lc, &rc);
    head[0] = plan;
    cost
}

/// The plan and cost of leaf `node`.
fn plan_leaf(node: &Node) -> (Plan, Cost) {
    let cost = node.aabb().surface_area() * C_BLOCK * node.count.div_ceil(BLOCK as u32) as f32;
    let plan = Plan {
        choice: [0; WIDE],
        expand: 0,
        count: node.count,
    };
    (plan, [cost; WIDE])
}

/// The plan and cost of interior `node` over `count` primitives from its children's costs
/// (`l` and `r`).
fn plan_node(node: &Node, count: u32, l: &Cost, r: &Cost) -> (Plan, Cost) {
    let area = node.aabb().surface_area();
    // dist[i]: the best split of `i` slots between the children.
    let mut dist = [(f32::INFINITY, 0u8); WIDE + 1];
    for (i, d) in dist.iter_mut().enumerate().skip(2) {
        for k in 1..i {
            let c = l[k - 1] + r[i - k - 1];
            if c < d.0 {
                *d = (c, k as u8);
            }
        }
    }
    let as_node = area * C_NODE + dist[WIDE].0;
    let as_leaf = if count <= MAX_LEAF_PRIMS {
        area * C_BLOCK * count.div_ceil(BLOCK as u32) as f32
    } else {
        f32::INFINITY
    };
    let mut p = Plan {
        choice: [0; WIDE],
        expand: dist[WIDE].1,
        count,
    };
    let mut cost = [0.0; WIDE];
    // `<=`: between equal costs, the leaf (fewer nodes to visit).
    if as_leaf <= as_node {
        cost[0] = as_leaf;
    } else {
        cost[0] = as_node;
        p.choice[0] = 1;
    }
    for (i, &(c, k)) in dist.iter().enumerate().skip(2) {
        if c < cost[i - 2] {
            cost[i - 1] = c;
            p.choice[i - 1] = k;
        } else {
            cost[i - 1] = cost[i - 2];
        }
    }
    (p, cost)
}

/// The BVH2 nodes filling a wide node's slots.
#[derive(Default)]
struct Slots {
    node: [usize; WIDE],
    len: usize,
}

impl Slots {
    fn push(&mut self, n: usize) {
        self.node[self.len] = n;
        self.len += 1;
    }

    fn as_slice(&self) -> &[usize] {
        &self.node[..self.len]
    }
}

/// Adds to `out` the BVH2 nodes that fill at most `slots` slots for node `n`'s subtree.
fn gather(nodes: &[Node], plans: &[Plan], n: usize, slots: usize, out: &mut Slots) {
    let node = &nodes[n];
    if node.is_leaf() || slots == 1 {
        out.push(n);
        return;
    }
    match plans[n].choice[slots - 1] {
        0 => gather(nodes, plans, n, slots - 1, out),
        k => {
            let k = usize::from(k);
            gather(nodes, plans, n + 1, k, out);
            gather(nodes, plans, node.first_or_right as usize, slots - k, out);
        }
    }
}

/// The BVH2 nodes filling the slots of the wide node standing for node `n` (`n` itself
/// when it is a leaf, which only the root of a tree of one leaf is).
fn wide_slots(nodes: &[Node], plans: &[Plan], n: usize) -> Slots {
    let node = &nodes[n];
    let mut slots = Slots::default();
    if node.is_leaf() {
        slots.push(n);
    } else {
        let k = usize::from(plans[n].expand);
        gather(nodes, plans, n + 1, k, &mut slots);
        gather(
            nodes,
            plans,
            node.first_or_right as usize,
            WIDE - k,
            &mut slots,
        );
    }
    slots
}

/// Whether a slot holding BVH2 node `node` (planned as `plan`) refers to a leaf rather than
/// to a wide node.
fn is_leaf_slot(node: &Node, plan: &Plan) -> bool {
    node.is_leaf() || plan.choice[0] == 0
}

/// What [`Builder::wide_node`] writes for node `n`: the node and its slots' targets. Only
/// the wide nodes below `n` are walked, not every BVH2 node, the slots of those over at
/// least [`PARALLEL_PRIMS`] primitives in parallel. Nothing is kept: the layout's total
/// walks the whole wide tree once, and each wide node that writes its slots in parallel
/// walks its subtree again for their parts (a few walks of the wide nodes in all, fewer
/// node visits than planning a size for every BVH2 node).
fn wide_size(nodes: &[Node], plans: &[Plan], n: usize) -> Size {
    let slots = wide_slots(nodes, plans, n);
    let slots = slots.as_slice();
    let one = Size { wide: 1, blocks: 0 };
    if plans[n].count >= PARALLEL_PRIMS {
        slots
            .par_iter()
            .map(|&s| child_size(nodes, plans, s))
            .reduce(Size::default, Size::add)
            .add(one)
    } else {
        slots
            .iter()
            .fold(one, |size, &s| size.add(child_size(nodes, plans, s)))
    }
}

/// What [`Builder::child`] writes for node `n`.
fn child_size(nodes: &[Node], plans: &[Plan], n: usize) -> Size {
    let plan = &plans[n];
    if is_leaf_slot(&nodes[n], plan) {
        leaf_size(plan.count as usize)
    } else {
        wide_size(nodes, plans, n)
    }
}

/// What [`Builder::leaf`] writes for a leaf of `count` primitives.
fn leaf_size(count: usize) -> Size {
    if count <= MAX_REF_BLOCKS * BLOCK {
        return Size {
            wide: 0,
            blocks: count.div_ceil(BLOCK) as u32,
        };
    }
    let per = count.div_ceil(WIDE);
    let mut size = Size { wide: 1, blocks: 0 };
    let mut left = count;
    while left > 0 {
        let n = per.min(left);
        size = size.add(leaf_size(n));
        left -= n;
    }
    size
}

/// The counts a part of the layout adds to the statistics.
#[derive(Clone, Copy, Default)]
struct Counts {
    leaves: usize,
    slots: usize,
    leaf_prims: usize,
}

impl Counts {
    fn add(self, other: Self) -> Self {
        Self {
            leaves: self.leaves + other.leaves,
            slots: self.slots + other.slots,
            leaf_prims: self.leaf_prims + other.leaf_prims,
        }
    }
}

/// A part of the layout's arrays, written front to back: `wide` is the whole's wide nodes
/// from `wide_base` on, `blocks` its blocks from `block_base` on, each exactly as long as
/// the part's [`Size`].
struct Out<'a> {
    wide: &'a mut [WideNode],
    wide_base: usize,
    wide_len: usize,
    blocks: &'a mut [TriBlock],
    block_base: usize,
    blocks_len: usize,
    counts: Counts,
}

impl<'a> Out<'a> {
    fn new(
        wide: &'a mut [WideNode],
        wide_base: usize,
        blocks: &'a mut [TriBlock],
        block_base: usize,
    ) -> Self {
        Self {
            wide,
            wide_base,
            wide_len: 0,
            blocks,
            block_base,
            blocks_len: 0,
            counts: Counts::default(),
        }
    }

    /// Writes the next wide node; returns its index in the whole.
    fn push_wide(&mut self, node: WideNode) -> usize {
        self.wide[self.wide_len] = node;
        self.wide_len += 1;
        self.wide_base + self.wide_len - 1
    }

    /// Overwrites wide node `index` (an index in the whole, written by this part).
    fn set_wide(&mut self, index: usize, node: WideNode) {
        self.wide[index - self.wide_base] = node;
    }

    /// Writes the next block.
    fn push_block(&mut self, block: TriBlock) {
        self.blocks[self.blocks_len] = block;
        self.blocks_len += 1;
    }

    /// What is left, cut into consecutive parts of `sizes`.
    fn split(&mut self, sizes: &[Size]) -> Vec<Out<'_>> {
        let mut wide = &mut self.wide[self.wide_len..];
        let mut blocks = &mut self.blocks[self.blocks_len..];
        let mut wide_base = self.wide_base + self.wide_len;
        let mut block_base = self.block_base + self.blocks_len;
        let mut parts = Vec::with_capacity(sizes.len());
        for size in sizes {
            let (w, rest) = std::mem::take(&mut wide).split_at_mut(size.wide as usize);
            wide = rest;
            let (b, rest) = std::mem::take(&mut blocks).split_at_mut(size.blocks as usize);
            blocks = rest;
            parts.push(Out::new(w, wide_base, b, block_base));
            wide_base += size.wide as usize;
            block_base += size.blocks as usize;
        }
        parts
    }

    /// Moves past `size` written by parts of [`Out::split`] that counted `counts`.
    fn skip(&mut self, size: Size, counts: Counts) {
        self.wide_len += size.wide as usize;
        self.blocks_len += size.blocks as usize;
        self.counts = self.counts.add(counts);
    }

    /// Checks that the part was written to its end: the plan's sizes and the writing agree.
    fn assert_full(&self) {
        assert_eq!(
            (self.wide_len, self.blocks_len),
            (self.wide.len(), self.blocks.len()),
            "the layout's planned sizes disagree with what was written"
        );
    }
}

/// How many primitives ahead (in leaf order) [`Builder::leaf`] prefetches the primitive
/// it will copy: leaves are written in leaf order, and the primitives of a mesh's leaf
/// order are scattered through the geometry.
const PREFETCH_AHEAD: usize = 8;

/// Writes the wide nodes and blocks the plan describes.
struct Builder<'a> {
    nodes: &'a [Node],
    plans: &'a [Plan],
    ids: &'a [u32],
    geometry: &'a Geometry,
}

impl Builder<'_> {
    /// Writes to `out` the wide node standing for BVH2 node `n` and its subtree, depth
    /// first (the node, then each slot's subtree or leaf blocks in the BVH2's depth-first
    /// order); returns its index and occlusion. Its slots are then put in any-hit order
    /// (the module's "slot order"). A node over at least [`PARALLEL_PRIMS`] primitives
    /// writes its slots' targets in parallel, each into the part of the arrays its size
    /// ([`child_size`]) marks out: the same arrays as one pass would write.
    fn wide_node(&self, n: usize, out: &mut Out) -> (u32, Occlusion) {
        let slots = wide_slots(self.nodes, self.plans, n);
        let slots = slots.as_slice();
        let index = out.push_wide(WideNode::EMPTY);
        out.counts.slots += slots.len();
        let mut wide = WideNode::EMPTY;
        let mut boxes = [Aabb::EMPTY; WIDE];
        for (slot, &s) in slots.iter().enumerate() {
            let b = self.nodes[s].aabb();
            boxes[slot] = b;
            for axis in 0..3 {
                wide.min[axis][slot] = b.min[axis];
                wide.max[axis][slot] = b.max[axis];
            }
        }
        let mut occlusion = [Occlusion::default(); WIDE];
        if self.plans[n].count >= PARALLEL_PRIMS {
            let sizes: Vec<Size> = slots
                .par_iter()
                .map(|&s| child_size(self.nodes, self.plans, s))
                .collect();
            let mut parts = out.split(&sizes);
            let children: Vec<(u32, Occlusion)> = parts
                .par_iter_mut()
                .zip(slots)
                .map(|(part, &s)| {
                    let child = self.child(s, part);
                    part.assert_full();
                    child
                })
                .collect();
            let counts = parts.iter().fold(Counts::default(), |c, p| c.add(p.counts));
            let size = sizes.iter().fold(Size::default(), |a, &b| a.add(b));
            out.skip(size, counts);
            for (slot, &(child, o)) in children.iter().enumerate() {
                (wide.child[slot], occlusion[slot]) = (child, o);
            }
        } else {
            for (slot, &s) in slots.iter().enumerate() {
                (wide.child[slot], occlusion[slot]) = self.child(s, out);
            }
        }
        let occlusion = &occlusion[..slots.len()];
        let order = &any_hit_order(occlusion)[..slots.len()];
        out.set_wide(index, wide.permuted(order));
        let bounds = self.nodes[n].aabb();
        let node = Occlusion::of_node(bounds, &boxes[..slots.len()], occlusion, order);
        (index as u32, node)
    }

    /// Writes to `out` what the slot holding BVH2 node `s` refers to (a leaf or a wide
    /// node); returns the reference and its occlusion.
    fn child(&self, s: usize, out: &mut Out) -> (u32, Occlusion) {
        let child = &self.nodes[s];
        let plan = &self.plans[s];
        if is_leaf_slot(child, plan) {
            let mut first = s;
            while !self.nodes[first].is_leaf() {
                first += 1;
            }
            let first = self.nodes[first].first_or_right as usize;
            self.leaf(first, plan.count as usize, child.aabb(), out)
        } else {
            self.wide_node(s, out)
        }
    }

    /// A reference to a leaf of the primitives at leaf-order positions `first..first +
    /// count`, all inside `bounds`, written to `out`, and its occlusion; more than eight
    /// blocks' worth become a wide node of leaves with the same box.
    fn leaf(&self, first: usize, count: usize, bounds: Aabb, out: &mut Out) -> (u32, Occlusion) {
        if count > MAX_REF_BLOCKS * BLOCK {
            let index = out.push_wide(WideNode::EMPTY);
            let per = count.div_ceil(WIDE);
            let mut wide = WideNode::EMPTY;
            let mut occlusion = [Occlusion::default(); WIDE];
            let mut slot = 0;
            let mut start = first;
            while start < first + count {
                let n = per.min(first + count - start);
                for axis in 0..3 {
                    wide.min[axis][slot] = bounds.min[axis];
                    wide.max[axis][slot] = bounds.max[axis];
                }
                (wide.child[slot], occlusion[slot]) = self.leaf(start, n, bounds, out);
                slot += 1;
                start += n;
            }
            out.counts.slots += slot;
            let occlusion = &occlusion[..slot];
            let order = &any_hit_order(occlusion)[..slot];
            out.set_wide(index, wide.permuted(order));
            let node = Occlusion::of_node(bounds, &[bounds; WIDE][..slot], occlusion, order);
            return (index as u32, node);
        }
        let first_block = out.block_base + out.blocks_len;
        let mut mixed = false;
        // The primitives block a line through the box independently.
        let area = bounds.surface_area();
        let mut open = 1.0;
        for (c, chunk) in self.ids[first..first + count].chunks(BLOCK).enumerate() {
            let mut block = TriBlock::EMPTY;
            for (lane, &id) in chunk.iter().enumerate() {
                if let Some(&ahead) = self.ids.get(first + c * BLOCK + lane + PREFETCH_AHEAD) {
                    crate::simd::prefetch(self.geometry.shape(ahead));
                }
                block.id[lane] = id;
                let shape = self.geometry.shape(id);
                open *= 1.0 - line_share(blocking_surface(shape), area);
                match shape {
                    Shape::Triangle(t) => {
                        for (k, v) in t.v.iter().enumerate() {
                            block.v[3 * k][lane] = v.x;
                            block.v[3 * k + 1][lane] = v.y;
                            block.v[3 * k + 2][lane] = v.z;
                        }
                    }
                    _ => mixed = true,
                }
            }
            out.push_block(block);
        }
        out.counts.leaves += 1;
        out.counts.leaf_prims += count;
        let blocks = count.div_ceil(BLOCK);
        let leaf = LeafRef {
            first: first_block,
            blocks,
            mixed,
        };
        let occlusion = Occlusion {
            blocked: 1.0 - open,
            cost: C_BLOCK * blocks as f32,
        };
        (leaf.encode(), occlusion)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_bvh::BvhParams;
    use raybench_geometry::{Sphere, Vec3};
    use raybench_scene::generators;
    use std::sync::Arc;

    #[test]
    fn tree_view_holds_every_primitive_once() {
        let soup = Geometry::new(
            generators::soup(3000, 5)
                .triangles()
                .map(Shape::Triangle)
                .collect(),
        );
        // Triangles and spheres mixed, and 100 coincident triangles (one leaf of many).
        let mut mixed: Vec<Shape> = generators::icosphere(2)
            .triangles()
            .map(Shape::Triangle)
            .collect();
        mixed.extend((0..50).map(|i| Shape::Sphere(Sphere::new(Vec3::splat(i as f32), 0.5))));
        let point = raybench_geometry::Triangle::new(Vec3::ONE, Vec3::ONE, Vec3::ONE);
        mixed.extend(std::iter::repeat_n(Shape::Triangle(point), 100));
        for g in [soup, Geometry::new(mixed), Geometry::default()] {
            let g = Arc::new(g);
            let bvh = Bvh::build_with(Arc::clone(&g), BvhParams::default());
            let layout = Layout::new(&bvh, &g);
            let view = layout.tree_view();
            view.check_leaves(&g).unwrap();
            assert_eq!(view.is_empty(), g.is_empty());
            if !g.is_empty() {
                let q = view.quality(&g, &Default::default(), layout.memory_bytes());
                assert!(q.sah.is_finite() && q.sah > 0.0, "{q:?}");
                assert!(q.epo.mean.is_finite() && q.epo.mean > 0.0, "{q:?}");
                assert_eq!(q.leaves, layout.leaves as u64);
                // The wide tree is no deeper than the binary one it was collapsed from.
                assert!(q.max_depth as usize <= bvh.depth(), "{q:?}");
            }
        }
    }

    /// A wall and, in front of it, a cloud of small triangles whose boxes the ray passes
    /// through without touching a triangle: the wall, likeliest to block per unit of
    /// cost, takes the highest occupied slot of the root, so an any-hit ray through the
    /// cloud to the wall is blocked on its first leaf. In depth-first order (the wall on
    /// the low side of the split, so in slot 0) the ray would walk the cloud first.
    #[test]
    fn any_hit_order_puts_the_likeliest_blocker_first() {
        use raybench_geometry::{Accel, Ray, RayCounters, Triangle};
        let mut shapes = vec![Shape::Triangle(Triangle::new(
            Vec3::new(-10.0, -100.0, -100.0),
            Vec3::new(-10.0, 100.0, -100.0),
            Vec3::new(-10.0, 0.0, 100.0),
        ))];
        // Thin triangles at x in [-9, -1], each in a plane y + z = d, |d| in [0.05, 0.25]:
        // their boxes all hold the axis, the triangles never meet it.
        let mut seed = 7u32;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            f64::from(seed) as f32 / u32::MAX as f32
        };
        for i in 0..400 {
            let x = -9.0 + 8.0 * next();
            let d = if i % 2 == 0 { 1.0 } else { -1.0 } * (0.05 + 0.2 * next());
            shapes.push(Shape::Triangle(Triangle::new(
                Vec3::new(x, -0.5, d + 0.5),
                Vec3::new(x, 0.5, d - 0.5),
                Vec3::new(x + 0.05, 0.5, d - 0.5),
            )));
        }
        let g = Arc::new(Geometry::new(shapes));
        let accel = crate::PacketAccel::build(Arc::clone(&g));
        let ray = Ray::with_interval(Vec3::ZERO, -Vec3::X, 0.0, 20.0);
        let mut counters = RayCounters::default();
        assert!(accel.occluded(&ray, &mut counters));
        assert!(counters.node_visits <= 3, "{counters:?}");
        assert_eq!(counters.prim_tests, 1, "{counters:?}");

        let bvh = Bvh::build_with(Arc::clone(&g), BvhParams::default());
        let layout = Layout::new(&bvh, &g);
        let root = &layout.wide[0];
        let last = root.child.iter().rposition(|&c| c != EMPTY_CHILD).unwrap();
        assert!(
            root.min[0][last] == -10.0 && root.max[0][last] == -10.0,
            "{root:?}"
        );
    }

    #[test]
    fn layout_is_the_same_on_any_thread_count() {
        // Large enough for the parallel plan and the parallel layout of wide nodes.
        let g = Arc::new(Geometry::new(
            generators::soup(40_000, 9)
                .triangles()
                .map(Shape::Triangle)
                .collect(),
        ));
        let bvh = Bvh::build_with(Arc::clone(&g), BvhParams::default());
        let on = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| Layout::new(&bvh, &g))
        };
        let (one, four) = (on(1), on(4));
        one.tree_view().check_leaves(&g).unwrap();
        let bits = |l: &Layout| {
            let mut v: Vec<u32> = Vec::new();
            for n in &l.wide {
                v.extend(n.min.iter().chain(&n.max).flatten().map(|x| x.to_bits()));
                v.extend(n.child);
            }
            for b in &l.blocks {
                v.extend(b.v.iter().flatten().map(|x| x.to_bits()));
                v.extend(b.id);
            }
            v
        };
        assert_eq!(bits(&one), bits(&four));
        assert_eq!(
            (one.leaves, one.slots, one.leaf_prims),
            (four.leaves, four.slots, four.leaf_prims)
        );
    }
}
