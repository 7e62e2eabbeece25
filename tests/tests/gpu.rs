//! The GPU backend (`wgpu`) against the naive oracle on every built-in scene, within the
//! tolerances of `raybench_tests::gpu`. Runs on whatever adapter wgpu finds: Mesa's lavapipe
//! (software Vulkan, about one CPU thread's speed) in CI, so images stay small. Skips when
//! there is no adapter, except under `CI=true`.

use raybench_core::{RenderError, Renderer};
use raybench_tests::gpu::check;

/// Ray casting at 64 x 64 (the equivalence test's size) on every built-in scene; the modes
/// with secondary rays at 32 x 32 on the scenes small enough for naive.
macro_rules! gpu_tests {
    ($($test:ident => $scene:literal, $modes:literal,)*) => {
        $(
            #[test]
            fn $test() {
                check($scene, if $modes { 32 } else { 64 }, $modes);
            }
        )*
    };
}

gpu_tests! {
    spheres => "spheres", true,
    whitted => "whitted", true,
    cornell_box => "cornell-box", true,
    suzanne => "suzanne", true,
    teapot => "teapot", true,
    random_spheres => "spheres:2000", true,
    terrain => "terrain:32", true,
    bunny_lowres => "bunny-lowres", false,
    bunny => "bunny", false,
    sponza => "sponza", false,
    soup => "soup:10000", false,
    icosphere => "icosphere:4", false,
    teapot_stadium => "teapot-stadium", false,
}

#[test]
fn a_missing_adapter_is_reported_not_panicked() {
    let request = raybench_wgpu::AdapterRequest::named("no such adapter 1f8e3c");
    let mut r = raybench_wgpu::WgpuRenderer::with_request("wgpu", "test", request);
    let reason = r.availability().unwrap_err();
    assert!(reason.contains("no such adapter 1f8e3c"), "{reason}");
    let scene =
        std::sync::Arc::new(raybench_scene::load("spheres", std::path::Path::new(".")).unwrap());
    match r.prepare(&scene) {
        Err(RenderError::Unavailable(why)) => assert_eq!(why, reason),
        other => panic!("expected Unavailable, got {other:?}"),
    }
    assert!(matches!(
        r.render(&Default::default()),
        Err(RenderError::NotPrepared)
    ));
}

#[test]
fn the_empty_scene_renders_background() {
    if !raybench_tests::gpu::available() {
        return;
    }
    let scene = raybench_tests::empty_scene();
    let r = raybench_tests::prepared("wgpu", &scene);
    let settings = raybench_core::RenderSettings {
        width: 8,
        height: 5,
        ..Default::default()
    };
    let f = r.render(&settings).unwrap();
    assert!(f.ids.iter().all(|&id| id == raybench_core::NO_HIT));
    assert!(f.color.iter().all(|&c| c == scene.background));
}

/// Height fields, CSG trees and the volume modes have no WGSL port: the backend refuses them with a
/// reason instead of rendering something else.
#[test]
fn kinds_and_modes_without_kernels_are_refused() {
    let r = raybench_wgpu::WgpuRenderer::new("wgpu", "test");
    for mode in [raybench_core::Mode::Mip, raybench_core::Mode::Composite] {
        let why = r.supports_mode(mode).unwrap_err();
        assert!(why.contains(mode.name()), "{why}");
    }
    let scene = raybench_scene::load("heightfield:8", std::path::Path::new(".")).unwrap();
    assert!(raybench_wgpu::check_kinds(&scene).is_err());
    let csg = raybench_scene::load("csg", std::path::Path::new(".")).unwrap();
    let why = raybench_wgpu::check_kinds(&csg).unwrap_err();
    assert!(why.contains("CSG"), "{why}");
    if !raybench_tests::gpu::available() {
        return;
    }
    let mut r = r;
    assert!(r.supports(&scene).unwrap_err().contains("height field"));
    assert!(matches!(
        r.prepare(&std::sync::Arc::new(scene)),
        Err(RenderError::Unsupported(_))
    ));
}
