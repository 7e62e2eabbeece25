//! The triangle objects of the scene format: `kind = "triangle"` (one, inline),
//! `kind = "polygons"` (faces of any size, triangulated) and `kind = "mesh"` (an OBJ, glTF
//! or PLY file); and the bare mesh file loaded as a scene of its own.

use super::{ObjectCx, TransformDesc, V3};
use crate::budget::{Holds, Reservation};
use crate::error::LoadError;
use crate::gltf_loader::load_gltf_file;
use crate::obj::{MeshData, load_obj_file};
use crate::ply::{Reserve, load_ply_file_reserving};
use crate::texture::add_textures;
use raybench_core::{PolygonMesh, Scene, SceneBuilder, Triangle, Vec3, VertexAttributes};
use serde::Deserialize;
use std::path::Path;

/// `kind = "triangle"`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TriangleDesc {
    vertices: [V3; 3],
    material: Option<String>,
}

/// `kind = "polygons"`: an inline polygon mesh.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PolygonsDesc {
    positions: Vec<V3>,
    faces: Vec<Vec<u32>>,
    material: Option<String>,
    #[serde(default)]
    transform: TransformDesc,
}

/// `kind = "mesh"`: a mesh file, with its own materials unless `material` overrides them,
/// shaded with its vertex normals unless `smooth = false`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MeshDesc {
    path: String,
    material: Option<String>,
    smooth: Option<bool>,
    #[serde(default)]
    transform: TransformDesc,
}

impl TriangleDesc {
    /// Adds the triangle.
    pub(super) fn add(&self, cx: &mut ObjectCx) -> Result<(), LoadError> {
        let m = cx.material(self.material.as_ref())?.unwrap_or(0);
        let tri = Triangle::new(
            self.vertices[0].into(),
            self.vertices[1].into(),
            self.vertices[2].into(),
        );
        let err = cx.err();
        cx.b.add_triangles("triangle", &[tri], &[m]).map_err(err)?;
        Ok(())
    }
}

impl PolygonsDesc {
    /// Triangulates the polygons (warning about self-intersecting ones), places and adds
    /// them.
    pub(super) fn add(&self, cx: &mut ObjectCx) -> Result<(), LoadError> {
        let err = cx.err();
        let m = cx.material(self.material.as_ref())?.unwrap_or(0);
        let poly = PolygonMesh {
            positions: self.positions.iter().map(|&v| Vec3::from(v)).collect(),
            faces: self.faces.clone(),
        };
        let triangulated = poly.triangulate().map_err(&err)?;
        if !triangulated.self_intersecting.is_empty() {
            cx.b.warn(format!(
                "{}: {}: {}",
                cx.ctx.file.display(),
                cx.what,
                crate::obj::self_intersecting(&triangulated.self_intersecting)
            ));
        }
        let mut mesh = triangulated.mesh;
        let xf = self.transform.checked().map_err(&err)?;
        if !xf.is_identity() {
            let a = xf.affine();
            mesh.transform(|v| a.transform_point3(v));
        }
        cx.b.add_mesh("polygons", &mesh, m).map_err(err)?;
        Ok(())
    }
}

impl MeshDesc {
    /// Loads the mesh file (reserving its triangles in the budget), places and adds it.
    pub(super) fn add(&self, cx: &mut ObjectCx) -> Result<(), LoadError> {
        let err = cx.err();
        let xf = self.transform.checked().map_err(&err)?;
        let path = cx.ctx.resolve(&self.path)?;
        let context = format!("{}: {}: {}", cx.ctx.file.display(), cx.what, path.display());
        let budget = &mut *cx.budget;
        let mut data = load_mesh_file(&path, &mut |n| {
            budget.reserve(Holds::Primitives(n), &context)
        })?;
        if !xf.is_identity() {
            let a = xf.affine();
            data.mesh.transform(|v| a.transform_point3(v));
            // Normals go through the inverse transpose (non-uniform scales bend them).
            let n = a.matrix3.inverse().transpose();
            for v in &mut data.normals {
                *v = n.mul_vec3(*v);
            }
        }
        if self.smooth == Some(false) {
            data.normals.clear();
        }
        let m = cx.material(self.material.as_ref())?;
        let context = format!("{}: {}", cx.ctx.file.display(), cx.what);
        add_mesh_data(cx.b, &self.path, data, m, cx.budget, &context)?;
        Ok(())
    }
}

