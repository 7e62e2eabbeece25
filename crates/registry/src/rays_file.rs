//! Ray files: a ray set written once (`raybench rays export`) and replayed by any tool
//! (`--rays-file`), so that other programs trace exactly the same rays. The format is
//! `docs/rays-format.md`: little endian, a 24-byte header (magic [`MAGIC`], version
//! [`VERSION`], the ray count, flags with [`FLAG_ANY_HIT`]) and 32 bytes per ray (origin,
//! direction, `t_min`, `t_max` as `f32`).
//!
//! Reading checks the header and the file's size against the count, and the count against
//! [`limits::MAX_EXPLICIT_RAYS`], before anything is allocated; every error names the byte
//! offset (and the record) where the file goes wrong.

use raybench_core::{Ray, Vec3, limits};
use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};

/// The first 8 bytes of every ray file.
pub const MAGIC: [u8; 8] = *b"RAYBENCH";
/// The format version this build reads and writes.
pub const VERSION: u32 = 1;
/// Flags bit 0: the rays ask for any hit (occlusion), not the closest hit.
pub const FLAG_ANY_HIT: u32 = 1;
/// Header size in bytes: magic (8), version (`u32` at 8), ray count (`u64` at 12), flags
/// (`u32` at 20).
pub const HEADER_BYTES: u64 = 24;
/// Bytes per ray: origin xyz, direction xyz, `t_min`, `t_max`, each an `f32`.
pub const RAY_BYTES: u64 = 32;

/// A ray set as a file holds it.
#[derive(Clone, Debug, PartialEq)]
pub struct RayFile {
    /// The rays, in file order.
    pub rays: Vec<Ray>,
    /// Whether they ask for any hit ([`FLAG_ANY_HIT`]).
    pub any_hit: bool,
}

/// Why a ray file cannot be read or written: the file, the byte offset where it goes
/// wrong, and the cause.
#[derive(Debug)]
pub struct RaysFileError {
    /// The file.
    pub path: PathBuf,
    /// Byte offset of the problem (`None`: the file as a whole, as in an I/O error).
    pub offset: Option<u64>,
    /// What is wrong.
    pub cause: String,
}

impl fmt::Display for RaysFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.offset {
            Some(at) => write!(f, "{}: byte {at}: {}", self.path.display(), self.cause),
            None => write!(f, "{}: {}", self.path.display(), self.cause),
        }
    }
}

impl std::error::Error for RaysFileError {}

/// The 24-byte header of `count` rays.
#[must_use]
pub fn header(count: u64, any_hit: bool) -> [u8; HEADER_BYTES as usize] {
    let mut h = [0u8; HEADER_BYTES as usize];
    h[..8].copy_from_slice(&MAGIC);
    h[8..12].copy_from_slice(&VERSION.to_le_bytes());
    h[12..20].copy_from_slice(&count.to_le_bytes());
    let flags = if any_hit { FLAG_ANY_HIT } else { 0 };
    h[20..24].copy_from_slice(&flags.to_le_bytes());
    h
}

/// The whole file's bytes for `rays`: the header, then each ray's origin, direction,
/// `t_min` and `t_max`.
#[must_use]
pub fn to_bytes(rays: &[Ray], any_hit: bool) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER_BYTES as usize + rays.len() * RAY_BYTES as usize);
    out.extend_from_slice(&header(rays.len() as u64, any_hit));
    for r in rays {
        for v in r.origin.to_array().into_iter().chain(r.dir.to_array()) {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(&r.t_min.to_le_bytes());
        out.extend_from_slice(&r.t_max.to_le_bytes());
    }
    out
}

