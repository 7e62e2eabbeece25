//! tinybvh's `BVH4_CPU` and `BVH8_CPU` (feature `tinybvh`) against the naive oracle. tinybvh
//! is a peer, not bound by the equivalence contract: its own triangle test and traversal
//! may give a ray through a shared edge the neighbouring triangle, or let it slip through,
//! so the rays that differ are counted and must stay a small fraction; where the ids agree,
//! `t` agrees within a relative tolerance.
#![cfg(feature = "tinybvh")]

use raybench_core::{
    Accel, Camera, Geometry, Hit, NoCounters, Plane, Ray, SceneBuilder, Shape, Sphere, Triangle,
    Vec3, ray_sets,
};
use raybench_naive::NaiveAccel;
use raybench_peers::{TinyBvhAccel, TinyBvhLayout};
use raybench_scene::generators;
use std::sync::Arc;

/// Most rays of a set whose answer may differ from naive's: one in 1,000 (edge and
/// grazing rays; in practice far fewer, printed by each check).
const MAX_DIFFER: f64 = 1e-3;

/// Relative `t` tolerance where the ids agree: tinybvh divides by the determinant through
/// an approximate reciprocal refined once.
const REL_T: f32 = 1e-4;

/// Whether tinybvh runs on this CPU; says why not when it does not.
fn available() -> bool {
    match raybench_peers::tinybvh_availability() {
        Ok(()) => true,
        Err(e) => {
            eprintln!("tinybvh skipped: {e}");
            false
        }
    }
}

fn tris(m: raybench_core::TriangleMesh) -> Vec<Shape> {
    m.triangles().map(Shape::Triangle).collect()
}

/// Small built-in meshes: a closed icosphere (every ray from inside hits, and many rays
/// run along its shared edges), a triangle soup and a terrain.
fn meshes() -> Vec<(&'static str, Arc<Geometry>)> {
    vec![
        (
            "icosphere:4",
            Arc::new(Geometry::new(tris(generators::icosphere(4)))),
        ),
        (
            "soup:3000",
            Arc::new(Geometry::new(tris(generators::soup(3000, 5)))),
        ),
        (
            "terrain:24",
            Arc::new(Geometry::new(tris(generators::terrain(24)))),
        ),
    ]
}

/// Camera rays framing the mesh, seeded incoherent rays in its box, rays from the centre
/// of its box outward (inside the icosphere: each must hit), and the camera rays again
/// with `t_min` past the camera's near side (tinybvh sees them from a moved origin).
fn ray_sets(g: &Arc<Geometry>) -> Vec<(&'static str, Vec<Ray>)> {
    let bounds = g.world_bounds();
    let primary = ray_sets::primary(&Camera::framing(bounds), 96, 80);
    let incoherent = ray_sets::incoherent(bounds, 4000, 7);
    let centre = bounds.center();
    let outward = (0..4000)
        .map(|i| {
            // A Fibonacci spiral of directions.
            let k = i as f32 + 0.5;
            let z = 1.0 - 2.0 * k / 4000.0;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = k * 2.399_963;
            Ray::new(centre, Vec3::new(r * phi.cos(), r * phi.sin(), z))
        })
        .collect();
    let naive = NaiveAccel::build(Arc::clone(g));
    let clipped = primary
        .iter()
        .map(|r| {
            // Half way to the first hit, or 1 for a miss: the hit stays in the interval.
            let t = naive
                .intersect(r, &mut NoCounters)
                .map_or(1.0, |h| 0.5 * h.t);
            Ray::with_interval(r.origin, r.dir, t, r.t_max)
        })
        .collect();
    vec![
        ("primary", primary),
        ("incoherent", incoherent),
        ("outward", outward),
        ("t_min", clipped),
    ]
}

