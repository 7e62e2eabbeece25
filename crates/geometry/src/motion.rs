//! Moving scenes: instances whose placement changes over frames (keyed or procedural) and
//! triangle meshes deformed per vertex, and the one function that gives a geometry's state
//! at frame `f` ([`Motion::geometry_at`]).
//!
//! A frame's geometry has the same ids and the same topology as every other frame's: the
//! same flat primitives of the same kinds in the same order, the same distinct meshes with
//! the same primitive counts, the same instances of the same meshes. Only positions change:
//! deformed triangles' vertices and moving instances' transforms (and so their world boxes).
//! A structure built over one frame can therefore be *refitted* to another
//! ([`crate::Accel::refit`]): its boxes recomputed bottom up, its topology kept
//! ([`same_topology`] is the check).
//!
//! Frame 0 is bit for bit the geometry a scene loads with: a key at frame 0 is its own
//! transform, every procedural motion and deformation is the identity at frame 0 and
//! returns its input unchanged there (no arithmetic that could round).

use crate::checks::check_transform;
use crate::error::SceneError;
use crate::geometry::{Geometry, Shape};
use crate::instance::Instance;
use crate::limits::{MAX_COORDINATE, MAX_TRANSFORM_CONDITION};
use crate::triangle::Triangle;
use glam::{Affine3A, Mat3A, Quat, Vec3};
use std::sync::Arc;

/// One key of a keyed placement: the instance's scale, rotation and translation at a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key {
    /// The frame it holds at.
    pub frame: u32,
    /// Per-axis scale (applied first).
    pub scale: Vec3,
    /// Rotation (applied second).
    pub rotation: Quat,
    /// Translation (applied last).
    pub translate: Vec3,
}

impl Key {
    /// The key's affine map: scale, then rotate, then translate.
    #[must_use]
    pub fn affine(&self) -> Affine3A {
        Affine3A::from_scale_rotation_translation(self.scale, self.rotation, self.translate)
    }
}

/// Where an instance's placement comes from before its procedural motion applies.
#[derive(Clone, Debug, PartialEq)]
pub enum Placement {
    /// One transform for every frame.
    Fixed(Affine3A),
    /// Keys at increasing frames; between two keys the translation and the scale are
    /// interpolated linearly and the rotation by quaternion slerp; before the first key the
    /// first holds, after the last the last.
    Keyed(Vec<Key>),
}

/// A procedural motion applied on top of an instance's [`Placement`] at frame `f`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Procedural {
    /// Turns about `axis` through the instance's origin (its placement's translation) by
    /// `degrees_per_frame` per frame: the placement's linear part is rotated, its
    /// translation kept.
    Spin {
        /// Unit axis.
        axis: Vec3,
        /// Degrees per frame (counter-clockwise about `axis`).
        degrees_per_frame: f32,
    },
    /// Moves the instance's origin on a circle about `axis` through `center` by
    /// `degrees_per_frame` per frame; its orientation is kept.
    Orbit {
        /// Unit axis.
        axis: Vec3,
        /// A point of the axis.
        center: Vec3,
        /// Degrees per frame.
        degrees_per_frame: f32,
    },
    /// Moves the instance by `offset * sin(2 pi (f / period + phase))`.
    Bob {
        /// The largest displacement.
        offset: Vec3,
        /// Frames per cycle.
        period: f32,
        /// Fraction of a cycle at frame 0.
        phase: f32,
    },
}

/// The angle `degrees_per_frame * frame` in radians, reduced modulo a turn in f64 so that
/// late frames keep their precision; exactly 0 at frame 0.
fn turn(degrees_per_frame: f32, frame: u32) -> f32 {
    (f64::from(degrees_per_frame) * f64::from(frame))
        .rem_euclid(360.0)
        .to_radians() as f32
}

