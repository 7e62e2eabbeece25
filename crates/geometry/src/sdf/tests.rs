//! The unit tests of the SDF models: distances, operations, the Lipschitz bound, the box, the
//! marching rules and the refusals.

use super::*;
use glam::Affine3A;

fn sphere(c: Vec3, r: f32) -> SdfNode {
    SdfNode::Leaf(SdfPrimitive::Sphere {
        center: c,
        radius: r,
    })
}

fn cube(c: Vec3, h: f32) -> SdfNode {
    SdfNode::Leaf(SdfPrimitive::Box {
        center: c,
        half_extents: Vec3::splat(h),
        rounding: 0.0,
    })
}

fn op(op: SdfOp, a: SdfNode, b: SdfNode) -> SdfNode {
    SdfNode::Op(op, Box::new(a), Box::new(b))
}

fn model(tree: &SdfNode) -> Sdf {
    Sdf::new(tree, SdfParams::DEFAULT).unwrap()
}

/// A tree with every primitive, operation and a transform.
fn everything() -> SdfNode {
    let torus = SdfNode::Leaf(SdfPrimitive::Torus {
        center: Vec3::new(0.5, 0.0, 0.0),
        major_radius: 0.6,
        minor_radius: 0.2,
    });
    let capsule = SdfNode::Leaf(SdfPrimitive::Capsule {
        a: Vec3::new(-1.0, 0.0, 0.0),
        b: Vec3::new(-0.2, 0.8, 0.1),
        radius: 0.25,
    });
    let cylinder = SdfNode::Leaf(SdfPrimitive::Cylinder {
        center: Vec3::new(0.0, -0.5, 0.3),
        radius: 0.3,
        half_height: 0.4,
    });
    let rounded = SdfNode::Leaf(SdfPrimitive::Box {
        center: Vec3::new(0.2, 0.3, -0.4),
        half_extents: Vec3::new(0.5, 0.3, 0.4),
        rounding: 0.1,
    });
    let turned = SdfNode::Transform(
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(1.7),
            glam::Quat::from_rotation_y(0.6) * glam::Quat::from_rotation_x(0.3),
            Vec3::new(0.1, 0.2, 0.3),
        ),
        Box::new(op(SdfOp::Blend(0.3), rounded, sphere(Vec3::ZERO, 0.5))),
    );
    op(
        SdfOp::SmoothUnion(0.3),
        op(SdfOp::Union, torus, capsule),
        op(
            SdfOp::Subtraction,
            op(SdfOp::Intersection, turned, cube(Vec3::ZERO, 0.9)),
            cylinder,
        ),
    )
}

/// Deterministic points in `[-s, s]^3` (a Weyl sequence).
fn points(n: usize, s: f32) -> impl Iterator<Item = Vec3> {
    let a = [0.754_877_7_f64, 0.569_840_3, 0.430_159_7];
    (1..=n).map(move |i| {
        let c = |k: usize| ((i as f64 * a[k]).fract() * 2.0 - 1.0) as f32 * s;
        Vec3::new(c(0), c(1), c(2))
    })
}

#[test]
fn primitives_are_exact_distances() {
    let d = |s: SdfPrimitive, p: Vec3| primitive_distance(&s, p);
    let c = Vec3::new(1.0, 2.0, 3.0);
    assert_eq!(
        d(
            SdfPrimitive::Sphere {
                center: c,
                radius: 1.0
            },
            c + Vec3::new(0.0, 3.0, 0.0)
        ),
        2.0
    );
    let b = SdfPrimitive::Box {
        center: Vec3::ZERO,
        half_extents: Vec3::new(1.0, 2.0, 3.0),
        rounding: 0.5,
    };
    assert_eq!(d(b, Vec3::new(3.0, 0.0, 0.0)), 2.0);
    assert_eq!(d(b, Vec3::ZERO), -1.0);
    // The rounded corner: distance to the sphere of radius 0.5 around (0.5, 1.5, 2.5).
    let corner = Vec3::new(0.5, 1.5, 2.5);
    assert!((d(b, corner + Vec3::ONE) - (3f32.sqrt() - 0.5)).abs() < 1e-6);
    let t = SdfPrimitive::Torus {
        center: Vec3::ZERO,
        major_radius: 2.0,
        minor_radius: 0.5,
    };
    assert_eq!(d(t, Vec3::new(2.0, 1.5, 0.0)), 1.0);
    assert_eq!(d(t, Vec3::ZERO), 1.5);
    let cap = SdfPrimitive::Capsule {
        a: Vec3::ZERO,
        b: Vec3::Y,
        radius: 0.5,
    };
    assert_eq!(d(cap, Vec3::new(2.0, 0.5, 0.0)), 1.5);
    assert_eq!(d(cap, Vec3::new(0.0, 3.0, 0.0)), 1.5);
    let cyl = SdfPrimitive::Cylinder {
        center: Vec3::ZERO,
        radius: 1.0,
        half_height: 2.0,
    };
    assert_eq!(d(cyl, Vec3::new(0.0, 5.0, 0.0)), 3.0);
    assert_eq!(d(cyl, Vec3::new(4.0, 6.0, 0.0)), 5.0);
    assert_eq!(d(cyl, Vec3::new(0.5, 0.0, 0.0)), -0.5);
}

