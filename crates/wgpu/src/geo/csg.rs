//! CSG trees on the GPU (`kernels/csg.wgsl`): every solid (sphere, box, cylinder, cone,
//! half-space, ellipsoid, torus, paraboloid), placed or not, under unions, intersections and
//! differences, as [`raybench_core::Csg`] evaluates them.
//!
//! **Record.** `a.xyz` and `c.xyz`: the tree's padded box ([`Csg::bounds`]); `b.x`: the
//! index in `geo` of the tree's first entry, `b.y`: its node count, `b.z`: its leaf count
//! (integers by their bits; `a.w`, `b.w` and `c.w` are the caller's).
//!
//! **Tree in `geo`.** The nodes in post-order ([`Csg::parts`]), one code per node packed four
//! to an entry ([`NODE_LEAF`] or an operator's [`op_code`]), then one [`LEAF_STRIDE`]-entry
//! record per leaf in leaf order: `[0]` the solid's first vector and its kind
//! ([`solid_code`]) in `w`, `[1]` its second vector and whether it is placed in `w`, and
//! for a placed leaf `[2..5]` the world-to-local map's columns (the translation in their
//! `w`) and `[5..8]` the normal matrix's columns.
//!
//! **Limits.** The kernels evaluate a tree with a stack of [`STACK`] entries, the scene
//! loader's [`MAX_CSG_DEPTH`], and number leaves in 8 bits, up to [`MAX_LEAVES`], the
//! loader's [`MAX_CSG_LEAVES`]: every tree the loader accepts fits, and [`supports`] checks
//! both again (a tree built past them is refused with the reason). The span ends of the
//! first `CSG_CACHE` (16) leaves are kept while the tree is evaluated; larger trees
//! evaluate the further leaves again at each event time (`kernels/csg.wgsl` has the
//! algorithm and the f32 formulation with its error bound).

use crate::records::{Geo, GpuPrim, next_index};
use raybench_core::limits::{MAX_CSG_DEPTH, MAX_CSG_LEAVES};
use raybench_core::{Csg, CsgOp, CsgPart, Solid, Vec3};

/// Entries of the kernels' evaluation stack (`CSG_STACK` in `csg.wgsl`): a post-order
/// evaluation of a tree `n` levels deep holds at most `n` results.
pub(crate) const STACK: usize = MAX_CSG_DEPTH;

/// Leaves the kernels number (`CSG_MAX_LEAVES` in `csg.wgsl`; ids take 8 bits of their
/// packed node states).
pub(crate) const MAX_LEAVES: usize = MAX_CSG_LEAVES;

/// Entries of `geo` per leaf (`CSG_LEAF_STRIDE` in `csg.wgsl`).
pub(crate) const LEAF_STRIDE: usize = 8;

/// The node code of a leaf (`CSG_NODE_LEAF`).
pub(crate) const NODE_LEAF: u32 = 3;

/// The node code of an operator: 0 union, 1 intersection, 2 difference.
fn op_code(op: CsgOp) -> u32 {
    match op {
        CsgOp::Union => 0,
        CsgOp::Intersection => 1,
        CsgOp::Difference => 2,
    }
}

/// A solid's kind code (`CSG_SPHERE` ... in `csg.wgsl`) and its two parameter vectors.
fn solid_code(s: &Solid) -> (u32, Vec3, Vec3) {
    match *s {
        Solid::Sphere { center, radius } => (0, center, Vec3::new(radius, 0.0, 0.0)),
        Solid::Box { min, max } => (1, min, max),
        Solid::Cylinder {
            base,
            radius,
            height,
        } => (2, base, Vec3::new(radius, height, 0.0)),
        Solid::Cone {
            base,
            radius,
            height,
        } => (3, base, Vec3::new(radius, height, 0.0)),
        Solid::HalfSpace { point, normal } => (4, point, normal),
        Solid::Ellipsoid { center, radii } => (5, center, radii),
        Solid::Torus {
            center,
            major_radius,
            minor_radius,
        } => (6, center, Vec3::new(major_radius, minor_radius, 0.0)),
        Solid::Paraboloid {
            base,
            radius,
            height,
        } => (7, base, Vec3::new(radius, height, 0.0)),
    }
}

/// The most results a post-order evaluation of `parts` holds at once.
fn stack_depth(parts: &[CsgPart]) -> usize {
    let (mut sp, mut most) = (0usize, 0usize);
    for p in parts {
        match p {
            CsgPart::Leaf(..) => {
                sp += 1;
                most = most.max(sp);
            }
            CsgPart::Op(_) => sp = sp.saturating_sub(1),
        }
    }
    most
}

