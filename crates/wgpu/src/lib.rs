//! # raybench-wgpu
//!
//! The GPU backend: ray casting, Whitted ray tracing, path tracing and the volume modes
//! (maximum-intensity projection and compositing, `volume.rs`) as WGSL compute kernels on
//! any adapter wgpu can open headless (Vulkan on Linux: an NVIDIA GPU, or Mesa's
//! software lavapipe in CI; Metal; DX12).
//!
//! - The scene's BVH2 is built on the CPU by `raybench-bvh` (binned SAH) and flattened into
//!   32-byte nodes; primitives are stored in leaf order (48 bytes each), so leaves index them
//!   directly. Kernels traverse it with a per-thread stack, near child first, with the
//!   core's closest-hit contract (closest `t`, ties to the smaller id, strict early exit).
//! - With [`Layout::Cwbvh`] (the `wgpu-cwbvh` backend) the same builder's BVH2, with
//!   leaves of up to three primitives, is collapsed into a compressed 8-wide BVH
//!   ([`cwbvh`]: 80-byte nodes, child boxes quantised outward to 8 bits per plane) and the
//!   kernels walk it with a stack of child groups in octant order (Ylitie, Karras and Laine
//!   2017), finding the same hits.
//! - Any-hit rays (`occlude_rays`) run a kernel of their own that stops at the first hit.
//! - The intersection routines, shading, optics and the counter-based random numbers are
//!   ports of `raybench-core`'s (`kernels/*.wgsl` name each original), so images match the
//!   CPU's within floating-point tolerance.
//! - Frames are split into dispatches of bounded work ([`plan`]); path tracing accumulates
//!   its samples progressively in the output buffer.
//! - Phases are timed separately: `build` and `upload` in `prepare`; `upload`, `gpu`
//!   (timestamp queries when the adapter has them) and `readback` per frame.
//!
//! **Architecture invariant:** this is the only crate that knows wgpu.

mod constants;
mod context;
pub mod cwbvh;
mod data;
mod geo;
mod instances;
pub mod plan;
mod records;
mod renderer;
mod shading;
mod volume;

pub use constants::{KERNEL_FILES, KERNELS_DIR_VAR, kernel_source, wgsl_constants};
pub use context::{AdapterRequest, describe};
pub use data::check_kinds;
pub use records::Layout;
pub use renderer::{Phased, WgpuRenderer};

/// Whether a wgpu adapter can be opened here (`WGPU_BACKEND`, `WGPU_ADAPTER_NAME`), or why
/// not.
///
/// # Errors
/// The reason, naming the adapters that were found.
pub fn availability() -> Result<(), String> {
    context::gpu(&AdapterRequest::from_env()).map(|_| ())
}

/// The adapter the environment selects (`WGPU_BACKEND`, `WGPU_ADAPTER_NAME`) when it is a
/// software one that runs on the CPU (Mesa's lavapipe where there is no GPU): its
/// description, as `raybench backends` shows it; `None` for a GPU, or when there is no
/// adapter.
#[must_use]
pub fn software_adapter() -> Option<String> {
    context::gpu(&AdapterRequest::from_env())
        .ok()
        .filter(|g| g.info.device_type == wgpu::DeviceType::Cpu)
        .map(|g| g.describe())
}
