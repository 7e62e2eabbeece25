//! Criterion benchmarks of raybench's accelerated backends against two peers, on one thread
//! per ray stream.
//!
//! Backends: `bvh` ([`raybench_bvh::Bvh`]), `obvhs` ([`raybench_bvh::ObvhsAccel`]), `grid`
//! ([`raybench_grid::Grid`]), `grid2` ([`raybench_grid::TwoLevelGrid`]) and `packet`
//! ([`raybench_packet::PacketAccel`], with the instruction set [`raybench_packet::Isa::detect`]
//! picks; `RAYBENCH_ISA` overrides it), traced through [`Accel::intersect_batch`] in batches
//! of 256 rays, as the renderer does; peers: `bvh-crate` (svenstaro's `bvh` crate) and `obvhs-bvh2`
//! (obvhs's own BVH2), built over the same triangles and testing them with raybench's own
//! primitive routine, so all of them pay the same per-primitive cost and only
//! the structure and its traversal differ.
//!
//! Scenes: the built-in `bunny` and `sponza` (their meshes come from the assets directory;
//! when one is missing the scene is skipped with a message) and the generators
//! `terrain:708` (about a million triangles) and `soup:100000` (where a uniform grid should
//! be close to a BVH).
//!
//! Benchmarks, named hierarchically so they can be filtered by regular expression:
//!
//! - `build/<backend>/<scene>`: building the structure from the scene's geometry (builders
//!   use rayon's global pool, i.e. every core);
//! - `trace/<backend>/<scene>/primary`: the 256 x 256 centre rays of the scene's camera, in
//!   the order the renderer traces them (16 x 16 tiles of 4 x 4 pixel blocks,
//!   [`raybench_core::rays::primary_tiled`]);
//! - `trace/<backend>/<scene>/incoherent`: 65,536 seeded random rays inside the scene's
//!   bounding box ([`raybench_core::rays::incoherent`], seed 1).
//!
//! Trace benchmarks run on the calling thread and report throughput in rays (criterion's
//! `elem/s`); the peers trace single rays one after the other. Before the benchmarks of a scene run, every
//! backend and peer traces both ray sets once, untimed, and the agreement of each with `bvh`
//! (same primitive hit, or both miss) is printed: the peers must agree on at least 99.9% of
//! the primary rays (they use the same triangle test, so only ties may go another way), so
//! the benchmark is known to compare like with like; `obvhs`, an exact backend, gets a
//! warning listing the rays where it differs at all.
//!
//! Run from the workspace root (the assets path is relative to it):
//!
//! ```text
//! RAYBENCH_ASSETS=../shared/scenes cargo bench -p raybench-tests --bench backends
//! RAYBENCH_ASSETS=../shared/scenes cargo bench -p raybench-tests --bench backends -- 'trace/.*/bunny'
//! cargo bench -p raybench-tests --bench backends -- terrain
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

use bvh::aabb::{Aabb as CrateAabb, Bounded};
use bvh::bounding_hierarchy::{BHShape, BoundingHierarchy};
use bvh::bvh::{Bvh as CrateBvh, BvhNode};
use criterion::{
    BenchmarkId, Criterion, SamplingMode, Throughput, criterion_group, criterion_main,
};
use obvhs::BvhBuildParams;
use obvhs::bvh2::Bvh2;
use obvhs::ray::RayHit;
use raybench_bvh::{Bvh, BvhParams, ObvhsAccel};
use raybench_core::{
    Accel, Geometry, NoCounters, PrimHit, Ray, Scene, Shape, Triangle, Vec3A, rays,
};
use raybench_grid::{Grid, GridParams, TwoLevelGrid, TwoLevelParams};
use raybench_packet::{PacketAccel, PacketParams};
use std::hint::black_box;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The scenes, in benchmark order.
const SCENES: [&str; 4] = ["bunny", "sponza", "terrain:708", "soup:100000"];
/// Primary rays: a `PRIMARY_SIZE x PRIMARY_SIZE` image.
const PRIMARY_SIZE: u32 = 256;
/// Number of incoherent rays.
const INCOHERENT_COUNT: usize = 65_536;
/// Seed of the incoherent rays.
const INCOHERENT_SEED: u32 = 1;
/// Smallest fraction of primary rays on which a peer must hit what `bvh` hits.
const MIN_AGREEMENT: f64 = 0.999;

