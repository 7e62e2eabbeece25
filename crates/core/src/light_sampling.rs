//! Next-event estimation from a point of a scene: a light chosen from the scene's
//! [`Emitters`] table, then a point on it sampled by the primitive's own routine
//! ([`crate::Shape::sample_light`]) or a direction from the environment map, with the
//! densities that multiple importance sampling weighs (`docs/sampling.md`).

use crate::LightPoint;
use crate::emitters::{Chosen, Emitters, weight};
use crate::scene::Scene;
use glam::Vec3;

/// A sampled light direction from a reference point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the reference point to the light.
    pub wi: Vec3,
    /// Distance to the light point (infinite for the environment).
    pub dist: f32,
    /// Radiance arriving along `-wi`.
    pub radiance: Vec3,
    /// Solid-angle density, the choice of the light included.
    pub pdf: f32,
}

impl Emitters {
    /// The probability of choosing primitive `prim` (0 when it is not a light).
    fn probability(&self, scene: &Scene, prim: u32) -> f32 {
        if !self.contains(prim) {
            return 0.0;
        }
        let shape = scene.geometry.shape(prim);
        weight(shape, scene.material_of(prim).emission).map_or(0.0, |w| (w / self.total()) as f32)
    }

    /// A light direction from `origin` (a point already offset from its surface): a light
    /// chosen with `u_light`, a point or direction on it from `u_point`. `None` when the
    /// chosen light cannot be seen from `origin` by this technique (BSDF sampling then
    /// carries it alone) or emits nothing towards it.
    #[must_use]
    pub fn sample(
        &self,
        scene: &Scene,
        origin: Vec3,
        u_light: f32,
        u_point: (f32, f32),
    ) -> Option<LightSample> {
        let prim = match self.pick(u_light)? {
            Chosen::Environment => {
                let env = scene.environment.as_deref()?;
                let (wi, radiance, pdf) = env.sample(u_point.0, u_point.1)?;
                let choice = (self.environment / self.total()) as f32;
                return Some(LightSample {
                    wi,
                    dist: f32::INFINITY,
                    radiance,
                    pdf: pdf * choice,
                });
            }
            Chosen::Primitive(prim) => prim,
        };
        let choice = self.probability(scene, prim);
        let LightPoint {
            point: y,
            normal,
            uv: (u, v),
            pdf,
        } = scene.geometry.shape(prim).sample_light(origin, u_point)?;
        let to = y - origin;
        let dist = to.length();
        let wi = to / dist;
        // One-sided: the light's front faces the reference point.
        if !(normal.dot(wi) < 0.0 && dist > 0.0 && dist.is_finite()) {
            return None;
        }
        let pdf = pdf * choice;
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(LightSample {
            wi,
            dist,
            radiance: scene.emission_at(prim, u, v),
            pdf,
        })
    }

    /// The solid-angle density with which [`Emitters::sample`] from `origin` would have
    /// produced the hit of primitive `prim` at `p` with unit geometric normal `normal`
    /// (0 when it would not: not a light, or `origin` inside its cone's sphere).
    #[must_use]
    pub fn pdf_hit(&self, scene: &Scene, origin: Vec3, prim: u32, p: Vec3, normal: Vec3) -> f32 {
        let choice = self.probability(scene, prim);
        if choice <= 0.0 {
            return 0.0;
        }
        let pdf = scene.geometry.shape(prim).light_pdf(origin, p, normal);
        // A density that overflowed is one `sample` discards: BSDF sampling alone then.
        let pdf = pdf * choice;
        if pdf.is_finite() { pdf } else { 0.0 }
    }

    /// The solid-angle density with which [`Emitters::sample`] picks the environment along
    /// unit direction `dir`.
    #[must_use]
    pub fn pdf_environment(&self, scene: &Scene, dir: Vec3) -> f32 {
        match scene.environment.as_deref() {
            Some(env) if self.environment > 0.0 => {
                env.pdf(dir) * (self.environment / self.total()) as f32
            }
            _ => 0.0,
        }
    }
}
