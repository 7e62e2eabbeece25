//! The `raybench` command end to end: happy paths, and every kind of bad input giving a
//! one-line error and a non-zero exit, never a panic (exit code 101) or a hang.

mod common;

use common::raybench;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// This suite's scratch folder `name` ([`common::tmp_dir`]).
fn tmp_dir(name: &str) -> PathBuf {
    common::tmp_dir("cli", name)
}

fn write(dir: &Path, name: &str, content: &[u8]) -> String {
    let p = dir.join(name);
    std::fs::write(&p, content).unwrap();
    p.to_str().unwrap().to_owned()
}

/// Asserts a clean failure: non-zero exit that is not a panic, and one `error:` line that
/// contains `needle`.
fn assert_clean_error(out: &Output, needle: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "succeeded; stderr: {stderr}");
    assert_ne!(out.status.code(), Some(101), "panicked: {stderr}");
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(errors.len(), 1, "expected one error line, got: {stderr}");
    assert!(
        errors[0].contains(needle),
        "error line {:?} lacks {needle:?}",
        errors[0]
    );
    assert_no_repeated_cause(errors[0]);
}

/// Fails when an error line states a cause twice in a row (`X: msg: msg`), as a chain of
/// errors that each print their source would.
fn assert_no_repeated_cause(line: &str) {
    let parts: Vec<&str> = line.split(": ").collect();
    for w in parts.windows(2) {
        assert_ne!(w[0], w[1], "repeated cause in {line:?}");
    }
    for (i, p) in parts.iter().enumerate() {
        assert!(
            p.len() < 8 || !parts[i + 1..].iter().any(|q| q.ends_with(p)),
            "repeated cause {p:?} in {line:?}"
        );
    }
}

