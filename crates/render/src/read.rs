//! Reading images back as linear RGB (PNG, OpenEXR, PFM), for `raybench diff`: PNG is
//! decoded from sRGB, EXR and PFM hold linear values already. Every size is checked against
//! [`MAX_DIMENSION`] before pixels are allocated.

use crate::output::ImageFormat;
use raybench_core::limits::MAX_DIMENSION;
use raybench_core::{Vec3, srgb_to_linear};
use std::path::{Path, PathBuf};

/// A linear RGB image, row by row from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` linear colours.
    pub color: Vec<Vec3>,
}

/// Why an image could not be read.
#[derive(Debug, thiserror::Error)]
#[error("{}: {message}", path.display())]
pub struct ReadError {
    /// The file.
    pub path: PathBuf,
    /// What is wrong, in words.
    pub message: String,
}

/// Reads `path` (`.png`, `.exr` or `.pfm`) as linear RGB.
///
/// # Errors
/// When the file is missing, of another type, malformed, or larger than [`MAX_DIMENSION`]
/// on a side.
pub fn read_linear(path: &Path) -> Result<LinearImage, ReadError> {
    let err = |message: String| ReadError {
        path: path.to_owned(),
        message,
    };
    match ImageFormat::from_path(path) {
        None => Err(err(
            "unknown image type (expected .png, .exr or .pfm)".into()
        )),
        Some(ImageFormat::Pfm) => {
            let bytes = std::fs::read(path).map_err(|e| err(e.to_string()))?;
            parse_pfm(&bytes).map_err(err)
        }
        Some(format) => {
            let mut reader = image::ImageReader::open(path).map_err(|e| err(e.to_string()))?;
            reader.set_format(if format == ImageFormat::Png {
                image::ImageFormat::Png
            } else {
                image::ImageFormat::OpenExr
            });
            let mut limits = image::Limits::default();
            limits.max_image_width = Some(MAX_DIMENSION);
            limits.max_image_height = Some(MAX_DIMENSION);
            reader.limits(limits);
            let img = reader.decode().map_err(|e| err(e.to_string()))?;
            let (width, height) = (img.width(), img.height());
            let color = if format == ImageFormat::Png {
                img.to_rgb8()
                    .pixels()
                    .map(|p| Vec3::from_array(p.0.map(|c| srgb_to_linear(f32::from(c) / 255.0))))
                    .collect()
            } else {
                img.to_rgb32f()
                    .pixels()
                    .map(|p| Vec3::from_array(p.0))
                    .collect()
            };
            Ok(LinearImage {
                width,
                height,
                color,
            })
        }
    }
}

