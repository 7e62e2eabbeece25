//! Spheres and the numerically stable ray/sphere test.

use crate::aabb::Aabb;
use crate::ray::Ray;
use glam::Vec3;

/// A sphere given by centre and radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: Vec3,
    /// Radius (positive).
    pub radius: f32,
}

impl Sphere {
    /// A sphere from centre and radius.
    #[inline]
    #[must_use]
    pub fn new(center: Vec3, radius: f32) -> Self {
        Self { center, radius }
    }

    /// The bounding box, padded by `radius * 2^-11`.
    ///
    /// The padding covers the rounding of grazing hits: near a tangent the discriminant
    /// loses half its bits, so a computed hit point can lie up to about `sqrt(eps) * r`
    /// (`~2.4e-4 r`) outside the true sphere, and an unpadded box could cull it.
    #[inline]
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        let r = Vec3::splat(self.radius.abs() * (1.0 + 1.0 / 2048.0));
        Aabb::new(self.center - r, self.center + r)
    }

    /// The smallest root of `|o + t d - c|^2 = r^2` inside `[ray.t_min, ray.t_max]`, so a
    /// ray starting inside hits the far side.
    ///
    /// Stable form of Haines et al., Ray Tracing Gems ch. 7: the discriminant is computed
    /// from the distance between the centre and the line (no cancellation for small
    /// spheres far away), and the two roots as `c / q` and `q / a` with
    /// `q = b + sign(b) sqrt(a * disc)` (no cancellation between `b` and the root).
    #[inline]
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<f32> {
        let f = ray.origin - self.center;
        let d = ray.dir;
        let a = d.dot(d);
        let b = -f.dot(d);
        let l = f + d * (b / a);
        let r2 = self.radius * self.radius;
        let disc = r2 - l.dot(l);
        // Also rejects NaN (`is_nan` is false for negative numbers).
        if disc < 0.0 || disc.is_nan() {
            return None;
        }
        let c = f.dot(f) - r2;
        // sqrt(a) * sqrt(disc), not sqrt(a * disc): the product overflows f32 once
        // |d| * r passes 1.8e19 (scenes at 1e15 with unnormalised directions).
        let q = b + (a.sqrt() * disc.sqrt()).copysign(b);
        let t0 = c / q;
        let t1 = q / a;
        let (near, far) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
        if near >= ray.t_min && near <= ray.t_max {
            Some(near)
        } else if far >= ray.t_min && far <= ray.t_max {
            Some(far)
        } else {
            None
        }
    }

    /// Outward unit normal at `p` (a point on the sphere).
    #[inline]
    #[must_use]
    pub fn normal_at(&self, p: Vec3) -> Vec3 {
        ((p - self.center) / self.radius).normalize_or(Vec3::Y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_distance_from_outside() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, 5.0), 1.0);
        let r = Ray::new(Vec3::ZERO, Vec3::Z);
        assert_eq!(s.intersect(&r), Some(4.0));
        // Unnormalised direction: t scales inversely.
        let r = Ray::new(Vec3::ZERO, Vec3::Z * 2.0);
        assert_eq!(s.intersect(&r), Some(2.0));
    }

    #[test]
    fn ray_starting_inside_hits_far_side() {
        let s = Sphere::new(Vec3::ZERO, 2.0);
        let r = Ray::new(Vec3::ZERO, Vec3::X);
        assert_eq!(s.intersect(&r), Some(2.0));
    }

    #[test]
    fn behind_and_missing() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, -5.0), 1.0);
        assert_eq!(s.intersect(&Ray::new(Vec3::ZERO, Vec3::Z)), None);
        let s = Sphere::new(Vec3::new(0.0, 3.0, 5.0), 1.0);
        assert_eq!(s.intersect(&Ray::new(Vec3::ZERO, Vec3::Z)), None);
    }

    #[test]
    fn small_sphere_far_away_is_stable() {
        // The naive quadratic loses the hit entirely here (b^2 - ac cancels).
        let s = Sphere::new(Vec3::new(0.0, 0.0, 1.0e5), 0.01);
        let t = s.intersect(&Ray::new(Vec3::ZERO, Vec3::Z)).unwrap();
        assert!((t - (1.0e5 - 0.01)).abs() <= 1.0e5 * 1e-6, "t = {t}");
    }

    #[test]
    fn huge_coordinates_do_not_overflow() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, 4.0e15), 1.0e14);
        let r = Ray::new(Vec3::ZERO, Vec3::new(0.0, 0.0, 4.0e15));
        let t = s.intersect(&r).unwrap();
        assert!((t - 0.975).abs() < 1e-5, "t = {t}");
    }

    #[test]
    fn nan_ray_misses() {
        let s = Sphere::new(Vec3::ZERO, 1.0);
        let r = Ray::new(Vec3::new(f32::NAN, 0.0, -3.0), Vec3::Z);
        assert_eq!(s.intersect(&r), None);
        let r = Ray::new(Vec3::new(0.0, 0.0, -3.0), Vec3::ZERO);
        assert_eq!(s.intersect(&r), None);
    }
}
