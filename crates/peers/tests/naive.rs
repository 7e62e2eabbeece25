//! The peers against the naive oracle on generated geometry. Peers are not bound by the
//! equivalence contract, so they must agree on nearly every ray, not on all: the `bvh`
//! crate (raybench's own primitive test, the crate's non-conservative box test) with `t`
//! bit-identical wherever the id agrees, Embree (its own triangle test) with `t` within
//! `1e-4` relative. The same holds for their two-level forms on an instanced scene
//! (`TwoLevel`, which the render crate builds for every CPU backend on such scenes).

use raybench_core::{
    Aabb, Accel, Affine3A, Camera, Geometry, Hit, Instance, NoCounters, Ray, SceneBuilder, Shape,
    Sphere, TwoLevel, Vec3, ray_sets,
};
use raybench_peers::BvhCrateAccel;
use raybench_scene::generators;
use std::sync::{Arc, OnceLock};

#[path = "../../naive/tests/oracle/mod.rs"]
mod oracle;

use oracle::{Oracle, OracleSet, oracles};

/// Smallest fraction of rays of a set on which a peer must hit what naive hits.
const MIN_AGREEMENT: f64 = 0.999;

fn tris(m: raybench_core::TriangleMesh) -> Vec<Shape> {
    m.triangles().map(Shape::Triangle).collect()
}

fn geometries() -> Vec<(&'static str, Arc<Geometry>)> {
    // Embree's backends take at most 64 spheres beside their triangles.
    generators::test_geometries(20)
}

/// An icosphere instanced 24 times (rotated, scaled, every third mirrored, every fourth
/// coincident with the previous one) beside a flat sphere.
fn instanced() -> Vec<(&'static str, Arc<Geometry>)> {
    let mesh = icosphere();
    let place = |k: usize| {
        let mirror = if k.is_multiple_of(3) { -1.0 } else { 1.0 };
        Affine3A::from_translation(Vec3::new((k % 6) as f32 - 2.5, (k / 6) as f32 - 1.5, 0.0))
            * Affine3A::from_rotation_y(0.4 * k as f32)
            * Affine3A::from_scale(Vec3::new(mirror * 0.5, 0.4, 0.6))
    };
    let instances = (0..24)
        .map(|k| Instance::new(0, &mesh, place(if k % 4 == 3 { k - 1 } else { k })).unwrap())
        .collect();
    let flat = vec![Shape::Sphere(Sphere::new(Vec3::new(0.0, 0.0, -2.0), 1.0))];
    vec![(
        "instanced icospheres",
        Arc::new(Geometry::with_instances(flat, vec![mesh], instances)),
    )]
}

/// Camera rays framing the geometry, seeded incoherent rays in its box, and rays that can
/// hit nothing (NaN and zero directions) or only a short interval.
fn ray_sets(g: &Geometry) -> Vec<(&'static str, Vec<Ray>)> {
    let bounds = if g.world_bounds().is_empty() {
        Aabb::new(-Vec3::ONE, Vec3::ONE)
    } else {
        g.world_bounds()
    };
    let primary = ray_sets::primary(&Camera::framing(bounds), 96, 80);
    let incoherent = ray_sets::incoherent(bounds, 4000, 7);
    let awkward = (0..64)
        .map(|i| {
            let r = &primary[(i * 97) % primary.len()];
            match i % 4 {
                0 => Ray::new(r.origin, Vec3::new(f32::NAN, 0.0, 1.0)),
                1 => Ray::new(r.origin, Vec3::ZERO),
                2 => Ray::with_interval(r.origin, r.dir, 0.0, 1e-3),
                _ => Ray::with_interval(r.origin, r.dir, 5.0, 4.0),
            }
        })
        .collect();
    vec![
        ("primary", primary),
        ("incoherent", incoherent),
        ("awkward", awkward),
    ]
}

/// The closest hits of `rays` through the batch entry point, in odd-sized batches (partial
/// packets at the end of each).
fn batch<A: Accel>(accel: &A, rays: &[Ray]) -> Vec<Option<Hit>> {
    let mut hits = vec![None; rays.len()];
    for (r, h) in rays.chunks(203).zip(hits.chunks_mut(203)) {
        accel.intersect_batch(r, h, &mut NoCounters);
    }
    hits
}

