//! The TOML scene format (documented in `docs/scene-format.md`).
//!
//! This file reads the scene file table by table (each error names the table, its index,
//! kind and line) and hands every table to the file of its kind: `camera.rs`,
//! `material.rs`, `light.rs` and `volume.rs` for the tables of those names; for each
//! `[[object]]`, the file of its `kind` (`simple.rs`: spheres and planes; `mesh.rs`:
//! triangles, polygons and mesh files; `generator.rs`; `heightfield.rs`; `csg.rs`: CSG trees
//! and the standalone analytic solids; `bezier.rs`; `sdf.rs`). A new object kind is one
//! file here with its table's struct and its `add`, plus its variant of [`ObjectDesc`] and
//! the one match arm that calls that `add`.

pub(crate) mod background;
mod bezier;
mod camera;
mod csg;
mod generator;
mod heightfield;
mod instance_array;
mod light;
mod material;
mod mesh;
mod motion;
mod sdf;
mod simple;
mod volume;

pub(crate) use mesh::bare_mesh_scene;

use crate::budget::Reservation;
use crate::error::LoadError;
use crate::io::read_text;
use crate::transform::Transform;
use raybench_core::{Scene, SceneBuilder, SceneError, Vec3};
use serde::Deserialize;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Scene files larger than this are refused before reading (meshes belong in mesh files).
const MAX_SCENE_FILE_BYTES: u64 = 64 << 20;

type V3 = [f32; 3];

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    background: Option<toml::Value>,
    /// One `[camera]` table or a `[[camera]]` list (told apart in `parse_and_build`).
    camera: Option<toml::Value>,
    // The arrays of tables are parsed table by table (`table_item`), so that an error
    // names the table, its index, kind and line rather than the array's first table.
    #[serde(default, rename = "material")]
    materials: Vec<toml::Table>,
    #[serde(default, rename = "light")]
    lights: Vec<toml::Table>,
    #[serde(default, rename = "object")]
    objects: Vec<toml::Table>,
    #[serde(default, rename = "volume")]
    volumes: Vec<toml::Table>,
    #[serde(default, rename = "instance")]
    instances: Vec<toml::Table>,
    #[serde(default, rename = "instance_array")]
    instance_arrays: Vec<toml::Table>,
    /// `[benchmark]`: a built-in scene's report metadata, read by `build.rs`; ignored here.
    #[serde(default, rename = "benchmark")]
    _benchmark: Option<serde::de::IgnoredAny>,
}

/// The 1-based line of the header of the `index`-th `[[array]]` table in `text`, if the
/// array is written with such headers (not inline).
fn header_line(text: &str, array: &str, index: usize) -> Option<usize> {
    let header = format!("[[{array}]]");
    text.lines()
        .enumerate()
        .filter(|(_, l)| {
            let squeezed: String = l.chars().filter(|c| !c.is_whitespace()).collect();
            squeezed.starts_with(&header)
        })
        .nth(index)
        .map(|(i, _)| i + 1)
}

/// The line of key `key` inside the table whose header is on line `header` (up to the next
/// table header that is not one of its sub-tables, `[array.sub]`).
fn key_line(text: &str, array: &str, header: usize, key: &str) -> Option<usize> {
    let sub = format!("[{array}.");
    text.lines()
        .enumerate()
        .skip(header)
        .take_while(|(_, l)| {
            let l = l.trim_start();
            !l.starts_with('[') || l.starts_with(&sub)
        })
        .find(|(_, l)| {
            l.trim_start()
                .strip_prefix(key)
                .is_some_and(|rest| rest.trim_start().starts_with(['=', '.']))
        })
        .map(|(i, _)| i + 1)
}

/// Parses the `index`-th table of the array `array` (`object`, `light`, ...) of a scene
/// file as `T`, and returns it with a label naming it in messages: `line 7: object 2
/// (sphere)` (the line of its header, its 1-based index, its kind). A parse error
/// names the same, at the line of the offending key when the message names one.
fn table_item<T: serde::de::DeserializeOwned>(
    text: &str,
    array: &str,
    index: usize,
    table: toml::Table,
    ctx: &Context,
) -> Result<(T, String), LoadError> {
    let header = header_line(text, array, index);
    let mut label = format!("{array} {}", index + 1);
    if let Some(kind) = table.get("kind").and_then(toml::Value::as_str) {
        label += &format!(" ({kind})");
    }
    let at = |line: Option<usize>| line.map_or(String::new(), |l| format!("line {l}: "));
    match toml::Value::Table(table).try_into::<T>() {
        Ok(item) => Ok((item, format!("{}{label}", at(header)))),
        Err(e) => {
            let message = e.message().trim_end().to_owned();
            // `unknown field `colour`, expected ...`: point at the key.
            let key = message
                .split('`')
                .nth(1)
                .filter(|_| message.starts_with("unknown field"));
            let line = header
                .and_then(|h| key.and_then(|k| key_line(text, array, h, k)))
                .or(header);
            Err(LoadError::Parse {
                path: ctx.file.clone(),
                message: format!("{}{label}: {message}", at(line)),
            })
        }
    }
}