#[test]
fn operations_follow_their_formulas() {
    assert_eq!(SdfOp::Union.apply(1.0, -2.0), -2.0);
    assert_eq!(SdfOp::Intersection.apply(1.0, -2.0), 1.0);
    assert_eq!(SdfOp::Subtraction.apply(-1.0, -2.0), 2.0);
    assert_eq!(SdfOp::Blend(0.25).apply(1.0, -3.0), 0.0);
    // Smooth union: equal operands lose k / 4; beyond k apart it is the minimum.
    assert_eq!(SdfOp::SmoothUnion(0.4).apply(1.0, 1.0), 0.9);
    assert_eq!(SdfOp::SmoothUnion(0.4).apply(1.0, 1.5), 1.0);
}

/// `|f(x) - f(y)| <= L |x - y|` over point pairs at several scales, on a tree with every
/// primitive and operation and a rotated, scaled transform.
#[test]
fn lipschitz_bound_holds_numerically() {
    let m = model(&everything());
    assert_eq!(m.lipschitz(), 1.0);
    let mut worst = 0.0f32;
    for (i, x) in points(20_000, 2.5).enumerate() {
        for (j, r) in [1.0f32, 0.1, 0.01].into_iter().enumerate() {
            let y = x + points(i * 3 + j + 7, r).last().unwrap();
            let dist = (x - y).length();
            if dist < 1e-3 {
                continue;
            }
            let ratio = (m.distance(x) - m.distance(y)).abs() / dist;
            worst = worst.max(ratio);
        }
    }
    // f32 rounding of values near 2 over distances above 1e-3: below 1e-3 relative.
    assert!(worst <= m.lipschitz() * 1.001, "worst ratio {worst}");
    // Not vacuous: somewhere the bound is nearly attained.
    assert!(worst > 0.9, "worst ratio {worst}");
}

/// Every sampled point where the field is below `2 eps` lies in the padded box, for a
/// smooth union whose operands are a rotated intersection (not an exact distance) and a
/// subtraction: the spread rule at work.
#[test]
fn the_box_holds_the_surface() {
    let wedge = SdfNode::Transform(
        Affine3A::from_rotation_z(0.7),
        Box::new(op(
            SdfOp::Intersection,
            cube(Vec3::new(0.9, 0.0, 0.0), 1.0),
            cube(Vec3::new(-0.9, 0.3, 0.0), 1.0),
        )),
    );
    let carved = op(
        SdfOp::Subtraction,
        cube(Vec3::new(0.0, 1.2, 0.0), 0.4),
        sphere(Vec3::new(0.0, 1.6, 0.0), 0.3),
    );
    for tree in [op(SdfOp::SmoothUnion(1.5), wedge, carved), everything()] {
        let m = model(&tree);
        let b = m.bounds();
        let mut inside = 0;
        for p in points(200_000, 4.0) {
            if m.distance(p) < 2.0 * m.tolerance() {
                inside += 1;
                assert!(
                    p.cmpge(b.min).all() && p.cmple(b.max).all(),
                    "{p} outside {b:?}"
                );
            }
        }
        assert!(inside > 1000, "{inside}");
    }
}

