//! Rays that stress a uniform grid, every backend against naive: along cell boundaries and
//! grid faces, starting exactly on the grid's box, axis-aligned; a single huge triangle; a
//! million tiny spheres in one corner with one large plane.

use raybench_core::{Accel, Ray, Scene, SceneBuilder, Sphere, TriangleMesh, Vec3};
use raybench_grid::{Grid, GridParams};
use raybench_tests::{assert_same_ray_hits, available, prepared};
use std::sync::Arc;

const BACKENDS: &[&str] = raybench_tests::ACCELERATED_BACKENDS;

fn check(what: &str, scene: &Arc<Scene>, rays: &[Ray]) {
    let (reference, _) = prepared(raybench_tests::ORACLE, scene)
        .trace_rays(rays, false)
        .unwrap();
    for name in available(BACKENDS) {
        let (hits, _) = prepared(name, scene).trace_rays(rays, false).unwrap();
        assert_same_ray_hits(&format!("{name}: {what}"), &reference, &hits);
    }
}

#[test]
fn rays_along_cell_boundaries_and_grid_faces() {
    for spec in ["soup:3000", "spheres:1500", "terrain:24"] {
        let scene = Arc::new(raybench_scene::load(spec, std::path::Path::new(".")).unwrap());
        let grid = Grid::build_with(Arc::clone(&scene.geometry), GridParams::default());
        let rays = raybench_tests::grid_boundary_rays(&grid);
        check(spec, &scene, &rays);
    }
}

/// Rays from far away (up to just inside the grid's `far_origin`: `FAR_ORIGIN` grid sizes
/// for a scene, `INSTANCE_FAR_ORIGIN` for the meshes instances place, whose rays start as
/// far from them as the camera is): along the cell boundaries and grid faces, and through
/// the vertices of watertight meshes, where the DDA's rounding of a far origin matters
/// most; every backend against naive, and the grid built for instances against naive.
#[test]
fn rays_from_far_origins() {
    for spec in ["soup:3000", "terrain:24", "icosphere:3"] {
        let scene = Arc::new(raybench_scene::load(spec, std::path::Path::new(".")).unwrap());
        let grid = Grid::build_with(Arc::clone(&scene.geometry), GridParams::default());
        let size = grid.bounds().extent().max_element();
        let mut targets: Vec<Ray> = raybench_tests::grid_boundary_rays(&grid)
            .into_iter()
            .step_by(3)
            .collect();
        // Through the vertices, from seeded directions.
        let vertices = scene.geometry.shapes().iter().filter_map(|s| match s {
            raybench_core::Shape::Triangle(t) => Some(t.v[0]),
            _ => None,
        });
        for (k, v) in vertices.step_by(7).enumerate() {
            let a = k as f32 * 2.399_963;
            let z = 1.0 - 2.0 * ((k as f32 * 0.618_034) % 1.0);
            let r = (1.0 - z * z).sqrt();
            targets.push(Ray::new(v, Vec3::new(r * a.cos(), z, r * a.sin())));
        }
        let far = |limit: f32| -> Vec<Ray> {
            targets
                .iter()
                .enumerate()
                .map(|(k, t)| {
                    let reach = [limit / 8.0, limit / 2.0, limit][k % 3] * 0.95 * size;
                    let dir = t.dir.normalize();
                    Ray::new(t.origin - dir * reach, dir)
                })
                .collect()
        };
        check(
            &format!("{spec}, far origins"),
            &scene,
            &far(raybench_grid::FAR_ORIGIN),
        );
        // The grid over a mesh that instances place walks the DDA from much farther.
        let rays = far(raybench_grid::INSTANCE_FAR_ORIGIN);
        let wide = grid.for_instances();
        let (reference, _) = prepared(raybench_tests::ORACLE, &scene)
            .trace_rays(&rays, false)
            .unwrap();
        let mut counters = raybench_core::RayCounters::default();
        let hits: Vec<_> = rays
            .iter()
            .map(|r| wide.intersect(r, &mut counters))
            .collect();
        assert_same_ray_hits(&format!("{spec}, instance grid"), &reference, &hits);
        assert!(
            counters.prim_tests < rays.len() as u64 * scene.geometry.len() as u64 / 4,
            "{spec}: the instance grid tested everything ({} tests)",
            counters.prim_tests
        );
    }
}

#[test]
fn single_huge_triangle() {
    let mut b = SceneBuilder::new("huge");
    let mesh = TriangleMesh {
        positions: vec![
            Vec3::new(-1e4, -1e4, 0.0),
            Vec3::new(1e4, -1e4, 1.0),
            Vec3::new(0.0, 1e4, -1.0),
        ],
        indices: vec![[0, 1, 2]],
    };
    b.add_mesh("t", &mesh, 0).unwrap();
    let scene = Arc::new(b.build());
    let mut rays = raybench_core::ray_sets::incoherent(scene.geometry.bounds(), 3000, 2);
    rays.extend((0..200).map(|i| {
        Ray::new(
            Vec3::new(i as f32 * 97.0 - 9000.0, 37.0 * i as f32 - 3000.0, 50.0),
            -Vec3::Z,
        )
    }));
    check("single huge triangle", &scene, &rays);
}

