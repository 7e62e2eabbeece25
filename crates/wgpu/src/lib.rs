//! # raybench-wgpu
//!
//! The GPU backend: ray casting, Whitted ray tracing and path tracing as WGSL compute
//! kernels on any adapter wgpu can open headless (Vulkan on Linux: an NVIDIA GPU, or Mesa's
//! software lavapipe in CI; Metal; DX12).
//!
//! - The scene's BVH2 is built on the CPU by `raybench-bvh` (binned SAH) and flattened into
//!   32-byte nodes; primitives are stored in leaf order (48 bytes each), so leaves index them
//!   directly. Kernels traverse it with a per-thread stack, near child first, with the
//!   core's closest-hit contract (closest `t`, ties to the smaller id, strict early exit).
//! - The intersection routines, shading, optics and the counter-based random numbers are
//!   ports of `raybench-core`'s (`kernels.wgsl` names each original), so images match the
//!   CPU's within floating-point tolerance.
//! - Frames are split into dispatches of bounded work ([`plan`]); path tracing accumulates
//!   its samples progressively in the output buffer.
//! - Phases are timed separately: `build` and `upload` in `prepare`; `upload`, `gpu`
//!   (timestamp queries when the adapter has them) and `readback` per frame.
//!
//! **Architecture invariant:** this is the only crate that knows wgpu.

mod constants;
mod context;
mod data;
pub mod plan;
mod renderer;

pub use constants::{kernel_source, wgsl_constants};
pub use context::{AdapterRequest, describe};
pub use data::{check_kinds, check_path_emitters};
pub use renderer::WgpuRenderer;

/// Whether a wgpu adapter can be opened here (`WGPU_BACKEND`, `WGPU_ADAPTER_NAME`), or why
/// not.
///
/// # Errors
/// The reason, naming the adapters that were found.
pub fn availability() -> Result<(), String> {
    context::gpu(&AdapterRequest::from_env()).map(|_| ())
}
