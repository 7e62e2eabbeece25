//! Instances: a mesh of its own placed in the scene by an affine transform, and the one
//! definition of an instance hit, which the naive loop ([`crate::Geometry::closest_every`])
//! and every two-level structure ([`crate::TwoLevel`]) share.
//!
//! An instance hit is the hit of the *instance-space ray*: the world ray carried into the
//! mesh's space by the inverse transform ([`Instance::local_ray`]: the origin as a point,
//! the direction as a vector, the direction not renormalised so that `t` is the same in
//! both spaces, the same `[t_min, t_max]`). The mesh's primitives are tested with the core's
//! routines on that ray; the hit's id is the instance's base plus the primitive's index in
//! its mesh; its normal is the mesh's geometric normal carried by the inverse transpose
//! ([`Instance::world_normal`]).

use crate::aabb::Aabb;
use crate::checks::check_transform;
use crate::error::SceneError;
use crate::ray::Ray;
use glam::{Affine3A, Mat3A, Vec3};

/// Relative padding of an instance's world box (`2^-12` of the box's largest absolute
/// coordinate plus its largest extent, on every side).
///
/// The box is the union of the 8 transformed corners of the mesh's box, so it contains the
/// exact image of every primitive; but a primitive's hit is found on the instance-space
/// ray, and carrying the world ray there (and the hit point back) rounds by a few ulps
/// times the transform's condition number (at most [`crate::limits::MAX_TRANSFORM_CONDITION`]
/// is accepted, but scenes use small ones). `2^-12` covers conditions up to about `2^9`
/// with the slab test's own conservative scaling on top; the box only culls, so a larger
/// pad costs a few extra visits and never a result.
pub const INSTANCE_BOX_PAD: f32 = 1.0 / 4096.0;

/// One instance: mesh `mesh` of the geometry's [`Geometry::meshes`], placed by `to_world`,
/// its primitives numbered from `base` in the flattened scene's ids.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    mesh: u32,
    base: u32,
    count: u32,
    to_world: Affine3A,
    to_local: Affine3A,
    normal: Mat3A,
    bounds: Aabb,
}

impl Instance {
    /// The placement of a mesh of `count` primitives within `mesh_bounds` (index
    /// `mesh_index` of the geometry's meshes) by `to_world`: what [`Instance::new`] (in
    /// `geometry.rs`, which checks that the mesh may be instanced) builds on, so that this
    /// module knows boxes and transforms and nothing of a geometry. Its base id is assigned
    /// by `Geometry::with_instances`.
    ///
    /// # Errors
    /// When the transform is not finite, singular or too badly conditioned
    /// ([`check_transform`]), or the world box overflows.
    pub(crate) fn placed(
        mesh_index: u32,
        count: u32,
        mesh_bounds: Aabb,
        to_world: Affine3A,
    ) -> Result<Self, SceneError> {
        let inverse = check_transform(to_world, "instance transform")?;
        let to_local = Affine3A {
            matrix3: inverse,
            translation: -(inverse * to_world.translation),
        };
        let b = mesh_bounds;
        let corners = (0..8).map(|i| {
            let pick = |bit: u32, lo: f32, hi: f32| if i & bit == 0 { lo } else { hi };
            to_world.transform_point3(Vec3::new(
                pick(1, b.min.x, b.max.x),
                pick(2, b.min.y, b.max.y),
                pick(4, b.min.z, b.max.z),
            ))
        });
        let world = Aabb::from_points(corners);
        let pad = (world.min.abs().max(world.max.abs()).max_element()
            + world.extent().max_element())
            * INSTANCE_BOX_PAD;
        let bounds = Aabb::new(world.min - Vec3::splat(pad), world.max + Vec3::splat(pad));
        if !(bounds.min.is_finite() && bounds.max.is_finite()) {
            return Err(SceneError::NonFinite("an instance's world box".into()));
        }
        Ok(Self {
            mesh: mesh_index,
            base: 0,
            count,
            to_world,
            to_local,
            normal: inverse.transpose(),
            bounds,
        })
    }

    /// The index of its mesh in [`Geometry::meshes`].
    #[inline]
    #[must_use]
    pub fn mesh(&self) -> u32 {
        self.mesh
    }

