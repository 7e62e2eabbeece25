//! `raybench info`, `scenes`, `backends` and `--version`: the listings (unbuilt backends,
//! the assets folder, the source revision) and the structure-quality table.

use crate::common::{assert_clean_error, raybench, raybench_command, raybench_ok};
use crate::tmp_dir;
use std::process::Output;

#[test]
fn listing_commands() {
    let o = raybench(&["scenes"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("cornell-box"));
    let o = raybench(&["backends"]);
    assert!(String::from_utf8_lossy(&o.stdout).starts_with("naive"));
    let o = raybench(&["backends", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v[0]["name"], "naive");
    let o = raybench(&["--version"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains(env!("CARGO_PKG_VERSION")));
    let o = raybench(&["info", "spheres"]);
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(
        s.contains("sphere") && s.contains("plane") && s.contains("naive"),
        "{s}"
    );
}

#[test]
fn info_prints_structure_quality() {
    let o = raybench_ok(&[
        "info",
        "soup:500",
        "--backends",
        "naive,bvh,packet,grid,grid2",
        "--width",
        "8",
        "--height",
        "8",
        "--epo-samples",
        "256",
    ]);
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(s.contains("C_t = 1, C_i = 1; EPO from 256 points"), "{s}");
    let line = |prefix: &str| {
        s.lines()
            .filter(|l| l.starts_with(prefix))
            .map(str::to_string)
            .collect::<Vec<_>>()
    };
    // Headers of the trees' and the grids' tables, then a row per structure.
    assert_eq!(line("backend").len(), 3, "{s}");
    assert!(line("backend")[1].contains("SAH") && line("backend")[1].contains("EPO ± error"));
    assert!(line("backend")[2].contains("fill") && line("backend")[2].contains("refs/prim"));
    for tree in ["bvh ", "packet "] {
        let rows = line(tree);
        let row = rows.last().unwrap_or_else(|| panic!("no {tree}row: {s}"));
        let sah: f64 = row.split_whitespace().nth(1).unwrap().parse().unwrap();
        assert!(sah > 1.0, "{row}");
        assert!(row.contains(" ± "), "{row}");
    }
    for grid in ["grid ", "grid2 "] {
        assert!(line(grid).last().is_some_and(|r| r.contains('%')), "{s}");
    }
    assert!(
        line("naive")
            .last()
            .is_some_and(|r| r.contains("no structure")),
        "{s}"
    );
}

#[test]
fn info_probes_a_volume_mode_on_the_gpu_as_on_the_cpu() {
    // The GPU kernels have every mode (the volume modes in `kernels/volume.wgsl`), so `info`
    // probes wgpu in `mip` as it probes bvh (a row of figures, one ray per pixel); where
    // there is no GPU, its line gives that reason, as `backends` does, never the mode.
    let o = raybench_ok(&["backends", "--json"]);
    let rows: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let gpu = rows
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["name"] == "wgpu")
        .expect("wgpu listed")
        .clone();
    let o = raybench_ok(&[
        "info",
        "phantom",
        "--mode",
        "mip",
        "--backends",
        "bvh,wgpu",
        "--width",
        "16",
        "--height",
        "16",
        "--threads",
        "1",
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    let line = |name: &str| {
        stdout
            .lines()
            .find(|l| l.split_whitespace().next() == Some(name))
            .unwrap_or_else(|| panic!("no {name} line: {stdout}"))
            .to_string()
    };
    // The fourth column is rays per pixel.
    let probed = |l: &str| l.split_whitespace().nth(3) == Some("1.00");
    assert!(probed(&line("bvh")), "{stdout}");
    let wgpu = line("wgpu");
    if gpu["available"] == true {
        assert!(probed(&wgpu), "{stdout}");
    } else {
        let reason = gpu["reason"].as_str().unwrap();
        assert!(
            wgpu.contains("unavailable: ") && wgpu.contains(reason) && !wgpu.contains("mode"),
            "{stdout}"
        );
    }
}

#[test]
fn listings_name_unbuilt_backends_the_assets_folder_and_the_revision() {
    // Every registered backend, built or not; the unbuilt ones with their cargo feature.
    let o = raybench(&["backends", "--json"]);
    let rows: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for name in ["embree", "embree-packet"] {
        let row = rows
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["name"] == name)
            .unwrap_or_else(|| panic!("{name} not listed: {rows}"));
        if !cfg!(feature = "embree") {
            assert_eq!(row["available"], false);
            assert!(row["reason"].as_str().unwrap().contains("feature `embree`"));
        }
    }
    if !cfg!(feature = "embree") {
        let o = raybench(&["backends"]);
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(
            text.lines()
                .any(|l| l.starts_with("embree-packet") && l.contains("not compiled in")),
            "{text}"
        );
        let o = raybench(&["compare", "spheres", "--backends", "embree"]);
        assert_clean_error(&o, "not compiled in");
    }

    // The assets folder as an absolute path without `..`, and whether it exists.
    let first_line = |o: &Output| {
        let stdout = String::from_utf8_lossy(&o.stdout);
        stdout.lines().next().unwrap_or_default().to_string()
    };
    let dir = tmp_dir("assets-listing");
    let missing = dir.join("sub").join("..").join("nowhere");
    let o = raybench(&["--assets", missing.to_str().unwrap(), "scenes"]);
    let first = first_line(&o);
    assert_eq!(
        first,
        format!(
            "# built-in scenes (assets: {}, which does not exist: set --assets or \
             RAYBENCH_ASSETS)",
            dir.canonicalize().unwrap().join("nowhere").display()
        )
    );
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    let o = raybench_command()
        .arg("scenes")
        .env("RAYBENCH_ASSETS", dir.join("sub").join(".."))
        .output()
        .unwrap();
    let first = first_line(&o);
    assert_eq!(
        first,
        format!(
            "# built-in scenes (assets: {})",
            dir.canonicalize().unwrap().display()
        )
    );
    std::fs::remove_dir_all(dir).unwrap();

    // `--version` names the revision the report records: the checkout's, or `unknown`.
    let o = raybench(&["--version"]);
    let version = raybench_registry::VERSION;
    assert_eq!(
        String::from_utf8_lossy(&o.stdout),
        format!("raybench {version}\n")
    );
    let revision = version
        .split_once(" (")
        .and_then(|(_, r)| r.strip_suffix(')'))
        .expect("VERSION is `X.Y.Z (revision)`");
    let git = std::process::Command::new("git")
        .args(["rev-parse", "--short", "HEAD"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output();
    if let Some(g) = git.ok().filter(|g| g.status.success()) {
        assert_eq!(revision, String::from_utf8_lossy(&g.stdout).trim());
    }
}
