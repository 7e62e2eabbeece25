//! Ray casting: camera rays only, with a simple shading that measures visibility (and the
//! frame of the volume modes, which shade the same camera rays).

use super::tile::TileOutput;
use super::wavefront::{self, Wavefront};
use crate::Accel;
use crate::Counters;
use crate::Hit;
use crate::Ray;
use crate::material::{Light, MaterialKind};
use crate::scene::Scene;
use glam::Vec3;

/// Direction light travels in ray-casting mode: the scene's first directional light, else a
/// fixed light from above-front-right.
#[must_use]
pub fn cast_light(scene: &Scene) -> Vec3 {
    scene
        .lights
        .iter()
        .find_map(|l| match *l {
            Light::Directional { direction, .. } => Some(direction),
            Light::Point { .. } => None,
        })
        .unwrap_or_else(|| Vec3::new(-0.4, -1.0, -0.6).normalize())
}

/// Ray-casting shading: the base colour (textures applied, no checkerboard) times a mix of
/// `|cos|` to the viewer and a directional light (no shadows), with the shading normal,
/// plus emission.
/// Deliberately simple: this mode measures visibility.
#[inline]
#[must_use]
pub fn shade_cast(scene: &Scene, light_dir: Vec3, ray: &Ray, hit: Option<&Hit>) -> Vec3 {
    let Some(hit) = hit else {
        return scene.background_along(ray.dir);
    };
    let m = scene.material_of(hit.prim);
    let d = ray.dir.normalize_or_zero();
    let shading = scene.shading(hit, ray.at(hit.t));
    // Both normals face the viewer.
    let (_, n, _) = wavefront::facing(hit.normal, shading.normal, d);
    let cos_view = -n.dot(d);
    let diffuse = n.dot(-light_dir).max(0.0);
    let albedo = match m.kind {
        MaterialKind::Diffuse => shading.base_color,
        MaterialKind::Mirror => m.specular.max(Vec3::splat(0.2)),
        MaterialKind::Glass => Vec3::new(0.75, 0.85, 0.9),
    };
    albedo * (0.35 * cos_view.abs() + 0.65 * diffuse) + shading.emission
}

/// Camera rays only, shaded by `shade` (ray casting, and the volume modes, which integrate
/// the volumes along the camera ray up to its surface hit).
pub(super) fn cast_tile<A: Accel, C: Counters>(
    scene: &Scene,
    mut st: Wavefront<A, C>,
    shade: impl Fn(&Scene, Vec3, &Ray, Option<&Hit>) -> Vec3,
) -> TileOutput<C> {
    let light_dir = cast_light(scene);
    let spp = st.settings.spp;
    if spp <= 1 {
        for ((c, r), h) in st
            .color
            .iter_mut()
            .zip(&st.centre_rays)
            .zip(&st.centre_hits)
        {
            *c = shade(scene, light_dir, r, h.as_ref());
        }
    } else {
        // Jittered samples for colour; ids and t stay those of the centre ray.
        for s in 0..spp {
            let rays: Vec<Ray> = st.camera_rays(s).map(|(_, ray, _)| ray).collect();
            let hits = st.trace(&rays);
            for ((acc, r), h) in st.color.iter_mut().zip(&rays).zip(&hits) {
                *acc += shade(scene, light_dir, r, h.as_ref());
            }
        }
        let inv = 1.0 / spp as f32;
        for c in &mut st.color {
            *c *= inv;
        }
    }
    st.finish()
}
