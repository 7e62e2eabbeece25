//! Every raybench CPU backend against the naive oracle: bit-identical primitive ids and `t`
//! on every built-in scene (camera rays, incoherent rays and the derived `diffuse` rays;
//! the any-hit `shadow` and `ao` rays compared on their boolean: `raybench_tests::check`)
//! and on rays aimed at shared edges and vertices.
//!
//! A new backend registered as exact (`raybench_registry::Roles::EXACT`) joins by itself:
//! `raybench_tests::EXACT_BACKENDS` is read from the registry.

use raybench_core::{Ray, Vec3};
use raybench_tests::{assert_same_ray_hits, available, check, load_or_skip, prepared};

/// Backends under test: every exact one but the oracle, which is the reference (its own
/// independence of the thread count is `determinism.rs`' business, on every scene kind).
const BACKENDS: &[&str] = raybench_tests::ACCELERATED_BACKENDS;

/// 64 x 64 ray casting: about 4k rays, so naive on the 69k-triangle meshes stays near 1 s.
const SIZE: u32 = 64;

macro_rules! scene_tests {
    ($($test:ident => $scene:literal,)*) => {
        $(
            #[test]
            fn $test() {
                check(&available(BACKENDS), $scene, SIZE);
            }
        )*
    };
}

scene_tests! {
    soup => "soup:10000",
    random_spheres => "spheres:2000",
    icosphere => "icosphere:4",
    terrain => "terrain:64",
    heightfield_generator => "heightfield:64",
}

/// Every built-in scene, a test each (`builtin_scene_tests!`, which fails when a scene file
/// has no test): ray casting, explicit and derived rays ([`check`], 64 x 64), then Whitted
/// and path tracing (`check_modes`) at 24 x 24, the `heavy` scenes at 12 x 12 (naive's
/// secondary rays over their tens of thousands of primitives cost seconds a frame). Left out:
/// scenes over [`raybench_tests::ORACLE_PRIMITIVES`] flattened, which `instances.rs` checks
/// against the baseline.
fn builtin_scene(name: &str) {
    let heavy = raybench_scene::builtin(name)
        .expect("a built-in scene")
        .benchmark
        .heavy;
    let Some(scene) = load_or_skip(name) else {
        return;
    };
    if scene.geometry.total_len() > raybench_tests::ORACLE_PRIMITIVES {
        eprintln!("{name}: too large for the oracle, checked by instances.rs");
        return;
    }
    let backends = available(BACKENDS);
    raybench_tests::check_loaded(&backends, name, &scene, SIZE);
    if let Some((_, why)) = MODES_DIVERGE.iter().find(|(n, _)| *n == name) {
        eprintln!("{name}: Whitted and path tracing left out: {why}");
        return;
    }
    raybench_tests::check_modes_loaded(&backends, name, &scene, if heavy { 12 } else { 24 });
}

/// Built-in scenes whose Whitted and path-traced frames are known to differ between exact
/// backends, and how; each has an ignored test below that shows it
/// (`cargo test -p raybench-tests --test integration -- --ignored modes_diverge`).
const MODES_DIVERGE: &[(&str, &str)] = &[(
    "teapot-stadium",
    "path tracing at 12 x 12, 2 samples, 4 bounces, seed 7: a bounce leaves the 600-unit \
     floor from 1.3e-5 above it (the origin offset scales with the hit point, near 0 in y, \
     not with the triangle's coordinates, near 300) and the watertight test, whose rounding \
     scales with the vertices, reports the floor again at t = 1.2e-5; naive, obvhs and the \
     grids take that false hit, bvh and packet cull it with the floor's flat box and hit the \
     far wall (1,449 rays against 1,457; 8 pixels sky against black); ray casting and the \
     explicit ray sets agree bit for bit",
)];

/// The disagreement [`MODES_DIVERGE`] records on `teapot-stadium`; fails until it is fixed.
#[test]
#[ignore = "known disagreement: see MODES_DIVERGE"]
fn modes_diverge_on_the_teapot_stadium() {
    raybench_tests::check_modes(&available(BACKENDS), "teapot-stadium", 12);
}

builtin_scene_tests!(super::builtin_scene);

macro_rules! mode_tests {
    ($($test:ident => $scene:literal,)*) => {
        $(
            #[test]
            fn $test() {
                raybench_tests::check_modes(&available(BACKENDS), $scene, 24);
            }
        )*
    };
}

// Whitted and path tracing on the scenes small enough for naive's secondary rays.
mode_tests! {
    modes_random_spheres => "spheres:2000",
    modes_terrain => "terrain:32",
}

