//! SDF models through the scene format, against analytic answers: sphere-traced hits within
//! the stated tolerance of raybench's analytic `Sphere`, of CSG boxes and CSG trees built
//! from the same solids, and of an f64 reference for the torus; normals within a stated
//! angle; hit/miss agreement away from silhouettes; the Lipschitz bound of the built-in
//! scene's models; the step limit; Whitted reflection and refraction against analytic
//! spheres (the self-intersection rule); a white furnace; and clear errors for bad input.
//! (Cross-backend equality on the built-in `sdf` scene is in `equivalence.rs`; the march's
//! rules are unit-tested in `raybench_core::sdf`.)
//!
//! **Stated accuracy** (checked here for every ray of the scans):
//! - a hit's distance along the ray from the analytic hit, `|t - t_a| |dir|`, is at most
//!   `eps / cos(theta)` (`eps` the model's absolute tolerance, `theta` the angle between the
//!   ray and the analytic normal) plus f32 rounding, for rays with `cos(theta) >= 0.05`;
//! - normals are within 1 degree of the analytic ones for rays with `cos(theta) >= 0.25`
//!   and hit points at least `8 eps` from edges and creases (the tetrahedron samples at
//!   `eps` see an edge's other face; the hit point is up to `4 eps` off the analytic one);
//! - the grazing rule: answers (hit or miss, and which part is hit) may differ only for rays
//!   within `4 eps` of a silhouette, found by moving the ray sideways by `4 eps` in four
//!   directions: a ray passing within `eps` of the surface counts as a hit there, and a ray
//!   grazing the surface may run out of steps.

use raybench_core::{
    Csg, CsgNode, CsgOp, Hit, NoCounters, Ray, Scene, Sdf, Shape, Solid, Sphere, Vec3,
};
use std::path::Path;

fn load(text: &str) -> Result<Scene, String> {
    raybench_scene::load_scene_str(text, "t", None, Path::new("/nonexistent"))
        .map_err(|e| e.to_string())
}

fn sdf_object(tree: &str) -> String {
    format!("[[object]]\nkind = \"sdf\"\ntree = {tree}\n")
}

/// The one SDF model of a scene file holding just `tree`.
fn model(tree: &str) -> Sdf {
    let scene = load(&sdf_object(tree)).unwrap();
    let Shape::Sdf(m) = scene.geometry.shape(0) else {
        panic!("not an SDF model")
    };
    (**m).clone()
}

/// Deterministic values in `[0, 1)` (an additive recurrence).
fn weyl(i: usize, k: usize) -> f32 {
    const A: [f64; 4] = [0.754_877_666, 0.569_840_291, 0.430_159_709, 0.618_033_989];
    ((i as f64 + 1.0) * A[k]).fract() as f32
}

/// Rays from points on a sphere of radius 6 around `center` aimed at points in a cube of
/// half size `spread` around it.
fn rays(n: usize, center: Vec3, spread: f32) -> impl Iterator<Item = Ray> {
    (0..n).map(move |i| {
        let z = 2.0 * weyl(i, 0) - 1.0;
        let phi = std::f32::consts::TAU * weyl(i, 1);
        let s = (1.0 - z * z).sqrt();
        let from = center + 6.0 * Vec3::new(s * phi.cos(), z, s * phi.sin());
        let to = center
            + spread * Vec3::new(2.0 * weyl(i, 2) - 1.0, 2.0 * weyl(i, 3) - 1.0, 0.0)
            + spread * Vec3::new(0.0, 0.0, 2.0 * weyl(i + 17, 2) - 1.0);
        Ray::new(from, to - from)
    })
}

/// Two unit vectors perpendicular to `d` and to each other.
fn sideways(d: Vec3) -> [Vec3; 2] {
    let d = d.normalize();
    let a = d.any_orthonormal_vector();
    [a, d.cross(a)]
}

/// Whether moving `ray` sideways by `delta` in any of four directions changes the analytic
/// answer discontinuously: from hit to miss or back, or the hit's distance by more than
/// [`JUMP`] (it moves to another part of the surface). The ray is then within `delta` of a
/// silhouette, the outer one or one of a part in front of another.
fn near_silhouette(ray: &Ray, delta: f32, analytic: &dyn Fn(&Ray) -> Option<(f32, Vec3)>) -> bool {
    let len = ray.dir.length();
    let here = analytic(ray).map(|h| h.0 * len);
    let [a, b] = sideways(ray.dir);
    [a, -a, b, -b].iter().any(|&s| {
        let there = analytic(&Ray::new(ray.origin + s * delta, ray.dir)).map(|h| h.0 * len);
        match (here, there) {
            (Some(x), Some(y)) => (x - y).abs() > JUMP,
            (x, y) => x.is_some() != y.is_some(),
        }
    })
}

