//! # raybench-tests
//!
//! Shared helpers of the cross-backend tests in `tests/tests/`: loading scenes (skipping, or
//! failing under `CI=true`, when the shared meshes are absent), rendering with a backend by
//! name, and [`check`], the one data-driven comparison against the naive oracle.

use raybench_core::{Frame, Hit, NO_HIT, RenderSettings, Renderer, Scene};
use std::sync::Arc;

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
            let b = raybench::backend(name).unwrap();
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
    let b = raybench::backend(name).unwrap();
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
    let r = prepared(name, scene);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| r.render(settings).unwrap())
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
/// many start inside nodes and next to surfaces).
/// Also asserts naive's exact counter (`rays * M` closest-hit tests). Skips (or fails under
/// CI) when the scene's meshes are absent.
///
/// # Panics
/// When any backend differs from the reference.
pub fn check(backends: &[&str], scene: &str, size: u32) {
    let Some(scene_data) = load_or_skip(scene) else {
        return;
    };
    let settings = RenderSettings {
        width: size,
        height: size,
        count: true,
        ..RenderSettings::default()
    };
    let reference = render_with("naive", &scene_data, &settings, 1);
    let m = scene_data.geometry.len() as u64;
    assert_eq!(reference.stats.rays, u64::from(size * size));
    assert_eq!(
        reference.stats.counters.unwrap().prim_tests,
        reference.stats.rays * m,
        "naive must test every primitive for every ray"
    );
    for &name in backends {
        for threads in [2, 3] {
            let frame = render_with(name, &scene_data, &settings, threads);
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
    let rays =
        raybench_core::rays::incoherent(scene_data.geometry.bounds(), (size * size) as usize, 1);
    let (reference_rays, _) = prepared("naive", &scene_data)
        .trace_rays(&rays, false)
        .unwrap();
    for &name in backends {
        let (hits, _) = prepared(name, &scene_data)
            .trace_rays(&rays, false)
            .unwrap();
        assert_same_ray_hits(
            &format!("{name} on {scene}, incoherent rays"),
            &reference_rays,
            &hits,
        );
    }
}

/// The equivalence check for the integrators with secondary rays: Whitted (4 bounces) and
/// path tracing (2 samples, 4 bounces) at `size x size` must give bit-identical colours, ids
/// and `t` with every backend and thread count. Meant for scenes small enough for naive.
///
/// # Panics
/// When any backend differs from the reference.
pub fn check_modes(backends: &[&str], scene: &str, size: u32) {
    let Some(scene_data) = load_or_skip(scene) else {
        return;
    };
    for (mode, spp) in [
        (raybench_core::Mode::Whitted, 1),
        (raybench_core::Mode::Path, 2),
    ] {
        let settings = RenderSettings {
            width: size,
            height: size,
            spp,
            mode,
            max_depth: 4,
            seed: 7,
            count: false,
        };
        let reference = render_with("naive", &scene_data, &settings, 1);
        for &name in backends {
            for threads in [2, 3] {
                let frame = render_with(name, &scene_data, &settings, threads);
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