/// A scale: one factor for every axis, or one per axis.
#[derive(Deserialize)]
#[serde(untagged)]
enum ScaleDesc {
    Uniform(f32),
    PerAxis(V3),
}

/// An object's `transform` table: scale, then rotate (degrees about x, y, z), then
/// translate.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct TransformDesc {
    scale: Option<ScaleDesc>,
    rotate: Option<V3>,
    translate: Option<V3>,
}

impl TransformDesc {
    /// The transform of an object's `transform` table, checked as CSG transforms are
    /// ([`raybench_core::check_transform`]): a zero scale would flatten the object into
    /// nothing and render an empty image without a word.
    fn checked(&self) -> Result<Transform, SceneError> {
        let xf = self.to_transform();
        if !xf.is_identity() {
            raybench_core::check_transform(xf.affine(), "transform")?;
        }
        Ok(xf)
    }

    /// The transform, unchecked.
    fn to_transform(&self) -> Transform {
        Transform {
            scale: match self.scale {
                None => Vec3::ONE,
                Some(ScaleDesc::Uniform(s)) => Vec3::splat(s),
                Some(ScaleDesc::PerAxis(s)) => Vec3::from(s),
            },
            rotate_degrees: self.rotate.map_or(Vec3::ZERO, Vec3::from),
            translate: self.translate.map_or(Vec3::ZERO, Vec3::from),
        }
    }
}

/// An `[[instance]]` table: a named instance mesh placed by an affine transform, with an
/// optional material for all its primitives.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct InstanceDesc {
    mesh: String,
    #[serde(default)]
    transform: TransformDesc,
    material: Option<String>,
    /// Its placement at frames, instead of `transform` (`motion.rs`).
    keys: Option<Vec<motion::KeyDesc>>,
    /// A procedural motion on top of its placement (`motion.rs`).
    motion: Option<motion::MotionDesc>,
}

/// The keys every `[[object]]` may carry besides its kind's, taken out of the table before
/// the kind's own struct reads it: `name` and `instance_only = true` make the object (or,
/// with several objects of one name, a group of objects) a mesh that `[[instance]]` tables
/// place and that is not drawn by itself. Returns the mesh's name for such an object.
fn take_instance_keys(
    table: &mut toml::Table,
    text: &str,
    index: usize,
    ctx: &Context,
) -> Result<Option<String>, LoadError> {
    let name = table.remove("name");
    let only = table.remove("instance_only");
    if name.is_none() && only.is_none() {
        return Ok(None);
    }
    let what = header_line(text, "object", index).map_or_else(
        || format!("object {}", index + 1),
        |l| format!("line {l}: object {}", index + 1),
    );
    let fail = |message: &str| LoadError::Parse {
        path: ctx.file.clone(),
        message: format!("{what}: {message}"),
    };
    match (name, only) {
        (Some(toml::Value::String(n)), Some(toml::Value::Boolean(true))) if !n.is_empty() => {
            Ok(Some(n))
        }
        (Some(toml::Value::String(_)), Some(toml::Value::Boolean(true))) => {
            Err(fail("an instance mesh's `name` must not be empty"))
        }
        (Some(toml::Value::String(_)), None | Some(toml::Value::Boolean(false))) => Err(fail(
            "`name` names an instance mesh and needs `instance_only = true` (objects drawn \
             by themselves have no name)",
        )),
        (None, Some(toml::Value::Boolean(_))) => Err(fail(
            "`instance_only` needs a `name` for [[instance]] tables to refer to",
        )),
        (Some(_), _) => Err(fail("`name` must be a string")),
        (None, Some(_)) => Err(fail("`instance_only` must be true or false")),
        (None, None) => Ok(None),
    }
}

/// The instance meshes of a scene file, in order of their first object: each one's name,
/// the label of its first object (for errors) and the builder its objects went to.
type Parts = Vec<(String, String, SceneBuilder)>;

/// What the `[[instance]]` and `[[instance_array]]` tables are added with: the file's text
/// and context, the scene so far, the materials by name, the memory budget, and the
/// instance meshes by name (each one's index in the scene and whether a table places it).
struct Placing<'a> {
    text: &'a str,
    ctx: &'a Context<'a>,
    b: &'a mut SceneBuilder,
    materials: &'a HashMap<String, u32>,
    budget: &'a mut Reservation,
    meshes: Vec<(String, u32, bool)>,
}