/// A change of the hit distance that counts as a jump to another part of the surface
/// (smooth parts move the hit by at most `4 eps / cos(theta)`, below 0.03 here).
const JUMP: f32 = 0.05;

/// What one comparison found.
#[derive(Debug, Default)]
struct Agreement {
    hits: usize,
    misses: usize,
    /// Rays near a silhouette whose answers differ (allowed).
    grazing_disagreements: usize,
    /// Largest `|t - t_a| |dir|`.
    max_dt: f32,
    /// Largest `|t - t_a| |dir| cos(theta) / eps` (at most 1 when the stated bound holds).
    max_ratio: f32,
    /// Normals compared.
    normals: usize,
    /// Largest normal angle, degrees.
    max_angle: f32,
}

/// Compares the SDF model's hits with `analytic` (distance and outward normal) over `n`
/// rays, asserting the stated accuracy; normals are checked where `smooth` says the
/// analytic hit point is away from edges.
fn compare(
    m: &Sdf,
    n: usize,
    center: Vec3,
    spread: f32,
    analytic: &dyn Fn(&Ray) -> Option<(f32, Vec3)>,
    smooth: &dyn Fn(Vec3) -> bool,
) -> Agreement {
    let eps = m.tolerance();
    let mut a = Agreement::default();
    for ray in rays(n, center, spread) {
        let want = analytic(&ray);
        let got = m.intersect(&ray).map(|h| h.t);
        let len = ray.dir.length();
        match (got, want) {
            (Some(t), Some((ta, na))) => {
                a.hits += 1;
                let cos = na.dot(ray.dir / len).abs();
                if cos < 0.05 {
                    continue;
                }
                let dt = (t - ta).abs() * len;
                // f32 rounding of points about 6 units out: a few ulps of 8.
                let slack = 4.0e-6;
                if dt > eps / cos + slack {
                    // Caught by a silhouette passed within `eps` on the way.
                    assert!(
                        near_silhouette(&ray, 4.0 * eps, analytic),
                        "{ray:?}: t {t} vs {ta}, {dt} > {eps} / {cos}"
                    );
                    a.grazing_disagreements += 1;
                    continue;
                }
                a.max_dt = a.max_dt.max(dt);
                a.max_ratio = a.max_ratio.max(dt * cos / eps);
                if cos >= 0.25 && smooth(ray.at(ta)) {
                    let angle = m.normal(ray.at(t)).angle_between(na).to_degrees();
                    assert!(angle < 1.0, "{ray:?}: normal off by {angle} degrees");
                    a.max_angle = a.max_angle.max(angle);
                    a.normals += 1;
                }
            }
            (None, None) => a.misses += 1,
            _ => {
                assert!(
                    near_silhouette(&ray, 4.0 * eps, analytic),
                    "{ray:?}: SDF {got:?} vs analytic {want:?} away from the silhouette"
                );
                a.grazing_disagreements += 1;
            }
        }
    }
    assert!(
        a.hits > n / 4 && a.misses > n / 20 && a.normals > n / 10,
        "{a:?}"
    );
    a
}

fn csg_hit(c: &Csg) -> impl Fn(&Ray) -> Option<(f32, Vec3)> + '_ {
    |r: &Ray| c.intersect(r).map(|h| (h.t, c.normal(r, &h)))
}

#[test]
fn sphere_matches_the_analytic_sphere() {
    let c = Vec3::new(0.5, 1.0, -0.5);
    let m = model("{ type = \"sphere\", center = [0.5, 1.0, -0.5], radius = 1.2 }");
    let s = Sphere::new(c, 1.2);
    let analytic = |r: &Ray| s.intersect(r).map(|h| (h.t, s.normal_at(r.at(h.t))));
    let a = compare(&m, 20_000, c, 1.5, &analytic, &|_| true);
    println!("sphere: eps {} {a:?}", m.tolerance());
}

