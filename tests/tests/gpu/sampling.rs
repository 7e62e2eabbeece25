//! The GPU beyond one frame per scene: the same frame rendered twice, and by a second
//! renderer, is bit-identical (the kernels' random numbers are keyed by pixel, sample and
//! bounce, and nothing carries over between dispatches); path tracing with BSDF sampling
//! only (no next-event estimation) agrees with the CPU; the derived ray sets (`shadow`,
//! `ao`, `diffuse`, generated from the CPU's primary hits) get the CPU's answers.

use raybench_core::ray_sets::{self, DerivedParams};
use raybench_core::{Frame, LightSampling, Mode, RaySet, RenderSettings};
use raybench_tests::gpu::{
    MAX_PATH_COLOR_MISMATCH, MAX_REL_DT, MIN_ID_MATCH, assert_close_colors, assert_close_hits,
    available, hit_keys, reach_dt,
};
use raybench_tests::{BASELINE, DEVICES, load_or_skip, mode_settings, prepared};

/// Ids, `t` and colours as bits, for an exact comparison.
fn frame_bits(f: &Frame) -> (Vec<u32>, Vec<u32>, Vec<[u32; 3]>) {
    (
        f.ids.clone(),
        f.t.iter().map(|t| t.to_bits()).collect(),
        f.color
            .iter()
            .map(|c| c.to_array().map(f32::to_bits))
            .collect(),
    )
}

#[test]
fn the_same_frame_twice_is_bit_identical() {
    if !available() {
        return;
    }
    let Some(scene) = load_or_skip("cornell-box") else {
        return;
    };
    for name in DEVICES {
        let gpu = prepared(name, &scene);
        for (mode, spp) in [(Mode::Whitted, 1), (Mode::Path, 4)] {
            let settings = mode_settings(32, mode, spp);
            let first = gpu.render(&settings).unwrap();
            let again = gpu.render(&settings).unwrap();
            let fresh = prepared(name, &scene).render(&settings).unwrap();
            let what = format!("{name} on cornell-box, {} spp {spp}", mode.name());
            assert!(
                first.color.iter().any(|c| *c != first.color[0]),
                "{what}: a flat image proves nothing"
            );
            assert!(
                frame_bits(&first) == frame_bits(&again),
                "{what}: the second render differs"
            );
            assert!(
                frame_bits(&first) == frame_bits(&fresh),
                "{what}: a second renderer's render differs"
            );
        }
    }
}

#[test]
fn bsdf_only_light_sampling_agrees_with_the_cpu() {
    if !available() {
        return;
    }
    let Some(scene) = load_or_skip("cornell-box") else {
        return;
    };
    let bsdf = RenderSettings {
        light_sampling: LightSampling::Bsdf,
        ..mode_settings(32, Mode::Path, 4)
    };
    let mis = mode_settings(32, Mode::Path, 4);
    let reference = prepared(BASELINE, &scene).render(&bsdf).unwrap();
    for name in DEVICES {
        let gpu = prepared(name, &scene);
        let frame = gpu.render(&bsdf).unwrap();
        let what = format!("{name} on cornell-box, path, BSDF sampling only");
        assert_close_hits(&what, &reference, &frame);
        assert_close_colors(
            &what,
            &reference.color,
            &frame.color,
            MAX_PATH_COLOR_MISMATCH,
        );
        // The setting reaches the kernel: next-event estimation changes most pixels.
        let with_mis = gpu.render(&mis).unwrap();
        let changed = frame
            .color
            .iter()
            .zip(&with_mis.color)
            .filter(|(a, b)| a != b)
            .count();
        assert!(
            changed > frame.color.len() / 2,
            "{what}: only {changed} pixels differ from MIS"
        );
    }
}

#[test]
fn derived_ray_sets_agree_with_the_cpu() {
    if !available() {
        return;
    }
    for scene in ["cornell-box", "dabrovic-sponza"] {
        let Some(s) = load_or_skip(scene) else {
            continue;
        };
        let size = 32;
        let settings = mode_settings(size, Mode::Cast, 1);
        let camera = s.view(&settings).expect("the scene's camera");
        let primary = ray_sets::primary_tiled(camera, size, size, raybench_render::TILE_SIZE);
        let cpu = prepared(BASELINE, &s);
        let (primary_hits, _) = cpu.trace_rays(&primary, false).unwrap();
        let gpus: Vec<_> = DEVICES
            .iter()
            .map(|name| (name, prepared(name, &s)))
            .collect();
        for set in RaySet::ALL.into_iter().filter(|s| s.is_derived()) {
            let rays =
                ray_sets::derived(set, &s, &primary, &primary_hits, &DerivedParams::default())
                    .unwrap_or_else(|e| panic!("{scene}, {} rays: {e}", set.name()));
            assert!(!rays.is_empty(), "{scene}: no {} rays", set.name());
            for (name, gpu) in &gpus {
                let what = format!("{name} on {scene}, {} rays", set.name());
                if set.any_hit() {
                    let (expected, _) = cpu.occlude_rays(&rays, false).unwrap();
                    let (blocked, _) = gpu.occlude_rays(&rays, false).unwrap();
                    let agree = expected
                        .iter()
                        .zip(&blocked)
                        .filter(|(a, b)| a == b)
                        .count();
                    let fraction = agree as f64 / rays.len() as f64;
                    eprintln!("{what}: {:.4}% agree", fraction * 100.0);
                    assert!(
                        fraction >= MIN_ID_MATCH,
                        "{what}: {:.4}% agree",
                        fraction * 100.0
                    );
                } else {
                    let (expected, _) = cpu.trace_rays(&rays, false).unwrap();
                    let (hits, _) = gpu.trace_rays(&rays, false).unwrap();
                    let ((ri, rt), (gi, gt)) = (hit_keys(&expected), hit_keys(&hits));
                    let c = raybench_registry::compare_hits(&ri, &rt, &gi, &gt);
                    let id_match = c.id_match + c.tie_mismatch as f64 / rays.len() as f64;
                    let dt = reach_dt(&rays, (&ri, &rt), (&gi, &gt));
                    eprintln!("{what}: {c:?}, dt relative to reach {dt:.1e}");
                    assert!(
                        id_match >= MIN_ID_MATCH && dt <= MAX_REL_DT,
                        "{what}: {c:?}, dt relative to reach {dt:.1e}"
                    );
                }
            }
        }
    }
}
