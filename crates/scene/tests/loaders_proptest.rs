//! Property tests of the loaders on generated inputs: structured generators assemble
//! valid-ish OBJ, TOML scene, `.bpt`, glTF (JSON and GLB) and raw volume inputs with random
//! counts, indices and numbers (NaN, infinities, huge, negative, out of range). Each
//! loader must return a `Result` without panicking, and whatever loads must be finite and
//! within the limits of `raybench_core::limits`.
//!
//! Deterministic: a fixed seed with the ChaCha generator and no failure files, so CI runs
//! the same cases every time.

use crate::ply_writer::{Decl, ENCODINGS, Element, Val, header_len, ply};
use base64::Engine as _;
use proptest::prelude::*;
use proptest::test_runner::{RngAlgorithm, RngSeed};
use raybench_core::limits::{MAX_BEZIER_PATCHES, MAX_PRIMITIVES, MAX_VOLUME_VOXELS};
use raybench_core::{Affine3A, TransferFunction, Vec3, Volume, VolumeData, VolumeParams};
use raybench_scene::samples::{RawSamples, SampleFormat, decode_raw};
use raybench_scene::{
    LoadError, MeshData, load_gltf_bytes, load_obj_bytes, load_ply_bytes, load_scene_str, parse_bpt,
};
use std::path::Path;

/// Generated inputs per loader.
const CASES: u32 = 2048;

/// The fixed configuration: `cases` cases from a fixed seed, no failure persistence.
fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        failure_persistence: None,
        rng_algorithm: RngAlgorithm::ChaCha,
        rng_seed: RngSeed::Fixed(0x7261_7962_656e_6368),
        max_shrink_iters: 2048,
        ..ProptestConfig::default()
    }
}

/// Runs `check` on `cases` generated inputs (shrinking any failure to a minimal input) and
/// returns how many of them loaded: `check` returns whether its input loaded. Callers
/// assert that enough did, so the generators keep reaching the loaders' success paths.
fn run_cases<S: Strategy>(
    cases: u32,
    strategy: S,
    check: impl Fn(S::Value) -> Result<bool, TestCaseError>,
) -> u32 {
    let loaded = std::cell::Cell::new(0);
    let mut runner = proptest::test_runner::TestRunner::new(config(cases));
    let result = runner.run(&strategy, |v| {
        if check(v)? {
            loaded.set(loaded.get() + 1);
        }
        Ok(())
    });
    if let Err(e) = result {
        panic!("{e}");
    }
    eprintln!("{} of {cases} generated inputs loaded", loaded.get());
    loaded.get()
}

/// Noise levels: 0 gives well-formed inputs (numbers finite and in range, indices valid),
/// 1 a few malformed values, 2 many. Each case draws its level first.
fn level() -> impl Strategy<Value = u8> {
    prop_oneof![2 => Just(0u8), 2 => Just(1), 1 => Just(2)]
}

/// A number that no loader should accept where a finite one is needed.
fn special() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("nan"),
        Just("inf"),
        Just("-inf"),
        Just("1e30"),
        Just("-3.0e38"),
        Just("1e39"),
        Just("1e300"),
        Just("1e-45"),
        Just("0.0"),
    ]
    .prop_map(str::to_owned)
}

/// A number as text: in `lo..hi` at level 0; at higher levels sometimes out of that range,
/// NaN, infinite, huge, tiny or overflowing f32.
fn num(level: u8, lo: f64, hi: f64) -> BoxedStrategy<String> {
    let ok = (lo..hi).prop_map(|x| format!("{x:?}"));
    if level == 0 {
        return ok.boxed();
    }
    let w = if level == 1 { 60 } else { 6 };
    prop_oneof![
        w => ok,
        1 => (-4.0f64..4.0).prop_map(|x| format!("{x:?}")),
        1 => special(),
    ]
    .boxed()
}

fn triple(level: u8) -> BoxedStrategy<String> {
    [
        num(level, -4.0, 4.0),
        num(level, -4.0, 4.0),
        num(level, -4.0, 4.0),
    ]
    .prop_map(|[a, b, c]| format!("{a} {b} {c}"))
    .boxed()
}

/// An OBJ index into `n` vertices: valid (absolute or relative) at level 0; at higher
/// levels sometimes zero, out of range or huge.
fn obj_index(level: u8, n: i64) -> BoxedStrategy<i64> {
    let ok = prop_oneof![1..=n, -n..=-1];
    if level == 0 {
        return ok.boxed();
    }
    let w = if level == 1 { 60 } else { 6 };
    prop_oneof![
        w => ok,
        2 => -12i64..14,
        1 => prop_oneof![
            Just(1_000_000_000_000),
            Just(-1_000_000_000_000),
            Just(i64::MAX),
            Just(i64::MIN),
            Just(i64::from(u32::MAX) + 2),
        ],
    ]
    .boxed()
}

