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
