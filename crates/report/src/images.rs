//! Image equality for the report: PSNR and FLIP of colour images, and heat maps of where
//! two results differ.

use raybench_core::{NO_HIT, Vec3};
use raybench_render::srgb8;
use std::path::Path;

/// A colour image as 8-bit sRGB, row by row.
#[derive(Clone, Debug, PartialEq)]
pub struct Rgb8 {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `3 * width * height` bytes.
    pub data: Vec<u8>,
}

impl Rgb8 {
    /// Linear colours converted as the PNG writer converts them (clamp, sRGB, 8 bits).
    #[must_use]
    pub fn from_linear(width: u32, height: u32, color: &[Vec3]) -> Self {
        Self {
            width,
            height,
            data: color.iter().flat_map(|&c| srgb8(c)).collect(),
        }
    }

    /// Writes a PNG.
    ///
    /// # Errors
    /// When the file cannot be written.
    pub fn save(&self, path: &Path) -> anyhow::Result<()> {
        Ok(raybench_render::write_rgb(
            path,
            self.width,
            self.height,
            self.data.clone(),
        )?)
    }
}

/// Peak signal-to-noise ratio of `test` against `reference` over all channels, in dB;
/// `None` for identical images (the PSNR is infinite).
///
/// # Panics
/// When the sizes differ.
#[must_use]
pub fn psnr(reference: &Rgb8, test: &Rgb8) -> Option<f64> {
    assert_eq!(reference.data.len(), test.data.len());
    let sse: f64 = reference
        .data
        .iter()
        .zip(&test.data)
        .map(|(&a, &b)| (f64::from(a) - f64::from(b)).powi(2))
        .sum();
    if sse == 0.0 {
        return None;
    }
    let mse = sse / reference.data.len() as f64;
    Some(10.0 * (255.0f64 * 255.0 / mse).log10())
}

/// Mean FLIP error of `test` against `reference` (NVIDIA's perceptual difference, LDR
/// version, at the default 67 pixels per degree), and the error map in the magma colour
/// map.
#[must_use]
pub fn flip(reference: &Rgb8, test: &Rgb8) -> (f64, Rgb8) {
    let r = nv_flip::FlipImageRgb8::with_data(reference.width, reference.height, &reference.data);
    let t = nv_flip::FlipImageRgb8::with_data(test.width, test.height, &test.data);
    let map = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let pool = nv_flip::FlipPool::from_image(&map);
    let visual = map.apply_color_lut(&nv_flip::magma_lut());
    (
        f64::from(pool.mean()),
        Rgb8 {
            width: reference.width,
            height: reference.height,
            data: visual.to_vec(),
        },
    )
}

/// `n >= 2` evenly spaced colours of the magma colour map that [`flip`] draws its error
/// maps in, from error 0 to error 1 (the colour key of those maps).
#[must_use]
pub fn magma_stops(n: usize) -> Vec<[u8; 3]> {
    let lut = nv_flip::magma_lut().to_vec();
    let last = lut.len() / 3 - 1;
    (0..n)
        .map(|i| {
            let j = 3 * (i * last / (n - 1).max(1));
            [lut[j], lut[j + 1], lut[j + 2]]
        })
        .collect()
}

/// A heat map of id differences: black where the ids agree, orange where both hit different
/// primitives, white where one hits and the other misses; the reference's image, darkened,
/// shows through agreeing pixels when given.
#[must_use]
pub fn ids_diff(
    width: u32,
    height: u32,
    reference: &[u32],
    test: &[u32],
    shade: Option<&Rgb8>,
) -> Rgb8 {
    let mut data = Vec::with_capacity(reference.len() * 3);
    for (i, (&a, &b)) in reference.iter().zip(test).enumerate() {
        let px = if a == b {
            shade.map_or([0, 0, 0], |s| {
                let p = &s.data[3 * i..3 * i + 3];
                [p[0] / 4, p[1] / 4, p[2] / 4]
            })
        } else if (a == NO_HIT) != (b == NO_HIT) {
            [255, 255, 255]
        } else {
            [255, 140, 0]
        };
        data.extend_from_slice(&px);
    }
    Rgb8 {
        width,
        height,
        data,
    }
}

