//! Flattening: a scene with instances turned into the same scene without them, every
//! instanced primitive carried to world space and stored flat (`raybench render --flatten`,
//! the report's `instancing` experiment).
//!
//! Ids do not change: they already number the flattened scene (the flat primitives, then
//! each instance's in instance order, [`Geometry`]), so a flattened primitive keeps the id of
//! the instanced one it replaces, and its material is its mesh's or the instance's override
//! ([`Scene::material_of`]).
//!
//! Only what flattens exactly is flattened, as each kind says ([`crate::Shape::to_world`]):
//! a triangle by transforming its three vertices (pbrt-v4 and Embree do the same when they
//! flatten), a sphere under a similarity (rotation, mirror, uniform scale, translation) into
//! the sphere of the transformed centre and scaled radius, and any primitive under the
//! identity. Anything else (a sphere under a non-uniform scale is an ellipsoid; a height
//! field, CSG tree, Bezier patch or SDF model carries its own inner geometry) is an error
//! naming the instance and the primitive.
//!
//! The flattened scene is not bit-identical with the instanced one: the instanced primitive
//! is tested on the instance-space ray, the flattened one on the world ray against
//! transformed vertices, and the two round differently (a few ulps times the transform's
//! condition number). `tests/tests/instances.rs` bounds the difference; the normals of
//! mirrored instances' triangles are opposite (the mirror reverses the winding, see
//! [`crate::Instance::world_normal`]).

use crate::emitters::Emitters;
use crate::limits;
use crate::{Geometry, Instance, Scene, SceneError};
use std::sync::Arc;

/// `geometry` without instances: its flat primitives, then every instance's primitives
/// carried to world space, in id order. `name_of(k)` names instance `k` in errors.
///
/// # Errors
/// When the flattened scene would exceed [`limits::MAX_PRIMITIVES`] (checked before
/// anything is allocated) or a primitive cannot be flattened exactly.
pub fn flatten_geometry(
    geometry: &Geometry,
    name_of: impl Fn(usize) -> String,
) -> Result<Geometry, SceneError> {
    let total = geometry.total_len();
    if total > limits::MAX_PRIMITIVES {
        return Err(SceneError::TooLarge(format!(
            "flattened, the scene would store {total} primitives (limit {})",
            limits::MAX_PRIMITIVES
        )));
    }
    let mut shapes = Vec::with_capacity(total);
    shapes.extend_from_slice(geometry.shapes());
    for (k, instance) in geometry.instances().iter().enumerate() {
        let xf = instance.to_world();
        let mesh = &geometry.meshes()[instance.mesh() as usize];
        for (local, shape) in mesh.shapes().iter().enumerate() {
            let flat = shape.to_world(&xf).map_err(|why| {
                SceneError::Invalid(format!(
                    "cannot flatten {} (instance {}, primitive {}): {why}",
                    name_of(k),
                    k + 1,
                    Instance::base(instance) as usize + local
                ))
            })?;
            shapes.push(flat);
        }
    }
    Ok(Geometry::new(shapes))
}

