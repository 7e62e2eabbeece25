//! The checked scene builder: objects, materials, lights, cameras and instances added one
//! by one, every value checked, global primitive ids assigned in call order.

use crate::Plane;
use crate::SceneError;
use crate::Sphere;
use crate::Triangle;
use crate::TriangleMesh;
use crate::attributes::{ShadingAttributes, VertexAttributes};
use crate::camera::{Camera, NamedCamera};
use crate::emitters::Emitters;
use crate::environment::Environment;
use crate::limits;
use crate::material::{Light, Material};
use crate::scene::{ObjectInfo, Scene};
use crate::texture::Texture;
use crate::voxels::Volume;
use crate::{Geometry, Instance, Shape};
use glam::Vec3;
use std::collections::HashMap;
use std::sync::Arc;

mod instances;

/// Builds a [`Scene`], object by object, assigning global primitive ids in call order and
/// checking every coordinate.
#[derive(Clone, Debug)]
pub struct SceneBuilder {
    name: String,
    cameras: Vec<NamedCamera>,
    background: Vec3,
    environment: Option<Arc<Environment>>,
    pub(crate) materials: Vec<Material>,
    lights: Vec<Light>,
    pub(crate) shapes: Vec<Shape>,
    pub(crate) prim_material: Vec<u32>,
    pub(crate) objects: Vec<ObjectInfo>,
    volumes: Vec<Arc<Volume>>,
    textures: Vec<Arc<Texture>>,
    texture_keys: HashMap<String, u32>,
    pub(crate) attributes: ShadingAttributes,
    /// What moves (`animation.rs`).
    pub(crate) motion: crate::Motion,
    warnings: Vec<String>,
    meshes: Vec<InstanceMesh>,
    pub(crate) instances: Vec<Instance>,
    instance_materials: Vec<Option<u32>>,
    instanced: u64,
    /// For a builder from [`SceneBuilder::part`]: how many materials and textures it
    /// started with (those it shares with its scene).
    shared: (usize, usize),
}

/// A distinct mesh that instances place: its name, primitives and their materials.
#[derive(Clone, Debug)]
struct InstanceMesh {
    name: String,
    geometry: Arc<Geometry>,
    materials: Arc<[u32]>,
    attributes: ShadingAttributes,
}

fn finite(v: Vec3, what: &str) -> Result<(), SceneError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(SceneError::NonFinite(what.to_string()))
    }
}

/// A colour or radiance: finite and no component negative (a negative colour or emission
/// is not light; it would render as silent garbage).
fn colour(v: Vec3, what: &str) -> Result<(), SceneError> {
    finite(v, what)?;
    if v.min_element() < 0.0 {
        return Err(SceneError::Invalid(format!(
            "{what} {v} has a negative component (colours and light are at least 0)"
        )));
    }
    Ok(())
}

/// A position: finite and within [`limits::MAX_COORDINATE`].
fn coordinate(v: Vec3, what: &str) -> Result<(), SceneError> {
    finite(v, what)?;
    if v.abs().max_element() > limits::MAX_COORDINATE {
        return Err(SceneError::TooLarge(format!(
            "{what} {v} exceeds the coordinate limit of {:e}",
            limits::MAX_COORDINATE
        )));
    }
    Ok(())
}

