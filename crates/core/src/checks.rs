//! Parameter checks and tree folding shared by the object kinds built from trees (CSG trees,
//! SDF models).

use crate::error::SceneError;
use crate::limits::MAX_COORDINATE;
use glam::Vec3;

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
