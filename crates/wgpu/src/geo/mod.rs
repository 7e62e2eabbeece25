//! The primitive kinds beyond triangles, spheres and planes as the kernels read them: each
//! kind's module writes the kind's 48-byte record ([`GpuPrim`]) and appends what does not
//! fit in it (samples, trees, control points, programs) to the `geo` buffer, which the
//! record points into; its WGSL port lives in `kernels/<kind>.wgsl` with a
//! `<kind>_hit(r, p, t_max) -> Cand` and a `<kind>_normal(r, p, h) -> vec3<f32>`.
//!
//! `a.w` (the kind) and `b.w` (the primitive id) of a record are set by the caller
//! (`data.rs`); the rest of the record is the kind's own.

pub(crate) mod bezier;
pub(crate) mod csg;
pub(crate) mod heightfield;
pub(crate) mod sdf;

use crate::records::{Geo, GpuPrim};
use raybench_core::Shape;

/// Whether the kernels can intersect `shape` (the kinds of this module; triangles, spheres
/// and planes always), or why not.
///
/// # Errors
/// The reason, naming the kind.
pub(crate) fn supports(shape: &Shape) -> Result<(), String> {
    match shape {
        Shape::Triangle(_) | Shape::Sphere(_) | Shape::Plane(_) => Ok(()),
        Shape::HeightField(x) => heightfield::supports(x),
        Shape::Csg(x) => csg::supports(x),
        Shape::Bezier(x) => bezier::supports(x),
        Shape::Sdf(x) => sdf::supports(x),
    }
}

/// The record of a shape of this module's kinds, its data appended to `geo`; `None` for
/// triangles, spheres and planes, which `data.rs` writes itself.
///
/// # Errors
/// When the kind has no port or its data does not fit ([`supports`]).
pub(crate) fn encode(shape: &Shape, geo: &mut Geo) -> Result<Option<GpuPrim>, String> {
    Ok(Some(match shape {
        Shape::Triangle(_) | Shape::Sphere(_) | Shape::Plane(_) => return Ok(None),
        Shape::HeightField(x) => heightfield::encode(x, geo)?,
        Shape::Csg(x) => csg::encode(x, geo)?,
        Shape::Bezier(x) => bezier::encode(x, geo)?,
        Shape::Sdf(x) => sdf::encode(x, geo)?,
    }))
}