/// The scene's triangles indexed by primitive id, or `None` when it has other primitives
/// (the peers only know triangles; every scene here is a triangle mesh).
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
// Peer: svenstaro's `bvh` crate.

/// A triangle as the `bvh` crate's builder wants it: a box and a slot for its node index.
#[derive(Clone, Copy, Debug)]
struct CrateTri {
    tri: Triangle,
    node: usize,
}

impl Bounded<f32, 3> for CrateTri {
    fn aabb(&self) -> CrateAabb<f32, 3> {
        let b = self.tri.bounds();
        CrateAabb::with_bounds(b.min.to_array().into(), b.max.to_array().into())
    }
}

impl BHShape<f32, 3> for CrateTri {
    fn set_bh_node_index(&mut self, index: usize) {
        self.node = index;
    }

    fn bh_node_index(&self) -> usize {
        self.node
    }
}

/// The `bvh` crate's tree (binned SAH, one triangle per leaf, built with rayon).
///
/// The crate has no closest-hit query of its own: `traverse` and `traverse_iterator` return
/// every shape whose box the ray touches, and the distance-ordered iterators keep a heap
/// and never stop early. So this peer walks the crate's own tree (`Bvh::nodes`, whose
/// interior nodes hold both children's boxes) with a small stack traversal: child boxes
/// tested with the crate's `Ray::intersection_slice_for_aabb`, nearer child first, a child
/// skipped when its entry lies beyond the best hit so far, leaves tested with raybench's
/// triangle routine and the closest kept under raybench's tie rule. This is the "bvh crate
/// tree, own stack traversal" row of `../shared/PEERS.md`.
struct CratePeer {
    bvh: CrateBvh<f32, 3>,
    /// Primitive tests go through raybench's own `Geometry::test_closest`, as in every
    /// raybench backend, so that only the structure and traversal differ.
    geometry: Arc<Geometry>,
}

impl CratePeer {
    fn shapes(tris: &[Triangle]) -> Vec<CrateTri> {
        tris.iter().map(|&tri| CrateTri { tri, node: 0 }).collect()
    }

    fn build(tris: &[Triangle], geometry: &Arc<Geometry>) -> Self {
        let mut shapes = Self::shapes(tris);
        let bvh = CrateBvh::build_par(&mut shapes);
        Self {
            bvh,
            geometry: Arc::clone(geometry),
        }
    }

    /// The crate's ray with raybench's direction (not normalised, so `t` agrees) and inverse.
    fn ray(ray: &Ray) -> bvh::ray::Ray<f32, 3> {
        bvh::ray::Ray {
            origin: ray.origin.to_array().into(),
            direction: ray.dir.to_array().into(),
            inv_direction: ray.inv_dir.to_array().into(),
        }
    }

    fn closest(
        &self,
        ray: &Ray,
        cray: &bvh::ray::Ray<f32, 3>,
        stack: &mut Vec<(usize, f32)>,
    ) -> Option<(u32, PrimHit)> {
        let nodes = &self.bvh.nodes;
        let mut best: Option<(u32, PrimHit)> = None;
        if nodes.is_empty() {
            return best;
        }
        let mut best_t = ray.t_max;
        stack.clear();
        // The crate keeps no box for the root: its children's boxes are tested on the way.
        stack.push((0, ray.t_min));
        while let Some((index, entry)) = stack.pop() {
            if entry > best_t {
                continue;
            }
            match &nodes[index] {
                BvhNode::Leaf { shape_index, .. } => {
                    self.geometry
                        .test_closest(*shape_index as u32, ray, &mut best);
                    best_t = best.map_or(ray.t_max, |(_, h)| h.t);
                }
                BvhNode::Node {
                    child_l_index,
                    child_l_aabb,
                    child_r_index,
                    child_r_aabb,
                    ..
                } => {
                    let entry_of = |b: &CrateAabb<f32, 3>| {
                        cray.intersection_slice_for_aabb(b)
                            .map(|(t0, _)| t0)
                            .filter(|&t0| t0 <= best_t)
                    };
                    match (entry_of(child_l_aabb), entry_of(child_r_aabb)) {
                        (Some(tl), Some(tr)) => {
                            if tl <= tr {
                                stack.push((*child_r_index, tr));
                                stack.push((*child_l_index, tl));
                            } else {
                                stack.push((*child_l_index, tl));
                                stack.push((*child_r_index, tr));
                            }
                        }
                        (Some(tl), None) => stack.push((*child_l_index, tl)),
                        (None, Some(tr)) => stack.push((*child_r_index, tr)),
                        (None, None) => {}
                    }
                }
            }
        }
        best
    }
}