fn obj_vertex_ref(level: u8, n: i64) -> impl Strategy<Value = String> {
    (
        obj_index(level, n),
        proptest::option::of(obj_index(level, 1)),
        proptest::option::of(obj_index(level, 1)),
    )
        .prop_map(|(v, t, n)| match (t, n) {
            (None, None) => format!("{v}"),
            (Some(t), None) => format!("{v}/{t}"),
            (t, Some(n)) => format!("{v}/{}/{n}", t.map_or(String::new(), |t| t.to_string())),
        })
}

/// A line that is not a vertex or face: other elements, statements and garbage.
fn obj_extra_line(level: u8) -> impl Strategy<Value = String> {
    prop_oneof![
        1 => (triple(level), num(level, 0.5, 2.0)).prop_map(|(p, w)| format!("v {p} {w}")),
        1 => (num(level, -1.0, 1.0), num(level, -1.0, 1.0)).prop_map(|(a, b)| format!("v {a} {b}")),
        1 => proptest::collection::vec(obj_vertex_ref(level, 3), 1..3)
            .prop_map(|f| format!("l {}", f.join(" "))),
        1 => Just("o part".to_owned()),
        1 => Just("g group".to_owned()),
        1 => Just("usemtl shiny".to_owned()),
        1 => Just("mtllib absent.mtl".to_owned()),
        1 => Just("s 1".to_owned()),
        1 => Just("# comment".to_owned()),
        1 => "[a-z0-9 ./-]{0,12}",
    ]
}

/// An OBJ file: `n` vertices with a normal and a texture coordinate, faces of three to
/// five corners, and at levels 1 and 2 extra lines inserted anywhere.
fn obj_text() -> impl Strategy<Value = String> {
    (level(), 3i64..9).prop_flat_map(|(level, n)| {
        let extras = if level == 0 { 0..1 } else { 0..6 };
        (
            proptest::collection::vec(triple(level), n as usize),
            proptest::collection::vec(
                proptest::collection::vec(obj_vertex_ref(level, n), 3..6),
                1..6,
            ),
            proptest::collection::vec(
                (any::<prop::sample::Index>(), obj_extra_line(level)),
                extras,
            ),
        )
            .prop_map(|(vertices, faces, extras)| {
                let mut lines: Vec<String> = vec!["vt 0 0".into(), "vn 0 0 1".into()];
                lines.extend(vertices.iter().map(|p| format!("v {p}")));
                lines.extend(faces.iter().map(|f| format!("f {}", f.join(" "))));
                for (at, line) in extras {
                    lines.insert(at.index(lines.len() + 1), line);
                }
                lines.join("\n")
            })
    })
}

/// What every loaded mesh must satisfy; whether `loaded` holds a mesh with triangles.
fn check_mesh(loaded: Result<MeshData, LoadError>) -> Result<bool, TestCaseError> {
    let Ok(m) = loaded else {
        return Ok(false);
    };
    prop_assert!(m.mesh.validate().is_ok(), "{:?}", m.mesh.validate());
    prop_assert!(m.mesh.positions.iter().all(|p| p.is_finite()));
    prop_assert!(m.mesh.indices.len() <= MAX_PRIMITIVES);
    prop_assert_eq!(m.triangle_material.len(), m.mesh.indices.len());
    for id in m.triangle_material.iter().flatten() {
        prop_assert!((*id as usize) < m.materials.len());
    }
    Ok(!m.mesh.indices.is_empty())
}

#[test]
fn obj_lines() {
    let loaded = run_cases(CASES, obj_text(), |text| {
        check_mesh(load_obj_bytes(text.as_bytes(), Path::new("p.obj")))
    });
    assert!(
        loaded >= CASES / 10,
        "only {loaded} of {CASES} inputs loaded"
    );
}
/// At level 0 `None`; at levels 1 and 2 sometimes (rarely, often) `Some` value of `bad`:
/// a replacement for one well-formed field.
fn maybe<T: std::fmt::Debug + Clone + 'static>(
    level: u8,
    bad: impl Strategy<Value = T> + 'static,
) -> BoxedStrategy<Option<T>> {
    match level {
        0 => Just(None).boxed(),
        1 => prop_oneof![24 => Just(None), 1 => bad.prop_map(Some)].boxed(),
        _ => prop_oneof![3 => Just(None), 1 => bad.prop_map(Some)].boxed(),
    }
}

