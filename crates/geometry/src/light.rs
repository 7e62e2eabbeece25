//! A primitive as a light: the weight by which next-event estimation chooses it and the
//! point it samples on it from a reference point (`docs/sampling.md`; the rendering core's
//! `Emitters` holds the table of lights and the choice).
//!
//! - triangle: a uniform point by area (pdf `1 / area` per unit area);
//! - sphere: a uniform direction in the cone the sphere subtends (pbrt-v4's
//!   `Sphere::Sample(ctx)`), the point where it meets the sphere's near side; nothing from
//!   inside the sphere, which sees only the sphere's back;
//! - any other bounded kind (CSG, SDF, Bezier, height field): a uniform direction in the
//!   cone of the primitive's bounding sphere, and the first hit of that direction on the
//!   primitive itself, found by the primitive's own intersection routine (not the
//!   accelerator); pdf `1 / solid angle of the cone`, and nothing when the direction misses
//!   the primitive or the reference point lies inside the bounding sphere (BSDF sampling
//!   then carries the light alone, with MIS weight 1, so the estimator stays unbiased);
//! - plane: not a light (unbounded).

use crate::geometry::{Shape, sphere_area};
use crate::ray::Ray;
use crate::sampling::{basis, triangle_point, triangle_weights};
use crate::sphere::Sphere;
use glam::Vec3;
use std::f32::consts::TAU;

/// The cone of directions from a point towards a sphere outside it.
struct Cone {
    /// Unit direction to the centre.
    axis: Vec3,
    /// `sin² θmax`.
    sin2_max: f32,
    /// `1 - cos θmax`, computed as `sin² / (1 + cos)` (no cancellation for small cones).
    one_minus_cos: f32,
}

impl Cone {
    /// The cone from `origin` to the sphere (`center`, `radius`), `None` from inside it.
    fn towards(origin: Vec3, center: Vec3, radius: f32) -> Option<Self> {
        let to = center - origin;
        let d2 = to.length_squared();
        let r2 = radius * radius;
        if !(d2 > r2 && d2.is_finite()) {
            return None;
        }
        let sin2_max = r2 / d2;
        let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
        Some(Self {
            axis: to / d2.sqrt(),
            sin2_max,
            one_minus_cos: sin2_max / (1.0 + cos_max),
        })
    }

    /// Density per solid angle of a uniform direction in the cone.
    fn pdf(&self) -> f32 {
        1.0 / (TAU * self.one_minus_cos)
    }

    /// `(cos θ, sin² θ)` of a uniform direction in the cone, from `u`.
    fn theta(&self, u: f32) -> (f32, f32) {
        let one_minus = u * self.one_minus_cos;
        (1.0 - one_minus, one_minus * (2.0 - one_minus))
    }

    /// The unit vector at angle (`cos`, `sin`) from the axis and azimuth `phi`, with the
    /// axis flipped by `sign`.
    fn direction(&self, cos: f32, sin: f32, phi: f32, sign: f32) -> Vec3 {
        let (t, b) = basis(self.axis);
        (t * (sin * phi.cos()) + b * (sin * phi.sin()) + self.axis * (sign * cos)).normalize()
    }
}

/// A point sampled on a light primitive ([`Shape::sample_light`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightPoint {
    /// The point.
    pub point: Vec3,
    /// The primitive's geometric normal there.
    pub normal: Vec3,
    /// Its surface parameters `(u, v)`, as a hit there reports them.
    pub uv: (f32, f32),
    /// Density per solid angle seen from the reference point (the choice of the light not
    /// included).
    pub pdf: f32,
}

impl Shape {
    /// The area in the weight by which a light is chosen (up to the emission): its
    /// [`Shape::area`] where known, else the area of its [`Shape::bounding_sphere`];
    /// `None` for a plane, or when the area is not positive and finite.
    #[must_use]
    pub fn light_area(&self) -> Option<f64> {
        let area = match self.area() {
            Some(a) => a,
            None => sphere_area(self.bounding_sphere()?.1),
        };
        (area > 0.0 && area.is_finite()).then_some(area)
    }

