//! Records the source revision the binary is built from, for `raybench --version` and the
//! machine description of every report: the environment variable `RAYBENCH_REVISION` at
//! build time when set (for packagers), else the short commit hash of the git checkout the
//! workspace is, with `-dirty` when the tracked sources (`crates/`, `tests/`, the manifest
//! and the lock file) differ from that commit, else `unknown` (a source tarball, or a
//! workspace inside another project's repository). Also records how it was compiled
//! (`RAYBENCH_BUILD`: the compiler's version, the optimisation level, debug assertions,
//! the target and `RUSTFLAGS`), for the reports' reproducibility block.

use std::path::{Path, PathBuf};
use std::process::Command;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=RAYBENCH_REVISION");
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
    let revision = std::env::var("RAYBENCH_REVISION")
        .ok()
        .map(|r| r.trim().to_string())
        .filter(|r| !r.is_empty())
        .or_else(|| git_revision(&manifest))
        .unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=RAYBENCH_REVISION={revision}");
    println!("cargo:rustc-env=RAYBENCH_BUILD={}", build_description());
}

/// `rustc 1.x.y (hash date), opt-level 3, debug assertions off, x86_64-unknown-linux-gnu,
/// RUSTFLAGS none`: what decides the code's speed besides the source. Cargo gives a build
/// script the compiler (`RUSTC`), the profile's settings and the flags of the crate it builds.
fn build_description() -> String {
    let var = |name: &str| std::env::var(name).unwrap_or_default();
    let rustc = Command::new(std::env::var_os("RUSTC").unwrap_or_else(|| "rustc".into()))
        .arg("--version")
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map_or_else(
            || "rustc (version unknown)".to_string(),
            |o| String::from_utf8_lossy(&o.stdout).trim().to_string(),
        );
    let flags: Vec<String> = var("CARGO_ENCODED_RUSTFLAGS")
        .split('\u{1f}')
        .filter(|f| !f.is_empty())
        .map(str::to_string)
        .collect();
    format!(
        "{rustc}, opt-level {}, debug assertions {}, {}, RUSTFLAGS {}",
        var("OPT_LEVEL"),
        if std::env::var_os("CARGO_CFG_DEBUG_ASSERTIONS").is_some() {
            "on"
        } else {
            "off"
        },
        var("TARGET"),
        if flags.is_empty() {
            "none".to_string()
        } else {
            flags.join(" ")
        }
    )
}

/// The output of `git ARGS` run in `dir`, trimmed; `None` when git is missing or fails.
fn git(dir: &Path, args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .current_dir(dir)
        .args(args)
        .output()
        .ok()?;
    let text = String::from_utf8_lossy(&out.stdout).trim().to_string();
    (out.status.success() && !text.is_empty()).then_some(text)
}

/// The short hash of `HEAD` when the workspace (two levels above this crate) is the top of
/// a git checkout, with `-dirty` when the tracked sources differ from it (staged or not);
/// asks Cargo to run this again when `HEAD` moves or a source changes.
fn git_revision(manifest: &Path) -> Option<String> {
    let workspace = manifest.join("../..").canonicalize().ok()?;
    let top = PathBuf::from(git(manifest, &["rev-parse", "--show-toplevel"])?);
    if top.canonicalize().ok()? != workspace {
        return None;
    }
    // HEAD, the branch it names and the packed refs (a worktree keeps them apart).
    let mut watched = vec!["HEAD".to_string(), "packed-refs".to_string()];
    watched.extend(git(manifest, &["symbolic-ref", "-q", "HEAD"]));
    for name in watched {
        if let Some(path) = git(manifest, &["rev-parse", "--git-path", &name]) {
            let path = manifest.join(path);
            // A missing file would make Cargo run this script on every build.
            if path.exists() {
                println!("cargo:rerun-if-changed={}", path.display());
            }
        }
    }
    let hash = git(manifest, &["rev-parse", "--short", "HEAD"])?;
    // Cargo scans a watched directory's files, so an edit anywhere in the sources reruns
    // this (a `git diff` of a few milliseconds).
    for source in SOURCES {
        println!(
            "cargo:rerun-if-changed={}",
            workspace.join(source).display()
        );
    }
    let mut diff = vec!["diff", "--quiet", "HEAD", "--"];
    diff.extend(SOURCES);
    let clean = Command::new("git")
        .current_dir(&workspace)
        .args(&diff)
        .status()
        .ok()?;
    // 0: no difference, 1: differences; anything else is git failing.
    match clean.code() {
        Some(0) => Some(hash),
        Some(1) => Some(format!("{hash}-dirty")),
        _ => None,
    }
}

/// The workspace paths whose changes make a build `-dirty`: everything compiled into the
/// binaries.
const SOURCES: [&str; 4] = ["crates", "tests", "Cargo.toml", "Cargo.lock"];
