//! The command as a process: an interrupt leaves the previous image whole, a closed pipe
//! ends it quietly, progress lines go to a terminal only, and GPU commands print no
//! stray lines from the platform's libraries.

use crate::common::{assert_success, raybench_command, write};
use crate::{root, tmp_dir};
use std::process::Command;

/// Ctrl-C during a render leaves no partial image under the final name: the previous file
/// there stays whole (images are written to a temporary name and renamed into place only
/// when complete), and the process ends by the signal, not a panic.
#[cfg(unix)]
#[test]
fn an_interrupted_render_leaves_the_previous_image_whole() {
    let dir = tmp_dir("interrupt");
    let out = write(&dir, "out.png", b"the previous image");
    // Long enough to be interrupted: path tracing at 1024 spp (minutes).
    let mut child = raybench_command()
        .args([
            "render", "spheres", "--mode", "path", "--spp", "1024", "--width", "512", "--height",
            "512", "--out", &out,
        ])
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("raybench runs");
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let sent = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(sent.success());
    let status = child.wait().unwrap();
    assert!(
        !status.success(),
        "the render finished before the interrupt"
    );
    assert_ne!(status.code(), Some(101), "panicked");
    assert_eq!(std::fs::read(&out).unwrap(), b"the previous image");
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, ["out.png"], "files left behind: {left:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn gpu_commands_print_no_wayland_noise() {
    // Mesa's device-selection layer probes Wayland while wgpu lists adapters; without
    // XDG_RUNTIME_DIR, libwayland printed an `error:` line about it, twice.
    let o = raybench_command()
        .args(["backends"])
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .unwrap();
    assert_success(&o);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!stderr.contains("XDG_RUNTIME_DIR"), "{stderr}");
}

#[test]
fn long_work_shows_progress_on_a_terminal_only() {
    let run = |args: &[&str], progress: Option<&str>| {
        let mut c = raybench_command();
        c.args(args).env_remove("RAYBENCH_PROGRESS");
        if let Some(p) = progress {
            c.env("RAYBENCH_PROGRESS", p);
        }
        let o = c.output().unwrap();
        assert_success(&o);
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let dir = tmp_dir("progress");
    let out = dir.join("p.png");
    let render = [
        "render",
        "spheres",
        "--width",
        "16",
        "--height",
        "16",
        "--out",
        out.to_str().unwrap(),
    ];
    let compare = [
        "compare",
        "spheres",
        "--width",
        "16",
        "--height",
        "16",
        "--repeat",
        "2",
        "--backends",
        "bvh,grid",
    ];
    // Stderr is a pipe here: no live line (a terminal would get one after 2 s of work).
    for args in [&render[..], &compare[..]] {
        let stderr = run(args, None);
        assert!(
            !stderr.contains("elapsed") && !stderr.contains('\r'),
            "{stderr}"
        );
    }
    // Forced, every step shows one (here at once, one line each).
    let stderr = run(&render, Some("always"));
    assert!(
        stderr
            .lines()
            .any(|l| l.starts_with("[........................] 0/1")
                && l.ends_with("render cast 16x16, 1 spp")),
        "{stderr}"
    );
    let stderr = run(&compare, Some("always"));
    for what in ["bvh: build", "bvh: counted warm-up", "grid: timed run 2/2"] {
        assert!(
            stderr
                .lines()
                .any(|l| l.starts_with('[') && l.contains("/6  ") && l.ends_with(what)),
            "{what}: {stderr}"
        );
    }
    // The report's step records: plain lines in a log, nothing under `never`; an unknown
    // value is ignored with one warning.
    let report_dir = dir.join("report");
    #[rustfmt::skip]
    let report = [
        "report", "--scenes", "spheres", "--backends", "bvh", "--modes", "cast", "--rays",
        "primary", "--size", "16", "--repeat", "1", "--min-sample", "0", "--no-scaling",
        "--out", report_dir.to_str().unwrap(),
    ];
    let stderr = run(&report, None);
    assert!(
        stderr.lines().any(|l| l.starts_with("1/1  0m")) && !stderr.contains("[#"),
        "{stderr}"
    );
    let stderr = run(&report, Some("never"));
    assert!(!stderr.lines().any(|l| l.starts_with("1/1")), "{stderr}");
    let stderr = run(&report, Some("sometimes"));
    assert_eq!(
        stderr
            .matches("warning: RAYBENCH_PROGRESS='sometimes' is ignored")
            .count(),
        1,
        "{stderr}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// A reader that closes the pipe early (`raybench compare-results A B --json | head`) ends
/// the command quietly: success, no panic on standard error.
#[test]
fn a_closed_pipe_ends_the_command_quietly() {
    use std::io::Read as _;
    use std::process::Stdio;
    let reports = root().join("reports");
    // A committed report: comparing it with itself prints far more than a pipe holds.
    let report = std::fs::read_dir(&reports)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.join("results.json").is_file())
        .expect("a committed report");
    let mut child = raybench_command()
        .args(["compare-results", "--json"])
        .arg(&report)
        .arg(&report)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("raybench runs");
    let mut first = [0u8; 16];
    child.stdout.take().unwrap().read_exact(&mut first).unwrap();
    // The read end is closed here; the rest of the output meets a broken pipe.
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{:?}: {stderr}", out.status);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(first.starts_with(b"{"));
}
