//! The CSG rules of the module documentation, leaf by leaf and operation by operation.

use super::*;
use crate::aabb::Aabb;
use crate::limits::{MAX_CSG_DEPTH, MAX_CSG_LEAVES};
use glam::Affine3A;

fn sphere(c: Vec3, r: f32) -> CsgNode {
    CsgNode::Leaf(Solid::Sphere {
        center: c,
        radius: r,
    })
}

fn cube(min: Vec3, max: Vec3) -> CsgNode {
    CsgNode::Leaf(Solid::Box { min, max })
}

fn op(op: CsgOp, a: CsgNode, b: CsgNode) -> CsgNode {
    CsgNode::Op(op, Box::new(a), Box::new(b))
}

/// The public answer, [`Csg::intersect`] completed by [`Csg::normal`], as one span end;
/// checked against the end the tree gives directly (the normal's re-evaluation finds the
/// same boundary).
fn full(c: &Csg, r: &Ray) -> Option<End> {
    let got = c.intersect(r).map(|h| End {
        t: h.t,
        normal: c.normal(r, &h),
        leaf: h.sub,
    });
    assert_eq!(got, c.first_end(r), "{r:?}");
    got
}

fn hit(tree: &CsgNode, o: Vec3, d: Vec3) -> Option<End> {
    full(&Csg::new(tree).unwrap(), &Ray::new(o, d))
}

const FROM_LEFT: Vec3 = Vec3::new(-10.0, 0.0, 0.0);

/// Regression (tests/tests/adversarial.rs): a ray starting at `x = 1.16e30` and going
/// straight down hit the cone of the built-in `csg` scene at `t = 4.3`.
#[test]
fn rays_far_outside_the_box_miss() {
    let cone = CsgNode::Leaf(Solid::Cone {
        base: Vec3::new(1.5, 1.0, -1.2),
        radius: 0.8,
        height: 1.2,
    });
    let o = Vec3::new(1.160_351_6e30, 6.501_904_5, -0.200_048_86);
    assert_eq!(hit(&cone, o, -Vec3::Y), None);
    assert!(hit(&cone, Vec3::new(1.5, 6.5, -1.2), -Vec3::Y).is_some());
}

#[test]
fn leaves_give_analytic_distances() {
    let cases = [
        (sphere(Vec3::ZERO, 2.0), 8.0, -Vec3::X),
        (cube(Vec3::splat(-1.0), Vec3::splat(1.0)), 9.0, -Vec3::X),
        (
            CsgNode::Leaf(Solid::Cylinder {
                base: Vec3::new(0.0, -1.0, 0.0),
                radius: 3.0,
                height: 2.0,
            }),
            7.0,
            -Vec3::X,
        ),
        (
            // Halfway up a cone of base radius 4 and height 2, the radius is 2.
            CsgNode::Leaf(Solid::Cone {
                base: Vec3::new(0.0, -1.0, 0.0),
                radius: 4.0,
                height: 2.0,
            }),
            8.0,
            Vec3::new(-1.0, 2.0, 0.0).normalize(),
        ),
    ];
    for (tree, t, n) in cases {
        let h = hit(&tree, FROM_LEFT, Vec3::X).unwrap();
        assert_eq!(h.t, t, "{tree:?}");
        assert!((h.normal - n).length() < 1e-6, "{tree:?}: {}", h.normal);
    }
}

#[test]
fn cylinder_and_cone_caps_from_above() {
    let cyl = CsgNode::Leaf(Solid::Cylinder {
        base: Vec3::ZERO,
        radius: 1.0,
        height: 2.0,
    });
    let h = hit(&cyl, Vec3::new(0.5, 10.0, 0.0), -Vec3::Y).unwrap();
    assert_eq!((h.t, h.normal), (8.0, Vec3::Y));
    let cone = CsgNode::Leaf(Solid::Cone {
        base: Vec3::ZERO,
        radius: 1.0,
        height: 2.0,
    });
    let h = hit(&cone, Vec3::new(0.0, -10.0, 0.0), Vec3::Y).unwrap();
    assert_eq!((h.t, h.normal), (10.0, -Vec3::Y));
    // Straight down the axis the apex is the first point.
    let h = hit(&cone, Vec3::new(0.0, 10.0, 0.0), -Vec3::Y).unwrap();
    assert_eq!(h.t, 8.0);
}

