//! A PLY writer for the tests (written independently of the loader's `ply-rs-bw`): any
//! elements, scalar and list properties of every type, in each of the three encodings.

use std::fmt::Write as _;

/// A PLY encoding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Enc {
    /// `ascii`.
    Ascii,
    /// `binary_little_endian`.
    Le,
    /// `binary_big_endian`.
    Be,
}

/// Every encoding.
pub const ENCODINGS: [Enc; 3] = [Enc::Ascii, Enc::Le, Enc::Be];

/// A property declaration: a scalar `(type, name)` or a list `(count type, type, name)`.
#[derive(Clone)]
pub enum Decl {
    /// `property TYPE NAME`.
    Scalar(&'static str, &'static str),
    /// `property list COUNT-TYPE TYPE NAME`.
    List(&'static str, &'static str, &'static str),
}

/// A property value (numbers as f64, exact for every PLY type).
#[derive(Clone)]
pub enum Val {
    /// A scalar.
    N(f64),
    /// A list.
    L(Vec<f64>),
}

/// An element: its name, properties and records.
pub struct Element {
    /// The element's name.
    pub name: &'static str,
    /// Its properties.
    pub decls: Vec<Decl>,
    /// Its records: one value per property.
    pub rows: Vec<Vec<Val>>,
}

/// Appends `v` as PLY type `ty` in encoding `enc` (ASCII: a word and a space).
fn put(out: &mut Vec<u8>, enc: Enc, ty: &str, v: f64) {
    macro_rules! bin {
        ($t:ty) => {{
            let x = v as $t;
            out.extend_from_slice(&match enc {
                Enc::Be => x.to_be_bytes(),
                _ => x.to_le_bytes(),
            });
        }};
    }
    if enc == Enc::Ascii {
        let word = match ty {
            "float" | "float32" => format!("{}", v as f32),
            "double" | "float64" => format!("{v}"),
            _ => format!("{}", v as i64),
        };
        out.extend_from_slice(word.as_bytes());
        out.push(b' ');
        return;
    }
    match ty {
        "char" | "int8" => bin!(i8),
        "uchar" | "uint8" => bin!(u8),
        "short" | "int16" => bin!(i16),
        "ushort" | "uint16" => bin!(u16),
        "int" | "int32" => bin!(i32),
        "uint" | "uint32" => bin!(u32),
        "float" | "float32" => bin!(f32),
        "double" | "float64" => bin!(f64),
        _ => panic!("unknown type {ty}"),
    }
}

/// A whole PLY file: header (with `extra_header` lines after the format line) and body.
pub fn ply(enc: Enc, extra_header: &str, elements: &[Element]) -> Vec<u8> {
    let format = match enc {
        Enc::Ascii => "ascii",
        Enc::Le => "binary_little_endian",
        Enc::Be => "binary_big_endian",
    };
    let mut h = format!("ply\nformat {format} 1.0\n{extra_header}");
    for e in elements {
        writeln!(h, "element {} {}", e.name, e.rows.len()).unwrap();
        for d in &e.decls {
            match d {
                Decl::Scalar(t, n) => writeln!(h, "property {t} {n}").unwrap(),
                Decl::List(c, t, n) => writeln!(h, "property list {c} {t} {n}").unwrap(),
            }
        }
    }
    h.push_str("end_header\n");
    let mut out = h.into_bytes();
    for e in elements {
        for row in &e.rows {
            for (d, v) in e.decls.iter().zip(row) {
                match (d, v) {
                    (Decl::Scalar(t, _), Val::N(x)) => put(&mut out, enc, t, *x),
                    (Decl::List(c, t, _), Val::L(xs)) => {
                        put(&mut out, enc, c, xs.len() as f64);
                        for &x in xs {
                            put(&mut out, enc, t, x);
                        }
                    }
                    _ => panic!("value does not match its declaration"),
                }
            }
            if enc == Enc::Ascii {
                out.pop();
                out.push(b'\n');
            }
        }
    }
    out
}

/// The length of a file's header (where its body starts).
pub fn header_len(bytes: &[u8]) -> usize {
    bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11
}