impl Procedural {
    /// Checks the parameters and normalises the axis.
    ///
    /// # Errors
    /// A zero or non-finite axis, a non-finite rate, centre, offset or phase, or a period
    /// that is not positive.
    pub fn checked(self) -> Result<Self, SceneError> {
        let rate = |r: f32, what: &str| {
            if r.is_finite() {
                Ok(())
            } else {
                Err(SceneError::NonFinite(format!("{what} degrees_per_frame")))
            }
        };
        let axis = |a: Vec3, what: &str| {
            if !a.is_finite() {
                return Err(SceneError::NonFinite(format!("{what} axis")));
            }
            a.try_normalize()
                .ok_or_else(|| SceneError::Invalid(format!("{what} axis is zero")))
        };
        Ok(match self {
            Self::Spin {
                axis: a,
                degrees_per_frame,
            } => {
                rate(degrees_per_frame, "spin")?;
                Self::Spin {
                    axis: axis(a, "spin")?,
                    degrees_per_frame,
                }
            }
            Self::Orbit {
                axis: a,
                center,
                degrees_per_frame,
            } => {
                rate(degrees_per_frame, "orbit")?;
                crate::checks::point(center, "orbit center")?;
                Self::Orbit {
                    axis: axis(a, "orbit")?,
                    center,
                    degrees_per_frame,
                }
            }
            Self::Bob {
                offset,
                period,
                phase,
            } => {
                crate::checks::point(offset, "bob offset")?;
                crate::checks::positive(period, "bob period")?;
                if !phase.is_finite() {
                    return Err(SceneError::NonFinite("bob phase".into()));
                }
                self
            }
        })
    }

    /// The motion applied to `base` at `frame`; `base` itself, untouched, where the motion
    /// is the identity (frame 0 of a spin or orbit, a bob at a zero of its sine).
    #[must_use]
    pub fn apply(&self, base: Affine3A, frame: u32) -> Affine3A {
        match *self {
            Self::Spin {
                axis,
                degrees_per_frame,
            } => {
                let angle = turn(degrees_per_frame, frame);
                if angle == 0.0 {
                    return base;
                }
                Affine3A {
                    matrix3: Mat3A::from_quat(Quat::from_axis_angle(axis, angle)) * base.matrix3,
                    translation: base.translation,
                }
            }
            Self::Orbit {
                axis,
                center,
                degrees_per_frame,
            } => {
                let angle = turn(degrees_per_frame, frame);
                if angle == 0.0 {
                    return base;
                }
                let r = Quat::from_axis_angle(axis, angle);
                let c = glam::Vec3A::from(center);
                Affine3A {
                    matrix3: base.matrix3,
                    translation: c + r * (base.translation - c),
                }
            }
            Self::Bob {
                offset,
                period,
                phase,
            } => {
                let cycles = (f64::from(frame) / f64::from(period) + f64::from(phase)).fract();
                let s = (cycles * std::f64::consts::TAU).sin() as f32;
                if s == 0.0 {
                    return base;
                }
                Affine3A {
                    matrix3: base.matrix3,
                    translation: base.translation + glam::Vec3A::from(offset * s),
                }
            }
        }
    }
}

/// How one instance moves: its placement, then an optional procedural motion.
#[derive(Clone, Debug, PartialEq)]
pub struct InstanceMotion {
    placement: Placement,
    procedural: Option<Procedural>,
}

