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
//! **Marching rules** (tested below and in `tests/tests/sdf.rs`):
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

use crate::aabb::Aabb;
use crate::checks;
use crate::error::SceneError;
use crate::hit::PrimHit;
use crate::limits::{
    MAX_COORDINATE, MAX_SDF_DEPTH, MAX_SDF_NODES, MAX_SDF_STEPS, MAX_SDF_TOLERANCE,
    MIN_SDF_TOLERANCE,
};
use crate::optree::{self, Builder, Counted, Limits, OpTree, Operator, Source, View};
use crate::ray::Ray;
use glam::{Affine3A, Mat3A, Vec2, Vec3, Vec3A};

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

/// A distance tree as scene files describe it; [`Sdf::new`] validates it.
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

/// What a transform node of the validated tree stores: it evaluates `scale * f(M^-1 p)`.
/// The inverse map is kept as its linear part and translation so that the node stays 80
/// bytes; [`Similarity::local`] applies it as `Affine3A::transform_point3` does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Similarity {
    linear: Mat3A,
    translation: Vec3,
    scale: f32,
}

impl Similarity {
    /// `M^-1 p`, with the operations of `Affine3A::transform_point3` in its order.
    #[inline]
    fn local(&self, p: Vec3) -> Vec3 {
        ((self.linear.x_axis * p.x)
            + (self.linear.y_axis * p.y)
            + (self.linear.z_axis * p.z)
            + Vec3A::from(self.translation))
        .into()
    }
}

/// A node of the validated tree.
type Node = optree::Node<SdfPrimitive, SdfOp, Similarity>;

/// The limits of [`Sdf::new`].
const LIMITS: Limits = Limits {
    what: "the SDF tree",
    depth: MAX_SDF_DEPTH,
    size: MAX_SDF_NODES,
    counted: Counted::Nodes,
};

/// What [`Sdf::new`] derives for a subtree: its box, its Lipschitz bound, and its *spread*
/// `g`: `{p : f(p) <= c}` lies within `g c` of the box on every axis, for every `c >= 0`
/// (the box bounds more than the surface: smooth unions and the padding need the sets where
/// `f` is small). Primitives are exact distances (`g = 1`); `min`, `max`, subtraction and
/// blends keep the larger `g` (boxes overlap and join per axis, and a blend is small only
/// where an operand is); a rotation widens it by the largest row sum of `|R|`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Bound {
    aabb: Aabb,
    lipschitz: f32,
    spread: f32,
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

    /// The bounding box (padded by `2 eps` plus `2^-11` of its largest extent).
    #[inline]
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.bounds
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

