//! Reflection, refraction, Fresnel, ray offsets and hemisphere sampling: the pure math of
//! the Whitted and path-tracing integrators.

use glam::Vec3;

pub use crate::sampling::{basis, triangle_point, triangle_weights};

/// Mirror reflection of direction `d` about normal `n`: `d - 2 (d . n) n` (either side of
/// the surface; `n` unit).
#[inline]
#[must_use]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Refraction of unit direction `d` through a surface with unit normal `n` facing the
/// incoming side (`d . n < 0`), from index `n1` into index `n2` (Snell's law
/// `n1 sin(theta1) = n2 sin(theta2)`). `None` on total internal reflection.
#[inline]
#[must_use]
pub fn refract(d: Vec3, n: Vec3, n1: f32, n2: f32) -> Option<Vec3> {
    let eta = n1 / n2;
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t > 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(eta * d + (eta * cos_i - cos_t) * n)
}

/// Exact unpolarised Fresnel reflectance of a dielectric interface, light arriving at
/// `cos_i` (cosine to the normal, in `[0, 1]`) from index `n1` into `n2`; 1 on total
/// internal reflection. At normal incidence it is `((n1 - n2) / (n1 + n2))^2`.
#[inline]
#[must_use]
pub fn fresnel_dielectric(cos_i: f32, n1: f32, n2: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin_t = n1 / n2 * (1.0 - cos_i * cos_i).max(0.0).sqrt();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
    let r_s = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let r_p = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    0.5 * (r_s * r_s + r_p * r_p)
}

/// Moves a ray origin `p` off the surface along `n` (the side the new ray leaves on) by a
/// few ulps of `p`'s coordinates: Waechter and Binder, "A Fast and Robust Method for
/// Avoiding Self-Intersection", Ray Tracing Gems ch. 6. Integer ulp steps away from the
/// origin, a small fixed step near it, so the offset scales with the coordinates' own
/// precision instead of being one epsilon for every scene size.
#[inline]
#[must_use]
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65_536.0;
    const INT_SCALE: f32 = 256.0;
    let step = |p: f32, n: f32| -> f32 {
        if p.abs() < ORIGIN {
            p + FLOAT_SCALE * n
        } else {
            let of = (INT_SCALE * n) as i32;
            let of = if p < 0.0 { -of } else { of };
            f32::from_bits((p.to_bits() as i32).wrapping_add(of) as u32)
        }
    };
    Vec3::new(step(p.x, n.x), step(p.y, n.y), step(p.z, n.z))
}

/// A cosine-weighted direction on the hemisphere around unit `n` from two uniform numbers
/// (Malley's method: a uniform disk point lifted to the hemisphere); pdf `cos / pi`.
#[inline]
#[must_use]
pub fn cosine_hemisphere(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let phi = std::f32::consts::TAU * u2;
    let (t, b) = basis(n);
    let z = (1.0 - u1).max(0.0).sqrt();
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * z).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-6
    }

    #[test]
    fn reflection_by_hand() {
        // 45 degrees onto the floor.
        let d = Vec3::new(1.0, -1.0, 0.0).normalize();
        assert!(close(
            reflect(d, Vec3::Y),
            Vec3::new(1.0, 1.0, 0.0).normalize()
        ));
        // Normal incidence comes straight back; the normal's side does not matter.
        assert!(close(reflect(-Vec3::Y, Vec3::Y), Vec3::Y));
        assert!(close(reflect(-Vec3::Y, -Vec3::Y), Vec3::Y));
    }

    #[test]
    fn refraction_obeys_snell() {
        let (n1, n2) = (1.0, 1.5);
        for deg in [0.0f32, 10.0, 30.0, 45.0, 60.0, 85.0] {
            let th = deg.to_radians();
            let d = Vec3::new(th.sin(), -th.cos(), 0.0);
            let t = refract(d, Vec3::Y, n1, n2).unwrap();
            assert!((t.length() - 1.0).abs() < 1e-5);
            let sin_t = t.x;
            assert!((n1 * th.sin() - n2 * sin_t).abs() < 1e-5, "{deg}: {t}");
            assert!(t.y < 0.0, "goes through");
        }
        // By hand: 30 degrees into glass: sin(theta_t) = 0.5 / 1.5.
        let d = Vec3::new(0.5, -(0.75f32).sqrt(), 0.0);
        let t = refract(d, Vec3::Y, 1.0, 1.5).unwrap();
        let expect = Vec3::new(1.0 / 3.0, -(1.0f32 - 1.0 / 9.0).sqrt(), 0.0);
        assert!(close(t, expect), "{t} vs {expect}");
    }

    #[test]
    fn total_internal_reflection_beyond_the_critical_angle() {
        let critical = (1.0f32 / 1.5).asin();
        let n = Vec3::Y;
        let below = critical - 0.01;
        let above = critical + 0.01;
        let d = |th: f32| Vec3::new(th.sin(), -th.cos(), 0.0);
        assert!(refract(d(below), n, 1.5, 1.0).is_some());
        assert!(refract(d(above), n, 1.5, 1.0).is_none());
        assert_eq!(fresnel_dielectric(above.cos(), 1.5, 1.0), 1.0);
        assert!(fresnel_dielectric(below.cos(), 1.5, 1.0) < 1.0);
    }

    #[test]
    fn fresnel_at_normal_incidence() {
        for (n1, n2) in [(1.0f32, 1.5f32), (1.5, 1.0), (1.0, 2.4), (1.33, 1.0)] {
            let expect = ((n1 - n2) / (n1 + n2)).powi(2);
            assert!((fresnel_dielectric(1.0, n1, n2) - expect).abs() < 1e-6);
        }
        // Grazing incidence reflects everything.
        assert!((fresnel_dielectric(0.0, 1.0, 1.5) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn offset_moves_off_the_surface_by_a_scaled_amount() {
        for p in [
            Vec3::new(0.001, 0.0, 0.0),
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-1.0e6, 5.0e5, 1.0),
        ] {
            let q = offset_ray_origin(p, Vec3::Y);
            assert!(q.y > p.y, "{p} -> {q}");
            assert_eq!((q.x, q.z), (p.x, p.z));
            let q = offset_ray_origin(p, -Vec3::Y);
            assert!(q.y < p.y);
        }
        // Far from the origin, the step is 256 ulps, not a fixed epsilon.
        let p = Vec3::new(0.0, 1.0e6, 0.0);
        let q = offset_ray_origin(p, Vec3::Y);
        assert!((q.y - p.y) > 1.0 && (q.y - p.y) < 100.0);
    }

    #[test]
    fn cosine_samples_lie_in_the_hemisphere_with_mean_cos_two_thirds() {
        let n = Vec3::new(0.3, 0.8, -0.52).normalize();
        let mut sum = 0.0;
        let count = 20_000;
        for i in 0..count {
            let u = crate::sampling::Sampler::new(i, 0, 0).next_2d();
            let d = cosine_hemisphere(n, u.0, u.1);
            assert!((d.length() - 1.0).abs() < 1e-4);
            let c = d.dot(n);
            assert!(c >= -1e-6);
            sum += c;
        }
        // E[cos] under pdf cos/pi is 2/3.
        let mean = sum / count as f32;
        assert!((mean - 2.0 / 3.0).abs() < 0.01, "{mean}");
    }
}
