//! Files that a scene file names (meshes, environment maps, patch files, height and volume
//! samples): when one cannot be used, the one-line error names the scene file, the line and
//! table that name it, and, for a file that is not found, every place looked in with what
//! is there instead.

use raybench_scene::{LoadError, load_toml_file};
use std::path::{Path, PathBuf};

/// This test's scratch folder `name`, fresh.
fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("raybench-referenced-{}-{name}", std::process::id()));
    std::fs::remove_dir_all(&d).ok();
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Loads the scene `text` written as `scene.toml` in `dir`, with the assets in `assets`.
fn load(dir: &Path, text: &str, assets: &Path) -> Result<raybench_core::Scene, LoadError> {
    let p = dir.join("scene.toml");
    std::fs::write(&p, text).unwrap();
    load_toml_file(&p, assets)
}

/// The error of loading `text`, checked to be one line naming the scene file.
fn error(dir: &Path, text: &str, assets: &Path) -> String {
    let e = load(dir, text, assets)
        .err()
        .unwrap_or_else(|| panic!("accepted: {text}"))
        .to_string();
    assert!(!e.contains('\n'), "{e}");
    assert!(
        e.starts_with(&dir.join("scene.toml").display().to_string()),
        "{e}"
    );
    e
}

/// A sphere, so that a scene has an object besides the one under test.
const SPHERE: &str = "[[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n";

/// Every key naming a file: a name found nowhere gives the scene file, the line, each
/// place looked in with what is there (missing, a folder), and how to point at the
/// assets; an empty name is refused as such.
#[test]
fn a_missing_file_names_the_scene_line_and_every_place() {
    let d = dir("missing");
    let assets = dir("missing-assets");
    std::fs::create_dir_all(assets.join("a-folder.obj")).unwrap();
    let cases = [
        format!("{SPHERE}[[object]]\nkind = \"mesh\"\npath = \"absent.obj\"\n"),
        format!("background = {{ map = \"absent.hdr\" }}\n{SPHERE}"),
        format!("{SPHERE}[[object]]\nkind = \"bezier\"\nfile = \"absent.bpt\"\n"),
        format!(
            "{SPHERE}[[object]]\nkind = \"height_field\"\nraw = \"absent.raw\"\n\
             size = [2, 2]\n"
        ),
        format!("{SPHERE}[[object]]\nkind = \"height_field\"\npng = \"absent.png\"\n"),
        format!("{SPHERE}[[volume]]\nraw = \"absent.raw\"\ndims = [2, 2, 2]\n"),
    ];
    let lines = [5, 1, 5, 5, 5, 5];
    for (text, line) in cases.iter().zip(lines) {
        let e = error(&d, text, &assets);
        assert!(e.contains(&format!("scene.toml: line {line}: ")), "{e}");
        assert!(e.contains("names no readable file"), "{e}");
        assert!(
            e.contains(&format!("looked at {}/absent.", d.display()))
                && e.contains(&format!("(missing) and {}/absent.", assets.display()))
                && e.ends_with(
                    "(missing); point --assets or RAYBENCH_ASSETS at the folder \
                                holding the shared scenes"
                ),
            "{e}"
        );
        assert!(!e.contains("which does not exist"), "{e}");
        assert!(
            load(&d, text, &assets)
                .err()
                .is_some_and(|e| e.is_missing_asset())
        );
    }
    // A folder in the assets.
    let e = error(
        &d,
        "[[object]]\nkind = \"mesh\"\npath = \"a-folder.obj\"\n",
        &assets,
    );
    assert!(
        e.contains("line 1: object 1 (mesh): `path` 'a-folder.obj' names no readable file")
            && e.contains("a-folder.obj (missing) and ")
            && e.contains("a-folder.obj (a folder, not a regular file)"),
        "{e}"
    );
    // An absolute path is looked for there only, and the assets are not mentioned.
    let e = error(
        &d,
        "[[object]]\nkind = \"mesh\"\npath = \"/nonexistent/m.obj\"\n",
        &assets,
    );
    assert!(
        e.contains("looked at /nonexistent/m.obj (missing)") && !e.contains("--assets"),
        "{e}"
    );
    // An empty name.
    for text in [
        "[[object]]\nkind = \"mesh\"\npath = \"\"\n".to_owned(),
        format!("background = {{ map = \" \" }}\n{SPHERE}"),
    ] {
        let e = error(&d, &text, &assets);
        assert!(e.contains("is empty: it names a file"), "{e}");
    }
}

