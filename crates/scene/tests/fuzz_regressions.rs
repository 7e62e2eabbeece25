//! Inputs that crashed, hung or exhausted memory in a loader (found by the fuzz targets in
//! `fuzz/` or while writing them), each fixed in the loader: every one must now give an
//! error (or load) quickly. Larger inputs live in `tests/fuzz-regressions/`.

use raybench_scene::{
    LoadError, load_gltf_bytes, load_obj_bytes, load_ply_bytes, load_scene_str, parse_bpt,
};
use std::path::Path;

/// The inputs kept as files, loaded by the loader their extension names.
fn load_regression_file(path: &Path) -> Result<(), LoadError> {
    let bytes = std::fs::read(path).unwrap();
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    match ext {
        "obj" => load_obj_bytes(&bytes, path).map(drop),
        "gltf" | "glb" => load_gltf_bytes(&bytes, path).map(drop),
        "ply" => load_ply_bytes(&bytes, path).map(drop),
        "bpt" => parse_bpt(&String::from_utf8_lossy(&bytes), path).map(drop),
        "toml" => load_scene_str(
            &String::from_utf8_lossy(&bytes),
            "t",
            None,
            Path::new("/nonexistent-assets"),
        )
        .map(drop),
        _ => panic!("{}: unknown regression input", path.display()),
    }
}

#[test]
fn regression_files_load_or_fail_cleanly() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz-regressions");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "md") {
            continue;
        }
        // Ok or Err both pass: a panic, hang or abort is the failure.
        let _ = load_regression_file(&path);
        n += 1;
    }
    assert!(n > 0, "no regression inputs in {}", dir.display());
}

/// Asserts that the face line `f`, after three vertices, a texture coordinate and a normal,
/// is refused as out of range.
fn assert_obj_index_refused(f: &str) {
    let text = format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n{f}\n");
    let e = load_obj_bytes(text.as_bytes(), Path::new("t.obj"))
        .map(drop)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("line 6: a vertex index is out of bounds"),
        "{f}: {e}"
    );
}

/// `tobj` multiplies texture and normal indices unchecked: `f 1//9223372036854775807`
/// overflowed (a panic in debug builds, the test profile). Indices beyond `u32` are now
/// refused before `tobj` sees them.
#[test]
fn obj_huge_normal_and_texture_indices_do_not_overflow() {
    for f in [
        "f 1//9223372036854775807 2//1 3//1",
        "f 1/9223372036854775807 2/1 3/1",
        "f 1/1/4611686018427387904 2/1/1 3/1/1",
    ] {
        assert_obj_index_refused(f);
    }
    // Ordinary relative and absolute indices still load.
    let ok = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 -1//-1\n";
    let m = load_obj_bytes(ok.as_bytes(), Path::new("t.obj")).unwrap();
    assert_eq!(m.mesh.indices.len(), 1);
}

/// A glTF chain of 100,000 nested nodes (node i's only child is node i + 1) overflowed the
/// stack: the node walk recursed once per level. It now keeps its own stack; the chain
/// loads, with every translation applied.
#[test]
fn gltf_deep_node_chain_does_not_overflow_the_stack() {
    use std::fmt::Write as _;
    const N: usize = 100_000;
    let mut nodes = String::new();
    for i in 0..N {
        if i > 0 {
            nodes.push(',');
        }
        if i + 1 < N {
            write!(nodes, r#"{{"children":[{}],"translation":[1,0,0]}}"#, i + 1).unwrap();
        } else {
            nodes.push_str(r#"{"mesh":0}"#);
        }
    }
    // One triangle, no indices, as a data URI (36 bytes of f32: 0,0,0 1,0,0 0,1,0).
    let text = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{nodes}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
        "buffers":[{{"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA","byteLength":36}}],
        "bufferViews":[{{"buffer":0,"byteLength":36}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}]}}"#
    );
    // A 2 MiB stack, as test threads get by default, made explicit.
    let data = std::thread::Builder::new()
        .stack_size(2 << 20)
        .spawn(move || load_gltf_bytes(text.as_bytes(), Path::new("chain.gltf")))
        .unwrap()
        .join()
        .expect("the loader must not overflow the stack")
        .unwrap();
    assert_eq!(data.mesh.indices.len(), 1);
    assert_eq!(data.mesh.positions[0].x, (N - 1) as f32);
}

