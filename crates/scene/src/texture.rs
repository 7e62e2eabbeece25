//! The image textures mesh files name (OBJ `map_Kd`, glTF `baseColorTexture` and
//! `emissiveTexture`): where each image is, and its decoding (PNG or JPEG through `image`,
//! sRGB to linear) once per scene. A texture that is missing, undecodable or too large is a
//! warning, and its material keeps its flat colour, as is one whose file is far smaller than
//! its decoded texels unless the user set the memory budget
//! ([`crate::samples::check_expansion`]); the memory budget refuses textures the scene
//! cannot hold.

use crate::budget::{Holds, Reservation};
use crate::error::LoadError;
use crate::samples::{DecodeError, decode_checked};
use raybench_core::{MAX_TEXTURE_SIZE, SceneBuilder, Texture, Wrap};
use std::path::PathBuf;
use std::sync::Arc;

/// Where a texture's encoded image is.
#[derive(Clone, Debug, PartialEq)]
pub enum ImageSource {
    /// An image file.
    File(PathBuf),
    /// Encoded bytes held in memory (a data URI or a glTF buffer view); `key` identifies
    /// them within a scene (the glTF file's path and the image's index).
    Bytes {
        /// What identifies these bytes (two equal keys are the same image).
        key: String,
        /// The encoded image.
        bytes: Arc<[u8]>,
    },
}

/// A colour texture a mesh file's material names: where its image is, a name for messages,
/// and its wrap modes. Colour textures hold sRGB-encoded values; they are decoded to linear
/// once, when the scene is built.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureRef {
    /// For messages: the image's file name or what holds it (`image 2 of duck.glb`).
    pub name: String,
    /// The encoded image.
    pub source: ImageSource,
    /// Wrap modes along `u` and `v`.
    pub wrap: [Wrap; 2],
}

impl TextureRef {
    /// What identifies the decoded texture within a scene: the source and the wrap modes.
    fn key(&self) -> String {
        let source = match &self.source {
            ImageSource::File(p) => std::fs::canonicalize(p)
                .unwrap_or_else(|_| p.clone())
                .display()
                .to_string(),
            ImageSource::Bytes { key, .. } => key.clone(),
        };
        format!("{source} {:?}", self.wrap)
    }
}

/// Largest image file read for a texture.
const MAX_IMAGE_FILE_BYTES: u64 = 1 << 30;

/// Decodes `tex` (its size checked against [`MAX_TEXTURE_SIZE`] and the budget before its
/// pixels are decoded). The outer error is the budget's refusal; the inner one says why
/// the texture cannot be used.
pub(crate) fn decode(
    tex: &TextureRef,
    budget: &mut Reservation,
    context: &str,
) -> Result<Result<Texture, String>, LoadError> {
    use std::io::{Cursor, Read as _};
    let bytes: Arc<[u8]> = match &tex.source {
        ImageSource::Bytes { bytes, .. } => Arc::clone(bytes),
        ImageSource::File(path) => {
            let read = || -> Result<Vec<u8>, String> {
                let meta = std::fs::metadata(path).map_err(|e| e.to_string())?;
                if !meta.is_file() {
                    return Err(crate::io::not_a_file_message(&meta));
                }
                if meta.len() > MAX_IMAGE_FILE_BYTES {
                    return Err(format!(
                        "the file has {} bytes (limit {MAX_IMAGE_FILE_BYTES})",
                        meta.len()
                    ));
                }
                let mut data = Vec::new();
                std::fs::File::open(path)
                    .and_then(|f| f.take(MAX_IMAGE_FILE_BYTES).read_to_end(&mut data))
                    .map_err(|e| e.to_string())?;
                Ok(data)
            };
            match read() {
                Ok(b) => b.into(),
                Err(why) => return Ok(Err(format!("{}: {why}", path.display()))),
            }
        }
    };
    let open = || {
        let r = image::ImageReader::new(Cursor::new(&bytes[..]))
            .with_guessed_format()
            .map_err(|e| DecodeError::Unreadable(crate::error::os_error(&e)))?;
        if r.format().is_none() {
            return Err(DecodeError::Unreadable("not a PNG or JPEG image".into()));
        }
        Ok(r)
    };
    let user_limit = budget.is_set_by_user();
    let check = |w: u32, h: u32| {
        if w == 0 || h == 0 || w > MAX_TEXTURE_SIZE || h > MAX_TEXTURE_SIZE {
            return Err(format!(
                "{w} x {h} texels (each side must be 1 to {MAX_TEXTURE_SIZE})"
            ));
        }
        crate::samples::check_expansion(w, h, bytes.len() as u64, user_limit)
    };
    let reserve = |texels| {
        budget.reserve(
            Holds::Texels(texels),
            &format!("{context}: texture {}", tex.name),
        )
    };
    // The widest decoded form (16-bit RGBA) and the 8-bit RGB copy: 11 bytes a texel.
    let img = match decode_checked(open, check, reserve, 11) {
        Ok(img) => img,
        Err(DecodeError::Unreadable(why) | DecodeError::Refused(why)) => return Ok(Err(why)),
        Err(DecodeError::Fatal(e)) => return Err(e),
    };
    let rgb = img.into_rgb8();
    let (w, h) = rgb.dimensions();
    Ok(
        Texture::from_srgb8(tex.name.clone(), w, h, rgb.as_raw(), tex.wrap)
            .map_err(|e| e.to_string()),
    )
}

