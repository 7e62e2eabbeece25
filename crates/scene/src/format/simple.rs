//! The `kind = "sphere"` and `kind = "plane"` objects of the scene format: one analytic
//! primitive each, written inline.

use super::{ObjectCx, V3};
use crate::error::LoadError;
use raybench_core::{Sphere, Vec3};
use serde::Deserialize;

/// `kind = "sphere"`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SphereDesc {
    center: V3,
    radius: f32,
    material: Option<String>,
}

/// `kind = "plane"`: the plane through `point` facing `normal`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PlaneDesc {
    point: V3,
    normal: V3,
    material: Option<String>,
}

impl SphereDesc {
    /// Adds the sphere.
    pub(super) fn add(&self, cx: &mut ObjectCx) -> Result<(), LoadError> {
        let m = cx.material(self.material.as_ref())?.unwrap_or(0);
        let err = cx.err();
        cx.b.add_sphere(Sphere::new(Vec3::from(self.center), self.radius), m)
            .map_err(err)?;
        Ok(())
    }
}

impl PlaneDesc {
    /// Adds the plane.
    pub(super) fn add(&self, cx: &mut ObjectCx) -> Result<(), LoadError> {
        let m = cx.material(self.material.as_ref())?.unwrap_or(0);
        let err = cx.err();
        cx.b.add_plane(Vec3::from(self.point), Vec3::from(self.normal), m)
            .map_err(err)?;
        Ok(())
    }
}
