//! Bad input gives one `error:` line and a non-zero exit, never a panic: malformed mesh,
//! glTF, scene, height-field and volume files, missing and special files, out-of-range
//! options, output paths checked before any work, and scenes that would render as silent
//! garbage (refused, or warned about).

use crate::common::{assert_clean_error, raybench, render, write};
use crate::tmp_dir;
use std::path::Path;
use std::process::Command;

/// Scene files that are refused, by name, with their text and what the error line says.
/// The height fields and volumes read `bad.png`, `huge.png` and `short.raw` beside them.
const BAD_FILES: &[(&str, &[u8], &str)] = &[
    (
        "oob.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
        "out of bounds",
    ),
    (
        "neg.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -5 2 3\n",
        "out of bounds",
    ),
    (
        "short.obj",
        b"v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n",
        "short.obj",
    ),
    (
        "trunc.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nv 0 0 ",
        "trunc.obj",
    ),
    (
        "nan.obj",
        b"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        "non-finite",
    ),
    (
        "inf.obj",
        b"v 1e39 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        "non-finite",
    ),
    ("garbage.obj", b"hello\x00\x01world\n", "no triangles"),
    (
        "trunc.gltf",
        br#"{"asset": {"version": "2.0"}, "meshes": ["#,
        "trunc.gltf",
    ),
    (
        "trunc.glb",
        b"glTF\x02\x00\x00\x00\xff\x00\x00\x00",
        "trunc.glb",
    ),
    ("bad.toml", b"[camera\nposition=", "line 1, column 8"),
    (
        "nan.toml",
        b"[[object]]\nkind = \"sphere\"\ncenter = [nan, 0, 0]\nradius = 1\n",
        "not finite",
    ),
    (
        "typo.toml",
        b"[[object]]\nkind = \"sphere\"\ncentre = [0, 0, 0]\nradius = 1\n",
        "centre",
    ),
    (
        "idx.toml",
        b"[[object]]\nkind = \"polygons\"\npositions = [[0,0,0]]\nfaces = [[0, 1, 2]]\n",
        "out of range",
    ),
    (
        "mesh.toml",
        b"[[object]]\nkind = \"mesh\"\npath = \"absent.obj\"\n",
        "absent.obj",
    ),
    (
        "cam.toml",
        b"[camera]\nposition = [0,0,0]\nlook_at = [0,0,0]\n",
        "cam.toml: camera: position and look_at are the same point [0, 0, 0]",
    ),
    ("scene.txt", b"hello", "unknown scene file type"),
    (
        "cam-up.toml",
        b"[camera]\nposition = [0,0,5]\nlook_at = [0,0,0]\nup = [0,0,1]\n",
        "cam-up.toml: camera: up [0, 0, 1] is zero or parallel to the view direction",
    ),
    // Height fields and volumes from broken or absurd files.
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

#[test]
fn bad_files_give_one_line_errors() {
    let dir = tmp_dir("bad");
    // What the height fields and volumes of `BAD_FILES` read.
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
    let missing_buffer = format!(
        "missing-buffer.gltf: buffer 0: {}: No such file or directory",
        dir.join("missing.bin").display()
    );
    let mut cases: Vec<(String, &str)> = BAD_FILES
        .iter()
        .map(|(name, text, needle)| (write(&dir, name, text), *needle))
        .collect();
    cases.extend([
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
        ("soup:0".to_owned(), "soup:0"),
        ("terrain:99999".to_owned(), "terrain:99999"),
        ("heightfield:0".to_owned(), "heightfield:0"),
    ]);
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
    let out = dir.join("o.png");
    for (scene, needle) in &cases {
        #[rustfmt::skip]
        let o = raybench(&[
            "render", scene, "--width", "8", "--height", "8", "--out", out.to_str().unwrap(),
        ]);
        assert_clean_error(&o, needle);
    }
    assert!(!out.exists());
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

/// What renders as silent garbage is refused (an empty scene, negative colours,
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
    let o = render(&flat, (4, 4), &out, &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("warning:"))
        .collect();
    assert_eq!(warnings.len(), 1, "{stderr}");
    assert!(warnings[0].contains("has zero area"), "{stderr}");
    assert!(out.exists());
    std::fs::remove_dir_all(dir).unwrap();
}

/// Faults a dependency would panic on, or silently swallow, are errors naming the file and
/// the place: a material library's short colour line (tobj unwraps it), its other malformed
/// statements (tobj turned them into "no materials"), and a glTF image without a source or
/// a buffer-view image without a MIME type (the gltf crate unwraps both).
#[test]
fn dependency_faults_are_errors_not_panics() {
    let dir = tmp_dir("dependency-faults");
    let obj = b"mtllib m.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let out = dir.join("o.png");
    for (mtl, needle) in [
        (
            "newmtl m\nKd 0.5 0.5\n",
            "line 2: `Kd` needs 3 finite numbers, found `0.5 0.5`",
        ),
        (
            "newmtl m\nKd\n",
            "line 2: `Kd` needs 3 finite numbers, found ``",
        ),
        ("newmtl m\n\nKs 1\n", "line 3: `Ks` needs 3 finite numbers"),
        ("newmtl m\nKa 1 1\n", "line 2: `Ka` needs 3"),
        ("newmtl m\nKe 1 2\n", "line 2: `Ke` needs 3"),
        (
            "newmtl m\nKd 1 1 1 1\n",
            "line 2: `Kd` needs 3 finite numbers, found `1 1 1 1`",
        ),
        ("newmtl m\nKd a b c\n", "line 2: `Kd` needs 3"),
        (
            "newmtl m\nillum banana\n",
            "line 2: `illum` needs one whole number",
        ),
        ("newmtl m\nNs nan\n", "line 2: `Ns` needs 1 finite number"),
        ("newmtl m\nmap_Kd\n", "line 2: `map_Kd` needs a file name"),
    ] {
        write(&dir, "m.mtl", mtl.as_bytes());
        let scene = write(&dir, "p.obj", obj);
        #[rustfmt::skip]
        let o = raybench(&["render", &scene, "--width", "8", "--height", "8", "--out", out.to_str().unwrap()]);
        assert_clean_error(&o, &format!("m.mtl: malformed material library: {needle}"));
    }
    // A well-formed library still loads, and a missing one still means no materials.
    write(
        &dir,
        "m.mtl",
        b"# a library\nnewmtl m\nKd 0.5 0.5 0.5 # grey\nNs 10\nillum 2\n",
    );
    let scene = write(&dir, "p.obj", obj);
    render(&scene, (8, 8), &out, &[]);
    std::fs::remove_file(dir.join("m.mtl")).unwrap();
    render(&scene, (8, 8), &out, &[]);

    let gltf = |images: &str| {
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "images": {images}, "textures": [{{"source": 0}}],
            "materials": [{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}}}}}]}}"#
        )
    };
    for (images, needle) in [
        ("[{}]", "image 0 has neither a uri nor a bufferView"),
        (
            r#"[{"bufferView": 0}]"#,
            "image 0 is in a bufferView but has no mimeType",
        ),
    ] {
        let scene = write(&dir, "i.gltf", gltf(images).as_bytes());
        #[rustfmt::skip]
        let o = raybench(&["render", &scene, "--width", "8", "--height", "8", "--out", out.to_str().unwrap()]);
        assert_clean_error(&o, &format!("i.gltf: {needle}"));
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// A write that fails part-way (here a file-size limit of 1 KiB, as a full disk or a quota
/// would) is one error line naming the file and a non-zero exit, and leaves neither the file
/// nor its temporary one: PNG, OpenEXR and PFM colour, the id image, and a diff's maps.
#[cfg(unix)]
#[test]
fn a_failed_write_is_an_error_and_leaves_no_file() {
    let dir = tmp_dir("file-size-limit");
    let limited = |args: &[&str]| {
        // The limit's signal ignored (as a shell does for a background job), so that the
        // write fails with "File too large" instead of killing the process.
        Command::new("sh")
            .arg("-c")
            .arg("trap '' XFSZ; ulimit -f 1; exec \"$0\" \"$@\"")
            .arg(env!("CARGO_BIN_EXE_raybench"))
            .args(args)
            .output()
            .expect("sh runs")
    };
    let at = |name: &str| dir.join(name).to_str().unwrap().to_owned();
    #[rustfmt::skip]
    let size = ["--width", "128", "--height", "128"];
    for name in ["x.png", "x.exr", "x.pfm"] {
        let out = at(name);
        let mut args = vec!["render", "spheres", "--out", &out];
        args.extend(size);
        assert_clean_error(&limited(&args), &format!("cannot write {out}"));
    }
    let (ids, small) = (at("ids.png"), at("small.pfm"));
    let mut args = vec!["render", "spheres", "--ids", &ids, "--out", &small];
    args.extend(size);
    // The colour (written first) or the id image: whichever passes the limit first.
    assert_clean_error(&limited(&args), "cannot write ");
    // diff's maps, over the limit: the same frame at two exposures.
    render("spheres", (128, 128), &dir.join("c.pfm"), &[]);
    render(
        "spheres",
        (128, 128),
        &dir.join("d.pfm"),
        &["--exposure", "-1"],
    );
    let maps = at("maps");
    let o = limited(&["diff", &at("c.pfm"), &at("d.pfm"), "--out", &maps]);
    assert_clean_error(&o, &format!("cannot write {maps}/"));
    let left: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .chain(std::fs::read_dir(&maps).unwrap())
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| {
            n.starts_with('x')
                || n.starts_with("ids")
                || n.starts_with("small")
                || n.contains("partial")
        })
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// A backend name that does not exist is refused before the scene loads (`loaded ...` is
/// what loading prints).
#[test]
fn unknown_backends_are_refused_before_the_scene_loads() {
    for command in ["compare", "info"] {
        let o = raybench(&[command, "spheres", "--backends", "bvh,nope"]);
        assert_clean_error(&o, "nope");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!stderr.contains("loaded"), "{command}: {stderr}");
    }
}
