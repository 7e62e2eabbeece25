//! # raybench-tests
//!
//! Shared helpers of the cross-backend tests in `tests/tests/`: loading scenes (skipping, or
//! failing under `CI=true`, when the shared meshes are absent), rendering with a backend by
//! name, and [`check`], the one data-driven comparison against the naive oracle; and the
//! benchmarks' shared parts: obvhs's own trees as peers ([`obvhs_peer`]) and the peer
//! benchmark's workload, measurement and results ([`peers`], run by `benches/peers.rs`).

pub mod obvhs_peer;
pub mod peers;

use raybench_core::{Frame, Hit, NO_HIT, Ray, RenderSettings, Renderer, Scene, TriangleMesh, Vec3};
use std::sync::Arc;

use raybench_registry::Roles;

/// The number of exact backends in the registry.
const EXACT_COUNT: usize = raybench_registry::count_with(Roles::EXACT);
/// Their names, read from the registry at compile time.
const EXACT_NAMES: [&str; EXACT_COUNT] = raybench_registry::names_with(Roles::EXACT);

/// Every backend bound by the bit-exact contract ([`Roles::EXACT`] in `raybench_registry::BACKENDS`),
/// the oracle first (the reference): the suites that compare backends with the oracle or
/// with themselves run each of these that this machine can run ([`available`]). A new
/// backend registered as exact joins them by itself.
pub const EXACT_BACKENDS: &[&str] = &EXACT_NAMES;

/// The oracle every exact backend is compared with (naive: [`Roles::ORACLE`]).
pub const ORACLE: &str = raybench_registry::name_with(Roles::ORACLE);

/// The baseline structure (the BVH: [`Roles::BASELINE`]), for tests that need one fast
/// exact backend rather than every one.
pub const BASELINE: &str = raybench_registry::name_with(Roles::BASELINE);

/// The most primitives (flattened) of a scene that the oracle's checks run on: 64 x 64
/// camera rays over 2^21 primitives are already 8.6 billion naive tests. The larger built-in
/// scenes (tens of millions of instanced triangles) are checked against [`BASELINE`]
/// instead (`tests/tests/instances.rs`).
pub const ORACLE_PRIMITIVES: usize = 1 << 21;

/// The backend on another device (the GPU: [`Roles::DEVICE`]), the first of [`DEVICES`].
pub const DEVICE: &str = raybench_registry::name_with(Roles::DEVICE);

/// Every backend on another device (the GPU kernels over each tree), from the registry's
/// roles: the GPU suites check each.
pub const DEVICES: [&str; raybench_registry::count_with(Roles::DEVICE)] =
    raybench_registry::names_with(Roles::DEVICE);

/// The number of exact backends but the oracle.
const ACCELERATED_COUNT: usize = EXACT_COUNT - raybench_registry::count_with(Roles::ORACLE);

/// The exact backends but the oracle (pinned variants included: each machine runs those it
/// can, through [`available`]): the suites that compare each with the oracle.
pub const ACCELERATED_BACKENDS: &[&str] = &accelerated();

/// [`ACCELERATED_BACKENDS`], at compile time.
const fn accelerated() -> [&'static str; ACCELERATED_COUNT] {
    let mut out = [""; ACCELERATED_COUNT];
    let (mut i, mut n) = (0, 0);
    while i < EXACT_COUNT {
        if !raybench_registry::backend_is(EXACT_NAMES[i], Roles::ORACLE) {
            out[n] = EXACT_NAMES[i];
            n += 1;
        }
        i += 1;
    }
    out
}

/// True under `CI=true`, where every asset is installed and skipping is failing.
#[must_use]
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true")
}

/// Loads `spec` (built-in name, generator or file). When its meshes are absent, prints why
/// and returns `None` (the caller skips), except under `CI=true`, where it panics.
///
/// # Panics
/// On any other loading error, and on a missing asset under `CI=true`.
#[must_use]
pub fn load_or_skip(spec: &str) -> Option<Arc<Scene>> {
    let assets = raybench_scene::assets_dir(None);
    match raybench_scene::load(spec, &assets) {
        Ok(s) => Some(Arc::new(s)),
        Err(e) if e.is_missing_asset() => {
            assert!(!in_ci(), "CI=true but an asset is missing: {e}");
            eprintln!("SKIPPED {spec}: {e}");
            None
        }
        Err(e) => panic!("cannot load {spec}: {e}"),
    }
}

/// The backends of `names` that can run on this machine; the others (a pinned instruction
/// set this CPU lacks) are left out with a message. Unknown names panic.
///
/// # Panics
/// When a name is not a registered backend.
#[must_use]
pub fn available<'a>(names: &[&'a str]) -> Vec<&'a str> {
    names
        .iter()
        .copied()
        .filter(|name| {
            let b = raybench_registry::backend(name).unwrap();
            match (b.make)().availability() {
                Ok(()) => true,
                Err(e) => {
                    eprintln!("SKIPPED backend {name}: {e}");
                    false
                }
            }
        })
        .collect()
}

/// A prepared renderer of the backend called `name`.
///
/// # Panics
/// When the backend is unknown, unavailable or does not support the scene.
#[must_use]
pub fn prepared(name: &str, scene: &Arc<Scene>) -> Box<dyn Renderer> {
    let b = raybench_registry::backend(name).unwrap();
    let mut r = (b.make)();
    r.availability()
        .unwrap_or_else(|e| panic!("{name} unavailable: {e}"));
    r.prepare(scene).unwrap();
    r
}

