//! Writing frames as images: 8-bit sRGB PNG (clamped, for looking at) or unclamped linear
//! radiance as OpenEXR (32-bit float RGB) or PFM (for measuring).

use raybench_core::{Frame, NO_HIT, Vec3};
use std::path::{Path, PathBuf};

/// Why an image could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// Writing a file failed.
    #[error("cannot write {}: {cause}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause (in the message, not a separate `source`).
        cause: std::io::Error,
    },
    /// Encoding or writing failed.
    #[error("cannot write {}: {cause}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The cause (in the message, not a separate `source`, which would print it twice
        /// in a chain of causes).
        cause: image::ImageError,
    },
    /// The path cannot take a PNG image (checked before rendering).
    #[error("{}: {message}", path.display())]
    Path {
        /// The file.
        path: PathBuf,
        /// Why it cannot be written.
        message: String,
    },
    /// Moving the finished file into place failed.
    #[error("cannot move {} to {}: {cause}", from.display(), path.display())]
    Rename {
        /// The temporary file.
        from: PathBuf,
        /// The final file.
        path: PathBuf,
        /// The cause (in the message, not a separate `source`).
        cause: std::io::Error,
    },
}

/// Linear to sRGB-encoded 8-bit, clamping to `[0, 1]` (NaN becomes 0).
#[must_use]
pub fn srgb8(c: Vec3) -> [u8; 3] {
    let enc = |x: f32| {
        let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
        let s = if x <= 0.003_130_8 {
            12.92 * x
        } else {
            1.055 * x.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0 + 0.5) as u8
    };
    [enc(c.x), enc(c.y), enc(c.z)]
}

/// A stable false colour for primitive id `id` (black for [`NO_HIT`]).
#[must_use]
pub fn id_color(id: u32) -> [u8; 3] {
    if id == NO_HIT {
        return [0, 0, 0];
    }
    let [h, _, _] = raybench_core::sampling::pcg3d([id, 0x1234_5678, 0x9abc_def0]);
    let b = h.to_le_bytes();
    // Keep colours away from black so that misses stand out.
    [b[0] | 0x40, b[1] | 0x40, b[2] | 0x40]
}

/// The temporary name a file is written under before [`write_atomically`] renames it into
/// place: `.partial` inserted before the extension (`a.png` -> `a.partial.png`), so that
/// the temporary file keeps its type's extension for anything that picks the format from
/// it (`image::open`, a viewer); raybench's own writers name their format explicitly.
#[must_use]
pub fn partial_path(path: &Path) -> PathBuf {
    let mut name = path.file_stem().unwrap_or_default().to_owned();
    name.push(".partial");
    if let Some(ext) = path.extension() {
        name.push(".");
        name.push(ext);
    }
    path.with_file_name(name)
}

/// Writes a file through a temporary name: `write` writes [`partial_path`]`(path)`, which is
/// then renamed to `path` (atomic within one file system). An interrupted or failed write
/// therefore never leaves a partial file, nor truncates an older one, under the final name;
/// on failure the temporary file is removed.
///
/// # Errors
/// What `write` returns, or [`OutputError::Rename`] when the rename fails.
pub fn write_atomically<E: From<OutputError>>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    let tmp = partial_path(path);
    if let Err(e) = write(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    std::fs::rename(&tmp, path).map_err(|cause| {
        let _ = std::fs::remove_file(&tmp);
        E::from(OutputError::Rename {
            from: tmp,
            path: path.to_owned(),
            cause,
        })
    })
}

/// Writes `bytes` to `path` through [`write_atomically`]: the temporary file is written
/// whole and synced to the disk before the rename, so every error of the write (a full
/// disk, a quota, a file-size limit) is reported, and nothing partial is left under
/// either name. Every file raybench writes goes through here: encoders write to memory
/// first (a buffered writer that flushes on drop would lose the last error).
///
/// # Errors
/// [`OutputError::Io`] when the file cannot be created, written or synced;
/// [`OutputError::Rename`].
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    use std::io::Write as _;
    write_atomically(path, |tmp| {
        let io = |cause| OutputError::Io {
            path: path.to_owned(),
            cause,
        };
        let mut file = std::fs::File::create(tmp).map_err(io)?;
        file.write_all(bytes).map_err(io)?;
        file.sync_all().map_err(io)
    })
}

/// The file formats a frame's colour can be written in, chosen by the file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// `.png`: 8-bit sRGB, clamped to `[0, 1]` (what people look at).
    Png,
    /// `.exr`: OpenEXR, 32-bit float linear RGB, unclamped.
    Exr,
    /// `.pfm`: portable float map, 32-bit float linear RGB, unclamped, little endian.
    Pfm,
}

