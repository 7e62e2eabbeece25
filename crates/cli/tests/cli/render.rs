//! `raybench render`: colour and id images, every volume and surface kind, PLY meshes and
//! Bezier patches from their files, and the scene's cameras chosen and adjusted.

use crate::common::{assert_clean_error, raybench, render, write};
use crate::tmp_dir;
use std::path::Path;

/// Fails when the image at `path` is one flat colour: nothing was drawn.
fn assert_not_flat(path: &Path, what: &str) -> image::RgbImage {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{what}: {}: {e}", path.display()))
        .to_rgb8();
    let first = *img.get_pixel(0, 0);
    assert!(img.pixels().any(|p| *p != first), "{what} is flat");
    img
}

#[test]
fn render_writes_colour_and_id_images() {
    let dir = tmp_dir("render");
    let out = dir.join("s.png");
    let ids = dir.join("ids.png");
    let o = render("spheres", (40, 30), &out, &["--ids", ids.to_str().unwrap()]);
    assert!(o.stdout.is_empty(), "render prints data only to files");
    for p in [&out, &ids] {
        let bytes = std::fs::read(p).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
    }
    assert!(!dir.join("s.png.partial").exists());
    std::fs::remove_dir_all(dir).unwrap();
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
        render(scene, (32, 32), &out, &["--mode", mode]);
        // Something is drawn: not one flat colour.
        let img = assert_not_flat(&out, &format!("{scene} {mode}"));
        assert_eq!(img.dimensions(), (32, 32));
    }
    std::fs::remove_dir_all(dir).unwrap();
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
        render(&spec, (24, 16), &out, &[]);
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
            "truncated.ply: face 2 (byte 230): the file ends inside this record: its list \
             'vertex_indices' of 3 entries needs 12 bytes, 9 are left",
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
        render(&file, (24, 24), &out, &["--mode", mode]);
        assert_not_flat(&out, &format!("{name} {mode}"));
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

/// `--camera` picks one of a scene's cameras by name or index, and the overrides adjust it;
/// bad choices are one error line.
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
        let id = dir.join("ids.png");
        let mut args = vec!["--ids", id.to_str().unwrap()];
        args.extend_from_slice(extra);
        render(&scene, (16, 16), &dir.join("c.png"), &args);
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
