//! Monte Carlo path tracing, bounce by bounce over a whole tile (wavefront).
//!
//! Estimator (documented in `docs/sampling.md`): cosine-weighted diffuse bounces; next-event
//! estimation at diffuse hits towards every point and directional light and towards one
//! emissive triangle picked by area (no multiple importance sampling); the emission of
//! triangles that next-event estimation samples is therefore counted only on camera rays and
//! after specular bounces, while other emitters (spheres, the environment) are counted on
//! every hit. Perfect mirrors; dielectrics choose reflection or refraction with the Fresnel
//! probability. Russian roulette from the third bounce on, surviving with the probability
//! of the last scattering's largest albedo (clamped to `[0.05, 0.95]`). Emitters are
//! one-sided, as pbrt's diffuse area lights: they emit on the side their geometric normal
//! points to (counter-clockwise winding); the Cornell box's light faces down.

use super::TileOutput;
use super::wavefront::{Segment, ShadowBatch, Surface, Wavefront};
use super::whitted::light_ray;
use crate::Ray;
use crate::Shape;
use crate::material::MaterialKind;
use crate::optics::{
    cosine_hemisphere, fresnel_dielectric, offset_ray_origin, reflect, refract, triangle_point,
};
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::{Accel, Counters};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Bounce from which Russian roulette may end paths.
pub const ROULETTE_DEPTH: u32 = 3;

/// Random dimensions used per bounce (see `docs/sampling.md`): bounce `b` draws from
/// dimensions `2 + 8 b ..`, in this order: emitter choice, emitter point (2), direction (2),
/// reflect-or-refract choice, roulette.
pub const DIMENSIONS_PER_BOUNCE: u32 = 8;

/// A path in flight.
#[derive(Clone, Copy)]
struct PathState {
    segment: Segment,
    /// Whether the last scattering was specular (or this is the camera ray): emission of
    /// sampled emitters is then counted on hit.
    specular: bool,
    sampler: Sampler,
}

/// Shadow rays towards emissive triangles stop this fraction short of the light, so that
/// the light's own triangle does not occlude it.
pub const SHADOW_SHORTEN: f32 = 1.0 - 1.0 / 1024.0;

/// Renders a tile by path tracing (the estimator of this module's documentation).
pub(super) fn path_tile<A: Accel, C: Counters>(
    scene: &Scene,
    mut st: Wavefront<A, C>,
) -> TileOutput<C> {
    let settings = st.settings;
    let sample_weight = Vec3::splat(1.0 / settings.spp as f32);
    let emitters = &scene.emitters;
    let emitter_area = emitters.total_area();

    for s in 0..settings.spp {
        let mut paths: Vec<PathState> = st
            .camera_rays(s)
            .map(|(pixel, ray, sampler)| PathState {
                segment: Segment {
                    pixel,
                    weight: sample_weight,
                    ray,
                },
                specular: true,
                sampler,
            })
            .collect();
        for depth in 0..=settings.max_depth {
            if paths.is_empty() {
                break;
            }
            let rays: Vec<Ray> = paths.iter().map(|p| p.segment.ray).collect();
            let hits = st.trace(&rays);

            let mut next = Vec::with_capacity(paths.len());
            let mut shadows = ShadowBatch::default();
            for (path, hit) in paths.iter_mut().zip(&hits) {
                let seg = path.segment;
                let px = seg.pixel as usize;
                let Some(Surface {
                    prim,
                    m,
                    p,
                    nf,
                    ns,
                    albedo,
                    emission,
                    front,
                    d,
                }) = st.surface(scene, &seg, hit.as_ref())
                else {
                    continue;
                };
                if front && (path.specular || !emitters.contains(prim)) {
                    st.color[px] += seg.weight * emission;
                }
                if depth == settings.max_depth {
                    continue;
                }
                path.sampler
                    .set_dimension(2 + depth * DIMENSIONS_PER_BOUNCE);
                let u_light = path.sampler.next_f32();
                let u_point = path.sampler.next_2d();
                let u_dir = path.sampler.next_2d();
                let u_choice = path.sampler.next_f32();
                let u_roulette = path.sampler.next_f32();

                let mut weight = seg.weight;
                let (dir, side) = match m.kind {
                    MaterialKind::Diffuse => {
                        let brdf = albedo * FRAC_1_PI;
                        for light in &scene.lights {
                            if let Some((ray, irradiance, _)) = light_ray(light, p, nf, ns) {
                                shadows.push(ray, px, weight * brdf * irradiance);
                            }
                        }
                        if let Some(id) = emitters.pick(u_light)
                            && let Shape::Triangle(tri) = scene.geometry.shape(id)
                        {
                            let y =
                                triangle_point(tri.v[0], tri.v[1], tri.v[2], u_point.0, u_point.1);
                            let origin = offset_ray_origin(p, nf);
                            let to = y - origin;
                            let dist2 = to.length_squared();
                            let wi = to / dist2.sqrt();
                            let cos_x = ns.dot(wi);
                            // One-sided: the light's front faces the shading point.
                            let cos_y = -tri.normal().dot(wi);
                            if cos_x > 0.0 && cos_y > 0.0 && dist2 > 0.0 && nf.dot(wi) > 0.0 {
                                // The point's barycentric weights of vertices 1 and 2.
                                let s = u_point.0.sqrt();
                                let le = scene.emission_at(id, u_point.1 * s, s - u_point.1 * s);
                                // pdf = 1 / area per unit area; geometry term cos cos / d^2.
                                let value =
                                    weight * brdf * le * (cos_x * cos_y / dist2 * emitter_area);
                                let ray = Ray::with_interval(origin, to, 0.0, SHADOW_SHORTEN);
                                shadows.push(ray, px, value);
                            }
                        }
                        weight *= albedo;
                        path.specular = false;
                        (cosine_hemisphere(ns, u_dir.0, u_dir.1), nf)
                    }
                    MaterialKind::Mirror => {
                        weight *= m.specular;
                        path.specular = true;
                        (reflect(d, ns), nf)
                    }
                    MaterialKind::Glass => {
                        let (n1, n2) = if front { (1.0, m.ior) } else { (m.ior, 1.0) };
                        let fr = fresnel_dielectric(-d.dot(ns), n1, n2);
                        weight *= m.specular;
                        path.specular = true;
                        match refract(d, ns, n1, n2) {
                            Some(t) if u_choice >= fr => (t, -nf),
                            _ => (reflect(d, ns), nf),
                        }
                    }
                };
                // A direction the shading normal sent below the geometric surface on the
                // side it leaves from ends the path (pbrt's rule).
                if dir.dot(side) < 0.0 {
                    continue;
                }
                let ray = Ray::new(offset_ray_origin(p, side), dir);
                if depth >= ROULETTE_DEPTH {
                    let q = weight.max_element() / seg.weight.max_element().max(f32::MIN_POSITIVE);
                    let q = q.clamp(0.05, 0.95);
                    if u_roulette >= q {
                        continue;
                    }
                    weight /= q;
                }
                if weight.max_element() <= 0.0 {
                    continue;
                }
                next.push(PathState {
                    segment: Segment {
                        pixel: seg.pixel,
                        weight,
                        ray,
                    },
                    ..*path
                });
            }
            st.add_unshadowed(&shadows);
            paths = next;
        }
    }
    st.finish()
}
