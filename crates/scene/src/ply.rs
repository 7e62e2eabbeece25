//! PLY meshes (the Stanford polygon format: ASCII, binary little endian and binary big
//! endian) through `ply-rs-bw`, which parses the header and each record; this module checks
//! the header against the file's size and raybench's limits before anything sized by it is
//! allocated, and turns records into a [`MeshData`].
//!
//! Read: the `vertex` element's `x`, `y`, `z` (any scalar type), its normals `nx`, `ny`,
//! `nz` and texture coordinates (`u v`, `s t`, `texture_u texture_v` or `texture_s
//! texture_t`) when all of a set are declared; the `face` element's `vertex_indices` (or
//! `vertex_index`) lists of any integer type, polygons triangulated as OBJ polygons are
//! ([`PolygonMesh::triangulate`]). Everything else (colours, edges, other elements,
//! comments, `obj_info`) is ignored.

use crate::error::LoadError;
use crate::obj::MeshData;
use ply_rs_bw::parser::{ParseError, Parser, Reader};
use ply_rs_bw::ply::{ElementDef, Encoding, Header, PropertyAccess, PropertyAccessResult};
use ply_rs_bw::ply::{PropertyType, ScalarType};
use raybench_core::limits::MAX_PRIMITIVES;
use raybench_core::{PolygonMesh, Vec2, Vec3};
use std::path::Path;

/// Reserves memory for this many more triangles, or refuses
/// ([`crate::budget::Reservation::reserve`]).
pub(crate) type Reserve<'a> = &'a mut dyn FnMut(u64) -> Result<(), LoadError>;

/// Loads a PLY file into triangles in face order: convex polygons as fans from their first
/// vertex (a quad splits along its first diagonal), simple non-convex ones by ear clipping,
/// self-intersecting ones as fans with a warning, as OBJ polygons. Vertex normals and
/// texture coordinates fill [`MeshData::normals`] and [`MeshData::uvs`] when the file has
/// them; there are no materials.
///
/// # Errors
/// When the file is missing or not a regular file; when its header is malformed, declares
/// more records than the file could hold or more than the limits allow, or lacks the
/// `vertex` element or its `x`, `y`, `z`; when a record is truncated or malformed, a
/// coordinate, normal or texture coordinate is not finite, a face has fewer than three
/// vertices or a vertex index out of range; when an ASCII record has more numbers than
/// the header's properties take, or a binary list's length runs past the file. The error
/// names the element, the record and its line (ASCII) or byte offset (binary). Bytes
/// after the last record (padding, or a header declaring too few records) are a warning.
pub fn load_ply_file(path: &Path) -> Result<MeshData, LoadError> {
    load_ply_file_reserving(path, &mut |_| Ok(()))
}

/// [`load_ply_file`], reserving the triangles through `reserve` before they are allocated:
/// the header's face count before any record is read, the rest once the faces' sizes are
/// known. In all, exactly the loaded triangles are reserved.
pub(crate) fn load_ply_file_reserving(
    path: &Path,
    reserve: Reserve<'_>,
) -> Result<MeshData, LoadError> {
    crate::io::check_regular_file(path)?;
    let bytes = std::fs::read(path).map_err(|cause| LoadError::Io {
        path: path.to_owned(),
        cause,
    })?;
    parse_ply(&bytes, path, reserve)
}

/// Parses a PLY file held in memory, as [`load_ply_file`] does (`path` names it in errors).
/// The fuzz target and property tests use it.
///
/// # Errors
/// As [`load_ply_file`], less the file errors.
#[doc(hidden)]
pub fn load_ply_bytes(bytes: &[u8], path: &Path) -> Result<MeshData, LoadError> {
    parse_ply(bytes, path, &mut |_| Ok(()))
}

/// The error for `path` with `message`.
fn parse_err(path: &Path, message: impl Into<String>) -> LoadError {
    LoadError::Parse {
        path: path.to_owned(),
        message: message.into(),
    }
}

/// The vertex properties raybench reads, by slot in a [`VertexRecord`].
const VERTEX_SLOTS: [&str; 14] = [
    "x",
    "y",
    "z",
    "nx",
    "ny",
    "nz",
    "u",
    "v",
    "s",
    "t",
    "texture_u",
    "texture_v",
    "texture_s",
    "texture_t",
];

