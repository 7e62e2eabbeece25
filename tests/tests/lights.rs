//! Every emitter is a light: next-event estimation with multiple importance sampling
//! (`--light-sampling mis`) against BSDF sampling alone (`bsdf`), on scenes with known
//! answers. Each comparison renders several seeds; the image means of the seeds are
//! independent, so their spread gives the standard error of the mean that the tolerances
//! are stated in.

use raybench_core::{
    Camera, Environment, LightSampling, Material, Mode, RenderSettings, Scene, SceneBuilder,
    TriangleMesh, Vec3,
};
use raybench_tests::{BASELINE, load_or_skip, render_with};
use std::sync::Arc;

/// Per-seed frames of `scene` in path mode.
fn frames(
    scene: &Arc<Scene>,
    size: u32,
    spp: u32,
    depth: u32,
    light_sampling: LightSampling,
    seeds: u32,
) -> Vec<Vec<Vec3>> {
    (0..seeds)
        .map(|seed| {
            let settings = RenderSettings {
                width: size,
                height: size,
                spp,
                mode: Mode::Path,
                max_depth: depth,
                seed: 1000 + seed,
                light_sampling,
                ..RenderSettings::default()
            };
            render_with(BASELINE, scene, &settings, 2).color
        })
        .collect()
}

/// Luminance-like scalar of a pixel (the channels' mean).
fn value(c: Vec3) -> f64 {
    f64::from(c.x + c.y + c.z) / 3.0
}

/// The mean of the image over all seeds, and its standard error from the seeds' spread.
fn mean_and_error(frames: &[Vec<Vec3>]) -> (f64, f64) {
    let means: Vec<f64> = frames
        .iter()
        .map(|f| f.iter().map(|&c| value(c)).sum::<f64>() / f.len() as f64)
        .collect();
    let k = means.len() as f64;
    let mean = means.iter().sum::<f64>() / k;
    let var = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (k - 1.0);
    (mean, (var / k).sqrt())
}

/// The per-pixel variance across seeds, averaged over the pixels.
fn pixel_variance(frames: &[Vec<Vec3>]) -> f64 {
    let k = frames.len() as f64;
    let n = frames[0].len();
    (0..n)
        .map(|i| {
            let m = frames.iter().map(|f| value(f[i])).sum::<f64>() / k;
            frames
                .iter()
                .map(|f| (value(f[i]) - m).powi(2))
                .sum::<f64>()
                / (k - 1.0)
        })
        .sum::<f64>()
        / n as f64
}

/// Asserts the two estimators agree within `sigmas` combined standard errors and returns
/// the ratio of their per-pixel variances (BSDF-only over MIS).
fn compare(scene: &Arc<Scene>, size: u32, spp: u32, depth: u32, seeds: u32, sigmas: f64) -> f64 {
    let mis = frames(scene, size, spp, depth, LightSampling::Mis, seeds);
    let bsdf = frames(scene, size, spp, depth, LightSampling::Bsdf, seeds);
    let (m1, e1) = mean_and_error(&mis);
    let (m2, e2) = mean_and_error(&bsdf);
    let tolerance = sigmas * (e1 * e1 + e2 * e2).sqrt();
    assert!(
        (m1 - m2).abs() <= tolerance,
        "{}: MIS mean {m1} +- {e1}, BSDF-only mean {m2} +- {e2}: apart by more than {sigmas} \
         standard errors",
        scene.name
    );
    let ratio = pixel_variance(&bsdf) / pixel_variance(&mis);
    eprintln!(
        "{}: MIS {m1:.5} +- {e1:.5}, BSDF {m2:.5} +- {e2:.5}, variance ratio {ratio:.1}",
        scene.name
    );
    ratio
}

fn diffuse(albedo: f32, emission: Vec3) -> Material {
    Material {
        name: "m".into(),
        base_color: Vec3::splat(albedo),
        emission,
        ..Material::default()
    }
}

/// A square floor at y = 0 (normal up) of half-size `h`.
fn floor(h: f32) -> TriangleMesh {
    TriangleMesh {
        positions: vec![
            Vec3::new(-h, 0.0, -h),
            Vec3::new(h, 0.0, -h),
            Vec3::new(h, 0.0, h),
            Vec3::new(-h, 0.0, h),
        ],
        indices: vec![[0, 2, 1], [0, 3, 2]],
    }
}

fn looking_down() -> Camera {
    Camera {
        position: Vec3::new(0.0, 3.0, 3.0),
        look_at: Vec3::new(0.0, 0.0, 0.0),
        up: Vec3::Y,
        vfov_degrees: 40.0,
    }
}