/// Checks `layout` against naive on every mesh and ray set: closest hits (batch and
/// single), then any hits of shadow rays ending short of naive's hit and of the rays
/// themselves. Returns the differing rays and the rays traced.
fn check_layout(layout: TinyBvhLayout) -> (usize, usize) {
    let (mut differ_total, mut traced) = (0, 0);
    for (mesh, g) in meshes() {
        let naive = NaiveAccel::build(Arc::clone(&g));
        let accel = TinyBvhAccel::build_with(Arc::clone(&g), layout);
        assert_eq!(accel.layout(), layout);
        for (set, rays) in ray_sets(&g) {
            let want: Vec<Option<Hit>> = rays
                .iter()
                .map(|r| naive.intersect(r, &mut NoCounters))
                .collect();
            let mut got = vec![None; rays.len()];
            for (r, h) in rays.chunks(203).zip(got.chunks_mut(203)) {
                accel.intersect_batch(r, h, &mut NoCounters);
            }
            let mut differ = 0;
            for (i, (w, h)) in want.iter().zip(&got).enumerate() {
                assert_eq!(
                    *h,
                    accel.intersect(&rays[i], &mut NoCounters),
                    "batch = single"
                );
                match (w, h) {
                    (None, None) => {}
                    (Some(w), Some(h)) if w.prim == h.prim => {
                        assert!(
                            (w.t - h.t).abs() <= REL_T * w.t.abs(),
                            "{} {mesh}/{set} ray {i}: t {} against naive's {}",
                            layout.name(),
                            h.t,
                            w.t
                        );
                        assert_eq!(w.normal, h.normal, "normals come from raybench");
                    }
                    _ => differ += 1,
                }
            }
            if set == "outward" && mesh.starts_with("icosphere") {
                assert!(want.iter().all(Option::is_some), "naive hits from inside");
            }
            // Any hits: shadow rays up to 90% of naive's hit (blocked only by another
            // triangle), then the rays themselves (blocked wherever naive hits).
            let shadow = ray_sets::shadow_probes(&rays, &want);
            let mut differ_any = 0;
            for probe in [&shadow, &rays] {
                let want: Vec<bool> = probe
                    .iter()
                    .map(|r| naive.occluded(r, &mut NoCounters))
                    .collect();
                let mut got = vec![false; probe.len()];
                for (r, o) in probe.chunks(203).zip(got.chunks_mut(203)) {
                    accel.occluded_batch(r, o, &mut NoCounters);
                }
                differ_any += want.iter().zip(&got).filter(|(w, o)| w != o).count();
            }
            eprintln!(
                "{} {mesh}/{set}: {differ} of {} closest hits and {differ_any} of {} any hits \
                 differ from naive",
                layout.name(),
                rays.len(),
                2 * rays.len()
            );
            for (what, d, n) in [
                ("closest", differ, rays.len()),
                ("any", differ_any, 2 * rays.len()),
            ] {
                assert!(
                    d as f64 <= MAX_DIFFER * n as f64,
                    "{} {mesh}/{set}: {d} of {n} {what} hits differ from naive",
                    layout.name()
                );
            }
            differ_total += differ + differ_any;
            traced += 3 * rays.len();
        }
    }
    (differ_total, traced)
}

#[test]
fn bvh4_cpu_agrees_with_naive_except_grazing_rays() {
    if available() {
        let (differ, traced) = check_layout(TinyBvhLayout::Bvh4);
        eprintln!("BVH4_CPU: {differ} of {traced} answers differ from naive");
    }
}

#[test]
fn bvh8_cpu_agrees_with_naive_except_grazing_rays() {
    if available() {
        let (differ, traced) = check_layout(TinyBvhLayout::Bvh8);
        eprintln!("BVH8_CPU: {differ} of {traced} answers differ from naive");
    }
}

#[test]
fn ray_intervals_planes_and_barycentrics() {
    if !available() {
        return;
    }
    // A triangle at z = 2 seen from the origin.
    let tri = Shape::Triangle(Triangle::new(
        Vec3::new(-1.0, -1.0, 2.0),
        Vec3::new(1.0, -1.0, 2.0),
        Vec3::new(0.0, 1.0, 2.0),
    ));
    let g = Arc::new(Geometry::new(vec![tri.clone()]));
    for layout in TinyBvhLayout::ALL {
        let a = TinyBvhAccel::build_with(Arc::clone(&g), layout);
        for (t_min, t_max, hit) in [
            (0.0, 10.0, true),
            (0.0, 1.5, false),
            (1.0, 10.0, true),
            (2.5, 10.0, false),
            (5.0, 4.0, false),
        ] {
            let r = Ray::with_interval(Vec3::ZERO, Vec3::Z, t_min, t_max);
            let h = a.intersect(&r, &mut NoCounters);
            assert_eq!(h.is_some(), hit, "{} [{t_min}, {t_max}]", layout.name());
            assert_eq!(a.occluded(&r, &mut NoCounters), hit);
            if let Some(h) = h {
                // `t` is raybench's, also from the moved origin.
                assert!((h.t - 2.0).abs() < 1e-6, "{h:?}");
            }
        }
        // An unnormalised direction: `t` in its units.
        let h = a
            .intersect(&Ray::new(Vec3::ZERO, 4.0 * Vec3::Z), &mut NoCounters)
            .unwrap();
        assert!((h.t - 0.5).abs() < 1e-6, "{h:?}");
        // Barycentrics of vertices 1 and 2 at (0, 0): u = 1/4, v = 1/2.
        let h = a
            .intersect(&Ray::new(Vec3::ZERO, Vec3::Z), &mut NoCounters)
            .unwrap();
        assert_eq!((h.prim, h.sub), (0, 0));
        assert!(
            (h.u - 0.25).abs() < 1e-5 && (h.v - 0.5).abs() < 1e-5,
            "{h:?}"
        );
    }
    // A plane in front hides the triangle, and is kept beside tinybvh.
    let plane = Shape::Plane(Plane::new(Vec3::new(0.0, 0.0, 1.0), Vec3::Z));
    let g = Arc::new(Geometry::new(vec![tri, plane]));
    raybench_peers::tinybvh_supports(&g).unwrap();
    let a = TinyBvhAccel::build(g);
    let h = a
        .intersect(&Ray::new(Vec3::ZERO, Vec3::Z), &mut NoCounters)
        .unwrap();
    assert_eq!(h.prim, 1);
}

