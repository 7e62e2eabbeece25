//! SDF models on the GPU (`kernels/sdf.wgsl`): not ported yet.

use super::Geo;
use crate::data::GpuPrim;
use raybench_core::Sdf;

/// Whether the kernels can intersect `x`, or why not.
///
/// # Errors
/// Always: the port is not written yet.
pub(crate) fn supports(_x: &Sdf) -> Result<(), String> {
    Err("the GPU kernels have no SDF model intersection (render it with a CPU backend)".into())
}

/// The record of `x`, its data appended to `geo`.
///
/// # Errors
/// See [`supports`].
pub(crate) fn encode(x: &Sdf, _geo: &mut Geo) -> Result<GpuPrim, String> {
    supports(x).map(|()| GpuPrim::default())
}
