//! What did not run, and how the report says so: scenes and experiments without their
//! assets, a backend without an adapter (a marked stub in the charts), GPU backends on a
//! software adapter, a workload without rays, and a scene over the memory budget.

use crate::common::{assert_success, merge, raybench_command, results};
use crate::{chart, markdown, report, scene_dir, shows_text, tmp_dir};
use raybench_report::charts::backend_style;
use std::path::Path;

#[test]
fn skipped_scenes_and_experiments_are_listed_once() {
    // No shared meshes: bunny and the Cornell box are skipped, and so is the `pixels`
    // experiment (the bunny at growing sizes). CI=true makes a missing asset an error.
    let (dir, assets) = (tmp_dir("skips"), tmp_dir("no-assets"));
    std::fs::create_dir_all(&assets).unwrap();
    let out = raybench_command()
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
            "--min-sample",
            "0",
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
    let md = markdown(&dir);
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
    assert_success(&merge(&[&dir], &merged));
    assert_eq!(results(&merged)["skipped"], r["skipped"]);
    assert!(markdown(&merged).contains("| 1/1 | experiment `pixels` | skipped |"));
    for d in [dir, assets, merged] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// Both GPU backends (`wgpu` over the BVH2, `wgpu-cwbvh` over the CWBVH) render every kind,
/// here a height field with bilinear cells, and are in the "GPU phases" table; a backend
/// that cannot run a scene (here the GPU backends with no adapter by that name: unavailable,
/// as on a machine without a GPU) keeps its place in the throughput charts: a marked stub
/// whose tooltip says why, never a silent gap.
#[test]
fn a_backend_that_did_not_run_is_marked_in_the_charts() {
    let (dir, scene) = scene_dir(
        "not-run",
        "bilinear.toml",
        "name = \"bilinear\"\n[camera]\nposition = [0, 2, 3]\nlook_at = [0, 0, 0]\nfov = 50\n\
         [[light]]\nkind = \"point\"\nposition = [2, 4, 2]\nintensity = [20, 20, 20]\n\
         [[object]]\nkind = \"height_field\"\nsource = \"terrain:8\"\ncells = \"bilinear\"\n",
    );
    let scenes = format!("spheres,{scene}");
    let report = |out: &Path, adapter: Option<&str>| {
        let mut cmd = raybench_command();
        if let Some(name) = adapter {
            cmd.env("WGPU_ADAPTER_NAME", name);
        }
        #[rustfmt::skip]
        let args = [
            "report", "--scenes", &scenes, "--backends", "naive,wgpu,wgpu-cwbvh",
            "--modes", "cast", "--size", "16", "--repeat", "1", "--min-sample", "0", "--no-scaling",
            "--out", out.to_str().unwrap(),
        ];
        let out = cmd.args(args).output().expect("raybench runs");
        assert_success(&out);
    };
    // Where an adapter exists, both GPU backends run both scenes.
    report(&dir, None);
    let r = results(&dir);
    let md = markdown(&dir);
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
            // Wall time and device time both; a software adapter named as such wherever
            // the backend's figures appear.
            let run = runs
                .iter()
                .find(|r| r["backend"] == gpu && r["scene"] == "spheres")
                .unwrap();
            assert!(
                run["device_seconds"]["median"].as_f64() > Some(0.0),
                "{run}"
            );
            assert!(
                run["device"].as_str().is_some_and(|d| !d.is_empty()),
                "{run}"
            );
            let software = run["software_device"] == true;
            let machine_gpu = r["shards"][0]["machine"]["gpu"].as_str().unwrap();
            assert_eq!(software, machine_gpu.contains("(software"), "{machine_gpu}");
            let label = if software {
                format!("{gpu} (software adapter)")
            } else {
                gpu.to_string()
            };
            let phases = &md[md.find("## GPU phases").expect("a GPU phases table")..];
            assert!(phases.contains(&format!("| {label} |")), "{phases}");
            assert!(phases.contains("| warm-up |"), "{phases}");
            let table = &md[md.find("## Scenes").unwrap()..];
            assert!(table.contains(&format!("| {label} |")), "{table}");
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
    let out = report(&dir, &[
        "--quick", "--scenes", "spheres", "--modes", "cast", "--rays", "primary",
        "--size", "16", "--repeat", "1", "--min-sample", "0", "--no-scaling",
    ]);
    assert_success(&out);
    let r = results(&dir);
    let runs = r["runs"].as_array().unwrap();
    let skipped = r["skipped"].as_array().unwrap();
    let md = markdown(&dir);
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
    let (dir, scene) = scene_dir(
        "no-lights",
        "dark.toml",
        "name = \"dark\"\n[[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n",
    );
    let out_dir = dir.join("out");
    #[rustfmt::skip]
    let out = report(&out_dir, &[
        "--scenes", &scene, "--backends", "naive,bvh", "--modes", "cast",
        "--rays", "primary,shadow", "--size", "16", "--repeat", "1", "--min-sample", "0", "--no-scaling",
    ]);
    assert_success(&out);
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
    let out = raybench_command()
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
            "--min-sample",
            "0",
            "--no-scaling",
            "--out",
            dir.to_str().unwrap(),
        ])
        .env("RAYBENCH_MEMORY_LIMIT", "8M")
        .env("CI", "true")
        .output()
        .unwrap();
    assert_success(&out);
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

