//! Every instruction set's kernels against the naive oracle: ids, `t` and barycentrics bit
//! for bit, for packets (coherent rays), single rays (incoherent rays) and any-hit queries,
//! on generated geometry and on packets built to be awkward.

use raybench_bvh::BvhParams;
use raybench_core::{
    Accel, Camera, Geometry, Hit, NoCounters, Plane, Ray, Shape, Sphere, Vec3, ray_sets,
};
use raybench_naive::NaiveAccel;
use raybench_packet::{Bvh2Builder, Interleave, Isa, PacketAccel, PacketParams};
use raybench_scene::generators;
use std::sync::{Arc, OnceLock};

#[path = "../../naive/tests/oracle/mod.rs"]
mod oracle;

use oracle::{Oracle, OracleSet};

fn geometries() -> Vec<(&'static str, Arc<Geometry>)> {
    let tris =
        |m: raybench_core::TriangleMesh| m.triangles().map(Shape::Triangle).collect::<Vec<_>>();
    let mut all = generators::test_geometries(200);
    // Coincident triangles: the tie rule must pick the smaller id everywhere.
    let twins = tris(generators::terrain(12));
    let mut coincident = twins.clone();
    coincident.extend(twins.iter().rev().cloned());
    all.push(("coincident", Arc::new(Geometry::new(coincident))));
    // A pile of identical triangles beside a mesh: no split separates them.
    let mut pile = tris(generators::icosphere(1));
    pile.extend(std::iter::repeat_n(twins[5].clone(), 100));
    all.push(("pile", Arc::new(Geometry::new(pile))));
    // Long thin triangles through a sphere's centre among its small ones: pre-splitting
    // cuts them into parts that sit in several leaves.
    let mut slivers: Vec<Shape> = (0..60)
        .map(|i| {
            let (s, c) = (i as f32 * 0.105).sin_cos();
            Shape::Triangle(raybench_core::Triangle::new(
                Vec3::new(c, -1.0, s),
                Vec3::new(-c, 1.0, -s),
                Vec3::new(-c * 0.99, 1.0, -s * 1.01),
            ))
        })
        .collect();
    slivers.extend(tris(generators::icosphere(3)));
    all.push(("slivers", Arc::new(Geometry::new(slivers))));
    all.push(("walls", walls_among_clutter(1000, 20)));
    all.push((
        "one sphere",
        Arc::new(Geometry::new(vec![Shape::Sphere(Sphere::new(
            Vec3::ZERO,
            1.0,
        ))])),
    ));
    all
}

/// An architectural scene's difficulty in miniature: `small` triangles of a soup among
/// `large` ones four times a soup's size (walls through the clutter), where the binned tree
/// is worst and obvhs's reinsertion saves most (the preset's pass saves about 8 % of the
/// SAH, as on Sponza).
fn walls_among_clutter(small: u32, large: u32) -> Arc<Geometry> {
    let mut tris: Vec<Shape> = generators::soup(small, 3)
        .triangles()
        .map(Shape::Triangle)
        .collect();
    tris.extend(generators::soup(large, 4).triangles().map(|t| {
        let c = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
        let [a, b, d] = t.v.map(|v| c + (v - c) * 4.0);
        Shape::Triangle(raybench_core::Triangle::new(a, b, d))
    }));
    Arc::new(Geometry::new(tris))
}

