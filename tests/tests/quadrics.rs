//! Tori, ellipsoids, paraboloids and placed (transformed) solids through the scene format:
//! analytic hit distances and normals as every CPU backend's scene sees them, CSG with a
//! torus, and clear errors for bad parameters and singular transforms. (Cross-backend
//! equality and the Whitted/path modes on the built-in `quadrics` scene are in
//! `equivalence.rs`; the quartic solver's accuracy against a dense f64 scan is unit-tested
//! in `crates/geometry/src/csg/quartic.rs`; the white furnace with these solids is in `csg.rs`.)

use raybench_core::{Hit, Ray, Scene, Shape, Vec3};
use std::path::Path;

fn load(text: &str) -> Result<Scene, String> {
    raybench_scene::load_scene_str(text, "t", None, Path::new("/nonexistent"))
        .map_err(|e| e.to_string())
}

fn closest(scene: &Scene, o: Vec3, d: Vec3) -> Option<Hit> {
    let mut c = raybench_core::NoCounters;
    scene.geometry.closest_brute_force(&Ray::new(o, d), &mut c)
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

/// One object of `kind` with the given fields.
fn object(kind: &str, fields: &str) -> String {
    format!("[[object]]\nkind = \"{kind}\"\n{fields}\n")
}

#[test]
fn standalone_solids_hit_analytically() {
    // A torus R = 2, r = 0.5 about y at the origin.
    let torus = load(&object(
        "torus",
        "center = [0, 0, 0]\nmajor_radius = 2\nminor_radius = 0.5",
    ))
    .unwrap();
    assert!(matches!(torus.geometry.shape(0), Shape::Csg(_)));
    let h = closest(&torus, Vec3::new(-10.0, 0.0, 0.0), Vec3::X).unwrap();
    assert_eq!((h.t, h.normal), (7.5, -Vec3::X));
    // Through the hole along the axis: nothing; down onto the tube's top: t = 9.5.
    assert!(closest(&torus, Vec3::new(0.0, 10.0, 0.0), -Vec3::Y).is_none());
    let h = closest(&torus, Vec3::new(0.0, 10.0, 2.0), -Vec3::Y).unwrap();
    assert_eq!((h.t, h.normal), (9.5, Vec3::Y));
    // A grazing ray through the tube at 45 degrees: the normal points from the tube's
    // centre circle to the hit point.
    let o = Vec3::new(-10.0, 0.3, 0.0);
    let h = closest(&torus, o, Vec3::X).unwrap();
    let x = -2.0 - (0.25f32 - 0.09).sqrt();
    assert!((h.t - (x + 10.0)).abs() < 1e-5, "{}", h.t);
    assert!(close(
        h.normal,
        (Vec3::new(x, 0.3, 0.0) - Vec3::new(-2.0, 0.0, 0.0)) / 0.5
    ));

    // An ellipsoid of radii (1, 2, 3): from above and from the front.
    let e = load(&object(
        "ellipsoid",
        "center = [0, 1, 0]\nradii = [1, 2, 3]",
    ))
    .unwrap();
    let h = closest(&e, Vec3::new(0.0, 10.0, 0.0), -Vec3::Y).unwrap();
    assert_eq!((h.t, h.normal), (7.0, Vec3::Y));
    // (The ellipsoid divides by its radii, so t is exact only to rounding.)
    let h = closest(&e, Vec3::new(0.0, 1.0, 10.0), -Vec3::Z).unwrap();
    assert!(
        (h.t - 7.0).abs() < 1e-5 && close(h.normal, Vec3::Z),
        "{h:?}"
    );

    // A paraboloid y = x^2 + z^2 capped at height 1: its wall at y = 0.25 is at x = 0.5 with
    // the normal along (-1, -1, 0) there; the cap from above.
    let p = load(&object(
        "paraboloid",
        "base = [0, 0, 0]\nradius = 1\nheight = 1",
    ))
    .unwrap();
    let h = closest(&p, Vec3::new(-5.0, 0.25, 0.0), Vec3::X).unwrap();
    assert_eq!(h.t, 4.5);
    assert!(
        close(h.normal, Vec3::new(-1.0, -1.0, 0.0).normalize()),
        "{}",
        h.normal
    );
    let h = closest(&p, Vec3::new(0.5, 5.0, 0.0), -Vec3::Y).unwrap();
    assert_eq!((h.t, h.normal), (4.0, Vec3::Y));
}

#[test]
fn transformed_solids_match_hand_computed_hits() {
    // A cylinder of radius 0.5 and height 4 laid along x (rotated -90 degrees about z), then
    // moved to stand 1 above the origin: its axis runs from (0, 1, 0) to (4, 1, 0).
    let cyl = load(&object(
        "cylinder",
        "base = [0, 0, 0]\nradius = 0.5\nheight = 4\n\
         transform = { rotate = [0, 0, -90], translate = [0, 1, 0] }",
    ))
    .unwrap();
    let h = closest(&cyl, Vec3::new(2.0, 10.0, 0.0), -Vec3::Y).unwrap();
    assert!(
        (h.t - 8.5).abs() < 1e-5 && close(h.normal, Vec3::Y),
        "{h:?}"
    );
    // Its end cap (the local top) faces +x.
    let h = closest(&cyl, Vec3::new(10.0, 1.0, 0.1), -Vec3::X).unwrap();
    assert!(
        (h.t - 6.0).abs() < 1e-5 && close(h.normal, Vec3::X),
        "{h:?}"
    );
    let b = cyl.geometry.shape(0).bounds().unwrap();
    assert!(b.min.x > -0.01 && b.max.x < 4.01 && b.min.y > 0.49 && b.max.y < 1.51);

    // A cone (radius 1, height 2) turned upside down by a 180-degree rotation about x and
    // lifted by 2: apex at the origin, base disc at y = 2 facing up.
    let cone = load(&object(
        "cone",
        "base = [0, 0, 0]\nradius = 1\nheight = 2\n\
         transform = { rotate = [180, 0, 0], translate = [0, 2, 0] }",
    ))
    .unwrap();
    let h = closest(&cone, Vec3::new(0.2, 10.0, 0.0), -Vec3::Y).unwrap();
    assert!(
        (h.t - 8.0).abs() < 1e-5 && close(h.normal, Vec3::Y),
        "{h:?}"
    );
    // At height 1 the radius is 0.5; the slanted wall's normal is along (2, -1, 0).
    let h = closest(&cone, Vec3::new(-5.0, 1.0, 0.0), Vec3::X).unwrap();
    assert!((h.t - 4.5).abs() < 1e-5, "{h:?}");
    assert!(
        close(h.normal, Vec3::new(-2.0, -1.0, 0.0).normalize()),
        "{h:?}"
    );

    // A sphere scaled non-uniformly is the ellipsoid with those radii; an unnormalised
    // direction keeps t in its units.
    let squashed = load(&object(
        "ellipsoid",
        "center = [0, 0, 0]\nradii = [1, 1, 1]\ntransform = { scale = [2, 0.5, 1], translate = [0, 1, 0] }",
    ))
    .unwrap();
    let h = closest(&squashed, Vec3::new(-10.0, 1.0, 0.0), Vec3::X * 2.0).unwrap();
    assert!(
        (h.t - 4.0).abs() < 1e-5 && close(h.normal, -Vec3::X),
        "{h:?}"
    );
    let h = closest(&squashed, Vec3::new(0.0, 10.0, 0.0), -Vec3::Y).unwrap();
    assert!(
        (h.t - 8.5).abs() < 1e-5 && close(h.normal, Vec3::Y),
        "{h:?}"
    );
    // Off-axis: the normal of x^2/4 + (y-1)^2/0.25 + z^2 = 1 at (sqrt2, 1 + sqrt0.125, 0)
    // is along (x/4, 4 (y-1), 0).
    let p = Vec3::new(2.0f32.sqrt(), 1.0 + 0.125f32.sqrt(), 0.0);
    let h = closest(&squashed, p + Vec3::Y * 5.0, -Vec3::Y).unwrap();
    assert!((h.t - 5.0).abs() < 1e-5, "{h:?}");
    let want = Vec3::new(p.x / 4.0, 4.0 * (p.y - 1.0), 0.0).normalize();
    assert!(close(h.normal, want), "{h:?} {want}");
}

#[test]
fn csg_with_a_torus_and_placed_operands() {
    // A torus R = 2, r = 0.5 minus a box over its x > 1 part, plus a ball scaled flat.
    let scene = load(
        r#"[[object]]
kind = "csg"
tree = { type = "union", operands = [
    { type = "difference", operands = [
        { type = "torus", center = [0, 0, 0], major_radius = 2, minor_radius = 0.5 },
        { type = "box", min = [-1, -1, -1], max = [1, 1, 1],
          transform = { scale = [1, 1, 3], translate = [2, 0, 0] } },
    ] },
    { type = "sphere", center = [0, 0, 0], radius = 1,
      transform = { scale = [0.5, 0.25, 0.5], translate = [0, 3, 0] } },
] }
"#,
    )
    .unwrap();
    // From the left: the torus's outer wall. From the right: the box removed the right part
    // of the ring, so the ray passes x = 2.5 .. 1.5 and the hole, to the ring's left part's
    // inner wall at x = -1.5.
    let h = closest(&scene, Vec3::new(-10.0, 0.0, 0.0), Vec3::X).unwrap();
    assert_eq!((h.t, h.sub), (7.5, 0));
    let h = closest(&scene, Vec3::new(10.0, 0.0, 0.0), -Vec3::X).unwrap();
    assert_eq!((h.t, h.sub, h.normal), (11.5, 0, Vec3::X));
    // From inside the tube (on its centre circle at z = 2) towards +x: the box's face at
    // x = 1 (leaf 1), its outward normal -x flipped.
    let h = closest(&scene, Vec3::new(0.0, 0.0, 2.0), Vec3::X).unwrap();
    assert!((h.t - 1.0).abs() < 1e-5 && h.sub == 1, "{h:?}");
    assert!(close(h.normal, Vec3::X), "{h:?}");
    // The flattened ball above: top at y = 3.25.
    let h = closest(&scene, Vec3::new(0.0, 10.0, 0.0), -Vec3::Y).unwrap();
    assert!(
        (h.t - 6.75).abs() < 1e-5 && h.sub == 2 && close(h.normal, Vec3::Y),
        "{h:?}"
    );
}

#[test]
fn the_built_in_scene_has_every_solid() {
    let scene = raybench_scene::load("quadrics", Path::new("/nonexistent")).unwrap();
    let solids = scene
        .geometry
        .shapes()
        .iter()
        .filter(|s| matches!(s, Shape::Csg(_)))
        .count();
    assert_eq!(solids, 7);
    let text = raybench_scene::BUILTIN_SCENES
        .iter()
        .find(|s| s.name == "quadrics")
        .unwrap()
        .source;
    for kind in [
        "torus",
        "ellipsoid",
        "paraboloid",
        "cylinder",
        "cone",
        "csg",
    ] {
        assert!(text.contains(&format!("kind = \"{kind}\"")), "{kind}");
    }
    for needle in [
        "kind = \"glass\"",
        "kind = \"mirror\"",
        "type = \"torus\"",
        "rotate",
    ] {
        assert!(text.contains(needle), "{needle}");
    }
}

#[test]
fn bad_solids_give_clear_errors() {
    let cases = [
        (
            object(
                "torus",
                "center = [0, 0, 0]\nmajor_radius = 0\nminor_radius = 1",
            ),
            "torus major radius must be positive",
        ),
        (
            object(
                "torus",
                "center = [0, 0, 0]\nmajor_radius = 1\nminor_radius = nan",
            ),
            "torus minor radius is not finite",
        ),
        (
            object("ellipsoid", "center = [0, 0, 0]\nradii = [1, -1, 1]"),
            "ellipsoid radius must be positive",
        ),
        (
            object("paraboloid", "base = [0, 0, 0]\nradius = 1\nheight = 0"),
            "paraboloid height must be positive",
        ),
        (
            object("cone", "base = [inf, 0, 0]\nradius = 1\nheight = 1"),
            "cone base is not finite",
        ),
        (
            object(
                "cylinder",
                "base = [0, 0, 0]\nradius = 1\nheight = 1\ntransform = { scale = [1, 0, 1] }",
            ),
            "singular",
        ),
        (
            object(
                "torus",
                "center = [0, 0, 0]\nmajor_radius = 1\nminor_radius = 0.5\n\
                 transform = { scale = [1, 1e-7, 1] }",
            ),
            "singular",
        ),
        (
            object(
                "ellipsoid",
                "center = [0, 0, 0]\nradii = [1, 1, 1]\ntransform = { translate = [nan, 0, 0] }",
            ),
            "transform is not finite",
        ),
        (
            object(
                "ellipsoid",
                "center = [0, 0, 0]\nradii = [1, 1, 1]\ntransform = { scale = 1e38 }",
            ),
            "exceeds",
        ),
        (
            object("torus", "center = [0, 0, 0]\nmajor_radius = 1"),
            "missing field `minor_radius`",
        ),
        (
            object(
                "torus",
                "center = [0, 0, 0]\nmajor_radius = 1\nminor_radius = 1\nradius = 2",
            ),
            "unknown field `radius`",
        ),
        (
            "[[object]]\nkind = \"csg\"\ntree = { type = \"union\", operands = [\n\
             { type = \"torus\", center = [0, 0, 0], major_radius = 1, minor_radius = 0.5, \
             material = \"red\" },\n\
             { type = \"sphere\", center = [0, 0, 0], radius = 1 }] }\n"
                .to_string(),
            "cannot have its own material",
        ),
    ];
    for (text, expected) in cases {
        let err = load(&text).unwrap_err();
        assert!(err.contains(expected), "{text}: {err}");
    }
}

/// Shadow rays leave every primitive of the built-in `quadrics`, `csg` and `sdf` scenes
/// cleanly: from each lit camera-ray hit (origin offset along the normal as the integrators
/// do), the ray towards each point light never hits the primitive it starts on within the
/// first 1e-3 of its length. Regression: the quadric solids' coefficients in f32 put camera
/// hits on a tilted cylinder 1e-5 off its surface, and 12% of its shadow rays re-hit it.
#[test]
fn shadow_rays_do_not_rehit_their_own_solid() {
    for name in ["quadrics", "csg", "sdf"] {
        shadow_rays_leave_cleanly(name);
    }
}

fn shadow_rays_leave_cleanly(name: &str) {
    let scene = raybench_scene::load(name, Path::new("/nonexistent")).unwrap();
    let rays = scene.camera.rays(256, 256);
    let mut c = raybench_core::NoCounters;
    let mut acne = std::collections::BTreeMap::<u32, (u32, u32)>::new();
    for y in 0..256 {
        for x in 0..256 {
            let ray = rays.center_ray(x, y);
            let Some(hit) = scene.geometry.closest_brute_force(&ray, &mut c) else {
                continue;
            };
            let p = ray.at(hit.t);
            let n = if hit.normal.dot(ray.dir) < 0.0 {
                hit.normal
            } else {
                -hit.normal
            };
            for light in &scene.lights {
                let raybench_core::Light::Point { position, .. } = *light else {
                    continue;
                };
                if n.dot(position - p) <= 0.0 {
                    continue;
                }
                let o = raybench_core::optics::offset_ray_origin(p, n);
                let shadow = Ray::with_interval(o, position - o, 0.0, 1.0);
                let e = acne.entry(hit.prim).or_default();
                e.0 += 1;
                if let Some(h) = scene.geometry.shape(hit.prim).intersect(&shadow)
                    && h.t < 1e-3
                {
                    e.1 += 1;
                }
            }
        }
    }
    let tested: u32 = acne.values().map(|&(n, _)| n).sum();
    assert!(tested > 5_000, "{name}: only {tested} shadow rays");
    assert!(
        acne.values().all(|&(_, bad)| bad == 0),
        "{name}: (shadow rays, re-hits) per primitive: {acne:?}"
    );
}
