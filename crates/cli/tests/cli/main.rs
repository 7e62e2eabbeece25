//! The `raybench` command end to end: happy paths, and every kind of bad input giving a
//! one-line error and a non-zero exit, never a panic (exit code 101) or a hang. One test
//! binary, its modules by subject: `render` (images, meshes, patches, cameras), `compare`
//! (the JSON rows, ray sets, ray files, `--flatten`), `info` (listings and structure
//! quality), `diff` (linear images measured against each other), `bad_input` (refused
//! files, options and output paths), `process` (signals, pipes, progress, stray output) and
//! `docs` (the manuals' statements checked against the command).

#[path = "../common/mod.rs"]
mod common;

mod bad_input;
mod compare;
mod diff;
mod docs;
mod info;
mod process;
mod render;

use std::path::{Path, PathBuf};

/// This suite's scratch folder `name` ([`common::tmp_dir`]).
fn tmp_dir(name: &str) -> PathBuf {
    common::tmp_dir("cli", name)
}

/// The workspace root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}