impl InstanceMotion {
    /// An instance motion, checked: keys in strictly increasing frames, finite, each scale
    /// axis keeping its sign across the keys (so the interpolation never passes through a
    /// zero scale), the ratio of the largest to the smallest scale at most
    /// [`MAX_TRANSFORM_CONDITION`], every key's transform accepted by [`check_transform`];
    /// the procedural motion by [`Procedural::checked`].
    ///
    /// # Errors
    /// [`SceneError::Invalid`] or [`SceneError::NonFinite`] naming the key (1-based) and
    /// the cause.
    pub fn new(placement: Placement, procedural: Option<Procedural>) -> Result<Self, SceneError> {
        match &placement {
            Placement::Fixed(a) => {
                check_transform(*a, "instance transform")?;
            }
            Placement::Keyed(keys) => {
                if keys.is_empty() {
                    return Err(SceneError::Invalid(
                        "`keys` is empty: give at least one key".into(),
                    ));
                }
                for (i, k) in keys.iter().enumerate() {
                    let what = format!("key {} (frame {})", i + 1, k.frame);
                    if i > 0 && k.frame <= keys[i - 1].frame {
                        return Err(SceneError::Invalid(format!(
                            "{what} does not come after the frame of key {} ({}): keys must \
                             be in strictly increasing frames",
                            i,
                            keys[i - 1].frame
                        )));
                    }
                    if !(k.scale.is_finite() && k.translate.is_finite() && k.rotation.is_finite()) {
                        return Err(SceneError::NonFinite(what));
                    }
                    if k.translate.abs().max_element() > MAX_COORDINATE {
                        return Err(SceneError::Invalid(format!(
                            "{what}: translate exceeds {MAX_COORDINATE:e} in magnitude"
                        )));
                    }
                    let first = keys[0].scale;
                    for axis in 0..3 {
                        if (k.scale[axis] > 0.0) != (first[axis] > 0.0) {
                            return Err(SceneError::Invalid(format!(
                                "{what}: scale {} changes sign on axis {} from key 1 ({}): \
                                 the interpolation would pass through a zero scale",
                                k.scale,
                                ["x", "y", "z"][axis],
                                first
                            )));
                        }
                    }
                    check_transform(k.affine(), &format!("{what} transform"))?;
                }
                let abs = keys.iter().map(|k| k.scale.abs());
                let hi = abs.clone().fold(0.0f32, |m, s| m.max(s.max_element()));
                let lo = abs.fold(f32::INFINITY, |m, s| m.min(s.min_element()));
                if hi / lo > MAX_TRANSFORM_CONDITION {
                    return Err(SceneError::Invalid(format!(
                        "the keys' scales range from {lo} to {hi}: their ratio exceeds the \
                         limit of {MAX_TRANSFORM_CONDITION:e}"
                    )));
                }
            }
        }
        let procedural = procedural.map(Procedural::checked).transpose()?;
        Ok(Self {
            placement,
            procedural,
        })
    }

    /// The placement before the procedural motion at `frame`.
    #[must_use]
    pub fn base_at(&self, frame: u32) -> Affine3A {
        match &self.placement {
            Placement::Fixed(a) => *a,
            Placement::Keyed(keys) => {
                // The first key after `frame`; the key before it (or at `frame`) holds.
                let next = keys.partition_point(|k| k.frame <= frame);
                if next == 0 {
                    return keys[0].affine();
                }
                let a = keys[next - 1];
                if a.frame == frame || next == keys.len() {
                    return a.affine();
                }
                let b = keys[next];
                let s = (frame - a.frame) as f32 / (b.frame - a.frame) as f32;
                Affine3A::from_scale_rotation_translation(
                    a.scale.lerp(b.scale, s),
                    a.rotation.slerp(b.rotation, s),
                    a.translate.lerp(b.translate, s),
                )
            }
        }
    }

    /// The instance's transform at `frame`: the placement, then the procedural motion.
    #[must_use]
    pub fn to_world(&self, frame: u32) -> Affine3A {
        let base = self.base_at(frame);
        match &self.procedural {
            Some(p) => p.apply(base, frame),
            None => base,
        }
    }

    /// True when the transform is the same at every frame (a fixed placement without a
    /// procedural motion, or a single key).
    #[must_use]
    pub fn is_static(&self) -> bool {
        self.procedural.is_none()
            && match &self.placement {
                Placement::Fixed(_) => true,
                Placement::Keyed(keys) => keys.len() == 1,
            }
    }
}

/// A per-vertex deformation of a triangle mesh over frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Deformation {
    /// Twists the mesh about the line parallel to axis `axis` (0: x, 1: y, 2: z) through the
    /// centre of its rest box: a vertex at height `h` along the axis (0 at the box's bottom,
    /// 1 at its top) turns by `h * degrees_per_frame * f` at frame `f` (right-handed about
    /// the axis), so the top turns ever further against the bottom.
    Twist {
        /// The axis, 0 (x), 1 (y) or 2 (z).
        axis: usize,
        /// Degrees per frame at the top of the box.
        degrees_per_frame: f32,
    },
}

/// Which part of a geometry a deformation applies to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeformTarget {
    /// The flat primitives ([`Geometry::shapes`]).
    Flat,
    /// Distinct mesh `k` ([`Geometry::meshes`]), and so every instance of it.
    Mesh(u32),
}

/// A deformation applied to a run of triangles: their rest positions and the parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Deform {
    target: DeformTarget,
    first: u32,
    rest: Vec<Triangle>,
    deformation: Deformation,
    /// The rest box's centre, bottom along the axis and extent along it.
    centre: Vec3,
    bottom: f32,
    height: f32,
}

