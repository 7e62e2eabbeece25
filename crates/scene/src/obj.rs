//! OBJ+MTL meshes through `tobj`.

use crate::error::LoadError;
use raybench_core::{Material, MaterialKind, NamedCamera, TriangleMesh, Vec2, Vec3};
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
    /// Per vertex (indexed like `mesh.positions`), the file's vertex normal; empty when the
    /// file has none.
    pub normals: Vec<Vec3>,
    /// Per vertex (indexed like `mesh.positions`), the file's texture coordinates; empty
    /// when the file has none.
    pub uvs: Vec<Vec2>,
    /// Cameras the file defines (glTF), in node order; a bare mesh scene renders the first.
    pub cameras: Vec<NamedCamera>,
    /// What is legal but surely not meant (self-intersecting polygons), one sentence each.
    pub warnings: Vec<String>,
}

/// The warning for the self-intersecting faces `bad` (0-based, at least one) of an
/// object: how many, the first, and what happens to them.
pub(crate) fn self_intersecting(bad: &[usize]) -> String {
    let first = bad.first().map_or(0, |f| f + 1);
    let which = if bad.len() == 1 {
        format!("face {first} is")
    } else {
        format!("{} faces (the first: face {first}) are", bad.len())
    };
    format!(
        "{which} self-intersecting (or concave with more than {} vertices): fanned from \
         the first vertex, which matches no fill rule",
        raybench_core::MAX_EAR_CLIP_VERTICES
    )
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

/// The options raybench loads OBJ files with: polygons kept whole (raybench triangulates
/// them: [`raybench_core::triangulate_polygon`]), points and lines ignored, one index per
/// attribute.
const OBJ_OPTIONS: tobj::LoadOptions = tobj::LoadOptions {
    single_index: false,
    triangulate: false,
    ignore_points: true,
    ignore_lines: true,
};

/// Loads an OBJ file (and its MTL, if readable) into triangles in file order. Polygons
/// become `n - 2` triangles each ([`raybench_core::triangulate_polygon`]): convex ones
/// as fans from their first vertex (a quad splits along its first diagonal), simple
/// non-convex ones by ear clipping, self-intersecting ones as fans with a warning. A
/// missing or unreadable MTL file means "no materials" (default material), as SOURCES.md
/// asks.
///
/// # Errors
/// When the file is missing, malformed, has out-of-range indices or non-finite coordinates.
pub fn load_obj_file(path: &Path) -> Result<MeshData, LoadError> {
    crate::check_regular_file(path)?;
    let bytes = std::fs::read(path).map_err(|cause| LoadError::Io {
        path: path.to_owned(),
        cause,
    })?;
    let dir = path.parent().unwrap_or(Path::new("."));
    parse_obj(&bytes, path, |mtl| load_mtl(&dir.join(mtl)))
}

/// Largest MTL file read (material libraries are small text files).
const MAX_MTL_BYTES: u64 = 16 << 20;

/// Reads an MTL file as `tobj` would, but through [`crate::format::read_text`]: a regular
/// file of bounded size, with a byte-order mark accepted.
fn load_mtl(path: &Path) -> tobj::MTLLoadResult {
    let text = crate::format::read_text(path, MAX_MTL_BYTES, "material library")
        .map_err(|_| tobj::LoadError::OpenFileFailed)?;
    tobj::load_mtl_buf(&mut text.as_bytes())
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
    let bytes = crate::strip_bom(bytes);
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
        if !m.positions.len().is_multiple_of(3)
            || (m.face_arities.is_empty() && !m.indices.len().is_multiple_of(3))
        {
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
        if m.indices.iter().any(|&i| u64::from(i) >= count) {
            return Err(LoadError::Parse {
                path: path.to_owned(),
                message: format!("object '{}' has a face index out of range", model.name),
            });
        }
        let local = &data.mesh.positions[base as usize..];
        let mut triangles = Vec::with_capacity(m.indices.len() / 3);
        // No arities: every face is a triangle.
        let arities: Box<dyn Iterator<Item = usize>> = if m.face_arities.is_empty() {
            Box::new(std::iter::repeat_n(3, m.indices.len() / 3))
        } else {
            Box::new(m.face_arities.iter().map(|&k| k as usize))
        };
        let mut start = 0;
        let mut bad = Vec::new();
        for (face, k) in arities.enumerate() {
            let Some(f) = m.indices.get(start..start + k) else {
                return Err(LoadError::Parse {
                    path: path.to_owned(),
                    message: format!("object '{}' has incomplete face data", model.name),
                });
            };
            start += k;
            if raybench_core::triangulate_polygon(local, f, &mut triangles)
                == raybench_core::PolygonKind::SelfIntersecting
            {
                bad.push(face);
            }
        }
        if !bad.is_empty() {
            data.warnings.push(format!(
                "{}: object '{}': {}",
                path.display(),
                model.name,
                self_intersecting(&bad)
            ));
        }
        let b = base as u32;
        for t in triangles {
            data.mesh.indices.push(t.map(|i| i + b));
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
