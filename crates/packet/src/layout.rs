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
//! subtree in parallel; the wide nodes and blocks are then written depth first, the slots of
//! a wide node over many primitives each into a layout of its own in parallel, appended in
//! slot order with their indices moved up. Both give the serial result bit for bit, on any
//! number of threads.
//!
//! **A leaf** is one or more [`TriBlock`]s: four triangles' nine coordinates each as four
//! lanes, then their primitive ids (160 bytes, Embree's `Triangle4` idea), so a leaf is one
//! run of cache lines and the ids needed to report a hit come with it. Lanes beyond the
//! leaf's primitives and lanes holding primitives that are not triangles have NaN
//! coordinates (never hit by the SIMD test); leaves with such primitives carry
//! [`MIXED_BIT`] and test them with the core's scalar routine.

use raybench_bvh::{Bvh, Node};
use raybench_geometry::{Aabb, Geometry, Shape, TreeView};
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
    /// [`EMPTY_CHILD`]. Occupied slots come first.
    pub child: [u32; WIDE],
}

const _: () = assert!(std::mem::size_of::<WideNode>() == 224);

impl WideNode {
    const EMPTY: Self = Self {
        min: [[f32::INFINITY; WIDE]; 3],
        max: [[f32::NEG_INFINITY; WIDE]; 3],
        child: [EMPTY_CHILD; WIDE],
    };
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

/// Per BVH2 node, what the dynamic program knows.
#[derive(Clone, Copy)]
struct Plan {
    /// `cost[i - 1]`: the cheapest cost with at most `i` slots.
    cost: [f32; WIDE],
    /// `choice[0]`: 1 when one slot holds a wide node, 0 when a leaf. `choice[i - 1]` for
    /// `i >= 2`: 0 when `i - 1` slots do as well, else the slots given to the first child.
    choice: [u8; WIDE],
    /// Slots given to the first child when the node becomes a wide node (eight in all).
    expand: u8,
    /// First leaf-order position and number of primitives below.
    first: u32,
    count: u32,
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
        let builder = Builder {
            nodes,
            plans: &plans,
            ids: bvh.prim_ids(),
            geometry,
        };
        layout.reserve(plans[0].count as usize);
        builder.wide_node(0, &mut layout);
        layout.wide.shrink_to_fit();
        layout.blocks.shrink_to_fit();
        layout
    }

    /// Reserves room for the layout of a subtree over `prims` primitives: at most one block
    /// and one wide node per primitive (each block holds one or more, and each wide node
    /// stands for a distinct interior node of the BVH2, or a leaf of more than eight blocks).
    /// Growing the arrays instead copied them and faulted their pages in twice: a fifth of
    /// a large mesh's collapse. What is reserved and never written is never touched, and
    /// [`Layout::new`] gives it back.
    fn reserve(&mut self, prims: usize) {
        self.wide.reserve(prims);
        self.blocks.reserve(prims);
    }

