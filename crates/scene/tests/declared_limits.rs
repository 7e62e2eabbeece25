//! Files that *declare* huge sizes are refused with a clear error before anything of that
//! size is allocated (`crates/core/src/limits.rs`): each test would exhaust memory, or take
//! minutes, if the declared size were believed; here each returns its error at once.

use raybench_core::limits;
use raybench_core::{RenderSettings, SceneError};
use raybench_scene::samples::{SampleFormat, decode_raw};
use raybench_scene::{LoadError, load_gltf_bytes, load_obj_bytes, load_scene_str, parse_bpt};
use std::path::Path;

fn scene(text: &str) -> Result<raybench_core::Scene, LoadError> {
    load_scene_str(text, "t", None, Path::new("/nonexistent-assets"))
}

fn assert_err_contains<T>(r: Result<T, LoadError>, needle: &str) {
    match r {
        Ok(_) => panic!("accepted; expected an error containing '{needle}'"),
        Err(e) => {
            let e = e.to_string();
            assert!(e.contains(needle), "'{e}' does not contain '{needle}'");
        }
    }
}

/// A glTF document of one triangle primitive whose accessors, views and buffer are as
/// given; the buffer is a data URI holding `data` (which may be shorter than declared).
fn gltf(accessor_count: u64, view_length: u64, buffer_length: u64, data: &[u8]) -> String {
    use base64::Engine as _;
    use std::fmt::Write as _;
    let b64 = base64::engine::general_purpose::STANDARD.encode(data);
    let mut s = String::new();
    write!(
        s,
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
        "nodes": [{{"mesh": 0}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
        "buffers": [{{"uri": "data:application/octet-stream;base64,{b64}", "byteLength": {buffer_length}}}],
        "bufferViews": [{{"buffer": 0, "byteLength": {view_length}}}],
        "accessors": [{{"bufferView": 0, "componentType": 5126, "count": {accessor_count},
            "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}}]}}"#
    )
    .unwrap();
    s
}

#[test]
fn gltf_sanity_one_triangle_loads() {
    let mut data = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        data.extend_from_slice(&v.to_le_bytes());
    }
    let m = load_gltf_bytes(gltf(3, 36, 36, &data).as_bytes(), Path::new("t.gltf")).unwrap();
    assert_eq!(m.mesh.indices.len(), 1);
}

#[test]
fn gltf_accessor_count_of_10_12_is_refused() {
    let data = [0u8; 36];
    let text = gltf(1_000_000_000_000, 36, 36, &data);
    assert_err_contains(
        load_gltf_bytes(text.as_bytes(), Path::new("t.gltf")),
        "runs past its buffer view",
    );
}

#[test]
fn gltf_buffer_byte_length_of_10_15_is_refused() {
    let data = [0u8; 36];
    let text = gltf(3, 36, 1_000_000_000_000_000, &data);
    assert_err_contains(
        load_gltf_bytes(text.as_bytes(), Path::new("t.gltf")),
        "the file declares 1000000000000000",
    );
    // The same length on the view and the accessor count to match: still refused by the
    // buffer's real size, before the accessor is read.
    let text = gltf(
        1_000_000_000_000_000 / 12,
        1_000_000_000_000_000,
        1_000_000_000_000_000,
        &data,
    );
    assert_err_contains(
        load_gltf_bytes(text.as_bytes(), Path::new("t.gltf")),
        "the file declares",
    );
}

#[test]
fn obj_indices_of_10_12_are_refused() {
    // OBJ declares no counts: the nearest thing is an index naming vertex 10^12.
    for f in [
        "f 1 2 1000000000000",
        "f 1 2 -1000000000000",
        "f 1/1000000000000 2 3",
        "f 1//1000000000000 2 3",
        "f 1 2 4294967299",
        "f 1/9223372036854775807 2 3",
        "f 1//9223372036854775807 2 3",
        "f 1 2 9223372036854775807",
        "f 1 2 -9223372036854775808",
    ] {
        let text = format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n{f}\n");
        let r = load_obj_bytes(text.as_bytes(), Path::new("t.obj"));
        assert!(r.is_err(), "{f}: accepted");
    }
}

#[test]
fn bpt_with_10_12_patches_is_refused() {
    assert_err_contains(
        parse_bpt("1000000000000\n3 3\n", Path::new("t.bpt")),
        "1000000000000 patches declared",
    );
}

#[test]
fn raw_volume_of_10_6_cubed_voxels_is_refused() {
    let e = raybench_core::voxels::check_volume_dims([1_000_000; 3]).unwrap_err();
    assert!(matches!(e, SceneError::TooLarge(_)), "{e}");
    // The raw decoder checks a count against the limit before looking at the bytes.
    assert_err_contains(
        decode_raw(
            &[],
            1_000_000_000_000_000_000,
            SampleFormat::F32,
            limits::MAX_VOLUME_VOXELS,
            Path::new("v.raw"),
        ),
        "exceed the limit",
    );
    // And a scene file naming such a volume is refused before its file is looked for.
    assert_err_contains(
        scene("[[volume]]\nraw = \"absent.raw\"\ndims = [1000000, 1000000, 1000000]\n"),
        "exceeds the limit",
    );
    // A raw height field of 10^9 x 10^9 samples (its file holds 2 bytes): refused from
    // the declared size, before the file is read.
    let raw = std::env::temp_dir().join(format!("raybench-limits-{}.raw", std::process::id()));
    std::fs::write(&raw, [0u8, 0]).unwrap();
    assert_err_contains(
        scene(&format!(
            "[[object]]\nkind = \"height_field\"\nraw = \"{}\"\n\
             size = [1000000000, 1000000000]\n",
            raw.display()
        )),
        "exceed the limit",
    );
    std::fs::remove_file(raw).ok();
}

#[test]
fn generator_of_10_12_spheres_is_refused() {
    for spec in [
        "spheres:1000000000000",
        "soup:1000000000000",
        "icosphere:1000000000000",
        "terrain:1000000000000",
    ] {
        let text = format!("[[object]]\nkind = \"generator\"\nspec = \"{spec}\"\n");
        assert_err_contains(scene(&text), "must be in");
    }
    assert_err_contains(
        raybench_scene::load("spheres:1000000000000", Path::new("/nonexistent-assets")),
        "must be in",
    );
    // The phantom volume likewise.
    assert_err_contains(
        scene("[[volume]]\nsource = \"phantom:1000000\"\n"),
        "N must be in",
    );
}

#[test]
fn resolution_of_10_9_squared_is_refused() {
    let s = RenderSettings {
        width: 1_000_000_000,
        height: 1_000_000_000,
        ..RenderSettings::default()
    };
    let e = s.validate().unwrap_err().to_string();
    assert!(e.contains("exceeds the limit"), "{e}");
}
