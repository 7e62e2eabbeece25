//! # raybench-naive
//!
//! The lecture's reference strategy: for each ray, test every primitive and keep the closest.
//! An `N x N` ray-cast frame of `M` primitives with `K` rays per pixel costs
//! `O(N^2 * M * K)` tests: exactly `rays * M` closest-hit tests, which the counters show.
//!
//! Because it tests primitives in id order and keeps a candidate only when it is strictly
//! closer (or equally close with a smaller id, which in id order never happens), it is the
//! definition of the right answer: every other raybench CPU backend is tested against it.
//!
//! With instances it tests every primitive of every instance too, in global id order, on
//! each instance's instance-space ray ([`Geometry::closest_every`]): `rays * total` tests,
//! where the total counts each instance's mesh once per instance. It does not go through
//! the two-level form the other backends use, so it checks that form instead of sharing it.

use raybench_geometry::{Accel, AccelStats, Counters, Geometry, Hit, Ray};
use std::sync::Arc;

/// No acceleration structure: a loop over all primitives.
#[derive(Clone, Debug)]
pub struct NaiveAccel {
    geometry: Arc<Geometry>,
}

impl Accel for NaiveAccel {
    const TESTS_INSTANCES: bool = true;

    fn build(geometry: Arc<Geometry>) -> Self {
        Self { geometry }
    }

    fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    #[inline]
    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        self.geometry.closest_every(ray, counters)
    }

    #[inline]
    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        self.geometry.occluded_every(ray, counters)
    }

    fn stats(&self) -> AccelStats {
        AccelStats {
            memory_bytes: 0,
            counts: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_geometry::{RayCounters, Shape, Sphere, Triangle, Vec3};

    #[test]
    fn closest_hit_and_tie_rule() {
        // Two identical triangles: the smaller id wins at equal t.
        let tri = Triangle::new(
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(1.0, -1.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
        );
        let g = Arc::new(Geometry::new(vec![
            Shape::Sphere(Sphere::new(Vec3::new(0.0, 0.0, 5.0), 1.0)),
            Shape::Triangle(tri),
            Shape::Triangle(tri),
        ]));
        let accel = NaiveAccel::build(g);
        let mut c = RayCounters::default();
        let hit = accel
            .intersect(&Ray::new(Vec3::ZERO, Vec3::Z), &mut c)
            .unwrap();
        assert_eq!((hit.prim, hit.t), (1, 1.0));
        assert_eq!(c.prim_tests, 3);
        assert!(accel.occluded(&Ray::new(Vec3::ZERO, Vec3::Z), &mut c));
        assert!(!accel.occluded(&Ray::new(Vec3::ZERO, -Vec3::Z), &mut c));
    }

    #[test]
    fn empty_geometry_misses() {
        let accel = NaiveAccel::build(Arc::new(Geometry::default()));
        assert!(
            accel
                .intersect(&Ray::new(Vec3::ZERO, Vec3::Z), &mut RayCounters::default())
                .is_none()
        );
    }
}