impl Deform {
    /// The deformation of the triangles `rest`, which are the primitives `first..` of
    /// `target`.
    ///
    /// # Errors
    /// No triangles, an axis other than 0, 1 or 2, a non-finite rate, or a mesh without
    /// extent along the axis (nothing to twist).
    pub fn new(
        target: DeformTarget,
        first: u32,
        rest: Vec<Triangle>,
        deformation: Deformation,
    ) -> Result<Self, SceneError> {
        let Deformation::Twist {
            axis,
            degrees_per_frame,
        } = deformation;
        if rest.is_empty() {
            return Err(SceneError::Invalid(
                "a deformed mesh has no triangles".into(),
            ));
        }
        if axis > 2 {
            return Err(SceneError::Invalid(format!(
                "twist axis {axis} is not 0 (x), 1 (y) or 2 (z)"
            )));
        }
        if !degrees_per_frame.is_finite() {
            return Err(SceneError::NonFinite("twist degrees_per_frame".into()));
        }
        let b = rest
            .iter()
            .fold(crate::Aabb::EMPTY, |b, t| b.union(t.bounds()));
        let height = b.max[axis] - b.min[axis];
        if !(height > 0.0 && height.is_finite()) {
            return Err(SceneError::Invalid(format!(
                "the twisted mesh is flat along the twist's axis ({}): nothing to twist",
                ["x", "y", "z"][axis]
            )));
        }
        Ok(Self {
            target,
            first,
            rest,
            deformation,
            centre: b.center(),
            bottom: b.min[axis],
            height,
        })
    }

    /// What it deforms.
    #[must_use]
    pub fn target(&self) -> DeformTarget {
        self.target
    }

    /// The same deformation applied to `target` (an instance mesh's builder deforms its
    /// flat primitives, which become a distinct mesh of the scene).
    #[must_use]
    pub fn with_target(mut self, target: DeformTarget) -> Self {
        self.target = target;
        self
    }

    /// The position of rest vertex `p` at `frame`: `p` itself where the turn is 0.
    #[must_use]
    pub fn vertex_at(&self, p: Vec3, frame: u32) -> Vec3 {
        let Deformation::Twist {
            axis,
            degrees_per_frame,
        } = self.deformation;
        let full = turn(degrees_per_frame, frame);
        let angle = full * ((p[axis] - self.bottom) / self.height);
        if angle == 0.0 {
            return p;
        }
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let (s, c) = angle.sin_cos();
        let (du, dv) = (p[u] - self.centre[u], p[v] - self.centre[v]);
        let mut q = p;
        q[u] = self.centre[u] + c * du - s * dv;
        q[v] = self.centre[v] + s * du + c * dv;
        q
    }

    /// Writes the deformed triangles at `frame` into `shapes` (the target's primitives).
    fn write(&self, shapes: &mut [Shape], frame: u32) {
        let out = &mut shapes[self.first as usize..self.first as usize + self.rest.len()];
        for (s, t) in out.iter_mut().zip(&self.rest) {
            *s = Shape::Triangle(Triangle::new(
                self.vertex_at(t.v[0], frame),
                self.vertex_at(t.v[1], frame),
                self.vertex_at(t.v[2], frame),
            ));
        }
    }
}

/// Everything that moves in a scene: instance motions by instance index, and deformations.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Motion {
    instances: Vec<(u32, InstanceMotion)>,
    deforms: Vec<Deform>,
}

impl Motion {
    /// No motion.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Moves instance `index` (of [`Geometry::instances`]) by `motion`; a later motion of
    /// the same instance replaces the earlier.
    pub fn move_instance(&mut self, index: u32, motion: InstanceMotion) {
        match self.instances.binary_search_by_key(&index, |(i, _)| *i) {
            Ok(k) => self.instances[k].1 = motion,
            Err(k) => self.instances.insert(k, (index, motion)),
        }
    }

    /// Adds a deformation.
    pub fn deform(&mut self, deform: Deform) {
        self.deforms.push(deform);
    }

