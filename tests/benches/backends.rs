//! Criterion benchmarks of raybench's accelerated backends against peers, on one thread
//! per ray stream.
//!
//! Backends: `bvh` ([`raybench_bvh::Bvh`]), `obvhs` ([`raybench_bvh::ObvhsAccel`]), `grid`
//! ([`raybench_grid::Grid`]), `grid2` ([`raybench_grid::TwoLevelGrid`]) and `packet`
//! ([`raybench_packet::PacketAccel`], with the instruction set [`raybench_packet::Isa::detect`]
//! picks; `RAYBENCH_ISA` overrides it), traced through [`Accel::intersect_batch`] in batches
//! of 256 rays, as the renderer does; peers: `bvh-crate` (svenstaro's `bvh` crate,
//! [`raybench_peers::BvhCrateAccel`], traced through the same batch entry point) and
//! `obvhs-bvh2` (obvhs's own BVH2), built over the same triangles and testing them with
//! raybench's own primitive routine, so all of them pay the same per-primitive cost and only
//! the structure and its traversal differ. With the feature `embree`
//! (`--features embree`, needs `libembree-dev`), also Intel Embree 3, which tests triangles
//! itself: `embree` ([`raybench_peers::EmbreeAccel`], one `rtcIntersect1` per ray) and
//! `embree-packet` ([`raybench_peers::EmbreePacketAccel`], 16-ray packets), both through
//! the batch entry point.
//!
//! Scenes: the report's quick matrix (`raybench_report::matrix_scenes(true)`: spheres, whitted,
//! cornell-box, bunny, sponza; the meshes come from the assets directory, and a scene whose
//! files are missing is skipped with a message) and the generators `terrain:708` (about a
//! million triangles) and `soup:100000` (where a uniform grid should be close to a BVH).
//!
//! Benchmarks, named hierarchically so they can be filtered by regular expression:
//!
//! - `build/<backend>/<scene>`: building the structure from the scene's geometry (builders
//!   use rayon's global pool, i.e. every core; Embree its own task system, also every core;
//!   Embree's device is created once, before any timing, and shared);
//! - `trace/<backend>/<scene>/primary`: the 256 x 256 centre rays of the scene's camera, in
//!   the order the renderer traces them (16 x 16 tiles of 4 x 4 pixel blocks,
//!   [`raybench_core::ray_sets::primary_tiled`]);
//! - `trace/<backend>/<scene>/incoherent`: 65,536 seeded random rays inside the scene's
//!   bounding box ([`raybench_core::ray_sets::incoherent`], seed 1);
//! - with `RAYBENCH_RAY_SETS=primary,incoherent,shadow,ao,diffuse` (or `all`; default
//!   `primary,incoherent`, to keep the suite's run time), also
//!   `trace/<backend>/<scene>/shadow`, `ao` and `diffuse`: the sets derived from `bvh`'s
//!   hits of the primary rays ([`raybench_core::ray_sets::derived`], default parameters;
//!   `docs/rays-format.md`), the any-hit sets `shadow` and `ao` through
//!   [`Accel::occluded_batch`];
//! - with `RAYBENCH_RAYS_FILE=FILE`, also `trace/<backend>/<scene>/file`: the rays of a ray
//!   file (`raybench rays export`), any hits when its flag says so.
//!
//! Trace benchmarks run on the calling thread and report throughput in rays (criterion's
//! `elem/s`); the peers other than `embree-packet` trace single rays one after the other.
//! Before the benchmarks of a scene run, every
//! backend and peer traces both ray sets once, untimed, and the agreement of each with `bvh`
//! (same primitive hit, or both miss) is printed: the peers must agree on at least 99.9% of
//! the primary rays (those using raybench's triangle test differ only on ties and the rare
//! ray their box test wrongly rejects; Embree's own triangle test may also decide an edge
//! the other way), so
//! the benchmark is known to compare like with like; `obvhs`, an exact backend, gets a
//! warning listing the rays where it differs at all.
//!
//! Run from the workspace root (the assets path is relative to it):
//!
//! ```text
//! RAYBENCH_ASSETS=../shared/scenes cargo bench -p raybench-tests --bench backends
//! RAYBENCH_ASSETS=../shared/scenes cargo bench -p raybench-tests --bench backends -- 'trace/.*/bunny'
//! cargo bench -p raybench-tests --bench backends -- terrain
//! RAYBENCH_ASSETS=../shared/scenes cargo bench -p raybench-tests --bench backends --features embree -- embree
//! ```
//!
//! Save a baseline, change the code, then compare against it:
//!
//! ```text
//! RAYBENCH_ASSETS=../shared/scenes cargo bench -p raybench-tests --bench backends -- --save-baseline main
//! RAYBENCH_ASSETS=../shared/scenes cargo bench -p raybench-tests --bench backends -- --baseline main
//! ```
//!
//! Samples are few and short (10 samples, 2 s) so the whole suite takes a few minutes;
//! criterion's own options (`--sample-size`, `--measurement-time`, `--warm-up-time`) override
//! that.

