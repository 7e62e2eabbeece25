//! The PLY loader: any bytes either load into finite, in-range triangles (with as many
//! normals and texture coordinates as vertices, when present) or are an error.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(m) = raybench_scene::load_ply_bytes(data, Path::new("fuzz.ply")) {
        m.mesh.validate().expect("a loaded PLY mesh is valid");
        assert_eq!(m.triangle_material.len(), m.mesh.indices.len());
        let n = m.mesh.positions.len();
        assert!(m.normals.is_empty() || m.normals.len() == n);
        assert!(m.uvs.is_empty() || m.uvs.len() == n);
        assert!(m.normals.iter().all(|v| v.is_finite()));
        assert!(m.uvs.iter().all(|v| v.is_finite()));
    }
});