/// A `.bpt` file: the count line and patches of `3 3` and 16 points; at levels 1 and 2 a
/// wrong, huge or garbage count, other degrees, missing or extra points, points of two or
/// four numbers.
fn bpt_text() -> impl Strategy<Value = (String, usize)> {
    level().prop_flat_map(|level| {
        let point = (
            triple(level),
            maybe(
                level,
                prop_oneof![
                    Just("1 2".to_owned()),
                    Just("1 2 3 4".to_owned()),
                    Just("a b c".to_owned())
                ],
            ),
        )
            .prop_map(|(p, bad)| bad.unwrap_or(p));
        let patch = (
            maybe(
                level,
                prop_oneof![Just("2 3"), Just("3"), Just("3 3 3"), Just("x y")],
            ),
            proptest::collection::vec(point, 16),
            maybe(level, 0usize..18),
        )
            .prop_map(|(degrees, mut points, keep)| {
                points.truncate(keep.unwrap_or(16));
                (degrees.unwrap_or("3 3"), points)
            });
        (
            proptest::collection::vec(patch, 1..4),
            maybe(level, 0usize..6),
            maybe(
                level,
                prop_oneof![Just("1000000000000"), Just("-1"), Just("x"), Just("")],
            ),
        )
            .prop_map(|(patches, count, bad_count)| {
                let declared = count.unwrap_or(patches.len());
                let mut s = format!(
                    "{}\n",
                    bad_count.map_or(declared.to_string(), str::to_owned)
                );
                for (degrees, points) in &patches {
                    s += degrees;
                    s.push('\n');
                    for p in points {
                        s += p;
                        s.push('\n');
                    }
                }
                (s, declared)
            })
    })
}

#[test]
fn bpt_files() {
    let loaded = run_cases(CASES, bpt_text(), |(text, declared)| {
        let Ok(patches) = parse_bpt(&text, Path::new("p.bpt")) else {
            return Ok(false);
        };
        prop_assert_eq!(patches.len(), declared);
        prop_assert!((1..=MAX_BEZIER_PATCHES).contains(&patches.len()));
        for p in &patches {
            prop_assert!(p.points.iter().all(|q| q.is_finite()));
        }
        Ok(true)
    });
    assert!(
        loaded >= CASES / 20,
        "only {loaded} of {CASES} inputs loaded"
    );
}
/// A TOML array of three numbers in `lo..hi` (at level 0).
fn v3(level: u8, lo: f64, hi: f64) -> BoxedStrategy<String> {
    [num(level, lo, hi), num(level, lo, hi), num(level, lo, hi)]
        .prop_map(|[a, b, c]| format!("[{a}, {b}, {c}]"))
        .boxed()
}

fn transform(level: u8) -> impl Strategy<Value = String> {
    prop_oneof![
        3 => Just(String::new()),
        1 => (num(level, 0.5, 2.0), v3(level, -90.0, 90.0), v3(level, -4.0, 4.0)).prop_map(
            |(s, r, t)| format!("transform = {{ scale = {s}, rotate = {r}, translate = {t} }}\n")
        ),
        1 => v3(level, 0.5, 2.0).prop_map(|s| format!("transform = {{ scale = {s} }}\n")),
    ]
}

fn material_ref(level: u8) -> impl Strategy<Value = String> {
    (
        prop_oneof![2 => Just(""), 1 => Just("material = \"a\"\n")],
        maybe(level, Just("material = \"missing\"\n")),
    )
        .prop_map(|(m, bad)| bad.unwrap_or(m).to_owned())
}

/// A generator spec: small arguments of known generators; at levels 1 and 2 unknown names,
/// zero, huge, negative and malformed arguments.
fn generator_spec(level: u8) -> impl Strategy<Value = String> {
    (
        prop_oneof![
            Just("spheres"),
            Just("soup"),
            Just("icosphere"),
            Just("terrain")
        ],
        1u64..4,
        maybe(
            level,
            prop_oneof![Just("heightfield"), Just("bogus"), Just("")],
        ),
        maybe(
            level,
            prop_oneof![
                Just("0"),
                Just("1000000000000"),
                Just("-3"),
                Just("x"),
                Just("")
            ],
        ),
    )
        .prop_map(|(g, n, bad_name, bad_n)| {
            format!(
                "{}:{}",
                bad_name.unwrap_or(g),
                bad_n.map_or(n.to_string(), str::to_owned)
            )
        })
}

