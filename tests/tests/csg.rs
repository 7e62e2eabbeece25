//! CSG trees through the scene format: analytic hit distances and normals of the combined
//! solids as every CPU backend's scene sees them, and clear errors for bad trees.
//! (Cross-backend equality on the built-in `csg` scene is in `equivalence.rs`; the span
//! rules are unit-tested in `raybench_core::csg`.)

use raybench_core::{Ray, Scene, Shape, Vec3};
use std::path::Path;

fn load(text: &str) -> Result<Scene, String> {
    raybench_scene::load_scene_str(text, "t", None, Path::new("/nonexistent"))
        .map_err(|e| e.to_string())
}

fn csg(tree: &str) -> String {
    format!("[[object]]\nkind = \"csg\"\ntree = {tree}\n")
}

/// A unit cube with a ball of radius 0.75 subtracted from its centre, a cylinder drilled
/// through along y.
const DRILLED: &str = r#"{ type = "difference", operands = [
    { type = "box", min = [-1, -1, -1], max = [1, 1, 1] },
    { type = "sphere", center = [0, 0, 0], radius = 0.75 },
    { type = "cylinder", base = [0, -2, 0], radius = 0.25, height = 4 },
] }"#;

#[test]
fn analytic_hits_through_the_scene() {
    let scene = load(&csg(DRILLED)).unwrap();
    assert_eq!(scene.geometry.len(), 1);
    let shape = scene.geometry.shape(0);
    assert!(matches!(shape, Shape::Csg(_)));
    let hit = |o: Vec3, d: Vec3| {
        let r = Ray::new(o, d);
        let mut c = raybench_core::NoCounters;
        scene.geometry.closest_brute_force(&r, &mut c)
    };
    // The front face of the cube.
    let h = hit(Vec3::new(0.5, 0.0, 5.0), -Vec3::Z).unwrap();
    assert_eq!((h.t, h.normal, h.sub), (4.0, Vec3::Z, 0));
    // Down the drilled hole: through both holes in the cube and the hollow, past the solid.
    assert!(hit(Vec3::new(0.0, 5.0, 0.0), -Vec3::Y).is_none());
    // From the centre (inside the hollow): the hollow's wall, its normal flipped inwards.
    let h = hit(Vec3::ZERO, Vec3::X).unwrap();
    assert_eq!((h.t, h.sub), (0.75, 1));
    assert!((h.normal + Vec3::X).length() < 1e-6, "{}", h.normal);
    // Inside the drilled hole, off the hollow: the cylinder's wall.
    let h = hit(Vec3::new(0.0, 0.9, 0.0), Vec3::X).unwrap();
    assert_eq!((h.t, h.sub, h.normal), (0.25, 2, -Vec3::X));
}

#[test]
fn the_built_in_scene_has_the_three_operations() {
    let scene = raybench_scene::load("csg", Path::new("/nonexistent")).unwrap();
    let trees = scene
        .geometry
        .shapes()
        .iter()
        .filter(|s| matches!(s, Shape::Csg(_)))
        .count();
    assert_eq!(trees, 4);
    let text = raybench_scene::BUILTIN_SCENES
        .iter()
        .find(|s| s.name == "csg")
        .unwrap()
        .source;
    for op in ["union", "intersection", "difference"] {
        assert!(text.contains(&format!("type = \"{op}\"")), "{op}");
    }
}