/// A FIFO and a symbolic link loop are found, and said to be what they are.
#[cfg(unix)]
#[test]
fn a_fifo_or_a_link_loop_is_named() {
    let d = dir("special");
    let assets = dir("special-assets");
    std::os::unix::fs::symlink("loop.obj", d.join("loop.obj")).unwrap();
    let e = error(
        &d,
        "[[object]]\nkind = \"mesh\"\npath = \"loop.obj\"\n",
        &assets,
    );
    assert!(e.contains("loop.obj (a symbolic link loop"), "{e}");
    let made = std::process::Command::new("mkfifo")
        .arg(d.join("pipe.raw"))
        .status();
    if !made.is_ok_and(|s| s.success()) {
        println!("skipped the FIFO: mkfifo is not available");
        return;
    }
    let e = error(
        &d,
        &format!("{SPHERE}[[volume]]\nraw = \"pipe.raw\"\ndims = [2, 2, 2]\n"),
        &assets,
    );
    assert!(
        e.contains("pipe.raw (a FIFO (named pipe), not a regular file)"),
        "{e}"
    );
}

/// The errors of a file that is found but cannot be used name the scene file and line
/// too: a raw file too long or too short (and which), a malformed mesh or patch file, a
/// generator spec out of range.
#[test]
fn errors_of_named_files_name_the_scene_and_line() {
    let d = dir("named");
    let assets = dir("named-assets");
    std::fs::write(d.join("v.raw"), [0u8; 20]).unwrap();
    std::fs::write(d.join("bad.obj"), "v 0 0 0\nf 1 2 3\n").unwrap();
    std::fs::write(d.join("bad.bpt"), "zero\n").unwrap();
    let cases = [
        (
            format!("{SPHERE}[[volume]]\nraw = \"v.raw\"\ndims = [2, 2, 2]\n"),
            "line 5: volume 1: ",
            "raw file holds 20 bytes, too long for 8 u16 samples (16 bytes)",
        ),
        (
            format!("{SPHERE}[[volume]]\nraw = \"v.raw\"\ndims = [2, 2, 2]\nformat = \"f32\"\n"),
            "line 5: volume 1: ",
            "raw file holds 20 bytes, too short for 8 f32 samples (32 bytes)",
        ),
        (
            format!(
                "{SPHERE}[[object]]\nkind = \"height_field\"\nraw = \"v.raw\"\nsize = [3, 3]\n\
                 format = \"u8\"\n"
            ),
            "line 5: object 2 (height_field): ",
            "too long for 9 u8 samples",
        ),
        (
            "[[object]]\nkind = \"mesh\"\npath = \"bad.obj\"\n".to_owned(),
            "line 1: object 1 (mesh): ",
            "bad.obj: ",
        ),
        (
            "[[object]]\nkind = \"bezier\"\nfile = \"bad.bpt\"\n".to_owned(),
            "line 1: object 1 (bezier): ",
            "bad.bpt: line 1: expected the number of patches",
        ),
        (
            format!("{SPHERE}[[object]]\nkind = \"generator\"\nspec = \"soup:0\"\n"),
            "line 5: object 2 (generator): ",
            "generator 'soup:0': 0 must be in",
        ),
        (
            format!("{SPHERE}[[volume]]\nsource = \"phantom:0\"\n"),
            "line 5: volume 1: ",
            "phantom:0",
        ),
    ];
    for (text, place, cause) in cases {
        let e = error(&d, &text, &assets);
        assert!(e.contains(&format!("scene.toml: {place}")), "{e}");
        assert!(e.contains(cause), "{e}");
    }
}