/// Adds the textures `refs` to the scene (each decoded once per scene: a texture already
/// added, from the same source with the same wrap modes, is reused) and returns each one's
/// index, or `None` where it cannot be used, with a warning naming it (`context` names the
/// mesh).
///
/// # Errors
/// [`LoadError::OverBudget`] when a texture does not fit in the memory budget.
pub(crate) fn add_textures(
    b: &mut SceneBuilder,
    refs: &[TextureRef],
    budget: &mut Reservation,
    context: &str,
) -> Result<Vec<Option<u32>>, LoadError> {
    let mut out = Vec::with_capacity(refs.len());
    for tex in refs {
        let key = tex.key();
        if let Some(i) = b.texture(&key) {
            out.push(Some(i));
            continue;
        }
        match decode(tex, budget, context)? {
            Ok(t) => out.push(Some(b.add_texture(key, t))),
            Err(why) => {
                b.warn(format!(
                    "{context}: texture {} cannot be used ({why}): its material keeps its \
                     flat colour",
                    tex.name
                ));
                out.push(None);
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::ImageEncoder as _;

    /// A `w x h` black PNG as a texture of encoded bytes.
    fn png(w: u32, h: u32) -> TextureRef {
        encoded(w, h, image::ImageFormat::Png)
    }

    /// A `w x h` black image in `format` as a texture of encoded bytes.
    fn encoded(w: u32, h: u32, format: image::ImageFormat) -> TextureRef {
        let mut out = std::io::Cursor::new(Vec::new());
        image::RgbImage::new(w, h)
            .write_to(&mut out, format)
            .unwrap();
        TextureRef {
            name: format!("{w}x{h}"),
            source: ImageSource::Bytes {
                key: format!("{w}x{h}"),
                bytes: out.into_inner().into(),
            },
            wrap: [Wrap::Repeat; 2],
        }
    }

    /// A texture whose file is far smaller than its texels (a decompression bomb) is a
    /// warning under the default budget, and decoded under a budget the user set.
    #[test]
    fn a_texture_that_expands_too_much_needs_a_user_limit() {
        // Black, compressed as well as PNG can: some 300 pixels a byte.
        let mut file = Vec::new();
        image::codecs::png::PngEncoder::new_with_quality(
            &mut file,
            image::codecs::png::CompressionType::Best,
            image::codecs::png::FilterType::NoFilter,
        )
        .write_image(
            &vec![0; 2048 * 2049 * 3],
            2048,
            2049,
            image::ExtendedColorType::Rgb8,
        )
        .unwrap();
        assert!(file.len() < 20_000, "{}", file.len());
        let bomb = TextureRef {
            name: "2048x2049".into(),
            source: ImageSource::Bytes {
                key: "bomb".into(),
                bytes: file.into(),
            },
            wrap: [Wrap::Repeat; 2],
        };
        let mut b = SceneBuilder::new("t");
        let mut budget = Reservation::with_limit(1 << 30);
        let ids = add_textures(&mut b, std::slice::from_ref(&bomb), &mut budget, "s").unwrap();
        assert_eq!(ids, [None]);
        let s = b.build();
        assert_eq!(s.warnings.len(), 1);
        let w = &s.warnings[0];
        assert!(
            w.starts_with(
                "s: texture 2048x2049 cannot be used (2048 x 2049 pixels from a file of "
            ) && w.contains("over the 64 that the default memory budget allows")
                && w.contains("set --memory-limit or RAYBENCH_MEMORY_LIMIT to decode it")
                && w.ends_with("its material keeps its flat colour"),
            "{w}"
        );
        // 2048 x 2048 is decoded whatever its file's size.
        let mut b = SceneBuilder::new("t");
        assert_eq!(
            add_textures(&mut b, &[png(2048, 2048)], &mut budget, "s").unwrap(),
            [Some(0)]
        );
        let mut b = SceneBuilder::new("t");
        let mut user = Reservation::with_user_limit(1 << 30);
        assert_eq!(
            add_textures(&mut b, &[bomb], &mut user, "s").unwrap(),
            [Some(0)]
        );
    }

    /// A decoder's error is one line of words: no Debug form of the decoder's types, no
    /// line break.
    #[test]
    fn decoder_errors_are_one_line_of_words() {
        let TextureRef {
            source: ImageSource::Bytes { bytes, .. },
            ..
        } = png(4, 4)
        else {
            unreachable!()
        };
        let mut crc = bytes.to_vec();
        crc[25] = 9; // inside IHDR: its CRC no longer matches
        let mut jpeg = b"\xff\xd8\xff\xe0junk".to_vec();
        jpeg.truncate(8);
        for (data, needle) in [(crc, "while decoding IHDR chunk"), (jpeg, "Jpeg")] {
            let tex = TextureRef {
                name: "x".into(),
                source: ImageSource::Bytes {
                    key: needle.into(),
                    bytes: data.into(),
                },
                wrap: [Wrap::Repeat; 2],
            };
            let mut b = SceneBuilder::new("t");
            add_textures(&mut b, &[tex], &mut Reservation::with_limit(1 << 30), "s").unwrap();
            let w = &b.build().warnings[0];
            assert!(w.contains(needle), "{w}");
            assert!(
                !w.contains('\n') && !w.contains(" { ") && !w.contains(".)"),
                "{w}"
            );
        }
    }

    #[test]
    fn sizes_and_the_budget_apply_before_decoding() {
        let mut b = SceneBuilder::new("t");
        let mut budget = Reservation::with_limit(1 << 20);
        // Small: decoded once, then reused.
        let small = png(4, 2);
        let ids = add_textures(&mut b, &[small.clone(), small], &mut budget, "s").unwrap();
        assert_eq!(ids, [Some(0), Some(0)]);
        // JPEG too.
        let jpeg = encoded(8, 8, image::ImageFormat::Jpeg);
        assert_eq!(
            add_textures(&mut b, &[jpeg], &mut budget, "s").unwrap(),
            [Some(1)]
        );
        // Wider than the limit: a warning and no texture.
        let ids = add_textures(&mut b, &[png(MAX_TEXTURE_SIZE + 1, 1)], &mut budget, "s");
        assert_eq!(ids.unwrap(), [None]);
        let s = b.build();
        assert_eq!(s.textures.len(), 2);
        assert!(
            s.warnings[0].contains("each side must be 1 to 16384"),
            "{:?}",
            s.warnings
        );
        // Over the budget (2048 x 2048 texels, 19 bytes each, in 1 MiB): refused.
        let mut b = SceneBuilder::new("t");
        let e = add_textures(&mut b, &[png(2048, 2048)], &mut budget, "scene.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("scene.toml: texture 2048x2048") && e.contains("texture texels"),
            "{e}"
        );
    }
}