/// The slot of the first normal component in [`VERTEX_SLOTS`].
const NORMAL_SLOT: usize = 3;

/// The texture-coordinate pairs accepted, in order of preference: the slots of their first
/// names in [`VERTEX_SLOTS`] (the second follows).
const UV_SLOTS: [usize; 4] = [6, 8, 10, 12];

/// The names of a face's vertex-index list, in order of preference.
const FACE_LISTS: [&str; 2] = ["vertex_indices", "vertex_index"];

/// One vertex record: the values of [`VERTEX_SLOTS`] (0 where absent), as `f64`, which
/// holds every PLY scalar type exactly.
struct VertexRecord([f64; VERTEX_SLOTS.len()]);

impl VertexRecord {
    fn set(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        match VERTEX_SLOTS.iter().position(|&s| s == name) {
            Some(i) => {
                self.0[i] = value;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::Ignored,
        }
    }
}

/// `PropertyAccess` setters that hand each value, converted by the closure-like
/// expression, to `self.set`.
macro_rules! setters {
    ($($setter:ident($t:ty) => |$v:ident| $e:expr),* $(,)?) => {
        $(fn $setter(&mut self, name: &str, $v: $t) -> PropertyAccessResult {
            self.set(name, $e)
        })*
    };
}

impl PropertyAccess for VertexRecord {
    fn new() -> Self {
        Self([0.0; VERTEX_SLOTS.len()])
    }
    setters! {
        set_char(i8) => |v| v.into(),
        set_uchar(u8) => |v| v.into(),
        set_short(i16) => |v| v.into(),
        set_ushort(u16) => |v| v.into(),
        set_int(i32) => |v| v.into(),
        set_uint(u32) => |v| v.into(),
        set_float(f32) => |v| v.into(),
        set_double(f64) => |v| v,
    }
}

/// One face record: the integer lists named [`FACE_LISTS`] as `u32`, or the first entry
/// that is no `u32` (negative or too large: out of range anyway).
#[derive(Default)]
struct FaceRecord([Option<Result<Vec<u32>, i64>>; FACE_LISTS.len()]);

impl FaceRecord {
    fn set<T: Copy + Into<i64>>(&mut self, name: &str, list: &[T]) -> PropertyAccessResult {
        match FACE_LISTS.iter().position(|&s| s == name) {
            Some(i) => {
                self.0[i] = Some(
                    list.iter()
                        .map(|&v| u32::try_from(v.into()).map_err(|_| v.into()))
                        .collect(),
                );
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::Ignored,
        }
    }
}

impl PropertyAccess for FaceRecord {
    fn new() -> Self {
        Self::default()
    }
    setters! {
        set_list_char(Vec<i8>) => |v| &v,
        set_list_uchar(Vec<u8>) => |v| &v,
        set_list_short(Vec<i16>) => |v| &v,
        set_list_ushort(Vec<u16>) => |v| &v,
        set_list_int(Vec<i32>) => |v| &v,
        set_list_uint(Vec<u32>) => |v| &v,
    }
}

/// A record of an element raybench does not read (every property ignored).
struct Skipped;

impl PropertyAccess for Skipped {
    fn new() -> Self {
        Self
    }
}

/// Bytes of one binary scalar.
fn scalar_bytes(t: &ScalarType) -> u64 {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// The PLY name of a scalar type.
fn scalar_name(t: &ScalarType) -> &'static str {
    match t {
        ScalarType::Char => "char",
        ScalarType::UChar => "uchar",
        ScalarType::Short => "short",
        ScalarType::UShort => "ushort",
        ScalarType::Int => "int",
        ScalarType::UInt => "uint",
        ScalarType::Float => "float",
        ScalarType::Double => "double",
    }
}

fn is_integer(t: &ScalarType) -> bool {
    !matches!(t, ScalarType::Float | ScalarType::Double)
}

/// What raybench reads of a file, from its header.
struct Plan {
    /// The number of vertices.
    vertices: usize,
    /// Whether the vertices carry `nx`, `ny`, `nz`.
    normals: bool,
    /// The slot of the first texture coordinate read ([`UV_SLOTS`]), if any.
    uv: Option<usize>,
    /// The slot in [`FACE_LISTS`] of the faces' vertex-index list, when there are faces.
    face_list: Option<usize>,
    /// The number of faces.
    faces: usize,
}

/// The smallest size in bytes of a record of `def`: binary scalars and list lengths at
/// their sizes (lists empty); in ASCII one character and one separator per number (an empty
/// line for no properties).
fn min_record_bytes(def: &ElementDef, encoding: Encoding) -> u64 {
    let mut bytes = 0u64;
    for p in def.properties.values() {
        bytes += match (&p.data_type, encoding) {
            (_, Encoding::Ascii) => 2,
            (PropertyType::Scalar(t) | PropertyType::List(t, _), _) => scalar_bytes(t),
        };
    }
    if encoding == Encoding::Ascii {
        bytes.max(1)
    } else {
        bytes
    }
}

/// Refuses an element or property declared twice: `ply-rs-bw` keeps the last definition of
/// a name and would read the records with the wrong layout.
fn check_duplicates(header_text: &str, path: &Path) -> Result<(), LoadError> {
    let mut elements: Vec<&str> = Vec::new();
    let mut properties: Vec<&str> = Vec::new();
    for (n, line) in header_text.lines().enumerate() {
        let words: Vec<&str> = line.split_whitespace().collect();
        let (seen, name, what) = match words.as_slice() {
            ["element", name, ..] => {
                properties.clear();
                (&mut elements, *name, format!("element '{name}'"))
            }
            ["property", .., name] => {
                let element = elements.last().copied().unwrap_or_default();
                let what = format!("property '{name}' of element '{element}'");
                (&mut properties, *name, what)
            }
            _ => continue,
        };
        if seen.contains(&name) {
            return Err(parse_err(
                path,
                format!("line {}: {what} is declared twice", n + 1),
            ));
        }
        seen.push(name);
    }
    Ok(())
}

/// Checks the header: list counts of integer types, the `vertex` element with `x`, `y`,
/// `z` numbers, the faces' vertex lists of integers, the counts within raybench's limits,
/// and the records no more than the `body` bytes after the header could hold. Nothing sized
/// by the header has been allocated yet.
fn plan(header: &Header, body: u64, path: &Path) -> Result<Plan, LoadError> {
    let err = |m: String| parse_err(path, m);
    for (e, def) in &header.elements {
        for (p, prop) in &def.properties {
            if let PropertyType::List(count, _) = &prop.data_type
                && !is_integer(count)
            {
                return Err(err(format!(
                    "property '{p}' of element '{e}': a list's length must have an integer \
                     type, not {}",
                    scalar_name(count)
                )));
            }
        }
    }
    let vertex = header
        .elements
        .get("vertex")
        .ok_or_else(|| err("the header declares no 'vertex' element".into()))?;
    let declared = |name: &str| -> Result<bool, LoadError> {
        match vertex.properties.get(name).map(|p| &p.data_type) {
            None => Ok(false),
            Some(PropertyType::Scalar(_)) => Ok(true),
            Some(PropertyType::List(..)) => Err(err(format!(
                "property '{name}' of element 'vertex' is a list, not a number"
            ))),
        }
    };
    for axis in &VERTEX_SLOTS[..NORMAL_SLOT] {
        if !declared(axis)? {
            return Err(err(format!("element 'vertex' has no property '{axis}'")));
        }
    }
    let mut normals = true;
    for name in &VERTEX_SLOTS[NORMAL_SLOT..NORMAL_SLOT + 3] {
        normals &= declared(name)?;
    }
    let mut uv = None;
    for &s in &UV_SLOTS {
        if declared(VERTEX_SLOTS[s])? && declared(VERTEX_SLOTS[s + 1])? && uv.is_none() {
            uv = Some(s);
        }
    }
    if u32::try_from(vertex.count).is_err() {
        return Err(err(format!(
            "the header declares {} vertices, more than the {} that 32-bit indices address",
            vertex.count,
            u32::MAX
        )));
    }
    let (face_list, faces) = match header.elements.get("face") {
        None => (None, 0),
        Some(face) => {
            let slot = FACE_LISTS
                .iter()
                .position(|n| face.properties.contains_key(*n))
                .ok_or_else(|| {
                    err(
                        "element 'face' has no property 'vertex_indices' (or 'vertex_index')"
                            .into(),
                    )
                })?;
            let name = FACE_LISTS[slot];
            match &face.properties[name].data_type {
                PropertyType::List(_, t) if is_integer(t) => {}
                t => {
                    return Err(err(format!(
                        "property '{name}' of element 'face' must be a list of integers, not {}",
                        match t {
                            PropertyType::List(_, t) => format!("a list of {}", scalar_name(t)),
                            PropertyType::Scalar(t) => format!("one {}", scalar_name(t)),
                        }
                    )));
                }
            }
            if face.count > MAX_PRIMITIVES {
                return Err(err(format!(
                    "the header declares {} faces, more than the limit of {MAX_PRIMITIVES} \
                     primitives",
                    face.count
                )));
            }
            (Some(slot), face.count)
        }
    };
    // Every record takes at least its minimum size: a header declaring more than the rest
    // of the file holds is refused before any record is read.
    let slack = u64::from(header.encoding == Encoding::Ascii); // the last line's newline
    let mut need = 0u64;
    for (name, def) in &header.elements {
        let min = min_record_bytes(def, header.encoding);
        need = need.saturating_add(min.saturating_mul(def.count as u64));
        if need > body + slack {
            return Err(err(format!(
                "the header declares {} '{name}' records of at least {min} bytes each, more \
                 than the {body} bytes after the header hold (truncated, or a corrupt header)",
                def.count
            )));
        }
    }
    Ok(Plan {
        vertices: vertex.count,
        normals,
        uv,
        face_list,
        faces,
    })
}

/// Where a record starts: its line (ASCII) or byte offset (binary).
#[derive(Clone, Copy)]
enum Place {
    Line(usize),
    Byte(usize),
}

impl std::fmt::Display for Place {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Line(n) => write!(f, "line {n}"),
            Self::Byte(n) => write!(f, "byte {n}"),
        }
    }
}

