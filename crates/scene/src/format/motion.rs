//! Motion in scene files: an `[[instance]]`'s `keys` (its placement at frames,
//! interpolated) and `motion` (a procedural spin, orbit or bob on top of its placement), and
//! an `[[object]]`'s `deform` (a triangle mesh twisted over frames). The motions themselves
//! and the geometry at a frame are `raybench_core`'s ([`raybench_core::Motion`]).

use super::{Context, ScaleDesc, TransformDesc, V3};
use crate::error::LoadError;
use raybench_core::{
    Affine3A, Deformation, InstanceMotion, Key, Placement, Procedural, SceneBuilder, Vec3,
};
use serde::Deserialize;

/// One key of an instance's `keys`: its transform at `frame` (scale, then rotate in degrees
/// about x, y, z, then translate, as a `transform` table).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct KeyDesc {
    frame: u32,
    scale: Option<ScaleDesc>,
    rotate: Option<V3>,
    translate: Option<V3>,
}

impl KeyDesc {
    fn key(&self) -> Key {
        let t = TransformDesc {
            scale: self.scale.as_ref().map(|s| match s {
                ScaleDesc::Uniform(u) => ScaleDesc::Uniform(*u),
                ScaleDesc::PerAxis(v) => ScaleDesc::PerAxis(*v),
            }),
            rotate: self.rotate,
            translate: self.translate,
        }
        .to_transform();
        Key {
            frame: self.frame,
            scale: t.scale,
            rotation: t.rotation(),
            translate: t.translate,
        }
    }
}

/// An instance's `motion` table, by its `kind`.
#[derive(Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub(super) enum MotionDesc {
    /// Turns about `axis` through the instance's origin.
    Spin { axis: V3, degrees_per_frame: f32 },
    /// Carries the instance's origin round `axis` through `center`.
    Orbit {
        axis: V3,
        center: V3,
        degrees_per_frame: f32,
    },
    /// Moves it back and forth by `offset` with a period of `period` frames.
    Bob {
        offset: V3,
        period: f32,
        #[serde(default)]
        phase: f32,
    },
}

impl MotionDesc {
    fn procedural(&self) -> Procedural {
        match *self {
            Self::Spin {
                axis,
                degrees_per_frame,
            } => Procedural::Spin {
                axis: Vec3::from(axis),
                degrees_per_frame,
            },
            Self::Orbit {
                axis,
                center,
                degrees_per_frame,
            } => Procedural::Orbit {
                axis: Vec3::from(axis),
                center: Vec3::from(center),
                degrees_per_frame,
            },
            Self::Bob {
                offset,
                period,
                phase,
            } => Procedural::Bob {
                offset: Vec3::from(offset),
                period,
                phase,
            },
        }
    }
}

/// An object's `deform` table, by its `kind`.
#[derive(Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub(super) enum DeformDesc {
    /// Twists the mesh about `axis` (`"x"`, `"y"` or `"z"`) through its box's centre.
    Twist {
        axis: String,
        degrees_per_frame: f32,
    },
}

/// What an `[[instance]]` table asks for: its transform at frame 0 (what the instance is
/// added with) and its motion, if it moves.
pub(super) fn placement(
    transform: &TransformDesc,
    keys: Option<&[KeyDesc]>,
    motion: Option<&MotionDesc>,
) -> Result<(Affine3A, Option<InstanceMotion>), String> {
    let placed =
        transform.scale.is_some() || transform.rotate.is_some() || transform.translate.is_some();
    let base = match keys {
        Some(_) if placed => {
            return Err(
                "give either `transform` or `keys` (the placement at frames), not both".into(),
            );
        }
        Some(keys) => Placement::Keyed(keys.iter().map(KeyDesc::key).collect()),
        None if motion.is_none() => return Ok((transform.to_transform().affine(), None)),
        None => Placement::Fixed(transform.to_transform().affine()),
    };
    let m =
        InstanceMotion::new(base, motion.map(MotionDesc::procedural)).map_err(|e| e.to_string())?;
    Ok((m.to_world(0), Some(m)))
}

