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
        let path = cx.ctx.resolve("path", &self.path, cx.what)?;
        let context = format!("{}: {}: {}", cx.ctx.file.display(), cx.what, path.display());
        let budget = &mut *cx.budget;
        let mut data = load_mesh_file(&path, &mut |n| {
            budget.reserve(Holds::Primitives(n), &context)
        })
        .map_err(cx.ctx.within(cx.what))?;
        if !xf.is_identity() {
            let a = xf.affine();
            data.mesh.transform(|v| a.transform_point3(v));
            // Normals go through the inverse transpose (non-uniform scales bend them).
            let n = a.matrix3.inverse().transpose();
            for v in &mut data.normals {
                *v = n.mul_vec3(*v);
            }
            // A shared mesh stays in its own space; its placements take the transform.
            for s in &mut data.shared {
                for p in &mut s.placements {
                    *p = a * *p;
                }
            }
        }
        if self.smooth == Some(false) {
            data.normals.clear();
            for s in &mut data.shared {
                s.data.normals.clear();
            }
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
    let data = match crate::io::extension(path).as_str() {
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
            // Each distinct triangle once: a shared mesh's placements are instances.
            let shared: usize = data.shared.iter().map(|s| s.data.mesh.indices.len()).sum();
            reserve((data.mesh.indices.len() + shared) as u64)?;
            data
        }
    };
    if data.mesh.indices.is_empty() && data.shared.is_empty() {
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
    let mut b = crate::generators::lit_builder(&name).map_err(scene_err)?;
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
/// object with their vertex normals and texture coordinates, and each of its shared meshes
/// ([`MeshData::shared`]) stored once and placed by instances. `context` names the mesh in
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
    // The scene's material of each of the file's materials (`None`: the default, 0).
    let ids: Vec<u32> = if override_material.is_some() {
        // The file's materials and their textures are not used.
        data.uvs.clear();
        for s in &mut data.shared {
            s.data.uvs.clear();
        }
        Vec::new()
    } else {
        let textures = add_textures(b, &data.textures, budget, context)?;
        let texture = |t: Option<u32>| t.and_then(|t| textures.get(t as usize).copied()?);
        let mut ids = Vec::with_capacity(data.materials.len());
        for mut m in std::mem::take(&mut data.materials) {
            m.base_color_texture = texture(m.base_color_texture);
            m.emission_texture = texture(m.emission_texture);
            ids.push(b.add_material(m).map_err(scene_err)?);
        }
        ids
    };
    let material_ids = |triangles: &[Option<u32>]| -> Vec<u32> {
        match override_material {
            Some(m) => vec![m; triangles.len()],
            None => triangles
                .iter()
                .map(|m| m.map_or(0, |i| ids[i as usize]))
                .collect(),
        }
    };
    for w in std::mem::take(&mut data.warnings) {
        b.warn(w);
    }
    if !data.mesh.indices.is_empty() {
        let materials = material_ids(&data.triangle_material);
        let attributes = VertexAttributes {
            normals: data.normals,
            uvs: data.uvs,
        };
        b.add_mesh_with_attributes(name, &data.mesh, attributes, &materials)
            .map_err(scene_err)?;
    }
    for shared in data.shared {
        let materials = material_ids(&shared.data.triangle_material);
        if materials.iter().any(|&m| b.material_emits(m)) {
            // Instanced emitters are not sampled as lights: the copies keep the image right.
            b.warn(format!(
                "{context}: {} is placed {} times but emits light: copied per placement \
                 (instanced primitives are not sampled as lights in this version)",
                shared.name,
                shared.placements.len()
            ));
            let copy = shared.copied();
            let attributes = VertexAttributes {
                normals: copy.normals,
                uvs: copy.uvs,
            };
            b.add_mesh_with_attributes(
                &shared.name,
                &copy.mesh,
                attributes,
                &material_ids(&copy.triangle_material),
            )
            .map_err(scene_err)?;
            continue;
        }
        let mut part = b.part();
        let attributes = VertexAttributes {
            normals: shared.data.normals,
            uvs: shared.data.uvs,
        };
        part.add_mesh_with_attributes(&shared.name, &shared.data.mesh, attributes, &materials)
            .map_err(scene_err)?;
        let mesh = b
            .add_instance_mesh(shared.name.clone(), part)
            .map_err(scene_err)?;
        for p in shared.placements {
            b.add_instance(mesh, p, None).map_err(scene_err)?;
        }
    }
    Ok(())
}
