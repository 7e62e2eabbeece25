//! The CSG tree: the set operations, the tree as scene files describe it, and its
//! validated post-order form.

use super::placement::Placement;
use super::solid::{Solid, finite_point, solid_bounds, validate};
use crate::aabb::Aabb;
use crate::checks;
use crate::error::SceneError;
use crate::limits::{MAX_CSG_DEPTH, MAX_CSG_LEAVES};
use glam::Affine3A;

/// A CSG set operation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CsgOp {
    /// Points in either operand (`min(A, B)`).
    Union,
    /// Points in both operands (`max(A, B)`).
    Intersection,
    /// Points in the first operand and not the second (`max(A, -B)`).
    Difference,
}

impl CsgOp {
    /// Lower-case name used in scene files.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Union => "union",
            Self::Intersection => "intersection",
            Self::Difference => "difference",
        }
    }

    #[inline]
    pub(super) fn apply(self, a: bool, b: bool) -> bool {
        match self {
            Self::Union => a || b,
            Self::Intersection => a && b,
            Self::Difference => a && !b,
        }
    }
}

/// A CSG tree as scene files describe it: operators with two operands, solids at the
/// leaves. [`Csg::new`] validates it.
#[derive(Clone, Debug, PartialEq)]
pub enum CsgNode {
    /// A solid.
    Leaf(Solid),
    /// A solid placed by an affine map from its local space to the tree's (scale, rotation
    /// and translation; non-uniform scale allowed, singular maps refused).
    Placed(Solid, Affine3A),
    /// An operator and its two operands.
    Op(CsgOp, Box<CsgNode>, Box<CsgNode>),
}

impl CsgNode {
    /// Folds `operands` with `op` into a balanced tree (a difference subtracts the union of
    /// all operands after the first), so that depth grows with the logarithm of the count.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] when there are fewer than two operands.
    pub fn fold(op: CsgOp, operands: Vec<CsgNode>) -> Result<Self, SceneError> {
        checks::at_least_two(&format!("a CSG {}", op.name()), &operands)?;
        let join = |op| move |a, b| Self::Op(op, Box::new(a), Box::new(b));
        Ok(checks::fold(
            operands,
            op == CsgOp::Difference,
            &join(op),
            &join(CsgOp::Union),
        ))
    }
}

/// A node of the validated tree, stored in post-order.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Node {
    Leaf(Solid, Option<Placement>),
    Op(CsgOp, usize, usize),
}

/// A bound that may be all of space (`None`).
pub(super) type Bound = Option<Aabb>;

/// Appends `node`'s subtree to `nodes` in post-order, validating it (`depth` is its
/// level, `leaves` the leaves so far); returns its bound.
pub(super) fn flatten(
    node: &CsgNode,
    depth: usize,
    nodes: &mut Vec<Node>,
    leaves: &mut u32,
) -> Result<Bound, SceneError> {
    if depth > MAX_CSG_DEPTH {
        return Err(SceneError::TooLarge(format!(
            "the CSG tree is deeper than {MAX_CSG_DEPTH} levels"
        )));
    }
    match node {
        CsgNode::Leaf(s) | CsgNode::Placed(s, _) => {
            if *leaves as usize >= MAX_CSG_LEAVES {
                return Err(SceneError::TooLarge(format!(
                    "the CSG tree has more than {MAX_CSG_LEAVES} solids"
                )));
            }
            let s = validate(*s)?;
            let to_world = match node {
                CsgNode::Placed(_, a) => Some(*a),
                _ => None,
            };
            let place = to_world.map(Placement::new).transpose()?;
            let bound = match (solid_bounds(&s), to_world) {
                (Some(b), Some(a)) => {
                    let b = Placement::bounds(a, b);
                    finite_point(b.min, "transformed solid's box")?;
                    finite_point(b.max, "transformed solid's box")?;
                    Some(b)
                }
                (b, _) => b,
            };
            *leaves += 1;
            nodes.push(Node::Leaf(s, place));
            Ok(bound)
        }
        CsgNode::Op(op, a, b) => {
            let ba = flatten(a, depth + 1, nodes, leaves)?;
            let ia = nodes.len() - 1;
            let bb = flatten(b, depth + 1, nodes, leaves)?;
            let ib = nodes.len() - 1;
            nodes.push(Node::Op(*op, ia, ib));
            Ok(match op {
                CsgOp::Union => match (ba, bb) {
                    (Some(x), Some(y)) => Some(x.union(y)),
                    _ => None,
                },
                CsgOp::Intersection => match (ba, bb) {
                    (Some(x), Some(y)) => Some(Aabb::new(x.min.max(y.min), x.max.min(y.max))),
                    (x, None) => x,
                    (None, y) => y,
                },
                CsgOp::Difference => ba,
            })
        }
    }
}
