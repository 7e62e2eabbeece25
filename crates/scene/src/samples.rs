//! Gridded data from files: greyscale PNG height maps and raw sample arrays (the common
//! format of CT and MRI volumes: little-endian samples, dimensions given beside the file).
//!
//! Sizes are checked against the limits before anything is allocated or decoded, and
//! every malformed file is a [`LoadError`] naming it.

use crate::error::LoadError;
use std::path::Path;

/// The type of one sample of a raw file (little-endian).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SampleFormat {
    /// Unsigned 8-bit.
    U8,
    /// Unsigned 16-bit.
    U16,
    /// 32-bit IEEE float.
    F32,
}

impl SampleFormat {
    /// The name scene files give the type (`u16`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::U8 => "u8",
            Self::U16 => "u16",
            Self::F32 => "f32",
        }
    }

    /// Bytes per sample.
    #[must_use]
    pub fn bytes(self) -> u64 {
        match self {
            Self::U8 => 1,
            Self::U16 => 2,
            Self::F32 => 4,
        }
    }
}

/// Samples of a raw file in their stored type.
#[derive(Clone, Debug, PartialEq)]
pub enum RawSamples {
    /// 8-bit samples.
    U8(Vec<u8>),
    /// 16-bit samples.
    U16(Vec<u16>),
    /// Float samples.
    F32(Vec<f32>),
}

impl From<RawSamples> for raybench_core::VolumeData {
    /// Volume data in the samples' stored type.
    fn from(samples: RawSamples) -> Self {
        match samples {
            RawSamples::U8(d) => Self::U8(d),
            RawSamples::U16(d) => Self::U16(d),
            RawSamples::F32(d) => Self::F32(d),
        }
    }
}

impl RawSamples {
    /// The samples as floats: integers normalised to `[0, 1]` (divided by 255 or 65535),
    /// floats as they are.
    #[must_use]
    pub fn to_unit_f32(&self) -> Vec<f32> {
        match self {
            Self::U8(v) => v.iter().map(|&x| f32::from(x) / 255.0).collect(),
            Self::U16(v) => v.iter().map(|&x| f32::from(x) / 65_535.0).collect(),
            Self::F32(v) => v.clone(),
        }
    }
}

/// Reads `count` samples of `format` from the raw file `path`, which must be a regular file
/// holding exactly that many bytes (`count` is checked against `max_count` first).
///
/// # Errors
/// [`LoadError::Io`] when unreadable, [`LoadError::Parse`] for something other than a
/// regular file, a size that does not match or a count above the limit, and for NaN or
/// infinite float samples.
pub fn read_raw(
    path: &Path,
    count: u64,
    format: SampleFormat,
    max_count: u64,
) -> Result<RawSamples, LoadError> {
    use std::io::Read as _;
    let expected = check_raw_count(path, count, format, max_count)?;
    let io = |cause| LoadError::Io {
        path: path.to_owned(),
        cause,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        // A device such as /dev/zero reports no length and never ends.
        return Err(raw_err(path, "not a regular file".into()));
    }
    if meta.len() != expected {
        return Err(size_mismatch(path, meta.len(), count, format));
    }
    // At most one byte more than expected: a file that grew meanwhile is caught below
    // without reading all of it.
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .map_err(io)?
        .take(expected + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 != expected {
        return Err(raw_err(path, "the file changed while it was read".into()));
    }
    decode_raw(&bytes, count, format, max_count, path)
}

/// Decodes `count` little-endian samples of `format` from `bytes`, which must hold exactly
/// that many (`count` is checked against `max_count` first; `path` names the data in
/// errors). [`read_raw`] uses it; so do the fuzz targets and property tests.
///
/// # Errors
/// [`LoadError::Parse`] for a count above the limit, a length that does not match, and NaN
/// or infinite float samples.
pub fn decode_raw(
    bytes: &[u8],
    count: u64,
    format: SampleFormat,
    max_count: u64,
    path: &Path,
) -> Result<RawSamples, LoadError> {
    let expected = check_raw_count(path, count, format, max_count)?;
    if bytes.len() as u64 != expected {
        return Err(size_mismatch(path, bytes.len() as u64, count, format));
    }
    Ok(match format {
        SampleFormat::U8 => RawSamples::U8(bytes.to_vec()),
        SampleFormat::U16 => RawSamples::U16(
            bytes
                .chunks_exact(2)
                .map(|c| u16::from_le_bytes([c[0], c[1]]))
                .collect(),
        ),
        SampleFormat::F32 => {
            let v: Vec<f32> = bytes
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect();
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                return Err(raw_err(path, format!("sample {} is not finite", i + 1)));
            }
            RawSamples::F32(v)
        }
    })
}

