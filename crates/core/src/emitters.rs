//! The table of lights that next-event estimation chooses from (`docs/sampling.md`): every
//! bounded emissive primitive and the environment map.
//!
//! A light is chosen with probability proportional to its power, up to the common factor
//! π: `area x luminance(emission)` for a primitive ([`Shape::light_area`]: the area of a
//! triangle, of a sphere, and of the bounding sphere for every other kind, whose true area
//! is not known) and `4π R² x mean luminance` for the environment (`R` the radius of the
//! scene's bounding sphere; pbrt-v4's `Phi` of an infinite light). How a point is then
//! sampled on a primitive is the primitive's own ([`Shape::sample_light`]); the environment
//! samples its map's piecewise-constant distribution ([`Environment::sample`]). The
//! sampling from a point of a scene is `light_sampling.rs`.
//!
//! Unbounded emitters (planes) are not lights: BSDF sampling alone finds them, and the
//! scene warns. Emitters are one-sided: they emit on the side their geometric normal
//! points to.

use crate::environment::{Environment, luminance};
use crate::material::Material;
use crate::{Geometry, Shape};
use glam::Vec3;
use std::collections::{HashMap, HashSet};

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

/// The choice weight of a primitive with emission `emission`, if it is a light.
pub(crate) fn weight(shape: &Shape, emission: Vec3) -> Option<f64> {
    let lum = f64::from(luminance(emission));
    if lum <= 0.0 {
        return None;
    }
    Some(shape.light_area()? * lum)
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
    pub(crate) fn total(&self) -> f64 {
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
}