// ---------------------------------------------------------------------------------------
// Peer: obvhs's BVH2.

/// obvhs's BVH2 from its own triangle builder (`build_bvh2_from_tris`, `medium_build`
/// preset: PLOC, reinsertion, leaves collapsed by cost), traced with its own
/// `Bvh2::ray_traverse`. The closure obvhs calls per leaf primitive tests raybench's triangle
/// and returns the best `t` so far, which obvhs uses to cull further nodes.
struct ObvhsPeer {
    bvh: Bvh2,
    /// As in [`CratePeer`]: raybench's primitive test.
    geometry: Arc<Geometry>,
}

impl ObvhsPeer {
    fn obvhs_tris(tris: &[Triangle]) -> Vec<obvhs::triangle::Triangle> {
        tris.iter()
            .map(|t| obvhs::triangle::Triangle {
                v0: Vec3A::from(t.v[0]),
                v1: Vec3A::from(t.v[1]),
                v2: Vec3A::from(t.v[2]),
            })
            .collect()
    }

    fn build_bvh2(otris: &[obvhs::triangle::Triangle]) -> Bvh2 {
        obvhs::bvh2::builder::build_bvh2_from_tris(
            otris,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        )
    }

    fn build(tris: &[Triangle], geometry: &Arc<Geometry>) -> Self {
        Self {
            bvh: Self::build_bvh2(&Self::obvhs_tris(tris)),
            geometry: Arc::clone(geometry),
        }
    }

    /// obvhs's own ray constructor (it replaces tiny direction components for its slab test).
    fn ray(ray: &Ray) -> obvhs::ray::Ray {
        obvhs::ray::Ray::new(
            Vec3A::from(ray.origin),
            Vec3A::from(ray.dir),
            ray.t_min,
            ray.t_max,
        )
    }

    fn closest(&self, ray: &Ray, oray: obvhs::ray::Ray) -> Option<(u32, PrimHit)> {
        let mut best: Option<(u32, PrimHit)> = None;
        let mut hit = RayHit::none();
        self.bvh.ray_traverse(oray, &mut hit, |_, i| {
            let id = self.bvh.primitive_indices[i];
            self.geometry.test_closest(id, ray, &mut best);
            best.map_or(f32::INFINITY, |(_, h)| h.t)
        });
        best
    }
}

// ---------------------------------------------------------------------------------------
// Benchmarks.

