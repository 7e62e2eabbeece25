//! The `[camera]` table, or the `[[camera]]` list, of the scene format.

use super::V3;
use raybench_core::{Camera, Vec3};
use serde::Deserialize;

/// A `[camera]` table or one `[[camera]]` entry: a pinhole camera at `position` looking
/// at `look_at`, optionally named (for `--camera NAME`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraDesc {
    pub(super) name: Option<String>,
    position: V3,
    look_at: V3,
    up: Option<V3>,
    fov: Option<f32>,
}

impl CameraDesc {
    /// The camera (`up` defaults to +y, the vertical field of view to 45 degrees); the
    /// scene builder checks it.
    pub(super) fn camera(&self) -> Camera {
        Camera {
            position: Vec3::from(self.position),
            look_at: Vec3::from(self.look_at),
            up: self.up.map_or(Vec3::Y, Vec3::from),
            vfov_degrees: self.fov.unwrap_or(45.0),
        }
    }
}
