//! The flat list of primitives that acceleration structures index into.

use crate::aabb::Aabb;
use crate::bezier::BezierPatch;
use crate::csg::Csg;
use crate::error::SceneError;
use crate::heightfield::HeightField;
use crate::hit::{Hit, PrimHit, keep_closer};
use crate::instance::Instance;
use crate::plane::Plane;
use crate::ray::Ray;
use crate::sdf::Sdf;
use crate::sphere::Sphere;
use crate::triangle::Triangle;
use glam::{Affine3A, Vec3};
use std::sync::Arc;

/// One primitive. A closed enum so that the per-ray path dispatches with a `match`, not a
/// virtual call (pbrt-v4's tagged pointers).
///
/// Object kinds with their own inner intersection (height fields; later Bezier patches,
/// implicit surfaces, CSG trees) are further variants holding their data behind an `Arc`;
/// they report a sub-primitive id in [`PrimHit::sub`].
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// A triangle (meshes are stored as their triangles).
    Triangle(Triangle),
    /// A sphere.
    Sphere(Sphere),
    /// An infinite plane (unbounded).
    Plane(Plane),
    /// A height field: one bounded primitive whose cells are walked directly; the
    /// sub-primitive id is the tessellated triangle's index (two per cell).
    HeightField(Arc<HeightField>),
    /// A CSG tree of analytic solids: one bounded primitive; the sub-primitive id is the
    /// index of the leaf hit.
    Csg(Arc<Csg>),
    /// A bicubic Bezier patch intersected directly (subdivision + Newton): one bounded
    /// primitive; sub-primitive id 0, `(u, v)` the patch parameters.
    Bezier(Arc<BezierPatch>),
    /// A signed-distance model intersected by sphere tracing: one bounded primitive
    /// (sub-primitive id 0).
    Sdf(Arc<Sdf>),
}

/// The kinds of primitive, for statistics and for backends that support only some.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PrimitiveKind {
    /// [`Shape::Triangle`].
    Triangle,
    /// [`Shape::Sphere`].
    Sphere,
    /// [`Shape::Plane`].
    Plane,
    /// [`Shape::HeightField`].
    HeightField,
    /// [`Shape::Csg`].
    Csg,
    /// [`Shape::Bezier`].
    Bezier,
    /// [`Shape::Sdf`].
    Sdf,
}

impl PrimitiveKind {
    /// Every kind, in declaration order ([`PrimitiveKind::index`]).
    pub const ALL: [Self; 7] = [
        Self::Triangle,
        Self::Sphere,
        Self::Plane,
        Self::HeightField,
        Self::Csg,
        Self::Bezier,
        Self::Sdf,
    ];

    /// The kind's position in [`PrimitiveKind::ALL`] (its declaration order), a dense
    /// number for tables and for the GPU kernels' kind numbers.
    #[inline]
    #[must_use]
    pub const fn index(self) -> u32 {
        self as u32
    }

    /// Lower-case name used in scene files and reports.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Triangle => "triangle",
            Self::Sphere => "sphere",
            Self::Plane => "plane",
            Self::HeightField => "height field",
            Self::Csg => "analytic solid / CSG tree",
            Self::Bezier => "Bezier patch",
            Self::Sdf => "SDF model",
        }
    }
}

impl Shape {
    /// The kind of this primitive.
    #[inline]
    #[must_use]
    pub fn kind(&self) -> PrimitiveKind {
        match self {
            Self::Triangle(_) => PrimitiveKind::Triangle,
            Self::Sphere(_) => PrimitiveKind::Sphere,
            Self::Plane(_) => PrimitiveKind::Plane,
            Self::HeightField(_) => PrimitiveKind::HeightField,
            Self::Csg(_) => PrimitiveKind::Csg,
            Self::Bezier(_) => PrimitiveKind::Bezier,
            Self::Sdf(_) => PrimitiveKind::Sdf,
        }
    }