/// Checks a primitive's parameters.
fn validate(p: &SdfPrimitive) -> Result<(), SceneError> {
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
fn validate_op(op: SdfOp) -> Result<(), SceneError> {
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

/// A primitive's bounding box.
fn primitive_bounds(p: &SdfPrimitive) -> Aabb {
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
fn primitive_distance(s: &SdfPrimitive, p: Vec3) -> f32 {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(c: Vec3, r: f32) -> SdfNode {
        SdfNode::Leaf(SdfPrimitive::Sphere {
            center: c,
            radius: r,
        })
    }

    fn cube(c: Vec3, h: f32) -> SdfNode {
        SdfNode::Leaf(SdfPrimitive::Box {
            center: c,
            half_extents: Vec3::splat(h),
            rounding: 0.0,
        })
    }

    fn op(op: SdfOp, a: SdfNode, b: SdfNode) -> SdfNode {
        SdfNode::Op(op, Box::new(a), Box::new(b))
    }

    fn model(tree: &SdfNode) -> Sdf {
        Sdf::new(tree, SdfParams::DEFAULT).unwrap()
    }

    /// A tree with every primitive, operation and a transform.
    fn everything() -> SdfNode {
        let torus = SdfNode::Leaf(SdfPrimitive::Torus {
            center: Vec3::new(0.5, 0.0, 0.0),
            major_radius: 0.6,
            minor_radius: 0.2,
        });
        let capsule = SdfNode::Leaf(SdfPrimitive::Capsule {
            a: Vec3::new(-1.0, 0.0, 0.0),
            b: Vec3::new(-0.2, 0.8, 0.1),
            radius: 0.25,
        });
        let cylinder = SdfNode::Leaf(SdfPrimitive::Cylinder {
            center: Vec3::new(0.0, -0.5, 0.3),
            radius: 0.3,
            half_height: 0.4,
        });
        let rounded = SdfNode::Leaf(SdfPrimitive::Box {
            center: Vec3::new(0.2, 0.3, -0.4),
            half_extents: Vec3::new(0.5, 0.3, 0.4),
            rounding: 0.1,
        });
        let turned = SdfNode::Transform(
            Affine3A::from_scale_rotation_translation(
                Vec3::splat(1.7),
                glam::Quat::from_rotation_y(0.6) * glam::Quat::from_rotation_x(0.3),
                Vec3::new(0.1, 0.2, 0.3),
            ),
            Box::new(op(SdfOp::Blend(0.3), rounded, sphere(Vec3::ZERO, 0.5))),
        );
        op(
            SdfOp::SmoothUnion(0.3),
            op(SdfOp::Union, torus, capsule),
            op(
                SdfOp::Subtraction,
                op(SdfOp::Intersection, turned, cube(Vec3::ZERO, 0.9)),
                cylinder,
            ),
        )
    }

    /// Deterministic points in `[-s, s]^3` (a Weyl sequence).
    fn points(n: usize, s: f32) -> impl Iterator<Item = Vec3> {
        let a = [0.754_877_7_f64, 0.569_840_3, 0.430_159_7];
        (1..=n).map(move |i| {
            let c = |k: usize| ((i as f64 * a[k]).fract() * 2.0 - 1.0) as f32 * s;
            Vec3::new(c(0), c(1), c(2))
        })
    }

    #[test]
    fn primitives_are_exact_distances() {
        let d = |s: SdfPrimitive, p: Vec3| primitive_distance(&s, p);
        let c = Vec3::new(1.0, 2.0, 3.0);
        assert_eq!(
            d(
                SdfPrimitive::Sphere {
                    center: c,
                    radius: 1.0
                },
                c + Vec3::new(0.0, 3.0, 0.0)
            ),
            2.0
        );
        let b = SdfPrimitive::Box {
            center: Vec3::ZERO,
            half_extents: Vec3::new(1.0, 2.0, 3.0),
            rounding: 0.5,
        };
        assert_eq!(d(b, Vec3::new(3.0, 0.0, 0.0)), 2.0);
        assert_eq!(d(b, Vec3::ZERO), -1.0);
        // The rounded corner: distance to the sphere of radius 0.5 around (0.5, 1.5, 2.5).
        let corner = Vec3::new(0.5, 1.5, 2.5);
        assert!((d(b, corner + Vec3::ONE) - (3f32.sqrt() - 0.5)).abs() < 1e-6);
        let t = SdfPrimitive::Torus {
            center: Vec3::ZERO,
            major_radius: 2.0,
            minor_radius: 0.5,
        };
        assert_eq!(d(t, Vec3::new(2.0, 1.5, 0.0)), 1.0);
        assert_eq!(d(t, Vec3::ZERO), 1.5);
        let cap = SdfPrimitive::Capsule {
            a: Vec3::ZERO,
            b: Vec3::Y,
            radius: 0.5,
        };
        assert_eq!(d(cap, Vec3::new(2.0, 0.5, 0.0)), 1.5);
        assert_eq!(d(cap, Vec3::new(0.0, 3.0, 0.0)), 1.5);
        let cyl = SdfPrimitive::Cylinder {
            center: Vec3::ZERO,
            radius: 1.0,
            half_height: 2.0,
        };
        assert_eq!(d(cyl, Vec3::new(0.0, 5.0, 0.0)), 3.0);
        assert_eq!(d(cyl, Vec3::new(4.0, 6.0, 0.0)), 5.0);
        assert_eq!(d(cyl, Vec3::new(0.5, 0.0, 0.0)), -0.5);
    }

    #[test]
    fn operations_follow_their_formulas() {
        assert_eq!(SdfOp::Union.apply(1.0, -2.0), -2.0);
        assert_eq!(SdfOp::Intersection.apply(1.0, -2.0), 1.0);
        assert_eq!(SdfOp::Subtraction.apply(-1.0, -2.0), 2.0);
        assert_eq!(SdfOp::Blend(0.25).apply(1.0, -3.0), 0.0);
        // Smooth union: equal operands lose k / 4; beyond k apart it is the minimum.
        assert_eq!(SdfOp::SmoothUnion(0.4).apply(1.0, 1.0), 0.9);
        assert_eq!(SdfOp::SmoothUnion(0.4).apply(1.0, 1.5), 1.0);
    }

    /// `|f(x) - f(y)| <= L |x - y|` over point pairs at several scales, on a tree with every
    /// primitive and operation and a rotated, scaled transform.
    #[test]
    fn lipschitz_bound_holds_numerically() {
        let m = model(&everything());
        assert_eq!(m.lipschitz(), 1.0);
        let mut worst = 0.0f32;
        for (i, x) in points(20_000, 2.5).enumerate() {
            for (j, r) in [1.0f32, 0.1, 0.01].into_iter().enumerate() {
                let y = x + points(i * 3 + j + 7, r).last().unwrap();
                let dist = (x - y).length();
                if dist < 1e-3 {
                    continue;
                }
                let ratio = (m.distance(x) - m.distance(y)).abs() / dist;
                worst = worst.max(ratio);
            }
        }
        // f32 rounding of values near 2 over distances above 1e-3: below 1e-3 relative.
        assert!(worst <= m.lipschitz() * 1.001, "worst ratio {worst}");
        // Not vacuous: somewhere the bound is nearly attained.
        assert!(worst > 0.9, "worst ratio {worst}");
    }

    /// Every sampled point where the field is below `2 eps` lies in the padded box, for a
    /// smooth union whose operands are a rotated intersection (not an exact distance) and a
    /// subtraction: the spread rule at work.
    #[test]
    fn the_box_holds_the_surface() {
        let wedge = SdfNode::Transform(
            Affine3A::from_rotation_z(0.7),
            Box::new(op(
                SdfOp::Intersection,
                cube(Vec3::new(0.9, 0.0, 0.0), 1.0),
                cube(Vec3::new(-0.9, 0.3, 0.0), 1.0),
            )),
        );
        let carved = op(
            SdfOp::Subtraction,
            cube(Vec3::new(0.0, 1.2, 0.0), 0.4),
            sphere(Vec3::new(0.0, 1.6, 0.0), 0.3),
        );
        for tree in [op(SdfOp::SmoothUnion(1.5), wedge, carved), everything()] {
            let m = model(&tree);
            let b = m.bounds();
            let mut inside = 0;
            for p in points(200_000, 4.0) {
                if m.distance(p) < 2.0 * m.tolerance() {
                    inside += 1;
                    assert!(
                        p.cmpge(b.min).all() && p.cmple(b.max).all(),
                        "{p} outside {b:?}"
                    );
                }
            }
            assert!(inside > 1000, "{inside}");
        }
    }

    #[test]
    fn sphere_hits_within_tolerance_and_normals_point_out() {
        let m = model(&sphere(Vec3::ZERO, 1.0));
        let eps = m.tolerance();
        assert!((eps - 1e-4 * 12f32.sqrt()).abs() < 1e-9, "{eps}");
        // Head-on: exact distances converge in one step.
        let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        let t = m.intersect(&r).map(|h| h.t).unwrap();
        assert!((t - 4.0).abs() <= eps, "{t}");
        assert!((m.normal(r.at(t)) - -Vec3::Z).length() < 1e-3);
        // From inside: the exit, normal still outward.
        let r = Ray::new(Vec3::ZERO, Vec3::X);
        let t = m.intersect(&r).map(|h| h.t).unwrap();
        assert!((t - 1.0).abs() <= eps, "{t}");
        assert!((m.normal(r.at(t)) - Vec3::X).length() < 1e-3);
        // Miss, and clipped by t_max.
        assert_eq!(
            m.intersect(&Ray::new(Vec3::new(0.0, 2.0, -5.0), Vec3::Z))
                .map(|h| h.t),
            None
        );
        let r = Ray::with_interval(Vec3::new(0.0, 0.0, -5.0), Vec3::Z, 0.0, 3.9);
        assert_eq!(m.intersect(&r).map(|h| h.t), None);
        // Unnormalised directions give the same point.
        let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z * 4.0);
        assert!((m.intersect(&r).map(|h| h.t).unwrap() - 1.0).abs() <= eps / 4.0);
    }

    /// A ray leaving the surface (reflection outward, refraction inward) does not re-hit it:
    /// it finds the far side, or nothing.
    #[test]
    fn rays_leaving_the_surface_do_not_rehit_it() {
        let m = model(&sphere(Vec3::ZERO, 1.0));
        let eps = m.tolerance();
        for offset in [-0.9 * eps, -0.3 * eps, 0.0, 0.3 * eps, 0.9 * eps] {
            let p = Vec3::new(0.0, 0.0, -1.0 - offset);
            // Outward: nothing else to hit.
            assert_eq!(
                m.intersect(&Ray::new(p, -Vec3::Z)).map(|h| h.t),
                None,
                "{offset}"
            );
            // Outward at a slant.
            assert_eq!(
                m.intersect(&Ray::new(p, Vec3::new(0.3, 0.0, -1.0)))
                    .map(|h| h.t),
                None
            );
            // Inward: the far side at t = 2.
            let t = m.intersect(&Ray::new(p, Vec3::Z)).map(|h| h.t).unwrap();
            assert!((t - 2.0).abs() <= 2.0 * eps, "{offset}: {t}");
        }
    }

    #[test]
    fn the_step_limit_makes_a_miss() {
        let tree = sphere(Vec3::ZERO, 1.0);
        let r = Ray::new(Vec3::new(0.0, 0.999, -5.0), Vec3::Z);
        let full = model(&tree).march(&r);
        assert!(full.t.is_some() && full.steps > 3, "{full:?}");
        let params = SdfParams {
            max_steps: full.steps - 1,
            ..SdfParams::DEFAULT
        };
        let short = Sdf::new(&tree, params).unwrap().march(&r);
        assert_eq!(
            short,
            March {
                t: None,
                steps: full.steps - 1
            }
        );
    }

    #[test]
    fn smooth_union_and_blend_change_the_surface_as_stated() {
        let a = sphere(Vec3::new(-1.0, 0.0, 0.0), 1.0);
        let b = sphere(Vec3::new(1.0, 0.0, 0.0), 1.0);
        // Between two touching balls the smooth union fills the gap by k / 4 at the middle
        // (both distances are 0 at the origin): the surface is at distance k/4 - ... along y.
        let m = model(&op(SdfOp::SmoothUnion(0.8), a.clone(), b.clone()));
        assert!((m.distance(Vec3::ZERO) + 0.2).abs() < 1e-6);
        let t = m
            .intersect(&Ray::new(Vec3::new(0.0, 5.0, 0.0), -Vec3::Y))
            .map(|h| h.t)
            .unwrap();
        assert!(t < 5.0 - 0.1, "the neck is filled: {t}");
        // A blend halfway between a ball and a box of the same centre.
        let m = model(&op(
            SdfOp::Blend(0.5),
            sphere(Vec3::ZERO, 1.0),
            cube(Vec3::ZERO, 1.0),
        ));
        assert!((m.distance(Vec3::new(2.0, 0.0, 0.0)) - 1.0).abs() < 1e-6);
        let diag = Vec3::ONE.normalize();
        let t = m
            .intersect(&Ray::new(diag * 5.0, -diag))
            .map(|h| h.t)
            .unwrap();
        // The surface on the diagonal is between the ball's (1) and the box's (sqrt 3).
        assert!((5.0 - t) > 1.05 && (5.0 - t) < 3f32.sqrt() - 0.05, "{t}");
    }

    #[test]
    fn transforms_scale_distances() {
        let m = model(&SdfNode::Transform(
            Affine3A::from_scale_rotation_translation(
                Vec3::splat(2.0),
                glam::Quat::from_rotation_z(0.5),
                Vec3::new(3.0, 0.0, 0.0),
            ),
            Box::new(sphere(Vec3::ZERO, 1.0)),
        ));
        assert!((m.distance(Vec3::new(3.0, 5.0, 0.0)) - 3.0).abs() < 1e-6);
        assert!((m.distance(Vec3::new(3.0, 0.0, 0.0)) + 2.0).abs() < 1e-6);
    }

    #[test]
    fn bad_models_are_refused() {
        let s = sphere(Vec3::ZERO, 1.0);
        let err = |tree: &SdfNode| Sdf::new(tree, SdfParams::DEFAULT).unwrap_err().to_string();
        assert!(SdfNode::fold(SdfOp::Union, vec![s.clone()]).is_err());
        assert!(SdfNode::fold(SdfOp::Blend(0.5), vec![s.clone(), s.clone(), s.clone()]).is_err());
        assert!(err(&sphere(Vec3::ZERO, -1.0)).contains("radius must be positive"));
        assert!(err(&sphere(Vec3::new(f32::NAN, 0.0, 0.0), 1.0)).contains("not finite"));
        let smooth = |k| op(SdfOp::SmoothUnion(k), s.clone(), s.clone());
        assert!(err(&smooth(0.0)).contains("k must be positive"));
        assert!(err(&smooth(f32::INFINITY)).contains("not finite"));
        let blend = |w| op(SdfOp::Blend(w), s.clone(), s.clone());
        assert!(err(&blend(1.5)).contains("w must lie in [0, 1]"));
        assert!(err(&blend(f32::NAN)).contains("not finite"));
        let stretched = SdfNode::Transform(
            Affine3A::from_scale(Vec3::new(1.0, 2.0, 1.0)),
            Box::new(s.clone()),
        );
        assert!(err(&stretched).contains("non-uniform scale"));
        let rounded = SdfNode::Leaf(SdfPrimitive::Box {
            center: Vec3::ZERO,
            half_extents: Vec3::ONE,
            rounding: 2.0,
        });
        assert!(err(&rounded).contains("rounding must lie in"));
        let disjoint = op(
            SdfOp::Intersection,
            s.clone(),
            sphere(Vec3::new(5.0, 0.0, 0.0), 1.0),
        );
        assert!(err(&disjoint).contains("empty"));
        let mut deep = s.clone();
        for _ in 0..MAX_SDF_DEPTH {
            deep = op(SdfOp::Union, deep, s.clone());
        }
        assert!(err(&deep).contains("deeper than"));
        let many = SdfNode::fold(SdfOp::Union, vec![s.clone(); MAX_SDF_NODES]).unwrap();
        assert!(err(&many).contains("more than"));
        for (tolerance, max_steps) in [(0.0, 10), (f32::NAN, 10), (1e-4, 0), (1e-4, 1 << 20)] {
            let params = SdfParams {
                tolerance,
                max_steps,
            };
            assert!(Sdf::new(&s, params).is_err(), "{params:?}");
        }
    }

    #[test]
    fn nan_and_zero_rays_miss() {
        let m = model(&everything());
        for r in [
            Ray::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X),
            Ray::new(Vec3::new(-5.0, 0.0, 0.0), Vec3::new(f32::NAN, 0.0, 0.0)),
            Ray::new(Vec3::new(-5.0, 0.0, 0.0), Vec3::ZERO),
        ] {
            assert_eq!(m.intersect(&r).map(|h| h.t), None);
        }
    }
}
