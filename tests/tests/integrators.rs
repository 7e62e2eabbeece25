//! Whitted and path tracing with known answers, in the style of pbrt-v4's
//! `integrators_test.cpp`: scenes whose mean radiance is known analytically, checked within
//! a tolerance derived from the sample variance.

use raybench_core::{
    Camera, Material, Mode, RenderSettings, SceneBuilder, Sphere, TriangleMesh, Vec3,
};
use raybench_tests::render_with;
use std::sync::Arc;

/// Mean and standard error of the mean of the pixels' red channel.
fn mean_and_error(values: &[Vec3]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().map(|c| f64::from(c.x)).sum::<f64>() / n;
    let var = values
        .iter()
        .map(|c| (f64::from(c.x) - mean).powi(2))
        .sum::<f64>()
        / (n - 1.0);
    (mean, (var / n).sqrt())
}

fn material(albedo: f32, emission: f32) -> Material {
    Material {
        name: "m".into(),
        base_color: Vec3::splat(albedo),
        emission: Vec3::splat(emission),
        ..Material::default()
    }
}

/// White furnace: diffuse spheres of albedo 1 under a uniform environment of radiance 1
/// reflect exactly what they receive, so every pixel's expected value is 1 (up to paths cut
/// at the maximum depth, negligible at 64 bounces with Russian roulette).
#[test]
fn white_furnace() {
    let mut b = SceneBuilder::new("furnace");
    b.background(Vec3::ONE).unwrap();
    let white = b.add_material(material(1.0, 0.0)).unwrap();
    // Several touching spheres, so that paths bounce between them and roulette kicks in.
    for s in raybench_scene::generators::random_spheres(40, 4) {
        b.add_sphere(Sphere::new(s.center, s.radius * 2.5), white)
            .unwrap();
    }
    b.camera(Camera {
        position: Vec3::new(0.0, 0.0, 4.0),
        look_at: Vec3::ZERO,
        up: Vec3::Y,
        vfov_degrees: 40.0,
    })
    .unwrap();
    let scene = Arc::new(b.build());
    let settings = RenderSettings {
        width: 48,
        height: 48,
        spp: 16,
        mode: Mode::Path,
        max_depth: 64,
        seed: 3,
        count: false,
        ..RenderSettings::default()
    };
    let frame = render_with(raybench_tests::BASELINE, &scene, &settings, 2);
    let (mean, err) = mean_and_error(&frame.color);
    assert!(
        (mean - 1.0).abs() < 5.0 * err + 1e-4,
        "mean {mean} +- {err}"
    );
    // Every pixel, not just the mean, is near 1: a biased estimator shows up here first.
    for c in &frame.color {
        assert!(c.x > 0.3 && c.x < 3.0, "pixel {c}");
    }
    // Misses see exactly the environment.
    assert!(frame.ids.contains(&raybench_core::NO_HIT));
}

/// Inside a closed diffuse emitter of albedo `rho` and emission `Le`, radiance is the same
/// everywhere: `Le (1 + rho + ... + rho^D)` with `D` the maximum depth. The emitter is a
/// mesh (its normals facing inwards), so this also checks next-event estimation towards
/// area lights, which carries every term after the first.
#[test]
fn inside_a_glowing_sphere() {
    let (rho, le, depth) = (0.5f32, 1.0f32, 6u32);
    let ico = raybench_scene::generators::icosphere(3);
    let inward = TriangleMesh {
        positions: ico.positions.iter().map(|&p| p * 2.0).collect(),
        indices: ico.indices.iter().map(|&[a, b, c]| [a, c, b]).collect(),
    };
    let mut b = SceneBuilder::new("glow");
    let m = b.add_material(material(rho, le)).unwrap();
    b.add_mesh("inward sphere", &inward, m).unwrap();
    b.camera(Camera {
        position: Vec3::new(0.2, -0.1, 0.3),
        look_at: Vec3::new(1.0, 0.2, -1.0),
        up: Vec3::Y,
        vfov_degrees: 60.0,
    })
    .unwrap();
    let scene = Arc::new(b.build());
    assert_eq!(scene.emitters.ids.len(), inward.indices.len());
    let settings = RenderSettings {
        width: 32,
        height: 32,
        spp: 32,
        mode: Mode::Path,
        max_depth: depth,
        seed: 11,
        count: false,
        ..RenderSettings::default()
    };
    let frame = render_with(raybench_tests::BASELINE, &scene, &settings, 2);
    let (mean, err) = mean_and_error(&frame.color);
    let expect: f64 = (0..=depth)
        .map(|k| f64::from(le) * f64::from(rho).powi(k as i32))
        .sum();
    assert!(
        (mean - expect).abs() < 5.0 * err + 1e-3,
        "mean {mean} +- {err}, expected {expect}"
    );
}

