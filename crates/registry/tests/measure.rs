use raybench_core::ray_sets::DerivedParams;
use raybench_core::{Camera, Light, Material, SceneBuilder, Sphere, Vec3};
use raybench_core::{NO_HIT, RayCounters, RaySet, RenderSettings, Scene};
use raybench_registry::Roles;
use raybench_registry::measure::*;
use std::sync::Arc;

/// Spheres on a large floor sphere in front of the default camera, a point light and an
/// emissive sphere above: every derived set has rays, some blocked, some not.
fn scene() -> Arc<Scene> {
    let mut b = SceneBuilder::new("derived");
    b.camera(Camera::default()).unwrap();
    let white = b.add_material(Material::default()).unwrap();
    let lamp = b
        .add_material(Material {
            emission: Vec3::splat(4.0),
            ..Material::default()
        })
        .unwrap();
    b.add_sphere(Sphere::new(Vec3::new(0.0, -101.0, 0.0), 100.0), white)
        .unwrap();
    for i in 0..5 {
        let x = i as f32 * 0.8 - 1.6;
        b.add_sphere(Sphere::new(Vec3::new(x, -0.6, (i % 2) as f32), 0.4), white)
            .unwrap();
    }
    b.add_sphere(Sphere::new(Vec3::new(0.5, 2.5, 0.0), 0.5), lamp)
        .unwrap();
    b.add_light(Light::Point {
        position: Vec3::new(-2.0, 3.0, 2.0),
        intensity: Vec3::ONE,
    })
    .unwrap();
    Arc::new(b.build())
}

fn settings() -> RenderSettings {
    RenderSettings {
        width: 24,
        height: 18,
        ..RenderSettings::default()
    }
}

/// Every exact backend traces the same primary hits, so the derived sets do not depend
/// on which one traced them: naive's and bvh's are the same rays, bit for bit.
#[test]
fn derived_sets_are_the_same_from_every_exact_backend() {
    let scene = scene();
    let oracle = raybench_registry::with_role(Roles::ORACLE).unwrap();
    let baseline = raybench_registry::with_role(Roles::BASELINE).unwrap();
    assert_ne!(oracle.name, baseline.name);
    let params = DerivedParams::default();
    for set in [RaySet::Shadow, RaySet::Ao, RaySet::Diffuse] {
        let a = derived_rays(set, &scene, &settings(), &params, oracle).unwrap();
        let b = derived_rays(set, &scene, &settings(), &params, baseline).unwrap();
        assert!(!a.rays.is_empty(), "{}", set.name());
        assert_eq!(a, b, "{}", set.name());
        let batch = explicit_rays(set, &scene, &settings(), &params)
            .unwrap()
            .unwrap();
        assert_eq!(batch.rays, a.rays);
        assert_eq!(batch.facing_away, a.facing_away);
        assert_eq!(batch.any_hit, set.any_hit());
    }
    assert!(
        explicit_rays(RaySet::Primary, &scene, &settings(), &params)
            .unwrap()
            .is_none()
    );
}

/// Each ray traced alone through a tree walked ray by ray does the work it does in the
/// batch: the per-ray counts add up to the batch's counters, for closest and any hits.
#[test]
fn per_ray_counts_add_up_to_the_batch() {
    let scene = scene();
    let baseline = raybench_registry::with_role(Roles::BASELINE).unwrap();
    let p = prepare(baseline, &scene).unwrap();
    let batch = explicit_rays(
        RaySet::Shadow,
        &scene,
        &settings(),
        &DerivedParams::default(),
    )
    .unwrap()
    .unwrap();
    let primary = primary_rays(&scene, &settings()).unwrap();
    for (rays, any_hit) in [(&primary, false), (&batch.rays, true)] {
        let each = counts_per_ray(p.renderer.as_ref(), rays, any_hit)
            .unwrap()
            .unwrap();
        assert_eq!(each.len(), rays.len());
        let mut sum = RayCounters::default();
        for c in &each {
            raybench_core::Counters::merge(&mut sum, c);
        }
        let whole = RayBatch {
            rays: rays.clone(),
            any_hit,
            facing_away: 0,
        };
        let m = measure(p.renderer.as_ref(), &settings(), Some(&whole), true).unwrap();
        assert_eq!(Some(sum), m.counters, "any hit: {any_hit}");
        assert!(each.iter().any(|c| c.node_visits != each[0].node_visits));
    }
}

/// Any-hit answers are recorded as [`OCCLUDED`] / [`NO_HIT`], equal to whether the
/// closest-hit query hits, and counted.
#[test]
fn any_hit_measurements_agree_with_closest_hits() {
    let scene = scene();
    let params = DerivedParams::default();
    let baseline = raybench_registry::with_role(Roles::BASELINE).unwrap();
    let p = prepare(baseline, &scene).unwrap();
    for set in [RaySet::Shadow, RaySet::Ao] {
        let batch = explicit_rays(set, &scene, &settings(), &params)
            .unwrap()
            .unwrap();
        let any = measure(p.renderer.as_ref(), &settings(), Some(&batch), true).unwrap();
        let closest = RayBatch {
            any_hit: false,
            ..batch.clone()
        };
        let all = measure(p.renderer.as_ref(), &settings(), Some(&closest), true).unwrap();
        assert_eq!(any.rays, batch.rays.len() as u64);
        let expected: Vec<u32> = all
            .ids
            .iter()
            .map(|&id| if id == NO_HIT { NO_HIT } else { OCCLUDED })
            .collect();
        assert_eq!(any.ids, expected, "{}", set.name());
        let blocked = any.ids.iter().filter(|&&id| id == OCCLUDED).count();
        assert!(
            blocked > 0 && blocked < any.ids.len(),
            "{}: {blocked} of {} blocked",
            set.name(),
            any.ids.len()
        );
        let c = raybench_registry::compare_hits(&any.ids, &any.t, &expected, &any.t);
        assert!(c.is_exact());
        let counters = any.counters.unwrap();
        assert!(counters.prim_tests > 0 && counters.node_visits > 0);
    }
}