fn raw_err(path: &Path, message: String) -> LoadError {
    LoadError::Parse {
        path: path.to_owned(),
        message,
    }
}

/// The byte size of `count` samples, once `count` is known to be within `max_count`.
fn check_raw_count(
    path: &Path,
    count: u64,
    format: SampleFormat,
    max_count: u64,
) -> Result<u64, LoadError> {
    if count > max_count {
        return Err(raw_err(
            path,
            format!("{count} samples exceed the limit of {max_count}"),
        ));
    }
    Ok(count * format.bytes())
}

/// The error for a raw file of `len` bytes where `count` samples of `format` need another
/// size: too short (truncated) or too long.
fn size_mismatch(path: &Path, len: u64, count: u64, format: SampleFormat) -> LoadError {
    let expected = count * format.bytes();
    let what = if len < expected { "short" } else { "long" };
    raw_err(
        path,
        format!(
            "raw file holds {len} bytes, too {what} for {count} {} samples ({expected} bytes): \
             check the declared dimensions and format",
            format.name()
        ),
    )
}

/// Images of at most this many pixels are never refused for their compression ratio
/// ([`check_expansion`]): 2048 x 2048, some 80 MB decoded.
pub(crate) const EXPANSION_FREE_PIXELS: u64 = 1 << 22;

/// The most pixels a larger image may have per byte of its file unless the user set the
/// memory budget ([`check_expansion`]). Photographs and painted textures have well under
/// 10 (a PNG or JPEG byte holds a few pixels at best); a 783 KB PNG of 16384 x 16384
/// zeros has 343 and would take gigabytes once decoded.
pub(crate) const MAX_PIXELS_PER_FILE_BYTE: u64 = 64;

/// Refuses a `w x h` image whose file of `file_bytes` bytes decodes to far more than it
/// holds (a decompression bomb, or a flat image better given as a colour): above
/// [`EXPANSION_FREE_PIXELS`] pixels, more than [`MAX_PIXELS_PER_FILE_BYTE`] per byte. A
/// memory budget the user set (`user_limit`) lifts the check: the budget alone then
/// decides.
///
/// # Errors
/// A sentence with the sizes and how to lift the check.
pub(crate) fn check_expansion(
    w: u32,
    h: u32,
    file_bytes: u64,
    user_limit: bool,
) -> Result<(), String> {
    let pixels = u64::from(w) * u64::from(h);
    if user_limit
        || pixels <= EXPANSION_FREE_PIXELS
        || pixels <= MAX_PIXELS_PER_FILE_BYTE.saturating_mul(file_bytes)
    {
        return Ok(());
    }
    Err(format!(
        "{w} x {h} pixels from a file of {}: {} pixels per byte, over the {} that the default \
         memory budget allows an image of more than {} pixels (a decompression bomb?); set \
         --memory-limit or RAYBENCH_MEMORY_LIMIT to decode it",
        crate::budget::human_bytes(file_bytes),
        pixels / file_bytes.max(1),
        MAX_PIXELS_PER_FILE_BYTE,
        EXPANSION_FREE_PIXELS
    ))
}

