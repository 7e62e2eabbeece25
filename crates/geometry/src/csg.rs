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
use crate::checks;
use crate::error::SceneError;
use crate::limits::{MAX_CSG_DEPTH, MAX_CSG_LEAVES};
use crate::ray::Ray;
use glam::{Affine3A, Mat3A, Vec3};

mod quartic;

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
    fn apply(self, a: bool, b: bool) -> bool {
        match self {
            Self::Union => a || b,
            Self::Intersection => a && b,
            Self::Difference => a && !b,
        }
    }
}

/// An analytic solid, a leaf of a CSG tree. Cylinders and cones stand on the `y` axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Solid {
    /// A ball.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius (positive).
        radius: f32,
    },
    /// An axis-aligned box.
    Box {
        /// Smallest corner.
        min: Vec3,
        /// Largest corner (each coordinate larger than `min`'s).
        max: Vec3,
    },
    /// A capped cylinder from `base` up to `base + height * Y`.
    Cylinder {
        /// Centre of the bottom cap.
        base: Vec3,
        /// Radius (positive).
        radius: f32,
        /// Height (positive).
        height: f32,
    },
    /// A capped cone with its base disc at `base` and its apex at `base + height * Y`.
    Cone {
        /// Centre of the base disc.
        base: Vec3,
        /// Radius of the base disc (positive).
        radius: f32,
        /// Height (positive).
        height: f32,
    },
    /// The half-space `dot(p - point, normal) <= 0` (unbounded: only usable where an
    /// intersection or a difference bounds it).
    HalfSpace {
        /// A point on the boundary plane.
        point: Vec3,
        /// Outward normal (normalised on construction).
        normal: Vec3,
    },
    // Issue 10, tori and quadrics.
    /// An axis-aligned ellipsoid: the unit ball scaled by `radii`, centred at `center` (a
    /// rotated one is a [`CsgNode::Placed`] ellipsoid).
    Ellipsoid {
        /// Centre.
        center: Vec3,
        /// Semi-axis lengths along x, y and z (each positive).
        radii: Vec3,
    },
    /// A torus about the vertical axis through `center`: the points within `minor_radius`
    /// of the circle of `major_radius` in the plane `y = center.y`. The solid is where
    /// `(|p|^2 + R^2 - r^2)^2 <= 4 R^2 (x^2 + z^2)` (relative to the centre), so a horn
    /// torus (`r = R`) closes its hole to a point and a spindle torus (`r > R`) is the
    /// outer "apple" with the inner "lemon" where the tube overlaps itself left hollow.
    Torus {
        /// Centre.
        center: Vec3,
        /// Radius `R` of the tube's centre circle (positive).
        major_radius: f32,
        /// Radius `r` of the tube (positive).
        minor_radius: f32,
    },
    /// A capped paraboloid opening upwards from its apex at `base`: the points with
    /// `x^2 + z^2 <= radius^2 (y / height)` (relative to the apex) up to `y = height`, where
    /// a disc of `radius` closes it.
    Paraboloid {
        /// The apex.
        base: Vec3,
        /// Radius of the cap disc (positive).
        radius: f32,
        /// Height of the cap above the apex (positive).
        height: f32,
    },
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

/// One end of a span: where, the outward normal of the combined solid there, and the leaf.
#[derive(Clone, Copy, Debug, PartialEq)]
struct End {
    t: f32,
    normal: Vec3,
    leaf: u32,
}

/// A closed interval of the ray's line inside a solid (`enter.t < exit.t`).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Span {
    enter: End,
    exit: End,
}

/// A node of the validated tree, stored in post-order.
#[derive(Clone, Debug, PartialEq)]
enum Node {
    Leaf(Solid, Option<Placement>),
    Op(CsgOp, usize, usize),
}

/// A placed leaf's maps: world to local for rays, and the normal matrix (the inverse
/// transpose of the local-to-world linear part) for normals.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Placement {
    to_local: Affine3A,
    normal: Mat3A,
}

impl Placement {
    /// Checks `to_world` (finite, not singular, condition number at most
    /// [`crate::limits::MAX_TRANSFORM_CONDITION`]) and inverts it.
    fn new(to_world: Affine3A) -> Result<Self, SceneError> {
        let inv = checks::check_transform(to_world, "CSG transform")?;
        Ok(Self {
            to_local: to_world.inverse(),
            normal: inv.transpose(),
        })
    }

    /// The box of the eight corners of `b` mapped by `to_world`.
    fn bounds(to_world: Affine3A, b: Aabb) -> Aabb {
        Aabb::from_points((0..8).map(|k| {
            let pick = |bit: usize, lo: f32, hi: f32| if k & bit == 0 { lo } else { hi };
            to_world.transform_point3(Vec3::new(
                pick(1, b.min.x, b.max.x),
                pick(2, b.min.y, b.max.y),
                pick(4, b.min.z, b.max.z),
            ))
        }))
    }
}

/// A hit with a CSG tree: distance, the leaf hit and the outward normal there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CsgHit {
    /// Ray parameter.
    pub t: f32,
    /// Index of the leaf (in the order leaves appear left to right in the tree).
    pub leaf: u32,
    /// Outward unit normal of the combined solid.
    pub normal: Vec3,
}

/// A validated CSG tree: one bounded primitive.
#[derive(Clone, Debug, PartialEq)]
pub struct Csg {
    nodes: Vec<Node>,
    leaves: u32,
    bounds: Aabb,
}

/// A bound that may be all of space (`None`).
type Bound = Option<Aabb>;