/// Takes an `[[object]]`'s `deform` key out of its table (before its kind's own struct
/// reads the table), parsed.
pub(super) fn take_deform(
    table: &mut toml::Table,
    what: impl Fn() -> String,
    ctx: &Context,
) -> Result<Option<Deformation>, LoadError> {
    let Some(value) = table.remove("deform") else {
        return Ok(None);
    };
    let fail = |message: String| LoadError::Parse {
        path: ctx.file.clone(),
        message: format!("{}: deform: {message}", what()),
    };
    let d: DeformDesc = value
        .try_into()
        .map_err(|e: toml::de::Error| fail(e.message().trim_end().to_owned()))?;
    let DeformDesc::Twist {
        axis,
        degrees_per_frame,
    } = d;
    let axis = match axis.as_str() {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        other => {
            return Err(fail(format!(
                "twist axis '{other}' is not \"x\", \"y\" or \"z\""
            )));
        }
    };
    Ok(Some(Deformation::Twist {
        axis,
        degrees_per_frame,
    }))
}

/// Deforms the object just added to `b` (see [`SceneBuilder::deform_last_object`]).
pub(super) fn deform(
    b: &mut SceneBuilder,
    deformation: Deformation,
    what: &str,
    ctx: &Context,
) -> Result<(), LoadError> {
    b.deform_last_object(deformation)
        .map_err(ctx.scene_err(&format!("{what}: deform")))
}

#[cfg(test)]
mod tests {
    use super::super::{assert_refused, load_test_scene as load};
    use raybench_core::Vec3;

    const MESH: &str = "[[object]]\nname = \"m\"\ninstance_only = true\nkind = \"generator\"\n\
                        spec = \"icosphere:1\"\n";

    /// Keys, procedural motions and a twist are read into the scene's motion; frame 0 is
    /// the scene as loaded, later frames move.
    #[test]
    fn motion_is_read() {
        let s = load(&format!(
            "[[object]]\nkind = \"generator\"\nspec = \"icosphere:2\"\n\
             transform = {{ scale = [1, 2, 0.5] }}\n\
             deform = {{ kind = \"twist\", axis = \"y\", degrees_per_frame = 10 }}\n\
             {MESH}\
             [[instance]]\nmesh = \"m\"\nkeys = [\n\
             {{ frame = 0, translate = [-2, 0, 0] }},\n\
             {{ frame = 10, translate = [2, 0, 0], rotate = [0, 90, 0], scale = 2 }},\n]\n\
             [[instance]]\nmesh = \"m\"\ntransform = {{ translate = [0, 3, 0] }}\n\
             motion = {{ kind = \"spin\", axis = [0, 1, 0], degrees_per_frame = 30 }}\n\
             [[instance]]\nmesh = \"m\"\n\
             motion = {{ kind = \"orbit\", axis = [0, 1, 0], center = [0, 0, 5], \
             degrees_per_frame = 90 }}\n\
             [[instance]]\nmesh = \"m\"\n\
             motion = {{ kind = \"bob\", offset = [0, 1, 0], period = 4, phase = 0.25 }}\n\
             [[instance]]\nmesh = \"m\"\ntransform = {{ translate = [5, 0, 0] }}\n"
        ))
        .unwrap();
        let m = s.motion.as_ref().expect("the scene moves");
        assert_eq!(m.instances().len(), 4);
        assert_eq!(m.deforms().len(), 1);
        let placed = |f: u32, k: usize| {
            let g = s.at_frame(f).unwrap().geometry;
            Vec3::from(g.instances()[k].to_world().translation)
        };
        // Keyed: halfway at frame 5, the last key after frame 10.
        assert_eq!(placed(0, 0), Vec3::new(-2.0, 0.0, 0.0));
        assert!((placed(5, 0) - Vec3::ZERO).length() < 1e-6);
        assert_eq!(placed(15, 0), Vec3::new(2.0, 0.0, 0.0));
        // Orbit: a quarter turn per frame about (0, 0, 5).
        assert!((placed(1, 2) - Vec3::new(-5.0, 0.0, 5.0)).length() < 1e-5);
        // Bob: a quarter period in at frame 0, so 1 up; at frame 2, 1 down.
        assert!((placed(0, 3) - Vec3::Y).length() < 1e-6);
        assert!((placed(2, 3) + Vec3::Y).length() < 1e-6);
        // Frame 0 is the scene as loaded.
        let f0 = s.at_frame(0).unwrap();
        assert_eq!(f0.geometry.shapes(), s.geometry.shapes());
        assert_eq!(f0.geometry.instances(), s.geometry.instances());
        assert_ne!(
            s.at_frame(3).unwrap().geometry.shapes(),
            s.geometry.shapes()
        );
        // A scene without motion has none.
        let still = load(&format!("{MESH}[[instance]]\nmesh = \"m\"\n")).unwrap();
        assert!(still.motion.is_none());
    }

