//! Instanced scenes (issue 23): every exact CPU backend against the naive oracle on scenes
//! of instances (mirrored, scaled, rotated, coincident, beside flat primitives, meshes of
//! triangles and spheres), bit-identical ids and `t` for closest hits and the same any-hit
//! answers, naive counting `rays x total` tests (`raybench_tests::check`); instanced scenes
//! against the same scenes flattened (`raybench_core::flatten`); and the built-in scenes
//! too large for the oracle against the baseline.
//!
//! The built-in scenes `instances` and `instance-grid` are checked by `equivalence.rs` with
//! every other built-in.

use raybench::Roles;
use raybench_core::{RayCounters, Scene};
use raybench_tests::{
    BASELINE, ORACLE, assert_same_hits, assert_same_ray_hits, available, check, check_modes,
    load_or_skip, prepared,
};
use std::path::PathBuf;
use std::sync::Arc;

/// Backends under test.
const BACKENDS: &[&str] = raybench_tests::EXACT_BACKENDS;

/// Writes `text` as the scene file `NAME.toml` in a folder of this test process.
fn scene_file(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("raybench-instances-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// A mesh `m` of a seeded triangle soup and a sphere, instanced 60 times on a grid with
/// rotations, non-uniform scales and mirrors, overlapping their neighbours, every fifth
/// coincident with the previous one, under a flat sphere and plane.
fn soup_field() -> String {
    let mut s = String::from(
        "[camera]\nposition = [0, 9, 12]\nlook_at = [0, 0, 0]\nfov = 50\n\
         [[object]]\nkind = \"plane\"\npoint = [0, -1.5, 0]\nnormal = [0, 1, 0]\n\
         [[object]]\nkind = \"sphere\"\ncenter = [0.5, 1, 0]\nradius = 1.3\n\
         [[object]]\nname = \"m\"\ninstance_only = true\nkind = \"generator\"\n\
         spec = \"soup:300\"\n\
         [[object]]\nname = \"m\"\ninstance_only = true\nkind = \"sphere\"\n\
         center = [0.2, 0.1, 0]\nradius = 0.3\n",
    );
    for k in 0..60 {
        let j = if k % 5 == 4 { k - 1 } else { k };
        let (x, z) = ((j % 10) as f32 - 4.5, (j / 10) as f32 * 1.1 - 3.0);
        let mirror = if j % 3 == 0 { -1.0 } else { 1.0 };
        s += &format!(
            "[[instance]]\nmesh = \"m\"\ntransform = {{ scale = [{}, {}, {}], \
             rotate = [{}, {}, {}], translate = [{x}, 0, {z}] }}\n",
            mirror * (0.9 + 0.05 * (j % 4) as f32),
            0.6 + 0.1 * (j % 3) as f32,
            1.1,
            7 * j,
            31 * j,
            13 * j,
        );
    }
    s
}

/// Every exact backend on a field of overlapping, mirrored, scaled and coincident
/// instances of a triangle-and-sphere mesh beside flat primitives.
#[test]
fn every_backend_on_a_field_of_instances() {
    let path = scene_file("soup-field", &soup_field());
    check(&available(BACKENDS), path.to_str().unwrap(), 64);
}

/// Whitted and path tracing through instances: reflections and shadows traced as batches
/// of secondary rays hit the same instanced primitives on every backend.
#[test]
fn modes_on_a_field_of_instances() {
    let path = scene_file("soup-field-modes", &soup_field());
    check_modes(&available(BACKENDS), path.to_str().unwrap(), 24);
}

/// Instances only (no flat primitive), all coincident: every ray that hits goes to the
/// first instance's id, on every backend.
#[test]
fn coincident_instances_take_the_smallest_id() {
    let mut text = String::from(
        "[camera]\nposition = [0, 0, 6]\nlook_at = [0, 0, 0]\n\
         [[object]]\nname = \"t\"\ninstance_only = true\nkind = \"generator\"\n\
         spec = \"icosphere:2\"\n",
    );
    for _ in 0..5 {
        text += "[[instance]]\nmesh = \"t\"\ntransform = { rotate = [10, 20, 30], \
                 scale = [1, -0.5, 1.5] }\n";
    }
    let path = scene_file("coincident", &text);
    let path = path.to_str().unwrap();
    check(&available(BACKENDS), path, 48);
    let scene = load_or_skip(path).unwrap();
    let n = scene.geometry.meshes()[0].len() as u32;
    for name in available(BACKENDS) {
        let frame = prepared(name, &scene)
            .render(&raybench_core::RenderSettings {
                width: 48,
                height: 48,
                ..Default::default()
            })
            .unwrap();
        let hits: Vec<u32> = frame
            .ids
            .iter()
            .copied()
            .filter(|&id| id != raybench_core::NO_HIT)
            .collect();
        assert!(hits.len() > 100, "{name}: {} hits", hits.len());
        assert!(
            hits.iter().all(|&id| id < n),
            "{name}: a coincident copy won a tie"
        );
    }
}

/// An instanced scene's hits against the same scene flattened (`raybench_core::flatten`,
/// as `--flatten` and the report's `instancing` experiment make it): the same ids for all
/// but one ray in a thousand and `t` within a relative `1e-4`, on incoherent rays and on
/// the rendered frame, both through the baseline; returns the hits on incoherent rays
/// and how many of them were on mirrored instances.
///
/// Not bit for bit: an instanced primitive is tested on the instance-space ray, the
/// flattened one on the world ray against transformed vertices, and the two round
/// differently (a few ulps times the transform's condition number, here below 4). So `t`
/// differs in its last bits, and a ray within those bits of a shared edge may meet the
/// neighbouring triangle (both meshes are watertight, so it never slips through). The
/// normals agree up to the side convention: a mirrored instance's normal is its mesh's
/// outward normal carried by the inverse transpose, while the flattened triangle's winding
/// is reversed, so they are opposite there.
fn assert_matches_flattened(scene: &Arc<Scene>) -> (usize, usize) {
    let g = &scene.geometry;
    let flat_scene = Arc::new(raybench_core::flatten(scene).unwrap());
    let flat = &flat_scene.geometry;
    assert!(!flat.has_instances());
    assert_eq!(flat.len(), g.total_len());
    let rays = raybench_core::ray_sets::incoherent(g.world_bounds(), 20_000, 3);
    // Through the baseline (bit-identical with the naive loop on both scenes, by the
    // contract, and fast enough for 20,000 rays over tens of thousands of primitives).
    let (instanced, _) = prepared(BASELINE, scene).trace_rays(&rays, false).unwrap();
    let (flattened, _) = prepared(BASELINE, &flat_scene)
        .trace_rays(&rays, false)
        .unwrap();
    let (mut hits, mut other_id, mut mirrored) = (0, 0, 0);
    for (&a, &b) in instanced.iter().zip(&flattened) {
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) if a.prim == b.prim => {
                hits += 1;
                assert!(
                    (a.t - b.t).abs() <= 1e-4 * a.t.abs().max(1.0),
                    "t {} against {}",
                    a.t,
                    b.t
                );
                let det = g.locate(a.prim).map_or(1.0, |(k, _)| {
                    g.instances()[k].to_world().matrix3.determinant()
                });
                let expected = if det < 0.0 { -b.normal } else { b.normal };
                mirrored += usize::from(det < 0.0);
                assert!((a.normal - expected).length() < 1e-3, "{a:?} against {b:?}");
            }
            _ => other_id += 1,
        }
    }
    assert!(
        other_id * 1000 <= hits,
        "{other_id} rays of {hits} hit another primitive"
    );
    // The rendered frames: the baseline's two-level structure against its flat one.
    let settings = raybench_core::RenderSettings {
        width: 96,
        height: 96,
        ..Default::default()
    };
    let a = prepared(BASELINE, scene).render(&settings).unwrap();
    let b = prepared(BASELINE, &flat_scene).render(&settings).unwrap();
    let seen = a
        .ids
        .iter()
        .filter(|&&id| id != raybench_core::NO_HIT)
        .count();
    let differ = a.ids.iter().zip(&b.ids).filter(|(x, y)| x != y).count();
    assert!(seen > 1000, "{seen} pixels hit");
    assert!(
        differ * 1000 <= seen,
        "{differ} of {seen} pixels hit another primitive flattened"
    );
    (hits, mirrored)
}