impl Csg {
    /// Validates `root` and computes its bounding box: leaves' boxes, joined by unions,
    /// overlapped by intersections, and a difference's first operand's.
    ///
    /// # Errors
    /// A parameter that is not finite or out of range, a tree deeper than
    /// [`MAX_CSG_DEPTH`] or with more than [`MAX_CSG_LEAVES`] leaves, a tree that is not
    /// bounded (a half-space not cut by an intersection) or whose box is empty.
    pub fn new(root: &CsgNode) -> Result<Self, SceneError> {
        let mut nodes = Vec::new();
        let mut leaves = 0u32;
        let bound = Self::flatten(root, 1, &mut nodes, &mut leaves)?;
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
            nodes,
            leaves,
            bounds: Aabb::new(b.min - pad, b.max + pad),
        })
    }

    fn flatten(
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
                let ba = Self::flatten(a, depth + 1, nodes, leaves)?;
                let ia = nodes.len() - 1;
                let bb = Self::flatten(b, depth + 1, nodes, leaves)?;
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

    /// The bounding box (padded by `2^-11` of its largest extent).
    #[inline]
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Number of leaves.
    #[inline]
    #[must_use]
    pub fn leaf_count(&self) -> u32 {
        self.leaves
    }

    /// Bytes held behind the primitive's `Arc`.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>() + self.nodes.len() * std::mem::size_of::<Node>()
    }

    /// The first boundary of the combined solid inside `[ray.t_min, ray.t_max]`.
    ///
    /// Rays that miss the tree's box miss without evaluating it: accelerators never test
    /// them, and far from the box the leaves' arithmetic overflows (an origin at `x = 1e30`
    /// made a cone's quadratic report a hit).
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<CsgHit> {
        self.bounds.intersect(ray, ray.t_max)?;
        let mut leaf = 0;
        let spans = self.spans(self.nodes.len() - 1, ray, &mut leaf);
        for s in spans.as_slice() {
            for e in [s.enter, s.exit] {
                if e.t > ray.t_max {
                    return None;
                }
                if e.t >= ray.t_min && e.t.is_finite() {
                    return Some(CsgHit {
                        t: e.t,
                        leaf: e.leaf,
                        normal: e.normal,
                    });
                }
            }
        }
        None
    }

    /// The spans of node `i` on the ray's whole line; `leaf` counts leaves in post-order.
    /// Leaves (at most two spans) allocate nothing; each operator one list.
    fn spans(&self, i: usize, ray: &Ray, leaf: &mut u32) -> Spans {
        match &self.nodes[i] {
            Node::Leaf(s, place) => {
                let id = *leaf;
                *leaf += 1;
                Spans::Leaf(leaf_spans(s, place.as_ref(), ray, id))
            }
            Node::Op(op, a, b) => {
                let sa = self.spans(*a, ray, leaf);
                let sb = self.spans(*b, ray, leaf);
                Spans::Many(combine(*op, sa.as_slice(), sb.as_slice()))
            }
        }
    }
}

/// The spans of a subtree: a leaf's (at most two, inline), or an operator's list.
enum Spans {
    Leaf(LeafSpans),
    Many(Vec<Span>),
}

impl Spans {
    fn as_slice(&self) -> &[Span] {
        match self {
            Self::Leaf(s) => &s.spans[..s.len],
            Self::Many(v) => v,
        }
    }
}

/// Up to two sorted, disjoint spans of one leaf, without a heap allocation.
struct LeafSpans {
    spans: [Span; 2],
    len: usize,
}

impl LeafSpans {
    const NONE: Self = Self {
        spans: [Span {
            enter: End {
                t: f32::NAN,
                normal: Vec3::ZERO,
                leaf: 0,
            },
            exit: End {
                t: f32::NAN,
                normal: Vec3::ZERO,
                leaf: 0,
            },
        }; 2],
        len: 0,
    };

    /// Appends `span` when it has positive length (tangent and NaN spans are dropped).
    fn push(&mut self, span: Span) {
        if let Some(s) = finish(span) {
            self.spans[self.len] = s;
            self.len += 1;
        }
    }
}

/// The spans of a leaf: the ray taken to its local space when it is placed, and its
/// normals brought back.
fn leaf_spans(s: &Solid, place: Option<&Placement>, ray: &Ray, leaf: u32) -> LeafSpans {
    let (o, d) = match place {
        None => (ray.origin, ray.dir),
        Some(p) => (
            p.to_local.transform_point3(ray.origin),
            p.to_local.transform_vector3(ray.dir),
        ),
    };
    let mut out = LeafSpans::NONE;
    if let Solid::Torus {
        center,
        major_radius,
        minor_radius,
    } = *s
    {
        let (hits, n) = quartic::torus(o - center, d, major_radius, minor_radius);
        let end = |(t, n): (f32, glam::DVec3)| End {
            t,
            normal: n.normalize_or(glam::DVec3::Y).as_vec3(),
            leaf,
        };
        for pair in hits[..n].chunks_exact(2) {
            out.push(Span {
                enter: end(pair[0]),
                exit: end(pair[1]),
            });
        }
    } else if let Some(span) = solid_span(s, o, d, leaf) {
        out.push(span);
    }
    if let Some(p) = place {
        for span in &mut out.spans[..out.len] {
            for e in [&mut span.enter, &mut span.exit] {
                e.normal = (p.normal * e.normal).normalize_or(e.normal);
            }
        }
    }
    out
}

/// Checks that a point is finite and within [`crate::limits::MAX_COORDINATE`].
fn finite_point(v: Vec3, what: &str) -> Result<(), SceneError> {
    checks::point(v, &format!("CSG {what}"))
}

/// Checks a solid's parameters and normalises a half-space's normal.
fn validate(s: Solid) -> Result<Solid, SceneError> {
    let finite = finite_point;
    let positive = |x: f32, what: &str| checks::positive(x, &format!("CSG {what}"));
    match s {
        Solid::Sphere { center, radius } => {
            finite(center, "sphere centre")?;
            positive(radius, "sphere radius")?;
        }
        Solid::Box { min, max } => {
            finite(min, "box min")?;
            finite(max, "box max")?;
            if !min.cmplt(max).all() {
                return Err(SceneError::Invalid(format!(
                    "CSG box min {min} must be below max {max} on every axis"
                )));
            }
        }
        Solid::Cylinder {
            base,
            radius,
            height,
        }
        | Solid::Cone {
            base,
            radius,
            height,
        }
        | Solid::Paraboloid {
            base,
            radius,
            height,
        } => {
            let kind = match s {
                Solid::Cylinder { .. } => "cylinder",
                Solid::Cone { .. } => "cone",
                _ => "paraboloid",
            };
            finite(base, &format!("{kind} base"))?;
            positive(radius, &format!("{kind} radius"))?;
            positive(height, &format!("{kind} height"))?;
        }
        Solid::HalfSpace { point, normal } => {
            finite(point, "half-space point")?;
            finite(normal, "half-space normal")?;
            let Some(n) = normal.try_normalize() else {
                return Err(SceneError::Invalid(
                    "CSG half-space normal must not be zero".into(),
                ));
            };
            return Ok(Solid::HalfSpace { point, normal: n });
        }
        Solid::Ellipsoid { center, radii } => {
            finite(center, "ellipsoid centre")?;
            for r in radii.to_array() {
                positive(r, "ellipsoid radius")?;
            }
        }
        Solid::Torus {
            center,
            major_radius,
            minor_radius,
        } => {
            finite(center, "torus centre")?;
            positive(major_radius, "torus major radius")?;
            positive(minor_radius, "torus minor radius")?;
        }
    }
    Ok(s)
}