/// A heat map of node or cell visits per pixel, `visits` row by row: each pixel's count
/// mapped linearly from 0 to the largest count in the image onto the magma colour map (the
/// [`magma_stops`] of the FLIP maps: 0 visits black, the image's maximum pale yellow); all
/// black where no pixel visits anything. The scale is the image's own, so the maps of two
/// backends share a colour only where they share a maximum (the report tables give it).
///
/// # Panics
/// When `visits` does not hold `width * height` counts.
#[must_use]
pub fn visits_heat_map(width: u32, height: u32, visits: &[u64]) -> Rgb8 {
    assert_eq!(visits.len() as u64, u64::from(width) * u64::from(height));
    let lut = nv_flip::magma_lut().to_vec();
    let last = (lut.len() / 3 - 1) as u128;
    let max = u128::from(visits.iter().copied().max().unwrap_or(0).max(1));
    let data = visits
        .iter()
        .flat_map(|&v| {
            // Rounded to the nearest entry, in integers.
            let j = 3 * ((u128::from(v) * last * 2 + max) / (2 * max)) as usize;
            [lut[j], lut[j + 1], lut[j + 2]]
        })
        .collect();
    Rgb8 {
        width,
        height,
        data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The heat map's ends are magma's: 0 visits its first colour, the image's maximum its
    /// last, and half the maximum the middle of the map.
    #[test]
    fn visits_heat_map_runs_from_zero_to_the_image_maximum() {
        let lut = nv_flip::magma_lut().to_vec();
        let n = lut.len() / 3;
        let entry = |i: usize| lut[3 * i..3 * i + 3].to_vec();
        let m = visits_heat_map(3, 1, &[0, 40, 80]);
        assert_eq!((m.width, m.height, m.data.len()), (3, 1, 9));
        assert_eq!(m.data[0..3], entry(0)[..]);
        assert_eq!(m.data[6..9], entry(n - 1)[..]);
        assert_eq!(
            m.data[3..6],
            entry(((n - 1) as f64 / 2.0).round() as usize)[..]
        );
        // Nothing visited: all the first colour, no division by zero.
        let none = visits_heat_map(2, 1, &[0, 0]);
        assert_eq!(none.data, [entry(0), entry(0)].concat());
    }

    fn image(v: u8) -> Rgb8 {
        Rgb8 {
            width: 8,
            height: 8,
            data: vec![v; 8 * 8 * 3],
        }
    }

    #[test]
    fn psnr_of_identical_and_different_images() {
        assert_eq!(psnr(&image(10), &image(10)), None);
        // Every channel off by 1: MSE 1, PSNR 20 log10(255).
        let p = psnr(&image(10), &image(11)).unwrap();
        assert!((p - 20.0 * 255f64.log10()).abs() < 1e-9, "{p}");
    }

    #[test]
    fn flip_is_zero_for_identical_images_and_grows_with_the_difference() {
        let mut a = image(0);
        for (i, b) in a.data.iter_mut().enumerate() {
            *b = (i * 7 % 256) as u8;
        }
        let (same, map) = flip(&a, &a);
        assert_eq!(same, 0.0);
        assert_eq!(map.data.len(), a.data.len());
        let (small, _) = flip(
            &a,
            &Rgb8 {
                data: a.data.iter().map(|&b| b.saturating_add(4)).collect(),
                ..a.clone()
            },
        );
        let (large, _) = flip(&a, &image(255));
        assert!(
            0.0 < small && small < large && large <= 1.0,
            "{small} {large}"
        );
    }

    #[test]
    fn magma_runs_from_dark_to_light() {
        let stops = magma_stops(9);
        assert_eq!(stops.len(), 9);
        let luma = |c: &[u8; 3]| u32::from(c[0]) + u32::from(c[1]) + u32::from(c[2]);
        assert!(
            stops.windows(2).all(|w| luma(&w[0]) < luma(&w[1])),
            "{stops:?}"
        );
        assert!(luma(&stops[0]) < 40 && luma(&stops[8]) > 600, "{stops:?}");
    }

    #[test]
    fn id_heat_map_marks_each_kind_of_difference() {
        let m = ids_diff(3, 1, &[1, 2, NO_HIT], &[1, 3, 4], None);
        assert_eq!(m.data, vec![0, 0, 0, 255, 140, 0, 255, 255, 255]);
    }
}
