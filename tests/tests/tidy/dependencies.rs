//! The crates' dependencies: the geometry depends on glam only, the CPU backends see the
//! geometry and not the scene, the core depends on what ARCHITECTURE.md allows and names
//! no clock, threads or I/O, and only the GPU backend knows wgpu.

use crate::workspace::{LAYERS, backend_crates, crate_dirs, dependencies, manifest};
use crate::{read, root, rust_sources, section, strip_comments_and_literals};

#[test]
fn the_geometry_crate_depends_on_glam_only() {
    let manifest = read(&root().join("crates/geometry/Cargo.toml"));
    assert_eq!(dependencies(&manifest, "[dependencies]"), ["glam"]);
    assert!(!manifest.contains("[build-dependencies]"));
}

/// Every CPU backend crate ([`workspace::backend_crates`]: the crates under `crates/` that
/// are not [`LAYERS`] and do not name `wgpu`) depends on `raybench-geometry` and not on the
/// rendering core or the scene loader: a structure sees the geometry, never the scene.
#[test]
fn cpu_backends_see_the_geometry_not_the_scene() {
    let backends = backend_crates(&root());
    assert!(
        backends.iter().any(|b| !b.gpu),
        "no CPU backend crate found"
    );
    assert!(backends.iter().any(|b| b.gpu), "no GPU backend crate found");
    for b in backends.iter().filter(|b| !b.gpu) {
        let deps = dependencies(&manifest(&root(), &b.dir), "[dependencies]");
        assert!(
            deps.iter().any(|d| d == "raybench-geometry"),
            "crates/{} must depend on raybench-geometry",
            b.dir
        );
        assert!(
            !deps
                .iter()
                .any(|d| d == "raybench-core" || d == "raybench-scene"),
            "crates/{} depends on the rendering core or the scene loader: {deps:?}",
            b.dir
        );
    }
}

/// The names the core section of ARCHITECTURE.md allows as the core's dependencies: the
/// backticked names of its sentence "it depends on `a` and `b` only".
fn allowed_core_dependencies(map: &str) -> Vec<String> {
    let Some(core) = section(map, "### `crates/core`") else {
        return Vec::new();
    };
    let flat = core.split_whitespace().collect::<Vec<_>>().join(" ");
    let Some(start) = flat.find("depends on ") else {
        return Vec::new();
    };
    let rest = &flat[start + "depends on ".len()..];
    let Some(end) = rest.find(" only") else {
        return Vec::new();
    };
    rest[..end]
        .split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_owned)
        .collect()
}

/// The core's `[dependencies]` are exactly what ARCHITECTURE.md's core section allows ("it
/// depends on `raybench-geometry` and `glam` only": no rayon, no wgpu, nothing that times or
/// threads), and it has no build script dependencies.
#[test]
fn the_core_depends_on_what_the_architecture_allows() {
    let root = root();
    let allowed = allowed_core_dependencies(&read(&root.join("ARCHITECTURE.md")));
    assert!(
        !allowed.is_empty(),
        "ARCHITECTURE.md's section ### `crates/core` no longer says \"it depends on `..` and \
         `..` only\""
    );
    let manifest = manifest(&root, "core");
    let mut deps = dependencies(&manifest, "[dependencies]");
    deps.sort();
    let mut allowed = allowed;
    allowed.sort();
    assert_eq!(
        deps, allowed,
        "crates/core/Cargo.toml against ARCHITECTURE.md"
    );
    assert!(!manifest.contains("[build-dependencies]"));
}

/// The paths of the standard library the core may not name: no clock, threads, files,
/// processes, environment, network or SIMD intrinsics.
const OUTSIDE_THE_CORE: [&str; 9] = [
    "std::time",
    "Instant",
    "std::thread",
    "std::fs",
    "std::io",
    "std::process",
    "std::env",
    "std::net",
    "arch::",
];

/// Which of `files` (path, text) name, in code (comments and literals aside), one of
/// [`OUTSIDE_THE_CORE`], each with the name it uses.
fn outside_the_core(files: &[(String, String)]) -> Vec<String> {
    named_in_code(files, &OUTSIDE_THE_CORE)
}

/// Which of `files` (path, text) name, in code (comments and literals aside), one of
/// `names`, as `path: name`.
fn named_in_code(files: &[(String, String)], names: &[&str]) -> Vec<String> {
    files
        .iter()
        .flat_map(|(path, text)| {
            let code = strip_comments_and_literals(text);
            names
                .iter()
                .filter(move |name| code.contains(*name))
                .map(move |name| format!("{path}: {name}"))
        })
        .collect()
}

/// ARCHITECTURE.md: the core knows nothing of timing, threads, I/O, SIMD intrinsics or GPUs
/// (the clock lives in the harness: `raybench_registry::TimedRenderer`).
#[test]
fn the_core_knows_no_clock_threads_or_io() {
    let files = rust_sources("crates/core");
    assert!(files.len() > 20, "found only {} files", files.len());
    let found = outside_the_core(&files);
    assert!(found.is_empty(), "the core names:\n{}", found.join("\n"));
}

