//! Instanced scenes: every exact CPU backend against the naive oracle on scenes
//! of instances (mirrored, scaled, rotated, coincident, beside flat primitives, meshes of
//! triangles and spheres), bit-identical ids and `t` for closest hits and the same any-hit
//! answers, naive counting `rays x total` tests (`raybench_tests::check`); instanced scenes
//! against the same scenes flattened (`raybench_core::flatten`); and the built-in scenes
//! too large for the oracle against the baseline.
//!
//! The built-in scenes `instances` and `instance-grid` are checked by `equivalence.rs` with
//! every other built-in.

use raybench_core::{RayCounters, Scene};
use raybench_registry::Roles;
use raybench_tests::{
    BASELINE, ORACLE, assert_same_hits, assert_same_ray_hits, available, check, check_modes,
    load_or_skip, prepared, render_with,
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
/// for bit, on camera and incoherent rays, and in Whitted and path-traced frames (16 x 16,
/// colours too). Each builds a two-level structure over the distinct meshes only, so this
/// is cheap where naive would take minutes. At least one scene is checked, unless the shared
/// meshes are absent (a skip that fails under `CI=true`).
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
    let (mut checked, mut skipped) = (Vec::new(), 0);
    for b in raybench_scene::BUILTIN_SCENES
        .iter()
        .filter(|b| b.benchmark.heavy)
    {
        let Some(scene) = load_or_skip(b.name) else {
            skipped += 1;
            continue;
        };
        if scene.geometry.total_len() <= raybench_tests::ORACLE_PRIMITIVES {
            continue;
        }
        checked.push(b.name);
        let reference = prepared(BASELINE, &scene).render(&settings).unwrap();
        let seen = reference
            .ids
            .iter()
            .filter(|&&id| id != raybench_core::NO_HIT)
            .count();
        assert!(seen > 1000, "{}: {seen} pixels hit", b.name);
        let rays = raybench_core::ray_sets::incoherent(scene.geometry.world_bounds(), 2304, 1);
        let baseline = prepared(BASELINE, &scene);
        let (ref_hits, _) = baseline.trace_rays(&rays, false).unwrap();
        let mode_references: Vec<_> = MODES
            .iter()
            .map(|&(mode, spp)| {
                baseline
                    .render(&raybench_tests::mode_settings(16, mode, spp))
                    .unwrap()
            })
            .collect();
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
            for (i, reference) in mode_references.iter().enumerate() {
                let (mode, spp) = MODES[i];
                let what = format!("{name} on {}, {}", b.name, mode.name());
                let frame = r
                    .render(&raybench_tests::mode_settings(16, mode, spp))
                    .unwrap();
                assert_same_hits(&what, reference, &frame);
                let bits = |c: &raybench_core::Vec3| c.to_array().map(f32::to_bits);
                assert!(
                    frame
                        .color
                        .iter()
                        .map(bits)
                        .eq(reference.color.iter().map(bits)),
                    "{what}: colours differ"
                );
            }
        }
    }
    eprintln!("checked against the baseline: {checked:?}");
    assert!(
        !checked.is_empty() || skipped > 0,
        "no built-in scene is over ORACLE_PRIMITIVES: nothing was checked"
    );
}

/// Whitted and path tracing (2 samples) on the large instanced scenes, against the baseline.
const MODES: [(raybench_core::Mode, u32); 2] = [
    (raybench_core::Mode::Whitted, 1),
    (raybench_core::Mode::Path, 2),
];

/// Every exact backend's two-level structure holds each distinct mesh's structure once
/// (its memory stays far below 60 copies' worth), and so do the GPU backends.
#[test]
fn structure_counts_meshes_once_on_every_backend() {
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
    // The GPU backends hold the mesh once too (where an adapter is found: skipped with the
    // reason, failing under `CI=true`, without one).
    if !raybench_tests::gpu::available() {
        return;
    }
    let mut devices = 0;
    for b in raybench_registry::BACKENDS
        .iter()
        .filter(|b| b.is(Roles::DEVICE))
    {
        let stats = prepared(b.name, &scene).structure().unwrap();
        assert!(
            stats.counts.contains(&("instances", 60)) && stats.counts.contains(&("meshes", 1)),
            "{}: {stats:?}",
            b.name
        );
        devices += 1;
    }
    assert_eq!(
        devices,
        raybench_tests::DEVICES.len(),
        "GPU backends checked"
    );
}

