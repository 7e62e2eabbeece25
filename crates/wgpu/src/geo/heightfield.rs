//! height fields on the GPU (`kernels/heightfield.wgsl`): not ported yet.

use super::Geo;
use crate::data::GpuPrim;
use raybench_core::HeightField;

/// Whether the kernels can intersect `x`, or why not.
///
/// # Errors
/// Always: the port is not written yet.
pub(crate) fn supports(_x: &HeightField) -> Result<(), String> {
    Err("the GPU kernels have no height field intersection (render it with a CPU backend)".into())
}

/// The record of `x`, its data appended to `geo`.
///
/// # Errors
/// See [`supports`].
pub(crate) fn encode(x: &HeightField, _geo: &mut Geo) -> Result<GpuPrim, String> {
    supports(x).map(|()| GpuPrim::default())
}
