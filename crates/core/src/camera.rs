//! The pinhole camera.

use crate::Aabb;
use crate::Ray;
use glam::Vec3;

/// A pinhole camera: position, point looked at, up vector and vertical field of view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// The eye.
    pub position: Vec3,
    /// The point at the image centre.
    pub look_at: Vec3,
    /// Up direction (need not be orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view in degrees, in `(0, 180)`.
    pub vfov_degrees: f32,
}

/// A camera with the name a scene gives it (`--camera NAME` picks it).
#[derive(Clone, Debug, PartialEq)]
pub struct NamedCamera {
    /// Its name: the scene file's `name`, a glTF camera's name, or a generated one
    /// (`camera`, `camera 2`, `auto` for the camera framing the geometry).
    pub name: String,
    /// The camera.
    pub camera: Camera,
}

/// Adjustments to a camera from the command line (`--look-from`, `--look-at`, `--up`,
/// `--fov`): each one given replaces the camera's own value.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CameraOverrides {
    /// New eye position.
    pub position: Option<Vec3>,
    /// New point at the image centre.
    pub look_at: Option<Vec3>,
    /// New up direction.
    pub up: Option<Vec3>,
    /// New vertical field of view in degrees.
    pub vfov_degrees: Option<f32>,
}

impl CameraOverrides {
    /// True when nothing is overridden.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }

    /// `camera` with the overridden values replaced, checked.
    ///
    /// # Errors
    /// When the result cannot produce rays ([`Camera::check`] says why).
    pub fn apply(&self, camera: Camera) -> Result<Camera, String> {
        let c = Camera {
            position: self.position.unwrap_or(camera.position),
            look_at: self.look_at.unwrap_or(camera.look_at),
            up: self.up.unwrap_or(camera.up),
            vfov_degrees: self.vfov_degrees.unwrap_or(camera.vfov_degrees),
        };
        c.check()?;
        Ok(c)
    }
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            position: Vec3::new(0.0, 0.0, 5.0),
            look_at: Vec3::ZERO,
            up: Vec3::Y,
            vfov_degrees: 45.0,
        }
    }
}

impl Camera {
    /// A camera framing `bounds` from the front-right-above (the automatic camera of bare
    /// mesh files): looking at the centre from a distance at which the bounding sphere fits
    /// the field of view.
    #[must_use]
    pub fn framing(bounds: Aabb) -> Self {
        if bounds.is_empty() || !bounds.extent().is_finite() {
            return Self::default();
        }
        let center = bounds.center();
        let radius = (bounds.extent().length() * 0.5).max(1e-3);
        let vfov_degrees = 40.0f32;
        let distance = radius / (vfov_degrees.to_radians() * 0.5).sin() * 1.05;
        let dir = Vec3::new(0.45, 0.35, 1.0).normalize();
        Self {
            position: center + dir * distance,
            look_at: center,
            up: Vec3::Y,
            vfov_degrees,
        }
    }

    /// True when the camera can produce rays: finite vectors, eye and target within
    /// [`crate::limits::MAX_COORDINATE`], distinct eye and target, an up vector not parallel
    /// to the view direction, and a field of view in `(0, 180)`.
    #[must_use]
    pub fn is_valid(&self) -> bool {
        self.check().is_ok()
    }

    /// Checks that the camera can produce rays, as [`Camera::is_valid`].
    ///
    /// # Errors
    /// The first condition that fails, in words, with the values involved.
    pub fn check(&self) -> Result<(), String> {
        for (name, v) in [
            ("position", self.position),
            ("look_at", self.look_at),
            ("up", self.up),
        ] {
            if !v.is_finite() {
                return Err(format!("{name} {v} is not finite"));
            }
        }
        // Points as every coordinate of a scene: within the f32 range the geometry resolves.
        for (name, v) in [("position", self.position), ("look_at", self.look_at)] {
            let largest = v.abs().max_element();
            if largest > crate::limits::MAX_COORDINATE {
                return Err(format!(
                    "{name} has a coordinate of magnitude {largest:e}, over the limit of {:e}",
                    crate::limits::MAX_COORDINATE
                ));
            }
        }
        let forward = self.look_at - self.position;
        if forward.length_squared() <= 0.0 {
            return Err(format!(
                "position and look_at are the same point {}",
                self.position
            ));
        }
        if forward.cross(self.up).length_squared() <= 0.0 {
            return Err(format!(
                "up {} is zero or parallel to the view direction {forward}",
                self.up
            ));
        }
        if !(self.vfov_degrees > 0.0 && self.vfov_degrees < 180.0) {
            return Err(format!(
                "fov {} is outside (0, 180) degrees",
                self.vfov_degrees
            ));
        }
        Ok(())
    }