/// Twelve mirrored, rotated, non-uniformly scaled icospheres beside a flat sphere, against
/// the scene flattened; the naive loop tests every primitive of every instance.
#[test]
fn instances_match_the_flattened_scene() {
    let mut text = String::from(
        "[camera]\nposition = [0, 0, 9]\nlook_at = [0, 0, 0]\n\
         [[object]]\nkind = \"sphere\"\ncenter = [0, 0, -3]\nradius = 0.5\n\
         [[object]]\nname = \"ico\"\ninstance_only = true\nkind = \"generator\"\n\
         spec = \"icosphere:3\"\n",
    );
    for k in 0..12 {
        let mirror = if k % 4 == 1 { -1.0 } else { 1.0 };
        text += &format!(
            "[[instance]]\nmesh = \"ico\"\ntransform = {{ scale = [{}, 0.7, 1.2], \
             rotate = [{}, {}, 0], translate = [{}, {}, 0] }}\n",
            mirror * 0.8,
            17 * k,
            29 * k,
            (k % 4) as f32 * 1.6 - 2.4,
            (k / 4) as f32 * 1.6 - 1.6,
        );
    }
    let path = scene_file("flatten", &text);
    let scene = load_or_skip(path.to_str().unwrap()).unwrap();
    let (hits, mirrored) = assert_matches_flattened(&scene);
    assert!(
        hits > 2000 && mirrored > 100,
        "{hits} hits, {mirrored} mirrored"
    );
    // The naive loop tests every primitive of every instance.
    let g = &scene.geometry;
    let rays = raybench_core::ray_sets::incoherent(g.world_bounds(), 100, 3);
    let mut counters = RayCounters::default();
    for ray in &rays {
        let _ = g.closest_every(ray, &mut counters);
    }
    assert_eq!(counters.prim_tests, 100 * g.total_len() as u64);
}