/// Renders `scene` with a fresh renderer of backend `name` on a pool of `threads` threads.
///
/// # Panics
/// As [`prepared`], or when rendering fails.
#[must_use]
pub fn render_with(
    name: &str,
    scene: &Arc<Scene>,
    settings: &RenderSettings,
    threads: usize,
) -> Frame {
    render_in_pool(prepared(name, scene).as_ref(), settings, threads)
}

/// Renders with the prepared renderer `r` on a pool of `threads` threads.
///
/// # Panics
/// When rendering fails.
#[must_use]
pub fn render_in_pool(r: &dyn Renderer, settings: &RenderSettings, threads: usize) -> Frame {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| r.render(settings).unwrap())
}

/// White furnace: renders `scene` (diffuse objects of albedo 1 under a uniform background of
/// radiance 1) with path tracing in `bvh` and asserts that the mean radiance is 1 within
/// five standard errors, and that some pixels hit an object. Paths that leak into objects or
/// are caught by the surface they leave use up the depth (64) and darken the mean.
///
/// # Panics
/// When the mean is off, or nothing is hit.
pub fn assert_white_furnace(scene: &Arc<Scene>) {
    let settings = RenderSettings {
        width: 40,
        height: 40,
        spp: 16,
        mode: raybench_core::Mode::Path,
        max_depth: 64,
        seed: 5,
        count: false,
        ..RenderSettings::default()
    };
    let frame = render_with(BASELINE, scene, &settings, 2);
    let n = frame.color.len() as f64;
    let mean = frame.color.iter().map(|c| f64::from(c.x)).sum::<f64>() / n;
    let var = frame
        .color
        .iter()
        .map(|c| (f64::from(c.x) - mean).powi(2))
        .sum::<f64>()
        / (n - 1.0);
    let err = (var / n).sqrt();
    assert!(
        (mean - 1.0).abs() < 5.0 * err + 1e-4,
        "mean {mean} +- {err}"
    );
    assert!(frame.ids.iter().any(|&id| id != NO_HIT));
}

/// Asserts that two frames have bit-identical primitive ids and `t`, naming the first
/// differing pixel.
///
/// # Panics
/// When they differ.
pub fn assert_same_hits(what: &str, reference: &Frame, frame: &Frame) {
    assert_eq!(reference.ids.len(), frame.ids.len(), "{what}: sizes differ");
    for i in 0..reference.ids.len() {
        let (a, b) = (reference.ids[i], frame.ids[i]);
        let (ta, tb) = (reference.t[i], frame.t[i]);
        assert!(
            a == b && ta.to_bits() == tb.to_bits(),
            "{what}: pixel ({}, {}) naive id {a} t {ta:e}, backend id {b} t {tb:e}",
            i as u32 % reference.width,
            i as u32 / reference.width,
        );
    }
}

/// Asserts that two hit lists (of [`Renderer::trace_rays`]) agree bit for bit.
///
/// # Panics
/// When they differ.
pub fn assert_same_ray_hits(what: &str, reference: &[Option<Hit>], hits: &[Option<Hit>]) {
    assert_eq!(reference.len(), hits.len());
    for (i, (a, b)) in reference.iter().zip(hits).enumerate() {
        let key = |h: &Option<Hit>| h.map_or((NO_HIT, 0), |h| (h.prim, h.t.to_bits()));
        assert_eq!(key(a), key(b), "{what}: ray {i}: naive {a:?} backend {b:?}");
    }
}

/// The one equivalence check: renders `scene` with naive on one thread (the reference) and
/// with each of `backends` on several threads, and asserts bit-identical ids and `t`; then
/// the same for `size * size` seeded incoherent rays (origins inside the scene's box, so
/// many start inside nodes and next to surfaces), and for the derived sets of a
/// `size / 2` square image (`check_derived`: shadow, ambient-occlusion and diffuse rays).
/// Also asserts naive's exact counter (`rays * M` closest-hit tests). Skips (or fails under
/// CI) when the scene's meshes are absent. Each backend's structure is built once and used
/// for every thread count and ray set (its builds are deterministic: `determinism.rs`).
///
/// # Panics
/// When any backend differs from the reference.
pub fn check(backends: &[&str], scene: &str, size: u32) {
    if let Some(scene_data) = load_or_skip(scene) {
        check_loaded(backends, scene, &scene_data, size);
    }
}

/// [`check`] on `scene_data`, already loaded (named `scene` in messages).
///
/// # Panics
/// When any backend differs from the reference.
pub fn check_loaded(backends: &[&str], scene: &str, scene_data: &Arc<Scene>, size: u32) {
    let settings = RenderSettings {
        width: size,
        height: size,
        count: true,
        ..RenderSettings::default()
    };
    let oracle = prepared(ORACLE, scene_data);
    let mut renderers: Vec<(&str, Box<dyn Renderer>)> = backends
        .iter()
        .map(|&name| (name, prepared(name, scene_data)))
        .collect();
    let reference = render_in_pool(oracle.as_ref(), &settings, 1);
    let m = scene_data.geometry.total_len() as u64;
    assert_eq!(reference.stats.rays, u64::from(size * size));
    assert_eq!(
        reference.stats.counters.unwrap().prim_tests,
        reference.stats.rays * m,
        "naive must test every primitive for every ray"
    );
    for (name, r) in &renderers {
        for threads in [2, 3] {
            let frame = render_in_pool(r.as_ref(), &settings, threads);
            assert_same_hits(
                &format!("{name} on {scene} ({threads} threads)"),
                &reference,
                &frame,
            );
            assert_eq!(
                frame.color, reference.color,
                "{name} on {scene}: colours differ"
            );
        }
    }
    let rays = raybench_core::ray_sets::incoherent(
        scene_data.geometry.world_bounds(),
        (size * size) as usize,
        1,
    );
    let (reference_rays, _) = oracle.trace_rays(&rays, false).unwrap();
    // Naive among `backends` checks its thread-count independence on the frames above; its
    // explicit rays would be the reference's own computation again.
    renderers.retain(|(name, _)| *name != ORACLE);
    for (name, r) in &renderers {
        let (hits, _) = r.trace_rays(&rays, false).unwrap();
        assert_same_ray_hits(
            &format!("{name} on {scene}, incoherent rays"),
            &reference_rays,
            &hits,
        );
    }
    check_derived(
        oracle.as_ref(),
        &renderers,
        scene,
        scene_data,
        (size / 2).max(1),
    );
}