impl Placing<'_> {
    /// The index in the scene of the instance mesh `name`, which a table now places
    /// (`None` when no instance mesh has that name).
    fn place(&mut self, name: &str) -> Option<u32> {
        let mesh = self.meshes.iter_mut().find(|(n, _, _)| n == name)?;
        mesh.2 = true;
        Some(mesh.1)
    }

    /// The id of the material `name` names for the table labelled `what` (`None` when the
    /// table names none).
    fn material(&self, what: &str, name: Option<&String>) -> Result<Option<u32>, LoadError> {
        material_id(self.materials, self.ctx, what, name)
    }
}

/// The id of the material `name` names for the table labelled `what` in messages (`None`
/// when the table names none).
fn material_id(
    materials: &HashMap<String, u32>,
    ctx: &Context,
    what: &str,
    name: Option<&String>,
) -> Result<Option<u32>, LoadError> {
    match name {
        None => Ok(None),
        Some(n) => materials
            .get(n)
            .copied()
            .map(Some)
            .ok_or_else(|| LoadError::Parse {
                path: ctx.file.clone(),
                message: format!("{what}: material '{n}' is not defined"),
            }),
    }
}

/// Adds every `[[instance]]` table: the meshes of `parts` first (each stored once), then
/// one instance per table, in file order; then the `[[instance_array]]` tables
/// (`instance_array.rs`).
fn add_instances(
    tables: Vec<toml::Table>,
    arrays: Vec<toml::Table>,
    parts: Parts,
    mut p: Placing,
) -> Result<(), LoadError> {
    let ctx = p.ctx;
    for (name, what, part) in parts {
        let i =
            p.b.add_instance_mesh(name.clone(), part)
                .map_err(ctx.scene_err(&what))?;
        p.meshes.push((name, i, false));
    }
    p.budget.reserve(
        crate::budget::Holds::Instances(tables.len() as u64),
        &format!("{}: [[instance]] tables", ctx.file.display()),
    )?;
    for (index, table) in tables.into_iter().enumerate() {
        let (d, what): (InstanceDesc, _) = table_item(p.text, "instance", index, table, ctx)?;
        let fail = |message: String| LoadError::Parse {
            path: ctx.file.clone(),
            message: format!("{what}: {message}"),
        };
        let Some(mesh) = p.place(&d.mesh) else {
            let known: Vec<String> = p.meshes.iter().map(|(n, _, _)| format!("'{n}'")).collect();
            return Err(fail(format!(
                "mesh '{}' is not defined (instance meshes are objects with a `name` and \
                 `instance_only = true`; this file has {})",
                d.mesh,
                if known.is_empty() {
                    "none".to_owned()
                } else {
                    known.join(", ")
                }
            )));
        };
        let material = p.material(&what, d.material.as_ref())?;
        let (affine, moving) =
            motion::placement(&d.transform, d.keys.as_deref(), d.motion.as_ref()).map_err(fail)?;
        p.b.add_instance(mesh, affine, material)
            .map_err(ctx.scene_err(&what))?;
        if let Some(m) = moving {
            let index = (p.b.instance_count() - 1) as u32;
            p.b.move_instance(index, m).map_err(ctx.scene_err(&what))?;
        }
    }
    instance_array::add(arrays, &mut p)?;
    for (name, _, used) in &p.meshes {
        if !used {
            p.b.warn(format!(
                "instance mesh '{name}' is placed by no [[instance]] or [[instance_array]]: \
                 it is not drawn"
            ));
        }
    }
    Ok(())
}

/// An `[[object]]` table, by its `kind`: each variant's table and its `add` live in the
/// file of that kind.
#[derive(Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
enum ObjectDesc {
    Sphere(simple::SphereDesc),
    Plane(simple::PlaneDesc),
    Triangle(mesh::TriangleDesc),
    Polygons(mesh::PolygonsDesc),
    Mesh(mesh::MeshDesc),
    Generator(generator::GeneratorDesc),
    HeightField(heightfield::HeightFieldDesc),
    Csg(csg::CsgDesc),
    // Analytic solids as objects: each is a one-leaf CSG primitive.
    Torus(csg::TorusDesc),
    Ellipsoid(csg::EllipsoidDesc),
    Cylinder(csg::RevolvedDesc),
    Cone(csg::RevolvedDesc),
    Paraboloid(csg::RevolvedDesc),
    Bezier(bezier::BezierDesc),
    Sdf(sdf::SdfDesc),
}

impl ObjectDesc {
    /// Adds the object to the scene: the one dispatch from a kind to its file.
    fn add(&self, cx: &mut ObjectCx) -> Result<(), LoadError> {
        match self {
            Self::Sphere(d) => d.add(cx),
            Self::Plane(d) => d.add(cx),
            Self::Triangle(d) => d.add(cx),
            Self::Polygons(d) => d.add(cx),
            Self::Mesh(d) => d.add(cx),
            Self::Generator(d) => d.add(cx),
            Self::HeightField(d) => d.add(cx),
            Self::Csg(d) => d.add(cx),
            Self::Torus(d) => d.add(cx),
            Self::Ellipsoid(d) => d.add(cx),
            Self::Cylinder(d) => d.add("cylinder", cx),
            Self::Cone(d) => d.add("cone", cx),
            Self::Paraboloid(d) => d.add("paraboloid", cx),
            Self::Bezier(d) => d.add(cx),
            Self::Sdf(d) => d.add(cx),
        }
    }
}

