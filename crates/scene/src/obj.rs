//! OBJ+MTL meshes through `tobj`.

use crate::error::LoadError;
use raybench_core::{Material, MaterialKind, TriangleMesh, Vec3};
use std::path::Path;

/// A loaded mesh with its materials: the shared shape of OBJ and glTF results.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    /// Positions and triangles, in file order.
    pub mesh: TriangleMesh,
    /// Materials defined by the file.
    pub materials: Vec<Material>,
    /// Per triangle, an index into `materials`, or `None` for the default material.
    pub triangle_material: Vec<Option<u32>>,
}

/// Maps an MTL material onto raybench's model (documented in `docs/scene-format.md`):
/// `Kd` base colour, `Ks` specular, `Ns` shininess, `Ke` emission, `Ni` index of refraction;
/// `illum` 3 (reflection) is a mirror, 4, 6 and 7 (refraction) are glass, others diffuse.
#[must_use]
pub fn material_from_mtl(m: &tobj::Material) -> Material {
    let v = |a: Option<[f32; 3]>| a.map(Vec3::from);
    let emission = v(m.emissive)
        .or_else(|| {
            // Older tobj versions keep Ke among the unknown parameters.
            m.unknown_param.get("Ke").and_then(|s| {
                let p: Vec<f32> = s
                    .split_whitespace()
                    .filter_map(|x| x.parse().ok())
                    .collect();
                (p.len() == 3).then(|| Vec3::new(p[0], p[1], p[2]))
            })
        })
        .unwrap_or(Vec3::ZERO);
    let kind = match m.illumination_model {
        Some(3) => MaterialKind::Mirror,
        Some(4 | 6 | 7) => MaterialKind::Glass,
        _ => MaterialKind::Diffuse,
    };
    let d = Material::default();
    Material {
        name: m.name.clone(),
        kind,
        base_color: v(m.diffuse).unwrap_or(d.base_color),
        // Mirrors and glass without Ks reflect fully (as in the TOML format).
        specular: v(m.specular).unwrap_or(if kind == MaterialKind::Diffuse {
            d.specular
        } else {
            Vec3::ONE
        }),
        shininess: m.shininess.unwrap_or(d.shininess),
        emission,
        ior: m.optical_density.filter(|&n| n > 0.0).unwrap_or(d.ior),
        checker: None,
    }
}

/// Loads an OBJ file (and its MTL, if readable) into triangles in file order: `tobj`
/// triangulates polygons as fans, so a quad splits along its first diagonal. A missing or
/// unreadable MTL file means "no materials" (default material), as SOURCES.md asks.
///
/// # Errors
/// When the file is missing, malformed, has out-of-range indices or non-finite coordinates.
pub fn load_obj_file(path: &Path) -> Result<MeshData, LoadError> {
    let opts = tobj::LoadOptions {
        single_index: false,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    if !path.is_file() {
        return Err(LoadError::NotFound {
            path: path.to_owned(),
        });
    }
    let (models, materials) = tobj::load_obj(path, &opts).map_err(|e| LoadError::Parse {
        path: path.to_owned(),
        message: format!("malformed OBJ: {e}"),
    })?;
    let materials: Vec<Material> = materials
        .map(|ms| ms.iter().map(material_from_mtl).collect())
        .unwrap_or_default();

    let mut data = MeshData {
        materials,
        ..Default::default()
    };
    for model in &models {
        let m = &model.mesh;
        if !m.positions.len().is_multiple_of(3) || !m.indices.len().is_multiple_of(3) {
            return Err(LoadError::Parse {
                path: path.to_owned(),
                message: format!("object '{}' has incomplete vertex or face data", model.name),
            });
        }
        let base = data.mesh.positions.len() as u64;
        let count = (m.positions.len() / 3) as u64;
        if base + count > u64::from(u32::MAX) {
            return Err(LoadError::Parse {
                path: path.to_owned(),
                message: "too many vertices".into(),
            });
        }
        for p in m.positions.chunks_exact(3) {
            let p = Vec3::new(p[0], p[1], p[2]);
            if !p.is_finite() {
                return Err(LoadError::Parse {
                    path: path.to_owned(),
                    message: format!("object '{}' has a non-finite vertex coordinate", model.name),
                });
            }
            data.mesh.positions.push(p);
        }
        let material = m
            .material_id
            .filter(|&id| id < data.materials.len())
            .map(|id| id as u32);
        for f in m.indices.chunks_exact(3) {
            if f.iter().any(|&i| u64::from(i) >= count) {
                return Err(LoadError::Parse {
                    path: path.to_owned(),
                    message: format!("object '{}' has a face index out of range", model.name),
                });
            }
            let b = base as u32;
            data.mesh.indices.push([f[0] + b, f[1] + b, f[2] + b]);
            data.triangle_material.push(material);
        }
    }
    Ok(data)
}