/// A ray's stored fields as bits (rays compare so even where a cached value is NaN).
fn ray_bits(r: &Ray) -> ([u32; 3], [u32; 3], u32, u32) {
    (
        r.origin.to_array().map(f32::to_bits),
        r.dir.to_array().map(f32::to_bits),
        r.t_min.to_bits(),
        r.t_max.to_bits(),
    )
}

/// The derived ray sets (`shadow`, `ao`, `diffuse`: [`ray_sets::derived`]) of a
/// `size x size` image of `scene`: generated from naive's primary hits (tile order), the
/// same rays, bit for bit, when generated from each backend's own primary hits; then the
/// closest-hit set traced with bit-identical ids and `t`, and the any-hit sets answered
/// with the same booleans, by every backend (naive's any hits being its closest hits'
/// `is_some`). Counters: naive's closest-hit tests are exactly `rays x M`. `oracle` is
/// naive prepared on `scene_data`, `renderers` each backend's, by name.
///
/// # Panics
/// When a backend differs from the reference.
fn check_derived(
    oracle: &dyn Renderer,
    renderers: &[(&str, Box<dyn Renderer>)],
    scene: &str,
    scene_data: &Arc<Scene>,
    size: u32,
) {
    use raybench_core::ray_sets::{self, DerivedParams};
    let settings = RenderSettings {
        width: size,
        height: size,
        ..RenderSettings::default()
    };
    let camera = scene_data.view(&settings).expect("the scene's camera");
    let primary = ray_sets::primary_tiled(camera, size, size, raybench_render::TILE_SIZE);
    let params = DerivedParams::default();
    let derived_sets: Vec<raybench_core::RaySet> = raybench_core::RaySet::ALL
        .into_iter()
        .filter(|s| s.is_derived())
        .collect();
    let (primary_hits, _) = oracle.trace_rays(&primary, false).unwrap();
    let m = scene_data.geometry.total_len() as u64;
    let mut reference = Vec::new();
    for &set in &derived_sets {
        let rays = ray_sets::derived(set, scene_data, &primary, &primary_hits, &params)
            .unwrap_or_else(|e| panic!("{scene}, {} rays: {e}", set.name()));
        let (closest, counters) = oracle.trace_rays(&rays, true).unwrap();
        assert_eq!(
            counters.unwrap().prim_tests,
            rays.len() as u64 * m,
            "naive must test every primitive for every {} ray",
            set.name()
        );
        let (occluded, _) = oracle.occlude_rays(&rays, true).unwrap();
        let blocked: Vec<bool> = closest.iter().map(Option::is_some).collect();
        assert_eq!(
            occluded,
            blocked,
            "{scene}: naive's any hits, {} rays",
            set.name()
        );
        reference.push((set, rays, closest, occluded));
    }
    for (name, r) in renderers {
        let (hits, _) = r.trace_rays(&primary, false).unwrap();
        for (set, rays, closest, occluded) in &reference {
            let what = format!("{name} on {scene}, {} rays", set.name());
            let own = ray_sets::derived(*set, scene_data, &primary, &hits, &params).unwrap();
            assert!(
                own.len() == rays.len()
                    && own
                        .iter()
                        .zip(rays)
                        .all(|(a, b)| ray_bits(a) == ray_bits(b)),
                "{what}: generated from {name}'s primary hits, the set differs"
            );
            if set.any_hit() {
                let (answers, _) = r.occlude_rays(rays, false).unwrap();
                if let Some(i) = (0..rays.len()).find(|&i| answers[i] != occluded[i]) {
                    panic!(
                        "{what}: ray {i}: naive occluded {}, backend {}",
                        occluded[i], answers[i]
                    );
                }
            } else {
                let (answers, _) = r.trace_rays(rays, false).unwrap();
                assert_same_ray_hits(&what, closest, &answers);
            }
        }
    }
}

/// A scene with no primitives and the background `[0.25, 0.5, 0.75]`, built directly:
/// scene files refuse an empty scene (nothing to render), but every backend must still
/// handle one.
///
/// # Panics
/// Never (the background is finite).
#[must_use]
pub fn empty_scene() -> Arc<Scene> {
    let mut b = raybench_core::SceneBuilder::new("empty");
    b.background(raybench_core::Vec3::new(0.25, 0.5, 0.75))
        .expect("a finite background");
    Arc::new(b.build())
}

/// The settings of the mode tests: `size x size`, 4 bounces, seed 7, not counted.
#[must_use]
pub fn mode_settings(size: u32, mode: raybench_core::Mode, spp: u32) -> RenderSettings {
    RenderSettings {
        width: size,
        height: size,
        spp,
        mode,
        max_depth: 4,
        seed: 7,
        count: false,
        ..RenderSettings::default()
    }
}

