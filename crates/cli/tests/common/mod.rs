//! What the command's integration tests share: running the built binary (and checking that
//! it succeeded or failed cleanly), a scratch folder per test named after the suite, the
//! process and the test, and reading what a report wrote.

// Each test binary uses its own subset of these helpers.
#![allow(dead_code)]

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `raybench` binary of this build, to be given arguments (and environment) and run.
pub fn raybench_command() -> Command {
    Command::new(env!("CARGO_BIN_EXE_raybench"))
}

/// Runs the `raybench` binary of this build with `args` and waits for it.
pub fn raybench(args: &[&str]) -> Output {
    raybench_command()
        .args(args)
        .output()
        .expect("raybench runs")
}

/// Fails, showing the command's standard error, unless it succeeded.
pub fn assert_success(out: &Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// [`raybench`], which must succeed.
pub fn raybench_ok(args: &[&str]) -> Output {
    let out = raybench(args);
    assert!(
        out.status.success(),
        "raybench {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// `raybench render SCENE --width W --height H --out OUT`, then `extra`, which must succeed.
pub fn render(scene: &str, (width, height): (u32, u32), out: &Path, extra: &[&str]) -> Output {
    let (width, height) = (width.to_string(), height.to_string());
    let mut args = vec![
        "render",
        scene,
        "--width",
        &width,
        "--height",
        &height,
        "--out",
        out.to_str().expect("a UTF-8 path"),
    ];
    args.extend_from_slice(extra);
    raybench_ok(&args)
}

/// `raybench merge INPUTS.. --out OUT`, not checked.
pub fn merge(inputs: &[&Path], out: &Path) -> Output {
    let mut args = vec!["merge"];
    args.extend(inputs.iter().map(|p| p.to_str().expect("a UTF-8 path")));
    args.extend(["--out", out.to_str().expect("a UTF-8 path")]);
    raybench(&args)
}

/// Asserts a clean failure: non-zero exit that is not a panic, and one `error:` line that
/// contains `needle`.
pub fn assert_clean_error(out: &Output, needle: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "succeeded; stderr: {stderr}");
    assert_ne!(out.status.code(), Some(101), "panicked: {stderr}");
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(errors.len(), 1, "expected one error line, got: {stderr}");
    assert!(
        errors[0].contains(needle),
        "error line {:?} lacks {needle:?}",
        errors[0]
    );
    assert_no_repeated_cause(errors[0]);
}

/// Fails when an error line states a cause twice in a row (`X: msg: msg`), as a chain of
/// errors that each print their source would.
pub fn assert_no_repeated_cause(line: &str) {
    let parts: Vec<&str> = line.split(": ").collect();
    for w in parts.windows(2) {
        assert_ne!(w[0], w[1], "repeated cause in {line:?}");
    }
    for (i, p) in parts.iter().enumerate() {
        assert!(
            p.len() < 8 || !parts[i + 1..].iter().any(|q| q.ends_with(p)),
            "repeated cause {p:?} in {line:?}"
        );
    }
}

/// Writes `content` to `dir/name` and returns the path.
pub fn write(dir: &Path, name: &str, content: &[u8]) -> String {
    let p = dir.join(name);
    std::fs::write(&p, content).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    p.to_str().expect("a UTF-8 path").to_owned()
}

/// The text of file `name` in `dir`.
pub fn read(dir: &Path, name: &str) -> String {
    let p = dir.join(name);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The `results.json` a report or a merge wrote to `dir`.
pub fn results(dir: &Path) -> Value {
    serde_json::from_str(&read(dir, "results.json")).expect("results.json is JSON")
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