fn batch_occluded<A: Accel>(accel: &A, rays: &[Ray]) -> Vec<bool> {
    let mut out = vec![false; rays.len()];
    for (r, o) in rays.chunks(203).zip(out.chunks_mut(203)) {
        accel.occluded_batch(r, o, &mut NoCounters);
    }
    out
}

/// Naive's answers on [`geometries`], computed once per test binary: they are most of each
/// peer's test time, and every peer is checked against the same ones.
fn flat_oracles() -> &'static [Oracle] {
    static ORACLES: OnceLock<Vec<Oracle>> = OnceLock::new();
    ORACLES.get_or_init(|| oracles(geometries(), ray_sets))
}

/// Naive's answers on [`instanced`], computed once per test binary.
fn instanced_oracles() -> &'static [Oracle] {
    static ORACLES: OnceLock<Vec<Oracle>> = OnceLock::new();
    ORACLES.get_or_init(|| oracles(instanced(), ray_sets))
}

/// Checks `build`'s accelerator against naive's answers on every geometry of `oracles` and
/// ray set: closest hits (batch and single) agree on at least [`MIN_AGREEMENT`] of each
/// set's rays with `t` within `rel_t` relative where the ids agree, any-hit results
/// likewise, and rays that can hit nothing miss.
fn check_against_naive<A: Accel>(
    name: &str,
    oracles: &[Oracle],
    build: impl Fn(Arc<Geometry>) -> A,
    rel_t: f32,
) {
    for oracle in oracles {
        let gname = oracle.name;
        let accel = build(Arc::clone(&oracle.geometry));
        for OracleSet {
            name: set,
            rays,
            closest: want,
            shadow,
            occluded,
        } in &oracle.sets
        {
            let got = batch(&accel, rays);
            let single: Vec<Option<Hit>> = rays
                .iter()
                .map(|r| accel.intersect(r, &mut NoCounters))
                .collect();
            for (mode, got) in [("batch", &got), ("single", &single)] {
                let mut same = 0;
                for (i, (w, h)) in want.iter().zip(got).enumerate() {
                    match (w, h) {
                        (None, None) => same += 1,
                        (Some(w), Some(h)) if w.prim == h.prim => {
                            same += 1;
                            let dt = (w.t - h.t).abs();
                            assert!(
                                dt <= rel_t * w.t.abs(),
                                "{name} {mode} {gname}/{set} ray {i}: t {} against naive's {}",
                                h.t,
                                w.t
                            );
                            assert_eq!(w.normal, h.normal, "normals come from raybench");
                        }
                        _ => {}
                    }
                    if !rays[i].is_valid() {
                        assert!(h.is_none(), "{name} {gname}/{set} ray {i} cannot hit");
                    }
                }
                let agree = f64::from(same) / rays.len().max(1) as f64;
                eprintln!("{name} {mode} {gname}/{set}: {:.3}% agree", 100.0 * agree);
                assert!(
                    agree >= MIN_AGREEMENT,
                    "{name} {mode} {gname}/{set}: agrees with naive on only {:.3}% of {} rays",
                    100.0 * agree,
                    rays.len()
                );
            }
            let got = batch_occluded(&accel, shadow);
            let single: Vec<bool> = shadow
                .iter()
                .map(|r| accel.occluded(r, &mut NoCounters))
                .collect();
            for (mode, got) in [("batch", &got), ("single", &single)] {
                let same = occluded.iter().zip(got).filter(|(w, o)| w == o).count();
                let agree = same as f64 / shadow.len().max(1) as f64;
                assert!(
                    agree >= MIN_AGREEMENT,
                    "{name} {mode} {gname}/{set}: any-hit agrees with naive on only {:.3}%",
                    100.0 * agree
                );
                for (i, r) in shadow.iter().enumerate() {
                    if !r.is_valid() {
                        assert!(!got[i], "{name} {gname}/{set} shadow ray {i} cannot hit");
                    }
                }
            }
        }
    }
}

#[test]
fn bvh_crate_matches_naive_except_ties() {
    // Same primitive routine as naive: where the ids agree, `t` is bit-identical.
    check_against_naive("bvh-crate", flat_oracles(), BvhCrateAccel::build, 0.0);
}

#[test]
fn bvh_crate_two_level_matches_naive_except_ties() {
    check_against_naive(
        "bvh-crate two-level",
        instanced_oracles(),
        TwoLevel::<BvhCrateAccel>::build,
        0.0,
    );
}