/// What adding one `[[object]]` needs: the scene so far, the file, the object's label in
/// messages (`line 7: object 2 (sphere)`), the memory budget and the materials by name.
struct ObjectCx<'a> {
    b: &'a mut SceneBuilder,
    ctx: &'a Context<'a>,
    what: &'a str,
    budget: &'a mut Reservation,
    materials: &'a HashMap<String, u32>,
}

impl ObjectCx<'_> {
    /// The id of the material `name` names (`None` when the object names none).
    fn material(&self, name: Option<&String>) -> Result<Option<u32>, LoadError> {
        material_id(self.materials, self.ctx, self.what, name)
    }

    /// The scene builder's errors about this object, as load errors naming it (the
    /// function owns its message, so the builder stays free to borrow).
    fn err(&self) -> impl Fn(SceneError) -> LoadError + use<> {
        self.ctx.scene_err(self.what)
    }
}

/// Where relative paths of a scene are looked up.
struct Context<'a> {
    scene: &'a str,
    file: PathBuf,
    dir: Option<&'a Path>,
    assets: &'a Path,
}

impl Context<'_> {
    /// The file `name` (the value of the key `key` of the table labelled `what`): an
    /// absolute path as it is; a relative one in the scene file's folder, then in the
    /// assets folder. Only a regular file is found.
    ///
    /// # Errors
    /// [`LoadError::MissingAsset`] naming the scene's file and line, every place looked in
    /// and what is there instead (missing, a folder, a FIFO, a symbolic link loop), or a
    /// parse error for an empty name.
    fn resolve(&self, key: &str, name: &str, what: &str) -> Result<PathBuf, LoadError> {
        if name.trim().is_empty() {
            return Err(LoadError::Parse {
                path: self.file.clone(),
                message: format!("{what}: `{key}` is empty: it names a file"),
            });
        }
        let p = Path::new(name);
        let mut places = Vec::new();
        if p.is_absolute() {
            places.push(p.to_owned());
        } else {
            if let Some(dir) = self.dir {
                places.push(dir.join(p));
            }
            places.push(self.assets.join(p));
        }
        let mut looked = Vec::new();
        for place in places {
            match crate::io::probe(&place) {
                Ok(()) => return Ok(place),
                Err(found) => looked.push((place, found)),
            }
        }
        Err(LoadError::MissingAsset {
            context: format!("{}: {what}", self.file.display()),
            key: format!("`{key}`"),
            name: name.to_owned(),
            looked,
            assets: !p.is_absolute(),
        })
    }

    /// The scene file and the table labelled `what`, for the errors of a file it names
    /// ([`LoadError::within`]).
    fn within(&self, what: &str) -> impl Fn(LoadError) -> LoadError + use<> {
        let context = format!("{}: {what}", self.file.display());
        move |e| e.within(&context)
    }

    fn scene_err(&self, what: &str) -> impl Fn(SceneError) -> LoadError + use<> {
        let context = format!("{}: {what}", self.file.display());
        move |cause| LoadError::Scene {
            context: context.clone(),
            cause,
        }
    }
}

/// Loads a `.toml` scene file; relative mesh paths resolve against its folder, then `assets`.
///
/// # Errors
/// When the file is missing, too large, malformed or invalid, or a mesh it names is.
pub fn load_toml_file(path: &Path, assets: &Path) -> Result<Scene, LoadError> {
    let text = read_text(path, MAX_SCENE_FILE_BYTES, "scene file")?;
    let name = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("scene")
        .to_owned();
    let ctx = Context {
        scene: &name,
        file: path.to_owned(),
        dir: path.parent(),
        assets,
    };
    parse_and_build(&text, &ctx)
}

/// Loads a scene from TOML text (the built-in scenes); relative mesh paths resolve against
/// `dir` (if any), then `assets`.
///
/// # Errors
/// When the text is malformed or invalid, or a mesh it names is.
pub fn load_scene_str(
    text: &str,
    name: &str,
    dir: Option<&Path>,
    assets: &Path,
) -> Result<Scene, LoadError> {
    let ctx = Context {
        scene: name,
        file: PathBuf::from(format!("{name}.toml")),
        dir,
        assets,
    };
    parse_and_build(text, &ctx)
}

