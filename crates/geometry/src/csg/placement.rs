//! Placing a solid by an affine map: the ray taken to the solid's local space and normals
//! brought back by the inverse transpose (the leaf's box is its local box's, mapped by
//! [`crate::aabb::Aabb::transformed`]).

use super::solid::{Solid, solid_spans};
use super::spans::LeafSpans;
use crate::checks;
use crate::error::SceneError;
use crate::ray::Ray;
use glam::{Affine3A, Mat3A};

/// A placed leaf's maps: world to local for rays, and the normal matrix (the inverse
/// transpose of the local-to-world linear part) for normals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Placement {
    pub(super) to_local: Affine3A,
    pub(super) normal: Mat3A,
}

impl Placement {
    /// Checks `to_world` (finite, not singular, condition number at most
    /// [`crate::limits::MAX_TRANSFORM_CONDITION`]) and inverts it.
    pub(super) fn new(to_world: Affine3A) -> Result<Self, SceneError> {
        let inv = checks::check_transform(to_world, "CSG transform")?;
        Ok(Self {
            to_local: to_world.inverse(),
            normal: inv.transpose(),
        })
    }
}

/// The spans of a leaf: the ray taken to its local space when it is placed, and its
/// normals brought back.
#[inline]
pub(super) fn leaf_spans(s: &Solid, place: Option<&Placement>, ray: &Ray, leaf: u32) -> LeafSpans {
    let (o, d) = match place {
        None => (ray.origin, ray.dir),
        Some(p) => (
            p.to_local.transform_point3(ray.origin),
            p.to_local.transform_vector3(ray.dir),
        ),
    };
    let mut out = solid_spans(s, o, d, leaf);
    if let Some(p) = place {
        for span in &mut out.spans[..out.len] {
            for e in [&mut span.enter, &mut span.exit] {
                e.normal = (p.normal * e.normal).normalize_or(e.normal);
            }
        }
    }
    out
}