fn object(level: u8) -> impl Strategy<Value = String> {
    let body = prop_oneof![
        4 => (v3(level, -4.0, 4.0), num(level, 0.1, 2.0)).prop_map(|(c, r)| {
            format!("kind = \"sphere\"\ncenter = {c}\nradius = {r}\n")
        }),
        1 => (v3(level, -4.0, 4.0), v3(level, 0.5, 1.0))
            .prop_map(|(p, n)| format!("kind = \"plane\"\npoint = {p}\nnormal = {n}\n")),
        3 => (v3(level, -4.0, 4.0), v3(level, -4.0, 4.0), v3(level, -4.0, 4.0)).prop_map(
            |(a, b, c)| format!("kind = \"triangle\"\nvertices = [{a}, {b}, {c}]\n")
        ),
        2 => (3usize..6).prop_flat_map(move |n| {
            let index = match level {
                0 => (0..n as i64).boxed(),
                _ => prop_oneof![12 => 0..n as i64, 1 => -2i64..9].boxed(),
            };
            (
                proptest::collection::vec(v3(level, -4.0, 4.0), n),
                proptest::collection::vec(proptest::collection::vec(index, 3..5), 1..3),
            )
        })
        .prop_map(|(p, f)| {
            let faces: Vec<String> = f.iter().map(|f| format!("{f:?}")).collect();
            format!(
                "kind = \"polygons\"\npositions = [{}]\nfaces = [{}]\n",
                p.join(", "),
                faces.join(", ")
            )
        }),
        2 => generator_spec(level).prop_map(|s| format!("kind = \"generator\"\nspec = \"{s}\"\n")),
        1 => (2usize..4, 2usize..4, maybe(level, 0usize..3)).prop_flat_map(move |(r, c, short)| {
            proptest::collection::vec(proptest::collection::vec(num(level, 0.0, 1.0), c), r)
                .prop_map(move |mut rows| {
                    if let Some(k) = short {
                        rows[0].truncate(k);
                    }
                    let rows: Vec<String> = rows.iter().map(|r| format!("[{}]", r.join(", "))).collect();
                    format!("kind = \"height_field\"\nheights = [{}]\n", rows.join(", "))
                })
        }),
        1 => (v3(level, -4.0, 4.0), num(level, 1.0, 2.0), num(level, 0.1, 0.9)).prop_map(
            |(c, a, b)| {
                format!(
                    "kind = \"torus\"\ncenter = {c}\nmajor_radius = {a}\nminor_radius = {b}\n"
                )
            }
        ),
        1 => (v3(level, 0.5, 2.0), num(level, 0.5, 2.0)).prop_map(|(a, r)| {
            format!(
                "kind = \"csg\"\ntree = {{ type = \"difference\", operands = [\
                 {{ type = \"box\", min = [-1, -1, -1], max = {a} }}, \
                 {{ type = \"sphere\", center = [0, 0, 0], radius = {r} }}] }}\n"
            )
        }),
    ];
    (body, material_ref(level), transform(level))
        .prop_map(|(b, m, t)| format!("[[object]]\n{b}{m}{t}"))
}

/// A scene file: background, camera, materials, lights, objects and maybe a volume, each
/// drawn at the case's level.
fn scene_text() -> impl Strategy<Value = String> {
    level().prop_flat_map(|level| {
        let camera = prop_oneof![
            1 => Just(String::new()),
            1 => (v3(level, 3.0, 6.0), v3(level, -1.0, 1.0), num(level, 20.0, 90.0)).prop_map(
                |(p, l, f)| format!("[camera]\nposition = {p}\nlook_at = {l}\nfov = {f}\n")
            ),
        ];
        let material = (
            prop_oneof![Just("a"), Just("b")],
            prop_oneof![Just("diffuse"), Just("mirror"), Just("glass")],
            maybe(level, Just("metal")),
            v3(level, 0.0, 1.0),
            num(level, 1.0, 2.0),
        )
            .prop_map(|(n, k, bad, c, ior)| {
                let k = bad.unwrap_or(k);
                format!("[[material]]\nname = \"{n}\"\nkind = \"{k}\"\ncolor = {c}\nior = {ior}\n")
            });
        let light = prop_oneof![
            (v3(level, -4.0, 4.0), v3(level, 0.0, 4.0)).prop_map(|(p, i)| {
                format!("[[light]]\nkind = \"point\"\nposition = {p}\nintensity = {i}\n")
            }),
            (v3(level, 0.5, 1.0), v3(level, 0.0, 4.0)).prop_map(|(d, r)| {
                format!("[[light]]\nkind = \"directional\"\ndirection = {d}\nradiance = {r}\n")
            }),
        ];
        let volume = prop_oneof![
            4 => Just(String::new()),
            1 => (
                prop_oneof![Just("1"), Just("2"), Just("3")],
                maybe(level, prop_oneof![Just("0"), Just("513"), Just("1000000000000")]),
            )
                .prop_map(|(n, bad)| {
                    format!("[[volume]]\nsource = \"phantom:{}\"\n", bad.unwrap_or(n))
                }),
        ];
        (
            proptest::option::of(v3(level, 0.0, 1.0)),
            camera,
            proptest::collection::vec(material, 0..3),
            proptest::collection::vec(light, 0..3),
            proptest::collection::vec(object(level), 1..5),
            volume,
        )
            .prop_map(|(bg, cam, mats, lights, objects, volume)| {
                let mut s = bg.map_or(String::new(), |b| format!("background = {b}\n"));
                s += &cam;
                for part in mats.iter().chain(&lights).chain(&objects) {
                    s += part;
                }
                s + &volume
            })
    })
}