/// An image decoder's error in one line of words: its first line, with the Debug form of
/// a PNG chunk type (`ChunkType { type: IHDR, critical: true, .. }`) given as its name.
pub(crate) fn image_error_words(e: &image::ImageError) -> String {
    let text = e.to_string();
    let mut line = text.lines().next().unwrap_or_default().trim().to_owned();
    while let Some(at) = line.find(" { type: ") {
        let name_start = line[..at]
            .rfind(|c: char| !c.is_alphanumeric() && c != '_')
            .map_or(0, |i| i + 1);
        let value_start = at + " { type: ".len();
        let Some(end) = line[at..].find('}').map(|i| at + i + 1) else {
            break;
        };
        let value: String = line[value_start..end]
            .chars()
            .take_while(|c| c.is_alphanumeric())
            .collect();
        line.replace_range(name_start..end, &value);
    }
    line.trim_end_matches(['.', ' ']).to_owned()
}

/// Why [`decode_checked`] gave no image.
pub(crate) enum DecodeError {
    /// The header or the pixels cannot be decoded (the decoder's words).
    Unreadable(String),
    /// The size check refused the image (its words).
    Refused(String),
    /// Opening the image, or the memory budget, failed: passed on as it is.
    Fatal(LoadError),
}

/// Decodes an image in two passes, the one way every image a scene names is read: its
/// header's size goes to `check` and its pixel count to `reserve` (the memory budget)
/// before any pixel is decoded, then the pixels are decoded under an allocation limit of
/// `alloc_bytes_per_pixel` per pixel. `open` gives a reader at the image's start (it is
/// called twice).
pub(crate) fn decode_checked<R: std::io::BufRead + std::io::Seek>(
    open: impl Fn() -> Result<image::ImageReader<R>, DecodeError>,
    check: impl FnOnce(u32, u32) -> Result<(), String>,
    reserve: impl FnOnce(u64) -> Result<(), LoadError>,
    alloc_bytes_per_pixel: u64,
) -> Result<image::DynamicImage, DecodeError> {
    let (w, h) = open()?
        .into_dimensions()
        .map_err(|e| DecodeError::Unreadable(image_error_words(&e)))?;
    check(w, h).map_err(DecodeError::Refused)?;
    let pixels = u64::from(w) * u64::from(h);
    reserve(pixels).map_err(DecodeError::Fatal)?;
    let mut reader = open()?;
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(pixels * alloc_bytes_per_pixel + (1 << 20));
    reader.limits(limits);
    reader
        .decode()
        .map_err(|e| DecodeError::Unreadable(image_error_words(&e)))
}

/// Decodes the image at `path` as `format` (`what` names it in errors: `PNG`), refusing
/// it from its header when it has more than `max_pixels` pixels, and calling `reserve`
/// with its pixel count before decoding (the memory budget). Decoding may allocate
/// `bytes_per_pixel` per pixel twice over (the widest decoded form and a conversion).
/// `contents` are the file's bytes when they are already in memory (the fuzz targets);
/// `None` reads the file.
///
/// # Errors
/// [`LoadError::Io`] when unreadable, [`LoadError::Parse`] when not decodable as `format`
/// or too large, and what `reserve` returns.
pub(crate) fn decode_image(
    path: &Path,
    contents: Option<&[u8]>,
    format: image::ImageFormat,
    what: &str,
    max_pixels: u64,
    bytes_per_pixel: u64,
    reserve: impl FnOnce(u64) -> Result<(), LoadError>,
) -> Result<image::DynamicImage, LoadError> {
    // The file's length, which the decoded size is checked against.
    let file_bytes = match contents {
        Some(bytes) => bytes.len() as u64,
        None => {
            // A FIFO would block the reader.
            crate::io::check_regular_file(path)?;
            std::fs::metadata(path).map_or(u64::MAX, |m| m.len())
        }
    };
    let user_limit = crate::budget::MemoryBudget::current().is_ok_and(|b| b.is_set_by_user());
    let check = |w: u32, h: u32| {
        let pixels = u64::from(w) * u64::from(h);
        if pixels > max_pixels {
            return Err(format!(
                "{w} x {h} image has {pixels} pixels (limit {max_pixels})"
            ));
        }
        check_expansion(w, h, file_bytes, user_limit)
    };
    let decoded = if let Some(bytes) = contents {
        let open = || {
            let mut r = image::ImageReader::new(std::io::Cursor::new(bytes));
            r.set_format(format);
            Ok(r)
        };
        decode_checked(open, check, reserve, 2 * bytes_per_pixel)
    } else {
        let open = || {
            let mut r = image::ImageReader::open(path).map_err(|cause| {
                DecodeError::Fatal(LoadError::Io {
                    path: path.to_owned(),
                    cause,
                })
            })?;
            r.set_format(format);
            Ok(r)
        };
        decode_checked(open, check, reserve, 2 * bytes_per_pixel)
    };
    let parse = |message: String| LoadError::Parse {
        path: path.to_owned(),
        message,
    };
    decoded.map_err(|e| match e {
        DecodeError::Unreadable(m) => parse(format!("not a readable {what}: {m}")),
        DecodeError::Refused(m) => parse(m),
        DecodeError::Fatal(e) => e,
    })
}