/// Modes named by `--modes` run on a scene file too (Whitted lit by the headlight where the
/// scene has no point or directional light, and saying so); the modes asked for that cannot
/// run are listed under Skipped with the reason, never claimed as run; a run where nothing
/// ran is an error; an empty ray file is skipped for what it is.
#[test]
fn modes_asked_for_run_on_scene_files_or_are_listed() {
    let (dir, scene) = scene_dir(
        "modes",
        "dark.toml",
        "name = \"dark\"\n[[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n",
    );
    let d = |name: &str| dir.join(name);
    #[rustfmt::skip]
    let common = [
        "--scenes", scene.as_str(), "--backends", "naive,bvh", "--rays", "primary", "--size", "16",
        "--repeat", "1", "--min-sample", "0", "--no-scaling",
    ];
    fn with<'a>(common: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
        [common, extra].concat()
    }
    // Named: whitted and path run; mip cannot, and says why.
    let out = report(
        &d("named"),
        &with(&common, &["--modes", "whitted,path,mip"]),
    );
    assert_success(&out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        stderr
            .matches("note: scene 'dark' has no point or directional light")
            .count(),
        1,
        "{stderr}"
    );
    let r = results(&d("named"));
    let runs = r["runs"].as_array().unwrap();
    let modes: Vec<&str> = runs.iter().map(|r| r["mode"].as_str().unwrap()).collect();
    assert_eq!(modes, ["whitted", "whitted", "path", "path"]);
    assert!(
        runs.iter()
            .all(|r| r["headlight"].as_bool().unwrap_or(false) == (r["mode"] == "whitted")),
        "{runs:?}"
    );
    let skipped = r["skipped"].as_array().unwrap();
    assert_eq!(skipped.len(), 1, "{skipped:?}");
    assert_eq!(skipped[0]["name"], "dark mip");
    assert!(
        skipped[0]["reason"]
            .as_str()
            .unwrap()
            .contains("the scene has none")
    );
    let md = markdown(&d("named"));
    assert!(md.contains("lit by a headlight"), "{md}");
    assert!(
        !md.contains("every scene, workload and backend ran"),
        "{md}"
    );
    // By default a scene file runs ray casting and lists the modes it was not asked for.
    assert_success(&report(&d("default"), &common));
    let r = results(&d("default"));
    let names: Vec<&str> = r["skipped"]
        .as_array()
        .unwrap()
        .iter()
        .map(|k| k["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["dark whitted", "dark path"]);
    // Nothing to run: an error naming why, after the report lists it.
    let out = report(&d("nothing"), &with(&common, &["--modes", "mip"]));
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(
            "error: nothing ran (workload dark mip: mip shows volumes, and the scene has none)"
        ),
        "{stderr}"
    );
    let md = markdown(&d("nothing"));
    assert!(
        md.contains("Nothing ran.") && md.contains("`dark mip`"),
        "{md}"
    );
    // An empty ray file: skipped as such, not as a scene its rays miss.
    let empty = d("empty.rays");
    raybench_registry::rays_file::write(&empty, &[], false).unwrap();
    #[rustfmt::skip]
    let out = report(&d("replay"), &[
        "--scenes", "spheres", "--backends", "naive,bvh", "--modes", "cast", "--rays", "primary",
        "--rays-file", empty.to_str().unwrap(), "--size", "16", "--repeat", "1", "--min-sample",
        "0", "--no-scaling",
    ]);
    assert_success(&out);
    let r = results(&d("replay"));
    let skipped = r["skipped"].as_array().unwrap();
    assert!(
        skipped.iter().any(|k| k["name"] == "spheres cast-file"
            && k["reason"].as_str().unwrap().contains("holds none")),
        "{skipped:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
