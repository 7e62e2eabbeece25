//! The glTF loader, `.gltf` JSON and `.glb` binary alike (the bytes decide): any input
//! either loads into finite, in-range triangles or is an error.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    // External buffer URIs resolve against a folder that does not exist.
    if let Ok(m) = raybench_scene::load_gltf_bytes(data, Path::new("/nonexistent-fuzz/f.gltf")) {
        m.mesh.validate().expect("a loaded glTF mesh is valid");
        assert_eq!(m.triangle_material.len(), m.mesh.indices.len());
    }
});