    /// A point on the primitive as a light seen from `origin` (a point already offset from
    /// its surface), from the uniform numbers `u` (the module's documentation says how
    /// each kind samples). `None` when this technique cannot reach the primitive from
    /// `origin`.
    #[must_use]
    pub fn sample_light(&self, origin: Vec3, u: (f32, f32)) -> Option<LightPoint> {
        match self {
            Self::Triangle(tri) => {
                let [_, w1, w2] = triangle_weights(u.0, u.1);
                let y = triangle_point(tri.v[0], tri.v[1], tri.v[2], u.0, u.1);
                let to = y - origin;
                let d2 = to.length_squared();
                let cos_y = -tri.normal().dot(to) / d2.sqrt();
                if !(cos_y > 0.0 && d2 > 0.0) {
                    return None;
                }
                let area = self.light_area()? as f32;
                Some(LightPoint {
                    point: y,
                    normal: tri.normal(),
                    uv: (w1, w2),
                    pdf: d2 / (cos_y * area),
                })
            }
            Self::Sphere(s) => {
                let cone = Cone::towards(origin, s.center, s.radius)?;
                let (cos, sin2) = cone.theta(u.0);
                // pbrt-v4: the angle alpha at the centre between the axis and the point.
                let sin_max = cone.sin2_max.sqrt();
                let cos_alpha = sin2 / sin_max + cos * (1.0 - sin2 / cone.sin2_max).max(0.0).sqrt();
                let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
                let n = cone.direction(cos_alpha, sin_alpha, TAU * u.1, -1.0);
                Some(LightPoint {
                    point: s.center + n * s.radius,
                    normal: n,
                    uv: Sphere::uv(n),
                    pdf: cone.pdf(),
                })
            }
            Self::Plane(_) => None,
            Self::HeightField(_) | Self::Csg(_) | Self::Bezier(_) | Self::Sdf(_) => {
                let (center, radius) = self.bounding_sphere()?;
                let cone = Cone::towards(origin, center, radius)?;
                let (cos, sin2) = cone.theta(u.0);
                let wi = cone.direction(cos, sin2.max(0.0).sqrt(), TAU * u.1, 1.0);
                let ray = Ray::new(origin, wi);
                let h = self.intersect(&ray)?;
                let hit = self.complete_hit(&ray, 0, h);
                Some(LightPoint {
                    point: ray.at(h.t),
                    normal: hit.normal,
                    uv: (hit.u, hit.v),
                    pdf: cone.pdf(),
                })
            }
        }
    }

    /// The density per solid angle with which [`Shape::sample_light`] from `origin` would
    /// have produced the point `p` of the primitive with unit geometric normal `normal`
    /// (the choice of the light not included; 0 when it would not, as from inside a
    /// cone's sphere).
    #[must_use]
    pub fn light_pdf(&self, origin: Vec3, p: Vec3, normal: Vec3) -> f32 {
        match self {
            Self::Triangle(_) => {
                let to = p - origin;
                let d2 = to.length_squared();
                let cos_y = normal.dot(to).abs() / d2.sqrt();
                let Some(area) = self.light_area() else {
                    return 0.0;
                };
                if cos_y.is_nan() || cos_y <= 0.0 {
                    return 0.0;
                }
                d2 / (cos_y * area as f32)
            }
            Self::Sphere(s) => Cone::towards(origin, s.center, s.radius).map_or(0.0, |c| c.pdf()),
            Self::Plane(_) => 0.0,
            Self::HeightField(_) | Self::Csg(_) | Self::Bezier(_) | Self::Sdf(_) => self
                .bounding_sphere()
                .and_then(|(c, r)| Cone::towards(origin, c, r))
                .map_or(0.0, |c| c.pdf()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cone's pdf integrates to one over the cone, and its directions stay inside it.
    #[test]
    fn cone_directions_stay_inside() {
        for &(d, r) in &[(10.0f32, 1.0f32), (1000.0, 0.01), (1.5, 1.0)] {
            let cone = Cone::towards(Vec3::ZERO, Vec3::new(0.0, 0.0, d), r).unwrap();
            let cos_max = 1.0 - cone.one_minus_cos;
            for k in 0..50 {
                let (cos, sin2) = cone.theta(k as f32 / 50.0);
                assert!(cos >= cos_max - 1e-6 && (cos * cos + sin2 - 1.0).abs() < 1e-5);
                let w = cone.direction(cos, sin2.sqrt(), 1.0, 1.0);
                assert!((w.z - cos).abs() < 1e-5);
            }
            let s2 = (f64::from(r) / f64::from(d)).powi(2);
            let exact = std::f64::consts::TAU * s2 / (1.0 + (1.0 - s2).sqrt());
            assert!((f64::from(1.0 / cone.pdf()) - exact).abs() <= 1e-5 * exact);
        }
        assert!(Cone::towards(Vec3::ZERO, Vec3::X * 0.5, 1.0).is_none());
    }
}
