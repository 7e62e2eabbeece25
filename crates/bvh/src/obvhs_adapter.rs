//! The `obvhs` backend: PLOC-built, reinsertion-optimised CWBVH8 with obvhs's own traversal,
//! made to obey raybench's equivalence contract.
//!
//! obvhs's node test is fast rather than conservative in three ways, each handled here:
//!
//! 1. **Rounding.** It evaluates slab distances as `q * (extent / d) + (p - o) / d` from
//!    quantised child boxes, with an absolute error of a few ulps of `|p - o| / |d|`. The
//!    primitive boxes given to the builder are therefore padded by `PAD_RELATIVE` of the
//!    scene's size (and at least `PAD_ABSOLUTE`), far more than that error for rays starting
//!    within a few scene diameters of the scene.
//! 2. **Entry clamp.** It clamps entry distances to at least `f32::EPSILON`, so a node whose
//!    box the ray leaves before `t = 1.2e-7` is skipped. With the padding, a ray that hits a
//!    primitive stays inside its padded box for at least `pad / |d|` beyond the hit, which
//!    exceeds the clamp for unit-length directions in scenes larger than about 0.01.
//! 3. **Direction inverse.** `obvhs::ray::Ray::new` replaces components below `f32::EPSILON`
//!    by `+-1/EPSILON`, which shrinks slab intervals; this adapter fills the ray itself with
//!    the true inverse, clamped to `+-1e30` (finite, so no `0 * inf`).
//!
//! The closure obvhs calls for each candidate applies raybench's tie rule and returns
//! [`cull_bound`] of the best `t`, so obvhs's own early exit gets the contract's slack.
//! Rays that are not finite skip obvhs and test every primitive, as naive does.
//!
//! Remaining limitation (documented in the README): rays with very long unnormalised
//! directions, or starting on a surface in a scene smaller than about 0.01, may lose a hit
//! closer than `f32::EPSILON` to their origin to the entry clamp.

use glam::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::RayHit;
use raybench_core::{Accel, AccelStats, Counters, Geometry, Hit, PrimHit, Ray, cull_bound};
use std::sync::Arc;
use std::time::Duration;

/// Box padding relative to the scene's largest extent or coordinate magnitude.
const PAD_RELATIVE: f32 = 1.0 / 65_536.0;
/// Smallest box padding.
const PAD_ABSOLUTE: f32 = 1.0e-6;
/// Largest magnitude of an inverse direction component handed to obvhs.
const INV_LIMIT: f32 = 1.0e30;

/// obvhs's CWBVH over the bounded primitives; unbounded ones in a side list.
pub struct ObvhsAccel {
    geometry: Arc<Geometry>,
    bvh: CwBvh,
    /// `bounded[bvh.primitive_indices[i]]` is the primitive id of obvhs's index `i`.
    ids: Vec<u32>,
    pad: f32,
}

impl std::fmt::Debug for ObvhsAccel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ObvhsAccel")
            .field("nodes", &self.bvh.nodes.len())
            .field("pad", &self.pad)
            .finish_non_exhaustive()
    }
}

impl ObvhsAccel {
    /// Builds with obvhs's `medium_build` preset (PLOC, reinsertion, up to 3 primitives
    /// per leaf).
    #[must_use]
    pub fn build_with(geometry: Arc<Geometry>, params: BvhBuildParams) -> Self {
        let bounds = geometry.bounds();
        let scale = if bounds.is_empty() {
            0.0
        } else {
            bounds
                .extent()
                .max_element()
                .max(bounds.min.abs().max_element())
                .max(bounds.max.abs().max_element())
        };
        let pad = (scale * PAD_RELATIVE).max(PAD_ABSOLUTE);
        let boxes: Vec<obvhs::aabb::Aabb> = geometry
            .bounded()
            .iter()
            .map(|&id| {
                let b = geometry.shape(id).bounds().unwrap_or_default();
                obvhs::aabb::Aabb {
                    min: Vec3A::from(b.min) - pad,
                    max: Vec3A::from(b.max) + pad,
                }
            })
            .collect();
        let bvh = if boxes.is_empty() {
            CwBvh::default()
        } else {
            obvhs::cwbvh::builder::build_cwbvh(&boxes, params, &mut Duration::default())
        };
        let ids = bvh
            .primitive_indices
            .iter()
            .map(|&i| geometry.bounded()[i as usize])
            .collect();
        Self {
            geometry,
            bvh,
            ids,
            pad,
        }
    }

    /// The ray as obvhs sees it: same origin and direction, inverse clamped to be finite.
    fn obvhs_ray(ray: &Ray) -> obvhs::ray::Ray {
        let inv = ray
            .inv_dir
            .clamp(glam::Vec3::splat(-INV_LIMIT), glam::Vec3::splat(INV_LIMIT));
        obvhs::ray::Ray {
            origin: Vec3A::from(ray.origin),
            direction: Vec3A::from(ray.dir),
            inv_direction: Vec3A::from(inv),
            tmin: ray.t_min,
            tmax: cull_bound(ray.t_max),
        }
    }

    fn brute_force<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        let g = &*self.geometry;
        let mut best = None;
        for id in 0..g.len() as u32 {
            g.test_closest(id, ray, &mut best);
        }
        counters.add_tests(g.len() as u64);
        g.complete(ray, best)
    }
}

impl Accel for ObvhsAccel {
    fn build(geometry: Arc<Geometry>) -> Self {
        Self::build_with(geometry, BvhBuildParams::medium_build())
    }

    fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        if !ray.is_valid() {
            return self.brute_force(ray, counters);
        }
        let g = &*self.geometry;
        let mut best: Option<(u32, PrimHit)> = None;
        for &id in g.unbounded() {
            g.test_closest(id, ray, &mut best);
        }
        let mut tests = g.unbounded().len() as u64;
        if !self.bvh.nodes.is_empty() {
            let mut hit = RayHit::none();
            let oray = Self::obvhs_ray(&ray.clipped(best.map_or(ray.t_max, |(_, h)| h.t)));
            self.bvh.ray_traverse(oray, &mut hit, |_, i| {
                tests += 1;
                g.test_closest(self.ids[i], ray, &mut best);
                // obvhs keeps a node only if its entry is at most this: the contract's slack.
                best.map_or(f32::INFINITY, |(_, h)| cull_bound(h.t))
            });
        }
        counters.add_tests(tests);
        g.complete(ray, best)
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        if !ray.is_valid() {
            return self.brute_force(ray, counters).is_some();
        }
        let g = &*self.geometry;
        let mut tests = 0u64;
        for &id in g.unbounded() {
            tests += 1;
            if g.shape(id).intersect(ray).is_some() {
                counters.add_tests(tests);
                return true;
            }
        }
        let mut hit = false;
        if !self.bvh.nodes.is_empty() {
            let oray = Self::obvhs_ray(ray);
            hit = !self.bvh.ray_traverse_miss(oray, |_, i| {
                tests += 1;
                if g.shape(self.ids[i]).intersect(ray).is_some() {
                    // Any finite value below obvhs's t_max ends the traversal.
                    0.0
                } else {
                    f32::INFINITY
                }
            });
        }
        counters.add_tests(tests);
        hit
    }

    fn stats(&self) -> AccelStats {
        AccelStats {
            memory_bytes: std::mem::size_of_val(self.bvh.nodes.as_slice())
                + std::mem::size_of_val(self.bvh.primitive_indices.as_slice())
                + std::mem::size_of_val(self.ids.as_slice()),
            counts: vec![("cwbvh8 nodes", self.bvh.nodes.len() as u64)],
        }
    }
}