#[test]
fn bad_trees_give_clear_errors() {
    let sphere = r#"{ type = "sphere", center = [0, 0, 0], radius = 1 }"#;
    let cases = [
        (
            r#"{ type = "union", operands = [] }"#.to_string(),
            "needs at least two operands",
        ),
        (
            format!(r#"{{ type = "difference", operands = [{sphere}] }}"#),
            "needs at least two operands",
        ),
        (
            r#"{ type = "sphere", center = [nan, 0, 0], radius = 1 }"#.into(),
            "not finite",
        ),
        (
            r#"{ type = "sphere", center = [0, 0, 0], radius = inf }"#.into(),
            "not finite",
        ),
        (
            r#"{ type = "cone", base = [0, 0, 0], radius = 1, height = -1 }"#.into(),
            "must be positive",
        ),
        (
            r#"{ type = "box", min = [0, 0, 0], max = [1, 0, 1] }"#.into(),
            "below max",
        ),
        (
            r#"{ type = "half_space", point = [0, 0, 0], normal = [0, 1, 0] }"#.into(),
            "unbounded",
        ),
        (
            format!(
                r#"{{ type = "intersection", operands = [{sphere},
                   {{ type = "sphere", center = [9, 0, 0], radius = 1 }}] }}"#
            ),
            "empty",
        ),
        (
            r#"{ type = "klein_bottle", center = [0, 0, 0] }"#.into(),
            "unknown variant",
        ),
    ];
    for (tree, expected) in cases {
        let err = load(&csg(&tree)).unwrap_err();
        assert!(err.contains(expected), "{tree}: {err}");
    }
}

/// Past `MAX_CSG_DEPTH` levels the loader refuses the tree; far deeper, the TOML parser's
/// own recursion limit refuses the file first. Neither overflows the stack.
#[test]
fn deep_trees_are_refused_without_a_crash() {
    let nested = |levels: usize| {
        let leaf = r#"{ type = "sphere", center = [0, 0, 0], radius = 1 }"#;
        let mut tree = leaf.to_string();
        for _ in 0..levels {
            tree = format!(r#"{{ type = "union", operands = [{tree}, {leaf}] }}"#);
        }
        load(&csg(&tree))
    };
    assert!(nested(raybench_core::limits::MAX_CSG_DEPTH - 1).is_ok());
    let err = nested(raybench_core::limits::MAX_CSG_DEPTH).unwrap_err();
    assert!(err.contains("deeper than"), "{err}");
    let err = nested(10_000).unwrap_err();
    assert!(err.contains("recursion"), "{err}");
}

/// White furnace with CSG solids: diffuse solids of albedo 1 under a uniform environment
/// of radiance 1 reflect exactly what they receive, so the mean radiance is 1: paths that
/// leaked into the solids or were caught by their own surface (a hit at the start of a
/// continued ray) would darken the image. (Diffuse shading faces the normal towards the ray,
/// so this does not see a normal's sign; `analytic_hits_through_the_scene` and the core's
/// unit tests check the signs.)
#[test]
fn white_furnace_with_csg_solids() {
    let mut text = String::from(
        "background = [1, 1, 1]\n[camera]\nposition = [0, 0, 4]\nlook_at = [0, 0, 0]\n\
         fov = 40\n[[material]]\nname = \"white\"\ncolor = [1, 1, 1]\nspecular = [0, 0, 0]\n",
    );
    text += &csg(DRILLED).replace("kind = \"csg\"", "kind = \"csg\"\nmaterial = \"white\"");
    text += &csg(r#"{ type = "union", operands = [
            { type = "sphere", center = [1.2, 1.0, 0.5], radius = 0.5 },
            { type = "cone", base = [1.2, 0.0, 0.5], radius = 0.5, height = 1.0 },
        ] }"#)
    .replace("kind = \"csg\"", "kind = \"csg\"\nmaterial = \"white\"");
    // Placed quadrics: a tilted torus, a squashed ellipsoid and a paraboloid, placed by transforms.
    text += "[[object]]\nkind = \"torus\"\ncenter = [0, 0, 0]\nmajor_radius = 0.5\n\
             minor_radius = 0.2\nmaterial = \"white\"\n\
             transform = { rotate = [60, 0, 20], translate = [-1.2, 1.0, 0.5] }\n\
             [[object]]\nkind = \"ellipsoid\"\ncenter = [0, 0, 0]\nradii = [0.6, 0.3, 0.4]\n\
             material = \"white\"\ntransform = { rotate = [0, 30, 0], translate = [-1.2, -1.0, 0.5] }\n\
             [[object]]\nkind = \"paraboloid\"\nbase = [1.2, -1.4, 0.5]\nradius = 0.5\n\
             height = 0.8\nmaterial = \"white\"\n";
    raybench_tests::assert_white_furnace(&std::sync::Arc::new(load(&text).unwrap()));
}
