//! Triangles and the watertight ray/triangle test.

use crate::aabb::Aabb;
use crate::ray::Ray;
use glam::Vec3;

/// A triangle by its three vertices (counter-clockwise seen from the side its normal points
/// to).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// The vertices `v0, v1, v2`.
    pub v: [Vec3; 3],
}

/// Where a ray crosses a triangle: distance and the barycentric weights of `v1` and `v2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter.
    pub t: f32,
    /// Weight of `v1`.
    pub u: f32,
    /// Weight of `v2`.
    pub v: f32,
}

impl Triangle {
    /// A triangle from three vertices.
    #[inline]
    #[must_use]
    pub fn new(v0: Vec3, v1: Vec3, v2: Vec3) -> Self {
        Self { v: [v0, v1, v2] }
    }

    /// The bounding box.
    #[inline]
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        Aabb::new(
            self.v[0].min(self.v[1]).min(self.v[2]),
            self.v[0].max(self.v[1]).max(self.v[2]),
        )
    }

    /// Unit geometric normal `normalize((v1 - v0) x (v2 - v0))`; `+Y` for a degenerate
    /// triangle (which is never hit anyway).
    #[inline]
    #[must_use]
    pub fn normal(&self) -> Vec3 {
        (self.v[1] - self.v[0])
            .cross(self.v[2] - self.v[0])
            .normalize_or(Vec3::Y)
    }

    /// The watertight ray/triangle test of Woop, Benthin and Wald, "Watertight Ray/Triangle
    /// Intersection", JCGT 2(1), 2013, without backface culling.
    ///
    /// The vertices are translated to the ray origin, permuted so that the ray's dominant
    /// axis is z, and sheared so that the ray becomes the +z axis ([`Ray`] caches the
    /// permutation and shear). The 2D edge functions `U, V, W` then decide inside/outside
    /// with consistent signs on shared edges and vertices, so no ray slips between two
    /// triangles of a closed mesh; where one of them is exactly 0 they are recomputed in
    /// f64. Hits on an edge or vertex count (both neighbours report them; the tie rule of
    /// [`crate::Hit::closer`] picks one).
    ///
    /// This routine is the definition of a triangle hit: SIMD and GPU backends reproduce
    /// its operations in this order. `t = T / det`, `u = U / det`, `v = V / det`.
    #[inline]
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<TriangleHit> {
        let (kx, ky, kz) = (ray.kx as usize, ray.ky as usize, ray.kz as usize);
        let (sx, sy, sz) = (ray.shear.x, ray.shear.y, ray.shear.z);

        let a = self.v[0] - ray.origin;
        let b = self.v[1] - ray.origin;
        let c = self.v[2] - ray.origin;

        // Permute the coordinates without bounds checks: pad to four and mask the index.
        let a = [a.x, a.y, a.z, 0.0];
        let b = [b.x, b.y, b.z, 0.0];
        let c = [c.x, c.y, c.z, 0.0];
        let (kx, ky, kz) = (kx & 3, ky & 3, kz & 3);

        let ax = a[kx] - sx * a[kz];
        let ay = a[ky] - sy * a[kz];
        let bx = b[kx] - sx * b[kz];
        let by = b[ky] - sy * b[kz];
        let cx = c[kx] - sx * c[kz];
        let cy = c[ky] - sy * c[kz];

        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;

        // Non-short-circuit `|`: one well-predicted branch instead of three random ones.
        if (u == 0.0) | (v == 0.0) | (w == 0.0) {
            let (ax, ay, bx, by, cx, cy) = (
                f64::from(ax),
                f64::from(ay),
                f64::from(bx),
                f64::from(by),
                f64::from(cx),
                f64::from(cy),
            );
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }

        let any_negative = (u < 0.0) | (v < 0.0) | (w < 0.0);
        let any_positive = (u > 0.0) | (v > 0.0) | (w > 0.0);
        if any_negative & any_positive {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }

        let az = sz * a[kz];
        let bz = sz * b[kz];
        let cz = sz * c[kz];
        let t_scaled = u * az + v * bz + w * cz;
        let t = t_scaled / det;
        // Range checks reject NaN too (rays with NaN or zero directions).
        if t < ray.t_min || t > ray.t_max || t.is_nan() {
            return None;
        }
        Some(TriangleHit {
            t,
            u: v / det,
            v: w / det,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> Triangle {
        Triangle::new(
            Vec3::new(-1.0, -1.0, 2.0),
            Vec3::new(1.0, -1.0, 2.0),
            Vec3::new(0.0, 1.0, 2.0),
        )
    }

    #[test]
    fn analytic_hit_and_barycentrics() {
        let h = tri().intersect(&Ray::new(Vec3::ZERO, Vec3::Z)).unwrap();
        assert_eq!(h.t, 2.0);
        assert!(
            (h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6,
            "{h:?}"
        );
        // From behind (no culling), oblique.
        let r = Ray::new(Vec3::new(0.0, 0.0, 4.0), Vec3::new(0.0, 0.0, -2.0));
        assert_eq!(tri().intersect(&r).unwrap().t, 1.0);
    }

    #[test]
    fn misses_outside_and_behind_and_beyond_t_max() {
        assert!(
            tri()
                .intersect(&Ray::new(Vec3::new(2.0, 0.0, 0.0), Vec3::Z))
                .is_none()
        );
        assert!(tri().intersect(&Ray::new(Vec3::ZERO, -Vec3::Z)).is_none());
        let r = Ray::with_interval(Vec3::ZERO, Vec3::Z, 0.0, 1.5);
        assert!(tri().intersect(&r).is_none());
    }

    #[test]
    fn degenerate_triangles_are_never_hit() {
        let p = Vec3::new(0.0, 0.0, 2.0);
        let repeated = Triangle::new(p, p, Vec3::new(1.0, 1.0, 2.0));
        let point = Triangle::new(p, p, p);
        for t in [repeated, point] {
            for dir in [Vec3::Z, Vec3::new(0.5, 0.5, 2.0), Vec3::new(0.0, 0.0, 1.0)] {
                assert!(t.intersect(&Ray::new(Vec3::ZERO, dir)).is_none());
            }
        }
    }

    #[test]
    fn ray_parallel_to_triangle_plane_misses() {
        let r = Ray::new(Vec3::new(-5.0, 0.0, 2.0), Vec3::X);
        assert!(tri().intersect(&r).is_none());
    }

    #[test]
    fn shared_edge_is_hit_by_exactly_one_side_or_both() {
        // Two triangles sharing the edge x = 0; a ray through the edge must hit at least one.
        let t1 = Triangle::new(
            Vec3::new(0.0, -1.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
            Vec3::new(-1.0, 0.0, 1.0),
        );
        let t2 = Triangle::new(
            Vec3::new(0.0, 1.0, 1.0),
            Vec3::new(0.0, -1.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
        );
        for i in 0..100 {
            let y = -0.99 + i as f32 * 0.0198;
            let r = Ray::new(
                Vec3::new(0.3, 0.1, -2.0),
                Vec3::new(0.0, y, 1.0) - Vec3::new(0.3, 0.1, -2.0),
            );
            assert!(
                t1.intersect(&r).is_some() || t2.intersect(&r).is_some(),
                "y = {y}"
            );
        }
    }

    #[test]
    fn nan_and_zero_rays_miss() {
        assert!(tri().intersect(&Ray::new(Vec3::ZERO, Vec3::ZERO)).is_none());
        assert!(
            tri()
                .intersect(&Ray::new(Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 1.0)))
                .is_none()
        );
        assert!(
            tri()
                .intersect(&Ray::new(Vec3::splat(f32::NAN), Vec3::Z))
                .is_none()
        );
    }
}
