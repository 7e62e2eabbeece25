//! Rays with the per-ray data the intersection routines need, computed once.

use glam::Vec3;

/// A ray `origin + t * dir` restricted to the interval `[t_min, t_max]`.
///
/// Construction caches the inverse direction (for slab tests) and the axis permutation and
/// shear constants of the watertight triangle test (Woop, Benthin and Wald, JCGT 2013), so
/// that each triangle test does no per-ray work. Build rays with [`Ray::new`] or
/// [`Ray::with_interval`]; the fields stay public for reading.
///
/// The layout is C's, with every `f32` first: `origin`, `dir`, `inv_dir`, `t_min`, `t_max`
/// and `shear` are the ray's first fourteen floats, in that order ([`Ray::FLOATS`]), so
/// SIMD code can load several consecutive fields of a ray at once and transpose rays into
/// lanes without a round trip through memory.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Ray {
    /// Where the ray starts.
    pub origin: Vec3,
    /// The direction; not required to be normalised (camera rays are).
    pub dir: Vec3,
    /// `1 / dir`, component-wise (infinite for zero components).
    pub inv_dir: Vec3,
    /// Hits closer than this are ignored.
    pub t_min: f32,
    /// Hits farther than this are ignored.
    pub t_max: f32,
    /// Watertight test: shear constants `(dir[kx] / dir[kz], dir[ky] / dir[kz], 1 / dir[kz])`.
    pub shear: Vec3,
    /// Watertight test: the axis along which `dir` has its largest magnitude.
    pub kz: u8,
    /// Watertight test: the first of the other two axes (swapped when `dir[kz] < 0`, which
    /// keeps the triangle's winding).
    pub kx: u8,
    /// Watertight test: the second of the other two axes.
    pub ky: u8,
}

// The layout [`Ray`] documents: its floats first, without padding.
const _: () = {
    use std::mem::offset_of;
    assert!(offset_of!(Ray, origin) == 0);
    assert!(offset_of!(Ray, dir) == 12);
    assert!(offset_of!(Ray, inv_dir) == 24);
    assert!(offset_of!(Ray, t_min) == 36);
    assert!(offset_of!(Ray, t_max) == 40);
    assert!(offset_of!(Ray, shear) == 44);
    assert!(offset_of!(Ray, kz) == 4 * Ray::FLOATS);
};

impl Ray {
    /// How many `f32`s the ray starts with (`origin`, `dir`, `inv_dir`, `t_min`, `t_max`,
    /// `shear`, in that order, without padding).
    pub const FLOATS: usize = 14;

    /// A ray over `[0, inf)`.
    #[inline]
    #[must_use]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self::with_interval(origin, dir, 0.0, f32::INFINITY)
    }

    /// A ray over `[t_min, t_max]`. A ray that is not valid ([`Ray::is_valid`]), or has a
    /// NaN bound, gets the empty interval `[inf, -inf]`, so that every primitive's range
    /// check and every slab test rejects it: without that, an infinite direction component
    /// shears every triangle to `t = 0` and hits it, a direction whose squared length
    /// overflows gives spheres a `t = -0` hit, and a NaN `t_min` passed the triangle's
    /// range check but no slab test. A negative `t_min` is raised to 0: the slab tests'
    /// conservative far scaling (`far * FAR_SCALE`) holds for distances ahead of the
    /// origin only, and accelerators culled hits behind it that naive found.
    #[inline]
    #[must_use]
    pub fn with_interval(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Self {
        let valid = valid(origin, dir) && !t_min.is_nan() && !t_max.is_nan();
        let (t_min, t_max) = if valid {
            (t_min.max(0.0), t_max)
        } else {
            (f32::INFINITY, f32::NEG_INFINITY)
        };
        let abs = dir.abs();
        // Largest component; ties go to the lower axis. NaN compares false and lands on z.
        let kz: usize = if abs.x >= abs.y && abs.x >= abs.z {
            0
        } else if abs.y >= abs.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let shear = Vec3::new(dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]);
        Self {
            origin,
            dir,
            inv_dir: dir.recip(),
            t_min,
            t_max,
            kz: kz as u8,
            kx: kx as u8,
            ky: ky as u8,
            shear,
        }
    }

    /// The point at parameter `t`.
    #[inline]
    #[must_use]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }

    /// True when the origin is finite and the direction's squared length is a positive
    /// finite `f32` (about `1e-22 < |dir| < 1.8e19`, so that quadratic tests neither
    /// overflow nor divide by zero): the rays that can hit anything. Others (NaN, infinite,
    /// zero, vanishing or overflowing directions) miss everywhere.
    #[inline]
    #[must_use]
    pub fn is_valid(&self) -> bool {
        valid(self.origin, self.dir)
    }

    /// The same ray with `t_max` replaced.
    #[inline]
    #[must_use]
    pub fn clipped(&self, t_max: f32) -> Self {
        Self { t_max, ..*self }
    }
}