/// A solid's bounding box (`None`: all of space).
fn solid_bounds(s: &Solid) -> Bound {
    match *s {
        Solid::Sphere { center, radius } => Some(Aabb::new(
            center - Vec3::splat(radius),
            center + Vec3::splat(radius),
        )),
        Solid::Box { min, max } => Some(Aabb::new(min, max)),
        Solid::Cylinder {
            base,
            radius,
            height,
        }
        | Solid::Cone {
            base,
            radius,
            height,
        }
        | Solid::Paraboloid {
            base,
            radius,
            height,
        } => Some(Aabb::new(
            base - Vec3::new(radius, 0.0, radius),
            base + Vec3::new(radius, height, radius),
        )),
        Solid::HalfSpace { .. } => None,
        Solid::Ellipsoid { center, radii } => Some(Aabb::new(center - radii, center + radii)),
        Solid::Torus {
            center,
            major_radius,
            minor_radius,
        } => {
            let e = major_radius + minor_radius;
            Some(Aabb::new(
                center - Vec3::new(e, minor_radius, e),
                center + Vec3::new(e, minor_radius, e),
            ))
        }
    }
}

/// The roots of `a t^2 - 2 b t + c` in ascending order (Haines et al.'s stable form), or
/// `None` when there are none or `a` is zero.
///
/// The quadric solids compute their coefficients and roots in f64 from the f32 ray: in f32
/// the discriminant `b^2 - a c` and `c` itself cancel catastrophically when the ray starts
/// far from a thin solid (a camera 10 units from a cylinder of radius 0.3 put its hits
/// about 1e-5 off the surface, more than the secondary rays' origin offset: shadow acne),
/// and in f64 the only error left is the f32 rounding of the inputs and of the roots.
#[inline]
fn quadratic(a: f64, b: f64, c: f64) -> Option<(f32, f32)> {
    let disc = b * b - a * c;
    if disc.is_nan() || disc < 0.0 || a == 0.0 {
        return None;
    }
    let q = b + disc.sqrt().copysign(b);
    let (t0, t1) = if q == 0.0 { (0.0, 0.0) } else { (c / q, q / a) };
    let (t0, t1) = (t0 as f32, t1 as f32);
    Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
}

/// The ray's line inside `slab_lo <= o + t d <= slab_hi` on one axis: `None` when it misses,
/// the whole line when it is parallel and strictly inside (a ray lying in a face plane is
/// tangent, and misses). Returns the interval with the outward
/// normal's sign (`-1` at the entry when `d > 0`).
#[inline]
fn slab(o: f32, d: f32, lo: f32, hi: f32) -> Option<(f32, f32, f32)> {
    if d == 0.0 {
        return (o > lo && o < hi).then_some((f32::NEG_INFINITY, f32::INFINITY, 0.0));
    }
    let t_lo = (lo - o) / d;
    let t_hi = (hi - o) / d;
    Some(if d > 0.0 {
        (t_lo, t_hi, -1.0)
    } else {
        (t_hi, t_lo, 1.0)
    })
}

/// The line `f + t d` inside the ball of `radius` about the origin, as the sphere
/// primitive computes it: the entry and exit `t`, ascending.
#[inline]
fn ball(f: Vec3, d: Vec3, radius: f32) -> Option<(f32, f32)> {
    let a = d.dot(d);
    let b = -f.dot(d);
    // Distance from the centre to the line, as the sphere primitive computes it.
    let l = f + d * (b / a);
    let r2 = radius * radius;
    let disc = r2 - l.dot(l);
    if disc.is_nan() || disc < 0.0 {
        return None;
    }
    let c = f.dot(f) - r2;
    let q = b + (a.sqrt() * disc.sqrt()).copysign(b);
    let (t0, t1) = (c / q, q / a);
    Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
}

/// A solid of revolution about y cut by the slab `(y0, y1)` whose caps have the normals
/// `caps` (entry, exit): the side's interval `(s0, s1)` where the caps do not cut it first.
/// On a tie the side keeps the boundary.
#[inline]
fn capped(
    (y0, y1): (f32, f32),
    (enter_cap, exit_cap): (Vec3, Vec3),
    (s0, s1): (f32, f32),
    side: impl Fn(f32) -> Vec3,
    end: impl Fn(f32, Vec3) -> End,
) -> Span {
    Span {
        enter: if y0 > s0 {
            end(y0, enter_cap)
        } else {
            end(s0, side(s0))
        },
        exit: if y1 < s1 {
            end(y1, exit_cap)
        } else {
            end(s1, side(s1))
        },
    }
}

