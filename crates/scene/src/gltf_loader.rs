//! glTF 2.0 meshes (`.gltf` with external or embedded buffers, and binary `.glb`).

use crate::error::LoadError;
use crate::obj::MeshData;
use base64::Engine as _;
use glam::{Mat4, Vec3};
use raybench_core::{Material, TriangleMesh};
use std::path::Path;

/// Node hierarchies deeper than this are refused (it also stops cycles).
const MAX_NODE_DEPTH: usize = 256;

fn parse_err(path: &Path, message: impl Into<String>) -> LoadError {
    LoadError::Parse {
        path: path.to_owned(),
        message: message.into(),
    }
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
                } else {
                    let file = base.join(uri);
                    std::fs::read(&file).map_err(|source| LoadError::Io { path: file, source })?
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
/// when there is no scene), with node transforms applied, in node order.
///
/// # Errors
/// When the file is missing, malformed, truncated, or has bad indices or coordinates.
pub fn load_gltf_file(path: &Path) -> Result<MeshData, LoadError> {
    let bytes = std::fs::read(path).map_err(|source| LoadError::Io {
        path: path.to_owned(),
        source,
    })?;
    let gltf = gltf::Gltf::from_slice(&bytes)
        .map_err(|e| parse_err(path, format!("malformed glTF: {e}")))?;
    let buffers = load_buffers(path, &gltf.document, gltf.blob.clone())?;
    let doc = &gltf.document;

    let mut data = MeshData {
        materials: doc.materials().map(|m| material_of(&m)).collect(),
        ..Default::default()
    };
    let scene = doc.default_scene().or_else(|| doc.scenes().next());
    match scene {
        Some(scene) => {
            for node in scene.nodes() {
                add_node(path, &node, Mat4::IDENTITY, &buffers, &mut data, 0)?;
            }
        }
        None => {
            for mesh in doc.meshes() {
                add_mesh(path, &mesh, Mat4::IDENTITY, &buffers, &mut data)?;
            }
        }
    }
    Ok(data)
}

fn add_node(
    path: &Path,
    node: &gltf::Node,
    parent: Mat4,
    buffers: &[Vec<u8>],
    data: &mut MeshData,
    depth: usize,
) -> Result<(), LoadError> {
    if depth > MAX_NODE_DEPTH {
        return Err(parse_err(path, "node hierarchy too deep (or cyclic)"));
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
        add_mesh(path, &mesh, world, buffers, data)?;
    }
    for child in node.children() {
        add_node(path, &child, world, buffers, data, depth + 1)?;
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
        if indices.len() % 3 != 0 {
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
        for [a, b, c] in local.indices {
            data.mesh.indices.push([a + base, b + base, c + base]);
            data.triangle_material.push(material);
        }
    }
    Ok(())
}