/// Straight down from 3 above the floor, seeing `|x|, |z| < 1.1` of it: lights at
/// `x = 1.5`, `y = 1` are out of view, so that the pixels' variance is the light's.
fn overhead() -> Camera {
    Camera {
        position: Vec3::new(0.0, 3.0, 0.0),
        look_at: Vec3::ZERO,
        up: Vec3::NEG_Z,
        vfov_degrees: 40.0,
    }
}

/// A floor lit by a small bright emissive object (a sphere, or through the scene format
/// any other kind) and nothing else.
fn lit_floor(name: &str, add_light: impl FnOnce(&mut SceneBuilder, u32)) -> Arc<Scene> {
    let mut b = SceneBuilder::new(name);
    b.background(Vec3::ZERO).unwrap();
    let grey = b.add_material(diffuse(0.6, Vec3::ZERO)).unwrap();
    let lamp = b.add_material(diffuse(0.0, Vec3::splat(200.0))).unwrap();
    b.add_mesh("floor", &floor(3.0), grey).unwrap();
    add_light(&mut b, lamp);
    b.camera(overhead()).unwrap();
    Arc::new(b.build())
}

/// Radiance `200` of the lamps, albedo `0.6` of the floor (as [`lit_floor`]).
const LAMP: f64 = 200.0;
const FLOOR_ALBEDO: f64 = 0.6;

/// The expected image mean of [`lit_floor`] lit by a sphere (`center`, `radius`) entirely
/// above the floor: a floor point at distance `d` from the centre receives
/// `E = pi L (r / d)^2 cos` with `cos = center.y / d`, so it shows `rho L r^2 center.y / d^3`;
/// averaged over the pixels' centre rays (the jitter's average differs by under 1e-3
/// relative: the pixels are small against `d`).
fn sphere_lit_mean(scene: &Scene, size: u32, center: Vec3, radius: f64) -> f64 {
    let rays = scene.camera.rays(size, size);
    let mut sum = 0.0;
    for y in 0..size {
        for x in 0..size {
            let ray = rays.center_ray(x, y);
            let p = ray.at(-ray.origin.y / ray.dir.y);
            let d = f64::from((center - p).length());
            sum += FLOOR_ALBEDO * LAMP * radius * radius * f64::from(center.y) / d.powi(3);
        }
    }
    sum / f64::from(size * size)
}

/// Asserts that `light_sampling`'s image mean of `scene` is `expect` within `sigmas`
/// standard errors and `relative`; returns the frames.
fn check_mean(
    scene: &Arc<Scene>,
    size: u32,
    spp: u32,
    light_sampling: LightSampling,
    expect: f64,
    relative: f64,
) -> Vec<Vec<Vec3>> {
    let f = frames(scene, size, spp, 2, light_sampling, 8);
    let (mean, err) = mean_and_error(&f);
    eprintln!(
        "{} {light_sampling:?}: {mean:.5} +- {err:.5}, expected {expect:.5}",
        scene.name
    );
    assert!(
        (mean - expect).abs() <= 4.0 * err + relative * expect,
        "{} {light_sampling:?}: mean {mean} +- {err}, expected {expect}",
        scene.name
    );
    f
}

/// (1) A small bright emissive sphere over a diffuse floor (out of the camera's view):
/// both estimators give the analytic image mean, MIS to 1 %, and BSDF sampling, which
/// rarely finds the light (it subtends about 0.01 sr), is many times noisier.
#[test]
fn small_sphere_mis_beats_bsdf_sampling() {
    let (center, radius) = (Vec3::new(1.5, 1.0, 0.2), 0.06);
    let scene = lit_floor("small sphere", |b, lamp| {
        b.add_sphere(raybench_core::Sphere::new(center, radius), lamp)
            .unwrap();
    });
    assert_eq!(scene.emitters.ids.len(), 1);
    let expect = sphere_lit_mean(&scene, 24, center, f64::from(radius));
    let mis = check_mean(&scene, 24, 8, LightSampling::Mis, expect, 0.01);
    let bsdf = check_mean(&scene, 24, 8, LightSampling::Bsdf, expect, 0.0);
    let ratio = pixel_variance(&bsdf) / pixel_variance(&mis);
    assert!(ratio > 10.0, "variance ratio {ratio}");
    assert!(mean_and_error(&mis).1 < 0.003 * expect);
}