/// The span of the line `o + t d` inside one convex solid (at most one span). A torus is
/// not convex: [`leaf_spans`] intersects it, and here it gives nothing.
fn solid_span(s: &Solid, o: Vec3, d: Vec3, leaf: u32) -> Option<Span> {
    let end = |t: f32, normal: Vec3| End { t, normal, leaf };
    let span = match *s {
        Solid::Sphere { center, radius } => {
            let (t0, t1) = ball(o - center, d, radius)?;
            let n = |t: f32| ((o + d * t - center) / radius).normalize_or(Vec3::Y);
            Span {
                enter: end(t0, n(t0)),
                exit: end(t1, n(t1)),
            }
        }
        Solid::Ellipsoid { center, radii } => {
            // The unit ball in coordinates divided by the radii; t is unchanged.
            let (f, du) = ((o - center) / radii, d / radii);
            let (t0, t1) = ball(f, du, 1.0)?;
            // The gradient of |p / radii|^2 is 2 p / radii^2: the unit-ball point / radii.
            let n = |t: f32| ((f + du * t) / radii).normalize_or(Vec3::Y);
            Span {
                enter: end(t0, n(t0)),
                exit: end(t1, n(t1)),
            }
        }
        Solid::Paraboloid {
            base,
            radius,
            height,
        } => {
            // Relative to the apex, inside where k (x^2 + z^2) - y <= 0; the cap is the slab's
            // top (its bottom at -inf never cuts).
            let f = o - base;
            let (y0, y1, sign) = slab(f.y, d.y, f32::NEG_INFINITY, height)?;
            let k = height / (radius * radius);
            // The quadric's coefficients in f64 (see `quadratic`).
            let (f6, d6) = (o.as_dvec3() - base.as_dvec3(), d.as_dvec3());
            let k6 = f64::from(height) / (f64::from(radius) * f64::from(radius));
            let a = k6 * (d6.x * d6.x + d6.z * d6.z);
            let bh = 0.5 * d6.y - k6 * (f6.x * d6.x + f6.z * d6.z);
            let c = k6 * (f6.x * f6.x + f6.z * f6.z) - f6.y;
            let side = if a == 0.0 {
                // Along the axis: the linear -2 b' t + c <= 0.
                if bh == 0.0 {
                    if c.is_nan() || c > 0.0 {
                        return None;
                    }
                    (f32::NEG_INFINITY, f32::INFINITY)
                } else if bh > 0.0 {
                    ((c / (2.0 * bh)) as f32, f32::INFINITY)
                } else {
                    (f32::NEG_INFINITY, (c / (2.0 * bh)) as f32)
                }
            } else {
                quadratic(a, bh, c)?
            };
            let normal = |t: f32| {
                let p = f + d * t;
                Vec3::new(2.0 * k * p.x, -1.0, 2.0 * k * p.z).normalize_or(-Vec3::Y)
            };
            let cap = Vec3::new(0.0, sign, 0.0);
            capped((y0, y1), (cap, -cap), side, normal, end)
        }
        Solid::Torus { .. } => return None,
        Solid::Box { min, max } => {
            let mut enter = end(f32::NEG_INFINITY, Vec3::ZERO);
            let mut exit = end(f32::INFINITY, Vec3::ZERO);
            for axis in 0..3 {
                let (t0, t1, sign) = slab(o[axis], d[axis], min[axis], max[axis])?;
                let mut n = Vec3::ZERO;
                n[axis] = sign;
                // Strict comparisons: on a tie (an edge) the lower axis keeps it.
                if t0 > enter.t {
                    enter = end(t0, n);
                }
                if t1 < exit.t {
                    exit = end(t1, -n);
                }
            }
            Span { enter, exit }
        }
        Solid::Cylinder {
            base,
            radius,
            height,
        } => {
            let (y0, y1, sign) = slab(o.y, d.y, base.y, base.y + height)?;
            // The quadric's coefficients in f64 (see `quadratic`).
            let (f, d6) = (o.as_dvec3() - base.as_dvec3(), d.as_dvec3());
            let a = d6.x * d6.x + d6.z * d6.z;
            let c = f.x * f.x + f.z * f.z - f64::from(radius) * f64::from(radius);
            let (s0, s1) = if a == 0.0 {
                if c.is_nan() || c > 0.0 {
                    return None;
                }
                (f32::NEG_INFINITY, f32::INFINITY)
            } else {
                quadratic(a, -(f.x * d6.x + f.z * d6.z), c)?
            };
            let side = |t: f32| {
                let p = o + d * t - base;
                Vec3::new(p.x, 0.0, p.z).normalize_or(Vec3::X)
            };
            let cap = Vec3::new(0.0, sign, 0.0);
            capped((y0, y1), (cap, -cap), (s0, s1), side, end)
        }
        Solid::Cone {
            base,
            radius,
            height,
        } => {
            let (y0, y1, sign) = slab(o.y, d.y, base.y, base.y + height)?;
            let k2 = (radius / height) * (radius / height);
            // Relative to the apex: inside the double cone where x^2 + z^2 <= k^2 y^2.
            let apex = base + Vec3::new(0.0, height, 0.0);
            let f = o - apex;
            // The quadric's coefficients in f64 (see `quadratic`).
            let (f6, d6) = (o.as_dvec3() - apex.as_dvec3(), d.as_dvec3());
            let k6 = (f64::from(radius) / f64::from(height)).powi(2);
            let a = d6.x * d6.x + d6.z * d6.z - k6 * d6.y * d6.y;
            let bh = -(f6.x * d6.x + f6.z * d6.z - k6 * f6.y * d6.y);
            let c = f6.x * f6.x + f6.z * f6.z - k6 * f6.y * f6.y;
            let normal = |t: f32| {
                let p = f + d * t;
                Vec3::new(p.x, -k2 * p.y, p.z).normalize_or(Vec3::Y)
            };
            // The line's parts inside the double cone: one interval, or two rays.
            let inside: [(f32, f32); 2] = if a == 0.0 {
                // One root of the linear equation 2 b' t = c (with b' = -bh).
                if bh == 0.0 {
                    if c.is_nan() || c > 0.0 {
                        return None;
                    }
                    [(f32::NEG_INFINITY, f32::INFINITY), (f32::NAN, f32::NAN)]
                } else {
                    let t = (c / (2.0 * bh)) as f32;
                    if bh > 0.0 {
                        [(t, f32::INFINITY), (f32::NAN, f32::NAN)]
                    } else {
                        [(f32::NEG_INFINITY, t), (f32::NAN, f32::NAN)]
                    }
                }
            } else {
                let Some((r0, r1)) = quadratic(a, bh, c) else {
                    // No real roots: the quadratic keeps the sign of `a` everywhere.
                    if a > 0.0 || a.is_nan() {
                        return None;
                    }
                    return finish(Span {
                        enter: end(y0, Vec3::new(0.0, sign, 0.0)),
                        exit: end(y1, Vec3::new(0.0, -sign, 0.0)),
                    });
                };
                if a > 0.0 {
                    [(r0, r1), (f32::NAN, f32::NAN)]
                } else {
                    [(f32::NEG_INFINITY, r0), (r1, f32::INFINITY)]
                }
            };
            // Only the nappe below the apex lies in the slab; keep the first non-empty piece.
            let mut found = None;
            for piece in inside {
                let caps = (Vec3::new(0.0, sign, 0.0), Vec3::new(0.0, -sign, 0.0));
                let span = capped((y0, y1), caps, piece, normal, end);
                if span.enter.t < span.exit.t {
                    found = Some(span);
                    break;
                }
            }
            found?
        }
        Solid::HalfSpace { point, normal } => {
            let dn = d.dot(normal);
            let dist = (o - point).dot(normal);
            if dn == 0.0 {
                if dist.is_nan() || dist > 0.0 {
                    return None;
                }
                Span {
                    enter: end(f32::NEG_INFINITY, -normal),
                    exit: end(f32::INFINITY, normal),
                }
            } else {
                let t = -dist / dn;
                if dn > 0.0 {
                    Span {
                        enter: end(f32::NEG_INFINITY, -normal),
                        exit: end(t, normal),
                    }
                } else {
                    Span {
                        enter: end(t, normal),
                        exit: end(f32::INFINITY, -normal),
                    }
                }
            }
        }
    };
    finish(span)
}

