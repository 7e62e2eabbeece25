//! SDF models (`kernels/sdf.wgsl`, `geo/sdf.rs`): beyond the built-in `sdf` scene (in
//! `builtin::sdf`), every operation (intersection too), a capsule whose ends
//! coincide, rotated and scaled transforms, and the deepest trees the loader accepts, which
//! fill the kernel's value stack (a right-leaning chain: `MAX_SDF_DEPTH` values) and point
//! stack (nested transforms with a sibling at every level, so that every saved point is
//! used).

use raybench_tests::gpu::hit_keys;

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
        let ((ri, rt), (gi, gt)) = (hit_keys(&reference_hits), hit_keys(&hits));
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