/// The payload after the header, read record by record.
struct Body<'a> {
    rest: &'a [u8],
    encoding: Encoding,
    /// The line of the next record (ASCII).
    line: usize,
    /// The file's length, for byte offsets (binary).
    len: usize,
}

impl Body<'_> {
    /// Where the next record starts, for messages.
    fn place(&self) -> Place {
        match self.encoding {
            Encoding::Ascii => Place::Line(self.line),
            _ => Place::Byte(self.len - self.rest.len()),
        }
    }

    /// Reads the next record of `def`; the error is the cause, in words.
    fn read<E: PropertyAccess>(
        &mut self,
        parser: &Parser<E>,
        def: &ElementDef,
    ) -> Result<E, String> {
        match self.encoding {
            Encoding::Ascii => {
                let line = self.next_line()?;
                let text =
                    std::str::from_utf8(line).map_err(|_| "the line is not text".to_owned())?;
                let record = parser
                    .read_ascii_element(text, def)
                    .map_err(|e| ascii_cause(&e))?;
                // `ply-rs-bw` ignores numbers beyond the properties.
                let (found, needed) = ascii_words(text, def);
                if found > needed {
                    return Err(format!(
                        "{found} numbers where the header's properties take {needed} (the \
                         header does not describe this line)"
                    ));
                }
                Ok(record)
            }
            Encoding::BinaryLittleEndian | Encoding::BinaryBigEndian => {
                let start = self.rest;
                let big = self.encoding == Encoding::BinaryBigEndian;
                let read = if big {
                    parser.read_big_endian_element(&mut self.rest, def)
                } else {
                    parser.read_little_endian_element(&mut self.rest, def)
                };
                read.map_err(|e| {
                    if e.kind() == std::io::ErrorKind::UnexpectedEof {
                        list_too_long(start, def, big).unwrap_or_else(truncated)
                    } else {
                        first_line(&e)
                    }
                })
            }
        }
    }

    /// What is left after the last record, when it is more than blank space, as a
    /// warning's words: the records hold less than the file (a header declaring too few
    /// records, or another file appended). Warned of, not refused: some writers pad files.
    fn leftover(&self) -> Option<String> {
        let rest = self.rest;
        match self.encoding {
            Encoding::Ascii => {
                let lines = rest
                    .split(|&b| b == b'\n')
                    .filter(|l| !l.trim_ascii().is_empty())
                    .count();
                (lines > 0).then(|| {
                    format!(
                        "{lines} non-blank line{} after the last record (from line {}) are \
                         ignored: the header declares fewer records than the file holds",
                        if lines == 1 { "" } else { "s" },
                        self.line
                    )
                })
            }
            _ => (!rest.is_empty()).then(|| {
                format!(
                    "{} bytes after the last record (from byte {}) are ignored: the header \
                     declares fewer records than the file holds",
                    rest.len(),
                    self.len - rest.len()
                )
            }),
        }
    }

    /// The next line (without its newline) of an ASCII body.
    fn next_line(&mut self) -> Result<&[u8], String> {
        if self.rest.is_empty() {
            return Err("the file ends before this record (truncated)".into());
        }
        let end = self.rest.iter().position(|&b| b == b'\n');
        let (line, rest) = match end {
            Some(n) => (&self.rest[..n], &self.rest[n + 1..]),
            None => (self.rest, &self.rest[self.rest.len()..]),
        };
        self.rest = rest;
        self.line += 1;
        Ok(line)
    }

    /// Skips the records of an element raybench does not read; the error is the 0-based
    /// record that failed, its place and why.
    fn skip(&mut self, def: &ElementDef) -> Result<(), (usize, Place, String)> {
        let fixed: Option<u64> = def
            .properties
            .values()
            .map(|p| match &p.data_type {
                PropertyType::Scalar(t) => Some(scalar_bytes(t)),
                PropertyType::List(..) => None,
            })
            .sum();
        match (self.encoding, fixed) {
            (Encoding::Ascii, _) => {
                for i in 0..def.count {
                    let place = self.place();
                    self.next_line().map_err(|why| (i, place, why))?;
                }
            }
            // Fixed-size binary records: skipped at once (records of no properties take no
            // bytes, however many are declared).
            (_, Some(size)) => {
                let total = size.saturating_mul(def.count as u64);
                if total > self.rest.len() as u64 {
                    let i = (self.rest.len() as u64 / size.max(1)) as usize;
                    self.rest = &self.rest[self.rest.len()..];
                    return Err((i, self.place(), truncated()));
                }
                self.rest = &self.rest[total as usize..];
            }
            (_, None) => {
                let parser = Parser::<Skipped>::new();
                for i in 0..def.count {
                    let place = self.place();
                    self.read(&parser, def).map_err(|why| (i, place, why))?;
                }
            }
        }
        Ok(())
    }
}