/// Parses a whole ray file held in memory (`path` only names it in errors).
///
/// # Errors
/// A header shorter than 24 bytes, another magic, version or flag bit, a count over
/// [`limits::MAX_EXPLICIT_RAYS`], or a size other than the header's count implies.
pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<RayFile, RaysFileError> {
    let (count, any_hit) =
        check_header(path, bytes.get(..HEADER_BYTES as usize), bytes.len() as u64)?;
    let records = &bytes[HEADER_BYTES as usize..];
    let f =
        |i: usize| f32::from_le_bytes([records[i], records[i + 1], records[i + 2], records[i + 3]]);
    let rays = (0..count as usize)
        .map(|k| {
            let b = k * RAY_BYTES as usize;
            let v = |j: usize| f(b + 4 * j);
            Ray::with_interval(
                Vec3::new(v(0), v(1), v(2)),
                Vec3::new(v(3), v(4), v(5)),
                v(6),
                v(7),
            )
        })
        .collect();
    Ok(RayFile { rays, any_hit })
}

/// Checks a header (`None`: the file is shorter than one) against the file's size `len`:
/// returns the ray count and the any-hit flag.
fn check_header(path: &Path, h: Option<&[u8]>, len: u64) -> Result<(u64, bool), RaysFileError> {
    let err = |offset: u64, cause: String| RaysFileError {
        path: path.to_owned(),
        offset: Some(offset),
        cause,
    };
    let Some(h) = h else {
        return Err(err(
            len,
            format!("the file ends inside the {HEADER_BYTES}-byte header (it holds {len} bytes)"),
        ));
    };
    let word = |at: usize| u32::from_le_bytes([h[at], h[at + 1], h[at + 2], h[at + 3]]);
    if h[..8] != MAGIC {
        return Err(err(
            0,
            format!(
                "not a ray file: the magic is {:?}, expected \"RAYBENCH\"",
                String::from_utf8_lossy(&h[..8])
            ),
        ));
    }
    let version = word(8);
    if version != VERSION {
        return Err(err(
            8,
            format!("version {version} is not supported (this build reads version {VERSION})"),
        ));
    }
    let mut count_bytes = [0u8; 8];
    count_bytes.copy_from_slice(&h[12..20]);
    let count = u64::from_le_bytes(count_bytes);
    if count > limits::MAX_EXPLICIT_RAYS {
        return Err(err(
            12,
            format!(
                "{count} rays exceed the limit of {}",
                limits::MAX_EXPLICIT_RAYS
            ),
        ));
    }
    let flags = word(20);
    if flags & !FLAG_ANY_HIT != 0 {
        return Err(err(
            20,
            format!(
                "unknown flag bits {:#x} (only bit 0, any hit, is defined)",
                flags & !FLAG_ANY_HIT
            ),
        ));
    }
    let expected = HEADER_BYTES + count * RAY_BYTES;
    if len != expected {
        let whole = len.saturating_sub(HEADER_BYTES) / RAY_BYTES;
        let cause = if len < expected {
            format!(
                "the file ends inside record {whole} (0-based): the header says {count} rays \
                 ({expected} bytes), the file holds {len} bytes"
            )
        } else {
            format!(
                "{} bytes after the last of the header's {count} rays ({expected} bytes expected)",
                len - expected
            )
        };
        return Err(err(len.min(expected), cause));
    }
    Ok((count, flags & FLAG_ANY_HIT != 0))
}

/// Reads a ray file, checking its header against its size before reading the rays.
///
/// # Errors
/// As [`from_bytes`], and when the file cannot be opened or read.
pub fn read(path: &Path) -> Result<RayFile, RaysFileError> {
    let io = |e: std::io::Error| RaysFileError {
        path: path.to_owned(),
        offset: None,
        cause: e.to_string(),
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    if !meta.is_file() {
        return Err(RaysFileError {
            path: path.to_owned(),
            offset: None,
            cause: "not a regular file".into(),
        });
    }
    let len = meta.len();
    let mut head = [0u8; HEADER_BYTES as usize];
    let got = read_up_to(&mut file, &mut head).map_err(io)?;
    check_header(path, (got == head.len()).then_some(&head[..]), len)?;
    // The size is now known to be the header's, at most 24 + 32 x 2^24 bytes.
    let mut bytes = Vec::with_capacity(len as usize);
    bytes.extend_from_slice(&head);
    file.read_to_end(&mut bytes).map_err(io)?;
    from_bytes(path, &bytes)
}

/// Reads until `buf` is full or the file ends; returns the bytes read.
fn read_up_to(file: &mut std::fs::File, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match file.read(&mut buf[got..])? {
            0 => break,
            n => got += n,
        }
    }
    Ok(got)
}