/// Rays with a NaN or zero direction, or an infinite origin, miss without trouble.
fn check_hopeless_rays<A: Accel>(accel: &A) {
    let rays = [
        Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::new(f32::NAN, 0.0, 1.0)),
        Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::ZERO),
        Ray::new(Vec3::splat(f32::NAN), Vec3::Z),
        Ray::new(Vec3::new(0.0, 0.0, f32::NEG_INFINITY), Vec3::Z),
    ];
    for r in &rays {
        assert_eq!(accel.intersect(r, &mut NoCounters), None, "{r:?}");
        assert!(!accel.occluded(r, &mut NoCounters), "{r:?}");
    }
    assert!(batch(accel, &rays).iter().all(Option::is_none));
    assert!(batch_occluded(accel, &rays).iter().all(|o| !o));
}

/// An icosphere whose centre ray hits it, for sanity checks.
fn icosphere() -> Arc<Geometry> {
    Arc::new(Geometry::new(tris(generators::icosphere(3))))
}

fn check_basics<A: Accel>(build: impl Fn(Arc<Geometry>) -> A) {
    let accel = build(icosphere());
    // Not along an axis: the `bvh` crate's box test misses boxes whose face plane holds an
    // axis-aligned ray, such as the triangles around the icosphere's pole.
    let toward = Ray::new(Vec3::new(0.1, 0.2, -5.0), Vec3::new(0.01, -0.02, 1.0));
    assert!(accel.intersect(&toward, &mut NoCounters).is_some());
    assert!(accel.occluded(&toward, &mut NoCounters));
    check_hopeless_rays(&accel);
    assert!(!accel.stats().counts.is_empty());

    let empty = build(Arc::new(Geometry::default()));
    assert_eq!(empty.intersect(&toward, &mut NoCounters), None);
    assert!(!empty.occluded(&toward, &mut NoCounters));
    check_hopeless_rays(&empty);
    let _ = empty.stats();
}

#[test]
fn bvh_crate_handles_hopeless_rays_and_empty_scenes() {
    check_basics(BvhCrateAccel::build);
}

/// Several threads tracing through one structure get what one thread gets.
fn check_threads<A: Accel>(accel: &A, rays: &[Ray]) {
    let want = batch(accel, rays);
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..4).map(|_| s.spawn(|| batch(accel, rays))).collect();
        for h in handles {
            assert_eq!(h.join().unwrap(), want);
        }
    });
}

#[test]
fn bvh_crate_is_shareable_between_threads() {
    let g = icosphere();
    let accel = BvhCrateAccel::build(Arc::clone(&g));
    check_threads(&accel, &ray_sets::incoherent(g.bounds(), 2000, 3));
}

#[test]
fn bvh_crate_supports_spheres() {
    let g = Arc::new(Geometry::new(vec![
        Shape::Sphere(Sphere::new(Vec3::new(0.0, 0.0, 3.0), 1.0)),
        Shape::Sphere(Sphere::new(Vec3::new(0.0, 0.0, 6.0), 1.0)),
    ]));
    let accel = BvhCrateAccel::build(g);
    let hit = accel
        .intersect(&Ray::new(Vec3::ZERO, Vec3::Z), &mut NoCounters)
        .unwrap();
    assert_eq!((hit.prim, hit.t), (0, 2.0));
    // A sphere scene builds a scene through the builder too.
    let mut b = SceneBuilder::new("spheres");
    b.add_sphere(Sphere::new(Vec3::ZERO, 1.0), 0).unwrap();
    assert_eq!(b.build().geometry.len(), 1);
}

#[cfg(feature = "embree")]
mod embree {
    use super::*;
    use raybench_peers::{EmbreeAccel, EmbreePacketAccel, MAX_SIDE_PRIMITIVES};

    /// Relative `t` tolerance against raybench's triangle test.
    const REL_T: f32 = 1e-4;

    #[test]
    fn embree_single_rays_agree_with_naive() {
        check_against_naive("embree", flat_oracles(), EmbreeAccel::build, REL_T);
    }

    #[test]
    fn embree_two_level_agrees_with_naive() {
        check_against_naive(
            "embree two-level",
            instanced_oracles(),
            TwoLevel::<EmbreeAccel>::build,
            REL_T,
        );
    }

