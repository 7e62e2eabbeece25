//! The parts of a signed-distance model as scene files describe them: the primitives, the
//! operations that combine them and the tree of both ([`SdfNode`]), with each part's checks,
//! its box and its exact distance. The leaf of the `sdf` modules: the build and the march
//! call down into it.

use crate::aabb::Aabb;
use crate::checks;
use crate::error::SceneError;
use crate::limits::MAX_COORDINATE;
use crate::optree::{self, Operator, Source, View};
use glam::{Affine3A, Vec2, Vec3};

/// A signed-distance primitive. Tori and cylinders have the `y` axis; transform nodes place
/// them otherwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SdfPrimitive {
    /// A ball.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius (positive).
        radius: f32,
    },
    /// An axis-aligned box whose edges may be rounded.
    Box {
        /// Centre.
        center: Vec3,
        /// Half extents (positive), rounding included.
        half_extents: Vec3,
        /// Edge rounding radius, from 0 up to the smallest half extent.
        rounding: f32,
    },
    /// A torus around the `y` axis through `center`.
    Torus {
        /// Centre.
        center: Vec3,
        /// Radius of the centre circle (positive).
        major_radius: f32,
        /// Radius of the tube (positive).
        minor_radius: f32,
    },
    /// The points within `radius` of the segment `a`-`b`.
    Capsule {
        /// One end of the segment.
        a: Vec3,
        /// The other end.
        b: Vec3,
        /// Radius (positive).
        radius: f32,
    },
    /// A capped cylinder on the `y` axis through `center`.
    Cylinder {
        /// Centre (halfway between the caps).
        center: Vec3,
        /// Radius (positive).
        radius: f32,
        /// Half the height (positive).
        half_height: f32,
    },
}

/// A binary operation on two distance fields.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SdfOp {
    /// `min(a, b)`.
    Union,
    /// `max(a, b)`.
    Intersection,
    /// `max(a, -b)`: the first operand with the second removed.
    Subtraction,
    /// The polynomial smooth minimum with blend radius `k` (positive).
    SmoothUnion(f32),
    /// `(1 - w) a + w b` with weight `w` in `[0, 1]`.
    Blend(f32),
}

impl SdfOp {
    /// Lower-case name used in scene files.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Union => "union",
            Self::Intersection => "intersection",
            Self::Subtraction => "subtraction",
            Self::SmoothUnion(_) => "smooth_union",
            Self::Blend(_) => "blend",
        }
    }

    /// Combines the operands' values.
    #[inline]
    #[must_use]
    pub fn apply(self, a: f32, b: f32) -> f32 {
        match self {
            Self::Union => a.min(b),
            Self::Intersection => a.max(b),
            Self::Subtraction => a.max(-b),
            Self::SmoothUnion(k) => {
                let h = (k - (a - b).abs()).max(0.0) / k;
                a.min(b) - h * h * k * 0.25
            }
            Self::Blend(w) => (1.0 - w) * a + w * b,
        }
    }

    /// The operation's Lipschitz bound from its operands' (see the module documentation).
    #[must_use]
    pub fn lipschitz(self, la: f32, lb: f32) -> f32 {
        match self {
            Self::Blend(w) => (1.0 - w) * la + w * lb,
            _ => la.max(lb),
        }
    }
}

/// A distance tree as scene files describe it; [`Sdf::new`](super::Sdf::new) validates it.
#[derive(Clone, Debug, PartialEq)]
pub enum SdfNode {
    /// A primitive.
    Leaf(SdfPrimitive),
    /// An operation and its two operands.
    Op(SdfOp, Box<SdfNode>, Box<SdfNode>),
    /// A similarity transform (rotation, uniform scale, translation) of a subtree.
    Transform(Affine3A, Box<SdfNode>),
}

impl SdfNode {
    /// Folds `operands` with `op` into a balanced tree, so that depth grows with the
    /// logarithm of the count. A subtraction removes the union of all operands after the
    /// first; a smooth union (not associative) is *defined* by this balanced fold; a blend
    /// takes exactly two operands.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] when there are fewer than two operands, or a blend has more.
    pub fn fold(op: SdfOp, operands: Vec<SdfNode>) -> Result<Self, SceneError> {
        if matches!(op, SdfOp::Blend(_)) && operands.len() > 2 {
            return Err(SceneError::Invalid(format!(
                "an SDF blend takes exactly two operands, found {}",
                operands.len()
            )));
        }
        optree::fold(
            &format!("an SDF {}", op.name()),
            op,
            operands,
            |op, a, b| Self::Op(op, Box::new(a), Box::new(b)),
        )
    }
}

impl Operator for SdfOp {
    const UNION: Self = Self::Union;
    const DIFFERENCE: Self = Self::Subtraction;
}

impl Source for SdfNode {
    type Leaf = SdfPrimitive;
    type Op = SdfOp;
    type Transform = Affine3A;

    fn view(&self) -> View<'_, Self> {
        match self {
            Self::Leaf(p) => View::Leaf(*p),
            Self::Op(op, a, b) => View::Op(*op, a, b),
            Self::Transform(m, child) => View::Wrap(m, child),
        }
    }
}

