//! Documented limits on what raybench accepts. Inputs beyond them are refused with an error,
//! never allowed to exhaust memory.

/// Largest accepted image width or height, in pixels.
pub const MAX_DIMENSION: u32 = 16_384;

/// Largest accepted `width * height * spp` (samples in one frame).
pub const MAX_SAMPLES: u64 = 1 << 34;

/// Largest accepted samples per pixel.
pub const MAX_SPP: u32 = 1 << 16;

/// Largest accepted number of primitives in one scene.
pub const MAX_PRIMITIVES: usize = 1 << 28;

/// Largest accepted ray depth (bounces).
pub const MAX_DEPTH: u32 = 64;