/// [`Ray::is_valid`] of an origin and a direction.
#[inline]
fn valid(origin: Vec3, dir: Vec3) -> bool {
    let length2 = dir.length_squared();
    origin.is_finite() && length2 > 0.0 && length2.is_finite()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permutation_picks_largest_axis_and_keeps_winding() {
        let r = Ray::new(Vec3::ZERO, Vec3::new(0.1, -3.0, 0.5));
        assert_eq!(r.kz, 1);
        // dir[kz] < 0 swaps kx and ky.
        assert_eq!((r.kx, r.ky), (0, 2));
        let r = Ray::new(Vec3::ZERO, Vec3::new(0.1, 3.0, 0.5));
        assert_eq!((r.kx, r.ky), (2, 0));
        assert_eq!(r.shear.z, 1.0 / 3.0);
    }

    #[test]
    fn validity() {
        assert!(Ray::new(Vec3::ZERO, Vec3::X).is_valid());
        assert!(!Ray::new(Vec3::ZERO, Vec3::ZERO).is_valid());
        assert!(!Ray::new(Vec3::splat(f32::NAN), Vec3::X).is_valid());
        assert!(!Ray::new(Vec3::ZERO, Vec3::new(0.0, 1e30, 0.0)).is_valid());
        assert!(!Ray::new(Vec3::ZERO, Vec3::splat(1e-40)).is_valid());
        assert!(Ray::new(Vec3::ZERO, Vec3::new(0.0, 1e-40, 1e-3)).is_valid());
    }

    /// Regression (tests/tests/adversarial.rs): a direction with an infinite component
    /// made the shear constants 0 and the triangle test returned `t = 0` hits.
    #[test]
    fn invalid_rays_hit_nothing() {
        let t = crate::Triangle::new(
            Vec3::new(-1.0, -1.0, 2.0),
            Vec3::new(1.0, -1.0, 2.0),
            Vec3::new(0.0, 1.0, 2.0),
        );
        for dir in [
            Vec3::new(0.01, 0.02, f32::INFINITY),
            Vec3::new(f32::NEG_INFINITY, 0.0, 1.0),
            Vec3::new(0.0, f32::NAN, 1.0),
            Vec3::ZERO,
        ] {
            let r = Ray::new(Vec3::ZERO, dir);
            assert!(t.intersect(&r).is_none(), "{dir}");
            let b = crate::Aabb::new(Vec3::splat(-1.0), Vec3::ONE);
            assert!(b.intersect(&r, r.t_max).is_none(), "{dir}");
        }
        // |dir|^2 overflows: the sphere test returned t = -0 from inside.
        let huge = Ray::new(Vec3::ZERO, Vec3::new(-0.01, 1e30, -1.0));
        assert!(
            crate::Sphere::new(Vec3::ZERO, 1.0)
                .intersect(&huge)
                .is_none()
        );
        // A NaN t_min passed the triangle's range check.
        let nan = Ray::with_interval(Vec3::ZERO, Vec3::Z, f32::NAN, 10.0);
        assert!(t.intersect(&nan).is_none());
        // A negative t_min is raised to 0 (no hit behind the origin).
        let behind = Ray::with_interval(Vec3::new(0.0, 0.0, 4.0), Vec3::Z, -10.0, 10.0);
        assert_eq!(behind.t_min, 0.0);
        assert!(t.intersect(&behind).is_none());
        let far = Ray::new(Vec3::new(0.0, 0.0, f32::NEG_INFINITY), Vec3::Z);
        assert!(t.intersect(&far).is_none());
        assert!(
            crate::Sphere::new(Vec3::ZERO, 1.0)
                .intersect(&far)
                .is_none()
        );
    }
}
