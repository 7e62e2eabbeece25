//! The code map of ARCHITECTURE.md names every source file of every crate, in the crate's
//! own section.

use crate::workspace::{crate_dirs, dependencies};
use crate::{read, root, rust_files, section};
use std::path::{Path, PathBuf};

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
    let mut crates: Vec<(String, PathBuf)> = crate_dirs(&root)
        .into_iter()
        .map(|name| {
            let src = root.join("crates").join(&name).join("src");
            (format!("### `crates/{name}`"), src)
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
