//! Spheres and the numerically stable ray/sphere test.

use crate::aabb::Aabb;
use crate::hit::PrimHit;
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
    /// ray starting inside hits the far side (the surface parameters are filled in by
    /// [`Sphere::uv`] when the hit is completed).
    ///
    /// The roots are [`line_in_ball`]'s, the stable form of Haines et al., Ray Tracing Gems
    /// ch. 7.
    #[inline]
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        let (near, far) = line_in_ball(ray.origin - self.center, ray.dir, self.radius)?;
        if near >= ray.t_min && near <= ray.t_max {
            Some(PrimHit::at(near))
        } else if far >= ray.t_min && far <= ray.t_max {
            Some(PrimHit::at(far))
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

    /// The surface parameters of the point with outward normal `n`: longitude in `[0, 1)`
    /// and latitude in `[0, 1]` (0 at the top).
    #[inline]
    #[must_use]
    pub fn uv(n: Vec3) -> (f32, f32) {
        let u = (n.z.atan2(n.x) / std::f32::consts::TAU).rem_euclid(1.0);
        let v = n.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
        (u, v)
    }
}

/// Where the line `f + t d` is inside the ball of `radius` about the origin: its entry and
/// exit `t`, ascending, or `None` when it misses. The one root finder of
/// [`Sphere::intersect`] and of the CSG sphere and ellipsoid (`f` is the line's origin
/// relative to the centre).
///
/// Stable form of Haines et al., Ray Tracing Gems ch. 7: the discriminant is computed from
/// the distance between the centre and the line (no cancellation for small spheres far
/// away), and the two roots as `c / q` and `q / a` with `q = b + sign(b) sqrt(a * disc)` (no
/// cancellation between `b` and the root).
#[inline]
#[must_use]
pub(crate) fn line_in_ball(f: Vec3, d: Vec3, radius: f32) -> Option<(f32, f32)> {
    let a = d.dot(d);
    let b = -f.dot(d);
    let l = f + d * (b / a);
    let r2 = radius * radius;
    let disc = r2 - l.dot(l);
    // Also rejects NaN (`is_nan` is false for negative numbers).
    if disc < 0.0 || disc.is_nan() {
        return None;
    }
    let c = f.dot(f) - r2;
    // sqrt(a) * sqrt(disc), not sqrt(a * disc): the product overflows f32 once |d| * r
    // passes 1.8e19 (scenes at 1e15 with unnormalised directions).
    let q = b + (a.sqrt() * disc.sqrt()).copysign(b);
    let (t0, t1) = (c / q, q / a);
    Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_distance_from_outside() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, 5.0), 1.0);
        let r = Ray::new(Vec3::ZERO, Vec3::Z);
        assert_eq!(s.intersect(&r).map(|h| h.t), Some(4.0));
        // Unnormalised direction: t scales inversely.
        let r = Ray::new(Vec3::ZERO, Vec3::Z * 2.0);
        assert_eq!(s.intersect(&r).map(|h| h.t), Some(2.0));
    }

    #[test]
    fn ray_starting_inside_hits_far_side() {
        let s = Sphere::new(Vec3::ZERO, 2.0);
        let r = Ray::new(Vec3::ZERO, Vec3::X);
        assert_eq!(s.intersect(&r).map(|h| h.t), Some(2.0));
    }

    #[test]
    fn behind_and_missing() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, -5.0), 1.0);
        assert_eq!(
            s.intersect(&Ray::new(Vec3::ZERO, Vec3::Z)).map(|h| h.t),
            None
        );
        let s = Sphere::new(Vec3::new(0.0, 3.0, 5.0), 1.0);
        assert_eq!(
            s.intersect(&Ray::new(Vec3::ZERO, Vec3::Z)).map(|h| h.t),
            None
        );
    }

    #[test]
    fn small_sphere_far_away_is_stable() {
        // The naive quadratic loses the hit entirely here (b^2 - ac cancels).
        let s = Sphere::new(Vec3::new(0.0, 0.0, 1.0e5), 0.01);
        let t = s.intersect(&Ray::new(Vec3::ZERO, Vec3::Z)).unwrap().t;
        assert!((t - (1.0e5 - 0.01)).abs() <= 1.0e5 * 1e-6, "t = {t}");
    }

    #[test]
    fn huge_coordinates_do_not_overflow() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, 4.0e15), 1.0e14);
        let r = Ray::new(Vec3::ZERO, Vec3::new(0.0, 0.0, 4.0e15));
        let t = s.intersect(&r).unwrap().t;
        assert!((t - 0.975).abs() < 1e-5, "t = {t}");
    }

    #[test]
    fn nan_ray_misses() {
        let s = Sphere::new(Vec3::ZERO, 1.0);
        let r = Ray::new(Vec3::new(f32::NAN, 0.0, -3.0), Vec3::Z);
        assert_eq!(s.intersect(&r).map(|h| h.t), None);
        let r = Ray::new(Vec3::new(0.0, 0.0, -3.0), Vec3::ZERO);
        assert_eq!(s.intersect(&r).map(|h| h.t), None);
    }
}
