//! Triangles and the watertight ray/triangle test.

use crate::aabb::Aabb;
use crate::hit::PrimHit;
use crate::ray::Ray;
use crate::stack::cull_bound;
use glam::Vec3;

/// A triangle by its three vertices (counter-clockwise seen from the side its normal points
/// to).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// The vertices `v0, v1, v2`.
    pub v: [Vec3; 3],
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
    /// This routine is the definition of a triangle hit: the SIMD kernels reproduce its
    /// operations in this order (the GPU kernels its edge test alone, within their
    /// tolerance). `t = T / det`, `u = V / det` (the weight of `v1`),
    /// `v = W / det` (the weight of `v2`); the sub-primitive id is 0.
    ///
    /// A hit also needs the ray to enter the triangle's box by then
    /// ([`Triangle::box_entered_by`]). For a ray nearly parallel to a long, thin
    /// triangle, the edge functions (rounded in the sheared frame) can accept a ray that
    /// passes beside it, at a `t` whose point lies outside the triangle's box: on Sponza, a
    /// sliver 11 units long and 0.01 wide was reported hit by an ambient-occlusion ray
    /// leaving its neighbour at 0.1 degrees to its plane, 0.005 from it, and no tree
    /// visits a box that ray never enters, so `naive` and every BVH disagreed. With the
    /// box check, every accelerator's conservative culling sees every hit.
    #[inline]
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        self.edge_test(ray)
            .filter(|hit| self.box_entered_by(ray, hit.t))
    }

    /// The watertight test alone (no box check), as [`Triangle::intersect`] describes it.
    #[inline]
    fn edge_test(&self, ray: &Ray) -> Option<PrimHit> {
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
        Some(PrimHit {
            t,
            sub: 0,
            u: v / det,
            v: w / det,
        })
    }

    /// Whether `ray` enters the triangle's box at or before the early-exit bound of a hit
    /// at `t` ([`crate::cull_bound`]), by the conservative slab test every tree culls
    /// with. A box holding the triangle is entered at least as early by the same test
    /// (its rounding is monotonic), so no accelerator culls a hit that passes this check:
    /// the premise of the equivalence contract's conservative culling ([`crate::Accel`]).
    /// The slack absorbs the few ulps by which the box's computed entry can exceed a
    /// triangle's computed `t` on a true hit.
    #[inline]
    #[must_use]
    pub fn box_entered_by(&self, ray: &Ray, t: f32) -> bool {
        self.bounds().intersect(ray, cull_bound(t)).is_some()
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

    /// A ray nearly parallel to a long sliver, passing beside it (Sponza's triangle 10153,
    /// and an ambient-occlusion ray leaving its neighbour): the edge functions accept it at
    /// a `t` whose point lies outside the sliver's box, which the ray never enters.
    #[test]
    fn a_hit_outside_the_triangles_box_is_no_hit() {
        let sliver = Triangle::new(
            Vec3::new(0.00724, 5.838312, 2.429488),
            Vec3::new(0.00724, 5.830812, 2.441489),
            Vec3::new(-10.83276, 5.830812, 2.441488),
        );
        let ray = Ray::with_interval(
            Vec3::new(-8.515367, 5.8383155, 2.429439),
            Vec3::new(-0.65317875, 0.40024507, -0.6427764),
            0.000_265_766,
            4.159_358_5,
        );
        let edges = sliver
            .edge_test(&ray)
            .expect("the edge functions accept the ray");
        assert_eq!(edges.t, 0.011_067_975);
        assert_eq!(sliver.bounds().intersect(&ray, f32::INFINITY), None);
        assert_eq!(sliver.intersect(&ray), None);
    }

    /// The box check keeps true hits where the box is flat (an axis-aligned triangle, whose
    /// box entry and `t` come from different arithmetic), at grazing angles too.
    #[test]
    fn flat_boxes_keep_their_hits() {
        let floor = Triangle::new(
            Vec3::new(-20.0, 0.0, -1.0),
            Vec3::new(20.0, 0.0, -1.0),
            Vec3::new(0.0, 0.0, 20.0),
        );
        for (o, d) in [
            (Vec3::new(0.3, 1.0, 0.3), Vec3::new(0.001, -1.0, 0.0)),
            (Vec3::new(-10.0, 0.01, 0.2), Vec3::new(1.0, -0.001, 0.0)),
            (Vec3::new(7.1, 3.3, -0.9), Vec3::new(-0.3, -0.7, 1.1)),
            (Vec3::new(0.1, -0.002, 0.1), Vec3::new(0.0001, 1.0, 0.0001)),
        ] {
            let ray = Ray::new(o, d);
            let edges = floor.edge_test(&ray).expect("the ray crosses the floor");
            assert_eq!(floor.intersect(&ray), Some(edges), "{o} {d}");
        }
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
