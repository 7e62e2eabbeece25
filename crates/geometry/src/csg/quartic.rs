//! Real roots of low-degree polynomials by derivative bracketing, and the torus built on it.
//!
//! **Method.** The roots of a polynomial `p` of degree `n <= 4` on `[lo, hi]` are found
//! from the roots of its derivative (found the same way, down to degree 1): between two
//! consecutive critical points `p` is monotone, so it has at most one root there, and it has
//! one exactly when `p` changes sign. Each such root is found by safeguarded Newton
//! iteration (a Newton step that leaves the bracket is replaced by bisection), all in `f64`.
//!
//! **Why robust.** Unlike closed forms (Ferrari's resolvent cubic), nothing cancels
//! catastrophically: every root with a sign change is bracketed, so it cannot be lost or
//! duplicated, and Newton converges quadratically inside its bracket. Roots of even
//! multiplicity (a tangent ray touching the torus) do not change the sign and are skipped,
//! which is the CSG rule that tangent rays miss. The torus moves the origin to the point
//! of the ray's line closest to its centre and measures lengths in units of `R + r`, so the
//! quartic's coefficients are of order one whatever the scene's scale or the ray origin's
//! distance.

/// Evaluates `p` (coefficients from the constant term up) at `x` by Horner's rule.
#[inline]
fn eval(p: &[f64], x: f64) -> f64 {
    p.iter().rev().fold(0.0, |acc, &c| acc * x + c)
}

/// The root of `p` in `[a, b]`, where `p(a)` and `p(b)` have opposite signs, by Newton
/// steps kept inside the shrinking bracket (bisection when a step leaves it).
fn bracketed(p: &[f64], dp: &[f64], mut a: f64, mut b: f64) -> f64 {
    let rising = eval(p, a) < 0.0;
    let mut x = 0.5 * (a + b);
    for _ in 0..100 {
        let fx = eval(p, x);
        if fx == 0.0 {
            return x;
        }
        if (fx < 0.0) == rising {
            a = x;
        } else {
            b = x;
        }
        let step = fx / eval(dp, x);
        let newton = x - step;
        let next = if newton > a && newton < b {
            newton
        } else {
            0.5 * (a + b)
        };
        if next == x || (b - a) <= 4.0 * f64::EPSILON * x.abs().max(f64::MIN_POSITIVE) {
            return next;
        }
        x = next;
    }
    x
}

/// The roots of `p` (degree `p.len() - 1`, between 1 and 4) in `(lo, hi)` where `p`
/// changes sign (zero counting as positive), ascending, written to `out`; returns how many.
pub(super) fn roots(p: &[f64], lo: f64, hi: f64, out: &mut [f64; 4]) -> usize {
    let n = p.len() - 1;
    debug_assert!((1..=4).contains(&n));
    if p[n] == 0.0 {
        // A lower degree than announced: drop the leading term.
        return if n == 1 {
            0
        } else {
            roots(&p[..n], lo, hi, out)
        };
    }
    if n == 1 {
        let x = -p[0] / p[1];
        out[0] = x;
        return usize::from(x > lo && x < hi);
    }
    // The derivative's roots split [lo, hi] into pieces where p is monotone.
    let mut dp = [0.0; 4];
    for (k, c) in p.iter().enumerate().skip(1) {
        dp[k - 1] = k as f64 * c;
    }
    let dp = &dp[..n];
    let mut crit = [0.0; 4];
    let k = roots(dp, lo, hi, &mut crit);
    let mut count = 0;
    let mut a = lo;
    let mut fa = eval(p, a);
    for &b in crit[..k].iter().chain(std::iter::once(&hi)) {
        let fb = eval(p, b);
        // Zero counts as positive (outside), so crossings pair up: a tangency at a critical
        // point is no crossing, and a sign change that starts there is bracketed once.
        if (fa < 0.0) != (fb < 0.0) {
            out[count] = bracketed(p, dp, a, b);
            count += 1;
        }
        (a, fa) = (b, fb);
    }
    count
}

