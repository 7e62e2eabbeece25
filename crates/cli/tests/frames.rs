//! `raybench render --frames N`: the frames of the built-in moving scene written
//! as numbered images, the same whether the structure is refitted or rebuilt, frame 0 the
//! scene's plain render; a still scene and bad values refused with one error line.

mod common;

use common::{assert_clean_error, assert_success, merge, raybench, raybench_ok};
use std::path::{Path, PathBuf};
use std::process::Output;

/// This suite's scratch folder `name` ([`common::tmp_dir`]).
fn tmp_dir(name: &str) -> PathBuf {
    common::tmp_dir("frames", name)
}

/// Renders `moving` at 40 x 30 with `extra` options into `dir/NAME.png` (and ids beside it).
fn render(dir: &Path, name: &str, extra: &[&str]) -> Output {
    let ids = dir.join(format!("{name}-ids.png"));
    let mut args = vec!["--ids", ids.to_str().unwrap()];
    args.extend_from_slice(extra);
    common::render("moving", (40, 30), &dir.join(format!("{name}.png")), &args)
}

fn bytes(p: PathBuf) -> Vec<u8> {
    std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn frames_are_numbered_deterministic_and_move() {
    let dir = tmp_dir("frames");
    let refit = render(&dir, "r", &["--backend", "bvh", "--frames", "4"]);
    let stderr = String::from_utf8_lossy(&refit.stderr);
    for f in 1..4 {
        assert!(stderr.contains(&format!("frame {f}: refit ")), "{stderr}");
    }
    assert!(
        stderr.contains("top "),
        "the two-level form's top level: {stderr}"
    );
    render(
        &dir,
        "b",
        &["--backend", "bvh", "--frames", "4", "--update", "rebuild"],
    );
    let other = render(&dir, "g", &["--backend", "grid", "--frames", "4"]);
    let stderr = String::from_utf8_lossy(&other.stderr);
    assert!(
        stderr.contains("frame 1: build "),
        "grid rebuilds: {stderr}"
    );
    render(&dir, "one", &["--backend", "bvh"]);
    for f in 0..4 {
        let name = |stem: &str| dir.join(format!("{stem}-{f:04}.png"));
        let r = bytes(name("r"));
        assert_eq!(r, bytes(name("b")), "frame {f}: refitted against rebuilt");
        assert_eq!(r, bytes(name("g")), "frame {f}: bvh against grid");
        assert_eq!(bytes(name("r-ids")), bytes(name("b-ids")), "frame {f}: ids");
    }
    assert_eq!(bytes(dir.join("r-0000.png")), bytes(dir.join("one.png")));
    assert_ne!(bytes(dir.join("r-0000.png")), bytes(dir.join("r-0003.png")));
    assert!(!dir.join("r-0004.png").exists());
}

#[test]
fn bad_frame_options_give_one_line_errors() {
    let dir = tmp_dir("bad");
    let out = dir.join("x.png");
    let out = out.to_str().unwrap();
    for (args, needle) in [
        (
            vec!["render", "instances", "--frames", "3", "--out", out],
            "scene 'instances' does not move",
        ),
        (
            vec!["render", "moving", "--frames", "0", "--out", out],
            "--frames 0: between 1 and",
        ),
        (
            vec!["render", "moving", "--update", "refresh", "--out", out],
            "unknown update policy 'refresh'",
        ),
    ] {
        assert_clean_error(&raybench(&args), needle);
    }
    assert!(!Path::new(out).exists());
}

/// The report's `motion` experiment (quick: 8 frames) writes its frames to `results.json`,
/// its section and charts to the report, and `merge` redraws the same section from them.
#[test]
fn the_motion_experiment_survives_a_merge() {
    let dir = tmp_dir("report");
    let (out, merged) = (dir.join("run"), dir.join("merged"));
    let o = raybench_ok(&[
        "report",
        "--quick",
        "--scenes",
        "moving",
        "--backends",
        "bvh,grid",
        "--modes",
        "cast",
        "--rays",
        "primary",
        "--size",
        "24",
        "--repeat",
        "1",
        "--experiments",
        "motion",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("motion: grid cannot refit"), "{stderr}");
    let results = common::results(&out);
    let frames = results["motion"].as_array().expect("motion frames");
    assert_eq!(frames.len(), 8, "bvh's 8 frames, grid left out");
    for (f, m) in frames.iter().enumerate() {
        assert_eq!(m["backend"], "bvh");
        assert_eq!(m["frame"], f);
        assert_eq!(m["refit_seconds"].is_null(), f == 0);
        assert!(m["sah_refitted"].as_f64().unwrap() > 0.0);
    }
    assert!(results["skipped"].as_array().unwrap().is_empty());
    assert_success(&merge(&[&out], &merged));
    let section = |d: &Path| {
        let md = common::read(d, "REPORT.md");
        let start = md.find("## Moving scenes").expect("the motion section");
        let end = md[start..]
            .find("\n## Charts")
            .map_or(md.len(), |e| start + e);
        md[start..end].to_string()
    };
    let s = section(&out);
    assert!(s.contains("| 7 |") && s.contains("rebuild"), "{s}");
    assert_eq!(s, section(&merged));
    for chart in ["motion-moving-bvh-time.svg", "motion-moving-bvh-sah.svg"] {
        assert!(merged.join("charts").join(chart).is_file(), "{chart}");
    }
}