    /// The global id of its mesh's primitive 0.
    #[inline]
    #[must_use]
    pub fn base(&self) -> u32 {
        self.base
    }

    /// Number of primitives (its mesh's).
    #[inline]
    #[must_use]
    pub fn count(&self) -> u32 {
        self.count
    }

    /// The placement, mesh space to world space.
    #[inline]
    #[must_use]
    pub fn to_world(&self) -> Affine3A {
        self.to_world
    }

    /// The inverse placement, world space to mesh space ([`Instance::local_ray`] applies
    /// it).
    #[inline]
    #[must_use]
    pub fn to_local(&self) -> Affine3A {
        self.to_local
    }

    /// The normal matrix, the inverse transpose ([`Instance::world_normal`] applies it).
    #[inline]
    #[must_use]
    pub fn normal_matrix(&self) -> Mat3A {
        self.normal
    }

    /// The world box: the 8 transformed corners of the mesh's box, padded outward by
    /// [`INSTANCE_BOX_PAD`] so that it is conservative.
    #[inline]
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The instance-space ray of the world ray `ray`: origin as a point, direction as a
    /// vector by the inverse transform, the direction not renormalised (so a hit's `t` is
    /// the world ray's `t`), the same `[t_min, t_max]`. The one function every backend
    /// calls, so they all test the same bits.
    #[inline]
    #[must_use]
    pub fn local_ray(&self, ray: &Ray) -> Ray {
        Ray::with_interval(
            self.to_local.transform_point3(ray.origin),
            self.to_local.transform_vector3(ray.dir),
            ray.t_min,
            ray.t_max,
        )
    }

    /// The world normal of a mesh-space normal: the inverse transpose, renormalised. The
    /// side is the mesh's side carried through the transform, so an outward normal stays
    /// outward under a mirror (pbrt's convention; the flattened scene's mirrored triangles,
    /// whose winding a mirror reverses, have the opposite normal).
    #[inline]
    #[must_use]
    pub fn world_normal(&self, n: Vec3) -> Vec3 {
        (self.normal * n).normalize_or(n)
    }

    /// Sets the base id (by [`Geometry::with_instances`]).
    pub(crate) fn set_base(&mut self, base: u32) {
        self.base = base;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Geometry, Shape, Sphere, Triangle};
    use glam::Quat;
    use std::sync::Arc;

    fn tri() -> Geometry {
        Geometry::new(vec![Shape::Triangle(Triangle::new(
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ))])
    }

    /// The instance-space ray of a translated instance, and the hit's `t` equal to the
    /// world distance.
    #[test]
    fn translation_moves_the_ray_and_keeps_t() {
        let mesh = tri();
        let i = Instance::new(
            0,
            &mesh,
            Affine3A::from_translation(Vec3::new(0.0, 0.0, 5.0)),
        )
        .unwrap();
        let r = i.local_ray(&Ray::new(Vec3::new(0.2, 0.1, 0.0), Vec3::Z));
        assert_eq!((r.origin, r.dir), (Vec3::new(0.2, 0.1, -5.0), Vec3::Z));
        let h = mesh.shape(0).intersect(&r).unwrap();
        assert_eq!(h.t, 5.0);
        assert_eq!(i.world_normal(Vec3::Z), Vec3::Z);
        assert!(i.bounds().min.z < 5.0 && i.bounds().max.z > 5.0);
    }