#[test]
fn the_three_operations() {
    let a = sphere(Vec3::new(-1.0, 0.0, 0.0), 2.0); // [-3, 1] on the x axis
    let b = sphere(Vec3::new(1.0, 0.0, 0.0), 2.0); // [-1, 3]
    let t = |tree: &CsgNode| hit(tree, FROM_LEFT, Vec3::X).map(|h| (h.t, h.normal));
    assert_eq!(
        t(&op(CsgOp::Union, a.clone(), b.clone())),
        Some((7.0, -Vec3::X))
    );
    assert_eq!(
        t(&op(CsgOp::Intersection, a.clone(), b.clone())),
        Some((9.0, -Vec3::X))
    );
    assert_eq!(
        t(&op(CsgOp::Difference, b.clone(), a.clone())),
        Some((11.0, -Vec3::X)),
        "the subtracted sphere's exit, its normal flipped"
    );
    // A ray inside the union hits its far side; inside the difference's hole, the rest.
    let inside = Ray::new(Vec3::ZERO, Vec3::X);
    let u = Csg::new(&op(CsgOp::Union, a.clone(), b.clone())).unwrap();
    assert_eq!(full(&u, &inside).unwrap().t, 3.0);
    let d = Csg::new(&op(CsgOp::Difference, b, a)).unwrap();
    let h = full(&d, &inside).unwrap();
    assert_eq!((h.t, h.normal), (1.0, -Vec3::X));
}

#[test]
fn coincident_faces_follow_the_regularised_rule() {
    let left = cube(Vec3::new(-2.0, -1.0, -1.0), Vec3::new(0.0, 1.0, 1.0));
    let right = cube(Vec3::new(0.0, -1.0, -1.0), Vec3::new(2.0, 1.0, 1.0));
    let u = Csg::new(&op(CsgOp::Union, left.clone(), right.clone())).unwrap();
    // From inside the left box the shared face x = 0 is not a boundary.
    let r = Ray::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::X);
    assert_eq!(full(&u, &r).unwrap().t, 3.0);
    // Touching solids intersect in nothing.
    let i = Csg::new(&op(CsgOp::Intersection, left.clone(), right)).unwrap();
    assert_eq!(full(&i, &Ray::new(FROM_LEFT, Vec3::X)), None);
    // A subtracted solid sharing the first's front face removes that face.
    let bite = cube(Vec3::new(-2.0, -1.0, -1.0), Vec3::new(-1.0, 1.0, 1.0));
    let d = Csg::new(&op(CsgOp::Difference, left, bite)).unwrap();
    let h = full(&d, &Ray::new(FROM_LEFT, Vec3::X)).unwrap();
    assert_eq!((h.t, h.normal), (9.0, -Vec3::X));
}

#[test]
fn tangent_rays_miss() {
    let s = sphere(Vec3::ZERO, 1.0);
    assert_eq!(hit(&s, Vec3::new(-5.0, 1.0, 0.0), Vec3::X), None);
    let b = cube(Vec3::splat(-1.0), Vec3::splat(1.0));
    // Along a face of the box: a zero-thickness overlap in y.
    assert_eq!(hit(&b, Vec3::new(-5.0, 1.0, 0.0), Vec3::X), None);
}

