//! OBJ+MTL meshes through `tobj`.

use crate::error::LoadError;
use crate::texture::{ImageSource, TextureRef};
use raybench_core::{Material, MaterialKind, NamedCamera, TriangleMesh, Vec2, Vec3, Wrap};
use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

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
    /// Per vertex (indexed like `mesh.positions`), the file's texture coordinates (glTF's
    /// convention: `v` counts down from the image's top row); empty when the file has none.
    pub uvs: Vec<Vec2>,
    /// Cameras the file defines (glTF), in node order; a bare mesh scene renders the first.
    pub cameras: Vec<NamedCamera>,
    /// The textures the materials name: a material's `base_color_texture` and
    /// `emission_texture` index this list (not yet the scene's textures; they are decoded
    /// when the mesh is added to a scene).
    pub textures: Vec<TextureRef>,
    /// What is legal but surely not meant (self-intersecting polygons), one sentence each.
    pub warnings: Vec<String>,
    /// Meshes the file places more than once (glTF meshes referenced by several nodes),
    /// each stored once in its own space, to become instances; `mesh` above holds the
    /// rest, placed.
    pub shared: Vec<SharedMesh>,
}

/// A mesh a file places several times: its triangles once, in the mesh's own space, and
/// where each copy goes.
#[derive(Clone, Debug, Default)]
pub struct SharedMesh {
    /// A name for messages (`glTF mesh 3 'wheel'`).
    pub name: String,
    /// Its triangles and vertex attributes. Its `triangle_material` indexes the
    /// enclosing [`MeshData::materials`]; its own `materials` and `textures` are empty.
    pub data: MeshData,
    /// Each placement's transform (mesh space to the file's space), in node order.
    pub placements: Vec<glam::Affine3A>,
}

impl SharedMesh {
    /// Its triangles placed by every placement in turn, as one mesh in the file's space
    /// (vertex normals through each placement's inverse transpose): the copy a file gets
    /// where its mesh cannot be instanced.
    #[must_use]
    pub fn copied(&self) -> MeshData {
        let mut out = MeshData::default();
        for p in &self.placements {
            let base = out.mesh.positions.len() as u32;
            out.mesh.positions.extend(
                self.data
                    .mesh
                    .positions
                    .iter()
                    .map(|&v| p.transform_point3(v)),
            );
            let n = p.matrix3.inverse().transpose();
            out.normals.extend(self.data.normals.iter().map(|&v| n * v));
            out.uvs.extend_from_slice(&self.data.uvs);
            out.mesh
                .indices
                .extend(self.data.mesh.indices.iter().map(|t| t.map(|i| i + base)));
            out.triangle_material
                .extend_from_slice(&self.data.triangle_material);
        }
        out
    }
}

impl MeshData {
    /// Extends the non-empty attribute lists to one entry per vertex: vertices of parts
    /// without normals get zero normals (their triangles are shaded with the geometric
    /// normal), those without texture coordinates `(0, 0)`.
    pub(crate) fn pad_attributes(&mut self) {
        let vertices = self.mesh.positions.len();
        if !self.normals.is_empty() {
            self.normals.resize(vertices, Vec3::ZERO);
        }
        if !self.uvs.is_empty() {
            self.uvs.resize(vertices, Vec2::ZERO);
        }
    }
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
        // As in scene files, an index of refraction that is not above 0 is refused (by
        // the scene builder), not replaced.
        ior: m.optical_density.unwrap_or(d.ior),
        checker: None,
        base_color_texture: None,
        emission_texture: None,
    }
}

/// The image file and wrap mode of an MTL texture statement's value (`map_Kd -clamp on
/// wood.png`): options are skipped (`-clamp on` clamps to the edge), backslashes become
/// slashes, the rest is the file name, relative to the MTL file's folder `dir`.
fn mtl_texture(value: &str, dir: &Path) -> Option<TextureRef> {
    let mut words = value.split_whitespace().peekable();
    let mut wrap = Wrap::Repeat;
    while let Some(option) = words.next_if(|w| w.starts_with('-')) {
        let numbers = match option {
            "-o" | "-s" | "-t" => 3,
            "-mm" => 2,
            "-clamp" => {
                if words.next() == Some("on") {
                    wrap = Wrap::ClampToEdge;
                }
                0
            }
            _ => 1,
        };
        for _ in 0..numbers {
            // `-o`, `-s` and `-t` take one to three numbers.
            if words.next_if(|w| w.parse::<f32>().is_ok()).is_none() {
                break;
            }
        }
    }
    let file = words.collect::<Vec<_>>().join(" ").replace('\\', "/");
    (!file.is_empty()).then(|| TextureRef {
        name: file.clone(),
        source: ImageSource::File(dir.join(&file)),
        wrap: [wrap; 2],
    })
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
    crate::io::check_regular_file(path)?;
    let bytes = std::fs::read(path).map_err(|cause| LoadError::Io {
        path: path.to_owned(),
        cause,
    })?;
    parse_obj_with_mtl(&bytes, path, |mtl| {
        crate::io::read_text(mtl, MAX_MTL_BYTES, "material library").ok()
    })
}

