//! `raybench diff A B`: how far image `B` is from the reference `A`. Errors are measured on
//! the linear values (PNG inputs decoded from sRGB); PSNR and FLIP on the images as
//! displayed (exposure applied, clamped, sRGB-encoded 8 bits), with the report's own metrics
//! ([`crate::images`]).

use crate::images::{Rgb8, flip, psnr};
use raybench_render::LinearImage;
use serde::Serialize;

/// The offset in the denominator of the relative squared error, `(b - a)^2 / (a^2 + 0.01)`
/// (as pbrt-v4's `imgtool diff`), so that black reference pixels do not divide by zero.
pub const REL_MSE_EPSILON: f64 = 0.01;

/// What `diff` measures; the JSON keys of `raybench diff --json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DiffStats {
    /// Width and height.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Mean linear value of the reference, over pixels and channels.
    pub mean_a: f64,
    /// Mean linear value of the test image.
    pub mean_b: f64,
    /// Mean absolute difference of linear values, over pixels and channels.
    pub mean_abs_error: f64,
    /// Largest absolute difference of linear values.
    pub max_abs_error: f64,
    /// Mean squared difference of linear values.
    pub mse: f64,
    /// Mean of `(b - a)^2 / (a^2 + 0.01)` ([`REL_MSE_EPSILON`]).
    pub rel_mse: f64,
    /// PSNR of the displayed images in dB; `None` when they are identical.
    pub psnr: Option<f64>,
    /// Mean FLIP of the displayed images (0 identical, 1 most different).
    pub flip: f64,
    /// Pixels of the reference with a channel that is not finite (NaN or infinite): they
    /// are left out of every other figure, and fail any `--fail-above` gate.
    pub non_finite_a: u64,
    /// Pixels of the test image with a channel that is not finite.
    pub non_finite_b: u64,
}

impl DiffStats {
    /// Whether either image has a pixel that is not finite.
    #[must_use]
    pub fn has_non_finite(&self) -> bool {
        self.non_finite_a + self.non_finite_b > 0
    }
}

/// A metric `--fail-above` can test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// [`DiffStats::flip`].
    Flip,
    /// [`DiffStats::mean_abs_error`].
    Mae,
    /// [`DiffStats::max_abs_error`].
    Max,
    /// [`DiffStats::mse`].
    Mse,
    /// [`DiffStats::rel_mse`].
    RelMse,
}

impl Metric {
    /// Every metric with its command-line name.
    pub const ALL: [(Self, &'static str); 5] = [
        (Self::Flip, "flip"),
        (Self::Mae, "mae"),
        (Self::Max, "max"),
        (Self::Mse, "mse"),
        (Self::RelMse, "relmse"),
    ];

    /// The metric named `name`.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.iter().find(|(_, n)| *n == name).map(|&(m, _)| m)
    }

    /// Its value in `stats`.
    #[must_use]
    pub fn of(self, stats: &DiffStats) -> f64 {
        match self {
            Self::Flip => stats.flip,
            Self::Mae => stats.mean_abs_error,
            Self::Max => stats.max_abs_error,
            Self::Mse => stats.mse,
            Self::RelMse => stats.rel_mse,
        }
    }
}

