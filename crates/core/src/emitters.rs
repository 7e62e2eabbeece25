//! Every bounded emissive primitive and the environment map as lights, for next-event
//! estimation with multiple importance sampling (`docs/sampling.md`).
//!
//! A light is chosen with probability proportional to its power, up to the common factor
//! π: `area x luminance(emission)` for a primitive (the area of a triangle, of a sphere,
//! and of the bounding sphere for every other kind, whose true area is not known) and
//! `4π R² x mean luminance` for the environment (`R` the radius of the scene's bounding
//! sphere; pbrt-v4's `Phi` of an infinite light). Then a point or direction on it:
//!
//! - triangle: a uniform point by area (pdf `1 / area` per unit area);
//! - sphere: a uniform direction in the cone the sphere subtends (pbrt-v4's
//!   `Sphere::Sample(ctx)`), the point where it meets the sphere's near side; nothing from
//!   inside the sphere, which sees only the sphere's back;
//! - any other bounded kind (CSG, SDF, Bezier, height field): a uniform direction in the
//!   cone of the primitive's bounding sphere, and the first hit of that direction on the
//!   primitive itself, found by the primitive's own intersection routine (not the
//!   accelerator); pdf `1 / solid angle of the cone`, and nothing when the direction misses
//!   the primitive or the reference point lies inside the bounding sphere (BSDF sampling
//!   then carries the light alone, with MIS weight 1, so the estimator stays unbiased);
//! - environment: the map's piecewise-constant distribution ([`Environment::sample`]).
//!
//! Unbounded emitters (planes) are not lights: BSDF sampling alone finds them, and the
//! scene warns. Emitters are one-sided: they emit on the side their geometric normal
//! points to.

use crate::environment::{Environment, luminance};
use crate::material::Material;
use crate::optics::{basis, triangle_point, triangle_weights};
use crate::scene::Scene;
use crate::{Geometry, Ray, Shape, Sphere};
use glam::Vec3;
use std::collections::{HashMap, HashSet};
use std::f32::consts::TAU;

/// The lights that next-event estimation samples: emissive bounded primitives with a
/// cumulative power table, and the environment's share.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Emitters {
    /// Primitive ids of the emissive bounded primitives, ascending.
    pub ids: Vec<u32>,
    /// `cdf[i]` = total weight (area x luminance) of `ids[..=i]`, summed in f64 so that the
    /// choice probability of a small triangle among millions stays its weight over the
    /// total.
    pub cdf: Vec<f64>,
    /// The environment map's weight (0 without one), chosen after every primitive.
    pub environment: f64,
}

/// The light a uniform number chose.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Chosen {
    /// An emissive primitive.
    Primitive(u32),
    /// The environment map.
    Environment,
}

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

/// The cone of directions from a point towards a sphere outside it.
struct Cone {
    /// Unit direction to the centre.
    axis: Vec3,
    /// `sin² θmax`.
    sin2_max: f32,
    /// `1 - cos θmax`, computed as `sin² / (1 + cos)` (no cancellation for small cones).
    one_minus_cos: f32,
}

impl Cone {
    /// The cone from `origin` to the sphere (`center`, `radius`), `None` from inside it.
    fn towards(origin: Vec3, center: Vec3, radius: f32) -> Option<Self> {
        let to = center - origin;
        let d2 = to.length_squared();
        let r2 = radius * radius;
        if !(d2 > r2 && d2.is_finite()) {
            return None;
        }
        let sin2_max = r2 / d2;
        let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
        Some(Self {
            axis: to / d2.sqrt(),
            sin2_max,
            one_minus_cos: sin2_max / (1.0 + cos_max),
        })
    }

    /// Density per solid angle of a uniform direction in the cone.
    fn pdf(&self) -> f32 {
        1.0 / (TAU * self.one_minus_cos)
    }

    /// `(cos θ, sin² θ)` of a uniform direction in the cone, from `u`.
    fn theta(&self, u: f32) -> (f32, f32) {
        let one_minus = u * self.one_minus_cos;
        (1.0 - one_minus, one_minus * (2.0 - one_minus))
    }

