//! The CSG tree: the set operations, the tree as scene files describe it, and its
//! validated post-order form (an [`OpTree`] whose leaves are solids, placed or not).

use super::placement::Placement;
use super::solid::{Bound, Solid, finite_point, solid_bounds, validate};
use super::spans::CsgOp;
use crate::aabb::Aabb;
use crate::error::SceneError;
use crate::limits::{MAX_CSG_DEPTH, MAX_CSG_LEAVES};
use crate::optree::{self, Builder, Counted, Limits, OpTree, Source, View};
use glam::Affine3A;
use std::convert::Infallible;

/// A CSG tree as scene files describe it: operators with two operands, solids at the
/// leaves. [`super::Csg::new`] validates it.
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
        optree::fold(&format!("a CSG {}", op.name()), op, operands, |op, a, b| {
            Self::Op(op, Box::new(a), Box::new(b))
        })
    }
}

/// A leaf of the validated tree: a solid and its placement, if it has one.
pub(super) type Leaf = (Solid, Option<Placement>);

/// The validated tree.
pub(super) type Tree = OpTree<Leaf, CsgOp, Infallible>;

/// A node of the validated tree.
pub(super) type Node = optree::Node<Leaf, CsgOp, Infallible>;

/// The limits of [`super::Csg::new`].
pub(super) const LIMITS: Limits = Limits {
    what: "the CSG tree",
    depth: MAX_CSG_DEPTH,
    size: MAX_CSG_LEAVES,
    counted: Counted::Leaves("solids"),
};

impl Source for CsgNode {
    type Leaf = (Solid, Option<Affine3A>);
    type Op = CsgOp;
    type Transform = Infallible;

    fn view(&self) -> View<'_, Self> {
        match self {
            Self::Leaf(s) => View::Leaf((*s, None)),
            Self::Placed(s, a) => View::Leaf((*s, Some(*a))),
            Self::Op(op, a, b) => View::Op(*op, a, b),
        }
    }
}

/// How [`super::Csg::new`] builds the validated tree: the leaves' checks and boxes and the
/// operators' boxes, the hooks of [`OpTree::build`].
pub(super) struct CsgBuilder;

impl Builder<CsgNode> for CsgBuilder {
    type Leaf = Leaf;
    type Wrap = Infallible;
    type Bound = Bound;

    fn leaf((s, to_world): (Solid, Option<Affine3A>)) -> Result<(Leaf, Bound), SceneError> {
        let s = validate(s)?;
        let place = to_world.map(Placement::new).transpose()?;
        let bound = match (solid_bounds(&s), to_world) {
            (Some(b), Some(a)) => {
                let b = b.transformed(a);
                finite_point(b.min, "transformed solid's box")?;
                finite_point(b.max, "transformed solid's box")?;
                Some(b)
            }
            (b, _) => b,
        };
        Ok(((s, place), bound))
    }

    fn check_op(_: CsgOp) -> Result<(), SceneError> {
        Ok(())
    }

    /// Unions join boxes, intersections overlap them, a difference keeps its first
    /// operand's; an unbounded operand (a half-space) leaves an intersection bounded by
    /// the other.
    fn op_bound(op: CsgOp, a: Bound, b: Bound) -> Bound {
        match op {
            CsgOp::Union => match (a, b) {
                (Some(x), Some(y)) => Some(x.union(y)),
                _ => None,
            },
            CsgOp::Intersection => match (a, b) {
                (Some(x), Some(y)) => Some(Aabb::new(x.min.max(y.min), x.max.min(y.max))),
                (x, None) => x,
                (None, y) => y,
            },
            CsgOp::Difference => a,
        }
    }

    fn wrap(t: &Infallible) -> Result<Infallible, SceneError> {
        match *t {}
    }

    fn wrap_bound(t: &Infallible, _: &Infallible, _: Bound) -> Result<Bound, SceneError> {
        match *t {}
    }
}
