//! Signed-distance-field models intersected by sphere tracing (Hart, "Sphere tracing: a
//! geometric method for the antialiased ray tracing of implicit surfaces", 1996).
//!
//! A model is a tree of distance primitives (sphere, box with optional rounding, torus,
//! capsule, capped cylinder) combined by union (`min`), intersection (`max`), subtraction
//! (`max(a, -b)`), smooth union (polynomial smooth minimum, radius `k`) and blend (`(1 - w) a +
//! w b`), with per-node similarity transforms (translate, rotate, uniform scale).
//!
//! **Lipschitz bound.** Every primitive's function is its exact signed distance, so 1-Lipschitz.
//! `min`, `max` and negation keep the larger of their operands' bounds. A transform node
//! evaluates `s * f(M^-1 p)` for a rotation-and-translation `M` and scale `s`: `M^-1` scales
//! lengths by `1 / s`, the factor `s` undoes it, the bound is kept. The polynomial smooth
//! minimum `smin(a, b) = min(a, b) - h^2 k / 4`, `h = max(k - |a - b|, 0) / k`, has partial
//! derivatives `1 - l` and `l` with `l = (k - |a - b|) / 2k` in `[0, 1]` inside the blend band
//! (and `(1, 0)` or `(0, 1)` outside it): its gradient is a convex combination of the
//! operands' gradients, so it keeps `max(L_a, L_b)`; a blend `(1 - w) a + w b` has
//! `(1 - w) L_a + w L_b <= max(L_a, L_b)`. [`Sdf::lipschitz`] is computed by these rules per
//! node (it comes to 1 for every tree the format can express) and checked numerically in the
//! tests. Non-uniform scale would break the bound (a stretched distance over-estimates in
//! the stretched direction) and is refused.
//!
//! **Marching rules** (tested in `tests.rs` and in `tests/tests/sdf.rs`):
//! - The march runs only inside the model's padded bounding box: the slab interval clipped
//!   to `[ray.t_min, ray.t_max]`, starting at its entry (which does not depend on `t_max`,
//!   so every backend sees the same steps and the same `t`). The box holds every point
//!   where `f < 2 eps` (the derivation is at `Bound`; tested by sampling).
//! - Each step advances by `|f| / (L |dir|)`. A hit is accepted where `|f| < eps`; `eps` is
//!   the *hit tolerance*, [`SdfParams::tolerance`] times the diagonal of the model's box
//!   (but at least `2^-17` of its largest coordinate, about 64 ulps of f32).
//! - After [`SdfParams::max_steps`] evaluations without a hit the ray *misses* (grazing
//!   rays near the silhouette are the ones that run out).
//! - **Self-intersection rule**: a ray that starts within `eps` of the surface (a secondary
//!   ray leaving it) first advances in fixed steps of `eps` (in distance) until `|f| >= eps`,
//!   and accepts no hit before that. Then the side is fixed by the sign of `f`: outside the
//!   march follows `f` and stops at the surface ahead; inside (refraction) it follows `-f`
//!   and stops at the exit.
//! - Normals are the gradient by the tetrahedron technique with step `eps`, normalised;
//!   the gradient of a signed distance points out of the model.
//!
//! **Files.** This module holds the validated model ([`Sdf`]) and its march; `primitive.rs`,
//! the leaf the others call down to, the parts scene files describe ([`SdfPrimitive`],
//! [`SdfOp`], [`SdfNode`]) with their checks, boxes and distances; `build.rs` the validation
//! of a scene's tree into the model's (transform nodes, per-subtree bounds).

mod build;
mod primitive;
#[cfg(test)]
mod tests;

use crate::aabb::Aabb;
use crate::error::SceneError;
use crate::hit::PrimHit;
use crate::limits::{
    MAX_SDF_DEPTH, MAX_SDF_NODES, MAX_SDF_STEPS, MAX_SDF_TOLERANCE, MIN_SDF_TOLERANCE,
};
use crate::optree::{self, Counted, Limits, OpTree};
use crate::ray::Ray;
use build::{Bound, Similarity};
use glam::Vec3;
use primitive::primitive_distance;
pub use primitive::{SdfNode, SdfOp, SdfPrimitive};

/// A node of the validated tree.
type Node = optree::Node<SdfPrimitive, SdfOp, Similarity>;

/// The limits of [`Sdf::new`].
const LIMITS: Limits = Limits {
    what: "the SDF tree",
    depth: MAX_SDF_DEPTH,
    size: MAX_SDF_NODES,
    counted: Counted::Nodes,
};