    /// Every bad motion is one error naming the file, the table, its line and the cause.
    #[test]
    fn motion_errors_name_the_problem() {
        let inst = |rest: &str| format!("{MESH}[[instance]]\nmesh = \"m\"\n{rest}");
        let cases = [
            (
                inst("keys = [{ frame = 4 }, { frame = 2 }]\n"),
                "line 6: instance 1: key 2 (frame 2) does not come after the frame of key 1",
            ),
            (inst("keys = []\n"), "line 6: instance 1: `keys` is empty"),
            (
                inst("keys = [{ frame = 0, scale = 1 }, { frame = 5, scale = -1 }]\n"),
                "changes sign on axis x",
            ),
            (
                inst("keys = [{ frame = 0 }]\ntransform = { translate = [1, 0, 0] }\n"),
                "line 6: instance 1: give either `transform` or `keys`",
            ),
            (
                inst("keys = [{ frame = 0, colour = 1 }]\n"),
                "line 6: instance 1: unknown field `colour`",
            ),
            (inst("keys = [{ frame = -1 }]\n"), "line 6: instance 1:"),
            (
                inst("motion = { kind = \"wobble\" }\n"),
                "line 6: instance 1: unknown variant `wobble`",
            ),
            (
                inst("motion = { kind = \"spin\", axis = [0, 0, 0], degrees_per_frame = 1 }\n"),
                "line 6: instance 1: spin axis is zero",
            ),
            (
                inst("motion = { kind = \"bob\", offset = [0, 1, 0], period = 0 }\n"),
                "line 6: instance 1: bob period must be positive",
            ),
            (
                inst("motion = { kind = \"spin\", axis = [0, 1, 0] }\n"),
                "missing field `degrees_per_frame`",
            ),
            (
                "[[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n\
                 deform = { kind = \"twist\", axis = \"y\", degrees_per_frame = 1 }\n"
                    .into(),
                "t.toml: line 1: object 1 (sphere): deform: only triangle meshes deform",
            ),
            (
                "[[object]]\nkind = \"generator\"\nspec = \"icosphere:1\"\n\
                 deform = { kind = \"twist\", axis = \"w\", degrees_per_frame = 1 }\n"
                    .into(),
                "line 1: object 1: deform: twist axis 'w' is not",
            ),
            (
                "[[object]]\nkind = \"generator\"\nspec = \"icosphere:1\"\n\
                 deform = { kind = \"bend\" }\n"
                    .into(),
                "line 1: object 1: deform: unknown variant `bend`",
            ),
            (
                "[[object]]\nkind = \"polygons\"\npositions = [[0,0,0],[1,0,0],[0,1,0]]\n\
                 faces = [[0,1,2]]\ndeform = { kind = \"twist\", axis = \"z\", \
                 degrees_per_frame = 1 }\n"
                    .into(),
                "flat along the twist's axis (z)",
            ),
            (
                "[[material]]\nname = \"lamp\"\nemission = [1, 1, 1]\n\
                 [[object]]\nkind = \"generator\"\nspec = \"icosphere:1\"\nmaterial = \"lamp\"\n\
                 deform = { kind = \"twist\", axis = \"y\", degrees_per_frame = 1 }\n"
                    .into(),
                "line 4: object 1 (generator): deform: icosphere:1 emits light",
            ),
        ];
        assert_refused(&cases);
    }
}
