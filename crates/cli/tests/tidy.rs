//! Tidy: invariants of the source tree that ARCHITECTURE.md states and a test enforces (as
//! rust-analyzer's `tidy` does; `tests/tests/tidy/` holds the crate-graph and code-map
//! ones). Here: only the registry (`crates/registry/src/lib.rs`) names
//! concrete backends. Outside it and the allow-list below, no Rust file uses a backend
//! crate and no Rust file holds a backend's name as a string literal; the rest of the
//! workspace reads the registry's roles (`raybench_registry::Roles`).

// The workspace's crates by their Cargo.toml files, shared with `tests/tests/tidy/`.
#[path = "../../../tests/tests/workspace/mod.rs"]
mod workspace;

use std::path::{Path, PathBuf};

/// The backend crates ([`workspace::backend_crates`]: every crate under `crates/` that is
/// not a layer), as Rust paths (`raybench_bvh`) and as folders (`crates/bvh/`). A backend
/// crate may name itself and the backends it builds on (packet and wgpu on raybench-bvh's
/// tree; the peers' tests compare with naive).
fn backend_crates() -> Vec<(String, String)> {
    workspace::backend_crates(&root())
        .into_iter()
        .map(|b| (b.package.replace('-', "_"), format!("crates/{}/", b.dir)))
        .collect()
}

/// Paths (relative to the workspace root; a trailing `/` is a folder) where backend crates
/// and names are allowed, and why.
const ALLOWED: &[(&str, &str)] = &[
    (
        "crates/registry/src/lib.rs",
        "the registry: the one place that maps names and roles to backends",
    ),
    (
        "crates/registry/src/presets.rs",
        "the registry's builder presets: each backend's named build parameters",
    ),
    (
        "crates/registry/src/timed.rs",
        "the registry's timed view of its two renderer kinds (the CPU's and the GPU's)",
    ),
    (
        "crates/registry/tests/",
        "the registry's own tests: its names, presets and timed renderers are their subject",
    ),
    (
        "crates/render/src/lib.rs",
        "CpuRenderer's unit tests need one Accel below the registry: naive (a dev-dependency)",
    ),
    (
        "crates/cli/tests/",
        "the command line's tests type backend names as a user does (and this test names the \
         backend crates it looks for)",
    ),
    (
        "tests/benches/",
        "the benchmarks measure named structures against each other: backends are their subject",
    ),
    (
        "tests/src/obvhs_peer.rs",
        "obvhs's own trees as peers, beside raybench-bvh's adapter",
    ),
    (
        "tests/src/peers.rs",
        "the peer benchmark: named contestants are its subject",
    ),
    (
        "tests/src/peers/",
        "the peer benchmark: named contestants are its subject",
    ),
    (
        "tests/src/lib.rs",
        "grid_boundary_rays reads the uniform grid's cells to aim rays along its planes",
    ),
    (
        "tests/tests/adversarial.rs",
        "aims rays along the uniform grid's cell planes (built with raybench-grid)",
    ),
    (
        "tests/tests/edge_cases.rs",
        "validates raybench-bvh's invariants on every degenerate scene",
    ),
    (
        "tests/tests/equivalence.rs",
        "validates raybench-bvh's invariants and maps each non-exact backend to its tolerance test",
    ),
    ("tests/tests/gpu/", "the GPU backend is its subject"),
    (
        "tests/tests/grid_cases.rs",
        "the uniform grid's resolution and cell cases are its subject",
    ),
    (
        "tests/tests/heightfield.rs",
        "compares the direct height field in chosen structures (a subset, for time)",
    ),
    (
        "tests/tests/watertight.rs",
        "a million-triangle case on chosen structures (a subset, for time) and Embree's watertight mode",
    ),
    (
        "tests/tests/quality.rs",
        "each tree's own view (raybench-bvh, obvhs's adapter, the bvh crate, packet) is its subject",
    ),
    (
        "tests/tests/tidy/",
        "the crate-graph checks name the GPU backend's folder: only it may know wgpu",
    ),
    (
        "tests/tests/workspace/",
        "the backend crates' rule: a GPU backend's dependencies name the `wgpu` crate, whose \
         name is also that backend's",
    ),
    (
        "tests/tests/peer_bench.rs",
        "the peer benchmark: named contestants are its subject",
    ),
];

/// The workspace root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .expect("crates/cli is two levels below the workspace root")
}

/// Every `.rs` file under `dir`, skipping build outputs and hidden folders.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if path.is_dir() {
            if name != "target" && !name.starts_with('.') {
                rust_files(&path, out);
            }
        } else if name.ends_with(".rs") {
            out.push(path);
        }
    }
}

/// The allow-list entry that covers `relative`, if any; a backend crate's own folder is
/// allowed ([`backend_crates`]).
fn allowed(relative: &str, backends: &[(String, String)]) -> Option<&'static str> {
    if backends
        .iter()
        .any(|(_, dir)| relative.starts_with(dir.as_str()))
    {
        return Some("a backend crate: it names itself and the backends it builds on");
    }
    ALLOWED
        .iter()
        .find(|(p, _)| {
            if p.ends_with('/') {
                relative.starts_with(p)
            } else {
                relative == *p
            }
        })
        .map(|(_, why)| *why)
}