/// Marching options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SdfParams {
    /// Hit tolerance relative to the diagonal of the model's bounding box, in
    /// `[MIN_SDF_TOLERANCE, MAX_SDF_TOLERANCE]`.
    pub tolerance: f32,
    /// Most field evaluations per ray, in `1..=MAX_SDF_STEPS`; a ray that reaches it misses.
    pub max_steps: u32,
}

impl SdfParams {
    /// The defaults: tolerance `1e-4` of the box diagonal, 256 steps.
    pub const DEFAULT: Self = Self {
        tolerance: 1.0e-4,
        max_steps: 256,
    };
}

impl Default for SdfParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The outcome of one march: the hit distance, if any, and the field evaluations it took.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct March {
    /// Ray parameter of the hit, or `None` for a miss.
    pub t: Option<f32>,
    /// Field evaluations made.
    pub steps: u32,
}

/// A node of a validated model's tree as [`Sdf::node`] shows it to backends that evaluate
/// the tree themselves (the GPU's flat programs); nodes are in post-order, operands before
/// the node, the root last ([`Sdf::node_count`] `- 1`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SdfNodeView {
    /// A primitive.
    Leaf(SdfPrimitive),
    /// `op.apply(f_a(p), f_b(p))` on the nodes at indices `a` and `b`.
    Op(SdfOp, usize, usize),
    /// `scale * f_child(q)` with `q = linear[0] p.x + linear[1] p.y + linear[2] p.z +
    /// translation`, summed in that order (the inverse of the node's similarity).
    Transform {
        /// Columns of the inverse map's linear part.
        linear: [Vec3; 3],
        /// The inverse map's translation.
        translation: Vec3,
        /// The similarity's uniform scale.
        scale: f32,
        /// Index of the transformed subtree's root.
        child: usize,
    },
}

/// A validated signed-distance model: one bounded primitive.
#[derive(Clone, Debug, PartialEq)]
pub struct Sdf {
    tree: OpTree<SdfPrimitive, SdfOp, Similarity>,
    bounds: Aabb,
    lipschitz: f32,
    eps: f32,
    max_steps: u32,
}

impl Sdf {
    /// Validates `root` and `params`, and computes the bounding box, the Lipschitz bound and
    /// the absolute hit tolerance.
    ///
    /// # Errors
    /// A parameter that is not finite or out of range, a transform that is not a
    /// similarity (non-uniform scale, shear, mirror), a tree deeper than [`MAX_SDF_DEPTH`] or
    /// with more than [`MAX_SDF_NODES`] nodes, or an empty model.
    pub fn new(root: &SdfNode, params: SdfParams) -> Result<Self, SceneError> {
        if !params.tolerance.is_finite() {
            return Err(SceneError::NonFinite("SDF tolerance".into()));
        }
        if !(MIN_SDF_TOLERANCE..=MAX_SDF_TOLERANCE).contains(&params.tolerance) {
            return Err(SceneError::Invalid(format!(
                "SDF tolerance must lie in [{MIN_SDF_TOLERANCE:e}, {MAX_SDF_TOLERANCE:e}] \
                 (relative to the model's box diagonal), found {}",
                params.tolerance
            )));
        }
        if !(1..=MAX_SDF_STEPS).contains(&params.max_steps) {
            return Err(SceneError::Invalid(format!(
                "SDF max_steps must lie in 1..={MAX_SDF_STEPS}, found {}",
                params.max_steps
            )));
        }
        let (
            tree,
            Bound {
                aabb: b,
                lipschitz,
                spread,
            },
            _,
        ) = OpTree::build::<_, Self>(root, &LIMITS)?;
        if b.is_empty() || (b.max - b.min).min_element() < 0.0 {
            return Err(SceneError::Invalid(
                "the SDF model is empty (the boxes of its intersected operands do not overlap)"
                    .into(),
            ));
        }
        let diagonal = (b.max - b.min).length();
        let magnitude = b.min.abs().max(b.max.abs()).max_element();
        let eps = (params.tolerance * diagonal).max(magnitude * (1.0 / 131_072.0));
        // The surface lies inside the unpadded box; the padding keeps the march's first
        // point off it (at least `2 eps` away) and covers rounding.
        let pad = Vec3::splat(2.0 * eps * spread + (b.max - b.min).max_element() / 2048.0);
        Ok(Self {
            tree,
            bounds: Aabb::new(b.min - pad, b.max + pad),
            lipschitz,
            eps,
            max_steps: params.max_steps,
        })
    }

    /// The Lipschitz bound `L` of the whole field: `|f(x) - f(y)| <= L |x - y|`.
    #[inline]
    #[must_use]
    pub fn lipschitz(&self) -> f32 {
        self.lipschitz
    }

