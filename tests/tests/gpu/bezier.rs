//! Bezier patches (`kernels/bezier.wgsl`): a flat patch with its analytic hits and a
//! parabolic cylinder's silhouette at grazing angles, besides the built-in `teapot-bezier`
//! scene in `builtin::teapot_bezier`.

use super::{assert_same_blocked, closest_hits};

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
    let reference = closest_hits(raybench_tests::ORACLE, scene, rays);
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
        assert_same_blocked(&format!("{what}, {name}"), gpu.as_ref(), rays, &reference);
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
    let hits = closest_hits(raybench_tests::DEVICE, &scene, &rays);
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
