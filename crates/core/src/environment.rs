//! The environment light: an equirectangular image around the scene, seen by every ray that
//! misses, and importance-sampled as a light in `path` mode.
//!
//! Convention (`docs/scene-format.md`): the scene's `+y` is up. A direction
//! `d = (sin θ cos φ, cos θ, sin θ sin φ)` (θ from `+y`, φ from `+x` towards `+z`, as
//! [`crate::Sphere::uv`]) reads the texel at `u = φ / 2π` (column, from the left edge) and
//! `v = θ / π` (row, from the top edge): the top row is straight up, `u = 0` looks along
//! `+x`, `u = 0.25` along `+z`. `rotate` turns the map about `+y` by that many degrees
//! (right-handed: `+x` towards `-z`), so the map's `u = 0` then looks along the rotated `+x`.
//! Lookups are nearest-texel (piecewise constant), which the sampling distribution matches
//! exactly.

use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// An equirectangular environment map with its sampling distribution.
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    width: u32,
    height: u32,
    /// Linear radiance per texel, rows from the top, already multiplied by the scale.
    texels: Vec<Vec3>,
    /// Rotation about `+y`, as cosine and sine.
    rotation: (f32, f32),
    /// Per row: the cumulative weight of its texels (`width` entries each).
    conditional: Vec<f64>,
    /// The cumulative weight of the rows (`height` entries).
    marginal: Vec<f64>,
    /// Mean luminance over the sphere of directions (`∫ lum dω / 4π`).
    mean_luminance: f64,
}

/// Rec. 709 luminance of linear RGB: the weight of emitters and texels in light choice.
#[inline]
#[must_use]
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Index of the interval of the cumulative table `cdf` holding `target`, and the position
/// of `target` inside it in `[0, 1)`.
fn pick(cdf: &[f64], target: f64) -> (usize, f32) {
    let i = cdf
        .partition_point(|&c| c <= target)
        .min(cdf.len().saturating_sub(1));
    let lo = if i == 0 { 0.0 } else { cdf[i - 1] };
    let w = cdf[i] - lo;
    let frac = if w > 0.0 { (target - lo) / w } else { 0.5 };
    (i, (frac as f32).clamp(0.0, 1.0 - f32::EPSILON / 2.0))
}

impl Environment {
    /// A map of `width x height` linear RGB texels (rows from the top), multiplied by
    /// `scale`, turned by `rotate_degrees` about `+y`. `None` when the sizes do not match,
    /// a size is zero, or a texel or the scale is negative or not finite.
    #[must_use]
    pub fn new(
        width: u32,
        height: u32,
        texels: Vec<Vec3>,
        scale: f32,
        rotate_degrees: f32,
    ) -> Option<Self> {
        let n = (width as usize).checked_mul(height as usize)?;
        if n == 0 || texels.len() != n || !(scale.is_finite() && scale >= 0.0) {
            return None;
        }
        if !rotate_degrees.is_finite() {
            return None;
        }
        let texels: Vec<Vec3> = texels.into_iter().map(|t| t * scale).collect();
        if texels
            .iter()
            .any(|t| !t.is_finite() || t.min_element() < 0.0)
        {
            return None;
        }
        let mut conditional = Vec::with_capacity(n);
        let mut marginal = Vec::with_capacity(height as usize);
        let mut rows = 0.0f64;
        let mut integral = 0.0f64;
        for (y, row) in texels.chunks(width as usize).enumerate() {
            // The sin θ factor of the equirectangular map's area element, at the row centre.
            let sin = f64::from(((y as f32 + 0.5) / height as f32 * PI).sin());
            let mut sum = 0.0f64;
            for t in row {
                sum += f64::from(luminance(*t));
                conditional.push(sum);
            }
            rows += sum * sin;
            marginal.push(rows);
            // Exact solid angle of the row's band: 2π (cos θ0 - cos θ1) / width per texel.
            let (t0, t1) = (
                f64::from(y as f32) / f64::from(height) * std::f64::consts::PI,
                f64::from(y as f32 + 1.0) / f64::from(height) * std::f64::consts::PI,
            );
            integral += sum * std::f64::consts::TAU * (t0.cos() - t1.cos()) / f64::from(width);
        }
        let r = rotate_degrees.to_radians();
        Some(Self {
            width,
            height,
            texels,
            rotation: (r.cos(), r.sin()),
            conditional,
            marginal,
            mean_luminance: integral / (4.0 * std::f64::consts::PI),
        })
    }

