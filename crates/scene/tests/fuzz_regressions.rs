//! Inputs that crashed, hung or exhausted memory in a loader (found by the fuzz targets in
//! `fuzz/` or while writing them), each fixed in the loader: every one must now give an
//! error (or load) quickly. Larger inputs live in `tests/fuzz-regressions/`.

use raybench_scene::{LoadError, load_gltf_bytes, load_obj_bytes, load_scene_str, parse_bpt};
use std::path::Path;

/// The inputs kept as files, loaded by the loader their extension names.
fn load_regression_file(path: &Path) -> Result<(), LoadError> {
    let bytes = std::fs::read(path).unwrap();
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    match ext {
        "obj" => load_obj_bytes(&bytes, path).map(drop),
        "gltf" | "glb" => load_gltf_bytes(&bytes, path).map(drop),
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
        let text = format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n{f}\n");
        let e = load_obj_bytes(text.as_bytes(), Path::new("t.obj"))
            .map(drop)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 6: a vertex index is out of range"),
            "{f}: {e}"
        );
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