    /// The bounding box, or `None` for unbounded primitives (planes).
    #[inline]
    #[must_use]
    pub fn bounds(&self) -> Option<Aabb> {
        match self {
            Self::Triangle(t) => Some(t.bounds()),
            Self::Sphere(s) => Some(s.bounds()),
            Self::Plane(_) => None,
            Self::HeightField(h) => Some(h.bounds()),
            Self::Csg(c) => Some(c.bounds()),
            Self::Bezier(b) => Some(b.bounds()),
            Self::Sdf(m) => Some(m.bounds()),
        }
    }

    /// The ray's closest hit with this primitive inside `[ray.t_min, ray.t_max]`.
    #[inline]
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        match self {
            Self::Triangle(tri) => tri.intersect(ray),
            Self::Sphere(s) => s.intersect(ray),
            Self::Plane(p) => p.intersect(ray),
            Self::HeightField(h) => h.intersect(ray),
            Self::Csg(c) => c.intersect(ray),
            Self::Bezier(b) => b.intersect(ray),
            Self::Sdf(m) => m.intersect(ray),
        }
    }

    /// Fills in the surface data (normal, parameters) of a hit found by [`Shape::intersect`].
    #[must_use]
    pub fn complete_hit(&self, ray: &Ray, prim: u32, h: PrimHit) -> Hit {
        let (normal, u, v) = match self {
            Self::Triangle(tri) => (tri.normal(), h.u, h.v),
            Self::Sphere(s) => {
                let n = s.normal_at(ray.at(h.t));
                let (u, v) = Sphere::uv(n);
                (n, u, v)
            }
            Self::Plane(p) => (p.normal, h.u, h.v),
            Self::HeightField(f) => (f.normal(h.sub, h.u, h.v), h.u, h.v),
            Self::Csg(c) => (c.normal(ray, &h), h.u, h.v),
            Self::Bezier(b) => (b.normal(h.u, h.v), h.u, h.v),
            Self::Sdf(m) => (m.normal(ray.at(h.t)), h.u, h.v),
        };
        Hit {
            t: h.t,
            prim,
            sub: h.sub,
            u,
            v,
            normal,
        }
    }

    /// The surface area, for the kinds whose area is computed: a triangle's (its edges'
    /// cross product in `f32`, halved in `f64`) and a sphere's (`4π r²`); `None` for a plane
    /// (unbounded) and for the kinds whose area is not known (height fields, CSG trees,
    /// Bezier patches, SDF models).
    #[must_use]
    pub fn area(&self) -> Option<f64> {
        match self {
            Self::Triangle(t) => {
                Some(0.5 * f64::from((t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).length()))
            }
            Self::Sphere(s) => Some(sphere_area(s.radius)),
            Self::Plane(_)
            | Self::HeightField(_)
            | Self::Csg(_)
            | Self::Bezier(_)
            | Self::Sdf(_) => None,
        }
    }

    /// A sphere around the primitive, `(centre, radius)`: a sphere's own; for every other
    /// bounded kind its box's centre and half diagonal; `None` for a plane.
    #[must_use]
    pub fn bounding_sphere(&self) -> Option<(Vec3, f32)> {
        let of_box = |b: Aabb| (b.center(), 0.5 * b.extent().length());
        match self {
            Self::Sphere(s) => Some((s.center, s.radius)),
            Self::Plane(_) => None,
            Self::Triangle(_)
            | Self::HeightField(_)
            | Self::Csg(_)
            | Self::Bezier(_)
            | Self::Sdf(_) => self.bounds().map(of_box),
        }
    }

    /// The point of the surface at the uniform numbers `(u, v)`, uniform by area, for the
    /// kinds whose [`Shape::area`] is known: triangles by the square-root map, spheres by `z`
    /// and the longitude; `None` for the others.
    #[must_use]
    pub fn uniform_point(&self, u: f32, v: f32) -> Option<Vec3> {
        match self {
            Self::Triangle(t) => {
                let su = u.sqrt();
                Some(t.v[0] * (1.0 - su) + t.v[1] * (su * (1.0 - v)) + t.v[2] * (su * v))
            }
            Self::Sphere(s) => {
                let z = 1.0 - 2.0 * u;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = std::f32::consts::TAU * v;
                Some(s.center + s.radius * Vec3::new(r * phi.cos(), r * phi.sin(), z))
            }
            Self::Plane(_)
            | Self::HeightField(_)
            | Self::Csg(_)
            | Self::Bezier(_)
            | Self::Sdf(_) => None,
        }
    }

    /// The primitive placed by `xf` in world space, where that is exact: a triangle by its
    /// three vertices, a sphere under a similarity (rotation, mirror, uniform scale,
    /// translation) as the sphere of the carried centre and scaled radius, and any
    /// primitive under the identity.
    ///
    /// # Errors
    /// Why it cannot be carried exactly: a sphere under a non-uniform scale is an ellipsoid;
    /// a plane, height field, CSG tree, Bezier patch or SDF model under any other transform.
    pub fn to_world(&self, xf: &Affine3A) -> Result<Shape, String> {
        match self {
            Self::Triangle(t) => Ok(Self::Triangle(Triangle {
                v: t.v.map(|v| xf.transform_point3(v)),
            })),
            Self::Sphere(s) => match similarity_scale(xf) {
                Some(k) => Ok(Self::Sphere(Sphere::new(
                    xf.transform_point3(s.center),
                    s.radius * k,
                ))),
                None if *xf == Affine3A::IDENTITY => Ok(self.clone()),
                None => Err(
                    "a sphere under a non-uniform scale or shear (an ellipsoid, which \
                     raybench stores only as a CSG solid)"
                        .into(),
                ),
            },
            Self::Plane(_)
            | Self::HeightField(_)
            | Self::Csg(_)
            | Self::Bezier(_)
            | Self::Sdf(_) => {
                if *xf == Affine3A::IDENTITY {
                    Ok(self.clone())
                } else {
                    Err(format!(
                        "a {} under a transform (only triangles and spheres are carried to \
                         world space)",
                        self.kind().name()
                    ))
                }
            }
        }
    }

    /// Bytes the primitive holds behind its `Arc` (0 for the kinds stored inline).
    #[must_use]
    pub fn heap_bytes(&self) -> usize {
        match self {
            Self::Triangle(_) | Self::Sphere(_) | Self::Plane(_) => 0,
            Self::HeightField(h) => h.memory_bytes(),
            Self::Csg(c) => c.memory_bytes(),
            Self::Bezier(b) => b.memory_bytes(),
            Self::Sdf(m) => m.memory_bytes(),
        }
    }
}