/// A glTF file of one smooth UV sphere (vertex normals) placed by five nodes, rotated,
/// non-uniformly scaled and one mirrored: with `shared`, every node names mesh 0; without,
/// node `k` names mesh `k`, five meshes with the same accessors (so each is placed once and
/// copied, as before instancing). The same scene either way.
fn spheres_gltf(shared: bool) -> String {
    use base64::Engine as _;
    let (rings, segments) = (8u16, 12u16);
    let (mut positions, mut indices) = (Vec::new(), Vec::new());
    for r in 0..=rings {
        let theta = std::f32::consts::PI * f32::from(r) / f32::from(rings);
        for s in 0..=segments {
            let phi = std::f32::consts::TAU * f32::from(s) / f32::from(segments);
            positions.extend([
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ]);
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b) = (r * row + s, (r + 1) * row + s);
            indices.extend([a, b, a + 1, a + 1, b, b + 1]);
        }
    }
    let mut bin: Vec<u8> = Vec::new();
    // Positions, then the same numbers as normals (a unit sphere's), then indices.
    for _ in 0..2 {
        bin.extend(positions.iter().flat_map(|x: &f32| x.to_le_bytes()));
    }
    bin.extend(indices.iter().flat_map(|i: &u16| i.to_le_bytes()));
    let vbytes = positions.len() * 4;
    let uri = base64::engine::general_purpose::STANDARD.encode(&bin);
    let nodes = [
        r#""translation": [-2.2, 0, 0]"#,
        r#""translation": [0, 0, 0], "rotation": [0, 0, 0.258819, 0.9659258], "scale": [-0.8, 0.8, 0.8]"#,
        r#""translation": [2.2, 0, 0], "rotation": [0.3826834, 0, 0, 0.9238795], "scale": [1, 0.5, 1]"#,
        r#""translation": [-1.1, 1.8, -1], "rotation": [0, 0.7071068, 0, 0.7071068], "scale": [0.6, 0.6, 1.4]"#,
        r#""translation": [1.1, 1.8, -1], "scale": [0.7, -0.7, 0.7]"#,
    ];
    let node_list: Vec<String> = nodes
        .iter()
        .enumerate()
        .map(|(k, t)| format!(r#"{{"mesh": {}, {t}}}"#, if shared { 0 } else { k }))
        .collect();
    let mesh = r#"{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2}]}"#;
    let meshes = vec![mesh; if shared { 1 } else { nodes.len() }].join(", ");
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0,
        "scenes": [{{"nodes": [0, 1, 2, 3, 4]}}],
        "nodes": [{}],
        "meshes": [{meshes}],
        "buffers": [{{"uri": "data:application/octet-stream;base64,{uri}", "byteLength": {}}}],
        "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": {vbytes}}},
                        {{"buffer": 0, "byteOffset": {vbytes}, "byteLength": {vbytes}}},
                        {{"buffer": 0, "byteOffset": {}, "byteLength": {}}}],
        "accessors": [
          {{"bufferView": 0, "componentType": 5126, "count": {n}, "type": "VEC3",
            "min": [-1, -1, -1], "max": [1, 1, 1]}},
          {{"bufferView": 1, "componentType": 5126, "count": {n}, "type": "VEC3"}},
          {{"bufferView": 2, "componentType": 5123, "count": {}, "type": "SCALAR"}}]}}"#,
        node_list.join(", "),
        bin.len(),
        2 * vbytes,
        indices.len() * 2,
        indices.len(),
        n = positions.len() / 3,
    )
}