/// The equivalence check for the integrators with secondary rays: Whitted (4 bounces) and
/// path tracing (2 samples, 4 bounces) at `size x size` must give bit-identical colours, ids
/// and `t` with every backend and thread count. Meant for scenes small enough for naive.
///
/// # Panics
/// When any backend differs from the reference.
pub fn check_modes(backends: &[&str], scene: &str, size: u32) {
    if let Some(scene_data) = load_or_skip(scene) {
        check_modes_loaded(backends, scene, &scene_data, size);
    }
}

/// [`check_modes`] on `scene_data`, already loaded (named `scene` in messages).
///
/// # Panics
/// When any backend differs from the reference.
pub fn check_modes_loaded(backends: &[&str], scene: &str, scene_data: &Arc<Scene>, size: u32) {
    // Each structure built once, for both modes and every thread count.
    let oracle = prepared(ORACLE, scene_data);
    let renderers: Vec<(&str, Box<dyn Renderer>)> = backends
        .iter()
        .map(|&name| (name, prepared(name, scene_data)))
        .collect();
    for (mode, spp) in [
        (raybench_core::Mode::Whitted, 1),
        (raybench_core::Mode::Path, 2),
    ] {
        let settings = mode_settings(size, mode, spp);
        let reference = render_in_pool(oracle.as_ref(), &settings, 1);
        for (name, r) in &renderers {
            for threads in [2, 3] {
                let frame = render_in_pool(r.as_ref(), &settings, threads);
                let what = format!("{name} on {scene}, {} ({threads} threads)", mode.name());
                assert_same_hits(&what, &reference, &frame);
                assert_eq!(
                    frame.stats.rays, reference.stats.rays,
                    "{what}: ray counts differ"
                );
                for (i, (a, b)) in reference.color.iter().zip(&frame.color).enumerate() {
                    assert!(
                        a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits),
                        "{what}: pixel {i} colour {a} vs {b}"
                    );
                }
            }
        }
    }
}

/// A mesh of separate triangles (no shared vertices), in the given order.
#[must_use]
pub fn triangles(tris: &[[Vec3; 3]]) -> TriangleMesh {
    TriangleMesh {
        positions: tris.iter().flatten().copied().collect(),
        indices: (0..tris.len() as u32)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect(),
    }
}

/// The cube `[-1, 1]^3` with each face split into `n x n` quads of two triangles, the
/// vertices shared between neighbouring triangles and faces (a closed, watertight mesh).
#[must_use]
pub fn cube_mesh(n: u32) -> TriangleMesh {
    let mut positions = Vec::new();
    let mut index = std::collections::HashMap::new();
    let mut vertex = |p: Vec3| -> u32 {
        let key = p.to_array().map(f32::to_bits);
        *index.entry(key).or_insert_with(|| {
            positions.push(p);
            positions.len() as u32 - 1
        })
    };
    let mut indices = Vec::new();
    let coordinate = |i: u32| -1.0 + 2.0 * i as f32 / n as f32;
    for axis in 0..3 {
        for side in [-1.0f32, 1.0] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let point = |i: u32, j: u32| {
                let mut p = Vec3::ZERO;
                p[axis] = side;
                p[u] = coordinate(i);
                p[v] = coordinate(j);
                p
            };
            for i in 0..n {
                for j in 0..n {
                    let q = [
                        vertex(point(i, j)),
                        vertex(point(i + 1, j)),
                        vertex(point(i + 1, j + 1)),
                        vertex(point(i, j + 1)),
                    ];
                    // Outward winding on both sides.
                    if side > 0.0 {
                        indices.push([q[0], q[1], q[2]]);
                        indices.push([q[0], q[2], q[3]]);
                    } else {
                        indices.push([q[0], q[2], q[1]]);
                        indices.push([q[0], q[3], q[2]]);
                    }
                }
            }
        }
    }
    TriangleMesh { positions, indices }
}

/// The octant of a ray's direction as the packet backends group rays (bit `a` set when the
/// inverse direction along axis `a` is negative).
#[must_use]
pub fn octant(r: &Ray) -> u8 {
    let s = r.inv_dir;
    u8::from(s.x < 0.0) | u8::from(s.y < 0.0) << 1 | u8::from(s.z < 0.0) << 2
}

/// `rays` sorted by [`octant`] (stably), so that consecutive rays form full coherent packets
/// in the packet backends (which trace runs of `packet_size` rays of one octant as packets).
#[must_use]
pub fn packed(rays: &[Ray]) -> Vec<Ray> {
    let mut sorted = rays.to_vec();
    sorted.sort_by_key(octant);
    sorted
}

/// The GPU's tolerances against the naive oracle. The GPU cannot be bit-exact: WGSL's
/// division and square root are not correctly rounded on Vulkan (2.5 ULP and about 1 ULP,
/// bounded by lavapipe on Vulkan), drivers may fuse `a * b + c`, and the triangle test has
/// no double-precision retry. A hit's `t` is a quotient of sums of such products, so its
/// relative error stays within a few hundred ULPs (1e-5); ids differ only on rays within
/// that rounding of an edge or of a second surface.
pub mod gpu {
    use super::{in_ci, load_or_skip, prepared};
    use raybench_core::{Frame, Mode, Vec3};
    use std::sync::Arc;

