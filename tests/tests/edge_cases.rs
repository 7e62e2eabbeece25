//! Degenerate and extreme scenes, every backend against naive: an empty scene, a single
//! primitive, all primitives with the same centroid, huge and tiny coordinates, zero-extent
//! boxes, rays starting inside boxes, axis-aligned rays and rays along box faces.

use raybench_core::{Ray, Scene, SceneBuilder, Sphere, TriangleMesh, Vec3};
use raybench_tests::{assert_same_ray_hits, available, prepared, triangles};
use std::sync::Arc;

const BACKENDS: &[&str] = raybench_tests::ACCELERATED_BACKENDS;

/// Rays that probe a scene of the given bounds from everywhere: incoherent rays from inside
/// the box, axis-aligned rays through a lattice (some exactly on box faces), and rays from
/// outside towards the centre.
fn probe_rays(scene: &Scene) -> Vec<Ray> {
    let b = scene.geometry.bounds();
    let (min, max) = if b.is_empty() {
        (Vec3::splat(-1.0), Vec3::splat(1.0))
    } else {
        (b.min, b.max)
    };
    let mut rays = raybench_core::ray_sets::incoherent(raybench_core::Aabb::new(min, max), 2000, 3);
    for i in 0..=4 {
        for j in 0..=4 {
            let f = |k: usize, a: usize| min[a] + (max[a] - min[a]) * k as f32 / 4.0;
            for axis in 0..3 {
                let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
                let mut o = Vec3::ZERO;
                o[a1] = f(i, a1);
                o[a2] = f(j, a2);
                o[axis] = min[axis] - (max[axis] - min[axis]) - 1.0;
                let mut d = Vec3::ZERO;
                d[axis] = 1.0;
                rays.push(Ray::new(o, d));
                let mut o2 = o;
                o2[axis] = max[axis] + (max[axis] - min[axis]) + 1.0;
                rays.push(Ray::new(o2, -d));
            }
        }
    }
    let c = (min + max) * 0.5;
    for k in 0..200 {
        let a = k as f32 * 0.7;
        let eye =
            c + Vec3::new(a.cos(), (a * 0.3).sin(), a.sin()) * ((max - min).length() + 1.0) * 2.0;
        rays.push(Ray::new(eye, c - eye));
    }
    rays
}

fn check_scene(what: &str, scene: Scene) {
    let scene = Arc::new(scene);
    let rays = probe_rays(&scene);
    let (reference, _) = prepared(raybench_tests::ORACLE, &scene)
        .trace_rays(&rays, false)
        .unwrap();
    for name in available(BACKENDS) {
        let (hits, _) = prepared(name, &scene).trace_rays(&rays, false).unwrap();
        assert_same_ray_hits(&format!("{name}: {what}"), &reference, &hits);
        let bvh = raybench_bvh::Bvh::build_with(
            Arc::clone(&scene.geometry),
            raybench_bvh::BvhParams::default(),
        );
        bvh.validate().unwrap_or_else(|e| panic!("{what}: {e}"));
    }
}

#[test]
fn empty_scene() {
    check_scene("empty", SceneBuilder::new("empty").build());
}

#[test]
fn single_primitive() {
    let mut b = SceneBuilder::new("one");
    b.add_sphere(Sphere::new(Vec3::new(0.0, 0.0, 0.0), 1.0), 0)
        .unwrap();
    check_scene("one sphere", b.build());
    let mut b = SceneBuilder::new("one");
    b.add_mesh("t", &triangles(&[[Vec3::ZERO, Vec3::X, Vec3::Y]]), 0)
        .unwrap();
    check_scene("one triangle", b.build());
}

#[test]
fn planes_only_and_mixed() {
    let mut b = SceneBuilder::new("planes");
    b.add_plane(Vec3::ZERO, Vec3::Y, 0).unwrap();
    b.add_plane(Vec3::new(0.0, 0.0, -3.0), Vec3::Z, 0).unwrap();
    check_scene("planes only", b.build());
    let mut b = SceneBuilder::new("mixed");
    b.add_plane(Vec3::ZERO, Vec3::Y, 0).unwrap();
    b.add_sphere(Sphere::new(Vec3::new(0.0, 0.5, 0.0), 0.5), 0)
        .unwrap();
    b.add_plane(Vec3::new(0.0, 0.5, 0.0), Vec3::Y, 0).unwrap();
    check_scene("planes through a sphere", b.build());
}

