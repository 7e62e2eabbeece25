//! glTF 2.0 meshes (`.gltf` with external or embedded buffers, and binary `.glb`).

use crate::error::LoadError;
use crate::obj::MeshData;
use crate::texture::{ImageSource, TextureRef};
use base64::Engine as _;
use glam::{Mat3, Mat4, Vec2, Vec3};
use raybench_core::{Camera, Material, NamedCamera, TriangleMesh, Wrap};
use std::collections::HashMap;
use std::path::Path;

fn parse_err(path: &Path, message: impl Into<String>) -> LoadError {
    LoadError::Parse {
        path: path.to_owned(),
        message: message.into(),
    }
}

/// Reads buffer `index` of the glTF file `gltf` from the external `file`: a regular file,
/// at most the declared length (so a URI naming `/dev/zero` or a huge file cannot exhaust
/// memory). Errors name the glTF file, the buffer and the buffer file's full path once.
fn read_external(
    gltf: &Path,
    index: usize,
    file: &Path,
    declared: usize,
) -> Result<Vec<u8>, LoadError> {
    use std::io::Read as _;
    let full = std::path::absolute(file).unwrap_or_else(|_| file.to_owned());
    let err = |why: String| parse_err(gltf, format!("buffer {index}: {}: {why}", full.display()));
    match std::fs::metadata(file) {
        Ok(m) if m.is_file() => {}
        Ok(m) => return Err(err(crate::io::not_a_file_message(&m))),
        Err(e) => return Err(err(e.to_string())),
    }
    let mut data = Vec::new();
    std::fs::File::open(file)
        .and_then(|f| f.take(declared as u64).read_to_end(&mut data))
        .map_err(|e| err(e.to_string()))?;
    Ok(data)
}

