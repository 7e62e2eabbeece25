//! The record of a ray/primitive hit.

use glam::Vec3;

/// The closest hit along a ray, as returned by an [`crate::Accel`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit point.
    pub t: f32,
    /// Global primitive id: objects in scene-file order, each mesh's triangles in file order
    /// after triangulation.
    pub prim: u32,
    /// Sub-primitive id for objects with inner parts (a height-field cell, a CSG leaf);
    /// 0 for simple primitives.
    pub sub: u32,
    /// First surface parameter (triangle: barycentric weight of vertex 1; sphere: longitude
    /// in [0, 1); plane: 0).
    pub u: f32,
    /// Second surface parameter (triangle: barycentric weight of vertex 2; sphere: latitude
    /// in [0, 1]; plane: 0).
    pub v: f32,
    /// Unit geometric normal, as the primitive defines it (not flipped towards the ray).
    pub normal: Vec3,
}

impl Hit {
    /// The workspace's tie rule: smaller `t` wins, equal `t` goes to the smaller primitive
    /// id. Every backend picks the closest hit with this comparison.
    #[inline]
    #[must_use]
    pub fn closer(t: f32, prim: u32, than_t: f32, than_prim: u32) -> bool {
        t < than_t || (t == than_t && prim < than_prim)
    }
}
