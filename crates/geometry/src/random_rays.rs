//! Seeded random rays: the `incoherent` ray set of benchmarks and tests, a pure function of
//! the scene's box, the count and the seed, so every backend and peer traces the same rays.

use crate::aabb::Aabb;
use crate::ray::Ray;
use crate::sampling::{pcg3d, to_unit_f32};
use glam::Vec3;

/// `count` incoherent rays for `bounds` under `seed`: ray `i` starts at a uniform point of
/// the box and points in a uniform direction (unit length), both from the counter-based
/// hash keyed by `(i, seed)`. An empty box puts every origin at zero.
#[must_use]
pub fn incoherent(bounds: Aabb, count: usize, seed: u32) -> Vec<Ray> {
    let (min, extent) = if bounds.is_empty() {
        (Vec3::ZERO, Vec3::ZERO)
    } else {
        (bounds.min, bounds.extent())
    };
    (0..count as u32)
        .map(|i| {
            let [a, b, c] = pcg3d([i, seed, 0x5EED_0001]);
            let [d, e, _] = pcg3d([i, seed, 0x5EED_0002]);
            let origin = min + extent * Vec3::new(to_unit_f32(a), to_unit_f32(b), to_unit_f32(c));
            let z = 1.0 - 2.0 * to_unit_f32(d);
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = std::f32::consts::TAU * to_unit_f32(e);
            Ray::new(origin, Vec3::new(r * phi.cos(), r * phi.sin(), z))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn incoherent_rays_are_seeded_inside_and_unit() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::new(2.0, 1.0, 1.0));
        let rays = incoherent(b, 1000, 7);
        assert_eq!(rays, incoherent(b, 1000, 7));
        assert_ne!(rays, incoherent(b, 1000, 8));
        for r in &rays {
            assert!(b.contains(&Aabb::new(r.origin, r.origin)));
            assert!((r.dir.length() - 1.0).abs() < 1e-5);
        }
        let mean: Vec3 = rays.iter().map(|r| r.dir).sum::<Vec3>() / 1000.0;
        assert!(
            mean.length() < 0.1,
            "directions are not uniform: mean {mean}"
        );
    }
}
