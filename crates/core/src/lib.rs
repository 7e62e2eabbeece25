//! # raybench-core
//!
//! The rendering core: the scene data model and its checked builder, materials and lights,
//! textures and the shading attributes of meshes, the pinhole camera, voxel volumes, the
//! per-pixel integrators, the standard ray sets, and the frame-level [`Renderer`] contract
//! that every backend is driven through.
//!
//! What a ray meets (rays, boxes, hits, primitives, [`Geometry`], the [`Accel`] contract and
//! its traversal kit) lives one crate below, in `raybench-geometry`, which this crate
//! re-exports whole: `raybench_core::Triangle` and `raybench_geometry::Triangle` are the same
//! type. CPU backends depend on `raybench-geometry` only.
//!
//! **Architecture invariant:** this crate knows nothing of threads, I/O, SIMD intrinsics or
//! GPUs. It depends on `raybench-geometry` and `glam` and nothing else.

mod animation;
mod attributes;
mod builder;
mod camera;
mod emitters;
mod environment;
mod flatten;
mod frame;
pub mod integrator;
mod light_sampling;
mod material;
pub mod optics;
pub mod ray_sets;
mod renderer;
mod scene;
mod texture;
pub mod voxels;

pub use raybench_geometry::*;

pub use attributes::{AttributeRange, AttributesAt, ShadingAttributes, VertexAttributes};
pub use builder::SceneBuilder;
pub use camera::{Camera, CameraOverrides, CameraRays, NamedCamera};
pub use emitters::{Chosen, Emitters};
pub use environment::{Environment, luminance};
pub use flatten::{flatten, flatten_geometry};
pub use frame::{Frame, FrameStats, NO_HIT, Timings};
pub use light_sampling::LightSample;
pub use material::{Checker, Light, Material, MaterialKind};
pub use ray_sets::RaySet;
pub use renderer::{LightSampling, Mode, RenderError, RenderSettings, Renderer, UpdatePolicy};
pub use scene::{ObjectInfo, Scene, SurfaceShading};
pub use texture::{MAX_TEXTURE_SIZE, Texture, Wrap, srgb_to_linear};
pub use voxels::{
    Sampling, TransferFunction, TransferPoint, Volume, VolumeData, VolumeParams, VolumeSample,
};
