//! The scene: camera, materials, lights and geometry.

use crate::attributes::{AttributesAt, ShadingAttributes};
use crate::camera::{Camera, CameraOverrides, NamedCamera};
use crate::emitters::Emitters;
use crate::environment::Environment;
use crate::material::{Light, Material};
use crate::texture::Texture;
use crate::voxels::Volume;
use crate::{Geometry, Hit};
use glam::{Vec2, Vec3};
use std::sync::Arc;

/// One object of the scene file and the primitive ids it became.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectInfo {
    /// A name for messages (`sphere`, a mesh file name, a generator spec).
    pub name: String,
    /// First primitive id.
    pub first: u32,
    /// Number of primitives.
    pub count: u32,
}

/// A complete scene. Geometry is shared (`Arc`) so that backends can hold it while the
/// scene stays usable.
#[derive(Clone, Debug)]
pub struct Scene {
    /// A name for reports.
    pub name: String,
    /// The camera rendered: the first of [`Scene::cameras`] unless
    /// [`Scene::select_camera`] chose another or overrides adjusted it.
    pub camera: Camera,
    /// Every camera the scene defines, in file order; at least one (the camera framing the
    /// geometry, named `auto`, when the scene has none).
    pub cameras: Vec<NamedCamera>,
    /// Radiance of rays that hit nothing (linear RGB), where there is no environment map.
    pub background: Vec3,
    /// The environment map that replaces the constant background, if any.
    pub environment: Option<Arc<Environment>>,
    /// Materials; `prim_material` indexes into this.
    pub materials: Vec<Material>,
    /// Light sources.
    pub lights: Vec<Light>,
    /// All primitives.
    pub geometry: Arc<Geometry>,
    /// Material index of each flat primitive (ids `0..geometry.len()`); instanced
    /// primitives' materials are [`Scene::mesh_materials`] or their instance's override
    /// ([`Scene::material_of`] reads both).
    pub prim_material: Vec<u32>,
    /// Material index of each primitive of each distinct instanced mesh, in
    /// [`Geometry::meshes`] order.
    pub mesh_materials: Vec<Arc<[u32]>>,
    /// Each instance's material override, in [`Geometry::instances`] order.
    pub instance_materials: Vec<Option<u32>>,
    /// The objects, in scene order, then one per instance.
    pub objects: Vec<ObjectInfo>,
    /// The lights next-event estimation samples: emissive bounded primitives and the
    /// environment map.
    pub emitters: Emitters,
    /// Voxel volumes, rendered by the modes `mip` and `composite` (not primitives: they
    /// have no ids and acceleration structures never see them).
    pub volumes: Vec<Arc<Volume>>,
    /// Image textures, each held once and shared by the materials naming it
    /// ([`Material::base_color_texture`], [`Material::emission_texture`]).
    pub textures: Vec<Arc<Texture>>,
    /// Vertex normals and texture coordinates of the meshes that have them (flat ids).
    pub attributes: ShadingAttributes,
    /// Vertex normals and texture coordinates of each distinct instanced mesh, by the
    /// mesh's own primitive index, in [`Geometry::meshes`] order; empty when no instanced
    /// mesh has any. An instance's normals are carried to world space by its inverse
    /// transpose ([`crate::Instance::world_normal`]).
    pub mesh_attributes: Vec<ShadingAttributes>,
    /// What is legal but surely not what was meant (an object whose triangles are all
    /// degenerate, ...), one sentence each; the command line prints them as warnings.
    pub warnings: Vec<String>,
    /// What moves over frames (`None`: a still scene); [`Scene::at_frame`] gives frame `f`,
    /// and `geometry` is frame 0.
    pub motion: Option<Arc<crate::Motion>>,
}

/// What a surface looks like at a hit, beyond where it is: what the integrators shade.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceShading {
    /// The unit shading normal, on the side the geometric normal ([`Hit::normal`]) points
    /// to: the vertex normals interpolated, or the geometric normal without them.
    pub normal: Vec3,
    /// The diffuse colour (checkerboard and base-colour texture applied).
    pub albedo: Vec3,
    /// The base colour times its texture, without the checkerboard: ray casting's colour
    /// (which leaves checkerboards out, as the GPU's port does).
    pub base_color: Vec3,
    /// The emitted radiance (emission texture applied).
    pub emission: Vec3,
}

impl Scene {
    /// Makes camera `which` the one rendered: a name from [`Scene::cameras`], else a
    /// 0-based index into it; then applies `overrides` to it.
    ///
    /// # Errors
    /// When no camera has that name or index (the message lists them), or the adjusted
    /// camera cannot produce rays.
    pub fn select_camera(
        &mut self,
        which: Option<&str>,
        overrides: &CameraOverrides,
    ) -> Result<(), String> {
        let base = match which {
            None => self.camera,
            Some(w) => {
                let found = self.cameras.iter().find(|c| c.name == w).or_else(|| {
                    w.trim()
                        .parse::<usize>()
                        .ok()
                        .and_then(|i| self.cameras.get(i))
                });
                let Some(found) = found else {
                    let names: Vec<String> = self
                        .cameras
                        .iter()
                        .enumerate()
                        .map(|(i, c)| format!("{i}: '{}'", c.name))
                        .collect();
                    return Err(format!(
                        "scene '{}' has no camera '{w}' (its cameras: {})",
                        self.name,
                        names.join(", ")
                    ));
                };
                found.camera
            }
        };
        self.camera = overrides
            .apply(base)
            .map_err(|e| format!("the adjusted camera cannot render: {e}"))?;
        Ok(())
    }