#[test]
fn sphere_hits_within_tolerance_and_normals_point_out() {
    let m = model(&sphere(Vec3::ZERO, 1.0));
    let eps = m.tolerance();
    assert!((eps - 1e-4 * 12f32.sqrt()).abs() < 1e-9, "{eps}");
    // Head-on: exact distances converge in one step.
    let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
    let t = m.intersect(&r).map(|h| h.t).unwrap();
    assert!((t - 4.0).abs() <= eps, "{t}");
    assert!((m.normal(r.at(t)) - -Vec3::Z).length() < 1e-3);
    // From inside: the exit, normal still outward.
    let r = Ray::new(Vec3::ZERO, Vec3::X);
    let t = m.intersect(&r).map(|h| h.t).unwrap();
    assert!((t - 1.0).abs() <= eps, "{t}");
    assert!((m.normal(r.at(t)) - Vec3::X).length() < 1e-3);
    // Miss, and clipped by t_max.
    assert_eq!(
        m.intersect(&Ray::new(Vec3::new(0.0, 2.0, -5.0), Vec3::Z))
            .map(|h| h.t),
        None
    );
    let r = Ray::with_interval(Vec3::new(0.0, 0.0, -5.0), Vec3::Z, 0.0, 3.9);
    assert_eq!(m.intersect(&r).map(|h| h.t), None);
    // Unnormalised directions give the same point.
    let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z * 4.0);
    assert!((m.intersect(&r).map(|h| h.t).unwrap() - 1.0).abs() <= eps / 4.0);
}

/// A ray leaving the surface (reflection outward, refraction inward) does not re-hit it:
/// it finds the far side, or nothing.
#[test]
fn rays_leaving_the_surface_do_not_rehit_it() {
    let m = model(&sphere(Vec3::ZERO, 1.0));
    let eps = m.tolerance();
    for offset in [-0.9 * eps, -0.3 * eps, 0.0, 0.3 * eps, 0.9 * eps] {
        let p = Vec3::new(0.0, 0.0, -1.0 - offset);
        // Outward: nothing else to hit.
        assert_eq!(
            m.intersect(&Ray::new(p, -Vec3::Z)).map(|h| h.t),
            None,
            "{offset}"
        );
        // Outward at a slant.
        assert_eq!(
            m.intersect(&Ray::new(p, Vec3::new(0.3, 0.0, -1.0)))
                .map(|h| h.t),
            None
        );
        // Inward: the far side at t = 2.
        let t = m.intersect(&Ray::new(p, Vec3::Z)).map(|h| h.t).unwrap();
        assert!((t - 2.0).abs() <= 2.0 * eps, "{offset}: {t}");
    }
}

#[test]
fn the_step_limit_makes_a_miss() {
    let tree = sphere(Vec3::ZERO, 1.0);
    let r = Ray::new(Vec3::new(0.0, 0.999, -5.0), Vec3::Z);
    let full = model(&tree).march(&r);
    assert!(full.t.is_some() && full.steps > 3, "{full:?}");
    let params = SdfParams {
        max_steps: full.steps - 1,
        ..SdfParams::DEFAULT
    };
    let short = Sdf::new(&tree, params).unwrap().march(&r);
    assert_eq!(
        short,
        March {
            t: None,
            steps: full.steps - 1
        }
    );
}

#[test]
fn smooth_union_and_blend_change_the_surface_as_stated() {
    let a = sphere(Vec3::new(-1.0, 0.0, 0.0), 1.0);
    let b = sphere(Vec3::new(1.0, 0.0, 0.0), 1.0);
    // Between two touching balls the smooth union fills the gap by k / 4 at the middle
    // (both distances are 0 at the origin): the surface is at distance k/4 - ... along y.
    let m = model(&op(SdfOp::SmoothUnion(0.8), a.clone(), b.clone()));
    assert!((m.distance(Vec3::ZERO) + 0.2).abs() < 1e-6);
    let t = m
        .intersect(&Ray::new(Vec3::new(0.0, 5.0, 0.0), -Vec3::Y))
        .map(|h| h.t)
        .unwrap();
    assert!(t < 5.0 - 0.1, "the neck is filled: {t}");
    // A blend halfway between a ball and a box of the same centre.
    let m = model(&op(
        SdfOp::Blend(0.5),
        sphere(Vec3::ZERO, 1.0),
        cube(Vec3::ZERO, 1.0),
    ));
    assert!((m.distance(Vec3::new(2.0, 0.0, 0.0)) - 1.0).abs() < 1e-6);
    let diag = Vec3::ONE.normalize();
    let t = m
        .intersect(&Ray::new(diag * 5.0, -diag))
        .map(|h| h.t)
        .unwrap();
    // The surface on the diagonal is between the ball's (1) and the box's (sqrt 3).
    assert!((5.0 - t) > 1.05 && (5.0 - t) < 3f32.sqrt() - 0.05, "{t}");
}

