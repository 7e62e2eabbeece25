//! # raybench-scene
//!
//! Everything that turns a name or a file into a [`Scene`]: the TOML scene format
//! (`docs/scene-format.md`), OBJ+MTL through `tobj`, glTF 2.0 through `gltf`, PLY through
//! `ply-rs-bw`, seeded procedural
//! generators (`soup:M`, `spheres:M`, `icosphere:L`, `terrain:N`) and the built-in scenes,
//! whose TOML sources live in `bench-scenes/` and are embedded in the binary.
//!
//! Scene specs resolve in this order: an existing file path (`.toml`, `.obj`, `.gltf`,
//! `.glb`, `.ply`), a built-in scene name, a generator spec. Mesh files named by scenes are looked
//! up relative to the scene file, then in the assets directory ([`assets_dir`]).
//!
//! Nothing here panics on bad input: every malformed, truncated or out-of-range file gives a
//! [`LoadError`] that names the file and the problem.

mod bpt;
mod budget;
mod builtin;
mod error;
mod format;
#[doc(hidden)]
pub mod fuzzing;
pub mod generators;
mod gltf_loader;
mod io;
mod obj;
pub mod phantom;
mod ply;
pub mod samples;
mod texture;
mod transform;

pub use bpt::{BptPatch, load_bpt_file, parse_bpt};
pub use budget::{
    DEFAULT_SHARE, MEMORY_LIMIT_ENV, MemoryBudget, flatten_within_budget, flattened_bytes_estimate,
    human_bytes, parse_size, set_memory_limit,
};
pub use builtin::{
    BUILTIN_SCENES, Benchmark, BuiltinScene, Matrix, builtin, for_experiment, matrix,
};
pub use error::LoadError;
pub use format::{load_scene_str, load_toml_file};
pub use gltf_loader::{load_gltf_bytes, load_gltf_file};
pub use obj::{MeshData, SharedMesh, load_obj_bytes, load_obj_file};
pub use ply::{load_ply_bytes, load_ply_file};
pub use texture::{ImageSource, TextureRef};
pub use transform::Transform;

use raybench_core::Scene;
use std::path::{Path, PathBuf};

/// The environment variable naming the assets directory.
pub const ASSETS_ENV: &str = "RAYBENCH_ASSETS";

/// The assets directory: `explicit` (the `--assets` option) if given, else
/// `$RAYBENCH_ASSETS`, else `assets/` at the workspace root.
#[must_use]
pub fn assets_dir(explicit: Option<&Path>) -> PathBuf {
    if let Some(p) = explicit {
        return p.to_owned();
    }
    if let Some(p) = std::env::var_os(ASSETS_ENV).filter(|p| !p.is_empty()) {
        return PathBuf::from(p);
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets")
}

/// Loads the scene named by `spec`: an existing file path, a built-in scene name or a
/// generator spec (see the crate documentation), with mesh files looked up in `assets`.
///
/// # Errors
/// [`LoadError::UnknownScene`] when `spec` is none of these; [`LoadError::MissingAsset`]
/// when a file the scene needs is absent; otherwise what loading reports.
pub fn load(spec: &str, assets: &Path) -> Result<Scene, LoadError> {
    let path = Path::new(spec);
    if path.is_file() {
        return load_file(path, assets);
    }
    if let Some(b) = BUILTIN_SCENES.iter().find(|b| b.name == spec) {
        return format::load_scene_str(b.source, b.name, None, assets);
    }
    if generators::is_generator_spec(spec) {
        return generators::generate_scene(spec);
    }
    if let Ok(meta) = std::fs::metadata(path) {
        return Err(io::not_a_file(path, &meta));
    }
    if path.extension().is_some() || spec.contains('/') {
        return Err(LoadError::NotFound {
            path: path.to_owned(),
        });
    }
    Err(LoadError::UnknownScene(spec.to_owned()))
}

/// Loads a scene file, choosing the format by extension: `.toml` scene files; `.obj`,
/// `.gltf`, `.glb` and `.ply` meshes get an automatic camera framing their bounding box.
///
/// # Errors
/// What the format's loader reports, or an unsupported extension.
pub fn load_file(path: &Path, assets: &Path) -> Result<Scene, LoadError> {
    match io::extension(path).as_str() {
        "toml" => load_toml_file(path, assets),
        "obj" | "gltf" | "glb" | "ply" => format::bare_mesh_scene(path),
        _ => Err(LoadError::Parse {
            path: path.to_owned(),
            message: "unknown scene file type (expected .toml, .obj, .gltf, .glb or .ply)".into(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_core::Vec3;

    /// Every text format accepts a leading UTF-8 byte-order mark: the first
    /// line is not swallowed into a garbage keyword.
    #[test]
    fn every_text_format_accepts_a_byte_order_mark() {
        let dir = std::env::temp_dir().join(format!("raybench-bom-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bom = |text: &str| [io::UTF8_BOM, text.as_bytes()].concat();
        let write = |name: &str, text: &str| std::fs::write(dir.join(name), bom(text)).unwrap();
        write("m.mtl", "newmtl red\nKd 0.8 0.1 0.1\n");
        write(
            "t.obj",
            "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n",
        );
        let obj = load_obj_file(&dir.join("t.obj")).unwrap();
        assert_eq!(obj.mesh.indices, [[0, 1, 2]]);
        assert_eq!(obj.materials[0].base_color, Vec3::new(0.8, 0.1, 0.1));
        write(
            "s.toml",
            "[[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n",
        );
        assert_eq!(
            load(dir.join("s.toml").to_str().unwrap(), &dir)
                .unwrap()
                .geometry
                .len(),
            1
        );
        let mut bpt = String::from("1\n3 3\n");
        for k in 0..16 {
            bpt += &format!("{} {} 0\n", k % 4, k / 4);
        }
        write("p.bpt", &bpt);
        assert_eq!(load_bpt_file(&dir.join("p.bpt")).unwrap().len(), 1);
        let gltf = r#"{"asset": {"version": "2.0"}}"#;
        write("g.gltf", gltf);
        assert!(load_gltf_file(&dir.join("g.gltf")).is_ok());
        std::fs::remove_dir_all(dir).ok();
    }
}