/// Whether the kernels can intersect `x`, or why not: its leaves and its evaluation stack
/// must fit the kernels' arrays ([`MAX_LEAVES`], [`STACK`]), which the scene loader's limits
/// guarantee.
///
/// # Errors
/// The reason, naming CSG trees.
pub(crate) fn supports(x: &Csg) -> Result<(), String> {
    let parts = x.parts();
    let leaves = parts
        .iter()
        .filter(|p| matches!(p, CsgPart::Leaf(..)))
        .count();
    if leaves > MAX_LEAVES {
        return Err(format!(
            "the GPU kernels intersect CSG trees of at most {MAX_LEAVES} solids, and this one \
             has {leaves} (render it with a CPU backend)"
        ));
    }
    let depth = stack_depth(&parts);
    if depth > STACK {
        return Err(format!(
            "the GPU kernels evaluate CSG trees holding at most {STACK} partial results, and \
             this one needs {depth} (render it with a CPU backend)"
        ));
    }
    Ok(())
}

/// The record of `x`, its tree appended to `geo` (layout in the module documentation).
///
/// # Errors
/// See [`supports`]; or when `geo` outgrows `u32` indices.
pub(crate) fn encode(x: &Csg, geo: &mut Geo) -> Result<GpuPrim, String> {
    supports(x)?;
    let parts = x.parts();
    let start = next_index(geo)?;
    let codes: Vec<u32> = parts
        .iter()
        .map(|p| match p {
            CsgPart::Leaf(..) => NODE_LEAF,
            CsgPart::Op(op) => op_code(*op),
        })
        .collect();
    for chunk in codes.chunks(4) {
        let mut e = [0.0f32; 4];
        for (slot, &c) in e.iter_mut().zip(chunk) {
            *slot = f32::from_bits(c);
        }
        geo.push(e);
    }
    let mut leaves = 0u32;
    for p in &parts {
        let CsgPart::Leaf(solid, place) = p else {
            continue;
        };
        leaves += 1;
        let (kind, p0, p1) = solid_code(solid);
        let mut entry = [[0.0f32; 4]; LEAF_STRIDE];
        entry[0] = [p0.x, p0.y, p0.z, f32::from_bits(kind)];
        entry[1] = [p1.x, p1.y, p1.z, f32::from_bits(u32::from(place.is_some()))];
        if let Some((to_local, normal)) = place {
            let m = to_local.matrix3;
            let t = to_local.translation;
            for (k, col) in [m.x_axis, m.y_axis, m.z_axis].into_iter().enumerate() {
                entry[2 + k] = [col.x, col.y, col.z, t[k]];
            }
            for (k, col) in normal.iter().enumerate() {
                entry[5 + k] = [col.x, col.y, col.z, 0.0];
            }
        }
        geo.extend_from_slice(&entry);
    }
    next_index(geo)?;
    let b = x.bounds();
    Ok(GpuPrim {
        a: [b.min.x, b.min.y, b.min.z, 0.0],
        b: [
            f32::from_bits(start),
            f32::from_bits(parts.len() as u32),
            f32::from_bits(leaves),
            0.0,
        ],
        c: [b.max.x, b.max.y, b.max.z, 0.0],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The kernels' array sizes are the Rust constants (the WGSL declares them itself).
    #[test]
    fn wgsl_constants_match() {
        let src = include_str!("../kernels/csg.wgsl");
        for (name, value) in [
            ("CSG_STACK", STACK),
            ("CSG_MAX_LEAVES", MAX_LEAVES),
            ("CSG_LEAF_STRIDE", LEAF_STRIDE),
            ("CSG_NODE_LEAF", NODE_LEAF as usize),
        ] {
            let decl = format!("const {name}: u32 = {value}u;");
            assert!(src.contains(&decl), "csg.wgsl must declare `{decl}`");
        }
    }

    /// A balanced tree of 256 leaves (the loader's most) fits; its stack needs 9 entries.
    #[test]
    fn the_loaders_largest_trees_fit() {
        let leaf = |k: usize| {
            raybench_core::CsgNode::Leaf(Solid::Sphere {
                center: Vec3::new(k as f32, 0.0, 0.0),
                radius: 0.75,
            })
        };
        let tree =
            raybench_core::CsgNode::fold(CsgOp::Union, (0..256).map(leaf).collect()).expect("fold");
        let csg = Csg::new(&tree).expect("valid");
        assert!(supports(&csg).is_ok());
        assert_eq!(stack_depth(&csg.parts()), 9);
        let mut geo = Geo::new();
        let p = encode(&csg, &mut geo).expect("encode");
        assert_eq!(p.b[1].to_bits(), 511);
        assert_eq!(p.b[2].to_bits(), 256);
        assert_eq!(geo.len(), 128 + 256 * LEAF_STRIDE);
        // A right-leaning chain 32 levels deep (the loader's deepest) needs 32.
        let mut node = leaf(0);
        for k in 1..32 {
            node = raybench_core::CsgNode::Op(CsgOp::Union, Box::new(leaf(k)), Box::new(node));
        }
        let csg = Csg::new(&node).expect("valid");
        assert_eq!(stack_depth(&csg.parts()), 32);
        assert!(supports(&csg).is_ok());
    }
}