    /// True when nothing moves.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.deforms.is_empty() && self.instances.iter().all(|(_, m)| m.is_static())
    }

    /// The moving instances' indices and motions, ascending.
    #[must_use]
    pub fn instances(&self) -> &[(u32, InstanceMotion)] {
        &self.instances
    }

    /// The deformations.
    #[must_use]
    pub fn deforms(&self) -> &[Deform] {
        &self.deforms
    }

    /// Whether a deformation applies to the flat primitives.
    #[must_use]
    pub fn deforms_flat(&self) -> bool {
        self.deforms.iter().any(|d| d.target == DeformTarget::Flat)
    }

    /// Whether a deformation applies to distinct mesh `k`.
    #[must_use]
    pub fn deforms_mesh(&self, k: u32) -> bool {
        self.deforms
            .iter()
            .any(|d| d.target == DeformTarget::Mesh(k))
    }

    /// The state at `frame` of `geometry` (a frame of this motion's scene, any frame): the
    /// same ids and topology ([`same_topology`]), deformed triangles at their frame's
    /// positions, moving instances at their frame's transforms, every instance of a
    /// deformed mesh with its box recomputed. Meshes that do not deform are shared with
    /// `geometry` (the same `Arc`), so a two-level structure sees which ones changed.
    ///
    /// # Errors
    /// When an instance's transform at `frame` is refused by [`Instance::new`] (checked
    /// motions keep their transforms invertible and finite, so only extreme scenes get
    /// here).
    ///
    /// # Panics
    /// When `geometry` is not a frame of this motion's scene (a deformation or an instance
    /// motion out of its range).
    pub fn geometry_at(&self, geometry: &Geometry, frame: u32) -> Result<Geometry, SceneError> {
        let mut shapes = geometry.shapes().to_vec();
        for d in self
            .deforms
            .iter()
            .filter(|d| d.target == DeformTarget::Flat)
        {
            d.write(&mut shapes, frame);
        }
        let meshes: Vec<Arc<Geometry>> = geometry
            .meshes()
            .iter()
            .enumerate()
            .map(|(k, m)| {
                let k = k as u32;
                if !self.deforms_mesh(k) {
                    return Arc::clone(m);
                }
                let mut mesh = m.shapes().to_vec();
                for d in self
                    .deforms
                    .iter()
                    .filter(|d| d.target == DeformTarget::Mesh(k))
                {
                    d.write(&mut mesh, frame);
                }
                Arc::new(Geometry::new(mesh))
            })
            .collect();
        let mut moving = self.instances.iter().peekable();
        let mut instances = Vec::with_capacity(geometry.instances().len());
        for (k, i) in geometry.instances().iter().enumerate() {
            let motion = moving
                .next_if(|(index, _)| *index as usize == k)
                .map(|(_, m)| m);
            let deformed = self.deforms_mesh(i.mesh());
            instances.push(match motion {
                Some(m) if !m.is_static() || deformed => {
                    let mesh = &meshes[i.mesh() as usize];
                    Instance::new(i.mesh(), mesh, m.to_world(frame))
                        .map_err(|e| SceneError::Invalid(format!("instance {}: {e}", k + 1)))?
                }
                _ if deformed => Instance::new(i.mesh(), &meshes[i.mesh() as usize], i.to_world())
                    .map_err(|e| SceneError::Invalid(format!("instance {}: {e}", k + 1)))?,
                _ => i.clone(),
            });
        }
        Ok(Geometry::with_instances(shapes, meshes, instances))
    }
}

