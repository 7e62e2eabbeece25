//! # raybench-scene
//!
//! Everything that turns a name or a file into a [`Scene`]: the TOML scene format
//! (`docs/scene-format.md`), OBJ+MTL through `tobj`, glTF 2.0 through `gltf`, seeded procedural
//! generators (`soup:M`, `spheres:M`, `icosphere:L`, `terrain:N`) and the built-in scenes,
//! whose TOML sources live in `bench-scenes/` and are embedded in the binary.
//!
//! Scene specs resolve in this order: an existing file path (`.toml`, `.obj`, `.gltf`,
//! `.glb`), a built-in scene name, a generator spec. Mesh files named by scenes are looked
//! up relative to the scene file, then in the assets directory ([`assets_dir`]).
//!
//! Nothing here panics on bad input: every malformed, truncated or out-of-range file gives a
//! [`LoadError`] that names the file and the problem.

mod bpt;
mod builtin;
mod error;
mod format;
pub mod generators;
mod gltf_loader;
pub mod grids;
mod obj;
mod sdf_format;
mod transform;
pub mod volumes;

pub use bpt::{BptPatch, load_bpt_file, parse_bpt};
pub use builtin::{BUILTIN_SCENES, BuiltinScene};
pub use error::LoadError;
pub use format::{load_scene_str, load_toml_file};
pub use gltf_loader::{load_gltf_bytes, load_gltf_file};
pub use obj::{MeshData, load_obj_bytes, load_obj_file};
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
    if path.extension().is_some() || spec.contains('/') {
        return Err(LoadError::NotFound {
            path: path.to_owned(),
        });
    }
    Err(LoadError::UnknownScene(spec.to_owned()))
}

/// A path's extension in lower case (empty when it has none).
pub(crate) fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default()
}

/// Loads a scene file, choosing the format by extension: `.toml` scene files; `.obj`,
/// `.gltf` and `.glb` meshes get an automatic camera framing their bounding box.
///
/// # Errors
/// What the format's loader reports, or an unsupported extension.
pub fn load_file(path: &Path, assets: &Path) -> Result<Scene, LoadError> {
    match extension(path).as_str() {
        "toml" => load_toml_file(path, assets),
        "obj" | "gltf" | "glb" => format::bare_mesh_scene(path),
        _ => Err(LoadError::Parse {
            path: path.to_owned(),
            message: "unknown scene file type (expected .toml, .obj, .gltf or .glb)".into(),
        }),
    }
}
