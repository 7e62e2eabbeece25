//! Documented limits on what raybench accepts. Inputs beyond them are refused with an error,
//! never allowed to exhaust memory.

/// Largest accepted image width or height, in pixels.
pub const MAX_DIMENSION: u32 = 16_384;

/// Largest accepted `width * height * spp` (samples in one frame).
pub const MAX_SAMPLES: u64 = 1 << 34;

/// Largest accepted samples per pixel.
pub const MAX_SPP: u32 = 1 << 16;

/// Largest accepted number of primitives in one scene (about 2.7 GB of primitives).
pub const MAX_PRIMITIVES: usize = 1 << 26;

/// Largest accepted number of primitives of a scene with instances, flattened (the flat
/// ones plus every instance's mesh, counted once per instance): every id of the flattened
/// scene is a `u32` below `NO_HIT` (`u32::MAX`). The stored primitives (the flat ones and
/// each distinct mesh once) stay bounded by [`MAX_PRIMITIVES`].
pub const MAX_INSTANCED_PRIMITIVES: u64 = u32::MAX as u64 - 1;

/// Largest accepted number of instances in one scene (each costs about 230 bytes: its
/// record, its material override and its share of the top-level tree).
pub const MAX_INSTANCES: usize = 1 << 20;

/// Largest accepted magnitude of a coordinate or radius: scene extents, squared radii and
/// products in the intersection routines then stay finite in f32.
pub const MAX_COORDINATE: f32 = 1.0e18;

/// Largest accepted number of explicitly generated rays (incoherent ray sets).
pub const MAX_EXPLICIT_RAYS: u64 = 1 << 24;

/// Largest accepted ray depth (bounces).
pub const MAX_DEPTH: u32 = 64;

/// Largest number of vertices of one height field (`8193^2`, 256 MiB of heights); PNG
/// headers and raw sizes are checked against it before anything is decoded.
pub const MAX_HEIGHT_FIELD_VERTICES: u64 = 1 << 26;

/// Largest number of voxels of one volume (`2^27`: 512 MiB as f32); raw sizes and
/// generator arguments are checked against it before anything is read.
pub const MAX_VOLUME_VOXELS: u64 = 1 << 27;

/// Deepest accepted CSG tree (operators nest at most this many levels; scene files fold
/// n-ary operators into balanced trees first).
pub const MAX_CSG_DEPTH: usize = 32;

/// Largest accepted number of solids in one CSG tree: every ray that reaches the tree's box
/// tests them all.
pub const MAX_CSG_LEAVES: usize = 256;

/// Largest accepted condition number (`|M|max * |M^-1|max` of the linear part) of a CSG
/// solid's transform: a zero or near-zero scale makes the local ray's direction overflow.
pub const MAX_TRANSFORM_CONDITION: f32 = 1e6;

/// Largest accepted number of Bezier patches in one `.bpt` file (the count on its first line
/// is checked against it before anything is allocated).
pub const MAX_BEZIER_PATCHES: usize = 1 << 20;
/// Deepest accepted SDF tree (operations and transforms nest at most this many levels;
/// scene files fold n-ary operations into balanced trees first).
pub const MAX_SDF_DEPTH: usize = 32;

/// Largest accepted number of nodes in one SDF tree: every march step evaluates them all.
pub const MAX_SDF_NODES: usize = 512;

/// Largest accepted SDF step limit (field evaluations per ray).
pub const MAX_SDF_STEPS: u32 = 4096;

/// Smallest accepted SDF hit tolerance, relative to the model's box diagonal (below it f32
/// rounding of the field would stall the march).
pub const MIN_SDF_TOLERANCE: f32 = 1.0e-6;

/// Largest accepted SDF hit tolerance, relative to the model's box diagonal.
pub const MAX_SDF_TOLERANCE: f32 = 1.0e-2;

/// Largest accepted number of worker threads (`--threads`). More threads than this only
/// slow rendering down (every tile is small; 5,000 threads took 35 s to render 64 x 64
/// pixels on 2 cores), and rayon starts each thread eagerly.
pub const MAX_THREADS: usize = 1024;

/// Smallest accepted sphere radius: its square (`1e-36`) stays a normal `f32` (above
/// `f32::MIN_POSITIVE`, `1.2e-38`); a smaller radius squares to a denormal or zero and the
/// sphere silently vanishes from the ray/sphere test.
pub const MIN_SPHERE_RADIUS: f32 = 1.0e-18;

/// Smallest accepted sphere radius relative to the largest magnitude of its centre's
/// coordinates (`f32::EPSILON`): a smaller sphere is below one unit in the last place of
/// its own position and cannot be located, let alone hit.
pub const MIN_RELATIVE_SPHERE_RADIUS: f32 = f32::EPSILON;

/// Estimated peak memory per primitive while a scene is loaded and an acceleration
/// structure is built over it, in bytes: the memory budget's unit for triangles, spheres
/// and patches. Measured as peak resident memory less a tiny scene's: `compare
/// spheres:1000000` (every backend in turn, the GPU's on llvmpipe) 565 B per sphere;
/// `render --backend packet` 434 B per sphere and 370 B per triangle at 4 million, linear
/// from 1 million (2-vCPU Zen 5 guest, release build).
pub const PRIMITIVE_BYTES_ESTIMATE: u64 = 600;

/// Estimated memory per height-field vertex (heights and the min-max tree), in bytes.
/// Measured: 8.3 B per vertex for `render heightfield:4096` (16.8 million vertices).
pub const HEIGHT_FIELD_VERTEX_BYTES_ESTIMATE: u64 = 10;

/// Estimated memory per voxel, in bytes. Measured: 4.0 B per voxel for a `phantom:512`
/// volume rendered in mode `mip`; raw files also hold their bytes while they are decoded.
pub const VOXEL_BYTES_ESTIMATE: u64 = 6;