/// Drops zero-length (tangent) and NaN spans.
#[inline]
fn finish(span: Span) -> Option<Span> {
    (span.enter.t < span.exit.t).then_some(span)
}

/// Combines two sorted, disjoint span lists with `op` in one merge sweep. Events at the same
/// `t` are applied together (the first operand's first); a span starts or ends where the
/// combined state changes, with the normal of the last event of the group that moved the
/// state to its new value, negated when it comes from a subtracted operand.
fn combine(op: CsgOp, a: &[Span], b: &[Span]) -> Vec<Span> {
    // Event k of a span list: span k / 2's entry (even k) or exit (odd k), read in place.
    struct Events<'a>(&'a [Span]);
    impl Events<'_> {
        fn len(&self) -> usize {
            2 * self.0.len()
        }
        fn get(&self, k: usize) -> Option<(End, bool)> {
            self.0.get(k / 2).map(|s| {
                if k.is_multiple_of(2) {
                    (s.enter, true)
                } else {
                    (s.exit, false)
                }
            })
        }
    }
    let (ea, eb) = (Events(a), Events(b));
    let (mut i, mut j) = (0, 0);
    let (mut in_a, mut in_b) = (false, false);
    let mut out = Vec::new();
    let mut open: Option<End> = None;
    while i < ea.len() || j < eb.len() {
        let t = match (ea.get(i), eb.get(j)) {
            (Some(x), Some(y)) => x.0.t.min(y.0.t),
            (Some(x), None) => x.0.t,
            (None, Some(y)) => y.0.t,
            (None, None) => break,
        };
        let before = op.apply(in_a, in_b);
        let mut chosen: Option<End> = None;
        while let Some((e, entering)) = ea.get(i).filter(|e| e.0.t == t) {
            in_a = entering;
            i += 1;
            if op.apply(in_a, in_b) != before {
                chosen = Some(e);
            }
        }
        while let Some((e, entering)) = eb.get(j).filter(|e| e.0.t == t) {
            in_b = entering;
            j += 1;
            if op.apply(in_a, in_b) != before {
                let normal = if op == CsgOp::Difference {
                    -e.normal
                } else {
                    e.normal
                };
                chosen = Some(End { normal, ..e });
            }
        }
        let after = op.apply(in_a, in_b);
        if after == before {
            continue;
        }
        let Some(e) = chosen else { continue };
        if after {
            open = Some(e);
        } else if let Some(enter) = open.take()
            && enter.t < e.t
        {
            out.push(Span { enter, exit: e });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(c: Vec3, r: f32) -> CsgNode {
        CsgNode::Leaf(Solid::Sphere {
            center: c,
            radius: r,
        })
    }

    fn cube(min: Vec3, max: Vec3) -> CsgNode {
        CsgNode::Leaf(Solid::Box { min, max })
    }

    fn op(op: CsgOp, a: CsgNode, b: CsgNode) -> CsgNode {
        CsgNode::Op(op, Box::new(a), Box::new(b))
    }

    fn hit(tree: &CsgNode, o: Vec3, d: Vec3) -> Option<CsgHit> {
        Csg::new(tree).unwrap().intersect(&Ray::new(o, d))
    }

    const FROM_LEFT: Vec3 = Vec3::new(-10.0, 0.0, 0.0);

    /// Regression (tests/tests/adversarial.rs): a ray starting at `x = 1.16e30` and going
    /// straight down hit the cone of the built-in `csg` scene at `t = 4.3`.
    #[test]
    fn rays_far_outside_the_box_miss() {
        let cone = CsgNode::Leaf(Solid::Cone {
            base: Vec3::new(1.5, 1.0, -1.2),
            radius: 0.8,
            height: 1.2,
        });
        let o = Vec3::new(1.160_351_6e30, 6.501_904_5, -0.200_048_86);
        assert_eq!(hit(&cone, o, -Vec3::Y), None);
        assert!(hit(&cone, Vec3::new(1.5, 6.5, -1.2), -Vec3::Y).is_some());
    }

    #[test]
    fn leaves_give_analytic_distances() {
        let cases = [
            (sphere(Vec3::ZERO, 2.0), 8.0, -Vec3::X),
            (cube(Vec3::splat(-1.0), Vec3::splat(1.0)), 9.0, -Vec3::X),
            (
                CsgNode::Leaf(Solid::Cylinder {
                    base: Vec3::new(0.0, -1.0, 0.0),
                    radius: 3.0,
                    height: 2.0,
                }),
                7.0,
                -Vec3::X,
            ),
            (
                // Halfway up a cone of base radius 4 and height 2, the radius is 2.
                CsgNode::Leaf(Solid::Cone {
                    base: Vec3::new(0.0, -1.0, 0.0),
                    radius: 4.0,
                    height: 2.0,
                }),
                8.0,
                Vec3::new(-1.0, 2.0, 0.0).normalize(),
            ),
        ];
        for (tree, t, n) in cases {
            let h = hit(&tree, FROM_LEFT, Vec3::X).unwrap();
            assert_eq!(h.t, t, "{tree:?}");
            assert!((h.normal - n).length() < 1e-6, "{tree:?}: {}", h.normal);
        }
    }

    #[test]
    fn cylinder_and_cone_caps_from_above() {
        let cyl = CsgNode::Leaf(Solid::Cylinder {
            base: Vec3::ZERO,
            radius: 1.0,
            height: 2.0,
        });
        let h = hit(&cyl, Vec3::new(0.5, 10.0, 0.0), -Vec3::Y).unwrap();
        assert_eq!((h.t, h.normal), (8.0, Vec3::Y));
        let cone = CsgNode::Leaf(Solid::Cone {
            base: Vec3::ZERO,
            radius: 1.0,
            height: 2.0,
        });
        let h = hit(&cone, Vec3::new(0.0, -10.0, 0.0), Vec3::Y).unwrap();
        assert_eq!((h.t, h.normal), (10.0, -Vec3::Y));
        // Straight down the axis the apex is the first point.
        let h = hit(&cone, Vec3::new(0.0, 10.0, 0.0), -Vec3::Y).unwrap();
        assert_eq!(h.t, 8.0);
    }

    #[test]
    fn the_three_operations() {
        let a = sphere(Vec3::new(-1.0, 0.0, 0.0), 2.0); // [-3, 1] on the x axis
        let b = sphere(Vec3::new(1.0, 0.0, 0.0), 2.0); // [-1, 3]
        let t = |tree: &CsgNode| hit(tree, FROM_LEFT, Vec3::X).map(|h| (h.t, h.normal));
        assert_eq!(
            t(&op(CsgOp::Union, a.clone(), b.clone())),
            Some((7.0, -Vec3::X))
        );
        assert_eq!(
            t(&op(CsgOp::Intersection, a.clone(), b.clone())),
            Some((9.0, -Vec3::X))
        );
        assert_eq!(
            t(&op(CsgOp::Difference, b.clone(), a.clone())),
            Some((11.0, -Vec3::X)),
            "the subtracted sphere's exit, its normal flipped"
        );
        // A ray inside the union hits its far side; inside the difference's hole, the rest.
        let inside = Ray::new(Vec3::ZERO, Vec3::X);
        let u = Csg::new(&op(CsgOp::Union, a.clone(), b.clone())).unwrap();
        assert_eq!(u.intersect(&inside).unwrap().t, 3.0);
        let d = Csg::new(&op(CsgOp::Difference, b, a)).unwrap();
        let h = d.intersect(&inside).unwrap();
        assert_eq!((h.t, h.normal), (1.0, -Vec3::X));
    }

    #[test]
    fn coincident_faces_follow_the_regularised_rule() {
        let left = cube(Vec3::new(-2.0, -1.0, -1.0), Vec3::new(0.0, 1.0, 1.0));
        let right = cube(Vec3::new(0.0, -1.0, -1.0), Vec3::new(2.0, 1.0, 1.0));
        let u = Csg::new(&op(CsgOp::Union, left.clone(), right.clone())).unwrap();
        // From inside the left box the shared face x = 0 is not a boundary.
        let r = Ray::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::X);
        assert_eq!(u.intersect(&r).unwrap().t, 3.0);
        // Touching solids intersect in nothing.
        let i = Csg::new(&op(CsgOp::Intersection, left.clone(), right)).unwrap();
        assert_eq!(i.intersect(&Ray::new(FROM_LEFT, Vec3::X)), None);
        // A subtracted solid sharing the first's front face removes that face.
        let bite = cube(Vec3::new(-2.0, -1.0, -1.0), Vec3::new(-1.0, 1.0, 1.0));
        let d = Csg::new(&op(CsgOp::Difference, left, bite)).unwrap();
        let h = d.intersect(&Ray::new(FROM_LEFT, Vec3::X)).unwrap();
        assert_eq!((h.t, h.normal), (9.0, -Vec3::X));
    }

    #[test]
    fn tangent_rays_miss() {
        let s = sphere(Vec3::ZERO, 1.0);
        assert_eq!(hit(&s, Vec3::new(-5.0, 1.0, 0.0), Vec3::X), None);
        let b = cube(Vec3::splat(-1.0), Vec3::splat(1.0));
        // Along a face of the box: a zero-thickness overlap in y.
        assert_eq!(hit(&b, Vec3::new(-5.0, 1.0, 0.0), Vec3::X), None);
    }

    #[test]
    fn half_spaces_cut() {
        // A ball cut by the plane x = 0, keeping x <= 0.
        let cut = op(
            CsgOp::Intersection,
            sphere(Vec3::ZERO, 2.0),
            CsgNode::Leaf(Solid::HalfSpace {
                point: Vec3::ZERO,
                normal: Vec3::new(3.0, 0.0, 0.0),
            }),
        );
        let c = Csg::new(&cut).unwrap();
        assert!(c.bounds().max.x < 2.0 + 0.01);
        let h = c
            .intersect(&Ray::new(Vec3::new(10.0, 0.0, 0.0), -Vec3::X))
            .unwrap();
        assert_eq!((h.t, h.normal), (10.0, Vec3::X));
        // A ray parallel to the plane on the kept side passes the ball's far side.
        let h = c
            .intersect(&Ray::new(Vec3::new(-1.0, -5.0, 0.0), Vec3::Y))
            .unwrap();
        assert!((h.t - (5.0 - 3.0f32.sqrt())).abs() < 1e-5);
    }

    #[test]
    fn leaf_ids_and_bounds() {
        let tree = CsgNode::fold(
            CsgOp::Difference,
            vec![
                cube(Vec3::splat(-1.0), Vec3::splat(1.0)),
                sphere(Vec3::new(-1.0, 0.0, 0.0), 0.5),
                sphere(Vec3::new(1.0, 0.0, 0.0), 0.5),
            ],
        )
        .unwrap();
        let c = Csg::new(&tree).unwrap();
        assert_eq!(c.leaf_count(), 3);
        assert!(
            c.bounds()
                .contains(&Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0)))
        );
        assert!(c.bounds().max.x < 1.01);
        let h = c.intersect(&Ray::new(FROM_LEFT, Vec3::X)).unwrap();
        assert_eq!((h.t, h.leaf), (9.5, 1));
        let h = c.intersect(&Ray::new(-FROM_LEFT, -Vec3::X)).unwrap();
        assert_eq!((h.t, h.leaf, h.normal), (9.5, 2, Vec3::X));
    }

    #[test]
    fn bad_trees_are_refused() {
        let s = sphere(Vec3::ZERO, 1.0);
        assert!(CsgNode::fold(CsgOp::Union, vec![s.clone()]).is_err());
        assert!(CsgNode::fold(CsgOp::Difference, vec![]).is_err());
        let bad = [
            sphere(Vec3::new(f32::NAN, 0.0, 0.0), 1.0),
            sphere(Vec3::ZERO, 0.0),
            sphere(Vec3::ZERO, f32::INFINITY),
            cube(Vec3::ONE, Vec3::ZERO),
            CsgNode::Leaf(Solid::HalfSpace {
                point: Vec3::ZERO,
                normal: Vec3::ZERO,
            }),
            // Unbounded: a half-space alone, or in a union.
            CsgNode::Leaf(Solid::HalfSpace {
                point: Vec3::ZERO,
                normal: Vec3::Y,
            }),
            // Empty: disjoint boxes intersected.
            op(
                CsgOp::Intersection,
                s.clone(),
                sphere(Vec3::new(5.0, 0.0, 0.0), 1.0),
            ),
        ];
        for tree in bad {
            assert!(Csg::new(&tree).is_err(), "{tree:?}");
        }
        let mut deep = s.clone();
        for _ in 0..MAX_CSG_DEPTH {
            deep = op(CsgOp::Union, deep, s.clone());
        }
        assert!(matches!(Csg::new(&deep), Err(SceneError::TooLarge(_))));
        let many = CsgNode::fold(CsgOp::Union, vec![s; MAX_CSG_LEAVES + 1]).unwrap();
        assert!(matches!(Csg::new(&many), Err(SceneError::TooLarge(_))));
    }

    fn torus(r_big: f32, r_small: f32) -> Solid {
        Solid::Torus {
            center: Vec3::ZERO,
            major_radius: r_big,
            minor_radius: r_small,
        }
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-6
    }

    #[test]
    fn quadrics_and_torus_give_analytic_hits() {
        // An ellipsoid of radii (2, 1, 3) from the left, from above, from behind.
        let e = CsgNode::Leaf(Solid::Ellipsoid {
            center: Vec3::new(1.0, 0.0, 0.0),
            radii: Vec3::new(2.0, 1.0, 3.0),
        });
        let h = hit(&e, FROM_LEFT, Vec3::X).unwrap();
        assert_eq!((h.t, h.normal), (9.0, -Vec3::X));
        let h = hit(&e, Vec3::new(1.0, 5.0, 0.0), -Vec3::Y).unwrap();
        assert_eq!((h.t, h.normal), (4.0, Vec3::Y));
        // At (x, 0, z) with x/2 = z/3 = 1/sqrt2 the normal is along (x/4, 0, z/9).
        let p = Vec3::new(1.0 + 2.0f32.sqrt(), 0.0, 1.5 * 2.0f32.sqrt());
        let h = hit(&e, p + Vec3::new(0.0, 0.0, 5.0), -Vec3::Z).unwrap();
        assert!((h.t - 5.0).abs() < 1e-5, "{}", h.t);
        let want = Vec3::new((p.x - 1.0) / 4.0, 0.0, p.z / 9.0).normalize();
        assert!(close(h.normal, want), "{}", h.normal);
        // A paraboloid y = x^2 + z^2 (radius 2 at height 4): its wall at height 1 is at
        // x = 1, the normal there along (2, -1, 0); straight down the axis, the cap then
        // the apex.
        let par = CsgNode::Leaf(Solid::Paraboloid {
            base: Vec3::ZERO,
            radius: 2.0,
            height: 4.0,
        });
        let h = hit(&par, Vec3::new(-10.0, 1.0, 0.0), Vec3::X).unwrap();
        assert_eq!(h.t, 9.0);
        assert!(close(h.normal, Vec3::new(-2.0, -1.0, 0.0).normalize()));
        let h = hit(&par, Vec3::new(0.0, 10.0, 0.0), -Vec3::Y).unwrap();
        assert_eq!((h.t, h.normal), (6.0, Vec3::Y));
        let inside = Csg::new(&par).unwrap();
        let h = inside.intersect(&Ray::new(Vec3::new(0.0, 2.0, 0.0), -Vec3::Y));
        assert_eq!(h.map(|h| h.t), Some(2.0));
        // Above the cap, beside it: miss; below the apex along the axis, the apex first.
        assert_eq!(hit(&par, Vec3::new(-10.0, 4.5, 0.0), Vec3::X), None);
        assert_eq!(
            hit(&par, Vec3::new(0.0, -3.0, 0.0), Vec3::Y).map(|h| h.t),
            Some(3.0)
        );
        // A torus R = 2, r = 0.5: the outer wall, then from inside the hole the inner wall,
        // and down the axis nothing.
        let t = CsgNode::Leaf(torus(2.0, 0.5));
        let h = hit(&t, FROM_LEFT, Vec3::X).unwrap();
        assert_eq!((h.t, h.normal), (7.5, -Vec3::X));
        let h = hit(&t, Vec3::ZERO, Vec3::X).unwrap();
        assert_eq!((h.t, h.normal), (1.5, -Vec3::X));
        assert_eq!(hit(&t, Vec3::new(0.0, 10.0, 0.0), -Vec3::Y), None);
        // From inside the tube: its far wall.
        let h = hit(&t, Vec3::new(2.0, 0.0, 0.0), Vec3::Y).unwrap();
        assert_eq!((h.t, h.normal), (0.5, Vec3::Y));
    }

    #[test]
    fn horn_and_spindle_tori() {
        // r = R: the hole closes to a point; along x through the centre the two halves meet
        // at the origin (a tangency in the middle of one span).
        let horn = CsgNode::Leaf(torus(1.0, 1.0));
        assert_eq!(hit(&horn, FROM_LEFT, Vec3::X).map(|h| h.t), Some(8.0));
        // r > R: the inner lemon (up to |y| = sqrt(r^2 - R^2) on the axis) is hollow.
        // At x = 0.2 the apple's top is at y = sqrt(4 - 0.8^2), the lemon's at
        // sqrt(4 - 1.2^2) = 1.6. (On the axis apple and lemon touch: a tangency.)
        let spindle = Csg::new(&CsgNode::Leaf(torus(1.0, 2.0))).unwrap();
        let down = Ray::new(Vec3::new(0.2, 10.0, 0.0), -Vec3::Y);
        let h = spindle.intersect(&down).unwrap();
        assert!((h.t - (10.0 - 3.36f32.sqrt())).abs() < 1e-5, "{h:?}");
        let h = spindle
            .intersect(&Ray::new(Vec3::new(0.2, 0.0, 0.0), Vec3::Y))
            .unwrap();
        assert!((h.t - 1.6).abs() < 1e-6 && h.normal.y < -0.5, "{h:?}");
    }

    #[test]
    fn placed_leaves() {
        use glam::Quat;
        // A cylinder of radius 1 and height 4 laid along x by a rotation about z, moved up.
        let cyl = Solid::Cylinder {
            base: Vec3::ZERO,
            radius: 1.0,
            height: 4.0,
        };
        let to_world = Affine3A::from_rotation_translation(
            Quat::from_rotation_z(-std::f32::consts::FRAC_PI_2),
            Vec3::new(0.0, 1.0, 0.0),
        );
        let c = Csg::new(&CsgNode::Placed(cyl, to_world)).unwrap();
        // Its axis runs from (0, 1, 0) to (4, 1, 0).
        assert!(c.bounds().contains(&Aabb::new(
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(4.0, 2.0, 1.0)
        )));
        assert!(c.bounds().max.x < 4.01 && c.bounds().min.y > -0.01);
        let h = c
            .intersect(&Ray::new(Vec3::new(2.0, 10.0, 0.0), -Vec3::Y))
            .unwrap();
        assert!(
            (h.t - 8.0).abs() < 1e-5 && close(h.normal, Vec3::Y),
            "{h:?}"
        );
        let h = c
            .intersect(&Ray::new(FROM_LEFT + Vec3::Y, Vec3::X))
            .unwrap();
        assert!(
            (h.t - 10.0).abs() < 1e-5 && close(h.normal, -Vec3::X),
            "{h:?}"
        );
        // A non-uniform scale: a unit sphere stretched to radii (2, 1, 1) is the ellipsoid,
        // normals by the inverse transpose; t is unchanged for an unnormalised direction.
        let ball = Solid::Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        };
        let stretched = Csg::new(&CsgNode::Placed(
            ball,
            Affine3A::from_scale(Vec3::new(2.0, 1.0, 1.0)),
        ))
        .unwrap();
        let ellipsoid = Csg::new(&CsgNode::Leaf(Solid::Ellipsoid {
            center: Vec3::ZERO,
            radii: Vec3::new(2.0, 1.0, 1.0),
        }))
        .unwrap();
        for (o, d) in [
            (FROM_LEFT, Vec3::X * 3.0),
            (Vec3::new(-3.0, 2.0, 0.5), Vec3::new(1.0, -0.7, 0.0)),
        ] {
            let (a, b) = (
                stretched.intersect(&Ray::new(o, d)).unwrap(),
                ellipsoid.intersect(&Ray::new(o, d)).unwrap(),
            );
            assert!((a.t - b.t).abs() < 1e-5 * b.t, "{a:?} {b:?}");
            assert!(close(a.normal, b.normal), "{a:?} {b:?}");
        }
        // An identity placement gives the unplaced leaf's answers.
        let plain = Csg::new(&CsgNode::Leaf(torus(2.0, 0.5))).unwrap();
        let placed = Csg::new(&CsgNode::Placed(torus(2.0, 0.5), Affine3A::IDENTITY)).unwrap();
        let r = Ray::new(Vec3::new(-6.0, 0.2, 0.3), Vec3::new(1.0, 0.0, 0.05));
        let (a, b) = (plain.intersect(&r).unwrap(), placed.intersect(&r).unwrap());
        assert!(a.t == b.t && close(a.normal, b.normal), "{a:?} {b:?}");
    }

    #[test]
    fn a_ring_cut_by_a_rotated_box() {
        use glam::Quat;
        // A torus R = 2, r = 0.5 minus a box rotated 45 degrees about y covering its +x
        // part: rays along the x axis see the ring on the left only.
        let cut = Affine3A::from_rotation_translation(
            Quat::from_rotation_y(std::f32::consts::FRAC_PI_4),
            Vec3::new(2.0, 0.0, 0.0),
        );
        let tree = op(
            CsgOp::Difference,
            CsgNode::Leaf(torus(2.0, 0.5)),
            CsgNode::Placed(
                Solid::Box {
                    min: Vec3::splat(-1.0),
                    max: Vec3::splat(1.0),
                },
                cut,
            ),
        );
        let c = Csg::new(&tree).unwrap();
        let h = c.intersect(&Ray::new(FROM_LEFT, Vec3::X)).unwrap();
        assert_eq!((h.t, h.leaf), (7.5, 0));
        // Along z at x = 1.8 the ring spans |z| <= sqrt(2.5^2 - 1.8^2) and the box
        // |z| <= sqrt2 - 0.2: the ring's wall, then from inside it the box's face, its
        // outward normal (-1, 0, -1) / sqrt2 flipped.
        let ring = (2.5f32 * 2.5 - 1.8 * 1.8).sqrt();
        let h = c
            .intersect(&Ray::new(Vec3::new(1.8, 0.0, -10.0), Vec3::Z))
            .unwrap();
        assert!((h.t - (10.0 - ring)).abs() < 1e-5 && h.leaf == 0, "{h:?}");
        let h = c
            .intersect(&Ray::new(Vec3::new(1.8, 0.0, -1.5), Vec3::Z))
            .unwrap();
        let face = 1.5 - (2.0f32.sqrt() - 0.2);
        assert!((h.t - face).abs() < 1e-5 && h.leaf == 1, "{h:?}");
        assert!(
            close(h.normal, Vec3::new(1.0, 0.0, 1.0).normalize()),
            "{h:?}"
        );
    }

    #[test]
    fn bad_solids_and_transforms_are_refused() {
        let torus_with = |r_big: f32, r_small: f32| CsgNode::Leaf(torus(r_big, r_small));
        let ball = Solid::Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        };
        let cases = [
            (torus_with(0.0, 1.0), "torus major radius must be positive"),
            (torus_with(1.0, -1.0), "torus minor radius must be positive"),
            (torus_with(f32::NAN, 1.0), "torus major radius"),
            (
                CsgNode::Leaf(Solid::Ellipsoid {
                    center: Vec3::ZERO,
                    radii: Vec3::new(1.0, 0.0, 1.0),
                }),
                "ellipsoid radius must be positive",
            ),
            (
                CsgNode::Leaf(Solid::Paraboloid {
                    base: Vec3::ZERO,
                    radius: 1.0,
                    height: f32::INFINITY,
                }),
                "paraboloid height",
            ),
            (
                CsgNode::Placed(ball, Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0))),
                "singular",
            ),
            (
                CsgNode::Placed(ball, Affine3A::from_scale(Vec3::new(1.0, 1e-7, 1.0))),
                "singular",
            ),
            (
                CsgNode::Placed(
                    ball,
                    Affine3A::from_translation(Vec3::new(f32::NAN, 0.0, 0.0)),
                ),
                "transform",
            ),
            (
                CsgNode::Placed(ball, Affine3A::from_translation(Vec3::new(1e30, 0.0, 0.0))),
                "exceeds",
            ),
        ];
        for (tree, want) in cases {
            let e = Csg::new(&tree).unwrap_err().to_string();
            assert!(e.contains(want), "{tree:?}: {e}");
        }
    }

    #[test]
    fn nan_and_zero_rays_miss() {
        let tree = op(
            CsgOp::Difference,
            cube(Vec3::splat(-1.0), Vec3::splat(1.0)),
            sphere(Vec3::ZERO, 1.2),
        );
        let c = Csg::new(&tree).unwrap();
        for r in [
            Ray::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X),
            Ray::new(FROM_LEFT, Vec3::new(f32::NAN, 0.0, 0.0)),
            Ray::new(FROM_LEFT, Vec3::ZERO),
        ] {
            assert_eq!(c.intersect(&r), None);
        }
    }
}
