//! Constructive solid geometry: trees of analytic solids combined by union, intersection and
//! difference, intersected by interval arithmetic on sorted span lists.
//!
//! Every leaf gives the spans (entry/exit intervals) where the ray's whole line lies inside
//! it; an operator combines its operands' sorted span lists in one merge sweep, which is the
//! lecture's `F = min(A, max(B, -C))` evaluated only where some operand changes sign. The
//! hit is the first span end inside `[ray.t_min, ray.t_max]`.
//!
//! **Rules** (tested below):
//! - Spans are closed intervals and every operation is *regularised*: spans of zero length
//!   are dropped, and events at the same `t` are applied together before the combined
//!   state is read. So two solids sharing a face behave as one solid in a union (the shared
//!   face disappears), touch in nothing in an intersection, and in a difference the
//!   subtracted solid removes a face it shares with the first.
//! - A tangent ray (a zero-length span, or a ray lying in a face plane) misses.
//! - A ray starting inside the combined solid hits its exit: spans are computed over the
//!   whole line and the first boundary at or after `t_min` is returned.
//! - Normals point out of the combined solid: a subtracted solid's boundary takes its
//!   normal negated.
//! - A leaf may be placed by an affine map ([`CsgNode::Placed`]): the ray is taken to the
//!   solid's local space by the inverse map without renormalising its direction (so `t` is
//!   the same in both spaces), normals come back by the inverse transpose, renormalised, and
//!   the leaf's box is the box of its local box's eight corners. Unplaced leaves skip all
//!   of this (bit-identical to solids without the feature).
//! - Leaves give at most two spans (a torus); convex solids one.

use crate::aabb::Aabb;
use crate::error::SceneError;
use crate::hit::PrimHit;
use crate::ray::Ray;
use glam::Vec3;

mod placement;
mod quartic;
mod solid;
mod spans;
#[cfg(test)]
mod tests;
mod tree;

pub use solid::Solid;
pub use spans::CsgOp;
use spans::{End, Spans};
pub use tree::CsgNode;
use tree::{CsgBuilder, Node, Tree};

/// A node of a validated tree as [`Csg::parts`] lists it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CsgPart {
    /// A solid, and when it is placed its world-to-local map and the columns of its normal
    /// matrix (the inverse transpose of the local-to-world linear part).
    Leaf(Solid, Option<(glam::Affine3A, [Vec3; 3])>),
    /// An operator on the two results before it.
    Op(CsgOp),
}

/// A validated CSG tree: one bounded primitive.
#[derive(Clone, Debug, PartialEq)]
pub struct Csg {
    tree: Tree,
    leaves: u32,
    bounds: Aabb,
}

impl Csg {
    /// Validates `root` and computes its bounding box: leaves' boxes, joined by unions,
    /// overlapped by intersections, and a difference's first operand's.
    ///
    /// # Errors
    /// A parameter that is not finite or out of range, a tree deeper than
    /// [`crate::limits::MAX_CSG_DEPTH`] or with more than [`crate::limits::MAX_CSG_LEAVES`]
    /// leaves, a tree that is not
    /// bounded (a half-space not cut by an intersection) or whose box is empty.
    pub fn new(root: &CsgNode) -> Result<Self, SceneError> {
        let (tree, bound, leaves) = Tree::build::<_, CsgBuilder>(root, &tree::LIMITS)?;
        let Some(b) = bound else {
            return Err(SceneError::Invalid(
                "the CSG tree is unbounded (a half-space must be cut by an intersection \
                 or be subtracted)"
                    .into(),
            ));
        };
        if b.is_empty() || (b.max - b.min).min_element() < 0.0 {
            return Err(SceneError::Invalid(
                "the CSG tree is empty (the boxes of its intersected operands do not overlap)"
                    .into(),
            ));
        }
        // Padding as the sphere's: grazing hits can be computed slightly outside a leaf.
        let pad = Vec3::splat((b.max - b.min).max_element() / 2048.0);
        Ok(Self {
            tree,
            leaves,
            bounds: Aabb::new(b.min - pad, b.max + pad),
        })
    }

