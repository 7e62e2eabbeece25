//! The frame every CPU structure's queries share, so that a backend writes only its walk.
//!
//! A closest-hit query ([`closest`]) tests the unbounded primitives kept beside the
//! structure, hands a [`Closest`] to the structure's walk, and completes the winner
//! ([`Geometry::complete`]); the walk decides which primitives to test
//! ([`Closest::test`]) and when to stop ([`Closest::limit`], rule 3 of the contract), and
//! counts its node or cell visits. An any-hit query ([`occluded`]) does the same with an
//! [`AnyHit`]. The way obvhs's `ray_traverse` takes a closure: the walk is the backend's, the
//! rules are the core's. The pieces the walks themselves share are the nearest-first
//! [`crate::NodeStack`] and the 3D-DDA ([`crate::dda()`]).

use crate::counters::Counters;
use crate::geometry::Geometry;
use crate::hit::{Hit, PrimHit};
use crate::ray::Ray;
use crate::stack::cull_bound;

/// One query in progress: the ray, the geometry its primitive ids index, the counters, and
/// the query's own state `S` (the best hit so far for [`Closest`], nothing for [`AnyHit`]).
#[derive(Debug)]
pub struct Query<'a, C: Counters, S> {
    geometry: &'a Geometry,
    ray: &'a Ray,
    counters: &'a mut C,
    state: S,
}

/// A closest-hit query in progress: its state is the best hit so far.
pub type Closest<'a, C> = Query<'a, C, Option<(u32, PrimHit)>>;

/// An any-hit query in progress.
pub type AnyHit<'a, C> = Query<'a, C, ()>;

impl<'a, C: Counters, S> Query<'a, C, S> {
    /// The geometry the primitive ids index.
    #[inline]
    #[must_use]
    pub fn geometry(&self) -> &'a Geometry {
        self.geometry
    }

    /// The original ray (rule 4: primitives are always tested with it).
    #[inline]
    #[must_use]
    pub fn ray(&self) -> &'a Ray {
        self.ray
    }

    /// Counts `n` visits of nodes or cells.
    #[inline]
    pub fn add_visits(&mut self, n: u64) {
        self.counters.add_visits(n);
    }
}

impl<C: Counters> Closest<'_, C> {
    /// Tests primitive `id` ([`Geometry::test_closest`]) and counts the test; returns
    /// whether it became the best hit.
    #[inline]
    pub fn test(&mut self, id: u32) -> bool {
        self.counters.add_tests(1);
        self.geometry.test_closest(id, self.ray, &mut self.state)
    }

    /// Whether a hit has been found.
    #[inline]
    #[must_use]
    pub fn has_hit(&self) -> bool {
        self.state.is_some()
    }

    /// The best hit's `t`, or the ray's `t_max` while there is none.
    #[inline]
    #[must_use]
    pub fn best_t(&self) -> f32 {
        self.state.map_or(self.ray.t_max, |(_, h)| h.t)
    }

    /// The largest entry distance at which a node or cell must still be visited
    /// ([`cull_bound`] of [`Closest::best_t`]): rule 3's strict early exit.
    #[inline]
    #[must_use]
    pub fn limit(&self) -> f32 {
        cull_bound(self.best_t())
    }
}

impl<C: Counters> AnyHit<'_, C> {
    /// Whether primitive `id` is hit in `[ray.t_min, ray.t_max]`; counts the test.
    #[inline]
    pub fn test(&mut self, id: u32) -> bool {
        self.counters.add_tests(1);
        self.geometry.shape(id).intersect(self.ray).is_some()
    }
}

/// The closest hit of `ray`: the unbounded primitives first, then `walk` over the
/// structure, then the winner completed. Counts every primitive test into `counters`.
#[inline]
pub fn closest<C: Counters>(
    geometry: &Geometry,
    ray: &Ray,
    counters: &mut C,
    walk: impl FnOnce(&mut Closest<'_, C>),
) -> Option<Hit> {
    let mut best = None;
    counters.add_tests(geometry.closest_unbounded(ray, &mut best));
    let mut query = Query {
        geometry,
        ray,
        counters,
        state: best,
    };
    walk(&mut query);
    geometry.complete(ray, query.state)
}

/// Whether anything blocks `ray`: the unbounded primitives first, then `walk` over the
/// structure, which returns whether it found a hit (and may stop at the first, in any
/// order).
#[inline]
pub fn occluded<C: Counters>(
    geometry: &Geometry,
    ray: &Ray,
    counters: &mut C,
    walk: impl FnOnce(&mut AnyHit<'_, C>) -> bool,
) -> bool {
    let (plane_hit, tests) = geometry.occluded_unbounded(ray);
    counters.add_tests(tests);
    plane_hit
        || walk(&mut Query {
            geometry,
            ray,
            counters,
            state: (),
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Plane, RayCounters, Shape, Sphere, Triangle};
    use glam::Vec3;

    fn scene() -> Geometry {
        Geometry::new(vec![
            Shape::Sphere(Sphere::new(Vec3::new(0.0, 0.0, -5.0), 1.0)),
            Shape::Plane(Plane::new(Vec3::new(0.0, -2.0, 0.0), Vec3::Y)),
            Shape::Triangle(Triangle::new(
                Vec3::new(-1.0, -1.0, -3.0),
                Vec3::new(1.0, -1.0, -3.0),
                Vec3::new(0.0, 1.0, -3.0),
            )),
        ])
    }

    #[test]
    fn the_frame_equals_brute_force_and_counts_every_test() {
        let g = scene();
        for dir in [Vec3::NEG_Z, Vec3::new(0.0, -1.0, -1.0), Vec3::Y] {
            let ray = Ray::new(Vec3::ZERO, dir);
            let mut counted = RayCounters::default();
            // A "walk" that tests every bounded primitive: the brute force.
            let hit = closest(&g, &ray, &mut counted, |q| {
                for &id in q.geometry().bounded() {
                    q.test(id);
                }
                q.add_visits(1);
            });
            let mut brute = RayCounters::default();
            assert_eq!(hit, g.closest_brute_force(&ray, &mut brute));
            assert_eq!(counted.prim_tests, brute.prim_tests);
            assert_eq!(counted.node_visits, 1);
            let any = occluded(&g, &ray, &mut RayCounters::default(), |q| {
                q.geometry().bounded().iter().any(|&id| q.test(id))
            });
            assert_eq!(any, hit.is_some());
        }
    }

    #[test]
    fn the_limit_follows_the_best_hit() {
        let g = scene();
        let ray = Ray::new(Vec3::ZERO, Vec3::NEG_Z);
        let _ = closest(&g, &ray, &mut RayCounters::default(), |q| {
            assert_eq!(q.best_t(), f32::INFINITY);
            assert!(q.test(0));
            assert_eq!(q.best_t(), 4.0);
            assert!(q.limit() > 4.0 && q.limit() < 4.001);
            assert!(q.test(2), "the triangle at t = 3 is closer");
            assert!(!q.test(0), "the sphere does not replace it");
        });
    }
}
