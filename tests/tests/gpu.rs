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
    let r = raybench_tests::prepared(raybench_tests::DEVICE, &scene);
    let settings = raybench_core::RenderSettings {
        width: 8,
        height: 5,
        ..Default::default()
    };
    let f = r.render(&settings).unwrap();
    assert!(f.ids.iter().all(|&id| id == raybench_core::NO_HIT));
    assert!(f.color.iter().all(|&c| c == scene.background));
}

/// Height fields, CSG trees, SDF models, Bezier patches and the volume modes have no WGSL port:
/// the backend refuses them with a
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
    let quadrics = raybench_scene::load("quadrics", std::path::Path::new(".")).unwrap();
    assert!(raybench_wgpu::check_kinds(&quadrics).is_err());
    let mut b = raybench_core::SceneBuilder::new("bezier");
    let points =
        std::array::from_fn(|k| raybench_core::Vec3::new((k % 4) as f32, (k / 4) as f32, 0.0));
    let patch = raybench_core::BezierPatch::new(points).unwrap();
    b.add_shapes(
        "patch",
        vec![raybench_core::Shape::Bezier(std::sync::Arc::new(patch))],
        0,
    )
    .unwrap();
    let why = raybench_wgpu::check_kinds(&b.build()).unwrap_err();
    assert!(why.contains("Bezier patch"), "{why}");
    let sdf = raybench_scene::load("sdf", std::path::Path::new(".")).unwrap();
    let why = raybench_wgpu::check_kinds(&sdf).unwrap_err();
    assert!(why.contains("SDF model"), "{why}");
    // Lights the path kernel cannot sample: an environment map (every mode: misses read
    // it), an emissive sphere (path only).
    let mut b = raybench_core::SceneBuilder::new("lights");
    let lamp = b
        .add_material(raybench_core::Material {
            emission: raybench_core::Vec3::ONE,
            ..raybench_core::Material::default()
        })
        .unwrap();
    b.add_sphere(
        raybench_core::Sphere::new(raybench_core::Vec3::ZERO, 1.0),
        lamp,
    )
    .unwrap();
    let lamp_scene = b.clone().build();
    assert!(raybench_wgpu::check_kinds(&lamp_scene).is_ok());
    let why = raybench_wgpu::check_path_emitters(&lamp_scene).unwrap_err();
    assert!(why.contains("sphere"), "{why}");
    let env = raybench_core::Environment::new(1, 1, vec![raybench_core::Vec3::ONE], 1.0, 0.0);
    b.environment(std::sync::Arc::new(env.unwrap()));
    let why = raybench_wgpu::check_kinds(&b.build()).unwrap_err();
    assert!(why.contains("environment map"), "{why}");
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

/// Rays no camera makes: NaN, zero and infinite directions must miss on the GPU as on the
/// CPU (and not poison their neighbours in the same workgroup); denormal, huge and
/// axis-aligned rays must find naive's hits.
#[test]
fn degenerate_and_extreme_rays_behave_as_on_the_cpu() {
    use raybench_core::{Ray, Vec3};
    if !raybench_tests::gpu::available() {
        return;
    }
    let scene = raybench_tests::load_or_skip("spheres:200").unwrap();
    let c = scene.geometry.bounds().center();
    let tiny = f32::MIN_POSITIVE / 4.0;
    let mut rays = vec![
        Ray::new(Vec3::splat(f32::NAN), Vec3::X),
        Ray::new(c, Vec3::new(f32::NAN, 1.0, 0.0)),
        Ray::new(c, Vec3::ZERO),
        Ray::new(c, Vec3::new(f32::INFINITY, 0.0, 0.0)),
        Ray::new(c + Vec3::splat(1e30), -Vec3::ONE),
    ];
    let must_miss = rays.len() - 1;
    for axis in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
        rays.push(Ray::new(c, axis));
        rays.push(Ray::new(c, axis + Vec3::splat(tiny)));
        rays.push(Ray::new(c - axis * 1e6, axis * 1e-20));
    }
    // Ordinary rays between them: a bad lane must not spoil the others.
    rays.extend(raybench_core::ray_sets::incoherent(
        scene.geometry.bounds(),
        64,
        3,
    ));
    let (reference, _) = raybench_tests::prepared(raybench_tests::ORACLE, &scene)
        .trace_rays(&rays, false)
        .unwrap();
    let (hits, _) = raybench_tests::prepared(raybench_tests::DEVICE, &scene)
        .trace_rays(&rays, false)
        .unwrap();
    for (i, (a, b)) in reference.iter().zip(&hits).enumerate() {
        if i < must_miss {
            assert!(
                a.is_none() && b.is_none(),
                "ray {i} {:?}: {a:?} {b:?}",
                rays[i]
            );
            continue;
        }
        assert_eq!(
            a.map(|h| h.prim),
            b.map(|h| h.prim),
            "ray {i} {:?}",
            rays[i]
        );
        if let (Some(a), Some(b)) = (a, b) {
            assert!(
                (a.t - b.t).abs() <= raybench_tests::gpu::MAX_REL_DT as f32 * a.t.abs(),
                "ray {i}: t {} vs {}",
                a.t,
                b.t
            );
        }
    }
}

/// Many samples on a small frame, split into many dispatches (progressive accumulation,
/// `plan::MAX_SAMPLES_PER_DISPATCH`): every sample is traced and the accumulated image
/// matches the CPU's.
#[test]
fn samples_split_over_dispatches_accumulate() {
    use raybench_core::{Mode, RenderSettings};
    if !raybench_tests::gpu::available() {
        return;
    }
    let scene = raybench_tests::load_or_skip("spheres").unwrap();
    let settings = RenderSettings {
        width: 8,
        height: 8,
        spp: 2_000,
        mode: Mode::Path,
        max_depth: 3,
        seed: 3,
        count: false,
        ..RenderSettings::default()
    };
    let pixels = u64::from(settings.width * settings.height);
    let plan = raybench_wgpu::plan::frame(
        settings.width,
        settings.height,
        settings.spp,
        raybench_wgpu::plan::budget(Mode::Path),
        pixels,
        65_535,
    );
    assert!(
        plan[0].dispatches.len() > 1,
        "the test must split: {plan:?}"
    );
    let reference = raybench_tests::render_with(raybench_tests::ORACLE, &scene, &settings, 2);
    let frame = raybench_tests::prepared(raybench_tests::DEVICE, &scene)
        .render(&settings)
        .unwrap();
    assert_eq!(frame.ids, reference.ids);
    // Every sample traced: a lost sample (as when lavapipe cut a thread's long loop, see
    // `plan::MAX_SAMPLES_PER_DISPATCH`) shows as missing rays. Paths may branch differently
    // on the GPU, so the counts agree within 1%.
    let (a, b) = (reference.stats.rays as f64, frame.stats.rays as f64);
    assert!((a - b).abs() <= 0.01 * a, "rays: naive {a}, wgpu {b}");
    raybench_tests::gpu::assert_close_colors(
        "wgpu, path, 2,000 samples",
        &reference.color,
        &frame.color,
        raybench_tests::gpu::MAX_PATH_COLOR_MISMATCH,
    );
}
