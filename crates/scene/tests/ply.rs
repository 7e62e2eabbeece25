//! The PLY loader: files these tests write themselves (from the shared OBJ meshes, in all
//! three encodings, and by hand) load into the triangles the OBJ loader makes, bit for
//! bit; normals and texture coordinates are read; every kind of malformed file is an error
//! naming the place and the cause.

use crate::ply_writer::{Decl, ENCODINGS, Element, Enc, Val, header_len, ply};
use raybench_core::{Vec2, Vec3};
use raybench_scene::{LoadError, MeshData, load_obj_bytes, load_obj_file, load_ply_bytes};
use std::fmt::Write as _;
use std::path::Path;

/// The `vertex` element of `positions` as floats.
fn vertices(positions: &[[f32; 3]]) -> Element {
    Element {
        name: "vertex",
        decls: vec![
            Decl::Scalar("float", "x"),
            Decl::Scalar("float", "y"),
            Decl::Scalar("float", "z"),
        ],
        rows: positions
            .iter()
            .map(|p| p.iter().map(|&c| Val::N(f64::from(c))).collect())
            .collect(),
    }
}

/// The `face` element of `faces` (uchar counts, int indices).
fn faces(faces: &[Vec<u32>]) -> Element {
    Element {
        name: "face",
        decls: vec![Decl::List("uchar", "int", "vertex_indices")],
        rows: faces
            .iter()
            .map(|f| vec![Val::L(f.iter().map(|&i| f64::from(i)).collect())])
            .collect(),
    }
}

/// A unit square in z = 0 as one quad, and its OBJ twin.
fn quad() -> (Vec<[f32; 3]>, Vec<Vec<u32>>) {
    (
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        vec![vec![0, 1, 2, 3]],
    )
}

fn load(bytes: &[u8]) -> Result<MeshData, LoadError> {
    load_ply_bytes(bytes, Path::new("t.ply"))
}

/// The triangles of a mesh as the bits of their vertices.
fn triangle_bits(m: &MeshData) -> Vec<[[u32; 3]; 3]> {
    m.mesh
        .triangles()
        .map(|t| t.v.map(|v| v.to_array().map(f32::to_bits)))
        .collect()
}

/// The error `bytes` give, as text.
fn error(bytes: &[u8]) -> String {
    match load(bytes) {
        Ok(m) => panic!(
            "loaded {} triangles; expected an error",
            m.mesh.indices.len()
        ),
        Err(e) => e.to_string(),
    }
}

fn assert_error(bytes: &[u8], needle: &str) {
    let e = error(bytes);
    assert!(e.starts_with("t.ply: "), "{e}");
    assert!(e.contains(needle), "{e:?} lacks {needle:?}");
    assert!(!e.contains('\n'), "a multi-line error: {e:?}");
}

/// Positions and polygons of an OBJ file's `v` and `f` lines (the first index of each
/// corner, 1-based or negative), parsed as `tobj` parses them.
fn obj_polygons(text: &str) -> (Vec<[f32; 3]>, Vec<Vec<u32>>) {
    let mut positions = Vec::new();
    let mut polygons = Vec::new();
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let p: Vec<f32> = words.take(3).map(|w| w.parse().unwrap()).collect();
                positions.push([p[0], p[1], p[2]]);
            }
            Some("f") => polygons.push(
                words
                    .map(|w| {
                        let i: i64 = w.split('/').next().unwrap().parse().unwrap();
                        if i < 0 {
                            (positions.len() as i64 + i) as u32
                        } else {
                            (i - 1) as u32
                        }
                    })
                    .collect(),
            ),
            _ => {}
        }
    }
    (positions, polygons)
}

/// The shared mesh `rel` under `$RAYBENCH_ASSETS`, or `None` (skipped with a reason)
/// when it is absent, except under `CI=true`, where it must be there.
fn shared_mesh(rel: &str) -> Option<std::path::PathBuf> {
    let path = raybench_scene::assets_dir(None).join(rel);
    if path.is_file() {
        return Some(path);
    }
    assert!(
        std::env::var("CI").map_or(true, |v| v != "true"),
        "CI=true but {} is missing",
        path.display()
    );
    eprintln!(
        "SKIPPED: {} is absent (set RAYBENCH_ASSETS to the shared scenes)",
        path.display()
    );
    None
}

