//! `[[instance_array]]`: one named instance mesh placed many times on a grid, with optional
//! seeded per-instance variation (documented in `docs/scene-format.md#instance-arrays`).
//!
//! Instance `k` of an array of `count = [nx, ny, nz]` sits at grid cell
//! `(i, j, l) = (k mod nx, (k / nx) mod ny, k / (nx ny))`; its transform is, applied to the
//! mesh in this order: the table's `transform` (the same for every instance), a uniform
//! scale drawn from `scale_range`, a rotation about `rotate_axis` by an angle drawn from
//! `rotate_degrees`, then the translation to `origin + spacing * (i, j, l)`. The draws come
//! from the counter-based hash of the renderer's sampler ([`raybench_core::sampling::pcg3d`])
//! keyed by `(k, dimension, seed)`, so an array is the same on every machine and every
//! instance is independent of the others' count.

use super::{Placing, TransformDesc, V3, table_item};
use crate::budget::Holds;
use crate::error::LoadError;
use raybench_core::sampling::{pcg3d, to_unit_f32};
use raybench_core::{Affine3A, Vec3, limits};
use serde::Deserialize;

/// The table's name in scene files.
const TABLE: &str = "instance_array";

/// The hash dimension of each per-instance draw.
const ROTATION: u32 = 0;
/// See [`ROTATION`].
const SCALE: u32 = 1;

/// A spacing: one distance for every axis, or one per axis.
#[derive(Deserialize)]
#[serde(untagged)]
enum SpacingDesc {
    Uniform(f32),
    PerAxis(V3),
}

/// An `[[instance_array]]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct InstanceArrayDesc {
    /// The instance mesh placed (an `[[object]]` with this `name` and `instance_only`).
    mesh: String,
    /// Instances along x, y and z (each at least 1).
    count: [u64; 3],
    /// Distance between neighbouring grid cells along each axis.
    spacing: SpacingDesc,
    /// Where cell `(0, 0, 0)` is.
    #[serde(default)]
    origin: V3,
    /// Applied to the mesh first, the same for every instance.
    #[serde(default)]
    transform: TransformDesc,
    /// Material of every instance (default: the mesh's own).
    material: Option<String>,
    /// Seed of the per-instance draws.
    #[serde(default)]
    seed: u32,
    /// Axis of the drawn rotation (default y, up).
    rotate_axis: Option<V3>,
    /// Range `[lo, hi]` of the drawn rotation angle, in degrees.
    rotate_degrees: Option<[f32; 2]>,
    /// Range `[lo, hi]` of the drawn uniform scale.
    scale_range: Option<[f32; 2]>,
}

/// A value uniform in `[range[0], range[1])` for instance `k`'s draw `dimension`.
fn draw(range: [f32; 2], k: u64, dimension: u32, seed: u32) -> f32 {
    // Instance indices stay below MAX_INSTANCES (2^20), so `k` fits a u32.
    let u = to_unit_f32(pcg3d([k as u32, dimension, seed])[0]);
    range[0] + (range[1] - range[0]) * u
}

/// Checks a `[lo, hi]` range: finite, ordered, and (for scales) above 0.
fn check_range(range: [f32; 2], key: &str, positive: bool) -> Result<(), String> {
    let [lo, hi] = range;
    if !(lo.is_finite() && hi.is_finite()) {
        return Err(format!("`{key}` [{lo}, {hi}] is not finite"));
    }
    if lo > hi {
        return Err(format!(
            "`{key}` [{lo}, {hi}]: the first bound exceeds the second"
        ));
    }
    if positive && lo <= 0.0 {
        return Err(format!("`{key}` [{lo}, {hi}]: scales must be above 0"));
    }
    Ok(())
}

