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
//! cornell-box, bunny, dabrovic-sponza; the meshes come from the assets directory, and a scene whose
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
//! Before the trace benchmarks of a scene run, every backend and peer built traces the ray
//! sets once, untimed, and the agreement of each with `bvh` (same primitive hit, or both
//! miss) is printed: `grid` and `packet` must agree on every ray, the peers on at least
//! 99.9% of the primary rays (those using raybench's triangle test differ only on ties and
//! the rare ray their box test wrongly rejects; Embree's own triangle test may also decide
//! an edge the other way), so the benchmark is known to compare like with like; `obvhs`,
//! an exact backend, gets a warning listing the rays where it differs at all.
//!
//! The filter decides what is prepared. The bench reads criterion's command line as
//! criterion does (the FILTER, a regular expression unless `--exact`; `--ignored`;
//! `--list`) and, from the benchmarks' names alone, loads a scene only when one of its
//! benchmarks is selected, builds only the backends and peers whose benchmarks are (and
//! `bvh` whenever a trace benchmark is: it derives the shadow, ao and diffuse rays and is
//! the reference of the check above), and checks only those. A filtered run thus pays for
//! what it times: `-- 'trace/(bvh|packet)/bunny/primary'` loads the bunny alone and builds
//! two structures. `--list` loads the selected scenes (a scene whose files are missing, a
//! peer that does not support a scene, have no benchmarks) but builds nothing.
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

/// Criterion's long options that take a value (`--name VALUE` or `--name=VALUE`), as
/// `Criterion::configure_from_args` (criterion 0.8) declares them: their values are not the
/// filter.
const VALUE_OPTIONS: [&str; 17] = [
    "--color",
    "--colour",
    "--save-baseline",
    "--baseline",
    "--baseline-lenient",
    "--format",
    "--profile-time",
    "--load-baseline",
    "--sample-size",
    "--warm-up-time",
    "--measurement-time",
    "--nresamples",
    "--noise-threshold",
    "--confidence-level",
    "--significance-level",
    "--plotting-backend",
    "--output-format",
];
/// The short forms among them (`-c`, `-s`, `-b`; the value follows in the same argument or
/// the next one).
const VALUE_SHORTS: [char; 3] = ['c', 's', 'b'];

/// Which benchmark ids criterion runs (or lists), read from the command line the way
/// `Criterion::configure_from_args` reads it: the positional FILTER, a regular expression
/// searched for in the id unless `--exact` asks for the whole id; none with `--ignored`.
///
/// Criterion parses the command line before any benchmark function runs (and exits on an
/// error), so the arguments seen here are valid ones.
struct Selection {
    filter: Filter,
    /// `--list`: criterion prints the selected ids and runs nothing.
    list: bool,
}

/// Criterion's `BenchmarkFilter`, the ids a [`Selection`] takes.
enum Filter {
    All,
    Regex(regex::Regex),
    Exact(String),
    Nothing,
}

impl Selection {
    /// The selection of `args` (the command line without the program name).
    ///
    /// # Panics
    /// When the filter is not a regular expression (criterion has refused it already).
    fn from_args(args: impl IntoIterator<Item = String>) -> Self {
        let (mut filter, mut exact, mut ignored, mut list) = (None, false, false, false);
        let mut args = args.into_iter();
        while let Some(arg) = args.next() {
            if arg == "--" {
                // Everything after `--` is positional.
                filter = filter.or(args.next());
                break;
            } else if let Some(long) = arg.strip_prefix("--") {
                match long {
                    "exact" => exact = true,
                    "ignored" => ignored = true,
                    "list" => list = true,
                    _ if VALUE_OPTIONS.contains(&arg.as_str()) => {
                        args.next();
                    }
                    _ => {}
                }
            } else if let Some(shorts) = arg.strip_prefix('-').filter(|s| !s.is_empty()) {
                // A cluster of short flags (`-vn`); a short option with a value ends it, and
                // takes the rest of the argument as its value or, when nothing is left, the
                // next argument.
                if shorts
                    .find(VALUE_SHORTS)
                    .is_some_and(|i| i + 1 == shorts.len())
                {
                    args.next();
                }
            } else {
                filter = filter.or(Some(arg));
            }
        }
        let filter = match filter {
            _ if ignored => Filter::Nothing,
            None => Filter::All,
            Some(f) if exact => Filter::Exact(f),
            Some(f) => Filter::Regex(
                regex::Regex::new(&f)
                    .unwrap_or_else(|e| panic!("cannot parse '{f}' as a regular expression: {e}")),
            ),
        };
        Self { filter, list }
    }