    /// Least fraction of pixels (or rays) whose primitive id equals naive's, counting ties
    /// (another primitive at the same distance within `raybench_registry::TIE_TOLERANCE`: coincident
    /// faces, such as the Cornell box's, which rounding may decide either way) as equal.
    pub const MIN_ID_MATCH: f64 = 0.999;
    /// Largest relative difference of `t` where the ids agree.
    pub const MAX_REL_DT: f64 = 1e-4;
    /// Largest fraction of pixels whose colour differs from the CPU's by more than
    /// [`COLOR_EPS`] in some channel, in ray casting and Whitted ray tracing: a ray that
    /// takes another branch (another primitive at a tie) changes its pixel wholly. About
    /// three times the worst measured (lavapipe on a 2-vCPU AMD EPYC KVM guest, 2026-12-04,
    /// every GPU test): 0.098 %, one pixel of 1,024, on `cornell-box` (a tie between its
    /// coincident faces, cast and Whitted) and on `sdf` (Whitted); 0 elsewhere.
    pub const MAX_COLOR_MISMATCH: f64 = 0.003;
    /// The same for path tracing: a diffuse bounce's direction goes through `sin` and `cos`,
    /// which GPUs approximate (absolute error about 1e-6), and a path that then grazes an
    /// edge differently changes its pixel wholly. About three times the worst measured
    /// (lavapipe on a 2-vCPU AMD EPYC KVM guest, 2026-12-04, every GPU test, 4 samples and 4
    /// bounces): 0.977 % of pixels, 10 of 1,024, on `spheres:2000` (2,000 small spheres);
    /// one pixel on `csg` and `quadrics`, 0 on the other scenes.
    pub const MAX_PATH_COLOR_MISMATCH: f64 = 0.03;
    /// Per-channel colour difference counted as equal (relative to the pixel's value).
    pub const COLOR_EPS: f32 = 1e-3;
    /// Largest relative difference of the mean colour of the whole image (one pixel in a
    /// 32 x 32 image that takes the other side of a tie moves the mean by about 1e-3). About
    /// three times the worst measured (lavapipe on a 2-vCPU AMD EPYC KVM guest, 2026-12-04,
    /// every GPU test): 1.5e-3, `cornell-box` in ray casting (its one tie); at most 2.3e-4
    /// elsewhere.
    pub const MAX_MEAN_DIFF: f32 = 5e-3;

    /// Largest difference of `t` where the ids agree, relative to the ray's reach
    /// `max(t, |origin| / |dir|)` rather than to `t` alone: rounding the origin (carrying it
    /// into an instance's space, or subtracting a vertex) moves `t` by a few ULPs of
    /// `|origin| / |dir|` whatever `t` is, so an incoherent ray starting close to a surface
    /// far from the world's origin sees a large error relative to its short `t`
    /// (`instance-grid` on lavapipe: 5.2e-6 at `t` near 0.036, 1.4e-4 of `t`, at most 5.5e-7
    /// of the reach).
    #[must_use]
    pub fn reach_dt(
        rays: &[raybench_core::Ray],
        (ref_ids, ref_t): (&[u32], &[f32]),
        (ids, t): (&[u32], &[f32]),
    ) -> f64 {
        let mut worst = 0.0f64;
        for (i, ray) in rays.iter().enumerate() {
            if ref_ids[i] == ids[i] && ref_ids[i] != raybench_core::NO_HIT {
                let reach =
                    f64::from(ref_t[i]).max(f64::from(ray.origin.length() / ray.dir.length()));
                worst = worst.max((f64::from(ref_t[i]) - f64::from(t[i])).abs() / reach);
            }
        }
        worst
    }

    /// The primitive ids and distances of `hits` (a miss as `NO_HIT` at infinity), as
    /// `raybench_registry::compare_hits` takes them.
    #[must_use]
    pub fn hit_keys(hits: &[Option<raybench_core::Hit>]) -> (Vec<u32>, Vec<f32>) {
        (
            hits.iter()
                .map(|h| h.map_or(raybench_core::NO_HIT, |h| h.prim))
                .collect(),
            hits.iter()
                .map(|h| h.map_or(f32::INFINITY, |h| h.t))
                .collect(),
        )
    }

    /// Whether the GPU backend can run; under `CI=true` (lavapipe installed) it must.
    ///
    /// # Panics
    /// Under `CI=true` when no adapter is found.
    #[must_use]
    pub fn available() -> bool {
        match (raybench_registry::backend(super::DEVICE).unwrap().make)().availability() {
            Ok(()) => true,
            Err(e) => {
                assert!(!in_ci(), "CI=true but the GPU backend is unavailable: {e}");
                eprintln!("SKIPPED wgpu: {e}");
                false
            }
        }
    }

    /// Asserts that ids and `t` of `frame` agree with `reference` within the tolerances.
    ///
    /// # Panics
    /// When they do not.
    pub fn assert_close_hits(what: &str, reference: &Frame, frame: &Frame) {
        let c = raybench_registry::compare_frames(reference, frame);
        let n = reference.ids.len().max(1) as f64;
        let id_match = c.id_match + c.tie_mismatch as f64 / n;
        eprintln!(
            "{what}: ids {:.4}%, max relative dt {:.1e}, ties {}, hit/miss {}",
            c.id_match * 100.0,
            c.max_rel_dt,
            c.tie_mismatch,
            c.hit_mismatch
        );
        assert!(
            id_match >= MIN_ID_MATCH,
            "{what}: ids match on {:.4}% of pixels, ties counted (least {}%)",
            id_match * 100.0,
            MIN_ID_MATCH * 100.0
        );
        assert!(
            c.max_rel_dt <= MAX_REL_DT,
            "{what}: relative t difference {:e} exceeds {MAX_REL_DT:e}",
            c.max_rel_dt
        );
    }