    /// The material of primitive `prim` (any id of the flattened scene).
    ///
    /// # Panics
    /// When `prim` is not an id of the scene.
    #[inline]
    #[must_use]
    pub fn material_of(&self, prim: u32) -> &Material {
        // The flat ids' lookup as before; only an id past them (an instance's) goes out of
        // line, where a flat scene's out-of-range id panicked before.
        let m = match self.prim_material.get(prim as usize) {
            Some(&m) => m,
            None => self.instanced_material(prim),
        };
        &self.materials[m as usize]
    }

    /// The material index of the instanced primitive `prim` (cold: kept out of a flat
    /// scene's shading path).
    #[cold]
    #[inline(never)]
    fn instanced_material(&self, prim: u32) -> u32 {
        let Some((k, local)) = self.geometry.locate(prim) else {
            panic!("primitive {prim} is not in the scene");
        };
        let mesh = self.geometry.instances()[k].mesh() as usize;
        self.instance_materials[k].unwrap_or_else(|| self.mesh_materials[mesh][local as usize])
    }

    /// Texture `t` at `uv`, or 1 without texture (a factor to multiply with).
    #[inline(always)]
    fn texel(&self, t: Option<u32>, uv: Option<Vec2>) -> Vec3 {
        match (t, uv) {
            (Some(t), Some(uv)) => self.textures[t as usize].sample(uv),
            _ => Vec3::ONE,
        }
    }

    /// The shading normal, colour and emission at `hit`, whose point is `p`. The vertex
    /// normals are interpolated with the hit's barycentric weights `u`, `v` and flipped,
    /// when they disagree with the winding, to the geometric normal's side. Inlined into
    /// every shader, so that what a shader leaves unused is not computed (out of line, the
    /// record's trip through the stack cost ray casting 4 to 11 % of whole frames).
    #[inline(always)]
    #[must_use]
    pub fn shading(&self, hit: &Hit, p: Vec3) -> SurfaceShading {
        let m = self.material_of(hit.prim);
        let at = self.attributes_at(hit.prim, hit.u, hit.v);
        let normal = match at.normal {
            Some(n) if n.dot(hit.normal) < 0.0 => -n,
            Some(n) => n,
            None => hit.normal,
        };
        let texel = self.texel(m.base_color_texture, at.uv);
        SurfaceShading {
            normal,
            albedo: m.albedo_at(p) * texel,
            base_color: m.base_color * texel,
            emission: m.emission * self.texel(m.emission_texture, at.uv),
        }
    }

    /// The radiance primitive `prim` emits at surface parameters `u`, `v` (for triangles
    /// the barycentric weights of vertices 1 and 2), the emission texture applied.
    #[inline]
    #[must_use]
    pub fn emission_at(&self, prim: u32, u: f32, v: f32) -> Vec3 {
        let m = self.material_of(prim);
        if m.emission_texture.is_none() {
            return m.emission;
        }
        m.emission * self.texel(m.emission_texture, self.attributes_at(prim, u, v).uv)
    }

    /// The shading attributes of primitive `prim` (any id of the flattened scene) at
    /// barycentric weights `u`, `v`: a flat primitive's from [`Scene::attributes`], an
    /// instanced one's from its mesh's, the normal carried to world space.
    #[inline(always)]
    fn attributes_at(&self, prim: u32, u: f32, v: f32) -> AttributesAt {
        if !self.mesh_attributes.is_empty() && prim as usize >= self.prim_material.len() {
            return self.instanced_attributes_at(prim, u, v);
        }
        self.attributes.at(prim, u, v)
    }

    /// [`Scene::attributes_at`] of an instanced primitive (cold: kept out of a flat
    /// scene's shading path).
    #[cold]
    #[inline(never)]
    fn instanced_attributes_at(&self, prim: u32, u: f32, v: f32) -> AttributesAt {
        let Some((k, local)) = self.geometry.locate(prim) else {
            return AttributesAt::default();
        };
        let instance = &self.geometry.instances()[k];
        let mut at = self.mesh_attributes[instance.mesh() as usize].at(local, u, v);
        at.normal = at.normal.map(|n| instance.world_normal(n));
        at
    }

    /// Whether some material uses a texture.
    #[must_use]
    pub fn has_textures(&self) -> bool {
        self.materials
            .iter()
            .any(|m| m.base_color_texture.is_some() || m.emission_texture.is_some())
    }

    /// The radiance arriving along a ray with direction `dir` that hits nothing: the
    /// environment map's, or the constant background.
    #[inline]
    #[must_use]
    pub fn background_along(&self, dir: Vec3) -> Vec3 {
        match &self.environment {
            Some(env) => env.radiance(dir),
            None => self.background,
        }
    }
}