    /// Whether the benchmark `id` runs (or is listed).
    fn selects(&self, id: &str) -> bool {
        match &self.filter {
            Filter::All => true,
            Filter::Regex(r) => r.is_match(id),
            Filter::Exact(e) => id == e,
            Filter::Nothing => false,
        }
    }
}

/// The backends and peers with a build benchmark, `build/<backend>/<scene>`.
const BUILD_BENCHMARKS: [&str; 8] = [
    "bvh",
    "obvhs",
    "grid2",
    "packet",
    "grid",
    "bvh-crate",
    "embree",
    "obvhs-bvh2",
];
/// The backends and peers with trace benchmarks, `trace/<backend>/<scene>/<set>`
/// (`packet-single` on the primary rays only).
const TRACE_BENCHMARKS: [&str; 10] = [
    "bvh",
    "packet",
    "packet-single",
    "obvhs",
    "grid2",
    "grid",
    "bvh-crate",
    "embree",
    "embree-packet",
    "obvhs-bvh2",
];

/// What the selection takes of one scene's benchmarks, decided from their names before the
/// scene is loaded. (The Embree names are there without the feature too, and the
/// `obvhs-bvh2` ones on any scene: a name no benchmark has only costs a regex match.)
struct Plan {
    /// The backends whose build benchmark is selected.
    build: Vec<&'static str>,
    /// The backends with a selected trace benchmark.
    trace: Vec<&'static str>,
    /// The ray sets with a selected trace benchmark.
    sets: Vec<&'static str>,
    /// Criterion only lists them.
    list: bool,
}

