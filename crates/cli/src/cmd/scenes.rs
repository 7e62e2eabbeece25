//! `raybench scenes`: the built-in scenes and generators.

use anyhow::Result;
use raybench_scene::{BUILTIN_SCENES, generators::GENERATORS};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// `assets` as an absolute path without `.` or `..` (symbolic links resolved when it
/// exists), and whether it exists.
pub(crate) fn resolved_dir(assets: &Path) -> (PathBuf, bool) {
    if let Ok(p) = assets.canonicalize() {
        return (p, true);
    }
    let absolute = std::path::absolute(assets).unwrap_or_else(|_| assets.to_owned());
    (raybench_scene::normalize_lexically(&absolute), false)
}

pub(crate) fn scenes(assets: &Path) -> Result<ExitCode> {
    let (dir, exists) = resolved_dir(assets);
    outln!(
        "# built-in scenes (assets: {}{})",
        dir.display(),
        if exists {
            ""
        } else {
            ", which does not exist: set --assets or RAYBENCH_ASSETS"
        }
    )?;
    // One name column for both lists, as wide as the longest name.
    let generator_names: Vec<String> = GENERATORS
        .iter()
        .map(|g| format!("{}:ARG", g.name))
        .collect();
    let width = BUILTIN_SCENES
        .iter()
        .map(|b| b.name.len())
        .chain(generator_names.iter().map(String::len))
        .max()
        .unwrap_or(0);
    for b in BUILTIN_SCENES {
        let missing: Vec<_> = b
            .assets
            .iter()
            .filter(|a| !assets.join(a).is_file())
            .collect();
        let state = if missing.is_empty() {
            "ok"
        } else {
            "missing-assets"
        };
        outln!("{:<width$} {state:<14} {}", b.name, b.description)?;
    }
    outln!("# generators (NAME:ARG)")?;
    for (g, name) in GENERATORS.iter().zip(&generator_names) {
        outln!(
            "{name:<width$} {:<14} {} (ARG = {}, at most {})",
            "ok",
            g.description,
            g.argument,
            g.max
        )?;
    }
    Ok(ExitCode::SUCCESS)
}
