//! Moving scenes at the scene level: the builder's entry points for instance motions and
//! deformed meshes, and [`Scene::at_frame`], the one function that gives a scene's state at
//! frame `f` (its geometry through [`crate::Motion::geometry_at`]; cameras, materials,
//! lights and ids are those of every frame).

use crate::builder::SceneBuilder;
use crate::scene::Scene;
use crate::{Deform, DeformTarget, Deformation, InstanceMotion, SceneError, Shape};
use std::sync::Arc;

impl Scene {
    /// True when something in the scene moves ([`Scene::motion`]).
    #[must_use]
    pub fn is_moving(&self) -> bool {
        self.motion.is_some()
    }

    /// The scene at frame `frame`: the same scene with its geometry at that frame (the same
    /// ids and topology, [`crate::same_topology`]); a still scene is returned as it is.
    /// Frame 0 is the scene as loaded, bit for bit.
    ///
    /// # Errors
    /// As [`crate::Motion::geometry_at`].
    pub fn at_frame(&self, frame: u32) -> Result<Scene, SceneError> {
        let mut scene = self.clone();
        if let Some(m) = &self.motion {
            scene.geometry = Arc::new(m.geometry_at(&self.geometry, frame)?);
        }
        Ok(scene)
    }
}

impl SceneBuilder {
    /// Number of instances added so far (the next one's index is this).
    #[must_use]
    pub fn instance_count(&self) -> usize {
        self.instances.len()
    }

    /// Moves instance `index` (0-based, in the order [`SceneBuilder::add_instance`] added
    /// them) by `motion`. The instance must have been added with `motion`'s transform at
    /// frame 0 ([`InstanceMotion::to_world`]), so that the scene as built is its frame 0.
    ///
    /// # Errors
    /// When there is no such instance, or it was not placed at `motion`'s frame 0.
    pub fn move_instance(&mut self, index: u32, motion: InstanceMotion) -> Result<(), SceneError> {
        let Some(i) = self.instances.get(index as usize) else {
            return Err(SceneError::Invalid(format!(
                "instance index {index} does not exist"
            )));
        };
        if i.to_world() != motion.to_world(0) {
            return Err(SceneError::Invalid(format!(
                "instance {} is not placed at its motion's frame 0",
                index + 1
            )));
        }
        self.motion.move_instance(index, motion);
        Ok(())
    }

    /// Deforms the object added last (in this builder: the scene's flat primitives, or an
    /// instance mesh's builder from [`SceneBuilder::part`], whose deformations go with the
    /// mesh to every instance of it) by `deformation` over frames. Its triangles' positions
    /// now are its rest positions (frame 0).
    ///
    /// # Errors
    /// When there is no object, it holds primitives other than triangles, its material
    /// emits light (emitters are sampled from their frame-0 shape), it has vertex normals
    /// (they would not follow the deformation), or [`Deform::new`] refuses it.
    pub fn deform_last_object(&mut self, deformation: Deformation) -> Result<(), SceneError> {
        let Some(object) = self.objects.last() else {
            return Err(SceneError::Invalid("there is no object to deform".into()));
        };
        let range = object.first as usize..(object.first + object.count) as usize;
        let mut rest = Vec::with_capacity(range.len());
        for s in &self.shapes[range.clone()] {
            match s {
                Shape::Triangle(t) => rest.push(*t),
                other => {
                    return Err(SceneError::Invalid(format!(
                        "only triangle meshes deform, and {} holds a {}",
                        object.name,
                        other.kind().name()
                    )));
                }
            }
        }
        if self.prim_material[range]
            .iter()
            .any(|&m| self.materials[m as usize].emission.max_element() > 0.0)
        {
            return Err(SceneError::Invalid(format!(
                "{} emits light: a deformed mesh cannot be a light in this version (lights \
                 are sampled from their shape at load)",
                object.name
            )));
        }
        if object.count > 0
            && self
                .attributes
                .at(object.first, 0.25, 0.25)
                .normal
                .is_some()
        {
            return Err(SceneError::Invalid(format!(
                "{} has vertex normals, which would not follow the deformation",
                object.name
            )));
        }
        let deform = Deform::new(DeformTarget::Flat, object.first, rest, deformation)?;
        self.motion.deform(deform);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::{
        Affine3A, Camera, Deformation, InstanceMotion, Material, Placement, Procedural,
        SceneBuilder, Sphere, TriangleMesh, Vec3,
    };

    fn mesh() -> TriangleMesh {
        TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(0.0, 2.0, 0.5)],
            indices: vec![[0, 1, 2]],
        }
    }

    #[test]
    fn frames_of_a_built_scene() {
        let mut b = SceneBuilder::new("t");
        b.camera(Camera {
            position: Vec3::new(0.0, 0.0, 9.0),
            look_at: Vec3::ZERO,
            up: Vec3::Y,
            vfov_degrees: 40.0,
        })
        .unwrap();
        b.add_mesh("m", &mesh(), 0).unwrap();
        let twist = Deformation::Twist {
            axis: 1,
            degrees_per_frame: 10.0,
        };
        b.deform_last_object(twist).unwrap();
        let mut part = b.part();
        part.add_mesh("p", &mesh(), 0).unwrap();
        part.deform_last_object(twist).unwrap();
        let k = b.add_instance_mesh("p", part).unwrap();
        let spin = InstanceMotion::new(
            Placement::Fixed(Affine3A::IDENTITY),
            Some(Procedural::Spin {
                axis: Vec3::Y,
                degrees_per_frame: 5.0,
            }),
        )
        .unwrap();
        b.add_instance(k, Affine3A::IDENTITY, None).unwrap();
        b.move_instance(0, spin.clone()).unwrap();
        assert!(b.move_instance(1, spin).is_err());
        let s = b.build();
        assert!(s.is_moving());
        let f0 = s.at_frame(0).unwrap();
        assert_eq!(f0.geometry.shapes(), s.geometry.shapes());
        assert_eq!(f0.geometry.instances(), s.geometry.instances());
        let f2 = s.at_frame(2).unwrap();
        assert_ne!(f2.geometry.shapes(), s.geometry.shapes());
        assert_ne!(
            f2.geometry.meshes()[0].shapes(),
            s.geometry.meshes()[0].shapes()
        );
        assert!(crate::same_topology(&s.geometry, &f2.geometry));
    }

    #[test]
    fn what_cannot_deform_is_refused() {
        let twist = Deformation::Twist {
            axis: 1,
            degrees_per_frame: 10.0,
        };
        let mut b = SceneBuilder::new("t");
        assert!(b.deform_last_object(twist).is_err());
        b.add_sphere(Sphere::new(Vec3::ZERO, 1.0), 0).unwrap();
        let e = b.deform_last_object(twist).unwrap_err().to_string();
        assert!(e.contains("only triangle meshes deform"), "{e}");
        let lamp = b
            .add_material(Material {
                emission: Vec3::ONE,
                ..Material::default()
            })
            .unwrap();
        b.add_mesh("lamp", &mesh(), lamp).unwrap();
        let e = b.deform_last_object(twist).unwrap_err().to_string();
        assert!(e.contains("emits light"), "{e}");
        let still = b.build();
        assert!(!still.is_moving());
        assert_eq!(
            still.at_frame(7).unwrap().geometry.shapes(),
            still.geometry.shapes()
        );
    }
}
