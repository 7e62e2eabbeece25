//! The experiments' sections of a quick report: a scaling experiment (`spp`) with its fits
//! and chart, the `presets` experiment, and the `instancing` section, which a merge writes
//! again from `results.json` alone.

use crate::common::{assert_success, merge, raybench_ok, results};
use crate::{chart, markdown, shows_text, tmp_dir};
use raybench_report::charts::backend_style;
use serde_json::Value;
use std::path::Path;

/// Whether the assets folder (`RAYBENCH_ASSETS`) holds `file`, which `what` is: when it
/// does not, says so and the test is skipped, except under `CI=true`, where it fails.
fn assets_hold(file: &str, what: &str) -> bool {
    let assets = std::env::var("RAYBENCH_ASSETS").unwrap_or_default();
    if Path::new(&assets).join(file).is_file() {
        return true;
    }
    assert!(
        std::env::var("CI").as_deref() != Ok("true"),
        "CI=true but {what} is missing"
    );
    eprintln!("SKIPPED: {what} is not in RAYBENCH_ASSETS");
    false
}

/// The results of a quick report of `experiment` by `backends` into `dir`, which must
/// succeed: the experiment on its own scenes, the matrix only `spheres` in ray casting, at
/// 16 x 16, one repeat.
fn quick_experiment(dir: &Path, backends: &str, experiment: &str) -> Value {
    #[rustfmt::skip]
    let args = [
        "report", "--quick", "--scenes", "spheres", "--modes", "cast", "--backends", backends,
        "--size", "16", "--repeat", "1", "--min-sample", "0", "--experiments", experiment,
        "--out", dir.to_str().unwrap(),
    ];
    raybench_ok(&args);
    results(dir)
}

