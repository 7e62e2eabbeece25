//! Reading files safely: what is no regular file is refused before it is opened, text is
//! read up to a size limit, and a UTF-8 byte-order mark is dropped. Every loader shares
//! these; they read no scene format.

use crate::error::LoadError;
use std::path::Path;

/// What a path that exists but is no regular file is, for messages: a folder, a FIFO or a
/// device (which may never end) is not "not found".
pub(crate) fn not_a_file_message(meta: &std::fs::Metadata) -> String {
    let kind = meta.file_type();
    let what = if kind.is_dir() {
        "a folder"
    } else {
        #[cfg(unix)]
        {
            use std::os::unix::fs::FileTypeExt as _;
            if kind.is_fifo() {
                "a FIFO (named pipe)"
            } else if kind.is_char_device() || kind.is_block_device() {
                "a device"
            } else if kind.is_socket() {
                "a socket"
            } else {
                "something other than a file"
            }
        }
        #[cfg(not(unix))]
        "something other than a file"
    };
    format!("is {what}, not a regular file")
}

/// What is at `path`, when it is not a regular file that can be opened: `missing`, `a
/// dangling symbolic link`, `a folder`, `a FIFO (named pipe)`, a symbolic link loop or
/// another error in the system's words. `Ok` for a regular file.
pub(crate) fn probe(path: &Path) -> Result<(), String> {
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_file() => Ok(()),
        Ok(meta) => Err(not_a_file_message(&meta)
            .trim_start_matches("is ")
            .to_owned()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            if std::fs::symlink_metadata(path).is_ok() {
                Err("a symbolic link to nothing".into())
            } else {
                Err("missing".into())
            }
        }
        Err(e) => Err(crate::error::os_error(&e)),
    }
}

/// The error for a path that exists but is no regular file ([`not_a_file_message`]).
pub(crate) fn not_a_file(path: &Path, meta: &std::fs::Metadata) -> LoadError {
    LoadError::Parse {
        path: path.to_owned(),
        message: not_a_file_message(meta),
    }
}

/// Checks that `path` is a regular file before it is opened (a FIFO or `/dev/zero` would
/// block or never end).
///
/// # Errors
/// [`LoadError::NotFound`] when it does not exist, [`LoadError::Io`] when its metadata
/// cannot be read, else [`not_a_file`]'s error for anything but a regular file.
pub(crate) fn check_regular_file(path: &Path) -> Result<(), LoadError> {
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_file() => Ok(()),
        Ok(meta) => Err(not_a_file(path, &meta)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(LoadError::NotFound {
            path: path.to_owned(),
        }),
        Err(cause) => Err(LoadError::Io {
            path: path.to_owned(),
            cause,
        }),
    }
}

/// The UTF-8 byte-order mark some editors write at the start of text files.
pub(crate) const UTF8_BOM: &[u8] = b"\xef\xbb\xbf";

/// `bytes` without a leading UTF-8 byte-order mark: every text format (TOML, OBJ, MTL,
/// `.bpt`, glTF JSON) accepts one.
pub(crate) fn strip_bom(bytes: &[u8]) -> &[u8] {
    bytes.strip_prefix(UTF8_BOM).unwrap_or(bytes)
}

/// `bytes` with every line end that is a lone carriage return (the classic Mac OS
/// convention) made a line feed: the line-oriented text formats read here (OBJ, MTL,
/// `.bpt`) accept CR, LF and CR LF line ends. (TOML defines its own line ends, and PLY's
/// header is read by `ply-rs-bw`: they are not changed.)
pub(crate) fn lone_cr_to_lf(bytes: &[u8]) -> std::borrow::Cow<'_, [u8]> {
    let lone = |i: usize| bytes[i] == b'\r' && bytes.get(i + 1) != Some(&b'\n');
    if !(0..bytes.len()).any(lone) {
        return std::borrow::Cow::Borrowed(bytes);
    }
    let mut out = bytes.to_vec();
    for (i, b) in out.iter_mut().enumerate() {
        if lone(i) {
            *b = b'\n';
        }
    }
    std::borrow::Cow::Owned(out)
}

/// A path's extension in lower case (empty when it has none).
pub(crate) fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default()
}

/// Reads a UTF-8 text file of at most `limit` bytes (checked before reading; `what` names
/// the kind of file in the error).
pub(crate) fn read_text(path: &Path, limit: u64, what: &str) -> Result<String, LoadError> {
    let io = |cause| LoadError::Io {
        path: path.to_owned(),
        cause,
    };
    // A device or pipe reports no length and may never end.
    check_regular_file(path)?;
    let len = std::fs::metadata(path).map_err(io)?.len();
    if len > limit {
        return Err(LoadError::Parse {
            path: path.to_owned(),
            message: format!("{what} of {len} bytes exceeds the limit of {limit}"),
        });
    }
    // At most `limit + 1` bytes, should the file grow meanwhile.
    let mut bytes = Vec::new();
    std::io::Read::read_to_end(
        &mut std::io::Read::take(std::fs::File::open(path).map_err(io)?, limit + 1),
        &mut bytes,
    )
    .map_err(io)?;
    if bytes.len() as u64 > limit {
        return Err(LoadError::Parse {
            path: path.to_owned(),
            message: format!("{what} exceeds the limit of {limit} bytes"),
        });
    }
    text_from_bytes(path, bytes)
}

/// The UTF-8 text of a text file's `bytes`, less a leading byte-order mark (`path` names
/// the file in the error).
pub(crate) fn text_from_bytes(path: &Path, mut bytes: Vec<u8>) -> Result<String, LoadError> {
    if bytes.starts_with(UTF8_BOM) {
        bytes.drain(..UTF8_BOM.len());
    }
    String::from_utf8(bytes).map_err(|_| LoadError::Parse {
        path: path.to_owned(),
        message: "not UTF-8 text".into(),
    })
}