#[test]
fn toml_scenes() {
    let loaded = run_cases(CASES, scene_text(), |text| {
        let loaded = load_scene_str(&text, "p", None, Path::new("/nonexistent-assets"));
        let Ok(scene) = loaded else {
            return Ok(false);
        };
        prop_assert!(scene.geometry.len() <= MAX_PRIMITIVES);
        prop_assert_eq!(scene.prim_material.len(), scene.geometry.len());
        prop_assert!(
            scene
                .prim_material
                .iter()
                .all(|&m| (m as usize) < scene.materials.len())
        );
        prop_assert!(scene.camera.is_valid());
        for shape in scene.geometry.shapes() {
            if let Some(b) = shape.bounds() {
                prop_assert!(b.min.is_finite() && b.max.is_finite(), "{:?}", b);
            }
        }
        for v in &scene.volumes {
            let [x, y, z] = v.dims();
            prop_assert!(u64::from(x) * u64::from(y) * u64::from(z) <= MAX_VOLUME_VOXELS);
        }
        Ok(!scene.geometry.is_empty())
    });
    assert!(
        loaded >= CASES / 10,
        "only {loaded} of {CASES} inputs loaded"
    );
}
/// A float sample: ordinary, or at levels 1 and 2 sometimes NaN, infinite or huge.
fn sample(level: u8) -> BoxedStrategy<f32> {
    (
        -3.0f32..3.0,
        maybe(
            level,
            prop_oneof![
                Just(f32::NAN),
                Just(f32::INFINITY),
                Just(f32::MAX),
                Just(2.0e18f32)
            ],
        ),
    )
        .prop_map(|(x, bad)| bad.unwrap_or(x))
        .boxed()
}

