//! Moving scenes: on every frame of the built-in `moving` scene (a twisting mesh,
//! instances moved by keys, spin, orbit and bob, a twisting instanced mesh) and of a flat
//! twisting scene, every exact backend, brought from frame to frame by
//! `Renderer::update` (refit where it can, and rebuild), returns the naive oracle's ids and
//! `t` bit for bit (camera rays) and its closest and any hits of seeded incoherent rays; so a
//! refitted tree is a valid, conservative tree on every frame.

use raybench_core::{RenderSettings, Renderer, Scene, UpdatePolicy, random_rays};
use raybench_tests::{
    ORACLE, assert_same_hits, assert_same_ray_hits, available, load_or_skip, prepared,
};
use std::sync::Arc;

/// Backends under test.
const BACKENDS: &[&str] = raybench_tests::EXACT_BACKENDS;

/// Frames checked: the report's 32.
const FRAMES: u32 = 32;

/// `scene`'s frames 0..FRAMES through every exact backend, one renderer per backend and
/// policy updated from frame to frame, each frame against a naive renderer prepared for it.
fn check_frames(scene: &Arc<Scene>, size: u32, rays: usize) {
    let settings = RenderSettings {
        width: size,
        height: size,
        ..RenderSettings::default()
    };
    let backends = available(BACKENDS);
    let mut renderers: Vec<(String, UpdatePolicy, Box<dyn Renderer>)> = Vec::new();
    for name in &backends {
        for policy in UpdatePolicy::ALL {
            renderers.push((name.to_string(), policy, prepared(name, scene)));
        }
    }
    let mut refitted = 0;
    for f in 0..FRAMES {
        let at = Arc::new(scene.at_frame(f).unwrap());
        let naive = prepared(ORACLE, &at);
        let reference = naive.render(&settings).unwrap();
        let incoherent = random_rays::incoherent(at.geometry.world_bounds(), rays, f);
        let (closest, _) = naive.trace_rays(&incoherent, false).unwrap();
        let (any, _) = naive.occlude_rays(&incoherent, false).unwrap();
        assert!(reference.ids.iter().any(|&i| i != raybench_core::NO_HIT));
        let mut rebuilds_only: Vec<String> = Vec::new();
        for (name, policy, r) in &mut renderers {
            let what = format!("{name} ({}) on {} frame {f}", policy.name(), scene.name);
            if f > 0 {
                let phases = r.update(&at, *policy).unwrap();
                refitted += usize::from(phases.get("refit").is_some());
                if *policy == UpdatePolicy::Rebuild {
                    assert!(phases.get("refit").is_none(), "{what}: {phases:?}");
                } else if phases.get("refit").is_none() {
                    rebuilds_only.push(name.clone());
                }
            }
            let frame = r.render(&settings).unwrap();
            assert_same_hits(&what, &reference, &frame);
            let (hits, _) = r.trace_rays(&incoherent, false).unwrap();
            assert_same_ray_hits(&what, &closest, &hits);
            let (occluded, _) = r.occlude_rays(&incoherent, false).unwrap();
            assert_eq!(occluded, any, "{what}: any hits differ");
        }
        // A backend that rebuilds under the refit policy too needs no second renderer.
        renderers.retain(|(name, policy, _)| {
            *policy == UpdatePolicy::Refit || !rebuilds_only.contains(name)
        });
    }
    // At least one backend refits (raybench's BVH and what builds on it).
    assert!(refitted > 0, "no backend refitted");
}

/// The built-in moving scene: instances (two-level forms: the flat part and the twisting
/// mesh refitted, the top level rebuilt every frame).
#[test]
fn every_backend_on_every_frame_of_the_moving_scene() {
    let Some(scene) = load_or_skip("moving") else {
        return;
    };
    assert!(scene.is_moving());
    check_frames(&scene, 24, 400);
}

/// A flat moving scene (no instances): the backends' own structures refitted.
#[test]
fn every_backend_on_every_frame_of_a_flat_twisting_mesh() {
    let scene = raybench_scene::load_scene_str(
        "[camera]\nposition = [0, 1, 7]\nlook_at = [0, 1, 0]\n\
         [[object]]\nkind = \"plane\"\npoint = [0, -1.5, 0]\nnormal = [0, 1, 0]\n\
         [[object]]\nkind = \"generator\"\nspec = \"icosphere:3\"\n\
         transform = { scale = [1.5, 2.5, 0.4], translate = [0, 1, 0] }\n\
         deform = { kind = \"twist\", axis = \"y\", degrees_per_frame = 11 }\n\
         [[object]]\nkind = \"sphere\"\ncenter = [1.2, 0.5, 0.6]\nradius = 0.5\n",
        "twist",
        None,
        std::path::Path::new("/nonexistent"),
    )
    .unwrap();
    assert!(scene.is_moving() && !scene.geometry.has_instances());
    check_frames(&Arc::new(scene), 24, 400);
}
