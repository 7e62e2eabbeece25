//! The CSG objects of the scene format: `kind = "csg"` (a tree of analytic solids) and the
//! standalone solids `torus`, `ellipsoid`, `cylinder`, `cone` and `paraboloid` (one-solid
//! trees), each solid optionally placed by its own transform.

use super::{ObjectCx, TransformDesc, V3};
use crate::error::LoadError;
use raybench_core::{Csg, CsgNode, CsgOp, SceneError, Solid, Vec3};
use serde::Deserialize;
use std::sync::Arc;

/// `kind = "csg"`: a tree of solids with one material.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CsgDesc {
    tree: CsgNodeDesc,
    material: Option<String>,
}

/// A node of a CSG tree: an operator with its operands, or a solid.
#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
enum CsgNodeDesc {
    Union {
        operands: Vec<CsgNodeDesc>,
    },
    Intersection {
        operands: Vec<CsgNodeDesc>,
    },
    Difference {
        operands: Vec<CsgNodeDesc>,
    },
    Sphere {
        center: V3,
        radius: f32,
        transform: Option<TransformDesc>,
    },
    Box {
        min: V3,
        max: V3,
        transform: Option<TransformDesc>,
    },
    Cylinder(RevolvedDesc),
    Cone(RevolvedDesc),
    HalfSpace {
        point: V3,
        normal: V3,
        transform: Option<TransformDesc>,
    },
    // Tori and quadrics.
    Torus(TorusDesc),
    Ellipsoid(EllipsoidDesc),
    Paraboloid(RevolvedDesc),
}

/// A torus about its local y axis, as a CSG operand or (with a material) an object.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TorusDesc {
    center: V3,
    major_radius: f32,
    minor_radius: f32,
    material: Option<String>,
    transform: Option<TransformDesc>,
}

/// An axis-aligned ellipsoid (before its transform), as a CSG operand or an object.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct EllipsoidDesc {
    center: V3,
    radii: V3,
    material: Option<String>,
    transform: Option<TransformDesc>,
}

/// A capped cylinder, cone or paraboloid standing on its local y axis, as a CSG operand
/// or an object.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RevolvedDesc {
    base: V3,
    radius: f32,
    height: f32,
    material: Option<String>,
    transform: Option<TransformDesc>,
}

impl RevolvedDesc {
    /// Adds the standalone cylinder, cone or paraboloid (`kind`).
    pub(super) fn add(&self, kind: &str, cx: &mut ObjectCx) -> Result<(), LoadError> {
        let (transform, material) = (self.transform.as_ref(), self.material.as_ref());
        add_solid(cx, kind, self.solid(kind), transform, material)
    }

    /// The solid this describes as a cylinder, a cone or a paraboloid (`kind`).
    fn solid(&self, kind: &str) -> Solid {
        let (base, radius, height) = (Vec3::from(self.base), self.radius, self.height);
        match kind {
            "cylinder" => Solid::Cylinder {
                base,
                radius,
                height,
            },
            "cone" => Solid::Cone {
                base,
                radius,
                height,
            },
            _ => Solid::Paraboloid {
                base,
                radius,
                height,
            },
        }
    }
}

/// A solid, placed when it has a transform other than the identity (an identity keeps
/// the unplaced fast path).
fn placed(solid: Solid, transform: Option<&TransformDesc>) -> CsgNode {
    match transform.map(TransformDesc::to_transform) {
        Some(xf) if !xf.is_identity() => CsgNode::Placed(solid, xf.affine()),
        _ => CsgNode::Leaf(solid),
    }
}

/// A CSG operand's solid: refused when it names a material (the tree's applies).
fn operand(
    solid: Solid,
    transform: Option<&TransformDesc>,
    material: Option<&String>,
) -> Result<CsgNode, SceneError> {
    if let Some(m) = material {
        return Err(SceneError::Invalid(format!(
            "a CSG operand cannot have its own material ('{m}'): the tree's `material` applies"
        )));
    }
    Ok(placed(solid, transform))
}

/// Adds a standalone analytic solid: a one-leaf CSG primitive named `name`.
fn add_solid(
    cx: &mut ObjectCx,
    name: &str,
    solid: Solid,
    transform: Option<&TransformDesc>,
    material: Option<&String>,
) -> Result<(), LoadError> {
    let err = cx.err();
    let m = cx.material(material)?.unwrap_or(0);
    let csg = Csg::new(&placed(solid, transform)).map_err(&err)?;
    cx.b.add_shapes(name, vec![raybench_core::Shape::Csg(Arc::new(csg))], m)
        .map_err(err)?;
    Ok(())
}