/// The general method (a uniform direction in the cone of the bounding sphere, the light
/// point found by the primitive's own intersection): a spherical ellipsoid (a one-solid CSG
/// primitive) and an SDF sphere light the floor like the analytic sphere, with MIS to 1 %
/// and with BSDF sampling; a true ellipsoid gives MIS and BSDF-only the same mean.
#[test]
fn other_emitter_kinds_are_sampled_too() {
    let center = Vec3::new(1.5, 1.0, 0.2);
    for (kind, object, sphere) in [
        (
            "csg sphere",
            "kind = \"ellipsoid\"\ncenter = [1.5, 1.0, 0.2]\nradii = [0.2, 0.2, 0.2]",
            true,
        ),
        (
            "sdf sphere",
            "kind = \"sdf\"\ntree = { type = \"sphere\", center = [1.5, 1.0, 0.2], radius = 0.2 }",
            true,
        ),
        (
            "ellipsoid",
            "kind = \"ellipsoid\"\ncenter = [1.5, 1.0, 0.2]\nradii = [0.3, 0.12, 0.2]",
            false,
        ),
    ] {
        let text = format!(
            "background = [0, 0, 0]\n\
             [camera]\nposition = [0, 3, 0]\nlook_at = [0, 0, 0]\nup = [0, 0, -1]\nfov = 40\n\
             [[material]]\nname = \"grey\"\ncolor = [0.6, 0.6, 0.6]\n\
             [[material]]\nname = \"lamp\"\ncolor = [0, 0, 0]\nemission = [200, 200, 200]\n\
             [[object]]\nkind = \"polygons\"\nmaterial = \"grey\"\n\
             positions = [[-3, 0, -3], [3, 0, -3], [3, 0, 3], [-3, 0, 3]]\n\
             faces = [[0, 3, 2, 1]]\n\
             [[object]]\nmaterial = \"lamp\"\n{object}\n"
        );
        let scene = Arc::new(
            raybench_scene::load_scene_str(&text, kind, None, std::path::Path::new("."))
                .unwrap_or_else(|e| panic!("{kind}: {e}")),
        );
        assert_eq!(scene.emitters.ids.len(), 1, "{kind}");
        if sphere {
            let expect = sphere_lit_mean(&scene, 16, center, 0.2);
            let mis = check_mean(&scene, 16, 64, LightSampling::Mis, expect, 0.01);
            let bsdf = check_mean(&scene, 16, 64, LightSampling::Bsdf, expect, 0.0);
            let ratio = pixel_variance(&bsdf) / pixel_variance(&mis);
            assert!(ratio > 4.0, "{kind}: variance ratio {ratio}");
        } else {
            let ratio = compare(&scene, 16, 16, 2, 8, 4.0);
            assert!(ratio > 4.0, "{kind}: variance ratio {ratio}");
        }
    }
}

/// (2) Unbiasedness on the built-in Cornell box: MIS and BSDF-only image means agree
/// within 4 combined standard errors (of eight seeds each).
#[test]
fn cornell_box_mis_and_bsdf_agree() {
    let Some(scene) = load_or_skip("cornell-box") else {
        return;
    };
    let ratio = compare(&scene, 32, 32, 5, 8, 4.0);
    assert!(ratio > 1.5, "variance ratio {ratio}");
}

/// (3) White furnace: inside a closed box whose every face has albedo `rho` and emission
/// `Le`, radiance is `Le (1 + rho + ... + rho^64)` = `Le / (1 - rho)` to 1e-19 everywhere.
/// At 64 bounces (with Russian roulette) the rendered mean matches it to 1 %, in both
/// estimators, and the standard error is small enough for that bound to bite.
#[test]
fn white_furnace_closed_box() {
    let (rho, le) = (0.5f32, 0.4f32);
    let c = [
        Vec3::new(-1.0, -1.0, -1.0),
        Vec3::new(1.0, -1.0, -1.0),
        Vec3::new(1.0, 1.0, -1.0),
        Vec3::new(-1.0, 1.0, -1.0),
        Vec3::new(-1.0, -1.0, 1.0),
        Vec3::new(1.0, -1.0, 1.0),
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(-1.0, 1.0, 1.0),
    ];
    // Counter-clockwise seen from inside: every normal points into the box.
    let quads = [
        [0, 1, 2, 3],
        [5, 4, 7, 6],
        [4, 0, 3, 7],
        [1, 5, 6, 2],
        [4, 5, 1, 0],
        [3, 2, 6, 7],
    ];
    let box_mesh = TriangleMesh {
        positions: c.to_vec(),
        indices: quads
            .iter()
            .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
            .collect(),
    };
    let mut b = SceneBuilder::new("furnace box");
    let m = b.add_material(diffuse(rho, Vec3::splat(le))).unwrap();
    b.add_mesh("box", &box_mesh, m).unwrap();
    b.camera(Camera {
        position: Vec3::new(0.1, -0.2, 0.3),
        look_at: Vec3::new(0.5, 0.3, -1.0),
        up: Vec3::Y,
        vfov_degrees: 90.0,
    })
    .unwrap();
    let scene = Arc::new(b.build());
    assert_eq!(scene.emitters.ids.len(), 12);
    let expect = f64::from(le) / (1.0 - f64::from(rho));
    for light_sampling in LightSampling::ALL {
        let f = frames(&scene, 16, 64, 64, light_sampling, 4);
        let (mean, err) = mean_and_error(&f);
        eprintln!("{light_sampling:?}: {mean} +- {err}, expected {expect}");
        assert!(
            err < 0.003 * expect,
            "standard error {err} too large for a 1 % bound"
        );
        assert!(
            (mean - expect).abs() < 0.01 * expect,
            "{light_sampling:?}: mean {mean} +- {err}, expected {expect}"
        );
    }
}