fn parse_and_build(text: &str, ctx: &Context) -> Result<Scene, LoadError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let file: SceneFile = toml::from_str(text).map_err(|e| {
        let position = e.span().map_or(String::new(), |span| {
            let before = text.get(..span.start).unwrap_or(text);
            let line = before.matches('\n').count() + 1;
            let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
            format!("line {line}, column {column}: ")
        });
        let mut message = e.message().trim_end().to_owned();
        // The parser's "duplicate key" names no key: its span is the key.
        if message == "duplicate key"
            && let Some(key) = e.span().and_then(|span| text.get(span))
        {
            let key = key.trim().trim_matches(['"', '\'']);
            message = format!("`{key}` is given twice (a key or a table may appear once)");
        }
        LoadError::Parse {
            path: ctx.file.clone(),
            message: format!("{position}{message}"),
        }
    })?;
    let mut budget = Reservation::new()?;
    let mut b = SceneBuilder::new(file.name.as_deref().unwrap_or(ctx.scene));
    if let Some(bg) = file.background {
        background::add(bg, text, ctx, &mut b, &mut budget)?;
    }
    match file.camera {
        None => {}
        Some(toml::Value::Array(list)) => {
            for (index, value) in list.into_iter().enumerate() {
                let toml::Value::Table(table) = value else {
                    return Err(LoadError::Parse {
                        path: ctx.file.clone(),
                        message: format!("camera {}: expected a table", index + 1),
                    });
                };
                let (c, what): (camera::CameraDesc, _) =
                    table_item(text, "camera", index, table, ctx)?;
                b.add_camera(c.name.as_deref(), c.camera())
                    .map_err(ctx.scene_err(&what))?;
            }
        }
        Some(value) => {
            let c: camera::CameraDesc = value.try_into().map_err(|e| {
                let line = text
                    .lines()
                    .position(|l| l.trim() == "[camera]")
                    .map_or(String::new(), |i| format!("line {}: ", i + 1));
                LoadError::Parse {
                    path: ctx.file.clone(),
                    message: format!("{line}camera: {}", e.message().trim_end()),
                }
            })?;
            b.add_camera(c.name.as_deref(), c.camera())
                .map_err(ctx.scene_err("camera"))?;
        }
    }
    let empty = file.objects.is_empty() && file.volumes.is_empty();
    let mut names: HashMap<String, u32> = HashMap::new();
    for (index, table) in file.materials.into_iter().enumerate() {
        let (m, what): (material::MaterialDesc, _) =
            table_item(text, "material", index, table, ctx)?;
        let id = b.add_material(m.material()).map_err(ctx.scene_err(&what))?;
        if names.insert(m.name.clone(), id).is_some() {
            return Err(LoadError::Parse {
                path: ctx.file.clone(),
                message: format!("{what}: material '{}' is defined twice", m.name),
            });
        }
    }
    for (index, table) in file.lights.into_iter().enumerate() {
        let (l, what): (light::LightDesc, _) = table_item(text, "light", index, table, ctx)?;
        b.add_light(l.light()).map_err(ctx.scene_err(&what))?;
    }
    let mut parts: Parts = Vec::new();
    for (index, mut table) in file.objects.into_iter().enumerate() {
        let mesh = take_instance_keys(&mut table, text, index, ctx)?;
        let deform = motion::take_deform(
            &mut table,
            || {
                header_line(text, "object", index).map_or_else(
                    || format!("object {}", index + 1),
                    |l| format!("line {l}: object {}", index + 1),
                )
            },
            ctx,
        )?;
        let (o, what): (ObjectDesc, _) = table_item(text, "object", index, table, ctx)?;
        let target = match mesh {
            None => &mut b,
            Some(name) => {
                let k = match parts.iter().position(|(n, _, _)| *n == name) {
                    Some(k) => k,
                    None => {
                        parts.push((name, what.clone(), b.part()));
                        parts.len() - 1
                    }
                };
                &mut parts[k].2
            }
        };
        o.add(&mut ObjectCx {
            b: target,
            ctx,
            what: &what,
            budget: &mut budget,
            materials: &names,
        })?;
        if let Some(d) = deform {
            motion::deform(target, d, &what, ctx)?;
        }
    }
    add_instances(
        file.instances,
        file.instance_arrays,
        parts,
        Placing {
            text,
            ctx,
            b: &mut b,
            materials: &names,
            budget: &mut budget,
            meshes: Vec::new(),
        },
    )?;
    for (index, table) in file.volumes.into_iter().enumerate() {
        let (v, what): (volume::VolumeDesc, _) = table_item(text, "volume", index, table, ctx)?;
        let volume = volume::volume(&v, ctx, &what, &mut budget)?;
        b.add_volume(std::sync::Arc::new(volume))
            .map_err(ctx.scene_err(&what))?;
    }
    if empty {
        return Err(LoadError::Parse {
            path: ctx.file.clone(),
            message: "the scene has no [[object]] and no [[volume]]: nothing to render".into(),
        });
    }
    Ok(b.build())
}