    /// Width and height in texels.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Linear radiance per texel, rows from the top, the scale applied (for backends that
    /// keep their own copy, such as the GPU's).
    #[must_use]
    pub fn texels(&self) -> &[Vec3] {
        &self.texels
    }

    /// The rotation about `+y` as cosine and sine, as [`Environment::radiance`] applies it.
    #[must_use]
    pub fn rotation(&self) -> (f32, f32) {
        self.rotation
    }

    /// The sampling tables: the rows' cumulative weights (`height` entries) and each row's
    /// cumulative texel weights (`width` entries per row), as [`Environment::sample`]
    /// searches them.
    #[must_use]
    pub fn tables(&self) -> (&[f64], &[f64]) {
        (&self.marginal, &self.conditional)
    }

    /// Mean luminance over all directions, `∫ lum(L) dω / 4π`: the environment's share in
    /// the choice of a light (`Emitters`).
    #[must_use]
    pub fn mean_luminance(&self) -> f64 {
        self.mean_luminance
    }

    /// The map's frame: world direction to map direction (the inverse rotation).
    #[inline]
    fn to_map(&self, d: Vec3) -> Vec3 {
        let (c, s) = self.rotation;
        Vec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z)
    }

    /// Map direction to world direction.
    #[inline]
    fn to_world(&self, d: Vec3) -> Vec3 {
        let (c, s) = self.rotation;
        Vec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
    }

    /// The texel column and row seen along map direction `d` (unit), and `sin θ`.
    #[inline]
    fn texel_of(&self, d: Vec3) -> (usize, usize, f32) {
        let u = (d.z.atan2(d.x) / TAU).rem_euclid(1.0);
        let cos = d.y.clamp(-1.0, 1.0);
        let v = cos.acos() / PI;
        let x = ((u * self.width as f32) as usize).min(self.width as usize - 1);
        let y = ((v * self.height as f32) as usize).min(self.height as usize - 1);
        (x, y, (1.0 - cos * cos).max(0.0).sqrt())
    }

    /// Radiance arriving along `-dir` from the environment (of a ray travelling along `dir`,
    /// any length).
    #[must_use]
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        let Some(d) = dir.try_normalize() else {
            return Vec3::ZERO;
        };
        let (x, y, _) = self.texel_of(self.to_map(d));
        self.texels[y * self.width as usize + x]
    }

    /// The solid-angle density with which [`Environment::sample`] picks world direction
    /// `dir` (0 where the map is black).
    #[must_use]
    pub fn pdf(&self, dir: Vec3) -> f32 {
        let Some(d) = dir.try_normalize() else {
            return 0.0;
        };
        let (x, y, sin) = self.texel_of(self.to_map(d));
        self.texel_pdf(x, y, sin)
    }

    /// The density of texel `(x, y)` per solid angle at a direction with `sin θ = sin`.
    fn texel_pdf(&self, x: usize, y: usize, sin: f32) -> f32 {
        let total = self.marginal.last().copied().unwrap_or(0.0);
        if total <= 0.0 || sin <= 0.0 {
            return 0.0;
        }
        let w = self.width as usize;
        let row = &self.conditional[y * w..(y + 1) * w];
        let texel = row[x] - if x == 0 { 0.0 } else { row[x - 1] };
        let row_sin = f64::from(((y as f32 + 0.5) / self.height as f32 * PI).sin());
        // pdf over (u, v) in [0,1)^2, then divided by the Jacobian 2π² sin θ.
        let pdf_uv = texel * row_sin / total * f64::from(self.width) * f64::from(self.height);
        (pdf_uv / (2.0 * f64::from(PI) * f64::from(PI) * f64::from(sin))) as f32
    }

    /// A world direction drawn from the piecewise-constant distribution of luminance times
    /// `sin θ` (a row by the marginal with `u0`, a texel in it by the row's own with `u1`,
    /// uniform inside the texel), with its radiance and solid-angle pdf; `None` for a black
    /// map or a pole.
    #[must_use]
    pub fn sample(&self, u0: f32, u1: f32) -> Option<(Vec3, Vec3, f32)> {
        let total = *self.marginal.last()?;
        if total <= 0.0 {
            return None;
        }
        let (y, fy) = pick(&self.marginal, f64::from(u0) * total);
        let w = self.width as usize;
        let row = &self.conditional[y * w..(y + 1) * w];
        let (x, fx) = pick(row, f64::from(u1) * row[w - 1]);
        let u = (x as f32 + fx) / self.width as f32;
        let v = (y as f32 + fy) / self.height as f32;
        let (theta, phi) = (v * PI, u * TAU);
        let sin = theta.sin();
        let d = Vec3::new(sin * phi.cos(), theta.cos(), sin * phi.sin());
        let pdf = self.texel_pdf(x, y, sin);
        if pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        Some((self.to_world(d), self.texels[y * w + x], pdf))
    }

    /// Bytes held.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.texels.len() * std::mem::size_of::<Vec3>()
            + (self.conditional.len() + self.marginal.len()) * std::mem::size_of::<f64>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(width: u32, height: u32, f: impl Fn(u32, u32) -> f32) -> Environment {
        let texels = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| Vec3::splat(f(x, y)))
            .collect();
        Environment::new(width, height, texels, 1.0, 0.0).unwrap()
    }

    #[test]
    fn convention_up_is_top_row_and_u0_is_plus_x() {
        let e = map(4, 2, |x, y| (y * 4 + x) as f32);
        assert!(e.radiance(Vec3::Y).x < 4.0);
        assert!(e.radiance(-Vec3::Y).x >= 4.0);
        // u = 0 along +x (just above the horizon: row 0), u = 0.25 along +z.
        let up = Vec3::new(0.0, 0.01, 0.0);
        assert_eq!(e.radiance(Vec3::X + up).x, 0.0);
        assert_eq!(e.radiance(Vec3::Z + up).x, 1.0);
        assert_eq!(e.radiance(-Vec3::X + up).x, 2.0);
        // Rotated by 90 degrees: the column that looked along +x now looks along -z.
        let texels = (0..8).map(|i| Vec3::splat(i as f32)).collect();
        let r = Environment::new(4, 2, texels, 1.0, 90.0).unwrap();
        assert_eq!(r.radiance(-Vec3::Z + up).x, 0.0);
        assert_eq!(r.radiance(Vec3::X + up).x, 1.0);
    }

    #[test]
    fn bad_maps_are_refused() {
        assert!(Environment::new(2, 2, vec![Vec3::ONE; 3], 1.0, 0.0).is_none());
        assert!(Environment::new(0, 2, vec![], 1.0, 0.0).is_none());
        assert!(Environment::new(1, 1, vec![Vec3::NAN], 1.0, 0.0).is_none());
        assert!(Environment::new(1, 1, vec![-Vec3::ONE], 1.0, 0.0).is_none());
        assert!(Environment::new(1, 1, vec![Vec3::ONE], f32::INFINITY, 0.0).is_none());
    }

    /// The pdf integrates to one over the sphere and agrees with the sampled pdf; a
    /// constant map's mean luminance is its value.
    #[test]
    fn pdf_is_normalised_and_matches_samples() {
        let e = map(16, 8, |x, y| if x == 3 && y == 2 { 50.0 } else { 1.0 });
        let n = 400;
        let mut integral = 0.0f64;
        for i in 0..n {
            let theta = (i as f32 + 0.5) / n as f32 * PI;
            for j in 0..2 * n {
                let phi = (j as f32 + 0.5) / (2 * n) as f32 * TAU;
                let d = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                );
                let dw = (PI / n as f32) * (TAU / (2 * n) as f32) * theta.sin();
                integral += f64::from(e.pdf(d) * dw);
            }
        }
        assert!((integral - 1.0).abs() < 2e-3, "{integral}");
        for k in 0..100 {
            let (u0, u1) = (
                (k as f32 + 0.37) / 100.0,
                ((k * 37 % 100) as f32 + 0.5) / 100.0,
            );
            let (d, _, pdf) = e.sample(u0, u1).unwrap();
            assert!((e.pdf(d) - pdf).abs() <= 1e-3 * pdf, "{} {pdf}", e.pdf(d));
        }
        let c = map(8, 4, |_, _| 2.0);
        assert!((c.mean_luminance() - 2.0).abs() < 1e-6);
    }
}