/// Replacements for a buffer view's offset, length and stride.
type ViewOverride = (Option<u64>, Option<u64>, Option<u32>);
/// Replacements for an accessor's component type, element type, count and offset.
type AccessorOverride = (Option<u32>, Option<&'static str>, Option<u64>, Option<u64>);

/// The fields of a glTF file that the generator varies; well-formed values first, each
/// replaced by a malformed one at levels 1 and 2.
#[derive(Clone, Debug)]
struct GltfParts {
    floats: Vec<f32>,
    indices: Vec<u16>,
    glb: bool,
    child: bool,
    indexed: bool,
    buffer_length: Option<u64>,
    /// Offset, length and stride of the positions' and the indices' views.
    views: [ViewOverride; 2],
    /// Component type, element type, count and offset of the two accessors.
    accessors: [AccessorOverride; 2],
    mode: Option<u32>,
    translation: Option<&'static str>,
    cut: Option<usize>,
}

fn gltf_parts() -> impl Strategy<Value = GltfParts> {
    (level(), 1usize..4).prop_flat_map(|(level, triangles)| {
        let n = 3 * triangles;
        let huge = || {
            prop_oneof![
                Just(1u64 << 40),
                Just(1_000_000_000_000_000),
                Just(u64::from(u32::MAX))
            ]
        };
        let view = || {
            (
                maybe(level, prop_oneof![0u64..48, huge()]),
                maybe(level, prop_oneof![0u64..64, huge()]),
                maybe(
                    level,
                    prop_oneof![Just(4u32), Just(12), Just(16), Just(252)],
                ),
            )
        };
        let accessor = || {
            (
                maybe(
                    level,
                    prop_oneof![Just(5123u32), Just(5125), Just(5121), Just(7)],
                ),
                maybe(
                    level,
                    prop_oneof![Just("SCALAR"), Just("VEC2"), Just("VEC3")],
                ),
                maybe(level, prop_oneof![0u64..8, huge()]),
                maybe(level, prop_oneof![1u64..16, huge()]),
            )
        };
        (
            (
                proptest::collection::vec(sample(level), 3 * n),
                proptest::collection::vec(0..n as u16, n),
                any::<bool>(),
                any::<bool>(),
                any::<bool>(),
            ),
            (
                maybe(level, prop_oneof![0u64..80, huge()]),
                [view(), view()],
                [accessor(), accessor()],
                maybe(level, prop_oneof![Just(0u32), Just(5), Just(9)]),
                maybe(
                    level,
                    prop_oneof![Just("[1e39, 0, 0]"), Just("[-3e38, 0, 0]")],
                ),
                maybe(level, 1usize..40),
            ),
        )
            .prop_map(
                |(
                    (floats, indices, glb, child, indexed),
                    (buffer_length, views, accessors, mode, translation, cut),
                )| GltfParts {
                    floats,
                    indices,
                    glb,
                    child,
                    indexed,
                    buffer_length,
                    views,
                    accessors,
                    mode,
                    translation,
                    cut,
                },
            )
    })
}

/// A glTF file, as JSON with a data URI or as GLB with a binary chunk: one mesh of one
/// primitive (positions, then u16 indices, in one buffer), on one node or on a node and
/// its child.
fn gltf_file() -> impl Strategy<Value = Vec<u8>> {
    gltf_parts().prop_map(|p| {
        let mut bin: Vec<u8> = p.floats.iter().flat_map(|f| f.to_le_bytes()).collect();
        let positions_len = bin.len() as u64;
        bin.extend(p.indices.iter().flat_map(|i| i.to_le_bytes()));
        let buffer_length = p.buffer_length.unwrap_or(bin.len() as u64);
        let uri = if p.glb {
            String::new()
        } else {
            format!(
                r#""uri": "data:application/octet-stream;base64,{}", "#,
                base64::engine::general_purpose::STANDARD.encode(&bin)
            )
        };
        let good_views = [
            (0, positions_len),
            (positions_len, bin.len() as u64 - positions_len),
        ];
        let views: Vec<String> = p
            .views
            .iter()
            .zip(good_views)
            .map(|(&(offset, length, stride), (o, l))| {
                let stride = stride.map_or(String::new(), |s| format!(r#", "byteStride": {s}"#));
                format!(
                    r#"{{"buffer": 0, "byteOffset": {}, "byteLength": {}{stride}}}"#,
                    offset.unwrap_or(o),
                    length.unwrap_or(l)
                )
            })
            .collect();
        let good_accessors = [
            (5126, "VEC3", p.floats.len() as u64 / 3),
            (5123, "SCALAR", p.indices.len() as u64),
        ];
        let accessors: Vec<String> = p
            .accessors
            .iter()
            .zip(good_accessors)
            .enumerate()
            .map(|(i, (&(ct, ty, count, offset), (c, t, n)))| {
                // glTF requires the bounds of positions (the loader does not use them).
                let bounds = if i == 0 {
                    r#""min": [-3, -3, -3], "max": [3, 3, 3], "#
                } else {
                    ""
                };
                format!(
                    r#"{{"bufferView": {i}, "componentType": {}, "count": {}, {bounds}
                    "byteOffset": {}, "type": "{}"}}"#,
                    ct.unwrap_or(c),
                    count.unwrap_or(n),
                    offset.unwrap_or(0),
                    ty.unwrap_or(t)
                )
            })
            .collect();
        let indices = if p.indexed { r#", "indices": 1"# } else { "" };
        let translation = p.translation.unwrap_or("[0, 0, 5]");
        let nodes = if p.child {
            format!(
                r#"[{{"mesh": 0, "translation": {translation}, "children": [1]}},
                {{"mesh": 0, "scale": [2, 2, 2]}}]"#
            )
        } else {
            format!(r#"[{{"mesh": 0, "translation": {translation}}}]"#)
        };
        let json = format!(
            r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
            "nodes": {nodes},
            "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}{indices},
                "mode": {}}}]}}],
            "buffers": [{{{uri}"byteLength": {buffer_length}}}],
            "bufferViews": [{}],
            "accessors": [{}]}}"#,
            p.mode.unwrap_or(4),
            views.join(", "),
            accessors.join(", ")
        );
        if !p.glb {
            return json.into_bytes();
        }
        let mut j = json.into_bytes();
        while !j.len().is_multiple_of(4) {
            j.push(b' ');
        }
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let total = 12 + 8 + j.len() + 8 + bin.len();
        let mut out = b"glTF".to_vec();
        for n in [2, total, j.len()] {
            out.extend_from_slice(&(n as u32).to_le_bytes());
        }
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&j);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
        if let Some(cut) = p.cut {
            out.truncate(out.len().saturating_sub(cut));
        }
        out
    })
}

