//! Parameter checks and tree folding shared by the object kinds built from trees (CSG trees,
//! SDF models).

use crate::error::SceneError;
use crate::limits::{MAX_COORDINATE, MAX_TRANSFORM_CONDITION};
use glam::{Affine3A, Mat3A, Vec3};

/// A point parameter: finite and within [`MAX_COORDINATE`]. `what` names it in the error
/// ("CSG sphere centre").
pub(crate) fn point(v: Vec3, what: &str) -> Result<(), SceneError> {
    if !v.is_finite() {
        Err(SceneError::NonFinite(what.to_string()))
    } else if v.abs().max_element() > MAX_COORDINATE {
        Err(SceneError::Invalid(format!(
            "{what} exceeds {MAX_COORDINATE:e} in magnitude"
        )))
    } else {
        Ok(())
    }
}

/// A size parameter: finite, positive and at most [`MAX_COORDINATE`].
pub(crate) fn positive(x: f32, what: &str) -> Result<(), SceneError> {
    if !x.is_finite() {
        Err(SceneError::NonFinite(what.to_string()))
    } else if !(x > 0.0 && x <= MAX_COORDINATE) {
        Err(SceneError::Invalid(format!(
            "{what} must be positive and at most {MAX_COORDINATE:e}, found {x}"
        )))
    } else {
        Ok(())
    }
}

/// An operator's operand list has at least two entries; `what` names the operator ("a CSG
/// union").
pub(crate) fn at_least_two<T>(what: &str, operands: &[T]) -> Result<(), SceneError> {
    if operands.len() < 2 {
        return Err(SceneError::Invalid(format!(
            "{what} needs at least two operands, found {}",
            operands.len()
        )));
    }
    Ok(())
}

/// `operands` (at least one) joined pairwise into a balanced binary tree, so that depth
/// grows with the logarithm of the count.
pub(crate) fn balanced<T>(mut operands: Vec<T>, join: &impl Fn(T, T) -> T) -> T {
    if operands.len() == 1 {
        return operands.pop().expect("one operand");
    }
    let right = operands.split_off(operands.len() / 2);
    join(balanced(operands, join), balanced(right, join))
}

/// An n-ary operator's operands folded into a balanced binary tree by `join`; for a
/// difference, the first operand joined with the others' balanced `union`.
pub(crate) fn fold<T>(
    mut operands: Vec<T>,
    difference: bool,
    join: &impl Fn(T, T) -> T,
    union: &impl Fn(T, T) -> T,
) -> T {
    if difference {
        let first = operands.remove(0);
        return join(first, balanced(operands, union));
    }
    balanced(operands, join)
}

/// Checks an object's placement `to_world` (`what` names it: "CSG transform", "transform"):
/// finite, its scale and translation within [`MAX_COORDINATE`], and its linear part
/// invertible with a condition number (`|M|max * |M^-1|max`) at most
/// [`MAX_TRANSFORM_CONDITION`]: a zero scale flattens an object into nothing (a mesh then
/// renders as an empty image), and a tiny one overflows the inverse. Returns the inverse
/// of the linear part.
///
/// # Errors
/// [`SceneError::NonFinite`] or [`SceneError::Invalid`] saying which condition fails.
pub fn check_transform(to_world: Affine3A, what: &str) -> Result<Mat3A, SceneError> {
    let m = to_world.matrix3;
    if !(m.is_finite() && to_world.translation.is_finite()) {
        return Err(SceneError::NonFinite(what.into()));
    }
    let norm = |a: Mat3A| {
        [a.x_axis, a.y_axis, a.z_axis]
            .iter()
            .map(|c| c.abs().max_element())
            .fold(0.0f32, f32::max)
    };
    if norm(m) > MAX_COORDINATE {
        return Err(SceneError::Invalid(format!(
            "{what}'s scale exceeds {MAX_COORDINATE:e}"
        )));
    }
    point(
        to_world.translation.into(),
        &format!("{what}'s translation"),
    )?;
    let inv = m.inverse();
    let cond = norm(m) * norm(inv);
    // NaN (from an overflowing inverse) fails the last comparison too.
    let conditioned = cond <= MAX_TRANSFORM_CONDITION;
    if m.determinant() == 0.0 || !inv.is_finite() || cond.is_nan() {
        return Err(SceneError::Invalid(format!(
            "{what} is singular (a zero scale?)"
        )));
    }
    if !conditioned {
        return Err(SceneError::Invalid(format!(
            "{what} is nearly singular (a tiny scale?): condition number {cond:e} above \
             {MAX_TRANSFORM_CONDITION:e}"
        )));
    }
    Ok(inv)
}
