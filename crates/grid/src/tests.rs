//! Unit tests of the grid: resolution, insertion, the walk, mailboxing.

use super::*;
use raybench_geometry::{Accel, Ray};
use raybench_geometry::{Shape, Sphere, Triangle};
use raybench_scene::generators;

fn soup_grid(n: u32) -> Grid {
    let g = Arc::new(Geometry::new(
        generators::soup(n, 4)
            .triangles()
            .map(Shape::Triangle)
            .collect(),
    ));
    Grid::build_with(g, GridParams::default())
}

/// f64 slab interval of `ray` with box `[lo, hi]`.
fn interval(ray: &Ray, lo: [f64; 3], hi: [f64; 3]) -> (f64, f64) {
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for a in 0..3 {
        let o = f64::from(ray.origin[a]);
        let d = f64::from(ray.dir[a]);
        if d == 0.0 {
            if o < lo[a] || o > hi[a] {
                return (1.0, 0.0);
            }
            continue;
        }
        let (mut n, mut f) = ((lo[a] - o) / d, (hi[a] - o) / d);
        if n > f {
            std::mem::swap(&mut n, &mut f);
        }
        t0 = t0.max(n);
        t1 = t1.min(f);
    }
    (t0, t1)
}

#[test]
fn dda_visits_every_cell_the_ray_really_crosses() {
    let grid = soup_grid(3000);
    let res = grid.resolution();
    let rays = raybench_geometry::random_rays::incoherent(grid.bounds(), 300, 9);
    let (min, cell) = (grid.bounds().min, grid.cell_size());
    for ray in &rays {
        let visited: std::collections::HashSet<[u32; 3]> =
            grid.cells_visited(ray).into_iter().collect();
        for z in 0..res[2] {
            for y in 0..res[1] {
                for x in 0..res[0] {
                    let lo = [0, 1, 2]
                        .map(|a| f64::from(min[a]) + f64::from([x, y, z][a]) * f64::from(cell[a]));
                    let hi = [0, 1, 2].map(|a| lo[a] + f64::from(cell[a]));
                    let (t0, t1) = interval(ray, lo, hi);
                    // Crossed by more than a sliver: must be visited.
                    if t1 - t0 > 1e-4 * f64::from(cell.min_element()) {
                        assert!(
                            visited.contains(&[x, y, z]),
                            "ray {ray:?} skipped cell {x} {y} {z}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn resolution_follows_the_primitive_count_and_cap() {
    let small = soup_grid(100);
    let large = soup_grid(20_000);
    let cells = |g: &Grid| {
        g.resolution()
            .iter()
            .map(|&r| u64::from(r))
            .product::<u64>()
    };
    assert!(cells(&large) > 50 * cells(&small));
    // lambda * M cells, roughly.
    let ratio = cells(&large) as f64 / (2.0 * 20_000.0);
    assert!((0.5..2.0).contains(&ratio), "{ratio}");
    let g = Arc::new(Geometry::new(
        generators::soup(20_000, 4)
            .triangles()
            .map(Shape::Triangle)
            .collect(),
    ));
    let capped = Grid::build_with(
        g,
        GridParams {
            lambda: 8.0,
            max_cells: 1000,
            ..GridParams::default()
        },
    );
    assert!(cells(&capped) <= 1000);
}

#[test]
fn mailboxing_tests_each_primitive_once_along_a_ray() {
    // One long thin triangle spanning every cell along x.
    let mut shapes = vec![Shape::Triangle(Triangle::new(
        Vec3::new(-10.0, 0.0, 0.0),
        Vec3::new(10.0, 0.0, 0.0),
        Vec3::new(10.0, 0.1, 0.0),
    ))];
    shapes.extend((0..500).map(|i| {
        Shape::Sphere(Sphere::new(
            Vec3::new(-9.0 + i as f32 * 0.036, 5.0, 5.0),
            0.01,
        ))
    }));
    let grid = Grid::build_with(Arc::new(Geometry::new(shapes)), GridParams::default());
    // Along the triangle's plane, just above it: crosses every cell it lists.
    let ray = Ray::new(Vec3::new(-11.0, 0.05, 0.0), Vec3::X);
    let mut c = raybench_geometry::RayCounters::default();
    let _ = grid.intersect(&ray, &mut c);
    assert!(c.node_visits > 5, "{} cells", c.node_visits);
    assert_eq!(
        c.prim_tests, 1,
        "tested once despite spanning {} cells",
        c.node_visits
    );
}

#[test]
fn primitives_spanning_everything_do_not_make_lists_quadratic() {
    // 3,000 triangles each crossing the whole box: at two cells per primitive the lists
    // would hold 3,000 x 6,000 entries; coarsening keeps them near 16 per primitive.
    let shapes: Vec<Shape> = (0..3000)
        .map(|i| {
            let a = i as f32 * 0.001;
            Shape::Triangle(Triangle::new(
                Vec3::new(-1.0, -1.0, -1.0 + a),
                Vec3::new(1.0, 1.0, 1.0 - a),
                Vec3::new(1.0, -1.0, a),
            ))
        })
        .collect();
    let grid = Grid::build_with(Arc::new(Geometry::new(shapes)), GridParams::default());
    let refs = grid.ids.len() as u64;
    let cells = grid.offsets.len() as u64 - 1;
    assert!(
        refs <= MAX_REFERENCES_PER_PRIMITIVE * 3000 + cells,
        "{refs} references"
    );
    let hit = grid.intersect(
        &Ray::new(Vec3::new(0.2, 0.1, -5.0), Vec3::Z),
        &mut raybench_geometry::NoCounters,
    );
    assert!(hit.is_some());
}

#[test]
fn triangle_box_test_keeps_touching_and_drops_missing_cells() {
    let (c, h) = (Vec3::ZERO, Vec3::splat(0.5));
    let t = |a: [f32; 3], b: [f32; 3], d: [f32; 3]| Triangle::new(a.into(), b.into(), d.into());
    // Through the centre.
    assert!(triangle_may_touch_box(
        &t([-2.0, -2.0, 0.0], [2.0, -2.0, 0.0], [0.0, 2.0, 0.0]),
        c,
        h
    ));
    // Its plane touches the box exactly at the corner (0.5, 0.5, 0.5): x + y + z = 1.5.
    assert!(triangle_may_touch_box(
        &t([1.5, 0.0, 0.0], [0.0, 1.5, 0.0], [0.0, 0.0, 1.5]),
        c,
        h
    ));
    // An edge exactly along a box edge.
    assert!(triangle_may_touch_box(
        &t([0.5, 0.5, -3.0], [0.5, 0.5, 3.0], [3.0, 3.0, 0.0]),
        c,
        h
    ));
    // A large triangle whose bounding box covers the cell but whose plane passes by.
    assert!(!triangle_may_touch_box(
        &t([2.0, -5.0, -5.0], [-5.0, 2.0, -5.0], [-5.0, -5.0, 2.0]),
        c,
        h
    ));
    // A sliver beside the box: an edge/axis cross product separates it.
    assert!(!triangle_may_touch_box(
        &t([0.6, 0.6, -3.0], [0.7, 0.7, 3.0], [3.0, 3.0, 0.0]),
        c,
        h
    ));
}

#[test]
fn zero_and_nan_directions_terminate_and_miss() {
    let grid = soup_grid(500);
    for dir in [Vec3::ZERO, Vec3::splat(f32::NAN)] {
        let r = Ray::new(Vec3::ZERO, dir);
        assert!(
            grid.intersect(&r, &mut raybench_geometry::NoCounters)
                .is_none()
        );
        assert!(!grid.occluded(&r, &mut raybench_geometry::NoCounters));
    }
}

#[test]
fn empty_and_flat_grids() {
    let g = Grid::build_with(Arc::new(Geometry::default()), GridParams::default());
    assert!(
        g.intersect(
            &Ray::new(Vec3::ZERO, Vec3::X),
            &mut raybench_geometry::NoCounters
        )
        .is_none()
    );
    let flat = Arc::new(Geometry::new(
        generators::terrain(1)
            .triangles()
            .map(|t| {
                Shape::Triangle(Triangle::new(
                    Vec3::new(t.v[0].x, 0.0, t.v[0].z),
                    Vec3::new(t.v[1].x, 0.0, t.v[1].z),
                    Vec3::new(t.v[2].x, 0.0, t.v[2].z),
                ))
            })
            .collect(),
    ));
    let g = Grid::build_with(flat, GridParams::default());
    let hit = g.intersect(
        &Ray::new(Vec3::new(0.1, 1.0, 0.2), -Vec3::Y),
        &mut raybench_geometry::NoCounters,
    );
    assert_eq!(hit.map(|h| h.t), Some(1.0));
}

#[test]
fn quality_counts_every_list() {
    use raybench_geometry::StructureQuality;
    let grid = soup_grid(2000);
    let Some(StructureQuality::Grid(q)) = grid.quality(&Default::default()) else {
        panic!("a grid's quality is a grid's");
    };
    let [nx, ny, nz] = grid.resolution();
    assert_eq!(q.cells, u64::from(nx * ny * nz));
    assert_eq!(q.references, grid.ids.len() as u64);
    assert_eq!(q.primitives, 2000);
    assert!(q.references >= 2000 && q.fill() > 0.0 && q.fill() <= 1.0);
    assert_eq!(q.list_lengths.0.iter().sum::<u64>(), q.non_empty_cells);
    // The two-level grid over the soup and a cluster of 300 small triangles (dense cells):
    // top cells without a sub-grid plus the sub-grids' cells.
    let mut shapes = grid.geometry.shapes().to_vec();
    shapes.extend((0..300).map(|i| {
        let o = Vec3::splat(0.001 * i as f32);
        Shape::Triangle(Triangle::new(o, o + Vec3::X * 0.01, o + Vec3::Y * 0.01))
    }));
    let two = TwoLevelGrid::build_with(
        Arc::new(Geometry::new(shapes)),
        crate::TwoLevelParams::default(),
    );
    let Some(StructureQuality::Grid(q2)) = two.quality(&Default::default()) else {
        panic!("a grid's quality is a grid's");
    };
    let count = |name: &str| {
        two.stats()
            .counts
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| *v)
            .unwrap()
    };
    let (subs, sub_cells) = (count("sub-grids"), count("sub-grid cells"));
    assert!(subs > 0, "the cluster makes dense cells");
    let top = count("nx") * count("ny") * count("nz");
    assert_eq!(q2.cells, top - subs + sub_cells);
    assert_eq!(q2.primitives, 2300);
}
