//! Axis-aligned bounding boxes and the conservative ray/box (slab) test.

use crate::ray::Ray;
use glam::{Vec3, Vec3A};

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
pub const FAR_SCALE: f32 =
    1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

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
    /// 2013). Each axis's near and far planes are picked by the sign of the inverse
    /// direction, and a `0 * inf = NaN` (a ray parallel to a slab, starting exactly in one of
    /// its planes) leaves that axis unconstrained instead of poisoning the result; a ray
    /// parallel to a slab and outside it gets `+-inf` on both planes and is rejected. The
    /// arithmetic is four-wide SIMD (`Vec3A`) without branches.
    #[inline]
    #[must_use]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        SlabRay::new(ray).entry(Vec3A::from(self.min), Vec3A::from(self.max), t_max)
    }
}

/// A ray prepared for many slab tests (what [`Aabb::intersect`] does, with the per-ray work
/// hoisted out of a traversal loop): origin, inverse direction and its signs in SIMD
/// registers.
#[derive(Clone, Copy, Debug)]
pub struct SlabRay {
    origin: Vec3A,
    inv: Vec3A,
    positive: glam::BVec3A,
    t_min: f32,
}

impl SlabRay {
    /// Prepares `ray`.
    #[inline]
    #[must_use]
    pub fn new(ray: &Ray) -> Self {
        let inv = Vec3A::from(ray.inv_dir);
        Self {
            origin: Vec3A::from(ray.origin),
            inv,
            positive: inv.cmpge(Vec3A::ZERO),
            t_min: ray.t_min,
        }
    }

    /// The entry distance into the box `[min, max]` clamped to `[t_min, t_max]`, or `None`:
    /// exactly [`Aabb::intersect`].
    #[inline]
    #[must_use]
    pub fn entry(&self, min: Vec3A, max: Vec3A, t_max: f32) -> Option<f32> {
        let near = (Vec3A::select(self.positive, min, max) - self.origin) * self.inv;
        let far = (Vec3A::select(self.positive, max, min) - self.origin) * self.inv;
        // 0 * inf = NaN: the ray lies in that slab's plane and the axis must not constrain
        // it. `x.max(splat)` is `_mm_max_ps(x, splat)` (second operand on NaN) or
        // `f32::max` (the non-NaN operand): either way a NaN lane becomes the bound.
        let t0 = near.max(Vec3A::splat(self.t_min)).max_element();
        let t1 = (far * FAR_SCALE).min(Vec3A::splat(t_max)).min_element();
        (t0 <= t1).then_some(t0)
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
        assert!(!Aabb::new(Vec3::ZERO, Vec3::ZERO).is_empty());
    }

    #[test]
    fn nan_free_for_rays_in_slab_planes() {
        // Every combination of origins on the box's faces and edges with axis directions.
        for &o in &[
            Vec3::ZERO,
            Vec3::ONE,
            Vec3::new(0.0, 1.0, 0.5),
            Vec3::new(1.0, 0.0, 1.0),
        ] {
            for axis in 0..3 {
                let mut d = Vec3::ZERO;
                d[axis] = 1.0;
                let back = o - d * 2.0;
                let r = Ray::new(back, d);
                let t = unit().intersect(&r, f32::INFINITY);
                assert!(t.is_some_and(|t| t.is_finite()), "{back} {d}: {t:?}");
            }
        }
    }
}
