//! The report of a small matrix: the files it promises (Markdown, JSON, images, SVG charts),
//! the results schema, several cameras with the verdict and a baseline, and a ray file
//! replayed as a workload.

use crate::common::{assert_clean_error, assert_success, raybench_ok, results};
use crate::{chart, common, markdown, report, scene_dir, shows_text, small_report, tmp_dir};
use raybench_report::charts::backend_style;
use serde_json::Value;
use std::path::Path;

#[test]
fn report_writes_markdown_json_images_and_charts() {
    let dir = tmp_dir("small");
    small_report(&dir, &[]);
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
    // Each ray's own work: percentiles on every ray-casting workload of bvh (walked ray by
    // ray, so its rays traced alone do the work of its counted pass), and the camera rays'
    // heat map of visits per pixel; none for naive, which visits no nodes.
    for run in runs.iter().filter(|r| r["mode"] == "cast") {
        let costs = &run["ray_costs"];
        let heat = run["images"]["visits"].as_str();
        if run["backend"] == "naive" {
            assert!(costs.is_null() && heat.is_none(), "{run}");
            continue;
        }
        if run["backend"] != "bvh" {
            continue;
        }
        assert_eq!(costs["rays"].as_u64(), run["rays"].as_u64(), "{run}");
        for (what, mean) in [("tests", "tests_per_ray"), ("visits", "visits_per_ray")] {
            let at = |k: &str| {
                costs[what][k]
                    .as_u64()
                    .unwrap_or_else(|| panic!("{what} {k}: {run}"))
            };
            let order = ["min", "p50", "p90", "p99", "max"].map(at);
            assert!(order.windows(2).all(|w| w[0] <= w[1]), "{what}: {order:?}");
            let mean = run[mean].as_f64().unwrap();
            assert!(
                order[0] as f64 <= mean && mean <= order[4] as f64,
                "{what}: mean {mean}, {order:?}"
            );
        }
        assert!(
            costs["visits"]["max"].as_u64() > costs["visits"]["min"].as_u64(),
            "{run}"
        );
        if run["ray_set"] == "primary" {
            let file = heat.unwrap_or_else(|| panic!("no heat map: {run}"));
            let img = image::open(dir.join(file)).unwrap();
            assert_eq!((img.width(), img.height()), (32, 32), "{file}");
        } else {
            assert!(heat.is_none(), "{run}");
        }
    }
    let md = markdown(&dir);
    assert!(
        md.contains(
            "Each ray's own work, every ray traced alone in an untimed pass: the nearest-rank \
             percentiles of the primitive tests and of the node or cell visits per ray, over 1024 \
             rays (the means are the table's above).\n\n\
             | backend | tests p50 | tests p90 | tests p99 | tests max |"
        ),
        "{md}"
    );
    assert!(md.starts_with("# raybench report"));
    assert!(md.contains("## Summary") && md.contains("### cornell-box"));
    // The empty scene: every backend's frame and batch of 32 x 32 camera rays that all
    // miss, on the run's worker threads, and its table after the summary.
    let empty = r["empty_scene"].as_array().unwrap();
    let names: Vec<&str> = empty
        .iter()
        .map(|e| e["backend"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["naive", "bvh", "packet"]);
    for e in empty {
        assert_eq!(
            (e["width"].as_u64(), e["rays"].as_u64()),
            (Some(32), Some(1024))
        );
        assert_eq!(e["threads"], machine["threads"], "{e}");
        assert!(e["frame"]["median"].as_f64().unwrap() > 0.0, "{e}");
        assert!(e["trace"]["median"].as_f64().unwrap() > 0.0, "{e}");
    }
    assert!(
        md.contains("The pipeline's fixed cost on an empty scene (no primitives: all 32 x 32 camera rays miss)")
            && md.contains("| backend | threads | frame ns/ray [interval] |"),
        "{md}"
    );
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

/// A scene with two cameras: every run covers both (its rays are theirs together), each
/// camera's figures are recorded and tabulated, the verdict opens the report, and a run set
/// beside itself (`compare-results`, `--baseline`) finds its workloads in both runs.
#[test]
fn several_cameras_verdict_and_baseline() {
    let (dir, scene) = scene_dir(
        "cameras",
        "two-views.toml",
        r#"name = "two-views"
camera = [
    { name = "front", position = [0, 1, 6], look_at = [0, 0.5, 0] },
    { name = "top", position = [0, 8, 0.5], look_at = [0, 0, 0] },
]
light = [{ kind = "point", position = [2, 5, 3], intensity = [20, 20, 20] }]
object = [
    { kind = "sphere", center = [0, 0.5, 0], radius = 1 },
    { kind = "sphere", center = [1.5, 0.3, 1], radius = 0.4 },
    { kind = "plane", point = [0, -0.5, 0], normal = [0, 1, 0] },
]
"#,
    );
    let out_dir = dir.join("run");
    let report = |out: &Path, extra: &[&str]| {
        #[rustfmt::skip]
        let mut args = vec![
            "--scenes", &scene, "--backends", "naive,bvh", "--modes", "cast",
            "--size", "24", "--repeat", "2", "--min-sample", "0", "--no-scaling",
        ];
        args.extend_from_slice(extra);
        report(out, &args)
    };
    let out = report(&out_dir, &[]);
    assert_success(&out);
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
    let md = markdown(&out_dir);
    assert!(md.find("## Verdict").unwrap() < md.find("## How to read").unwrap());
    assert!(md.contains("Each of the scene's 2 cameras"), "{md}");
    assert!(md.contains("| `front` | `top` |"), "{md}");
    assert!(md.contains("bit-identical in 5 of 5 workloads"), "{md}");

    // The run beside itself: every workload in both, none faster or slower.
    let out = raybench_ok(&[
        "compare-results",
        out_dir.to_str().unwrap(),
        out_dir.join("results.json").to_str().unwrap(),
        "--json",
    ]);
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
    assert_success(&out);
    let md = markdown(&second);
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
    let dir = common::tmp_dir("report", "replay");
    let file = dir.join("ao.rays");
    #[rustfmt::skip]
    let export = [
        "rays", "export", "spheres", "--rays", "ao", "--width", "20", "--height", "20",
        "--out", file.to_str().unwrap(),
    ];
    raybench_ok(&export);
    // Header: 8-byte magic, version, count (docs/rays-format.md).
    let bytes = std::fs::read(&file).unwrap();
    let count = u64::from_le_bytes(bytes[12..20].try_into().unwrap());
    assert!(count > 0);
    for (extra, sets) in [
        (vec![], vec!["file"]),
        (vec!["--rays", "primary"], vec!["primary", "file"]),
    ] {
        let run_dir = dir.join(format!("run-{}", sets.len()));
        #[rustfmt::skip]
        let mut args = vec![
            "--scenes", "spheres", "--backends", "naive,bvh", "--modes", "cast", "--size", "16",
            "--repeat", "1", "--min-sample", "0", "--no-scaling", "--rays-file", file.to_str().unwrap(),
        ];
        args.extend_from_slice(&extra);
        assert_success(&report(&run_dir, &args));
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
        let md = markdown(&run_dir);
        assert!(md.contains("replayed from the run's ray file"), "{md}");
    }
    // A bad ray file fails before anything is measured, with one error line.
    std::fs::write(dir.join("bad.rays"), b"RAYBENCH").unwrap();
    let out = report(
        &dir.join("bad"),
        &[
            "--scenes",
            "spheres",
            "--no-scaling",
            "--rays-file",
            dir.join("bad.rays").to_str().unwrap(),
        ],
    );
    assert_clean_error(&out, "bad.rays");
    assert!(!dir.join("bad").join("results.json").exists());
    let _ = std::fs::remove_dir_all(&dir);
}