/// The numbers on an ASCII record's line, and how many the properties of `def` take (a
/// list takes its length and its entries), counted once the record has parsed.
fn ascii_words(line: &str, def: &ElementDef) -> (usize, usize) {
    let words: Vec<&str> = line.split_whitespace().collect();
    let mut needed = 0usize;
    for p in def.properties.values() {
        needed += match &p.data_type {
            PropertyType::Scalar(_) => 1,
            PropertyType::List(..) => {
                let n = words
                    .get(needed)
                    .and_then(|w| w.parse::<f64>().ok())
                    .unwrap_or(0.0);
                1 + n as usize
            }
        };
    }
    (words.len(), needed)
}

/// Why a binary record of `def` starting at `bytes` ran past the file, when a list's
/// length is the cause: the length and what it needs, against what the file has left.
/// `None` when every list fits (the file ends inside the record: truncated).
fn list_too_long(bytes: &[u8], def: &ElementDef, big: bool) -> Option<String> {
    let mut at = 0u64;
    for (name, p) in &def.properties {
        match &p.data_type {
            PropertyType::Scalar(t) => at += scalar_bytes(t),
            PropertyType::List(count, t) => {
                let size = scalar_bytes(count);
                let raw = bytes.get(at as usize..(at + size) as usize)?;
                let mut word = [0u8; 8];
                if big {
                    word[8 - raw.len()..].copy_from_slice(raw);
                } else {
                    word[..raw.len()].copy_from_slice(raw);
                }
                let n = if big {
                    u64::from_be_bytes(word)
                } else {
                    u64::from_le_bytes(word)
                };
                // Signed count types: a negative length is read as huge, and is wrong too.
                at += size;
                let need = n.saturating_mul(scalar_bytes(t));
                let left = (bytes.len() as u64).saturating_sub(at);
                if need > left {
                    return Some(format!(
                        "the file ends inside this record: its list '{name}' of {n} entries \
                         needs {need} bytes, {left} are left (a corrupt list length, or a \
                         truncated file)"
                    ));
                }
                at += need;
            }
        }
    }
    None
}