fn load_buffers(
    path: &Path,
    doc: &gltf::Document,
    blob: Option<Vec<u8>>,
) -> Result<Vec<Vec<u8>>, LoadError> {
    let base = path.parent().unwrap_or(Path::new("."));
    let mut blob = blob;
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => blob
                .take()
                .ok_or_else(|| parse_err(path, "buffer refers to a missing GLB binary chunk"))?,
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, payload) = rest
                        .split_once(";base64,")
                        .ok_or_else(|| parse_err(path, "data URI is not base64"))?;
                    base64::engine::general_purpose::STANDARD
                        .decode(payload)
                        .map_err(|e| parse_err(path, format!("bad base64 buffer: {e}")))?
                } else if let Some(scheme) = uri_scheme(uri) {
                    return Err(parse_err(
                        path,
                        format!("buffer {}: {}", buffer.index(), not_fetched(uri, scheme)),
                    ));
                } else {
                    read_external(path, buffer.index(), &base.join(uri), buffer.length())?
                }
            }
        };
        if data.len() < buffer.length() {
            return Err(parse_err(
                path,
                format!(
                    "buffer {} holds {} bytes, the file declares {}",
                    buffer.index(),
                    data.len(),
                    buffer.length()
                ),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// The `gltf` crate's validation, after the one check it relies on without making: its
/// hook on primitives indexes the accessors with the POSITION attribute's index unchecked
/// (a panic when that accessor does not exist).
fn validate(path: &Path, root: &gltf::json::Root) -> Result<(), LoadError> {
    use gltf::json::validation::{Checked, Validate as _};
    for (m, mesh) in root.meshes.iter().enumerate() {
        for prim in &mesh.primitives {
            let position = prim
                .attributes
                .get(&Checked::Valid(gltf::Semantic::Positions));
            if position.is_some_and(|a| a.value() >= root.accessors.len()) {
                return Err(parse_err(
                    path,
                    format!("mesh {m}: the POSITION accessor does not exist"),
                ));
            }
        }
    }
    // What the gltf crate unwraps without checking (`Image::source`): an image is either
    // in a buffer view, with its MIME type, or at a URI.
    for (i, image) in root.images.iter().enumerate() {
        match (&image.uri, &image.buffer_view, &image.mime_type) {
            (None, None, _) => {
                return Err(parse_err(
                    path,
                    format!("image {i} has neither a uri nor a bufferView"),
                ));
            }
            (_, Some(_), None) => {
                return Err(parse_err(
                    path,
                    format!("image {i} is in a bufferView but has no mimeType"),
                ));
            }
            _ => {}
        }
    }
    for (i, node) in root.nodes.iter().enumerate() {
        check_node_transform(node).map_err(|why| parse_err(path, format!("node {i}: {why}")))?;
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |at, e| {
        errors.push(format!("{}: {e}", at()));
    });
    match errors.first() {
        None => Ok(()),
        Some(first) => Err(parse_err(path, format!("invalid glTF: {first}"))),
    }
}

/// How far a node's rotation may be from a unit quaternion (glTF requires one; writers
/// round).
const UNIT_QUATERNION_TOLERANCE: f32 = 1e-3;

/// Refuses what the `gltf` crate would read silently as another transform: a `matrix`
/// beside `translation`, `rotation` or `scale` (the crate uses the matrix and drops the
/// others; glTF allows one form or the other), a projective `matrix` (last row not
/// `0 0 0 1`: its projection would be dropped), and a `rotation` that is no unit
/// quaternion (a zero one would be read as no rotation, a longer one as a scale too).
fn check_node_transform(node: &gltf::json::Node) -> Result<(), String> {
    if let Some(m) = node.matrix {
        let trs: Vec<&str> = [
            ("translation", node.translation.is_some()),
            ("rotation", node.rotation.is_some()),
            ("scale", node.scale.is_some()),
        ]
        .iter()
        .filter_map(|&(name, set)| set.then_some(name))
        .collect();
        if !trs.is_empty() {
            return Err(format!(
                "has both a matrix and {} (glTF allows one form or the other)",
                trs.join(" and ")
            ));
        }
        // Column-major: the last row is elements 3, 7, 11 and 15.
        let last = [m[3], m[7], m[11], m[15]];
        if last != [0.0, 0.0, 0.0, 1.0] {
            return Err(format!(
                "its matrix is projective: the last row is [{}, {}, {}, {}], not [0, 0, 0, 1]",
                last[0], last[1], last[2], last[3]
            ));
        }
    }
    if let Some(q) = node.rotation {
        let q = glam::Vec4::from(q.0);
        let length = q.length();
        if !q.is_finite() || (length - 1.0).abs() > UNIT_QUATERNION_TOLERANCE {
            return Err(format!(
                "rotation [{}, {}, {}, {}] is not a unit quaternion (its length is {length})",
                q.x, q.y, q.z, q.w
            ));
        }
    }
    Ok(())
}

fn material_of(m: &gltf::Material) -> Material {
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, _] = pbr.base_color_factor();
    Material {
        name: m.name().unwrap_or("gltf").to_owned(),
        base_color: Vec3::new(r, g, b),
        emission: Vec3::from(m.emissive_factor()),
        ..Material::default()
    }
}

/// Loads every triangle primitive of the default scene (or the first scene, or every mesh
/// when there is no scene), with node transforms applied, in node order. A mesh that
/// several nodes place is read once into [`MeshData::shared`] with each node's transform
/// (the scene loader makes its placements instances); the others are placed in
/// [`MeshData::mesh`].
///
/// # Errors
/// When the file is missing, malformed, truncated, or has bad indices or coordinates.
pub fn load_gltf_file(path: &Path) -> Result<MeshData, LoadError> {
    crate::io::check_regular_file(path)?;
    let bytes = std::fs::read(path).map_err(|cause| LoadError::Io {
        path: path.to_owned(),
        cause,
    })?;
    load_gltf_bytes(&bytes, path)
}

/// Loads a `.gltf` (JSON) or `.glb` (binary) file held in memory, as [`load_gltf_file`]
/// does: `path` names it in errors and its folder is where external buffers are looked up.
/// The fuzz targets and property tests use it.
///
/// # Errors
/// As [`load_gltf_file`], less the error of reading `path` itself.
#[doc(hidden)]
pub fn load_gltf_bytes(bytes: &[u8], path: &Path) -> Result<MeshData, LoadError> {
    // A `.gltf` written with a byte-order mark (JSON parsers refuse one).
    let bytes = crate::io::strip_bom(bytes);
    // The `gltf` crate subtracts the 12-byte header from the GLB's declared length
    // unchecked (an overflow, a panic in debug builds, when it declares less).
    if let Some(header) = bytes.strip_prefix(b"glTF")
        && let Some(length) = header.get(4..8)
        && u32::from_le_bytes([length[0], length[1], length[2], length[3]]) < 12
    {
        return Err(parse_err(
            path,
            "malformed glTF: the GLB header declares a length shorter than the header",
        ));
    }
    let gltf = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| parse_err(path, format!("malformed glTF: {e}")))?;
    validate(path, gltf.document.as_json())?;
    let buffers = load_buffers(path, &gltf.document, gltf.blob.clone())?;
    let doc = &gltf.document;

    let mut data = MeshData {
        materials: doc.materials().map(|m| material_of(&m)).collect(),
        ..Default::default()
    };
    add_material_textures(path, doc, &buffers, &mut data);
    let scene = doc.default_scene().or_else(|| doc.scenes().next());
    match scene {
        Some(scene) => {
            let mut visited = vec![false; doc.nodes().len()];
            let mut placements = Vec::new();
            for node in scene.nodes() {
                add_node(path, &node, &mut data, &mut visited, &mut placements)?;
            }
            add_placed_meshes(path, doc, &placements, &buffers, &mut data)?;
        }
        None => {
            for mesh in doc.meshes() {
                add_mesh(path, &mesh, Mat4::IDENTITY, &buffers, &mut data)?;
            }
        }
    }
    let distinct = data.mesh.indices.len()
        + data
            .shared
            .iter()
            .map(|s| s.data.mesh.indices.len())
            .sum::<usize>();
    if distinct > raybench_core::limits::MAX_PRIMITIVES {
        return Err(parse_err(path, "more triangles than the primitive limit"));
    }
    Ok(data)
}

/// A node's mesh and where the node puts it: `(mesh index, node index, world matrix)`.
type Placement = (usize, usize, Mat4);

/// Adds the meshes the scene's nodes place, in node order: a mesh placed by one node is
/// transformed and added to `data.mesh` (as before instancing); a mesh placed by several
/// nodes is read once, in its own space, into [`MeshData::shared`] with every placement,
/// to become instances (not copies).
fn add_placed_meshes(
    path: &Path,
    doc: &gltf::Document,
    placements: &[Placement],
    buffers: &[Vec<u8>],
    data: &mut MeshData,
) -> Result<(), LoadError> {
    let meshes: Vec<gltf::Mesh> = doc.meshes().collect();
    let mut uses = vec![0usize; meshes.len()];
    for &(mesh, _, _) in placements {
        uses[mesh] += 1;
    }
    let mut shared: HashMap<usize, usize> = HashMap::new();
    for &(index, node, world) in placements {
        let mesh = meshes
            .get(index)
            .ok_or_else(|| parse_err(path, format!("node {node}: mesh {index} does not exist")))?;
        if uses[index] == 1 {
            add_mesh(path, mesh, world, buffers, data)?;
            continue;
        }
        let k = match shared.get(&index) {
            Some(&k) => k,
            None => {
                let mut own = MeshData::default();
                add_mesh(path, mesh, Mat4::IDENTITY, buffers, &mut own)?;
                if own.mesh.indices.is_empty() {
                    // No triangle primitives (points or lines only): nothing to place.
                    continue;
                }
                let name = mesh.name().map_or_else(
                    || format!("glTF mesh {index}"),
                    |n| format!("glTF mesh {index} '{n}'"),
                );
                data.shared.push(crate::obj::SharedMesh {
                    name,
                    data: own,
                    placements: Vec::new(),
                });
                shared.insert(index, data.shared.len() - 1);
                data.shared.len() - 1
            }
        };
        data.shared[k]
            .placements
            .push(glam::Affine3A::from_mat4(world));
    }
    Ok(())
}

/// Collects the meshes of `root` and its descendants with their world matrices, and adds
/// their cameras, depth first in node order. The walk keeps its own stack: a chain of many
/// nested nodes must not overflow the thread's.
fn add_node(
    path: &Path,
    root: &gltf::Node,
    data: &mut MeshData,
    visited: &mut [bool],
    placements: &mut Vec<Placement>,
) -> Result<(), LoadError> {
    let mut stack = vec![(root.clone(), Mat4::IDENTITY)];
    while let Some((node, parent)) = stack.pop() {
        // glTF node hierarchies are strict trees: a node reached twice is a cycle or a
        // shared child, which could multiply the geometry exponentially.
        let seen = visited
            .get_mut(node.index())
            .ok_or_else(|| parse_err(path, "node index out of range"))?;
        if std::mem::replace(seen, true) {
            return Err(parse_err(
                path,
                format!(
                    "node {} is reached twice (node hierarchies must be trees)",
                    node.index()
                ),
            ));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() {
            return Err(parse_err(
                path,
                format!("node {} has a non-finite transform", node.index()),
            ));
        }
        if let Some(mesh) = node.mesh() {
            // As scene files' transforms: a zero scale would flatten the mesh into nothing.
            let linear = glam::Affine3A::from_mat4(world);
            raybench_core::check_transform(linear, "transform").map_err(|e| {
                parse_err(
                    path,
                    format!("node {} (mesh {}): {e}", node.index(), mesh.index()),
                )
            })?;
            placements.push((mesh.index(), node.index(), world));
        }
        if let Some(camera) = node.camera() {
            add_camera(&camera, node.index(), world, data);
        }
        // Reversed, so that the first child is visited next (node order, as before).
        let children: Vec<gltf::Node> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    Ok(())
}

/// Adds the camera of node `node` placed by `world`: glTF cameras look down their local -z
/// with +y up, and a perspective camera's `yfov` is the vertical field of view in radians
/// (its aspect ratio is left to the image size). Orthographic cameras and cameras that
/// cannot produce rays are skipped with a warning; a name used twice gets the node index.
fn add_camera(camera: &gltf::Camera, node: usize, world: Mat4, data: &mut MeshData) {
    let label = camera
        .name()
        .map_or_else(|| format!("camera {}", camera.index()), str::to_owned);
    let gltf::camera::Projection::Perspective(p) = camera.projection() else {
        data.warnings.push(format!(
            "glTF camera '{label}' (node {node}) is orthographic: skipped (only pinhole cameras \
             render)"
        ));
        return;
    };
    let position = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(-Vec3::Z).normalize_or_zero();
    let cam = Camera {
        position,
        look_at: position + forward,
        up: world.transform_vector3(Vec3::Y),
        vfov_degrees: p.yfov().to_degrees(),
    };
    if let Err(e) = cam.check() {
        data.warnings
            .push(format!("glTF camera '{label}' (node {node}): {e}: skipped"));
        return;
    }
    let name = if data.cameras.iter().any(|c| c.name == label) {
        format!("{label} (node {node})")
    } else {
        label
    };
    data.cameras.push(NamedCamera { name, camera: cam });
}

/// Refuses an accessor the `gltf` crate's readers would panic on: strides no shorter than
/// an element of `elem` bytes, at least one element, and data inside its buffer view.
fn check_accessor(
    path: &Path,
    a: &gltf::Accessor,
    what: &str,
    elem: usize,
) -> Result<(), LoadError> {
    let bad = |why: &str| parse_err(path, format!("accessor {} ({what}): {why}", a.index()));
    if a.count() == 0 {
        return Err(bad("no elements"));
    }
    let view = a
        .view()
        .ok_or_else(|| bad("no buffer view (sparse accessors are not supported)"))?;
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err(bad("byte stride shorter than an element"));
    }
    let end = a
        .offset()
        .checked_add(
            (a.count() - 1)
                .checked_mul(stride)
                .ok_or_else(|| bad("too large"))?,
        )
        .and_then(|e| e.checked_add(elem))
        .ok_or_else(|| bad("too large"))?;
    if end > view.length() {
        return Err(bad("runs past its buffer view"));
    }
    let view_end = view
        .offset()
        .checked_add(view.length())
        .ok_or_else(|| bad("too large"))?;
    if view_end > view.buffer().length() {
        return Err(bad("buffer view runs past its buffer"));
    }
    Ok(())
}

/// Refuses accessors the `gltf` crate's readers would panic on: positions must be `f32`
/// VEC3 and indices unsigned scalars, with strides no shorter than an element, at least one
/// element, and data inside their buffer view.
fn check_accessors(path: &Path, prim: &gltf::Primitive) -> Result<(), LoadError> {
    use gltf::accessor::{DataType, Dimensions};
    let check = |a: &gltf::Accessor, what: &str, elem: usize| check_accessor(path, a, what, elem);
    let position = prim
        .get(&gltf::Semantic::Positions)
        .ok_or_else(|| parse_err(path, "a primitive has no POSITION attribute"))?;
    if position.data_type() != DataType::F32 || position.dimensions() != Dimensions::Vec3 {
        return Err(parse_err(path, "POSITION must be f32 VEC3"));
    }
    check(&position, "POSITION", 12)?;
    if let Some(indices) = prim.indices() {
        let size = match indices.data_type() {
            DataType::U8 => 1,
            DataType::U16 => 2,
            DataType::U32 => 4,
            _ => return Err(parse_err(path, "indices must be unsigned integers")),
        };
        if indices.dimensions() != Dimensions::Scalar {
            return Err(parse_err(path, "indices must be scalars"));
        }
        check(&indices, "indices", size)?;
    }
    Ok(())
}

fn add_mesh(
    path: &Path,
    mesh: &gltf::Mesh,
    world: Mat4,
    buffers: &[Vec<u8>],
    data: &mut MeshData,
) -> Result<(), LoadError> {
    for prim in mesh.primitives() {
        if prim.mode() != gltf::mesh::Mode::Triangles {
            // Points, lines and strips carry no triangles of the list kind: skipped.
            continue;
        }
        check_accessors(path, &prim)?;
        let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
        let positions: Vec<Vec3> = reader
            .read_positions()
            .ok_or_else(|| {
                parse_err(
                    path,
                    format!("mesh {} has a primitive without positions", mesh.index()),
                )
            })?
            .map(|p| world.transform_point3(Vec3::from(p)))
            .collect();
        let count = positions.len();
        let indices: Vec<u32> = match reader.read_indices() {
            Some(ix) => ix.into_u32().collect(),
            None => (0..count as u32).collect(),
        };
        if !indices.len().is_multiple_of(3) {
            return Err(parse_err(
                path,
                format!("mesh {}: index count is not a multiple of 3", mesh.index()),
            ));
        }
        let local = TriangleMesh {
            positions,
            indices: indices
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
        };
        local
            .validate()
            .map_err(|e| parse_err(path, format!("mesh {}: {e}", mesh.index())))?;
        let base = data.mesh.positions.len() as u32;
        let material = prim.material().index().map(|i| i as u32);
        data.mesh.positions.extend_from_slice(&local.positions);
        add_shading_attributes(
            path,
            mesh.index(),
            &prim,
            world,
            buffers,
            base as usize,
            data,
        )?;
        for [a, b, c] in local.indices {
            data.mesh.indices.push([a + base, b + base, c + base]);
            data.triangle_material.push(material);
        }
        if data.mesh.indices.len() > raybench_core::limits::MAX_PRIMITIVES {
            return Err(parse_err(path, "more triangles than the primitive limit"));
        }
    }
    Ok(())
}

/// Reads a primitive's vertex normals (`NORMAL`, through the inverse transpose of the
/// node's world matrix) and texture coordinates (`TEXCOORD_0`) into `data`, whose vertices
/// of this primitive start at `base`; then pads the lists to every vertex so far
/// ([`MeshData::pad_attributes`]).
fn add_shading_attributes(
    path: &Path,
    mesh: usize,
    prim: &gltf::Primitive,
    world: Mat4,
    buffers: &[Vec<u8>],
    base: usize,
    data: &mut MeshData,
) -> Result<(), LoadError> {
    use gltf::accessor::{DataType, Dimensions};
    let count = data.mesh.positions.len() - base;
    let check = |a: &gltf::Accessor, what: &str, elem: usize| {
        check_accessor(path, a, what, elem)?;
        if a.count() != count {
            return Err(parse_err(
                path,
                format!(
                    "mesh {mesh}: {what} has {} elements for {count} vertices",
                    a.count()
                ),
            ));
        }
        Ok(())
    };
    let normal = prim.get(&gltf::Semantic::Normals);
    if let Some(a) = &normal {
        if a.data_type() != DataType::F32 || a.dimensions() != Dimensions::Vec3 {
            return Err(parse_err(
                path,
                format!("mesh {mesh}: NORMAL must be f32 VEC3"),
            ));
        }
        check(a, "NORMAL", 12)?;
    }
    let uv = prim.get(&gltf::Semantic::TexCoords(0));
    if let Some(a) = &uv {
        let elem = match (a.data_type(), a.normalized()) {
            (DataType::F32, _) => 8,
            (DataType::U8, true) => 2,
            (DataType::U16, true) => 4,
            _ => {
                return Err(parse_err(
                    path,
                    format!("mesh {mesh}: TEXCOORD_0 must be f32 or normalised u8 or u16"),
                ));
            }
        };
        if a.dimensions() != Dimensions::Vec2 {
            return Err(parse_err(
                path,
                format!("mesh {mesh}: TEXCOORD_0 must be VEC2"),
            ));
        }
        check(a, "TEXCOORD_0", elem)?;
    }
    let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    if normal.is_some()
        && let Some(normals) = reader.read_normals()
    {
        let m = Mat3::from_mat4(world).inverse().transpose();
        data.normals.resize(base, Vec3::ZERO);
        data.normals.extend(normals.map(|n| m * Vec3::from(n)));
    }
    if uv.is_some()
        && let Some(uvs) = reader.read_tex_coords(0)
    {
        data.uvs.resize(base, Vec2::ZERO);
        data.uvs.extend(uvs.into_f32().map(Vec2::from));
    }
    data.pad_attributes();
    Ok(())
}

/// The scheme of an absolute URI (`http` of `http://example.com/a.png`), when `uri` has
/// one: glTF names files by relative references, and only `data:` URIs are read in place.
/// (A one-letter "scheme" is a Windows drive, `C:`.)
fn uri_scheme(uri: &str) -> Option<&str> {
    let (scheme, _) = uri.split_once(':')?;
    let mut chars = scheme.chars();
    (scheme.len() > 1
        && chars.next().is_some_and(|c| c.is_ascii_alphabetic())
        && chars.all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.')))
    .then_some(scheme)
}

/// Why a URI with a scheme other than `data:` is not read.
fn not_fetched(uri: &str, scheme: &str) -> String {
    let shown: String = uri.chars().take(80).collect();
    format!(
        "its URI '{shown}' is a {scheme}: URI, which raybench does not fetch (it reads files \
         beside the glTF file and data: URIs)"
    )
}

/// `%XX` escapes of a URI decoded (image file names with spaces).
fn percent_decode(uri: &str) -> String {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = b
            .get(i + 1..i + 3)
            .and_then(|h| std::str::from_utf8(h).ok())
            .and_then(|h| u8::from_str_radix(h, 16).ok());
        match (b[i], hex) {
            (b'%', Some(x)) => {
                out.push(x);
                i += 3;
            }
            (c, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// The texture a material's texture slot names (`what`: `baseColorTexture`, ...): its
/// image (a file beside the glTF file, a data URI or a buffer view) and its sampler's wrap
/// modes; `Err` says why it cannot be used.
fn texture_ref(
    path: &Path,
    info: &gltf::texture::Info,
    buffers: &[Vec<u8>],
) -> Result<TextureRef, String> {
    use gltf::texture::WrappingMode;
    if info.tex_coord() != 0 {
        return Err(format!(
            "it uses TEXCOORD_{} (only TEXCOORD_0 is read)",
            info.tex_coord()
        ));
    }
    let texture = info.texture();
    let image = texture.source();
    let wrap = |m: WrappingMode| match m {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
    };
    let sampler = texture.sampler();
    let wrap = [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())];
    let key = format!("{} image {}", path.display(), image.index());
    let name = format!("image {} of {}", image.index(), path.display());
    let bytes = |bytes: Vec<u8>| ImageSource::Bytes {
        key: key.clone(),
        bytes: bytes.into(),
    };
    let source = match image.source() {
        gltf::image::Source::View { view, .. } => {
            let start = view.offset();
            let data = buffers
                .get(view.buffer().index())
                .and_then(|b| b.get(start..start.checked_add(view.length())?))
                .ok_or("its buffer view runs past its buffer")?;
            bytes(data.to_vec())
        }
        gltf::image::Source::Uri { uri, .. } => match uri.strip_prefix("data:") {
            Some(rest) => {
                let (_, payload) = rest
                    .split_once(";base64,")
                    .ok_or("its data URI is not base64")?;
                let data = base64::engine::general_purpose::STANDARD
                    .decode(payload)
                    .map_err(|e| format!("bad base64 image: {e}"))?;
                bytes(data)
            }
            None if uri_scheme(uri).is_some() => {
                return Err(not_fetched(uri, uri_scheme(uri).unwrap_or_default()));
            }
            None => {
                let file = path
                    .parent()
                    .unwrap_or(Path::new("."))
                    .join(percent_decode(uri));
                return Ok(TextureRef {
                    name: file.display().to_string(),
                    source: ImageSource::File(file),
                    wrap,
                });
            }
        },
    };
    Ok(TextureRef { name, source, wrap })
}

/// Points the file's materials at their base-colour and emissive textures (glTF
/// `baseColorTexture` and `emissiveTexture`, which multiply `baseColorFactor` and
/// `emissiveFactor`), listed once each in `data.textures`; one that cannot be located is a
/// warning and a flat colour.
fn add_material_textures(
    path: &Path,
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    data: &mut MeshData,
) {
    let mut listed: HashMap<usize, Option<u32>> = HashMap::new();
    let mut slot = |info: Option<gltf::texture::Info>, what: &str, data: &mut MeshData| {
        let info = info?;
        *listed.entry(info.texture().index()).or_insert_with(|| {
            match texture_ref(path, &info, buffers) {
                Ok(t) => {
                    data.textures.push(t);
                    Some(data.textures.len() as u32 - 1)
                }
                Err(why) => {
                    data.warnings.push(format!(
                        "{}: texture {} ({what}) cannot be used ({why}): its materials keep \
                         their flat colour",
                        path.display(),
                        info.texture().index()
                    ));
                    None
                }
            }
        })
    };
    for (i, m) in doc.materials().enumerate() {
        let base = slot(
            m.pbr_metallic_roughness().base_color_texture(),
            "baseColorTexture",
            data,
        );
        let emissive = slot(m.emissive_texture(), "emissiveTexture", data);
        if let Some(material) = data.materials.get_mut(i) {
            material.base_color_texture = base;
            material.emission_texture = emissive;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One triangle (positions f32, indices u16) as a buffer, and the JSON describing it.
    fn triangle_gltf(uri: Option<&str>) -> (Vec<u8>, String) {
        let mut bin = Vec::new();
        for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
            bin.extend_from_slice(&v.to_le_bytes());
        }
        for i in [0u16, 1, 2, 0] {
            bin.extend_from_slice(&i.to_le_bytes());
        }
        let uri = uri.map_or(String::new(), |u| format!(r#""uri": "{u}", "#));
        let json = format!(
            r#"{{"asset": {{"version": "2.0"}}, "scene": 0,
            "scenes": [{{"nodes": [0]}}],
            "nodes": [{{"mesh": 0, "translation": [0, 0, 5]}}],
            "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}}],
            "materials": [{{"name": "m", "pbrMetallicRoughness": {{"baseColorFactor": [1, 0, 0, 1]}}}}],
            "buffers": [{{{uri}"byteLength": {len}}}],
            "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}},
                            {{"buffer": 0, "byteOffset": 36, "byteLength": 6}}],
            "accessors": [
              {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                "min": [0, 0, 0], "max": [1, 1, 0]}},
              {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}}]}}"#,
            len = bin.len()
        );
        (bin, json)
    }

    fn tmp(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("raybench-gltf-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d.join(name)
    }

    fn check(data: &MeshData) {
        assert_eq!(data.mesh.indices.len(), 1);
        assert_eq!(
            data.mesh.positions[1],
            Vec3::new(1.0, 0.0, 5.0),
            "node translation applied"
        );
        assert_eq!(data.triangle_material, vec![Some(0)]);
        assert_eq!(data.materials[0].base_color, Vec3::new(1.0, 0.0, 0.0));
    }

    #[test]
    fn embedded_external_and_binary_gltf() {
        let (bin, _) = triangle_gltf(None);
        let data_uri = format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&bin)
        );
        let (_, json) = triangle_gltf(Some(&data_uri));
        let p = tmp("embedded.gltf");
        std::fs::write(&p, &json).unwrap();
        check(&load_gltf_file(&p).unwrap());

        let (_, json) = triangle_gltf(Some("tri.bin"));
        std::fs::write(tmp("tri.bin"), &bin).unwrap();
        let p = tmp("external.gltf");
        std::fs::write(&p, &json).unwrap();
        check(&load_gltf_file(&p).unwrap());

        // GLB: header, JSON chunk (padded with spaces), BIN chunk (padded with zeros).
        let (_, json) = triangle_gltf(None);
        let mut j = json.into_bytes();
        while !j.len().is_multiple_of(4) {
            j.push(b' ');
        }
        let mut b = bin.clone();
        while !b.len().is_multiple_of(4) {
            b.push(0);
        }
        let total = 12 + 8 + j.len() + 8 + b.len();
        let mut glb = Vec::new();
        glb.extend_from_slice(b"glTF");
        glb.extend_from_slice(&2u32.to_le_bytes());
        glb.extend_from_slice(&(total as u32).to_le_bytes());
        glb.extend_from_slice(&(j.len() as u32).to_le_bytes());
        glb.extend_from_slice(b"JSON");
        glb.extend_from_slice(&j);
        glb.extend_from_slice(&(b.len() as u32).to_le_bytes());
        glb.extend_from_slice(b"BIN\0");
        glb.extend_from_slice(&b);
        let p = tmp("tri.glb");
        std::fs::write(&p, &glb).unwrap();
        check(&load_gltf_file(&p).unwrap());

        // Truncated GLB and a buffer shorter than declared are errors, not panics.
        std::fs::write(&p, &glb[..glb.len() - 10]).unwrap();
        assert!(load_gltf_file(&p).is_err());
        let (_, json) = triangle_gltf(Some("short.bin"));
        std::fs::write(tmp("short.bin"), &bin[..10]).unwrap();
        let p = tmp("short.gltf");
        std::fs::write(&p, &json).unwrap();
        let e = load_gltf_file(&p).unwrap_err().to_string();
        assert!(e.contains("declares"), "{e}");
        // A missing external buffer names it.
        let (_, json) = triangle_gltf(Some("absent.bin"));
        let p = tmp("absent.gltf");
        std::fs::write(&p, &json).unwrap();
        let e = load_gltf_file(&p).unwrap_err().to_string();
        assert!(e.contains("absent.bin"), "{e}");
    }

    /// A triangle glTF with its buffer embedded, whose node is `node` (JSON).
    fn with_node(node: &str) -> String {
        let (bin, _) = triangle_gltf(None);
        let data_uri = format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&bin)
        );
        let (_, json) = triangle_gltf(Some(&data_uri));
        json.replace(r#"{"mesh": 0, "translation": [0, 0, 5]}"#, node)
    }

    /// An emitting mesh placed twice is copied, with one warning of plain words (no run
    /// of spaces from a broken line continuation).
    #[test]
    fn an_instanced_emitter_is_copied_with_a_plain_warning() {
        let json = with_node(r#"{"mesh": 0, "translation": [0, 0, 5]}, {"mesh": 0}"#)
            .replacen(r#""nodes": [0]}"#, r#""nodes": [0, 1]}"#, 1)
            .replacen(
                r#""name": "m","#,
                r#""name": "m", "emissiveFactor": [1, 1, 1],"#,
                1,
            );
        let p = tmp("emitter.gltf");
        std::fs::write(&p, &json).unwrap();
        let scene = tmp("emitter.toml");
        std::fs::write(
            &scene,
            "[[object]]\nkind = \"mesh\"\npath = \"emitter.gltf\"\n",
        )
        .unwrap();
        let s = crate::format::load_toml_file(&scene, Path::new("/nonexistent")).unwrap();
        assert_eq!(s.geometry.len(), 2);
        let w: Vec<&String> = s
            .warnings
            .iter()
            .filter(|w| w.contains("emits light"))
            .collect();
        assert_eq!(w.len(), 1, "{:?}", s.warnings);
        assert!(
            w[0].ends_with(
                "glTF mesh 0 is placed 2 times but emits light: copied per placement \
                 (instanced primitives are not sampled as lights in this version)"
            ) && !w[0].contains("  "),
            "{}",
            w[0]
        );
    }

    /// Node transforms that the `gltf` crate would read as another transform are refused,
    /// naming the node and the cause.
    #[test]
    fn node_transforms_that_would_be_misread_are_refused() {
        let cases = [
            (
                r#"{"mesh": 0, "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,5,1],
                   "translation": [1, 0, 0]}"#,
                "t.gltf: node 0: has both a matrix and translation (glTF allows one form or \
                 the other)",
            ),
            (
                r#"{"mesh": 0, "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0.5, 0,0,5,1]}"#,
                "t.gltf: node 0: its matrix is projective: the last row is [0, 0, 0.5, 1], \
                 not [0, 0, 0, 1]",
            ),
            (
                r#"{"mesh": 0, "rotation": [0, 0, 0, 0]}"#,
                "t.gltf: node 0: rotation [0, 0, 0, 0] is not a unit quaternion (its length \
                 is 0)",
            ),
            (
                r#"{"mesh": 0, "rotation": [0, 0, 0, 2]}"#,
                "is not a unit quaternion (its length is 2)",
            ),
        ];
        for (node, expected) in cases {
            let e = load_gltf_bytes(with_node(node).as_bytes(), Path::new("t.gltf"))
                .err()
                .unwrap_or_else(|| panic!("accepted: {node}"))
                .to_string();
            assert!(e.contains(expected), "{node}: {e}");
        }
        // A matrix alone, and a rotation within rounding of unit length, load.
        for node in [
            r#"{"mesh": 0, "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,5,1]}"#,
            r#"{"mesh": 0, "rotation": [0, 0, 0, 0.9999999], "translation": [0, 0, 5]}"#,
        ] {
            check(&load_gltf_bytes(with_node(node).as_bytes(), Path::new("t.gltf")).unwrap());
        }
    }

    /// Remote URIs are not fetched, and said so: a buffer's is an error, a texture's a
    /// warning that keeps the flat colour.
    #[test]
    fn remote_uris_are_not_fetched() {
        let (_, json) = triangle_gltf(Some("http://example.com/tri.bin"));
        let e = load_gltf_bytes(json.as_bytes(), Path::new("t.gltf"))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "t.gltf: buffer 0: its URI 'http://example.com/tri.bin' is a http: URI, which \
             raybench does not fetch (it reads files beside the glTF file and data: URIs)"
        );
        let json = with_node(r#"{"mesh": 0, "translation": [0, 0, 5]}"#).replace(
            r#""pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1]}"#,
            r#""pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1],
               "baseColorTexture": {"index": 0}}}], "textures": [{"source": 0}],
               "images": [{"uri": "https://example.com/wood.png""#,
        );
        let data = load_gltf_bytes(json.as_bytes(), Path::new("t.gltf")).unwrap();
        assert!(data.textures.is_empty());
        assert_eq!(data.warnings.len(), 1, "{:?}", data.warnings);
        assert!(
            data.warnings[0].contains(
                "texture 0 (baseColorTexture) cannot be used (its URI \
                 'https://example.com/wood.png' is a https: URI, which raybench does not fetch"
            ),
            "{:?}",
            data.warnings
        );
        assert_eq!(uri_scheme("C:/textures/a.png"), None);
        assert_eq!(uri_scheme("wood%20grain.png"), None);
        assert_eq!(uri_scheme("file:///a.png"), Some("file"));
    }

    #[test]
    fn crafted_accessors_and_shared_nodes_are_errors() {
        let (bin, _) = triangle_gltf(None);
        let data_uri = format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&bin)
        );
        let (_, json) = triangle_gltf(Some(&data_uri));
        let cases = [
            // A 4-byte stride on 12-byte positions (the gltf crate asserts on it).
            (
                json.replacen(
                    r#""byteLength": 36}"#,
                    r#""byteLength": 36, "byteStride": 4}"#,
                    1,
                ),
                "stride",
            ),
            // No elements.
            (
                json.replacen(
                    r#""count": 3, "type": "VEC3""#,
                    r#""count": 0, "type": "VEC3""#,
                    1,
                ),
                "no elements",
            ),
            // Node 0 listed twice in the scene.
            (
                json.replacen(r#""nodes": [0]}"#, r#""nodes": [0, 0]}"#, 1),
                "twice",
            ),
        ];
        for (i, (text, needle)) in cases.iter().enumerate() {
            assert_ne!(text, &json, "case {i} did not change the file");
            let p = tmp(&format!("crafted{i}.gltf"));
            std::fs::write(&p, text).unwrap();
            let e = load_gltf_file(&p).map(|_| ()).unwrap_err().to_string();
            assert!(e.contains(needle), "case {i}: {e}");
        }
    }

    /// A mesh placed by several nodes is read once with every placement (to become
    /// instances); a mesh placed by one node stays placed in `mesh`.
    #[test]
    fn meshes_placed_by_several_nodes_are_shared() {
        let (bin, _) = triangle_gltf(None);
        let data_uri = format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&bin)
        );
        let (_, json) = triangle_gltf(Some(&data_uri));
        let json = json
            .replacen(
                r#""nodes": [0]}"#,
                r#""nodes": [0, 1, 2]}"#,
                1,
            )
            .replacen(
                r#""nodes": [{"mesh": 0, "translation": [0, 0, 5]}]"#,
                r#""nodes": [{"mesh": 0, "translation": [0, 0, 5]},
                             {"mesh": 1, "scale": [2, 2, 2]},
                             {"mesh": 0, "translation": [3, 0, 0], "children": [3]},
                             {"mesh": 0, "translation": [0, 1, 0]}]"#,
                1,
            )
            .replacen(
                r#""meshes": [{"primitives""#,
                r#""meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}, {"primitives""#,
                1,
            );
        let p = tmp("shared.gltf");
        std::fs::write(&p, &json).unwrap();
        let data = load_gltf_file(&p).unwrap();
        // Mesh 1 (one node) is placed: scaled by 2.
        assert_eq!(data.mesh.indices.len(), 1);
        assert_eq!(data.mesh.positions[1], Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(data.triangle_material, vec![Some(0)]);
        // Mesh 0 (three nodes, one of them a child) is read once in its own space.
        assert_eq!(data.shared.len(), 1);
        let shared = &data.shared[0];
        assert_eq!(shared.name, "glTF mesh 0 'tri'");
        assert_eq!(shared.data.mesh.indices.len(), 1);
        assert_eq!(shared.data.mesh.positions[1], Vec3::X);
        let at: Vec<Vec3> = shared
            .placements
            .iter()
            .map(|a| a.transform_point3(Vec3::ZERO))
            .collect();
        assert_eq!(
            at,
            [
                Vec3::new(0.0, 0.0, 5.0),
                Vec3::new(3.0, 0.0, 0.0),
                Vec3::new(3.0, 1.0, 0.0)
            ],
            "node order, the child under its parent's transform"
        );
        // Its copy is the three placed triangles.
        let copy = shared.copied();
        assert_eq!(copy.mesh.indices, [[0, 1, 2], [3, 4, 5], [6, 7, 8]]);
        assert_eq!(copy.mesh.positions[4], Vec3::new(4.0, 0.0, 0.0));
    }

    #[test]
    fn out_of_range_indices_are_errors() {
        let (mut bin, _) = triangle_gltf(None);
        // Index 2 becomes 9.
        bin[40..42].copy_from_slice(&9u16.to_le_bytes());
        let data_uri = format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&bin)
        );
        let (_, json) = triangle_gltf(Some(&data_uri));
        let p = tmp("oob.gltf");
        std::fs::write(&p, &json).unwrap();
        let e = load_gltf_file(&p).unwrap_err().to_string();
        assert!(e.contains("out of range"), "{e}");
    }
}
