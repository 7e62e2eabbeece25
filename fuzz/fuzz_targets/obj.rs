//! The OBJ loader: any bytes either load into finite, in-range triangles or are an error.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(m) = raybench_scene::load_obj_bytes(data, Path::new("fuzz.obj")) {
        m.mesh.validate().expect("a loaded OBJ mesh is valid");
        assert_eq!(m.triangle_material.len(), m.mesh.indices.len());
    }
});