#[test]
fn transforms_scale_distances() {
    let m = model(&SdfNode::Transform(
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(2.0),
            glam::Quat::from_rotation_z(0.5),
            Vec3::new(3.0, 0.0, 0.0),
        ),
        Box::new(sphere(Vec3::ZERO, 1.0)),
    ));
    assert!((m.distance(Vec3::new(3.0, 5.0, 0.0)) - 3.0).abs() < 1e-6);
    assert!((m.distance(Vec3::new(3.0, 0.0, 0.0)) + 2.0).abs() < 1e-6);
}

#[test]
fn bad_models_are_refused() {
    let s = sphere(Vec3::ZERO, 1.0);
    let err = |tree: &SdfNode| Sdf::new(tree, SdfParams::DEFAULT).unwrap_err().to_string();
    assert!(SdfNode::fold(SdfOp::Union, vec![s.clone()]).is_err());
    assert!(SdfNode::fold(SdfOp::Blend(0.5), vec![s.clone(), s.clone(), s.clone()]).is_err());
    assert!(err(&sphere(Vec3::ZERO, -1.0)).contains("radius must be positive"));
    assert!(err(&sphere(Vec3::new(f32::NAN, 0.0, 0.0), 1.0)).contains("not finite"));
    let smooth = |k| op(SdfOp::SmoothUnion(k), s.clone(), s.clone());
    assert!(err(&smooth(0.0)).contains("k must be positive"));
    assert!(err(&smooth(f32::INFINITY)).contains("not finite"));
    let blend = |w| op(SdfOp::Blend(w), s.clone(), s.clone());
    assert!(err(&blend(1.5)).contains("w must lie in [0, 1]"));
    assert!(err(&blend(f32::NAN)).contains("not finite"));
    let stretched = SdfNode::Transform(
        Affine3A::from_scale(Vec3::new(1.0, 2.0, 1.0)),
        Box::new(s.clone()),
    );
    assert!(err(&stretched).contains("non-uniform scale"));
    let rounded = SdfNode::Leaf(SdfPrimitive::Box {
        center: Vec3::ZERO,
        half_extents: Vec3::ONE,
        rounding: 2.0,
    });
    assert!(err(&rounded).contains("rounding must lie in"));
    let disjoint = op(
        SdfOp::Intersection,
        s.clone(),
        sphere(Vec3::new(5.0, 0.0, 0.0), 1.0),
    );
    assert!(err(&disjoint).contains("empty"));
    let mut deep = s.clone();
    for _ in 0..MAX_SDF_DEPTH {
        deep = op(SdfOp::Union, deep, s.clone());
    }
    assert!(err(&deep).contains("deeper than"));
    let many = SdfNode::fold(SdfOp::Union, vec![s.clone(); MAX_SDF_NODES]).unwrap();
    assert!(err(&many).contains("more than"));
    for (tolerance, max_steps) in [(0.0, 10), (f32::NAN, 10), (1e-4, 0), (1e-4, 1 << 20)] {
        let params = SdfParams {
            tolerance,
            max_steps,
        };
        assert!(Sdf::new(&s, params).is_err(), "{params:?}");
    }
}

#[test]
fn nan_and_zero_rays_miss() {
    let m = model(&everything());
    for r in [
        Ray::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X),
        Ray::new(Vec3::new(-5.0, 0.0, 0.0), Vec3::new(f32::NAN, 0.0, 0.0)),
        Ray::new(Vec3::new(-5.0, 0.0, 0.0), Vec3::ZERO),
    ] {
        assert_eq!(m.intersect(&r).map(|h| h.t), None);
    }
}