/// The crossings of the line `o + t d` with the torus of major radius `major` about the
/// y axis and minor radius `minor`, centred at the origin: up to four `t`, ascending, each
/// with the outward normal there (unnormalised), and their count (0, 2 or 4; 0 for a zero
/// or non-finite direction).
pub(super) fn torus(
    o: glam::Vec3,
    d: glam::Vec3,
    major: f32,
    minor: f32,
) -> ([(f32, glam::DVec3); 4], usize) {
    let mut hits = [(0.0, glam::DVec3::ZERO); 4];
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let (big, small) = (f64::from(major), f64::from(minor));
    let unit = big + small;
    let dd = d.length();
    if !(dd > 0.0 && dd.is_finite() && o.is_finite()) {
        return (hits, 0);
    }
    let u = d / dd;
    // The point of the line closest to the centre, in units of R + r.
    let t0 = -o.dot(u);
    let p = (o + u * t0) / unit;
    if p.length_squared() >= 1.0 {
        // The line misses the bounding sphere.
        return (hits, 0);
    }
    let (big, small) = (big / unit, small / unit);
    let r2 = 4.0 * big * big;
    let h = p.dot(u);
    let g = p.length_squared() + big * big - small * small;
    let (uxz, pu, pxz) = (
        u.x * u.x + u.z * u.z,
        p.x * u.x + p.z * u.z,
        p.x * p.x + p.z * p.z,
    );
    // (|p + s u|^2 + R^2 - r^2)^2 - 4 R^2 ((p + s u).x^2 + (p + s u).z^2), |u| = 1.
    let quartic = [
        g * g - r2 * pxz,
        4.0 * h * g - 2.0 * r2 * pu,
        4.0 * h * h + 2.0 * g - r2 * uxz,
        4.0 * h,
        1.0,
    ];
    let mut s = [0.0; 4];
    // Every crossing lies inside the bounding sphere, |s| <= 1; the ends are well outside.
    let n = roots(&quartic, -1.25, 1.25, &mut s);
    for (hit, &s) in hits.iter_mut().zip(&s[..n]) {
        let q = p + u * s;
        let n = q * (4.0 * (q.length_squared() + big * big - small * small))
            - glam::DVec3::new(q.x, 0.0, q.z) * (2.0 * r2);
        *hit = (((t0 + s * unit) / dd) as f32, n);
    }
    (hits, n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec3, Vec3};

    /// `(sqrt(x^2 + z^2) - R)^2 + y^2 - r^2` at `o + t d`, in f64: negative inside the
    /// (ring) torus; the reference the solver is checked against.
    fn inside(o: DVec3, d: DVec3, big: f64, small: f64, t: f64) -> f64 {
        let p = o + d * t;
        let rho = (p.x * p.x + p.z * p.z).sqrt() - big;
        rho * rho + p.y * p.y - small * small
    }

    /// Sign changes of [`inside`] found by a dense scan of `steps` steps over the bounding
    /// sphere's chord, each refined by bisection to f64 precision.
    fn scan(o: Vec3, d: Vec3, big: f32, small: f32, steps: usize) -> Vec<f64> {
        let (o, d) = (o.as_dvec3(), d.as_dvec3());
        let (big, small) = (f64::from(big), f64::from(small));
        let g = |t: f64| inside(o, d, big, small, t);
        let (a, b, c) = (d.dot(d), o.dot(d), o.dot(o) - (big + small).powi(2) * 1.01);
        let disc = b * b - a * c;
        if disc <= 0.0 {
            return Vec::new();
        }
        let (t0, t1) = ((-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a);
        let mut out = Vec::new();
        let step = (t1 - t0) / steps as f64;
        for i in 0..steps {
            let (mut lo, mut hi) = (t0 + step * i as f64, t0 + step * (i + 1) as f64);
            if (g(lo) < 0.0) == (g(hi) < 0.0) {
                continue;
            }
            let rising = g(lo) < 0.0;
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if mid == lo || mid == hi {
                    break;
                }
                if (g(mid) < 0.0) == rising {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            out.push(0.5 * (lo + hi));
        }
        out
    }

    fn ts(o: Vec3, d: Vec3, big: f32, small: f32) -> Vec<f32> {
        let (h, n) = torus(o, d, big, small);
        h[..n].iter().map(|h| h.0).collect()
    }

    /// A small deterministic generator for test rays (SplitMix64).
    struct Mix(u64);
    impl Mix {
        fn next(&mut self) -> f32 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
        }
        fn vec(&mut self) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next()) * 2.0 - 1.0
        }
    }

    #[test]
    fn polynomial_roots() {
        // (x - 0.1)(x - 0.2)(x + 0.5)(x - 0.9), and one with a double root at 0.5 that is
        // no crossing.
        let p = [-0.009, 0.127, -0.31, -0.7, 1.0];
        let mut out = [0.0; 4];
        assert_eq!(roots(&p, -2.0, 2.0, &mut out), 4);
        for (r, want) in out.iter().zip([-0.5, 0.1, 0.2, 0.9]) {
            assert!((r - want).abs() < 1e-14, "{r} {want}");
        }
        // (x - 0.5)^2 (x - 1.5)(x - 2), exact in binary: the double root is a tangency,
        // no crossing, or at worst a vanishing pair from rounding.
        let p = [0.75, -3.875, 6.75, -4.5, 1.0];
        let n = roots(&p, -3.0, 3.0, &mut out);
        assert!(n == 2 || n == 4, "{n}");
        assert!((out[n - 2] - 1.5).abs() < 1e-14 && (out[n - 1] - 2.0).abs() < 1e-14);
        if n == 4 {
            assert!(
                (out[0] - 0.5).abs() < 1e-7 && out[1] - out[0] < 1e-7,
                "{out:?}"
            );
        }
    }

    #[test]
    fn known_torus_hits() {
        // R = 2, r = 0.5 about y: along x through the centre, four crossings.
        assert_eq!(
            ts(Vec3::new(-10.0, 0.0, 0.0), Vec3::X, 2.0, 0.5),
            [7.5, 8.5, 11.5, 12.5]
        );
        // Down the axis, through the hole: nothing. Down through the tube: one span.
        assert!(ts(Vec3::new(0.0, 10.0, 0.0), -Vec3::Y, 2.0, 0.5).is_empty());
        assert_eq!(
            ts(Vec3::new(2.0, 10.0, 0.0), -Vec3::Y, 2.0, 0.5),
            [9.5, 10.5]
        );
        // An unnormalised direction: t scales with it.
        assert_eq!(
            ts(Vec3::new(-10.0, 0.0, 0.0), Vec3::X * 4.0, 2.0, 0.5),
            [1.875, 2.125, 2.875, 3.125]
        );
        // Small and huge tori seen from 10^4 of their sizes away: the coefficients are
        // scaled to the torus, so the relative error stays at f32 rounding.
        for scale in [1e-3f32, 1e5] {
            let (o, big, small) = (Vec3::new(-1e4 * scale, 0.0, 0.0), 2.0 * scale, 0.5 * scale);
            let got = ts(o, Vec3::X, big, small);
            // Exact in f64 from the f32 inputs.
            let (x, b, r) = (-f64::from(o.x), f64::from(big), f64::from(small));
            let want = [x - b - r, x - b + r, x + b - r, x + b + r];
            assert_eq!(got.len(), 4, "{scale}: {got:?}");
            for (g, w) in got.iter().zip(want) {
                assert!(
                    (f64::from(*g) - w).abs() <= 1e-7 * w,
                    "{scale}: {got:?} {want:?}"
                );
            }
        }
        // The normals point out of the tube.
        let (h, _) = torus(Vec3::new(-10.0, 0.0, 0.0), Vec3::X, 2.0, 0.5);
        let n: Vec<Vec3> = h.iter().map(|h| h.1.normalize().as_vec3()).collect();
        assert_eq!(n, [-Vec3::X, Vec3::X, -Vec3::X, Vec3::X]);
    }

    #[test]
    fn tangent_and_near_tangent_rays() {
        // Along the top of the tube (y = r): tangent along a whole circle's two points.
        let on_top = ts(Vec3::new(-10.0, 0.5, 0.0), Vec3::X, 2.0, 0.5);
        assert!(
            on_top.chunks(2).all(|p| p[1] - p[0] < 1e-3),
            "tangent spans must be empty or vanishing: {on_top:?}"
        );
        // Just below it: two short spans around x = -2 and x = 2.
        let y = 0.5 * (1.0 - 1e-4);
        let below = ts(Vec3::new(-10.0, y, 0.0), Vec3::X, 2.0, 0.5);
        assert_eq!(below.len(), 4, "{below:?}");
        let want = scan(Vec3::new(-10.0, y, 0.0), Vec3::X, 2.0, 0.5, 200_000);
        for (a, b) in below.iter().zip(&want) {
            assert!(
                (f64::from(*a) - b).abs() < 1e-5 * b.abs(),
                "{below:?} {want:?}"
            );
        }
        // Tangent to the inner equator from inside the hole (x = R - r on the z axis).
        let inner = ts(Vec3::new(1.5, 0.0, -10.0), Vec3::Z, 2.0, 0.5);
        assert!(inner.len() == 2 || inner.len() == 4, "{inner:?}");
    }

    /// The measured accuracy: random rays from outside and inside against the dense scan.
    /// Run with `--nocapture` to see the numbers.
    #[test]
    fn random_rays_match_a_dense_scan() {
        let mut rng = Mix(7);
        let (mut worst, mut worst_rel): (f64, f64) = (0.0, 0.0);
        let (mut rays, mut roots_checked, mut count_mismatch) = (0, 0, 0);
        for scale in [1e-3f32, 1.0, 1e4] {
            for _ in 0..400 {
                let big = scale * (0.5 + rng.next() * 2.0);
                let small = big * (0.05 + 0.9 * rng.next());
                let o = rng.vec() * scale * 8.0;
                // Aim at a random point of the tube's centre circle's neighbourhood.
                let phi = rng.next() * std::f32::consts::TAU;
                let target =
                    Vec3::new(phi.cos() * big, 0.0, phi.sin() * big) + rng.vec() * small * 1.2;
                let d = (target - o) * (0.1 + 2.0 * rng.next());
                let got = ts(o, d, big, small);
                let want = scan(o, d, big, small, 20_000);
                rays += 1;
                if got.len() != want.len() {
                    // Only near-tangent rays, whose crossing pairs lie within a scan step.
                    count_mismatch += 1;
                    continue;
                }
                for (g, w) in got.iter().zip(&want) {
                    // Relative to the distance scale |o| + R + r over |d|.
                    let unit = f64::from((o.length() + big + small) / d.length());
                    worst = worst.max((f64::from(*g) - w).abs() / unit);
                    worst_rel = worst_rel.max((f64::from(*g) - w).abs() / w.abs());
                    roots_checked += 1;
                }
            }
        }
        println!(
            "torus: {rays} rays, {roots_checked} crossings, {count_mismatch} count mismatches, \
             max |t - t_ref| / t_scale = {worst:e}, max |t - t_ref| / |t_ref| = {worst_rel:e}"
        );
        assert!(count_mismatch * 100 <= rays, "{count_mismatch} of {rays}");
        assert!(roots_checked > rays, "{roots_checked}");
        assert!(worst < 1e-6, "{worst:e}");
    }
}