/// Coherent rays: a camera framing the geometry, row by row; plus incoherent rays; plus rays
/// from inside the geometry's box along the axes (packets whose lanes start inside boxes)
/// and packets mixing hits, misses, NaN and zero directions and octants.
fn ray_sets(g: &Geometry) -> Vec<(&'static str, Vec<Ray>)> {
    let bounds = if g.bounds().is_empty() {
        raybench_core::Aabb::new(-Vec3::ONE, Vec3::ONE)
    } else {
        g.bounds()
    };
    let camera = Camera::framing(bounds);
    let primary = ray_sets::primary(&camera, 48, 40);
    let incoherent = ray_sets::incoherent(bounds, 3000, 7);
    let c = bounds.center();
    let inside: Vec<Ray> = (0..64)
        .map(|i| {
            let a = i as f32 * 0.37;
            Ray::new(
                c + 0.01 * Vec3::new(a.sin(), 0.0, a.cos()),
                Vec3::new(0.2, -0.1 + 0.003 * i as f32, 1.0),
            )
        })
        .collect();
    let mut awkward = Vec::new();
    for i in 0..48 {
        let r = &primary[(i * 37) % primary.len()];
        awkward.push(match i % 6 {
            0 => Ray::new(r.origin, -r.dir),
            1 => Ray::new(r.origin, Vec3::new(f32::NAN, 0.0, 1.0)),
            2 => Ray::new(r.origin, Vec3::ZERO),
            3 => Ray::with_interval(r.origin, r.dir, 0.0, 1e-3),
            _ => *r,
        });
    }
    vec![
        ("primary", primary),
        ("incoherent", incoherent),
        ("inside", inside),
        ("awkward", awkward),
    ]
}

fn same(a: &Option<Hit>, b: &Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            a.prim == b.prim
                && a.t.to_bits() == b.t.to_bits()
                && a.u.to_bits() == b.u.to_bits()
                && a.v.to_bits() == b.v.to_bits()
        }
        _ => false,
    }
}

fn check_isa(isa: Isa, packets: bool) {
    check(PacketParams {
        isa,
        packets,
        ..PacketParams::default()
    });
}

/// Naive's answers on every ray set of every geometry of [`geometries`], computed once per
/// test binary: every instruction set and tree is checked against the same ones.
fn oracles() -> &'static [Oracle] {
    static ORACLES: OnceLock<Vec<Oracle>> = OnceLock::new();
    ORACLES.get_or_init(|| oracle::oracles(geometries(), ray_sets))
}

fn check(params: PacketParams) {
    let (isa, packets) = (params.isa, params.packets);
    for Oracle {
        name,
        geometry,
        sets,
    } in oracles()
    {
        let accel = PacketAccel::build_with(Arc::clone(geometry), params);
        assert_eq!(accel.params().isa, isa);
        for OracleSet {
            name: set,
            rays,
            closest: want,
            shadow,
            occluded: want_occluded,
        } in sets
        {
            let mut got = vec![None; rays.len()];
            // Odd batch lengths leave partial packets at the end.
            for (r, h) in rays.chunks(203).zip(got.chunks_mut(203)) {
                accel.intersect_batch(r, h, &mut NoCounters);
            }
            for (i, (w, h)) in want.iter().zip(&got).enumerate() {
                assert!(
                    same(w, h),
                    "{isa} packets={packets} {name}/{set} ray {i}: naive {w:?}, packet {h:?}"
                );
                let one = accel.intersect(&rays[i], &mut NoCounters);
                assert!(
                    same(w, &one),
                    "{isa} single {name}/{set} ray {i}: naive {w:?}, packet {one:?}"
                );
            }
            let mut got = vec![false; shadow.len()];
            for (r, o) in shadow.chunks(203).zip(got.chunks_mut(203)) {
                accel.occluded_batch(r, o, &mut NoCounters);
            }
            for (i, (w, o)) in want_occluded.iter().zip(&got).enumerate() {
                assert_eq!(w, o, "{isa} packets={packets} {name}/{set} shadow ray {i}");
                assert_eq!(
                    *w,
                    accel.occluded(&shadow[i], &mut NoCounters),
                    "{isa} single {name}/{set} shadow ray {i}"
                );
            }
        }
    }
}

#[test]
fn portable_matches_naive() {
    check_isa(Isa::Portable, true);
    check_isa(Isa::Portable, false);
}