/// Backends not bound by the bit-exact contract, and where each is compared with naive
/// within its tolerance.
const TOLERANCE_TESTED: &[(&str, &str)] = &[
    ("wgpu", "tests/tests/gpu/"),
    ("wgpu-cwbvh", "tests/tests/gpu/"),
    ("bvh-crate", "crates/peers/tests/naive.rs"),
    ("embree", "crates/peers/tests/naive.rs (feature embree)"),
    (
        "embree-packet",
        "crates/peers/tests/naive.rs (feature embree)",
    ),
];

/// Exact backends are under test by their role (`EXACT_BACKENDS` is read from the
/// registry); every other one must name where it is compared with the oracle.
#[test]
fn every_backend_is_under_test() {
    for b in raybench_registry::BACKENDS.iter().filter(|b| !b.exact()) {
        assert!(
            TOLERANCE_TESTED.iter().any(|(n, _)| *n == b.name),
            "backend {} is tested nowhere: add it to TOLERANCE_TESTED with its test",
            b.name
        );
    }
}

/// Rays from outside aimed at every vertex and edge midpoint of a closed icosphere, and rays
/// from its centre: every one must hit (the watertight test lets none through a shared edge
/// or vertex), and every backend must return naive's hits bit for bit.
#[test]
fn rays_at_shared_edges_and_vertices_never_pass_through() {
    let scene = load_or_skip("icosphere:3").unwrap();
    let mut targets = Vec::new();
    for s in scene.geometry.shapes() {
        if let raybench_core::Shape::Triangle(t) = s {
            for k in 0..3 {
                targets.push(t.v[k]);
                targets.push((t.v[k] + t.v[(k + 1) % 3]) * 0.5);
            }
        }
    }
    let mut rays = Vec::new();
    for (i, &p) in targets.iter().enumerate() {
        // From outside, about 14 degrees off the normal (a ray aimed at a silhouette point
        // may graze past legitimately, so targets are approached from their front), from
        // the centre, and from an off-centre point inside.
        let side = p.any_orthonormal_vector() * (0.25 + (i % 5) as f32 * 0.1);
        let eye = p * 3.0 + side;
        rays.push(Ray::new(eye, p - eye));
        rays.push(Ray::new(Vec3::ZERO, p));
        let inside = Vec3::new(0.3, -0.2, 0.1);
        rays.push(Ray::new(inside, p - inside));
    }
    let naive = prepared(raybench_tests::ORACLE, &scene);
    let (reference, _) = naive.trace_rays(&rays, false).unwrap();
    let misses = reference.iter().filter(|h| h.is_none()).count();
    assert_eq!(
        misses,
        0,
        "{misses} of {} edge/vertex rays passed through",
        rays.len()
    );
    for name in available(BACKENDS) {
        let (hits, _) = prepared(name, &scene).trace_rays(&rays, false).unwrap();
        assert_same_ray_hits(name, &reference, &hits);
    }
}

/// An empty scene renders the background everywhere.
#[test]
fn empty_scene_renders_background() {
    let scene = raybench_tests::empty_scene();
    let settings = raybench_core::RenderSettings {
        width: 8,
        height: 8,
        ..Default::default()
    };
    for name in available(raybench_tests::EXACT_BACKENDS) {
        let f = raybench_tests::render_with(name, &scene, &settings, 2);
        assert!(f.ids.iter().all(|&id| id == raybench_core::NO_HIT));
        assert!(f.color.iter().all(|&c| c == Vec3::new(0.25, 0.5, 0.75)));
    }
}

/// `Bvh::validate` on the structure built over every built-in scene and the generators
/// above, with every preset.
#[test]
fn bvh_invariants_hold_on_every_scene() {
    let generators = ["soup:10000", "spheres:2000", "icosphere:4", "terrain:64"];
    let builtin = raybench_scene::BUILTIN_SCENES.iter().map(|b| b.name);
    for spec in builtin.chain(generators) {
        let Some(scene) = raybench_tests::load_or_skip(spec) else {
            continue;
        };
        for params in [
            raybench_bvh::BvhParams::fast(),
            raybench_bvh::BvhParams::medium(),
            raybench_bvh::BvhParams::quality(),
        ] {
            let bvh = raybench_bvh::Bvh::build_with(std::sync::Arc::clone(&scene.geometry), params);
            bvh.validate()
                .unwrap_or_else(|e| panic!("{spec} {params:?}: {e}"));
        }
    }
}
