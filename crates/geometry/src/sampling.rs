//! Counter-based random numbers: a pure function of (pixel, sample, dimension, seed), so
//! images do not depend on thread count or scheduling, and the GPU can reproduce them.
//! Pinned in `docs/sampling.md`. Also the maps from uniform numbers to points and frames
//! that light and BSDF sampling share.

use glam::Vec3;

/// The `pcg3d` hash of Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT 2020:
/// a bijection on `u32^3` with good avalanche, three multiply-adds and a shift.
#[inline]
#[must_use]
pub fn pcg3d(v: [u32; 3]) -> [u32; 3] {
    let [mut x, mut y, mut z] = v.map(|c| c.wrapping_mul(1_664_525).wrapping_add(1_013_904_223));
    x = x.wrapping_add(y.wrapping_mul(z));
    y = y.wrapping_add(z.wrapping_mul(x));
    z = z.wrapping_add(x.wrapping_mul(y));
    x ^= x >> 16;
    y ^= y >> 16;
    z ^= z >> 16;
    x = x.wrapping_add(y.wrapping_mul(z));
    y = y.wrapping_add(z.wrapping_mul(x));
    z = z.wrapping_add(x.wrapping_mul(y));
    [x, y, z]
}

/// Maps 32 random bits to a float uniform in `[0, 1)` (the top 24 bits, exactly).
#[inline]
#[must_use]
pub fn to_unit_f32(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// The random stream of one pixel sample. Each call to [`Sampler::next_f32`] advances the
/// dimension; integrators use fixed dimensions per bounce (see `docs/sampling.md`), so the
/// numbers are keyed by pixel, sample and bounce.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sampler {
    pixel: u32,
    sample: u32,
    dimension: u32,
    seed: u32,
}

impl Sampler {
    /// The stream of sample `sample` of pixel `pixel` (row-major index) under `seed`.
    #[inline]
    #[must_use]
    pub fn new(pixel: u32, sample: u32, seed: u32) -> Self {
        Self {
            pixel,
            sample,
            dimension: 0,
            seed,
        }
    }

    /// Jumps to dimension `dimension` (for example `2 + 8 * bounce`).
    #[inline]
    pub fn set_dimension(&mut self, dimension: u32) {
        self.dimension = dimension;
    }

    /// The next uniform number in `[0, 1)`.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        let [x, _, _] = pcg3d([
            self.pixel,
            self.sample,
            self.dimension ^ self.seed.wrapping_mul(0x9E37_79B9),
        ]);
        self.dimension = self.dimension.wrapping_add(1);
        to_unit_f32(x)
    }

    /// The next two numbers.
    #[inline]
    pub fn next_2d(&mut self) -> (f32, f32) {
        let a = self.next_f32();
        (a, self.next_f32())
    }
}

/// An orthonormal basis `(t, b)` completing unit `n` (Duff et al., "Building an Orthonormal
/// Basis, Revisited", JCGT 2017).
#[inline]
#[must_use]
pub fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// A uniform point on the triangle `(a, b, c)` from two uniform numbers (barycentrics
/// `(1 - sqrt(u1), u2 sqrt(u1))`, pbrt's `SampleUniformTriangle` mapping).
#[inline]
#[must_use]
pub fn triangle_point(a: Vec3, b: Vec3, c: Vec3, u1: f32, u2: f32) -> Vec3 {
    let [w0, w1, w2] = triangle_weights(u1, u2);
    a * w0 + b * w1 + c * w2
}

/// The barycentric weights of [`triangle_point`]'s point: `(1 - sqrt(u1), u2 sqrt(u1))` and
/// the rest; weights 1 and 2 are the point's surface parameters `(u, v)` (as in a hit).
#[inline]
#[must_use]
pub fn triangle_weights(u1: f32, u2: f32) -> [f32; 3] {
    let s = u1.sqrt();
    let w0 = 1.0 - s;
    let w1 = u2 * s;
    [w0, w1, 1.0 - w0 - w1]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values_pin_the_generator() {
        // Pinned (computed independently from the formula in docs/sampling.md) so that any
        // change to the generator, which would change every image, is deliberate.
        assert_eq!(
            pcg3d([0, 0, 0]),
            [2_611_992_518, 2_833_812_075, 1_058_359_340]
        );
        assert_eq!(
            pcg3d([1, 2, 3]),
            [4_204_755_366, 1_223_881_804, 1_500_469_937]
        );
        let mut s = Sampler::new(7, 3, 0);
        assert_eq!(s.next_f32(), (2_221_848_401u32 >> 8) as f32 / 16_777_216.0);
    }

    #[test]
    fn uniform_mean_and_range() {
        let mut sum = 0.0f64;
        let n = 100_000;
        for i in 0..n {
            let x = Sampler::new(i, 0, 1).next_f32();
            assert!((0.0..1.0).contains(&x));
            sum += f64::from(x);
        }
        let mean = sum / f64::from(n);
        // Standard error 1/sqrt(12 n) ~ 0.0009: five sigma.
        assert!((mean - 0.5).abs() < 0.0046, "mean {mean}");
    }

    #[test]
    fn streams_differ_by_pixel_sample_and_seed() {
        let a = Sampler::new(1, 0, 0).next_f32();
        assert_ne!(a, Sampler::new(2, 0, 0).next_f32());
        assert_ne!(a, Sampler::new(1, 1, 0).next_f32());
        assert_ne!(a, Sampler::new(1, 0, 1).next_f32());
    }
}