/// Loads a mesh file by its extension, reserving its triangles in the memory budget through
/// `reserve`: a PLY file's before they are allocated (its header declares them), the other
/// formats' once loaded. A file without triangles is refused.
fn load_mesh_file(path: &Path, reserve: Reserve<'_>) -> Result<MeshData, LoadError> {
    let data = match crate::extension(path).as_str() {
        "ply" => load_ply_file_reserving(path, reserve)?,
        ext => {
            let data = match ext {
                "obj" => load_obj_file(path)?,
                "gltf" | "glb" => load_gltf_file(path)?,
                _ => {
                    return Err(LoadError::Parse {
                        path: path.to_owned(),
                        message: "unknown mesh file type (expected .obj, .gltf, .glb or .ply)"
                            .into(),
                    });
                }
            };
            reserve(data.mesh.indices.len() as u64)?;
            data
        }
    };
    if data.mesh.indices.is_empty() {
        return Err(LoadError::Parse {
            path: path.to_owned(),
            message: "no triangles found (is this a mesh file?)".into(),
        });
    }
    Ok(data)
}

/// A scene of one mesh file with a light, a grey-blue background and a camera framing it.
pub(crate) fn bare_mesh_scene(path: &Path) -> Result<Scene, LoadError> {
    let mut budget = Reservation::new()?;
    let context = path.display().to_string();
    let data = load_mesh_file(path, &mut |n| {
        budget.reserve(Holds::Primitives(n), &context)
    })?;
    let name = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("mesh")
        .to_owned();
    let scene_err = |cause| LoadError::Scene {
        context: path.display().to_string(),
        cause,
    };
    let mut b = crate::lit_builder(&name).map_err(scene_err)?;
    for c in &data.cameras {
        b.add_camera(Some(&c.name), c.camera).map_err(scene_err)?;
    }
    add_mesh_data(
        &mut b,
        &name,
        data,
        None,
        &mut budget,
        &path.display().to_string(),
    )?;
    Ok(b.build())
}

/// Adds a loaded mesh: its own materials (unless `override_material`) with their textures
/// (decoded once per scene; one that cannot be used is a warning), its triangles as one
/// object with their vertex normals and texture coordinates. `context` names the mesh in
/// messages.
fn add_mesh_data(
    b: &mut SceneBuilder,
    name: &str,
    mut data: MeshData,
    override_material: Option<u32>,
    budget: &mut Reservation,
    context: &str,
) -> Result<(), LoadError> {
    let scene_err = |cause| LoadError::Scene {
        context: context.to_owned(),
        cause,
    };
    let materials: Vec<u32> = match override_material {
        Some(m) => {
            // The file's materials and their textures are not used.
            data.uvs.clear();
            vec![m; data.mesh.indices.len()]
        }
        None => {
            let textures = add_textures(b, &data.textures, budget, context)?;
            let texture = |t: Option<u32>| t.and_then(|t| textures.get(t as usize).copied()?);
            let mut ids = Vec::with_capacity(data.materials.len());
            for mut m in data.materials {
                m.base_color_texture = texture(m.base_color_texture);
                m.emission_texture = texture(m.emission_texture);
                ids.push(b.add_material(m).map_err(scene_err)?);
            }
            data.triangle_material
                .iter()
                .map(|m| m.map_or(0, |i| ids[i as usize]))
                .collect()
        }
    };
    for w in data.warnings {
        b.warn(w);
    }
    let attributes = VertexAttributes {
        normals: data.normals,
        uvs: data.uvs,
    };
    b.add_mesh_with_attributes(name, &data.mesh, attributes, &materials)
        .map_err(scene_err)?;
    Ok(())
}
