//! Instances: the parts an instance mesh is built from ([`SceneBuilder::part`]), its
//! materials and textures adopted by the scene, and the placed copies with their checks.

use super::{InstanceMesh, SceneBuilder};
use crate::{Geometry, Instance, SceneError, limits};
use glam::Affine3A;
use std::sync::Arc;

impl SceneBuilder {
    /// An empty builder with this one's materials and textures, in which the objects of an
    /// instance mesh are added before [`SceneBuilder::add_instance_mesh`] takes them.
    #[must_use]
    pub fn part(&self) -> Self {
        let mut part = Self::new(self.name.clone());
        part.materials.clone_from(&self.materials);
        part.textures.clone_from(&self.textures);
        part.texture_keys.clone_from(&self.texture_keys);
        part.shared = (part.materials.len(), part.textures.len());
        part
    }

    /// Takes the materials and textures `part` added (a mesh file's own) into this scene,
    /// and returns its primitives' material indices in this scene's numbering.
    fn adopt_materials(&mut self, part: &SceneBuilder) -> Vec<u32> {
        let (m0, t0) = part.shared;
        let textures: Vec<u32> = (t0..part.textures.len())
            .map(|t| {
                let key = part
                    .texture_keys
                    .iter()
                    .find(|&(_, &i)| i as usize == t)
                    .map_or_else(|| format!("instance texture {t}"), |(k, _)| k.clone());
                if let Some(&i) = self.texture_keys.get(&key) {
                    return i;
                }
                self.textures.push(Arc::clone(&part.textures[t]));
                let i = (self.textures.len() - 1) as u32;
                self.texture_keys.insert(key, i);
                i
            })
            .collect();
        let remap_texture = |t: Option<u32>| {
            t.map(|t| match (t as usize).checked_sub(t0) {
                Some(k) => textures[k],
                None => t,
            })
        };
        let materials: Vec<u32> = part.materials[m0..]
            .iter()
            .map(|m| {
                let mut m = m.clone();
                m.base_color_texture = remap_texture(m.base_color_texture);
                m.emission_texture = remap_texture(m.emission_texture);
                self.materials.push(m);
                (self.materials.len() - 1) as u32
            })
            .collect();
        part.prim_material
            .iter()
            .map(|&m| match (m as usize).checked_sub(m0) {
                Some(k) => materials[k],
                None => m,
            })
            .collect()
    }

    /// Makes the primitives of `part` (a builder from [`SceneBuilder::part`]) a mesh that
    /// instances can place, named `name` in messages; returns its index for
    /// [`SceneBuilder::add_instance`]. Its primitives are stored once, however many
    /// instances place them, with its vertex normals and texture coordinates (each
    /// instance's normals carried by its inverse transpose); its cameras, lights and
    /// volumes are not taken.
    ///
    /// # Errors
    /// When the mesh has no primitives or an unbounded one (a plane), or the scene's
    /// stored primitives would exceed [`limits::MAX_PRIMITIVES`].
    pub fn add_instance_mesh(
        &mut self,
        name: impl Into<String>,
        part: SceneBuilder,
    ) -> Result<u32, SceneError> {
        let name = name.into();
        if part.shapes.is_empty() {
            return Err(SceneError::Invalid(format!(
                "instance mesh '{name}' has no primitives"
            )));
        }
        if part.shapes.iter().any(|s| s.bounds().is_none()) {
            return Err(SceneError::Invalid(format!(
                "instance mesh '{name}' holds a plane: only bounded primitives can be \
                 instanced"
            )));
        }
        self.check_room(part.shapes.len())?;
        let materials = self.adopt_materials(&part);
        for w in part.warnings {
            self.warn(w);
        }
        self.meshes.push(InstanceMesh {
            name,
            geometry: Arc::new(Geometry::new(part.shapes)),
            materials: materials.into(),
            attributes: part.attributes,
        });
        let mesh = (self.meshes.len() - 1) as u32;
        // The part's deformations target its flat primitives: now they target the mesh.
        for d in part.motion.deforms() {
            self.motion
                .deform(d.clone().with_target(crate::DeformTarget::Mesh(mesh)));
        }
        Ok(mesh)
    }

    /// Places mesh `mesh` (from [`SceneBuilder::add_instance_mesh`]) by `to_world`, with
    /// its own materials or `material` for all its primitives. Its primitives' ids follow
    /// every flat primitive's, in instance order, whenever the instance is added.
    ///
    /// # Errors
    /// When the mesh or material does not exist, the transform is not finite, singular or
    /// badly conditioned, a material of the instance emits light (instanced emitters are
    /// not sampled as lights in this version), or the scene would exceed
    /// [`limits::MAX_INSTANCES`] instances or [`limits::MAX_INSTANCED_PRIMITIVES`]
    /// primitives flattened.
    pub fn add_instance(
        &mut self,
        mesh: u32,
        to_world: Affine3A,
        material: Option<u32>,
    ) -> Result<&mut Self, SceneError> {
        let Some(m) = self.meshes.get(mesh as usize) else {
            return Err(SceneError::Invalid(format!(
                "instance mesh index {mesh} does not exist"
            )));
        };
        if let Some(material) = material {
            self.check_material(material)?;
        }
        let instance = Instance::new(mesh, &m.geometry, to_world)?;
        let emissive = match material {
            Some(i) => self.material_emits(i),
            None => m.materials.iter().any(|&i| self.material_emits(i)),
        };
        if emissive {
            return Err(SceneError::Invalid(format!(
                "an instance of '{}' emits light: instanced primitives are not sampled as \
                 lights in this version (use a non-emissive material)",
                m.name
            )));
        }
        if self.instances.len() >= limits::MAX_INSTANCES {
            return Err(SceneError::TooLarge(format!(
                "the scene would have more than {} instances",
                limits::MAX_INSTANCES
            )));
        }
        self.check_total(u64::from(instance.count()))?;
        self.instanced += u64::from(instance.count());
        self.instances.push(instance);
        self.instance_materials.push(material);
        Ok(self)
    }

    /// Checks, before anything is allocated, that `count` more instances of mesh `mesh`
    /// fit in [`limits::MAX_INSTANCES`] and [`limits::MAX_INSTANCED_PRIMITIVES`] (for
    /// arrays of instances, which would otherwise find out one instance at a time).
    ///
    /// # Errors
    /// When the mesh does not exist or a limit would be exceeded.
    pub fn check_instances(&self, mesh: u32, count: u64) -> Result<(), SceneError> {
        let Some(m) = self.meshes.get(mesh as usize) else {
            return Err(SceneError::Invalid(format!(
                "instance mesh index {mesh} does not exist"
            )));
        };
        let instances = self.instances.len() as u64 + count;
        if instances > limits::MAX_INSTANCES as u64 {
            return Err(SceneError::TooLarge(format!(
                "the scene would have {instances} instances (limit {})",
                limits::MAX_INSTANCES
            )));
        }
        self.check_total(count.saturating_mul(m.geometry.len() as u64))
    }
}
