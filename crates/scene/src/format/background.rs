//! The `background` key of the scene format: a constant colour `[r, g, b]`, or an
//! environment map `{ map = "sky.exr", rotate = 90, scale = 1 }` (an equirectangular
//! OpenEXR or Radiance `.hdr` image in linear light; the convention is
//! `raybench_core::Environment`'s, documented in `docs/scene-format.md`).

use super::{Context, V3};
use crate::budget::{Holds, Reservation};
use crate::error::LoadError;
use raybench_core::{Environment, SceneBuilder, Vec3};
use serde::Deserialize;
use std::path::Path;
use std::sync::Arc;

/// The most texels an environment map may have (16384 x 8192).
pub(crate) const MAX_ENVIRONMENT_TEXELS: u64 = 1 << 27;

/// `background = { map = ..., rotate = ..., scale = ... }`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MapDesc {
    /// The image, relative to the scene file's folder, then the assets folder.
    map: String,
    /// Degrees about the up axis (`+y`).
    #[serde(default)]
    rotate: f32,
    /// A multiplier of the map's radiance.
    #[serde(default = "one")]
    scale: f32,
}

fn one() -> f32 {
    1.0
}

/// `background: ` with the line of the key, for messages.
fn label(text: &str) -> String {
    let line = text.lines().position(|l| {
        l.trim_start()
            .strip_prefix("background")
            .is_some_and(|rest| rest.trim_start().starts_with('='))
    });
    line.map_or("background".into(), |l| {
        format!("line {}: background", l + 1)
    })
}

/// Sets the scene's background from the value of the `background` key.
pub(super) fn add(
    value: toml::Value,
    text: &str,
    ctx: &Context,
    b: &mut SceneBuilder,
    budget: &mut Reservation,
) -> Result<(), LoadError> {
    let what = label(text);
    let parse = |message: String| LoadError::Parse {
        path: ctx.file.clone(),
        message: format!("{what}: {message}"),
    };
    match value {
        toml::Value::Table(t) => {
            let desc: MapDesc = toml::Value::Table(t)
                .try_into()
                .map_err(|e: toml::de::Error| parse(e.message().trim_end().to_owned()))?;
            if !desc.rotate.is_finite() {
                return Err(parse(format!(
                    "rotate {} must be finite (degrees about +y)",
                    desc.rotate
                )));
            }
            if !(desc.scale.is_finite() && desc.scale >= 0.0) {
                return Err(parse(format!(
                    "scale {} must be finite and at least 0",
                    desc.scale
                )));
            }
            let path = ctx.resolve("map", &desc.map, &what)?;
            let context = format!("{}: {what}", ctx.file.display());
            let (w, h, texels, negative) =
                read_map(&path, None, budget, &context).map_err(ctx.within(&what))?;
            if negative {
                b.warn(format!(
                    "{context}: {} has negative texels, read as 0",
                    path.display()
                ));
            }
            let env = Environment::new(w, h, texels, desc.scale, desc.rotate).ok_or_else(|| {
                LoadError::Parse {
                    path: path.clone(),
                    message: "the map's radiance times the scale overflows f32".into(),
                }
                .within(&context)
            })?;
            b.environment(Arc::new(env));
            Ok(())
        }
        toml::Value::Array(values) => {
            // A list: a colour, whose numbers are wrong.
            let shown: Vec<String> = values
                .iter()
                .map(|v| match v {
                    toml::Value::Integer(i) => i.to_string(),
                    toml::Value::Float(f) => f.to_string(),
                    toml::Value::String(s) => format!("{s:?}"),
                    other => format!("a {}", other.type_str()),
                })
                .collect();
            let shown = format!("[{}]", shown.join(", "));
            let rgb: V3 = toml::Value::Array(values)
                .try_into()
                .map_err(|_| parse(format!("a colour needs 3 numbers [r, g, b], found {shown}")))?;
            b.background(Vec3::from(rgb))
                .map_err(ctx.scene_err(&what))?;
            Ok(())
        }
        other => {
            let kind = other.type_str();
            let article = if kind.starts_with(['a', 'e', 'i', 'o', 'u']) {
                "an"
            } else {
                "a"
            };
            Err(parse(format!(
                "expected a colour [r, g, b] or a map {{ map = \"sky.exr\", ... }}, found \
                 {article} {kind}"
            )))
        }
    }
}