/// The comparison of `b` against the reference `a`, with the error map (absolute linear
/// error, mean over channels, scaled so the largest is white: black, purple, orange,
/// white in the magma colour map) and the FLIP map (magma).
///
/// # Errors
/// When the sizes differ.
pub fn diff(
    a: &LinearImage,
    b: &LinearImage,
    exposure: f32,
) -> Result<(DiffStats, Rgb8, Rgb8), String> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(format!(
            "the images differ in size: {} x {} against {} x {}",
            a.width, a.height, b.width, b.height
        ));
    }
    let (mut sum_a, mut sum_b, mut abs, mut max, mut sq, mut rel) =
        (0.0, 0.0, 0.0, 0.0f64, 0.0, 0.0);
    let (mut non_finite_a, mut non_finite_b, mut counted) = (0u64, 0u64, 0usize);
    let mut per_pixel = Vec::with_capacity(a.color.len());
    for (ca, cb) in a.color.iter().zip(&b.color) {
        let (fa, fb) = (ca.is_finite(), cb.is_finite());
        non_finite_a += u64::from(!fa);
        non_finite_b += u64::from(!fb);
        if !(fa && fb) {
            per_pixel.push(0.0);
            continue;
        }
        counted += 1;
        let mut pixel = 0.0;
        for (x, y) in ca.to_array().into_iter().zip(cb.to_array()) {
            let (x, y) = (f64::from(x), f64::from(y));
            let d = y - x;
            sum_a += x;
            sum_b += y;
            abs += d.abs();
            max = max.max(d.abs());
            sq += d * d;
            rel += d * d / (x * x + REL_MSE_EPSILON);
            pixel += d.abs() / 3.0;
        }
        per_pixel.push(pixel);
    }
    let n = (counted * 3).max(1) as f64;
    let scale = exposure.exp2();
    let shown = |img: &LinearImage| {
        let scaled: Vec<_> = img.color.iter().map(|&c| c * scale).collect();
        Rgb8::from_linear(img.width, img.height, &scaled)
    };
    let (ra, rb) = (shown(a), shown(b));
    let (mean_flip, flip_map) = flip(&ra, &rb);
    let peak = per_pixel.iter().copied().fold(0.0f64, f64::max);
    let normalised: Vec<f32> = per_pixel
        .iter()
        .map(|&e| if peak > 0.0 { (e / peak) as f32 } else { 0.0 })
        .collect();
    let error_map = Rgb8 {
        width: a.width,
        height: a.height,
        data: nv_flip::FlipImageFloat::with_data(a.width, a.height, &normalised)
            .apply_color_lut(&nv_flip::magma_lut())
            .to_vec(),
    };
    let stats = DiffStats {
        width: a.width,
        height: a.height,
        mean_a: sum_a / n,
        mean_b: sum_b / n,
        mean_abs_error: abs / n,
        max_abs_error: max,
        mse: sq / n,
        rel_mse: rel / n,
        psnr: psnr(&ra, &rb),
        flip: mean_flip,
        non_finite_a,
        non_finite_b,
    };
    Ok((stats, error_map, flip_map))
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_core::Vec3;

    fn image(color: Vec<Vec3>) -> LinearImage {
        LinearImage {
            width: 2,
            height: 2,
            color,
        }
    }

    #[test]
    fn identical_images_have_no_error() {
        let a = image(vec![
            Vec3::splat(0.5),
            Vec3::ONE,
            Vec3::ZERO,
            Vec3::splat(3.0),
        ]);
        let (s, _, _) = diff(&a, &a, 0.0).unwrap();
        assert_eq!(
            (s.mean_abs_error, s.max_abs_error, s.mse, s.rel_mse),
            (0.0, 0.0, 0.0, 0.0)
        );
        assert_eq!((s.psnr, s.flip), (None, 0.0));
        assert!((s.mean_a - 4.5 / 4.0).abs() < 1e-12);
    }

    #[test]
    fn errors_are_measured_on_linear_values() {
        let a = image(vec![
            Vec3::ZERO,
            Vec3::ONE,
            Vec3::splat(2.0),
            Vec3::splat(4.0),
        ]);
        let b = image(vec![
            Vec3::ZERO,
            Vec3::ONE,
            Vec3::splat(2.0),
            Vec3::splat(5.0),
        ]);
        let (s, error_map, flip_map) = diff(&a, &b, 0.0).unwrap();
        assert_eq!(s.max_abs_error, 1.0);
        assert_eq!(s.mean_abs_error, 0.25);
        assert_eq!(s.mse, 0.25);
        assert!((s.rel_mse - 0.25 / 16.01).abs() < 1e-12);
        // Both last pixels clamp to white: the displayed images agree.
        assert_eq!((s.psnr, s.flip), (None, 0.0));
        // The error map is brightest at the differing pixel.
        let lum = |i: usize| {
            error_map.data[3 * i..3 * i + 3]
                .iter()
                .map(|&v| u32::from(v))
                .sum::<u32>()
        };
        assert!(lum(3) > lum(0) && lum(0) == lum(1));
        assert_eq!(flip_map.data.len(), 12);
        // At exposure -3 the difference shows.
        let (s, _, _) = diff(&a, &b, -3.0).unwrap();
        assert!(s.psnr.is_some() && s.flip > 0.0);
        assert_eq!(
            Metric::from_name("relmse").map(|m| m.of(&s)),
            Some(s.rel_mse)
        );
        let c = LinearImage {
            width: 4,
            height: 1,
            color: vec![Vec3::ZERO; 4],
        };
        assert!(diff(&a, &c, 0.0).unwrap_err().contains("differ in size"));
    }

    #[test]
    fn non_finite_pixels_are_counted_and_left_out() {
        let a = image(vec![Vec3::ONE; 4]);
        let b = image(vec![
            Vec3::new(f32::NAN, 1.0, 1.0),
            Vec3::ONE,
            Vec3::splat(f32::INFINITY),
            Vec3::splat(2.0),
        ]);
        let (s, _, _) = diff(&a, &b, 0.0).unwrap();
        assert_eq!((s.non_finite_a, s.non_finite_b), (0, 2));
        assert!(s.has_non_finite());
        // Over the two finite pairs: one equal, one off by 1 in every channel.
        assert_eq!((s.max_abs_error, s.mean_abs_error), (1.0, 0.5));
        assert!(s.mean_b.is_finite() && s.mse.is_finite() && s.rel_mse.is_finite());
        let (s, _, _) = diff(&b, &b, 0.0).unwrap();
        assert_eq!((s.non_finite_a, s.non_finite_b), (2, 2));
    }
}