/// Reads a greyscale (or colour: its luma) 8- or 16-bit PNG as `(width, height, samples)`
/// with samples in `[0, 1]`, row by row from the top. Images with more than `max_pixels`
/// pixels are refused from their header, before decoding.
///
/// # Errors
/// [`LoadError::Io`] when unreadable, [`LoadError::Parse`] when not a decodable PNG or too
/// large.
pub fn read_png_gray(path: &Path, max_pixels: u64) -> Result<(u32, u32, Vec<f32>), LoadError> {
    // Room for the decoded image in its widest form (16-bit RGBA).
    let img = decode_image(
        path,
        None,
        image::ImageFormat::Png,
        "PNG",
        max_pixels,
        8,
        |_| Ok(()),
    )?;
    let (w, h) = (img.width(), img.height());
    let luma = img.into_luma16();
    Ok((
        w,
        h,
        luma.into_raw()
            .into_iter()
            .map(|x| f32::from(x) / 65_535.0)
            .collect(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str, bytes: &[u8]) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("raybench-samples-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    #[test]
    fn raw_sizes_and_values() {
        let p = temp("a.raw", &[0, 0, 255, 255]);
        assert_eq!(
            read_raw(&p, 2, SampleFormat::U16, 10).unwrap(),
            RawSamples::U16(vec![0, 65535])
        );
        assert_eq!(
            read_raw(&p, 4, SampleFormat::U8, 10).unwrap().to_unit_f32(),
            vec![0.0, 0.0, 1.0, 1.0]
        );
        assert!(read_raw(&p, 3, SampleFormat::U8, 10).is_err());
        assert!(read_raw(&p, 4, SampleFormat::U8, 3).is_err());
        let nan = temp("nan.raw", &f32::NAN.to_le_bytes());
        assert!(read_raw(&nan, 1, SampleFormat::F32, 10).is_err());
        assert!(read_raw(Path::new("/nonexistent.raw"), 1, SampleFormat::U8, 10).is_err());
        // A device reports length 0 and never ends: refused, not read (a zero count would
        // otherwise match its length and read forever).
        if Path::new("/dev/zero").exists() {
            let e = read_raw(Path::new("/dev/zero"), 0, SampleFormat::U8, 10).unwrap_err();
            assert!(e.to_string().contains("not a regular file"), "{e}");
        }
    }

    #[test]
    fn png_round_trip_and_garbage() {
        let p = std::env::temp_dir().join(format!("raybench-samples-{}.png", std::process::id()));
        let img =
            image::ImageBuffer::<image::Luma<u16>, _>::from_raw(2, 1, vec![0u16, 65535]).unwrap();
        img.save(&p).unwrap();
        let (w, h, v) = read_png_gray(&p, 100).unwrap();
        assert_eq!((w, h, v), (2, 1, vec![0.0, 1.0]));
        assert!(read_png_gray(&p, 1).is_err());
        let bad = temp("bad.png", b"\x89PNG\r\n\x1a\nnot really");
        assert!(read_png_gray(&bad, 100).is_err());
        std::fs::remove_file(p).ok();
    }
}
