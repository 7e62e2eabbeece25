//! `raybench diff` on the linear images `render --out` writes as EXR or PFM: the same values
//! in both formats, `--exposure`, the error maps, `--fail-above`'s exit status, and bad
//! images refused with one error line.

use crate::common::{assert_clean_error, assert_success, raybench, render, write};
use crate::tmp_dir;
use std::process::Output;

/// `--out` writes unclamped linear radiance as EXR or PFM (scaled by `--exposure`), and
/// `raybench diff` measures images against each other.
#[test]
fn linear_output_and_diff() {
    let dir = tmp_dir("linear");
    let path = |n: &str| dir.join(n).to_str().unwrap().to_owned();
    for (name, extra) in [
        ("a.exr", &[][..]),
        ("a.pfm", &[]),
        ("a.png", &[]),
        ("half.pfm", &["--exposure", "-1"]),
    ] {
        render("spheres", (32, 24), &dir.join(name), extra);
    }
    let diff = |args: &[&str]| {
        let mut all = vec!["diff"];
        all.extend_from_slice(args);
        raybench(&all)
    };
    let json = |o: &Output| -> serde_json::Value {
        assert_success(o);
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
    // A pixel that is not a number passes no gate, whatever the metric; it is counted.
    let pfm = |name: &str, values: [f32; 6]| {
        let mut bytes = b"PF\n2 1\n-1.0\n".to_vec();
        bytes.extend(values.iter().flat_map(|v| v.to_le_bytes()));
        write(&dir, name, &bytes)
    };
    let finite = pfm("finite.pfm", [0.5; 6]);
    let nan = pfm("nan.pfm", [0.5, 0.5, 0.5, f32::NAN, 0.5, 0.5]);
    for metric in ["flip", "mae", "max", "mse", "relmse"] {
        let o = diff(&[&finite, &nan, "--fail-above", "1", "--metric", metric]);
        assert_eq!(o.status.code(), Some(2), "{metric}");
        let (stdout, stderr) = (
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr),
        );
        assert!(
            stdout.contains("non-finite      0 (A)  1 (B) pixels"),
            "{stdout}"
        );
        assert!(
            stderr.contains("0 pixels of A and 1 of B are not finite"),
            "{stderr}"
        );
    }
    let counted = json(&diff(&[&nan, &finite, "--json"]));
    assert_eq!(
        (
            counted["non_finite_a"].as_u64(),
            counted["non_finite_b"].as_u64()
        ),
        (Some(1), Some(0))
    );
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
