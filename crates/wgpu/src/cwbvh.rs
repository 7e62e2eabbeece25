//! The compressed 8-wide BVH (CWBVH) of the `wgpu-cwbvh` kernels, after Ylitie, Karras and
//! Laine, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs" (HPG
//! 2017): 80-byte nodes whose eight child boxes are quantised to 8 bits per plane against
//! a per-node origin and per-axis power-of-two scales.
//!
//! The tree is raybench-bvh's own binned-SAH BVH2 (built with leaves of at most
//! [`LEAF_SIZE`] primitives), collapsed: a wide node takes the two children of a BVH2 node
//! and repeatedly opens the interior child of largest surface area until it has eight
//! children or only leaves (one build, many layouts, as tinybvh's `BVH8_CWBVH`).
//!
//! **Conservative quantisation.** A child's decoded plane is `p + q * 2^e`, computed in
//! `f32`. With `q < 256` and `2^e` a normal power of two the product is exact, so the sum is
//! rounded once whether or not a compiler fuses it: the CPU computes here exactly what the
//! GPU decodes. Each `q` is moved outward until the decoded box contains the child's box
//! (also when a GPU flushes denormal results to zero), so the kernel's slab test on the
//! decoded box (the BVH2 kernel's `box_entry`, conservative through `FAR_SCALE`) never
//! culls a box the exact one would enter: both kernels test the same candidate primitives
//! and find the same closest hits.

use raybench_bvh::{Bvh, BvhParams};
use raybench_core::{Aabb, Geometry, TreeView, Vec3};

/// Largest leaf of the BVH2 that is collapsed: a leaf child's primitive count takes three
/// bits of its metadata byte and its offset five, so that eight leaf children of up to three
/// primitives (24 in all) fit one node's primitive range, as in Ylitie et al.
pub const LEAF_SIZE: usize = 3;

/// Children per node.
pub const WIDTH: usize = 8;

/// The build parameters of the collapsed BVH2: raybench-bvh's default with leaves of up to
/// [`LEAF_SIZE`].
#[must_use]
pub fn bvh2_params() -> BvhParams {
    BvhParams {
        max_leaf_size: LEAF_SIZE,
        ..BvhParams::medium()
    }
}

/// 80-byte CWBVH node (Ylitie et al.'s layout), as 20 little-endian words:
///
/// - words 0-2: the origin `p` (`f32` bits); word 3: the three biased exponents (bytes 0-2,
///   `2^(e - 127)`) and the interior-child mask `imask` (byte 3, bit `s`: slot `s` holds an
///   interior node);
/// - word 4: index of the first interior child (interior children are stored together, in
///   slot order); word 5: index of the first primitive of the leaf children;
///   words 6-7: per slot a metadata byte: 0 for an empty or interior slot, else
///   `count << 5 | offset` (primitives `[prim_base + offset, + count)`);
/// - words 8-19: per slot the quantised planes, eight bytes each: `lo.x`, `lo.y`, `lo.z`,
///   `hi.x`, `hi.y`, `hi.z`.
///
/// Children sit in slots by the direction of their centre from the node's centre (slot `s`
/// holds the child farthest along `(-1)^s.bit0, (-1)^s.bit1, (-1)^s.bit2`), so that visiting
/// slot `j ^ o ^ 7` at step `j` for a ray of octant `o` is about near to far.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct WideNode {
    /// The words above.
    pub words: [u32; 20],
}

const _: () = assert!(std::mem::size_of::<WideNode>() == 80);

/// Word of the first quantised plane array (`lo.x`).
const PLANES: usize = 8;

impl WideNode {
    fn byte(&self, word: usize, slot: usize) -> u32 {
        (self.words[word + slot / 4] >> (8 * (slot % 4))) & 0xff
    }

    fn set_byte(&mut self, word: usize, slot: usize, value: u32) {
        self.words[word + slot / 4] |= (value & 0xff) << (8 * (slot % 4));
    }

