//! Monte Carlo path tracing, bounce by bounce over a whole tile (wavefront).
//!
//! Estimator (documented in `docs/sampling.md`): cosine-weighted diffuse bounces; at every
//! diffuse hit, one shadow ray per point and directional light, and (with
//! [`LightSampling::Mis`]) next-event estimation towards one light chosen by power (an
//! emissive bounded primitive or the environment map, `crate::emitters`), combined with the
//! BSDF-sampled direction by Veach's power heuristic: the emission a path hits after a
//! diffuse bounce, or the environment it escapes to, is weighted by
//! `p_bsdf² / (p_bsdf² + p_light²)`, the light sample by `p_light² / (p_light² + p_bsdf²)`.
//! Camera rays and rays after specular bounces count what they hit fully. With
//! [`LightSampling::Bsdf`] only the delta lights are sampled and every emission counts on
//! hit. Perfect mirrors; dielectrics choose reflection or refraction with the Fresnel
//! probability. Russian roulette from the third bounce on, surviving with the probability
//! of the last scattering's largest albedo (clamped to `[0.05, 0.95]`). Emitters are
//! one-sided, as pbrt's diffuse area lights: they emit on the side their geometric normal
//! points to (counter-clockwise winding); the Cornell box's light faces down.

use super::tile::TileOutput;
use super::wavefront::{Segment, ShadowBatch, Surface, Wavefront};
use super::whitted::light_ray;
use crate::Ray;
use crate::material::MaterialKind;
use crate::optics::{cosine_hemisphere, fresnel_dielectric, offset_ray_origin, reflect, refract};
use crate::renderer::LightSampling;
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::{Accel, Counters};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Bounce from which Russian roulette may end paths.
pub const ROULETTE_DEPTH: u32 = 3;

/// Random dimensions used per bounce (see `docs/sampling.md`): bounce `b` draws from
/// dimensions `2 + 8 b ..`, in this order: light choice, point on the light or direction
/// of the environment (2), BSDF direction (2), reflect-or-refract choice, roulette.
pub const DIMENSIONS_PER_BOUNCE: u32 = 8;

/// A path in flight.
#[derive(Clone, Copy)]
struct PathState {
    segment: Segment,
    /// Whether the last scattering was specular (or this is the camera ray): what the ray
    /// hits then counts fully, as no light sample could have found it.
    specular: bool,
    /// After a diffuse scattering: the solid-angle density with which the ray's direction
    /// was sampled (for the MIS weight of the emission it hits).
    pdf_bsdf: f32,
    sampler: Sampler,
}

/// Shadow rays towards sampled light points stop this fraction short of the light, so
/// that the light's own surface does not occlude it.
pub const SHADOW_SHORTEN: f32 = 1.0 - 1.0 / 1024.0;

/// Veach's power heuristic (exponent 2) for one sample of each technique: the weight of
/// the technique with density `a` against the one with density `b`, written as
/// `1 / (1 + (b / a)²)` so that huge densities (tiny light cones) do not overflow.
#[inline]
#[must_use]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    if a <= 0.0 {
        return 0.0;
    }
    let r = b / a;
    1.0 / (1.0 + r * r)
}

/// Renders a tile by path tracing (the estimator of this module's documentation).
pub(super) fn path_tile<A: Accel, C: Counters>(
    scene: &Scene,
    mut st: Wavefront<A, C>,
) -> TileOutput<C> {
    let settings = st.settings;
    let sample_weight = Vec3::splat(1.0 / settings.spp as f32);
    let emitters = &scene.emitters;
    let mis = settings.light_sampling == LightSampling::Mis && !emitters.is_empty();

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
                pdf_bsdf: 0.0,
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
                // What the ray found counts fully unless a light sample at the previous
                // (diffuse) vertex could have found it too.
                let weighted = mis && !path.specular;
                let Some(hit) = hit else {
                    let mut w = 1.0;
                    if weighted && scene.environment.is_some() {
                        let d = seg.ray.dir.normalize();
                        w = power_heuristic(path.pdf_bsdf, emitters.pdf_environment(scene, d));
                    }
                    st.color[px] += seg.weight * w * scene.background_along(seg.ray.dir);
                    continue;
                };
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
                }) = st.surface(scene, &seg, Some(hit))
                else {
                    continue;
                };
                if front && emission.max_element() > 0.0 {
                    let mut w = 1.0;
                    if weighted {
                        let light = emitters.pdf_hit(scene, seg.ray.origin, prim, p, hit.normal);
                        w = power_heuristic(path.pdf_bsdf, light);
                    }
                    st.color[px] += seg.weight * w * emission;
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
                        let origin = offset_ray_origin(p, nf);
                        if mis && let Some(ls) = emitters.sample(scene, origin, u_light, u_point) {
                            // The shading normal's cosine; a light below the geometric surface does
                            // not light it.
                            let cos_x = ns.dot(ls.wi);
                            if cos_x > 0.0
                                && nf.dot(ls.wi) > 0.0
                                && ls.pdf > 0.0
                                && ls.pdf.is_finite()
                            {
                                let w = power_heuristic(ls.pdf, cos_x * FRAC_1_PI);
                                let value = weight * brdf * ls.radiance * (cos_x * w / ls.pdf);
                                let ray = if ls.dist.is_finite() {
                                    Ray::with_interval(origin, ls.wi * ls.dist, 0.0, SHADOW_SHORTEN)
                                } else {
                                    Ray::new(origin, ls.wi)
                                };
                                shadows.push(ray, px, value);
                            }
                        }
                        weight *= albedo;
                        path.specular = false;
                        let dir = cosine_hemisphere(ns, u_dir.0, u_dir.1);
                        path.pdf_bsdf = ns.dot(dir).max(0.0) * FRAC_1_PI;
                        (dir, nf)
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
