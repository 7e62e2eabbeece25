//! The `[[material]]` tables of the scene format.

use super::V3;
use raybench_core::{Material, MaterialKind, Vec3};
use serde::Deserialize;

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum KindDesc {
    Diffuse,
    Mirror,
    Glass,
}

/// A `[[material]]` table; objects refer to it by `name`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MaterialDesc {
    pub(super) name: String,
    kind: Option<KindDesc>,
    color: Option<V3>,
    specular: Option<V3>,
    shininess: Option<f32>,
    emission: Option<V3>,
    ior: Option<f32>,
    checker: Option<CheckerDesc>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CheckerDesc {
    color: V3,
    size: f32,
}

impl MaterialDesc {
    /// The material, with [`Material::default`]'s values for what the table leaves out
    /// (but a white specular colour for mirrors and glass); the scene builder checks it.
    pub(super) fn material(&self) -> Material {
        let d = Material::default();
        let kind = match self.kind.unwrap_or(KindDesc::Diffuse) {
            KindDesc::Diffuse => MaterialKind::Diffuse,
            KindDesc::Mirror => MaterialKind::Mirror,
            KindDesc::Glass => MaterialKind::Glass,
        };
        Material {
            name: self.name.clone(),
            kind,
            base_color: self.color.map_or(d.base_color, Vec3::from),
            specular: self.specular.map_or(
                if kind == MaterialKind::Diffuse {
                    d.specular
                } else {
                    Vec3::ONE
                },
                Vec3::from,
            ),
            shininess: self.shininess.unwrap_or(d.shininess),
            emission: self.emission.map_or(d.emission, Vec3::from),
            ior: self.ior.unwrap_or(d.ior),
            checker: self.checker.as_ref().map(|c| raybench_core::Checker {
                color: Vec3::from(c.color),
                size: c.size,
            }),
            base_color_texture: None,
            emission_texture: None,
        }
    }
}
