//! Invariants of the code's layout that a reader relies on and a compiler does not check, in
//! the spirit of rust-analyzer's `tidy` tests: the crates' dependencies (the geometry's, the
//! core's, the backends'; only the GPU backend knows wgpu), the code map of ARCHITECTURE.md
//! covering every source file, no module cycles, and the WGSL kernels naming the Rust
//! routines they port. Each check is tested on a planted example that must fail it.
//!
//! One test binary, its modules by subject: `dependencies`, `code_map`, `cycles` and
//! `kernels`; here, what they share: reading the tree and telling code from comments and
//! literals.

#[path = "../workspace/mod.rs"]
mod workspace;

mod code_map;
mod cycles;
mod dependencies;
mod kernels;

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

/// Every `.rs` file below the workspace folder `dir` (such as `crates/core` or `tests`), as
/// its path from the workspace root and its text, sorted by path.
fn rust_sources(dir: &str) -> Vec<(String, String)> {
    let base = root().join(dir);
    rust_files(&base)
        .into_iter()
        .map(|f| {
            let path = format!("{dir}/{}", f.to_string_lossy().replace('\\', "/"));
            (path, read(&base.join(&f)))
        })
        .collect()
}

/// Every `.rs` file below `dir` (build outputs and hidden folders aside), relative to it,
/// sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for entry in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let path = entry.expect("a directory entry").path();
            let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
            if path.is_dir() {
                // Build outputs and hidden folders hold no sources of ours.
                if name.is_some_and(|n| n != "target" && !n.starts_with('.')) {
                    todo.push(path);
                }
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

/// Blanks out the comments, string literals and character literals of Rust source `src`
/// (each replaced by spaces; newlines are kept), so that what is left is code: `crate::`
/// in a doc comment or a message is not a dependency. Handles nested block comments,
/// escapes, raw strings (`r#"..."#`, `br"..."`) and tells character literals (`'a'`,
/// `'\n'`) from lifetimes (`'a`).
fn strip_comments_and_literals(src: &str) -> String {
    let s: Vec<char> = src.chars().collect();
    let mut out = String::with_capacity(src.len());
    let blank = |out: &mut String, c: char| out.push(if c == '\n' { '\n' } else { ' ' });
    let mut i = 0;
    while i < s.len() {
        let c = s[i];
        let next = s.get(i + 1).copied();
        let ident_before = i > 0 && (s[i - 1].is_alphanumeric() || s[i - 1] == '_');
        if c == '/' && next == Some('/') {
            while i < s.len() && s[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < s.len() {
                if s[i] == '/' && s.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if s[i] == '*' && s.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    blank(&mut out, s[i]);
                    i += 1;
                }
            }
        } else if !ident_before && (c == 'r' || (c == 'b' && next == Some('r'))) && {
            let mut j = i + if c == 'b' { 2 } else { 1 };
            while s.get(j) == Some(&'#') {
                j += 1;
            }
            s.get(j) == Some(&'"')
        } {
            // A raw string: `r`, some hashes, a quote; it ends at a quote and as many hashes.
            i += if c == 'b' { 2 } else { 1 };
            let mut hashes = 0;
            while s[i] == '#' {
                hashes += 1;
                i += 1;
            }
            i += 1;
            while i < s.len() {
                if s[i] == '"' && (1..=hashes).all(|k| s.get(i + k) == Some(&'#')) {
                    i += 1 + hashes;
                    break;
                }
                blank(&mut out, s[i]);
                i += 1;
            }
        } else if c == '"' {
            i += 1;
            while i < s.len() && s[i] != '"' {
                if s[i] == '\\' {
                    blank(&mut out, s[i]);
                    i += 1;
                }
                if i < s.len() {
                    blank(&mut out, s[i]);
                    i += 1;
                }
            }
            i += 1;
        } else if c == '\'' && next == Some('\\') {
            // An escaped character literal: up to the closing quote.
            i += 2;
            while i < s.len() && s[i] != '\'' {
                i += 1;
            }
            i += 1;
        } else if c == '\'' && s.get(i + 2) == Some(&'\'') {
            i += 3;
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}
