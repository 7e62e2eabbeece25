//! Bilinear patches and the ray/patch test of Reshetov, "Cool Patches: A Geometric Approach
//! to Ray/Bilinear Patch Intersections" (Ray Tracing Gems, ch. 8, 2019).

use crate::ray::Ray;
use glam::Vec3;

/// The bilinear patch `P(u, v) = (1-u)(1-v) q00 + u (1-v) q10 + u v q11 + (1-u) v q01`
/// through four corners (not necessarily coplanar).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BilinearPatch {
    /// Corner at `(u, v) = (0, 0)`.
    pub q00: Vec3,
    /// Corner at `(1, 0)`.
    pub q10: Vec3,
    /// Corner at `(1, 1)`.
    pub q11: Vec3,
    /// Corner at `(0, 1)`.
    pub q01: Vec3,
}

/// Where a ray meets a patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchHit {
    /// Ray parameter.
    pub t: f32,
    /// Patch parameter along `q00 -> q10`.
    pub u: f32,
    /// Patch parameter along `q00 -> q01`.
    pub v: f32,
}

impl BilinearPatch {
    /// The point at `(u, v)`.
    #[must_use]
    pub fn point(&self, u: f32, v: f32) -> Vec3 {
        let a = self.q00.lerp(self.q10, u);
        let b = self.q01.lerp(self.q11, u);
        a.lerp(b, v)
    }

    /// The unit normal `dP/du x dP/dv` at `(u, v)` (`+Y` where it vanishes).
    #[must_use]
    pub fn normal(&self, u: f32, v: f32) -> Vec3 {
        let du = (self.q10 - self.q00).lerp(self.q11 - self.q01, v);
        let dv = (self.q01 - self.q00).lerp(self.q11 - self.q10, u);
        du.cross(dv).normalize_or(Vec3::Y)
    }

    /// The closest hit inside `[ray.t_min, ray.t_max]`.
    ///
    /// Fixing `u` makes the patch a segment from `pa = lerp(q00, q10, u)` to
    /// `lerp(q01, q11, u)`; the ray meets that segment's line where the triple product of
    /// the ray direction, the segment and `pa - origin` vanishes, which is a quadratic
    /// `a + b u + c u^2` in `u`. Each root in `[0, 1]` gives `t` and `v` from the closest
    /// points of the ray and the segment's line. The roots are taken in the numerically
    /// stable form (`q = -(b + sign(b) sqrt(disc)) / 2`, roots `q / c` and `a / q`), and a
    /// trapezoid (`c = 0`) has the one root `-a / b`.
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<PatchHit> {
        let d = ray.dir;
        let e10 = self.q10 - self.q00;
        let e11 = self.q11 - self.q10;
        let e00 = self.q01 - self.q00;
        let qn = e10.cross(self.q01 - self.q11);
        let q00 = self.q00 - ray.origin;
        let q10 = self.q10 - ray.origin;
        let a = q00.cross(d).dot(e00);
        let c = qn.dot(d);
        let b = q10.cross(d).dot(e11) - (a + c);
        let disc = b * b - 4.0 * a * c;
        // Also rejects NaN.
        if disc < 0.0 || disc.is_nan() {
            return None;
        }
        let (u1, u2) = if c == 0.0 {
            if b == 0.0 {
                return None;
            }
            (-a / b, f32::NAN)
        } else {
            let q = -0.5 * (b + disc.sqrt().copysign(b));
            (q / c, if q == 0.0 { f32::NAN } else { a / q })
        };
        let mut best: Option<PatchHit> = None;
        for u in [u1, u2] {
            if !(0.0..=1.0).contains(&u) {
                continue;
            }
            let pa = q00.lerp(q10, u);
            let pb = e00.lerp(e11, u);
            let n = d.cross(pb);
            let det = n.dot(n);
            if det == 0.0 {
                continue;
            }
            let m = n.cross(pa);
            let t = m.dot(pb) / det;
            let v = m.dot(d);
            if (0.0..=det).contains(&v)
                && t >= ray.t_min
                && t <= ray.t_max
                && best.is_none_or(|h| t < h.t)
            {
                best = Some(PatchHit { t, u, v: v / det });
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{pcg3d, to_unit_f32};

    #[test]
    fn flat_square_analytic() {
        let p = BilinearPatch {
            q00: Vec3::new(0.0, 0.0, 0.0),
            q10: Vec3::new(2.0, 0.0, 0.0),
            q11: Vec3::new(2.0, 0.0, 2.0),
            q01: Vec3::new(0.0, 0.0, 2.0),
        };
        let h = p
            .intersect(&Ray::new(Vec3::new(0.5, 3.0, 1.5), -Vec3::Y))
            .unwrap();
        assert_eq!(h.t, 3.0);
        assert!(
            (h.u - 0.25).abs() < 1e-6 && (h.v - 0.75).abs() < 1e-6,
            "{h:?}"
        );
        assert!(
            p.intersect(&Ray::new(Vec3::new(2.5, 3.0, 1.0), -Vec3::Y))
                .is_none()
        );
        assert!(
            p.intersect(&Ray::new(Vec3::new(1.0, 3.0, 1.0), Vec3::Y))
                .is_none()
        );
        assert!(p.normal(0.3, 0.3).abs().y > 0.999);
    }

    #[test]
    fn hits_lie_on_the_twisted_patch() {
        // A hyperbolic paraboloid: corners at alternating heights.
        let p = BilinearPatch {
            q00: Vec3::new(-1.0, 0.0, -1.0),
            q10: Vec3::new(1.0, 0.5, -1.0),
            q11: Vec3::new(1.0, 0.0, 1.0),
            q01: Vec3::new(-1.0, 0.5, 1.0),
        };
        let mut hits = 0;
        for k in 0..2000u32 {
            let r = |d| to_unit_f32(pcg3d([k, 21, d])[0]);
            let o = Vec3::new(r(0) * 6.0 - 3.0, r(1) * 4.0 - 2.0, r(2) * 6.0 - 3.0);
            let target = Vec3::new(r(3) * 2.4 - 1.2, r(4) * 0.6 - 0.05, r(5) * 2.4 - 1.2);
            let ray = Ray::new(o, target - o);
            if let Some(h) = p.intersect(&ray) {
                hits += 1;
                let on_ray = ray.at(h.t);
                let on_patch = p.point(h.u, h.v);
                assert!(
                    (on_ray - on_patch).length() < 1e-4,
                    "ray {k}: {on_ray} vs {on_patch}"
                );
            }
        }
        assert!(hits > 500, "{hits}");
    }
}