/// The backend crates and backend-name literals on the code lines (comments aside) of
/// `text`: `(line, what)`.
fn violations(text: &str, names: &[&str], crates: &[(String, String)]) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let code = line.trim_start();
        if code.starts_with("//") {
            continue;
        }
        for (c, _) in crates {
            if code.contains(c.as_str()) {
                found.push((i + 1, format!("uses crate {c}")));
            }
        }
        for n in names {
            if code.contains(&format!("\"{n}\"")) {
                found.push((i + 1, format!("names backend \"{n}\"")));
            }
        }
    }
    found
}

/// Every backend name, built or not.
fn backend_names() -> Vec<&'static str> {
    raybench_registry::BACKENDS
        .iter()
        .map(|b| b.name)
        .chain(raybench_registry::NOT_BUILT.iter().map(|n| n.name))
        .collect()
}

#[test]
fn only_the_registry_names_backends() {
    let root = root();
    let names = backend_names();
    let backends = backend_crates();
    assert!(
        backends.len() > 3,
        "found only {} backend crates",
        backends.len()
    );
    let mut files = Vec::new();
    for dir in ["crates", "tests", "fuzz"] {
        rust_files(&root.join(dir), &mut files);
    }
    assert!(files.len() > 50, "found only {} Rust files", files.len());
    let mut problems = Vec::new();
    for file in &files {
        let relative = file
            .strip_prefix(&root)
            .expect("under the root")
            .to_string_lossy()
            .replace('\\', "/");
        if allowed(&relative, &backends).is_some() {
            continue;
        }
        let text = std::fs::read_to_string(file).expect("a readable source file");
        for (line, what) in violations(&text, &names, &backends) {
            problems.push(format!("{relative}:{line}: {what}"));
        }
    }
    assert!(
        problems.is_empty(),
        "outside the registry (crates/registry/src/lib.rs), code reads the registry's roles \
         (raybench_registry::Roles) instead of naming backends; or add the file to ALLOWED in \
         crates/cli/tests/tidy.rs with the reason:\n{}",
        problems.join("\n")
    );
}

/// Every entry of the allow-list exists, so that it cannot silently cover nothing.
#[test]
fn the_allow_list_names_existing_paths() {
    let root = root();
    for (path, why) in ALLOWED {
        assert!(!why.is_empty());
        assert!(
            root.join(path).exists(),
            "ALLOWED names {path}, which is gone"
        );
    }
}

/// The check itself: it sees a backend crate and a backend name, and not comments.
#[test]
fn the_check_finds_what_it_looks_for() {
    let names = backend_names();
    let backends = backend_crates();
    let text = "use raybench_packet::Isa;\nlet b = backend(\"bvh\");\n// \"naive\" in a comment\n";
    let found = violations(text, &names, &backends);
    assert_eq!(found.len(), 2, "{found:?}");
    assert_eq!(found[0].0, 1);
    assert_eq!(found[1].0, 2);
    assert!(allowed("crates/registry/src/lib.rs", &backends).is_some());
    assert!(allowed("crates/bvh/src/lib.rs", &backends).is_some());
    assert!(allowed("crates/report/src/lib.rs", &backends).is_none());
}

/// The lines of `text` that declare a table of [`TABLES`] as a `const` rather than a
/// `static`.
fn const_tables(text: &str) -> Vec<usize> {
    text.lines()
        .enumerate()
        .filter(|(_, line)| {
            let line = line.trim_start();
            let line = line.strip_prefix("pub ").unwrap_or(line);
            line.strip_prefix("const ")
                .is_some_and(|rest| TABLES.iter().any(|t| rest.contains(&format!(": &[{t}]"))))
        })
        .map(|(i, _)| i + 1)
        .collect()
}

/// The registry's tables whose entries point to code (each backend's `make`).
const TABLES: &[&str] = &["Backend", "Preset"];

/// The registry's tables of backends and presets are statics: a `const` is evaluated again
/// in every crate that uses it, which compiles every backend's renderer again there (the
/// command line, the report and the tests: a fifth of the test build's compiler time).
#[test]
fn the_registry_tables_are_statics() {
    let dir = root().join("crates/registry/src");
    let mut files = Vec::new();
    rust_files(&dir, &mut files);
    let mut problems = Vec::new();
    let mut statics = 0;
    for file in &files {
        let text = std::fs::read_to_string(file).expect("a readable source file");
        statics += TABLES
            .iter()
            .filter(|t| text.contains(&format!("pub static {}S: &[{t}]", t.to_uppercase())))
            .count();
        for line in const_tables(&text) {
            problems.push(format!("{}:{line}", file.display()));
        }
    }
    assert!(
        problems.is_empty(),
        "make these statics:\n{}",
        problems.join("\n")
    );
    assert_eq!(
        statics,
        TABLES.len(),
        "BACKENDS and PRESETS are no longer found"
    );
    // The check sees a planted constant table.
    assert_eq!(
        const_tables("x\npub const BACKENDS: &[Backend] = &[\n"),
        [2]
    );
    assert!(const_tables("pub static PRESETS: &[Preset] = &[\n").is_empty());
}
