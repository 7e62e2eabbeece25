//! obvhs's own trees and traversals as peers (`obvhs-bvh2`, `obvhs-cwbvh`), shared by the
//! criterion suite (`benches/backends.rs`) and the peer benchmark (`benches/peers.rs`).
//!
//! Unlike raybench's `obvhs` backend ([`raybench_bvh::ObvhsAccel`], which adapts obvhs's
//! CWBVH so that its node test stays conservative), these run obvhs as its users do: the
//! tree from obvhs's own triangle builder, walked by obvhs's own traversal, in the scene's
//! coordinates. The closure obvhs calls per leaf primitive tests raybench's triangle and
//! returns the best `t` so far, which obvhs uses to cull further nodes; so only the
//! structure and the traversal differ from raybench's backends. Not exact (obvhs's box test
//! is not conservative at every ray), so the benchmarks count their differences.

use obvhs::BvhBuildParams;
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::RayHit;
use raybench_core::{
    Accel, AccelStats, Counters, Geometry, Hit, PrimHit, Ray, Shape, Triangle, Vec3A,
};
use std::sync::Arc;
use std::time::Duration;

/// One of obvhs's trees: how to build it from triangles and how to walk it.
pub trait ObvhsTree: Send + Sync + Sized + 'static {
    /// The peer's name in the benchmarks.
    const NAME: &'static str;

    /// The tree over `tris` (obvhs's `medium_build` preset: PLOC, reinsertion, leaves
    /// collapsed by cost).
    fn build_tree(tris: &[obvhs::triangle::Triangle]) -> Self;

    /// Primitive id of traversal primitive `i`.
    fn primitive(&self, i: usize) -> u32;

    /// The tree's primitive ids (indices into the triangles it was built from), to be
    /// mapped to raybench ids once after the build.
    fn primitive_ids_mut(&mut self) -> &mut [u32];

    /// Bytes of nodes and primitive ids.
    fn memory_bytes(&self) -> usize;

    /// Closest-hit walk: `test(i)` tests traversal primitive `i` and returns the best `t` so
    /// far (`inf` when none).
    fn closest(&self, ray: obvhs::ray::Ray, test: impl FnMut(usize) -> f32);

    /// Any-hit walk: true when `test(i)` returned a `t` below the ray's `tmax`.
    fn any(&self, ray: obvhs::ray::Ray, test: impl FnMut(usize) -> f32) -> bool;

    /// Node count.
    fn nodes(&self) -> usize;
}

/// [`ObvhsTree`] for obvhs's tree type `$tree` (the same fields and walk functions),
/// named `$name`, built by `$build`.
macro_rules! obvhs_tree {
    ($tree:ty, $name:literal, $build:path) => {
        impl ObvhsTree for $tree {
            const NAME: &'static str = $name;

            fn build_tree(tris: &[obvhs::triangle::Triangle]) -> Self {
                $build(
                    tris,
                    BvhBuildParams::medium_build(),
                    &mut Duration::default(),
                )
            }

            #[inline]
            fn primitive(&self, i: usize) -> u32 {
                self.primitive_indices[i]
            }

            #[inline]
            fn closest(&self, ray: obvhs::ray::Ray, mut test: impl FnMut(usize) -> f32) {
                self.ray_traverse(ray, &mut RayHit::none(), |_, i| test(i));
            }

            #[inline]
            fn any(&self, ray: obvhs::ray::Ray, mut test: impl FnMut(usize) -> f32) -> bool {
                !self.ray_traverse_miss(ray, |_, i| test(i))
            }

            fn nodes(&self) -> usize {
                self.nodes.len()
            }

            fn primitive_ids_mut(&mut self) -> &mut [u32] {
                &mut self.primitive_indices
            }

            fn memory_bytes(&self) -> usize {
                std::mem::size_of_val(self.nodes.as_slice())
                    + std::mem::size_of_val(self.primitive_indices.as_slice())
            }
        }
    };
}

obvhs_tree!(
    Bvh2,
    "obvhs-bvh2",
    obvhs::bvh2::builder::build_bvh2_from_tris
);
obvhs_tree!(
    CwBvh,
    "obvhs-cwbvh",
    obvhs::cwbvh::builder::build_cwbvh_from_tris
);

