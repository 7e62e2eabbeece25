//! SDF models on the GPU (`kernels/sdf.wgsl`): raybench-geometry's `Sdf` (sphere tracing of
//! a tree of distance primitives, operations and similarity transforms) as a flat postfix
//! program in `geo` that the kernel evaluates with two small stacks (WGSL has no recursion).
//!
//! **Record.** `a.xyz` and `b.xyz`: the model's padded box (`Sdf::bounds`, where the march
//! runs); `c.x`: the index of the program's header in `geo` (bits), `c.y`: the index one past
//! its last entry (bits), `c.z`: the hit tolerance `eps` (`Sdf::tolerance`), `c.w`: the
//! Lipschitz bound `L` (`Sdf::lipschitz`).
//!
//! **Program.** A header entry `(bits(max_steps), 0, 0, 0)`, then the tree's nodes as
//! instructions in the CPU's evaluation order (`Sdf::eval`: first operand, second operand,
//! operation), each an entry whose `x` holds the opcode's bits and more entries as below:
//! - a primitive pushes its distance at the current point: `(op, centre or end a)` and
//!   `(radius)` (sphere), `(half extents, rounding)` (box), `(major, minor radius)` (torus),
//!   `(end b, radius)` (capsule), `(radius, half height)` (cylinder);
//! - an operation `(op, k or w)` replaces the top two values `a`, `b` by `op.apply(a, b)`;
//! - a transform is split around its subtree: [`SDF_ENTER`] `(op, translation)` and three
//!   entries with the columns of the inverse map's linear part saves the current point on
//!   the point stack and maps it (`Similarity::local`: the same operations in the same
//!   order); [`SDF_LEAVE`] `(op, scale)` after the subtree restores the point and multiplies
//!   the top value by the scale.
//!
//! Everything is f32 on the CPU too (the SDF code has no f64), and every value is computed
//! by the same operations in the same order, so the distances differ only by the GPU's
//! rounding of `sqrt` (`length`), division (the capsule's projection, the smooth union's
//! `/ k`, the box clip) and any fused multiply-add the driver forms: a few ulps of each
//! operand. See `kernels/sdf.wgsl` for what that does to the march: at worst one step more
//! or fewer, which moves `t` by about `eps / (L |dir|)`, i.e. a relative `eps / distance`.
//!
//! **Measured** (`tests/tests/gpu/`, lavapipe, both GPU backends against naive): on `sdf`
//! ids agree on 100% of pixels in cast, Whitted and path modes with a largest relative `t`
//! difference of 2.0e-7; colours differ on 0% (cast, path) and 0.098% (Whitted: one pixel
//! of 1,024); incoherent closest hits are bit-identical and any-hit rays agree on 100%. On
//! the deepest-trees scene of `tests/tests/gpu/sdf.rs`: 100% ids, 1.7e-7, 0% colours, identical
//! incoherent hits. A real GPU (approximate `sqrt` and division) was not available; by the
//! bound above a camera ray of `sdf` stays below the shared 1e-4 (`eps / distance` is at
//! most about 4e-5 there), while an explicit ray that hits within `eps / 1e-4` of its
//! origin (about 3 units for `sdf`'s largest model) could exceed it if its step count
//! flipped.
//!
//! **Stacks.** The value stack holds one value per pending first operand on the path to the
//! node being evaluated plus the value being formed, so it needs at most the tree's depth
//! ([`value_stack_need`]); the point stack holds one point per enclosing transform
//! ([`point_stack_need`]), at most the depth minus one. The kernel allocates
//! [`SDF_VALUES`] and [`SDF_POINTS`] entries, enough for every tree the loader accepts
//! (`MAX_SDF_DEPTH`); [`supports`] still checks each tree's need and refuses beyond them.

use crate::records::{Geo, GpuPrim, next_index};
use raybench_core::limits::{MAX_SDF_DEPTH, MAX_SDF_NODES};
use raybench_core::{Sdf, SdfNodeView, SdfOp, SdfPrimitive, Vec3};

