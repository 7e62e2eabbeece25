//! Watertightness on every backend: rays from inside closed meshes, aimed exactly at
//! vertices, edge midpoints and other points on shared edges, must all hit (none escapes
//! through a crack between two triangles), and every backend must return the same hits.
//!
//! The meshes: an icosphere (`icosphere:4`, 5k triangles), a cube whose faces are split
//! into 12 x 12 quads (1,728 triangles, edges along the axes where ray and box arithmetic
//! is exact), and `icosphere:8` (1.3M triangles: long thin edges of 3e-3, rounding at
//! every vertex). The rays run in octant-sorted order, so that the packet backends trace
//! them as full packets. The ray starts inside a convex mesh, so its one hit lies at the
//! target, at `t = 1` (the direction is `target - origin`) up to rounding.

use raybench_core::{Ray, Scene, SceneBuilder, Shape, TriangleMesh, Vec3};
use raybench_tests::{assert_same_ray_hits, available, cube_mesh, packed, prepared};
use std::sync::Arc;

/// Every exact CPU backend.
const BACKENDS: &[&str] = raybench_tests::EXACT_BACKENDS;

/// Largest `|t - 1|` of a hit at the aimed-at point: rounding of the direction and of the
/// triangle test, far below the distance to any other part of the mesh.
const T_TOLERANCE: f32 = 1e-4;

fn scene(mesh: &TriangleMesh) -> Arc<Scene> {
    let mut b = SceneBuilder::new("closed");
    b.add_mesh("closed", mesh, 0).unwrap();
    Arc::new(b.build())
}

/// Targets on every `stride`-th triangle: its vertices, edge midpoints and the points at
/// 1/7 and 5/7 of each edge (on the shared edge, not at a vertex).
fn targets(scene: &Scene, stride: usize) -> Vec<Vec3> {
    let mut out = Vec::new();
    for s in scene.geometry.shapes().iter().step_by(stride) {
        if let Shape::Triangle(t) = s {
            for k in 0..3 {
                let (p, q) = (t.v[k], t.v[(k + 1) % 3]);
                out.extend([
                    p,
                    (p + q) * 0.5,
                    p + (q - p) / 7.0,
                    p + (q - p) * (5.0 / 7.0),
                ]);
            }
        }
    }
    out
}

/// Rays from several inside points (the centre and off-centre points, some on the axes'
/// planes) to every target, sorted into packets.
fn inside_rays(targets: &[Vec3], scale: f32) -> Vec<Ray> {
    let origins = [
        Vec3::ZERO,
        Vec3::new(0.3, -0.2, 0.1),
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::new(-0.45, 0.0, 0.25),
    ];
    let mut rays = Vec::new();
    for (i, &p) in targets.iter().enumerate() {
        let o = origins[i % origins.len()] * scale;
        rays.push(Ray::new(o, p - o));
    }
    packed(&rays)
}

/// Traces `rays` with `backends`, the first being the reference: every ray hits near
/// `t = 1` and all backends agree bit for bit.
fn check(what: &str, scene: &Arc<Scene>, rays: &[Ray], backends: &[&str]) {
    let (reference, _) = prepared(backends[0], scene)
        .trace_rays(rays, false)
        .unwrap();
    for (i, (r, h)) in rays.iter().zip(&reference).enumerate() {
        let h = h.unwrap_or_else(|| panic!("{what}: ray {i} {r:?} escaped ({})", backends[0]));
        assert!(
            (h.t - 1.0).abs() <= T_TOLERANCE,
            "{what}: ray {i} hit at t = {} (expected 1)",
            h.t
        );
    }
    for &name in &backends[1..] {
        let (hits, _) = prepared(name, scene).trace_rays(rays, false).unwrap();
        assert_same_ray_hits(&format!("{name}: {what}"), &reference, &hits);
    }
}

#[test]
fn icosphere_from_inside() {
    let s = scene(&raybench_scene::generators::icosphere(4));
    let rays = inside_rays(&targets(&s, 1), 1.0);
    assert!(rays.len() > 50_000);
    check("icosphere:4", &s, &rays, &available(BACKENDS));
}

#[test]
fn subdivided_cube_from_inside() {
    let s = scene(&cube_mesh(12));
    let rays = inside_rays(&targets(&s, 1), 1.0);
    check("cube 12 x 12", &s, &rays, &available(BACKENDS));
}

/// 1.3M triangles; bvh is the reference, 1 triangle in 97 is aimed at (160k rays). Naive
/// is left out (it would test every triangle for every ray), and so are the packet
/// backends pinned to one instruction set: they share `packet`'s structure and kernels,
/// differ only in SIMD width, and are tested on the two smaller meshes (each 1.3M build
/// costs seconds).
#[test]
fn a_million_triangle_icosphere_from_inside() {
    let s = scene(&raybench_scene::generators::icosphere(8));
    assert!(s.geometry.len() > 1_000_000);
    let rays = inside_rays(&targets(&s, 97), 1.0);
    let backends = ["bvh", "obvhs", "grid", "grid2", "packet"];
    check("icosphere:8", &s, &rays, &available(&backends));
}

/// The embree peers (feature `embree`): Embree's watertight mode must let no inside ray
/// escape either (its `t` is its own, so only hit/miss is compared).
#[cfg(feature = "embree")]
#[test]
fn embree_from_inside() {
    for mesh in [raybench_scene::generators::icosphere(4), cube_mesh(12)] {
        let s = scene(&mesh);
        let rays = inside_rays(&targets(&s, 1), 1.0);
        for name in ["embree", "embree-packet"] {
            let (hits, _) = prepared(name, &s).trace_rays(&rays, false).unwrap();
            let escaped = hits.iter().filter(|h| h.is_none()).count();
            assert_eq!(
                escaped,
                0,
                "{name}: {escaped} of {} rays escaped",
                rays.len()
            );
        }
    }
}
