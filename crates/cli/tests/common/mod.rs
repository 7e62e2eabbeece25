//! What the command's integration tests share: running the built binary, and a scratch
//! folder per test named after the suite, the process and the test.

// Each test binary uses its own subset of these helpers.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Output};

/// Runs the `raybench` binary of this build with `args` and waits for it.
pub fn raybench(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raybench"))
        .args(args)
        .output()
        .expect("raybench runs")
}

/// `raybench-SUITE-PID-NAME` in the temporary folder, removed if a run left it there and
/// not created (for a command that must create it itself).
pub fn fresh_path(suite: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("raybench-{suite}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// [`fresh_path`], created empty.
pub fn tmp_dir(suite: &str, name: &str) -> PathBuf {
    let dir = fresh_path(suite, name);
    std::fs::create_dir_all(&dir).expect("a scratch folder");
    dir
}