    /// Appends `part`, a layout of its own whose child reference `child` (a wide node, or a
    /// leaf) roots it, and returns that reference as it reads here: `part`'s wide node
    /// indices and block indices move up by what this layout holds.
    fn append(&mut self, part: Self, child: u32) -> u32 {
        let wide = self.wide.len() as u32;
        let blocks = self.blocks.len() as u32;
        assert!(
            self.blocks.len() + part.blocks.len() <= FIRST_MASK as usize + 1,
            "more than 2^27 leaf blocks"
        );
        let relocate = |c: u32| {
            if c == EMPTY_CHILD {
                c
            } else if c & LEAF_BIT != 0 {
                let mut leaf = LeafRef::decode(c);
                leaf.first += blocks as usize;
                leaf.encode()
            } else {
                c + wide
            }
        };
        self.wide.extend(part.wide.iter().map(|node| WideNode {
            child: node.child.map(relocate),
            ..*node
        }));
        self.blocks.extend_from_slice(&part.blocks);
        self.leaves += part.leaves;
        self.slots += part.slots;
        self.leaf_prims += part.leaf_prims;
        relocate(child)
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

impl Plan {
    const EMPTY: Self = Self {
        cost: [0.0; WIDE],
        choice: [0; WIDE],
        expand: 0,
        first: 0,
        count: 0,
    };
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
    let mut plans = vec![Plan::EMPTY; nodes.len()];
    plan_subtree(nodes, 0, &mut plans);
    plans
}

/// Plans the subtree of BVH2 node `root`, whose nodes are `root..root + plans.len()`.
fn plan_subtree(nodes: &[Node], root: usize, plans: &mut [Plan]) {
    let node = &nodes[root];
    if plans.len() < PARALLEL_NODES || node.is_leaf() {
        for i in (0..plans.len()).rev() {
            let node = &nodes[root + i];
            plans[i] = if node.is_leaf() {
                plan_node(node, &Plan::EMPTY, &Plan::EMPTY)
            } else {
                let right = node.first_or_right as usize - root;
                plan_node(node, &plans[i + 1], &plans[right])
            };
        }
        return;
    }
    let right = node.first_or_right as usize - root;
    let (head, rest) = plans.split_at_mut(1);
    let (l, r) = rest.split_at_mut(right - 1);
    rayon::join(
        || plan_subtree(nodes, root + 1, l),
        || plan_subtree(nodes, root + right, r),
    );
    head[0] = plan_node(node, &l[0], &r[0]);
}

/// The plan of `node` from its children's (`l` and `r`, unused for a leaf).
fn plan_node(node: &Node, l: &Plan, r: &Plan) -> Plan {
    let area = node.aabb().surface_area();
    if node.is_leaf() {
        let cost = area * C_BLOCK * node.count.div_ceil(BLOCK as u32) as f32;
        return Plan {
            cost: [cost; WIDE],
            choice: [0; WIDE],
            expand: 0,
            first: node.first_or_right,
            count: node.count,
        };
    }
    let count = l.count + r.count;
    // dist[i]: the best split of `i` slots between the children.
    let mut dist = [(f32::INFINITY, 0u8); WIDE + 1];
    for (i, d) in dist.iter_mut().enumerate().skip(2) {
        for k in 1..i {
            let c = l.cost[k - 1] + r.cost[i - k - 1];
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
        cost: [0.0; WIDE],
        choice: [0; WIDE],
        expand: dist[WIDE].1,
        first: l.first,
        count,
    };
    // `<=`: between equal costs, the leaf (fewer nodes to visit).
    if as_leaf <= as_node {
        p.cost[0] = as_leaf;
    } else {
        p.cost[0] = as_node;
        p.choice[0] = 1;
    }
    for (i, &(cost, k)) in dist.iter().enumerate().skip(2) {
        if cost < p.cost[i - 2] {
            p.cost[i - 1] = cost;
            p.choice[i - 1] = k;
        } else {
            p.cost[i - 1] = p.cost[i - 2];
        }
    }
    p
}

/// Writes the wide nodes and blocks the plan describes.
struct Builder<'a> {
    nodes: &'a [Node],
    plans: &'a [Plan],
    ids: &'a [u32],
    geometry: &'a Geometry,
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

impl Builder<'_> {
    /// The BVH2 nodes that fill at most `slots` slots for node `n`'s subtree.
    fn gather(&self, n: usize, slots: usize, out: &mut Slots) {
        let node = &self.nodes[n];
        if node.is_leaf() || slots == 1 {
            out.push(n);
            return;
        }
        match self.plans[n].choice[slots - 1] {
            0 => self.gather(n, slots - 1, out),
            k => {
                let k = usize::from(k);
                self.gather(n + 1, k, out);
                self.gather(node.first_or_right as usize, slots - k, out);
            }
        }
    }

    /// Appends to `out` the wide node standing for BVH2 node `n` and its subtree, depth
    /// first (the node, then each slot's subtree or leaf blocks in slot order); returns its
    /// index. A node over at least [`PARALLEL_PRIMS`] primitives lays out its slots in
    /// parallel, each into a layout of its own, and appends them in slot order: the same
    /// arrays as one pass would write.
    fn wide_node(&self, n: usize, out: &mut Layout) -> u32 {
        let node = self.nodes[n];
        let mut slots = Slots::default();
        if node.is_leaf() {
            slots.push(n);
        } else {
            let k = usize::from(self.plans[n].expand);
            self.gather(n + 1, k, &mut slots);
            self.gather(node.first_or_right as usize, WIDE - k, &mut slots);
        }
        let slots = slots.as_slice();
        let index = out.wide.len();
        out.wide.push(WideNode::EMPTY);
        out.slots += slots.len();
        let mut wide = WideNode::EMPTY;
        for (slot, &s) in slots.iter().enumerate() {
            let b = self.nodes[s].aabb();
            for axis in 0..3 {
                wide.min[axis][slot] = b.min[axis];
                wide.max[axis][slot] = b.max[axis];
            }
        }
        if self.plans[n].count >= PARALLEL_PRIMS {
            let parts: Vec<(Layout, u32)> = slots
                .par_iter()
                .map(|&s| {
                    let mut part = Layout::default();
                    part.reserve(self.plans[s].count as usize);
                    let child = self.child(s, &mut part);
                    (part, child)
                })
                .collect();
            for (slot, (part, child)) in parts.into_iter().enumerate() {
                wide.child[slot] = out.append(part, child);
            }
        } else {
            for (slot, &s) in slots.iter().enumerate() {
                wide.child[slot] = self.child(s, out);
            }
        }
        out.wide[index] = wide;
        index as u32
    }

    /// Appends to `out` what the slot holding BVH2 node `s` refers to (a leaf or a wide
    /// node); returns the reference.
    fn child(&self, s: usize, out: &mut Layout) -> u32 {
        let child = &self.nodes[s];
        let plan = &self.plans[s];
        if child.is_leaf() || plan.choice[0] == 0 {
            self.leaf(plan.first as usize, plan.count as usize, child.aabb(), out)
        } else {
            self.wide_node(s, out)
        }
    }

    /// A reference to a leaf of the primitives at leaf-order positions `first..first +
    /// count`, all inside `bounds`, appended to `out`; more than eight blocks' worth become
    /// a wide node of leaves with the same box.
    fn leaf(&self, first: usize, count: usize, bounds: Aabb, out: &mut Layout) -> u32 {
        if count > MAX_REF_BLOCKS * BLOCK {
            let index = out.wide.len();
            out.wide.push(WideNode::EMPTY);
            let per = count.div_ceil(WIDE);
            let mut wide = WideNode::EMPTY;
            let mut slot = 0;
            let mut start = first;
            while start < first + count {
                let n = per.min(first + count - start);
                for axis in 0..3 {
                    wide.min[axis][slot] = bounds.min[axis];
                    wide.max[axis][slot] = bounds.max[axis];
                }
                wide.child[slot] = self.leaf(start, n, bounds, out);
                slot += 1;
                start += n;
            }
            out.slots += slot;
            out.wide[index] = wide;
            return index as u32;
        }
        let first_block = out.blocks.len();
        let mut mixed = false;
        for chunk in self.ids[first..first + count].chunks(BLOCK) {
            let mut block = TriBlock::EMPTY;
            for (lane, &id) in chunk.iter().enumerate() {
                block.id[lane] = id;
                match self.geometry.shape(id) {
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
            out.blocks.push(block);
        }
        assert!(
            out.blocks.len() <= FIRST_MASK as usize + 1,
            "more than 2^27 leaf blocks"
        );
        out.leaves += 1;
        out.leaf_prims += count;
        LeafRef {
            first: first_block,
            blocks: count.div_ceil(BLOCK),
            mixed,
        }
        .encode()
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
