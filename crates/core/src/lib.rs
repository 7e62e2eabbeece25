//! # raybench-core
//!
//! The vocabulary every raybench crate shares: rays, boxes and hits, the primitives and their
//! ray intersection routines, the scene data model, the pinhole camera, the per-pixel
//! integrators, and the two-level renderer contract ([`Accel`] for CPU strategies,
//! [`Renderer`] at frame level).
//!
//! The scalar intersection routines in this crate are the workspace's *definition* of a hit:
//! every backend calls them (or, for SIMD and GPU backends, ports them operation by operation),
//! so that all raybench CPU backends return bit-identical results. See [`Accel`] for the
//! equivalence contract.
//!
//! **Architecture invariant:** this crate knows nothing of threads, I/O, SIMD intrinsics or
//! GPUs. It depends on `glam` and nothing else.

mod aabb;
mod accel;
mod bezier;
mod bilinear;
mod camera;
mod checks;
mod csg;
mod emitters;
mod error;
mod frame;
mod geometry;
mod heightfield;
mod hit;
pub mod integrator;
pub mod limits;
mod material;
mod mesh;
pub mod optics;
mod plane;
mod ray;
pub mod rays;
mod renderer;
pub mod sampling;
mod scene;
mod sdf;
mod sphere;
mod triangle;
pub mod volume;

pub use aabb::{Aabb, FAR_SCALE, SlabRay};
pub use accel::{
    Accel, AccelStats, BatchTracer, CULL_SLACK, Counters, NoCounters, NodeStack, RayCounters,
    cull_bound,
};
pub use bezier::{BezierPatch, BezierStats, FALLBACK_DEPTH, MAX_NEWTON_ITERATIONS, REGION_DEPTH};
pub use bilinear::{BilinearPatch, PatchHit};
pub use camera::{Camera, CameraRays};
pub use checks::check_transform;
pub use csg::{Csg, CsgHit, CsgNode, CsgOp, Solid};
pub use emitters::Emitters;
pub use error::SceneError;
pub use frame::{Frame, FrameStats, NO_HIT, Timings};
pub use geometry::{Geometry, PrimHit, PrimitiveKind, Shape};
pub use heightfield::{CellSurface, HeightField, HeightFieldTraversal, MAX_HEIGHT_FIELD_VERTICES};
pub use hit::Hit;
pub use material::{Checker, Light, Material, MaterialKind};
pub use mesh::{
    MAX_EAR_CLIP_VERTICES, PolygonKind, PolygonMesh, TriangleMesh, Triangulated,
    triangulate_polygon,
};
pub use plane::Plane;
pub use ray::Ray;
pub use rays::RaySet;
pub use renderer::{Mode, RenderError, RenderSettings, Renderer, TracedRays};
pub use scene::{ObjectInfo, Scene, SceneBuilder};
pub use sdf::{March, Sdf, SdfNode, SdfOp, SdfParams, SdfPrimitive};
pub use sphere::Sphere;
pub use triangle::Triangle;
pub use volume::{
    Sampling, TransferFunction, TransferPoint, Volume, VolumeData, VolumeParams, VolumeSample,
};

pub use glam::{Affine3A, Vec3, Vec3A};
