//! The `kind = "sdf"` object of the scene format: a tree of signed-distance primitives and
//! operations (documented in `docs/scene-format.md`, section "SDF models").

use super::{ObjectCx, ScaleDesc, V3};
use crate::error::LoadError;
use crate::transform::Transform;
use raybench_core::limits::MAX_SDF_DEPTH;
use raybench_core::{SceneError, Sdf, SdfNode, SdfOp, SdfParams, SdfPrimitive, Vec3};
use serde::Deserialize;
use std::sync::Arc;

/// An `[[object]]` table with `kind = "sdf"`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SdfDesc {
    tree: SdfNodeDesc,
    /// Hit tolerance relative to the model's box diagonal.
    tolerance: Option<f32>,
    /// Step limit.
    max_steps: Option<u32>,
    material: Option<String>,
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
    /// Builds the model and adds it.
    pub(super) fn add(&self, cx: &mut ObjectCx) -> Result<(), LoadError> {
        let err = cx.err();
        let m = cx.material(self.material.as_ref())?.unwrap_or(0);
        let model = self.build().map_err(&err)?;
        cx.b.add_shapes("sdf", vec![raybench_core::Shape::Sdf(Arc::new(model))], m)
            .map_err(err)?;
        Ok(())
    }

    /// Builds and validates the model.
    fn build(&self) -> Result<Sdf, SceneError> {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn build(tree: &str, options: &str) -> Result<Sdf, String> {
        let d: SdfDesc =
            toml::from_str(&format!("{options}\ntree = {tree}")).map_err(|e| e.to_string())?;
        d.build().map_err(|e| e.to_string())
    }

    #[test]
    fn every_node_type_parses() {
        let tree = r#"{ type = "smooth_union", k = 0.2, operands = [
            { type = "sphere", center = [0, 0, 0], radius = 1 },
            { type = "box", center = [2, 0, 0], half_extents = [0.5, 0.5, 0.5], rounding = 0.1 },
            { type = "torus", center = [0, 2, 0], major_radius = 1, minor_radius = 0.2 },
            { type = "capsule", a = [0, 0, 2], b = [1, 0, 2], radius = 0.2 },
            { type = "cylinder", center = [0, -2, 0], radius = 0.5, half_height = 0.3 },
            { type = "union", operands = [
                { type = "sphere", center = [3, 3, 3], radius = 0.5 },
                { type = "sphere", center = [3, 4, 3], radius = 0.5 } ] },
            { type = "intersection", operands = [
                { type = "sphere", center = [-3, 0, 0], radius = 0.5 },
                { type = "sphere", center = [-3.5, 0, 0], radius = 0.5 } ] },
            { type = "difference", operands = [
                { type = "sphere", center = [0, 0, -3], radius = 0.5 },
                { type = "sphere", center = [0, 0, -3.5], radius = 0.3 } ] },
            { type = "blend", w = 0.5, operands = [
                { type = "sphere", center = [-3, -3, 0], radius = 0.5 },
                { type = "box", center = [-3, -3, 0], half_extents = [0.4, 0.4, 0.4] } ] },
        ] }"#;
        let m = build(tree, "tolerance = 1e-3\nmax_steps = 100").unwrap();
        assert_eq!(m.max_steps(), 100);
        assert!(m.distance(Vec3::ZERO) < -0.9);
    }

    /// Scale, then rotate (degrees about x, y, z), then translate: as object transforms.
    #[test]
    fn transforms_follow_the_object_transform_convention() {
        let tree = r#"{ type = "transform", scale = 2, rotate = [0, 0, 90], translate = [5, 0, 0],
            operand = { type = "capsule", a = [0, 0, 0], b = [1, 0, 0], radius = 0.1 } }"#;
        let m = build(tree, "").unwrap();
        // The segment from (5, 0, 0) to (5, 2, 0), radius 0.2.
        assert!((m.distance(Vec3::new(5.0, 2.2, 0.0))).abs() < 1e-5);
        assert!((m.distance(Vec3::new(6.0, 1.0, 0.0)) - 0.8).abs() < 1e-5);
        let err = build(&tree.replace("scale = 2", "scale = [2, 2, 3]"), "").unwrap_err();
        assert!(err.contains("non-uniform scale"), "{err}");
    }
}