impl ImageFormat {
    /// The format named by `path`'s extension (any case), if it is one of these.
    #[must_use]
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "png" => Some(Self::Png),
            "exr" => Some(Self::Exr),
            "pfm" => Some(Self::Pfm),
            _ => None,
        }
    }

    /// The format's name in messages.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Png => "PNG",
            Self::Exr => "OpenEXR",
            Self::Pfm => "PFM",
        }
    }

    /// The file names it takes, in messages.
    #[must_use]
    pub fn pattern(self) -> &'static str {
        match self {
            Self::Png => "*.png",
            Self::Exr => "*.exr",
            Self::Pfm => "*.pfm",
        }
    }

    /// Every format a frame's colour can be written in.
    pub const ALL: [Self; 3] = [Self::Png, Self::Exr, Self::Pfm];
}

/// Checks, before any work, that an image can be written at `path`: its extension is one of
/// `formats` (a file under another name would mislead), it is not a folder, its folder
/// exists, and a file can be created there (a probe file is created and removed again), so
/// that a long render is never wasted on a path that cannot take
/// its result. Returns the format.
///
/// # Errors
/// [`OutputError::Path`] saying which of these fails.
pub fn check_image_path(path: &Path, formats: &[ImageFormat]) -> Result<ImageFormat, OutputError> {
    let err = |message: String| OutputError::Path {
        path: path.to_owned(),
        message,
    };
    let format = ImageFormat::from_path(path).filter(|f| formats.contains(f));
    let Some(format) = format else {
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        let list = |f: &dyn Fn(ImageFormat) -> &'static str| {
            let names: Vec<&str> = formats.iter().map(|&x| f(x)).collect();
            match names.split_last() {
                Some((last, rest)) if !rest.is_empty() => {
                    format!("{} or {last}", rest.join(", "))
                }
                _ => names.concat(),
            }
        };
        return Err(err(format!(
            "images are written as {} only: name the file {} (got {})",
            list(&|f| f.name()),
            list(&|f| f.pattern()),
            if ext.is_empty() {
                "no extension".to_owned()
            } else {
                format!("'.{ext}'")
            }
        )));
    };
    if path.is_dir() {
        return Err(err("is a folder, not a file".into()));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(err(format!("the folder {} does not exist", dir.display())));
    }
    // A probe of a name no one else uses (not `partial_path`, which a killed earlier run may
    // have left behind: the write replaces such a leftover).
    let probe = dir.join(format!(".raybench-probe-{}", std::process::id()));
    std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .open(&probe)
        .map_err(|e| err(format!("cannot create a file in {}: {e}", dir.display())))?;
    let _ = std::fs::remove_file(&probe);
    Ok(format)
}

/// [`check_image_path`] for a PNG image (the id images, the report's pictures).
///
/// # Errors
/// As [`check_image_path`].
pub fn check_png_path(path: &Path) -> Result<(), OutputError> {
    check_image_path(path, &[ImageFormat::Png]).map(|_| ())
}

/// Writes RGB bytes (`3 * width * height`, row by row) to `path` as a PNG, through
/// [`write_atomically`].
///
/// # Errors
/// When the file cannot be written or renamed.
pub fn write_rgb(path: &Path, width: u32, height: u32, rgb: Vec<u8>) -> Result<(), OutputError> {
    use image::ImageEncoder as _;
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(&rgb, width, height, image::ExtendedColorType::Rgb8)
        .map_err(|cause| OutputError::Write {
            path: path.to_owned(),
            cause,
        })?;
    write_file(path, &png)
}

/// Writes the frame's colour (linear, clamped, sRGB-encoded) as a PNG.
///
/// # Errors
/// When the file cannot be written.
pub fn write_color_png(frame: &Frame, path: &Path) -> Result<(), OutputError> {
    let rgb = frame.color.iter().flat_map(|&c| srgb8(c)).collect();
    write_rgb(path, frame.width, frame.height, rgb)
}

/// Writes the frame's colour times `2^exposure` in the format of `path`'s extension
/// ([`ImageFormat`]): a clamped sRGB PNG, or unclamped linear radiance as OpenEXR or PFM
/// (exposure 0 writes the radiance itself).
///
/// # Errors
/// When the extension names no format, or the file cannot be written.
pub fn write_color(frame: &Frame, path: &Path, exposure: f32) -> Result<(), OutputError> {
    let scale = exposure.exp2();
    let scaled = || frame.color.iter().map(move |&c| c * scale);
    match ImageFormat::from_path(path) {
        Some(ImageFormat::Png) => {
            let rgb = scaled().flat_map(srgb8).collect();
            write_rgb(path, frame.width, frame.height, rgb)
        }
        Some(ImageFormat::Exr) => {
            let data: Vec<f32> = scaled().flat_map(|c| c.to_array()).collect();
            let img = image::Rgb32FImage::from_raw(frame.width, frame.height, data)
                .expect("a frame holds width x height colours");
            let mut exr = std::io::Cursor::new(Vec::new());
            image::DynamicImage::ImageRgb32F(img)
                .write_to(&mut exr, image::ImageFormat::OpenExr)
                .map_err(|cause| OutputError::Write {
                    path: path.to_owned(),
                    cause,
                })?;
            write_file(path, exr.get_ref())
        }
        Some(ImageFormat::Pfm) => {
            let bytes = pfm_bytes(frame.width, frame.height, &scaled().collect::<Vec<_>>());
            write_file(path, &bytes)
        }
        None => check_image_path(path, &ImageFormat::ALL).map(|_| ()),
    }
}

