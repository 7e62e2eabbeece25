//! The `[[light]]` tables of the scene format.

use super::V3;
use raybench_core::{Light, Vec3};
use serde::Deserialize;

/// A `[[light]]` table, by its `kind`.
#[derive(Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub(super) enum LightDesc {
    Point(PointLightDesc),
    Directional(DirectionalLightDesc),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PointLightDesc {
    position: V3,
    intensity: V3,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DirectionalLightDesc {
    direction: V3,
    radiance: V3,
}

impl LightDesc {
    /// The light; the scene builder checks it.
    pub(super) fn light(&self) -> Light {
        match self {
            Self::Point(p) => Light::Point {
                position: Vec3::from(p.position),
                intensity: Vec3::from(p.intensity),
            },
            Self::Directional(d) => Light::Directional {
                direction: Vec3::from(d.direction),
                radiance: Vec3::from(d.radiance),
            },
        }
    }
}