impl TorusDesc {
    /// Adds the standalone torus.
    pub(super) fn add(&self, cx: &mut ObjectCx) -> Result<(), LoadError> {
        let (transform, material) = (self.transform.as_ref(), self.material.as_ref());
        add_solid(cx, "torus", self.solid(), transform, material)
    }

    fn solid(&self) -> Solid {
        Solid::Torus {
            center: Vec3::from(self.center),
            major_radius: self.major_radius,
            minor_radius: self.minor_radius,
        }
    }
}

impl EllipsoidDesc {
    /// Adds the standalone ellipsoid.
    pub(super) fn add(&self, cx: &mut ObjectCx) -> Result<(), LoadError> {
        let (transform, material) = (self.transform.as_ref(), self.material.as_ref());
        add_solid(cx, "ellipsoid", self.solid(), transform, material)
    }

    fn solid(&self) -> Solid {
        Solid::Ellipsoid {
            center: Vec3::from(self.center),
            radii: Vec3::from(self.radii),
        }
    }
}

/// Converts a scene file's tree into the core's, checking the depth before recursing
/// further (operators are folded into balanced binary trees).
fn csg_node(d: &CsgNodeDesc, depth: usize) -> Result<CsgNode, SceneError> {
    use raybench_core::limits::MAX_CSG_DEPTH;
    if depth > MAX_CSG_DEPTH {
        return Err(SceneError::TooLarge(format!(
            "the CSG tree is deeper than {MAX_CSG_DEPTH} levels"
        )));
    }
    let fold = |op: CsgOp, operands: &[CsgNodeDesc]| -> Result<CsgNode, SceneError> {
        let nodes = operands
            .iter()
            .map(|o| csg_node(o, depth + 1))
            .collect::<Result<Vec<_>, _>>()?;
        CsgNode::fold(op, nodes)
    };
    Ok(match d {
        CsgNodeDesc::Union { operands } => fold(CsgOp::Union, operands)?,
        CsgNodeDesc::Intersection { operands } => fold(CsgOp::Intersection, operands)?,
        CsgNodeDesc::Difference { operands } => fold(CsgOp::Difference, operands)?,
        CsgNodeDesc::Sphere {
            center,
            radius,
            transform,
        } => placed(
            Solid::Sphere {
                center: Vec3::from(*center),
                radius: *radius,
            },
            transform.as_ref(),
        ),
        CsgNodeDesc::Box {
            min,
            max,
            transform,
        } => placed(
            Solid::Box {
                min: Vec3::from(*min),
                max: Vec3::from(*max),
            },
            transform.as_ref(),
        ),
        CsgNodeDesc::HalfSpace {
            point,
            normal,
            transform,
        } => placed(
            Solid::HalfSpace {
                point: Vec3::from(*point),
                normal: Vec3::from(*normal),
            },
            transform.as_ref(),
        ),
        CsgNodeDesc::Cylinder(r) => operand(
            r.solid("cylinder"),
            r.transform.as_ref(),
            r.material.as_ref(),
        )?,
        CsgNodeDesc::Cone(r) => {
            operand(r.solid("cone"), r.transform.as_ref(), r.material.as_ref())?
        }
        CsgNodeDesc::Paraboloid(r) => operand(
            r.solid("paraboloid"),
            r.transform.as_ref(),
            r.material.as_ref(),
        )?,
        CsgNodeDesc::Torus(t) => operand(t.solid(), t.transform.as_ref(), t.material.as_ref())?,
        CsgNodeDesc::Ellipsoid(e) => operand(e.solid(), e.transform.as_ref(), e.material.as_ref())?,
    })
}

impl CsgDesc {
    /// Converts the tree, checks it and adds it.
    pub(super) fn add(&self, cx: &mut ObjectCx) -> Result<(), LoadError> {
        let err = cx.err();
        let m = cx.material(self.material.as_ref())?.unwrap_or(0);
        let tree = csg_node(&self.tree, 1).map_err(&err)?;
        let csg = Csg::new(&tree).map_err(&err)?;
        cx.b.add_shapes("csg", vec![raybench_core::Shape::Csg(Arc::new(csg))], m)
            .map_err(err)?;
        Ok(())
    }
}