#[test]
fn sse41_matches_naive() {
    if Isa::Sse41.is_available() {
        check_isa(Isa::Sse41, true);
    } else {
        eprintln!("SKIPPED: this CPU has no SSE4.1");
    }
}

#[test]
fn avx2_matches_naive() {
    if Isa::Avx2.is_available() {
        check_isa(Isa::Avx2, true);
        check_isa(Isa::Avx2, false);
    } else {
        eprintln!("SKIPPED: this CPU has no AVX2");
    }
}

/// Every ray alone, two and four in flight (the test meshes fit any cache, so `Auto` alone
/// would never take the interleaved paths).
#[test]
fn every_interleave_matches_naive() {
    let isa = Isa::detect();
    for interleave in [Interleave::One, Interleave::Two, Interleave::Four] {
        check(PacketParams {
            isa,
            packets: false,
            interleave,
            ..PacketParams::default()
        });
    }
}

#[test]
fn avx512_matches_naive() {
    if Isa::Avx512.is_available() {
        check_isa(Isa::Avx512, true);
    } else {
        eprintln!("SKIPPED: this CPU has no AVX-512F");
    }
}

/// The BVH8 is collapsed from whatever BVH2 it is given: other presets, a BVH2 split down
/// to single primitives, one whose leaves hold more than a leaf reference can name (100
/// coincident triangles in one leaf, laid out as a small tree of leaves), and one over
/// pre-split triangles (a triangle in several leaves); then obvhs's PLOC trees and binned
/// trees after obvhs's reinsertion.
#[test]
fn every_bvh2_collapses_exactly() {
    let coarse = BvhParams {
        max_leaf_size: 100,
        ..BvhParams::fast()
    };
    let fine = BvhParams {
        max_leaf_size: 1,
        ..BvhParams::medium()
    };
    let presplit = BvhParams {
        presplit: BvhParams::PRESPLIT,
        ..BvhParams::medium()
    };
    for bvh in [
        BvhParams::fast(),
        BvhParams::quality(),
        fine,
        coarse,
        presplit,
    ] {
        check(PacketParams {
            bvh: Bvh2Builder::Binned(bvh),
            ..PacketParams::default()
        });
    }
    // obvhs's PLOC trees: leaves of one, two (the `ploc` preset) and eight primitives.
    for max_leaf in [1, 2, 8] {
        check(PacketParams {
            bvh: Bvh2Builder::Ploc { max_leaf },
            ..PacketParams::default()
        });
    }
    // Binned trees after reinsertion: the preset's, and one with leaves of one primitive
    // (the pass's tree is kept on the walls, the others' gain too little).
    let walls = &oracles()
        .iter()
        .find(|o| o.name == "walls")
        .unwrap()
        .geometry;
    for bvh in [BvhParams::medium(), fine] {
        assert_ne!(
            Bvh2Builder::Reinserted(bvh)
                .build(Arc::clone(walls))
                .nodes(),
            Bvh2Builder::Binned(bvh).build(Arc::clone(walls)).nodes(),
            "the walls' tree was not reinserted"
        );
        check(PacketParams {
            bvh: Bvh2Builder::Reinserted(bvh),
            ..PacketParams::default()
        });
    }
}