impl SceneBuilder {
    /// An empty scene named `name`, with the default material at index 0.
    #[must_use]
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            cameras: Vec::new(),
            background: Vec3::new(0.05, 0.05, 0.08),
            environment: None,
            materials: vec![Material::default()],
            lights: Vec::new(),
            shapes: Vec::new(),
            prim_material: Vec::new(),
            objects: Vec::new(),
            volumes: Vec::new(),
            textures: Vec::new(),
            texture_keys: HashMap::new(),
            attributes: ShadingAttributes::default(),
            motion: crate::Motion::new(),
            warnings: Vec::new(),
            meshes: Vec::new(),
            instances: Vec::new(),
            instance_materials: Vec::new(),
            instanced: 0,
            shared: (1, 0),
        }
    }

    /// Whether material `material` (an index [`SceneBuilder::add_material`] returned)
    /// emits light.
    ///
    /// # Panics
    /// When there is no such material.
    #[must_use]
    pub fn material_emits(&self, material: u32) -> bool {
        self.materials[material as usize].emission.max_element() > 0.0
    }

    /// Checks that `more` primitives fit in [`limits::MAX_INSTANCED_PRIMITIVES`], the
    /// flattened scene's ids.
    fn check_total(&self, more: u64) -> Result<(), SceneError> {
        let total = (self.shapes.len() as u64 + self.instanced).saturating_add(more);
        if total > limits::MAX_INSTANCED_PRIMITIVES {
            return Err(SceneError::TooLarge(format!(
                "the scene would have {total} primitives once its instances are counted \
                 (limit {})",
                limits::MAX_INSTANCED_PRIMITIVES
            )));
        }
        Ok(())
    }

    /// Adds a camera named `camera` (`camera 2`, ... when that name is taken); the first
    /// camera added is the one rendered by default. Without any, [`SceneBuilder::build`]
    /// frames the geometry.
    ///
    /// # Errors
    /// When the camera cannot produce rays ([`Camera::check`] says why).
    pub fn camera(&mut self, camera: Camera) -> Result<&mut Self, SceneError> {
        self.add_camera(None, camera)
    }

    /// Adds a camera under `name` (a generated one, `camera` or `camera N`, when `None`).
    ///
    /// # Errors
    /// When the camera cannot produce rays ([`Camera::check`] says why) or the name is
    /// taken.
    pub fn add_camera(
        &mut self,
        name: Option<&str>,
        camera: Camera,
    ) -> Result<&mut Self, SceneError> {
        camera.check().map_err(SceneError::Invalid)?;
        let taken = |n: &str| self.cameras.iter().any(|c| c.name == n);
        let name = match name {
            Some(n) if taken(n) => {
                return Err(SceneError::Invalid(format!("two cameras are named '{n}'")));
            }
            Some(n) => n.to_owned(),
            None => (1..)
                .map(|i| {
                    if i == 1 {
                        "camera".to_owned()
                    } else {
                        format!("camera {i}")
                    }
                })
                .find(|n| !taken(n))
                .unwrap_or_default(),
        };
        self.cameras.push(NamedCamera { name, camera });
        Ok(self)
    }

    /// Sets the background radiance.
    ///
    /// # Errors
    /// When it is not finite or has a negative component.
    pub fn background(&mut self, color: Vec3) -> Result<&mut Self, SceneError> {
        colour(color, "background")?;
        self.background = color;
        Ok(self)
    }

    /// Sets an environment map as the background (seen by rays that miss, sampled as a
    /// light in `path` mode); it replaces the constant background.
    pub fn environment(&mut self, environment: Arc<Environment>) -> &mut Self {
        self.environment = Some(environment);
        self
    }

    /// Adds a material and returns its index.
    ///
    /// # Errors
    /// When a colour or parameter is not finite, a colour or the emission has a negative
    /// component, the ior is not above 0 or the shininess is below 0.
    pub fn add_material(&mut self, m: Material) -> Result<u32, SceneError> {
        let what = format!("material '{}'", m.name);
        colour(m.base_color, &format!("{what}: color"))?;
        colour(m.specular, &format!("{what}: specular"))?;
        colour(m.emission, &format!("{what}: emission"))?;
        if !(m.ior.is_finite() && m.ior > 0.0) {
            return Err(SceneError::Invalid(format!(
                "{what}: ior {} must be positive and finite",
                m.ior
            )));
        }
        // A negative exponent makes the highlight infinite where n.h is 0.
        if !(m.shininess.is_finite() && m.shininess >= 0.0) {
            return Err(SceneError::Invalid(format!(
                "{what}: shininess {} must be finite and at least 0",
                m.shininess
            )));
        }
        for t in [m.base_color_texture, m.emission_texture]
            .into_iter()
            .flatten()
        {
            if t as usize >= self.textures.len() {
                return Err(SceneError::Invalid(format!(
                    "{what}: texture index {t} does not exist"
                )));
            }
        }
        if let Some(c) = m.checker {
            colour(c.color, &format!("{what}: checker color"))?;
            if !(c.size.is_finite() && c.size > 0.0) {
                return Err(SceneError::Invalid(format!(
                    "{what}: checker size must be positive and finite"
                )));
            }
        }
        self.materials.push(m);
        Ok((self.materials.len() - 1) as u32)
    }

    /// Adds a texture under `key` (what identifies its source: a canonical file path and
    /// its wrap modes, say) and returns its index; a texture already added under `key` is
    /// not added again, its index is returned.
    pub fn add_texture(&mut self, key: impl Into<String>, texture: Texture) -> u32 {
        let key = key.into();
        if let Some(&i) = self.texture_keys.get(&key) {
            return i;
        }
        self.textures.push(Arc::new(texture));
        let i = (self.textures.len() - 1) as u32;
        self.texture_keys.insert(key, i);
        i
    }

    /// The index of the texture added under `key`, if any (so a loader decodes each image
    /// once per scene).
    #[must_use]
    pub fn texture(&self, key: &str) -> Option<u32> {
        self.texture_keys.get(key).copied()
    }

    /// Adds a light.
    ///
    /// # Errors
    /// When a vector is not finite, a direction is zero or an intensity or radiance has a
    /// negative component.
    pub fn add_light(&mut self, light: Light) -> Result<&mut Self, SceneError> {
        let light = match light {
            Light::Point {
                position,
                intensity,
            } => {
                coordinate(position, "light position")?;
                colour(intensity, "light intensity")?;
                light
            }
            Light::Directional {
                direction,
                radiance,
            } => {
                finite(direction, "light direction")?;
                colour(radiance, "light radiance")?;
                let Some(direction) = direction.try_normalize() else {
                    return Err(SceneError::Invalid("light direction is zero".into()));
                };
                Light::Directional {
                    direction,
                    radiance,
                }
            }
        };
        self.lights.push(light);
        Ok(self)
    }

    /// Checks that `more` stored primitives fit in [`limits::MAX_PRIMITIVES`] (the flat
    /// ones and each instance mesh's once) and in the flattened ids.
    fn check_room(&self, more: usize) -> Result<(), SceneError> {
        let stored: usize = self.meshes.iter().map(|m| m.geometry.len()).sum();
        if self.shapes.len() + stored + more > limits::MAX_PRIMITIVES {
            return Err(SceneError::TooLarge(format!(
                "the scene would have {} primitives (limit {})",
                self.shapes.len() + stored + more,
                limits::MAX_PRIMITIVES
            )));
        }
        self.check_total(more as u64)
    }

    fn check_material(&self, material: u32) -> Result<(), SceneError> {
        if material as usize >= self.materials.len() {
            return Err(SceneError::Invalid(format!(
                "material index {material} does not exist"
            )));
        }
        Ok(())
    }

    fn push_object(
        &mut self,
        name: String,
        shapes: impl IntoIterator<Item = Shape>,
        material: u32,
    ) {
        let first = self.shapes.len() as u32;
        self.shapes.extend(shapes);
        let count = self.shapes.len() as u32 - first;
        self.prim_material.resize(self.shapes.len(), material);
        self.objects.push(ObjectInfo { name, first, count });
    }

    /// Adds a sphere with material index `material`.
    ///
    /// # Errors
    /// When the centre or radius is not finite, or the radius is not positive, above
    /// [`limits::MAX_COORDINATE`] or too small for `f32` ([`limits::MIN_SPHERE_RADIUS`],
    /// [`limits::MIN_RELATIVE_SPHERE_RADIUS`]).
    pub fn add_sphere(&mut self, sphere: Sphere, material: u32) -> Result<&mut Self, SceneError> {
        coordinate(sphere.center, "sphere centre")?;
        let r = sphere.radius;
        if !(r.is_finite() && r > 0.0 && r <= limits::MAX_COORDINATE) {
            return Err(SceneError::Invalid(format!(
                "sphere radius {r} must be positive, finite and at most {:e}",
                limits::MAX_COORDINATE
            )));
        }
        let min = limits::MIN_SPHERE_RADIUS
            .max(limits::MIN_RELATIVE_SPHERE_RADIUS * sphere.center.abs().max_element());
        if r < min {
            return Err(SceneError::Invalid(format!(
                "sphere radius {r:e} is below {min:e}, the smallest that f32 resolves at \
                 centre {} (radii start at {:e} and at {:e} times the centre's largest \
                 coordinate)",
                sphere.center,
                limits::MIN_SPHERE_RADIUS,
                limits::MIN_RELATIVE_SPHERE_RADIUS
            )));
        }
        self.check_material(material)?;
        self.check_room(1)?;
        self.push_object("sphere".into(), [Shape::Sphere(sphere)], material);
        Ok(self)
    }

    /// Adds an infinite plane.
    ///
    /// # Errors
    /// When a vector is not finite or the normal is zero.
    pub fn add_plane(
        &mut self,
        point: Vec3,
        normal: Vec3,
        material: u32,
    ) -> Result<&mut Self, SceneError> {
        coordinate(point, "plane point")?;
        finite(normal, "plane normal")?;
        if normal.length_squared() == 0.0 {
            return Err(SceneError::Invalid("plane normal is zero".into()));
        }
        self.check_material(material)?;
        self.check_room(1)?;
        self.push_object(
            "plane".into(),
            [Shape::Plane(Plane::new(point, normal))],
            material,
        );
        Ok(self)
    }

    /// Adds a triangle mesh (one object, its triangles in index order). Degenerate triangles
    /// are kept so that ids stay those of the file; they are never hit.
    ///
    /// # Errors
    /// From [`TriangleMesh::validate`], or when the scene grows past the limit.
    pub fn add_mesh(
        &mut self,
        name: impl Into<String>,
        mesh: &TriangleMesh,
        material: u32,
    ) -> Result<&mut Self, SceneError> {
        mesh.validate()?;
        self.check_material(material)?;
        self.check_room(mesh.indices.len())?;
        let name = name.into();
        self.warn_if_degenerate(&name, mesh.triangles());
        self.push_object(name, mesh.triangles().map(Shape::Triangle), material);
        Ok(self)
    }

    /// Adds primitives that their own checked constructors built (a height field, a CSG
    /// tree, Bezier patches, an SDF model: any kind with an object of its own) as one
    /// object, one primitive id per shape in order. The one entry point of such kinds, so a
    /// new kind needs nothing here.
    ///
    /// # Errors
    /// When the material does not exist, the scene is full, or a bounded shape's box is not
    /// finite.
    pub fn add_shapes(
        &mut self,
        name: impl Into<String>,
        shapes: Vec<Shape>,
        material: u32,
    ) -> Result<&mut Self, SceneError> {
        let name = name.into();
        self.check_material(material)?;
        self.check_room(shapes.len())?;
        for s in &shapes {
            if let Some(b) = s.bounds()
                && !(b.min.is_finite() && b.max.is_finite())
            {
                return Err(SceneError::NonFinite(format!("the box of {name}")));
            }
        }
        self.push_object(name, shapes, material);
        Ok(self)
    }

    /// Adds triangles with one material each (`materials[i]` for `triangles[i]`), as one
    /// object: how OBJ files with several `usemtl` groups arrive.
    ///
    /// # Errors
    /// When a vertex is not finite, a material does not exist, or the lengths differ.
    pub fn add_triangles(
        &mut self,
        name: impl Into<String>,
        triangles: &[Triangle],
        materials: &[u32],
    ) -> Result<&mut Self, SceneError> {
        if triangles.len() != materials.len() {
            return Err(SceneError::Invalid(
                "one material per triangle needed".into(),
            ));
        }
        for (i, t) in triangles.iter().enumerate() {
            for v in t.v {
                coordinate(v, &format!("vertex of triangle {}", i + 1))?;
            }
        }
        for &m in materials {
            self.check_material(m)?;
        }
        self.check_room(triangles.len())?;
        let name = name.into();
        self.warn_if_degenerate(&name, triangles.iter().copied());
        let first = self.shapes.len() as u32;
        self.shapes
            .extend(triangles.iter().copied().map(Shape::Triangle));
        self.prim_material.extend_from_slice(materials);
        self.objects.push(ObjectInfo {
            name,
            first,
            count: triangles.len() as u32,
        });
        Ok(self)
    }

    /// Adds a triangle mesh with one material per triangle (`materials[i]` for triangle
    /// `i`) and per-vertex shading attributes, as one object: the entry point of mesh
    /// files. Either attribute list may be empty; a non-empty one has one entry per vertex.
    /// Vertex normals are normalised; zero or non-finite ones are replaced by the geometric
    /// normal of their triangles, with a warning. Texture coordinates outside `[0, 1]` wrap
    /// (the texture's modes decide how).
    ///
    /// # Errors
    /// From [`TriangleMesh::validate`]; when an attribute list's length is not the vertex
    /// count, a texture coordinate is not finite, a material does not exist, the lengths of
    /// `materials` and the triangles differ, or the scene grows past the limit.
    pub fn add_mesh_with_attributes(
        &mut self,
        name: impl Into<String>,
        mesh: &TriangleMesh,
        attributes: VertexAttributes,
        materials: &[u32],
    ) -> Result<&mut Self, SceneError> {
        let name = name.into();
        mesh.validate()?;
        let vertices = mesh.positions.len();
        for (what, len) in [
            ("vertex normals", attributes.normals.len()),
            ("texture coordinates", attributes.uvs.len()),
        ] {
            if len != 0 && len != vertices {
                return Err(SceneError::Invalid(format!(
                    "{name}: {len} {what} for {vertices} vertices"
                )));
            }
        }
        if let Some(i) = attributes.uvs.iter().position(|uv| !uv.is_finite()) {
            return Err(SceneError::NonFinite(format!(
                "{name}: texture coordinates of vertex {}",
                i + 1
            )));
        }
        let mut unusable = 0usize;
        let normals: Vec<Vec3> = attributes
            .normals
            .iter()
            .map(|n| {
                n.try_normalize().unwrap_or_else(|| {
                    unusable += 1;
                    Vec3::ZERO
                })
            })
            .collect();
        let triangles: Vec<Triangle> = mesh.triangles().collect();
        let first = self.shapes.len() as u32;
        self.add_triangles(name.clone(), &triangles, materials)?;
        if unusable > 0 {
            self.warn(format!(
                "{name}: {unusable} vertex normals are zero or not finite: their triangles \
 \
                 are shaded with their geometric normals"
            ));
        }
        self.attributes
            .push(first, mesh.indices.clone(), normals, attributes.uvs);
        Ok(self)
    }

    /// Adds a voxel volume.
    ///
    /// # Errors
    /// When its bounds exceed [`limits::MAX_COORDINATE`].
    pub fn add_volume(&mut self, volume: Arc<Volume>) -> Result<&mut Self, SceneError> {
        let b = volume.bounds();
        coordinate(b.min, "volume bounds")?;
        coordinate(b.max, "volume bounds")?;
        self.volumes.push(volume);
        Ok(self)
    }

    /// Records a warning: something legal but surely not what was meant. It ends up in
    /// [`Scene::warnings`].
    /// A warning already recorded is not repeated (a missing texture named by several
    /// materials is one warning).
    pub fn warn(&mut self, message: impl Into<String>) {
        let message = message.into();
        if !self.warnings.contains(&message) {
            self.warnings.push(message);
        }
    }

    /// Warns when every one of an object's triangles (at least one) has zero area: they are
    /// kept, so that ids stay those of the file, but never hit, so the object is invisible.
    fn warn_if_degenerate(&mut self, name: &str, mut triangles: impl Iterator<Item = Triangle>) {
        let mut any = false;
        let all = triangles.all(|t| {
            any = true;
            (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]) == Vec3::ZERO
        });
        if any && all {
            self.warn(format!(
                "every triangle of {name} has zero area: it will not be visible"
            ));
        }
    }

    /// Number of primitives added so far.
    #[must_use]
    pub fn primitive_count(&self) -> usize {
        self.shapes.len()
    }

    /// Number of materials so far.
    #[must_use]
    pub fn material_count(&self) -> usize {
        self.materials.len()
    }

    /// Finishes the scene; without a camera, one framing the geometry is chosen.
    #[must_use]
    pub fn build(mut self) -> Scene {
        let mesh_materials = self.meshes.iter().map(|m| m.materials.clone()).collect();
        let mesh_attributes = if self.meshes.iter().all(|m| m.attributes.is_empty()) {
            Vec::new()
        } else {
            self.meshes.iter().map(|m| m.attributes.clone()).collect()
        };
        let geometry = Geometry::with_instances(
            self.shapes,
            self.meshes
                .iter()
                .map(|m| Arc::clone(&m.geometry))
                .collect(),
            self.instances,
        );
        for i in geometry.instances() {
            self.objects.push(ObjectInfo {
                name: format!("instance of {}", self.meshes[i.mesh() as usize].name),
                first: i.base(),
                count: i.count(),
            });
        }
        let framed = self
            .volumes
            .iter()
            .fold(geometry.world_bounds(), |b, v| b.union(v.bounds()));
        let mut cameras = self.cameras;
        if cameras.is_empty() {
            cameras.push(NamedCamera {
                name: "auto".into(),
                camera: Camera::framing(framed),
            });
        }
        let camera = cameras[0].camera;
        let (emitters, left_out) = Emitters::new(
            &geometry,
            &self.prim_material,
            &self.materials,
            self.environment.as_deref(),
        );
        if left_out.unbounded > 0 {
            self.warnings.push(format!(
                "{} emissive plane(s) are unbounded: path tracing finds their light \
 \
                 by BSDF sampling only (no next-event estimation), so expect noise",
                left_out.unbounded
            ));
        }
        if let Some(first) = left_out.first_hidden {
            self.warnings.push(format!(
                "{} emissive triangle(s) (the first: primitive {first}) coincide with a \
                 triangle of a smaller id, which every ray hits instead: they are not sampled \
                 as lights",
                left_out.hidden
            ));
        }
        Scene {
            name: self.name,
            camera,
            cameras,
            background: self.background,
            environment: self.environment,
            materials: self.materials,
            lights: self.lights,
            geometry: Arc::new(geometry),
            prim_material: self.prim_material,
            mesh_materials,
            instance_materials: self.instance_materials,
            objects: self.objects,
            emitters,
            volumes: self.volumes,
            textures: self.textures,
            attributes: self.attributes,
            mesh_attributes,
            warnings: self.warnings,
            motion: (!self.motion.is_empty()).then(|| Arc::new(self.motion)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Hit;
    use glam::Vec2;

    #[test]
    fn ids_follow_insertion_order() {
        let mut b = SceneBuilder::new("t");
        b.add_sphere(Sphere::new(Vec3::ZERO, 1.0), 0).unwrap();
        let mesh = TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            indices: vec![[0, 1, 2], [0, 2, 1]],
        };
        b.add_mesh("m", &mesh, 0).unwrap();
        b.add_plane(Vec3::ZERO, Vec3::Y, 0).unwrap();
        let s = b.build();
        assert_eq!(s.geometry.len(), 4);
        assert_eq!(s.geometry.unbounded(), &[3]);
        assert_eq!(s.objects[1].first, 1);
        assert_eq!(s.objects[1].count, 2);
    }

    #[test]
    fn bad_values_are_refused() {
        let mut b = SceneBuilder::new("t");
        assert!(b.add_sphere(Sphere::new(Vec3::NAN, 1.0), 0).is_err());
        assert!(b.add_sphere(Sphere::new(Vec3::ZERO, -1.0), 0).is_err());
        assert!(b.add_sphere(Sphere::new(Vec3::ZERO, 1.0), 7).is_err());
        assert!(b.add_plane(Vec3::ZERO, Vec3::ZERO, 0).is_err());
        assert!(b.background(Vec3::INFINITY).is_err());
        // Objects built elsewhere: a non-finite box and a missing material are refused.
        let nan = Shape::Sphere(Sphere::new(Vec3::NAN, 1.0));
        assert!(b.add_shapes("s", vec![nan], 0).is_err());
        let ok = Shape::Sphere(Sphere::new(Vec3::ZERO, 1.0));
        assert!(b.add_shapes("s", vec![ok.clone()], 7).is_err());
        assert_eq!(b.primitive_count(), 0);
        b.add_shapes("s", vec![ok.clone(), ok], 0).unwrap();
        assert_eq!(b.primitive_count(), 2);
    }

    /// Every bounded emitter is a light; an emissive plane is not (it has no bounds) and
    /// gets a warning.
    #[test]
    fn bounded_emitters_are_lights_and_planes_warn() {
        let mut b = SceneBuilder::new("t");
        let lamp = b
            .add_material(Material {
                emission: Vec3::ONE,
                ..Material::default()
            })
            .unwrap();
        b.add_sphere(Sphere::new(Vec3::ZERO, 1.0), lamp).unwrap();
        b.add_sphere(Sphere::new(Vec3::X * 3.0, 1.0), 0).unwrap();
        b.add_plane(Vec3::ZERO, Vec3::Y, lamp).unwrap();
        let s = b.build();
        assert_eq!(s.emitters.ids, vec![0]);
        assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
        assert!(
            s.warnings[0].contains("BSDF sampling only"),
            "{:?}",
            s.warnings
        );
    }

    #[test]
    fn attributes_are_checked_and_shade_only() {
        let mesh = TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            indices: vec![[0, 1, 2]],
        };
        let attrs = |normals: Vec<Vec3>, uvs: Vec<Vec2>| VertexAttributes { normals, uvs };
        let mut b = SceneBuilder::new("t");
        let e = b
            .add_mesh_with_attributes("m", &mesh, attrs(vec![Vec3::Z; 2], vec![]), &[0])
            .unwrap_err()
            .to_string();
        assert!(e.contains("2 vertex normals for 3 vertices"), "{e}");
        let nan = vec![Vec2::ZERO, Vec2::NAN, Vec2::ONE];
        let e = b
            .add_mesh_with_attributes("m", &mesh, attrs(vec![], nan), &[0])
            .unwrap_err()
            .to_string();
        assert!(e.contains("texture coordinates of vertex 2"), "{e}");
        assert_eq!(b.primitive_count(), 0);
        // Normals opposite to the winding, one of them NaN: the geometric normal, a warning.
        let n = vec![-Vec3::Z, Vec3::NAN, -Vec3::Z];
        b.add_mesh_with_attributes("m", &mesh, attrs(n, vec![]), &[0])
            .unwrap();
        let n = vec![-Vec3::Z, Vec3::new(0.0, 1.0, -1.0), -Vec3::Z];
        b.add_mesh_with_attributes("m", &mesh, attrs(n, vec![]), &[0])
            .unwrap();
        let s = b.build();
        assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
        let hit = |prim| Hit {
            t: 1.0,
            prim,
            sub: 0,
            u: 0.5,
            v: 0.0,
            normal: Vec3::Z,
        };
        assert_eq!(s.shading(&hit(0), Vec3::ZERO).normal, Vec3::Z);
        // Half-way between -z and (0, 1, -1) / sqrt 2, turned to the geometric normal's side.
        let n = s.shading(&hit(1), Vec3::ZERO).normal;
        let half = 0.5 * 0.5f32.sqrt();
        let expect = -Vec3::new(0.0, half, -0.5 - half).normalize();
        assert!((n - expect).length() < 1e-6, "{n}");
    }

    /// Bad values: negative colours, a sphere too small for f32, all-degenerate meshes.
    #[test]
    fn silent_garbage_is_refused_or_warned() {
        let mut b = SceneBuilder::new("t");
        let neg = |base_color, emission| Material {
            name: "m".into(),
            base_color,
            emission,
            ..Material::default()
        };
        let e = b
            .add_material(neg(Vec3::new(-1.0, 5.0, 0.5), Vec3::ZERO))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("color [-1, 5, 0.5] has a negative component"),
            "{e}"
        );
        let e = b
            .add_material(neg(Vec3::ONE, Vec3::new(0.0, -2.0, 0.0)))
            .unwrap_err()
            .to_string();
        assert!(e.contains("emission"), "{e}");
        assert!(b.background(Vec3::new(0.0, -0.1, 0.0)).is_err());
        assert!(
            b.add_light(Light::Point {
                position: Vec3::ZERO,
                intensity: -Vec3::ONE
            })
            .is_err()
        );
        let e = b
            .add_sphere(Sphere::new(Vec3::ZERO, 1e-40), 0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("is below 1e-18"), "{e}");
        // Relative to the centre: 1e-4 at 1e4 is below one ulp (1e4 * 2^-23 = 1.2e-3).
        assert!(
            b.add_sphere(Sphere::new(Vec3::splat(1e4), 1e-4), 0)
                .is_err()
        );
        b.add_sphere(Sphere::new(Vec3::splat(1e4), 1e-2), 0)
            .unwrap();
        b.add_sphere(Sphere::new(Vec3::ZERO, 1e-18), 0).unwrap();
        let flat = TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
            indices: vec![[0, 1, 2], [0, 0, 0]],
        };
        b.add_mesh("flat.obj", &flat, 0).unwrap();
        let fine = TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            indices: vec![[0, 1, 2], [0, 0, 0]],
        };
        b.add_mesh("fine.obj", &fine, 0).unwrap();
        let s = b.build();
        assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
        assert!(s.warnings[0].contains("flat.obj"), "{:?}", s.warnings);
    }
}