    /// The bounding box (padded by `2^-11` of its largest extent).
    #[inline]
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The first boundary of the combined solid inside `[ray.t_min, ray.t_max]`; the
    /// sub-primitive id is the index of the leaf hit (in the order leaves appear left to
    /// right in the tree), and [`Csg::normal`] gives the normal there.
    ///
    /// Rays that miss the tree's box miss without evaluating it: accelerators never test
    /// them, and far from the box the leaves' arithmetic overflows (an origin at `x = 1e30`
    /// made a cone's quadratic report a hit).
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        self.first_end(ray).map(|e| PrimHit {
            t: e.t,
            sub: e.leaf,
            u: 0.0,
            v: 0.0,
        })
    }

    /// The outward unit normal of the combined solid at `hit`, a hit of `ray` found by
    /// [`Csg::intersect`] (a subtracted solid's boundary has its normal negated); `Y` if
    /// the boundary is not found again.
    ///
    /// The tree is evaluated again for the ray clipped to the hit: once per closest hit,
    /// and deterministic, so it finds the same boundary.
    #[must_use]
    pub fn normal(&self, ray: &Ray, hit: &PrimHit) -> Vec3 {
        self.first_end(&ray.clipped(hit.t))
            .map_or(Vec3::Y, |e| e.normal)
    }

    /// Bytes held behind the primitive's `Arc`.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>() + self.tree.memory_bytes()
    }

    /// Number of leaves.
    #[inline]
    #[must_use]
    pub fn leaf_count(&self) -> u32 {
        self.leaves
    }

    /// The validated tree in evaluation order, for backends that evaluate it themselves (the
    /// GPU kernels): post-order, so each operator applies to the two results before it (the
    /// first operand's first) and leaves come in the order of their ids.
    #[must_use]
    pub fn parts(&self) -> Vec<CsgPart> {
        (0..self.tree.len())
            .map(|i| match self.tree.node(i) {
                Node::Leaf((s, place)) => CsgPart::Leaf(
                    *s,
                    place.map(|p| {
                        (
                            p.to_local,
                            [p.normal.x_axis, p.normal.y_axis, p.normal.z_axis].map(Vec3::from),
                        )
                    }),
                ),
                Node::Op(op, _, _) => CsgPart::Op(*op),
                Node::Wrap(never, _) => match *never {},
            })
            .collect()
    }

    /// The first span end inside `[ray.t_min, ray.t_max]`.
    fn first_end(&self, ray: &Ray) -> Option<End> {
        self.bounds.intersect(ray, ray.t_max)?;
        let mut leaf = 0;
        let spans = self.spans(self.tree.root(), ray, &mut leaf);
        for s in spans.as_slice() {
            for e in [s.enter, s.exit] {
                if e.t > ray.t_max {
                    return None;
                }
                if e.t >= ray.t_min && e.t.is_finite() {
                    return Some(e);
                }
            }
        }
        None
    }

    /// The spans of node `i` on the ray's whole line; `leaf` counts leaves in post-order.
    /// Leaves (at most two spans) allocate nothing; each operator one list.
    fn spans(&self, i: usize, ray: &Ray, leaf: &mut u32) -> Spans {
        match self.tree.node(i) {
            Node::Leaf((s, place)) => {
                let id = *leaf;
                *leaf += 1;
                Spans::Leaf(placement::leaf_spans(s, place.as_ref(), ray, id))
            }
            Node::Op(op, a, b) => {
                let sa = self.spans(*a, ray, leaf);
                let sb = self.spans(*b, ray, leaf);
                Spans::Many(spans::combine(*op, sa.as_slice(), sb.as_slice()))
            }
            Node::Wrap(never, _) => match *never {},
        }
    }
}
