//! The data the kernels read: triangles as structure of arrays, the BVH2's per-node
//! traversal order for packets, and the BVH8 collapsed from the BVH2.

use raybench_bvh::{Bvh, Node};
use raybench_core::{Aabb, Geometry, Shape};

/// Children per wide node.
pub(crate) const WIDE: usize = 8;

/// Marks a wide child (and a stack entry) as a leaf: the low bits index [`Layout::leaves`].
pub(crate) const LEAF_BIT: u32 = 1 << 31;

/// An unused child slot (its box is empty, so no ray enters it).
pub(crate) const EMPTY_CHILD: u32 = u32::MAX;

/// Padding after the last triangle so that a leaf's `W`-lane loads never leave the arrays.
const PAD: usize = 16;

/// A BVH8 node: the eight children's boxes in structure-of-arrays form, so that one SIMD
/// slab test checks all of them against one ray (Embree's and tinybvh's layout).
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug)]
pub(crate) struct WideNode {
    /// `min[axis][child]`.
    pub min: [[f32; WIDE]; 3],
    /// `max[axis][child]`.
    pub max: [[f32; WIDE]; 3],
    /// A wide node index, `LEAF_BIT | leaf index`, or [`EMPTY_CHILD`].
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

/// A leaf: a range of the leaf-ordered primitive arrays.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Leaf {
    /// First position in [`Layout::ids`] and the triangle arrays.
    pub first: u32,
    /// Number of primitives (at least 1).
    pub count: u32,
    /// Whether every primitive of the leaf is a triangle (else the leaf is tested with the
    /// core's scalar routine, primitive by primitive).
    pub all_triangles: bool,
}

/// Everything the packet backend traverses.
#[derive(Debug)]
pub(crate) struct Layout {
    /// The BVH2 the packets walk (and the BVH8 was collapsed from).
    pub bvh: Bvh,
    /// Per BVH2 interior node: the split axis (bits 0-1), and bit 2 set when the second
    /// child lies before the first along it (so the far-to-near order flips).
    pub order: Vec<u8>,
    /// Per BVH2 node: whether its primitives are all triangles (leaves only).
    pub node_all_triangles: Vec<bool>,
    /// The BVH8; node 0 is the root. Empty when there are no bounded primitives.
    pub wide: Vec<WideNode>,
    /// The BVH8's leaves (the BVH2's leaves).
    pub leaves: Vec<Leaf>,
    /// Primitive ids in leaf order (the BVH2's), padded.
    pub ids: Vec<u32>,
    /// Triangle vertex coordinates in leaf order: `tri[3 * vertex + axis][position]`; NaN
    /// for primitives that are not triangles (a NaN triangle is never hit) and for the
    /// padding.
    pub tri: [Vec<f32>; 9],
    /// Whether the primitive at each leaf position is a triangle.
    pub is_triangle: Vec<bool>,
}

impl Layout {
    /// Lays out `bvh` (built over `geometry`).
    pub fn new(bvh: Bvh, geometry: &Geometry) -> Self {
        let ids = bvh.prim_ids().to_vec();
        let n = ids.len();
        let mut tri: [Vec<f32>; 9] = std::array::from_fn(|_| vec![f32::NAN; n + PAD]);
        let mut is_triangle = vec![false; n];
        for (pos, &id) in ids.iter().enumerate() {
            if let Shape::Triangle(t) = geometry.shape(id) {
                is_triangle[pos] = true;
                for (k, v) in t.v.iter().enumerate() {
                    tri[3 * k][pos] = v.x;
                    tri[3 * k + 1][pos] = v.y;
                    tri[3 * k + 2][pos] = v.z;
                }
            }
        }
        let nodes = bvh.nodes();
        let all_tris = |first: u32, count: u32| {
            is_triangle[first as usize..(first + count) as usize]
                .iter()
                .all(|&t| t)
        };
        let node_all_triangles = nodes
            .iter()
            .map(|n| n.is_leaf() && all_tris(n.first_or_right, n.count))
            .collect();
        let order = (0..nodes.len())
            .map(|i| {
                let n = &nodes[i];
                if n.is_leaf() {
                    return 0;
                }
                let (l, r) = (nodes[i + 1].aabb(), nodes[n.first_or_right as usize].aabb());
                let d = r.center() - l.center();
                let axis = d.abs().max_position();
                axis as u8 | if d[axis] < 0.0 { 4 } else { 0 }
            })
            .collect();

        let mut layout = Self {
            bvh,
            order,
            node_all_triangles,
            wide: Vec::new(),
            leaves: Vec::new(),
            ids,
            tri,
            is_triangle,
        };
        layout.ids.resize(n + PAD, u32::MAX);
        if !layout.bvh.nodes().is_empty() {
            layout.collapse(0);
        }
        layout
    }

    /// Appends the wide node standing for BVH2 node `root` and its subtree; returns its
    /// index. Children are gathered by opening the interior child with the largest surface
    /// area until there are eight (the usual greedy collapse, Embree's BVH8 builder).
    fn collapse(&mut self, root: usize) -> u32 {
        let nodes = self.bvh.nodes();
        let mut kids: Vec<usize> = if nodes[root].is_leaf() {
            vec![root]
        } else {
            vec![root + 1, nodes[root].first_or_right as usize]
        };
        while kids.len() < WIDE {
            let widest = kids
                .iter()
                .enumerate()
                .filter(|&(_, &k)| !nodes[k].is_leaf())
                .max_by(|a, b| {
                    let area = |k: usize| nodes[k].aabb().surface_area();
                    area(*a.1).total_cmp(&area(*b.1))
                });
            let Some((slot, &k)) = widest else { break };
            kids[slot] = k + 1;
            kids.push(nodes[k].first_or_right as usize);
        }
        let index = self.wide.len();
        self.wide.push(WideNode::EMPTY);
        let mut node = WideNode::EMPTY;
        for (slot, &k) in kids.iter().enumerate() {
            let n: Node = self.bvh.nodes()[k];
            let b: Aabb = n.aabb();
            for axis in 0..3 {
                node.min[axis][slot] = b.min[axis];
                node.max[axis][slot] = b.max[axis];
            }
            node.child[slot] = if n.is_leaf() {
                let leaf = self.leaves.len() as u32;
                self.leaves.push(Leaf {
                    first: n.first_or_right,
                    count: n.count,
                    all_triangles: self.node_all_triangles[k],
                });
                LEAF_BIT | leaf
            } else {
                self.collapse(k)
            };
        }
        self.wide[index] = node;
        index as u32
    }

    /// Bytes held (not counting the shared geometry).
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        self.bvh.nodes().len() * (size_of::<Node>() + 2)
            + self.wide.len() * size_of::<WideNode>()
            + self.leaves.len() * size_of::<Leaf>()
            + self.ids.len() * size_of::<u32>()
            + self.tri.iter().map(Vec::len).sum::<usize>() * size_of::<f32>()
            + self.is_triangle.len()
    }
}
