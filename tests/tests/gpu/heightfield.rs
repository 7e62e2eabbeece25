//! Height fields (`kernels/heightfield.wgsl`, `kernels/bilinear.wgsl`): placed, faceted,
//! walked by the 2D-DDA, of one cell or one row, of non-square and bilinear cells; and the
//! sub-primitives of their hits.

use super::{closest_hits, scene_toml, scratch};
use raybench_tests::gpu::check;

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
    let dir = scratch("hf");
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
        scene_toml(&dir, name, &text)
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
    let reference = closest_hits(raybench_tests::ORACLE, &scene, &rays);
    for name in raybench_tests::DEVICES {
        let hits = closest_hits(name, &scene, &rays);
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
