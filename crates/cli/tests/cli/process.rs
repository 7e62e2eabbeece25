//! The command as a process: an interrupt leaves the previous image whole, a closed pipe
//! ends it quietly, progress lines go to a terminal only, and GPU commands print no
//! stray lines from the platform's libraries.

use crate::common::{assert_success, raybench_command, write};
use crate::{root, tmp_dir};
use std::process::Command;

/// Whether this process ignores SIGINT: a disposition inherited from whoever started the
/// tests (a background job of a non-interactive shell has it so) and passed on through
/// `exec`, so that `kill -INT` would end no child. Linux's `/proc/self/status` says;
/// elsewhere it is taken as not ignored.
#[cfg(unix)]
fn sigint_ignored() -> bool {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|status| {
            let mask = status.lines().find_map(|l| l.strip_prefix("SigIgn:"))?;
            u64::from_str_radix(mask.trim(), 16).ok()
        })
        .is_some_and(|mask| mask & (1 << (2 - 1)) != 0)
}

/// `raybench` as a command that an interrupt ends: where this process ignores SIGINT
/// ([`sigint_ignored`]), started through coreutils' `env --default-signal=INT`, which
/// restores the default action before it runs raybench in its place (same process).
#[cfg(unix)]
fn interruptible_raybench() -> Command {
    if !sigint_ignored() {
        return raybench_command();
    }
    let mut command = Command::new("env");
    command
        .arg("--default-signal=INT")
        .arg(raybench_command().get_program());
    command
}

/// Ctrl-C while the image is being written, the moment an in-place write would leave a
/// truncated file under the final name: the previous file there stays whole (images are
/// written to a temporary name and renamed into place only when complete), and the process
/// ends by the signal. The temporary name is made a named pipe before the run, so that the
/// writer opens it and then blocks half-way (a pipe holds 64 KiB; the 128 x 128 PFM is
/// 192 KiB): the interrupt comes once the image's first bytes have arrived, with no clock.
/// A write that does not go through the temporary name ends the run first, and fails here.
/// The temporary name is all that is left beside the image (a killed process removes
/// nothing; the next write replaces it).
#[cfg(unix)]
#[test]
fn an_interrupted_render_leaves_the_previous_image_whole() {
    use std::io::Read as _;
    let dir = tmp_dir("interrupt");
    let out = write(&dir, "out.pfm", b"the previous image");
    let partial = dir.join("out.partial.pfm");
    let made = Command::new("mkfifo")
        .arg(&partial)
        .status()
        .expect("mkfifo runs");
    assert!(made.success());
    let mut child = interruptible_raybench()
        .args([
            "render", "spheres", "--width", "128", "--height", "128", "--out", &out,
        ])
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("raybench runs");
    // The pipe's reader: opening blocks until raybench opens the temporary file to write;
    // then the image's first two bytes. The open file is handed over and kept open until
    // the process has ended, so that the writer stays blocked (not broken off).
    let (tx, rx) = std::sync::mpsc::channel();
    let fifo = partial.clone();
    std::thread::spawn(move || {
        let mut file = std::fs::File::open(&fifo).unwrap();
        let mut head = [0u8; 2];
        file.read_exact(&mut head).unwrap();
        let _ = tx.send((file, head));
    });
    // At most 3,000 polls 20 ms apart (a minute; the render takes well under a second).
    let mut writing = None;
    for _ in 0..3000 {
        if let Ok(w) = rx.try_recv() {
            writing = Some(w);
            break;
        }
        if let Some(status) = child.try_wait().unwrap() {
            panic!(
                "raybench ended ({status}) without writing through the temporary name; \
                 out.pfm holds {} bytes",
                std::fs::metadata(&out).map_or(0, |m| m.len())
            );
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let Some((reader, head)) = writing else {
        let _ = child.kill();
        panic!("nothing written to the temporary file");
    };
    assert_eq!(&head, b"PF", "not a PFM image");
    interrupt_and_check(&mut child, &out, "");
    drop(reader);
    let mut left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    left.sort();
    assert_eq!(left, ["out.partial.pfm", "out.pfm"], "files left: {left:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Ctrl-C while the render runs (its progress line has said so) writes nothing: the
/// previous image at the output path stays whole, no other file appears, and the process
/// ends by the signal.
#[cfg(unix)]
#[test]
fn an_interrupt_during_the_render_writes_nothing() {
    use std::io::BufRead as _;
    let dir = tmp_dir("interrupt-render");
    let out = write(&dir, "out.png", b"the previous image");
    // Path tracing at 1024 spp (minutes): interrupted once its step has begun.
    let mut child = interruptible_raybench()
        .args([
            "render", "spheres", "--mode", "path", "--spp", "1024", "--width", "512", "--height",
            "512", "--out", &out,
        ])
        .env("RAYBENCH_PROGRESS", "always")
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("raybench runs");
    // Read up to the step's first progress line (the end of stderr if it never comes); the
    // pipe stays open until the process has ended.
    let mut lines = std::io::BufReader::new(child.stderr.take().unwrap()).lines();
    let mut seen = Vec::new();
    for line in lines.by_ref() {
        let line = line.unwrap();
        let rendering = line.starts_with('[') && line.ends_with("render path 512x512, 1024 spp");
        seen.push(line);
        if rendering {
            break;
        }
    }
    assert!(
        seen.last().is_some_and(|l| l.ends_with("1024 spp")),
        "the render never began: {seen:?}"
    );
    interrupt_and_check(&mut child, &out, &format!("{seen:?}"));
    drop(lines);
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, ["out.png"], "files left behind: {left:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Sends SIGINT to `child`, waits for it, and asserts that the signal ended it and that
/// `out` still holds "the previous image" (`context` is added to the messages).
#[cfg(unix)]
fn interrupt_and_check(child: &mut std::process::Child, out: &str, context: &str) {
    let sent = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(sent.success());
    // At most 3,000 polls 20 ms apart: a process the signal does not end is killed and
    // reported rather than waited for (it would wait on the test's pipe for ever).
    let mut status = None;
    for _ in 0..3000 {
        status = child.try_wait().unwrap();
        if status.is_some() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let Some(status) = status else {
        let _ = child.kill();
        let _ = child.wait();
        panic!("SIGINT did not end raybench within a minute; {context}");
    };
    assert_eq!(
        std::os::unix::process::ExitStatusExt::signal(&status),
        Some(2),
        "not ended by SIGINT: {status}; {context}"
    );
    assert_eq!(
        std::fs::read(out).ok().as_deref(),
        Some(&b"the previous image"[..]),
        "the previous image at the output path is not whole; {context}"
    );
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
    // Two steps: the scene, then the empty scene that measures the pipeline's fixed cost.
    let stderr = run(&report, None);
    assert!(
        stderr.lines().any(|l| l.starts_with("1/2  0m"))
            && stderr.lines().any(|l| l.starts_with("2/2  0m"))
            && !stderr.contains("[#"),
        "{stderr}"
    );
    let stderr = run(&report, Some("never"));
    assert!(!stderr.lines().any(|l| l.starts_with("1/2")), "{stderr}");
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
