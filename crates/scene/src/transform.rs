//! Object placement.

use glam::{Affine3A, EulerRot, Quat, Vec3};

/// Scale, then rotate (degrees about x, then y, then z), then translate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Per-axis scale.
    pub scale: Vec3,
    /// Rotation in degrees about x, y and z, applied in that order.
    pub rotate_degrees: Vec3,
    /// Translation.
    pub translate: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Self {
            scale: Vec3::ONE,
            rotate_degrees: Vec3::ZERO,
            translate: Vec3::ZERO,
        }
    }
}

impl Transform {
    /// The affine map.
    #[must_use]
    pub fn affine(&self) -> Affine3A {
        Affine3A::from_scale_rotation_translation(self.scale, self.rotation(), self.translate)
    }

    /// The rotation: about x, then y, then z.
    #[must_use]
    pub fn rotation(&self) -> Quat {
        let r = self.rotate_degrees;
        Quat::from_euler(
            EulerRot::ZYX,
            r.z.to_radians(),
            r.y.to_radians(),
            r.x.to_radians(),
        )
    }

    /// True for the identity (nothing to apply).
    #[must_use]
    pub fn is_identity(&self) -> bool {
        *self == Self::default()
    }
}