/// The area of a sphere of radius `r`, `4π r²` in `f64` (written `2 τ r²`).
#[must_use]
pub(crate) fn sphere_area(r: f32) -> f64 {
    2.0 * std::f64::consts::TAU * f64::from(r).powi(2)
}

/// Relative tolerance under which a transform's linear part counts as a similarity (its
/// columns orthogonal and of one length): Euler-angle rotations built in `f32` are
/// orthogonal to a few ulps, far below it; a deliberate non-uniform scale is far above.
const SIMILARITY_TOLERANCE: f32 = 1e-5;

/// The uniform scale of `xf`'s linear part when it is a similarity (a rotation, possibly
/// mirrored, times a uniform scale), else `None`.
fn similarity_scale(xf: &Affine3A) -> Option<f32> {
    let m = xf.matrix3;
    let cols = [m.x_axis, m.y_axis, m.z_axis];
    let len = cols.map(|c| c.length());
    let s = len[0];
    let tol = SIMILARITY_TOLERANCE * s;
    let equal = len.iter().all(|l| (l - s).abs() <= tol);
    let orthogonal = [(0, 1), (0, 2), (1, 2)]
        .iter()
        .all(|&(a, b)| cols[a].dot(cols[b]).abs() <= tol * s);
    (equal && orthogonal && s > 0.0).then_some(s)
}

