//! Whitted ray tracing, bounce by bounce over a whole tile (wavefront): every bounce's rays,
//! and then its shadow rays, go through the accelerator's batch entry points.

use super::tile::TileOutput;
use super::wavefront::{Segment, ShadowBatch, Surface, Wavefront};
use crate::Ray;
use crate::material::{Light, MaterialKind};
use crate::optics::{fresnel_dielectric, offset_ray_origin, reflect, refract};
use crate::scene::Scene;
use crate::{Accel, Counters};
use glam::Vec3;

/// Ambient term of diffuse surfaces, as a fraction of their colour (Whitted's `k_a`).
pub const AMBIENT: f32 = 0.05;

/// A shadow ray from `p` towards light `light`, and the unshadowed light it would bring
/// (irradiance on the shading normal `ns`, unit direction), or `None` when the light is
/// behind the surface: below the shading normal's hemisphere or below the geometric
/// surface (normal `nf`, which also offsets the ray's origin), both facing the viewer.
#[inline]
pub(super) fn light_ray(light: &Light, p: Vec3, nf: Vec3, ns: Vec3) -> Option<(Ray, Vec3, Vec3)> {
    let origin = offset_ray_origin(p, nf);
    match *light {
        Light::Point {
            position,
            intensity,
        } => {
            let to = position - p;
            let dist2 = to.length_squared();
            let dir = to / dist2.sqrt();
            let cos = ns.dot(dir);
            if !(cos > 0.0 && dist2 > 0.0 && nf.dot(dir) > 0.0) {
                return None;
            }
            // Parametrised from the offset origin to the light: blockers at t in [0, 1).
            let ray = Ray::with_interval(origin, position - origin, 0.0, 1.0);
            Some((ray, intensity * (cos / dist2), dir))
        }
        Light::Directional {
            direction,
            radiance,
        } => {
            let dir = -direction;
            let cos = ns.dot(dir);
            if !(cos > 0.0 && nf.dot(dir) > 0.0) {
                return None;
            }
            Some((Ray::new(origin, dir), radiance * cos, dir))
        }
    }
}

/// What a message says of a scene Whitted ray tracing lights by its [`headlight`] (after the
/// scene's name).
pub const HEADLIGHT_NOTE: &str = "has no point or directional light, and Whitted ray tracing \
    sees no area lights: it is lit by a headlight along the view direction";

/// The light Whitted ray tracing uses in a scene without point or directional lights (it
/// sees no area lights: emissive surfaces show only their own glow): a headlight, a
/// directional light of radiance 1 travelling along the camera's view direction `forward`,
/// so that everything the camera sees is lit.
#[must_use]
pub fn headlight(forward: Vec3) -> Light {
    Light::Directional {
        direction: forward,
        radiance: Vec3::ONE,
    }
}

/// Renders a tile by Whitted ray tracing: `max_depth` bounces of mirror and glass rays,
/// direct light with shadow rays at diffuse hits (from the scene's point and directional
/// lights, or its [`headlight`] where it has none).
pub(super) fn whitted_tile<A: Accel, C: Counters>(
    scene: &Scene,
    mut st: Wavefront<A, C>,
) -> TileOutput<C> {
    let settings = st.settings;
    let sample_weight = Vec3::splat(1.0 / settings.spp as f32);
    let fallback = [headlight(st.camera.forward)];
    let lights: &[Light] = if scene.lights.is_empty() {
        &fallback
    } else {
        &scene.lights
    };

    for s in 0..settings.spp {
        // One sample: the centre rays (already traced); several: jittered rays.
        let mut segments: Vec<Segment> = if settings.spp == 1 {
            st.centre_rays
                .iter()
                .enumerate()
                .map(|(i, &ray)| Segment {
                    pixel: i as u32,
                    weight: sample_weight,
                    ray,
                })
                .collect()
        } else {
            st.camera_rays(s)
                .map(|(pixel, ray, _)| Segment {
                    pixel,
                    weight: sample_weight,
                    ray,
                })
                .collect()
        };
        for depth in 0..=settings.max_depth {
            if segments.is_empty() {
                break;
            }
            let hits = if depth == 0 && settings.spp == 1 {
                st.centre_hits.clone()
            } else {
                let rays: Vec<Ray> = segments.iter().map(|s| s.ray).collect();
                st.trace(&rays)
            };
            let mut next = Vec::new();
            let mut shadows = ShadowBatch::default();
            for (seg, hit) in segments.iter().zip(&hits) {
                let px = seg.pixel as usize;
                let Some(Surface {
                    m,
                    p,
                    nf,
                    ns,
                    albedo,
                    emission,
                    front,
                    d,
                    ..
                }) = st.surface(scene, seg, hit.as_ref())
                else {
                    continue;
                };
                if front {
                    st.color[px] += seg.weight * emission;
                }
                // Mirror and glass rays bent by the shading normal below the geometric
                // surface on their side are dropped (pbrt's rule): they would start inside.
                let mut bounce = |weight: Vec3, dir: Vec3, side: Vec3| {
                    if dir.dot(side) < 0.0 {
                        return;
                    }
                    next.push(Segment {
                        pixel: seg.pixel,
                        weight,
                        ray: Ray::new(offset_ray_origin(p, side), dir),
                    });
                };
                match m.kind {
                    MaterialKind::Diffuse => {
                        st.color[px] += seg.weight * albedo * AMBIENT;
                        for light in lights {
                            let Some((ray, irradiance, wi)) = light_ray(light, p, nf, ns) else {
                                continue;
                            };
                            // Lambert plus a Blinn-Phong highlight.
                            let h = (wi - d).normalize_or_zero();
                            let spec = m.specular * ns.dot(h).max(0.0).powf(m.shininess);
                            shadows.push(ray, px, seg.weight * irradiance * (albedo + spec));
                        }
                    }
                    MaterialKind::Mirror if depth < settings.max_depth => {
                        bounce(seg.weight * m.specular, reflect(d, ns), nf);
                    }
                    MaterialKind::Glass if depth < settings.max_depth => {
                        // Entering when the ray meets the side the normal points to.
                        let (n1, n2) = if front { (1.0, m.ior) } else { (m.ior, 1.0) };
                        let fr = fresnel_dielectric(-d.dot(ns), n1, n2);
                        bounce(seg.weight * m.specular * fr, reflect(d, ns), nf);
                        if let Some(t) = refract(d, ns, n1, n2) {
                            bounce(seg.weight * m.specular * (1.0 - fr), t, -nf);
                        }
                    }
                    MaterialKind::Mirror | MaterialKind::Glass => {}
                }
            }
            st.add_unshadowed(&shadows);
            // Drop contributions too small to matter (keeps glass-in-glass from doubling
            // the ray count every bounce for nothing); relative to one sample's weight, so
            // the cut does not depend on the sample count.
            let cut = 1e-4 * sample_weight.x;
            next.retain(|s| s.weight.max_element() > cut);
            segments = next;
        }
    }
    st.finish()
}
