//! Height fields intersected directly against the same terrain tessellated into triangles:
//! with the two-triangles-per-cell rule the cell triangles are the mesh's triangles, so
//! every hit and `t` must equal the mesh's (rendered by naive or by the BVH) bit for bit,
//! with the sub-primitive id equal to the mesh triangle's id. Both traversals (min-max tree
//! and plain 2D-DDA), with and without a placement, on camera rays, incoherent rays and
//! rays aimed at the grid's vertices and edges (where cells tie across their borders).

use raybench_core::sampling::{pcg3d, to_unit_f32};
use raybench_core::{Hit, Ray, RenderSettings, Scene, Shape, Vec3};
use raybench_tests::{prepared, render_with};
use std::path::Path;
use std::sync::Arc;

/// Placements: none, and scale + rotation + translation (so the vertices are rounded by
/// `transform_point3` exactly as the mesh's are).
const PLACEMENTS: &[&str] = &[
    "",
    "transform = { scale = [1.3, 0.8, 0.7], rotate = [12, 33, -7], translate = [0.2, -0.1, 0.4] }",
];

fn load(text: &str) -> Arc<Scene> {
    Arc::new(raybench_scene::load_scene_str(text, "t", None, Path::new("/nonexistent")).unwrap())
}

/// The tessellated and the direct scene of `terrain:n` under `placement`.
fn pair(n: u32, placement: &str, traversal: &str) -> (Arc<Scene>, Arc<Scene>) {
    let camera = "[camera]\nposition = [0.3, 1.2, 2.2]\nlook_at = [0, -0.1, 0]\n";
    let mesh = load(&format!(
        "{camera}[[object]]\nkind = \"generator\"\nspec = \"terrain:{n}\"\n{placement}\n"
    ));
    let direct = load(&format!(
        "{camera}[[object]]\nkind = \"height_field\"\nsource = \"terrain:{n}\"\n\
         traversal = \"{traversal}\"\n{placement}\n"
    ));
    (mesh, direct)
}

/// Rays aimed at vertices and edge midpoints of the mesh from random origins above and
/// around it, plus incoherent rays from inside its box.
fn probes(mesh: &Scene, count: u32) -> Vec<Ray> {
    let g = &mesh.geometry;
    let b = g.bounds();
    let mut rays = raybench_core::ray_sets::incoherent(b, count as usize, 11);
    for k in 0..count {
        let u = |d| to_unit_f32(pcg3d([k, 77, d])[0]);
        let tri = match g.shape((u(0) * g.len() as f32) as u32 % g.len() as u32) {
            Shape::Triangle(t) => *t,
            _ => unreachable!(),
        };
        let target = match k % 3 {
            0 => tri.v[(k / 3 % 3) as usize],
            1 => (tri.v[0] + tri.v[1]) * 0.5,
            _ => (tri.v[1] + tri.v[2]) * 0.5,
        };
        let o = b.center()
            + (Vec3::new(u(1), u(2), u(3)) * 2.0 - 1.0) * b.extent() * 1.5
            + Vec3::Y * b.extent().y * 2.0;
        rays.push(Ray::new(o, target - o));
        // Axis-parallel rays straight down through vertices.
        rays.push(Ray::new(target + Vec3::Y * 3.0, -Vec3::Y));
    }
    rays
}

fn same(what: &str, mesh: &[Option<Hit>], direct: &[Option<Hit>]) {
    let mut hits = 0;
    for (i, (m, d)) in mesh.iter().zip(direct).enumerate() {
        let key_m = m.map(|h| (h.prim, h.t.to_bits()));
        let key_d = d.map(|h| (h.sub, h.t.to_bits()));
        assert_eq!(key_m, key_d, "{what}: ray {i}: mesh {m:?}, direct {d:?}");
        hits += usize::from(m.is_some());
    }
    assert!(hits > mesh.len() / 4, "{what}: only {hits} hits");
}