    /// Asserts that two colour buffers agree within the tolerances above.
    ///
    /// # Panics
    /// When they do not.
    pub fn assert_close_colors(what: &str, reference: &[Vec3], colors: &[Vec3], max_mismatch: f64) {
        assert_eq!(reference.len(), colors.len());
        let differ = reference
            .iter()
            .zip(colors)
            .filter(|(a, b)| {
                let d = (**a - **b).abs();
                d.cmpgt(a.abs().max(Vec3::ONE) * COLOR_EPS).any() || !b.is_finite()
            })
            .count();
        let fraction = differ as f64 / reference.len().max(1) as f64;
        let mean = |c: &[Vec3]| c.iter().copied().sum::<Vec3>() / c.len().max(1) as f32;
        let (ma, mb) = (mean(reference), mean(colors));
        let rel = ((ma - mb).abs() / ma.abs().max(Vec3::splat(1e-3))).max_element();
        eprintln!(
            "{what}: {:.3}% of pixels differ, mean colour relative difference {rel:.1e}",
            fraction * 100.0
        );
        assert!(
            fraction <= max_mismatch,
            "{what}: {:.3}% of pixels differ (most {}%)",
            fraction * 100.0,
            max_mismatch * 100.0
        );
        assert!(
            rel <= MAX_MEAN_DIFF,
            "{what}: mean colour {mb} vs {ma} (relative {rel:e})"
        );
    }

    /// Every GPU backend ([`super::DEVICES`]) against the CPU on `scene`: ray casting at
    /// `size x size` and as many seeded incoherent rays, closest hits and any hits (at full
    /// length and shortened to a twentieth of the scene's diagonal); with `modes`, ray
    /// casting at 4 samples, Whitted (4 bounces) and path tracing (4 samples, 4 bounces, the
    /// same seed) at `size x size` too. Ray counts agree: exactly in ray casting and for
    /// explicit rays, within 1% where paths may branch differently.
    ///
    /// The scene is loaded and the CPU's answers computed once, with [`super::BASELINE`] (the
    /// BVH, bit-identical to naive: `equivalence.rs` checks it on every built-in scene and
    /// kind), and shared by the GPU backends. The other trees' kernels differ from the
    /// first's only in the tree walk, which ray casting and explicit rays exercise on every
    /// scene (and, bit for bit, `the_gpu_trees_find_the_same_hits`); their Whitted and path
    /// kernels are checked on scenes of triangles, spheres and planes only, as each kind's
    /// pipelines take 4 to 8 s each to compile on lavapipe.
    ///
    /// # Panics
    /// When a GPU backend differs beyond the tolerances.
    pub fn check(scene: &str, size: u32, modes: bool) {
        if !available() {
            return;
        }
        let Some(s) = load_or_skip(scene) else {
            return;
        };
        let plain = !s.geometry.has_instances()
            && s.geometry.shapes().iter().all(|shape| {
                use raybench_core::PrimitiveKind as K;
                matches!(shape.kind(), K::Triangle | K::Sphere | K::Plane)
            });
        let reference = Reference::new(&s, size, modes);
        let (first, rest) = super::DEVICES.split_first().expect("a GPU backend");
        check_backend(first, scene, &s, &reference, modes);
        for name in rest {
            check_backend(name, scene, &s, &reference, modes && plain);
        }
    }

    /// The CPU's answers on one scene, for every GPU backend: frames by mode and sample
    /// count (ray casting at one sample first), seeded incoherent rays (each twice: at full
    /// length, then shortened) with their closest hits and any-hit answers.
    struct Reference {
        frames: Vec<(Mode, u32, Frame)>,
        rays: Vec<raybench_core::Ray>,
        closest: Vec<Option<raybench_core::Hit>>,
        blocked: Vec<bool>,
    }

    impl Reference {
        /// [`super::BASELINE`]'s answers on `s` at `size x size` (with `modes`, the
        /// secondary modes too).
        fn new(s: &Arc<raybench_core::Scene>, size: u32, modes: bool) -> Self {
            let cpu = prepared(super::BASELINE, s);
            let mut cases = vec![(Mode::Cast, 1)];
            if modes {
                cases.extend([(Mode::Cast, 4), (Mode::Whitted, 1), (Mode::Path, 4)]);
            }
            let frames = cases
                .into_iter()
                .map(|(mode, spp)| {
                    let settings = super::mode_settings(size, mode, spp);
                    (mode, spp, cpu.render(&settings).unwrap())
                })
                .collect();
            let mut rays = raybench_core::ray_sets::incoherent(
                s.geometry.world_bounds(),
                (size * size) as usize,
                1,
            );
            let (closest, _) = cpu.trace_rays(&rays, false).unwrap();
            // Any hit, at full length and shortened (shadow rays end before the light).
            let short = s.geometry.world_bounds().extent().length() / 20.0;
            let n = rays.len();
            rays.extend_from_within(..);
            for r in &mut rays[n..] {
                r.t_max = short / r.dir.length();
            }
            let (blocked, _) = cpu.occlude_rays(&rays, false).unwrap();
            Self {
                frames,
                rays,
                closest,
                blocked,
            }
        }
    }