// `criterion_group!` and `criterion_main!` generate public items without documentation.
#![allow(missing_docs)]

use criterion::{
    BenchmarkId, Criterion, SamplingMode, Throughput, criterion_group, criterion_main,
};
use obvhs::bvh2::Bvh2;
use raybench_bvh::{Bvh, BvhParams, ObvhsAccel};
use raybench_core::{Accel, Geometry, NoCounters, Ray, RaySet, Scene, Shape, Triangle, ray_sets};
use raybench_grid::{Grid, GridParams, TwoLevelGrid, TwoLevelParams};
use raybench_packet::{PacketAccel, PacketParams};
use raybench_peers::BvhCrateAccel;
#[cfg(feature = "embree")]
use raybench_peers::{EmbreeAccel, EmbreePacketAccel};
use raybench_tests::obvhs_peer::{ObvhsPeer, ObvhsTree};
use std::hint::black_box;
use std::time::{Duration, Instant};

/// Scenes beyond the report's quick list: a million-triangle height field and a soup
/// (where a uniform grid should be close to a BVH).
const EXTRA_SCENES: [&str; 2] = ["terrain:708", "soup:100000"];
/// Primary rays: a `PRIMARY_SIZE x PRIMARY_SIZE` image.
const PRIMARY_SIZE: u32 = 256;
/// Number of incoherent rays.
const INCOHERENT_COUNT: usize = 65_536;
/// Seed of the incoherent rays.
const INCOHERENT_SEED: u32 = 1;
/// Smallest fraction of primary rays on which a peer must hit what `bvh` hits (ties
/// counted).
const MIN_AGREEMENT: f64 = 0.999;
/// Relative difference in `t` under which two different primitives are a tie.
const TIE_TOLERANCE: f32 = 1e-4;

/// The scene's triangles indexed by primitive id, or `None` when it has other primitives
/// (the obvhs peer only knows triangles; every scene here is a triangle mesh).
fn triangles(g: &Geometry) -> Option<Vec<Triangle>> {
    g.shapes()
        .iter()
        .map(|s| match s {
            Shape::Triangle(t) => Some(*t),
            _ => None,
        })
        .collect()
}

// ---------------------------------------------------------------------------------------
// Benchmarks.

