//! CSG trees on the GPU (`kernels/csg.wgsl`): not ported yet.

use super::Geo;
use crate::data::GpuPrim;
use raybench_core::Csg;

/// Whether the kernels can intersect `x`, or why not.
///
/// # Errors
/// Always: the port is not written yet.
pub(crate) fn supports(_x: &Csg) -> Result<(), String> {
    Err("the GPU kernels have no CSG tree intersection (render it with a CPU backend)".into())
}

/// The record of `x`, its data appended to `geo`.
///
/// # Errors
/// See [`supports`].
pub(crate) fn encode(x: &Csg, _geo: &mut Geo) -> Result<GpuPrim, String> {
    supports(x).map(|()| GpuPrim::default())
}
