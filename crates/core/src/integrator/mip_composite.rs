//! The volume modes: maximum-intensity projection and emission-absorption compositing of
//! the scene's voxel volumes along each camera ray, cut by the first surface.

use super::cast::shade_cast;
use crate::Hit;
use crate::Ray;
use crate::scene::Scene;
use crate::voxels::VolumeSample;
use glam::Vec3;

/// The colour of a camera ray in the volume modes. The surface behind (or the background)
/// is shaded as in ray casting; every volume is integrated from where the ray enters it to
/// where it leaves it or meets that surface.
///
/// - Maximum-intensity projection (`composite` false): the grey level of the largest value
///   met, through each volume's window; where it is brighter than the surface colour it
///   wins, channel by channel (so a black background gives the classic X-ray-like image).
/// - Compositing (`composite` true): `C + T * surface`, with the colour `C` and
///   transmittance `T` accumulated front to back through the volumes in the order the ray
///   enters them (overlapping volumes are taken one after the other, not interleaved).
#[must_use]
pub fn shade_volumes(
    scene: &Scene,
    light_dir: Vec3,
    ray: &Ray,
    hit: Option<&Hit>,
    composite: bool,
) -> Vec3 {
    let surface = shade_cast(scene, light_dir, ray, hit);
    if scene.volumes.is_empty() {
        return surface;
    }
    let t_max = hit.map_or(ray.t_max, |h| h.t);
    if !composite {
        let mut grey = f32::NEG_INFINITY;
        for v in &scene.volumes {
            let mut acc = VolumeSample::default();
            v.integrate(ray, t_max, false, &mut acc);
            if acc.crossed {
                let [lo, hi] = v.params().window;
                grey = grey.max(((acc.max - lo) / (hi - lo)).clamp(0.0, 1.0));
            }
        }
        return if grey >= 0.0 {
            surface.max(Vec3::splat(grey))
        } else {
            surface
        };
    }
    // Front to back: volumes in the order the ray enters them (ties by scene order).
    let mut order: Vec<(f32, usize)> = scene
        .volumes
        .iter()
        .enumerate()
        .filter_map(|(i, v)| v.grid_ray(ray, t_max).map(|(_, _, t0, _)| (t0, i)))
        .collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut acc = VolumeSample::default();
    for (_, i) in order {
        scene.volumes[i].integrate(ray, t_max, true, &mut acc);
        if acc.transmittance < 1.0 - crate::voxels::EARLY_TERMINATION {
            break;
        }
    }
    acc.color + surface * acc.transmittance
}