/// Loads scene text as the scene `t.toml`, without assets (for the unit tests of every
/// kind's file).
#[cfg(test)]
fn load_test_scene(text: &str) -> Result<Scene, LoadError> {
    load_scene_str(text, "t", None, Path::new("/nonexistent"))
}

/// Checks that [`load_test_scene`] refuses each scene text of `cases` with an error that
/// names the file and contains the case's needle (for the unit tests of every kind's file).
#[cfg(test)]
fn assert_refused(cases: &[(String, &str)]) {
    for (text, needle) in cases {
        let e = load_test_scene(text)
            .err()
            .unwrap_or_else(|| panic!("accepted: {text}"))
            .to_string();
        assert!(e.contains(needle), "{text:?} -> {e}");
        assert!(e.starts_with("t.toml: "), "{e}");
    }
}

#[cfg(test)]
mod tests {
    use super::{assert_refused, load_test_scene as load};
    use raybench_core::MaterialKind;

    #[test]
    fn full_example() {
        let s = load(
            r#"
            name = "demo"
            background = [0, 0, 0]
            [camera]
            position = [0, 1, 5]
            look_at = [0, 0, 0]
            fov = 40
            [[material]]
            name = "red"
            color = [0.8, 0.1, 0.1]
            [[material]]
            name = "glass"
            kind = "glass"
            ior = 1.5
            [[light]]
            kind = "point"
            position = [0, 5, 0]
            intensity = [10, 10, 10]
            [[object]]
            kind = "sphere"
            center = [0, 0, 0]
            radius = 1
            material = "red"
            [[object]]
            kind = "plane"
            point = [0, -1, 0]
            normal = [0, 1, 0]
            [[object]]
            kind = "polygons"
            positions = [[0,0,0],[1,0,0],[1,1,0],[0,1,0]]
            faces = [[0,1,2,3]]
            transform = { scale = 2, translate = [0, 0, 1] }
            [[object]]
            kind = "generator"
            spec = "spheres:3"
            "#,
        )
        .unwrap();
        assert_eq!(s.name, "demo");
        assert_eq!(s.geometry.len(), 1 + 1 + 2 + 3);
        assert_eq!(s.material_of(0).name, "red");
        assert_eq!(s.materials[2].kind, MaterialKind::Glass);
        assert_eq!(s.lights.len(), 1);
    }

    #[test]
    fn errors_name_the_problem() {
        let cases = [
            ("[[object]]\nkind = \"cube\"", "cube"),
            ("[[object]]\nkind = \"sphere\"\ncenter = [0,0,0]", "radius"),
            (
                "[[object]]\nkind = \"sphere\"\ncenter = [0,0,0]\nradius = 1\ncolour = 3",
                "colour",
            ),
            (
                "[[object]]\nkind = \"sphere\"\ncenter = [0,0,0]\nradius = 1\nmaterial = \"x\"",
                "'x'",
            ),
            (
                "[[object]]\nkind = \"sphere\"\ncenter = [nan,0,0]\nradius = 1",
                "not finite",
            ),
            (
                "[[object]]\nkind = \"sphere\"\ncenter = [inf,0,0]\nradius = 1",
                "not finite",
            ),
            (
                "[[object]]\nkind = \"sphere\"\ncenter = [0,0,0]\nradius = 0",
                "radius",
            ),
            ("[camera]\nposition = [0,0,0]\nlook_at = [0,0,0]", "camera"),
            (
                "[[object]]\nkind = \"mesh\"\npath = \"nope.obj\"",
                "nope.obj",
            ),
            (
                "[[object]]\nkind = \"generator\"\nspec = \"soup:0\"",
                "soup:0",
            ),
            (
                "[[object]]\nkind = \"polygons\"\npositions = [[0,0,0]]\nfaces = [[0,1,2]]",
                "out of range",
            ),
            ("[[object]\nkind = ", "TOML"),
            (
                "[[material]]\nname = \"a\"\n[[material]]\nname = \"a\"",
                "twice",
            ),
        ];
        for (text, needle) in cases {
            let e = load(text)
                .err()
                .unwrap_or_else(|| panic!("accepted: {text}"))
                .to_string();
            assert!(
                e.to_lowercase().contains(&needle.to_lowercase()) || needle == "TOML",
                "{text:?} -> {e}"
            );
        }
    }