    #[test]
    fn embree_packets_of_16_agree_with_naive() {
        check_against_naive(
            "embree-packet",
            flat_oracles(),
            EmbreePacketAccel::build,
            REL_T,
        );
        let g = icosphere();
        assert_eq!(EmbreePacketAccel::build(g).width(), 16);
    }

    #[test]
    fn embree_packets_of_8_agree_with_naive() {
        check_against_naive(
            "embree-packet (8)",
            flat_oracles(),
            |g| EmbreePacketAccel::build_with_width(g, 8),
            REL_T,
        );
    }

    #[test]
    fn embree_handles_hopeless_rays_and_empty_scenes() {
        check_basics(EmbreeAccel::build);
        check_basics(EmbreePacketAccel::build);
        check_basics(|g| EmbreePacketAccel::build_with_width(g, 8));
    }

    #[test]
    fn embree_is_shareable_between_threads() {
        let g = icosphere();
        let rays = ray_sets::incoherent(g.bounds(), 2000, 3);
        check_threads(&EmbreeAccel::build(Arc::clone(&g)), &rays);
        check_threads(&EmbreePacketAccel::build(Arc::clone(&g)), &rays);
    }

    #[test]
    fn embree_respects_ray_intervals() {
        // A triangle at z = 2 seen from the origin.
        let g = Arc::new(Geometry::new(vec![Shape::Triangle(
            raybench_core::Triangle::new(
                Vec3::new(-1.0, -1.0, 2.0),
                Vec3::new(1.0, -1.0, 2.0),
                Vec3::new(0.0, 1.0, 2.0),
            ),
        )]));
        let a = EmbreeAccel::build(Arc::clone(&g));
        let p = EmbreePacketAccel::build(g);
        for (t_min, t_max, hit) in [(0.0, 10.0, true), (0.0, 1.5, false), (2.5, 10.0, false)] {
            let r = Ray::with_interval(Vec3::ZERO, Vec3::Z, t_min, t_max);
            assert_eq!(a.intersect(&r, &mut NoCounters).is_some(), hit);
            assert_eq!(a.occluded(&r, &mut NoCounters), hit);
            assert_eq!(batch(&p, &[r])[0].is_some(), hit);
            assert_eq!(batch_occluded(&p, &[r])[0], hit);
        }
        let h = a
            .intersect(&Ray::new(Vec3::ZERO, Vec3::Z), &mut NoCounters)
            .unwrap();
        assert_eq!((h.prim, h.sub), (0, 0));
        assert!((h.t - 2.0).abs() < 1e-6);
        // Barycentrics of vertices 1 and 2 at (0, 0): u = 1/4, v = 1/2.
        assert!(
            (h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6,
            "{h:?}"
        );
    }

    #[test]
    fn a_plane_in_front_clips_embree() {
        // A plane at z = 1 hides the icosphere (radius 1 around the origin) from z = -5.
        let mut shapes = tris(generators::icosphere(2));
        shapes.push(Shape::Plane(raybench_core::Plane::new(
            Vec3::new(0.0, 0.0, -3.0),
            Vec3::Z,
        )));
        let plane = shapes.len() as u32 - 1;
        let g = Arc::new(Geometry::new(shapes));
        let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        for hit in [
            EmbreeAccel::build(Arc::clone(&g)).intersect(&r, &mut NoCounters),
            batch(&EmbreePacketAccel::build(Arc::clone(&g)), &[r])[0],
        ] {
            assert_eq!(hit.map(|h| h.prim), Some(plane));
        }
    }

    #[test]
    fn scenes_with_many_spheres_are_unsupported() {
        let scene = |n: usize| {
            let mut b = SceneBuilder::new("spheres");
            for i in 0..n {
                b.add_sphere(Sphere::new(Vec3::new(i as f32, 0.0, 0.0), 0.4), 0)
                    .unwrap();
            }
            b.build()
        };
        assert!(raybench_peers::embree_supports(&scene(3).geometry).is_ok());
        assert!(raybench_peers::embree_supports(&scene(MAX_SIDE_PRIMITIVES + 1).geometry).is_err());
    }

    #[test]
    fn embree_reports_its_version() {
        raybench_peers::embree_availability().unwrap();
        let v = raybench_peers::embree_version().unwrap();
        eprintln!("{v}");
        assert!(v.starts_with("Embree 3."), "{v}");
    }
}