    /// The interior-child mask.
    #[must_use]
    pub fn imask(&self) -> u32 {
        self.words[3] >> 24
    }

    /// Whether slot `slot` is empty.
    #[must_use]
    pub fn is_empty(&self, slot: usize) -> bool {
        (self.imask() >> slot) & 1 == 0 && self.byte(6, slot) == 0
    }

    /// The node index of interior slot `slot`.
    #[must_use]
    pub fn child(&self, slot: usize) -> u32 {
        self.words[4] + (self.imask() & ((1 << slot) - 1)).count_ones()
    }

    /// The primitive range `(first, count)` of leaf slot `slot`.
    #[must_use]
    pub fn prims(&self, slot: usize) -> (u32, u32) {
        let meta = self.byte(6, slot);
        (self.words[5] + (meta & 31), meta >> 5)
    }

    /// The box of slot `slot` as the kernel decodes it.
    #[must_use]
    pub fn child_box(&self, slot: usize) -> Aabb {
        let mut lo = [0.0f32; 3];
        let mut hi = [0.0f32; 3];
        for a in 0..3 {
            let p = f32::from_bits(self.words[a]);
            let s = scale((self.words[3] >> (8 * a)) & 0xff);
            lo[a] = decode(p, self.byte(PLANES + 2 * a, slot), s);
            hi[a] = decode(p, self.byte(PLANES + 6 + 2 * a, slot), s);
        }
        Aabb::new(Vec3::from(lo), Vec3::from(hi))
    }
}

/// `2^(e - 127)` for a biased exponent `e` in `1..=254`, as the kernel makes it from the bits.
fn scale(e: u32) -> f32 {
    f32::from_bits(e << 23)
}

/// A decoded plane: `p + q * s` (the product is exact: `q < 256`, `s` a power of two).
fn decode(p: f32, q: u32, s: f32) -> f32 {
    p + q as f32 * s
}

/// `x` as a GPU that flushes denormal results to zero may see it.
fn flushed(x: f32) -> f32 {
    if x.is_subnormal() { 0.0 } else { x }
}

/// Per-axis quantisation of a node's children: the origin, the biased exponent, and each
/// child's `(lo, hi)` bytes, with every decoded plane outside (or on) the child's.
fn quantise_axis(
    node_lo: f32,
    node_hi: f32,
    children: &[(f32, f32)],
) -> (f32, u32, Vec<(u32, u32)>) {
    // A denormal origin moves down to the nearest normal number or zero, so that a GPU
    // flushing it reads the same value.
    let p = if node_lo.is_subnormal() {
        if node_lo < 0.0 {
            -f32::MIN_POSITIVE
        } else {
            0.0
        }
    } else {
        node_lo
    };
    let extent = f64::from(node_hi) - f64::from(p);
    // The smallest exponent whose 255 steps could cover the extent; rounding may need more.
    let mut e = if extent > 0.0 {
        ((extent / 255.0).log2().ceil() as i32 + 127).clamp(1, 254) as u32
    } else {
        1
    };
    'exponent: loop {
        let s = scale(e);
        let mut q = Vec::with_capacity(children.len());
        for &(lo, hi) in children {
            let mut qlo = ((f64::from(lo) - f64::from(p)) / f64::from(s))
                .floor()
                .clamp(0.0, 255.0) as u32;
            // q = 0 decodes to p <= lo, so this ends.
            while qlo > 0 && (decode(p, qlo, s) > lo || flushed(decode(p, qlo, s)) > lo) {
                qlo -= 1;
            }
            let mut qhi = ((f64::from(hi) - f64::from(p)) / f64::from(s))
                .ceil()
                .clamp(0.0, 255.0) as u32;
            while decode(p, qhi, s) < hi || flushed(decode(p, qhi, s)) < hi {
                if qhi == 255 {
                    if e < 254 {
                        e += 1;
                        continue 'exponent;
                    }
                    break;
                }
                qhi += 1;
            }
            q.push((qlo, qhi));
        }
        return (p, e, q);
    }
}