/// The built-in scene of instance arrays (seeded rotations and scales of triangle meshes
/// and of a sphere) against itself flattened; and the built-in `instances` scene, whose
/// sphere under a non-uniform scale cannot be flattened exactly, refused with the reason.
#[test]
fn builtin_instances_against_their_flattened_form() {
    let grid = raybench_scene::for_experiment("instancing").expect("a scene names it");
    let scene = load_or_skip(grid.name).unwrap();
    let (hits, _) = assert_matches_flattened(&scene);
    assert!(hits > 5000, "{hits} hits");
    let scene = load_or_skip("instances").unwrap();
    let e = raybench_core::flatten(&scene).unwrap_err().to_string();
    assert!(
        e.starts_with("cannot flatten the instance of gem (instance 3, primitive")
            && e.contains("non-uniform scale"),
        "{e}"
    );
}

/// The built-in scenes too large for the oracle's check in `equivalence.rs` (over
/// [`raybench_tests::ORACLE_PRIMITIVES`] flattened: the field of bunnies and teapots, 12.6
/// million instanced triangles): every accelerated exact backend against the baseline, bit
/// for bit, on camera and incoherent rays. Each builds a two-level structure over the
/// distinct meshes only, so this is cheap where naive would take minutes.
#[test]
fn large_instanced_scenes_against_the_baseline() {
    let backends: Vec<&str> = available(raybench_tests::ACCELERATED_BACKENDS)
        .into_iter()
        .filter(|&n| n != BASELINE)
        .collect();
    let settings = raybench_core::RenderSettings {
        width: 48,
        height: 48,
        ..Default::default()
    };
    for b in raybench_scene::BUILTIN_SCENES
        .iter()
        .filter(|b| b.benchmark.heavy)
    {
        let Some(scene) = load_or_skip(b.name) else {
            continue;
        };
        if scene.geometry.total_len() <= raybench_tests::ORACLE_PRIMITIVES {
            continue;
        }
        let reference = prepared(BASELINE, &scene).render(&settings).unwrap();
        let seen = reference
            .ids
            .iter()
            .filter(|&&id| id != raybench_core::NO_HIT)
            .count();
        assert!(seen > 1000, "{}: {seen} pixels hit", b.name);
        let rays = raybench_core::ray_sets::incoherent(scene.geometry.world_bounds(), 2304, 1);
        let (ref_hits, _) = prepared(BASELINE, &scene).trace_rays(&rays, false).unwrap();
        for &name in &backends {
            let r = prepared(name, &scene);
            let frame = r.render(&settings).unwrap();
            assert_same_hits(&format!("{name} on {}", b.name), &reference, &frame);
            let (hits, _) = r.trace_rays(&rays, false).unwrap();
            assert_same_ray_hits(
                &format!("{name} on {}, incoherent", b.name),
                &ref_hits,
                &hits,
            );
        }
    }
}

/// Every exact backend's two-level structure holds each distinct mesh's structure once
/// (its memory stays far below 60 copies' worth), and a device backend refuses an
/// instanced scene with its reason.
#[test]
fn structure_counts_meshes_once_and_devices_refuse() {
    let path = scene_file("structure", &soup_field());
    let scene = load_or_skip(path.to_str().unwrap()).unwrap();
    let mesh_scene = load_or_skip("soup:300").unwrap();
    for name in available(BACKENDS).into_iter().filter(|&n| n != ORACLE) {
        let stats = prepared(name, &scene).structure().unwrap();
        assert!(
            stats.counts.contains(&("instances", 60)),
            "{name}: {stats:?}"
        );
        assert!(stats.counts.contains(&("meshes", 1)), "{name}: {stats:?}");
        let one = prepared(name, &mesh_scene).structure().unwrap();
        assert!(
            stats.memory_bytes < 4 * one.memory_bytes + (64 << 10),
            "{name}: {} bytes for 60 instances, {} for one mesh",
            stats.memory_bytes,
            one.memory_bytes
        );
    }
    for b in raybench::BACKENDS.iter().filter(|b| b.is(Roles::DEVICE)) {
        let why = (b.make)().supports(&scene).unwrap_err();
        assert!(why.contains("no instances"), "{}: {why}", b.name);
    }
}
