//! # raybench-geometry
//!
//! What a ray meets, and nothing about pictures: rays, boxes and hits, the primitives and
//! their ray intersection routines, the id-indexed [`Geometry`], the [`Accel`] contract that
//! every CPU acceleration strategy implements, and the traversal kit they share.
//!
//! Every primitive's `intersect` returns the one hit record [`PrimHit`] (distance,
//! sub-primitive, surface parameters); [`Shape::complete_hit`] adds the primitive's normal.
//!
//! The scalar intersection routines in this crate are the workspace's *definition* of a hit:
//! every backend calls them (or, for SIMD and GPU backends, ports them operation by operation),
//! so that all raybench CPU backends return bit-identical results. See [`Accel`] for the
//! equivalence contract.
//!
//! The backends (`raybench-naive`, `-bvh`, `-grid`, `-packet`, `-peers`) depend on this crate
//! only; the rendering core (`raybench-core`: scene, materials, camera, integrators, the
//! `Renderer` contract) sits above it and re-exports it.
//!
//! **Architecture invariant:** this crate knows nothing of threads, I/O, SIMD intrinsics,
//! GPUs or images. It depends on `glam` and nothing else.

mod aabb;
mod accel;
mod bezier;
mod bilinear;
mod checks;
mod counters;
mod csg;
mod dda;
mod error;
mod geometry;
mod heightfield;
mod hit;
mod instance;
mod light;
pub mod limits;
mod mesh;
pub mod motion;
mod optree;
mod plane;
pub mod quality;
pub mod random_rays;
mod ray;
pub mod sampling;
mod sdf;
mod sphere;
mod stack;
pub mod traverse;
mod triangle;
mod two_level;

pub use aabb::{Aabb, FAR_SCALE, SlabRay};
pub use accel::{Accel, AccelStats, BatchTracer, ray_by_ray};
pub use bezier::{
    BezierPatch, BezierStats, FALLBACK_DEPTH, MAX_NEWTON_ITERATIONS, REGION_DEPTH, UV_MARGIN,
};
pub use bilinear::BilinearPatch;
pub use checks::check_transform;
pub use counters::{Counters, NoCounters, RayCounters};
pub use csg::{Csg, CsgNode, CsgOp, CsgPart, Solid};
pub use dda::dda;
pub use error::SceneError;
pub use geometry::{Geometry, PrimitiveKind, Shape};
pub use heightfield::{CellSurface, HeightField, HeightFieldTraversal, MAX_HEIGHT_FIELD_VERTICES};
pub use hit::{Hit, PrimHit, keep_closer};
pub use instance::{INSTANCE_BOX_PAD, Instance};
pub use light::LightPoint;
pub use mesh::{
    MAX_EAR_CLIP_VERTICES, PolygonKind, PolygonMesh, TriangleMesh, Triangulated,
    triangulate_polygon,
};
pub use motion::{
    Deform, DeformTarget, Deformation, InstanceMotion, Key, Motion, Placement, Procedural,
    same_topology,
};
pub use plane::Plane;
pub use quality::{
    CostConstants, Epo, GridQuality, LeafCounts, QualityParams, SizeHistogram, StructureQuality,
    TreeQuality, TreeView,
};
pub use ray::Ray;
pub use sdf::{March, Sdf, SdfNode, SdfNodeView, SdfOp, SdfParams, SdfPrimitive};
pub use sphere::Sphere;
pub use stack::{CULL_SLACK, NodeStack, cull_bound};
pub use triangle::Triangle;
pub use two_level::{TopLevel, TopNode, TwoLevel};

pub use glam::{Affine3A, Vec2, Vec3, Vec3A};