impl InstanceArrayDesc {
    /// The checked grid size (instances in all), spacing and rotation axis.
    fn checked(&self) -> Result<(u64, Vec3, Vec3), String> {
        if self.count.contains(&0) {
            return Err(format!(
                "`count` {:?} has a zero: every axis needs at least 1 instance",
                self.count
            ));
        }
        let n = self.count.iter().try_fold(1u64, |n, &c| n.checked_mul(c));
        let n = match n {
            Some(n) if n <= limits::MAX_INSTANCES as u64 => n,
            _ => {
                return Err(format!(
                    "`count` {:?} makes more than {} instances (the limit)",
                    self.count,
                    limits::MAX_INSTANCES
                ));
            }
        };
        let spacing = match self.spacing {
            SpacingDesc::Uniform(s) => Vec3::splat(s),
            SpacingDesc::PerAxis(s) => Vec3::from(s),
        };
        let origin = Vec3::from(self.origin);
        for (v, key) in [(spacing, "spacing"), (origin, "origin")] {
            if !v.is_finite() {
                return Err(format!("`{key}` {v} is not finite"));
            }
        }
        let axis = Vec3::from(self.rotate_axis.unwrap_or([0.0, 1.0, 0.0]));
        let Some(axis) = axis.try_normalize() else {
            return Err(format!("`rotate_axis` {axis} is not a direction"));
        };
        if let Some(r) = self.rotate_degrees {
            check_range(r, "rotate_degrees", false)?;
        }
        if let Some(r) = self.scale_range {
            check_range(r, "scale_range", true)?;
        }
        Ok((n, spacing, axis))
    }

    /// The transform of instance `k` at grid cell `cell`.
    fn placement(&self, k: u64, cell: Vec3, spacing: Vec3, axis: Vec3) -> Affine3A {
        let base = self.transform.to_transform().affine();
        let scale = self
            .scale_range
            .map_or(1.0, |r| draw(r, k, SCALE, self.seed));
        let angle = self
            .rotate_degrees
            .map_or(0.0, |r| draw(r, k, ROTATION, self.seed));
        let turn = Affine3A::from_axis_angle(axis, angle.to_radians());
        Affine3A::from_translation(Vec3::from(self.origin) + spacing * cell)
            * turn
            * Affine3A::from_scale(Vec3::splat(scale))
            * base
    }
}