#[test]
fn same_centroid() {
    // 300 triangles of different sizes and orientations, all centred at the origin, plus
    // coincident duplicates (equal t: the tie rule must pick the smaller id everywhere).
    let mut tris = Vec::new();
    for i in 0..300 {
        let a = i as f32 * 0.37;
        let s = 0.1 + (i % 7) as f32 * 0.2;
        let v0 = Vec3::new(a.cos(), a.sin(), 0.3 * (a * 2.0).sin()) * s;
        let v1 = Vec3::new((a + 2.1).cos(), (a + 2.1).sin(), 0.1) * s;
        let v2 = -(v0 + v1);
        tris.push([v0, v1, v2]);
        if i % 10 == 0 {
            tris.push([v0, v1, v2]);
        }
    }
    let mut b = SceneBuilder::new("centroid");
    b.add_mesh("c", &triangles(&tris), 0).unwrap();
    check_scene("same centroid", b.build());
}

#[test]
fn huge_and_tiny_coordinates() {
    for scale in [1.0e-6f32, 1.0e-3, 1.0e6, 1.0e15] {
        let m = raybench_scene::generators::soup(500, 9);
        let scaled = TriangleMesh {
            positions: m
                .positions
                .iter()
                .map(|&p| p * scale + Vec3::splat(scale * 3.0))
                .collect(),
            indices: m.indices.clone(),
        };
        let mut b = SceneBuilder::new("scaled");
        b.add_mesh("s", &scaled, 0).unwrap();
        for s in raybench_scene::generators::random_spheres(100, 2) {
            b.add_sphere(Sphere::new(s.center * scale, s.radius * scale), 0)
                .unwrap();
        }
        check_scene(&format!("scale {scale:e}"), b.build());
    }
}

#[test]
fn zero_extent_boxes() {
    // Axis-aligned triangles (flat boxes), degenerate triangles (lines and points) and a
    // grid of triangles lying exactly on box faces.
    let mut tris = Vec::new();
    for i in 0..20 {
        let x = i as f32 * 0.25;
        tris.push([
            Vec3::new(x, 0.0, 0.0),
            Vec3::new(x, 1.0, 0.0),
            Vec3::new(x, 0.0, 1.0),
        ]);
        tris.push([
            Vec3::new(0.0, x, 0.0),
            Vec3::new(1.0, x, 0.0),
            Vec3::new(0.0, x, 1.0),
        ]);
        tris.push([
            Vec3::new(x, x, 0.0),
            Vec3::new(x, x, 0.0),
            Vec3::new(x, x, 0.0),
        ]);
        tris.push([
            Vec3::new(0.0, 0.0, x),
            Vec3::new(1.0, 1.0, x),
            Vec3::new(2.0, 2.0, x),
        ]);
    }
    let mut b = SceneBuilder::new("flat");
    b.add_mesh("f", &triangles(&tris), 0).unwrap();
    check_scene("zero-extent boxes", b.build());
}

#[test]
fn rays_start_inside_boxes_and_on_surfaces() {
    let Some(scene) = raybench_tests::load_or_skip("icosphere:3") else {
        return;
    };
    // Origins on vertices and at triangle centres, directions outward and inward.
    let mut rays = Vec::new();
    for s in scene.geometry.shapes().iter().take(400) {
        if let raybench_core::Shape::Triangle(t) = s {
            let c = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
            rays.push(Ray::new(c, c));
            rays.push(Ray::new(c, -c));
            rays.push(Ray::new(t.v[0], Vec3::new(0.3, -0.2, 0.9)));
        }
    }
    let (reference, _) = prepared(raybench_tests::ORACLE, &scene)
        .trace_rays(&rays, false)
        .unwrap();
    for name in available(BACKENDS) {
        let (hits, _) = prepared(name, &scene).trace_rays(&rays, false).unwrap();
        assert_same_ray_hits(name, &reference, &hits);
    }
}
