//! The analytic solids at a CSG tree's leaves: their parameters' checks, their boxes and
//! the spans of a line inside them.

use super::quartic;
use super::spans::{End, LeafSpans, Span, finish};
use crate::aabb::Aabb;
use crate::checks;
use crate::error::SceneError;
use crate::sphere::line_in_ball;
use glam::Vec3;

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
    // Tori and quadrics.
    /// An axis-aligned ellipsoid: the unit ball scaled by `radii`, centred at `center` (a
    /// rotated one is a [`crate::CsgNode::Placed`] ellipsoid).
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

impl Solid {
    /// A solid standing on the `y` axis from `base` (a cylinder, a cone, a paraboloid): its
    /// name, base, radius and height; `None` for the others.
    fn axial(&self) -> Option<(&'static str, Vec3, f32, f32)> {
        match *self {
            Self::Cylinder {
                base,
                radius,
                height,
            } => Some(("cylinder", base, radius, height)),
            Self::Cone {
                base,
                radius,
                height,
            } => Some(("cone", base, radius, height)),
            Self::Paraboloid {
                base,
                radius,
                height,
            } => Some(("paraboloid", base, radius, height)),
            _ => None,
        }
    }
}

/// Checks that a point is finite and within [`crate::limits::MAX_COORDINATE`].
pub(super) fn finite_point(v: Vec3, what: &str) -> Result<(), SceneError> {
    checks::point(v, &format!("CSG {what}"))
}

/// Checks a solid's parameters and normalises a half-space's normal.
pub(super) fn validate(s: Solid) -> Result<Solid, SceneError> {
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
        Solid::Cylinder { .. } | Solid::Cone { .. } | Solid::Paraboloid { .. } => {
            if let Some((kind, base, radius, height)) = s.axial() {
                finite(base, &format!("{kind} base"))?;
                positive(radius, &format!("{kind} radius"))?;
                positive(height, &format!("{kind} height"))?;
            }
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
        } => checks::torus("CSG", center, major_radius, minor_radius)?,
    }
    Ok(s)
}

/// A bound that may be all of space (`None`).
pub(super) type Bound = Option<Aabb>;

/// A solid's bounding box (`None`: all of space).
pub(super) fn solid_bounds(s: &Solid) -> Bound {
    match *s {
        Solid::Sphere { center, radius } => Some(Aabb::new(
            center - Vec3::splat(radius),
            center + Vec3::splat(radius),
        )),
        Solid::Box { min, max } => Some(Aabb::new(min, max)),
        Solid::Cylinder { .. } | Solid::Cone { .. } | Solid::Paraboloid { .. } => {
            s.axial().map(|(_, base, radius, height)| {
                Aabb::new(
                    base - Vec3::new(radius, 0.0, radius),
                    base + Vec3::new(radius, height, radius),
                )
            })
        }
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

/// The spans of the line `o + t d` (in the solid's own space) inside solid `s`, whose
/// ends carry the leaf id `leaf`: a torus by its quartic, every other solid by
/// [`solid_span`].
#[inline]
pub(super) fn solid_spans(s: &Solid, o: Vec3, d: Vec3, leaf: u32) -> LeafSpans {
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
    out
}

/// The span of the line `o + t d` inside one convex solid (at most one span). A torus is
/// not convex: [`solid_spans`] intersects it, and here it gives nothing.
#[inline]
fn solid_span(s: &Solid, o: Vec3, d: Vec3, leaf: u32) -> Option<Span> {
    let end = |t: f32, normal: Vec3| End { t, normal, leaf };
    let span = match *s {
        Solid::Sphere { center, radius } => {
            let (t0, t1) = line_in_ball(o - center, d, radius)?;
            let n = |t: f32| ((o + d * t - center) / radius).normalize_or(Vec3::Y);
            Span {
                enter: end(t0, n(t0)),
                exit: end(t1, n(t1)),
            }
        }
        Solid::Ellipsoid { center, radii } => {
            // The unit ball in coordinates divided by the radii; t is unchanged.
            let (f, du) = ((o - center) / radii, d / radii);
            let (t0, t1) = line_in_ball(f, du, 1.0)?;
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