/// Which files of `files` (path, text) name the `wgpu` crate: a Cargo.toml with a `wgpu`
/// dependency key in any section, or Rust code (comments and literals aside) with a path
/// `wgpu::` that is not the end of a longer name (`raybench_wgpu::` is not `wgpu::`).
fn names_wgpu(files: &[(String, String)]) -> Vec<String> {
    files
        .iter()
        .filter(|(path, text)| {
            if path.ends_with("Cargo.toml") {
                text.lines().any(|l| {
                    l.split_once('=')
                        .is_some_and(|(k, _)| k.trim() == "wgpu" && !l.trim().starts_with('#'))
                })
            } else {
                let code = strip_comments_and_literals(text);
                code.match_indices("wgpu::").any(|(i, _)| {
                    !code[..i]
                        .chars()
                        .next_back()
                        .is_some_and(|c| c.is_alphanumeric() || c == '_')
                })
            }
        })
        .map(|(path, _)| path.clone())
        .collect()
}

/// ARCHITECTURE.md: `crates/wgpu` is the only crate that knows wgpu. No other crate's
/// Cargo.toml (nor `tests/`'s) names the `wgpu` crate, and no other Rust source (under
/// `crates/`, `tests/`, `fuzz/`) has a `wgpu::` path. The workspace's own Cargo.toml declares
/// the version in `[workspace.dependencies]`, which is no use of it.
#[test]
fn only_the_gpu_backend_knows_wgpu() {
    let root = root();
    let mut files = Vec::new();
    for dir in crate_dirs(&root) {
        if dir == "wgpu" {
            continue;
        }
        files.push((format!("crates/{dir}/Cargo.toml"), manifest(&root, &dir)));
        files.extend(rust_sources(&format!("crates/{dir}")));
    }
    files.push((
        "tests/Cargo.toml".into(),
        read(&root.join("tests/Cargo.toml")),
    ));
    for dir in ["tests", "fuzz"] {
        if root.join(dir).is_dir() {
            files.extend(rust_sources(dir));
        }
    }
    assert!(files.len() > 50, "found only {} files", files.len());
    let found = names_wgpu(&files);
    assert!(
        found.is_empty(),
        "only crates/wgpu knows wgpu; these name it:\n{}",
        found.join("\n")
    );
}

#[test]
fn the_dependency_checks_can_fail() {
    let map = "### `crates/core` (x)\n\nText. It\ndepends on `raybench-geometry` and `glam`\nonly.\n\
               ### `crates/scene`\nit depends on `toml` only.\n";
    assert_eq!(
        allowed_core_dependencies(map),
        ["raybench-geometry", "glam"]
    );
    assert!(allowed_core_dependencies("### `crates/scene`\n").is_empty());
    let files = [
        (
            "a/Cargo.toml".to_owned(),
            "[dependencies]\nwgpu = 1\n".to_owned(),
        ),
        (
            "b/Cargo.toml".to_owned(),
            "[dependencies]\nraybench-wgpu = 1\n# wgpu = 1\n".to_owned(),
        ),
        ("c.rs".to_owned(), "fn f(_: wgpu::Device) {}\n".to_owned()),
        (
            "d.rs".to_owned(),
            "// wgpu::Device\nuse raybench_wgpu::X;\nconst S: &str = \"wgpu::\";\n".to_owned(),
        ),
    ];
    assert_eq!(names_wgpu(&files), ["a/Cargo.toml", "c.rs"]);
    let core = [
        (
            "e.rs".to_owned(),
            "fn f() { let t = std::time::Instant::now(); }\n".to_owned(),
        ),
        (
            "f.rs".to_owned(),
            "// std::fs\nconst S: &str = \"std::io\";\n".to_owned(),
        ),
    ];
    assert_eq!(
        outside_the_core(&core),
        ["e.rs: std::time", "e.rs: Instant"]
    );
    assert!(LAYERS.iter().any(|(l, _)| *l == "core"));
}

/// The clock's names a test may not use: a test that reads the time asserts something about
/// the machine's load, not the code (timings live in the benchmarks and the report).
const CLOCKS: [&str; 2] = ["Instant", "SystemTime"];

/// Which of `files` (path, text) name, in code (comments and literals aside), one of
/// [`CLOCKS`], each with the name it uses.
fn clock_readers(files: &[(String, String)]) -> Vec<String> {
    named_in_code(files, &CLOCKS)
}

/// docs/testing.md: nothing in a test measures time. Every integration test (`tests/tests/`
/// and each crate's `tests/`) is read; waits count their pauses instead of reading a clock.
#[test]
fn no_test_reads_a_clock() {
    let mut files = rust_sources("tests/tests");
    for krate in crate_dirs(&root()) {
        if root().join("crates").join(&krate).join("tests").is_dir() {
            files.extend(rust_sources(&format!("crates/{krate}/tests")));
        }
    }
    assert!(files.len() > 40, "found only {} files", files.len());
    let found = clock_readers(&files);
    assert!(
        found.is_empty(),
        "tests that read a clock:\n{}",
        found.join("\n")
    );
}

/// The check sees a clock in code and ignores the word in comments and strings.
#[test]
fn the_clock_check_can_fail() {
    let files = [
        (
            "a.rs".to_owned(),
            "// Instant\nconst S: &str = \"SystemTime\";\n".to_owned(),
        ),
        (
            "b.rs".to_owned(),
            "fn f() { let t = std::time::Instant::now(); }\n".to_owned(),
        ),
        (
            "c.rs".to_owned(),
            "fn g() { let _ = std::time::SystemTime::now(); }\n".to_owned(),
        ),
    ];
    assert_eq!(clock_readers(&files), ["b.rs: Instant", "c.rs: SystemTime"]);
}
