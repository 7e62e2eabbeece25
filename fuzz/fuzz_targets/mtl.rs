//! MTL material libraries, as an OBJ file's `mtllib` reads them: the fuzzed bytes are the
//! library of a fixed OBJ (a textured triangle using material `a`, a quad using `b`). Any
//! library either loads into finite materials that index what exists, or is an error; the
//! materials then go through the scene builder's own check, which may refuse them.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raybench_core::SceneBuilder;
use std::path::Path;

const OBJ: &[u8] = b"mtllib fuzz.mtl
v 0 0 0
v 1 0 0
v 0 1 0
v 1 1 0
vt 0 0
vt 1 0
vt 0 1
usemtl a
f 1/1 2/2 3/3
usemtl b
f 1 2 4 3
";

fuzz_target!(|data: &[u8]| {
    let Ok(m) = raybench_scene::fuzzing::load_obj_with_mtl(OBJ, data, Path::new("/fuzz/f.obj"))
    else {
        return;
    };
    m.mesh.validate().expect("a loaded OBJ mesh is valid");
    assert_eq!(m.triangle_material.len(), m.mesh.indices.len());
    assert_eq!(m.mesh.indices.len(), 3);
    for &t in m.triangle_material.iter().flatten() {
        assert!((t as usize) < m.materials.len());
    }
    let mut b = SceneBuilder::new("fuzz");
    for mat in &m.materials {
        assert!(mat.base_color.is_finite() && mat.specular.is_finite());
        assert!(mat.emission.is_finite() && mat.shininess.is_finite());
        assert!(mat.ior.is_finite() && mat.ior > 0.0, "ior {}", mat.ior);
        assert!(mat.emission_texture.is_none());
        if let Some(t) = mat.base_color_texture {
            assert!((t as usize) < m.textures.len());
        }
        // As when the scene's textures could not be decoded.
        let mut mat = mat.clone();
        mat.base_color_texture = None;
        let _ = b.add_material(mat);
    }
    for t in &m.textures {
        assert!(!t.name.is_empty());
    }
});