/// A glTF mesh that several nodes place becomes instances (stored once), and renders like
/// the same file with one mesh per node: the same ids for all but a few pixels (see
/// `instances_match_the_flattened_scene` for why not all) and the same smooth shading on
/// rotated, mirrored and uniformly scaled instances, so its vertex normals follow each
/// instance's transform. Every exact
/// backend agrees with naive on it.
#[test]
fn gltf_meshes_placed_by_several_nodes_are_instances() {
    // Scene files with one camera: framing the geometry would frame the instances' boxes.
    let file = |name: &str, gltf: String| {
        let dir = scene_file(name, "").parent().unwrap().to_owned();
        std::fs::write(dir.join(format!("{name}.gltf")), gltf).unwrap();
        scene_file(
            name,
            &format!(
                "[camera]\nposition = [0, 1, 7]\nlook_at = [0, 0.6, 0]\nfov = 50\n\
                 [[light]]\nkind = \"point\"\nposition = [3, 6, 5]\nintensity = [50, 50, 50]\n\
                 [[object]]\nkind = \"mesh\"\npath = \"{name}.gltf\"\n"
            ),
        )
    };
    let (shared, copied) = (
        file("shared", spheres_gltf(true)),
        file("copied", spheres_gltf(false)),
    );
    let a = load_or_skip(shared.to_str().unwrap()).unwrap();
    let b = load_or_skip(copied.to_str().unwrap()).unwrap();
    let (ga, gb) = (&a.geometry, &b.geometry);
    assert_eq!(
        (ga.len(), ga.meshes().len(), ga.instances().len()),
        (0, 1, 5)
    );
    assert!(!gb.has_instances() && gb.len() == ga.total_len());
    assert!(
        a.warnings.is_empty(),
        "the instanced mesh keeps its normals: {:?}",
        a.warnings
    );
    check(&available(BACKENDS), shared.to_str().unwrap(), 48);
    // The GPU kernels shade instanced vertex normals too (against naive on a textured
    // instanced mesh: `instanced_smooth_textured_mesh` in `tests/tests/gpu/shading.rs`).
    for b in raybench_registry::BACKENDS
        .iter()
        .filter(|b| b.is(Roles::DEVICE))
    {
        assert_eq!((b.make)().supports(&a), Ok(()), "{}", b.name);
    }

    let settings = raybench_tests::mode_settings(96, raybench_core::Mode::Cast, 1);
    let (fa, fb) = (
        render_with(BASELINE, &a, &settings, 2),
        render_with(BASELINE, &b, &settings, 2),
    );
    let (mut same, mut other, mut uniform, mut worst) = (0, 0, 0, 0.0f32);
    for i in 0..fa.ids.len() {
        if fa.ids[i] != fb.ids[i] {
            other += 1;
        } else if let Some((k, _)) = ga.locate(fa.ids[i]) {
            same += 1;
            // Under a non-uniform scale, normals normalised per vertex and then
            // interpolated (the copy) differ from normals interpolated and then carried
            // (the instance): compared where the scale is uniform (rotations, mirrors).
            let m = ga.instances()[k].to_world().matrix3;
            let lengths = [m.x_axis.length(), m.y_axis.length(), m.z_axis.length()];
            if lengths.iter().all(|l| (l - lengths[0]).abs() < 1e-5) {
                uniform += 1;
                worst = worst.max((fa.color[i] - fb.color[i]).abs().max_element());
            }
        }
    }
    assert!(
        same > 2000 && other * 100 <= same,
        "{same} same, {other} other"
    );
    assert!(
        uniform > 1000,
        "{uniform} pixels of uniformly scaled instances"
    );
    assert!(worst < 1e-3, "shading differs by {worst}");

    // Flattened (`raybench_core::flatten`), the instanced file shades as the copied one
    // everywhere, non-uniform scales included: its vertex normals are carried vertex by
    // vertex and then interpolated, as the copies' are.
    let flat = Arc::new(raybench_core::flatten(&a).unwrap());
    assert!(!flat.geometry.has_instances() && flat.mesh_attributes.is_empty());
    let ff = render_with(BASELINE, &flat, &settings, 2);
    let (mut both, mut worst) = (0, 0.0f32);
    for i in 0..ff.ids.len() {
        if ff.ids[i] == fb.ids[i] && ff.ids[i] != raybench_core::NO_HIT {
            both += 1;
            worst = worst.max((ff.color[i] - fb.color[i]).abs().max_element());
        }
    }
    assert!(both > 2000, "{both} pixels on the same primitive");
    assert!(worst < 1e-3, "flattened shading differs by {worst}");
}