/// Opcode: a sphere (`kernels/sdf.wgsl` declares the same numbers; a test compares them).
pub(crate) const SDF_SPHERE: u32 = 0;
/// Opcode: a box with optional rounding.
pub(crate) const SDF_BOX: u32 = 1;
/// Opcode: a torus around `y`.
pub(crate) const SDF_TORUS: u32 = 2;
/// Opcode: a capsule.
pub(crate) const SDF_CAPSULE: u32 = 3;
/// Opcode: a capped cylinder on `y`.
pub(crate) const SDF_CYLINDER: u32 = 4;
/// Opcode: union (`min`).
pub(crate) const SDF_UNION: u32 = 5;
/// Opcode: intersection (`max`).
pub(crate) const SDF_INTERSECTION: u32 = 6;
/// Opcode: subtraction (`max(a, -b)`).
pub(crate) const SDF_SUBTRACTION: u32 = 7;
/// Opcode: smooth union with radius `k`.
pub(crate) const SDF_SMOOTH_UNION: u32 = 8;
/// Opcode: blend with weight `w`.
pub(crate) const SDF_BLEND: u32 = 9;
/// Opcode: enter a transform (save and map the point).
pub(crate) const SDF_ENTER: u32 = 10;
/// Opcode: leave a transform (restore the point, scale the value).
pub(crate) const SDF_LEAVE: u32 = 11;

/// Entries of the kernel's value stack (`SDF_VALUES` in `kernels/sdf.wgsl`).
pub(crate) const SDF_VALUES: usize = 32;
/// Entries of the kernel's point stack (`SDF_POINTS` in `kernels/sdf.wgsl`).
pub(crate) const SDF_POINTS: usize = 32;

// Every tree within the loader's depth limit fits the stacks (the needs are bounded by the
// depth and the depth minus one).
const _: () = assert!(MAX_SDF_DEPTH <= SDF_VALUES && MAX_SDF_DEPTH <= SDF_POINTS + 1);

/// Values held at once while evaluating node `i` in post-order (first operand, second
/// operand, operation): a leaf pushes one; an operation holds its first operand's value
/// while the second is evaluated.
fn value_stack_need(x: &Sdf, i: usize) -> usize {
    match x.node(i) {
        SdfNodeView::Leaf(_) => 1,
        SdfNodeView::Op(_, a, b) => value_stack_need(x, a).max(1 + value_stack_need(x, b)),
        SdfNodeView::Transform { child, .. } => value_stack_need(x, child),
    }
}

/// Points saved at once while evaluating node `i`: one per enclosing transform.
fn point_stack_need(x: &Sdf, i: usize) -> usize {
    match x.node(i) {
        SdfNodeView::Leaf(_) => 0,
        SdfNodeView::Op(_, a, b) => point_stack_need(x, a).max(point_stack_need(x, b)),
        SdfNodeView::Transform { child, .. } => 1 + point_stack_need(x, child),
    }
}

/// Whether the kernels can intersect `x`, or why not: its program must fit the kernel's
/// stacks (always true of a tree within the loader's `MAX_SDF_DEPTH` and `MAX_SDF_NODES`).
///
/// # Errors
/// The tree needs more stack entries than the kernel allocates, or has more nodes than the
/// loader allows.
pub(crate) fn supports(x: &Sdf) -> Result<(), String> {
    let n = x.node_count();
    if n == 0 || n > MAX_SDF_NODES {
        return Err(format!(
            "the GPU kernels take SDF models of 1 to {MAX_SDF_NODES} nodes, found {n}"
        ));
    }
    let root = n - 1;
    let values = value_stack_need(x, root);
    let points = point_stack_need(x, root);
    if values > SDF_VALUES || points > SDF_POINTS {
        return Err(format!(
            "the SDF model needs {values} values and {points} nested transforms on the GPU \
             kernel's stacks, which hold {SDF_VALUES} and {SDF_POINTS} (render it with a CPU \
             backend)"
        ));
    }
    Ok(())
}

/// An entry whose `x` holds `op`'s bits.
fn head(op: u32, v: Vec3) -> [f32; 4] {
    [f32::from_bits(op), v.x, v.y, v.z]
}