#[test]
fn hopeless_rays_and_empty_scenes_miss() {
    if !available() {
        return;
    }
    let rays = [
        Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::new(f32::NAN, 0.0, 1.0)),
        Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::ZERO),
        Ray::new(Vec3::splat(f32::NAN), Vec3::Z),
        Ray::new(Vec3::new(0.0, 0.0, f32::NEG_INFINITY), Vec3::Z),
        Ray::with_interval(Vec3::new(0.0, 0.0, -5.0), Vec3::Z, f32::NAN, 10.0),
        Ray::with_interval(Vec3::new(0.0, 0.0, -5.0), Vec3::Z, 0.0, f32::NAN),
    ];
    let sphere = Arc::new(Geometry::new(tris(generators::icosphere(3))));
    for layout in TinyBvhLayout::ALL {
        for g in [Arc::clone(&sphere), Arc::new(Geometry::default())] {
            let a = TinyBvhAccel::build_with(g, layout);
            for r in &rays {
                assert_eq!(a.intersect(r, &mut NoCounters), None, "{r:?}");
                assert!(!a.occluded(r, &mut NoCounters), "{r:?}");
            }
            assert!(!a.stats().counts.is_empty());
        }
    }
}

#[test]
fn one_structure_serves_several_threads() {
    if !available() {
        return;
    }
    let g = Arc::new(Geometry::new(tris(generators::icosphere(4))));
    let rays = ray_sets::incoherent(g.world_bounds(), 3000, 3);
    let a = TinyBvhAccel::build(Arc::clone(&g));
    let trace = || {
        rays.iter()
            .map(|r| a.intersect(r, &mut NoCounters))
            .collect::<Vec<_>>()
    };
    let want = trace();
    std::thread::scope(|s| {
        // Builds on other threads meanwhile (tinybvh's builds are serialised).
        let builds: Vec<_> = (0..2)
            .map(|_| s.spawn(|| TinyBvhAccel::build(Arc::clone(&g)).stats()))
            .collect();
        let traces: Vec<_> = (0..3).map(|_| s.spawn(trace)).collect();
        for t in traces {
            assert_eq!(t.join().unwrap(), want);
        }
        for b in builds {
            b.join().unwrap();
        }
    });
}

#[test]
fn scenes_with_other_primitives_are_refused() {
    let mut b = SceneBuilder::new("spheres");
    b.add_sphere(Sphere::new(Vec3::ZERO, 1.0), 0).unwrap();
    let e = raybench_peers::tinybvh_supports(&b.build().geometry).unwrap_err();
    assert!(e.contains("triangles only") && e.contains("sphere"), "{e}");
    let mesh = Geometry::new(tris(generators::icosphere(2)));
    assert!(raybench_peers::tinybvh_supports(&mesh).is_ok());
}

#[test]
fn a_cpu_without_avx2_is_refused_with_a_reason() {
    assert!(raybench_peers::tinybvh_availability_with(true, true).is_ok());
    let e = raybench_peers::tinybvh_availability_with(false, true).unwrap_err();
    assert!(e.contains("lacks AVX2") && e.contains("BVH8_CPU"), "{e}");
    let e = raybench_peers::tinybvh_availability_with(false, false).unwrap_err();
    assert!(e.contains("AVX2 and FMA"), "{e}");
}