/// Writes `rays` to `path` (replacing it) through [`raybench_render::write_file`]: whole or
/// not at all.
///
/// # Errors
/// When the file cannot be written.
pub fn write(path: &Path, rays: &[Ray], any_hit: bool) -> Result<(), RaysFileError> {
    raybench_render::write_file(path, &to_bytes(rays, any_hit)).map_err(|e| RaysFileError {
        path: path.to_owned(),
        offset: None,
        cause: match e {
            raybench_render::OutputError::Io { cause, .. } => cause.to_string(),
            other => other.to_string(),
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rays() -> Vec<Ray> {
        vec![
            Ray::new(Vec3::new(1.0, -2.0, 3.5), Vec3::new(0.0, 0.6, -0.8)),
            Ray::with_interval(Vec3::ZERO, Vec3::X, 0.25, 7.0),
            // Not valid: kept as the empty interval it was given.
            Ray::with_interval(Vec3::ZERO, Vec3::ZERO, 0.0, 1.0),
            Ray::with_interval(
                Vec3::new(-0.0, f32::MIN_POSITIVE, 1e18),
                Vec3::new(1e-3, -3.0, 2.0),
                1e-30,
                f32::MAX,
            ),
        ]
    }

    /// A ray's stored fields as bits (an invalid ray's cached shear is NaN, so rays are
    /// compared by what the file holds).
    fn bits(r: &Ray) -> ([u32; 3], [u32; 3], u32, u32) {
        (
            r.origin.to_array().map(f32::to_bits),
            r.dir.to_array().map(f32::to_bits),
            r.t_min.to_bits(),
            r.t_max.to_bits(),
        )
    }

    fn path() -> &'static Path {
        Path::new("test.rays")
    }

    #[test]
    fn rays_round_trip_bit_for_bit() {
        for any_hit in [false, true] {
            let bytes = to_bytes(&rays(), any_hit);
            assert_eq!(bytes.len() as u64, HEADER_BYTES + 4 * RAY_BYTES);
            let back = from_bytes(path(), &bytes).unwrap();
            assert_eq!(back.any_hit, any_hit);
            assert_eq!(back.rays.len(), 4);
            for (a, b) in rays().iter().zip(&back.rays) {
                assert_eq!(bits(a), bits(b));
            }
        }
        assert_eq!(from_bytes(path(), &to_bytes(&[], false)).unwrap().rays, []);
    }

    #[test]
    fn the_header_is_as_documented() {
        let h = header(0x0102_0304_0506_0708, true);
        assert_eq!(&h[..8], b"RAYBENCH");
        assert_eq!(h[8..12], [1, 0, 0, 0]);
        assert_eq!(h[12..20], [8, 7, 6, 5, 4, 3, 2, 1]);
        assert_eq!(h[20..24], [1, 0, 0, 0]);
        let one = to_bytes(&[Ray::with_interval(Vec3::X, Vec3::Y, 0.5, 2.0)], false);
        assert_eq!(one[24..28], 1.0f32.to_le_bytes());
        assert_eq!(one[40..44], 1.0f32.to_le_bytes());
        assert_eq!(one[48..52], 0.5f32.to_le_bytes());
        assert_eq!(one[52..56], 2.0f32.to_le_bytes());
    }

    /// Every truncation, and every extra byte, is an error naming an offset, never a panic.
    #[test]
    fn every_truncation_is_an_error() {
        let bytes = to_bytes(&rays(), true);
        for n in 0..bytes.len() {
            let e = from_bytes(path(), &bytes[..n]).unwrap_err();
            assert!(e.offset.is_some(), "{e}");
            assert!(e.to_string().starts_with("test.rays: byte "), "{e}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        let e = from_bytes(path(), &longer).unwrap_err();
        assert!(e.cause.contains("1 bytes after"), "{e}");
        let e = from_bytes(path(), &bytes[..HEADER_BYTES as usize + 40]).unwrap_err();
        assert!(e.cause.contains("inside record 1"), "{e}");
    }

    #[test]
    fn bad_headers_are_refused() {
        let good = to_bytes(&rays(), false);
        let with = |at: usize, patch: &[u8]| {
            let mut b = good.clone();
            b[at..at + patch.len()].copy_from_slice(patch);
            from_bytes(path(), &b).unwrap_err()
        };
        let e = with(0, b"RAYBENCX");
        assert_eq!(e.offset, Some(0));
        assert!(e.cause.contains("not a ray file"), "{e}");
        let e = with(8, &2u32.to_le_bytes());
        assert_eq!(e.offset, Some(8));
        assert!(e.cause.contains("version 2"), "{e}");
        for flags in [2u32, 0x8000_0000, 3] {
            let e = with(20, &flags.to_le_bytes());
            assert_eq!(e.offset, Some(20));
            assert!(e.cause.contains("unknown flag bits"), "{e}");
        }
        // A count beyond the limit (or one whose size would overflow) is refused from the
        // header, before any allocation.
        for count in [limits::MAX_EXPLICIT_RAYS + 1, u64::MAX] {
            let e = with(12, &count.to_le_bytes());
            assert_eq!(e.offset, Some(12));
            assert!(e.cause.contains("exceed the limit"), "{e}");
        }
        // A count that disagrees with the size.
        let e = with(12, &5u64.to_le_bytes());
        assert!(e.cause.contains("the header says 5 rays"), "{e}");
        let e = with(12, &3u64.to_le_bytes());
        assert!(e.cause.contains("32 bytes after"), "{e}");
    }

    /// Seeded random byte strings and random single-byte corruptions: an answer or an
    /// error, never a panic; a corrupted file that still parses has the right size.
    /// The seeds of the `rays_file` fuzz target (`fuzz/seeds/rays_file/`) are valid files.
    #[test]
    fn fuzz_seeds_parse() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/seeds/rays_file");
        let mut n = 0;
        for entry in std::fs::read_dir(dir).unwrap() {
            let p = entry.unwrap().path();
            let f = read(&p).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(std::fs::read(&p).unwrap(), to_bytes(&f.rays, f.any_hit));
            n += 1;
        }
        assert!(n >= 2);
    }

    #[test]
    fn random_bytes_never_panic() {
        let good = to_bytes(&rays(), true);
        let mut state = 0x1234_5678u32;
        let mut next = || {
            state = raybench_core::sampling::pcg3d([state, 7, 11])[0];
            state
        };
        for _ in 0..2000 {
            let mut b = good.clone();
            let at = next() as usize % b.len();
            b[at] = next() as u8;
            if let Ok(f) = from_bytes(path(), &b) {
                assert_eq!(f.rays.len(), 4);
            }
            let n = next() as usize % 80;
            let noise: Vec<u8> = (0..n).map(|_| next() as u8).collect();
            assert!(from_bytes(path(), &noise).is_err());
        }
    }

    #[test]
    fn files_round_trip_and_name_themselves() {
        let dir = std::env::temp_dir().join(format!("raybench-rays-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("set.rays");
        write(&p, &rays(), true).unwrap();
        let back = read(&p).unwrap();
        assert!(back.any_hit);
        let same = back
            .rays
            .iter()
            .zip(&rays())
            .all(|(a, b)| bits(a) == bits(b));
        assert!(same && back.rays.len() == 4);
        std::fs::write(&p, &to_bytes(&rays(), true)[..30]).unwrap();
        let e = read(&p).unwrap_err();
        assert!(
            e.to_string()
                .starts_with(&format!("{}: byte 30:", p.display())),
            "{e}"
        );
        let e = read(&dir.join("absent.rays")).unwrap_err();
        assert!(e.to_string().contains("absent.rays"), "{e}");
        assert!(read(&dir).unwrap_err().cause.contains("not a regular file"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