fn truncated() -> String {
    "the file ends inside this record (truncated)".into()
}

/// The cause of a failed ASCII record, in one line.
fn ascii_cause(e: &ParseError) -> String {
    let text = e.to_string();
    let value = text
        .lines()
        .find_map(|l| l.trim().strip_prefix("Value: "))
        .unwrap_or_default()
        .to_owned();
    let first = first_line(e);
    if first.starts_with("couldn't parse element line") {
        "not a line of numbers (a number is malformed, or a word such as nan)".into()
    } else if first.starts_with("parse error") {
        format!("{value} is not a number of the declared type")
    } else if first.starts_with("expected element of type") {
        "too few numbers for the header's properties".into()
    } else if let Some(at) = first.strip_prefix("couldn't parse element at index ") {
        let index = at.split(':').next().unwrap_or_default();
        format!("list entry {index} is not a number of the declared type")
    } else {
        first
    }
}

/// The first line of `e`'s message, without its line number and final full stop, starting
/// in lower case.
fn first_line(e: &ParseError) -> String {
    let text = e.to_string();
    let text = match e.line() {
        Some(n) => text
            .strip_prefix(&format!("Line {n}: "))
            .unwrap_or(&text)
            .to_owned(),
        None => text,
    };
    let first = text.lines().next().unwrap_or_default().trim();
    let first = first.trim_end_matches(['.', ',', ' ']);
    // Lower case, as a cause after a colon.
    let mut chars = first.chars();
    chars
        .next()
        .map(|c| c.to_lowercase().chain(chars).collect())
        .unwrap_or_default()
}