/// Text files (`.bpt`, scene files) must be regular files: a device that reports length 0
/// and never ends (here `/dev/zero`) was read until memory ran out.
#[test]
fn bezier_file_on_an_endless_device_is_refused() {
    let dev = Path::new("/dev/zero");
    if !dev.exists() {
        return;
    }
    let e = raybench_scene::load_bpt_file(dev).unwrap_err().to_string();
    assert!(e.contains("not a regular file"), "{e}");
}

/// Volume dims multiplied in u64: `[2^22; 3]` wrapped to 0 voxels and passed the limit,
/// `[u32::MAX; 3]` overflowed (a panic in debug builds). Found by the property tests (and
/// the `raw_volume` fuzz target).
#[test]
fn volume_dims_product_does_not_wrap() {
    use raybench_core::SceneError;
    use raybench_core::voxels::check_volume_dims;
    for dims in [[1 << 22; 3], [u32::MAX; 3], [1 << 21, 1 << 21, 1 << 22]] {
        let e = check_volume_dims(dims).unwrap_err();
        assert!(matches!(e, SceneError::TooLarge(_)), "{dims:?}: {e}");
    }
    let text = "[[volume]]\nraw = \"absent.raw\"\ndims = [4194304, 4194304, 4194304]\n";
    let e = load_scene_str(text, "t", None, Path::new("/nonexistent-assets"))
        .map(drop)
        .unwrap_err()
        .to_string();
    assert!(e.contains("exceeds the limit"), "{e}");
    assert_eq!(check_volume_dims([2, 3, 4]).unwrap(), 24);
}

/// A relative texture or normal index reaching before the first element (`vt` count 1,
/// index -5) became a huge index in `tobj`, whose `vt * 2` overflowed (found by the
/// property tests). Such indices are refused before `tobj` sees them.
#[test]
fn obj_relative_index_before_the_first_element_is_refused() {
    for f in ["f 1/-5 2/1 3/1", "f 1//-2 2//1 3//1", "f -4 1 2"] {
        assert_obj_index_refused(f);
    }
    let ok = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-1 2/1 -1/-1\n";
    assert_eq!(
        load_obj_bytes(ok.as_bytes(), Path::new("t.obj"))
            .unwrap()
            .mesh
            .indices
            .len(),
        1
    );
}

/// An OBJ vertex at `1e30` (finite, beyond `MAX_COORDINATE`) was returned by the OBJ loader
/// as it was (found by the property tests); the loader now validates its mesh as the glTF
/// loader does.
#[test]
fn obj_coordinate_beyond_the_limit_is_refused() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 0 1e30\nf 1 2 3\n";
    let e = load_obj_bytes(text.as_bytes(), Path::new("t.obj"))
        .map(drop)
        .unwrap_err()
        .to_string();
    assert!(e.contains("exceeds the coordinate limit"), "{e}");
}

/// The seed inputs of the fuzz targets (`fuzz/seeds/<target>/`) are well-formed: each
/// loads, so fuzzing starts from the loaders' success paths.
#[test]
fn fuzz_seeds_load() {
    let seeds = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/seeds");
    let mut n = 0;
    for target in ["scene_toml", "obj", "gltf", "ply", "bpt", "raw_volume"] {
        for entry in std::fs::read_dir(seeds.join(target)).unwrap() {
            let path = entry.unwrap().path();
            let bytes = std::fs::read(&path).unwrap();
            let text = || String::from_utf8(bytes.clone()).unwrap();
            let loaded = match target {
                "scene_toml" => load_scene_str(&text(), "seed", None, Path::new("/nonexistent"))
                    .map(|s| assert!(s.geometry.total_len() > 0 || !s.volumes.is_empty())),
                "obj" => load_obj_bytes(&bytes, &path).map(|m| assert!(!m.mesh.indices.is_empty())),
                "gltf" => load_gltf_bytes(&bytes, &path)
                    .map(|m| assert!(!m.mesh.indices.is_empty() || !m.shared.is_empty())),
                "ply" => load_ply_bytes(&bytes, &path).map(|m| assert!(!m.mesh.indices.is_empty())),
                "bpt" => parse_bpt(&text(), &path).map(drop),
                _ => {
                    // The raw_volume target's layout: three u32 dims, a format byte, samples.
                    use raybench_scene::samples::{SampleFormat, decode_raw};
                    let dim =
                        |i: usize| u32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap());
                    let dims = [dim(0), dim(1), dim(2)];
                    let format = [SampleFormat::U8, SampleFormat::U16, SampleFormat::F32]
                        [usize::from(bytes[12] % 3)];
                    let count = raybench_core::voxels::check_volume_dims(dims).unwrap();
                    decode_raw(&bytes[13..], count, format, count, &path).map(drop)
                }
            };
            if let Err(e) = loaded {
                panic!("{}: {e}", path.display());
            }
            n += 1;
        }
    }
    assert!(n >= 10, "only {n} seeds");
}

