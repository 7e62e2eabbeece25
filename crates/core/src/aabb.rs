//! Axis-aligned bounding boxes and the conservative ray/box (slab) test.

use crate::ray::Ray;
use glam::Vec3;

/// An axis-aligned box. The empty box has `min = +inf`, `max = -inf`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

/// `1 + 2 * gamma(3)` with `gamma(n) = n * eps / (1 - n * eps)` and `eps = 2^-24` (pbrt):
/// scaling the far distance by this makes the f32 slab test conservative (Ize 2013).
const FAR_SCALE: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box: the identity of [`Aabb::union`].
    pub const EMPTY: Self = Self {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    /// A box from two corners.
    #[inline]
    #[must_use]
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The smallest box holding all `points`.
    #[must_use]
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Self {
        points.into_iter().fold(Self::EMPTY, Self::grow)
    }

    /// This box grown to hold `p`.
    #[inline]
    #[must_use]
    pub fn grow(self, p: Vec3) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// The smallest box holding both.
    #[inline]
    #[must_use]
    pub fn union(self, other: Self) -> Self {
        Self {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// True when `min <= max` on every axis.
    #[inline]
    #[must_use]
    pub fn is_empty(&self) -> bool {
        !(self.min.cmple(self.max).all())
    }

    /// `max - min`.
    #[inline]
    #[must_use]
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// The centre point.
    #[inline]
    #[must_use]
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Surface area (0 for the empty box).
    #[inline]
    #[must_use]
    pub fn surface_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// True when `other` lies inside this box (boundaries included).
    #[inline]
    #[must_use]
    pub fn contains(&self, other: &Self) -> bool {
        self.min.cmple(other.min).all() && self.max.cmpge(other.max).all()
    }

    /// Conservative slab test: the entry distance of `ray` into the box, clamped to
    /// `[ray.t_min, t_max]`, or `None` when the ray certainly misses that stretch.
    ///
    /// Conservative means it may accept a ray that misses, never reject one that hits: the
    /// far distance is scaled by `1 + 2 gamma(3)` (Ize, "Robust BVH Ray Traversal", JCGT
    /// 2013), and the `0 * inf = NaN` of a ray parallel to a slab and starting exactly on
    /// its plane leaves that axis unconstrained instead of poisoning the result. A ray
    /// parallel to a slab and outside it gets `+-inf` distances and is rejected.
    #[inline]
    #[must_use]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let mut t0 = ray.t_min;
        let mut t1 = t_max;
        for axis in 0..3 {
            let inv = ray.inv_dir[axis];
            // Pick the slab planes by the direction's sign (not by swapping distances), so
            // that the empty box stays empty.
            let (lo, hi) = if inv >= 0.0 {
                (self.min[axis], self.max[axis])
            } else {
                (self.max[axis], self.min[axis])
            };
            let near = (lo - ray.origin[axis]) * inv;
            let far = (hi - ray.origin[axis]) * inv * FAR_SCALE;
            // Written so that a NaN bound compares false and keeps the interval.
            if near > t0 {
                t0 = near;
            }
            if far < t1 {
                t1 = far;
            }
            if t0 > t1 {
                return None;
            }
        }
        Some(t0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Aabb {
        Aabb::new(Vec3::ZERO, Vec3::ONE)
    }

    #[test]
    fn hit_and_miss() {
        let r = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::Z);
        assert_eq!(unit().intersect(&r, f32::INFINITY), Some(1.0));
        let r = Ray::new(Vec3::new(1.5, 0.5, -1.0), Vec3::Z);
        assert_eq!(unit().intersect(&r, f32::INFINITY), None);
        // Beyond t_max.
        let r = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::Z);
        assert_eq!(unit().intersect(&r, 0.5), None);
    }

    #[test]
    fn ray_starting_inside_enters_at_t_min() {
        let r = Ray::new(Vec3::splat(0.5), Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(unit().intersect(&r, f32::INFINITY), Some(0.0));
    }

    #[test]
    fn parallel_rays_on_and_off_the_slab_planes() {
        // Parallel to x slabs, lying exactly in the plane x = 0: 0 * inf = NaN must not reject.
        let r = Ray::new(Vec3::new(0.0, 0.5, -1.0), Vec3::Z);
        assert_eq!(unit().intersect(&r, f32::INFINITY), Some(1.0));
        let r = Ray::new(Vec3::new(1.0, 0.5, -1.0), Vec3::Z);
        assert_eq!(unit().intersect(&r, f32::INFINITY), Some(1.0));
        // Negative zero direction component.
        let r = Ray::new(Vec3::new(1.0, 0.5, -1.0), Vec3::new(-0.0, 0.0, 1.0));
        assert!(unit().intersect(&r, f32::INFINITY).is_some());
        // Parallel and outside.
        let r = Ray::new(Vec3::new(1.0001, 0.5, -1.0), Vec3::Z);
        assert_eq!(unit().intersect(&r, f32::INFINITY), None);
    }

    #[test]
    fn zero_extent_box() {
        let flat = Aabb::new(Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 1.0, 1.0));
        let r = Ray::new(Vec3::new(0.5, 0.5, 0.0), Vec3::Z);
        assert_eq!(flat.intersect(&r, f32::INFINITY), Some(1.0));
    }

    #[test]
    fn empty_box() {
        let r = Ray::new(Vec3::ZERO, Vec3::X);
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.intersect(&r, f32::INFINITY), None);
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
    }
}
