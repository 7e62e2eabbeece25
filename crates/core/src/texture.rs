//! Image textures: linear RGB texels looked up bilinearly with per-axis wrap modes.
//!
//! Conventions are glTF's (and OpenGL's for the texel grid): texture coordinate `(0, 0)` is
//! the top-left corner of the image's first row, `u` runs along a row and `v` down the rows;
//! texel `(i, j)` has its centre at `((i + 0.5) / width, (j + 0.5) / height)`. A lookup
//! blends the four texels whose centres surround the point, their indices wrapped by each
//! axis's [`Wrap`] mode. OBJ files count `v` up from the bottom row; their loader flips it.

use crate::SceneError;
use glam::{Vec2, Vec3};

/// Largest width or height of a texture, in texels: a 16384 x 16384 texture already takes
/// 3 GiB of linear texels; the scene loader's memory budget bounds the total.
pub const MAX_TEXTURE_SIZE: u32 = 16_384;

/// What happens to texel indices outside the image, per axis (glTF sampler `wrapS` and
/// `wrapT`, OpenGL's `GL_REPEAT`, `GL_CLAMP_TO_EDGE`, `GL_MIRRORED_REPEAT`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// The image tiles the plane (glTF's default).
    #[default]
    Repeat,
    /// Indices are clamped to the first and last texel.
    ClampToEdge,
    /// The image tiles the plane, every other copy mirrored.
    MirroredRepeat,
}

impl Wrap {
    /// Texel index `i` of an axis with `n` texels, wrapped into `0..n`.
    #[inline]
    #[must_use]
    pub fn index(self, i: i64, n: u32) -> usize {
        let n = i64::from(n.max(1));
        let k = match self {
            Self::Repeat => i.rem_euclid(n),
            Self::ClampToEdge => i.clamp(0, n - 1),
            Self::MirroredRepeat => {
                let k = i.rem_euclid(2 * n);
                if k >= n { 2 * n - 1 - k } else { k }
            }
        };
        k as usize
    }
}

/// One image texture: its size, linear RGB texels row by row from the top, and the wrap
/// mode of each axis. Colour images are decoded from sRGB to linear once, when loaded
/// ([`srgb_to_linear`]), so lookups blend linear values.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// A name for messages (the image file, or the glTF file and image index).
    pub name: String,
    width: u32,
    height: u32,
    texels: Vec<Vec3>,
    /// Wrap modes along `u` (rows) and `v` (columns).
    pub wrap: [Wrap; 2],
}

impl Texture {
    /// A texture of `width x height` linear texels, row by row from the top.
    ///
    /// # Errors
    /// When a side is 0 or above [`MAX_TEXTURE_SIZE`], the texel count is not
    /// `width * height`, or a texel is not finite or has a negative component.
    pub fn new(
        name: impl Into<String>,
        width: u32,
        height: u32,
        texels: Vec<Vec3>,
        wrap: [Wrap; 2],
    ) -> Result<Self, SceneError> {
        let name = name.into();
        if width == 0 || height == 0 || width > MAX_TEXTURE_SIZE || height > MAX_TEXTURE_SIZE {
            return Err(SceneError::Invalid(format!(
                "texture {name}: {width} x {height} texels (each side must be 1 to \
                 {MAX_TEXTURE_SIZE})"
            )));
        }
        if texels.len() as u64 != u64::from(width) * u64::from(height) {
            return Err(SceneError::Invalid(format!(
                "texture {name}: {} texels for {width} x {height}",
                texels.len()
            )));
        }
        if let Some(i) = texels
            .iter()
            .position(|t| !t.is_finite() || t.min_element() < 0.0)
        {
            return Err(SceneError::Invalid(format!(
                "texture {name}: texel {i} is {} (texels are finite and at least 0)",
                texels[i]
            )));
        }
        Ok(Self {
            name,
            width,
            height,
            texels,
            wrap,
        })
    }

    /// A colour texture from 8-bit sRGB-encoded RGB texels (three bytes each, row by row
    /// from the top), decoded to linear once here.
    ///
    /// # Errors
    /// As [`Texture::new`] (sizes).
    pub fn from_srgb8(
        name: impl Into<String>,
        width: u32,
        height: u32,
        rgb: &[u8],
        wrap: [Wrap; 2],
    ) -> Result<Self, SceneError> {
        let lut: Vec<f32> = (0..=255u8)
            .map(|c| srgb_to_linear(c as f32 / 255.0))
            .collect();
        let texels = rgb
            .chunks_exact(3)
            .map(|c| Vec3::new(lut[c[0] as usize], lut[c[1] as usize], lut[c[2] as usize]))
            .collect();
        Self::new(name, width, height, texels, wrap)
    }

    /// Width in texels.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Texel `(i, j)` (column, row from the top), its indices wrapped.
    #[inline]
    #[must_use]
    pub fn texel(&self, i: i64, j: i64) -> Vec3 {
        let x = self.wrap[0].index(i, self.width);
        let y = self.wrap[1].index(j, self.height);
        self.texels[y * self.width as usize + x]
    }

