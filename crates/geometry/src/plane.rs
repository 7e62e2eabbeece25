//! Infinite planes.

use crate::ray::Ray;
use glam::Vec3;

/// The infinite plane through `point` with unit `normal`. Planes are unbounded: every
/// acceleration structure keeps them in a side list tested by every ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// A point on the plane.
    pub point: Vec3,
    /// Unit normal.
    pub normal: Vec3,
}

impl Plane {
    /// A plane from a point and a (not necessarily unit) normal, which is normalised.
    #[inline]
    #[must_use]
    pub fn new(point: Vec3, normal: Vec3) -> Self {
        Self {
            point,
            normal: normal.normalize_or_zero(),
        }
    }

    /// `t` where the ray crosses the plane, if inside `[ray.t_min, ray.t_max]`. A ray
    /// parallel to the plane (including one lying in it) does not hit, and neither does a
    /// ray with an infinite or NaN component (an infinite direction would give `t = 0`, an
    /// infinite origin `t = inf`): `denom` and `t` must be finite.
    #[inline]
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<f32> {
        let denom = self.normal.dot(ray.dir);
        if denom == 0.0 || !denom.is_finite() {
            return None;
        }
        let t = self.normal.dot(self.point - ray.origin) / denom;
        (t >= ray.t_min && t <= ray.t_max && t.is_finite()).then_some(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_hit_from_both_sides() {
        let p = Plane::new(Vec3::new(0.0, -1.0, 0.0), Vec3::Y);
        assert_eq!(p.intersect(&Ray::new(Vec3::ZERO, -Vec3::Y)), Some(1.0));
        let r = Ray::new(Vec3::new(0.0, -3.0, 0.0), Vec3::Y);
        assert_eq!(p.intersect(&r), Some(2.0));
        assert_eq!(p.intersect(&Ray::new(Vec3::ZERO, Vec3::Y)), None);
    }

    #[test]
    fn parallel_ray_does_not_hit() {
        let p = Plane::new(Vec3::ZERO, Vec3::Y);
        assert_eq!(p.intersect(&Ray::new(Vec3::Y, Vec3::X)), None);
        // Lying in the plane.
        assert_eq!(p.intersect(&Ray::new(Vec3::ZERO, Vec3::X)), None);
    }

    /// Regression (tests/tests/adversarial.rs): an infinite direction component gave
    /// `t = -0.0` and an infinite origin `t = inf`, both accepted as hits.
    #[test]
    fn rays_with_infinite_components_do_not_hit() {
        let p = Plane::new(Vec3::new(0.0, -1.0, 0.0), Vec3::Y);
        let up = Vec3::new(-0.01, f32::INFINITY, -1.0);
        assert_eq!(p.intersect(&Ray::new(Vec3::new(0.2, 0.3, 6.0), up)), None);
        let far = Vec3::new(0.0, f32::INFINITY, 0.0);
        assert_eq!(p.intersect(&Ray::new(far, -Vec3::Y)), None);
        assert_eq!(p.intersect(&Ray::new(Vec3::ZERO, Vec3::NAN)), None);
    }
}