/// Every primitive of a scene, indexed by global primitive id, with the split into bounded
/// primitives (which acceleration structures organise) and unbounded ones (tested by every
/// ray), and the scene's instances.
///
/// Ids number the flattened scene: the primitives stored here (the *flat* ones) are
/// `0..len()`; instance `k`'s primitives follow at `base_k .. base_k + n(mesh_k)` in
/// instance order, up to [`Geometry::total_len`]. [`Geometry::shapes`], [`Geometry::bounded`],
/// [`Geometry::unbounded`], [`Geometry::bounds`] and the query helpers whose names do not say
/// otherwise are about the flat primitives only: a structure built over a geometry with
/// instances organises its flat part, and [`crate::TwoLevel`] adds the instances (the
/// render crate's `CpuRenderer` picks it by itself). [`Geometry::closest_every`] and
/// [`Geometry::occluded_every`] (the naive loop) and [`Geometry::complete_global`] cover
/// every id.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    shapes: Vec<Shape>,
    bounded: Vec<u32>,
    unbounded: Vec<u32>,
    bounds: Aabb,
    meshes: Vec<Arc<Geometry>>,
    instances: Vec<Instance>,
    total: usize,
}

impl Geometry {
    /// Geometry from primitives in id order.
    ///
    /// # Panics
    /// When there are `u32::MAX` primitives or more (scene loaders refuse such scenes first).
    #[must_use]
    pub fn new(shapes: Vec<Shape>) -> Self {
        assert!(shapes.len() < u32::MAX as usize, "too many primitives");
        let mut bounded = Vec::new();
        let mut unbounded = Vec::new();
        let mut bounds = Aabb::EMPTY;
        for (i, s) in shapes.iter().enumerate() {
            match s.bounds() {
                Some(b) => {
                    bounded.push(i as u32);
                    bounds = bounds.union(b);
                }
                None => unbounded.push(i as u32),
            }
        }
        let total = shapes.len();
        Self {
            shapes,
            bounded,
            unbounded,
            bounds,
            meshes: Vec::new(),
            instances: Vec::new(),
            total,
        }
    }

    /// Geometry from the flat primitives in id order, the distinct meshes that instances
    /// place, and the instances in id order (each built by [`Instance::new`] with its
    /// mesh's index); assigns the instances' base ids after the flat primitives.
    ///
    /// # Panics
    /// When an instance names a mesh that is not in `meshes`, or the flattened total
    /// reaches `u32::MAX` ([`crate::limits::MAX_INSTANCED_PRIMITIVES`]: scene loaders refuse
    /// such scenes first).
    #[must_use]
    pub fn with_instances(
        shapes: Vec<Shape>,
        meshes: Vec<Arc<Geometry>>,
        mut instances: Vec<Instance>,
    ) -> Self {
        let mut g = Self::new(shapes);
        let mut total = g.shapes.len() as u64;
        for i in &mut instances {
            let mesh = &meshes[i.mesh() as usize];
            assert_eq!(mesh.len(), i.count() as usize, "instance of another mesh");
            i.set_base(total as u32);
            total += u64::from(i.count());
            assert!(
                total <= crate::limits::MAX_INSTANCED_PRIMITIVES,
                "too many instanced primitives"
            );
        }
        g.meshes = meshes;
        g.instances = instances;
        g.total = total as usize;
        g
    }

    /// The distinct meshes the instances place (each one structure in a two-level form).
    #[inline]
    #[must_use]
    pub fn meshes(&self) -> &[Arc<Geometry>] {
        &self.meshes
    }

    /// The instances, in id order.
    #[inline]
    #[must_use]
    pub fn instances(&self) -> &[Instance] {
        &self.instances
    }

    /// True when the geometry has instances.
    #[inline]
    #[must_use]
    pub fn has_instances(&self) -> bool {
        !self.instances.is_empty()
    }

    /// Number of primitives of the flattened scene: the flat ones plus every instance's.
    #[inline]
    #[must_use]
    pub fn total_len(&self) -> usize {
        self.total
    }

