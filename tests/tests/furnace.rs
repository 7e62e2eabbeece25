//! The path tracer against an analytic reference: the Cornell box's own geometry
//! as a furnace (`scripts/cornell-furnace.toml`: every surface albedo 0.5 and emission 0.5,
//! the background 1.0, so the exact radiance is 1.0 on every pixel), path traced with
//! `--max-depth 64` (next-event estimation with MIS towards every triangle), written as
//! OpenEXR and read back. The image mean must agree with 1.0 within 1 %, with samples
//! enough for three standard errors to be under 1 %. `scripts/cornell-furnace.sh` runs
//! the same check at 256 x 256 over seeds outside CI.

use raybench_core::{Mode, RenderSettings};
use raybench_tests::{BASELINE, load_or_skip, render_with};

#[test]
fn cornell_box_furnace_written_as_exr_agrees_within_one_percent() {
    let spec = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scripts/cornell-furnace.toml"
    );
    let Some(scene) = load_or_skip(spec) else {
        return;
    };
    let settings = RenderSettings {
        width: 48,
        height: 48,
        spp: 32,
        mode: Mode::Path,
        max_depth: 64,
        seed: 3,
        ..RenderSettings::default()
    };
    let frame = render_with(BASELINE, &scene, &settings, 2);
    let dir = std::env::temp_dir().join(format!("raybench-furnace-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let exr = dir.join("furnace.exr");
    raybench_render::write_color(&frame, &exr, 0.0).unwrap();
    let image = raybench_render::read_linear(&exr).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(
        image.color, frame.color,
        "EXR holds the linear radiance exactly"
    );

    // Pixels are independent estimates; the standard error of their mean follows from
    // their spread.
    let values: Vec<f64> = image
        .color
        .iter()
        .flat_map(|c| c.to_array())
        .map(f64::from)
        .collect();
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let se = (var / n).sqrt();
    eprintln!("furnace in the Cornell box: image mean {mean:.5} +- {se:.5}");
    assert!(
        3.0 * se < 0.01,
        "standard error {se}: too few samples for a 1 % bound"
    );
    assert!(
        (mean - 1.0).abs() <= 0.01,
        "image mean {mean} +- {se}, exact 1.0"
    );
    assert!(
        frame.ids.iter().any(|&id| id != raybench_core::NO_HIT),
        "the camera sees the box"
    );
}