/// The shared OBJ meshes written as PLY in every encoding load into the OBJ loader's
/// triangles, bit for bit (the suzanne's quads triangulated alike), and suzanne's
/// per-vertex normals come back exactly.
#[test]
fn shared_meshes_as_ply_match_their_obj() {
    for rel in [
        "bunny-lowres/bunny-lowres.obj",
        "suzanne/suzanne.obj",
        "teapot/teapot.obj",
    ] {
        let Some(path) = shared_mesh(rel) else {
            continue;
        };
        let obj = load_obj_file(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let (positions, polygons) = obj_polygons(&text);
        // suzanne's `vn` lines share the `v` lines' indices: per-vertex normals.
        let normals: Vec<[f32; 3]> = text
            .lines()
            .filter_map(|l| l.strip_prefix("vn "))
            .map(|l| {
                let n: Vec<f32> = l.split_whitespace().map(|w| w.parse().unwrap()).collect();
                [n[0], n[1], n[2]]
            })
            .collect();
        let mut vertex = vertices(&positions);
        if normals.len() == positions.len() {
            for (name, axis) in [("nx", 0), ("ny", 1), ("nz", 2)] {
                vertex.decls.push(Decl::Scalar("float", name));
                for (row, n) in vertex.rows.iter_mut().zip(&normals) {
                    row.push(Val::N(f64::from(n[axis])));
                }
            }
        }
        let elements = [vertex, faces(&polygons)];
        for enc in ENCODINGS {
            let m = load(&ply(
                enc,
                "comment written by raybench's tests\n",
                &elements,
            ))
            .unwrap_or_else(|e| panic!("{rel} {enc:?}: {e}"));
            assert_eq!(triangle_bits(&m), triangle_bits(&obj), "{rel} {enc:?}");
            assert!(m.uvs.is_empty());
            if normals.len() == positions.len() {
                let got: Vec<[f32; 3]> = m.normals.iter().map(|n| n.to_array()).collect();
                assert_eq!(got, normals, "{rel} {enc:?}");
            } else {
                assert!(m.normals.is_empty());
            }
            assert_eq!(m.triangle_material, vec![None; m.mesh.indices.len()]);
            assert!(m.warnings.is_empty(), "{:?}", m.warnings);
        }
    }
}

/// Quads, a concave pentagon and a self-intersecting quad split as the OBJ loader splits
/// them (fans, ear clipping, a fan with a warning).
#[test]
fn polygons_split_as_obj_polygons() {
    let positions = [
        [0.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [2.0, 2.0, 0.0],
        [1.0, 0.5, 0.0],
        [0.0, 2.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
        [1.0, 0.0, 1.0],
        [0.0, 1.0, 1.0],
    ];
    let polygons = vec![vec![0, 1, 2, 4], vec![0, 1, 2, 3, 4], vec![5, 6, 7, 8]];
    let mut obj = String::new();
    for p in positions {
        writeln!(obj, "v {} {} {}", p[0], p[1], p[2]).unwrap();
    }
    for f in &polygons {
        let words: Vec<String> = f.iter().map(|i| (i + 1).to_string()).collect();
        writeln!(obj, "f {}", words.join(" ")).unwrap();
    }
    let obj = load_obj_bytes(obj.as_bytes(), Path::new("t.obj")).unwrap();
    assert_eq!(obj.mesh.indices.len(), 2 + 3 + 2);
    for enc in ENCODINGS {
        let m = load(&ply(enc, "", &[vertices(&positions), faces(&polygons)])).unwrap();
        // (`tobj` numbers vertices in order of use: the triangles, not the indices, agree.)
        assert_eq!(triangle_bits(&m), triangle_bits(&obj), "{enc:?}");
        assert_eq!(m.warnings.len(), 1, "{:?}", m.warnings);
        assert!(
            m.warnings[0].starts_with("t.ply: face 3 is self-intersecting"),
            "{:?}",
            m.warnings
        );
    }
}

/// Normals and each spelling of texture coordinates are read, in any scalar type.
#[test]
fn normals_and_texture_coordinates_are_read() {
    let (positions, polys) = quad();
    for (u, v) in [
        ("u", "v"),
        ("s", "t"),
        ("texture_u", "texture_v"),
        ("texture_s", "texture_t"),
    ] {
        for enc in ENCODINGS {
            let mut vertex = vertices(&positions);
            vertex.decls.extend([
                Decl::Scalar("double", "nx"),
                Decl::Scalar("float", "ny"),
                Decl::Scalar("char", "nz"),
                Decl::Scalar("uchar", "red"),
                Decl::Scalar("float", u),
                Decl::Scalar("double", v),
            ]);
            for (i, row) in vertex.rows.iter_mut().enumerate() {
                let i = i as f64;
                row.extend([0.0, 0.0, 1.0, 200.0, i * 0.25, 1.0 - i * 0.5].map(Val::N));
            }
            let m = load(&ply(enc, "", &[vertex, faces(&polys)])).unwrap();
            assert_eq!(m.normals, vec![Vec3::Z; 4], "{u} {enc:?}");
            // `v` counts up from the bottom row, as OBJ's `vt`: flipped to glTF's convention.
            let uvs: Vec<Vec2> = (0..4)
                .map(|i| Vec2::new(i as f32 * 0.25, 1.0 - (1.0 - i as f32 * 0.5)))
                .collect();
            assert_eq!(m.uvs, uvs, "{u} {enc:?}");
            assert_eq!(m.mesh.indices, [[0, 1, 2], [0, 2, 3]]);
        }
    }
    // A partial set is no set: no normals without nz, no coordinates without v.
    let mut vertex = vertices(&positions);
    vertex
        .decls
        .extend([Decl::Scalar("float", "nx"), Decl::Scalar("float", "u")]);
    for row in &mut vertex.rows {
        row.extend([Val::N(0.0), Val::N(0.5)]);
    }
    let m = load(&ply(Enc::Ascii, "", &[vertex, faces(&polys)])).unwrap();
    assert!(m.normals.is_empty() && m.uvs.is_empty());
}

/// Coordinates of every scalar type, indices of every integer type, `vertex_index` for
/// `vertex_indices`, other elements (with lists) and properties, comments and `obj_info`,
/// and faces before vertices: all read or ignored as they should be.
#[test]
fn every_type_and_layout_loads() {
    let (positions, polys) = quad();
    for coord in [
        "char", "uchar", "short", "ushort", "int", "uint", "float", "double", "int8", "uint8",
        "int16", "uint16", "int32", "uint32", "float32", "float64",
    ] {
        for (count, index) in [
            ("uchar", "uchar"),
            ("char", "char"),
            ("ushort", "short"),
            ("uint", "ushort"),
            ("int", "uint"),
        ] {
            for enc in ENCODINGS {
                let mut vertex = vertices(&positions);
                vertex.decls = ["x", "y", "z"].map(|n| Decl::Scalar(coord, n)).to_vec();
                let mut face = faces(&polys);
                face.decls = vec![
                    Decl::Scalar("uchar", "flags"),
                    Decl::List(count, index, "vertex_index"),
                ];
                for row in &mut face.rows {
                    row.insert(0, Val::N(7.0));
                }
                let edge = Element {
                    name: "edge",
                    decls: vec![
                        Decl::Scalar("int", "vertex1"),
                        Decl::Scalar("int", "vertex2"),
                    ],
                    rows: vec![vec![Val::N(0.0), Val::N(1.0)]],
                };
                let material = Element {
                    name: "material",
                    decls: vec![
                        Decl::List("uchar", "float", "ambient"),
                        Decl::Scalar("double", "power"),
                    ],
                    rows: vec![vec![Val::L(vec![0.5; 3]), Val::N(2.0)]; 2],
                };
                let m = load(&ply(
                    enc,
                    "comment a comment\nobj_info some info\n",
                    &[face, material, vertex, edge],
                ))
                .unwrap_or_else(|e| panic!("{coord} {count} {index} {enc:?}: {e}"));
                assert_eq!(m.mesh.indices, [[0, 1, 2], [0, 2, 3]]);
                let p: Vec<[f32; 3]> = m.mesh.positions.iter().map(|p| p.to_array()).collect();
                assert_eq!(p, positions);
            }
        }
    }
}

/// Windows line ends, a byte-order mark and a missing final newline are accepted.
#[test]
fn ascii_variants_load() {
    let (positions, polys) = quad();
    let text = ply(Enc::Ascii, "", &[vertices(&positions), faces(&polys)]);
    let crlf = String::from_utf8(text.clone())
        .unwrap()
        .replace('\n', "\r\n");
    let mut bom = b"\xef\xbb\xbf".to_vec();
    bom.extend_from_slice(&text);
    let unterminated = &text[..text.len() - 1];
    for bytes in [crlf.as_bytes(), &bom, unterminated] {
        assert_eq!(load(bytes).unwrap().mesh.indices.len(), 2);
    }
}

/// The quad's file with the header line `from` replaced by `to`.
fn edited(enc: Enc, from: &str, to: &str) -> Vec<u8> {
    let (positions, polys) = quad();
    let bytes = ply(enc, "", &[vertices(&positions), faces(&polys)]);
    let end = header_len(&bytes);
    let header = String::from_utf8(bytes[..end].to_vec()).unwrap();
    assert!(header.contains(from), "{header} lacks {from}");
    let mut out = header.replacen(from, to, 1).into_bytes();
    out.extend_from_slice(&bytes[end..]);
    out
}

/// Headers that declare more records than the file holds are refused before any record is
/// read, in every encoding, however large the count.
#[test]
fn headers_declaring_more_than_the_file_holds_are_refused() {
    for enc in ENCODINGS {
        for count in ["7", "1000000", "4000000000"] {
            assert_error(
                &edited(enc, "element vertex 4", &format!("element vertex {count}")),
                &format!("the header declares {count} 'vertex' records of at least"),
            );
        }
        assert_error(
            &edited(enc, "element face 1", "element face 60000000"),
            "the header declares 60000000 'face' records",
        );
    }
    // Binary: 4 vertices of 12 bytes and one face of 1 + 4 * 4 bytes, 65 in all; a face
    // takes at least its 1-byte length.
    let e = error(&edited(Enc::Le, "element face 1", "element face 18"));
    assert!(
        e.ends_with(
            "the header declares 18 'face' records of at least 1 bytes each, more than the \
             65 bytes after the header hold (truncated, or a corrupt header)"
        ),
        "{e}"
    );
    assert!(error(&edited(Enc::Le, "element face 1", "element face 17")).contains("truncated"));
}

/// Counts over raybench's limits are refused from the header.
#[test]
fn counts_over_the_limits_are_refused() {
    assert_error(
        &edited(Enc::Le, "element face 1", "element face 100000000"),
        "the header declares 100000000 faces, more than the limit of 67108864 primitives",
    );
    assert_error(
        &edited(Enc::Le, "element vertex 4", "element vertex 5000000000"),
        "the header declares 5000000000 vertices, more than the 4294967295 that 32-bit \
         indices address",
    );
}

/// Every malformed record is an error naming the element, the record, its line or byte
/// and the cause.
#[test]
fn malformed_records_name_their_place() {
    let (positions, polys) = quad();
    let good = |enc| ply(enc, "", &[vertices(&positions), faces(&polys)]);
    // The body starts on line 10 (ASCII).
    let ascii = String::from_utf8(good(Enc::Ascii)).unwrap();
    let ascii_with = |from: &str, to: &str| ascii.replacen(from, to, 1).into_bytes();
    assert_error(
        &ascii_with("4 0 1 2 3", "4 0 1 2 9"),
        "face 1 (line 14): vertex index 9 is out of range (the file has 4 vertices)",
    );
    assert_error(
        &ascii_with("4 0 1 2 3", "4 0 1 2 -1"),
        "face 1 (line 14): vertex index -1 is out of range",
    );
    assert_error(
        &ascii_with("4 0 1 2 3", "2 0 1"),
        "face 1 (line 14): 2 vertex indices (a face needs at least 3)",
    );
    assert_error(
        &ascii_with("1 0 0\n", "1 nan 0\n"),
        "vertex 2 (line 11): not a line of numbers",
    );
    assert_error(
        &ascii_with("1 0 0\n", "1 0.5x 0\n"),
        "vertex 2 (line 11): not a line of numbers",
    );
    assert_error(
        &ascii_with("1 0 0\n", "1 0\n"),
        "vertex 2 (line 11): too few numbers for the header's properties",
    );
    assert_error(
        &ascii_with("1 0 0\n", "1 1e39 0\n"),
        "vertex 2 (line 11): coordinate y is not finite",
    );
    assert_error(
        &ascii_with("4 0 1 2 3", "4 0 1.5 2 3"),
        "face 1 (line 14): list entry 1 is not a number of the declared type",
    );
    assert_error(
        &ascii_with("4 0 1 2 3", "4.0 0 1 2 3"),
        "face 1 (line 14): '4.0' is not a number of the declared type",
    );
    assert_error(
        &ascii_with("4 0 1 2 3", "5 0 1 2 3"),
        "face 1 (line 14): expected 5 list elements, but found only 4",
    );
    assert_error(
        &ascii_with("1 0 0\n", "1 \u{e9} 0\n"),
        "vertex 2 (line 11): not a line of numbers",
    );
    let mut not_text = ascii.clone().into_bytes();
    let at = ascii.find("1 0 0\n").unwrap();
    not_text[at + 2] = 0xff;
    assert_error(&not_text, "vertex 2 (line 11): the line is not text");
    // The ASCII file cut before the face's line, but long enough for the header's check.
    let cut = ascii.replacen("0 1 0\n4 0 1 2 3\n", "0 1 0                ", 1);
    assert_error(
        cut.as_bytes(),
        "face 1 (line 14): the file ends before this record (truncated)",
    );

    for enc in [Enc::Le, Enc::Be] {
        let bytes = good(enc);
        let body = bytes.len() - 65;
        // Vertex 2's y is NaN; then infinite.
        for bad in [f32::NAN, f32::INFINITY] {
            let mut b = bytes.clone();
            let at = body + 12 + 4;
            let v = if enc == Enc::Le {
                bad.to_le_bytes()
            } else {
                bad.to_be_bytes()
            };
            b[at..at + 4].copy_from_slice(&v);
            assert_error(
                &b,
                &format!("vertex 2 (byte {}): coordinate y is not finite", body + 12),
            );
        }
        // The face's count says 5: the fifth index runs past the end.
        let mut b = bytes.clone();
        b[body + 48] = 5;
        assert_error(
            &b,
            &format!(
                "face 1 (byte {}): the file ends inside this record: its list \
                 'vertex_indices' of 5 entries needs 20 bytes, 16 are left",
                body + 48
            ),
        );
        let mut b = bytes.clone();
        let at = body + 48 + 1 + 8;
        b[at..at + 4].copy_from_slice(&if enc == Enc::Le {
            7i32.to_le_bytes()
        } else {
            7i32.to_be_bytes()
        });
        assert_error(
            &b,
            &format!(
                "face 1 (byte {}): vertex index 7 is out of range (the file has 4 vertices)",
                body + 48
            ),
        );
    }
    // A double beyond f32 and a non-finite normal or texture coordinate.
    let mut vertex = vertices(&positions);
    vertex.decls[1] = Decl::Scalar("double", "y");
    vertex.rows[3][1] = Val::N(1e300);
    let b = ply(Enc::Be, "", &[vertex, faces(&polys)]);
    assert_error(
        &b,
        &format!(
            "vertex 4 (byte {}): coordinate y is not finite",
            header_len(&b) + 3 * 16
        ),
    );
    for (names, message) in [
        (["nx", "ny", "nz"], "the normal is not finite"),
        (["u", "v", "red"], "the texture coordinates are not finite"),
    ] {
        let mut vertex = vertices(&positions);
        vertex.decls.extend(names.map(|n| Decl::Scalar("float", n)));
        for row in &mut vertex.rows {
            row.extend([Val::N(0.0), Val::N(f64::INFINITY), Val::N(1.0)]);
        }
        let b = ply(Enc::Le, "", &[vertex, faces(&polys)]);
        assert_error(
            &b,
            &format!("vertex 1 (byte {}): {message}", header_len(&b)),
        );
    }
    // Coordinates over raybench's coordinate limit.
    let mut vertex = vertices(&positions);
    vertex.rows[2][0] = Val::N(1e20);
    assert_error(
        &ply(Enc::Le, "", &[vertex, faces(&polys)]),
        "vertex 3 exceeds the coordinate limit of 1e18",
    );
    // A negative binary list length, and an ignored element cut short.
    let mut face = faces(&polys);
    face.decls = vec![Decl::List("char", "int", "vertex_indices")];
    let mut b = ply(Enc::Le, "", &[vertices(&positions), face]);
    let at = header_len(&b) + 48;
    b[at] = 0xff;
    assert_error(
        &b,
        &format!("face 1 (byte {at}): list length cannot be negative (i8)"),
    );
    let skipped = |rows: usize| Element {
        name: "edge",
        decls: vec![Decl::Scalar("int", "a"), Decl::List("uchar", "int", "b")],
        rows: vec![vec![Val::N(1.0), Val::L(vec![1.0, 2.0])]; rows],
    };
    let mut b = ply(Enc::Le, "", &[vertices(&positions), skipped(2)]);
    b.truncate(b.len() - 2);
    assert_error(
        &b,
        &format!(
            "edge 2 (byte {}): the file ends inside this record: its list 'b' of 2 entries \
             needs 8 bytes, 6 are left",
            header_len(&b) + 48 + 13
        ),
    );
}

/// Headers that are malformed, lack what raybench reads, or declare something twice.
#[test]
fn bad_headers_are_refused() {
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (
            b"solid cube\n".to_vec(),
            "malformed PLY header: line 1: not a PLY file (the first line is not 'ply')",
        ),
        (b"".to_vec(), "malformed PLY header"),
        (
            b"ply\nformat ascii 1.0\nelement vertex 0\n".to_vec(),
            "malformed PLY header: line 4: the header has no 'end_header' line",
        ),
        (
            b"ply\nelement vertex 0\nend_header\n".to_vec(),
            "malformed PLY header: ",
        ),
        (
            edited(Enc::Ascii, "property float y", "property flaot y"),
            "malformed PLY header: line 5: malformed header line 'property flaot y'",
        ),
        (
            edited(
                Enc::Ascii,
                "element vertex 4\n",
                "property float w\nelement vertex 4\n",
            ),
            "malformed PLY header: line 3: 'property float w' comes before any element",
        ),
        (
            edited(Enc::Ascii, "element vertex", "element vertices"),
            "the header declares no 'vertex' element",
        ),
        (
            edited(Enc::Le, "property float y\n", ""),
            "element 'vertex' has no property 'y'",
        ),
        (
            edited(Enc::Le, "property float x", "property list uchar float x"),
            "property 'x' of element 'vertex' is a list, not a number",
        ),
        (
            edited(Enc::Le, "vertex_indices", "corners"),
            "element 'face' has no property 'vertex_indices' (or 'vertex_index')",
        ),
        (
            edited(
                Enc::Le,
                "list uchar int vertex_indices",
                "list uchar float vertex_indices",
            ),
            "property 'vertex_indices' of element 'face' must be a list of integers, not a list \
             of float",
        ),
        (
            edited(
                Enc::Le,
                "property list uchar int vertex_indices",
                "property int vertex_indices",
            ),
            "property 'vertex_indices' of element 'face' must be a list of integers, not one int",
        ),
        (
            edited(Enc::Le, "list uchar int", "list float int"),
            "property 'vertex_indices' of element 'face': a list's length must have an integer \
             type, not float",
        ),
        (
            edited(
                Enc::Le,
                "property float z\n",
                "property float z\nproperty float y\n",
            ),
            "line 7: property 'y' of element 'vertex' is declared twice",
        ),
        (
            edited(
                Enc::Le,
                "element face 1\n",
                "element vertex 0\nelement face 1\n",
            ),
            "line 7: element 'vertex' is declared twice",
        ),
    ];
    for (bytes, needle) in cases {
        assert_error(&bytes, needle);
    }
}

/// A file of vertices and no faces loads no triangles (a scene refuses it: no triangles).
#[test]
fn a_point_cloud_has_no_triangles() {
    let (positions, _) = quad();
    for enc in ENCODINGS {
        let m = load(&ply(enc, "", &[vertices(&positions)])).unwrap();
        assert!(m.mesh.indices.is_empty());
        assert_eq!(m.mesh.positions.len(), 4);
    }
}

/// A scene file's `kind = "mesh"` takes a PLY file, and a bare PLY file is a scene.
#[test]
fn ply_files_are_meshes_and_scenes() {
    let dir = std::env::temp_dir().join(format!("raybench-ply-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (positions, polys) = quad();
    let file = dir.join("quad.ply");
    std::fs::write(
        &file,
        ply(Enc::Le, "", &[vertices(&positions), faces(&polys)]),
    )
    .unwrap();
    let scene = raybench_scene::load_scene_str(
        "[[object]]\nkind = \"mesh\"\npath = \"quad.ply\"\ntransform = { translate = [0, 0, 1] }\n",
        "t",
        Some(&dir),
        &dir,
    )
    .unwrap();
    assert_eq!(scene.geometry.len(), 2);
    let bare = raybench_scene::load(file.to_str().unwrap(), &dir).unwrap();
    assert_eq!(bare.geometry.len(), 2);
    let empty = dir.join("points.ply");
    std::fs::write(&empty, ply(Enc::Ascii, "", &[vertices(&positions)])).unwrap();
    let e = raybench_scene::load(empty.to_str().unwrap(), &dir)
        .map(drop)
        .unwrap_err()
        .to_string();
    assert!(
        e.ends_with("points.ply: no triangles found (is this a mesh file?)"),
        "{e}"
    );
    std::fs::remove_dir_all(dir).ok();
}

/// A record the header does not describe is refused: an ASCII line with more numbers
/// than the properties take, a binary list whose length runs past the file (said so,
/// not "truncated"). Bytes after the last record are a warning (some writers pad files).
#[test]
fn records_the_header_does_not_describe() {
    let (positions, polys) = quad();
    let good = |enc| ply(enc, "", &[vertices(&positions), faces(&polys)]);
    let ascii = String::from_utf8(good(Enc::Ascii)).unwrap();
    let ascii_with = |from: &str, to: &str| ascii.replacen(from, to, 1).into_bytes();
    assert_error(
        &ascii_with("1 0 0\n", "1 0 0 7\n"),
        "vertex 2 (line 11): 4 numbers where the header's properties take 3",
    );
    assert_error(
        &ascii_with("4 0 1 2 3", "4 0 1 2 3 0"),
        "face 1 (line 14): 6 numbers where the header's properties take 5",
    );
    for enc in [Enc::Le, Enc::Be] {
        let mut bytes = good(enc);
        // The face's list length is its record's first byte, 17 bytes before the end.
        let at = bytes.len() - 17;
        assert_eq!(bytes[at], 4);
        bytes[at] = 255;
        let e = error(&bytes);
        assert!(
            e.contains("face 1 (byte ")
                && e.contains(
                    "the file ends inside this record: its list 'vertex_indices' of 255 \
                     entries needs 1020 bytes, 16 are left (a corrupt list length, or a \
                     truncated file)"
                ),
            "{enc:?}: {e}"
        );
        // A record cut short outside a list says "truncated" alone.
        let tail = Element {
            name: "edge",
            decls: vec![Decl::List("uchar", "int", "b"), Decl::Scalar("int", "a")],
            rows: vec![vec![Val::L(vec![1.0, 2.0]), Val::N(1.0)]],
        };
        let mut short = ply(enc, "", &[vertices(&positions), tail]);
        short.truncate(short.len() - 2);
        let e = error(&short);
        assert!(
            e.contains("edge 1 (byte ") && e.ends_with("ends inside this record (truncated)"),
            "{e}"
        );
        // Trailing bytes: loaded, with a warning.
        let mut padded = good(enc);
        padded.extend_from_slice(b"\0\0\0junk");
        let m = load(&padded).unwrap();
        assert_eq!(m.mesh.indices.len(), 2);
        assert!(
            m.warnings
                .iter()
                .any(|w| w.starts_with("t.ply: 7 bytes after the last record")),
            "{:?}",
            m.warnings
        );
        assert!(load(&good(enc)).unwrap().warnings.is_empty());
    }
    let mut trailing = ascii.clone();
    trailing += "\n  \n1 2 3\n";
    let m = load(trailing.as_bytes()).unwrap();
    assert!(
        m.warnings
            .iter()
            .any(|w| w.contains("1 non-blank line after the last record")),
        "{:?}",
        m.warnings
    );
    // Blank lines at the end are no warning.
    let m = load(format!("{ascii}\n\n").as_bytes()).unwrap();
    assert!(m.warnings.is_empty(), "{:?}", m.warnings);
}