/// Adds every `[[instance_array]]` table of the file, in order, after the `[[instance]]`
/// tables (so their ids follow those instances'), marking the meshes they place as used.
///
/// # Errors
/// A table that does not parse, names an unknown mesh or material, has a bad count,
/// spacing or range, would exceed [`limits::MAX_INSTANCES`] or
/// [`limits::MAX_INSTANCED_PRIMITIVES`] (checked before any instance is added) or the
/// memory budget, or places an instance whose transform is refused; one message naming the
/// file, the table's line and index, and the cause.
pub(super) fn add(tables: Vec<toml::Table>, p: &mut Placing) -> Result<(), LoadError> {
    let ctx = p.ctx;
    for (index, table) in tables.into_iter().enumerate() {
        let (d, what): (InstanceArrayDesc, _) = table_item(p.text, TABLE, index, table, ctx)?;
        let fail = |message: String| LoadError::Parse {
            path: ctx.file.clone(),
            message: format!("{what}: {message}"),
        };
        let Some(mesh) = p.place(&d.mesh) else {
            return Err(fail(format!(
                "mesh '{}' is not defined (instance meshes are objects with a `name` and \
                 `instance_only = true`)",
                d.mesh
            )));
        };
        let material = p.material(&what, d.material.as_ref())?;
        let (n, spacing, axis) = d.checked().map_err(fail)?;
        // A zero spacing along an axis of several instances stacks them in one place:
        // legal, but every ray that meets one tests them all.
        let stacked: Vec<&str> = ["x", "y", "z"]
            .into_iter()
            .zip(d.count)
            .zip(spacing.to_array())
            .filter(|&((_, count), s)| count > 1 && s == 0.0)
            .map(|((axis, _), _)| axis)
            .collect();
        if !stacked.is_empty() {
            p.b.warn(format!(
                "{}: {what}: `spacing` is 0 along {} where `count` places several instances: \
                 they coincide, drawn over each other, and every ray that meets one tests them \
                 all",
                ctx.file.display(),
                stacked.join(" and ")
            ));
        }
        p.b.check_instances(mesh, n).map_err(ctx.scene_err(&what))?;
        p.budget.reserve(
            Holds::Instances(n),
            &format!("{}: {what}", ctx.file.display()),
        )?;
        let [nx, ny, _] = d.count;
        for k in 0..n {
            let cell = Vec3::new(
                (k % nx) as f32,
                ((k / nx) % ny) as f32,
                (k / (nx * ny)) as f32,
            );
            let xf = d.placement(k, cell, spacing, axis);
            p.b.add_instance(mesh, xf, material).map_err(|e| {
                let place = format!("{what}: instance {} (cell {cell})", k + 1);
                ctx.scene_err(&place)(e)
            })?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::{assert_refused, load_test_scene as load};

    /// An icosphere mesh named `m` and a material `red`, for the arrays below.
    const MESH: &str = "[[material]]\nname = \"red\"\ncolor = [1, 0, 0]\n\
                        [[object]]\nname = \"m\"\ninstance_only = true\nkind = \"generator\"\n\
                        spec = \"icosphere:1\"\n";

    fn array(keys: &str) -> String {
        format!("{MESH}[[instance_array]]\nmesh = \"m\"\n{keys}\n")
    }

    /// A 4 x 1 x 3 grid: 12 instances in cell order (x fastest), each translated to its
    /// cell, ids after the flat primitives, the material override applied.
    #[test]
    fn a_grid_places_count_instances() {
        let s = load(&array(
            "count = [4, 1, 3]\nspacing = [2, 0, 3]\norigin = [-3, 1, 0]\nmaterial = \"red\"",
        ))
        .unwrap();
        let g = &s.geometry;
        assert_eq!(g.instances().len(), 12);
        let n = g.meshes()[0].len();
        assert_eq!(g.total_len(), 12 * n);
        let t = |k: usize| g.instances()[k].to_world().translation;
        assert_eq!(t(0), raybench_core::Vec3A::new(-3.0, 1.0, 0.0));
        assert_eq!(t(1), raybench_core::Vec3A::new(-1.0, 1.0, 0.0));
        assert_eq!(t(4), raybench_core::Vec3A::new(-3.0, 1.0, 3.0));
        assert_eq!(t(11), raybench_core::Vec3A::new(3.0, 1.0, 6.0));
        assert_eq!(s.material_of((5 * n) as u32).name, "red");
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    }

    /// Instances stacked by a zero spacing are one warning; a zero spacing along an axis
    /// of one instance is none.
    #[test]
    fn a_zero_spacing_is_a_warning() {
        let s = load(&array("count = [3, 1, 2]\nspacing = 0")).unwrap();
        assert_eq!(
            s.warnings,
            [
                "t.toml: line 9: instance_array 1: `spacing` is 0 along x and z where `count` \
              places several instances: they coincide, drawn over each other, and every ray \
              that meets one tests them all"
            ]
        );
        let s = load(&array("count = [3, 1, 2]\nspacing = [1, 0, 1]")).unwrap();
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    }

    /// The seeded variation: the same seed gives the same transforms (run to run, and
    /// instance k's draw does not depend on the grid's size); another seed others; angles
    /// and scales stay in their ranges.
    #[test]
    fn variation_is_seeded_and_in_range() {
        let keys = |seed: u32, count: &str| {
            array(&format!(
                "count = {count}\nspacing = 3\nseed = {seed}\nrotate_axis = [0, 0, 1]\n\
                 rotate_degrees = [10, 80]\nscale_range = [0.5, 1.5]"
            ))
        };
        let xfs = |text: String| -> Vec<raybench_core::Affine3A> {
            let s = load(&text).unwrap();
            s.geometry
                .instances()
                .iter()
                .map(|i| i.to_world())
                .collect()
        };
        let a = xfs(keys(7, "[5, 5, 1]"));
        assert_eq!(a, xfs(keys(7, "[5, 5, 1]")));
        let wider = xfs(keys(7, "[25, 1, 1]"));
        for k in 0..25 {
            assert_eq!(a[k].matrix3, wider[k].matrix3, "instance {k}");
        }
        let other = xfs(keys(8, "[5, 5, 1]"));
        assert!(a.iter().zip(&other).all(|(x, y)| x.matrix3 != y.matrix3));
        let (mut scales, mut angles) = (Vec::new(), Vec::new());
        for xf in &a {
            let m = xf.matrix3;
            let s = m.x_axis.length();
            scales.push(s);
            // A rotation about z: x maps into the xy plane at the drawn angle.
            assert!(m.x_axis.z.abs() < 1e-6 && (m.z_axis.z - s).abs() < 1e-5);
            angles.push(m.x_axis.y.atan2(m.x_axis.x).to_degrees());
        }
        assert!(
            scales.iter().all(|&s| (0.5..1.5).contains(&s)),
            "{scales:?}"
        );
        assert!(
            angles.iter().all(|&d| (9.99..80.01).contains(&d)),
            "{angles:?}"
        );
        let spread = |v: &[f32]| {
            v.iter().copied().fold(f32::MIN, f32::max) - v.iter().copied().fold(f32::MAX, f32::min)
        };
        assert!(spread(&scales) > 0.5 && spread(&angles) > 35.0);
    }

    /// Every bad array is one error naming the file, the table's line and index, and the
    /// cause; a count over the limits is refused before any instance is made.
    #[test]
    fn array_errors_name_the_problem() {
        let cases = [
            (
                array("count = [2, 2]\nspacing = 1"),
                "line 9: instance_array 1: invalid length 2",
            ),
            (
                array("count = [2, 0, 2]\nspacing = 1"),
                "line 9: instance_array 1: `count` [2, 0, 2] has a zero",
            ),
            (
                array("count = [2, -1, 2]\nspacing = 1"),
                "line 9: instance_array 1:",
            ),
            (
                array("count = [1024, 1024, 2]\nspacing = 1"),
                "line 9: instance_array 1: `count` [1024, 1024, 2] makes more than 1048576 instances",
            ),
            (
                array("count = [4294967296, 4294967296, 4294967296]\nspacing = 1"),
                "makes more than 1048576 instances",
            ),
            (
                array("count = [1, 1, 1]\nspacing = [1, nan, 1]"),
                "`spacing` [1, NaN, 1] is not finite",
            ),
            (
                array("count = [2, 1, 1]\nspacing = 1\nscale_range = [0, 2]"),
                "`scale_range` [0, 2]: scales must be above 0",
            ),
            (
                array("count = [2, 1, 1]\nspacing = 1\nrotate_degrees = [90, 10]"),
                "`rotate_degrees` [90, 10]: the first bound exceeds the second",
            ),
            (
                array("count = [2, 1, 1]\nspacing = 1\nrotate_axis = [0, 0, 0]"),
                "`rotate_axis` [0, 0, 0] is not a direction",
            ),
            (
                array("count = [2, 1, 1]\nspacing = 1\nmaterial = \"x\""),
                "material 'x' is not defined",
            ),
            (
                array("count = [2, 1, 1]\nspacing = 1\njitter = 3"),
                "line 13: instance_array 1: unknown field `jitter`",
            ),
            (
                format!("{MESH}[[instance_array]]\nmesh = \"n\"\ncount = [1, 1, 1]\nspacing = 1\n"),
                "line 9: instance_array 1: mesh 'n' is not defined",
            ),
            (
                array("count = [3, 1, 1]\nspacing = 1\ntransform = { scale = [1, 0, 1] }"),
                "line 9: instance_array 1: instance 1 (cell [0, 0, 0]): instance transform is singular",
            ),
            (
                array("count = [3, 1, 1]\nspacing = 1e30"),
                "line 9: instance_array 1: instance 2 (cell [1, 0, 0]): instance transform",
            ),
        ];
        assert_refused(&cases);
    }

    /// The limit on instanced primitives is checked before anything is added: a million
    /// instances of a 16,000-triangle mesh (more than 2^32 primitives flattened) is
    /// refused by the count alone (made one by one, they would not fit in memory).
    #[test]
    fn the_instanced_total_is_checked_first() {
        let text = "[[object]]\nname = \"m\"\ninstance_only = true\nkind = \"generator\"\n\
                    spec = \"soup:16000\"\n\
                    [[instance_array]]\nmesh = \"m\"\ncount = [1024, 1024, 1]\nspacing = 1\n";
        let e = load(text).expect_err("accepted").to_string();
        assert!(
            e.contains("primitives once its instances are counted"),
            "{e}"
        );
        assert!(e.contains("line 6: instance_array 1"), "{e}");
    }
}
