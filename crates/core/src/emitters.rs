//! Emissive triangles as area lights, sampled by area for next-event estimation.

use crate::material::Material;
use crate::{Geometry, Shape};

/// The emissive triangles of a scene with a cumulative area table.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Emitters {
    /// Primitive ids of emissive triangles, ascending.
    pub ids: Vec<u32>,
    /// `cdf[i]` = total area of `ids[..=i]`, summed in f64 so that the picking probability
    /// of a small triangle among millions stays its area over the total.
    pub cdf: Vec<f64>,
}

impl Emitters {
    /// Collects every triangle with non-zero emission and positive area.
    #[must_use]
    pub fn new(geometry: &Geometry, prim_material: &[u32], materials: &[Material]) -> Self {
        let mut ids = Vec::new();
        let mut cdf = Vec::new();
        let mut total = 0.0f64;
        for (id, shape) in geometry.shapes().iter().enumerate() {
            let Shape::Triangle(t) = shape else { continue };
            let m = &materials[prim_material[id] as usize];
            if m.emission.max_element() <= 0.0 {
                continue;
            }
            let area = 0.5 * (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).length();
            if area > 0.0 && area.is_finite() {
                total += f64::from(area);
                ids.push(id as u32);
                cdf.push(total);
            }
        }
        Self { ids, cdf }
    }

    /// Total emitting area.
    #[must_use]
    pub fn total_area(&self) -> f32 {
        self.cdf.last().copied().unwrap_or(0.0) as f32
    }

    /// True when there is no area light.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// Whether primitive `id` is sampled here (its emission then reaches diffuse surfaces
    /// through next-event estimation, not through hits after diffuse bounces).
    #[must_use]
    pub fn contains(&self, id: u32) -> bool {
        self.ids.binary_search(&id).is_ok()
    }

    /// The emitter chosen by `u` in `[0, 1)` with probability proportional to its area.
    #[must_use]
    pub fn pick(&self, u: f32) -> Option<u32> {
        let target = f64::from(u) * self.cdf.last().copied().unwrap_or(0.0);
        let i = self.cdf.partition_point(|&c| c <= target);
        self.ids
            .get(i.min(self.ids.len().saturating_sub(1)))
            .copied()
    }
}