#[test]
fn half_spaces_cut() {
    // A ball cut by the plane x = 0, keeping x <= 0.
    let cut = op(
        CsgOp::Intersection,
        sphere(Vec3::ZERO, 2.0),
        CsgNode::Leaf(Solid::HalfSpace {
            point: Vec3::ZERO,
            normal: Vec3::new(3.0, 0.0, 0.0),
        }),
    );
    let c = Csg::new(&cut).unwrap();
    assert!(c.bounds().max.x < 2.0 + 0.01);
    let h = full(&c, &Ray::new(Vec3::new(10.0, 0.0, 0.0), -Vec3::X)).unwrap();
    assert_eq!((h.t, h.normal), (10.0, Vec3::X));
    // A ray parallel to the plane on the kept side passes the ball's far side.
    let h = full(&c, &Ray::new(Vec3::new(-1.0, -5.0, 0.0), Vec3::Y)).unwrap();
    assert!((h.t - (5.0 - 3.0f32.sqrt())).abs() < 1e-5);
}

#[test]
fn leaf_ids_and_bounds() {
    let tree = CsgNode::fold(
        CsgOp::Difference,
        vec![
            cube(Vec3::splat(-1.0), Vec3::splat(1.0)),
            sphere(Vec3::new(-1.0, 0.0, 0.0), 0.5),
            sphere(Vec3::new(1.0, 0.0, 0.0), 0.5),
        ],
    )
    .unwrap();
    let c = Csg::new(&tree).unwrap();
    assert_eq!(c.leaf_count(), 3);
    assert!(
        c.bounds()
            .contains(&Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0)))
    );
    assert!(c.bounds().max.x < 1.01);
    let h = full(&c, &Ray::new(FROM_LEFT, Vec3::X)).unwrap();
    assert_eq!((h.t, h.leaf), (9.5, 1));
    let h = full(&c, &Ray::new(-FROM_LEFT, -Vec3::X)).unwrap();
    assert_eq!((h.t, h.leaf, h.normal), (9.5, 2, Vec3::X));
}

#[test]
fn bad_trees_are_refused() {
    let s = sphere(Vec3::ZERO, 1.0);
    assert!(CsgNode::fold(CsgOp::Union, vec![s.clone()]).is_err());
    assert!(CsgNode::fold(CsgOp::Difference, vec![]).is_err());
    let bad = [
        sphere(Vec3::new(f32::NAN, 0.0, 0.0), 1.0),
        sphere(Vec3::ZERO, 0.0),
        sphere(Vec3::ZERO, f32::INFINITY),
        cube(Vec3::ONE, Vec3::ZERO),
        CsgNode::Leaf(Solid::HalfSpace {
            point: Vec3::ZERO,
            normal: Vec3::ZERO,
        }),
        // Unbounded: a half-space alone, or in a union.
        CsgNode::Leaf(Solid::HalfSpace {
            point: Vec3::ZERO,
            normal: Vec3::Y,
        }),
        // Empty: disjoint boxes intersected.
        op(
            CsgOp::Intersection,
            s.clone(),
            sphere(Vec3::new(5.0, 0.0, 0.0), 1.0),
        ),
    ];
    for tree in bad {
        assert!(Csg::new(&tree).is_err(), "{tree:?}");
    }
    let mut deep = s.clone();
    for _ in 0..MAX_CSG_DEPTH {
        deep = op(CsgOp::Union, deep, s.clone());
    }
    assert!(matches!(Csg::new(&deep), Err(SceneError::TooLarge(_))));
    let many = CsgNode::fold(CsgOp::Union, vec![s; MAX_CSG_LEAVES + 1]).unwrap();
    assert!(matches!(Csg::new(&many), Err(SceneError::TooLarge(_))));
}

fn torus(r_big: f32, r_small: f32) -> Solid {
    Solid::Torus {
        center: Vec3::ZERO,
        major_radius: r_big,
        minor_radius: r_small,
    }
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-6
}