/// `scene` without instances ([`flatten_geometry`]): the same primitives under the same
/// ids, each instanced primitive with its mesh's material or its instance's override and
/// its mesh's vertex normals (each carried by the instance's inverse transpose, then
/// interpolated: under a non-uniform scale that differs slightly from the instanced
/// shading, which interpolates first) and texture coordinates; cameras, lights,
/// materials, objects and volumes unchanged. A scene without instances
/// comes back as it is.
///
/// # Errors
/// As [`flatten_geometry`].
pub fn flatten(scene: &Scene) -> Result<Scene, SceneError> {
    let g = &scene.geometry;
    if !g.has_instances() {
        return Ok(scene.clone());
    }
    let name_of = |k: usize| {
        let base = g.instances()[k].base();
        scene.objects.iter().find(|o| o.first == base).map_or_else(
            || format!("instance {}", k + 1),
            |o| format!("the {}", o.name),
        )
    };
    let geometry = flatten_geometry(g, name_of)?;
    let mut prim_material = Vec::with_capacity(geometry.len());
    prim_material.extend_from_slice(&scene.prim_material);
    for (k, instance) in g.instances().iter().enumerate() {
        let mesh = &scene.mesh_materials[instance.mesh() as usize];
        match scene.instance_materials[k] {
            Some(m) => prim_material.extend(std::iter::repeat_n(m, mesh.len())),
            None => prim_material.extend_from_slice(mesh),
        }
    }
    let mut attributes = scene.attributes.clone();
    if !scene.mesh_attributes.is_empty() {
        for instance in g.instances() {
            let mesh = &scene.mesh_attributes[instance.mesh() as usize];
            attributes.push_placed(mesh, instance.base(), |n| instance.world_normal(n));
        }
    }
    let (emitters, _) = Emitters::new(
        &geometry,
        &prim_material,
        &scene.materials,
        scene.environment.as_deref(),
    );
    Ok(Scene {
        geometry: Arc::new(geometry),
        prim_material,
        mesh_materials: Vec::new(),
        instance_materials: Vec::new(),
        attributes,
        mesh_attributes: Vec::new(),
        emitters,
        ..scene.clone()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Affine3A, RayCounters, SceneBuilder, Shape, Sphere, Triangle, Vec3};
    use glam::Quat;

    /// A scene of one flat sphere and a mesh (two triangles and a sphere) placed three
    /// times: plain, rotated and scaled uniformly with a mirror, and (when `stretch`)
    /// stretched along x.
    fn scene(stretch: bool) -> Scene {
        let mut b = SceneBuilder::new("t");
        let red = b
            .add_material(crate::Material {
                name: "red".into(),
                ..Default::default()
            })
            .unwrap();
        b.add_sphere(Sphere::new(Vec3::new(0.0, 0.0, -5.0), 1.0), 0)
            .unwrap();
        let mut part = b.part();
        part.add_shapes(
            "m",
            vec![
                Shape::Triangle(Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)),
                Shape::Triangle(Triangle::new(Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y)),
                Shape::Sphere(Sphere::new(Vec3::new(0.5, 0.5, 1.0), 0.25)),
            ],
            red,
        )
        .unwrap();
        let m = b.add_instance_mesh("m", part).unwrap();
        b.add_instance(
            m,
            Affine3A::from_translation(Vec3::new(3.0, 0.0, 0.0)),
            None,
        )
        .unwrap();
        let turned = Affine3A::from_scale_rotation_translation(
            Vec3::new(-2.0, 2.0, 2.0),
            Quat::from_rotation_y(0.7),
            Vec3::new(-3.0, 1.0, 0.0),
        );
        b.add_instance(m, turned, Some(0)).unwrap();
        if stretch {
            b.add_instance(m, Affine3A::from_scale(Vec3::new(3.0, 1.0, 1.0)), None)
                .unwrap();
        }
        b.build()
    }

    /// The flattened scene stores every primitive under its id, with its material, and
    /// its hits are the instanced scene's (ids equal, `t` within rounding).
    #[test]
    fn flattening_keeps_ids_materials_and_hits() {
        let s = scene(false);
        let f = flatten(&s).unwrap();
        let (g, fg) = (&s.geometry, &f.geometry);
        assert!(!fg.has_instances());
        assert_eq!(fg.len(), g.total_len());
        assert_eq!(fg.total_len(), 7);
        for id in 0..7 {
            assert_eq!(s.material_of(id).name, f.material_of(id).name, "id {id}");
        }
        assert_eq!(f.material_of(1).name, "red");
        assert_eq!(f.material_of(4).name, "default", "the override");
        // The plain instance's triangle moved by 3 along x.
        let Shape::Triangle(t) = fg.shape(1) else {
            panic!("not a triangle")
        };
        assert_eq!(t.v[1], Vec3::new(4.0, 0.0, 0.0));
        // The mirrored, scaled sphere: radius doubled.
        let Shape::Sphere(ball) = fg.shape(6) else {
            panic!("not a sphere")
        };
        assert!((ball.radius - 0.5).abs() < 1e-6, "{}", ball.radius);
        let rays = crate::ray_sets::incoherent(g.world_bounds(), 4000, 7);
        let mut hits = 0;
        for ray in &rays {
            let a = g.closest_every(ray, &mut RayCounters::default());
            let b = fg.closest_every(ray, &mut RayCounters::default());
            assert_eq!(a.map(|h| h.prim), b.map(|h| h.prim), "{ray:?}");
            if let (Some(a), Some(b)) = (a, b) {
                hits += 1;
                assert!((a.t - b.t).abs() <= 1e-5 * a.t.max(1.0), "{a:?} {b:?}");
            }
        }
        assert!(hits > 100, "{hits} hits");
    }

    /// A sphere under a non-uniform scale cannot be flattened exactly: the error names the
    /// instance and the primitive.
    #[test]
    fn a_stretched_sphere_is_refused() {
        let e = flatten(&scene(true)).unwrap_err().to_string();
        assert!(
            e.contains("cannot flatten the instance of m (instance 3, primitive 9)")
                && e.contains("non-uniform scale"),
            "{e}"
        );
    }

    /// A scene without instances comes back unchanged.
    #[test]
    fn a_flat_scene_is_unchanged() {
        let mut b = SceneBuilder::new("flat");
        b.add_sphere(Sphere::new(Vec3::ZERO, 1.0), 0).unwrap();
        let s = b.build();
        let f = flatten(&s).unwrap();
        assert!(Arc::ptr_eq(&s.geometry, &f.geometry));
    }
}