/// The message for a header `ply-rs-bw` refused.
fn header_message(e: &ParseError, header: &[u8]) -> String {
    let first = first_line(e);
    let why = if first.starts_with("expected magic number") {
        "not a PLY file (the first line is not 'ply')".to_owned()
    } else if first.starts_with("unexpected end of file while reading header") {
        "the header has no 'end_header' line".to_owned()
    } else if first.starts_with("couldn't parse line") || first.starts_with("property") {
        let n = e.line().unwrap_or(0);
        let line = header
            .split(|&b| b == b'\n')
            .nth(n.saturating_sub(1))
            .unwrap_or_default();
        let text: String = String::from_utf8_lossy(line)
            .trim_end()
            .chars()
            .take(80)
            .collect();
        if first.starts_with("property") {
            format!("'{}' comes before any element", text.escape_debug())
        } else {
            format!("malformed header line '{}'", text.escape_debug())
        }
    } else if e.kind() == std::io::ErrorKind::InvalidData {
        "the header is not text".to_owned()
    } else {
        first
    };
    match e.line() {
        Some(n) => format!("malformed PLY header: line {n}: {why}"),
        None => format!("malformed PLY header: {why}"),
    }
}

/// Reads a vertex record into `out`, refusing non-finite values.
fn add_vertex(r: &VertexRecord, plan: &Plan, out: &mut MeshData) -> Result<(), String> {
    let v = |i: usize| r.0[i] as f32;
    let p = Vec3::new(v(0), v(1), v(2));
    if let Some(axis) = (0..3).find(|&a| !p[a].is_finite()) {
        return Err(format!(
            "coordinate {} is not finite (NaN, infinite or beyond f32)",
            VERTEX_SLOTS[axis]
        ));
    }
    out.mesh.positions.push(p);
    if plan.normals {
        let n = Vec3::new(v(NORMAL_SLOT), v(NORMAL_SLOT + 1), v(NORMAL_SLOT + 2));
        if !n.is_finite() {
            return Err("the normal is not finite".into());
        }
        out.normals.push(n);
    }
    if let Some(s) = plan.uv {
        // PLY's `v` counts up from the image's bottom row, as OBJ's `vt`; `MeshData` holds
        // glTF's convention (from the top row).
        let uv = Vec2::new(v(s), 1.0 - v(s + 1));
        if !uv.is_finite() {
            return Err("the texture coordinates are not finite".into());
        }
        out.uvs.push(uv);
    }
    Ok(())
}