/// A scaling experiment end to end (`spp`: the Cornell box, named by its `[benchmark]`
/// table, path traced at growing samples per pixel): its points, fits, table and chart.
#[test]
fn a_scaling_experiment_runs_and_is_written() {
    if !assets_hold("cornell-box/CornellBox-Original.obj", "the Cornell box") {
        return;
    }
    let dir = tmp_dir("scaling");
    let r = quick_experiment(&dir, "bvh", "spp");
    let points = r["scaling"].as_array().unwrap();
    // --quick: K = 1, 2, 4, 8, 16.
    assert_eq!(points.len(), 5);
    for p in points {
        assert_eq!(p["experiment"], "spp");
        assert_eq!(p["series"], "cornell-box");
        assert_eq!(p["backend"], "bvh");
        // The repetitions behind the median: one here (noise unknown), counted.
        let t = &p["timing"];
        assert_eq!(t["median"], p["seconds"], "{p}");
        assert_eq!(t["samples"].as_array().map(Vec::len), Some(1), "{p}");
        assert!(
            t["interval"].is_null() && t["contended"].as_u64().is_some(),
            "{p}"
        );
    }
    let noise = markdown(&dir);
    assert!(
        noise.contains("of the scaling experiments' 5 points, 0 have a median's interval"),
        "{noise}"
    );
    assert_eq!(r["fits"][0]["experiment"], "spp");
    let md = markdown(&dir);
    assert!(md.contains("## Scaling"), "{md}");
    assert!(md.contains("| spp | cornell-box | bvh |"), "{md}");
    // The chart draws the fitted power law dashed, its slope in the legend.
    assert!(
        md.contains("(charts/scaling-spp-cornell-box-seconds.svg)"),
        "{md}"
    );
    let svg = chart(&dir, "scaling-spp-cornell-box-seconds");
    let colour = backend_style("bvh").unwrap().colour;
    let fit = svg
        .split_once("<g><title>bvh: fitted ")
        .and_then(|(_, g)| g.split_once("</g>"))
        .map_or("", |(g, _)| g);
    assert!(
        fit.matches(&format!("stroke=\"{colour}\"")).count() >= 3,
        "dashes: {svg}"
    );
    let slope = r["fits"][0]["slope"].as_f64().unwrap();
    assert!(
        shows_text(&svg, &format!("bvh (slope {slope:.2})")),
        "{svg}"
    );
    assert!(shows_text(&svg, "samples per pixel (K)"), "{svg}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The `presets` experiment end to end on the scene whose `[benchmark]` table names it (the
/// bunny), with two presets named as `BACKEND:PRESET`: a build time, a camera-ray and an
/// incoherent point per preset, its tables and charts.
#[test]
fn the_presets_experiment_runs_and_is_written() {
    if !assets_hold("bunny/stanford-bunny.obj", "the bunny") {
        return;
    }
    let dir = tmp_dir("presets");
    let r = quick_experiment(
        &dir,
        "bvh:fast,bvh:quality,bvh:ploc_fastest_build,bvh:ploc_medium_build",
        "presets",
    );
    let points = r["scaling"].as_array().unwrap();
    // --quick: the bunny alone; four presets (two builders under bvh's kernel), two ray sets.
    assert_eq!(points.len(), 8, "{points:?}");
    for p in points {
        assert_eq!(p["experiment"], "presets");
        assert!(p["build_seconds"].as_f64().unwrap() > 0.0, "{p}");
        assert!(p["memory_bytes"].as_u64().unwrap() > 0, "{p}");
        assert_eq!(p["rays"], 256);
        // The tree's figures for the fixed-kernel analysis, leaf counts over these rays.
        let q = &p["quality"];
        assert_eq!(q["kind"], "tree", "{p}");
        assert!(q["sah"].as_f64().unwrap() > 1.0, "{p}");
        let (mean, sd) = (
            q["leaves_per_ray"].as_f64().unwrap(),
            q["leaf_count_std_dev"].as_f64().unwrap(),
        );
        assert!(mean > 0.0 && sd >= 0.0, "{p}");
        assert!(p["visits_per_ray"].as_f64().unwrap() > 0.0, "{p}");
    }
    for (series, backend) in [
        ("bunny primary", "bvh:fast"),
        ("bunny incoherent", "bvh:quality"),
    ] {
        assert!(
            points
                .iter()
                .any(|p| p["series"] == series && p["backend"] == backend),
            "{series} {backend}"
        );
    }
    // One point per series and backend: no fits.
    assert!(r["fits"].as_array().unwrap().is_empty());
    let md = markdown(&dir);
    assert!(
        md.contains("## Build presets: build time against trace time"),
        "{md}"
    );
    assert!(md.contains("| bunny | bvh:fast |"), "{md}");
    assert!(md.contains("| bunny | bvh | "), "{md}");
    // The four trees under one kernel, correlated with an interval (n = 4).
    assert!(
        md.contains("## Tree quality against trace time, kernel held fixed"),
        "{md}"
    );
    for set in ["primary", "incoherent"] {
        let row = md
            .lines()
            .find(|l| l.starts_with(&format!("| bunny | {set} | bvh | 2.0 | 4 | ")))
            .unwrap_or_else(|| panic!("{set}: {md}"));
        assert!(row.contains(" ["), "an interval: {row}");
        assert!(
            md.contains(&format!("(charts/fixed-kernel-sah-bunny-{set}.svg)")),
            "{md}"
        );
    }
    assert!(
        md.contains("| bunny | primary | bvh:ploc_medium_build | "),
        "{md}"
    );
    // Both presets in bvh's colour, told apart by their markers.
    for stem in ["presets-bunny-primary", "presets-bunny-time-to-image"] {
        assert!(md.contains(&format!("(charts/{stem}.svg)")), "{md}");
        let svg = chart(&dir, stem);
        for preset in ["bvh:fast", "bvh:quality"] {
            assert!(shows_text(&svg, preset), "{svg}");
        }
        let colour = backend_style("bvh").unwrap().colour;
        assert!(svg.contains(&format!("fill=\"{colour}\"")), "{svg}");
    }
    assert_ne!(
        backend_style("bvh:fast").unwrap().marker,
        backend_style("bvh:quality").unwrap().marker
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The `instancing` experiment of the quick report: the small instanced scene (the one
/// whose `[benchmark]` table names it, self-contained) instanced and flattened with the
/// baseline and the packet backend, its table, ratios and chart; `raybench merge` of the
/// one result writes the same section from `results.json` alone.
#[test]
fn the_quick_report_has_the_instancing_section() {
    let (dir, merged) = (tmp_dir("instancing"), tmp_dir("instancing-merged"));
    let r = quick_experiment(&dir, "bvh,packet", "instancing");
    let points = r["scaling"].as_array().unwrap();
    assert_eq!(points.len(), 4, "{points:?}");
    for p in points {
        assert_eq!(p["experiment"], "instancing");
        assert_eq!(p["x"], 49_649.0, "the flattened count: {p}");
        assert_eq!(p["rays"], 256);
        let stored = p["stored_primitives"].as_u64().unwrap();
        match p["series"].as_str().unwrap() {
            "instance-grid instanced" => assert_eq!(stored, 1 + 320 + 8 + 1),
            "instance-grid flattened" => assert_eq!(stored, 49_649),
            other => panic!("series {other}"),
        }
        assert!(p["build_seconds"].as_f64().unwrap() > 0.0, "{p}");
        assert!(p["memory_bytes"].as_u64().unwrap() > 0, "{p}");
    }
    let md = markdown(&dir);
    assert!(
        md.contains("## Instancing: instanced against flattened"),
        "{md}"
    );
    assert!(
        md.contains("| instance-grid | instanced | bvh | 330 | 49649 |"),
        "{md}"
    );
    assert!(
        md.contains("- instance-grid, packet: flattened takes"),
        "{md}"
    );
    assert!(md.contains("(charts/instancing-throughput.svg)"), "{md}");
    let svg = chart(&dir, "instancing-throughput");
    assert!(shows_text(&svg, "instance-grid flattened"), "{svg}");
    assert_success(&merge(&[&dir], &merged));
    let section = |md: &str| {
        let start = md.find("## Instancing").expect("the section");
        let rest = &md[start + 3..];
        md[start..start + 3 + rest.find("\n## ").unwrap_or(rest.len())].to_string()
    };
    let again = markdown(&merged);
    assert_eq!(section(&md), section(&again));
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&merged);
}