/// Parses a PFM file: `PF` (colour) or `Pf` (grey) header, width and height, a scale whose
/// sign gives the byte order (negative: little endian), then the rows bottom to top.
///
/// # Errors
/// In words, when the header is malformed, the size exceeds [`MAX_DIMENSION`] or the data
/// is shorter than declared.
pub fn parse_pfm(bytes: &[u8]) -> Result<LinearImage, String> {
    // The header is three whitespace-separated tokens after the magic, then one whitespace
    // byte; it is ASCII and short.
    let mut fields = Vec::with_capacity(4);
    let mut pos = 0;
    while fields.len() < 4 {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() && pos - start < 32 {
            pos += 1;
        }
        if start == pos {
            return Err("truncated PFM header".into());
        }
        fields.push(String::from_utf8_lossy(&bytes[start..pos]).into_owned());
    }
    pos += 1; // the single whitespace byte ending the header
    let channels = match fields[0].as_str() {
        "PF" => 3,
        "Pf" => 1,
        m => return Err(format!("not a PFM file (magic '{m}', expected PF or Pf)")),
    };
    let dim = |s: &str, what: &str| -> Result<u32, String> {
        let v: u32 = s
            .parse()
            .map_err(|_| format!("PFM {what} '{s}' is not a whole number"))?;
        if v == 0 || v > MAX_DIMENSION {
            return Err(format!("PFM {what} {v} is outside 1..={MAX_DIMENSION}"));
        }
        Ok(v)
    };
    let width = dim(&fields[1], "width")?;
    let height = dim(&fields[2], "height")?;
    let scale: f32 = fields[3]
        .parse()
        .ok()
        .filter(|s: &f32| s.is_finite() && *s != 0.0)
        .ok_or_else(|| format!("PFM scale '{}' is not a non-zero number", fields[3]))?;
    let little = scale < 0.0;
    let n = width as usize * height as usize * channels;
    let data = bytes.get(pos.min(bytes.len())..).unwrap_or_default();
    if data.len() < n * 4 {
        return Err(format!(
            "PFM data holds {} bytes, {width} x {height} x {channels} floats need {}",
            data.len(),
            n * 4
        ));
    }
    let value = |i: usize| {
        let b = [
            data[4 * i],
            data[4 * i + 1],
            data[4 * i + 2],
            data[4 * i + 3],
        ];
        if little {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    };
    let (w, h) = (width as usize, height as usize);
    let mut color = Vec::with_capacity(w * h);
    for row in (0..h).rev() {
        for x in 0..w {
            let i = (row * w + x) * channels;
            color.push(if channels == 3 {
                Vec3::new(value(i), value(i + 1), value(i + 2))
            } else {
                Vec3::splat(value(i))
            });
        }
    }
    Ok(LinearImage {
        width,
        height,
        color,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::{pfm_bytes, write_color};
    use raybench_core::Frame;

    #[test]
    fn srgb_round_trip() {
        for code in [0u8, 1, 10, 100, 188, 254, 255] {
            let back = crate::srgb8(Vec3::splat(srgb_to_linear(f32::from(code) / 255.0)));
            assert_eq!(back[0], code);
        }
    }

    #[test]
    fn pfm_round_trip_and_errors() {
        let color = vec![
            Vec3::new(1.5, -2.0, 0.25),
            Vec3::new(100.0, 0.0, 1e-6),
            Vec3::new(3.0, 4.0, 5.0),
            Vec3::ZERO,
            Vec3::ONE,
            Vec3::splat(7.0),
        ];
        let bytes = pfm_bytes(3, 2, &color);
        let img = parse_pfm(&bytes).unwrap();
        assert_eq!((img.width, img.height), (3, 2));
        assert_eq!(img.color, color);
        for (bad, needle) in [
            (&b"P6\n1 1\n-1.0\n"[..], "magic"),
            (b"PF\n0 1\n-1.0\n", "width 0"),
            (b"PF\n1 99999\n-1.0\n", "height 99999"),
            (b"PF\n1 1\n0\n", "scale"),
            (b"PF\n2 2\n-1.0\n\0\0\0\0", "need 48"),
            (b"PF\n1", "truncated"),
            (b"", "truncated"),
        ] {
            let e = parse_pfm(bad).unwrap_err();
            assert!(e.contains(needle), "{e}");
        }
        // Big endian, grey.
        let mut grey = b"Pf\n1 1\n1.0\n".to_vec();
        grey.extend_from_slice(&2.5f32.to_be_bytes());
        assert_eq!(parse_pfm(&grey).unwrap().color, [Vec3::splat(2.5)]);
    }

    #[test]
    fn every_format_round_trips_through_the_writer() {
        let frame = Frame {
            width: 2,
            height: 2,
            color: vec![
                Vec3::new(0.0, 0.5, 1.0),
                Vec3::new(2.0, 17.5, 0.001),
                Vec3::new(0.25, 0.0, 0.0),
                Vec3::new(1e3, 1e-3, 0.5),
            ],
            ..Default::default()
        };
        let dir = std::env::temp_dir().join(format!("raybench-read-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for name in ["a.exr", "a.pfm"] {
            let p = dir.join(name);
            write_color(&frame, &p, 0.0).unwrap();
            let img = read_linear(&p).unwrap();
            assert_eq!(
                img.color, frame.color,
                "{name}: linear values unclamped, exact"
            );
            write_color(&frame, &p, 1.0).unwrap();
            let img = read_linear(&p).unwrap();
            assert_eq!(
                img.color[1],
                frame.color[1] * 2.0,
                "{name}: exposure +1 doubles"
            );
        }
        let p = dir.join("a.png");
        write_color(&frame, &p, 0.0).unwrap();
        let img = read_linear(&p).unwrap();
        assert!((img.color[0].y - 0.5).abs() < 0.005, "{}", img.color[0]);
        assert_eq!(img.color[1].y, 1.0, "PNG clamps");
        let e = read_linear(&dir.join("a.jpg")).unwrap_err().to_string();
        assert!(e.contains("unknown image type"), "{e}");
        let e = read_linear(&dir.join("missing.exr"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing.exr"), "{e}");
        std::fs::write(dir.join("bad.exr"), b"not an exr").unwrap();
        assert!(read_linear(&dir.join("bad.exr")).is_err());
        assert!(write_color(&frame, &dir.join("a.tiff"), 0.0).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }
}
