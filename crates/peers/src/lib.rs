//! # raybench-peers
//!
//! Other people's acceleration structures behind raybench's [`Accel`] trait, so that the
//! harness can render, time and compare them like its own backends:
//!
//! - [`BvhCrateAccel`] (backend `bvh-crate`): svenstaro's `bvh` crate's tree, traced by a
//!   stack traversal that tests primitives with raybench's own routine;
//! - with the cargo feature `embree` (it links the system library `libembree3`; Debian:
//!   `apt install libembree-dev`): `EmbreeAccel` (backend `embree`, Intel Embree 3 with
//!   single rays) and `EmbreePacketAccel` (backend `embree-packet`, packets of 16 rays).
//!
//! None of them is bound by the equivalence contract of [`Accel`]: the `bvh` crate's box
//! test is not conservative and Embree tests triangles with its own routine, so they agree
//! with naive on nearly every ray, not bit for bit. Planes are kept beside every structure
//! and tested by every ray, as in raybench's backends, and hits are completed (normals,
//! surface parameters) by raybench's [`raybench_geometry::Geometry::complete`].
//!
//! [`Accel`]: raybench_geometry::Accel

mod bvh_crate;
#[cfg(feature = "embree")]
mod embree;

pub use bvh_crate::BvhCrateAccel;
#[cfg(feature = "embree")]
pub use embree::{
    DEFAULT_PACKET_WIDTH, EmbreeAccel, EmbreeMode, EmbreePacketAccel, EmbreeQuality,
    MAX_SIDE_PRIMITIVES, availability as embree_availability, supports as embree_supports,
    version as embree_version,
};
