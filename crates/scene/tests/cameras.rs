//! glTF cameras: perspective cameras placed by their nodes' world transforms
//! become the scene's named cameras; orthographic ones are skipped with a warning.

use raybench_core::Vec3;
use raybench_scene::load_gltf_bytes;
use std::path::Path;

/// One triangle, a perspective camera on a translated and rotated node (a child of a
/// translated parent), a second one without a name, and an orthographic camera.
fn gltf_with_cameras() -> String {
    use base64::Engine as _;
    let mut bin = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    let b64 = base64::engine::general_purpose::STANDARD.encode(&bin);
    // Node 2 turns 90 degrees about +y (quaternion [0, sin 45, 0, cos 45]): its -z looks
    // along world -x.
    let h = std::f32::consts::FRAC_1_SQRT_2;
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0,
        "scenes": [{{"nodes": [0, 1, 3]}}],
        "nodes": [
          {{"mesh": 0}},
          {{"translation": [0, 0, 10], "children": [2]}},
          {{"camera": 0, "translation": [5, 1, 0], "rotation": [0, {h}, 0, {h}]}},
          {{"children": [4, 5]}},
          {{"camera": 1, "translation": [0, 0, 3]}},
          {{"camera": 2}}],
        "cameras": [
          {{"name": "overview", "type": "perspective",
            "perspective": {{"yfov": 0.5, "znear": 0.1}}}},
          {{"type": "perspective", "perspective": {{"yfov": 1.0, "znear": 0.1}}}},
          {{"name": "flat", "type": "orthographic",
            "orthographic": {{"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 100}}}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
        "buffers": [{{"uri": "data:application/octet-stream;base64,{b64}", "byteLength": 36}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
        "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
            "min": [0, 0, 0], "max": [1, 1, 0]}}]}}"#
    )
}

#[test]
fn gltf_cameras_are_placed_by_their_nodes_and_named() {
    let data = load_gltf_bytes(gltf_with_cameras().as_bytes(), Path::new("t.gltf")).unwrap();
    let names: Vec<&str> = data.cameras.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["overview", "camera 1"]);
    let c = data.cameras[0].camera;
    assert!(
        (c.position - Vec3::new(5.0, 1.0, 10.0)).length() < 1e-5,
        "{c:?}"
    );
    let forward = (c.look_at - c.position).normalize();
    assert!((forward - Vec3::NEG_X).length() < 1e-5, "{forward}");
    assert!((c.up - Vec3::Y).length() < 1e-5, "{}", c.up);
    assert!((c.vfov_degrees - 0.5f32.to_degrees()).abs() < 1e-4);
    let c = data.cameras[1].camera;
    assert_eq!(c.position, Vec3::new(0.0, 0.0, 3.0));
    assert!((c.look_at - Vec3::new(0.0, 0.0, 2.0)).length() < 1e-6);
    assert!(
        data.warnings
            .iter()
            .any(|w| w.contains("'flat'") && w.contains("orthographic")),
        "{:?}",
        data.warnings
    );
}

#[test]
fn a_bare_gltf_scene_renders_its_first_camera_and_lists_all() {
    let dir = std::env::temp_dir().join(format!("raybench-cameras-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("cams.gltf");
    std::fs::write(&path, gltf_with_cameras()).unwrap();
    let mut scene =
        raybench_scene::load(path.to_str().unwrap(), Path::new("/nonexistent")).unwrap();
    assert_eq!(scene.cameras.len(), 2);
    assert_eq!(scene.camera, scene.cameras[0].camera);
    let overrides = raybench_core::CameraOverrides {
        vfov_degrees: Some(20.0),
        ..Default::default()
    };
    scene.select_camera(Some("camera 1"), &overrides).unwrap();
    assert_eq!(scene.camera.position, Vec3::new(0.0, 0.0, 3.0));
    assert_eq!(scene.camera.vfov_degrees, 20.0);
    std::fs::remove_dir_all(&dir).ok();
}