    /// A non-uniform scale leaves the direction unnormalised and `t` the world distance;
    /// the normal goes by the inverse transpose (a plane tilted 45 degrees in mesh space
    /// tilts less once stretched along x).
    #[test]
    fn non_uniform_scale_keeps_t_and_uses_the_inverse_transpose() {
        let mesh = tri();
        let s = Affine3A::from_scale(Vec3::new(4.0, 1.0, 2.0));
        let i = Instance::new(0, &mesh, s).unwrap();
        let r = i.local_ray(&Ray::new(Vec3::new(0.0, 0.0, -6.0), Vec3::Z));
        assert_eq!(r.dir, Vec3::new(0.0, 0.0, 0.5));
        assert_eq!(mesh.shape(0).intersect(&r).unwrap().t, 6.0);
        let n = i.world_normal(Vec3::new(1.0, 0.0, 1.0).normalize());
        let expected = Vec3::new(0.25, 0.0, 0.5).normalize();
        assert!((n - expected).length() < 1e-6, "{n}");
        // A sphere's normal at its stretched pole stays outward and unit.
        let ball = Geometry::new(vec![Shape::Sphere(Sphere::new(Vec3::ZERO, 1.0))]);
        let i = Instance::new(0, &ball, s).unwrap();
        let ray = Ray::new(Vec3::new(10.0, 0.0, 0.0), Vec3::NEG_X);
        let local = i.local_ray(&ray);
        let h = ball.shape(0).intersect(&local).unwrap();
        assert_eq!(h.t, 6.0);
        let hit = ball.shape(0).complete_hit(&local, 0, h);
        assert_eq!(i.world_normal(hit.normal), Vec3::X);
    }

    /// A rotation by 90 degrees about y carries the ray and the normal.
    #[test]
    fn rotation_carries_ray_and_normal() {
        let mesh = tri();
        let rot = Affine3A::from_quat(Quat::from_rotation_y(std::f32::consts::FRAC_PI_2));
        let i = Instance::new(0, &mesh, rot).unwrap();
        // The triangle's normal +Z becomes +X.
        let n = i.world_normal(Vec3::Z);
        assert!((n - Vec3::X).length() < 1e-6, "{n}");
        let ray = Ray::new(Vec3::new(-3.0, 0.0, 0.2), Vec3::X);
        let h = mesh.shape(0).intersect(&i.local_ray(&ray)).unwrap();
        assert!((h.t - 3.0).abs() < 1e-6, "{}", h.t);
    }

    /// A mirror keeps the side: the outward normal of a sphere stays outward, and a
    /// triangle's normal is its mesh normal mirrored (not the reversed winding's).
    #[test]
    fn mirror_keeps_the_side() {
        let m = Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let mesh = tri();
        let i = Instance::new(0, &mesh, m).unwrap();
        assert_eq!(i.world_normal(Vec3::Z), Vec3::Z);
        assert_eq!(i.world_normal(Vec3::X), Vec3::NEG_X);
        let ball = Geometry::new(vec![Shape::Sphere(Sphere::new(
            Vec3::new(1.0, 0.0, 0.0),
            1.0,
        ))]);
        let i = Instance::new(0, &ball, m).unwrap();
        let ray = Ray::new(Vec3::new(-5.0, 0.0, 0.0), Vec3::X);
        let local = i.local_ray(&ray);
        let h = ball.shape(0).intersect(&local).unwrap();
        assert_eq!(h.t, 3.0, "the mirrored sphere sits at x = -1");
        let n = i.world_normal(ball.shape(0).complete_hit(&local, 0, h).normal);
        assert_eq!(n, Vec3::NEG_X, "outward, towards the ray's origin");
    }

    #[test]
    fn bad_instances_are_refused() {
        let mesh = tri();
        for (xf, needle) in [
            (Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0)), "singular"),
            (
                Affine3A::from_translation(Vec3::splat(f32::NAN)),
                "not finite",
            ),
            (
                Affine3A::from_scale(Vec3::new(1e-7, 1.0, 1.0)),
                "nearly singular",
            ),
        ] {
            let e = Instance::new(0, &mesh, xf).unwrap_err().to_string();
            assert!(e.contains(needle), "{e}");
        }
        let e = Instance::new(0, &Geometry::default(), Affine3A::IDENTITY).unwrap_err();
        assert!(e.to_string().contains("no primitives"));
        let plane = Geometry::new(vec![Shape::Plane(crate::Plane::new(Vec3::ZERO, Vec3::Y))]);
        let e = Instance::new(0, &plane, Affine3A::IDENTITY).unwrap_err();
        assert!(e.to_string().contains("unbounded"));
        let nested = Geometry::with_instances(
            tri().shapes().to_vec(),
            vec![Arc::new(tri())],
            vec![Instance::new(0, &tri(), Affine3A::IDENTITY).unwrap()],
        );
        let e = Instance::new(0, &nested, Affine3A::IDENTITY).unwrap_err();
        assert!(e.to_string().contains("one level"));
    }
}
