//! # raybench-peers
//!
//! Other people's acceleration structures behind raybench's [`Accel`] trait, so that the
//! harness can render, time and compare them like its own backends:
//!
//! - [`BvhCrateAccel`] (backend `bvh-crate`): svenstaro's `bvh` crate's tree, traced by a
//!   stack traversal that tests primitives with raybench's own routine;
//! - with the cargo feature `embree` (it links the system library `libembree3`; Debian:
//!   `apt install libembree-dev`): `EmbreeAccel` (backend `embree`, Intel Embree 3 with
//!   single rays) and `EmbreePacketAccel` (backend `embree-packet`, packets of 16 rays);
//! - with the cargo feature `tinybvh` (it compiles a C++ shim of ours against the
//!   `tiny_bvh.h` that the `tinybvh-rs` crate ships, tinybvh 1.6.8, with AVX2 and FMA; the
//!   crate's Rust API is not used): `TinyBvhAccel`, Jacco Bikker's tinybvh with its
//!   `BVH4_CPU` or `BVH8_CPU` layout (`TinyBvhLayout`), built by tinybvh and traced with its
//!   single-ray kernels (the peer benchmark's `tinybvh4` and `tinybvh8`; triangles only, on
//!   x86-64 CPUs with AVX2 and FMA: `tinybvh_availability` says why not elsewhere).
//!
//! None of them is bound by the equivalence contract of [`Accel`]: the `bvh` crate's box
//! test is not conservative and Embree and tinybvh test triangles with their own routines,
//! so they agree with naive on nearly every ray, not bit for bit. Planes are kept beside every structure
//! and tested by every ray, as in raybench's backends, and hits are completed (normals,
//! surface parameters) by raybench's [`raybench_geometry::Geometry::complete`].
//!
//! [`Accel`]: raybench_geometry::Accel

mod bvh_crate;
#[cfg(feature = "embree")]
mod embree;
#[cfg(feature = "tinybvh")]
mod tinybvh;

pub use bvh_crate::BvhCrateAccel;
#[cfg(feature = "embree")]
pub use embree::{
    DEFAULT_PACKET_WIDTH, EmbreeAccel, EmbreeMode, EmbreePacketAccel, EmbreeQuality,
    MAX_SIDE_PRIMITIVES, availability as embree_availability, supports as embree_supports,
    version as embree_version,
};
#[cfg(feature = "tinybvh")]
pub use tinybvh::{
    TinyBvhAccel, TinyBvhLayout, VERSION as TINYBVH_VERSION, availability as tinybvh_availability,
    availability_with as tinybvh_availability_with, supports as tinybvh_supports,
};

/// The closest hit among the planes ([`raybench_geometry::Geometry::closest_unbounded`])
/// and the `side` primitives a foreign structure keeps beside itself: the best hit its own
/// answer must improve on. Counts the tests.
#[cfg(any(feature = "embree", feature = "tinybvh"))]
fn closest_beside<C: raybench_geometry::Counters>(
    g: &raybench_geometry::Geometry,
    side: &[u32],
    ray: &raybench_geometry::Ray,
    counters: &mut C,
) -> Option<(u32, raybench_geometry::PrimHit)> {
    let mut best = None;
    let mut tests = g.closest_unbounded(ray, &mut best);
    for &id in side {
        g.test_closest(id, ray, &mut best);
    }
    tests += side.len() as u64;
    counters.add_tests(tests);
    best
}

/// Whether a plane or one of the `side` primitives blocks `ray`. Counts the tests.
#[cfg(any(feature = "embree", feature = "tinybvh"))]
fn occluded_beside<C: raybench_geometry::Counters>(
    g: &raybench_geometry::Geometry,
    side: &[u32],
    ray: &raybench_geometry::Ray,
    counters: &mut C,
) -> bool {
    let (hit, tests) = g.occluded_unbounded(ray);
    counters.add_tests(tests);
    if hit {
        return true;
    }
    for (k, &id) in side.iter().enumerate() {
        if g.shape(id).intersect(ray).is_some() {
            counters.add_tests(k as u64 + 1);
            return true;
        }
    }
    counters.add_tests(side.len() as u64);
    false
}