/// A PFM file: the `PF` header (colour), width and height, scale `-1.0` (little endian),
/// then the rows bottom to top, three `f32` per pixel.
#[must_use]
pub fn pfm_bytes(width: u32, height: u32, color: &[Vec3]) -> Vec<u8> {
    let mut out = format!("PF\n{width} {height}\n-1.0\n").into_bytes();
    out.reserve(color.len() * 12);
    for row in (0..height as usize).rev() {
        let start = row * width as usize;
        for c in &color[start..start + width as usize] {
            for x in c.to_array() {
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
    }
    out
}

/// Writes the frame's primitive ids as a false-colour PNG.
///
/// # Errors
/// When the file cannot be written.
pub fn write_ids_png(frame: &Frame, path: &Path) -> Result<(), OutputError> {
    let rgb = frame.ids.iter().flat_map(|&id| id_color(id)).collect();
    write_rgb(path, frame.width, frame.height, rgb)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_endpoints() {
        assert_eq!(srgb8(Vec3::ZERO), [0, 0, 0]);
        assert_eq!(srgb8(Vec3::ONE), [255, 255, 255]);
        assert_eq!(srgb8(Vec3::splat(f32::NAN)), [0, 0, 0]);
        assert_eq!(srgb8(Vec3::splat(0.5))[0], 188);
    }

    #[test]
    fn writes_png_and_reports_bad_paths() {
        let frame = Frame {
            width: 2,
            height: 1,
            color: vec![Vec3::ONE, Vec3::ZERO],
            ids: vec![0, NO_HIT],
            t: vec![1.0, f32::INFINITY],
            ..Default::default()
        };
        let dir = std::env::temp_dir().join(format!("raybench-out-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.png");
        write_color_png(&frame, &p).unwrap();
        write_ids_png(&frame, &dir.join("b.png")).unwrap();
        let img = image::open(&p).unwrap().to_rgb8();
        assert_eq!(img.get_pixel(0, 0).0, [255, 255, 255]);
        assert!(!dir.join("a.partial.png").exists());
        assert_eq!(
            partial_path(Path::new("x/a.png")),
            Path::new("x/a.partial.png")
        );
        assert_eq!(partial_path(Path::new("x/a")), Path::new("x/a.partial"));
        // A failed write removes its temporary file and leaves an older file whole.
        std::fs::write(dir.join("c.txt"), "old").unwrap();
        let failed = write_atomically::<OutputError>(&dir.join("c.txt"), |tmp| {
            std::fs::write(tmp, "new, half written").unwrap();
            Err(OutputError::Rename {
                from: tmp.to_owned(),
                path: tmp.to_owned(),
                cause: std::io::Error::other("interrupted"),
            })
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read_to_string(dir.join("c.txt")).unwrap(), "old");
        assert!(!dir.join("c.partial.txt").exists());
        assert!(write_color_png(&frame, &dir.join("no/such/dir.png")).is_err());
        // Checked before rendering: the extension, the folder, writability.
        assert!(check_png_path(&dir.join("ok.png")).is_ok());
        assert!(check_png_path(&dir.join("OK.PNG")).is_ok());
        assert!(!dir.join("ok.partial.png").exists());
        // A temporary file a killed earlier write left behind blocks neither the check nor
        // the write, which replaces it.
        std::fs::write(dir.join("stale.partial.png"), "left over").unwrap();
        assert!(check_png_path(&dir.join("stale.png")).is_ok());
        write_color_png(&frame, &dir.join("stale.png")).unwrap();
        assert!(!dir.join("stale.partial.png").exists());
        assert!(image::open(dir.join("stale.png")).is_ok());
        for (p, needle) in [
            (dir.join("x.exr"), "'.exr'"),
            (dir.join("x.jpg"), "'.jpg'"),
            (dir.join("x"), "no extension"),
            (dir.join("no/such/dir.png"), "does not exist"),
        ] {
            let e = check_png_path(&p).unwrap_err().to_string();
            assert!(e.contains(needle), "{e}");
        }
        std::fs::create_dir_all(dir.join("d.png")).unwrap();
        let e = check_png_path(&dir.join("d.png")).unwrap_err().to_string();
        assert!(e.contains("folder"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