#[test]
fn quadrics_and_torus_give_analytic_hits() {
    // An ellipsoid of radii (2, 1, 3) from the left, from above, from behind.
    let e = CsgNode::Leaf(Solid::Ellipsoid {
        center: Vec3::new(1.0, 0.0, 0.0),
        radii: Vec3::new(2.0, 1.0, 3.0),
    });
    let h = hit(&e, FROM_LEFT, Vec3::X).unwrap();
    assert_eq!((h.t, h.normal), (9.0, -Vec3::X));
    let h = hit(&e, Vec3::new(1.0, 5.0, 0.0), -Vec3::Y).unwrap();
    assert_eq!((h.t, h.normal), (4.0, Vec3::Y));
    // At (x, 0, z) with x/2 = z/3 = 1/sqrt2 the normal is along (x/4, 0, z/9).
    let p = Vec3::new(1.0 + 2.0f32.sqrt(), 0.0, 1.5 * 2.0f32.sqrt());
    let h = hit(&e, p + Vec3::new(0.0, 0.0, 5.0), -Vec3::Z).unwrap();
    assert!((h.t - 5.0).abs() < 1e-5, "{}", h.t);
    let want = Vec3::new((p.x - 1.0) / 4.0, 0.0, p.z / 9.0).normalize();
    assert!(close(h.normal, want), "{}", h.normal);
    // A paraboloid y = x^2 + z^2 (radius 2 at height 4): its wall at height 1 is at
    // x = 1, the normal there along (2, -1, 0); straight down the axis, the cap then
    // the apex.
    let par = CsgNode::Leaf(Solid::Paraboloid {
        base: Vec3::ZERO,
        radius: 2.0,
        height: 4.0,
    });
    let h = hit(&par, Vec3::new(-10.0, 1.0, 0.0), Vec3::X).unwrap();
    assert_eq!(h.t, 9.0);
    assert!(close(h.normal, Vec3::new(-2.0, -1.0, 0.0).normalize()));
    let h = hit(&par, Vec3::new(0.0, 10.0, 0.0), -Vec3::Y).unwrap();
    assert_eq!((h.t, h.normal), (6.0, Vec3::Y));
    let inside = Csg::new(&par).unwrap();
    let h = full(&inside, &Ray::new(Vec3::new(0.0, 2.0, 0.0), -Vec3::Y));
    assert_eq!(h.map(|h| h.t), Some(2.0));
    // Above the cap, beside it: miss; below the apex along the axis, the apex first.
    assert_eq!(hit(&par, Vec3::new(-10.0, 4.5, 0.0), Vec3::X), None);
    assert_eq!(
        hit(&par, Vec3::new(0.0, -3.0, 0.0), Vec3::Y).map(|h| h.t),
        Some(3.0)
    );
    // A torus R = 2, r = 0.5: the outer wall, then from inside the hole the inner wall,
    // and down the axis nothing.
    let t = CsgNode::Leaf(torus(2.0, 0.5));
    let h = hit(&t, FROM_LEFT, Vec3::X).unwrap();
    assert_eq!((h.t, h.normal), (7.5, -Vec3::X));
    let h = hit(&t, Vec3::ZERO, Vec3::X).unwrap();
    assert_eq!((h.t, h.normal), (1.5, -Vec3::X));
    assert_eq!(hit(&t, Vec3::new(0.0, 10.0, 0.0), -Vec3::Y), None);
    // From inside the tube: its far wall.
    let h = hit(&t, Vec3::new(2.0, 0.0, 0.0), Vec3::Y).unwrap();
    assert_eq!((h.t, h.normal), (0.5, Vec3::Y));
}

#[test]
fn horn_and_spindle_tori() {
    // r = R: the hole closes to a point; along x through the centre the two halves meet
    // at the origin (a tangency in the middle of one span).
    let horn = CsgNode::Leaf(torus(1.0, 1.0));
    assert_eq!(hit(&horn, FROM_LEFT, Vec3::X).map(|h| h.t), Some(8.0));
    // r > R: the inner lemon (up to |y| = sqrt(r^2 - R^2) on the axis) is hollow.
    // At x = 0.2 the apple's top is at y = sqrt(4 - 0.8^2), the lemon's at
    // sqrt(4 - 1.2^2) = 1.6. (On the axis apple and lemon touch: a tangency.)
    let spindle = Csg::new(&CsgNode::Leaf(torus(1.0, 2.0))).unwrap();
    let down = Ray::new(Vec3::new(0.2, 10.0, 0.0), -Vec3::Y);
    let h = full(&spindle, &down).unwrap();
    assert!((h.t - (10.0 - 3.36f32.sqrt())).abs() < 1e-5, "{h:?}");
    let h = full(&spindle, &Ray::new(Vec3::new(0.2, 0.0, 0.0), Vec3::Y)).unwrap();
    assert!((h.t - 1.6).abs() < 1e-6 && h.normal.y < -0.5, "{h:?}");
}