/// An obvhs tree over a scene's triangles behind [`Accel`]; planes are tested beside it by
/// every ray, as in raybench's backends, and hits completed by [`Geometry::complete`].
/// Scenes with bounded primitives other than triangles are refused ([`ObvhsPeer::supports`]).
pub struct ObvhsPeer<T: ObvhsTree> {
    tree: T,
    /// Primitive tests go through raybench's own `Geometry::test_closest`, as in every
    /// raybench backend, so that only the structure and traversal differ.
    geometry: Arc<Geometry>,
}

/// The ids of `g`'s bounded primitives (all triangles) and the triangles, or `None` when
/// another bounded primitive is among them.
fn triangles(g: &Geometry) -> Option<(Vec<u32>, Vec<Triangle>)> {
    g.bounded()
        .iter()
        .map(|&id| match g.shape(id) {
            Shape::Triangle(t) => Some((id, *t)),
            _ => None,
        })
        .collect()
}

impl<T: ObvhsTree> ObvhsPeer<T> {
    /// The triangles in obvhs's format.
    #[must_use]
    pub fn obvhs_tris(tris: &[Triangle]) -> Vec<obvhs::triangle::Triangle> {
        tris.iter()
            .map(|t| obvhs::triangle::Triangle {
                v0: Vec3A::from(t.v[0]),
                v1: Vec3A::from(t.v[1]),
                v2: Vec3A::from(t.v[2]),
            })
            .collect()
    }

    /// Whether the peer supports `scene`: triangles and planes only.
    ///
    /// # Errors
    /// Why not.
    pub fn supports(geometry: &Geometry) -> Result<(), String> {
        triangles(geometry)
            .map(|_| ())
            .ok_or_else(|| format!("{}: triangles and planes only", T::NAME))
    }

    /// obvhs's own ray constructor (it replaces tiny direction components for its slab
    /// test).
    #[must_use]
    #[inline]
    pub fn ray(ray: &Ray) -> obvhs::ray::Ray {
        obvhs::ray::Ray::new(
            Vec3A::from(ray.origin),
            Vec3A::from(ray.dir),
            ray.t_min,
            ray.t_max,
        )
    }

    /// The closest hit of `ray` (whose obvhs twin is `oray`) among the tree's triangles,
    /// improving on `best`.
    #[inline]
    pub fn closest(
        &self,
        ray: &Ray,
        oray: obvhs::ray::Ray,
        mut best: Option<(u32, PrimHit)>,
    ) -> Option<(u32, PrimHit)> {
        self.tree.closest(oray, |i| {
            self.geometry
                .test_closest(self.tree.primitive(i), ray, &mut best);
            best.map_or(f32::INFINITY, |(_, h)| h.t)
        });
        best
    }
}

impl<T: ObvhsTree> Accel for ObvhsPeer<T> {
    /// # Panics
    /// When a bounded primitive is not a triangle ([`ObvhsPeer::supports`] says so first).
    fn build(geometry: Arc<Geometry>) -> Self {
        let (ids, tris) = triangles(&geometry)
            .unwrap_or_else(|| panic!("{}: triangles and planes only", T::NAME));
        let mut tree = T::build_tree(&Self::obvhs_tris(&tris));
        // obvhs indexes the triangles it was given: map them to raybench ids once, so the
        // walk reads one id per primitive, as obvhs's users do.
        for p in tree.primitive_ids_mut() {
            *p = ids[*p as usize];
        }
        Self { tree, geometry }
    }

    fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        let mut best = None;
        counters.add_tests(self.geometry.closest_unbounded(ray, &mut best));
        let best = self.closest(ray, Self::ray(ray), best);
        self.geometry.complete(ray, best)
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        let (hit, tests) = self.geometry.occluded_unbounded(ray);
        counters.add_tests(tests);
        hit || self.tree.any(Self::ray(ray), |i| {
            let id = self.tree.primitive(i);
            if self.geometry.shape(id).intersect(ray).is_some() {
                f32::NEG_INFINITY
            } else {
                f32::INFINITY
            }
        })
    }

    fn stats(&self) -> AccelStats {
        AccelStats {
            memory_bytes: self.tree.memory_bytes(),
            counts: vec![("obvhs nodes", self.tree.nodes() as u64)],
        }
    }
}