    /// Bounds of the flat bounded primitives and of every instance's world box.
    #[must_use]
    pub fn world_bounds(&self) -> Aabb {
        self.instances
            .iter()
            .fold(self.bounds, |b, i| b.union(i.bounds()))
    }

    /// The index in [`Geometry::instances`] of the instance that global id `id` belongs
    /// to and the id's index in its mesh, or `None` for a flat primitive's id or one past
    /// the total.
    #[must_use]
    pub fn locate(&self, id: u32) -> Option<(usize, u32)> {
        if (id as usize) < self.shapes.len() || (id as usize) >= self.total {
            return None;
        }
        let k = self.instances.partition_point(|i| i.base() <= id) - 1;
        Some((k, id - self.instances[k].base()))
    }

    /// All primitives, indexed by id.
    #[inline]
    #[must_use]
    pub fn shapes(&self) -> &[Shape] {
        &self.shapes
    }

    /// Number of primitives.
    #[inline]
    #[must_use]
    pub fn len(&self) -> usize {
        self.shapes.len()
    }

    /// True when there are no primitives.
    #[inline]
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.shapes.is_empty()
    }

    /// The primitive with id `id`.
    #[inline]
    #[must_use]
    pub fn shape(&self, id: u32) -> &Shape {
        &self.shapes[id as usize]
    }

    /// Ids of the bounded primitives, ascending.
    #[inline]
    #[must_use]
    pub fn bounded(&self) -> &[u32] {
        &self.bounded
    }

    /// Ids of the unbounded primitives (planes), ascending.
    #[inline]
    #[must_use]
    pub fn unbounded(&self) -> &[u32] {
        &self.unbounded
    }

    /// Bounds of all bounded primitives (empty when there are none).
    #[inline]
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Bytes held by the primitives: the shape list, the id lists, and what objects such
    /// as height fields hold behind their `Arc`; with instances, each distinct mesh once
    /// and the instance records.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.flat_memory_bytes()
            + self.meshes.iter().map(|m| m.memory_bytes()).sum::<usize>()
            + self.instances.len() * std::mem::size_of::<Instance>()
    }

    /// [`Geometry::memory_bytes`] of the flat primitives.
    fn flat_memory_bytes(&self) -> usize {
        let heap: usize = self.shapes.iter().map(Shape::heap_bytes).sum();
        self.shapes.len() * std::mem::size_of::<Shape>()
            + (self.bounded.len() + self.unbounded.len()) * 4
            + heap
    }

    /// Primitive counts by kind, in [`PrimitiveKind::ALL`] order, zero counts included.
    #[must_use]
    pub fn count_by_kind(&self) -> Vec<(PrimitiveKind, usize)> {
        PrimitiveKind::ALL
            .iter()
            .map(|&k| (k, self.shapes.iter().filter(|s| s.kind() == k).count()))
            .collect()
    }

    /// Tests primitive `id` and, if it is hit closer than `best` under the tie rule
    /// ([`keep_closer`]), replaces `best`. Returns whether it replaced.
    #[inline]
    pub fn test_closest(&self, id: u32, ray: &Ray, best: &mut Option<(u32, PrimHit)>) -> bool {
        // The primitive sees the original ray, clipped only to the best t so far (a hit at
        // exactly that t must still be seen for the tie rule).
        let t_max = best.map_or(ray.t_max, |(_, h)| h.t);
        let Some(h) = self.shape(id).intersect(&ray.clipped(t_max)) else {
            return false;
        };
        keep_closer(best, id, h)
    }

    /// Tests every unbounded primitive (the planes every structure keeps beside itself) as
    /// [`Geometry::test_closest`] does; returns how many were tested.
    #[inline]
    pub fn closest_unbounded(&self, ray: &Ray, best: &mut Option<(u32, PrimHit)>) -> u64 {
        for &id in &self.unbounded {
            self.test_closest(id, ray, best);
        }
        self.unbounded.len() as u64
    }

    /// Whether an unbounded primitive is hit, and how many were tested to find out.
    #[inline]
    #[must_use]
    pub fn occluded_unbounded(&self, ray: &Ray) -> (bool, u64) {
        for (i, &id) in self.unbounded.iter().enumerate() {
            if self.shape(id).intersect(ray).is_some() {
                return (true, i as u64 + 1);
            }
        }
        (false, self.unbounded.len() as u64)
    }

    /// The closest hit found by testing every primitive in id order: the naive strategy,
    /// and the exact fallback of accelerators for rays they cannot place.
    #[must_use]
    pub fn closest_brute_force<C: crate::Counters>(
        &self,
        ray: &Ray,
        counters: &mut C,
    ) -> Option<Hit> {
        let mut best = None;
        for id in 0..self.len() as u32 {
            self.test_closest(id, ray, &mut best);
        }
        counters.add_tests(self.len() as u64);
        self.complete(ray, best)
    }

    /// Whether any primitive is hit, testing in id order and stopping at the first hit.
    #[must_use]
    pub fn occluded_brute_force<C: crate::Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        for (i, shape) in self.shapes.iter().enumerate() {
            if shape.intersect(ray).is_some() {
                counters.add_tests(i as u64 + 1);
                return true;
            }
        }
        counters.add_tests(self.len() as u64);
        false
    }

    /// Whether `ray` (valid) misses the box of every bounded primitive, by the slab test
    /// [`Aabb::intersect`] that the tree backends trust at any distance: then only the
    /// unbounded primitives can be hit.
    #[inline]
    fn misses_bounded(&self, ray: &Ray) -> bool {
        ray.is_valid() && self.bounds.intersect(ray, ray.t_max).is_none()
    }

    /// The exact closest hit of a ray that a structure cannot place (an origin too far for
    /// its arithmetic, or an invalid ray): the unbounded primitives alone when the ray
    /// misses the bounded primitives' box, as most rays from far out on a ground plane do;
    /// otherwise [`Geometry::closest_brute_force`].
    #[must_use]
    pub fn closest_unplaced<C: crate::Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        if !self.misses_bounded(ray) {
            return self.closest_brute_force(ray, counters);
        }
        let mut best = None;
        counters.add_tests(self.closest_unbounded(ray, &mut best));
        self.complete(ray, best)
    }

    /// [`Geometry::closest_unplaced`] for any hit: the unbounded primitives alone when the
    /// ray misses the bounded primitives' box, otherwise
    /// [`Geometry::occluded_brute_force`].
    #[must_use]
    pub fn occluded_unplaced<C: crate::Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        if !self.misses_bounded(ray) {
            return self.occluded_brute_force(ray, counters);
        }
        let (hit, tests) = self.occluded_unbounded(ray);
        counters.add_tests(tests);
        hit
    }

    /// Turns the winner of [`Geometry::test_closest`] into a full [`Hit`] (flat ids only:
    /// instanced ones go through [`Geometry::complete_global`]).
    #[inline]
    #[must_use]
    pub fn complete(&self, ray: &Ray, best: Option<(u32, PrimHit)>) -> Option<Hit> {
        best.map(|(id, h)| self.shape(id).complete_hit(ray, id, h))
    }

    /// [`Geometry::complete`] for any id of the flattened scene: an instanced primitive is
    /// completed on its instance-space ray ([`Instance::local_ray`]) with its global id,
    /// and its normal carried to world space ([`Instance::world_normal`]). The one
    /// completion of an instance hit.
    #[must_use]
    pub fn complete_global(&self, ray: &Ray, best: Option<(u32, PrimHit)>) -> Option<Hit> {
        let (id, h) = best?;
        let Some((k, local)) = self.locate(id) else {
            return self.complete(ray, best);
        };
        let instance = &self.instances[k];
        let mesh = &self.meshes[instance.mesh() as usize];
        let mut hit = mesh
            .shape(local)
            .complete_hit(&instance.local_ray(ray), id, h);
        hit.normal = instance.world_normal(hit.normal);
        Some(hit)
    }

    /// The closest hit over every primitive of the flattened scene in global id order:
    /// the flat ones, then each instance's on its instance-space ray. The naive strategy;
    /// counts [`Geometry::total_len`] tests.
    #[must_use]
    pub fn closest_every<C: crate::Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        if self.instances.is_empty() {
            return self.closest_brute_force(ray, counters);
        }
        let mut best = None;
        for id in 0..self.len() as u32 {
            self.test_closest(id, ray, &mut best);
        }
        for instance in &self.instances {
            let mesh = &self.meshes[instance.mesh() as usize];
            let local = instance.local_ray(ray);
            for (l, shape) in mesh.shapes.iter().enumerate() {
                let t_max = best.map_or(local.t_max, |(_, h): (u32, PrimHit)| h.t);
                if let Some(h) = shape.intersect(&local.clipped(t_max)) {
                    keep_closer(&mut best, instance.base() + l as u32, h);
                }
            }
        }
        counters.add_tests(self.total as u64);
        self.complete_global(ray, best)
    }

    /// Whether any primitive of the flattened scene is hit, in global id order, stopping at
    /// the first; counts the tests made.
    #[must_use]
    pub fn occluded_every<C: crate::Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        if self.occluded_brute_force(ray, counters) {
            return true;
        }
        for instance in &self.instances {
            let local = instance.local_ray(ray);
            let shapes = &self.meshes[instance.mesh() as usize].shapes;
            if let Some(i) = shapes.iter().position(|s| s.intersect(&local).is_some()) {
                counters.add_tests(i as u64 + 1);
                return true;
            }
            counters.add_tests(shapes.len() as u64);
        }
        false
    }
}