#[test]
fn placed_leaves() {
    use glam::Quat;
    // A cylinder of radius 1 and height 4 laid along x by a rotation about z, moved up.
    let cyl = Solid::Cylinder {
        base: Vec3::ZERO,
        radius: 1.0,
        height: 4.0,
    };
    let to_world = Affine3A::from_rotation_translation(
        Quat::from_rotation_z(-std::f32::consts::FRAC_PI_2),
        Vec3::new(0.0, 1.0, 0.0),
    );
    let c = Csg::new(&CsgNode::Placed(cyl, to_world)).unwrap();
    // Its axis runs from (0, 1, 0) to (4, 1, 0).
    assert!(c.bounds().contains(&Aabb::new(
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::new(4.0, 2.0, 1.0)
    )));
    assert!(c.bounds().max.x < 4.01 && c.bounds().min.y > -0.01);
    let h = full(&c, &Ray::new(Vec3::new(2.0, 10.0, 0.0), -Vec3::Y)).unwrap();
    assert!(
        (h.t - 8.0).abs() < 1e-5 && close(h.normal, Vec3::Y),
        "{h:?}"
    );
    let h = full(&c, &Ray::new(FROM_LEFT + Vec3::Y, Vec3::X)).unwrap();
    assert!(
        (h.t - 10.0).abs() < 1e-5 && close(h.normal, -Vec3::X),
        "{h:?}"
    );
    // A non-uniform scale: a unit sphere stretched to radii (2, 1, 1) is the ellipsoid,
    // normals by the inverse transpose; t is unchanged for an unnormalised direction.
    let ball = Solid::Sphere {
        center: Vec3::ZERO,
        radius: 1.0,
    };
    let stretched = Csg::new(&CsgNode::Placed(
        ball,
        Affine3A::from_scale(Vec3::new(2.0, 1.0, 1.0)),
    ))
    .unwrap();
    let ellipsoid = Csg::new(&CsgNode::Leaf(Solid::Ellipsoid {
        center: Vec3::ZERO,
        radii: Vec3::new(2.0, 1.0, 1.0),
    }))
    .unwrap();
    for (o, d) in [
        (FROM_LEFT, Vec3::X * 3.0),
        (Vec3::new(-3.0, 2.0, 0.5), Vec3::new(1.0, -0.7, 0.0)),
    ] {
        let (a, b) = (
            full(&stretched, &Ray::new(o, d)).unwrap(),
            full(&ellipsoid, &Ray::new(o, d)).unwrap(),
        );
        assert!((a.t - b.t).abs() < 1e-5 * b.t, "{a:?} {b:?}");
        assert!(close(a.normal, b.normal), "{a:?} {b:?}");
    }
    // An identity placement gives the unplaced leaf's answers.
    let plain = Csg::new(&CsgNode::Leaf(torus(2.0, 0.5))).unwrap();
    let placed = Csg::new(&CsgNode::Placed(torus(2.0, 0.5), Affine3A::IDENTITY)).unwrap();
    let r = Ray::new(Vec3::new(-6.0, 0.2, 0.3), Vec3::new(1.0, 0.0, 0.05));
    let (a, b) = (full(&plain, &r).unwrap(), full(&placed, &r).unwrap());
    assert!(a.t == b.t && close(a.normal, b.normal), "{a:?} {b:?}");
}