/// The collapsed tree: wide nodes, and the primitive ids in the order its leaves index.
pub struct Cwbvh {
    /// Nodes; the root is node 0 (none for a scene without bounded primitives).
    pub nodes: Vec<WideNode>,
    /// Primitive ids in leaf order.
    pub prim_ids: Vec<u32>,
    /// The box of the root (the BVH2's root box; the kernels do not test it).
    pub root: Aabb,
    /// Leaf slots.
    pub leaves: u64,
    /// Levels of wide nodes.
    pub depth: u32,
}

impl Cwbvh {
    /// Collapses `bvh`.
    ///
    /// # Errors
    /// When a box is not finite, or a leaf holds more than [`LEAF_SIZE`] primitives (build
    /// the BVH2 with [`bvh2_params`]).
    pub fn collapse(bvh: &Bvh) -> Result<Self, String> {
        let b2 = bvh.nodes();
        let mut out = Self {
            nodes: Vec::new(),
            prim_ids: Vec::new(),
            root: Aabb::EMPTY,
            leaves: 0,
            depth: 0,
        };
        if b2.is_empty() {
            return Ok(out);
        }
        out.root = b2[0].aabb();
        out.nodes.push(WideNode::default());
        // (wide node to fill, BVH2 node it stands for, its level)
        let mut work = vec![(0usize, 0u32, 1u32)];
        while let Some((w, n, level)) = work.pop() {
            out.depth = out.depth.max(level);
            // The children: open the interior child of largest area until eight.
            let mut children = vec![n];
            while children.len() < WIDTH {
                let Some(i) = (0..children.len())
                    .filter(|&i| !b2[children[i] as usize].is_leaf())
                    .max_by(|&i, &j| {
                        let a = |k: usize| b2[children[k] as usize].aabb().surface_area();
                        a(i).total_cmp(&a(j)).then(j.cmp(&i))
                    })
                else {
                    break;
                };
                let c = children.swap_remove(i);
                children.push(c + 1);
                children.push(b2[c as usize].first_or_right);
            }
            let boxes: Vec<Aabb> = children.iter().map(|&c| b2[c as usize].aabb()).collect();
            let node_box = b2[n as usize].aabb();
            if ![node_box.min, node_box.max].iter().all(|v| v.is_finite()) {
                return Err(format!("a BVH node's box is not finite: {node_box:?}"));
            }
            let slots = assign_slots(&node_box, &boxes);
            let mut node = WideNode::default();
            for a in 0..3 {
                let planes: Vec<(f32, f32)> = boxes.iter().map(|b| (b.min[a], b.max[a])).collect();
                let (p, e, q) = quantise_axis(node_box.min[a], node_box.max[a], &planes);
                node.words[a] = p.to_bits();
                node.words[3] |= e << (8 * a);
                for (k, &(qlo, qhi)) in q.iter().enumerate() {
                    node.set_byte(PLANES + 2 * a, slots[k], qlo);
                    node.set_byte(PLANES + 6 + 2 * a, slots[k], qhi);
                }
            }
            // Interior children first get consecutive indices, in slot order; leaves' primitives
            // are appended in slot order.
            let mut by_slot: Vec<(usize, u32)> = slots
                .iter()
                .copied()
                .zip(children.iter().copied())
                .collect();
            by_slot.sort_unstable();
            node.words[4] = out.nodes.len() as u32;
            node.words[5] = out.prim_ids.len() as u32;
            for &(slot, c) in &by_slot {
                let c2 = &b2[c as usize];
                if c2.is_leaf() {
                    if c2.count as usize > LEAF_SIZE {
                        return Err(format!(
                            "a BVH2 leaf holds {} primitives, more than the CWBVH's {LEAF_SIZE}",
                            c2.count
                        ));
                    }
                    let offset = out.prim_ids.len() as u32 - node.words[5];
                    node.set_byte(6, slot, c2.count << 5 | offset);
                    let first = c2.first_or_right as usize;
                    out.prim_ids
                        .extend_from_slice(&bvh.prim_ids()[first..first + c2.count as usize]);
                    out.leaves += 1;
                } else {
                    node.words[3] |= 1 << (24 + slot);
                    work.push((out.nodes.len(), c, level + 1));
                    out.nodes.push(WideNode::default());
                }
            }
            out.nodes[w] = node;
        }
        Ok(out)
    }