    /// GPU backend `name` against `reference` on scene `s` (named `scene`): every frame of
    /// the reference with `modes`, the first (ray casting, one sample) only without.
    fn check_backend(
        name: &str,
        scene: &str,
        s: &Arc<raybench_core::Scene>,
        reference: &Reference,
        modes: bool,
    ) {
        let gpu = prepared(name, s);
        let cases = if modes { reference.frames.len() } else { 1 };
        for (mode, spp, expected) in &reference.frames[..cases] {
            let settings = super::mode_settings(expected.width, *mode, *spp);
            let frame = gpu.render(&settings).unwrap();
            let what = format!("{name} on {scene}, {} spp {spp}", mode.name());
            assert_close_hits(&what, expected, &frame);
            let (a, b) = (expected.stats.rays, frame.stats.rays);
            if *mode == Mode::Cast {
                assert_eq!(a, b, "{what}: rays");
            } else {
                assert!(
                    a.abs_diff(b) as f64 <= 0.01 * a as f64,
                    "{what}: rays {a} vs {b}"
                );
            }
            let max_mismatch = if *mode == Mode::Path {
                MAX_PATH_COLOR_MISMATCH
            } else {
                MAX_COLOR_MISMATCH
            };
            assert_close_colors(&what, &expected.color, &frame.color, max_mismatch);
        }
        let n = reference.closest.len();
        let rays = &reference.rays[..n];
        let (hits, _) = gpu.trace_rays(rays, false).unwrap();
        assert_eq!(hits.len(), n);
        let ((ri, rt), (gi, gt)) = (hit_keys(&reference.closest), hit_keys(&hits));
        let c = raybench_registry::compare_hits(&ri, &rt, &gi, &gt);
        eprintln!("{name} on {scene}, incoherent rays: {c:?}");
        let id_match = c.id_match + c.tie_mismatch as f64 / n.max(1) as f64;
        let dt = reach_dt(rays, (&ri, &rt), (&gi, &gt));
        eprintln!("{name} on {scene}, incoherent rays: dt relative to reach {dt:.1e}");
        assert!(
            id_match >= MIN_ID_MATCH && dt <= MAX_REL_DT,
            "{name} on {scene}, incoherent rays: {c:?}, dt relative to reach {dt:.1e}"
        );
        let (blocked, _) = gpu.occlude_rays(&reference.rays, false).unwrap();
        assert_eq!(blocked.len(), reference.rays.len());
        let agree = reference
            .blocked
            .iter()
            .zip(&blocked)
            .filter(|(a, b)| a == b)
            .count();
        let fraction = agree as f64 / blocked.len().max(1) as f64;
        eprintln!(
            "{name} on {scene}, any-hit rays: {:.4}% agree",
            fraction * 100.0
        );
        assert!(
            fraction >= MIN_ID_MATCH,
            "{name} on {scene}, any-hit rays agree on {:.4}% (least {}%)",
            fraction * 100.0,
            MIN_ID_MATCH * 100.0
        );
    }

    /// Most pixels whose colour may differ from the CPU's by more than [`COLOR_EPS`] in the
    /// volume modes (a count: none is measured to). The kernels port the integration operation for
    /// operation in f32 (`crates/wgpu/src/volume.rs`), but the GPU's division (2.5 ULP),
    /// `exp` (3 + 2|x| ULP) and fused multiply-adds move a DDA crossing, a trilinear weight
    /// or a segment's opacity by a few ULP, and compositing sums one such error per voxel
    /// segment (at most 382 on the 128^3 phantom). That stays near 1e-5; a pixel differs beyond
    /// [`COLOR_EPS`] only where a sample lands on the other side of a sharp step of the
    /// transfer function (the phantom's orange ellipsoids, sigma 12 against 0.6), or where
    /// early termination stops one segment earlier. Measured on lavapipe (a 2-vCPU AMD EPYC
    /// KVM guest, 2026-12-04, both GPU trees, `phantom` and `volumes-cut` at 32 x 32, every
    /// volume mode): no pixel beyond [`COLOR_EPS`], the largest difference 4.7e-5
    /// (compositing on the phantom; [`check_volumes`] logs it). So two pixels: a sample that
    /// lands on the other side of one step, not a share of the image.
    pub const MAX_VOLUME_COLOR_MISMATCH_PIXELS: usize = 2;

    /// A scene whose volumes are cut by surfaces, overlap and differ in every option the
    /// volume kernels read: a trilinear phantom with empty-space skipping and the phantom's
    /// transfer function, a sphere inside it and a plane behind; and a smaller rotated,
    /// translated phantom, nearest sampling, no skipping, a narrow window and the default
    /// ramp, overlapping the first.
    pub const VOLUMES_SCENE: &str = r#"
name = "volumes-cut"
background = [0.1, 0.1, 0.15]

[camera]
position = [0.6, 0.5, 3.0]
look_at = [0.0, 0.0, 0.0]
fov = 42

[[object]]
kind = "sphere"
center = [0.15, 0.05, 0.2]
radius = 0.3

[[object]]
kind = "plane"
point = [0.0, 0.0, -1.2]
normal = [0.0, 0.0, 1.0]

[[volume]]
source = "phantom:50"
sampling = "trilinear"
transfer = [
  { value = 0.0, color = [0.0, 0.0, 0.0], sigma = 0.0 },
  { value = 0.12, color = [0.0, 0.0, 0.0], sigma = 0.0 },
  { value = 0.2, color = [0.15, 0.3, 0.6], sigma = 0.6 },
  { value = 0.25, color = [0.2, 0.3, 0.5], sigma = 0.6 },
  { value = 0.3, color = [1.0, 0.55, 0.15], sigma = 12.0 },
  { value = 0.5, color = [1.0, 1.0, 1.0], sigma = 0.0 },
  { value = 0.9, color = [1.0, 1.0, 1.0], sigma = 0.0 },
  { value = 1.0, color = [0.9, 0.9, 0.85], sigma = 1.5 },
]

[[volume]]
source = "phantom:21"
skip_empty = false
window = [0.1, 0.6]
transform = { scale = 0.6, rotate = [10, 30, 0], translate = [0.5, 0.3, 0.4] }
"#;

