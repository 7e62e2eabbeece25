//! Invariants of the code's layout that a reader relies on and a compiler does not check, in
//! the spirit of rust-analyzer's `tidy` tests: the geometry crate's dependencies, and the
//! code map of ARCHITECTURE.md covering every source file.

use std::path::{Path, PathBuf};

/// The workspace root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ sits in the workspace")
        .to_path_buf()
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The dependency names of one `[section]` of a Cargo.toml (keys of `name = ...` lines).
fn dependencies(manifest: &str, section: &str) -> Vec<String> {
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

#[test]
fn the_geometry_crate_depends_on_glam_only() {
    let manifest = read(&root().join("crates/geometry/Cargo.toml"));
    assert_eq!(dependencies(&manifest, "[dependencies]"), ["glam"]);
    assert!(!manifest.contains("[build-dependencies]"));
}

#[test]
fn cpu_backends_see_the_geometry_not_the_scene() {
    for backend in ["naive", "bvh", "grid", "packet", "peers"] {
        let manifest = read(&root().join(format!("crates/{backend}/Cargo.toml")));
        let deps = dependencies(&manifest, "[dependencies]");
        assert!(
            deps.iter().any(|d| d == "raybench-geometry"),
            "crates/{backend} must depend on raybench-geometry"
        );
        assert!(
            !deps
                .iter()
                .any(|d| d == "raybench-core" || d == "raybench-scene"),
            "crates/{backend} depends on the rendering core or the scene loader: {deps:?}"
        );
    }
}

/// Every `.rs` file below `dir`, relative to it, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for entry in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let path = entry.expect("a directory entry").path();
            if path.is_dir() {
                todo.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path.strip_prefix(dir).expect("below dir").to_path_buf());
            }
        }
    }
    out.sort();
    out
}

/// The text of the code-map section whose heading starts with `heading`.
fn section<'a>(map: &'a str, heading: &str) -> Option<&'a str> {
    let start = map.find(heading)?;
    let rest = &map[start + heading.len()..];
    Some(&rest[..rest.find("\n### ").unwrap_or(rest.len())])
}

/// How a file is named in its crate's section: `lib.rs` and `main.rs` by the section itself,
/// `X/mod.rs` as the folder `` `X/` ``, anything else by its file name (or its path).
fn mentioned(section: &str, file: &Path) -> bool {
    let name = file.file_name().and_then(|n| n.to_str()).unwrap_or("");
    let path = file.to_string_lossy().replace('\\', "/");
    match name {
        "lib.rs" | "main.rs" => true,
        "mod.rs" => {
            let folder = file
                .parent()
                .map(|p| p.to_string_lossy().replace('\\', "/"));
            folder.is_some_and(|f| section.contains(&format!("`{f}/`")))
        }
        _ => section.contains(&format!("`{name}`")) || section.contains(&path),
    }
}

#[test]
fn the_code_map_names_every_source_file() {
    let root = root();
    let map = read(&root.join("ARCHITECTURE.md"));
    let mut missing = Vec::new();
    let mut crates: Vec<(String, PathBuf)> = std::fs::read_dir(root.join("crates"))
        .expect("crates/")
        .map(|e| e.expect("an entry").path())
        .filter(|p| p.join("Cargo.toml").exists())
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (format!("### `crates/{name}`"), p.join("src"))
        })
        .collect();
    crates.push(("### `tests`".into(), root.join("tests/src")));
    crates.sort();
    for (heading, src) in crates {
        let Some(text) = section(&map, &heading) else {
            missing.push(format!("no section {heading}"));
            continue;
        };
        for file in rust_files(&src) {
            if !mentioned(text, &file) {
                missing.push(format!("{heading}: {}", file.display()));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "ARCHITECTURE.md's code map does not name:\n{}",
        missing.join("\n")
    );
}

#[test]
fn the_code_map_check_can_fail() {
    let section = "`bvh.rs` and `csg/` and `report/results.rs`";
    assert!(mentioned(section, Path::new("bvh.rs")));
    assert!(mentioned(section, Path::new("csg/mod.rs")));
    assert!(mentioned(section, Path::new("report/results.rs")));
    assert!(!mentioned(section, Path::new("grid.rs")));
    assert!(!mentioned(section, Path::new("report/mod.rs")));
    assert_eq!(
        dependencies(
            "[dependencies]\nglam = 1\n# c\n[dev-dependencies]\nx = 2\n",
            "[dependencies]"
        ),
        ["glam"]
    );
}
