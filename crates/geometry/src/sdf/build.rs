//! How [`Sdf::new`] validates a scene's tree into the model's: the transform nodes'
//! [`Similarity`], the [`Bound`] derived for each subtree, and the [`Builder`] that
//! [`OpTree::build`](crate::optree::OpTree::build) calls for every node.

use super::Sdf;
use super::primitive::{SdfNode, SdfOp, SdfPrimitive, primitive_bounds, validate, validate_op};
use crate::aabb::Aabb;
use crate::error::SceneError;
use crate::limits::MAX_COORDINATE;
use crate::optree::Builder;
use glam::{Affine3A, Mat3A, Vec3, Vec3A};

/// What a transform node of the validated tree stores: it evaluates `scale * f(M^-1 p)`.
/// The inverse map is kept as its linear part and translation so that the node stays 80
/// bytes; [`Similarity::local`] applies it as `Affine3A::transform_point3` does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Similarity {
    /// The inverse map's linear part.
    pub(super) linear: Mat3A,
    /// The inverse map's translation.
    pub(super) translation: Vec3,
    /// The similarity's uniform scale.
    pub(super) scale: f32,
}

impl Similarity {
    /// `M^-1 p`, with the operations of `Affine3A::transform_point3` in its order.
    #[inline]
    pub(super) fn local(&self, p: Vec3) -> Vec3 {
        ((self.linear.x_axis * p.x)
            + (self.linear.y_axis * p.y)
            + (self.linear.z_axis * p.z)
            + Vec3A::from(self.translation))
        .into()
    }
}

/// What [`Sdf::new`] derives for a subtree: its box, its Lipschitz bound, and its *spread*
/// `g`: `{p : f(p) <= c}` lies within `g c` of the box on every axis, for every `c >= 0`
/// (the box bounds more than the surface: smooth unions and the padding need the sets where
/// `f` is small). Primitives are exact distances (`g = 1`); `min`, `max`, subtraction and
/// blends keep the larger `g` (boxes overlap and join per axis, and a blend is small only
/// where an operand is); a rotation widens it by the largest row sum of `|R|`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Bound {
    /// The subtree's box.
    pub(super) aabb: Aabb,
    /// The subtree's Lipschitz bound.
    pub(super) lipschitz: f32,
    /// The subtree's spread `g`.
    pub(super) spread: f32,
}

impl Builder<SdfNode> for Sdf {
    type Leaf = SdfPrimitive;
    type Wrap = Similarity;
    type Bound = Bound;

    fn leaf(p: SdfPrimitive) -> Result<(SdfPrimitive, Bound), SceneError> {
        validate(&p)?;
        let bound = Bound {
            aabb: primitive_bounds(&p),
            lipschitz: 1.0,
            spread: 1.0,
        };
        Ok((p, bound))
    }

    fn check_op(op: SdfOp) -> Result<(), SceneError> {
        validate_op(op)
    }

    fn op_bound(op: SdfOp, a: Bound, b: Bound) -> Bound {
        let (ba, bb) = (a.aabb, b.aabb);
        let spread = a.spread.max(b.spread);
        let aabb = match op {
            SdfOp::Union | SdfOp::Blend(_) => ba.union(bb),
            SdfOp::Intersection => Aabb::new(ba.min.max(bb.min), ba.max.min(bb.max)),
            SdfOp::Subtraction => ba,
            // smin >= min(a, b) - k / 4: the surface lies where min(a, b) <= k / 4,
            // within `spread * k / 4` of the operands' boxes (see `Bound`).
            SdfOp::SmoothUnion(k) => {
                let u = ba.union(bb);
                let pad = Vec3::splat(spread * k / 4.0);
                Aabb::new(u.min - pad, u.max + pad)
            }
        };
        Bound {
            aabb,
            lipschitz: op.lipschitz(a.lipschitz, b.lipschitz),
            spread,
        }
    }

    fn wrap(m: &Affine3A) -> Result<Similarity, SceneError> {
        let scale = similarity_scale(m)?;
        let inverse = m.inverse();
        Ok(Similarity {
            linear: inverse.matrix3,
            translation: inverse.translation.into(),
            scale,
        })
    }

    fn wrap_bound(m: &Affine3A, w: &Similarity, child: Bound) -> Result<Bound, SceneError> {
        let b = child.aabb.transformed(*m);
        if !(b.min.is_finite() && b.max.is_finite())
            || b.min.abs().max(b.max.abs()).max_element() > MAX_COORDINATE
        {
            return Err(SceneError::Invalid(format!(
                "an SDF transform places the model beyond {MAX_COORDINATE:e}"
            )));
        }
        // A cube of half size r, rotated, has a box of half size r times the largest row
        // sum of |R| (at most sqrt 3).
        let r = m.matrix3 * (1.0 / w.scale);
        let rows = r.transpose();
        let turn = [rows.x_axis, rows.y_axis, rows.z_axis]
            .map(|row| row.abs().element_sum())
            .into_iter()
            .fold(1.0f32, f32::max);
        Ok(Bound {
            aabb: b,
            lipschitz: child.lipschitz,
            spread: child.spread * turn,
        })
    }
}

/// The uniform scale of a similarity transform, or an error for anything else.
fn similarity_scale(m: &Affine3A) -> Result<f32, SceneError> {
    if !(m.matrix3.is_finite() && m.translation.is_finite()) {
        return Err(SceneError::NonFinite("SDF transform".into()));
    }
    let cols = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis];
    let lengths = cols.map(|c| c.length());
    let s = lengths[0];
    let similar = s > 0.0
        && lengths.iter().all(|&l| (l - s).abs() <= 1e-5 * s)
        && cols[0].dot(cols[1]).abs() <= 1e-5 * s * s
        && cols[0].dot(cols[2]).abs() <= 1e-5 * s * s
        && cols[1].dot(cols[2]).abs() <= 1e-5 * s * s
        && m.matrix3.determinant() > 0.0;
    if !similar {
        return Err(SceneError::Invalid(format!(
            "an SDF transform must be a rotation, a uniform scale and a translation (column \
             lengths {lengths:?}): non-uniform scale, shear or mirroring would break the \
             distance bound that sphere tracing relies on"
        )));
    }
    if !(1.0 / MAX_COORDINATE..=MAX_COORDINATE).contains(&s) {
        return Err(SceneError::Invalid(format!(
            "an SDF transform's scale must lie in [{:e}, {MAX_COORDINATE:e}], found {s}",
            1.0 / MAX_COORDINATE
        )));
    }
    Ok(s)
}