/// A tree too large for the preset's pass to take a fifth of its nodes: the pass takes
/// `REINSERTION_CANDIDATES` of them, still lowers the cost, and the hits stay the binned
/// tree's (which `every_bvh2_collapses_exactly` checks against the oracle). Where the pass
/// gains less than `MIN_REINSERTION_GAIN` the binned tree comes back as it was.
#[test]
fn a_large_tree_is_reinserted_over_capped_candidates() {
    let soup = Arc::new(Geometry::new(
        generators::soup(20_000, 1)
            .triangles()
            .map(Shape::Triangle)
            .collect(),
    ));
    let binned = Bvh2Builder::Binned(BvhParams::medium()).build(Arc::clone(&soup));
    let kept = Bvh2Builder::REINSERTED.build(Arc::clone(&soup));
    assert_eq!(kept.nodes(), binned.nodes());
    assert_eq!(kept.prim_ids(), binned.prim_ids());
    let g = walls_among_clutter(20_000, 100);
    let binned = Bvh2Builder::Binned(BvhParams::medium()).build(Arc::clone(&g));
    let reinserted = Bvh2Builder::REINSERTED.build(Arc::clone(&g));
    assert!(
        binned.nodes().len() > 5 * Bvh2Builder::REINSERTION_CANDIDATES,
        "{} nodes: a fifth of them is under the cap",
        binned.nodes().len()
    );
    reinserted.validate().unwrap();
    assert!(
        reinserted.sah_cost() < binned.sah_cost() * (1.0 - Bvh2Builder::MIN_REINSERTION_GAIN),
        "SAH {} -> {}",
        binned.sah_cost(),
        reinserted.sah_cost()
    );
    let rays = ray_sets::incoherent(g.bounds(), 20_000, 7);
    let mut hits = 0;
    for ray in &rays {
        let (a, b) = (
            reinserted.intersect(ray, &mut NoCounters),
            binned.intersect(ray, &mut NoCounters),
        );
        assert!(same(&a, &b), "{ray:?}: {a:?} against {b:?}");
        hits += usize::from(b.is_some());
    }
    assert!(hits > 1000, "only {hits} of {} rays hit", rays.len());
}

#[test]
fn detection_picks_an_available_set() {
    assert!(Isa::detect().is_available());
    assert!(Isa::Portable.is_available());
}

/// One coherent packet (a shared octant, so it takes the packet path) whose lanes miss,
/// hit a sphere, hit triangles, start inside boxes, or have a zero-length interval.
#[test]
fn one_packet_with_every_kind_of_lane() {
    let mut shapes: Vec<Shape> = generators::icosphere(2)
        .triangles()
        .map(Shape::Triangle)
        .collect();
    shapes.push(Shape::Sphere(Sphere::new(Vec3::new(3.0, 0.0, 0.0), 0.5)));
    shapes.push(Shape::Plane(Plane::new(Vec3::new(0.0, -4.0, 0.0), Vec3::Y)));
    let g = Arc::new(Geometry::new(shapes));
    let naive = NaiveAccel::build(Arc::clone(&g));
    let origin = Vec3::new(-0.9, 0.3, -6.0);
    let rays: Vec<Ray> = (0..32)
        .map(|i| {
            let x = 0.05 + 0.2 * i as f32;
            let dir = Vec3::new(x, 0.01 * i as f32, 1.0);
            match i % 8 {
                // Lanes that start inside the icosphere's box (and inside the sphere).
                3 => Ray::new(Vec3::new(0.1, 0.1, 0.1), dir),
                5 => Ray::new(Vec3::new(3.0, 0.0, 0.0), dir),
                // An empty interval.
                6 => Ray::with_interval(origin, dir, 2.0, 2.0),
                _ => Ray::new(origin, dir),
            }
        })
        .collect();
    for isa in Isa::ALL.into_iter().filter(|i| i.is_available()) {
        let accel = PacketAccel::build_with(
            Arc::clone(&g),
            PacketParams {
                isa,
                ..PacketParams::default()
            },
        );
        let mut hits = vec![None; rays.len()];
        accel.intersect_batch(&rays, &mut hits, &mut NoCounters);
        let mut kinds = std::collections::BTreeSet::new();
        for (i, (r, h)) in rays.iter().zip(&hits).enumerate() {
            let want = naive.intersect(r, &mut NoCounters);
            assert!(
                same(&want, h),
                "{isa} lane {i}: naive {want:?}, packet {h:?}"
            );
            kinds.insert(h.map(|h| g.shape(h.prim).kind()));
        }
        // The packet really mixes misses, triangles and the sphere.
        assert!(kinds.len() >= 3, "{kinds:?}");
    }
}