#[test]
fn boxes_match_csg_boxes() {
    let m = model("{ type = \"box\", center = [0.0, 1.0, 0.0], half_extents = [1.0, 0.5, 0.75] }");
    let min = Vec3::new(-1.0, 0.5, -0.75);
    let max = Vec3::new(1.0, 1.5, 0.75);
    let c = Csg::new(&CsgNode::Leaf(Solid::Box { min, max })).unwrap();
    let eps = m.tolerance();
    // Away from edges: at least 2 eps from two faces at once.
    let smooth = |p: Vec3| {
        let d = (p - min).abs().min((max - p).abs());
        let mut near = d.to_array();
        near.sort_by(f32::total_cmp);
        near[1] > 8.0 * eps
    };
    let a = compare(&m, 20_000, Vec3::Y, 1.3, &csg_hit(&c), &smooth);
    println!("box: eps {eps} {a:?}");
}

#[test]
fn union_and_subtraction_match_the_csg_trees_of_the_same_solids() {
    let sphere = Solid::Sphere {
        center: Vec3::new(0.6, 0.4, 0.3),
        radius: 0.8,
    };
    let cube = Solid::Box {
        min: Vec3::splat(-0.7),
        max: Vec3::splat(0.7),
    };
    let sdf_sphere = "{ type = \"sphere\", center = [0.6, 0.4, 0.3], radius = 0.8 }";
    let sdf_box = "{ type = \"box\", center = [0, 0, 0], half_extents = [0.7, 0.7, 0.7] }";
    for (op, name) in [(CsgOp::Union, "union"), (CsgOp::Difference, "subtraction")] {
        let tree = CsgNode::Op(
            op,
            Box::new(CsgNode::Leaf(cube)),
            Box::new(CsgNode::Leaf(sphere)),
        );
        let c = Csg::new(&tree).unwrap();
        let m = model(&format!(
            "{{ type = \"{name}\", operands = [{sdf_box}, {sdf_sphere}] }}"
        ));
        let eps = m.tolerance();
        // Away from the creases where the box and the ball meet, and from the box's edges:
        // the field there is exact within `2 eps` of the surface.
        let smooth = |p: Vec3| {
            let ball = ((p - Vec3::new(0.6, 0.4, 0.3)).length() - 0.8).abs();
            let d = (p.abs() - Vec3::splat(0.7)).abs().to_array();
            let mut sorted = d;
            sorted.sort_by(f32::total_cmp);
            let on_ball = ball < 2.0 * eps;
            // On the ball, the box's faces are far; on a face, the ball and other faces are.
            if on_ball {
                sorted[0] > 8.0 * eps
            } else {
                ball > 8.0 * eps && sorted[1] > 8.0 * eps
            }
        };
        let a = compare(&m, 20_000, Vec3::ZERO, 1.2, &csg_hit(&c), &smooth);
        println!("{name}: eps {eps} {a:?}");
    }
}