/// A million tiny spheres packed in one corner and one large plane: most cells are empty,
/// the corner's are crowded (the "teapot in a stadium" of spheres).
#[test]
fn a_million_tiny_spheres_in_a_corner_and_a_plane() {
    let mut b = SceneBuilder::new("corner");
    b.add_plane(Vec3::new(0.0, -1.0, 0.0), Vec3::Y, 0).unwrap();
    for s in raybench_scene::generators::random_spheres(1_000_000, 6) {
        b.add_sphere(
            Sphere::new(s.center * 0.01 + Vec3::splat(9.0), s.radius * 0.01),
            0,
        )
        .unwrap();
    }
    // A big sphere at the other end so the grid spans the whole room.
    b.add_sphere(Sphere::new(Vec3::splat(-9.0), 0.5), 0)
        .unwrap();
    let scene = Arc::new(b.build());
    let target = Vec3::splat(9.0);
    let mut rays: Vec<Ray> = (0..160)
        .map(|i| {
            let a = i as f32 * 0.39;
            let eye = Vec3::new(a.cos() * 5.0, 3.0 + (a * 0.7).sin(), a.sin() * 5.0);
            let jitter = Vec3::new((a * 3.1).sin(), (a * 2.3).cos(), (a * 1.7).sin()) * 0.006;
            Ray::new(eye, target + jitter - eye)
        })
        .collect();
    rays.extend((0..40).map(|i| {
        Ray::new(
            Vec3::new(i as f32 * 0.4 - 8.0, 5.0, 0.0),
            Vec3::new(0.1, -1.0, 0.05),
        )
    }));
    check("million spheres in a corner", &scene, &rays);
}

/// Rays starting beyond every structure's far-origin bound, as shadow and bounce rays from
/// far out on a ground plane do: every backend against naive, and the grids' and the obvhs
/// adapter's exact fallback tests only the plane for the rays that miss the mesh's box
/// (before, it tested all of the mesh's triangles for each of them).
#[test]
fn rays_from_beyond_the_far_origin_bounds_test_only_what_they_can_hit() {
    let mut b = SceneBuilder::new("far ground");
    b.add_plane(Vec3::new(0.0, -1.0, 0.0), Vec3::Y, 0).unwrap();
    let soup = raybench_scene::load("soup:2000", std::path::Path::new(".")).unwrap();
    for shape in soup.geometry.shapes() {
        if let raybench_core::Shape::Triangle(t) = shape {
            let mesh = TriangleMesh {
                positions: t.v.to_vec(),
                indices: vec![[0, 1, 2]],
            };
            b.add_mesh("t", &mesh, 0).unwrap();
        }
    }
    let scene = Arc::new(b.build());
    let size = scene.geometry.bounds().extent().max_element();
    // Origins on the ground from 200 to 20,000 scene sizes out (beyond the grids' 8 and
    // 128 and obvhs's 128): half of the rays head up and away (missing the mesh's box), a
    // quarter back at the scene's centre, a quarter down through the ground.
    let mut away = Vec::new();
    let mut rays = Vec::new();
    for k in 0..400 {
        let a = k as f32 * 2.399_963;
        let reach = size * [200.0, 2_000.0, 20_000.0][k % 3];
        let origin = Vec3::new(a.cos() * reach, -1.0 + 1e-3, a.sin() * reach);
        let ray = match k % 4 {
            0 | 1 => Ray::new(origin, Vec3::new(a.cos(), 1.0, a.sin())),
            2 => Ray::new(origin, -origin),
            _ => Ray::new(origin, Vec3::new(0.1, -1.0, 0.2)),
        };
        if k % 4 < 2 {
            away.push(ray);
        }
        rays.push(ray);
    }
    check("far ground", &scene, &rays);
    let per_ray = |tests: u64| tests as f64 / away.len() as f64;
    let mut grid_tests = raybench_core::RayCounters::default();
    let mut two_level_tests = raybench_core::RayCounters::default();
    let mut obvhs_tests = raybench_core::RayCounters::default();
    let grid = Grid::build(Arc::clone(&scene.geometry));
    let two_level = raybench_grid::TwoLevelGrid::build(Arc::clone(&scene.geometry));
    let obvhs = raybench_bvh::ObvhsAccel::build(Arc::clone(&scene.geometry));
    for ray in &away {
        assert!(grid.intersect(ray, &mut grid_tests).is_none());
        assert!(!two_level.occluded(ray, &mut two_level_tests));
        assert!(obvhs.intersect(ray, &mut obvhs_tests).is_none());
        assert!(!obvhs.occluded(ray, &mut obvhs_tests));
    }
    assert_eq!(per_ray(grid_tests.prim_tests), 1.0, "grid");
    assert_eq!(per_ray(two_level_tests.prim_tests), 1.0, "grid2");
    assert_eq!(per_ray(obvhs_tests.prim_tests), 2.0, "obvhs");
}