/// An environment map of `width x height` texels from `f(x, y)`.
fn map(width: u32, height: u32, f: impl Fn(u32, u32) -> f32) -> Arc<Environment> {
    let f = &f;
    let texels = (0..height)
        .flat_map(|y| (0..width).map(move |x| Vec3::splat(f(x, y))))
        .collect();
    Arc::new(Environment::new(width, height, texels, 1.0, 30.0).unwrap())
}

/// A diffuse floor and a diffuse sphere under `sky` (a constant background, or a map).
fn under_sky(name: &str, sky: Result<Vec3, Arc<Environment>>) -> Arc<Scene> {
    let mut b = SceneBuilder::new(name);
    match sky {
        Ok(c) => {
            b.background(c).unwrap();
        }
        Err(env) => {
            b.environment(env);
        }
    }
    let grey = b.add_material(diffuse(0.6, Vec3::ZERO)).unwrap();
    b.add_mesh("floor", &floor(3.0), grey).unwrap();
    b.add_sphere(
        raybench_core::Sphere::new(Vec3::new(0.0, 0.5, 0.0), 0.5),
        grey,
    )
    .unwrap();
    b.camera(looking_down()).unwrap();
    Arc::new(b.build())
}

/// (4a) A constant environment map lights the scene like the constant background of the
/// same radiance (the background is BSDF-sampled only, the map by MIS): same mean.
#[test]
fn constant_map_is_the_constant_background() {
    let flat = under_sky("background", Ok(Vec3::splat(0.7)));
    let mapped = under_sky("map", Err(map(16, 8, |_, _| 0.7)));
    assert!(flat.emitters.is_empty() && !mapped.emitters.is_empty());
    let a = frames(&flat, 16, 8, 4, LightSampling::Mis, 6);
    let b = frames(&mapped, 16, 8, 4, LightSampling::Mis, 6);
    let (m1, e1) = mean_and_error(&a);
    let (m2, e2) = mean_and_error(&b);
    assert!(
        (m1 - m2).abs() <= 4.0 * (e1 * e1 + e2 * e2).sqrt(),
        "background {m1} +- {e1}, map {m2} +- {e2}"
    );
}

/// (4b) A map dark but for one bright patch above the horizon lights a diffuse plane with
/// irradiance `E = sum over texels of L (phi1 - phi0) (sin^2 theta1 - sin^2 theta0) / 2`,
/// so every pixel of the plane is `rho E / pi`; MIS finds the patch far more often than
/// BSDF sampling.
#[test]
fn bright_patch_of_a_map_lights_a_plane() {
    let (w, h) = (64u32, 32u32);
    let bright = |x: u32, y: u32| (10..14).contains(&x) && (5..8).contains(&y);
    let (sun, sky) = (40.0f32, 0.05f32);
    let env = map(w, h, |x, y| if bright(x, y) { sun } else { sky });
    let rho = 0.6f64;
    let mut e = 0.0f64;
    for y in 0..h / 2 {
        let (t0, t1) = (
            f64::from(y) / f64::from(h) * std::f64::consts::PI,
            f64::from(y + 1) / f64::from(h) * std::f64::consts::PI,
        );
        for x in 0..w {
            let l = f64::from(if bright(x, y) { sun } else { sky });
            e += l * std::f64::consts::TAU / f64::from(w) * (t1.sin().powi(2) - t0.sin().powi(2))
                / 2.0;
        }
    }
    let expect = rho * e / std::f64::consts::PI;
    let mut b = SceneBuilder::new("patch");
    b.environment(env);
    let grey = b.add_material(diffuse(rho as f32, Vec3::ZERO)).unwrap();
    b.add_plane(Vec3::ZERO, Vec3::Y, grey).unwrap();
    b.camera(Camera {
        position: Vec3::new(0.0, 1.0, 0.0),
        look_at: Vec3::new(0.0, 0.0, -0.2),
        up: Vec3::Y,
        vfov_degrees: 30.0,
    })
    .unwrap();
    let scene = Arc::new(b.build());
    let mis = frames(&scene, 12, 8, 1, LightSampling::Mis, 6);
    let (mean, err) = mean_and_error(&mis);
    eprintln!("patch: {mean} +- {err}, expected {expect}");
    assert!(
        (mean - expect).abs() <= 4.0 * err + 1e-4 * expect,
        "mean {mean} +- {err}, expected {expect}"
    );
    let ratio = compare(&scene, 12, 64, 1, 6, 4.0);
    assert!(ratio > 5.0, "variance ratio {ratio}");
}