#[test]
fn gltf_files() {
    let loaded = run_cases(CASES, gltf_file(), |bytes| {
        // External URIs (none here) would resolve against a folder that does not exist.
        check_mesh(load_gltf_bytes(
            &bytes,
            Path::new("/nonexistent-dir/p.gltf"),
        ))
    });
    assert!(
        loaded >= CASES / 20,
        "only {loaded} of {CASES} inputs loaded"
    );
}
/// Raw volume bytes: dims (small, zero or huge), a format, and samples of exactly the
/// right length (floats with NaN and infinities) or of a random length.
fn raw_volume() -> impl Strategy<Value = ([u32; 3], SampleFormat, Vec<u8>)> {
    let dim = prop_oneof![8 => 0u32..4, 1 => Just(1_000_000), 1 => Just(u32::MAX)];
    let format = prop_oneof![
        Just(SampleFormat::U8),
        Just(SampleFormat::U16),
        Just(SampleFormat::F32)
    ];
    (
        [dim.clone(), dim.clone(), dim],
        format,
        proptest::collection::vec(sample(1), 0..64),
        proptest::collection::vec(any::<u8>(), 0..64),
        any::<bool>(),
    )
        .prop_map(|(dims, format, floats, noise, exact)| {
            let count = dims.iter().map(|&d| u128::from(d)).product::<u128>();
            let bytes = if exact && count <= 27 {
                let count = count as u64;
                let n = (count * format.bytes()) as usize;
                let mut b: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
                b.resize(n, 7);
                b
            } else {
                noise
            };
            (dims, format, bytes)
        })
}

#[test]
fn raw_volumes() {
    let loaded = run_cases(CASES, raw_volume(), |(dims, format, bytes)| {
        let Ok(count) = raybench_core::voxels::check_volume_dims(dims) else {
            return Ok(false);
        };
        prop_assert!(count <= MAX_VOLUME_VOXELS);
        let Ok(samples) = decode_raw(&bytes, count, format, MAX_VOLUME_VOXELS, Path::new("p.raw"))
        else {
            return Ok(false);
        };
        prop_assert_eq!(bytes.len() as u64, count * format.bytes());
        if let RawSamples::F32(d) = &samples {
            prop_assert!(d.iter().all(|x| x.is_finite()));
        }
        let v = Volume::new(
            dims,
            Vec3::ONE,
            VolumeData::from(samples),
            Affine3A::IDENTITY,
            TransferFunction::ramp(10.0),
            VolumeParams::default(),
        );
        let Ok(v) = v else {
            return Ok(false);
        };
        prop_assert_eq!(v.dims(), dims);
        prop_assert!(v.voxel([0, 0, 0]).is_finite());
        Ok(true)
    });
    assert!(
        loaded >= CASES / 20,
        "only {loaded} of {CASES} inputs loaded"
    );
}

/// The PLY scalar types.
const PLY_TYPES: [&str; 8] = [
    "char", "uchar", "short", "ushort", "int", "uint", "float", "double",
];

/// A PLY number: in `lo..hi` at level 0; at higher levels sometimes NaN, infinite, huge or
/// beyond f32 (cast to the property's type by the writer: integers saturate).
fn ply_num(level: u8, lo: f64, hi: f64) -> BoxedStrategy<f64> {
    let bad = prop_oneof![
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(-1e30),
        Just(1e39),
        Just(1e300),
        Just(-1.0),
        Just(4e9),
    ];
    (lo..hi, maybe(level, bad))
        .prop_map(|(ok, bad)| bad.unwrap_or(ok))
        .boxed()
}

/// How a generated PLY file is spoilt after writing, at levels 1 and 2.
#[derive(Clone, Debug)]
enum Spoil {
    /// Cut at this share of its length.
    Truncate(prop::sample::Index),
    /// One byte replaced.
    Byte(prop::sample::Index, u8),
    /// The first element's declared count changed to this.
    Count(u64),
}

