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

/// The options raybench loads OBJ files with: polygons triangulated as fans, points and
/// lines ignored, one index per attribute.
const OBJ_OPTIONS: tobj::LoadOptions = tobj::LoadOptions {
    single_index: false,
    triangulate: true,
    ignore_points: true,
    ignore_lines: true,
};

/// Loads an OBJ file (and its MTL, if readable) into triangles in file order: `tobj`
/// triangulates polygons as fans, so a quad splits along its first diagonal. A missing or
/// unreadable MTL file means "no materials" (default material), as SOURCES.md asks.
///
/// # Errors
/// When the file is missing, malformed, has out-of-range indices or non-finite coordinates.
pub fn load_obj_file(path: &Path) -> Result<MeshData, LoadError> {
    if !path.is_file() {
        return Err(LoadError::NotFound {
            path: path.to_owned(),
        });
    }
    let bytes = std::fs::read(path).map_err(|source| LoadError::Io {
        path: path.to_owned(),
        source,
    })?;
    let dir = path.parent().unwrap_or(Path::new("."));
    parse_obj(&bytes, path, |mtl| tobj::load_mtl(dir.join(mtl)))
}

/// Parses OBJ text from memory (`path` names it in errors); `mtllib` statements load no
/// materials. The fuzz targets and property tests use it; [`load_obj_file`] shares its code.
///
/// # Errors
/// As [`load_obj_file`], less the file errors.
#[doc(hidden)]
pub fn load_obj_bytes(bytes: &[u8], path: &Path) -> Result<MeshData, LoadError> {
    parse_obj(bytes, path, |_| Err(tobj::LoadError::OpenFileFailed))
}

/// Refuses face, line and point elements with an index beyond `u32` in magnitude or a
/// relative (negative) index reaching before the first element: `tobj` turns the latter
/// into huge indices and multiplies texture and normal indices unchecked (an overflow, a
/// panic in debug builds). No mesh has more than `u32::MAX` vertices.
fn check_index_magnitudes(bytes: &[u8], path: &Path) -> Result<(), LoadError> {
    // Positions, texture coordinates and normals seen so far.
    let mut counts = [0u64; 3];
    for (n, line) in bytes.split(|&b| b == b'\n').enumerate() {
        // Lines that are not UTF-8 are refused by `tobj` itself.
        let Ok(line) = std::str::from_utf8(line) else {
            continue;
        };
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => counts[0] += 1,
            Some("vt") => counts[1] += 1,
            Some("vn") => counts[2] += 1,
            Some("f" | "l" | "p") => {
                let bad = words.any(|w| {
                    w.split('/').zip(counts).any(|(i, count)| {
                        i.parse::<i64>().is_ok_and(|i| {
                            i.unsigned_abs() > u64::from(u32::MAX)
                                || (i < 0 && i.unsigned_abs() > count)
                        })
                    })
                });
                if bad {
                    return Err(LoadError::Parse {
                        path: path.to_owned(),
                        message: format!("line {}: a vertex index is out of bounds", n + 1),
                    });
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// Parses OBJ text, with `mtl` loading the material libraries it names.
fn parse_obj(
    bytes: &[u8],
    path: &Path,
    mtl: impl Fn(&Path) -> tobj::MTLLoadResult,
) -> Result<MeshData, LoadError> {
    check_index_magnitudes(bytes, path)?;
    let (models, materials) =
        tobj::load_obj_buf(&mut { bytes }, &OBJ_OPTIONS, mtl).map_err(|e| LoadError::Parse {
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
    // Finite coordinates can still exceed the coordinate limit (`1e30`).
    data.mesh.validate().map_err(|e| LoadError::Parse {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    Ok(data)
}
