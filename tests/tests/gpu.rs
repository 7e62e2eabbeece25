//! The GPU backends (`wgpu` over the BVH2, `wgpu-cwbvh` over the compressed wide BVH:
//! `raybench_tests::DEVICES`) against the naive oracle on every built-in scene, within the
//! tolerances of `raybench_tests::gpu`, closest hits and any hits. Runs on whatever adapter wgpu finds: Mesa's lavapipe
//! (software Vulkan, about one CPU thread's speed) in CI, so images stay small. Skips when
//! there is no adapter, except under `CI=true`.

use raybench_core::{RenderError, Renderer};
use raybench_tests::gpu::check;

/// Built-in scenes that `every_builtin_scene` leaves to another test, and why.
const ELSEWHERE: &[(&str, &str)] = &[(
    "phantom",
    "volumes without surfaces: phantom_volume_modes compares its modes (mip, composite)",
)];

/// Built-in scenes checked in ray casting only (the secondary modes are for the scenes
/// that are not `heavy`), and why.
const CAST_ONLY: &[(&str, &str)] = &[(
    "bunny-lowres",
    "3,674 triangles: its secondary modes on the oracle and on lavapipe cost minutes for \
     what the smaller triangle scenes already check",
)];

/// Ray casting at 64 x 64 (the equivalence test's size) on every built-in scene
/// (`raybench_scene::BUILTIN_SCENES`, found from `bench-scenes/`, so a new scene file is
/// checked by itself); the modes with secondary rays at 32 x 32 on the scenes that are not
/// `heavy` (their `[benchmark]` table says so) nor in [`CAST_ONLY`]. Left out: the scenes of
/// [`ELSEWHERE`], and, as in the equivalence tests, the heavy ones over
/// [`raybench_tests::ORACLE_PRIMITIVES`] flattened, too large for the oracle.
#[test]
fn every_builtin_scene() {
    for (name, why) in ELSEWHERE.iter().chain(CAST_ONLY) {
        assert!(
            raybench_scene::BUILTIN_SCENES
                .iter()
                .any(|b| b.name == *name),
            "{name} is no built-in scene ({why})"
        );
    }
    for b in raybench_scene::BUILTIN_SCENES {
        if let Some((_, why)) = ELSEWHERE.iter().find(|(n, _)| *n == b.name) {
            eprintln!("{}: left out: {why}", b.name);
            continue;
        }
        if b.benchmark.heavy
            && raybench_tests::load_or_skip(b.name)
                .is_some_and(|s| s.geometry.total_len() > raybench_tests::ORACLE_PRIMITIVES)
        {
            eprintln!("{}: left out: too large for the oracle", b.name);
            continue;
        }
        let modes = !b.benchmark.heavy && !CAST_ONLY.iter().any(|(n, _)| *n == b.name);
        check(b.name, if modes { 32 } else { 64 }, modes);
    }
}

/// The generator specs, as the equivalence tests check them: ray casting at 64 x 64, the
/// modes with secondary rays at 32 x 32 on the small ones.
macro_rules! gpu_tests {
    ($($test:ident => $scene:literal, $modes:literal,)*) => {
        $(
            #[test]
            fn $test() {
                check($scene, if $modes { 32 } else { 64 }, $modes);
            }
        )*
    };
}

gpu_tests! {
    random_spheres => "spheres:2000", true,
    terrain => "terrain:32", true,
    soup => "soup:10000", false,
    icosphere => "icosphere:4", false,
    heightfield_generator => "heightfield:64", true,
}

#[test]
fn a_missing_adapter_is_reported_not_panicked() {
    let request = raybench_wgpu::AdapterRequest::named("no such adapter 1f8e3c");
    let mut r = raybench_wgpu::WgpuRenderer::with_request("wgpu", "test", request);
    let reason = r.availability().unwrap_err();
    assert!(reason.contains("no such adapter 1f8e3c"), "{reason}");
    let scene =
        std::sync::Arc::new(raybench_scene::load("spheres", std::path::Path::new(".")).unwrap());
    match r.prepare(&scene) {
        Err(RenderError::Unavailable(why)) => assert_eq!(why, reason),
        other => panic!("expected Unavailable, got {other:?}"),
    }
    assert!(matches!(
        r.render(&Default::default()),
        Err(RenderError::NotPrepared)
    ));
}

#[test]
fn the_empty_scene_renders_background() {
    if !raybench_tests::gpu::available() {
        return;
    }
    let scene = raybench_tests::empty_scene();
    for name in raybench_tests::DEVICES {
        let r = raybench_tests::prepared(name, &scene);
        let settings = raybench_core::RenderSettings {
            width: 8,
            height: 5,
            ..Default::default()
        };
        let f = r.render(&settings).unwrap();
        assert!(
            f.ids.iter().all(|&id| id == raybench_core::NO_HIT),
            "{name}"
        );
        assert!(f.color.iter().all(|&c| c == scene.background), "{name}");
        let rays = [raybench_core::Ray::new(
            raybench_core::Vec3::ZERO,
            raybench_core::Vec3::X,
        )];
        assert_eq!(r.occlude_rays(&rays, false).unwrap().0, [false], "{name}");
    }
}

/// Every kind and every mode has a kernel (height fields with bilinear cells in
/// `kernels/bilinear.wgsl`, the volume modes in `kernels/volume.wgsl`).
#[test]
fn every_kind_and_mode_has_a_kernel() {
    let r = raybench_wgpu::WgpuRenderer::new("wgpu", "test");
    for mode in [raybench_core::Mode::Mip, raybench_core::Mode::Composite] {
        assert_eq!(r.supports_mode(mode), Ok(()), "{}", mode.name());
    }
    let mut b = raybench_core::SceneBuilder::new("bilinear");
    let field = raybench_core::HeightField::new(2, 2, vec![0.0; 9], None)
        .unwrap()
        .with_surface(raybench_core::CellSurface::Bilinear);
    b.add_shapes(
        "field",
        vec![raybench_core::Shape::HeightField(std::sync::Arc::new(
            field,
        ))],
        0,
    )
    .unwrap();
    let scene = b.build();
    assert!(raybench_wgpu::check_kinds(&scene).is_ok());
    let mut b = raybench_core::SceneBuilder::new("bezier");
    let points =
        std::array::from_fn(|k| raybench_core::Vec3::new((k % 4) as f32, (k / 4) as f32, 0.0));
    let patch = raybench_core::BezierPatch::new(points).unwrap();
    b.add_shapes(
        "patch",
        vec![raybench_core::Shape::Bezier(std::sync::Arc::new(patch))],
        0,
    )
    .unwrap();
    // Bezier patches have their port (`kernels/bezier.wgsl`).
    assert!(raybench_wgpu::check_kinds(&b.build()).is_ok());
    // Environment maps and emissive spheres are ported (see the shading tests below).
    let mut b = raybench_core::SceneBuilder::new("lights");
    let lamp = b
        .add_material(raybench_core::Material {
            emission: raybench_core::Vec3::ONE,
            ..raybench_core::Material::default()
        })
        .unwrap();
    b.add_sphere(
        raybench_core::Sphere::new(raybench_core::Vec3::ZERO, 1.0),
        lamp,
    )
    .unwrap();
    let lamp_scene = b.clone().build();
    assert!(raybench_wgpu::check_kinds(&lamp_scene).is_ok());
    let env = raybench_core::Environment::new(1, 1, vec![raybench_core::Vec3::ONE], 1.0, 0.0);
    b.environment(std::sync::Arc::new(env.unwrap()));
    assert!(raybench_wgpu::check_kinds(&b.build()).is_ok());
    if !raybench_tests::gpu::available() {
        return;
    }
    let mut r = r;
    assert_eq!(r.supports(&scene), Ok(()));
    assert!(r.prepare(&std::sync::Arc::new(scene)).is_ok());
}