    /// The bilinearly filtered value at texture coordinates `uv` (the module's
    /// conventions). Coordinates outside `[0, 1]` wrap by the texture's modes; a
    /// non-finite coordinate reads texel 0 of its axis (scene builders refuse them).
    #[inline]
    #[must_use]
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        // Texel space with texel centres at integers.
        let x = f64::from(uv.x) * f64::from(self.width) - 0.5;
        let y = f64::from(uv.y) * f64::from(self.height) - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        // Saturating casts: huge coordinates stay defined (and wrap as far-away indices).
        let (i, j) = (x0 as i64, y0 as i64);
        let top = self.texel(i, j) * (1.0 - fx) + self.texel(i.saturating_add(1), j) * fx;
        let j1 = j.saturating_add(1);
        let bottom = self.texel(i, j1) * (1.0 - fx) + self.texel(i.saturating_add(1), j1) * fx;
        let v = top * (1.0 - fy) + bottom * fy;
        if v.is_finite() { v } else { self.texels[0] }
    }

    /// Bytes the texels take.
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.texels.len() * std::mem::size_of::<Vec3>()
    }
}

/// The sRGB transfer function's inverse (IEC 61966-2-1): an encoded value in `[0, 1]` to
/// linear light.
#[inline]
#[must_use]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 x 2 texture: red, green / blue, white.
    fn quad(wrap: [Wrap; 2]) -> Texture {
        let t = vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE];
        Texture::new("q", 2, 2, t, wrap).unwrap()
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).abs().max_element() < 1e-6
    }

    #[test]
    fn texel_centres_read_their_texel() {
        let t = quad([Wrap::Repeat; 2]);
        assert!(close(t.sample(Vec2::new(0.25, 0.25)), Vec3::X));
        assert!(close(t.sample(Vec2::new(0.75, 0.25)), Vec3::Y));
        assert!(close(t.sample(Vec2::new(0.25, 0.75)), Vec3::Z));
        assert!(close(t.sample(Vec2::new(0.75, 0.75)), Vec3::ONE));
    }

    #[test]
    fn bilinear_between_centres() {
        let t = quad([Wrap::ClampToEdge; 2]);
        // Halfway between the top two centres.
        assert!(close(
            t.sample(Vec2::new(0.5, 0.25)),
            Vec3::new(0.5, 0.5, 0.0)
        ));
        // The image centre: the mean of all four.
        assert!(close(t.sample(Vec2::new(0.5, 0.5)), Vec3::splat(0.5)));
        // A quarter of the way from red's centre towards green's: 3/4 red, 1/4 green.
        assert!(close(
            t.sample(Vec2::new(0.375, 0.25)),
            Vec3::new(0.75, 0.25, 0.0)
        ));
    }

    #[test]
    fn wrap_modes() {
        // Index arithmetic of each mode on a 3-texel axis.
        let idx = |w: Wrap| (-4..7).map(|i| w.index(i, 3)).collect::<Vec<_>>();
        assert_eq!(idx(Wrap::Repeat), [2, 0, 1, 2, 0, 1, 2, 0, 1, 2, 0]);
        assert_eq!(idx(Wrap::ClampToEdge), [0, 0, 0, 0, 0, 1, 2, 2, 2, 2, 2]);
        assert_eq!(idx(Wrap::MirroredRepeat), [2, 2, 1, 0, 0, 1, 2, 2, 1, 0, 0]);
        // At the left edge (u = 0, halfway between texel -1 and texel 0 centres).
        let edge = Vec2::new(0.0, 0.25);
        // Repeat blends with the last column (green), clamp and mirror stay red.
        assert!(close(
            quad([Wrap::Repeat; 2]).sample(edge),
            Vec3::new(0.5, 0.5, 0.0)
        ));
        assert!(close(quad([Wrap::ClampToEdge; 2]).sample(edge), Vec3::X));
        assert!(close(quad([Wrap::MirroredRepeat; 2]).sample(edge), Vec3::X));
        // Out-of-range coordinates: repeat is periodic, mirror reflects, clamp sticks.
        let t = quad([Wrap::Repeat; 2]);
        assert!(close(t.sample(Vec2::new(3.75, -1.75)), Vec3::Y));
        let m = quad([Wrap::MirroredRepeat; 2]);
        assert!(close(m.sample(Vec2::new(1.25, 0.25)), Vec3::Y));
        assert!(close(m.sample(Vec2::new(-0.25, 0.25)), Vec3::X));
        let c = quad([Wrap::ClampToEdge, Wrap::Repeat]);
        assert!(close(c.sample(Vec2::new(9.0, 1.25)), Vec3::Y));
        // Far away and non-finite coordinates stay defined.
        assert!(t.sample(Vec2::new(1e30, -1e30)).is_finite());
        assert!(t.sample(Vec2::new(f32::NAN, f32::INFINITY)).is_finite());
    }

    #[test]
    fn srgb_is_decoded_once_at_load() {
        let t = Texture::from_srgb8("s", 2, 1, &[0, 128, 255, 188, 188, 188], [Wrap::Repeat; 2])
            .unwrap();
        let a = t.texel(0, 0);
        assert_eq!(a.x, 0.0);
        assert!((a.y - 0.2158605).abs() < 1e-6, "{a}");
        assert_eq!(a.z, 1.0);
        // 188 is about 0.5 in linear light.
        assert!((t.texel(1, 0).x - 0.5029).abs() < 1e-3);
        assert!(Texture::from_srgb8("s", 2, 2, &[0; 6], [Wrap::Repeat; 2]).is_err());
        assert!(Texture::new("z", 0, 1, vec![], [Wrap::Repeat; 2]).is_err());
        assert!(Texture::new("n", 1, 1, vec![Vec3::NAN], [Wrap::Repeat; 2]).is_err());
    }
}
