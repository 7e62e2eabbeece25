//! `raybench report` and `raybench merge` end to end, on small matrices: the files a report
//! promises, the results schema, sharding by scene, merging, and bad options.

mod common;

use common::raybench;
use raybench_report::charts::backend_style;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// This suite's scratch folder `name` ([`common::fresh_path`]).
fn tmp_dir(name: &str) -> PathBuf {
    common::fresh_path("report", name)
}

/// The SVG text of chart `stem` of the report in `dir`, checked to be one SVG document
/// whose ids all start with the stem.
fn chart(dir: &Path, stem: &str) -> String {
    let path = dir.join(format!("charts/{stem}.svg"));
    let svg = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
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

fn results(dir: &Path) -> Value {
    let text = std::fs::read_to_string(dir.join("results.json")).expect("results.json written");
    serde_json::from_str(&text).expect("results.json is JSON")
}

/// A small report: two self-contained scenes, three backends, 32 x 32, no scaling.
fn small_report(dir: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "report",
        "--scenes",
        "spheres,cornell-box",
        "--backends",
        "naive,bvh,packet",
        "--size",
        "32",
        "--repeat",
        "1",
        "--no-scaling",
        "--out",
        dir.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    raybench(&args)
}

#[test]
fn report_writes_markdown_json_images_and_charts() {
    let dir = tmp_dir("small");
    let out = small_report(&dir, &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = results(&dir);
    assert_eq!(r["schema"], "raybench-results/1");
    let machine = &r["shards"][0]["machine"];
    assert!(machine["cpu"].as_str().is_some_and(|s| !s.is_empty()));
    assert!(machine["isa"].as_str().unwrap().contains("lanes"));
    let runs = r["runs"].as_array().unwrap();
    // spheres: cast with the five ray sets + whitted; cornell-box: the same + path.
    assert_eq!(runs.len(), (6 + 7) * 3);
    // Every ray set ran on both scenes, with rays: the Cornell box, lit by its emissive
    // quad alone, has shadow rays too.
    for set in ["primary", "incoherent", "shadow", "ao", "diffuse"] {
        for scene in ["spheres", "cornell-box"] {
            assert!(
                runs.iter().any(|r| r["ray_set"] == set
                    && r["scene"] == scene
                    && r["rays"].as_u64().is_some_and(|n| n > 0)),
                "no {set} rays on {scene}"
            );
        }
    }
    for run in runs {
        assert_eq!(run["status"], "ok", "{run}");
        assert_eq!(run["reference"], "naive");
        let eq = &run["equality"];
        assert_eq!(eq["pass"], true, "{run}");
        assert_eq!(eq["identical"], true, "{run}");
        // Identical images: an infinite PSNR is null, flagged by `identical`.
        assert!(eq["psnr_db"].is_null());
        assert!(run["mrays_per_s"].as_f64().unwrap() > 0.0);
        assert!(run["seconds"]["median"].as_f64().unwrap() > 0.0);
        assert!(run["tests_per_ray"].as_f64().unwrap() > 0.0);
        if run["ray_set"] == "primary" {
            assert!(eq["flip_mean"].as_f64() == Some(0.0), "{run}");
        }
        // Structure quality: trees for bvh and packet, none for naive.
        let q = &run["quality"];
        if run["backend"] == "naive" {
            assert!(q.is_null(), "{run}");
        } else {
            assert_eq!(q["kind"], "tree", "{run}");
            assert_eq!(
                (q["c_t"].as_f64(), q["c_i"].as_f64()),
                (Some(1.0), Some(1.0))
            );
            assert!(q["sah"].as_f64().unwrap() > 1.0, "{run}");
            assert!(q["epo"].as_f64().unwrap() >= 0.0, "{run}");
            assert_eq!(q["leaf_sizes"].as_array().unwrap().len(), 7, "{run}");
        }
    }
    // The reference's images exist; identical backends write none.
    for run in runs {
        match run["images"]["color"].as_str() {
            Some(img) => {
                assert_eq!(run["backend"], "naive");
                assert!(dir.join(img).is_file(), "{img}");
            }
            None => assert!(run["backend"] != "naive" || run["ray_set"] != "primary"),
        }
    }
    let md = std::fs::read_to_string(dir.join("REPORT.md")).unwrap();
    assert!(md.starts_with("# raybench report"));
    assert!(md.contains("## Summary") && md.contains("### cornell-box"));
    assert!(md.contains("## Structure quality"), "{md}");
    assert!(md.contains("| cornell-box | packet | "), "{md}");
    assert!(
        md.contains("the tree with the lowest SAH cost was the fastest in"),
        "{md}"
    );
    // Charts: SVG only, each shown in REPORT.md; the throughput chart shows every backend
    // in its own colour, with a tooltip on each bar.
    assert!(!md.contains("> Charts:"), "{md}");
    assert!(
        md.contains(
            "**Throughput, cast (primary rays)**\n\n![Throughput, cast (primary rays)](charts/throughput-cast-primary.svg)"
        ),
        "{md}"
    );
    let svg = chart(&dir, "throughput-cast-primary");
    for backend in ["naive", "bvh", "packet"] {
        let colour = backend_style(backend).unwrap().colour;
        assert!(shows_text(&svg, backend), "{backend}: {svg}");
        assert!(
            svg.contains(&format!("fill=\"{colour}\"")),
            "{backend}: {svg}"
        );
        assert!(
            svg.contains(&format!("<title>{backend} on cornell-box\n")),
            "{svg}"
        );
    }
    assert!(shows_text(&svg, "rays per second (millions)"), "{svg}");
    // Every run ran: no stub marks a backend that did not.
    assert!(!shows_text(&svg, "×"), "{svg}");
    for chart_name in ["sah", "epo"] {
        for set in ["primary", "incoherent"] {
            let stem = format!("quality-{chart_name}-cast-{set}");
            assert!(
                md.contains(&format!("](charts/{stem}.svg)")),
                "{stem}: {md}"
            );
            chart(&dir, &stem);
        }
    }
    let pngs = std::fs::read_dir(dir.join("charts"))
        .unwrap()
        .filter(|e| e.as_ref().unwrap().path().extension() != Some("svg".as_ref()))
        .count();
    assert_eq!(pngs, 0, "only SVG charts");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn shards_split_by_scene_and_merge_back() {
    let (a, b, m) = (tmp_dir("shard1"), tmp_dir("shard2"), tmp_dir("merged"));
    for (dir, shard) in [(&a, "1/2"), (&b, "2/2")] {
        let out = small_report(dir, &["--shard", shard]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let scenes = |dir: &Path| -> Vec<String> {
        let mut s: Vec<String> = results(dir)["runs"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r["scene"].as_str().unwrap().to_string())
            .collect();
        s.dedup();
        s
    };
    assert_eq!(scenes(&a), ["spheres"]);
    assert_eq!(scenes(&b), ["cornell-box"]);
    let out = raybench(&[
        "merge",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--out",
        m.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = results(&m);
    assert_eq!(r["shards"].as_array().unwrap().len(), 2);
    assert_eq!(r["shards"][1]["index"], 2);
    let runs = r["runs"].as_array().unwrap();
    assert_eq!(runs.len(), (6 + 7) * 3);
    assert!(
        runs.iter()
            .any(|r| r["scene"] == "cornell-box" && r["shard"] == 1)
    );
    for run in runs {
        if let Some(img) = run["images"]["color"].as_str() {
            assert!(m.join(img).is_file(), "{img} not copied");
        }
    }
    assert!(
        std::fs::read_to_string(m.join("REPORT.md"))
            .unwrap()
            .contains("Shard 2/2")
    );
    // A shard given twice, as the same folder or inside a merged report, is refused: it
    // would double its rows.
    let again = tmp_dir("merged-again");
    for pair in [[&a, &a], [&m, &b]] {
        let out = raybench(&[
            "merge",
            pair[0].to_str().unwrap(),
            pair[1].to_str().unwrap(),
            "--out",
            again.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{pair:?} merged: {stderr}");
        assert_ne!(out.status.code(), Some(101), "{stderr}");
        let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
        assert_eq!(errors.len(), 1, "{stderr}");
        assert!(errors[0].contains("same shard"), "{stderr}");
        assert!(!again.join("results.json").exists());
    }
    // A copy of a shard (another run of the same part) measures the same runs.
    let rerun = tmp_dir("shard1-rerun");
    assert!(small_report(&rerun, &["--shard", "1/2"]).status.success());
    let out = raybench(&[
        "merge",
        a.to_str().unwrap(),
        rerun.to_str().unwrap(),
        "--out",
        again.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("both measure spheres"),
        "{stderr}"
    );
    for d in [a, b, m, again, rerun] {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn bad_report_options_are_refused_cleanly() {
    let dir = tmp_dir("bad");
    let d = dir.to_str().unwrap();
    for args in [
        vec!["report", "--shard", "3/2", "--out", d],
        vec!["report", "--shard", "0/2", "--out", d],
        vec!["report", "--shard", "x", "--out", d],
        vec!["report", "--backends", "nope", "--out", d],
        vec![
            "report",
            "--scenes",
            "no-such-scene",
            "--no-scaling",
            "--out",
            d,
        ],
        vec!["report", "--size", "5", "--out", d],
        vec!["report", "--modes", "raster", "--out", d],
        vec!["report", "--rays", "sideways", "--out", d],
        vec!["report", "--ao-rays", "0", "--out", d],
        vec!["merge", "/nonexistent-raybench-dir", "--out", d],
    ] {
        let out = raybench(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert_ne!(out.status.code(), Some(101), "{args:?} panicked: {stderr}");
        assert!(stderr.contains("error"), "{args:?}: {stderr}");
    }
    // A results file of another schema is refused.
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("results.json"), r#"{"schema": "other/9"}"#).unwrap();
    let out = raybench(&["merge", d, "--out", &format!("{d}-out")]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("schema"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn skipped_scenes_and_experiments_are_listed_once() {
    // No shared meshes: bunny and the Cornell box are skipped, and so is the `pixels`
    // experiment (the bunny at growing sizes). CI=true makes a missing asset an error.
    let (dir, assets) = (tmp_dir("skips"), tmp_dir("no-assets"));
    std::fs::create_dir_all(&assets).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_raybench"))
        .args([
            "report",
            "--scenes",
            "spheres,bunny,cornell-box",
            "--backends",
            "bvh,packet",
            "--size",
            "16",
            "--repeat",
            "1",
            "--experiments",
            "pixels",
            "--out",
            dir.to_str().unwrap(),
        ])
        .env("RAYBENCH_ASSETS", &assets)
        .env_remove("CI")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let r = results(&dir);
    let skipped: Vec<(String, String, String)> = r["skipped"]
        .as_array()
        .expect("a skipped list")
        .iter()
        .map(|s| {
            let file = if s["name"] == "cornell-box" {
                "CornellBox-Original.obj"
            } else {
                "stanford-bunny.obj"
            };
            assert!(s["reason"].as_str().unwrap().contains(file), "{s}");
            assert_eq!(s["shard"], 0);
            (
                s["kind"].as_str().unwrap().to_string(),
                s["name"].as_str().unwrap().to_string(),
                s["status"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    let expected = [
        ("scene", "bunny"),
        ("scene", "cornell-box"),
        ("experiment", "pixels"),
    ];
    assert_eq!(
        skipped,
        expected.map(|(k, n)| (k.to_string(), n.to_string(), "skipped".to_string()))
    );
    let md = std::fs::read_to_string(dir.join("REPORT.md")).unwrap();
    assert!(md.contains("## Skipped"), "{md}");
    for (kind, name) in expected {
        assert!(
            md.contains(&format!("| 1/1 | {kind} `{name}` | skipped |")),
            "{md}"
        );
        // Said once on stderr, not once per backend or per point.
        let lines = stderr
            .lines()
            .filter(|l| l.starts_with(&format!("skipped {kind} {name}: ")))
            .count();
        assert_eq!(lines, 1, "{kind} {name}: {stderr}");
    }
    assert_eq!(
        stderr.lines().filter(|l| l.contains("bunny")).count(),
        2,
        "{stderr}"
    );
    // A merge carries the skips through.
    let merged = tmp_dir("skips-merged");
    let out = raybench(&[
        "merge",
        dir.to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(results(&merged)["skipped"], r["skipped"]);
    assert!(
        std::fs::read_to_string(merged.join("REPORT.md"))
            .unwrap()
            .contains("| 1/1 | experiment `pixels` | skipped |")
    );
    for d in [dir, assets, merged] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// A scaling experiment end to end (`spp`: the Cornell box, named by its `[benchmark]`
/// table, path traced at growing samples per pixel): its points, fits, table and chart.
#[test]
fn a_scaling_experiment_runs_and_is_written() {
    let assets = std::env::var("RAYBENCH_ASSETS").unwrap_or_default();
    if !Path::new(&assets)
        .join("cornell-box/CornellBox-Original.obj")
        .is_file()
    {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true but the Cornell box is missing"
        );
        eprintln!("SKIPPED: the Cornell box is not in RAYBENCH_ASSETS");
        return;
    }
    let dir = tmp_dir("scaling");
    let out = raybench(&[
        "report",
        "--quick",
        "--scenes",
        "spheres",
        "--modes",
        "cast",
        "--backends",
        "bvh",
        "--size",
        "16",
        "--repeat",
        "1",
        "--experiments",
        "spp",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = results(&dir);
    let points = r["scaling"].as_array().unwrap();
    // --quick: K = 1, 2, 4, 8, 16.
    assert_eq!(points.len(), 5);
    for p in points {
        assert_eq!(p["experiment"], "spp");
        assert_eq!(p["series"], "cornell-box");
        assert_eq!(p["backend"], "bvh");
    }
    assert_eq!(r["fits"][0]["experiment"], "spp");
    let md = std::fs::read_to_string(dir.join("REPORT.md")).unwrap();
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

/// A scene with two cameras: every run covers both (its rays are theirs together), each
/// camera's figures are recorded and tabulated, the verdict opens the report, and a run set
/// beside itself (`compare-results`, `--baseline`) finds its workloads in both runs.
#[test]
fn several_cameras_verdict_and_baseline() {
    let dir = tmp_dir("cameras");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("two-views.toml");
    std::fs::write(
        &scene,
        r#"name = "two-views"
[[camera]]
name = "front"
position = [0, 1, 6]
look_at = [0, 0.5, 0]
[[camera]]
name = "top"
position = [0, 8, 0.5]
look_at = [0, 0, 0]
[[light]]
kind = "point"
position = [2, 5, 3]
intensity = [20, 20, 20]
[[object]]
kind = "sphere"
center = [0, 0.5, 0]
radius = 1
[[object]]
kind = "sphere"
center = [1.5, 0.3, 1]
radius = 0.4
[[object]]
kind = "plane"
point = [0, -0.5, 0]
normal = [0, 1, 0]
"#,
    )
    .unwrap();
    let out_dir = dir.join("run");
    let report = |out: &Path, extra: &[&str]| {
        let mut args = vec![
            "report",
            "--scenes",
            scene.to_str().unwrap(),
            "--backends",
            "naive,bvh",
            "--modes",
            "cast",
            "--size",
            "24",
            "--repeat",
            "2",
            "--no-scaling",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        raybench(&args)
    };
    let out = report(&out_dir, &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = results(&out_dir);
    let runs = r["runs"].as_array().unwrap();
    for run in runs {
        let cameras = run["cameras"].as_array();
        if run["ray_set"] == "incoherent" {
            // The random rays do not start at a camera: measured once.
            assert!(cameras.is_none(), "{run}");
            continue;
        }
        let cameras = cameras.expect("both cameras recorded");
        let names: Vec<&str> = cameras
            .iter()
            .map(|c| c["name"].as_str().unwrap())
            .collect();
        assert_eq!(names, ["front", "top"], "{run}");
        let rays: u64 = cameras.iter().map(|c| c["rays"].as_u64().unwrap()).sum();
        assert_eq!(run["rays"].as_u64().unwrap(), rays);
        if run["ray_set"] == "primary" {
            assert_eq!(rays, 2 * 24 * 24);
        } else {
            // Derived from both cameras' primary hits.
            assert!(rays > 0 && cameras.iter().all(|c| c["rays"].as_u64() > Some(0)));
        }
        if run["backend"] == "bvh" {
            assert!(cameras.iter().all(|c| c["identical"] == true), "{run}");
        }
    }
    let md = std::fs::read_to_string(out_dir.join("REPORT.md")).unwrap();
    assert!(md.find("## Verdict").unwrap() < md.find("## How to read").unwrap());
    assert!(md.contains("Each of the scene's 2 cameras"), "{md}");
    assert!(md.contains("| `front` | `top` |"), "{md}");
    assert!(md.contains("bit-identical in 5 of 5 workloads"), "{md}");

    // The run beside itself: every workload in both, none faster or slower.
    let out = raybench(&[
        "compare-results",
        out_dir.to_str().unwrap(),
        out_dir.join("results.json").to_str().unwrap(),
        "--json",
    ]);
    assert!(out.status.success());
    let c: Value = serde_json::from_slice(&out.stdout).unwrap();
    let changes = c["changes"].as_array().unwrap();
    assert_eq!(changes.len(), runs.len());
    assert!(
        changes
            .iter()
            .all(|x| x["verdict"] == "within noise" && x["ratio"] == 1.0)
    );
    // --baseline adds the section to a new run's report.
    let second = dir.join("second");
    let out = report(&second, &["--baseline", out_dir.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let md = std::fs::read_to_string(second.join("REPORT.md")).unwrap();
    assert!(md.contains("## Before and after"), "{md}");
    assert!(md.contains("10 workloads in both"), "{md}");
    // A missing baseline fails before measuring anything.
    let out = report(&dir.join("third"), &["--baseline", "/nonexistent-raybench"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.starts_with("error:"),
        "{stderr}"
    );
    assert!(!dir.join("third").join("results.json").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// `report --rays-file` replays an exported ray set on the scene as the workload
/// `cast-file`, alone unless `--rays` names sets too, every backend on the same rays.
#[test]
fn report_replays_a_ray_file() {
    let dir = tmp_dir("replay");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("ao.rays");
    let out = raybench(&[
        "rays",
        "export",
        "spheres",
        "--rays",
        "ao",
        "--width",
        "20",
        "--height",
        "20",
        "--out",
        file.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // Header: 8-byte magic, version, count (docs/rays-format.md).
    let bytes = std::fs::read(&file).unwrap();
    let count = u64::from_le_bytes(bytes[12..20].try_into().unwrap());
    assert!(count > 0);
    for (extra, sets) in [
        (vec![], vec!["file"]),
        (vec!["--rays", "primary"], vec!["primary", "file"]),
    ] {
        let run_dir = dir.join(format!("run-{}", sets.len()));
        let mut args = vec![
            "report",
            "--scenes",
            "spheres",
            "--backends",
            "naive,bvh",
            "--modes",
            "cast",
            "--size",
            "16",
            "--repeat",
            "1",
            "--no-scaling",
            "--rays-file",
            file.to_str().unwrap(),
            "--out",
            run_dir.to_str().unwrap(),
        ];
        args.extend_from_slice(&extra);
        let out = raybench(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let r = results(&run_dir);
        let runs = r["runs"].as_array().unwrap();
        let got: Vec<&str> = runs
            .iter()
            .filter(|r| r["backend"] == "bvh")
            .map(|r| r["ray_set"].as_str().unwrap())
            .collect();
        assert_eq!(got, sets);
        for run in runs.iter().filter(|r| r["ray_set"] == "file") {
            assert_eq!(run["rays"].as_u64(), Some(count), "{run}");
            assert_eq!(run["equality"]["identical"], true, "{run}");
        }
        let md = std::fs::read_to_string(run_dir.join("REPORT.md")).unwrap();
        assert!(md.contains("replayed from the run's ray file"), "{md}");
    }
    // A bad ray file fails before anything is measured, with one error line.
    std::fs::write(dir.join("bad.rays"), b"RAYBENCH").unwrap();
    let out = raybench(&[
        "report",
        "--scenes",
        "spheres",
        "--no-scaling",
        "--rays-file",
        dir.join("bad.rays").to_str().unwrap(),
        "--out",
        dir.join("bad").to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert_eq!(
        stderr.lines().filter(|l| l.starts_with("error:")).count(),
        1,
        "{stderr}"
    );
    assert!(!dir.join("bad").join("results.json").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The `presets` experiment end to end on the scene whose `[benchmark]` table names it (the
/// bunny), with two presets named as `BACKEND:PRESET`: a build time, a camera-ray and an
/// incoherent point per preset, its tables and charts.
#[test]
fn the_presets_experiment_runs_and_is_written() {
    let assets = std::env::var("RAYBENCH_ASSETS").unwrap_or_default();
    if !Path::new(&assets)
        .join("bunny/stanford-bunny.obj")
        .is_file()
    {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true but the bunny is missing"
        );
        eprintln!("SKIPPED: the bunny is not in RAYBENCH_ASSETS");
        return;
    }
    let dir = tmp_dir("presets");
    let out = raybench(&[
        "report",
        "--quick",
        "--scenes",
        "spheres",
        "--modes",
        "cast",
        "--backends",
        "bvh:fast,bvh:quality",
        "--size",
        "16",
        "--repeat",
        "1",
        "--experiments",
        "presets",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = results(&dir);
    let points = r["scaling"].as_array().unwrap();
    // --quick: the bunny alone; two presets, two ray sets.
    assert_eq!(points.len(), 4, "{points:?}");
    for p in points {
        assert_eq!(p["experiment"], "presets");
        assert!(p["build_seconds"].as_f64().unwrap() > 0.0, "{p}");
        assert!(p["memory_bytes"].as_u64().unwrap() > 0, "{p}");
        assert_eq!(p["rays"], 256);
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
    let md = std::fs::read_to_string(dir.join("REPORT.md")).unwrap();
    assert!(
        md.contains("## Build presets: build time against trace time"),
        "{md}"
    );
    assert!(md.contains("| bunny | bvh:fast |"), "{md}");
    assert!(md.contains("| bunny | bvh | "), "{md}");
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
    let out = raybench(&[
        "report",
        "--quick",
        "--scenes",
        "spheres",
        "--modes",
        "cast",
        "--backends",
        "bvh,packet",
        "--size",
        "16",
        "--repeat",
        "1",
        "--experiments",
        "instancing",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = results(&dir);
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
    let md = std::fs::read_to_string(dir.join("REPORT.md")).unwrap();
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
    let out = raybench(&[
        "merge",
        dir.to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let section = |md: &str| {
        let start = md.find("## Instancing").expect("the section");
        let rest = &md[start + 3..];
        md[start..start + 3 + rest.find("\n## ").unwrap_or(rest.len())].to_string()
    };
    let again = std::fs::read_to_string(merged.join("REPORT.md")).unwrap();
    assert_eq!(section(&md), section(&again));
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&merged);
}

/// Both GPU backends (`wgpu` over the BVH2, `wgpu-cwbvh` over the CWBVH) render every kind,
/// here a height field with bilinear cells, and are in the "GPU phases" table; a backend
/// that cannot run a scene (here the GPU backends with no adapter by that name: unavailable,
/// as on a machine without a GPU) keeps its place in the throughput charts: a marked stub
/// whose tooltip says why, never a silent gap.
#[test]
fn a_backend_that_did_not_run_is_marked_in_the_charts() {
    let dir = tmp_dir("not-run");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("bilinear.toml");
    std::fs::write(
        &scene,
        "name = \"bilinear\"\n[camera]\nposition = [0, 2, 3]\nlook_at = [0, 0, 0]\nfov = 50\n\
         [[light]]\nkind = \"point\"\nposition = [2, 4, 2]\nintensity = [20, 20, 20]\n\
         [[object]]\nkind = \"height_field\"\nsource = \"terrain:8\"\ncells = \"bilinear\"\n",
    )
    .unwrap();
    let scenes = format!("spheres,{}", scene.display());
    let report = |out: &Path, adapter: Option<&str>| {
        let mut command = Command::new(env!("CARGO_BIN_EXE_raybench"));
        if let Some(name) = adapter {
            command.env("WGPU_ADAPTER_NAME", name);
        }
        #[rustfmt::skip]
        let args = [
            "report", "--scenes", &scenes, "--backends", "naive,wgpu,wgpu-cwbvh",
            "--modes", "cast", "--size", "16", "--repeat", "1", "--no-scaling",
            "--out", out.to_str().unwrap(),
        ];
        let out = command.args(args).output().expect("raybench runs");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    // Where an adapter exists, both GPU backends run both scenes.
    report(&dir, None);
    let r = results(&dir);
    let md = std::fs::read_to_string(dir.join("REPORT.md")).unwrap();
    let runs = r["runs"].as_array().unwrap();
    for gpu in ["wgpu", "wgpu-cwbvh"] {
        let status = |scene: &str| {
            runs.iter()
                .find(|r| r["backend"] == gpu && r["scene"] == scene)
                .unwrap_or_else(|| panic!("a {gpu} run on {scene}"))["status"]
                .as_str()
                .unwrap()
                .to_string()
        };
        if status("spheres") == "ok" {
            assert_eq!(status("bilinear"), "ok", "{gpu} on bilinear");
            let phases = &md[md.find("## GPU phases").expect("a GPU phases table")..];
            assert!(phases.contains(&format!("| {gpu} |")), "{phases}");
        } else {
            assert_eq!(status("spheres"), "unavailable", "{gpu} on spheres");
        }
    }
    // With no such adapter, the GPU columns are stubs that say why.
    let none = dir.join("no-adapter");
    report(&none, Some("no such adapter 5c1d"));
    let r = results(&none);
    let svg = chart(&none, "throughput-cast-primary");
    for gpu in ["wgpu", "wgpu-cwbvh"] {
        let run = r["runs"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["backend"] == gpu && r["scene"] == "bilinear")
            .unwrap_or_else(|| panic!("a {gpu} run on bilinear"));
        assert_eq!(run["status"], "unavailable", "{run}");
        assert!(
            svg.contains(&format!("<title>{gpu} on bilinear: unavailable: ")),
            "{svg}"
        );
        let colour = backend_style(gpu).unwrap().colour;
        assert!(svg.contains(&format!("stroke=\"{colour}\"")), "{svg}");
    }
    assert!(shows_text(&svg, "×"), "{svg}");
    assert!(shows_text(&svg, "× did not run (hover: why)"), "{svg}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The main job (`report --quick`, every backend) leaves the GPU backends out when the
/// adapter is a software one (lavapipe in CI), saying so under "Skipped"; where the adapter
/// is a GPU they run, and where there is none they are runs marked unavailable.
#[test]
fn a_quick_run_leaves_software_gpus_out() {
    let dir = tmp_dir("quick-software");
    #[rustfmt::skip]
    let out = raybench(&[
        "report", "--quick", "--scenes", "spheres", "--modes", "cast", "--rays", "primary",
        "--size", "16", "--repeat", "1", "--no-scaling", "--out", dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = results(&dir);
    let runs = r["runs"].as_array().unwrap();
    let skipped = r["skipped"].as_array().unwrap();
    let md = std::fs::read_to_string(dir.join("REPORT.md")).unwrap();
    for gpu in ["wgpu", "wgpu-cwbvh"] {
        let ran = runs.iter().any(|r| r["backend"] == gpu);
        let left_out = skipped
            .iter()
            .find(|k| k["kind"] == "backend" && k["name"] == gpu);
        if raybench_registry::software_device().is_some() {
            assert!(!ran, "{gpu} ran on a software adapter");
            let k = left_out.unwrap_or_else(|| panic!("{gpu} is not listed as skipped"));
            assert!(
                k["reason"].as_str().unwrap().contains("software adapter"),
                "{k}"
            );
            assert!(md.contains(&format!("backend `{gpu}` | skipped |")), "{md}");
        } else {
            assert!(ran && left_out.is_none(), "{gpu}: {skipped:?}");
        }
    }
    assert!(
        runs.iter()
            .any(|r| r["backend"] == "bvh" && r["status"] == "ok")
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A derived set without rays (shadow rays in a scene without lights) is not timed: the
/// workload is listed as skipped with the reason, and the other sets run.
#[test]
fn a_workload_without_rays_is_skipped_with_its_reason() {
    let dir = tmp_dir("no-lights");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("dark.toml");
    std::fs::write(
        &scene,
        "name = \"dark\"\n[[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n",
    )
    .unwrap();
    let out_dir = dir.join("out");
    let out = raybench(&[
        "report",
        "--scenes",
        scene.to_str().unwrap(),
        "--backends",
        "naive,bvh",
        "--modes",
        "cast",
        "--rays",
        "primary,shadow",
        "--size",
        "16",
        "--repeat",
        "1",
        "--no-scaling",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = results(&out_dir);
    let sets: Vec<&str> = r["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["ray_set"].as_str().unwrap())
        .collect();
    assert_eq!(sets, ["primary", "primary"]);
    let skipped = r["skipped"].as_array().unwrap();
    assert_eq!(skipped.len(), 1, "{skipped:?}");
    assert_eq!(skipped[0]["kind"], "workload");
    assert_eq!(skipped[0]["name"], "dark cast-shadow");
    assert!(skipped[0]["reason"].as_str().unwrap().contains("no light"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A scene over the machine's memory budget (the largest scaling points on a small machine)
/// is skipped with the budget's message, even under `CI=true`, and the run goes on.
#[test]
fn a_scene_over_the_memory_budget_is_skipped() {
    let dir = tmp_dir("over-budget");
    let out = Command::new(env!("CARGO_BIN_EXE_raybench"))
        .args([
            "report",
            "--scenes",
            "spheres,soup:200000",
            "--backends",
            "bvh",
            "--modes",
            "cast",
            "--rays",
            "primary",
            "--size",
            "16",
            "--repeat",
            "1",
            "--no-scaling",
            "--out",
            dir.to_str().unwrap(),
        ])
        .env("RAYBENCH_MEMORY_LIMIT", "8M")
        .env("CI", "true")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = results(&dir);
    assert_eq!(r["runs"].as_array().unwrap().len(), 1);
    let skipped = r["skipped"].as_array().unwrap();
    assert_eq!(skipped.len(), 1, "{skipped:?}");
    assert_eq!(skipped[0]["name"], "soup:200000");
    assert!(
        skipped[0]["reason"]
            .as_str()
            .unwrap()
            .contains("memory budget"),
        "{skipped:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The attribute values `name="..."` of an HTML text.
fn attributes<'a>(html: &'a str, name: &str) -> Vec<&'a str> {
    let key = format!(" {name}=\"");
    html.match_indices(&key)
        .map(|(i, _)| {
            let rest = &html[i + key.len()..];
            &rest[..rest.find('"').unwrap()]
        })
        .collect()
}

/// `REPORT.html` (written by `report` and by `merge`): one page opening with the verdict and
/// a table of contents, every Markdown table sortable, one viewer per scene and mode with
/// frames, and every file it shows beside it (relative paths, nothing from the network).
/// The browser test (`tests/browser.rs`) drives the page; this checks what it is made of.
#[test]
fn report_html_is_one_page_with_viewers_and_local_files() {
    let (dir, merged) = (tmp_dir("html"), tmp_dir("html-merged"));
    let out = small_report(&dir, &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = raybench(&[
        "merge",
        dir.to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for d in [&dir, &merged] {
        let html = std::fs::read_to_string(d.join("REPORT.html")).expect("REPORT.html written");
        let md = std::fs::read_to_string(d.join("REPORT.md")).unwrap();
        assert!(html.starts_with("<!DOCTYPE html>"), "{html}");
        assert!(html.contains("<nav id=\"toc\""));
        // The verdict first: before the shards' machines and the reading guide.
        let at = |needle: &str| html.find(needle).unwrap_or_else(|| panic!("{needle}"));
        assert!(at("<h2 id=\"verdict\">") < at("<details class=\"machines\">"));
        assert!(at("<details class=\"machines\">") < at("<h2 id=\"how-to-read-this-report\">"));
        for id in attributes(&html, "href")
            .into_iter()
            .filter(|h| h.starts_with('#'))
        {
            assert!(
                html.contains(&format!("id=\"{}\"", &id[1..])),
                "a link to {id} without its target"
            );
        }
        // Every Markdown table, sortable.
        let tables = md.lines().filter(|l| l.starts_with("|---")).count();
        assert!(tables > 5);
        assert_eq!(html.matches("<table class=\"sortable\">").count(), tables);
        // One viewer per scene and mode with frames: spheres cast and whitted, the Cornell
        // box cast, whitted and path; naive the reference, then bvh and packet.
        assert!(
            !html.contains("raybench-viewer"),
            "a marker left in the page"
        );
        let viewers = attributes(&html, "id")
            .into_iter()
            .filter(|i| i.starts_with("viewer-"))
            .collect::<Vec<_>>();
        assert_eq!(
            viewers,
            [
                "viewer-spheres-cast",
                "viewer-spheres-whitted",
                "viewer-cornell-box-cast",
                "viewer-cornell-box-whitted",
                "viewer-cornell-box-path"
            ]
        );
        let picks: Vec<&str> = attributes(&html, "data-backend");
        assert!(
            picks.windows(3).any(|w| w == ["naive", "bvh", "packet"]),
            "{picks:?}"
        );
        assert_eq!(html.matches("data-reference=\"true\"").count(), 5);
        // Files beside the page, by relative paths that exist; no network.
        let mut files = attributes(&html, "src");
        // The charts, embedded as objects.
        files.extend(attributes(&html, "data"));
        for a in ["data-image", "data-ids", "data-flip"] {
            files.extend(attributes(&html, a).into_iter().filter(|f| !f.is_empty()));
        }
        assert!(files.len() >= 5);
        for f in files {
            assert!(!f.contains("//") && !f.starts_with('/'), "{f}");
            assert!(d.join(f).is_file(), "{f} is not beside the page");
        }
        // No address but the SVG namespace: nothing is fetched.
        let without_namespaces = html
            .replace("http://www.w3.org/2000/svg", "")
            .replace("http://www.w3.org/1999/xlink", "");
        assert!(
            !without_namespaces.contains("http"),
            "an address in the page"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&merged);
}
