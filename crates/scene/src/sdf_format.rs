//! The `kind = "sdf"` object of the scene format: a tree of signed-distance primitives and
//! operations (documented in `docs/scene-format.md`, section "SDF models").

use crate::format::ScaleDesc;
use crate::transform::Transform;
use raybench_core::limits::MAX_SDF_DEPTH;
use raybench_core::{SceneError, Sdf, SdfNode, SdfOp, SdfParams, SdfPrimitive, Vec3};
use serde::Deserialize;

type V3 = [f32; 3];

/// An `[[object]]` table with `kind = "sdf"`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SdfDesc {
    tree: SdfNodeDesc,
    /// Hit tolerance relative to the model's box diagonal.
    tolerance: Option<f32>,
    /// Step limit.
    max_steps: Option<u32>,
    pub(crate) material: Option<String>,
}

/// A node of an SDF tree: an operation with its operands, a transform of one operand, or a
/// primitive.
#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
enum SdfNodeDesc {
    Union {
        operands: Vec<SdfNodeDesc>,
    },
    Intersection {
        operands: Vec<SdfNodeDesc>,
    },
    #[serde(alias = "difference")]
    Subtraction {
        operands: Vec<SdfNodeDesc>,
    },
    SmoothUnion {
        k: f32,
        operands: Vec<SdfNodeDesc>,
    },
    Blend {
        w: f32,
        operands: Vec<SdfNodeDesc>,
    },
    Transform {
        translate: Option<V3>,
        rotate: Option<V3>,
        scale: Option<ScaleDesc>,
        operand: Box<SdfNodeDesc>,
    },
    Sphere {
        center: V3,
        radius: f32,
    },
    Box {
        center: V3,
        half_extents: V3,
        #[serde(default)]
        rounding: f32,
    },
    Torus {
        center: V3,
        major_radius: f32,
        minor_radius: f32,
    },
    Capsule {
        a: V3,
        b: V3,
        radius: f32,
    },
    Cylinder {
        center: V3,
        radius: f32,
        half_height: f32,
    },
}

impl SdfDesc {
    /// Builds and validates the model.
    pub(crate) fn build(&self) -> Result<Sdf, SceneError> {
        let tree = node(&self.tree, 1)?;
        let params = SdfParams {
            tolerance: self.tolerance.unwrap_or(SdfParams::DEFAULT.tolerance),
            max_steps: self.max_steps.unwrap_or(SdfParams::DEFAULT.max_steps),
        };
        Sdf::new(&tree, params)
    }
}

/// Converts a scene file's tree into the core's, checking the depth before recursing
/// further (n-ary operations are folded into balanced binary trees).
fn node(d: &SdfNodeDesc, depth: usize) -> Result<SdfNode, SceneError> {
    if depth > MAX_SDF_DEPTH {
        return Err(SceneError::TooLarge(format!(
            "the SDF tree is deeper than {MAX_SDF_DEPTH} levels"
        )));
    }
    let fold = |op: SdfOp, operands: &[SdfNodeDesc]| -> Result<SdfNode, SceneError> {
        let nodes = operands
            .iter()
            .map(|o| node(o, depth + 1))
            .collect::<Result<Vec<_>, _>>()?;
        SdfNode::fold(op, nodes)
    };
    let v = |a: &V3| Vec3::from(*a);
    Ok(match d {
        SdfNodeDesc::Union { operands } => fold(SdfOp::Union, operands)?,
        SdfNodeDesc::Intersection { operands } => fold(SdfOp::Intersection, operands)?,
        SdfNodeDesc::Subtraction { operands } => fold(SdfOp::Subtraction, operands)?,
        SdfNodeDesc::SmoothUnion { k, operands } => fold(SdfOp::SmoothUnion(*k), operands)?,
        SdfNodeDesc::Blend { w, operands } => fold(SdfOp::Blend(*w), operands)?,
        SdfNodeDesc::Transform {
            translate,
            rotate,
            scale,
            operand,
        } => {
            let t = Transform {
                scale: match scale {
                    None => Vec3::ONE,
                    Some(ScaleDesc::Uniform(s)) => Vec3::splat(*s),
                    Some(ScaleDesc::PerAxis(s)) => v(s),
                },
                rotate_degrees: rotate.as_ref().map_or(Vec3::ZERO, v),
                translate: translate.as_ref().map_or(Vec3::ZERO, v),
            };
            SdfNode::Transform(t.affine(), Box::new(node(operand, depth + 1)?))
        }
        SdfNodeDesc::Sphere { center, radius } => SdfNode::Leaf(SdfPrimitive::Sphere {
            center: v(center),
            radius: *radius,
        }),
        SdfNodeDesc::Box {
            center,
            half_extents,
            rounding,
        } => SdfNode::Leaf(SdfPrimitive::Box {
            center: v(center),
            half_extents: v(half_extents),
            rounding: *rounding,
        }),
        SdfNodeDesc::Torus {
            center,
            major_radius,
            minor_radius,
        } => SdfNode::Leaf(SdfPrimitive::Torus {
            center: v(center),
            major_radius: *major_radius,
            minor_radius: *minor_radius,
        }),
        SdfNodeDesc::Capsule { a, b, radius } => SdfNode::Leaf(SdfPrimitive::Capsule {
            a: v(a),
            b: v(b),
            radius: *radius,
        }),
        SdfNodeDesc::Cylinder {
            center,
            radius,
            half_height,
        } => SdfNode::Leaf(SdfPrimitive::Cylinder {
            center: v(center),
            radius: *radius,
            half_height: *half_height,
        }),
    })
}