#[test]
fn direct_height_field_equals_the_tessellated_mesh() {
    for placement in PLACEMENTS {
        for traversal in ["tree", "dda"] {
            for n in [1, 7, 64] {
                let (mesh, direct) = pair(n, placement, traversal);
                let what = format!("terrain:{n} {traversal} [{placement}]");
                let rays = probes(&mesh, 1500);
                let (reference, _) = prepared(raybench_tests::ORACLE, &mesh)
                    .trace_rays(&rays, false)
                    .unwrap();
                let (bvh, _) = prepared(raybench_tests::BASELINE, &mesh)
                    .trace_rays(&rays, false)
                    .unwrap();
                let key = |h: &Option<Hit>| h.map(|h| (h.prim, h.t.to_bits()));
                assert!(reference.iter().map(key).eq(bvh.iter().map(key)), "{what}");
                for backend in ["naive", "bvh", "grid", "packet"] {
                    let (hits, _) = prepared(backend, &direct).trace_rays(&rays, false).unwrap();
                    same(&format!("{what} {backend}"), &reference, &hits);
                }
                // Camera rays through the whole frame.
                let settings = RenderSettings {
                    width: 48,
                    height: 48,
                    ..RenderSettings::default()
                };
                let fm = render_with(raybench_tests::BASELINE, &mesh, &settings, 2);
                let fd = render_with(raybench_tests::BASELINE, &direct, &settings, 2);
                for (p, (tm, td)) in fm.t.iter().zip(&fd.t).enumerate() {
                    assert_eq!(tm.to_bits(), td.to_bits(), "{what}: pixel {p}");
                }
            }
        }
    }
}

#[test]
fn height_field_generator_matches_terrain_generator() {
    let mesh = Arc::new(raybench_scene::load("terrain:33", Path::new("/nonexistent")).unwrap());
    let direct =
        Arc::new(raybench_scene::load("heightfield:33", Path::new("/nonexistent")).unwrap());
    assert_eq!(direct.geometry.len(), 1);
    let rays = probes(&mesh, 1000);
    let (reference, _) = prepared(raybench_tests::ORACLE, &mesh)
        .trace_rays(&rays, false)
        .unwrap();
    let (hits, _) = prepared(raybench_tests::BASELINE, &direct)
        .trace_rays(&rays, false)
        .unwrap();
    same("heightfield:33", &reference, &hits);
}

#[test]
fn bilinear_cells_agree_across_backends_traversals_and_threads() {
    for placement in PLACEMENTS {
        let (mesh, _) = pair(24, placement, "tree");
        let rays = probes(&mesh, 800);
        let mut reference: Option<Vec<Option<Hit>>> = None;
        for traversal in ["tree", "dda"] {
            let scene = load(&format!(
                "[[object]]\nkind = \"height_field\"\nsource = \"terrain:24\"\n\
                 cells = \"bilinear\"\ntraversal = \"{traversal}\"\n{placement}\n"
            ));
            let naive = prepared(raybench_tests::ORACLE, &scene)
                .trace_rays(&rays, false)
                .unwrap()
                .0;
            let reference = reference.get_or_insert_with(|| naive.clone());
            let key = |h: &Option<Hit>| h.map(|h| (h.prim, h.sub, h.t.to_bits()));
            assert!(
                reference.iter().map(key).eq(naive.iter().map(key)),
                "{traversal}"
            );
            assert!(naive.iter().filter(|h| h.is_some()).count() > rays.len() / 4);
            for backend in ["bvh", "obvhs", "grid", "grid2", "packet"] {
                let hits = prepared(backend, &scene)
                    .trace_rays(&rays, false)
                    .unwrap()
                    .0;
                assert!(
                    naive.iter().map(key).eq(hits.iter().map(key)),
                    "{backend} {traversal} [{placement}]"
                );
            }
            let settings = RenderSettings {
                width: 32,
                height: 32,
                ..RenderSettings::default()
            };
            let a = render_with(raybench_tests::ORACLE, &scene, &settings, 1);
            let b = render_with("packet", &scene, &settings, 3);
            raybench_tests::assert_same_hits("bilinear frame", &a, &b);
            assert_eq!(a.color, b.color);
        }
    }
}