impl Instance {
    /// Instance of `mesh` (index `mesh_index` of the geometry's meshes) placed by
    /// `to_world`. Its base id is assigned by [`Geometry::with_instances`].
    ///
    /// # Errors
    /// When the transform is not finite, singular or too badly conditioned
    /// ([`crate::checks::check_transform`]), or the mesh has no primitives, an unbounded one
    /// or instances of its own.
    pub fn new(mesh_index: u32, mesh: &Geometry, to_world: Affine3A) -> Result<Self, SceneError> {
        if mesh.is_empty() {
            return Err(SceneError::Invalid(
                "an instance's mesh has no primitives".into(),
            ));
        }
        if !mesh.unbounded().is_empty() {
            return Err(SceneError::Invalid(
                "an instance's mesh holds an unbounded primitive (a plane): only bounded \
                 primitives can be instanced"
                    .into(),
            ));
        }
        if mesh.has_instances() {
            return Err(SceneError::Invalid(
                "an instance's mesh holds instances itself (one level only)".into(),
            ));
        }
        Instance::placed(mesh_index, mesh.len() as u32, mesh.bounds(), to_world)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn all_kinds_are_listed_in_index_order() {
        for (i, k) in PrimitiveKind::ALL.iter().enumerate() {
            assert_eq!(k.index() as usize, i, "{k:?}");
        }
    }

    /// The kinds with an area have uniform points on it, and the others none.
    #[test]
    fn areas_and_uniform_points_go_together() {
        let shapes = [
            Shape::Triangle(Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)),
            Shape::Sphere(Sphere::new(Vec3::ONE, 2.0)),
            Shape::Plane(Plane::new(Vec3::ZERO, Vec3::Y)),
        ];
        for s in &shapes {
            assert_eq!(
                s.area().is_some(),
                s.uniform_point(0.3, 0.6).is_some(),
                "{s:?}"
            );
        }
        assert_eq!(shapes[0].area(), Some(0.5));
        let p = shapes[1].uniform_point(0.3, 0.6).unwrap();
        assert!(((p - Vec3::ONE).length() - 2.0).abs() < 1e-5);
        assert_eq!(shapes[1].bounding_sphere(), Some((Vec3::ONE, 2.0)));
        assert_eq!(shapes[2].bounding_sphere(), None);
    }
}
