//! The workspace's crates as their `Cargo.toml` files describe them: which are layers and
//! which are backends. Shared by the tidy tests (`tests/tests/tidy/`, and
//! `crates/cli/tests/tidy.rs` through a `#[path]` attribute), so that both derive the
//! backend crates by one rule instead of keeping lists by hand.

// Each test binary that includes this module uses a part of it.
#![allow(dead_code)]

use std::path::Path;

/// The crates under `crates/` that are layers of the renderer, not backends, and what each
/// is. Every other crate under `crates/` is a backend ([`backend_crates`]).
pub const LAYERS: &[(&str, &str)] = &[
    (
        "geometry",
        "rays, primitives and the Accel contract: the ground floor",
    ),
    (
        "core",
        "the rendering core: the scene model, integrators, the Renderer contract",
    ),
    ("scene", "the scene loader"),
    ("render", "the CPU renderer over any Accel"),
    ("cli", "the raybench command"),
    ("registry", "the backend registry"),
    ("report", "the benchmark report"),
];

/// The dependency names of one `[section]` of a Cargo.toml (keys of `name = ...` lines).
#[must_use]
pub fn dependencies(manifest: &str, section: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut inside = false;
    for line in manifest.lines() {
        let line = line.trim();
        if line.starts_with('[') {
            inside = line == section;
            continue;
        }
        if inside
            && !line.starts_with('#')
            && let Some((key, _)) = line.split_once('=')
        {
            out.push(key.trim().to_string());
        }
    }
    out
}

/// The names of the folders under `root/crates` that hold a crate (a `Cargo.toml`), sorted.
#[must_use]
pub fn crate_dirs(root: &Path) -> Vec<String> {
    let mut out: Vec<String> = std::fs::read_dir(root.join("crates"))
        .expect("crates/")
        .map(|e| e.expect("an entry").path())
        .filter(|p| p.join("Cargo.toml").exists())
        .map(|p| {
            p.file_name()
                .expect("a name")
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    out.sort();
    out
}

/// The text of `root/crates/<dir>/Cargo.toml`.
///
/// # Panics
/// When it cannot be read.
#[must_use]
pub fn manifest(root: &Path, dir: &str) -> String {
    let path = root.join("crates").join(dir).join("Cargo.toml");
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The package name of a Cargo.toml (`name = ...` in `[package]`).
#[must_use]
pub fn package_name(manifest: &str) -> String {
    let mut inside = false;
    for line in manifest.lines() {
        let line = line.trim();
        if line.starts_with('[') {
            inside = line == "[package]";
        } else if inside
            && let Some(("name", value)) = line.split_once('=').map(|(k, v)| (k.trim(), v))
        {
            return value.trim().trim_matches('"').to_owned();
        }
    }
    panic!("a Cargo.toml without [package] name")
}

/// A backend crate: its folder under `crates/`, its package name, and whether it is a GPU
/// backend.
pub struct BackendCrate {
    /// The folder under `crates/`.
    pub dir: String,
    /// The package name (`raybench-bvh`).
    pub package: String,
    /// A GPU backend: its `[dependencies]` name the `wgpu` crate. The others are CPU
    /// backends.
    pub gpu: bool,
}

/// The backend crates, by rule: every crate under `crates/` that is not one of the
/// [`LAYERS`]; a backend whose `[dependencies]` name the `wgpu` crate is a GPU backend, every
/// other a CPU backend. So a new backend crate is checked by every tidy test as soon as it
/// exists, and a new layer must be added to [`LAYERS`] with what it is.
#[must_use]
pub fn backend_crates(root: &Path) -> Vec<BackendCrate> {
    crate_dirs(root)
        .into_iter()
        .filter(|dir| !LAYERS.iter().any(|(layer, _)| layer == dir))
        .map(|dir| {
            let text = manifest(root, &dir);
            BackendCrate {
                package: package_name(&text),
                gpu: dependencies(&text, "[dependencies]")
                    .iter()
                    .any(|d| d == "wgpu"),
                dir,
            }
        })
        .collect()
}