    /// The unit vector at angle (`cos`, `sin`) from the axis and azimuth `phi`, with the
    /// axis flipped by `sign`.
    fn direction(&self, cos: f32, sin: f32, phi: f32, sign: f32) -> Vec3 {
        let (t, b) = basis(self.axis);
        (t * (sin * phi.cos()) + b * (sin * phi.sin()) + self.axis * (sign * cos)).normalize()
    }
}

/// The bounding sphere of a bounded primitive: its box's centre and half diagonal.
fn bounding_sphere(shape: &Shape) -> Option<(Vec3, f32)> {
    let b = shape.bounds()?;
    Some((b.center(), 0.5 * b.extent().length()))
}

/// The area used in the choice weight (see the module's documentation).
fn light_area(shape: &Shape) -> Option<f64> {
    let area = match shape {
        Shape::Triangle(t) => 0.5 * f64::from((t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).length()),
        Shape::Sphere(s) => 2.0 * std::f64::consts::TAU * f64::from(s.radius).powi(2),
        Shape::Plane(_) => return None,
        other => {
            let (_, r) = bounding_sphere(other)?;
            2.0 * std::f64::consts::TAU * f64::from(r).powi(2)
        }
    };
    (area > 0.0 && area.is_finite()).then_some(area)
}

/// The choice weight of a primitive with emission `emission`, if it is a light.
fn weight(shape: &Shape, emission: Vec3) -> Option<f64> {
    let lum = f64::from(luminance(emission));
    if lum <= 0.0 {
        return None;
    }
    Some(light_area(shape)? * lum)
}

/// A triangle's vertices as bits, sorted, so that coincident triangles share the key
/// whatever their winding and first vertex (`-0.0` counted as `0.0`).
fn triangle_key(v: &[Vec3; 3]) -> [[u32; 3]; 3] {
    let mut key = v.map(|p| (p + Vec3::ZERO).to_array().map(f32::to_bits));
    key.sort_unstable();
    key
}

/// The emissive triangles among `emissive` (ascending ids) that coincide with a triangle of
/// a smaller id: every ray that reaches them hits that one instead (equal `t`, the tie
/// rule), so light sampled on them would be light no path ever sees.
fn hidden_triangles(geometry: &Geometry, emissive: &[u32]) -> HashSet<u32> {
    let mut by_key: HashMap<[[u32; 3]; 3], Vec<u32>> = HashMap::new();
    for &id in emissive {
        if let Shape::Triangle(t) = geometry.shape(id) {
            by_key.entry(triangle_key(&t.v)).or_default().push(id);
        }
    }
    let mut hidden = HashSet::new();
    let Some(&last) = emissive.last() else {
        return hidden;
    };
    // The first triangle met in id order with an emitter's key is the one rays hit.
    for (id, shape) in geometry.shapes().iter().enumerate().take(last as usize + 1) {
        if by_key.is_empty() {
            break;
        }
        let Shape::Triangle(t) = shape else { continue };
        if let Some(emitters) = by_key.remove(&triangle_key(&t.v)) {
            hidden.extend(emitters.into_iter().filter(|&e| e > id as u32));
        }
    }
    hidden
}

/// What [`Emitters::new`] leaves out, for the scene's warnings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LeftOut {
    /// Emissive primitives without bounds (planes): found by BSDF sampling only.
    pub unbounded: usize,
    /// Emissive triangles that coincide with a triangle of a smaller id, which every ray
    /// hits instead: not lights.
    pub hidden: usize,
    /// The first of those hidden triangles.
    pub first_hidden: Option<u32>,
}