/// A Lambertian floor under a uniform sky and nothing else reflects `albedo * sky`.
#[test]
fn lambertian_plane_under_uniform_sky() {
    let mut b = SceneBuilder::new("sky");
    b.background(Vec3::splat(0.8)).unwrap();
    let m = b.add_material(material(0.6, 0.0)).unwrap();
    b.add_plane(Vec3::ZERO, Vec3::Y, m).unwrap();
    b.camera(Camera {
        position: Vec3::new(0.0, 1.0, 0.0),
        look_at: Vec3::new(0.0, 0.0, -0.5),
        up: Vec3::Y,
        vfov_degrees: 50.0,
    })
    .unwrap();
    let scene = Arc::new(b.build());
    let settings = RenderSettings {
        width: 16,
        height: 16,
        spp: 4,
        mode: Mode::Path,
        max_depth: 4,
        seed: 0,
        count: false,
        ..RenderSettings::default()
    };
    let frame = render_with(raybench_tests::ORACLE, &scene, &settings, 1);
    for c in &frame.color {
        assert!((c.x - 0.48).abs() < 1e-4, "pixel {c}");
    }
}

/// Whitted's secondary rays survive any sample count: a mirror sphere filling the pixel
/// reflects the background at 1 and at 16,384 samples alike.
#[test]
fn whitted_mirrors_do_not_fade_with_many_samples() {
    let mut b = SceneBuilder::new("mirror");
    b.background(Vec3::splat(0.5)).unwrap();
    let mirror = b
        .add_material(Material {
            name: "mirror".into(),
            kind: raybench_core::MaterialKind::Mirror,
            specular: Vec3::splat(0.8),
            ..Material::default()
        })
        .unwrap();
    b.add_sphere(Sphere::new(Vec3::ZERO, 1.0), mirror).unwrap();
    b.camera(Camera {
        position: Vec3::new(0.0, 0.0, 5.0),
        look_at: Vec3::ZERO,
        up: Vec3::Y,
        vfov_degrees: 0.5,
    })
    .unwrap();
    let scene = Arc::new(b.build());
    for spp in [1, 16_384] {
        let settings = RenderSettings {
            width: 1,
            height: 1,
            spp,
            mode: Mode::Whitted,
            ..Default::default()
        };
        let c = render_with(raybench_tests::ORACLE, &scene, &settings, 1).color[0];
        assert!((c.x - 0.4).abs() < 1e-3, "spp {spp}: {c}");
    }
}

/// The Whitted radiance of the one pixel of a diffuse plane (albedo 0.5) seen from straight
/// above at height 1 (the eye 0.001 off the axis, a 1-degree view), lit by `light` or, with
/// `None`, by nothing but what Whitted ray tracing gives a scene without lights.
fn whitted_plane_pixel(light: Option<raybench_core::Light>) -> Vec3 {
    let mut b = SceneBuilder::new("plane");
    let m = b.add_material(material(0.5, 0.0)).unwrap();
    b.add_plane(Vec3::ZERO, Vec3::Y, m).unwrap();
    if let Some(light) = light {
        b.add_light(light).unwrap();
    }
    b.camera(Camera {
        position: Vec3::new(0.0, 1.0, 0.001),
        look_at: Vec3::ZERO,
        up: Vec3::Z,
        vfov_degrees: 1.0,
    })
    .unwrap();
    let scene = Arc::new(b.build());
    let settings = RenderSettings {
        width: 1,
        height: 1,
        mode: Mode::Whitted,
        ..Default::default()
    };
    render_with(raybench_tests::ORACLE, &scene, &settings, 1).color[0]
}

/// Whitted: a diffuse plane lit by one point light straight above, no ambient occlusion:
/// radiance `albedo * I / d^2 + ambient`.
#[test]
fn whitted_point_light_falls_off_with_distance_squared() {
    let c = whitted_plane_pixel(Some(raybench_core::Light::Point {
        position: Vec3::new(0.0, 2.0, 0.0),
        intensity: Vec3::splat(8.0),
    }));
    // 0.5 * 8 / 2^2 + 0.05 * 0.5 (ambient).
    let expect = 0.5 * 8.0 / 4.0 + 0.05 * 0.5;
    assert!((c.x - expect).abs() < 1e-3, "{c}");
}

/// Whitted in a scene without point or directional lights: the headlight, radiance 1 along
/// the view direction, lights a diffuse plane seen head on with `albedo * 1 + ambient`
/// (without it the plane would show its ambient term alone).
#[test]
fn whitted_lights_a_scene_without_lights_by_a_headlight() {
    let c = whitted_plane_pixel(None);
    // Nearly head on (the eye is 0.001 off the axis): cos within 1e-6 of 1.
    let expect = 0.5 + 0.05 * 0.5;
    assert!((c.x - expect).abs() < 1e-3, "{c}");
}
