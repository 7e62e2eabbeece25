//! `raybench report` and `raybench merge` end to end, on small matrices. One test binary,
//! its modules by subject: `matrix` (the files a report promises, the results schema, several
//! cameras, a baseline, a replayed ray file), `html` (`REPORT.html`), `merge` (sharding by
//! scene, merging, bad options), `experiments` (the scaling, presets and instancing
//! sections), `skips` (what did not run, and how the report says so), `slurm` (the
//! Slurm scripts on a one-node cluster of the test's own), `synthetic` (committed shards
//! merged, every figure of the report checked against hand arithmetic) and `timing` (how
//! timings and their noise are stated).

#[path = "../common/mod.rs"]
mod common;

mod experiments;
mod html;
mod matrix;
mod merge;
mod skips;
mod slurm;
mod synthetic;
mod timing;

use common::{raybench, raybench_ok};
use std::path::{Path, PathBuf};
use std::process::Output;

/// This suite's scratch folder `name` ([`common::fresh_path`]): not created, as `report`
/// creates the folder it writes to.
fn tmp_dir(name: &str) -> PathBuf {
    common::fresh_path("report", name)
}

/// This suite's scratch folder `name`, created, with the scene file `file` of text `toml`
/// in it: the folder and the scene's path.
fn scene_dir(name: &str, file: &str, toml: &str) -> (PathBuf, String) {
    let dir = common::tmp_dir("report", name);
    let scene = common::write(&dir, file, toml.as_bytes());
    (dir, scene)
}

/// `raybench report ARGS --out DIR`, not checked.
fn report(dir: &Path, args: &[&str]) -> Output {
    let mut all = vec!["report"];
    all.extend_from_slice(args);
    all.extend(["--out", dir.to_str().expect("a UTF-8 path")]);
    raybench(&all)
}

/// A small report, which must succeed: two self-contained scenes, three backends, 32 x 32,
/// no scaling.
fn small_report(dir: &Path, extra: &[&str]) -> Output {
    #[rustfmt::skip]
    let mut args = vec![
        "report", "--scenes", "spheres,cornell-box", "--backends", "naive,bvh,packet",
        "--size", "32", "--repeat", "1", "--min-sample", "0", "--no-scaling", "--out", dir.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    raybench_ok(&args)
}

/// The `REPORT.md` a report or a merge wrote to `dir`.
fn markdown(dir: &Path) -> String {
    common::read(dir, "REPORT.md")
}

/// The SVG text of chart `stem` of the report in `dir`, checked to be one SVG document
/// whose ids all start with the stem.
fn chart(dir: &Path, stem: &str) -> String {
    let svg = common::read(dir, &format!("charts/{stem}.svg"));
    assert!(
        svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\"") && svg.ends_with("</svg>\n"),
        "{svg}"
    );
    for part in svg.split(" id=\"").skip(1) {
        assert!(part.starts_with(&format!("{stem}-")), "{stem}: {part}");
    }
    svg
}

/// Whether `svg` has a text element that reads `text` (escaped), whatever the white space
/// around it.
fn shows_text(svg: &str, text: &str) -> bool {
    svg.split("<text ").skip(1).any(|t| {
        t.split_once('>')
            .and_then(|(_, rest)| rest.split_once("</text>"))
            .is_some_and(|(inner, _)| inner.trim() == text)
    })
}