/// Checks a face record's vertex list: at least three indices, each in range.
fn face_indices(r: FaceRecord, plan: &Plan) -> Result<Vec<u32>, String> {
    let [a, b] = r.0;
    let list = match plan.face_list {
        Some(0) => a,
        _ => b,
    }
    .unwrap_or(Ok(Vec::new()));
    let out_of_range = |i: i64| {
        format!(
            "vertex index {i} is out of range (the file has {} vertices)",
            plan.vertices
        )
    };
    let list = list.map_err(out_of_range)?;
    if list.len() < 3 {
        return Err(format!(
            "{} vertex indices (a face needs at least 3)",
            list.len()
        ));
    }
    match list.iter().find(|&&i| i as usize >= plan.vertices) {
        Some(&i) => Err(out_of_range(i.into())),
        None => Ok(list),
    }
}

/// Parses a PLY file, reserving its triangles through `reserve` before allocating them.
fn parse_ply(bytes: &[u8], path: &Path, reserve: Reserve<'_>) -> Result<MeshData, LoadError> {
    let bytes = crate::io::strip_bom(bytes);
    let mut reader = Reader::new(bytes);
    let header = Parser::<Skipped>::new()
        .read_header(&mut reader)
        .map_err(|e| parse_err(path, header_message(&e, bytes)))?;
    let body_line = reader.line();
    let rest = reader.into_inner();
    let header_text = String::from_utf8_lossy(&bytes[..bytes.len() - rest.len()]);
    check_duplicates(&header_text, path)?;
    let plan = plan(&header, rest.len() as u64, path)?;
    reserve(plan.faces as u64)?;

    let mut data = MeshData::default();
    data.mesh.positions.reserve_exact(plan.vertices);
    if plan.normals {
        data.normals.reserve_exact(plan.vertices);
    }
    if plan.uv.is_some() {
        data.uvs.reserve_exact(plan.vertices);
    }
    // Not preallocated: a face record may be a single byte.
    let mut faces: Vec<Vec<u32>> = Vec::new();
    let mut triangles = 0u64;
    let mut body = Body {
        rest,
        encoding: header.encoding,
        line: body_line,
        len: bytes.len(),
    };
    let record_err = |name: &str, i: usize, place: Place, why: String| {
        parse_err(path, format!("{name} {} ({place}): {why}", i + 1))
    };
    for (name, def) in &header.elements {
        match name.as_str() {
            "vertex" => {
                let parser = Parser::<VertexRecord>::new();
                for i in 0..def.count {
                    let place = body.place();
                    body.read(&parser, def)
                        .and_then(|r| add_vertex(&r, &plan, &mut data))
                        .map_err(|why| record_err(name, i, place, why))?;
                }
            }
            "face" => {
                let parser = Parser::<FaceRecord>::new();
                for i in 0..def.count {
                    let place = body.place();
                    let face = body
                        .read(&parser, def)
                        .and_then(|r| face_indices(r, &plan))
                        .map_err(|why| record_err(name, i, place, why))?;
                    // A polygon of n vertices becomes n - 2 triangles.
                    triangles += face.len() as u64 - 2;
                    if triangles > MAX_PRIMITIVES as u64 {
                        return Err(record_err(
                            name,
                            i,
                            place,
                            format!(
                                "the faces so far make {triangles} triangles, more than the \
                                 limit of {MAX_PRIMITIVES} primitives"
                            ),
                        ));
                    }
                    faces.push(face);
                }
            }
            _ => body
                .skip(def)
                .map_err(|(i, place, why)| record_err(name, i, place, why))?,
        }
    }

    if let Some(why) = body.leftover() {
        data.warnings.push(format!("{}: {why}", path.display()));
    }
    // The triangles beyond one per face, reserved before they are made.
    reserve(triangles - plan.faces as u64)?;
    let polygons = PolygonMesh {
        positions: std::mem::take(&mut data.mesh.positions),
        faces,
    };
    let triangulated = polygons
        .triangulate()
        .map_err(|e| parse_err(path, e.to_string()))?;
    drop(polygons);
    if !triangulated.self_intersecting.is_empty() {
        data.warnings.push(format!(
            "{}: {}",
            path.display(),
            crate::obj::self_intersecting(&triangulated.self_intersecting)
        ));
    }
    data.mesh = triangulated.mesh;
    data.triangle_material = vec![None; data.mesh.indices.len()];
    Ok(data)
}
