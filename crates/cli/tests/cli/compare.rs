//! `raybench compare`: the documented keys of its JSON rows, every backend on incoherent
//! rays and in every mode, the derived ray sets exported to ray files and replayed, and
//! `--flatten` against the instanced scene.

use crate::common::{assert_clean_error, raybench, raybench_ok, write};
use crate::tmp_dir;
use serde_json::Value;

/// The rows of `raybench compare ARGS --repeat 1 --json`, which must succeed.
fn compare_rows(args: &[&str]) -> Vec<Value> {
    let mut all = vec!["compare"];
    all.extend_from_slice(args);
    all.extend(["--repeat", "1", "--json"]);
    let o = raybench_ok(&all);
    let v: Value = serde_json::from_slice(&o.stdout).expect("exactly one JSON document");
    v.as_array().expect("an array of rows").clone()
}

/// Whether the registry holds `row`'s backend as an exact one.
fn exact(row: &Value) -> bool {
    raybench_registry::backend(row["backend"].as_str().unwrap())
        .unwrap()
        .exact()
}

#[test]
fn compare_json_has_the_documented_keys() {
    let rows = compare_rows(&["spheres", "--width", "32", "--height", "32"]);
    assert!(!rows.is_empty());
    let keys = [
        "backend",
        "reference",
        "available",
        "reason",
        "scene",
        "mode",
        "width",
        "height",
        "spp",
        "build_seconds",
        "render_seconds",
        "rays",
        "mrays_per_s",
        "tests_per_ray",
        "id_match",
        "hit_mismatch",
        "max_abs_dt",
    ];
    for row in &rows {
        for k in keys {
            assert!(row.get(k).is_some(), "missing key {k} in {row}");
        }
    }
    assert_eq!(rows[0]["reference"], true);
    assert_eq!(rows[0]["rays"], 32 * 32);
    assert_eq!(rows[0]["id_match"], 1.0);
    // Naive tests all 6 primitives of `spheres` for every ray.
    assert_eq!(rows[0]["tests_per_ray"], 6.0);
}

#[test]
fn compare_incoherent_rays_with_every_backend() {
    let rows = compare_rows(&[
        "spheres:200",
        "--width",
        "32",
        "--height",
        "32",
        "--rays",
        "incoherent",
    ]);
    // Every backend but the variants, which run only when named.
    let listed = raybench_registry::BACKENDS
        .iter()
        .filter(|b| !b.is(raybench_registry::Roles::PINNED))
        .count();
    assert_eq!(rows.len(), listed);
    for row in &rows {
        if !exact(row) && row["available"] == false {
            // A peer may refuse the scene (Embree: more spheres than it tests beside itself).
            continue;
        }
        assert_eq!(row["ray_set"], "incoherent");
        assert_eq!(row["rays"], 32 * 32);
        assert_eq!(row["id_match"], 1.0, "{row}");
    }
}