impl Emitters {
    /// Collects every bounded primitive with non-zero emission and positive area, and the
    /// environment map (weighted with the radius of `geometry`'s bounding sphere). Returns
    /// also what it leaves out: unbounded emitters, and emissive triangles hidden by a
    /// coincident triangle of a smaller id (the tie rule), which no ray ever sees.
    #[must_use]
    pub fn new(
        geometry: &Geometry,
        prim_material: &[u32],
        materials: &[Material],
        environment: Option<&Environment>,
    ) -> (Self, LeftOut) {
        let mut ids = Vec::new();
        let mut cdf = Vec::new();
        let mut total = 0.0f64;
        let mut left_out = LeftOut::default();
        let emissive: Vec<u32> = (0..geometry.len() as u32)
            .filter(|&id| {
                materials[prim_material[id as usize] as usize]
                    .emission
                    .max_element()
                    > 0.0
            })
            .collect();
        let hidden = hidden_triangles(geometry, &emissive);
        left_out.hidden = hidden.len();
        left_out.first_hidden = hidden.iter().min().copied();
        for &id in &emissive {
            let shape = geometry.shape(id);
            let m = &materials[prim_material[id as usize] as usize];
            if shape.bounds().is_none() {
                left_out.unbounded += 1;
                continue;
            }
            if hidden.contains(&id) {
                continue;
            }
            if let Some(w) = weight(shape, m.emission) {
                total += w;
                ids.push(id);
                cdf.push(total);
            }
        }
        let environment = environment.map_or(0.0, |e| {
            let b = geometry.bounds();
            let r = if b.is_empty() {
                1.0
            } else {
                f64::from(0.5 * b.extent().length()).max(1e-6)
            };
            2.0 * std::f64::consts::TAU * r * r * e.mean_luminance()
        });
        let environment = if environment.is_finite() {
            environment
        } else {
            0.0
        };
        (
            Self {
                ids,
                cdf,
                environment,
            },
            left_out,
        )
    }

    /// The emissive primitives' total weight (area x luminance), as the GPU reads it.
    #[must_use]
    pub fn total_weight(&self) -> f32 {
        self.cdf.last().copied().unwrap_or(0.0) as f32
    }

    /// The weight of every light, the environment included.
    fn total(&self) -> f64 {
        self.cdf.last().copied().unwrap_or(0.0) + self.environment
    }