/// A scene with its ray sets and every structure built once, for the trace benchmarks.
struct Prepared {
    name: &'static str,
    scene: Scene,
    ray_sets: [(&'static str, Vec<Ray>); 2],
    tris: Option<Vec<Triangle>>,
    bvh: Bvh,
    obvhs: ObvhsAccel,
    grid: Grid,
    grid2: TwoLevelGrid,
    packet: PacketAccel,
    /// `packet` with interval culling (a measured option).
    packet_interval: PacketAccel,
    peers: Option<(CratePeer, ObvhsPeer)>,
    /// One untimed build of each backend, to size the build benchmarks' measurement time.
    build_times: [(&'static str, Duration); 7],
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
    let ray_sets = [
        (
            "primary",
            rays::primary_tiled(
                &scene.camera,
                PRIMARY_SIZE,
                PRIMARY_SIZE,
                raybench_render::TILE_SIZE,
            ),
        ),
        (
            "incoherent",
            rays::incoherent(g.bounds(), INCOHERENT_COUNT, INCOHERENT_SEED),
        ),
    ];
    let (bvh, t_bvh) = timed(|| Bvh::build_with(g.clone(), BvhParams::default()));
    let (obvhs, t_obvhs) = timed(|| ObvhsAccel::build(g.clone()));
    let (grid, t_grid) = timed(|| Grid::build_with(g.clone(), GridParams::default()));
    let (grid2, t_grid2) = timed(|| TwoLevelGrid::build_with(g.clone(), TwoLevelParams::default()));
    let (packet, t_packet) = timed(|| PacketAccel::build_with(g.clone(), PacketParams::default()));
    let packet_interval = PacketAccel::build_with(
        g.clone(),
        PacketParams {
            interval_cull: true,
            ..PacketParams::default()
        },
    );
    let tris = triangles(&g);
    if tris.is_none() {
        eprintln!("scene {name} has non-triangle primitives: skipping the peers");
    }
    let (crate_peer, t_crate) = timed(|| {
        tris.as_deref()
            .map(|t| CratePeer::build(t, &scene.geometry))
    });
    let (obvhs_peer, t_bvh2) = timed(|| {
        tris.as_deref()
            .map(|t| ObvhsPeer::build(t, &scene.geometry))
    });
    eprintln!(
        "scene {name}: {} primitives; untimed builds: bvh {t_bvh:.2?}, obvhs {t_obvhs:.2?}, \
         grid {t_grid:.2?}, grid2 {t_grid2:.2?}, packet {t_packet:.2?} ({}), bvh-crate {t_crate:.2?}, obvhs-bvh2 {t_bvh2:.2?}",
        g.len(),
        packet.params().isa
    );
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
        packet_interval,
        peers: crate_peer.zip(obvhs_peer),
        build_times: [
            ("bvh", t_bvh),
            ("obvhs", t_obvhs),
            ("grid", t_grid),
            ("grid2", t_grid2),
            ("packet", t_packet),
            ("bvh-crate", t_crate),
            ("obvhs-bvh2", t_bvh2),
        ],
    })
}

/// Checks, outside any timing, that every backend and peer finds the same primitives as
/// `bvh` (all of them on `obvhs`, at least [`MIN_AGREEMENT`] of the primary rays on the
/// peers; ties may legitimately go another way there), and prints the agreement.
fn check_agreement(p: &Prepared) {
    for (set, rays) in &p.ray_sets {
        let reference: Vec<Option<u32>> = rays
            .iter()
            .map(|r| p.bvh.intersect(r, &mut NoCounters).map(|h| h.prim))
            .collect();
        let agree = |ids: &mut dyn Iterator<Item = Option<u32>>| {
            let same = ids.zip(&reference).filter(|(a, b)| a == *b).count();
            same as f64 / reference.len() as f64
        };
        let mut results = vec![
            (
                "obvhs",
                agree(
                    &mut rays
                        .iter()
                        .map(|r| p.obvhs.intersect(r, &mut NoCounters).map(|h| h.prim)),
                ),
            ),
            (
                "grid",
                agree(
                    &mut rays
                        .iter()
                        .map(|r| p.grid.intersect(r, &mut NoCounters).map(|h| h.prim)),
                ),
            ),
            (
                "packet",
                agree(
                    &mut batch(&p.packet, rays)
                        .into_iter()
                        .map(|h| h.map(|h| h.prim)),
                ),
            ),
        ];
        if let Some((crate_peer, obvhs_peer)) = &p.peers {
            let mut stack = Vec::new();
            results.push((
                "bvh-crate",
                agree(&mut rays.iter().map(|r| {
                    crate_peer
                        .closest(r, &CratePeer::ray(r), &mut stack)
                        .map(|(id, _)| id)
                })),
            ));
            results.push((
                "obvhs-bvh2",
                agree(
                    &mut rays
                        .iter()
                        .map(|r| obvhs_peer.closest(r, ObvhsPeer::ray(r)).map(|(id, _)| id)),
                ),
            ));
        }
        let hits = reference.iter().filter(|h| h.is_some()).count();
        let line: Vec<String> = results
            .iter()
            .map(|(b, a)| format!("{b} {:.3}%", 100.0 * a))
            .collect();
        eprintln!(
            "scene {} {set}: {hits}/{} rays hit; agreement with bvh: {}",
            p.name,
            rays.len(),
            line.join(", ")
        );
        // `obvhs` is an exact backend: the equivalence tests demand bit-identical hits, so a
        // difference here is a bug to report, not a reason to stop measuring.
        if results[0].1 < 1.0 {
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
        for (backend, a) in &results[1..3] {
            assert_eq!(*a, 1.0, "{backend}, an exact backend, differs from bvh");
        }
        if *set == "primary" {
            for (backend, a) in &results[3..] {
                assert!(
                    *a >= MIN_AGREEMENT,
                    "{backend} agrees with bvh on only {:.3}% of the {} primary rays",
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
    if let Some(tris) = &p.tris {
        // The peers' inputs in their own formats, prepared outside the timing.
        let mut shapes = CratePeer::shapes(tris);
        group.measurement_time(target("bvh-crate"));
        group.bench_function(BenchmarkId::new("bvh-crate", p.name), |b| {
            b.iter_with_large_drop(|| CrateBvh::build_par(black_box(&mut shapes)));
        });
        let otris = ObvhsPeer::obvhs_tris(tris);
        group.measurement_time(target("obvhs-bvh2"));
        group.bench_function(BenchmarkId::new("obvhs-bvh2", p.name), |b| {
            b.iter_with_large_drop(|| ObvhsPeer::build_bvh2(black_box(&otris)));
        });
    }
    group.finish();
}

fn bench_trace(c: &mut Criterion, p: &Prepared) {
    let mut group = c.benchmark_group("trace");
    // An iteration traces every ray of a set (tens of milliseconds): a fixed iteration count
    // per sample keeps 10 samples within the measurement time.
    group.sampling_mode(SamplingMode::Flat);
    for (set, rays) in &p.ray_sets {
        group.throughput(Throughput::Elements(rays.len() as u64));
        let id = |backend: &str| BenchmarkId::new(backend, format!("{}/{set}", p.name));
        let mut hits = vec![None; rays.len()];

        group.bench_function(id("bvh"), |b| {
            b.iter(|| trace(&p.bvh, black_box(rays), &mut hits));
        });
        group.bench_function(id("packet"), |b| {
            b.iter(|| trace(&p.packet, black_box(rays), &mut hits));
        });
        if *set == "primary" {
            group.bench_function(id("packet-interval"), |b| {
                b.iter(|| trace(&p.packet_interval, black_box(rays), &mut hits));
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
        if let Some((crate_peer, obvhs_peer)) = &p.peers {
            let g = &*p.scene.geometry;
            // The peers' own ray types, like raybench's rays, are made outside the timing.
            // Their hits are completed like the backends' (normal, barycentrics).
            let crate_rays: Vec<_> = rays.iter().map(CratePeer::ray).collect();
            let mut stack = Vec::with_capacity(64);
            group.bench_function(id("bvh-crate"), |b| {
                b.iter(|| {
                    for (ray, cray) in rays.iter().zip(&crate_rays) {
                        let ray = black_box(ray);
                        let best = crate_peer.closest(ray, cray, &mut stack);
                        black_box(g.complete(ray, best));
                    }
                });
            });
            let obvhs_rays: Vec<_> = rays.iter().map(ObvhsPeer::ray).collect();
            group.bench_function(id("obvhs-bvh2"), |b| {
                b.iter(|| {
                    for (ray, oray) in rays.iter().zip(&obvhs_rays) {
                        let ray = black_box(ray);
                        let best = obvhs_peer.closest(ray, *oray);
                        black_box(g.complete(ray, best));
                    }
                });
            });
        }
    }
    group.finish();
}

fn benches_all(c: &mut Criterion) {
    for name in SCENES {
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