/// Textures and shading normals are ported (`shading.rs`): scenes with them are accepted
/// (without an adapter too), as are faceted ones without textures.
#[test]
fn textures_and_shading_normals_are_accepted() {
    use raybench_core::{
        Material, Renderer as _, SceneBuilder, Texture, TriangleMesh, Vec2, Vec3, VertexAttributes,
        Wrap,
    };
    let r = raybench_wgpu::WgpuRenderer::new("wgpu", "test");
    let mesh = TriangleMesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        indices: vec![[0, 1, 2]],
    };
    let scene = |normals: Vec<Vec3>, textured: bool| {
        let mut b = SceneBuilder::new("t");
        let mut m = Material::default();
        if textured {
            let t = Texture::new("t", 1, 1, vec![Vec3::ONE], [Wrap::Repeat; 2]).unwrap();
            m.base_color_texture = Some(b.add_texture("t", t));
        }
        let m = b.add_material(m).unwrap();
        let uvs = vec![Vec2::ZERO; 3];
        b.add_mesh_with_attributes("m", &mesh, VertexAttributes { normals, uvs }, &[m])
            .unwrap();
        b.build()
    };
    assert_eq!(r.supports(&scene(vec![], true)), Ok(()));
    assert_eq!(r.supports(&scene(vec![Vec3::Z; 3], false)), Ok(()));
    // Texture coordinates alone change nothing the GPU renders.
    let plain = scene(vec![], false);
    assert!(!plain.attributes.is_empty());
    assert_eq!(r.supports(&plain), Ok(()));
}

/// Rays no camera makes: NaN, zero and infinite directions must miss on the GPU as on the
/// CPU (and not poison their neighbours in the same workgroup); denormal, huge and
/// axis-aligned rays must find naive's hits.
#[test]
fn degenerate_and_extreme_rays_behave_as_on_the_cpu() {
    use raybench_core::{Ray, Vec3};
    if !raybench_tests::gpu::available() {
        return;
    }
    let scene = raybench_tests::load_or_skip("spheres:200").unwrap();
    let c = scene.geometry.bounds().center();
    let tiny = f32::MIN_POSITIVE / 4.0;
    let mut rays = vec![
        Ray::new(Vec3::splat(f32::NAN), Vec3::X),
        Ray::new(c, Vec3::new(f32::NAN, 1.0, 0.0)),
        Ray::new(c, Vec3::ZERO),
        Ray::new(c, Vec3::new(f32::INFINITY, 0.0, 0.0)),
        Ray::new(c + Vec3::splat(1e30), -Vec3::ONE),
    ];
    let must_miss = rays.len() - 1;
    for axis in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
        rays.push(Ray::new(c, axis));
        rays.push(Ray::new(c, axis + Vec3::splat(tiny)));
        rays.push(Ray::new(c - axis * 1e6, axis * 1e-20));
    }
    // Ordinary rays between them: a bad lane must not spoil the others.
    rays.extend(raybench_core::ray_sets::incoherent(
        scene.geometry.bounds(),
        64,
        3,
    ));
    let (reference, _) = raybench_tests::prepared(raybench_tests::ORACLE, &scene)
        .trace_rays(&rays, false)
        .unwrap();
    for name in raybench_tests::DEVICES {
        let gpu = raybench_tests::prepared(name, &scene);
        let (hits, _) = gpu.trace_rays(&rays, false).unwrap();
        check_extreme(name, &rays, &reference, &hits, must_miss);
        // The any-hit kernel: the same rays blocked.
        let (blocked, _) = gpu.occlude_rays(&rays, false).unwrap();
        let expected: Vec<bool> = reference.iter().map(Option::is_some).collect();
        assert_eq!(blocked, expected, "{name}: any-hit rays");
    }
}

/// Every ray of `hits` as `reference` has it: the first `must_miss` miss, the others hit the
/// same primitive within [`raybench_tests::gpu::MAX_REL_DT`].
fn check_extreme(
    name: &str,
    rays: &[raybench_core::Ray],
    reference: &[Option<raybench_core::Hit>],
    hits: &[Option<raybench_core::Hit>],
    must_miss: usize,
) {
    for (i, (a, b)) in reference.iter().zip(hits).enumerate() {
        if i < must_miss {
            assert!(
                a.is_none() && b.is_none(),
                "{name}: ray {i} {:?}: {a:?} {b:?}",
                rays[i]
            );
            continue;
        }
        assert_eq!(
            a.map(|h| h.prim),
            b.map(|h| h.prim),
            "{name}: ray {i} {:?}",
            rays[i]
        );
        if let (Some(a), Some(b)) = (a, b) {
            assert!(
                (a.t - b.t).abs() <= raybench_tests::gpu::MAX_REL_DT as f32 * a.t.abs(),
                "{name}: ray {i}: t {} vs {}",
                a.t,
                b.t
            );
        }
    }
}

/// Many samples on a small frame, split into many dispatches (progressive accumulation,
/// `plan::MAX_SAMPLES_PER_DISPATCH`): every sample is traced and the accumulated image
/// matches the CPU's.
#[test]
fn samples_split_over_dispatches_accumulate() {
    use raybench_core::{Mode, RenderSettings};
    if !raybench_tests::gpu::available() {
        return;
    }
    let scene = raybench_tests::load_or_skip("spheres").unwrap();
    let settings = RenderSettings {
        width: 8,
        height: 8,
        spp: 2_000,
        mode: Mode::Path,
        max_depth: 3,
        seed: 3,
        count: false,
        ..RenderSettings::default()
    };
    let pixels = u64::from(settings.width * settings.height);
    let plan = raybench_wgpu::plan::frame(
        settings.width,
        settings.height,
        settings.spp,
        raybench_wgpu::plan::budget(Mode::Path),
        pixels,
        raybench_wgpu::plan::MAX_SAMPLES_PER_DISPATCH,
        65_535,
    );
    assert!(
        plan[0].dispatches.len() > 1,
        "the test must split: {plan:?}"
    );
    let reference = raybench_tests::render_with(raybench_tests::ORACLE, &scene, &settings, 2);
    for name in raybench_tests::DEVICES {
        let frame = raybench_tests::prepared(name, &scene)
            .render(&settings)
            .unwrap();
        assert_eq!(frame.ids, reference.ids, "{name}");
        // Every sample traced: a lost sample (as when lavapipe cut a thread's long loop, see
        // `plan::MAX_SAMPLES_PER_DISPATCH`) shows as missing rays. Paths may branch
        // differently on the GPU, so the counts agree within 1%.
        let (a, b) = (reference.stats.rays as f64, frame.stats.rays as f64);
        assert!((a - b).abs() <= 0.01 * a, "rays: naive {a}, {name} {b}");
        raybench_tests::gpu::assert_close_colors(
            &format!("{name}, path, 2,000 samples"),
            &reference.color,
            &frame.color,
            raybench_tests::gpu::MAX_PATH_COLOR_MISMATCH,
        );
    }
}