impl Plan {
    fn new(selection: &Selection, scene: &str, sets: &[&'static str]) -> Self {
        let build = BUILD_BENCHMARKS
            .into_iter()
            .filter(|b| selection.selects(&format!("build/{b}/{scene}")))
            .collect();
        let (mut trace, mut traced_sets) = (Vec::new(), Vec::new());
        for b in TRACE_BENCHMARKS {
            for &s in sets {
                if (b != "packet-single" || s == "primary")
                    && selection.selects(&format!("trace/{b}/{scene}/{s}"))
                {
                    if !trace.contains(&b) {
                        trace.push(b);
                    }
                    if !traced_sets.contains(&s) {
                        traced_sets.push(s);
                    }
                }
            }
        }
        Self {
            build,
            trace,
            sets: traced_sets,
            list: selection.list,
        }
    }

    /// Nothing of the scene is selected: it is not even loaded.
    fn is_empty(&self) -> bool {
        self.build.is_empty() && self.trace.is_empty()
    }

    /// Trace benchmarks run: `bvh` is built.
    fn traces(&self) -> bool {
        !self.list && !self.trace.is_empty()
    }

    /// Trace benchmarks run on the ray set `set`: its rays are made.
    fn traces_set(&self, set: &str) -> bool {
        !self.list && self.sets.contains(&set)
    }

    /// Whether `backend` is built: one of its benchmarks runs, or it is `bvh` and trace
    /// benchmarks run (it derives the shadow, ao and diffuse rays, and is the reference of
    /// the agreement check). Listing builds nothing.
    fn builds(&self, backend: &str) -> bool {
        !self.list
            && (self.build.contains(&backend)
                || self.trace.contains(&backend)
                || (backend == "bvh" && self.traces()))
    }
}

/// The ray sets the trace benchmarks use: `RAYBENCH_RAY_SETS` (default
/// `primary,incoherent`; `all`), then `file` when `RAYBENCH_RAYS_FILE` is set. Their names
/// are known from the environment alone, before anything is built.
struct RaySets {
    sets: Vec<RaySet>,
    file: Option<std::ffi::OsString>,
}

/// A ray set's name, rays, and whether they ask for any hit.
type Rays = (&'static str, Vec<Ray>, bool);

impl RaySets {
    /// # Panics
    /// On an unknown set name (the message says which).
    fn from_env() -> Self {
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
        Self {
            sets: RaySet::ALL
                .into_iter()
                .filter(|s| wanted.contains(s))
                .collect(),
            file: std::env::var_os("RAYBENCH_RAYS_FILE"),
        }
    }

    fn names(&self) -> Vec<&'static str> {
        let file = self.file.as_ref().map(|_| "file");
        self.sets.iter().map(|s| s.name()).chain(file).collect()
    }

    /// Each set, with its rays on `scene` when `plan` traces it (the derived ones from
    /// `bvh`'s primary hits; `bvh` is built then), without them otherwise: such a set's
    /// benchmarks are registered with criterion (which lists them, or skips them) but never
    /// run. (Whether an unread ray file asks for any hit is not known; its benchmarks have
    /// the same names either way.)
    ///
    /// # Panics
    /// On a bad ray file (the message says why).
    fn make(&self, scene: &Scene, bvh: &Option<Bvh>, plan: &Plan) -> Vec<Rays> {
        let primary = ray_sets::primary_tiled(
            &scene.camera,
            PRIMARY_SIZE,
            PRIMARY_SIZE,
            raybench_render::TILE_SIZE,
        );
        let derives = self
            .sets
            .iter()
            .any(|s| s.is_derived() && plan.traces_set(s.name()));
        let primary_hits = if derives {
            batch(built(bvh), &primary)
        } else {
            Vec::new()
        };
        let mut sets: Vec<Rays> = self
            .sets
            .iter()
            .map(|&set| {
                let rays = match set {
                    _ if !plan.traces_set(set.name()) => Vec::new(),
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
        if let Some(path) = &self.file {
            sets.push(if plan.traces_set("file") {
                let file = raybench_registry::rays_file::read(std::path::Path::new(path))
                    .unwrap_or_else(|e| panic!("RAYBENCH_RAYS_FILE: {e}"));
                ("file", file.rays, file.any_hit)
            } else {
                ("file", Vec::new(), false)
            });
        }
        sets
    }
}

/// A scene with its ray sets and the structures its selected benchmarks need, built once.
///
/// Every benchmark the scene supports is registered with criterion, which runs (or lists)
/// the selected ones only; a structure is `None` when none of its benchmarks is selected,
/// and a set's rays are empty when none of its trace benchmarks is.
struct Prepared {
    name: &'static str,
    scene: Scene,
    ray_sets: Vec<Rays>,
    /// The triangles when the scene has nothing else (the obvhs-bvh2 peer needs them).
    tris: Option<Vec<Triangle>>,
    bvh: Option<Bvh>,
    obvhs: Option<ObvhsAccel>,
    grid: Option<Grid>,
    grid2: Option<TwoLevelGrid>,
    packet: Option<PacketAccel>,
    /// `packet` without packets: every ray alone through the same BVH8 (what packets buy).
    packet_single: Option<PacketAccel>,
    bvh_crate: Option<BvhCrateAccel>,
    /// obvhs's BVH2 and its traversal ([`raybench_tests::obvhs_peer`]).
    obvhs_peer: Option<ObvhsPeer<Bvh2>>,
    /// Whether Embree supports the scene (its benchmarks exist).
    #[cfg(feature = "embree")]
    embree_supported: bool,
    /// Embree with single rays.
    #[cfg(feature = "embree")]
    embree: Option<EmbreeAccel>,
    /// Embree with 16-ray packets.
    #[cfg(feature = "embree")]
    embree_packet: Option<EmbreePacketAccel>,
    /// One untimed build of each backend built, to size the build benchmarks' measurement
    /// time.
    build_times: Vec<(&'static str, Duration)>,
}

/// The structure of a benchmark that runs: [`prepare`] built it, since the selection that
/// criterion applies is the one [`Plan`] read.
fn built<T>(structure: &Option<T>) -> &T {
    structure
        .as_ref()
        .expect("a selected benchmark's structure is built")
}

fn timed<T>(f: impl FnOnce() -> T) -> (T, Duration) {
    let start = Instant::now();
    let out = f();
    (out, start.elapsed())
}

/// The untimed builds of one scene: those its plan asks for, each timed.
struct Builds<'a> {
    plan: &'a Plan,
    times: Vec<(&'static str, Duration)>,
}

impl Builds<'_> {
    /// `backend` built by `f` when the plan builds it.
    fn build<T>(&mut self, backend: &'static str, f: impl FnOnce() -> T) -> Option<T> {
        if !self.plan.builds(backend) {
            return None;
        }
        let (built, t) = timed(f);
        self.times.push((backend, t));
        Some(built)
    }
}

fn prepare(name: &'static str, plan: &Plan, sets: &RaySets) -> Option<Prepared> {
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
    let mut builds = Builds {
        plan,
        times: Vec::new(),
    };
    let bvh = builds.build("bvh", || Bvh::build_with(g.clone(), BvhParams::default()));
    let ray_sets = sets.make(&scene, &bvh, plan);
    let obvhs = builds.build("obvhs", || ObvhsAccel::build(g.clone()));
    let grid = builds.build("grid", || {
        Grid::build_with(g.clone(), GridParams::default())
    });
    let grid2 = builds.build("grid2", || {
        TwoLevelGrid::build_with(g.clone(), TwoLevelParams::default())
    });
    let packet = builds.build("packet", || {
        PacketAccel::build_with(g.clone(), PacketParams::default())
    });
    let packet_single = builds.build("packet-single", || {
        PacketAccel::build_with(
            g.clone(),
            PacketParams {
                packets: false,
                ..PacketParams::default()
            },
        )
    });
    let tris = triangles(&g);
    if tris.is_none() {
        eprintln!("scene {name} has non-triangle primitives: skipping the obvhs-bvh2 peer");
    }
    let bvh_crate = builds.build("bvh-crate", || BvhCrateAccel::build(g.clone()));
    let obvhs_peer = tris
        .as_ref()
        .and_then(|_| builds.build("obvhs-bvh2", || ObvhsPeer::build(g.clone())));
    #[cfg(feature = "embree")]
    let embree_supported = match raybench_peers::embree_availability()
        .and_then(|()| raybench_peers::embree_supports(&scene.geometry))
    {
        Ok(()) => true,
        Err(e) => {
            eprintln!("scene {name}: skipping Embree: {e}");
            false
        }
    };
    // The device is created by the first build (untimed, here) and shared afterwards.
    #[cfg(feature = "embree")]
    let (embree, embree_packet) = if embree_supported {
        (
            builds.build("embree", || EmbreeAccel::build(g.clone())),
            builds.build("embree-packet", || EmbreePacketAccel::build(g.clone())),
        )
    } else {
        (None, None)
    };
    if !builds.times.is_empty() {
        let notes = packet
            .as_ref()
            .or(packet_single.as_ref())
            .map(|p| format!("; packet ISA {}", p.params().isa))
            .unwrap_or_default();
        #[cfg(feature = "embree")]
        let notes = if embree.is_some() || embree_packet.is_some() {
            let version = raybench_peers::embree_version().unwrap_or_default();
            format!("{notes}; {version}")
        } else {
            notes
        };
        let times: Vec<String> = builds
            .times
            .iter()
            .map(|(backend, t)| format!("{backend} {t:.2?}"))
            .collect();
        eprintln!(
            "scene {name}: {} primitives; untimed builds: {}{notes}",
            g.len(),
            times.join(", ")
        );
    }
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
        embree_supported,
        #[cfg(feature = "embree")]
        embree,
        #[cfg(feature = "embree")]
        embree_packet,
        build_times: builds.times,
    })
}

/// Checks, outside any timing, that every backend and peer built finds the same primitives
/// as `bvh` (all of them on `obvhs`, `grid` and `packet`, at least [`MIN_AGREEMENT`] of the
/// primary rays on the peers; ties may legitimately go another way there), and prints the
/// agreement, on the ray sets that `plan` traces (`bvh` is built then).
fn check_agreement(p: &Prepared, plan: &Plan) {
    for (set, rays, _) in p.ray_sets.iter().filter(|(s, ..)| plan.traces_set(s)) {
        let bvh = built(&p.bvh);
        let reference: Vec<Option<(u32, f32)>> = rays
            .iter()
            .map(|r| bvh.intersect(r, &mut NoCounters).map(|h| (h.prim, h.t)))
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
        // Through the batch entry point.
        let agree_batch = |hits: Vec<Option<raybench_core::Hit>>| {
            agree(&mut hits.into_iter().map(|h| h.map(|h| (h.prim, h.t))))
        };
        let mut results = Vec::new();
        if let Some(obvhs) = &p.obvhs {
            results.push((
                "obvhs",
                agree(
                    &mut rays
                        .iter()
                        .map(|r| obvhs.intersect(r, &mut NoCounters).map(|h| (h.prim, h.t))),
                ),
            ));
        }
        if let Some(grid) = &p.grid {
            results.push((
                "grid",
                agree(
                    &mut rays
                        .iter()
                        .map(|r| grid.intersect(r, &mut NoCounters).map(|h| (h.prim, h.t))),
                ),
            ));
        }
        if let Some(packet) = &p.packet {
            results.push(("packet", agree_batch(batch(packet, rays))));
        }
        if let Some(bvh_crate) = &p.bvh_crate {
            results.push(("bvh-crate", agree_batch(batch(bvh_crate, rays))));
        }
        #[cfg(feature = "embree")]
        if let Some(single) = &p.embree {
            results.push(("embree", agree_batch(batch(single, rays))));
        }
        #[cfg(feature = "embree")]
        if let Some(packets) = &p.embree_packet {
            results.push(("embree-packet", agree_batch(batch(packets, rays))));
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
            if line.is_empty() {
                "no other backend built".to_owned()
            } else {
                line.join(", ")
            }
        );
        for (backend, (a, t)) in &results {
            match *backend {
                // `obvhs` is an exact backend: the equivalence tests demand bit-identical
                // hits, so a difference here is a bug to report, not a reason to stop
                // measuring.
                "obvhs" if *a < 1.0 => {
                    let obvhs = built(&p.obvhs);
                    let diffs = rays.iter().enumerate().filter_map(|(i, r)| {
                        let a = bvh.intersect(r, &mut NoCounters);
                        let b = obvhs.intersect(r, &mut NoCounters);
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
                "obvhs" => {}
                "grid" | "packet" => {
                    assert_eq!(*a, 1.0, "{backend}, an exact backend, differs from bvh");
                }
                _ if *set == "primary" => assert!(
                    *t >= MIN_AGREEMENT,
                    "{backend} agrees with bvh on only {:.3}% of the {} primary rays (ties counted)",
                    100.0 * t,
                    p.name
                ),
                _ => {}
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

type Group<'a> = criterion::BenchmarkGroup<'a, criterion::measurement::WallTime>;

fn bench_build(c: &mut Criterion, p: &Prepared) {
    let mut group = c.benchmark_group("build");
    // Builds take milliseconds to a second: a fixed iteration count per sample, and a
    // measurement time that fits the 10 samples. (A backend not built here has no
    // benchmark selected: its measurement time does not matter.)
    group.sampling_mode(SamplingMode::Flat);
    let target = |backend: &str| {
        let t = p
            .build_times
            .iter()
            .find(|(b, _)| *b == backend)
            .map_or(Duration::ZERO, |(_, t)| *t);
        (t * 15).max(Duration::from_secs(2))
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
    if p.embree_supported {
        // Embree's device exists already (the untimed build made it): this times the copy
        // of the triangles into Embree's buffers and its BVH build.
        group.measurement_time(target("embree"));
        group.bench_function(BenchmarkId::new("embree", p.name), |b| {
            b.iter_with_large_drop(|| EmbreeAccel::build(black_box(g.clone())));
        });
    }
    if let Some(tris) = &p.tris {
        // The peer's input in its own format, prepared outside the timing (when the peer is
        // built, i.e. one of its benchmarks runs).
        let otris = p
            .obvhs_peer
            .as_ref()
            .map(|_| ObvhsPeer::<Bvh2>::obvhs_tris(tris));
        group.measurement_time(target("obvhs-bvh2"));
        group.bench_function(BenchmarkId::new("obvhs-bvh2", p.name), |b| {
            let otris = built(&otris);
            b.iter_with_large_drop(|| Bvh2::build_tree(black_box(otris)));
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
        let g = &mut group;
        bench_closest(g, id("bvh"), &p.bvh, rays, &mut hits);
        bench_closest(g, id("packet"), &p.packet, rays, &mut hits);
        if *set == "primary" {
            bench_closest(g, id("packet-single"), &p.packet_single, rays, &mut hits);
        }
        bench_closest(g, id("obvhs"), &p.obvhs, rays, &mut hits);
        bench_closest(g, id("grid2"), &p.grid2, rays, &mut hits);
        bench_closest(g, id("grid"), &p.grid, rays, &mut hits);
        bench_closest(g, id("bvh-crate"), &p.bvh_crate, rays, &mut hits);
        #[cfg(feature = "embree")]
        if p.embree_supported {
            bench_closest(g, id("embree"), &p.embree, rays, &mut hits);
            bench_closest(g, id("embree-packet"), &p.embree_packet, rays, &mut hits);
        }
        if p.tris.is_some() {
            let geometry = &*p.scene.geometry;
            // The peer's own ray type, like raybench's rays, is made outside the timing.
            // Its hits are completed like the backends' (normal, barycentrics).
            let obvhs_rays: Vec<_> = rays.iter().map(ObvhsPeer::<Bvh2>::ray).collect();
            group.bench_function(id("obvhs-bvh2"), |b| {
                let obvhs_peer = built(&p.obvhs_peer);
                b.iter(|| {
                    for (ray, oray) in rays.iter().zip(&obvhs_rays) {
                        let ray = black_box(ray);
                        let best = obvhs_peer.closest(ray, *oray, None);
                        black_box(geometry.complete(ray, best));
                    }
                });
            });
        }
    }
    group.finish();
}

/// Registers the closest-hit benchmark `id`: `accel` through [`Accel::intersect_batch`]
/// in batches of [`BATCH`] rays.
fn bench_closest<A: Accel>(
    group: &mut Group<'_>,
    id: BenchmarkId,
    accel: &Option<A>,
    rays: &[Ray],
    hits: &mut [Option<raybench_core::Hit>],
) {
    group.bench_function(id, |b| {
        let accel = built(accel);
        b.iter(|| trace(accel, black_box(rays), hits));
    });
}

/// The any-hit benchmarks of one ray set: every backend and peer through
/// [`Accel::occluded_batch`] in batches of [`BATCH`] rays.
fn bench_occlusion(
    group: &mut Group<'_>,
    p: &Prepared,
    rays: &[Ray],
    id: &dyn Fn(&str) -> BenchmarkId,
) {
    let mut occluded = vec![false; rays.len()];
    let o = &mut occluded;
    bench_any_hit(group, id("bvh"), &p.bvh, rays, o);
    bench_any_hit(group, id("packet"), &p.packet, rays, o);
    bench_any_hit(group, id("obvhs"), &p.obvhs, rays, o);
    bench_any_hit(group, id("grid2"), &p.grid2, rays, o);
    bench_any_hit(group, id("grid"), &p.grid, rays, o);
    bench_any_hit(group, id("bvh-crate"), &p.bvh_crate, rays, o);
    #[cfg(feature = "embree")]
    if p.embree_supported {
        bench_any_hit(group, id("embree"), &p.embree, rays, o);
        bench_any_hit(group, id("embree-packet"), &p.embree_packet, rays, o);
    }
    if p.tris.is_some() {
        bench_any_hit(group, id("obvhs-bvh2"), &p.obvhs_peer, rays, o);
    }
}

/// Registers the any-hit benchmark `id`: `accel` through [`Accel::occluded_batch`] in
/// batches of [`BATCH`] rays.
fn bench_any_hit<A: Accel>(
    group: &mut Group<'_>,
    id: BenchmarkId,
    accel: &Option<A>,
    rays: &[Ray],
    occluded: &mut [bool],
) {
    group.bench_function(id, |b| {
        let accel = built(accel);
        b.iter(|| {
            for (r, o) in black_box(rays)
                .chunks(BATCH)
                .zip(occluded.chunks_mut(BATCH))
            {
                accel.occluded_batch(r, o, &mut NoCounters);
            }
            black_box(&occluded);
        });
    });
}

fn benches_all(c: &mut Criterion) {
    let selection = Selection::from_args(std::env::args().skip(1));
    let sets = RaySets::from_env();
    let names = sets.names();
    // The phantom is a volume without primitives: its integration is benched in
    // `benches/grids.rs`.
    let quick = raybench_report::matrix_scenes(true);
    let scenes = quick
        .iter()
        .filter(|&&n| n != "phantom")
        .chain(&EXTRA_SCENES);
    for &name in scenes {
        let plan = Plan::new(&selection, name, &names);
        if plan.is_empty() {
            continue;
        }
        let Some(p) = prepare(name, &plan, &sets) else {
            continue;
        };
        check_agreement(&p, &plan);
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