    /// Bytes of the nodes.
    #[must_use]
    pub fn bytes(&self) -> u64 {
        self.nodes.len() as u64 * 80
    }

    /// The tree as the quality metrics see it: every wide node an interior node, every leaf
    /// slot a leaf, each with the box the kernel decodes; the root with the BVH2's root box.
    #[must_use]
    pub fn tree_view(&self) -> TreeView {
        let mut view = TreeView::new();
        if !self.nodes.is_empty() {
            self.view_node(0, self.root, &mut view);
        }
        view
    }

    fn view_node(&self, index: u32, bounds: Aabb, view: &mut TreeView) -> u32 {
        let node = self.nodes[index as usize];
        let mut children = Vec::with_capacity(WIDTH);
        for slot in 0..WIDTH {
            if node.is_empty(slot) {
                continue;
            }
            let b = node.child_box(slot);
            children.push(if (node.imask() >> slot) & 1 == 1 {
                self.view_node(node.child(slot), b, view)
            } else {
                let (first, count) = node.prims(slot);
                view.leaf(b, &self.prim_ids[first as usize..(first + count) as usize])
            });
        }
        view.interior(bounds, &children)
    }
}

/// Slots of `boxes` in a node of box `node`: the (child, slot) pairs are taken greedily by
/// how far the child's centre lies along the slot's diagonal direction.
fn assign_slots(node: &Aabb, boxes: &[Aabb]) -> Vec<usize> {
    let centre = node.center();
    let mut pairs = Vec::with_capacity(boxes.len() * WIDTH);
    for (k, b) in boxes.iter().enumerate() {
        let d = b.center() - centre;
        for s in 0..WIDTH {
            let dir = Vec3::new(
                if s & 1 == 0 { 1.0 } else { -1.0 },
                if s & 2 == 0 { 1.0 } else { -1.0 },
                if s & 4 == 0 { 1.0 } else { -1.0 },
            );
            pairs.push((d.dot(dir), k, s));
        }
    }
    // Farthest first; ties by child, then slot, so the assignment is deterministic.
    pairs.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut slots = vec![usize::MAX; boxes.len()];
    let mut taken = [false; WIDTH];
    for (_, k, s) in pairs {
        if slots[k] == usize::MAX && !taken[s] {
            slots[k] = s;
            taken[s] = true;
        }
    }
    slots
}

/// Checks every decoded box of `tree`: each must hold the boxes of all primitives below
/// its slot (the tests call it; the kernels rely on it).
///
/// # Errors
/// The first slot whose decoded box misses a primitive's box.
pub fn check_conservative(tree: &Cwbvh, geometry: &Geometry) -> Result<(), String> {
    if tree.nodes.is_empty() {
        return Ok(());
    }
    check_node(tree, geometry, 0).map(|_| ())
}