    /// The ray generator for a `width x height` image.
    #[must_use]
    pub fn rays(&self, width: u32, height: u32) -> CameraRays {
        let forward = (self.look_at - self.position).normalize_or(-Vec3::Z);
        let right = forward.cross(self.up).normalize_or(Vec3::X);
        let up = right.cross(forward);
        let half_h = (self.vfov_degrees.to_radians() * 0.5).tan();
        let aspect = width as f32 / height.max(1) as f32;
        CameraRays {
            origin: self.position,
            forward,
            right: right * (half_h * aspect),
            up: up * half_h,
            inv_width: 1.0 / width.max(1) as f32,
            inv_height: 1.0 / height.max(1) as f32,
        }
    }
}

/// Primary-ray generator of a [`Camera`] for one image size.
#[derive(Clone, Copy, Debug)]
pub struct CameraRays {
    /// The eye.
    pub origin: Vec3,
    /// Unit view direction.
    pub forward: Vec3,
    /// Right, scaled to half the image width at unit distance.
    pub right: Vec3,
    /// Up, scaled to half the image height at unit distance.
    pub up: Vec3,
    /// `1 / width`.
    pub inv_width: f32,
    /// `1 / height`.
    pub inv_height: f32,
}

impl CameraRays {
    /// The ray through image position `(px, py)` in pixels, `(0, 0)` the top-left corner of
    /// the image: the centre of pixel `(x, y)` is `(x + 0.5, y + 0.5)`. The direction is
    /// normalised, so `t` is a distance.
    #[inline]
    #[must_use]
    pub fn ray(&self, px: f32, py: f32) -> Ray {
        let sx = 2.0 * px * self.inv_width - 1.0;
        let sy = 1.0 - 2.0 * py * self.inv_height;
        let dir = (self.forward + self.right * sx + self.up * sy).normalize();
        Ray::new(self.origin, dir)
    }

    /// The primary ray through the centre of pixel `(x, y)`.
    #[inline]
    #[must_use]
    pub fn center_ray(&self, x: u32, y: u32) -> Ray {
        self.ray(x as f32 + 0.5, y as f32 + 0.5)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_pixel_looks_at_target() {
        let cam = Camera::default();
        let rays = cam.rays(3, 3);
        let r = rays.center_ray(1, 1);
        assert!((r.dir - -Vec3::Z).length() < 1e-6);
        // Top-left pixel points up and left.
        let r = rays.center_ray(0, 0);
        assert!(r.dir.x < 0.0 && r.dir.y > 0.0);
    }

    #[test]
    fn validity() {
        assert!(Camera::default().is_valid());
        let c = Camera {
            up: Vec3::Z,
            ..Camera::default()
        };
        assert!(!c.is_valid());
        let c = Camera {
            vfov_degrees: 0.0,
            ..Camera::default()
        };
        assert!(!c.is_valid());
        assert!(Camera::framing(Aabb::new(Vec3::ZERO, Vec3::ONE)).is_valid());
    }

    #[test]
    fn overrides_replace_only_what_is_given_and_are_checked() {
        let cam = Camera::default();
        assert!(CameraOverrides::default().is_empty());
        assert_eq!(CameraOverrides::default().apply(cam), Ok(cam));
        let o = CameraOverrides {
            vfov_degrees: Some(30.0),
            look_at: Some(Vec3::X),
            ..Default::default()
        };
        let c = o.apply(cam).unwrap();
        assert_eq!((c.vfov_degrees, c.look_at), (30.0, Vec3::X));
        assert_eq!((c.position, c.up), (cam.position, cam.up));
        let bad = CameraOverrides {
            look_at: Some(cam.position),
            ..Default::default()
        };
        assert!(bad.apply(cam).unwrap_err().contains("same point"));
        let bad = CameraOverrides {
            vfov_degrees: Some(180.0),
            ..Default::default()
        };
        assert!(bad.apply(cam).unwrap_err().contains("fov"));
    }
}
