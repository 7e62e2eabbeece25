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
pub mod generators;
mod gltf_loader;
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

use raybench_core::{Light, Scene, SceneBuilder, SceneError, Vec3};
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
        return Err(not_a_file(path, &meta));
    }
    if path.extension().is_some() || spec.contains('/') {
        return Err(LoadError::NotFound {
            path: path.to_owned(),
        });
    }
    Err(LoadError::UnknownScene(spec.to_owned()))
}

/// A builder for a scene of one mesh file or generator spec: a grey-blue background and
/// one directional light from above (the camera frames the geometry by default).
pub(crate) fn lit_builder(name: &str) -> Result<SceneBuilder, SceneError> {
    let mut b = SceneBuilder::new(name);
    b.background(Vec3::new(0.55, 0.65, 0.8))?;
    b.add_light(Light::Directional {
        direction: Vec3::new(-0.4, -1.0, -0.6),
        radiance: Vec3::ONE,
    })?;
    Ok(b)
}

/// What a path that exists but is no regular file is, for messages: a folder, a FIFO or a
/// device (which may never end) is not "not found".
pub(crate) fn not_a_file_message(meta: &std::fs::Metadata) -> String {
    let kind = meta.file_type();
    let what = if kind.is_dir() {
        "a folder"
    } else {
        #[cfg(unix)]
        {
            use std::os::unix::fs::FileTypeExt as _;
            if kind.is_fifo() {
                "a FIFO (named pipe)"
            } else if kind.is_char_device() || kind.is_block_device() {
                "a device"
            } else if kind.is_socket() {
                "a socket"
            } else {
                "something other than a file"
            }
        }
        #[cfg(not(unix))]
        "something other than a file"
    };
    format!("is {what}, not a regular file")
}

/// The error for a path that exists but is no regular file ([`not_a_file_message`]).
pub(crate) fn not_a_file(path: &Path, meta: &std::fs::Metadata) -> LoadError {
    LoadError::Parse {
        path: path.to_owned(),
        message: not_a_file_message(meta),
    }
}

/// Checks that `path` is a regular file before it is opened (a FIFO or `/dev/zero` would
/// block or never end).
///
/// # Errors
/// [`LoadError::NotFound`] when it does not exist, [`LoadError::Io`] when its metadata
/// cannot be read, else [`not_a_file`]'s error for anything but a regular file.
pub(crate) fn check_regular_file(path: &Path) -> Result<(), LoadError> {
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_file() => Ok(()),
        Ok(meta) => Err(not_a_file(path, &meta)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(LoadError::NotFound {
            path: path.to_owned(),
        }),
        Err(cause) => Err(LoadError::Io {
            path: path.to_owned(),
            cause,
        }),
    }
}

/// The UTF-8 byte-order mark some editors write at the start of text files.
const UTF8_BOM: &[u8] = b"\xef\xbb\xbf";

/// `bytes` without a leading UTF-8 byte-order mark: every text format (TOML, OBJ, MTL,
/// `.bpt`, glTF JSON) accepts one.
pub(crate) fn strip_bom(bytes: &[u8]) -> &[u8] {
    bytes.strip_prefix(UTF8_BOM).unwrap_or(bytes)
}

/// A path's extension in lower case (empty when it has none).
pub(crate) fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default()
}

/// Loads a scene file, choosing the format by extension: `.toml` scene files; `.obj`,
/// `.gltf`, `.glb` and `.ply` meshes get an automatic camera framing their bounding box.
///
/// # Errors
/// What the format's loader reports, or an unsupported extension.
pub fn load_file(path: &Path, assets: &Path) -> Result<Scene, LoadError> {
    match extension(path).as_str() {
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

    /// Every text format accepts a leading UTF-8 byte-order mark (issue 18): the first
    /// line is not swallowed into a garbage keyword.
    #[test]
    fn every_text_format_accepts_a_byte_order_mark() {
        let dir = std::env::temp_dir().join(format!("raybench-bom-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bom = |text: &str| [UTF8_BOM, text.as_bytes()].concat();
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