/// Whether `a` and `b` have the same ids and topology, so that a structure built over one
/// can be refitted to the other: the same flat primitives' kinds in the same order (so the
/// same bounded and unbounded ids), the same number of distinct meshes with the same
/// primitive counts, the same instances of the same meshes.
#[must_use]
pub fn same_topology(a: &Geometry, b: &Geometry) -> bool {
    let kinds = |x: &Geometry, y: &Geometry| {
        x.len() == y.len()
            && x.bounded() == y.bounded()
            && x.shapes()
                .iter()
                .zip(y.shapes())
                .all(|(s, t)| s.kind() == t.kind())
    };
    kinds(a, b)
        && a.meshes().len() == b.meshes().len()
        && a.meshes()
            .iter()
            .zip(b.meshes())
            .all(|(x, y)| Arc::ptr_eq(x, y) || kinds(x, y))
        && a.instances().len() == b.instances().len()
        && a.instances()
            .iter()
            .zip(b.instances())
            .all(|(x, y)| x.mesh() == y.mesh() && x.base() == y.base())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(frame: u32, t: Vec3, degrees: f32, s: f32) -> Key {
        Key {
            frame,
            scale: Vec3::splat(s),
            rotation: Quat::from_rotation_y(degrees.to_radians()),
            translate: t,
        }
    }

    #[test]
    fn keys_interpolate_and_hold() {
        let m = InstanceMotion::new(
            Placement::Keyed(vec![
                key(2, Vec3::ZERO, 0.0, 1.0),
                key(6, Vec3::new(4.0, 0.0, 0.0), 90.0, 3.0),
            ]),
            None,
        )
        .unwrap();
        // Before the first key and at it: the first key, exactly.
        assert_eq!(m.to_world(0), key(2, Vec3::ZERO, 0.0, 1.0).affine());
        assert_eq!(m.to_world(2), m.to_world(0));
        // Half-way: translation and scale halfway, 45 degrees by slerp.
        let mid = m.to_world(4);
        let (s, r, t) = mid.to_scale_rotation_translation();
        assert!((t - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6, "{t}");
        assert!((s - Vec3::splat(2.0)).length() < 1e-5, "{s}");
        let angle = r.angle_between(Quat::IDENTITY).to_degrees();
        assert!((angle - 45.0).abs() < 1e-3, "{angle}");
        // After the last key: the last key.
        assert_eq!(m.to_world(100), key(6, Vec3::X * 4.0, 90.0, 3.0).affine());
        assert!(!m.is_static());
    }

    #[test]
    fn bad_keys_are_refused() {
        let cases = [
            (vec![], "empty"),
            (
                vec![key(3, Vec3::ZERO, 0.0, 1.0), key(3, Vec3::ONE, 0.0, 1.0)],
                "key 2 (frame 3) does not come after",
            ),
            (
                vec![key(0, Vec3::ZERO, 0.0, 1.0), key(4, Vec3::ONE, 0.0, -1.0)],
                "changes sign",
            ),
            (
                vec![key(0, Vec3::ZERO, 0.0, 1.0), key(4, Vec3::NAN, 0.0, 1.0)],
                "key 2 (frame 4) is not finite",
            ),
            (
                vec![key(0, Vec3::ZERO, 0.0, 1e-4), key(4, Vec3::ONE, 0.0, 1e4)],
                "ratio exceeds",
            ),
        ];
        for (keys, needle) in cases {
            let e = InstanceMotion::new(Placement::Keyed(keys), None)
                .unwrap_err()
                .to_string();
            assert!(e.contains(needle), "{e}");
        }
        let bad = Procedural::Spin {
            axis: Vec3::ZERO,
            degrees_per_frame: 1.0,
        };
        let e = InstanceMotion::new(Placement::Fixed(Affine3A::IDENTITY), Some(bad))
            .unwrap_err()
            .to_string();
        assert!(e.contains("spin axis is zero"), "{e}");
        let bob = Procedural::Bob {
            offset: Vec3::Y,
            period: 0.0,
            phase: 0.0,
        };
        assert!(InstanceMotion::new(Placement::Fixed(Affine3A::IDENTITY), Some(bob)).is_err());
    }

    #[test]
    fn procedural_motions() {
        let base = Affine3A::from_translation(Vec3::new(2.0, 0.0, 0.0));
        let spin = Procedural::Spin {
            axis: Vec3::Y,
            degrees_per_frame: 90.0,
        };
        assert_eq!(spin.apply(base, 0), base);
        let a = spin.apply(base, 1);
        assert_eq!(a.translation, base.translation);
        assert!((a.transform_vector3(Vec3::X) - Vec3::NEG_Z).length() < 1e-6);
        let orbit = Procedural::Orbit {
            axis: Vec3::Y,
            center: Vec3::ZERO,
            degrees_per_frame: 90.0,
        };
        let o = orbit.apply(base, 1);
        assert!((Vec3::from(o.translation) - Vec3::new(0.0, 0.0, -2.0)).length() < 1e-6);
        assert_eq!(o.matrix3, base.matrix3);
        assert_eq!(
            orbit.apply(base, 4),
            base,
            "a whole turn is frame 0's angle"
        );
        let bob = Procedural::Bob {
            offset: Vec3::Y,
            period: 4.0,
            phase: 0.0,
        };
        assert_eq!(bob.apply(base, 0), base);
        let b = bob.apply(base, 1);
        assert!((Vec3::from(b.translation) - Vec3::new(2.0, 1.0, 0.0)).length() < 1e-6);
    }

    #[test]
    fn twist_turns_the_top_and_keeps_frame_zero() {
        let rest = vec![Triangle::new(
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(-1.0, 2.0, 0.0),
        )];
        let d = Deform::new(
            DeformTarget::Flat,
            0,
            rest.clone(),
            Deformation::Twist {
                axis: 1,
                degrees_per_frame: 45.0,
            },
        )
        .unwrap();
        for v in rest[0].v {
            assert_eq!(d.vertex_at(v, 0), v);
        }
        // The bottom never turns; the top turns 90 degrees at frame 2 about the box's
        // centre line (x = 0, z = 0), right-handed about +y: +x goes to -z.
        assert_eq!(d.vertex_at(Vec3::X, 2), Vec3::X);
        let top = d.vertex_at(Vec3::new(1.0, 2.0, 0.0), 2);
        assert!((top - Vec3::new(0.0, 2.0, -1.0)).length() < 1e-6, "{top}");
        let flat = Deform::new(
            DeformTarget::Flat,
            0,
            rest,
            Deformation::Twist {
                axis: 2,
                degrees_per_frame: 1.0,
            },
        );
        assert!(flat.unwrap_err().to_string().contains("flat along"));
    }

    /// Frame 0 of a geometry is the geometry; other frames keep the ids and topology, move
    /// what moves, share the meshes that do not deform.
    #[test]
    fn frames_keep_ids_and_topology() {
        let tri = |x: f32| {
            Shape::Triangle(Triangle::new(
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 1.0, 0.0, 0.0),
                Vec3::new(x, 1.0, 0.5),
            ))
        };
        let mesh = Arc::new(Geometry::new(vec![tri(0.0), tri(1.0)]));
        let still = Arc::new(Geometry::new(vec![tri(5.0)]));
        let place = Affine3A::from_translation(Vec3::new(0.0, 0.0, 3.0));
        let g = Geometry::with_instances(
            vec![tri(-2.0), tri(-1.0)],
            vec![Arc::clone(&mesh), Arc::clone(&still)],
            vec![
                Instance::new(0, &mesh, place).unwrap(),
                Instance::new(1, &still, place).unwrap(),
                Instance::new(1, &still, Affine3A::IDENTITY).unwrap(),
            ],
        );
        let twist = Deformation::Twist {
            axis: 1,
            degrees_per_frame: 10.0,
        };
        let mut m = Motion::new();
        let rest = |g: &Geometry| {
            g.shapes()
                .iter()
                .map(|s| match s {
                    Shape::Triangle(t) => *t,
                    _ => unreachable!(),
                })
                .collect::<Vec<_>>()
        };
        m.deform(Deform::new(DeformTarget::Flat, 0, rest(&g), twist).unwrap());
        m.deform(Deform::new(DeformTarget::Mesh(0), 0, rest(&mesh), twist).unwrap());
        let spin = Procedural::Spin {
            axis: Vec3::Z,
            degrees_per_frame: 30.0,
        };
        m.move_instance(
            1,
            InstanceMotion::new(Placement::Fixed(place), Some(spin)).unwrap(),
        );
        assert!(!m.is_empty() && m.deforms_flat() && m.deforms_mesh(0));
        let f0 = m.geometry_at(&g, 0).unwrap();
        assert_eq!(f0.shapes(), g.shapes());
        assert_eq!(f0.instances(), g.instances());
        let f3 = m.geometry_at(&g, 3).unwrap();
        assert!(same_topology(&g, &f3));
        assert_ne!(f3.shapes(), g.shapes());
        assert_ne!(f3.meshes()[0].shapes(), mesh.shapes());
        assert!(
            Arc::ptr_eq(&f3.meshes()[1], &still),
            "a still mesh is shared"
        );
        assert_ne!(f3.instances()[1].to_world(), place);
        assert_eq!(f3.instances()[2], g.instances()[2]);
        // Frame 3 from frame 3 is frame 3 from the rest: deformations start from the rest.
        let again = m.geometry_at(&f3, 3).unwrap();
        assert_eq!(again.shapes(), f3.shapes());
        assert_eq!(again.instances(), f3.instances());
        let other = Geometry::new(vec![tri(0.0)]);
        assert!(!same_topology(&g, &other));
    }
}
