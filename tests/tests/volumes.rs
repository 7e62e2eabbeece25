//! Direct volume rendering with known answers: the maximum-intensity projection of one
//! bright ellipsoid, Beer-Lambert through a homogeneous block cut by a surface, and the
//! volume modes giving bit-identical frames with every backend and thread count (the
//! integration is the core's; backends only trace the surfaces that cut it).

use raybench_core::{
    Affine3A, Camera, Material, Mode, Ray, RenderSettings, Scene, SceneBuilder, Sphere,
    TransferFunction, TransferPoint, Vec3, Volume, VolumeData, VolumeParams, VolumeSample,
};
use raybench_scene::phantom::{Ellipsoid, rasterize};
use raybench_tests::{available, render_with};
use std::sync::Arc;

const BACKENDS: &[&str] = raybench_tests::ACCELERATED_BACKENDS;

#[test]
fn mip_of_one_ellipsoid_is_its_value_inside_its_outline_and_zero_outside() {
    let (a, b) = (0.6, 0.35);
    let e = Ellipsoid {
        value: 0.7,
        axes: [a, b, 0.5],
        center: [0.1, -0.2, 0.0],
        angles: [0.0; 3],
    };
    let n = 96;
    for sampling in [
        raybench_core::Sampling::Nearest,
        raybench_core::Sampling::Trilinear,
    ] {
        for skip_empty in [false, true] {
            let v = Volume::new(
                [n; 3],
                Vec3::splat(2.0 / n as f32),
                VolumeData::F32(rasterize(&[e], n)),
                Affine3A::IDENTITY,
                TransferFunction::ramp(1.0),
                VolumeParams {
                    sampling,
                    skip_empty,
                    ..VolumeParams::default()
                },
            )
            .unwrap();
            // Parallel rays along -z over a lattice; the projected outline is the ellipse
            // ((x - 0.1) / a)^2 + ((y + 0.2) / b)^2 = 1. A band of two voxels around it is
            // left out (voxelisation, and trilinear blending, blur the border).
            let voxel = 2.0 / n as f32;
            let (mut inside, mut outside) = (0, 0);
            for i in 0..120 {
                for j in 0..120 {
                    let x = -1.0 + 2.0 * (i as f32 + 0.37) / 120.0;
                    let y = -1.0 + 2.0 * (j as f32 + 0.61) / 120.0;
                    let r = Ray::new(Vec3::new(x, y, 3.0), -Vec3::Z);
                    let mut acc = VolumeSample::default();
                    v.integrate(&r, f32::INFINITY, false, &mut acc);
                    let (dx, dy) = (x - 0.1, y + 0.2);
                    let q = ((dx / a).powi(2) + (dy / b).powi(2)).sqrt();
                    let margin = 2.0 * voxel / a.min(b);
                    if q < 1.0 - margin {
                        assert_eq!(acc.max, 0.7, "({x}, {y}) inside");
                        inside += 1;
                    } else if q > 1.0 + margin {
                        assert_eq!(acc.max, 0.0, "({x}, {y}) outside");
                        outside += 1;
                    }
                }
            }
            assert!(inside > 1000 && outside > 1000, "{inside} {outside}");
        }
    }
}

/// A homogeneous block of extinction `SIGMA` in `[-1, 1]^3` with white emission, black
/// background, and an emissive black plane at `z = PLANE_Z` inside it.
const SIGMA: f32 = 1.3;
const PLANE_Z: f32 = -0.25;
const PLANE_EMISSION: f32 = 0.5;