/// Appends node `i`'s subtree as instructions in the CPU's evaluation order.
fn emit(x: &Sdf, i: usize, geo: &mut Geo) {
    match x.node(i) {
        SdfNodeView::Leaf(s) => geo.extend(match s {
            SdfPrimitive::Sphere { center, radius } => {
                [head(SDF_SPHERE, center), [radius, 0.0, 0.0, 0.0]]
            }
            SdfPrimitive::Box {
                center,
                half_extents: h,
                rounding,
            } => [head(SDF_BOX, center), [h.x, h.y, h.z, rounding]],
            SdfPrimitive::Torus {
                center,
                major_radius,
                minor_radius,
            } => [
                head(SDF_TORUS, center),
                [major_radius, minor_radius, 0.0, 0.0],
            ],
            SdfPrimitive::Capsule { a, b, radius } => {
                [head(SDF_CAPSULE, a), [b.x, b.y, b.z, radius]]
            }
            SdfPrimitive::Cylinder {
                center,
                radius,
                half_height,
            } => [head(SDF_CYLINDER, center), [radius, half_height, 0.0, 0.0]],
        }),
        SdfNodeView::Op(op, a, b) => {
            emit(x, a, geo);
            emit(x, b, geo);
            let (code, param) = match op {
                SdfOp::Union => (SDF_UNION, 0.0),
                SdfOp::Intersection => (SDF_INTERSECTION, 0.0),
                SdfOp::Subtraction => (SDF_SUBTRACTION, 0.0),
                SdfOp::SmoothUnion(k) => (SDF_SMOOTH_UNION, k),
                SdfOp::Blend(w) => (SDF_BLEND, w),
            };
            geo.push(head(code, Vec3::new(param, 0.0, 0.0)));
        }
        SdfNodeView::Transform {
            linear,
            translation,
            scale,
            child,
        } => {
            geo.push(head(SDF_ENTER, translation));
            geo.extend(linear.map(|c| [c.x, c.y, c.z, 0.0]));
            emit(x, child, geo);
            geo.push(head(SDF_LEAVE, Vec3::new(scale, 0.0, 0.0)));
        }
    }
}

