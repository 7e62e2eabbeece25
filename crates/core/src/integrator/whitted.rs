//! Whitted ray tracing, bounce by bounce over a whole tile (wavefront): every bounce's rays,
//! and then its shadow rays, go through the accelerator's batch entry points.

use super::{Tile, TileOutput, TileState, add_unshadowed, tile_pixels};
use crate::Hit;
use crate::Ray;
use crate::camera::CameraRays;
use crate::material::{Light, MaterialKind};
use crate::optics::{fresnel_dielectric, offset_ray_origin, reflect, refract};
use crate::renderer::RenderSettings;
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::{Accel, Counters};
use glam::Vec3;

/// Ambient term of diffuse surfaces, as a fraction of their colour (Whitted's `k_a`).
pub const AMBIENT: f32 = 0.05;

/// A ray in flight and what its radiance is worth to its pixel.
#[derive(Clone, Copy)]
pub(super) struct Segment {
    /// Index of the pixel in the tile.
    pub pixel: u32,
    /// Product of the weights along the way.
    pub weight: Vec3,
    /// The ray.
    pub ray: Ray,
}

/// The shading frame of a hit: point, unit normal facing the incoming ray, and whether the
/// ray arrived on the side the geometric normal points to.
#[inline]
pub(super) fn shading_frame(ray: &Ray, hit: &Hit) -> (Vec3, Vec3, bool) {
    let p = ray.at(hit.t);
    let front = hit.normal.dot(ray.dir) < 0.0;
    (p, if front { hit.normal } else { -hit.normal }, front)
}

/// A shadow ray from `p` (normal `n`) towards light `light`, and the unshadowed light it
/// would bring (irradiance, unit direction), or `None` when the light is behind the surface.
#[inline]
pub(super) fn light_ray(light: &Light, p: Vec3, n: Vec3) -> Option<(Ray, Vec3, Vec3)> {
    let origin = offset_ray_origin(p, n);
    match *light {
        Light::Point {
            position,
            intensity,
        } => {
            let to = position - p;
            let dist2 = to.length_squared();
            let dir = to / dist2.sqrt();
            let cos = n.dot(dir);
            if !(cos > 0.0 && dist2 > 0.0) {
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
            let cos = n.dot(dir);
            if cos <= 0.0 {
                return None;
            }
            Some((Ray::new(origin, dir), radiance * cos, dir))
        }
    }
}

pub(super) fn whitted_tile<A: Accel, C: Counters>(
    scene: &Scene,
    accel: &A,
    camera: &CameraRays,
    settings: &RenderSettings,
    tile: Tile,
) -> TileOutput<C> {
    let mut st = TileState::<C>::new(accel, camera, tile);
    let sample_weight = Vec3::splat(1.0 / settings.spp as f32);

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
            tile_pixels(tile, settings.width)
                .enumerate()
                .map(|(i, (x, y, pixel))| {
                    let (jx, jy) = Sampler::new(pixel, s, settings.seed).next_2d();
                    Segment {
                        pixel: i as u32,
                        weight: sample_weight,
                        ray: camera.ray(x as f32 + jx, y as f32 + jy),
                    }
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
                let mut hits = vec![None; rays.len()];
                accel.intersect_batch(&rays, &mut hits, &mut st.counters);
                st.traced += rays.len() as u64;
                hits
            };
            let mut next = Vec::new();
            let mut shadow_rays = Vec::new();
            let mut shadow_light = Vec::new();
            for (seg, hit) in segments.iter().zip(&hits) {
                let px = seg.pixel as usize;
                let Some(hit) = hit else {
                    st.color[px] += seg.weight * scene.background;
                    continue;
                };
                let m = scene.material_of(hit.prim);
                let (p, nf, front) = shading_frame(&seg.ray, hit);
                let d = seg.ray.dir.normalize();
                if front {
                    st.color[px] += seg.weight * m.emission;
                }
                match m.kind {
                    MaterialKind::Diffuse => {
                        let albedo = m.albedo_at(p);
                        st.color[px] += seg.weight * albedo * AMBIENT;
                        for light in &scene.lights {
                            let Some((ray, irradiance, wi)) = light_ray(light, p, nf) else {
                                continue;
                            };
                            // Lambert plus a Blinn-Phong highlight.
                            let h = (wi - d).normalize_or_zero();
                            let spec = m.specular * nf.dot(h).max(0.0).powf(m.shininess);
                            shadow_rays.push(ray);
                            shadow_light.push((px, seg.weight * irradiance * (albedo + spec)));
                        }
                    }
                    MaterialKind::Mirror if depth < settings.max_depth => {
                        next.push(Segment {
                            pixel: seg.pixel,
                            weight: seg.weight * m.specular,
                            ray: Ray::new(offset_ray_origin(p, nf), reflect(d, nf)),
                        });
                    }
                    MaterialKind::Glass if depth < settings.max_depth => {
                        // Entering when the ray meets the side the normal points to.
                        let (n1, n2) = if front { (1.0, m.ior) } else { (m.ior, 1.0) };
                        let fr = fresnel_dielectric(-d.dot(nf), n1, n2);
                        next.push(Segment {
                            pixel: seg.pixel,
                            weight: seg.weight * m.specular * fr,
                            ray: Ray::new(offset_ray_origin(p, nf), reflect(d, nf)),
                        });
                        if let Some(t) = refract(d, nf, n1, n2) {
                            next.push(Segment {
                                pixel: seg.pixel,
                                weight: seg.weight * m.specular * (1.0 - fr),
                                ray: Ray::new(offset_ray_origin(p, -nf), t),
                            });
                        }
                    }
                    MaterialKind::Mirror | MaterialKind::Glass => {}
                }
            }
            st.traced += add_unshadowed(
                accel,
                &shadow_rays,
                &shadow_light,
                &mut st.color,
                &mut st.counters,
            );
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
