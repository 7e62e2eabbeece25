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
//!
//! Every format draws the same line between errors and warnings. Refused: what the file's
//! own layout does not describe (an OBJ face or a PLY face of fewer than three vertices,
//! numbers beyond a PLY record's properties, a list running past the end of the file),
//! values a scene file would refuse (an MTL `Ni` of 0 as `ior = 0`, `Ns` below 0 as
//! `shininess`), and transforms a library would silently read as another (a glTF node with
//! both a matrix and TRS properties, a projective matrix, a rotation that is no unit
//! quaternion). Warned of, and loaded: what is legal, or common in files found in the
//! wild, but surely not what was meant (self-intersecting polygons, bytes after a PLY
//! file's last record, instances stacked by a zero spacing, a texture that cannot be used,
//! which keeps its material's flat colour). A file a scene names that cannot be used is an
//! error naming the scene file, the line and the table.

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
    DEFAULT_SHARE, MEMORY_LIMIT_ENV, MemoryBudget, available_memory, flatten_within_budget,
    flattened_bytes_estimate, human_bytes, parse_size, set_memory_limit,
};
pub use builtin::{
    BUILTIN_SCENES, Benchmark, BuiltinScene, Matrix, Purpose, builtin, for_experiment, matrix,
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
    default_assets_dir()
}

/// `assets/` at the workspace root, with no `..` in it (it appears in messages): the
/// canonical path when it exists, else the path normalised lexically.
fn default_assets_dir() -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    std::fs::canonicalize(&path).unwrap_or_else(|_| normalize_lexically(&path))
}

/// `path` with its `.` components dropped and each `..` taking away the component before
/// it (without looking at the file system: a `..` after a symbolic link may differ).
#[must_use]
pub fn normalize_lexically(path: &Path) -> PathBuf {
    use std::path::Component;
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                if matches!(out.components().next_back(), Some(Component::Normal(_))) {
                    out.pop();
                } else if !matches!(
                    out.components().next_back(),
                    Some(Component::RootDir | Component::Prefix(_))
                ) {
                    out.push("..");
                }
            }
            c => out.push(c),
        }
    }
    out
}

/// The prefix of a scene spec that asks for the scene flattened ([`flatten_within_budget`]:
/// every instance's primitives carried to world space and stored flat): `flat:bunny-field`,
/// a scene of 12.6 million triangles stored flat.
pub const FLAT_PREFIX: &str = "flat:";

/// Loads the scene named by `spec`: an existing file path, a built-in scene name or a
/// generator spec (see the crate documentation), with mesh files looked up in `assets`;
/// any of these behind [`FLAT_PREFIX`] flattened, and named by the whole spec
/// (`flat:bunny-field`), so that its runs are told apart from the instanced scene's.
///
/// # Errors
/// [`LoadError::UnknownScene`] when `spec` is none of these; [`LoadError::MissingAsset`]
/// when a file the scene needs is absent; [`LoadError::OverBudget`] when the flattened form
/// would not fit the memory budget; otherwise what loading reports.
pub fn load(spec: &str, assets: &Path) -> Result<Scene, LoadError> {
    if let Some(inner) = spec.strip_prefix(FLAT_PREFIX) {
        let mut flat = flatten_within_budget(&load(inner, assets)?)?;
        flat.name = spec.to_string();
        return Ok(flat);
    }
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
    match std::fs::metadata(path) {
        Ok(meta) => return Err(io::not_a_file(path, &meta)),
        // A symbolic link loop, a folder that cannot be read: the system's words.
        Err(cause) if cause.kind() != std::io::ErrorKind::NotFound => {
            return Err(LoadError::Io {
                path: path.to_owned(),
                cause,
            });
        }
        Err(_) => {}
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

    /// `flat:NAME` is the scene flattened, named by the whole spec; a flat scene flattened
    /// again is the same; a bad inner spec is the inner spec's error.
    #[test]
    fn the_flat_prefix_flattens_and_names_the_scene() {
        let assets = Path::new(".");
        let instanced = load("instance-grid", assets).unwrap();
        assert!(instanced.geometry.has_instances());
        let flat = load("flat:instance-grid", assets).unwrap();
        assert_eq!(flat.name, "flat:instance-grid");
        assert!(!flat.geometry.has_instances());
        assert_eq!(flat.geometry.len(), instanced.geometry.total_len());
        assert_eq!(flat.geometry.len(), 49_649);
        assert_eq!(load("flat:soup:100", assets).unwrap().geometry.len(), 100);
        assert!(matches!(
            load("flat:nothing-here", assets),
            Err(LoadError::UnknownScene(s)) if s == "nothing-here"
        ));
    }

    /// A scene path that is a symbolic link loop says so (it was "file not found"); a
    /// missing one is not found.
    #[cfg(unix)]
    #[test]
    fn a_symbolic_link_loop_is_named() {
        let dir = std::env::temp_dir().join(format!("raybench-loop-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let link = dir.join("loop.obj");
        std::fs::remove_file(&link).ok();
        std::os::unix::fs::symlink("loop.obj", &link).unwrap();
        let e = load(link.to_str().unwrap(), &dir).unwrap_err().to_string();
        assert!(e.contains("loop.obj: a symbolic link loop ("), "{e}");
        let e = load_file(&link, &dir).unwrap_err().to_string();
        assert!(e.contains("loop.obj: a symbolic link loop ("), "{e}");
        let absent = dir.join("absent.obj");
        let e = load(absent.to_str().unwrap(), &dir)
            .unwrap_err()
            .to_string();
        assert!(e.ends_with("absent.obj: file not found"), "{e}");
        std::fs::remove_dir_all(dir).ok();
    }

    /// The default assets folder appears in messages: no `..` in it.
    #[test]
    fn the_default_assets_folder_is_normalised() {
        let dir = default_assets_dir();
        assert!(dir.is_absolute(), "{}", dir.display());
        assert!(
            !dir.components()
                .any(|c| matches!(c, std::path::Component::ParentDir)),
            "{}",
            dir.display()
        );
        assert!(dir.ends_with("assets"), "{}", dir.display());
        assert_eq!(
            normalize_lexically(Path::new("/a/b/crates/cli/../../../assets/./x")),
            Path::new("/a/assets/x")
        );
        assert_eq!(normalize_lexically(Path::new("/../a")), Path::new("/a"));
        assert_eq!(normalize_lexically(Path::new("../a/..")), Path::new(".."));
    }

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