/// Reads an OpenEXR (`.exr`) or Radiance (`.hdr`) image as linear RGB rows from the top,
/// checking its size against [`MAX_ENVIRONMENT_TEXELS`] and the budget from its header.
/// Also says whether negative texels were read as 0. The extension of `path` gives the
/// format; `contents` are the file's bytes when already in memory (the fuzz targets),
/// `None` reads the file.
pub(crate) fn read_map(
    path: &Path,
    contents: Option<&[u8]>,
    budget: &mut Reservation,
    context: &str,
) -> Result<(u32, u32, Vec<Vec3>, bool), LoadError> {
    let parse = |message: String| LoadError::Parse {
        path: path.to_owned(),
        message,
    };
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let format = match ext.as_deref() {
        Some("exr") => image::ImageFormat::OpenExr,
        Some("hdr") => image::ImageFormat::Hdr,
        _ => {
            return Err(parse(
                "an environment map must be an OpenEXR (.exr) or Radiance (.hdr) image".into(),
            ));
        }
    };
    let img = crate::samples::decode_image(
        path,
        contents,
        format,
        "image",
        MAX_ENVIRONMENT_TEXELS,
        // The widest decoded form: RGBA f32.
        16,
        |texels| budget.reserve(Holds::EnvironmentTexels(texels), context),
    )?;
    let (w, h) = (img.width(), img.height());
    if w == 0 || h == 0 {
        return Err(parse(format!("the {w} x {h} environment map is empty")));
    }
    let rgb = img.into_rgb32f();
    let mut negative = false;
    let mut out = Vec::with_capacity(rgb.pixels().len());
    for p in rgb.pixels() {
        let v = Vec3::from(p.0);
        if !v.is_finite() {
            let i = out.len() as u32;
            return Err(parse(format!(
                "texel ({}, {}) is not finite ({v})",
                i % w,
                i / w
            )));
        }
        negative |= v.min_element() < 0.0;
        out.push(v.max(Vec3::ZERO));
    }
    Ok((w, h, out, negative))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn dir() -> PathBuf {
        let d = std::env::temp_dir().join(format!("raybench-background-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// A 4 x 2 map whose texel (x, y) has red `y * 4 + x`, written as `name`.
    fn write_map(name: &str) -> PathBuf {
        let p = dir().join(name);
        let data: Vec<f32> = (0..8).flat_map(|i| [i as f32, 0.5, 0.25]).collect();
        image::DynamicImage::ImageRgb32F(image::Rgb32FImage::from_raw(4, 2, data).unwrap())
            .save(&p)
            .unwrap();
        p
    }

    fn scene(name: &str, background: &str) -> Result<raybench_core::Scene, LoadError> {
        let p = dir().join(name);
        let text = format!(
            "{background}\n[[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n"
        );
        std::fs::write(&p, text).unwrap();
        crate::format::load_toml_file(&p, Path::new("/nonexistent"))
    }

    #[test]
    fn maps_load_in_both_formats_with_rotation_and_scale() {
        write_map("sky.hdr");
        write_map("sky.exr");
        let up = Vec3::new(0.0, 0.01, 0.0);
        for file in ["sky.hdr", "sky.exr"] {
            let s = scene(
                "a.toml",
                &format!("background = {{ map = \"{file}\", rotate = 90, scale = 2 }}"),
            )
            .unwrap();
            let env = s.environment.as_deref().unwrap();
            assert_eq!(env.size(), (4, 2));
            // Rotated by 90 degrees: the map's u = 0 column looks along -z, u = 0.25 along +x.
            let r = |d: Vec3| env.radiance(d + up).x;
            assert!((r(-Vec3::Z) - 0.0).abs() < 1e-2, "{file}");
            assert!((r(Vec3::X) - 2.0).abs() < 1e-2, "{file}: {}", r(Vec3::X));
            assert!((env.radiance(-Vec3::Y).y - 1.0).abs() < 1e-2, "{file}");
            assert!(!s.emitters.is_empty());
        }
        // The constant background still parses.
        let s = scene("b.toml", "background = [0.1, 0.2, 0.3]").unwrap();
        assert!(s.environment.is_none());
        assert_eq!(s.background, Vec3::new(0.1, 0.2, 0.3));
    }

    #[test]
    fn bad_maps_are_one_line_errors() {
        write_map("sky.hdr");
        let png = dir().join("sky.png");
        std::fs::write(&png, b"not really").unwrap();
        std::fs::write(dir().join("broken.exr"), b"not an exr").unwrap();
        for (background, expect) in [
            ("background = { map = \"sky.png\" }", ".exr) or Radiance"),
            (
                "background = { map = \"sky.hdr\", spin = 3 }",
                "line 1: background: unknown field",
            ),
            (
                "background = { map = \"sky.hdr\", scale = -1 }",
                "line 1: background: scale -1 must be finite and at least 0",
            ),
            (
                "background = { map = \"sky.hdr\", rotate = inf }",
                "line 1: background: rotate inf must be finite (degrees about +y)",
            ),
            ("background = 3", "found an integer"),
            (
                "background = \"blue\"",
                "line 1: background: expected a colour [r, g, b] or a map { map = \"sky.exr\", \
                 ... }, found a string",
            ),
            (
                "background = [1, 0]",
                "line 1: background: a colour needs 3 numbers [r, g, b], found [1, 0]",
            ),
            (
                "background = [1, \"a\", 0]",
                "a colour needs 3 numbers [r, g, b], found [1, \"a\", 0]",
            ),
            (
                "background = { map = \"broken.exr\" }",
                "not a readable image",
            ),
            ("background = { map = \"absent.hdr\" }", "absent.hdr"),
        ] {
            let e = scene("c.toml", background).unwrap_err().to_string();
            assert!(e.contains(expect), "{background}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }
}