/// The record of `x`, its program appended to `geo` (layout in the module documentation).
///
/// # Errors
/// See [`supports`]; also when `geo` outgrows `u32` indices.
pub(crate) fn encode(x: &Sdf, geo: &mut Geo) -> Result<GpuPrim, String> {
    supports(x)?;
    let start = next_index(geo)?;
    geo.push([f32::from_bits(x.max_steps()), 0.0, 0.0, 0.0]);
    emit(x, x.node_count() - 1, geo);
    let end = next_index(geo)?;
    let b = x.bounds();
    Ok(GpuPrim {
        a: [b.min.x, b.min.y, b.min.z, 0.0],
        b: [b.max.x, b.max.y, b.max.z, 0.0],
        c: [
            f32::from_bits(start),
            f32::from_bits(end),
            x.tolerance(),
            x.lipschitz(),
        ],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_core::{SdfNode, SdfParams};

    /// The opcodes and stack sizes `kernels/sdf.wgsl` declares are the ones above.
    #[test]
    fn the_kernel_declares_the_same_constants() {
        let wgsl = include_str!("../kernels/sdf.wgsl");
        let expected = [
            ("SDF_SPHERE", SDF_SPHERE),
            ("SDF_BOX", SDF_BOX),
            ("SDF_TORUS", SDF_TORUS),
            ("SDF_CAPSULE", SDF_CAPSULE),
            ("SDF_CYLINDER", SDF_CYLINDER),
            ("SDF_UNION", SDF_UNION),
            ("SDF_INTERSECTION", SDF_INTERSECTION),
            ("SDF_SUBTRACTION", SDF_SUBTRACTION),
            ("SDF_SMOOTH_UNION", SDF_SMOOTH_UNION),
            ("SDF_BLEND", SDF_BLEND),
            ("SDF_ENTER", SDF_ENTER),
            ("SDF_LEAVE", SDF_LEAVE),
            ("SDF_VALUES", SDF_VALUES as u32),
            ("SDF_POINTS", SDF_POINTS as u32),
        ];
        for (name, value) in expected {
            let line = format!("const {name}: u32 = {value}u;");
            assert!(wgsl.contains(&line), "kernels/sdf.wgsl lacks `{line}`");
        }
    }

    fn sphere(x: f32) -> SdfNode {
        SdfNode::Leaf(SdfPrimitive::Sphere {
            center: Vec3::new(x, 0.0, 0.0),
            radius: 1.0,
        })
    }

    /// A right-leaning chain of `n` unions under `n` transforms at the deepest level the loader
    /// allows: the needs are the depth (values) and the transform nesting (points).
    #[test]
    fn stack_needs_follow_the_tree() {
        let chain = |n: usize| {
            let mut t = sphere(0.0);
            for i in 0..n {
                t = SdfNode::Op(SdfOp::Union, Box::new(sphere(i as f32)), Box::new(t));
            }
            t
        };
        let m = Sdf::new(&chain(MAX_SDF_DEPTH - 1), SdfParams::DEFAULT).unwrap();
        assert_eq!(value_stack_need(&m, m.node_count() - 1), MAX_SDF_DEPTH);
        assert_eq!(point_stack_need(&m, m.node_count() - 1), 0);
        assert!(supports(&m).is_ok());
        let mut t = sphere(0.0);
        for _ in 0..MAX_SDF_DEPTH - 1 {
            t = SdfNode::Transform(
                raybench_core::Affine3A::from_translation(Vec3::X),
                Box::new(t),
            );
        }
        let m = Sdf::new(&t, SdfParams::DEFAULT).unwrap();
        assert_eq!(value_stack_need(&m, m.node_count() - 1), 1);
        assert_eq!(point_stack_need(&m, m.node_count() - 1), MAX_SDF_DEPTH - 1);
        assert!(supports(&m).is_ok());
        // A left-leaning chain holds two values at most.
        let mut t = sphere(0.0);
        for i in 0..8 {
            t = SdfNode::Op(SdfOp::Union, Box::new(t), Box::new(sphere(i as f32)));
        }
        let m = Sdf::new(&t, SdfParams::DEFAULT).unwrap();
        assert_eq!(value_stack_need(&m, m.node_count() - 1), 2);
    }

    /// `kernels/sdf.wgsl`'s `sdf_distance` and its helpers in Rust, with glam's types where
    /// the CPU uses them: the program in `geo[first..end]` at `x`.
    fn run(geo: &Geo, first: usize, end: usize, x: Vec3) -> f32 {
        use raybench_core::{Vec2, Vec3A};
        let v = |e: [f32; 4]| Vec3::new(e[0], e[1], e[2]);
        let (mut values, mut points, mut p, mut pc) = (Vec::new(), Vec::new(), x, first);
        while pc < end {
            let e = geo[pc];
            let (op, h) = (e[0].to_bits(), Vec3::new(e[1], e[2], e[3]));
            if op <= SDF_CYLINDER {
                let f = geo[pc + 1];
                values.push(match op {
                    SDF_SPHERE => (p - h).length() - f[0],
                    SDF_BOX => {
                        let q = (p - h).abs() - (v(f) - Vec3::splat(f[3]));
                        q.max(Vec3::ZERO).length() + q.max_element().min(0.0) - f[3]
                    }
                    SDF_TORUS => {
                        let q = p - h;
                        Vec2::new(Vec2::new(q.x, q.z).length() - f[0], q.y).length() - f[1]
                    }
                    SDF_CAPSULE => {
                        let (pa, ba) = (p - h, v(f) - h);
                        let len2 = ba.dot(ba);
                        let t = if len2 > 0.0 {
                            (pa.dot(ba) / len2).clamp(0.0, 1.0)
                        } else {
                            0.0
                        };
                        (pa - ba * t).length() - f[3]
                    }
                    _ => {
                        let q = p - h;
                        let d = Vec2::new(Vec2::new(q.x, q.z).length(), q.y).abs()
                            - Vec2::new(f[0], f[1]);
                        d.max_element().min(0.0) + d.max(Vec2::ZERO).length()
                    }
                });
                pc += 2;
            } else if op <= SDF_BLEND {
                let b = values.pop().unwrap();
                let a = values.pop().unwrap();
                let k = e[1];
                values.push(
                    match op {
                        SDF_UNION => SdfOp::Union,
                        SDF_INTERSECTION => SdfOp::Intersection,
                        SDF_SUBTRACTION => SdfOp::Subtraction,
                        SDF_SMOOTH_UNION => SdfOp::SmoothUnion(k),
                        _ => SdfOp::Blend(k),
                    }
                    .apply(a, b),
                );
                pc += 1;
            } else if op == SDF_ENTER {
                points.push(p);
                let c = |i: usize| Vec3A::from(v(geo[pc + i]));
                p = (c(1) * p.x + c(2) * p.y + c(3) * p.z + Vec3A::from(h)).into();
                pc += 4;
            } else {
                p = points.pop().unwrap();
                let top = values.last_mut().unwrap();
                *top *= e[1];
                pc += 1;
            }
        }
        assert_eq!((values.len(), points.len()), (1, 0));
        values[0]
    }

    /// The program of a tree with every primitive, operation and nested, rotated and scaled
    /// transforms, run as the kernel runs it, gives `Sdf::distance` bit for bit (the kernel's
    /// differences are then only the GPU's rounding).
    #[test]
    fn programs_compute_the_cpu_distance() {
        use raybench_core::Affine3A;
        let leaf = SdfNode::Leaf;
        let op = |o, a, b| SdfNode::Op(o, Box::new(a), Box::new(b));
        let turned = SdfNode::Transform(
            Affine3A::from_translation(Vec3::new(0.1, 0.2, 0.3))
                * Affine3A::from_rotation_y(0.6)
                * Affine3A::from_scale(Vec3::splat(1.7)),
            Box::new(op(
                SdfOp::Blend(0.3),
                leaf(SdfPrimitive::Box {
                    center: Vec3::new(0.2, 0.3, -0.4),
                    half_extents: Vec3::new(0.5, 0.3, 0.4),
                    rounding: 0.1,
                }),
                SdfNode::Transform(
                    Affine3A::from_rotation_x(0.3) * Affine3A::from_scale(Vec3::splat(0.5)),
                    Box::new(leaf(SdfPrimitive::Torus {
                        center: Vec3::new(0.5, 0.0, 0.0),
                        major_radius: 0.6,
                        minor_radius: 0.2,
                    })),
                ),
            )),
        );
        let capsules = op(
            SdfOp::Union,
            leaf(SdfPrimitive::Capsule {
                a: Vec3::new(-1.0, 0.0, 0.0),
                b: Vec3::new(-0.2, 0.8, 0.1),
                radius: 0.25,
            }),
            leaf(SdfPrimitive::Capsule {
                a: Vec3::new(0.3, 0.3, 0.3),
                b: Vec3::new(0.3, 0.3, 0.3),
                radius: 0.2,
            }),
        );
        let tree = op(
            SdfOp::SmoothUnion(0.3),
            op(SdfOp::Intersection, turned, sphere(0.2)),
            op(
                SdfOp::Subtraction,
                capsules,
                leaf(SdfPrimitive::Cylinder {
                    center: Vec3::new(0.0, -0.5, 0.3),
                    radius: 0.3,
                    half_height: 0.4,
                }),
            ),
        );
        let m = Sdf::new(&tree, SdfParams::DEFAULT).unwrap();
        let mut geo = Geo::new();
        let rec = encode(&m, &mut geo).unwrap();
        let (first, end) = (rec.c[0].to_bits() as usize + 1, rec.c[1].to_bits() as usize);
        let mut differ = 0;
        for i in 0..20_000u32 {
            // A Weyl sequence in [-2.5, 2.5]^3.
            let u = |a: f32| ((i as f32 * a).fract() - 0.5) * 5.0;
            let x = Vec3::new(u(0.754_877_7), u(0.569_840_3), u(0.438_289_4));
            if run(&geo, first, end, x).to_bits() != m.distance(x).to_bits() {
                differ += 1;
            }
        }
        assert_eq!(differ, 0);
    }

    /// The program's layout: header, the operands before their operation, transforms around
    /// their subtree.
    #[test]
    fn programs_are_postfix() {
        let t = SdfNode::Op(
            SdfOp::SmoothUnion(0.5),
            Box::new(sphere(0.0)),
            Box::new(SdfNode::Transform(
                raybench_core::Affine3A::from_scale(Vec3::splat(2.0)),
                Box::new(sphere(1.0)),
            )),
        );
        let m = Sdf::new(&t, SdfParams::DEFAULT).unwrap();
        let mut geo = vec![[0.0; 4]; 3];
        let p = encode(&m, &mut geo).unwrap();
        assert_eq!(p.c[0].to_bits(), 3);
        assert_eq!(p.c[1].to_bits() as usize, geo.len());
        assert_eq!(p.c[2], m.tolerance());
        let ops: Vec<u32> = [4, 6, 10, 12, 13]
            .iter()
            .map(|&i| geo[i][0].to_bits())
            .collect();
        assert_eq!(
            ops,
            [
                SDF_SPHERE,
                SDF_ENTER,
                SDF_SPHERE,
                SDF_LEAVE,
                SDF_SMOOTH_UNION
            ]
        );
        assert_eq!(geo[12][1], 2.0);
        assert_eq!(geo[13][1], 0.5);
        assert_eq!(geo[3][0].to_bits(), m.max_steps());
        assert_eq!(geo.len(), 3 + 1 + 2 + 4 + 2 + 1 + 1);
    }
}