/// A PLY file in a random encoding: `n` vertices of a random coordinate type (sometimes
/// with normals and texture coordinates), faces of three to six corners with random integer
/// list types, sometimes an ignored element with a list, faces first or last; at levels 1
/// and 2 bad numbers and indices, and a truncated, altered or miscounted file. With it, the
/// number of triangles it makes when it loads and is not spoilt.
fn ply_file() -> impl Strategy<Value = (Vec<u8>, Option<usize>)> {
    (level(), 3usize..9).prop_flat_map(|(level, n)| {
        let bad_index = prop_oneof![Just(-1i64), Just(9), Just(1 << 40)];
        let index = (0..n as u32, maybe(level, bad_index))
            .prop_map(|(ok, bad)| bad.map_or(f64::from(ok), |b| b as f64));
        let coordinate = || ply_num(level, -4.0, 4.0);
        let spoil = prop_oneof![
            any::<prop::sample::Index>().prop_map(Spoil::Truncate),
            (any::<prop::sample::Index>(), any::<u8>()).prop_map(|(i, b)| Spoil::Byte(i, b)),
            prop_oneof![
                Just(0u64),
                Just(2),
                Just(1 << 20),
                Just(1 << 40),
                Just(u64::MAX)
            ]
            .prop_map(Spoil::Count),
        ];
        (
            (0..3usize, 0..8usize, 0..6usize, 0..6usize),
            proptest::collection::vec([coordinate(), coordinate(), coordinate()], n),
            proptest::collection::vec(proptest::collection::vec(index, 3..7), 1..6),
            (any::<bool>(), any::<bool>(), any::<bool>()),
            maybe(level, spoil),
        )
            .prop_map(|(types, coords, faces, flags, spoil)| {
                let (enc, coord, count, index) = types;
                let (attributes, extra, faces_first) = flags;
                let mut decls: Vec<Decl> = ["x", "y", "z"]
                    .map(|a| Decl::Scalar(PLY_TYPES[coord], a))
                    .to_vec();
                if attributes {
                    decls.extend(["nx", "ny", "nz", "s", "t"].map(|a| Decl::Scalar("float", a)));
                }
                let rows = coords
                    .iter()
                    .map(|p| {
                        let mut row: Vec<Val> = p.iter().map(|&c| Val::N(c)).collect();
                        if attributes {
                            row.extend([0.0, 0.0, 1.0, p[0], p[1]].map(Val::N));
                        }
                        row
                    })
                    .collect();
                let triangles = faces.iter().map(|f| f.len() - 2).sum();
                let list = Decl::List(PLY_TYPES[count], PLY_TYPES[index], "vertex_indices");
                let mut elements = vec![
                    Element {
                        name: "vertex",
                        decls,
                        rows,
                    },
                    Element {
                        name: "face",
                        decls: vec![list],
                        rows: faces.into_iter().map(|f| vec![Val::L(f)]).collect(),
                    },
                ];
                if faces_first {
                    elements.reverse();
                }
                if extra {
                    let edge = Element {
                        name: "edge",
                        decls: vec![Decl::Scalar("int", "a"), Decl::List("uchar", "float", "w")],
                        rows: vec![vec![Val::N(1.0), Val::L(vec![0.5, 2.0])]; 2],
                    };
                    elements.insert(1, edge);
                }
                let mut bytes = ply(ENCODINGS[enc], "comment generated\n", &elements);
                match &spoil {
                    None => {}
                    Some(Spoil::Truncate(at)) => bytes.truncate(at.index(bytes.len())),
                    Some(Spoil::Byte(at, b)) => {
                        let at = at.index(bytes.len());
                        bytes[at] = *b;
                    }
                    Some(Spoil::Count(c)) => {
                        let first = &elements[0];
                        let from = format!("element {} {}\n", first.name, first.rows.len());
                        let to = format!("element {} {c}\n", first.name);
                        let end = header_len(&bytes);
                        let header = String::from_utf8_lossy(&bytes[..end]).replacen(&from, &to, 1);
                        bytes = [header.as_bytes(), &bytes[end..]].concat();
                    }
                }
                (bytes, spoil.is_none().then_some(triangles))
            })
    })
}

#[test]
fn ply_files() {
    let loaded = run_cases(CASES, ply_file(), |(bytes, triangles)| {
        let loaded = load_ply_bytes(&bytes, Path::new("p.ply"));
        if let Ok(m) = &loaded {
            let n = m.mesh.positions.len();
            prop_assert!(m.normals.is_empty() || m.normals.len() == n);
            prop_assert!(m.uvs.is_empty() || m.uvs.len() == n);
            prop_assert!(m.normals.iter().all(|v| v.is_finite()));
            prop_assert!(m.uvs.iter().all(|v| v.is_finite()));
            if let Some(t) = triangles {
                prop_assert_eq!(m.mesh.indices.len(), t);
            }
        }
        check_mesh(loaded)
    });
    assert!(
        loaded >= CASES / 4,
        "only {loaded} of {CASES} inputs loaded"
    );
}