    /// True when there is no light to sample.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.total() <= 0.0
    }

    /// Whether primitive `id` is sampled here.
    #[must_use]
    pub fn contains(&self, id: u32) -> bool {
        self.ids.binary_search(&id).is_ok()
    }

    /// The light chosen by `u` in `[0, 1)` with probability proportional to its weight.
    #[must_use]
    pub fn pick(&self, u: f32) -> Option<Chosen> {
        let total = self.total();
        if total <= 0.0 {
            return None;
        }
        let target = f64::from(u) * total;
        let i = self.cdf.partition_point(|&c| c <= target);
        match self.ids.get(i) {
            Some(&id) => Some(Chosen::Primitive(id)),
            None if self.environment > 0.0 => Some(Chosen::Environment),
            None => self.ids.last().map(|&id| Chosen::Primitive(id)),
        }
    }

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
        let shape = scene.geometry.shape(prim);
        let (y, normal, (u, v), pdf) = match shape {
            Shape::Triangle(tri) => {
                let [_, w1, w2] = triangle_weights(u_point.0, u_point.1);
                let y = triangle_point(tri.v[0], tri.v[1], tri.v[2], u_point.0, u_point.1);
                let to = y - origin;
                let d2 = to.length_squared();
                let cos_y = -tri.normal().dot(to) / d2.sqrt();
                if !(cos_y > 0.0 && d2 > 0.0) {
                    return None;
                }
                let area = light_area(shape)? as f32;
                (y, tri.normal(), (w1, w2), d2 / (cos_y * area))
            }
            Shape::Sphere(s) => {
                let cone = Cone::towards(origin, s.center, s.radius)?;
                let (cos, sin2) = cone.theta(u_point.0);
                // pbrt-v4: the angle alpha at the centre between the axis and the point.
                let sin_max = cone.sin2_max.sqrt();
                let cos_alpha = sin2 / sin_max + cos * (1.0 - sin2 / cone.sin2_max).max(0.0).sqrt();
                let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
                let n = cone.direction(cos_alpha, sin_alpha, TAU * u_point.1, -1.0);
                let y = s.center + n * s.radius;
                (y, n, Sphere::uv(n), cone.pdf())
            }
            Shape::Plane(_) => return None,
            other => {
                let (center, radius) = bounding_sphere(other)?;
                let cone = Cone::towards(origin, center, radius)?;
                let (cos, sin2) = cone.theta(u_point.0);
                let wi = cone.direction(cos, sin2.max(0.0).sqrt(), TAU * u_point.1, 1.0);
                let ray = Ray::new(origin, wi);
                let h = other.intersect(&ray)?;
                let hit = other.complete_hit(&ray, prim, h);
                (ray.at(h.t), hit.normal, (hit.u, hit.v), cone.pdf())
            }
        };
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
        let shape = scene.geometry.shape(prim);
        let pdf = match shape {
            Shape::Triangle(_) => {
                let to = p - origin;
                let d2 = to.length_squared();
                let cos_y = normal.dot(to).abs() / d2.sqrt();
                let Some(area) = light_area(shape) else {
                    return 0.0;
                };
                if cos_y.is_nan() || cos_y <= 0.0 {
                    return 0.0;
                }
                d2 / (cos_y * area as f32)
            }
            Shape::Sphere(s) => Cone::towards(origin, s.center, s.radius).map_or(0.0, |c| c.pdf()),
            Shape::Plane(_) => 0.0,
            other => bounding_sphere(other)
                .and_then(|(c, r)| Cone::towards(origin, c, r))
                .map_or(0.0, |c| c.pdf()),
        };
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Triangle;

    /// An emissive triangle coinciding with one of a smaller id (whatever its winding or
    /// first vertex) is never hit, so it is no light; the visible one stays.
    #[test]
    fn coincident_emitters_behind_a_smaller_id_are_not_lights() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let far = Vec3::Z * 5.0;
        let shapes = vec![
            Shape::Triangle(Triangle::new(a, b, c)),
            Shape::Triangle(Triangle::new(a + far, b + far, c + far)),
            Shape::Triangle(Triangle::new(c, b, a)),
            Shape::Triangle(Triangle::new(b + far, c + far, a + far)),
            Shape::Triangle(Triangle::new(-b, c, a)),
        ];
        let geometry = Geometry::new(shapes);
        let lamp = Material {
            emission: Vec3::ONE,
            ..Material::default()
        };
        // Triangle 0 is not emissive and hides 2; 1 is emissive and hides 3; 4 is alone.
        let materials = [Material::default(), lamp];
        let (e, left) = Emitters::new(&geometry, &[0, 1, 1, 1, 1], &materials, None);
        assert_eq!(e.ids, vec![1, 4]);
        assert_eq!((left.hidden, left.first_hidden), (2, Some(2)));
    }

    /// The cone's pdf integrates to one over the cone, and its directions stay inside it.
    #[test]
    fn cone_directions_stay_inside() {
        for &(d, r) in &[(10.0f32, 1.0f32), (1000.0, 0.01), (1.5, 1.0)] {
            let cone = Cone::towards(Vec3::ZERO, Vec3::new(0.0, 0.0, d), r).unwrap();
            let cos_max = 1.0 - cone.one_minus_cos;
            for k in 0..50 {
                let (cos, sin2) = cone.theta(k as f32 / 50.0);
                assert!(cos >= cos_max - 1e-6 && (cos * cos + sin2 - 1.0).abs() < 1e-5);
                let w = cone.direction(cos, sin2.sqrt(), 1.0, 1.0);
                assert!((w.z - cos).abs() < 1e-5);
            }
            let s2 = (f64::from(r) / f64::from(d)).powi(2);
            let exact = std::f64::consts::TAU * s2 / (1.0 + (1.0 - s2).sqrt());
            assert!((f64::from(1.0 / cone.pdf()) - exact).abs() <= 1e-5 * exact);
        }
        assert!(Cone::towards(Vec3::ZERO, Vec3::X * 0.5, 1.0).is_none());
    }
}