/// Checks a primitive's parameters.
pub(super) fn validate(p: &SdfPrimitive) -> Result<(), SceneError> {
    let point = |v: Vec3, what: &str| checks::point(v, &format!("SDF {what}"));
    let positive = |x: f32, what: &str| checks::positive(x, &format!("SDF {what}"));
    match *p {
        SdfPrimitive::Sphere { center, radius } => {
            point(center, "sphere centre")?;
            positive(radius, "sphere radius")
        }
        SdfPrimitive::Box {
            center,
            half_extents,
            rounding,
        } => {
            point(center, "box centre")?;
            for h in half_extents.to_array() {
                positive(h, "box half extent")?;
            }
            if !rounding.is_finite() {
                return Err(SceneError::NonFinite("SDF box rounding".into()));
            }
            if !(rounding >= 0.0 && rounding <= half_extents.min_element()) {
                return Err(SceneError::Invalid(format!(
                    "SDF box rounding must lie in [0, smallest half extent {}], found {rounding}",
                    half_extents.min_element()
                )));
            }
            Ok(())
        }
        SdfPrimitive::Torus {
            center,
            major_radius,
            minor_radius,
        } => checks::torus("SDF", center, major_radius, minor_radius),
        SdfPrimitive::Capsule { a, b, radius } => {
            point(a, "capsule end a")?;
            point(b, "capsule end b")?;
            positive(radius, "capsule radius")
        }
        SdfPrimitive::Cylinder {
            center,
            radius,
            half_height,
        } => {
            point(center, "cylinder centre")?;
            positive(radius, "cylinder radius")?;
            positive(half_height, "cylinder half height")
        }
    }
}

/// Checks an operation's parameter.
pub(super) fn validate_op(op: SdfOp) -> Result<(), SceneError> {
    match op {
        SdfOp::SmoothUnion(k) if !k.is_finite() => {
            Err(SceneError::NonFinite("SDF smooth_union k".into()))
        }
        SdfOp::SmoothUnion(k) if !(k > 0.0 && k <= MAX_COORDINATE) => Err(SceneError::Invalid(
            format!("SDF smooth_union k must be positive, found {k}"),
        )),
        SdfOp::Blend(w) if !w.is_finite() => Err(SceneError::NonFinite("SDF blend w".into())),
        SdfOp::Blend(w) if !(0.0..=1.0).contains(&w) => Err(SceneError::Invalid(format!(
            "SDF blend weight w must lie in [0, 1], found {w}"
        ))),
        _ => Ok(()),
    }
}

/// A primitive's bounding box.
pub(super) fn primitive_bounds(p: &SdfPrimitive) -> Aabb {
    let around = |c: Vec3, h: Vec3| Aabb::new(c - h, c + h);
    match *p {
        SdfPrimitive::Sphere { center, radius } => around(center, Vec3::splat(radius)),
        SdfPrimitive::Box {
            center,
            half_extents,
            ..
        } => around(center, half_extents),
        SdfPrimitive::Torus {
            center,
            major_radius,
            minor_radius,
        } => {
            let r = major_radius + minor_radius;
            around(center, Vec3::new(r, minor_radius, r))
        }
        SdfPrimitive::Capsule { a, b, radius } => Aabb::new(
            a.min(b) - Vec3::splat(radius),
            a.max(b) + Vec3::splat(radius),
        ),
        SdfPrimitive::Cylinder {
            center,
            radius,
            half_height,
        } => around(center, Vec3::new(radius, half_height, radius)),
    }
}

/// A primitive's exact signed distance at `p` (Quilez's formulas).
#[inline]
pub(super) fn primitive_distance(s: &SdfPrimitive, p: Vec3) -> f32 {
    match *s {
        SdfPrimitive::Sphere { center, radius } => (p - center).length() - radius,
        SdfPrimitive::Box {
            center,
            half_extents,
            rounding,
        } => {
            let q = (p - center).abs() - (half_extents - Vec3::splat(rounding));
            q.max(Vec3::ZERO).length() + q.max_element().min(0.0) - rounding
        }
        SdfPrimitive::Torus {
            center,
            major_radius,
            minor_radius,
        } => {
            let q = p - center;
            Vec2::new(Vec2::new(q.x, q.z).length() - major_radius, q.y).length() - minor_radius
        }
        SdfPrimitive::Capsule { a, b, radius } => {
            let (pa, ba) = (p - a, b - a);
            let len2 = ba.dot(ba);
            let h = if len2 > 0.0 {
                (pa.dot(ba) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (pa - ba * h).length() - radius
        }
        SdfPrimitive::Cylinder {
            center,
            radius,
            half_height,
        } => {
            let q = p - center;
            let d =
                Vec2::new(Vec2::new(q.x, q.z).length(), q.y).abs() - Vec2::new(radius, half_height);
            d.max_element().min(0.0) + d.max(Vec2::ZERO).length()
        }
    }
}