/// The torus `(|p.xz| - R)^2 + p.y^2 = r^2` around `c`: the first root of its quartic
/// implicit function along the ray, by a fine scan for a sign change and bisection in f64.
fn torus_reference(ray: &Ray, c: Vec3, big: f64, small: f64) -> Option<(f32, Vec3)> {
    let o = (ray.origin - c).as_dvec3();
    let d = ray.dir.as_dvec3();
    let f = |t: f64| {
        let p = o + d * t;
        let q = p.length_squared() + big * big - small * small;
        q * q - 4.0 * big * big * (p.x * p.x + p.z * p.z)
    };
    // The scan covers the ray's stretch within 8 units of the centre, in steps far below
    // the tube's size (a tangent double root between samples is a grazing ray).
    let len = d.length();
    let steps = 200_000;
    let (t_end, dt) = (12.0 / len, 12.0 / len / f64::from(steps));
    let mut t0 = 0.0;
    let mut f0 = f(t0);
    for i in 1..=steps {
        let t1 = f64::from(i) * dt;
        let f1 = f(t1);
        if f0.signum() != f1.signum() {
            let (mut lo, mut hi) = (t0, t1);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if f(mid).signum() == f0.signum() {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let t = 0.5 * (lo + hi);
            let p = o + d * t;
            let ring = glam::DVec3::new(p.x, 0.0, p.z).normalize() * big;
            let n = (p - ring).normalize().as_vec3();
            return Some((t as f32, n));
        }
        (t0, f0) = (t1, f1);
        if t1 > t_end {
            break;
        }
    }
    None
}

#[test]
fn torus_matches_an_f64_reference() {
    let c = Vec3::new(0.2, 1.0, -0.3);
    let m = model(
        "{ type = \"torus\", center = [0.2, 1.0, -0.3], major_radius = 1.0, minor_radius = 0.35 }",
    );
    let analytic = |r: &Ray| torus_reference(r, c, 1.0, 0.35);
    let a = compare(&m, 2_000, c, 1.4, &analytic, &|_| true);
    println!("torus: eps {} {a:?}", m.tolerance());
}

/// The same torus as an analytic CSG solid (the f64 quartic of `raybench_core::csg`): the
/// sphere-traced hits are within the same stated tolerance of its hits, on 20,000 rays.
#[test]
fn torus_matches_the_analytic_csg_torus() {
    let c = Vec3::new(0.2, 1.0, -0.3);
    let m = model(
        "{ type = \"torus\", center = [0.2, 1.0, -0.3], major_radius = 1.0, minor_radius = 0.35 }",
    );
    let torus = Csg::new(&CsgNode::Leaf(Solid::Torus {
        center: c,
        major_radius: 1.0,
        minor_radius: 0.35,
    }))
    .unwrap();
    let a = compare(&m, 20_000, c, 1.4, &csg_hit(&torus), &|_| true);
    println!("analytic torus: eps {} {a:?}", m.tolerance());
}

/// `|f(x) - f(y)| <= L |x - y|` for every model of the built-in scene, over point pairs in
/// and around its box.
#[test]
fn the_built_in_models_respect_their_lipschitz_bound() {
    let scene = raybench_scene::load("sdf", Path::new("/nonexistent")).unwrap();
    let models: Vec<_> = scene
        .geometry
        .shapes()
        .iter()
        .filter_map(|s| match s {
            Shape::Sdf(m) => Some(m.clone()),
            _ => None,
        })
        .collect();
    assert_eq!(models.len(), 4);
    for m in models {
        let b = m.bounds();
        let (lo, size) = (b.min - b.extent() * 0.25, b.extent() * 1.5);
        let point = |i: usize, k: usize| {
            lo + size * Vec3::new(weyl(i, k % 4), weyl(i, (k + 1) % 4), weyl(i, (k + 2) % 4))
        };
        let mut worst = 0.0f32;
        for i in 0..20_000 {
            let x = point(i, 0);
            let y = x + (point(i * 7 + 3, 1) - lo - size * 0.5) * [1.0, 0.1, 0.01][i % 3];
            let dist = (x - y).length();
            if dist > 1e-3 {
                worst = worst.max((m.distance(x) - m.distance(y)).abs() / dist);
            }
        }
        assert_eq!(m.lipschitz(), 1.0);
        assert!(worst <= 1.001 * m.lipschitz(), "worst {worst}");
        assert!(worst > 0.5, "the sampling sees the field's slope: {worst}");
    }
}

#[test]
fn the_step_limit_makes_rays_miss() {
    let tree = "{ type = \"sphere\", center = [0, 0, 0], radius = 1 }";
    let closest = |text: &str, o: Vec3| -> Option<Hit> {
        let scene = load(text).unwrap();
        scene
            .geometry
            .closest_brute_force(&Ray::new(o, Vec3::Z), &mut NoCounters)
    };
    let head_on = Vec3::new(0.0, 0.0, -5.0);
    let grazing = Vec3::new(0.0, 0.99, -5.0);
    let full = sdf_object(tree);
    assert!(closest(&full, head_on).is_some());
    assert!(closest(&full, grazing).is_some());
    // Head-on rays converge in two steps; the grazing one needs more than four.
    let short = full.replace("kind = \"sdf\"", "kind = \"sdf\"\nmax_steps = 4");
    assert!(closest(&short, head_on).is_some());
    assert!(closest(&short, grazing).is_none());
    let one = full.replace("kind = \"sdf\"", "kind = \"sdf\"\nmax_steps = 1");
    assert!(closest(&one, head_on).is_none());
}

/// A scene with a glass ball and a mirror ball over a checker floor, either analytic
/// spheres or SDF spheres.
fn balls(sdf: bool) -> Scene {
    let ball = |c: &str, r: f32, material: &str| {
        if sdf {
            format!(
                "[[object]]\nkind = \"sdf\"\nmaterial = \"{material}\"\n\
                 tree = {{ type = \"sphere\", center = {c}, radius = {r} }}\n"
            )
        } else {
            format!(
                "[[object]]\nkind = \"sphere\"\nmaterial = \"{material}\"\ncenter = {c}\n\
                 radius = {r}\n"
            )
        }
    };
    let mut text = String::from(
        "background = [0.4, 0.6, 0.9]\n[camera]\nposition = [0, 1.5, 5]\nlook_at = [0, 0.8, 0]\n\
         fov = 45\n[[material]]\nname = \"floor\"\ncolor = [0.9, 0.9, 0.3]\n\
         checker = { color = [0.2, 0.3, 0.8], size = 0.5 }\n\
         [[material]]\nname = \"glass\"\nkind = \"glass\"\nior = 1.5\nspecular = [1, 1, 1]\n\
         [[material]]\nname = \"mirror\"\nkind = \"mirror\"\nspecular = [0.9, 0.9, 0.9]\n\
         [[light]]\nkind = \"point\"\nposition = [-3, 5, 4]\nintensity = [30, 30, 30]\n\
         [[object]]\nkind = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 1, 0]\nmaterial = \"floor\"\n",
    );
    text += &ball("[-0.7, 0.8, 0.0]", 0.8, "glass");
    text += &ball("[1.0, 0.6, -0.5]", 0.6, "mirror");
    load(&text).unwrap()
}

/// Whitted reflection and refraction through SDF balls give the analytic balls' image:
/// a secondary ray caught by the surface it leaves (or a refracted ray that never finds the
/// exit) would change whole regions of it. Pixels may differ only along the silhouettes
/// (hit/miss flips and the f32 differences of grazing refractions).
#[test]
fn whitted_reflection_and_refraction_match_analytic_balls() {
    use raybench_core::{Mode, RenderSettings};
    let settings = RenderSettings {
        width: 64,
        height: 64,
        spp: 1,
        mode: Mode::Whitted,
        max_depth: 8,
        seed: 1,
        count: false,
        ..RenderSettings::default()
    };
    let render = |sdf: bool| {
        raybench_tests::render_with(
            raybench_tests::ORACLE,
            &std::sync::Arc::new(balls(sdf)),
            &settings,
            2,
        )
    };
    let (a, b) = (render(false), render(true));
    let differing = a
        .color
        .iter()
        .zip(&b.color)
        .filter(|(x, y)| (**x - **y).abs().max_element() > 0.02)
        .count();
    let on_balls = a.ids.iter().filter(|&&id| id == 1 || id == 2).count();
    println!("{differing} of {on_balls} ball pixels differ");
    assert!(on_balls > 300, "{on_balls}");
    assert!(
        differing * 50 < on_balls,
        "{differing} of {on_balls} pixels differ"
    );
}

/// White furnace with SDF models: diffuse models of albedo 1 under a uniform environment of
/// radiance 1 give a mean radiance of 1; paths caught by the surface they leave or trapped
/// inside would use up the depth and darken it.
#[test]
fn white_furnace_with_sdf_models() {
    let mut text = String::from(
        "background = [1, 1, 1]\n[camera]\nposition = [0, 0, 4]\nlook_at = [0, 0, 0]\n\
         fov = 40\n[[material]]\nname = \"white\"\ncolor = [1, 1, 1]\nspecular = [0, 0, 0]\n",
    );
    let white = |tree: &str| {
        sdf_object(tree).replace("kind = \"sdf\"", "kind = \"sdf\"\nmaterial = \"white\"")
    };
    text += &white(
        r#"{ type = "smooth_union", k = 0.3, operands = [
            { type = "sphere", center = [-0.5, 0, 0], radius = 0.6 },
            { type = "capsule", a = [-0.5, 0, 0], b = [0.6, 0.8, 0], radius = 0.2 },
        ] }"#,
    );
    text += &white(
        r#"{ type = "transform", rotate = [60, 0, 20], translate = [0.6, -0.6, 0], operand =
            { type = "torus", center = [0, 0, 0], major_radius = 0.5, minor_radius = 0.2 } }"#,
    );
    raybench_tests::assert_white_furnace(&std::sync::Arc::new(load(&text).unwrap()));
}