/// The derived ray sets through `compare` (any-hit sets compared on their boolean), and
/// each exported to a ray file and replayed with `--rays-file`: the same rays, so the same
/// ray counts, work per ray and agreement; `info` probes a ray file.
#[test]
fn derived_ray_sets_export_and_replay() {
    let dir = tmp_dir("rays");
    let size = ["--width", "32", "--height", "24"];
    let compare = |source: &[&str]| {
        let mut args = vec!["spheres"];
        args.extend_from_slice(&size);
        args.extend_from_slice(source);
        compare_rows(&args)
    };
    for (set, any_hit) in [("shadow", true), ("ao", true), ("diffuse", false)] {
        let file = dir.join(format!("{set}.rays"));
        let file = file.to_str().unwrap();
        let mut args = vec!["rays", "export", "spheres", "--rays", set, "--out", file];
        args.extend_from_slice(&size);
        raybench_ok(&args);
        let bytes = std::fs::read(file).unwrap();
        assert_eq!(&bytes[..8], b"RAYBENCH");
        assert_eq!(bytes[20], u8::from(any_hit), "{set}: the any-hit flag");
        let by_set = compare(&["--rays", set]);
        let by_file = compare(&["--rays-file", file]);
        assert_eq!(by_set.len(), by_file.len());
        let mut compared = 0;
        for (a, b) in by_set.iter().zip(&by_file) {
            assert_eq!(a["backend"], b["backend"]);
            if a["available"] == false {
                continue;
            }
            let rays = a["rays"].as_u64().unwrap();
            assert!(rays > 0, "{set}: {a}");
            assert_eq!(bytes.len() as u64, 24 + 32 * rays, "{set}: the file's size");
            assert_eq!(a["ray_set"], set);
            assert_eq!(b["ray_set"], format!("file:{set}.rays"));
            for k in ["rays", "tests_per_ray", "id_match", "hit_mismatch"] {
                assert_eq!(a[k], b[k], "{set}: {k} of {}", a["backend"]);
            }
            if exact(a) {
                assert_eq!(a["id_match"], 1.0, "{a}");
                compared += 1;
            }
        }
        assert!(compared >= 2, "{set}: {compared} exact backends compared");
        let o = raybench_ok(&["info", "spheres", "--rays-file", file]);
        let stdout = String::from_utf8_lossy(&o.stdout);
        let kind = if any_hit { "any-hit" } else { "closest-hit" };
        assert!(
            stdout.contains(&format!("file:{set}.rays rays (")),
            "{stdout}"
        );
        assert!(stdout.contains(kind), "{stdout}");
    }
    // A ray file and a ray set are exclusive; a bad file names itself and the byte.
    let o = raybench(&[
        "compare",
        "spheres",
        "--rays",
        "ao",
        "--rays-file",
        "x.rays",
    ]);
    assert_clean_error(&o, "cannot be used with");
    let bad = write(
        &dir,
        "magic.rays",
        b"RAYBENCX\x01\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0",
    );
    let o = raybench(&["compare", "spheres", "--rays-file", &bad]);
    assert_clean_error(&o, "magic.rays: byte 0: not a ray file");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn every_mode_renders_and_compares() {
    for mode in ["cast", "whitted", "path"] {
        #[rustfmt::skip]
        let rows = compare_rows(&[
            "whitted", "--mode", mode, "--spp", "2", "--max-depth", "3", "--seed", "5",
            "--width", "24", "--height", "24",
        ]);
        for row in &rows {
            assert_eq!(row["mode"], mode);
            assert_eq!(row["id_match"], 1.0, "{row}");
            let rays = row["rays"].as_u64().unwrap();
            // Cast: centre + 2 jittered rays per pixel; the others add secondary rays.
            if mode == "cast" {
                assert_eq!(rays, 24 * 24 * 3);
            } else {
                assert!(rays > 24 * 24 * 3, "{mode}: {rays} rays");
            }
        }
    }
}

/// `--flatten`: `info` of the built-in instance arrays counts the same primitives, stored
/// flat (no instances left), and `compare` of the flattened scene runs (both backends agree
/// bit for bit); naive tests an instanced scene's flattened total per ray.
#[test]
fn flatten_turns_instances_into_flat_primitives() {
    let info = |extra: &[&str]| {
        #[rustfmt::skip]
        let mut args = vec![
            "info", "instance-grid", "--backends", "bvh", "--width", "8", "--height", "8",
        ];
        args.extend_from_slice(extra);
        String::from_utf8_lossy(&raybench_ok(&args).stdout).into_owned()
    };
    let (instanced, flat) = (info(&[]), info(&["--flatten"]));
    for s in [&instanced, &flat] {
        assert!(s.contains("primitives  49649\n"), "{s}");
    }
    assert!(
        instanced.contains("instances   688 of 3 meshes"),
        "{instanced}"
    );
    assert!(!flat.contains("instances "), "{flat}");
    assert!(
        flat.lines()
            .any(|l| l.split_whitespace().eq(["triangle", "49536"])),
        "{flat}"
    );
    #[rustfmt::skip]
    let rows = compare_rows(&[
        "instance-grid", "--flatten", "--backends", "bvh,packet", "--width", "24", "--height", "24",
    ]);
    assert_eq!(rows[1]["id_match"], 1.0, "{rows:?}");
    // The default list of the instanced scene: naive leads it and tests every primitive of
    // the flattened scene per ray (what its budget counts), not the 330 stored.
    let rows = compare_rows(&["instance-grid", "--width", "24", "--height", "24"]);
    assert_eq!(rows[0]["tests_per_ray"], 49_649.0, "{rows:?}");
}