/// A scene with its ray sets and every structure built once, for the trace benchmarks.
struct Prepared {
    name: &'static str,
    scene: Scene,
    /// Name, rays, and whether they ask for any hit.
    ray_sets: Vec<(&'static str, Vec<Ray>, bool)>,
    tris: Option<Vec<Triangle>>,
    bvh: Bvh,
    obvhs: ObvhsAccel,
    grid: Grid,
    grid2: TwoLevelGrid,
    packet: PacketAccel,
    /// `packet` without packets: every ray alone through the same BVH8 (what packets buy).
    packet_single: PacketAccel,
    bvh_crate: BvhCrateAccel,
    /// obvhs's BVH2 and its traversal ([`raybench_tests::obvhs_peer`]).
    obvhs_peer: Option<ObvhsPeer<Bvh2>>,
    /// Embree with single rays and with packets, when it supports the scene.
    #[cfg(feature = "embree")]
    embree: Option<(EmbreeAccel, EmbreePacketAccel)>,
    /// One untimed build of each backend, to size the build benchmarks' measurement time.
    build_times: Vec<(&'static str, Duration)>,
}

fn timed<T>(f: impl FnOnce() -> T) -> (T, Duration) {
    let start = Instant::now();
    let out = f();
    (out, start.elapsed())
}

fn prepare(name: &'static str) -> Option<Prepared> {
    let scene = match raybench_scene::load(name, &raybench_scene::assets_dir(None)) {
        Ok(s) => s,
        Err(e) if e.is_missing_asset() => {
            eprintln!(
                "skipping scene {name}: {e} (set {} to the assets directory)",
                raybench_scene::ASSETS_ENV
            );
            return None;
        }
        Err(e) => panic!("cannot load scene {name}: {e}"),
    };
    let g = scene.geometry.clone();
    let (bvh, t_bvh) = timed(|| Bvh::build_with(g.clone(), BvhParams::default()));
    let ray_sets = chosen_ray_sets(&scene, &bvh);
    let (obvhs, t_obvhs) = timed(|| ObvhsAccel::build(g.clone()));
    let (grid, t_grid) = timed(|| Grid::build_with(g.clone(), GridParams::default()));
    let (grid2, t_grid2) = timed(|| TwoLevelGrid::build_with(g.clone(), TwoLevelParams::default()));
    let (packet, t_packet) = timed(|| PacketAccel::build_with(g.clone(), PacketParams::default()));
    let packet_single = PacketAccel::build_with(
        g.clone(),
        PacketParams {
            packets: false,
            ..PacketParams::default()
        },
    );
    let tris = triangles(&g);
    if tris.is_none() {
        eprintln!("scene {name} has non-triangle primitives: skipping the obvhs-bvh2 peer");
    }
    let (bvh_crate, t_crate) = timed(|| BvhCrateAccel::build(g.clone()));
    let (obvhs_peer, t_bvh2) = timed(|| tris.as_ref().map(|_| ObvhsPeer::build(g.clone())));
    eprintln!(
        "scene {name}: {} primitives; untimed builds: bvh {t_bvh:.2?}, obvhs {t_obvhs:.2?}, \
         grid {t_grid:.2?}, grid2 {t_grid2:.2?}, packet {t_packet:.2?} ({}), bvh-crate {t_crate:.2?}, obvhs-bvh2 {t_bvh2:.2?}",
        g.len(),
        packet.params().isa
    );
    // Embree's build joins the list with the feature `embree`.
    #[cfg_attr(not(feature = "embree"), allow(unused_mut))]
    let mut build_times = vec![
        ("bvh", t_bvh),
        ("obvhs", t_obvhs),
        ("grid", t_grid),
        ("grid2", t_grid2),
        ("packet", t_packet),
        ("bvh-crate", t_crate),
        ("obvhs-bvh2", t_bvh2),
    ];
    // The device is created by the first build (untimed, here) and shared afterwards.
    #[cfg(feature = "embree")]
    let embree = match raybench_peers::embree_availability()
        .and_then(|()| raybench_peers::embree_supports(&scene.geometry))
    {
        Ok(()) => {
            let (single, t_embree) = timed(|| EmbreeAccel::build(g.clone()));
            let packets = EmbreePacketAccel::build(g.clone());
            eprintln!(
                "scene {name}: untimed build: embree {t_embree:.2?} ({})",
                raybench_peers::embree_version().unwrap_or_default()
            );
            build_times.push(("embree", t_embree));
            Some((single, packets))
        }
        Err(e) => {
            eprintln!("scene {name}: skipping Embree: {e}");
            None
        }
    };
    Some(Prepared {
        name,
        scene,
        ray_sets,
        tris,
        bvh,
        obvhs,
        grid,
        grid2,
        packet,
        packet_single,
        bvh_crate,
        obvhs_peer,
        #[cfg(feature = "embree")]
        embree,
        build_times,
    })
}

/// The ray sets of `RAYBENCH_RAY_SETS` (default `primary,incoherent`; `all`), the derived
/// ones from `bvh`'s primary hits, then the rays of `RAYBENCH_RAYS_FILE` when it is set.
///
/// # Panics
/// On an unknown set name or a bad ray file (the message says which).
fn chosen_ray_sets(scene: &Scene, bvh: &Bvh) -> Vec<(&'static str, Vec<Ray>, bool)> {
    let wanted: Vec<RaySet> = match std::env::var("RAYBENCH_RAY_SETS") {
        Ok(v) if v.trim() == "all" => RaySet::ALL.to_vec(),
        Ok(v) => v
            .split(',')
            .map(|n| {
                RaySet::from_name(n.trim())
                    .unwrap_or_else(|| panic!("RAYBENCH_RAY_SETS: unknown ray set '{n}'"))
            })
            .collect(),
        Err(_) => vec![RaySet::Primary, RaySet::Incoherent],
    };
    let primary = ray_sets::primary_tiled(
        &scene.camera,
        PRIMARY_SIZE,
        PRIMARY_SIZE,
        raybench_render::TILE_SIZE,
    );
    let primary_hits = batch(bvh, &primary);
    let mut sets: Vec<(&'static str, Vec<Ray>, bool)> = RaySet::ALL
        .into_iter()
        .filter(|s| wanted.contains(s))
        .map(|set| {
            let rays = match set {
                RaySet::Primary => primary.clone(),
                RaySet::Incoherent => ray_sets::incoherent(
                    scene.geometry.world_bounds(),
                    INCOHERENT_COUNT,
                    INCOHERENT_SEED,
                ),
                _ => ray_sets::derived(
                    set,
                    scene,
                    &primary,
                    &primary_hits,
                    &ray_sets::DerivedParams::default(),
                )
                .unwrap_or_else(|e| panic!("{} rays: {e}", set.name())),
            };
            (set.name(), rays, set.any_hit())
        })
        .collect();
    if let Some(path) = std::env::var_os("RAYBENCH_RAYS_FILE") {
        let file = raybench_registry::rays_file::read(std::path::Path::new(&path))
            .unwrap_or_else(|e| panic!("RAYBENCH_RAYS_FILE: {e}"));
        sets.push(("file", file.rays, file.any_hit));
    }
    sets
}

/// Checks, outside any timing, that every backend and peer finds the same primitives as
/// `bvh` (all of them on `obvhs`, at least [`MIN_AGREEMENT`] of the primary rays on the
/// peers; ties may legitimately go another way there), and prints the agreement.
fn check_agreement(p: &Prepared) {
    for (set, rays, _) in &p.ray_sets {
        let reference: Vec<Option<(u32, f32)>> = rays
            .iter()
            .map(|r| p.bvh.intersect(r, &mut NoCounters).map(|h| (h.prim, h.t)))
            .collect();
        // Agreement: the same primitive, or both miss, or (peers only) a tie: another
        // primitive at the same distance within TIE_TOLERANCE (coincident surfaces, such as
        // the Cornell box's blocks on the floor, where each library breaks the tie its own
        // way; the report counts them the same way).
        let agree = |hits: &mut dyn Iterator<Item = Option<(u32, f32)>>| {
            let (mut same, mut tied) = (0usize, 0usize);
            for (a, b) in hits.zip(&reference) {
                match (a, *b) {
                    (None, None) => same += 1,
                    (Some((ia, _)), Some((ib, _))) if ia == ib => same += 1,
                    (Some((_, ta)), Some((_, tb)))
                        if (ta - tb).abs() <= TIE_TOLERANCE * ta.abs().max(tb.abs()) =>
                    {
                        tied += 1;
                    }
                    _ => {}
                }
            }
            let n = reference.len() as f64;
            (same as f64 / n, (same + tied) as f64 / n)
        };
        let mut results = vec![
            (
                "obvhs",
                agree(
                    &mut rays
                        .iter()
                        .map(|r| p.obvhs.intersect(r, &mut NoCounters).map(|h| (h.prim, h.t))),
                ),
            ),
            (
                "grid",
                agree(
                    &mut rays
                        .iter()
                        .map(|r| p.grid.intersect(r, &mut NoCounters).map(|h| (h.prim, h.t))),
                ),
            ),
            (
                "packet",
                agree(
                    &mut batch(&p.packet, rays)
                        .into_iter()
                        .map(|h| h.map(|h| (h.prim, h.t))),
                ),
            ),
        ];
        results.push((
            "bvh-crate",
            agree(
                &mut batch(&p.bvh_crate, rays)
                    .into_iter()
                    .map(|h| h.map(|h| (h.prim, h.t))),
            ),
        ));
        #[cfg(feature = "embree")]
        if let Some((single, packets)) = &p.embree {
            results.push((
                "embree",
                agree(
                    &mut batch(single, rays)
                        .into_iter()
                        .map(|h| h.map(|h| (h.prim, h.t))),
                ),
            ));
            results.push((
                "embree-packet",
                agree(
                    &mut batch(packets, rays)
                        .into_iter()
                        .map(|h| h.map(|h| (h.prim, h.t))),
                ),
            ));
        }
        if let Some(obvhs_peer) = &p.obvhs_peer {
            results.push((
                "obvhs-bvh2",
                agree(&mut rays.iter().map(|r| {
                    obvhs_peer
                        .closest(r, ObvhsPeer::<Bvh2>::ray(r), None)
                        .map(|(id, h)| (id, h.t))
                })),
            ));
        }
        let hits = reference.iter().filter(|h| h.is_some()).count();
        let line: Vec<String> = results
            .iter()
            .map(|(b, (a, t))| format!("{b} {:.3}% ({:.3}% with ties)", 100.0 * a, 100.0 * t))
            .collect();
        eprintln!(
            "scene {} {set}: {hits}/{} rays hit; agreement with bvh: {}",
            p.name,
            rays.len(),
            line.join(", ")
        );
        // `obvhs` is an exact backend: the equivalence tests demand bit-identical hits, so a
        // difference here is a bug to report, not a reason to stop measuring.
        if results[0].1.0 < 1.0 {
            let diffs = rays.iter().enumerate().filter_map(|(i, r)| {
                let a = p.bvh.intersect(r, &mut NoCounters);
                let b = p.obvhs.intersect(r, &mut NoCounters);
                (a.map(|h| h.prim) != b.map(|h| h.prim)).then(|| {
                    format!(
                        "ray {i}: bvh {:?}, obvhs {:?}",
                        a.map(|h| (h.prim, h.t)),
                        b.map(|h| (h.prim, h.t))
                    )
                })
            });
            for d in diffs.take(5) {
                eprintln!(
                    "  WARNING: obvhs differs from bvh (prim, t) on {} {set} {d}",
                    p.name
                );
            }
        }
        for (backend, (a, _)) in &results[1..3] {
            assert_eq!(*a, 1.0, "{backend}, an exact backend, differs from bvh");
        }
        if *set == "primary" {
            for (backend, (_, a)) in &results[3..] {
                assert!(
                    *a >= MIN_AGREEMENT,
                    "{backend} agrees with bvh on only {:.3}% of the {} primary rays (ties counted)",
                    100.0 * a,
                    p.name
                );
            }
        }
    }
}

/// Rays per batch in the trace benchmarks: a 16 x 16 tile, what the renderer sends.
const BATCH: usize = 256;

/// Traces `rays` through the batch entry point into `hits`.
fn trace<A: Accel>(accel: &A, rays: &[Ray], hits: &mut [Option<raybench_core::Hit>]) {
    for (r, h) in rays.chunks(BATCH).zip(hits.chunks_mut(BATCH)) {
        accel.intersect_batch(r, h, &mut NoCounters);
    }
    black_box(hits);
}

/// The hits of `rays` through the batch entry point.
fn batch<A: Accel>(accel: &A, rays: &[Ray]) -> Vec<Option<raybench_core::Hit>> {
    let mut hits = vec![None; rays.len()];
    trace(accel, rays, &mut hits);
    hits
}

fn bench_build(c: &mut Criterion, p: &Prepared) {
    let mut group = c.benchmark_group("build");
    // Builds take milliseconds to a second: a fixed iteration count per sample, and a
    // measurement time that fits the 10 samples.
    group.sampling_mode(SamplingMode::Flat);
    let target = |backend: &str| {
        let (_, t) = p.build_times.iter().find(|(b, _)| *b == backend).unwrap();
        (*t * 15).max(Duration::from_secs(2))
    };
    let g = &p.scene.geometry;

    group.measurement_time(target("bvh"));
    group.bench_function(BenchmarkId::new("bvh", p.name), |b| {
        b.iter_with_large_drop(|| Bvh::build_with(black_box(g.clone()), BvhParams::default()));
    });
    group.measurement_time(target("obvhs"));
    group.bench_function(BenchmarkId::new("obvhs", p.name), |b| {
        b.iter_with_large_drop(|| ObvhsAccel::build(black_box(g.clone())));
    });
    group.measurement_time(target("grid2"));
    group.bench_function(BenchmarkId::new("grid2", p.name), |b| {
        b.iter_with_large_drop(|| {
            TwoLevelGrid::build_with(black_box(g.clone()), TwoLevelParams::default())
        });
    });
    group.measurement_time(target("packet"));
    group.bench_function(BenchmarkId::new("packet", p.name), |b| {
        b.iter_with_large_drop(|| {
            PacketAccel::build_with(black_box(g.clone()), PacketParams::default())
        });
    });
    group.measurement_time(target("grid"));
    group.bench_function(BenchmarkId::new("grid", p.name), |b| {
        b.iter_with_large_drop(|| Grid::build_with(black_box(g.clone()), GridParams::default()));
    });
    group.measurement_time(target("bvh-crate"));
    group.bench_function(BenchmarkId::new("bvh-crate", p.name), |b| {
        b.iter_with_large_drop(|| BvhCrateAccel::build(black_box(g.clone())));
    });
    #[cfg(feature = "embree")]
    if p.embree.is_some() {
        // Embree's device exists already (the untimed build made it): this times the copy
        // of the triangles into Embree's buffers and its BVH build.
        group.measurement_time(target("embree"));
        group.bench_function(BenchmarkId::new("embree", p.name), |b| {
            b.iter_with_large_drop(|| EmbreeAccel::build(black_box(g.clone())));
        });
    }
    if let Some(tris) = &p.tris {
        // The peer's input in its own format, prepared outside the timing.
        let otris = ObvhsPeer::<Bvh2>::obvhs_tris(tris);
        group.measurement_time(target("obvhs-bvh2"));
        group.bench_function(BenchmarkId::new("obvhs-bvh2", p.name), |b| {
            b.iter_with_large_drop(|| Bvh2::build_tree(black_box(&otris)));
        });
    }
    group.finish();
}

fn bench_trace(c: &mut Criterion, p: &Prepared) {
    let mut group = c.benchmark_group("trace");
    // An iteration traces every ray of a set (tens of milliseconds): a fixed iteration count
    // per sample keeps 10 samples within the measurement time.
    group.sampling_mode(SamplingMode::Flat);
    for (set, rays, any_hit) in &p.ray_sets {
        group.throughput(Throughput::Elements(rays.len() as u64));
        let id = |backend: &str| BenchmarkId::new(backend, format!("{}/{set}", p.name));
        if *any_hit {
            bench_occlusion(&mut group, p, rays, &id);
            continue;
        }
        let mut hits = vec![None; rays.len()];

        group.bench_function(id("bvh"), |b| {
            b.iter(|| trace(&p.bvh, black_box(rays), &mut hits));
        });
        group.bench_function(id("packet"), |b| {
            b.iter(|| trace(&p.packet, black_box(rays), &mut hits));
        });
        if *set == "primary" {
            group.bench_function(id("packet-single"), |b| {
                b.iter(|| trace(&p.packet_single, black_box(rays), &mut hits));
            });
        }
        group.bench_function(id("obvhs"), |b| {
            b.iter(|| trace(&p.obvhs, black_box(rays), &mut hits));
        });
        group.bench_function(id("grid2"), |b| {
            b.iter(|| trace(&p.grid2, black_box(rays), &mut hits));
        });
        group.bench_function(id("grid"), |b| {
            b.iter(|| trace(&p.grid, black_box(rays), &mut hits));
        });
        group.bench_function(id("bvh-crate"), |b| {
            b.iter(|| trace(&p.bvh_crate, black_box(rays), &mut hits));
        });
        #[cfg(feature = "embree")]
        if let Some((single, packets)) = &p.embree {
            group.bench_function(id("embree"), |b| {
                b.iter(|| trace(single, black_box(rays), &mut hits));
            });
            group.bench_function(id("embree-packet"), |b| {
                b.iter(|| trace(packets, black_box(rays), &mut hits));
            });
        }
        if let Some(obvhs_peer) = &p.obvhs_peer {
            let g = &*p.scene.geometry;
            // The peer's own ray type, like raybench's rays, is made outside the timing.
            // Its hits are completed like the backends' (normal, barycentrics).
            let obvhs_rays: Vec<_> = rays.iter().map(ObvhsPeer::<Bvh2>::ray).collect();
            group.bench_function(id("obvhs-bvh2"), |b| {
                b.iter(|| {
                    for (ray, oray) in rays.iter().zip(&obvhs_rays) {
                        let ray = black_box(ray);
                        let best = obvhs_peer.closest(ray, *oray, None);
                        black_box(g.complete(ray, best));
                    }
                });
            });
        }
    }
    group.finish();
}

/// The any-hit benchmarks of one ray set: every backend and peer through
/// [`Accel::occluded_batch`] in batches of [`BATCH`] rays.
fn bench_occlusion(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    p: &Prepared,
    rays: &[Ray],
    id: &dyn Fn(&str) -> BenchmarkId,
) {
    let mut occluded = vec![false; rays.len()];
    let mut run = |name: &str, occlude: &dyn Fn(&[Ray], &mut [bool])| {
        group.bench_function(id(name), |b| {
            b.iter(|| {
                for (r, o) in black_box(rays)
                    .chunks(BATCH)
                    .zip(occluded.chunks_mut(BATCH))
                {
                    occlude(r, o);
                }
                black_box(&occluded);
            });
        });
    };
    run("bvh", &|r, o| p.bvh.occluded_batch(r, o, &mut NoCounters));
    run("packet", &|r, o| {
        p.packet.occluded_batch(r, o, &mut NoCounters)
    });
    run("obvhs", &|r, o| {
        p.obvhs.occluded_batch(r, o, &mut NoCounters)
    });
    run("grid2", &|r, o| {
        p.grid2.occluded_batch(r, o, &mut NoCounters)
    });
    run("grid", &|r, o| p.grid.occluded_batch(r, o, &mut NoCounters));
    run("bvh-crate", &|r, o| {
        p.bvh_crate.occluded_batch(r, o, &mut NoCounters)
    });
    #[cfg(feature = "embree")]
    if let Some((single, packets)) = &p.embree {
        run("embree", &|r, o| {
            single.occluded_batch(r, o, &mut NoCounters)
        });
        run("embree-packet", &|r, o| {
            packets.occluded_batch(r, o, &mut NoCounters)
        });
    }
    if let Some(obvhs_peer) = &p.obvhs_peer {
        run("obvhs-bvh2", &|r, o| {
            obvhs_peer.occluded_batch(r, o, &mut NoCounters)
        });
    }
}

fn benches_all(c: &mut Criterion) {
    // The phantom is a volume without primitives: its integration is benched in
    // `benches/grids.rs`.
    let quick = raybench_report::matrix_scenes(true);
    let scenes = quick
        .iter()
        .filter(|&&n| n != "phantom")
        .chain(&EXTRA_SCENES);
    for &name in scenes {
        let Some(p) = prepare(name) else { continue };
        check_agreement(&p);
        bench_build(c, &p);
        bench_trace(c, &p);
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    targets = benches_all
}
criterion_main!(benches);