#[test]
fn bad_models_give_clear_errors() {
    let cases = [
        (
            "{ type = \"union\", operands = [] }",
            "needs at least two operands",
        ),
        (
            "{ type = \"sphere\", center = [0, 0, 0], radius = -1 }",
            "radius must be positive",
        ),
        (
            "{ type = \"sphere\", center = [0, nan, 0], radius = 1 }",
            "not finite",
        ),
        (
            "{ type = \"smooth_union\", k = 0, operands = [\
             { type = \"sphere\", center = [0, 0, 0], radius = 1 },\
             { type = \"sphere\", center = [1, 0, 0], radius = 1 }] }",
            "k must be positive",
        ),
        (
            "{ type = \"blend\", w = 1.5, operands = [\
             { type = \"sphere\", center = [0, 0, 0], radius = 1 },\
             { type = \"sphere\", center = [1, 0, 0], radius = 1 }] }",
            "w must lie in [0, 1]",
        ),
        (
            "{ type = \"transform\", scale = [1, 2, 1], operand = \
             { type = \"sphere\", center = [0, 0, 0], radius = 1 } }",
            "non-uniform scale",
        ),
        (
            "{ type = \"torus\", center = [0, 0, 0], major_radius = 1, minor_radius = 0 }",
            "minor radius must be positive",
        ),
        (
            "{ type = \"box\", center = [0, 0, 0], half_extents = [1, 1, 1], rounding = -0.1 }",
            "rounding must lie in",
        ),
        (
            "{ type = \"sphere\", center = [0, 0, 0], radius = 1, colour = 3 }",
            "unknown field",
        ),
        ("{ type = \"blob\" }", "unknown variant"),
    ];
    for (tree, want) in cases {
        let err = load(&sdf_object(tree)).unwrap_err();
        assert!(err.contains(want), "{tree}: {err}");
    }
    let sphere = "{ type = \"sphere\", center = [0, 0, 0], radius = 1 }";
    // Past MAX_SDF_DEPTH levels the loader refuses the tree; far deeper, the TOML parser's
    // own recursion limit refuses the file first. Neither overflows the stack.
    let nested = |levels: usize| {
        let mut tree = sphere.to_string();
        for _ in 0..levels {
            tree = format!("{{ type = \"union\", operands = [{tree}, {sphere}] }}");
        }
        load(&sdf_object(&tree))
    };
    assert!(nested(raybench_core::limits::MAX_SDF_DEPTH - 1).is_ok());
    let err = nested(raybench_core::limits::MAX_SDF_DEPTH).unwrap_err();
    assert!(err.contains("deeper than 32"), "{err}");
    let err = nested(10_000).unwrap_err();
    assert!(err.contains("recursion"), "{err}");
    for (option, want) in [
        ("tolerance = 0.5", "tolerance must lie in"),
        ("max_steps = 100000", "max_steps must lie in"),
        ("max_steps = 0", "max_steps must lie in"),
    ] {
        let text =
            sdf_object(sphere).replace("kind = \"sdf\"", &format!("kind = \"sdf\"\n{option}"));
        let err = load(&text).unwrap_err();
        assert!(err.contains(want), "{option}: {err}");
    }
}

/// Steps per primary ray on the built-in scene's models (printed; run with `--nocapture`):
/// rays converge well within the step limit. The cost of a march against an analytic
/// intersection is a benchmark (`cargo bench -p raybench-tests --bench sdf`).
#[test]
fn steps_per_ray_on_the_built_in_scene() {
    let scene = raybench_scene::load("sdf", Path::new("/nonexistent")).unwrap();
    let (w, h) = (256u32, 256u32);
    let cam = scene.camera.rays(w, h);
    let (mut steps, mut marched, mut hits) = (0u64, 0u64, 0u64);
    for y in 0..h {
        for x in 0..w {
            let ray = cam.center_ray(x, y);
            for s in scene.geometry.shapes() {
                if let Shape::Sdf(m) = s {
                    let r = m.march(&ray);
                    if r.steps > 0 {
                        marched += 1;
                        steps += u64::from(r.steps);
                        hits += u64::from(r.t.is_some());
                    }
                }
            }
        }
    }
    let mean = steps as f64 / marched as f64;
    println!("{marched} marches (rays entering a model's box), {hits} hits, {mean:.1} steps each");
    assert!(marched > 1000 && mean < 64.0, "{mean}");
}
