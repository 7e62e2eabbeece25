//! Structure quality (`raybench_core::quality`) on generated and real scenes: every tree's
//! leaves hold every bounded primitive once, the `bvh` backend's SAH is `Bvh::sah_cost`, a
//! tree without overlap has an EPO of 0, and every registered backend reports finite
//! figures of the kind its structure has.

use raybench_bvh::{Bvh, ObvhsAccel};
use raybench_core::{
    Accel, Geometry, QualityParams, Scene, Shape, Sphere, StructureQuality, TreeQuality, Vec3,
};
use raybench_packet::PacketAccel;
use raybench_peers::BvhCrateAccel;
use raybench_registry::{BACKENDS, Roles};
use raybench_tests::load_or_skip;
use std::sync::Arc;

/// A generated soup, spheres and, where the shared meshes are installed, the low-resolution
/// bunny and the Cornell box.
fn scenes() -> Vec<Arc<Scene>> {
    ["soup:1000", "spheres", "bunny-lowres", "cornell-box"]
        .into_iter()
        .filter_map(load_or_skip)
        .collect()
}

fn tree(q: Option<StructureQuality>, what: &str) -> TreeQuality {
    match q {
        Some(StructureQuality::Tree(t)) => t,
        other => panic!("{what}: not a tree: {other:?}"),
    }
}

#[test]
fn every_tree_holds_every_bounded_primitive_once() {
    for scene in scenes() {
        let g = &scene.geometry;
        let name = &scene.name;
        Bvh::build(Arc::clone(g))
            .tree_view()
            .check_leaves(g)
            .unwrap_or_else(|e| panic!("{name} bvh: {e}"));
        ObvhsAccel::build(Arc::clone(g))
            .tree_view()
            .check_leaves(g)
            .unwrap_or_else(|e| panic!("{name} obvhs: {e}"));
        BvhCrateAccel::build(Arc::clone(g))
            .tree_view()
            .check_leaves(g)
            .unwrap_or_else(|e| panic!("{name} bvh-crate: {e}"));
        // The packet backend's view is its crate's own (`crates/packet`, unit tests); here
        // its figures: one reference per bounded primitive.
        let q = tree(
            PacketAccel::build(Arc::clone(g)).quality(&QualityParams::default()),
            name,
        );
        assert_eq!(q.references, g.bounded().len() as u64, "{name} packet");
    }
}

#[test]
fn bvh_sah_is_sah_cost() {
    for scene in scenes() {
        let bvh = Bvh::build(Arc::clone(&scene.geometry));
        let q = tree(bvh.quality(&QualityParams::default()), &scene.name);
        assert_eq!(q.sah, bvh.sah_cost(), "{}", scene.name);
        assert!(q.sah > 1.0, "{}: {}", scene.name, q.sah);
    }
}

#[test]
fn a_tree_without_overlap_has_no_epo() {
    // Unit spheres ten apart on a line: every split separates them, no box overlaps
    // another's spheres.
    let g = Arc::new(Geometry::new(
        (0..64)
            .map(|i| Shape::Sphere(Sphere::new(Vec3::new(10.0 * i as f32, 0.0, 0.0), 1.0)))
            .collect(),
    ));
    let p = QualityParams::default();
    let trees = [
        ("bvh", Bvh::build(Arc::clone(&g)).quality(&p)),
        ("obvhs", ObvhsAccel::build(Arc::clone(&g)).quality(&p)),
        ("packet", PacketAccel::build(Arc::clone(&g)).quality(&p)),
        (
            "bvh-crate",
            BvhCrateAccel::build(Arc::clone(&g)).quality(&p),
        ),
    ];
    for (name, q) in trees {
        let q = tree(q, name);
        assert_eq!(q.epo.samples, p.epo_samples, "{name}");
        assert_eq!((q.epo.mean, q.epo.std_error), (0.0, 0.0), "{name}");
        assert_eq!(q.references, 64, "{name}");
    }
}

#[test]
fn every_backend_reports_finite_figures_of_its_kind() {
    let params = QualityParams {
        epo_samples: 1024,
        ..QualityParams::default()
    };
    // Without an adapter the GPU backends are skipped with the reason (failing under
    // `CI=true`); so is any other backend that cannot run here or take the scene.
    let gpu = raybench_tests::gpu::available();
    let scenes = scenes();
    let (mut checked, mut devices) = (0, 0);
    for scene in &scenes {
        let bounded = scene.geometry.bounded().len() as u64;
        for b in BACKENDS {
            let mut r = (b.make)();
            if b.is(Roles::DEVICE) && !gpu {
                continue;
            }
            if let Err(e) = r.availability() {
                eprintln!("SKIPPED {}: {e}", b.name);
                continue;
            }
            if let Err(e) = r.supports(scene) {
                eprintln!("SKIPPED {} on {}: {e}", b.name, scene.name);
                continue;
            }
            checked += 1;
            devices += usize::from(b.is(Roles::DEVICE));
            r.prepare(scene).unwrap();
            let what = format!("{} {}", scene.name, b.name);
            match r.quality(&params) {
                Some(StructureQuality::Tree(t)) => {
                    assert!(t.sah.is_finite() && t.sah > 0.0, "{what}: SAH {}", t.sah);
                    assert!(
                        t.epo.mean.is_finite() && t.epo.mean >= 0.0 && t.epo.std_error.is_finite(),
                        "{what}: {:?}",
                        t.epo
                    );
                    assert_eq!(t.references, bounded, "{what}");
                    assert_eq!(t.leaf_sizes.0.iter().sum::<u64>(), t.leaves, "{what}");
                    assert!(t.max_depth >= 1 && t.bytes_per_primitive > 0.0, "{what}");
                    assert!(t.mean_leaf_depth <= f64::from(t.max_depth), "{what}");
                }
                Some(StructureQuality::Grid(g)) => {
                    // Grids list a primitive in every cell it overlaps.
                    assert!(g.references >= bounded, "{what}");
                    assert!(g.fill() > 0.0 && g.fill() <= 1.0, "{what}");
                    assert_eq!(g.primitives, bounded, "{what}");
                }
                Some(StructureQuality::NotReadable(reason)) => {
                    assert!(b.is(Roles::PEER), "{what}: {reason}");
                }
                None => assert!(b.is(Roles::BRUTE_FORCE), "{what}: no figures"),
            }
        }
    }
    assert!(checked > 0, "no backend reported figures");
    if gpu {
        assert_eq!(
            devices,
            raybench_tests::DEVICES.len() * scenes.len(),
            "GPU backends' figures"
        );
    }
}