fn block_scene() -> Scene {
    let mut b = SceneBuilder::new("block");
    b.background(Vec3::ZERO).unwrap();
    b.camera(Camera {
        position: Vec3::new(0.2, 0.1, 4.0),
        look_at: Vec3::ZERO,
        up: Vec3::Y,
        vfov_degrees: 30.0,
    })
    .unwrap();
    let black = b
        .add_material(Material {
            name: "black".into(),
            base_color: Vec3::ZERO,
            emission: Vec3::splat(PLANE_EMISSION),
            ..Material::default()
        })
        .unwrap();
    b.add_plane(Vec3::new(0.0, 0.0, PLANE_Z), Vec3::Z, black)
        .unwrap();
    // A small sphere in front of part of the block: its pixels see less of the volume.
    b.add_sphere(Sphere::new(Vec3::new(0.5, 0.5, 0.6), 0.2), black)
        .unwrap();
    let tf = TransferFunction::new(vec![TransferPoint {
        value: 0.0,
        color: Vec3::ONE,
        sigma: SIGMA,
    }])
    .unwrap();
    let v = Volume::new(
        [16, 16, 16],
        Vec3::splat(0.125),
        VolumeData::U16(vec![1000; 16 * 16 * 16]),
        Affine3A::IDENTITY,
        tf,
        VolumeParams::default(),
    )
    .unwrap();
    b.add_volume(Arc::new(v)).unwrap();
    b.build()
}

#[test]
fn composite_of_a_homogeneous_block_follows_beer_lambert_up_to_the_surface() {
    let scene = Arc::new(block_scene());
    let settings = RenderSettings {
        width: 40,
        height: 40,
        mode: Mode::Composite,
        ..RenderSettings::default()
    };
    let frame = render_with(raybench_tests::BASELINE, &scene, &settings, 2);
    let cam = scene.camera.rays(40, 40);
    let mut checked = 0;
    for y in 0..40 {
        for x in 0..40 {
            let i = (y * 40 + x) as usize;
            let ray = cam.center_ray(x, y);
            // Entry into the block: the z = 1 face (the camera is in front of it).
            let t_in = (1.0 - ray.origin.z) / ray.dir.z;
            let p = ray.at(t_in);
            if p.x.abs() > 0.98 || p.y.abs() > 0.98 {
                continue;
            }
            // Leaving at the surface, or through a side of the block first.
            let t_exit = (0..3)
                .filter(|&a| ray.dir[a] != 0.0)
                .map(|a| (ray.dir[a].signum() - ray.origin[a]) / ray.dir[a])
                .fold(f32::INFINITY, f32::min);
            let t_out = frame.t[i].min(t_exit);
            let length = (t_out - t_in) * ray.dir.length();
            let transmittance = (-SIGMA * length).exp();
            // Whatever the ray meets after the volume (plane or sphere) emits the same.
            let surface = if frame.t[i].is_finite() {
                PLANE_EMISSION
            } else {
                0.0
            };
            let expected = (1.0 - transmittance) + transmittance * surface;
            let got = frame.color[i].x;
            assert!(
                (got - expected).abs() < 1e-3,
                "pixel ({x}, {y}): {got} vs {expected} (length {length})"
            );
            checked += 1;
        }
    }
    assert!(checked > 400, "{checked}");
}

#[test]
fn volume_modes_are_identical_with_every_backend_and_thread_count() {
    let block = Arc::new(block_scene());
    let phantom = raybench_tests::load_or_skip("phantom").unwrap();
    for scene in [&block, &phantom] {
        for mode in [Mode::Mip, Mode::Composite] {
            for spp in [1, 2] {
                let settings = RenderSettings {
                    width: 32,
                    height: 32,
                    spp,
                    mode,
                    ..RenderSettings::default()
                };
                let reference = render_with(raybench_tests::ORACLE, scene, &settings, 1);
                for name in available(BACKENDS) {
                    for threads in [2, 3] {
                        let f = render_with(name, scene, &settings, threads);
                        let what = format!("{name} {} {} spp {spp}", scene.name, mode.name());
                        raybench_tests::assert_same_hits(&what, &reference, &f);
                        assert!(
                            reference
                                .color
                                .iter()
                                .zip(&f.color)
                                .all(|(a, b)| a.to_array().map(f32::to_bits)
                                    == b.to_array().map(f32::to_bits)),
                            "{what}: colours differ"
                        );
                    }
                }
            }
        }
    }
}
