//! Determinism: every exact CPU backend renders bit-identical frames (colours, primitive ids
//! and `t`, and the ray count) on 1, 2 and 7 rayon threads and across two runs on the same
//! thread count, in every mode: ray casting, Whitted, path tracing (2 samples), and the
//! volume modes mip and composite on the `phantom` volume; on every kind of scene: meshes and
//! spheres, CSG, quadrics, SDFs, volumes, instances, motion, height fields, Bezier patches,
//! textures and smooth normals. Frames are small (24 x 24) so naive stays fast.
//!
//! Cross-backend agreement is `equivalence.rs`' and `volumes.rs`' business; this suite
//! proves that no backend's result depends on scheduling (work stealing, tile order, shared
//! state) or on state left over from an earlier render.

use raybench_core::{Frame, Mode};
use raybench_tests::{available, load_or_skip, mode_settings, prepared};

/// Every exact CPU backend.
const BACKENDS: &[&str] = raybench_tests::EXACT_BACKENDS;

/// Frame side in pixels.
const SIZE: u32 = 24;

/// Asserts that `frame` equals `reference` bit for bit: colours, ids, `t`, ray count.
fn assert_identical(what: &str, reference: &Frame, frame: &Frame) {
    raybench_tests::assert_same_hits(what, reference, frame);
    assert_eq!(reference.stats.rays, frame.stats.rays, "{what}: ray counts");
    for (i, (a, b)) in reference.color.iter().zip(&frame.color).enumerate() {
        assert!(
            a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits),
            "{what}: pixel {i} colour {a} vs {b}"
        );
    }
}

/// Renders `scene` in each of `modes` with every backend: one renderer per backend renders
/// on 1 thread (the reference), 2 threads, 7 threads, and 7 threads again.
fn check(scene: &str, modes: &[(Mode, u32)]) {
    let Some(scene_data) = load_or_skip(scene) else {
        return;
    };
    for name in available(BACKENDS) {
        let r = prepared(name, &scene_data);
        for &(mode, spp) in modes {
            let settings = mode_settings(SIZE, mode, spp);
            let render = |threads: usize| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| r.render(&settings).unwrap())
            };
            let reference = render(1);
            assert!(
                reference.color.iter().any(|c| *c != reference.color[0]),
                "{name} {scene} {}: a flat image proves nothing",
                mode.name()
            );
            for (run, threads) in [2, 7, 7].into_iter().enumerate() {
                let what = format!(
                    "{name} on {scene}, {} spp {spp}, {threads} threads (run {run})",
                    mode.name()
                );
                assert_identical(&what, &reference, &render(threads));
            }
        }
    }
}

const SURFACE_MODES: &[(Mode, u32)] = &[(Mode::Cast, 1), (Mode::Whitted, 1), (Mode::Path, 2)];

#[test]
fn surface_modes_on_the_cornell_box() {
    check("cornell-box", SURFACE_MODES);
}

#[test]
fn surface_modes_on_the_whitted_scene() {
    check("whitted", SURFACE_MODES);
}

#[test]
fn surface_modes_on_mixed_primitives() {
    // CSG, quadrics and an SDF: the analytic primitives with the most arithmetic.
    for scene in ["csg", "quadrics", "sdf"] {
        check(scene, &[(Mode::Cast, 1), (Mode::Path, 2)]);
    }
}

#[test]
fn volume_modes_on_the_phantom() {
    check("phantom", &[(Mode::Mip, 1), (Mode::Composite, 2)]);
}

/// A scene file of `tests/scenes/`.
fn test_scene(name: &str) -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    path.to_str().expect("a UTF-8 path").to_owned()
}

#[test]
fn surface_modes_on_instanced_and_moving_scenes() {
    // Instances (per-instance transforms, the two-level walk) and motion (the frame's time).
    for scene in ["instances", "moving"] {
        check(scene, SURFACE_MODES);
    }
}

#[test]
fn surface_modes_on_height_fields_and_bezier_patches() {
    // Walked directly, not tessellated: the height-field walk and the patches' Newton steps.
    for scene in ["heightfield", "teapot-bezier"] {
        check(scene, SURFACE_MODES);
    }
}

#[test]
fn surface_modes_on_textured_and_smooth_shaded_meshes() {
    // Texture lookups and interpolated normals, on a glTF mesh and on instanced OBJ meshes.
    for scene in ["textured-smooth.toml", "instanced-smooth.toml"] {
        check(&test_scene(scene), SURFACE_MODES);
    }
}