/// The union of the primitive boxes below wide node `index`, after checking its slots.
fn check_node(tree: &Cwbvh, geometry: &Geometry, index: u32) -> Result<Aabb, String> {
    let node = tree.nodes[index as usize];
    let mut all = Aabb::EMPTY;
    for slot in 0..WIDTH {
        if node.is_empty(slot) {
            continue;
        }
        let below = if (node.imask() >> slot) & 1 == 1 {
            check_node(tree, geometry, node.child(slot))?
        } else {
            let (first, count) = node.prims(slot);
            tree.prim_ids[first as usize..(first + count) as usize]
                .iter()
                .filter_map(|&id| geometry.shape(id).bounds())
                .fold(Aabb::EMPTY, Aabb::union)
        };
        let b = node.child_box(slot);
        if !below.is_empty() && !b.contains(&below) {
            return Err(format!(
                "node {index} slot {slot}: the decoded box {b:?} does not hold {below:?}"
            ));
        }
        all = all.union(below);
    }
    Ok(all)
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_core::{Shape, Sphere};
    use std::sync::Arc;

    /// Collapses `geometry`'s BVH2 and checks the tree: decoded boxes hold their primitives,
    /// every bounded primitive sits in one leaf once, nodes have two to eight children.
    fn check(geometry: Arc<Geometry>) -> Cwbvh {
        let bvh = Bvh::build_with(Arc::clone(&geometry), bvh2_params());
        let tree = Cwbvh::collapse(&bvh).unwrap();
        check_conservative(&tree, &geometry).unwrap();
        tree.tree_view().check_leaves(&geometry).unwrap();
        let mut ids = tree.prim_ids.clone();
        ids.sort_unstable();
        let mut bounded = geometry.bounded().to_vec();
        bounded.sort_unstable();
        assert_eq!(ids, bounded);
        for n in &tree.nodes {
            let used = (0..WIDTH).filter(|&s| !n.is_empty(s)).count();
            assert!((1..=WIDTH).contains(&used));
        }
        tree
    }

    #[test]
    fn collapsed_trees_are_conservative_on_generated_scenes() {
        for name in [
            "soup:3000",
            "spheres:2000",
            "terrain:24",
            "spheres:5",
            "icosphere:3",
        ] {
            let scene = raybench_scene::load(name, std::path::Path::new(".")).unwrap();
            let tree = check(Arc::clone(&scene.geometry));
            // Eight-wide: far fewer nodes than the BVH2's.
            let bvh = Bvh::build_with(Arc::clone(&scene.geometry), bvh2_params());
            assert!(tree.nodes.len() * 3 < bvh.nodes().len(), "{name}");
        }
    }

    /// Tiny, huge, negative and denormal coordinates, a flat box, one primitive.
    #[test]
    fn quantisation_rounds_outward_at_extreme_scales() {
        let tiny = f32::MIN_POSITIVE;
        let cases: [Vec<(Vec3, f32)>; 5] = [
            (0..40)
                .map(|i| (Vec3::splat(i as f32 * 3e-39), 1e-39))
                .collect(),
            (0..40)
                .map(|i| (Vec3::new(1e30 + i as f32 * 1e28, -3e29, 7.0), 1e27))
                .collect(),
            (0..40)
                .map(|i| (Vec3::new(-1000.0 - i as f32 * 0.001, 5.0, -1e-3), 1e-4))
                .collect(),
            (0..40)
                .map(|i| (Vec3::new(i as f32, 0.0, 0.0), tiny))
                .collect(),
            vec![(Vec3::new(0.1, 0.2, 0.3), 0.05)],
        ];
        for spheres in cases {
            let shapes = spheres
                .into_iter()
                .map(|(c, r)| Shape::Sphere(Sphere::new(c, r)))
                .collect();
            check(Arc::new(Geometry::new(shapes)));
        }
    }

    #[test]
    fn an_empty_scene_has_no_nodes() {
        let tree = check(Arc::new(Geometry::new(Vec::new())));
        assert!(tree.nodes.is_empty() && tree.prim_ids.is_empty());
    }

    #[test]
    fn decoded_planes_are_exact_sums() {
        // q * 2^e is exact for q < 256, so p + q * s rounds once, as a fused multiply-add.
        for (p, q, e) in [(1.0f32, 255u32, 100u32), (-3.5, 17, 1), (1e30, 200, 230)] {
            let s = scale(e);
            let fused = (q as f32).mul_add(s, p);
            assert_eq!(decode(p, q, s).to_bits(), fused.to_bits());
            assert_eq!(
                f64::from(q as f32 * s),
                f64::from(q) * f64::from(s),
                "product exact"
            );
        }
    }
}