    /// [`VOLUMES_SCENE`], loaded.
    ///
    /// # Panics
    /// When it does not load.
    #[must_use]
    pub fn volumes_scene() -> std::sync::Arc<raybench_core::Scene> {
        let assets = raybench_scene::assets_dir(None);
        std::sync::Arc::new(
            raybench_scene::load_scene_str(VOLUMES_SCENE, "volumes-cut", None, &assets).unwrap(),
        )
    }

    /// Every GPU backend against the CPU (the BVH) on `scene` (a built-in name, or
    /// [`VOLUMES_SCENE`] for `"volumes-cut"`) in the volume modes at `size x size`:
    /// maximum-intensity projection and compositing at one sample, compositing at 4
    /// jittered samples. Centre-ray ids and `t` within [`MIN_ID_MATCH`] and
    /// [`MAX_REL_DT`], ray counts exactly (camera rays only, as on the CPU), colours within
    /// [`COLOR_EPS`] but for [`MAX_VOLUME_COLOR_MISMATCH_PIXELS`] pixels, and the mean
    /// colour within [`MAX_MEAN_DIFF`].
    ///
    /// # Panics
    /// When a GPU backend differs beyond the tolerances.
    pub fn check_volumes(scene: &str, size: u32) {
        if !available() {
            return;
        }
        let s = if scene == "volumes-cut" {
            volumes_scene()
        } else {
            let Some(s) = load_or_skip(scene) else {
                return;
            };
            s
        };
        assert!(!s.volumes.is_empty(), "{scene} has no volumes");
        // The CPU's frames once for every GPU backend ([`super::BASELINE`], bit-identical to
        // naive in the volume modes too: `volumes.rs`).
        let cpu = prepared(super::BASELINE, &s);
        let references: Vec<_> = [(Mode::Mip, 1), (Mode::Composite, 1), (Mode::Composite, 4)]
            .into_iter()
            .map(|(mode, spp)| {
                let settings = super::mode_settings(size, mode, spp);
                let frame = cpu.render(&settings).unwrap();
                (mode, spp, settings, frame)
            })
            .collect();
        for name in super::DEVICES {
            let gpu = prepared(name, &s);
            for (mode, spp, settings, reference) in &references {
                let frame = gpu.render(settings).unwrap();
                let what = format!("{name} on {scene}, {} spp {spp}", mode.name());
                assert_close_hits(&what, reference, &frame);
                assert_eq!(reference.stats.rays, frame.stats.rays, "{what}: rays");
                let worst = reference
                    .color
                    .iter()
                    .zip(&frame.color)
                    .map(|(a, b)| ((*a - *b).abs() / a.abs().max(Vec3::ONE)).max_element())
                    .fold(0.0f32, f32::max);
                eprintln!("{what}: largest colour difference {worst:.2e} (relative, at least 1)");
                assert_close_colors(
                    &what,
                    &reference.color,
                    &frame.color,
                    MAX_VOLUME_COLOR_MISMATCH_PIXELS as f64 / reference.color.len().max(1) as f64,
                );
            }
        }
    }
}

/// Rays lying in `grid`'s cell-boundary planes and faces, and starting on its box (shared by
/// `grid_cases.rs` and `adversarial.rs`).
#[must_use]
pub fn grid_boundary_rays(grid: &raybench_grid::Grid) -> Vec<Ray> {
    let b = grid.bounds();
    let cell = grid.cell_size();
    let res = grid.resolution();
    let mut rays = Vec::new();
    for a in 0..3 {
        let (u, v) = ((a + 1) % 3, (a + 2) % 3);
        for i in 0..=res[u] {
            for j in (0..=res[v]).step_by(((res[v] / 6).max(1)) as usize) {
                let mut o = b.min;
                o[u] = b.min[u] + i as f32 * cell[u];
                o[v] = b.min[v] + j as f32 * cell[v];
                // Along axis a, exactly on the boundary lines of u and v, from outside, from the
                // box face, and from the middle.
                let mut d = Vec3::ZERO;
                d[a] = 1.0;
                let mut outside = o;
                outside[a] = b.min[a] - 1.0;
                rays.push(Ray::new(outside, d));
                rays.push(Ray::new(o, d));
                let mut far = o;
                far[a] = b.max[a];
                rays.push(Ray::new(far, -d));
                // Diagonal inside the boundary plane of u.
                let mut dd = Vec3::ZERO;
                dd[a] = 1.0;
                dd[v] = 0.37;
                rays.push(Ray::new(outside, dd));
            }
        }
    }
    // From the box's corners towards the centre and along its edges.
    let c = b.center();
    for k in 0..8 {
        let corner = Vec3::new(
            if k & 1 == 0 { b.min.x } else { b.max.x },
            if k & 2 == 0 { b.min.y } else { b.max.y },
            if k & 4 == 0 { b.min.z } else { b.max.z },
        );
        rays.push(Ray::new(corner, c - corner));
        rays.push(Ray::new(corner, Vec3::new(c.x - corner.x, 0.0, 0.0)));
    }
    rays
}