#[test]
fn a_ring_cut_by_a_rotated_box() {
    use glam::Quat;
    // A torus R = 2, r = 0.5 minus a box rotated 45 degrees about y covering its +x
    // part: rays along the x axis see the ring on the left only.
    let cut = Affine3A::from_rotation_translation(
        Quat::from_rotation_y(std::f32::consts::FRAC_PI_4),
        Vec3::new(2.0, 0.0, 0.0),
    );
    let tree = op(
        CsgOp::Difference,
        CsgNode::Leaf(torus(2.0, 0.5)),
        CsgNode::Placed(
            Solid::Box {
                min: Vec3::splat(-1.0),
                max: Vec3::splat(1.0),
            },
            cut,
        ),
    );
    let c = Csg::new(&tree).unwrap();
    let h = full(&c, &Ray::new(FROM_LEFT, Vec3::X)).unwrap();
    assert_eq!((h.t, h.leaf), (7.5, 0));
    // Along z at x = 1.8 the ring spans |z| <= sqrt(2.5^2 - 1.8^2) and the box
    // |z| <= sqrt2 - 0.2: the ring's wall, then from inside it the box's face, its
    // outward normal (-1, 0, -1) / sqrt2 flipped.
    let ring = (2.5f32 * 2.5 - 1.8 * 1.8).sqrt();
    let h = full(&c, &Ray::new(Vec3::new(1.8, 0.0, -10.0), Vec3::Z)).unwrap();
    assert!((h.t - (10.0 - ring)).abs() < 1e-5 && h.leaf == 0, "{h:?}");
    let h = full(&c, &Ray::new(Vec3::new(1.8, 0.0, -1.5), Vec3::Z)).unwrap();
    let face = 1.5 - (2.0f32.sqrt() - 0.2);
    assert!((h.t - face).abs() < 1e-5 && h.leaf == 1, "{h:?}");
    assert!(
        close(h.normal, Vec3::new(1.0, 0.0, 1.0).normalize()),
        "{h:?}"
    );
}

#[test]
fn bad_solids_and_transforms_are_refused() {
    let torus_with = |r_big: f32, r_small: f32| CsgNode::Leaf(torus(r_big, r_small));
    let ball = Solid::Sphere {
        center: Vec3::ZERO,
        radius: 1.0,
    };
    let cases = [
        (torus_with(0.0, 1.0), "torus major radius must be positive"),
        (torus_with(1.0, -1.0), "torus minor radius must be positive"),
        (torus_with(f32::NAN, 1.0), "torus major radius"),
        (
            CsgNode::Leaf(Solid::Ellipsoid {
                center: Vec3::ZERO,
                radii: Vec3::new(1.0, 0.0, 1.0),
            }),
            "ellipsoid radius must be positive",
        ),
        (
            CsgNode::Leaf(Solid::Paraboloid {
                base: Vec3::ZERO,
                radius: 1.0,
                height: f32::INFINITY,
            }),
            "paraboloid height",
        ),
        (
            CsgNode::Placed(ball, Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0))),
            "singular",
        ),
        (
            CsgNode::Placed(ball, Affine3A::from_scale(Vec3::new(1.0, 1e-7, 1.0))),
            "singular",
        ),
        (
            CsgNode::Placed(
                ball,
                Affine3A::from_translation(Vec3::new(f32::NAN, 0.0, 0.0)),
            ),
            "transform",
        ),
        (
            CsgNode::Placed(ball, Affine3A::from_translation(Vec3::new(1e30, 0.0, 0.0))),
            "exceeds",
        ),
    ];
    for (tree, want) in cases {
        let e = Csg::new(&tree).unwrap_err().to_string();
        assert!(e.contains(want), "{tree:?}: {e}");
    }
}

#[test]
fn nan_and_zero_rays_miss() {
    let tree = op(
        CsgOp::Difference,
        cube(Vec3::splat(-1.0), Vec3::splat(1.0)),
        sphere(Vec3::ZERO, 1.2),
    );
    let c = Csg::new(&tree).unwrap();
    for r in [
        Ray::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X),
        Ray::new(FROM_LEFT, Vec3::new(f32::NAN, 0.0, 0.0)),
        Ray::new(FROM_LEFT, Vec3::ZERO),
    ] {
        assert_eq!(full(&c, &r), None);
    }
}