/// The two GPU trees walk to the same hits: every ray of a seeded incoherent set and every
/// pixel of a small frame get the same primitive and bit-identical `t` from `wgpu` and
/// `wgpu-cwbvh` (the same primitive routine on the same rays; only the culling differs, and
/// both cull conservatively), and their node-visit counters differ as their trees do.
#[test]
fn the_gpu_trees_find_the_same_hits() {
    if !raybench_tests::gpu::available() {
        return;
    }
    for scene in [
        "teapot",
        "spheres:2000",
        "soup:2000",
        "terrain:32",
        "instance-grid",
    ] {
        // `teapot` needs the shared meshes: skipped, saying so, without them.
        let Some(s) = raybench_tests::load_or_skip(scene) else {
            continue;
        };
        let rays = raybench_core::ray_sets::incoherent(s.geometry.world_bounds(), 4096, 5);
        let results: Vec<_> = raybench_tests::DEVICES
            .iter()
            .map(|name| {
                let r = raybench_tests::prepared(name, &s);
                let (hits, counters) = r.trace_rays(&rays, true).unwrap();
                let settings = raybench_tests::mode_settings(48, raybench_core::Mode::Cast, 1);
                let frame = r.render(&settings).unwrap();
                let key: Vec<(u32, u32)> = hits
                    .iter()
                    .map(|h| h.map_or((raybench_core::NO_HIT, 0), |h| (h.prim, h.t.to_bits())))
                    .collect();
                (key, frame.ids, frame.t, counters.unwrap())
            })
            .collect();
        for w in results.windows(2) {
            assert_eq!(w[0].0, w[1].0, "{scene}: explicit rays");
            assert_eq!(w[0].1, w[1].1, "{scene}: pixel ids");
            assert!(
                w[0].2
                    .iter()
                    .zip(&w[1].2)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "{scene}: pixel t"
            );
            assert_eq!(w[0].3.node_visits == 0, w[1].3.node_visits == 0, "{scene}");
            eprintln!(
                "{scene}: node visits {} vs {}, primitive tests {} vs {}",
                w[0].3.node_visits, w[1].3.node_visits, w[0].3.prim_tests, w[1].3.prim_tests
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// SDF models (`kernels/sdf.wgsl`, `geo/sdf.rs`): beyond the built-in `sdf` scene (in
// `gpu_tests!`), every operation (intersection too), a capsule whose ends coincide, rotated
// and scaled transforms, and the deepest trees the loader accepts, which fill the kernel's
// value stack (a right-leaning chain: `MAX_SDF_DEPTH` values) and point stack
// (nested transforms with a sibling at every level, so that every saved point is used).

/// A sphere leaf.
fn sdf_ball(center: raybench_core::Vec3, radius: f32) -> raybench_core::SdfNode {
    raybench_core::SdfNode::Leaf(raybench_core::SdfPrimitive::Sphere { center, radius })
}

/// `op` on two subtrees.
fn sdf_op(
    op: raybench_core::SdfOp,
    a: raybench_core::SdfNode,
    b: raybench_core::SdfNode,
) -> raybench_core::SdfNode {
    raybench_core::SdfNode::Op(op, Box::new(a), Box::new(b))
}

/// Three SDF models over a floor: glass with every operation and primitive (ids 1), a
/// mirror chain of `MAX_SDF_DEPTH - 1` unions (id 2), a diffuse torus under nested
/// transforms, each with a ball beside its subtree, `MAX_SDF_DEPTH` levels in all (id 3);
/// and the world centres of those balls.
fn sdf_models_scene() -> (
    std::sync::Arc<raybench_core::Scene>,
    Vec<raybench_core::Vec3>,
) {
    use raybench_core::limits::MAX_SDF_DEPTH;
    use raybench_core::{
        Affine3A, Camera, Light, Material, MaterialKind, Sdf, SdfNode, SdfOp, SdfParams,
        SdfPrimitive, Shape, Vec3,
    };
    let v = Vec3::new;
    let mut b = raybench_core::SceneBuilder::new("sdf-models");
    b.camera(Camera {
        position: v(0.0, 2.0, 6.0),
        look_at: v(0.0, 0.6, 0.0),
        up: Vec3::Y,
        vfov_degrees: 45.0,
    })
    .unwrap();
    b.add_light(Light::Point {
        position: v(-3.0, 5.0, 4.0),
        intensity: v(30.0, 30.0, 30.0),
    })
    .unwrap();
    let material = |name: &str, kind, color| Material {
        name: name.into(),
        kind,
        base_color: color,
        specular: Vec3::splat(0.9),
        shininess: 20.0,
        ior: 1.5,
        ..Material::default()
    };
    let floor = b
        .add_material(material("floor", MaterialKind::Diffuse, v(0.8, 0.7, 0.4)))
        .unwrap();
    let glass = b
        .add_material(material("glass", MaterialKind::Glass, Vec3::ONE))
        .unwrap();
    let mirror = b
        .add_material(material("mirror", MaterialKind::Mirror, Vec3::ONE))
        .unwrap();
    let clay = b
        .add_material(material("clay", MaterialKind::Diffuse, v(0.8, 0.4, 0.3)))
        .unwrap();
    b.add_plane(Vec3::ZERO, Vec3::Y, floor).unwrap();
    // Every operation and primitive, a scaled and rotated transform, a capsule of length 0.
    let c = v(-1.9, 0.8, 0.0);
    let rounded = SdfNode::Leaf(SdfPrimitive::Box {
        center: c,
        half_extents: v(0.6, 0.5, 0.5),
        rounding: 0.1,
    });
    let turned = SdfNode::Transform(
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.5),
            glam::Quat::from_rotation_x(0.6),
            c + v(0.0, 0.55, 0.0),
        ),
        Box::new(sdf_op(
            SdfOp::Blend(0.3),
            SdfNode::Leaf(SdfPrimitive::Torus {
                center: Vec3::ZERO,
                major_radius: 0.8,
                minor_radius: 0.3,
            }),
            SdfNode::Leaf(SdfPrimitive::Cylinder {
                center: Vec3::ZERO,
                radius: 0.5,
                half_height: 0.4,
            }),
        )),
    );
    let cut = sdf_op(
        SdfOp::Union,
        SdfNode::Leaf(SdfPrimitive::Capsule {
            a: c + v(-0.7, -0.1, 0.5),
            b: c + v(0.7, 0.1, 0.5),
            radius: 0.15,
        }),
        SdfNode::Leaf(SdfPrimitive::Capsule {
            a: c + v(0.3, 0.0, 0.55),
            b: c + v(0.3, 0.0, 0.55),
            radius: 0.25,
        }),
    );
    let every = sdf_op(
        SdfOp::Subtraction,
        sdf_op(
            SdfOp::SmoothUnion(0.2),
            sdf_op(SdfOp::Intersection, rounded, sdf_ball(c, 0.75)),
            turned,
        ),
        cut,
    );
    // A right-leaning chain: the deepest value stack.
    let mut chain = sdf_ball(v(0.0, 0.5, 0.0), 0.4);
    for i in 1..MAX_SDF_DEPTH {
        let a = i as f32 * std::f32::consts::TAU / (MAX_SDF_DEPTH - 1) as f32;
        let ball = sdf_ball(v(0.45 * a.cos(), 0.5 + 0.1 * a.sin(), 0.45 * a.sin()), 0.15);
        chain = sdf_op(SdfOp::Union, ball, chain);
    }
    // Nested transforms, each turning and scaling a little, with a ball beside the subtree
    // at every level, evaluated after it: every saved point is restored and used.
    let mut nested = SdfNode::Leaf(SdfPrimitive::Torus {
        center: Vec3::ZERO,
        major_radius: 0.5,
        minor_radius: 0.15,
    });
    // The balls' centres, in the frame of `nested` as it grows.
    let mut centres = Vec::new();
    for i in 0..(MAX_SDF_DEPTH - 2) / 2 {
        let scale = if i % 2 == 0 { 1.25 } else { 0.8 };
        let m = Affine3A::from_scale_rotation_translation(
            Vec3::splat(scale),
            glam::Quat::from_rotation_z(0.3),
            v(0.01, 0.0, 0.0),
        );
        let centre = v(0.6, 0.0, 0.1);
        centres.push(centre);
        centres = centres.iter().map(|&c| m.transform_point3(c)).collect();
        nested = SdfNode::Transform(
            m,
            Box::new(sdf_op(SdfOp::Union, nested, sdf_ball(centre, 0.06))),
        );
    }
    let outer = Affine3A::from_translation(v(1.9, 0.7, 0.0));
    let centres = centres.iter().map(|&c| outer.transform_point3(c)).collect();
    nested = SdfNode::Transform(outer, Box::new(nested));
    for (name, tree, m) in [
        ("every", every, glass),
        ("chain", chain, mirror),
        ("nested", nested, clay),
    ] {
        let model = Sdf::new(&tree, SdfParams::DEFAULT).unwrap();
        b.add_shapes(name, vec![Shape::Sdf(std::sync::Arc::new(model))], m)
            .unwrap();
    }
    (std::sync::Arc::new(b.build()), centres)
}

/// Every GPU backend against naive on [`sdf_models_scene`]: ray casting and Whitted at 32 x
/// 32 and incoherent closest-hit rays, within the shared tolerances of
/// `raybench_tests::gpu`.
#[test]
fn sdf_every_operation_and_the_deepest_trees() {
    use raybench_core::Vec3;
    use raybench_tests::gpu::{MAX_COLOR_MISMATCH, MAX_REL_DT, MIN_ID_MATCH};
    if !raybench_tests::gpu::available() {
        return;
    }
    let (scene, centres) = sdf_models_scene();
    let oracle = raybench_tests::prepared(raybench_tests::ORACLE, &scene);
    // Incoherent rays in the models' box.
    let models = scene
        .geometry
        .shapes()
        .iter()
        .filter_map(raybench_core::Shape::bounds)
        .fold(raybench_core::Aabb::EMPTY, raybench_core::Aabb::union);
    // From a random point of the box towards another (the rays of one seed aimed at the
    // origins of another), so that most of them cross the models.
    let targets = raybench_core::ray_sets::incoherent(models, 1024, 4);
    let rays: Vec<raybench_core::Ray> = raybench_core::ray_sets::incoherent(models, 1024, 3)
        .iter()
        .zip(&targets)
        .map(|(r, to)| raybench_core::Ray::new(r.origin, to.origin - r.origin))
        .collect();
    let (reference_hits, _) = oracle.trace_rays(&rays, false).unwrap();
    for name in raybench_tests::DEVICES {
        let gpu = raybench_tests::prepared(name, &scene);
        for mode in [raybench_core::Mode::Cast, raybench_core::Mode::Whitted] {
            let settings = raybench_tests::mode_settings(32, mode, 1);
            let reference =
                raybench_tests::render_with(raybench_tests::ORACLE, &scene, &settings, 2);
            // The camera sees each model.
            for id in 1..=3 {
                assert!(reference.ids.contains(&id), "model {id} not in view");
            }
            let frame = gpu.render(&settings).unwrap();
            let what = format!("{name} on sdf models, {}", mode.name());
            raybench_tests::gpu::assert_close_hits(&what, &reference, &frame);
            raybench_tests::gpu::assert_close_colors(
                &what,
                &reference.color,
                &frame.color,
                MAX_COLOR_MISMATCH,
            );
        }
        // Rays aimed at the nested model's balls from three sides: a ball misplaced (a
        // saved point restored wrong) changes their hits, which must all agree.
        let aimed: Vec<raybench_core::Ray> = centres
            .iter()
            .flat_map(|&c| {
                [Vec3::Z, Vec3::Y, Vec3::X - Vec3::Z]
                    .map(|d| raybench_core::Ray::new(c + d * 3.0, -d))
            })
            .collect();
        let (want, _) = oracle.trace_rays(&aimed, false).unwrap();
        let (got, _) = gpu.trace_rays(&aimed, false).unwrap();
        for (i, (w, g)) in want.iter().zip(&got).enumerate() {
            let w = w.unwrap_or_else(|| panic!("aimed ray {i} misses on the CPU"));
            let agree =
                g.is_some_and(|g| g.prim == w.prim && (w.t - g.t).abs() <= MAX_REL_DT as f32 * w.t);
            assert!(agree, "{name}: aimed ray {i}: {w:?} vs {g:?}");
        }
        let (hits, _) = gpu.trace_rays(&rays, false).unwrap();
        let key = |h: &[Option<raybench_core::Hit>]| -> (Vec<u32>, Vec<f32>) {
            (
                h.iter()
                    .map(|h| h.map_or(raybench_core::NO_HIT, |h| h.prim))
                    .collect(),
                h.iter().map(|h| h.map_or(f32::INFINITY, |h| h.t)).collect(),
            )
        };
        let ((ri, rt), (gi, gt)) = (key(&reference_hits), key(&hits));
        let c = raybench_registry::compare_hits(&ri, &rt, &gi, &gt);
        let on_models = ri.iter().filter(|&&id| (1..=3).contains(&id)).count();
        eprintln!("{name} on sdf models, incoherent rays ({on_models} hit a model): {c:?}");
        let id_match = c.id_match + c.tie_mismatch as f64 / rays.len() as f64;
        assert!(
            id_match >= MIN_ID_MATCH && c.max_rel_dt <= MAX_REL_DT,
            "{name} on sdf models, incoherent rays: {c:?}"
        );
    }
}

// ---------------------------------------------------------------------------------------
// Shading: textures, shading normals, every bounded emitter as a light of `path`, the
// environment map (`crates/wgpu/src/shading.rs`, `kernels/lights.wgsl`). The scenes are the
// files of `tests/scenes/`; each runs `raybench_tests::gpu::check` (ray casting at 1 and 4
// samples, Whitted, path tracing at 4 samples with MIS, explicit rays) at 32 x 32 with the
// shared tolerances, none widened.

/// The path of scene file `name` in `tests/scenes/`.
fn scene_file(name: &str) -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    path.to_str().unwrap().to_owned()
}

/// Emissive spheres (sampled by their cone) and an emissive triangle light a floor, a
/// diffuse and a mirror sphere; no point light, black background.
#[test]
fn emissive_spheres_are_sampled_lights() {
    check(&scene_file("emissive-spheres.toml"), 32, true);
}

/// A rotated 16 x 8 equirectangular map with a sun texel, and a small emissive sphere:
/// misses read the map in every mode; path tracing samples the map's distribution and the
/// sphere, with MIS.
#[test]
fn environment_map_lights_the_scene() {
    check(&scene_file("environment.toml"), 32, true);
}

/// A UV sphere with vertex normals and texture coordinates on a floor whose coordinates
/// repeat the texture, under a directional, a point and an emissive-sphere light.
#[test]
fn textured_smooth_mesh() {
    check(&scene_file("textured-smooth.toml"), 32, true);
}

/// A smooth textured mesh placed five times (as it is, rotated, mirrored, scaled unevenly,
/// with a material override): each instance's vertex normals carried by its normal matrix,
/// its texture coordinates read from the mesh's own table (`shading::mesh_attribute_tables`).
#[test]
fn instanced_smooth_textured_mesh() {
    check(&scene_file("instanced-smooth.toml"), 32, true);
}

/// Suzanne with her vertex normals (the built-in scene facets her).
#[test]
fn smooth_suzanne() {
    check(&scene_file("smooth-suzanne.toml"), 32, true);
}

// ---------------------------------------------------------------------------------------
// Height fields (`kernels/heightfield.wgsl`).

/// Height fields the built-in scenes do not cover, written as scene files and checked
/// against naive with [`check`] (ray casting, incoherent closest and any-hit rays; Whitted
/// and path tracing on the first):
/// a placed field (rotated, scaled unevenly, moved) with smooth normals, the same faceted,
/// a field that asks for the 2D-DDA walk (the GPU walks the tree: the same hits), a single
/// cell and a single row (trees of depth 0 and of one side only), and a field of non-square
/// cells; then placed fields of bilinear cells (`cells = "bilinear"`: the patch through each
/// cell's corners, `kernels/bilinear.wgsl`), smooth and faceted.
#[test]
fn height_field_variants_match_naive() {
    let dir = std::env::temp_dir().join(format!("raybench-gpu-hf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let rows = |nx: u32, nz: u32| -> String {
        let mut out = Vec::new();
        for j in 0..=nz {
            let row: Vec<String> = (0..=nx)
                .map(|i| {
                    let (x, z) = (i as f32 / nx as f32, j as f32 / nz.max(1) as f32);
                    format!(
                        "{:.4}",
                        0.3 * (7.0 * x).sin() * (5.0 * z + 1.0).cos() + 0.1 * x
                    )
                })
                .collect();
            out.push(format!("[{}]", row.join(", ")));
        }
        format!("[{}]", out.join(", "))
    };
    let scene = |name: &str, object: &str| {
        let text = format!(
            "name = \"{name}\"\nbackground = [0.5, 0.6, 0.8]\n\
             [camera]\nposition = [0.3, 1.6, 2.4]\nlook_at = [0.0, 0.0, 0.0]\nfov = 50\n\
             [[material]]\nname = \"land\"\ncolor = [0.4, 0.6, 0.3]\n\
             specular = [0.1, 0.1, 0.1]\nshininess = 16\n\
             [[material]]\nname = \"mirror\"\nkind = \"mirror\"\nspecular = [0.9, 0.9, 0.9]\n\
             [[light]]\nkind = \"directional\"\ndirection = [-0.4, -0.8, -0.3]\n\
             radiance = [1.0, 1.0, 1.0]\n\
             [[object]]\nkind = \"sphere\"\ncenter = [0.3, 0.6, -0.2]\nradius = 0.2\n\
             material = \"mirror\"\n\
             [[object]]\nkind = \"height_field\"\nmaterial = \"land\"\n{object}\n"
        );
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, text).unwrap();
        path.to_str().unwrap().to_owned()
    };
    let placed = "transform = { scale = [1.2, 1.5, 0.8], rotate = [10.0, 35.0, -5.0], \
                  translate = [0.1, -0.1, 0.05] }";
    let cases = [
        scene(
            "hf-placed",
            &format!("heights = {}\n{placed}", rows(40, 40)),
        ),
        scene(
            "hf-faceted",
            &format!("heights = {}\nsmooth = false\n{placed}", rows(24, 17)),
        ),
        scene(
            "hf-dda",
            &format!("heights = {}\ntraversal = \"dda\"", rows(33, 20)),
        ),
        scene("hf-one-cell", &format!("heights = {}", rows(1, 1))),
        scene("hf-one-row", &format!("heights = {}", rows(37, 1))),
        scene(
            "hf-bilinear",
            &format!("heights = {}\ncells = \"bilinear\"\n{placed}", rows(40, 40)),
        ),
        scene(
            "hf-bilinear-faceted",
            &format!(
                "heights = {}\ncells = \"bilinear\"\nsmooth = false\n{placed}",
                rows(24, 17)
            ),
        ),
    ];
    // Every mode on the placed field; ray casting (which shades with the normals) and explicit
    // rays on the others (naive's secondary rays are slow on lavapipe's one thread; every
    // mode on `hf-bilinear`, measured once: 0 pixels differ).
    for (k, spec) in cases.iter().enumerate() {
        check(spec, 32, k == 0);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The sub-primitive ids (the cell triangles) and the surface parameters of height-field
/// hits are naive's: seeded incoherent rays and rays from above aimed at every cell of the
/// `heightfield:48` field.
#[test]
fn height_field_hits_carry_naive_sub_primitives() {
    use raybench_core::{Ray, Vec3};
    if !raybench_tests::gpu::available() {
        return;
    }
    let scene = raybench_tests::load_or_skip("heightfield:48").unwrap();
    let mut rays = raybench_core::ray_sets::incoherent(scene.geometry.bounds(), 4096, 9);
    for j in 0..48 {
        for i in 0..48 {
            let target = Vec3::new(
                -1.0 + (i as f32 + 0.3) / 24.0,
                0.0,
                -1.0 + (j as f32 + 0.6) / 24.0,
            );
            let eye = Vec3::new(0.4, 2.0, 1.5);
            rays.push(Ray::new(eye, target - eye));
        }
    }
    let (reference, _) = raybench_tests::prepared(raybench_tests::ORACLE, &scene)
        .trace_rays(&rays, false)
        .unwrap();
    for name in raybench_tests::DEVICES {
        let (hits, _) = raybench_tests::prepared(name, &scene)
            .trace_rays(&rays, false)
            .unwrap();
        let (mut hit, mut same, mut max_dt, mut max_duv) = (0usize, 0usize, 0.0f32, 0.0f32);
        for (a, b) in reference.iter().zip(&hits) {
            assert_eq!(a.is_some(), b.is_some(), "{name}: hit or miss");
            if let (Some(a), Some(b)) = (a, b) {
                hit += 1;
                if (a.prim, a.sub) == (b.prim, b.sub) {
                    same += 1;
                    max_dt = max_dt.max((a.t - b.t).abs() / a.t.abs());
                    max_duv = max_duv.max((a.u - b.u).abs().max((a.v - b.v).abs()));
                }
            }
        }
        let fraction = same as f64 / hit.max(1) as f64;
        eprintln!(
            "{name}: {hit} hits, sub-primitives {:.4}% equal, max relative dt {max_dt:.1e}, \
             max du, dv {max_duv:.1e}",
            fraction * 100.0
        );
        assert!(hit > 2000, "{name}: too few hits ({hit})");
        assert!(fraction >= raybench_tests::gpu::MIN_ID_MATCH, "{name}");
        assert!(
            f64::from(max_dt) <= raybench_tests::gpu::MAX_REL_DT,
            "{name}"
        );
        assert!(max_duv <= 1e-3, "{name}: u, v differ by {max_duv}");
    }
}

// ---------------------------------------------------------------------------------------
// The volume modes (`mip`, `composite`): the phantom, and a scene whose volumes are cut by
// surfaces and overlap (`raybench_tests::gpu::VOLUMES_SCENE`).

#[test]
fn phantom_volume_modes() {
    raybench_tests::gpu::check_volumes("phantom", 32);
}

#[test]
fn volumes_cut_by_surfaces() {
    raybench_tests::gpu::check_volumes("volumes-cut", 32);
}

// ---------------------------------------------------------------------------------------
// Bezier patches (`kernels/bezier.wgsl`): a flat patch with its analytic hits and a
// parabolic cylinder's silhouette at grazing angles, besides `teapot_bezier` above.

/// The bound `kernels/bezier.wgsl` states on the true residual `|F| = |S(u, v) - o - t d|`
/// of a hit it accepts, relative to the scale `M` of its f32 rounding (`M` = the largest
/// control-point coordinate relative to the patch centre `c`, plus `|o - c|` and `|t d|`,
/// maximum norms): `2^-17`. To first order `t` is then off the exact root by at most
/// `BEZIER_RESIDUAL M / (|d| |cos|)`, `cos` between the ray and the surface normal.
const BEZIER_RESIDUAL: f64 = 1.0 / 131_072.0;

/// A scene of the given Bezier patches (primitive ids in order).
fn bezier_scene(patches: &[[raybench_core::Vec3; 16]]) -> std::sync::Arc<raybench_core::Scene> {
    let mut b = raybench_core::SceneBuilder::new("bezier");
    let shapes = patches
        .iter()
        .map(|p| {
            raybench_core::Shape::Bezier(std::sync::Arc::new(
                raybench_core::BezierPatch::new(*p).unwrap(),
            ))
        })
        .collect();
    b.add_shapes("patches", shapes, 0).unwrap();
    std::sync::Arc::new(b.build())
}

/// The largest `|t_gpu - t_cpu|` the stated residual bound allows for a hit of `ray` on
/// `patch` at naive's hit `h` (plus the CPU's own Newton tolerance and a few ulps of `t`).
fn bezier_dt_bound(
    patch: &raybench_core::BezierPatch,
    ray: &raybench_core::Ray,
    h: &raybench_core::Hit,
) -> f64 {
    let b = raybench_core::Aabb::from_points(*patch.points());
    let c = b.center();
    let e = patch
        .points()
        .iter()
        .map(|p| (*p - c).abs().max_element())
        .fold(0.0f32, f32::max);
    let m = f64::from(e)
        + f64::from((ray.origin - c).abs().max_element())
        + f64::from((ray.dir * h.t).abs().max_element());
    let cos = f64::from(patch.normal(h.u, h.v).dot(ray.dir.normalize()).abs());
    let d = f64::from(ray.dir.length());
    (BEZIER_RESIDUAL * m + patch.tolerance()) / (d * cos)
        + 4.0 * f64::from(h.t.abs()) * f64::from(f32::EPSILON)
}

/// Every GPU backend's closest and any hits of `rays` on the single-patch `scene` against
/// naive's: the same hit or miss on every ray (the cases keep clear of the residual bound),
/// `t` within [`bezier_dt_bound`]; returns the largest relative `t` difference.
fn check_bezier_rays(
    what: &str,
    scene: &std::sync::Arc<raybench_core::Scene>,
    rays: &[raybench_core::Ray],
) -> f64 {
    let raybench_core::Shape::Bezier(patch) = scene.geometry.shape(0) else {
        panic!("{what}: not a patch");
    };
    let (reference, _) = raybench_tests::prepared(raybench_tests::ORACLE, scene)
        .trace_rays(rays, false)
        .unwrap();
    let mut worst = 0.0f64;
    for name in raybench_tests::DEVICES {
        let gpu = raybench_tests::prepared(name, scene);
        let (hits, _) = gpu.trace_rays(rays, false).unwrap();
        for (i, (a, b)) in reference.iter().zip(&hits).enumerate() {
            assert_eq!(
                a.is_some(),
                b.is_some(),
                "{what}, {name}: ray {i} {:?}: naive {a:?}, gpu {b:?}",
                rays[i]
            );
            if let (Some(a), Some(b)) = (a, b) {
                let dt = f64::from((a.t - b.t).abs());
                let bound = bezier_dt_bound(patch, &rays[i], a);
                assert!(
                    dt <= bound,
                    "{what}, {name}: ray {i} {:?}: t {} vs {} (bound {bound:e})",
                    rays[i],
                    a.t,
                    b.t
                );
                worst = worst.max(dt / f64::from(a.t));
            }
        }
        let (blocked, _) = gpu.occlude_rays(rays, false).unwrap();
        let expected: Vec<bool> = reference.iter().map(Option::is_some).collect();
        assert_eq!(blocked, expected, "{what}, {name}: any-hit rays");
    }
    eprintln!(
        "{what}: {} rays, {} hits, max relative dt {worst:.1e}",
        rays.len(),
        reference.iter().flatten().count()
    );
    worst
}

/// A flat patch far from the origin (`S(u, v) = (100 + 3u, -50 + 3v, 7)`): rays from above
/// at angles down to 1 degree off the plane, aimed inside, on and outside its edges, hit as
/// naive's do, at the analytic `t` within the bound.
#[test]
fn bezier_flat_patch() {
    use raybench_core::{Ray, Vec3};
    if !raybench_tests::gpu::available() {
        return;
    }
    let corner = Vec3::new(100.0, -50.0, 7.0);
    let points = std::array::from_fn(|k| corner + Vec3::new((k % 4) as f32, (k / 4) as f32, 0.0));
    let scene = bezier_scene(&[points]);
    let mut rays = Vec::new();
    for (k, elevation) in [90.0f32, 60.0, 20.0, 5.0, 1.0].into_iter().enumerate() {
        for (j, azimuth) in [0.0f32, 1.0, 2.3, 4.0, 5.5].into_iter().enumerate() {
            let (e, a) = (elevation.to_radians(), azimuth + 0.1 * k as f32);
            let dir = -Vec3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin());
            for target in [
                (0.5, 0.5),
                (0.01, 2.9),
                (1.7, 0.3),
                (0.0, 1.5),
                (3.0, 2.0),
                (-0.01, 1.0),
                (3.2, 3.1),
            ] {
                let at = corner + Vec3::new(target.0 + 0.01 * j as f32, target.1, 0.0);
                rays.push(Ray::new(at - dir * (4.0 + j as f32), dir));
            }
        }
    }
    let worst = check_bezier_rays("flat patch", &scene, &rays);
    assert!(worst <= raybench_tests::gpu::MAX_REL_DT, "{worst:e}");
    // The analytic distance: the plane z = 7, within the bound.
    let (hits, _) = raybench_tests::prepared(raybench_tests::DEVICE, &scene)
        .trace_rays(&rays, false)
        .unwrap();
    for (r, h) in rays.iter().zip(&hits) {
        if let Some(h) = h {
            let exact = f64::from(7.0 - r.origin.z) / f64::from(r.dir.z);
            assert!(
                (f64::from(h.t) - exact).abs() <= 1e-5 * exact,
                "{r:?}: {} vs {exact}",
                h.t
            );
        }
    }
}

/// A parabolic cylinder `z = x^2` (exactly a Bezier patch: `x = 2u - 1`, `y = 2v - 1`),
/// met by rays along `x` at heights `z` near its bottom: two roots at `x = -+sqrt(z)` that
/// merge into the tangent ray at `z = 0` (cosines down to 0.02 at `z = 1e-4`). Rays above the
/// residual bound's reach (`|z|` at least 1e-4, the bound being about 4e-5 here) hit or miss
/// as naive's do, and `t` agrees within the bound; so do rays just inside and outside the
/// silhouette seen from an oblique viewpoint.
#[test]
fn bezier_silhouettes_at_grazing_angles() {
    use raybench_core::{Ray, Vec3};
    if !raybench_tests::gpu::available() {
        return;
    }
    let c = [-1.0f32, -1.0 / 3.0, 1.0 / 3.0, 1.0];
    let z = [1.0f32, -1.0 / 3.0, -1.0 / 3.0, 1.0];
    let points = std::array::from_fn(|k| Vec3::new(c[k % 4], c[k / 4], z[k % 4]));
    let scene = bezier_scene(&[points]);
    let mut rays = Vec::new();
    for height in [-1e-2f32, -1e-3, -1e-4, 1e-4, 3e-4, 1e-3, 1e-2, 0.1, 0.5] {
        for y in [-0.9f32, -0.31, 0.0, 0.42, 0.77] {
            rays.push(Ray::new(Vec3::new(-3.0, y, height), Vec3::X));
            rays.push(Ray::new(Vec3::new(3.0, y, height), -Vec3::X));
            // Tilted in y: still along the cylinder's tangent plane at the bottom.
            rays.push(Ray::new(
                Vec3::new(-3.0, y - 0.6, height),
                Vec3::new(1.0, 0.2, 0.0),
            ));
        }
    }
    // Oblique rays at the silhouette seen from o = (2.5, y, 0.5), outside the cup: the
    // tangent from o touches z = x^2 at x0 = 2.5 - sqrt(5.75); rays aimed just above the
    // touching point enter the cup (two crossings), just below it they pass by.
    let x0 = 2.5 - 5.75f32.sqrt();
    for y in [-0.8f32, -0.2, 0.0, 0.35, 0.9] {
        let o = Vec3::new(2.5, y + 0.3, 0.5);
        for lift in [-1e-2f32, -1e-3, -1e-4, 1e-4, 1e-3, 1e-2] {
            let target = Vec3::new(x0, y, x0 * x0 + lift);
            rays.push(Ray::new(o, target - o));
        }
    }
    let worst = check_bezier_rays("parabolic cylinder", &scene, &rays);
    eprintln!("parabolic cylinder: max relative dt {worst:e}");
}

// ---------------------------------------------------------------------------------------
// CSG trees, tori and quadrics (`kernels/csg.wgsl`): each solid alone, placed and not;
// tori edge-on, where camera rays graze the tube; the solids a thousand units from the
// origin, seen from close by and from far away (the f32 forms that replace the core's
// f64); nested differences over shared faces. Each scene goes through `check` unchanged.

/// Writes `toml` to a file of the test's own and runs [`check`] on it (32 x 32; with
/// `modes`, every mode).
fn check_toml(name: &str, toml: &str, modes: bool) {
    let dir = std::env::temp_dir().join(format!("raybench-gpu-csg-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, toml).unwrap();
    check(path.to_str().unwrap(), 32, modes);
}

/// Materials and lights shared by the scenes below.
const CSG_LOOK: &str = r#"
background = [0.45, 0.6, 0.85]

[[material]]
name = "red"
color = [0.8, 0.2, 0.15]
specular = [0.4, 0.4, 0.4]
shininess = 40

[[material]]
name = "glass"
kind = "glass"
ior = 1.5
specular = [1.0, 1.0, 1.0]

[[light]]
kind = "point"
position = [-4.0, 7.0, 5.0]
intensity = [45.0, 45.0, 45.0]
"#;

#[test]
fn csg_each_solid_alone() {
    let objects = r#"
[camera]
position = [0.0, 2.5, 9.0]
look_at = [0.0, 0.5, 0.0]
fov = 50

[[object]]
kind = "csg"
material = "red"
tree = { type = "sphere", center = [-3.0, 0.5, 0.0], radius = 0.6 }

[[object]]
kind = "csg"
material = "red"
tree = { type = "box", min = [-0.5, -0.5, -0.5], max = [0.5, 0.5, 0.5],
         transform = { scale = [1.0, 1.2, 0.8], rotate = [10.0, 35.0, 0.0], translate = [-1.6, 0.6, 0.0] } }

[[object]]
kind = "cylinder"
base = [-0.3, 0.0, 0.0]
radius = 0.4
height = 1.2
material = "red"

[[object]]
kind = "cone"
base = [0.8, 0.0, 0.0]
radius = 0.5
height = 1.2
material = "glass"

[[object]]
kind = "csg"
material = "red"
tree = { type = "intersection", operands = [
    { type = "half_space", point = [2.0, 0.5, 0.0], normal = [0.3, 1.0, 0.2] },
    { type = "box", min = [1.6, 0.0, -0.4], max = [2.4, 1.0, 0.4] },
] }

[[object]]
kind = "ellipsoid"
center = [0.0, 0.0, 0.0]
radii = [0.4, 0.7, 0.3]
material = "red"
transform = { rotate = [0.0, 0.0, 30.0], translate = [3.2, 0.7, 0.0] }

[[object]]
kind = "torus"
center = [0.0, 0.0, 0.0]
major_radius = 0.7
minor_radius = 0.25
material = "red"
transform = { rotate = [60.0, 20.0, 0.0], translate = [-1.5, 2.2, -1.0] }

[[object]]
kind = "paraboloid"
base = [0.0, 0.0, 0.0]
radius = 0.6
height = 0.9
material = "glass"
transform = { rotate = [0.0, 0.0, 160.0], translate = [1.5, 2.8, -1.0] }
"#;
    check_toml(
        "each-solid",
        &format!("name = \"csg-solids\"\n{CSG_LOOK}{objects}"),
        true,
    );
}

#[test]
fn csg_tori_edge_on() {
    // The camera in the plane of the first torus: every ray grazes its tube or crosses it
    // at a shallow angle; a spindle torus (r > R) and a horn torus (r = R) beside it.
    let objects = r#"
[camera]
position = [0.0, 0.5, 6.0]
look_at = [0.0, 0.5, 0.0]
fov = 45

[[object]]
kind = "torus"
center = [-1.2, 0.5, 0.0]
major_radius = 1.0
minor_radius = 0.3
material = "red"

[[object]]
kind = "torus"
center = [0.0, 0.0, 0.0]
major_radius = 0.5
minor_radius = 0.6
material = "red"
transform = { rotate = [2.0, 0.0, 0.0], translate = [1.4, 0.5, 0.0] }

[[object]]
kind = "torus"
center = [0.0, 0.0, 0.0]
major_radius = 0.5
minor_radius = 0.5
material = "glass"
transform = { rotate = [88.0, 0.0, 0.0], translate = [0.0, 1.8, -1.0] }
"#;
    check_toml(
        "tori-edge-on",
        &format!("name = \"csg-tori\"\n{CSG_LOOK}{objects}"),
        true,
    );
}

/// Solids 1000 units from the origin, seen from near and far: every image agrees
/// (far-near: ids 100%, relative dt 2.5e-7, no pixel differs in any mode). Among the
/// incoherent rays one that starts about 1e-3 from a surface differs by 3.0e-7 in `t`,
/// 3.0e-4 of its short `t` (coordinates near 1000 have an ulp of 6e-5: f32 cannot place
/// such a ray's origin more closely), which is why explicit rays are compared relative to
/// their reach ([`raybench_tests::gpu::reach_dt`]).
#[test]
fn csg_far_from_the_origin() {
    // The quadrics and a torus 1000 units out on x, seen from 8 units and from 300.
    let objects = |cam: &str| {
        format!(
            r#"
[camera]
position = {cam}
look_at = [1000.0, 0.6, 0.0]
fov = 40

[[object]]
kind = "torus"
center = [0.0, 0.0, 0.0]
major_radius = 0.8
minor_radius = 0.3
material = "red"
transform = {{ rotate = [30.0, 0.0, 0.0], translate = [998.5, 0.4, 0.0] }}

[[object]]
kind = "cylinder"
base = [1000.0, 0.0, 0.0]
radius = 0.3
height = 1.4
material = "red"

[[object]]
kind = "cone"
base = [1001.2, 0.0, 0.0]
radius = 0.5
height = 1.2
material = "red"

[[object]]
kind = "paraboloid"
base = [1000.0, 1.6, -1.0]
radius = 0.5
height = 0.6
material = "red"

[[object]]
kind = "ellipsoid"
center = [1001.0, 1.7, -1.0]
radii = [0.5, 0.3, 0.4]
material = "red"
"#
        )
    };
    // Every mode from near; ray casting and explicit rays from far.
    for (name, cam, modes) in [
        ("far-near", "[1000.0, 2.0, 8.0]", true),
        ("far-far", "[1000.0, 60.0, 300.0]", false),
    ] {
        check_toml(
            name,
            &format!("name = \"csg-{name}\"\n{CSG_LOOK}{}", objects(cam)),
            modes,
        );
    }
}

/// Every mode. (Path tracing once traced 1.6% fewer rays than naive here, and 2.3% on
/// `quadrics`: lavapipe cut threads whose loops over four samples in one dispatch passed its
/// iteration cap; software adapters now trace one sample per dispatch, `plan::max_samples`.)
#[test]
fn csg_nested_differences() {
    // A difference inside a difference (normals negated twice), faces shared between the
    // operands, and a torus cut by a box and a half-space.
    let objects = r#"
[camera]
position = [0.5, 3.0, 6.0]
look_at = [0.0, 0.5, 0.0]
fov = 45

[[object]]
kind = "csg"
material = "red"
tree = { type = "difference", operands = [
    { type = "box", min = [-2.0, 0.0, -1.0], max = [0.0, 2.0, 1.0] },
    { type = "difference", operands = [
        { type = "sphere", center = [-1.0, 2.0, 0.0], radius = 0.9 },
        { type = "cylinder", base = [-1.0, 0.0, 0.0], radius = 0.3, height = 2.0 },
    ] },
    { type = "box", min = [-2.0, 0.0, 0.5], max = [-1.5, 2.0, 1.0] },
] }

[[object]]
kind = "csg"
material = "glass"
tree = { type = "intersection", operands = [
    { type = "difference", operands = [
        { type = "torus", center = [1.3, 0.4, 0.0], major_radius = 0.8, minor_radius = 0.35 },
        { type = "box", min = [1.3, 0.0, 0.0], max = [2.5, 1.0, 1.2] },
    ] },
    { type = "half_space", point = [1.3, 0.55, 0.0], normal = [0.0, 1.0, 0.0] },
] }

# A union of 20 spheres (more leaves than the kernels keep: the rest are evaluated again at
# each event) less a box.
[[object]]
kind = "csg"
material = "red"
tree = { type = "difference", operands = [
    { type = "union", operands = [
    { type = "sphere", center = [-2.00, 0.25, 1.2], radius = 0.22 },
    { type = "sphere", center = [-1.80, 0.35, 1.2], radius = 0.22 },
    { type = "sphere", center = [-1.60, 0.45, 1.2], radius = 0.22 },
    { type = "sphere", center = [-1.40, 0.25, 1.2], radius = 0.22 },
    { type = "sphere", center = [-1.20, 0.35, 1.2], radius = 0.22 },
    { type = "sphere", center = [-1.00, 0.45, 1.2], radius = 0.22 },
    { type = "sphere", center = [-0.80, 0.25, 1.2], radius = 0.22 },
    { type = "sphere", center = [-0.60, 0.35, 1.2], radius = 0.22 },
    { type = "sphere", center = [-0.40, 0.45, 1.2], radius = 0.22 },
    { type = "sphere", center = [-0.20, 0.25, 1.2], radius = 0.22 },
    { type = "sphere", center = [0.00, 0.35, 1.2], radius = 0.22 },
    { type = "sphere", center = [0.20, 0.45, 1.2], radius = 0.22 },
    { type = "sphere", center = [0.40, 0.25, 1.2], radius = 0.22 },
    { type = "sphere", center = [0.60, 0.35, 1.2], radius = 0.22 },
    { type = "sphere", center = [0.80, 0.45, 1.2], radius = 0.22 },
    { type = "sphere", center = [1.00, 0.25, 1.2], radius = 0.22 },
    { type = "sphere", center = [1.20, 0.35, 1.2], radius = 0.22 },
    { type = "sphere", center = [1.40, 0.45, 1.2], radius = 0.22 },
    { type = "sphere", center = [1.60, 0.25, 1.2], radius = 0.22 },
    { type = "sphere", center = [1.80, 0.35, 1.2], radius = 0.22 },
    ] },
    { type = "box", min = [-1.2, 0.3, 0.9], max = [-0.6, 1.0, 1.6] },
] }
"#;
    check_toml(
        "nested",
        &format!("name = \"csg-nested\"\n{CSG_LOOK}{objects}"),
        true,
    );
}