    /// The absolute hit tolerance `eps` (world units).
    #[inline]
    #[must_use]
    pub fn tolerance(&self) -> f32 {
        self.eps
    }

    /// The step limit.
    #[inline]
    #[must_use]
    pub fn max_steps(&self) -> u32 {
        self.max_steps
    }

    /// Number of tree nodes.
    #[inline]
    #[must_use]
    pub fn node_count(&self) -> usize {
        self.tree.len()
    }

    /// The bounding box (padded by `2 eps` plus `2^-11` of its largest extent).
    #[inline]
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Node `i` of the tree (`i < node_count()`, the root last): see [`SdfNodeView`].
    ///
    /// # Panics
    /// When `i` is out of range.
    #[must_use]
    pub fn node(&self, i: usize) -> SdfNodeView {
        match self.tree.node(i) {
            Node::Leaf(s) => SdfNodeView::Leaf(*s),
            Node::Op(op, a, b) => SdfNodeView::Op(*op, *a, *b),
            Node::Wrap(m, child) => SdfNodeView::Transform {
                linear: [m.linear.x_axis, m.linear.y_axis, m.linear.z_axis].map(Vec3::from),
                translation: m.translation,
                scale: m.scale,
                child: *child,
            },
        }
    }

    /// Bytes held behind the primitive's `Arc`.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>() + self.tree.memory_bytes()
    }

    /// The field's value at `p`: negative inside the model.
    #[inline]
    #[must_use]
    pub fn distance(&self, p: Vec3) -> f32 {
        self.eval(self.tree.root(), p)
    }

    fn eval(&self, i: usize, p: Vec3) -> f32 {
        match self.tree.node(i) {
            Node::Leaf(s) => primitive_distance(s, p),
            Node::Op(op, a, b) => op.apply(self.eval(*a, p), self.eval(*b, p)),
            Node::Wrap(m, child) => m.scale * self.eval(*child, m.local(p)),
        }
    }

    /// The ray's first surface point inside `[ray.t_min, ray.t_max]` under the marching rules
    /// of the module documentation.
    #[inline]
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        self.march(ray).t.map(PrimHit::at)
    }

    /// [`Sdf::intersect`] with the number of field evaluations it made.
    #[must_use]
    pub fn march(&self, ray: &Ray) -> March {
        let mut steps = 0;
        let Some((t0, t1)) = self.clip(ray) else {
            return March { t: None, steps };
        };
        // `1 / (L |dir|)`: a step of `|f| * per_unit` in t moves `|f| / L` in space. (Each
        // step waits on the last: the march is latency-bound: tens of ns a step.)
        let per_unit = 1.0 / (ray.dir.length() * self.lipschitz);
        let eps = self.eps;
        let leave = eps * per_unit;
        let mut t = t0;
        // 0 while leaving the surface band, then the sign of f on the ray's side.
        let mut side = 0.0f32;
        while steps < self.max_steps {
            steps += 1;
            let f = self.distance(ray.at(t));
            if side == 0.0 && f.abs() >= eps {
                side = f.signum();
            }
            if side == 0.0 {
                t += leave;
            } else {
                let g = side * f;
                if g < eps {
                    return March { t: Some(t), steps };
                }
                t += g * per_unit;
            }
            if t > t1 || t.is_nan() {
                break;
            }
        }
        March { t: None, steps }
    }

    /// The ray's interval inside the padded box, clipped to `[t_min, t_max]`.
    fn clip(&self, ray: &Ray) -> Option<(f32, f32)> {
        if !ray.is_valid() {
            return None;
        }
        let (mut t0, mut t1) = (ray.t_min, ray.t_max);
        for axis in 0..3 {
            let (o, d) = (ray.origin[axis], ray.dir[axis]);
            let (lo, hi) = (self.bounds.min[axis], self.bounds.max[axis]);
            if d == 0.0 {
                if !(o >= lo && o <= hi) {
                    return None;
                }
                continue;
            }
            let (a, b) = ((lo - o) / d, (hi - o) / d);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
        (t0 <= t1).then_some((t0, t1))
    }

    /// The outward unit normal at `p`: the field's gradient by the tetrahedron technique
    /// (four evaluations at `p + eps * k_i`), normalised; `Y` where it vanishes.
    #[must_use]
    pub fn normal(&self, p: Vec3) -> Vec3 {
        const K: [Vec3; 4] = [
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(1.0, 1.0, 1.0),
        ];
        K.iter()
            .map(|&k| k * self.distance(p + k * self.eps))
            .sum::<Vec3>()
            .normalize_or(Vec3::Y)
    }
}