    /// A `[[camera]]` list of named cameras besides the single `[camera]` table;
    /// the first is rendered, `select_camera` picks another by name or index.
    #[test]
    fn camera_lists() {
        let sphere = "[[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n";
        let one = load(&format!(
            "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n{sphere}"
        ))
        .unwrap();
        assert_eq!(one.cameras.len(), 1);
        assert_eq!(one.cameras[0].name, "camera");
        let mut many = load(&format!(
            "[[camera]]\nname = \"front\"\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\
             [[camera]]\nposition = [5, 0, 0]\nlook_at = [0, 0, 0]\nfov = 30\n\
             [[camera]]\nname = \"top\"\nposition = [0, 5, 0]\nlook_at = [0, 0, 0]\n\
             up = [0, 0, -1]\n{sphere}"
        ))
        .unwrap();
        let names: Vec<&str> = many.cameras.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["front", "camera", "top"]);
        assert_eq!(many.camera.position.z, 5.0);
        let none = raybench_core::CameraOverrides::default();
        many.select_camera(Some("top"), &none).unwrap();
        assert_eq!(many.camera.position.y, 5.0);
        many.select_camera(Some("1"), &none).unwrap();
        assert_eq!(many.camera.vfov_degrees, 30.0);
        let e = many.select_camera(Some("side"), &none).unwrap_err();
        assert!(e.contains("0: 'front', 1: 'camera', 2: 'top'"), "{e}");
        let e = many.select_camera(Some("7"), &none).unwrap_err();
        assert!(e.contains("no camera '7'"), "{e}");
        // Without cameras the framing camera is named `auto`.
        let auto = load(sphere).unwrap();
        assert_eq!(auto.cameras[0].name, "auto");
        // Errors name the entry and its line.
        let e = load(&format!(
            "[[camera]]\nname = \"a\"\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\
             [[camera]]\nname = \"a\"\nposition = [0, 0, 4]\nlook_at = [0, 0, 0]\n{sphere}"
        ))
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("line 5: camera 2: two cameras are named 'a'"),
            "{e}"
        );
        let e = load(&format!(
            "[[camera]]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfovy = 3\n{sphere}"
        ))
        .unwrap_err()
        .to_string();
        assert!(e.contains("line 4: camera 1: unknown field `fovy`"), "{e}");
        let e = load(&format!(
            "\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfovy = 3\n{sphere}"
        ))
        .unwrap_err()
        .to_string();
        assert!(e.contains("line 2: camera: unknown field `fovy`"), "{e}");
    }

    /// A key or table given twice is named, at its second line.
    #[test]
    fn duplicate_keys_are_named() {
        for (text, expected) in [
            (
                "name = \"a\"\nname = \"b\"\n",
                "t.toml: line 2, column 1: `name` is given twice (a key or a table may \
                 appear once)",
            ),
            (
                "[[object]]\nkind = \"sphere\"\nradius = 1\nradius = 2\n",
                "t.toml: line 4, column 1: `radius` is given twice",
            ),
            (
                "[camera]\nfov = 1\n[camera]\nfov = 2\n",
                "t.toml: line 3, column 2: `camera` is given twice",
            ),
        ] {
            let e = load(text).unwrap_err().to_string();
            assert!(e.starts_with(expected), "{e}");
        }
    }

    #[test]
    fn empty_scene_is_refused() {
        for text in [
            "",
            "background = [1, 0, 0]\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]",
        ] {
            let e = load(text).unwrap_err().to_string();
            assert!(e.contains("nothing to render"), "{e}");
        }
    }

    /// An error in the second object names it, its kind and its line, and an
    /// unknown key points at the key's own line.
    #[test]
    fn errors_point_at_the_offending_table_and_key() {
        let text = "[[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n\
                    \n[[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n\
                    colour = 3\n";
        let e = load(text).unwrap_err().to_string();
        assert!(
            e.contains("t.toml: line 10: object 2 (sphere): unknown field `colour`"),
            "{e}"
        );
        let text = "[[object]]\nkind = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 1, 0]\n\
                    [[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\n";
        let e = load(text).unwrap_err().to_string();
        assert!(
            e.contains("line 5: object 2 (sphere): missing field `radius`"),
            "{e}"
        );
        let text = "[[object]]\nkind = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 1, 0]\n\
                    [[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = -1\n";
        let e = load(text).unwrap_err().to_string();
        assert!(
            e.contains("line 5: object 2 (sphere): sphere radius -1"),
            "{e}"
        );
        let text = "[[light]]\nkind = \"point\"\nposition = [0, 0, 0]\nintensity = [1, 1, 1]\n\
                    [[light]]\nkind = \"point\"\nposition = [0, 0, 0]\nintensity = [1, -1, 1]\n\
                    [[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n";
        let e = load(text).unwrap_err().to_string();
        assert!(
            e.contains("line 5: light 2 (point): light intensity"),
            "{e}"
        );
        // Sub-tables of the object and keys of later tables are not mistaken for it.
        let text = "[[object]]\nkind = \"mesh\"\npath = \"a.obj\"\n[object.transform]\n\
                    scael = 2\n";
        let e = load(text).unwrap_err().to_string();
        assert!(e.contains("object 1 (mesh)") && e.contains("scael"), "{e}");
    }

    /// Named `instance_only` objects (one or a group) become meshes stored once,
    /// `[[instance]]` tables place them; ids follow the flat primitives in instance order,
    /// materials come from the mesh or the instance's override.
    #[test]
    fn instances() {
        let s = load(
            "[[material]]\nname = \"red\"\ncolor = [1, 0, 0]\n\
             [[material]]\nname = \"blue\"\ncolor = [0, 0, 1]\n\
             [[object]]\nkind = \"sphere\"\ncenter = [0, 0, -5]\nradius = 1\n\
             [[object]]\nname = \"m\"\ninstance_only = true\nkind = \"generator\"\n\
             spec = \"soup:10\"\nmaterial = \"red\"\n\
             [[object]]\nname = \"m\"\ninstance_only = true\nkind = \"sphere\"\n\
             center = [0, 0, 0]\nradius = 0.5\n\
             [[object]]\nname = \"unused\"\ninstance_only = true\nkind = \"sphere\"\n\
             center = [0, 0, 0]\nradius = 0.5\n\
             [[instance]]\nmesh = \"m\"\n\
             [[instance]]\nmesh = \"m\"\nmaterial = \"blue\"\n\
             transform = { scale = [-1, 2, 1], rotate = [0, 90, 0], translate = [3, 0, 0] }\n",
        )
        .unwrap();
        let g = &s.geometry;
        assert_eq!((g.len(), g.meshes().len(), g.instances().len()), (1, 2, 2));
        assert_eq!(g.meshes()[0].len(), 11);
        assert_eq!(g.total_len(), 1 + 2 * 11);
        assert_eq!(g.instances()[1].base(), 12);
        assert_eq!(s.material_of(0).name, "default");
        assert_eq!(s.material_of(1).name, "red");
        assert_eq!(s.material_of(11).name, "default", "the group's sphere");
        assert_eq!(s.material_of(12).name, "blue");
        assert_eq!(s.material_of(22).name, "blue");
        let names: Vec<&str> = s.objects.iter().map(|o| o.name.as_str()).collect();
        assert_eq!(names, ["sphere", "instance of m", "instance of m"]);
        assert!(
            s.warnings
                .iter()
                .any(|w| w.contains("'unused' is placed by no [[instance]]")),
            "{:?}",
            s.warnings
        );
    }

    /// Every bad instance is one error naming the table, its line and the cause.
    #[test]
    fn instance_errors_name_the_problem() {
        let mesh = "[[object]]\nname = \"m\"\ninstance_only = true\nkind = \"sphere\"\n\
                    center = [0, 0, 0]\nradius = 1\n";
        let cases = [
            (
                format!("{mesh}[[instance]]\nmesh = \"n\"\n"),
                "line 7: instance 1: mesh 'n' is not defined",
            ),
            (
                format!("{mesh}[[instance]]\nmesh = \"m\"\ntransform = {{ scale = [1, 0, 1] }}\n"),
                "line 7: instance 1: instance transform is singular",
            ),
            (
                format!(
                    "{mesh}[[instance]]\nmesh = \"m\"\n\
                     transform = {{ translate = [nan, 0, 0] }}\n"
                ),
                "instance transform is not finite",
            ),
            (
                format!("{mesh}[[instance]]\nmesh = \"m\"\nmaterial = \"x\"\n"),
                "line 7: instance 1: material 'x' is not defined",
            ),
            (
                format!("{mesh}[[instance]]\nmesh = \"m\"\nscale = 2\n"),
                "line 9: instance 1: unknown field `scale`",
            ),
            (
                format!(
                    "[[material]]\nname = \"lamp\"\nemission = [1, 1, 1]\n{mesh}\
                     [[instance]]\nmesh = \"m\"\nmaterial = \"lamp\"\n"
                ),
                "emits light",
            ),
            (
                "[[object]]\nname = \"m\"\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n"
                    .into(),
                "line 1: object 1: `name` names an instance mesh and needs `instance_only = true`",
            ),
            (
                "[[object]]\ninstance_only = true\nkind = \"sphere\"\ncenter = [0, 0, 0]\n\
                 radius = 1\n"
                    .into(),
                "`instance_only` needs a `name`",
            ),
            (
                "[[object]]\nname = \"p\"\ninstance_only = true\nkind = \"plane\"\n\
                 point = [0, 0, 0]\nnormal = [0, 1, 0]\n[[instance]]\nmesh = \"p\"\n"
                    .into(),
                "line 1: object 1 (plane): instance mesh 'p' holds a plane",
            ),
            (
                "[[object]]\nname = 3\ninstance_only = true\nkind = \"sphere\"\n\
                 center = [0, 0, 0]\nradius = 1\n"
                    .into(),
                "`name` must be a string",
            ),
        ];
        assert_refused(&cases);
    }
}