/// Parses OBJ bytes (`path` names them; `mtllib` files are relative to its folder) whose
/// material libraries `read_mtl` gives as text (`None`: unreadable, "no materials"):
/// [`load_obj_file`] reads them from files, the fuzz targets from memory.
pub(crate) fn parse_obj_with_mtl(
    bytes: &[u8],
    path: &Path,
    read_mtl: impl Fn(&Path) -> Option<String>,
) -> Result<MeshData, LoadError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    // The folder of each material's MTL file, in material order (map_Kd is relative to it).
    let mtl_dirs = RefCell::new(Vec::new());
    // A malformed material library is an error naming its line (tobj would panic on some
    // faults and turn the others into "no materials"); tobj's loader callback can only
    // say that it failed, so the error waits here.
    let mtl_fault = RefCell::new(None);
    let data = parse_obj(
        bytes,
        path,
        |mtl| {
            let mtl = dir.join(mtl);
            let result = match load_mtl(&mtl, read_mtl(&mtl)) {
                Ok(result) => result,
                Err(fault) => {
                    mtl_fault.borrow_mut().get_or_insert(fault);
                    return Err(tobj::LoadError::MaterialParseError);
                }
            };
            if let Ok((ms, _)) = &result {
                let mtl_dir = mtl.parent().map_or_else(|| dir.to_owned(), Path::to_owned);
                mtl_dirs
                    .borrow_mut()
                    .extend(ms.iter().map(|_| mtl_dir.clone()));
            }
            result
        },
        |i| mtl_dirs.borrow().get(i).cloned(),
    );
    match mtl_fault.into_inner() {
        Some(fault) => Err(fault),
        None => data,
    }
}

/// Largest MTL file read (material libraries are small text files).
const MAX_MTL_BYTES: u64 = 16 << 20;

/// Parses the MTL file `path` as `tobj` would, from its `text` (read through
/// [`crate::io::read_text`]: a regular file of bounded size, with a byte-order mark
/// accepted). An unreadable file (`None`) gives tobj's "no materials"; a malformed one,
/// checked before tobj parses it ([`check_mtl`]), the error naming its line.
fn load_mtl(path: &Path, text: Option<String>) -> Result<tobj::MTLLoadResult, LoadError> {
    let Some(text) = text else {
        return Ok(Err(tobj::LoadError::OpenFileFailed));
    };
    let text = crate::io::lone_cr_to_lf(text.as_bytes());
    let text = String::from_utf8_lossy(&text);
    check_mtl(&text).map_err(|message| LoadError::Parse {
        path: path.to_owned(),
        message: format!("malformed material library: {message}"),
    })?;
    Ok(tobj::load_mtl_buf(&mut text.as_bytes()))
}

/// The statements of an MTL file that tobj parses, checked as it would parse them: each
/// colour (`Ka`, `Kd`, `Ks`, `Ke`) exactly three finite numbers, `Ns`, `Ni` and `d` one,
/// `illum` one whole number, `newmtl` and every map a name; and the values as scene files
/// check them: `Ns` (shininess) at least 0 and `Ni` (index of refraction) above 0. The
/// first fault, with its line.
fn check_mtl(text: &str) -> Result<(), String> {
    let numbers = |key: &str, args: &[&str], n: usize| {
        let ok = args.len() == n
            && args
                .iter()
                .all(|a| a.parse::<f32>().is_ok_and(f32::is_finite));
        (!ok).then(|| {
            format!(
                "`{key}` needs {n} finite number{}, found `{}`",
                if n == 1 { "" } else { "s" },
                args.join(" ")
            )
        })
    };
    // One finite number within a range, for the field `name`.
    let bounded = |key: &str, args: &[&str], name: &str, ok: fn(f32) -> bool, range: &str| {
        numbers(key, args, 1).or_else(|| {
            let v: f32 = args[0].parse().unwrap_or(f32::NAN);
            (!ok(v)).then(|| format!("`{key}` ({name}) must be {range}, found `{}`", args[0]))
        })
    };
    for (i, line) in text.lines().enumerate() {
        // A comment may follow a statement (`Ka 0.63 0.065 0.05 # Red`, in the Cornell
        // box's library).
        let statement = line.split_once('#').map_or(line, |(s, _)| s);
        let mut words = statement.split_whitespace();
        let Some(key) = words.next() else { continue };
        let args: Vec<&str> = words.collect();
        let fault = match key {
            "Ka" | "Kd" | "Ks" | "Ke" => numbers(key, &args, 3),
            "Ns" => bounded(key, &args, "shininess", |v| v >= 0.0, "at least 0"),
            "Ni" => bounded(key, &args, "index of refraction", |v| v > 0.0, "above 0"),
            "d" => numbers(key, &args, 1),
            "illum" => (args.len() != 1 || args[0].parse::<u32>().is_err())
                .then(|| format!("`illum` needs one whole number, found `{}`", args.join(" "))),
            "newmtl" => args.is_empty().then(|| "`newmtl` needs a name".to_string()),
            "bump" | "map_Ka" | "map_Kd" | "map_Ks" | "map_Bump" | "map_bump" | "map_Ns"
            | "map_ns" | "map_NS" | "map_d" => args
                .is_empty()
                .then(|| format!("`{key}` needs a file name")),
            _ => None,
        };
        if let Some(fault) = fault {
            return Err(format!("line {}: {fault}", i + 1));
        }
    }
    Ok(())
}