#[test]
fn render_writes_colour_and_id_images() {
    let dir = tmp_dir("render");
    let out = dir.join("s.png");
    let ids = dir.join("ids.png");
    let o = raybench(&[
        "render",
        "spheres",
        "--width",
        "40",
        "--height",
        "30",
        "--out",
        out.to_str().unwrap(),
        "--ids",
        ids.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(o.stdout.is_empty(), "render prints data only to files");
    for p in [&out, &ids] {
        let bytes = std::fs::read(p).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
    }
    assert!(!dir.join("s.png.partial").exists());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn compare_json_has_the_documented_keys() {
    let o = raybench(&[
        "compare", "spheres", "--width", "32", "--height", "32", "--repeat", "1", "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_slice(&o.stdout).expect("exactly one JSON document");
    let rows = v.as_array().unwrap();
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
    for row in rows {
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
    let o = raybench(&[
        "compare",
        "spheres:200",
        "--width",
        "32",
        "--height",
        "32",
        "--repeat",
        "1",
        "--rays",
        "incoherent",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let rows = v.as_array().unwrap();
    // Every backend but the variants, which run only when named.
    let listed = raybench_registry::BACKENDS
        .iter()
        .filter(|b| !b.is(raybench_registry::Roles::PINNED))
        .count();
    assert_eq!(rows.len(), listed);
    for row in rows {
        let b = raybench_registry::backend(row["backend"].as_str().unwrap()).unwrap();
        if !b.exact() && row["available"] == false {
            // A peer may refuse the scene (Embree: more spheres than it tests beside itself).
            continue;
        }
        assert_eq!(row["ray_set"], "incoherent");
        assert_eq!(row["rays"], 32 * 32);
        assert_eq!(row["id_match"], 1.0, "{row}");
    }
}

/// Issue 21: the derived ray sets through `compare` (any-hit sets compared on their
/// boolean), and each exported to a ray file and replayed with `--rays-file`: the same
/// rays, so the same ray counts, work per ray and agreement; `info` probes a ray file.
#[test]
fn derived_ray_sets_export_and_replay() {
    let dir = tmp_dir("rays");
    let size = ["--width", "32", "--height", "24"];
    let compare = |source: &[&str]| -> Vec<serde_json::Value> {
        let mut args = vec!["compare", "spheres", "--repeat", "1", "--json"];
        args.extend_from_slice(&size);
        args.extend_from_slice(source);
        let o = raybench(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        v.as_array().unwrap().clone()
    };
    for (set, any_hit) in [("shadow", true), ("ao", true), ("diffuse", false)] {
        let file = dir.join(format!("{set}.rays"));
        let file = file.to_str().unwrap();
        let mut args = vec!["rays", "export", "spheres", "--rays", set, "--out", file];
        args.extend_from_slice(&size);
        let o = raybench(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
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
            if raybench_registry::backend(a["backend"].as_str().unwrap())
                .unwrap()
                .exact()
            {
                assert_eq!(a["id_match"], 1.0, "{a}");
                compared += 1;
            }
        }
        assert!(compared >= 2, "{set}: {compared} exact backends compared");
        let o = raybench(&["info", "spheres", "--rays-file", file]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
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
fn volume_modes_render_the_phantom_and_height_fields_and_csg_render() {
    let dir = tmp_dir("volumes");
    for (scene, mode) in [
        ("phantom", "mip"),
        ("phantom", "composite"),
        ("heightfield", "whitted"),
        ("heightfield:64", "cast"),
        ("csg", "whitted"),
        ("csg", "path"),
        ("sdf", "whitted"),
        ("sdf", "path"),
        ("quadrics", "whitted"),
        ("quadrics", "path"),
    ] {
        let out = dir.join(format!("{mode}.png"));
        let o = raybench(&[
            "render",
            scene,
            "--mode",
            mode,
            "--width",
            "32",
            "--height",
            "32",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            o.status.success(),
            "{scene} {mode}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let img = image::open(&out).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (32, 32));
        // Something is drawn: not one flat colour.
        let first = *img.get_pixel(0, 0);
        assert!(img.pixels().any(|p| *p != first), "{scene} {mode} is flat");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn every_mode_renders_and_compares() {
    for mode in ["cast", "whitted", "path"] {
        let o = raybench(&[
            "compare",
            "whitted",
            "--mode",
            mode,
            "--spp",
            "2",
            "--max-depth",
            "3",
            "--seed",
            "5",
            "--width",
            "24",
            "--height",
            "24",
            "--repeat",
            "1",
            "--json",
        ]);
        assert!(
            o.status.success(),
            "{mode}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        for row in v.as_array().unwrap() {
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

/// `--flatten`: `info` of the built-in instance arrays counts the same primitives, stored
/// flat (no instances left), and `compare` of the flattened scene runs (both backends agree
/// bit for bit); naive tests an instanced scene's flattened total per ray.
#[test]
fn flatten_turns_instances_into_flat_primitives() {
    let info = |extra: &[&str]| {
        let mut args = vec![
            "info",
            "instance-grid",
            "--backends",
            "bvh",
            "--width",
            "8",
            "--height",
            "8",
        ];
        args.extend_from_slice(extra);
        let o = raybench(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).into_owned()
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
    assert!(flat.contains("  triangle  49536\n"), "{flat}");
    let o = raybench(&[
        "compare",
        "instance-grid",
        "--flatten",
        "--backends",
        "bvh,packet",
        "--width",
        "24",
        "--height",
        "24",
        "--repeat",
        "1",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(rows[1]["id_match"], 1.0, "{rows}");
    // The default list of the instanced scene: naive leads it and tests every primitive of
    // the flattened scene per ray (what its budget counts), not the 330 stored.
    let o = raybench(&[
        "compare",
        "instance-grid",
        "--width",
        "24",
        "--height",
        "24",
        "--repeat",
        "1",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(rows[0]["tests_per_ray"], 49_649.0, "{rows}");
}

#[test]
fn info_prints_structure_quality() {
    let o = raybench(&[
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
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
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
fn bad_files_give_one_line_errors() {
    let dir = tmp_dir("bad");
    let missing_buffer = format!(
        "missing-buffer.gltf: buffer 0: {}: No such file or directory",
        dir.join("missing.bin").display()
    );
    let mut cases: Vec<(String, &str)> = vec![
        (
            write(&dir, "oob.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"),
            "out of bounds",
        ),
        (
            write(&dir, "neg.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -5 2 3\n"),
            "out of bounds",
        ),
        (
            write(&dir, "short.obj", b"v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n"),
            "short.obj",
        ),
        (
            write(
                &dir,
                "trunc.obj",
                b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nv 0 0 ",
            ),
            "trunc.obj",
        ),
        (
            write(&dir, "nan.obj", b"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
            "non-finite",
        ),
        (
            write(&dir, "inf.obj", b"v 1e39 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
            "non-finite",
        ),
        (
            write(&dir, "garbage.obj", b"hello\x00\x01world\n"),
            "no triangles",
        ),
        (
            write(
                &dir,
                "trunc.gltf",
                br#"{"asset": {"version": "2.0"}, "meshes": ["#,
            ),
            "trunc.gltf",
        ),
        (
            write(&dir, "trunc.glb", b"glTF\x02\x00\x00\x00\xff\x00\x00\x00"),
            "trunc.glb",
        ),
        (
            write(&dir, "bad.toml", b"[camera\nposition="),
            "line 1, column 8",
        ),
        (
            write(
                &dir,
                "nan.toml",
                b"[[object]]\nkind = \"sphere\"\ncenter = [nan, 0, 0]\nradius = 1\n",
            ),
            "not finite",
        ),
        (
            write(
                &dir,
                "typo.toml",
                b"[[object]]\nkind = \"sphere\"\ncentre = [0, 0, 0]\nradius = 1\n",
            ),
            "centre",
        ),
        (
            write(
                &dir,
                "idx.toml",
                b"[[object]]\nkind = \"polygons\"\npositions = [[0,0,0]]\nfaces = [[0, 1, 2]]\n",
            ),
            "out of range",
        ),
        (
            write(
                &dir,
                "mesh.toml",
                b"[[object]]\nkind = \"mesh\"\npath = \"absent.obj\"\n",
            ),
            "absent.obj",
        ),
        (
            write(
                &dir,
                "cam.toml",
                b"[camera]\nposition = [0,0,0]\nlook_at = [0,0,0]\n",
            ),
            "cam.toml: camera: position and look_at are the same point [0, 0, 0]",
        ),
        (
            write(&dir, "scene.txt", b"hello"),
            "unknown scene file type",
        ),
        (
            dir.join("missing.obj").to_str().unwrap().to_owned(),
            "file not found",
        ),
        ("no-such-scene".to_owned(), "unknown scene"),
        (
            dir.to_str().unwrap().to_owned(),
            "is a folder, not a regular file",
        ),
        ("/dev/zero".to_owned(), "/dev/zero: is a device, not a regular file"),
        (
            write(
                &dir,
                "missing-buffer.gltf",
                br#"{"asset": {"version": "2.0"}, "buffers": [{"uri": "missing.bin", "byteLength": 12}]}"#,
            ),
            &missing_buffer,
        ),
        (
            write(
                &dir,
                "cam-up.toml",
                b"[camera]\nposition = [0,0,5]\nlook_at = [0,0,0]\nup = [0,0,1]\n",
            ),
            "cam-up.toml: camera: up [0, 0, 1] is zero or parallel to the view direction",
        ),
        ("soup:0".to_owned(), "soup:0"),
        ("terrain:99999".to_owned(), "terrain:99999"),
        ("heightfield:0".to_owned(), "heightfield:0"),
    ];
    #[cfg(unix)]
    {
        let fifo = dir.join("fifo.toml");
        let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
        assert!(made.success());
        cases.push((
            fifo.to_str().unwrap().to_owned(),
            "fifo.toml: is a FIFO (named pipe), not a regular file",
        ));
    }
    // Height fields and volumes from broken or absurd files.
    write(&dir, "bad.png", b"\x89PNG\r\n\x1a\nnot really a png");
    write(&dir, "short.raw", &[0u8; 10]);
    let huge_png = {
        // A valid header claiming 1,000,000 x 1,000,000 pixels, and nothing after it.
        let mut b = b"\x89PNG\r\n\x1a\n\x00\x00\x00\x0dIHDR".to_vec();
        b.extend_from_slice(&1_000_000u32.to_be_bytes());
        b.extend_from_slice(&1_000_000u32.to_be_bytes());
        b.extend_from_slice(&[16, 0, 0, 0, 0]);
        let crc = 0u32; // Wrong on purpose: either check refuses it.
        b.extend_from_slice(&crc.to_be_bytes());
        b
    };
    write(&dir, "huge.png", &huge_png);
    let grid_cases: Vec<(&str, &[u8], &str)> = vec![
        (
            "hf-png.toml",
            b"[[object]]\nkind = \"height_field\"\npng = \"bad.png\"\n",
            "bad.png",
        ),
        (
            "hf-huge.toml",
            b"[[object]]\nkind = \"height_field\"\npng = \"huge.png\"\n",
            "huge.png",
        ),
        (
            "hf-raw.toml",
            b"[[object]]\nkind = \"height_field\"\nraw = \"short.raw\"\nsize = [4, 4]\n",
            "short.raw",
        ),
        (
            "hf-two.toml",
            b"[[object]]\nkind = \"height_field\"\nsource = \"terrain:4\"\nheights = [[0, 0], [0, 0]]\n",
            "exactly one",
        ),
        (
            "hf-nan.toml",
            b"[[object]]\nkind = \"height_field\"\nheights = [[0, nan], [0, 0]]\n",
            "not finite",
        ),
        (
            "hf-ragged.toml",
            b"[[object]]\nkind = \"height_field\"\nheights = [[0, 0], [0]]\n",
            "same length",
        ),
        (
            "vol-raw.toml",
            b"[[volume]]\nraw = \"short.raw\"\ndims = [2, 2, 2]\nformat = \"u16\"\n",
            "short.raw",
        ),
        (
            "vol-huge.toml",
            b"[[volume]]\nraw = \"short.raw\"\ndims = [100000, 100000, 100000]\n",
            "exceeds the limit",
        ),
        (
            "vol-zero.toml",
            b"[[volume]]\nraw = \"short.raw\"\ndims = [0, 2, 5]\nformat = \"u8\"\n",
            "empty",
        ),
        (
            "vol-spacing.toml",
            b"[[volume]]\nsource = \"phantom:4\"\nspacing = [1, -1, 1]\n",
            "spacing",
        ),
        (
            "vol-tf.toml",
            b"[[volume]]\nsource = \"phantom:4\"\ntransfer = [{ value = 0.5, color = [1, 1, 1], sigma = 1 }, { value = 0.2, color = [1, 1, 1], sigma = 1 }]\n",
            "increasing",
        ),
        (
            "vol-big.toml",
            b"[[volume]]\nsource = \"phantom:100000\"\n",
            "phantom:100000",
        ),
    ];
    for (name, text, needle) in grid_cases {
        let scene = write(&dir, name, text);
        let o = raybench(&[
            "render",
            &scene,
            "--width",
            "8",
            "--height",
            "8",
            "--out",
            dir.join("o.png").to_str().unwrap(),
        ]);
        assert_clean_error(&o, needle);
    }
    for (scene, needle) in &cases {
        let o = raybench(&[
            "render",
            scene,
            "--width",
            "8",
            "--height",
            "8",
            "--out",
            dir.join("o.png").to_str().unwrap(),
        ]);
        assert_clean_error(&o, needle);
    }
    assert!(!dir.join("o.png").exists());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_options_give_one_line_errors() {
    let cases: &[(&[&str], &str)] = &[
        (&["render", "spheres", "--width", "0"], "empty"),
        (&["render", "spheres", "--height", "0"], "empty"),
        (&["render", "spheres", "--width", "100000"], "limit"),
        (&["render", "spheres", "--spp", "0"], "samples per pixel"),
        (
            &["render", "spheres", "--backend", "bogus"],
            "unknown backend",
        ),
        (&["render", "spheres", "--mode", "bogus"], "unknown mode"),
        (&["render", "spheres", "--max-depth", "1000"], "max depth"),
        (
            &[
                "render",
                "spheres",
                "--threads",
                "0",
                "--width",
                "4",
                "--height",
                "4",
            ],
            "threads",
        ),
        (
            &["render", "spheres", "--threads", "100000"],
            "--threads 100000: between 1 and 1024",
        ),
        (
            &["compare", "spheres", "--threads", "5000"],
            "--threads 5000: between 1 and 1024",
        ),
        (
            &["report", "--quick", "--threads", "1025"],
            "--threads 1025: between 1 and 1024",
        ),
        (
            &["compare", "spheres", "--backends", "naive,bogus"],
            "unknown backend",
        ),
        (&["compare", "spheres", "--repeat", "0"], "repeat"),
        (&["compare", "spheres", "--repeat", "4294967295"], "repeat"),
        (
            &[
                "compare",
                "spheres",
                "--rays",
                "incoherent",
                "--width",
                "16384",
                "--height",
                "16384",
            ],
            "limit",
        ),
        (
            &["compare", "spheres", "--rays", "sideways"],
            "unknown ray set",
        ),
        (&["render", "spheres", "--width=-3"], "width"),
        (
            &[
                "render",
                "bunny",
                "--assets",
                "/nonexistent-raybench-assets",
            ],
            "stanford-bunny.obj",
        ),
        (
            &[
                "render",
                "teapot-bezier",
                "--assets",
                "/nonexistent-raybench-assets",
            ],
            "teapot-bezier/teapot.bpt",
        ),
    ];
    for (args, needle) in cases {
        let o = raybench(args);
        assert_clean_error(&o, needle);
    }
}

/// `--out` and `--ids` are checked before the scene is even loaded: colour is written as
/// PNG, EXR or PFM, ids as PNG, and the folder must exist.
#[test]
fn output_paths_are_checked_before_rendering() {
    let dir = tmp_dir("outpaths");
    let missing = dir.join("no-such-dir/x.png");
    let ok = dir.join("ok.png");
    let cases: [(&[&str], &str); 4] = [
        (
            &["--out", "x.tiff"],
            "x.tiff: images are written as PNG, OpenEXR or PFM only",
        ),
        (
            &["--out", "x.jpg"],
            "name the file *.png, *.exr or *.pfm (got '.jpg')",
        ),
        (
            &["--out", missing.to_str().unwrap()],
            "no-such-dir does not exist",
        ),
        (
            &["--out", ok.to_str().unwrap(), "--ids", "ids.jpeg"],
            "ids.jpeg: images are written as PNG only",
        ),
    ];
    for (extra, needle) in cases {
        // A scene that would take minutes to render: refused at once.
        let mut args = vec![
            "render",
            "terrain:4096",
            "--mode",
            "path",
            "--spp",
            "1024",
            "--width",
            "4096",
            "--height",
            "4096",
        ];
        args.extend_from_slice(extra);
        let o = raybench(&args);
        assert_clean_error(&o, needle);
        assert!(
            !String::from_utf8_lossy(&o.stderr).contains("loaded"),
            "the scene was loaded before the path was checked"
        );
    }
    assert!(!Path::new("x.exr").exists() && !Path::new("x.jpg").exists());
    std::fs::remove_dir_all(dir).unwrap();
}

/// Issue 18: what renders as silent garbage is refused (an empty scene, negative colours,
/// a sphere too small for f32, `--mode mip` without volumes) or warned about (a mesh whose
/// triangles all have zero area).
#[test]
fn silent_garbage_is_refused_or_warned() {
    let dir = tmp_dir("garbage");
    let sphere = "[[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n";
    let cases: Vec<(&[&str], String, &str)> = vec![
        (
            &[],
            write(&dir, "empty.toml", b"background = [1.0, 0.0, 0.0]\n"),
            "empty.toml: the scene has no [[object]] and no [[volume]]: nothing to render",
        ),
        (
            &[],
            write(
                &dir,
                "neg.toml",
                format!(
                    "[[material]]\nname = \"m\"\ncolor = [-1, 5, 0.5]\n{sphere}material = \"m\"\n"
                )
                .as_bytes(),
            ),
            "neg.toml: line 1: material 1: material 'm': color [-1, 5, 0.5] has a negative component",
        ),
        (
            &[],
            write(
                &dir,
                "emit.toml",
                format!("[[material]]\nname = \"m\"\nemission = [0, -2, 0]\n{sphere}").as_bytes(),
            ),
            "material 'm': emission [0, -2, 0] has a negative component",
        ),
        (
            &[],
            {
                write(&dir, "neg.mtl", b"newmtl bad\nKd -1 5 0.5\n");
                write(
                    &dir,
                    "neg.obj",
                    b"mtllib neg.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl bad\nf 1 2 3\n",
                )
            },
            "neg.obj: material 'bad': color [-1, 5, 0.5] has a negative component",
        ),
        (
            &[],
            write(
                &dir,
                "tiny.toml",
                b"[[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1e-40\n",
            ),
            "tiny.toml: line 1: object 1 (sphere): sphere radius 1e-40 is below 1e-18",
        ),
        (
            &["--mode", "mip"],
            "spheres".to_owned(),
            "--mode mip shows volumes, and scene 'spheres' has none",
        ),
        (
            &["--mode", "composite"],
            "spheres".to_owned(),
            "--mode composite shows volumes, and scene 'spheres' has none",
        ),
    ];
    for (extra, scene, needle) in &cases {
        let mut args = vec!["render", scene, "--width", "4", "--height", "4", "--out"];
        let out = dir.join("o.png");
        args.push(out.to_str().unwrap());
        args.extend_from_slice(extra);
        assert_clean_error(&raybench(&args), needle);
    }
    let o = raybench(&[
        "compare", "spheres", "--mode", "mip", "--width", "4", "--height", "4",
    ]);
    assert_clean_error(&o, "--mode mip shows volumes");
    // Legal but surely unintended: one warning line, and the image is written.
    let flat = write(&dir, "flat.obj", b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    let out = dir.join("flat.png");
    let o = raybench(&[
        "render",
        &flat,
        "--width",
        "4",
        "--height",
        "4",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("warning:"))
        .collect();
    assert_eq!(warnings.len(), 1, "{stderr}");
    assert!(warnings[0].contains("has zero area"), "{stderr}");
    assert!(out.exists());
    std::fs::remove_dir_all(dir).unwrap();
}

/// A `.bpt` file of one bicubic patch (a bump over `[0, 3]^2`) and `count` declared.
fn bump_bpt(count: u32) -> String {
    let mut s = format!("{count}\n3 3\n");
    for j in 0..4 {
        for i in 0..4 {
            let z = if (1..3).contains(&i) && (1..3).contains(&j) {
                1.5
            } else {
                0.0
            };
            s += &format!("{i} {j} {z}\n");
        }
    }
    s
}

/// A PLY file renders as a bare scene and as a scene's mesh object, in ASCII and binary;
/// bad PLY files (out-of-range index, truncated binary data, a header declaring more than
/// the file holds, no `vertex` element, not PLY at all, over the memory budget) give one
/// `error:` line naming the file, the place and the cause.
#[test]
fn ply_meshes_render_and_bad_ones_give_one_line_errors() {
    let dir = tmp_dir("ply");
    let header = |format: &str| {
        format!(
            "ply\nformat {format} 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
             property float z\nelement face 2\nproperty list uchar int vertex_indices\n\
             end_header\n"
        )
    };
    let corners = [
        [-1.0f32, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let faces = [[0i32, 1, 2], [0, 1, 3]];
    let ascii = format!(
        "{}-1 -1 0\n1 -1 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n",
        header("ascii")
    );
    let mut binary = header("binary_little_endian").into_bytes();
    for c in corners.iter().flatten() {
        binary.extend_from_slice(&c.to_le_bytes());
    }
    for f in faces {
        binary.push(3);
        for i in f {
            binary.extend_from_slice(&i.to_le_bytes());
        }
    }
    let out = dir.join("ply.png");
    let scene = write(
        &dir,
        "scene.toml",
        b"[[object]]\nkind = \"mesh\"\npath = \"binary.ply\"\n\
          [[object]]\nkind = \"mesh\"\npath = \"ascii.ply\"\ntransform = { translate = [3, 0, 0] }\n",
    );
    for spec in [
        write(&dir, "ascii.ply", ascii.as_bytes()),
        write(&dir, "binary.ply", &binary),
        scene,
    ] {
        let o = raybench(&[
            "render",
            &spec,
            "--width",
            "24",
            "--height",
            "16",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            o.status.success(),
            "{spec}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert_eq!(&std::fs::read(&out).unwrap()[1..4], b"PNG");
        std::fs::remove_file(&out).unwrap();
    }
    let truncated = &binary[..binary.len() - 3];
    let cases = [
        (
            write(
                &dir,
                "index.ply",
                ascii.replace("3 0 1 3", "3 0 1 4").as_bytes(),
            ),
            "index.ply: face 2 (line 15): vertex index 4 is out of range (the file has 4 vertices)",
        ),
        (
            write(&dir, "truncated.ply", truncated),
            "truncated.ply: face 2 (byte 230): the file ends inside this record (truncated)",
        ),
        (
            write(
                &dir,
                "huge.ply",
                header("binary_big_endian")
                    .replace("vertex 4", "vertex 4000000000")
                    .as_bytes(),
            ),
            "huge.ply: the header declares 4000000000 'vertex' records of at least 12 bytes each, \
             more than the 0 bytes after the header hold",
        ),
        (
            write(
                &dir,
                "novertex.ply",
                ascii.replace("vertex 4", "point 4").as_bytes(),
            ),
            "novertex.ply: the header declares no 'vertex' element",
        ),
        (
            write(&dir, "stl.ply", b"solid cube\nfacet normal 0 0 1\n"),
            "stl.ply: malformed PLY header: line 1: not a PLY file (the first line is not 'ply')",
        ),
    ];
    for (path, needle) in &cases {
        assert_clean_error(&raybench(&["render", path]), needle);
    }
    // The budget is checked against the header's face count before any face is read.
    let o = raybench(&[
        "render",
        &dir.join("binary.ply").to_string_lossy(),
        "--memory-limit",
        "1K",
    ]);
    assert_clean_error(&o, "binary.ply: needs about 1.2 KiB for 2 primitives");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bezier_patches_render_directly_and_tessellated() {
    let dir = tmp_dir("bezier");
    write(&dir, "bump.bpt", bump_bpt(1).as_bytes());
    write(&dir, "short.bpt", bump_bpt(2).as_bytes());
    let scene = |extra: &str, file: &str| {
        format!(
            "[camera]\nposition = [1.5, 6.0, 4.0]\nlook_at = [1.5, 0.5, -1.5]\n\
             [[light]]\nkind = \"point\"\nposition = [0.0, 8.0, 0.0]\nintensity = [40.0, 40.0, 40.0]\n\
             [[object]]\nkind = \"bezier\"\nfile = \"{file}\"\n\
             transform = {{ rotate = [-90.0, 0.0, 0.0] }}\n{extra}"
        )
    };
    for (name, extra, mode) in [
        ("direct", "", "whitted"),
        ("direct", "", "path"),
        ("tessellated", "tessellate = 4", "cast"),
    ] {
        let file = write(
            &dir,
            &format!("{name}.toml"),
            scene(extra, "bump.bpt").as_bytes(),
        );
        let out = dir.join(format!("{name}-{mode}.png"));
        let o = raybench(&[
            "render",
            &file,
            "--mode",
            mode,
            "--width",
            "24",
            "--height",
            "24",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            o.status.success(),
            "{name} {mode}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let img = image::open(&out).unwrap().to_rgb8();
        let first = *img.get_pixel(0, 0);
        assert!(img.pixels().any(|p| *p != first), "{name} {mode} is flat");
    }
    // A file that declares more patches than it holds: a clean error with the line.
    let bad = write(&dir, "bad.toml", scene("", "short.bpt").as_bytes());
    let o = raybench(&["render", &bad, "--width", "8", "--height", "8"]);
    assert_clean_error(
        &o,
        "line 18: the file ends after 1 patches; the first line declares 2",
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// Ctrl-C during a render leaves no partial image under the final name: the previous file
/// there stays whole (images are written to a temporary name and renamed into place only
/// when complete), and the process ends by the signal, not a panic.
#[cfg(unix)]
#[test]
fn an_interrupted_render_leaves_the_previous_image_whole() {
    let dir = tmp_dir("interrupt");
    let out = write(&dir, "out.png", b"the previous image");
    // Long enough to be interrupted: path tracing at 1024 spp (minutes).
    let mut child = Command::new(env!("CARGO_BIN_EXE_raybench"))
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
fn info_marks_missing_modes_unavailable_as_compare_does() {
    // `info` marks a backend that lacks the mode on its line instead of failing. The GPU
    // kernels have every mode now (the volume modes in `kernels/volume.wgsl`), so wgpu is
    // marked only where there is no GPU, for that reason, never for the mode.
    let o = raybench(&[
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
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let line = |name: &str| {
        stdout
            .lines()
            .find(|l| l.split_whitespace().next() == Some(name))
            .unwrap_or_else(|| panic!("no {name} line: {stdout}"))
            .to_string()
    };
    assert!(!line("bvh").contains("unavailable"), "{stdout}");
    let wgpu = line("wgpu");
    assert!(
        !wgpu.contains("mode") && !wgpu.contains("render it with a CPU backend"),
        "{stdout}"
    );
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
    let o = Command::new(env!("CARGO_BIN_EXE_raybench"))
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
    let git = Command::new("git")
        .args(["rev-parse", "--short", "HEAD"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output();
    if let Some(g) = git.ok().filter(|g| g.status.success()) {
        assert_eq!(revision, String::from_utf8_lossy(&g.stdout).trim());
    }
}

#[test]
fn gpu_commands_print_no_wayland_noise() {
    // Mesa's device-selection layer probes Wayland while wgpu lists adapters; without
    // XDG_RUNTIME_DIR, libwayland printed an `error:` line about it, twice.
    let o = Command::new(env!("CARGO_BIN_EXE_raybench"))
        .args(["backends"])
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .unwrap();
    assert!(o.status.success());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!stderr.contains("XDG_RUNTIME_DIR"), "{stderr}");
}

#[test]
fn long_work_shows_progress_on_a_terminal_only() {
    let run = |args: &[&str], progress: Option<&str>| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_raybench"));
        c.args(args).env_remove("RAYBENCH_PROGRESS");
        if let Some(p) = progress {
            c.env("RAYBENCH_PROGRESS", p);
        }
        let o = c.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
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
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn docs_state_the_modes_and_the_defaults() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let read = |p: &str| std::fs::read_to_string(root.join(p)).unwrap();
    // Every mode a result can hold.
    let results = read("docs/results.md");
    let row = results
        .lines()
        .find(|l| l.starts_with("| `mode` |"))
        .expect("a mode row");
    for m in raybench_core::Mode::ALL {
        assert!(row.contains(&format!("`{}`", m.name())), "{row}");
    }
    // The background of a scene file that sets none, which lights `path` renders.
    let scene = raybench_scene::load_scene_str(
        "[[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n",
        "one-sphere",
        None,
        Path::new("."),
    )
    .unwrap();
    let bg = scene.background;
    let stated = format!("default `[{}, {}, {}]`", bg.x, bg.y, bg.z);
    assert!(read("docs/scene-format.md").contains(&stated), "{stated}");
    assert!(read("docs/cli.md").contains(&stated), "{stated}");
    // The default `--max-depth` of every command that has one.
    for cmd in ["render", "compare", "info"] {
        let o = raybench(&[cmd, "--help"]);
        let help = String::from_utf8_lossy(&o.stdout);
        let option = &help[help.find("--max-depth").expect("a --max-depth option")..];
        let option = &option[..option[2..].find("--").map_or(option.len(), |i| i + 2)];
        let default = option
            .split("[default: ")
            .nth(1)
            .and_then(|d| d.split(']').next())
            .unwrap_or_else(|| panic!("{cmd}: no default in {option}"));
        assert!(
            read("docs/scene-format.md").contains(&format!("**default {default}**")),
            "{cmd}: {default}"
        );
        assert!(read("docs/cli.md").contains(&format!("`--max-depth {default}`")));
    }
}

/// The table of refused inputs in docs/cli.md stays true: every row's command is run from the
/// workspace root and must fail cleanly with one `error:` line containing the row's
/// message, and every fixture in `crates/cli/tests/bad-input/` is used by a row (or by a
/// fixture a row uses), so that the table and the files cannot drift apart.
#[test]
fn docs_bad_input_table_is_true() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let doc = std::fs::read_to_string(root.join("docs/cli.md")).unwrap();
    let table = doc
        .split_once("<!-- bad-input-table -->")
        .and_then(|(_, rest)| rest.split_once("<!-- /bad-input-table -->"))
        .map(|(table, _)| table)
        .expect("docs/cli.md has the bad-input table between its markers");
    // A code span: `text`, or `` text `` when the text holds backticks.
    let code = |cell: &str| {
        let cell = cell.trim();
        let inner = cell
            .strip_prefix("``")
            .and_then(|c| c.strip_suffix("``"))
            .or_else(|| cell.strip_prefix('`').and_then(|c| c.strip_suffix('`')));
        inner
            .unwrap_or_else(|| panic!("cell {cell:?} is not `code`"))
            .trim()
            .to_owned()
    };
    let mut rows = 0;
    for line in table.lines().filter(|l| l.starts_with("| ")) {
        let cells: Vec<&str> = line.trim_matches('|').split(" | ").collect();
        if cells.len() != 3 || cells[0].trim() == "input" || cells[0].starts_with('-') {
            continue;
        }
        let (command, message) = (code(cells[1]), code(cells[2]));
        let mut words = command.split_whitespace().peekable();
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_raybench"));
        cmd.current_dir(&root);
        while let Some((k, v)) = words.peek().and_then(|w| w.split_once('=')) {
            cmd.env(k, v);
            words.next();
        }
        assert_eq!(words.next(), Some("raybench"), "{command}");
        let out = cmd.args(words).output().expect("raybench runs");
        // `...` stands for text that varies (an absolute path): the pieces must appear in
        // order.
        let expected = message.strip_prefix("error: ").unwrap_or(&message);
        let mut pieces = expected.split("...");
        let first = pieces.next().unwrap_or_default();
        assert_clean_error(&out, first);
        let stderr = String::from_utf8_lossy(&out.stderr);
        let line = stderr
            .lines()
            .find(|l| l.starts_with("error"))
            .unwrap_or_default();
        let mut at = line.find(first).unwrap_or_default() + first.len();
        for piece in pieces {
            let found = line[at..].find(piece);
            assert!(
                found.is_some(),
                "{command}: {line:?} lacks {piece:?} (in order)"
            );
            at += found.unwrap_or_default() + piece.len();
        }
        rows += 1;
    }
    assert!(
        rows >= 30,
        "only {rows} rows in the bad-input table of docs/cli.md"
    );
    let fixtures = root.join("crates/cli/tests/bad-input");
    let used: String = std::fs::read_dir(&fixtures)
        .unwrap()
        .map(|e| std::fs::read_to_string(e.unwrap().path()).unwrap_or_default())
        .chain([table.to_owned()])
        .collect();
    for e in std::fs::read_dir(&fixtures).unwrap() {
        let name = e.unwrap().file_name().into_string().unwrap();
        assert!(
            table.contains(&format!("bad-input/{name}"))
                || used.contains(&format!("\"{name}\""))
                || used.contains(&format!(" {name}\n")),
            "fixture {name} is used by no row of the table in docs/cli.md"
        );
    }
}

/// Issue 20: `--out` writes unclamped linear radiance as EXR or PFM (scaled by
/// `--exposure`), and `raybench diff` measures images against each other.
#[test]
fn linear_output_and_diff() {
    let dir = tmp_dir("linear");
    let path = |n: &str| dir.join(n).to_str().unwrap().to_owned();
    let render = |out: &str, extra: &[&str]| {
        let mut args = vec![
            "render", "spheres", "--width", "32", "--height", "24", "--out", out,
        ];
        args.extend_from_slice(extra);
        let o = raybench(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    render(&path("a.exr"), &[]);
    render(&path("a.pfm"), &[]);
    render(&path("a.png"), &[]);
    render(&path("half.pfm"), &["--exposure", "-1"]);
    let diff = |args: &[&str]| {
        let mut all = vec!["diff"];
        all.extend_from_slice(args);
        raybench(&all)
    };
    let json = |o: &Output| -> serde_json::Value {
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    // EXR and PFM hold the same linear values.
    let same = json(&diff(&[&path("a.exr"), &path("a.pfm"), "--json"]));
    assert_eq!(same["max_abs_error"], 0.0);
    assert!(same["psnr"].is_null());
    // Exposure -1 halves every value.
    let half = json(&diff(&[&path("a.exr"), &path("half.pfm"), "--json"]));
    let (ma, mb) = (
        half["mean_a"].as_f64().unwrap(),
        half["mean_b"].as_f64().unwrap(),
    );
    assert!((mb - ma / 2.0).abs() < 1e-6 * ma, "{ma} {mb}");
    assert!(half["flip"].as_f64().unwrap() > 0.0);
    // The PNG is the clamped, quantised EXR: close, not equal.
    let png = json(&diff(&[&path("a.exr"), &path("a.png"), "--json"]));
    assert!(png["mean_abs_error"].as_f64().unwrap() < 0.01, "{png}");
    // Maps, and --fail-above's status 2.
    let maps = dir.join("maps");
    let o = diff(&[
        &path("a.exr"),
        &path("half.pfm"),
        "--out",
        maps.to_str().unwrap(),
        "--fail-above",
        "0.001",
        "--metric",
        "mae",
    ]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("mean FLIP"));
    for m in ["error.png", "flip.png"] {
        assert_eq!(&std::fs::read(maps.join(m)).unwrap()[1..4], b"PNG");
    }
    let o = diff(&[&path("a.exr"), &path("a.pfm"), "--fail-above", "0"]);
    assert!(o.status.success());
    // Bad input: one error line each.
    let small = path("small.pfm");
    std::fs::write(&small, b"PF\n1 1\n-1.0\n\0\0\0\0\0\0\0\0\0\0\0\0").unwrap();
    let bad = write(&dir, "bad.pfm", b"PF\n4 4\n-1.0\n");
    let cases: [(&[&str], &str); 5] = [
        (
            &[&path("a.exr"), &small],
            "differ in size: 32 x 24 against 1 x 1",
        ),
        (&[&path("a.exr"), &bad], "bad.pfm: PFM data holds 0 bytes"),
        (&[&path("a.exr"), &path("none.exr")], "none.exr"),
        (&[&path("a.exr"), "x.gif"], "x.gif: unknown image type"),
        (
            &[&path("a.exr"), &path("a.pfm"), "--metric", "psnr"],
            "unknown metric 'psnr'",
        ),
    ];
    for (args, needle) in cases {
        assert_clean_error(&diff(args), needle);
    }
}

/// Issue 20: `--camera` picks one of a scene's cameras by name or index, and the overrides
/// adjust it; bad choices are one error line.
#[test]
fn cameras_are_chosen_and_adjusted() {
    let dir = tmp_dir("cameras");
    let scene = write(
        &dir,
        "cams.toml",
        b"[[camera]]\nname = \"front\"\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\
          [[camera]]\nname = \"side\"\nposition = [5, 0, 0]\nlook_at = [0, 0, 0]\n\
          [[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n\
          [[object]]\nkind = \"sphere\"\ncenter = [0, 0, 3]\nradius = 0.5\n",
    );
    let ids = |extra: &[&str]| {
        let out = dir.join("c.png");
        let id = dir.join("ids.png");
        let mut args = vec![
            "render",
            &scene,
            "--width",
            "16",
            "--height",
            "16",
            "--out",
            out.to_str().unwrap(),
            "--ids",
            id.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let o = raybench(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read(&id).unwrap()
    };
    let front = ids(&[]);
    assert_eq!(ids(&["--camera", "front"]), front);
    assert_eq!(ids(&["--camera", "0"]), front);
    let side = ids(&["--camera", "side"]);
    assert_ne!(side, front);
    assert_eq!(ids(&["--camera", "1"]), side);
    // The overrides move the front camera to the side camera's place.
    assert_eq!(ids(&["--look-from", "5,0,0"]), side);
    assert_ne!(ids(&["--fov", "10"]), front);
    let o = raybench(&["info", &scene, "--backends", "bvh"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("cameras     2") && text.contains("'side'"),
        "{text}"
    );
    let cases: [(&[&str], &str); 4] = [
        (
            &["--camera", "top"],
            "no camera 'top' (its cameras: 0: 'front', 1: 'side')",
        ),
        (
            &["--look-at", "0,0,5"],
            "position and look_at are the same point",
        ),
        (&["--fov", "190"], "fov 190 is outside (0, 180)"),
        (&["--up", "1,x,0"], "'1,x,0' is not three numbers"),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["render", &scene, "--width", "8", "--height", "8"];
        args.extend_from_slice(extra);
        assert_clean_error(&raybench(&args), needle);
    }
}

/// A reader that closes the pipe early (`raybench compare-results A B --json | head`) ends
/// the command quietly: success, no panic on standard error.
#[test]
fn a_closed_pipe_ends_the_command_quietly() {
    use std::io::Read as _;
    use std::process::Stdio;
    let reports = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../reports");
    // A committed report: comparing it with itself prints far more than a pipe holds.
    let report = std::fs::read_dir(&reports)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.join("results.json").is_file())
        .expect("a committed report");
    let mut child = Command::new(env!("CARGO_BIN_EXE_raybench"))
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
