//! Rays with the per-ray data the intersection routines need, computed once.

use glam::Vec3;

/// A ray `origin + t * dir` restricted to the interval `[t_min, t_max]`.
///
/// Construction caches the inverse direction (for slab tests) and the axis permutation and
/// shear constants of the watertight triangle test (Woop, Benthin and Wald, JCGT 2013), so
/// that each triangle test does no per-ray work. Build rays with [`Ray::new`] or
/// [`Ray::with_interval`]; the fields stay public for reading.
#[derive(Clone, Copy, Debug, PartialEq)]
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
    /// Watertight test: the axis along which `dir` has its largest magnitude.
    pub kz: u8,
    /// Watertight test: the first of the other two axes (swapped when `dir[kz] < 0`, which
    /// keeps the triangle's winding).
    pub kx: u8,
    /// Watertight test: the second of the other two axes.
    pub ky: u8,
    /// Watertight test: shear constants `(dir[kx] / dir[kz], dir[ky] / dir[kz], 1 / dir[kz])`.
    pub shear: Vec3,
}

impl Ray {
    /// A ray over `[0, inf)`.
    #[inline]
    #[must_use]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self::with_interval(origin, dir, 0.0, f32::INFINITY)
    }

    /// A ray over `[t_min, t_max]`.
    #[inline]
    #[must_use]
    pub fn with_interval(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Self {
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

    /// True when origin and direction are finite and the direction is not zero: the rays
    /// that can hit anything. Others (NaN, infinite, zero direction) miss everywhere.
    #[inline]
    #[must_use]
    pub fn is_valid(&self) -> bool {
        self.origin.is_finite() && self.dir.is_finite() && self.dir != Vec3::ZERO
    }

    /// The same ray with `t_max` replaced.
    #[inline]
    #[must_use]
    pub fn clipped(&self, t_max: f32) -> Self {
        Self { t_max, ..*self }
    }
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
    }
}