/// Parses OBJ text from memory (`path` names it in errors); `mtllib` statements load no
/// materials. The fuzz targets and property tests use it; [`load_obj_file`] shares its code.
///
/// # Errors
/// As [`load_obj_file`], less the file errors.
#[doc(hidden)]
pub fn load_obj_bytes(bytes: &[u8], path: &Path) -> Result<MeshData, LoadError> {
    parse_obj(
        bytes,
        path,
        |_| Err(tobj::LoadError::OpenFileFailed),
        |_| None,
    )
}

/// Refuses face, line and point elements with an index beyond `u32` in magnitude or a
/// relative (negative) index reaching before the first element: `tobj` turns the latter
/// into huge indices and multiplies texture and normal indices unchecked (an overflow, a
/// panic in debug builds). No mesh has more than `u32::MAX` vertices. Refuses faces of
/// fewer than three vertices too, as PLY and scene files do (`tobj` drops them unsaid).
fn check_elements(bytes: &[u8], path: &Path) -> Result<(), LoadError> {
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
            Some(key @ ("f" | "l" | "p")) => {
                let corners = words.clone().count();
                if key == "f" && corners < 3 {
                    return Err(LoadError::Parse {
                        path: path.to_owned(),
                        message: format!(
                            "line {}: a face needs at least 3 vertices, found {corners}",
                            n + 1
                        ),
                    });
                }
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

/// Gives each distinct (position, texture coordinate, normal) triple of an object's face
/// corners a vertex of its own, when the object has normals or texture coordinates (OBJ
/// indexes them separately, `MeshData` per vertex): a position keeps its index for the
/// first triple that uses it, later different triples get copies appended to
/// `data.mesh.positions`, which already holds the object's positions from `base` on. The
/// normals and texture coordinates go to `data.normals` and `data.uvs` (`v` flipped to
/// count down from the image's top row). Returns the faces' corners as vertex indices
/// relative to `base`, or `None` without attributes (the corners are the position indices).
fn weld_attributes(
    m: &tobj::Mesh,
    base: usize,
    data: &mut MeshData,
    object: &str,
    path: &Path,
) -> Result<Option<Vec<u32>>, LoadError> {
    let (has_n, has_t) = (!m.normal_indices.is_empty(), !m.texcoord_indices.is_empty());
    if !has_n && !has_t {
        return Ok(None);
    }
    let bad = |what: &str| LoadError::Parse {
        path: path.to_owned(),
        message: format!("object '{object}' has {what}"),
    };
    if (has_n && m.normal_indices.len() != m.indices.len())
        || (has_t && m.texcoord_indices.len() != m.indices.len())
    {
        return Err(bad("incomplete normal or texture coordinate indices"));
    }
    let normal = |i: u32| {
        let i = i as usize * 3;
        m.normals
            .get(i..i + 3)
            .map(|n| Vec3::new(n[0], n[1], n[2]))
            .ok_or_else(|| bad("a normal index out of range"))
    };
    let uv = |i: u32| {
        let i = i as usize * 2;
        m.texcoords
            .get(i..i + 2)
            .map(|t| Vec2::new(t[0], 1.0 - t[1]))
            .ok_or_else(|| bad("a texture coordinate index out of range"))
    };
    let count = data.mesh.positions.len();
    if has_n {
        data.normals.resize(count, Vec3::ZERO);
    }
    if has_t {
        data.uvs.resize(count, Vec2::ZERO);
    }
    // The (texture coordinate, normal) pair each position's own vertex took.
    let mut owner: Vec<Option<(u32, u32)>> = vec![None; count - base];
    let mut copies: HashMap<(u32, u32, u32), u32> = HashMap::new();
    let mut corners = Vec::with_capacity(m.indices.len());
    for (k, &p) in m.indices.iter().enumerate() {
        let t = if has_t { m.texcoord_indices[k] } else { 0 };
        let n = if has_n { m.normal_indices[k] } else { 0 };
        let slot = owner
            .get_mut(p as usize)
            .ok_or_else(|| bad("a face index out of range"))?;
        let vertex = match *slot {
            Some(pair) if pair == (t, n) => p,
            None => {
                *slot = Some((t, n));
                if has_n {
                    data.normals[base + p as usize] = normal(n)?;
                }
                if has_t {
                    data.uvs[base + p as usize] = uv(t)?;
                }
                p
            }
            Some(_) => match copies.get(&(p, t, n)) {
                Some(&v) => v,
                None => {
                    let v = data.mesh.positions.len() - base;
                    if data.mesh.positions.len() >= u32::MAX as usize {
                        return Err(bad("too many vertices"));
                    }
                    data.mesh
                        .positions
                        .push(data.mesh.positions[base + p as usize]);
                    if has_n {
                        data.normals.push(normal(n)?);
                    }
                    if has_t {
                        data.uvs.push(uv(t)?);
                    }
                    copies.insert((p, t, n), v as u32);
                    v as u32
                }
            },
        };
        corners.push(vertex);
    }
    Ok(Some(corners))
}

/// Parses OBJ text, with `mtl` loading the material libraries it names and `texture_dir`
/// giving the folder textures of material `i` are relative to (its MTL file's).
fn parse_obj(
    bytes: &[u8],
    path: &Path,
    mtl: impl Fn(&Path) -> tobj::MTLLoadResult,
    texture_dir: impl Fn(usize) -> Option<PathBuf>,
) -> Result<MeshData, LoadError> {
    let bytes = crate::io::lone_cr_to_lf(crate::io::strip_bom(bytes));
    let bytes = &bytes[..];
    check_elements(bytes, path)?;
    let (models, materials) =
        tobj::load_obj_buf(&mut { bytes }, &OBJ_OPTIONS, mtl).map_err(|e| LoadError::Parse {
            path: path.to_owned(),
            message: format!("malformed OBJ: {e}"),
        })?;
    let mut data = MeshData::default();
    for (i, m) in materials.unwrap_or_default().iter().enumerate() {
        let mut material = material_from_mtl(m);
        if let Some(value) = &m.diffuse_texture
            && let Some(dir) = texture_dir(i)
            && let Some(texture) = mtl_texture(value, &dir)
        {
            material.base_color_texture = Some(data.textures.len() as u32);
            // The texture is the colour when Kd does not scale it.
            if m.diffuse.is_none() {
                material.base_color = Vec3::ONE;
            }
            data.textures.push(texture);
        }
        data.materials.push(material);
    }
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
        let welded = weld_attributes(m, base as usize, &mut data, &model.name, path)?;
        let corners = welded.as_deref().unwrap_or(&m.indices);
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
            let Some(f) = corners.get(start..start + k) else {
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
    data.pad_attributes();
    // Finite coordinates can still exceed the coordinate limit (`1e30`).
    data.mesh.validate().map_err(|e| LoadError::Parse {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    Ok(data)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh scratch folder `name` for this module's tests.
    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("raybench-obj-{}-{name}", std::process::id()));
        std::fs::remove_dir_all(&d).ok();
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// A triangle whose material library is `mtl`, written in `dir`; the loader's result.
    fn with_mtl(dir: &Path, mtl: &str) -> Result<MeshData, LoadError> {
        std::fs::write(dir.join("m.mtl"), mtl).unwrap();
        let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
        std::fs::write(dir.join("t.obj"), obj).unwrap();
        load_obj_file(&dir.join("t.obj"))
    }

    /// MTL values are refused where scene files refuse them, and the message names the
    /// statement and the field it sets (not another one): no value is silently replaced.
    #[test]
    fn mtl_values_are_refused_as_scene_files_refuse_them() {
        let d = dir("mtl-values");
        let cases = [
            ("Ns nan", "line 2: `Ns` needs 1 finite number, found `nan`"),
            (
                "Ns -50",
                "line 2: `Ns` (shininess) must be at least 0, found `-50`",
            ),
            (
                "Ni 0",
                "line 2: `Ni` (index of refraction) must be above 0, found `0`",
            ),
            (
                "Ni -1.5",
                "`Ni` (index of refraction) must be above 0, found `-1.5`",
            ),
            ("Ni nan", "line 2: `Ni` needs 1 finite number, found `nan`"),
            (
                "Kd a b c",
                "line 2: `Kd` needs 3 finite numbers, found `a b c`",
            ),
            (
                "Kd 1 1 1 1",
                "line 2: `Kd` needs 3 finite numbers, found `1 1 1 1`",
            ),
            (
                "illum banana",
                "line 2: `illum` needs one whole number, found `banana`",
            ),
        ];
        for (statement, needle) in cases {
            let e = with_mtl(&d, &format!("newmtl a\n{statement}\n"))
                .err()
                .unwrap_or_else(|| panic!("accepted: {statement}"))
                .to_string();
            assert!(e.contains("m.mtl: malformed material library: "), "{e}");
            assert!(e.contains(needle), "{statement}: {e}");
        }
        // In range: accepted and kept.
        let data = with_mtl(&d, "newmtl a\nNs 0\nNi 1.33\nillum 4\n").unwrap();
        assert_eq!(data.materials[0].ior, 1.33);
        assert_eq!(data.materials[0].shininess, 0.0);
        // `material_from_mtl` passes the index on: the scene builder refuses it, as it
        // refuses `ior = 0` in a scene file.
        let m = tobj::Material {
            optical_density: Some(0.0),
            ..Default::default()
        };
        assert_eq!(material_from_mtl(&m).ior, 0.0);
        let e = raybench_core::SceneBuilder::new("t")
            .add_material(material_from_mtl(&m))
            .unwrap_err()
            .to_string();
        assert!(e.contains("ior 0 must be positive"), "{e}");
        // Scene files: the shininess is named as such.
        for (value, needle) in [
            ("nan", "shininess NaN must be finite"),
            ("-50", "shininess -50 must be finite and at least 0"),
        ] {
            let text = format!(
                "[[material]]\nname = \"a\"\nshininess = {value}\n[[object]]\n\
                 kind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n"
            );
            let e = crate::format::load_scene_str(&text, "t", None, Path::new("/nonexistent"))
                .err()
                .unwrap_or_else(|| panic!("accepted: {value}"))
                .to_string();
            assert!(e.contains(needle) && !e.contains("ior"), "{e}");
        }
    }

    /// A face of fewer than three vertices is refused with its line, as PLY and scene
    /// files refuse one (it was dropped unsaid).
    #[test]
    fn two_vertex_faces_are_refused() {
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n";
        let e = load_obj_bytes(obj.as_bytes(), Path::new("t.obj"))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "t.obj: line 5: a face needs at least 3 vertices, found 2"
        );
        // Lines (`l 1 2`) and points stay ignored.
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nl 1 2\np 1\n";
        let data = load_obj_bytes(obj.as_bytes(), Path::new("t.obj")).unwrap();
        assert_eq!(data.mesh.indices.len(), 1);
    }

    /// Lines ending in CR alone (classic Mac OS) read as lines, in the OBJ file and in its
    /// material library.
    #[test]
    fn cr_line_ends_are_line_ends() {
        let d = dir("cr");
        std::fs::write(d.join("m.mtl"), "newmtl a\rKd 0.5 0.25 1\r").unwrap();
        let obj = "mtllib m.mtl\rv 0 0 0\rv 1 0 0\rv 0 1 0\rv 1 1 0\rusemtl a\rf 1 2 3\rf 2 4 3\r";
        std::fs::write(d.join("t.obj"), obj).unwrap();
        let data = load_obj_file(&d.join("t.obj")).unwrap();
        assert_eq!(data.mesh.indices, [[0, 1, 2], [1, 3, 2]]);
        assert_eq!(data.materials[0].base_color, Vec3::new(0.5, 0.25, 1.0));
        // Mixed with CR LF.
        let data = load_obj_bytes(
            b"v 0 0 0\r\nv 1 0 0\rv 0 1 0\r\nf 1 2 3",
            Path::new("t.obj"),
        )
        .unwrap();
        assert_eq!(data.mesh.indices.len(), 1);
        // A patch file too.
        let mut bpt = String::from("1\r3 3\r");
        for k in 0..16 {
            bpt += &format!("{} {} 0\r", k % 4, k / 4);
        }
        assert_eq!(crate::parse_bpt(&bpt, Path::new("p.bpt")).unwrap().len(), 1);
    }
}