/// The seeds of the fuzz targets for material libraries, environment maps and textures
/// load through their entry points (`raybench_scene::fuzzing`), each into what its target
/// checks: materials for the target's OBJ, a map, a texture. A map's and a texture's first
/// byte chooses the format or the wrap modes; the rest is the file.
#[test]
fn fuzz_seeds_of_materials_and_images_load() {
    use raybench_scene::fuzzing::{decode_texture, load_obj_with_mtl, read_environment_map};
    let seeds = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/seeds");
    let files = |target: &str| -> Vec<(std::path::PathBuf, Vec<u8>)> {
        let mut v: Vec<_> = std::fs::read_dir(seeds.join(target))
            .unwrap()
            .map(|e| {
                let p = e.unwrap().path();
                let bytes = std::fs::read(&p).unwrap();
                (p, bytes)
            })
            .collect();
        v.sort();
        assert!(v.len() >= 2, "{target}: {} seeds", v.len());
        v
    };
    let obj = "mtllib fuzz.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
    for (path, bytes) in files("mtl") {
        let m = load_obj_with_mtl(obj.as_bytes(), &bytes, Path::new("/fuzz/f.obj"))
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert_eq!(m.materials.len(), 2, "{}", path.display());
        assert_eq!(m.textures.len(), 1, "{}", path.display());
        assert!(m.triangle_material[0].is_some(), "{}", path.display());
    }
    let mut formats = [false; 2];
    for (path, bytes) in files("env_map") {
        let hdr = bytes[0] & 1 == 1;
        formats[usize::from(hdr)] = true;
        let name = if hdr { "seed.hdr" } else { "seed.exr" };
        let (w, h, texels, _) = read_environment_map(&bytes[1..], Path::new(name), 1 << 20)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert_eq!(texels.len(), (w * h) as usize);
    }
    assert_eq!(formats, [true; 2], "both map formats have seeds");
    for (path, bytes) in files("texture") {
        let t = decode_texture(&bytes[1..], [raybench_core::Wrap::Repeat; 2], 1 << 20)
            .unwrap()
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(t.width() > 1, "{}", path.display());
    }
}

/// A GLB header declaring a total length below its own 12 bytes made the `gltf` crate
/// subtract with overflow (found by the `gltf` fuzz target; the input is
/// `fuzz-regressions/glb-header-length-underflow.glb`). It is refused first.
#[test]
fn glb_header_length_shorter_than_the_header_is_refused() {
    for length in [0u32, 11] {
        let mut glb = b"glTF".to_vec();
        glb.extend_from_slice(&2u32.to_le_bytes());
        glb.extend_from_slice(&length.to_le_bytes());
        glb.extend_from_slice(&[0; 16]);
        let e = load_gltf_bytes(&glb, Path::new("t.glb"))
            .map(drop)
            .unwrap_err()
            .to_string();
        assert!(e.contains("shorter than the header"), "{e}");
    }
}

/// A primitive whose POSITION names an accessor that does not exist made the `gltf` crate's
/// validation index out of bounds, a panic in every build (found by the `gltf` fuzz
/// target; the input is `fuzz-regressions/gltf-position-accessor-missing.gltf`). The loader
/// checks that index before validating.
#[test]
fn gltf_position_accessor_that_does_not_exist_is_refused() {
    let text = r#"{"asset": {"version": "2.0"},
        "meshes": [{"primitives": [{"attributes": {"POSITION": 5}}]}]}"#;
    let e = load_gltf_bytes(text.as_bytes(), Path::new("t.gltf"))
        .map(drop)
        .unwrap_err()
        .to_string();
    assert!(e.contains("POSITION accessor does not exist"), "{e}");
}
