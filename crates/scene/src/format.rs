//! The TOML scene format (documented in `docs/scene-format.md`).

use crate::bpt::load_bpt_file;
use crate::budget::{Holds, Reservation};
use crate::error::LoadError;
use crate::generators::{self, Generated};
use crate::gltf_loader::load_gltf_file;
use crate::grids::{SampleFormat, read_png_gray, read_raw};
use crate::obj::{MeshData, load_obj_file};
use crate::transform::Transform;
use crate::volumes;
use raybench_core::voxels::{MAX_VOLUME_VOXELS, check_volume_dims};
use raybench_core::{
    BezierPatch, Camera, CellSurface, Csg, CsgNode, CsgOp, HeightField, HeightFieldTraversal,
    Light, MAX_HEIGHT_FIELD_VERTICES, Material, MaterialKind, PolygonMesh, Scene, SceneBuilder,
    SceneError, Solid, Sphere, Triangle, TriangleMesh, Vec3,
};
use raybench_core::{Sampling, TransferFunction, TransferPoint, Volume, VolumeData, VolumeParams};
use serde::Deserialize;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Scene files larger than this are refused before reading (meshes belong in mesh files).
const MAX_SCENE_FILE_BYTES: u64 = 64 << 20;

type V3 = [f32; 3];

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    background: Option<V3>,
    camera: Option<CameraDesc>,
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

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum SamplingDesc {
    Nearest,
    Trilinear,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TransferDesc {
    value: f32,
    color: V3,
    sigma: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct VolumeDesc {
    /// `phantom:N`.
    source: Option<String>,
    /// A raw file of `dims` little-endian samples, x fastest.
    raw: Option<String>,
    dims: Option<[u32; 3]>,
    format: Option<SampleFormat>,
    /// Object units per voxel along x, y, z.
    spacing: Option<ScaleDesc>,
    sampling: Option<SamplingDesc>,
    skip_empty: Option<bool>,
    window: Option<[f32; 2]>,
    transfer: Option<Vec<TransferDesc>>,
    #[serde(default)]
    transform: TransformDesc,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraDesc {
    position: V3,
    look_at: V3,
    up: Option<V3>,
    fov: Option<f32>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum KindDesc {
    Diffuse,
    Mirror,
    Glass,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialDesc {
    name: String,
    kind: Option<KindDesc>,
    color: Option<V3>,
    specular: Option<V3>,
    shininess: Option<f32>,
    emission: Option<V3>,
    ior: Option<f32>,
    checker: Option<CheckerDesc>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CheckerDesc {
    color: V3,
    size: f32,
}

#[derive(Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
enum LightDesc {
    Point(PointLightDesc),
    Directional(DirectionalLightDesc),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PointLightDesc {
    position: V3,
    intensity: V3,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DirectionalLightDesc {
    direction: V3,
    radiance: V3,
}

#[derive(Deserialize)]
#[serde(untagged)]
pub(crate) enum ScaleDesc {
    Uniform(f32),
    PerAxis(V3),
}

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

#[derive(Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
enum ObjectDesc {
    Sphere(SphereDesc),
    Plane(PlaneDesc),
    Triangle(TriangleDesc),
    Polygons(PolygonsDesc),
    Mesh(MeshDesc),
    Generator(GeneratorDesc),
    HeightField(HeightFieldDesc),
    Csg(CsgDesc),
    // Issue 10, analytic solids as objects: each is a one-leaf CSG primitive.
    Torus(TorusDesc),
    Ellipsoid(EllipsoidDesc),
    Cylinder(RevolvedDesc),
    Cone(RevolvedDesc),
    Paraboloid(RevolvedDesc),
    Bezier(BezierDesc),
    Sdf(crate::sdf_format::SdfDesc),
}

/// Bicubic Bezier patches from a `.bpt` file, intersected directly or tessellated.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BezierDesc {
    file: String,
    material: Option<String>,
    #[serde(default)]
    transform: TransformDesc,
    /// `N`: `N x N` quads (two triangles each) per patch instead of the direct patches.
    tessellate: Option<u32>,
}

/// Largest accepted `tessellate = N` (`2 N^2` triangles per patch).
const MAX_TESSELLATE: u32 = 1024;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CsgDesc {
    tree: CsgNodeDesc,
    material: Option<String>,
}

/// A node of a CSG tree: an operator with its operands, or a solid.
#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
enum CsgNodeDesc {
    Union {
        operands: Vec<CsgNodeDesc>,
    },
    Intersection {
        operands: Vec<CsgNodeDesc>,
    },
    Difference {
        operands: Vec<CsgNodeDesc>,
    },
    Sphere {
        center: V3,
        radius: f32,
        transform: Option<TransformDesc>,
    },
    Box {
        min: V3,
        max: V3,
        transform: Option<TransformDesc>,
    },
    Cylinder(RevolvedDesc),
    Cone(RevolvedDesc),
    HalfSpace {
        point: V3,
        normal: V3,
        transform: Option<TransformDesc>,
    },
    // Issue 10, tori and quadrics.
    Torus(TorusDesc),
    Ellipsoid(EllipsoidDesc),
    Paraboloid(RevolvedDesc),
}

/// A torus about its local y axis, as a CSG operand or (with a material) an object.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TorusDesc {
    center: V3,
    major_radius: f32,
    minor_radius: f32,
    material: Option<String>,
    transform: Option<TransformDesc>,
}

/// An axis-aligned ellipsoid (before its transform), as a CSG operand or an object.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EllipsoidDesc {
    center: V3,
    radii: V3,
    material: Option<String>,
    transform: Option<TransformDesc>,
}

/// A capped cylinder, cone or paraboloid standing on its local y axis, as a CSG operand
/// or an object.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RevolvedDesc {
    base: V3,
    radius: f32,
    height: f32,
    material: Option<String>,
    transform: Option<TransformDesc>,
}

impl RevolvedDesc {
    /// The solid this describes as a cylinder, a cone or a paraboloid (`kind`).
    fn solid(&self, kind: &str) -> Solid {
        let (base, radius, height) = (Vec3::from(self.base), self.radius, self.height);
        match kind {
            "cylinder" => Solid::Cylinder {
                base,
                radius,
                height,
            },
            "cone" => Solid::Cone {
                base,
                radius,
                height,
            },
            _ => Solid::Paraboloid {
                base,
                radius,
                height,
            },
        }
    }
}

/// A solid, placed when it has a transform other than the identity (an identity keeps
/// the unplaced fast path).
fn placed(solid: Solid, transform: Option<&TransformDesc>) -> CsgNode {
    match transform.map(TransformDesc::to_transform) {
        Some(xf) if !xf.is_identity() => CsgNode::Placed(solid, xf.affine()),
        _ => CsgNode::Leaf(solid),
    }
}

/// A CSG operand's solid: refused when it names a material (the tree's applies).
fn operand(
    solid: Solid,
    transform: Option<&TransformDesc>,
    material: Option<&String>,
) -> Result<CsgNode, SceneError> {
    if let Some(m) = material {
        return Err(SceneError::Invalid(format!(
            "a CSG operand cannot have its own material ('{m}'): the tree's `material` applies"
        )));
    }
    Ok(placed(solid, transform))
}

/// Adds a standalone analytic solid: a one-leaf CSG primitive named `name`.
fn add_solid(
    b: &mut SceneBuilder,
    name: &str,
    solid: Solid,
    transform: Option<&TransformDesc>,
    material: u32,
) -> Result<(), SceneError> {
    let csg = Csg::new(&placed(solid, transform))?;
    b.add_csg(name, Arc::new(csg), material)?;
    Ok(())
}

impl TorusDesc {
    fn solid(&self) -> Solid {
        Solid::Torus {
            center: Vec3::from(self.center),
            major_radius: self.major_radius,
            minor_radius: self.minor_radius,
        }
    }
}

impl EllipsoidDesc {
    fn solid(&self) -> Solid {
        Solid::Ellipsoid {
            center: Vec3::from(self.center),
            radii: Vec3::from(self.radii),
        }
    }
}

/// Converts a scene file's tree into the core's, checking the depth before recursing
/// further (operators are folded into balanced binary trees).
fn csg_node(d: &CsgNodeDesc, depth: usize) -> Result<CsgNode, SceneError> {
    use raybench_core::limits::MAX_CSG_DEPTH;
    if depth > MAX_CSG_DEPTH {
        return Err(SceneError::TooLarge(format!(
            "the CSG tree is deeper than {MAX_CSG_DEPTH} levels"
        )));
    }
    let fold = |op: CsgOp, operands: &[CsgNodeDesc]| -> Result<CsgNode, SceneError> {
        let nodes = operands
            .iter()
            .map(|o| csg_node(o, depth + 1))
            .collect::<Result<Vec<_>, _>>()?;
        CsgNode::fold(op, nodes)
    };
    Ok(match d {
        CsgNodeDesc::Union { operands } => fold(CsgOp::Union, operands)?,
        CsgNodeDesc::Intersection { operands } => fold(CsgOp::Intersection, operands)?,
        CsgNodeDesc::Difference { operands } => fold(CsgOp::Difference, operands)?,
        CsgNodeDesc::Sphere {
            center,
            radius,
            transform,
        } => placed(
            Solid::Sphere {
                center: Vec3::from(*center),
                radius: *radius,
            },
            transform.as_ref(),
        ),
        CsgNodeDesc::Box {
            min,
            max,
            transform,
        } => placed(
            Solid::Box {
                min: Vec3::from(*min),
                max: Vec3::from(*max),
            },
            transform.as_ref(),
        ),
        CsgNodeDesc::HalfSpace {
            point,
            normal,
            transform,
        } => placed(
            Solid::HalfSpace {
                point: Vec3::from(*point),
                normal: Vec3::from(*normal),
            },
            transform.as_ref(),
        ),
        CsgNodeDesc::Cylinder(r) => operand(
            r.solid("cylinder"),
            r.transform.as_ref(),
            r.material.as_ref(),
        )?,
        CsgNodeDesc::Cone(r) => {
            operand(r.solid("cone"), r.transform.as_ref(), r.material.as_ref())?
        }
        CsgNodeDesc::Paraboloid(r) => operand(
            r.solid("paraboloid"),
            r.transform.as_ref(),
            r.material.as_ref(),
        )?,
        CsgNodeDesc::Torus(t) => operand(t.solid(), t.transform.as_ref(), t.material.as_ref())?,
        CsgNodeDesc::Ellipsoid(e) => operand(e.solid(), e.transform.as_ref(), e.material.as_ref())?,
    })
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SphereDesc {
    center: V3,
    radius: f32,
    material: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlaneDesc {
    point: V3,
    normal: V3,
    material: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TriangleDesc {
    vertices: [V3; 3],
    material: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PolygonsDesc {
    positions: Vec<V3>,
    faces: Vec<Vec<u32>>,
    material: Option<String>,
    #[serde(default)]
    transform: TransformDesc,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshDesc {
    path: String,
    material: Option<String>,
    #[serde(default)]
    transform: TransformDesc,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GeneratorDesc {
    spec: String,
    seed: Option<u32>,
    material: Option<String>,
    #[serde(default)]
    transform: TransformDesc,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum TraversalDesc {
    Tree,
    Dda,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum CellsDesc {
    Triangles,
    Bilinear,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HeightFieldDesc {
    /// `terrain:N`: the heights of the terrain generator.
    source: Option<String>,
    /// An 8- or 16-bit greyscale PNG: one vertex per pixel, heights in [0, 1].
    png: Option<String>,
    /// A raw file of `size[0] x size[1]` little-endian samples.
    raw: Option<String>,
    /// Vertices per row and rows (raw files).
    size: Option<[u32; 2]>,
    /// Sample type of the raw file (default u16).
    format: Option<SampleFormat>,
    /// Vertex heights inline, row by row.
    heights: Option<Vec<Vec<f32>>>,
    traversal: Option<TraversalDesc>,
    cells: Option<CellsDesc>,
    smooth: Option<bool>,
    material: Option<String>,
    #[serde(default)]
    transform: TransformDesc,
}

/// Where relative paths of a scene are looked up.
struct Context<'a> {
    scene: &'a str,
    file: PathBuf,
    dir: Option<&'a Path>,
    assets: &'a Path,
}

impl Context<'_> {
    fn resolve(&self, rel: &str) -> Result<PathBuf, LoadError> {
        let p = Path::new(rel);
        if p.is_absolute() {
            return if p.is_file() {
                Ok(p.to_owned())
            } else {
                Err(self.missing(p.to_owned()))
            };
        }
        if let Some(dir) = self.dir {
            let candidate = dir.join(p);
            if candidate.is_file() {
                return Ok(candidate);
            }
        }
        let candidate = self.assets.join(p);
        if candidate.is_file() {
            Ok(candidate)
        } else {
            Err(self.missing(candidate))
        }
    }

    fn missing(&self, path: PathBuf) -> LoadError {
        LoadError::MissingAsset {
            scene: self.scene.to_owned(),
            path,
        }
    }

    fn scene_err(&self, what: &str) -> impl Fn(SceneError) -> LoadError + '_ {
        let context = format!("{}: {what}", self.file.display());
        move |cause| LoadError::Scene {
            context: context.clone(),
            cause,
        }
    }
}

/// Reads a UTF-8 text file of at most `limit` bytes (checked before reading; `what` names
/// the kind of file in the error).
pub(crate) fn read_text(path: &Path, limit: u64, what: &str) -> Result<String, LoadError> {
    let io = |cause| LoadError::Io {
        path: path.to_owned(),
        cause,
    };
    // A device or pipe reports no length and may never end.
    crate::check_regular_file(path)?;
    let len = std::fs::metadata(path).map_err(io)?.len();
    if len > limit {
        return Err(LoadError::Parse {
            path: path.to_owned(),
            message: format!("{what} of {len} bytes exceeds the limit of {limit}"),
        });
    }
    // At most `limit + 1` bytes, should the file grow meanwhile.
    let mut bytes = Vec::new();
    std::io::Read::read_to_end(
        &mut std::io::Read::take(std::fs::File::open(path).map_err(io)?, limit + 1),
        &mut bytes,
    )
    .map_err(io)?;
    if bytes.len() as u64 > limit {
        return Err(LoadError::Parse {
            path: path.to_owned(),
            message: format!("{what} exceeds the limit of {limit} bytes"),
        });
    }
    if bytes.starts_with(crate::UTF8_BOM) {
        bytes.drain(..crate::UTF8_BOM.len());
    }
    String::from_utf8(bytes).map_err(|_| LoadError::Parse {
        path: path.to_owned(),
        message: "not UTF-8 text".into(),
    })
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

fn load_mesh_file(path: &Path) -> Result<MeshData, LoadError> {
    let data = load_mesh_file_any(path)?;
    if data.mesh.indices.is_empty() {
        return Err(LoadError::Parse {
            path: path.to_owned(),
            message: "no triangles found (is this a mesh file?)".into(),
        });
    }
    Ok(data)
}

fn load_mesh_file_any(path: &Path) -> Result<MeshData, LoadError> {
    match crate::extension(path).as_str() {
        "obj" => load_obj_file(path),
        "gltf" | "glb" => load_gltf_file(path),
        _ => Err(LoadError::Parse {
            path: path.to_owned(),
            message: "unknown mesh file type (expected .obj, .gltf or .glb)".into(),
        }),
    }
}

/// A scene of one mesh file with a light, a grey-blue background and a camera framing it.
pub(crate) fn bare_mesh_scene(path: &Path) -> Result<Scene, LoadError> {
    let data = load_mesh_file(path)?;
    Reservation::new()?.reserve(
        Holds::Primitives(data.mesh.indices.len() as u64),
        &path.display().to_string(),
    )?;
    let name = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("mesh")
        .to_owned();
    let scene_err = |cause| LoadError::Scene {
        context: path.display().to_string(),
        cause,
    };
    let mut b = SceneBuilder::new(&name);
    b.background(Vec3::new(0.55, 0.65, 0.8))
        .map_err(scene_err)?;
    b.add_light(Light::Directional {
        direction: Vec3::new(-0.4, -1.0, -0.6),
        radiance: Vec3::ONE,
    })
    .map_err(scene_err)?;
    add_mesh_data(&mut b, &name, data, None).map_err(scene_err)?;
    Ok(b.build())
}

/// Adds a loaded mesh: its own materials (unless `override_material`), its triangles as one
/// object.
fn add_mesh_data(
    b: &mut SceneBuilder,
    name: &str,
    data: MeshData,
    override_material: Option<u32>,
) -> Result<(), SceneError> {
    let materials: Vec<u32> = match override_material {
        Some(m) => vec![m; data.mesh.indices.len()],
        None => {
            let mut ids = Vec::with_capacity(data.materials.len());
            for m in data.materials {
                ids.push(b.add_material(m)?);
            }
            data.triangle_material
                .iter()
                .map(|m| m.map_or(0, |i| ids[i as usize]))
                .collect()
        }
    };
    for w in data.warnings {
        b.warn(w);
    }
    data.mesh.validate()?;
    let triangles: Vec<Triangle> = data.mesh.triangles().collect();
    b.add_triangles(name, &triangles, &materials)?;
    Ok(())
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
        LoadError::Parse {
            path: ctx.file.clone(),
            message: format!("{position}{}", e.message()),
        }
    })?;
    let mut budget = Reservation::new()?;
    let mut b = SceneBuilder::new(file.name.as_deref().unwrap_or(ctx.scene));
    if let Some(bg) = file.background {
        b.background(Vec3::from(bg))
            .map_err(ctx.scene_err("background"))?;
    }
    if let Some(c) = &file.camera {
        b.camera(Camera {
            position: Vec3::from(c.position),
            look_at: Vec3::from(c.look_at),
            up: c.up.map_or(Vec3::Y, Vec3::from),
            vfov_degrees: c.fov.unwrap_or(45.0),
        })
        .map_err(ctx.scene_err("camera"))?;
    }
    let empty = file.objects.is_empty() && file.volumes.is_empty();
    let mut names: HashMap<String, u32> = HashMap::new();
    for (index, table) in file.materials.into_iter().enumerate() {
        let (m, what): (MaterialDesc, _) = table_item(text, "material", index, table, ctx)?;
        let d = Material::default();
        let kind = match m.kind.unwrap_or(KindDesc::Diffuse) {
            KindDesc::Diffuse => MaterialKind::Diffuse,
            KindDesc::Mirror => MaterialKind::Mirror,
            KindDesc::Glass => MaterialKind::Glass,
        };
        let id = b
            .add_material(Material {
                name: m.name.clone(),
                kind,
                base_color: m.color.map_or(d.base_color, Vec3::from),
                specular: m.specular.map_or(
                    if kind == MaterialKind::Diffuse {
                        d.specular
                    } else {
                        Vec3::ONE
                    },
                    Vec3::from,
                ),
                shininess: m.shininess.unwrap_or(d.shininess),
                emission: m.emission.map_or(d.emission, Vec3::from),
                ior: m.ior.unwrap_or(d.ior),
                checker: m.checker.as_ref().map(|c| raybench_core::Checker {
                    color: Vec3::from(c.color),
                    size: c.size,
                }),
            })
            .map_err(ctx.scene_err(&what))?;
        if names.insert(m.name.clone(), id).is_some() {
            return Err(LoadError::Parse {
                path: ctx.file.clone(),
                message: format!("{what}: material '{}' is defined twice", m.name),
            });
        }
    }
    for (index, table) in file.lights.into_iter().enumerate() {
        let (l, what): (LightDesc, _) = table_item(text, "light", index, table, ctx)?;
        let light = match l {
            LightDesc::Point(p) => Light::Point {
                position: Vec3::from(p.position),
                intensity: Vec3::from(p.intensity),
            },
            LightDesc::Directional(d) => Light::Directional {
                direction: Vec3::from(d.direction),
                radiance: Vec3::from(d.radiance),
            },
        };
        b.add_light(light).map_err(ctx.scene_err(&what))?;
    }
    for (index, table) in file.objects.into_iter().enumerate() {
        let (o, what): (ObjectDesc, _) = table_item(text, "object", index, table, ctx)?;
        let err = ctx.scene_err(&what);
        let material = |name: &Option<String>| -> Result<Option<u32>, LoadError> {
            match name {
                None => Ok(None),
                Some(n) => names
                    .get(n)
                    .copied()
                    .map(Some)
                    .ok_or_else(|| LoadError::Parse {
                        path: ctx.file.clone(),
                        message: format!("{what}: material '{n}' is not defined"),
                    }),
            }
        };
        match &o {
            ObjectDesc::Sphere(s) => {
                let m = material(&s.material)?.unwrap_or(0);
                b.add_sphere(Sphere::new(Vec3::from(s.center), s.radius), m)
                    .map_err(err)?;
            }
            ObjectDesc::Plane(p) => {
                let m = material(&p.material)?.unwrap_or(0);
                b.add_plane(Vec3::from(p.point), Vec3::from(p.normal), m)
                    .map_err(err)?;
            }
            ObjectDesc::Triangle(t) => {
                let m = material(&t.material)?.unwrap_or(0);
                let tri = Triangle::new(
                    t.vertices[0].into(),
                    t.vertices[1].into(),
                    t.vertices[2].into(),
                );
                b.add_triangles("triangle", &[tri], &[m]).map_err(err)?;
            }
            ObjectDesc::Polygons(p) => {
                let m = material(&p.material)?.unwrap_or(0);
                let poly = PolygonMesh {
                    positions: p.positions.iter().map(|&v| Vec3::from(v)).collect(),
                    faces: p.faces.clone(),
                };
                let triangulated = poly.triangulate().map_err(&err)?;
                if !triangulated.self_intersecting.is_empty() {
                    b.warn(format!(
                        "{}: {what}: {}",
                        ctx.file.display(),
                        crate::obj::self_intersecting(&triangulated.self_intersecting)
                    ));
                }
                let mut mesh = triangulated.mesh;
                let xf = p.transform.checked().map_err(&err)?;
                if !xf.is_identity() {
                    let a = xf.affine();
                    mesh.transform(|v| a.transform_point3(v));
                }
                b.add_mesh("polygons", &mesh, m).map_err(err)?;
            }
            ObjectDesc::Mesh(md) => {
                let xf = md.transform.checked().map_err(&err)?;
                let path = ctx.resolve(&md.path)?;
                let mut data = load_mesh_file(&path)?;
                budget.reserve(
                    Holds::Primitives(data.mesh.indices.len() as u64),
                    &format!("{}: {what}: {}", ctx.file.display(), path.display()),
                )?;
                if !xf.is_identity() {
                    let a = xf.affine();
                    data.mesh.transform(|v| a.transform_point3(v));
                }
                let m = material(&md.material)?;
                add_mesh_data(&mut b, &md.path, data, m).map_err(err)?;
            }
            ObjectDesc::Generator(g) => {
                // Refuse before generating: a one-line spec can ask for 2e7 primitives.
                let (info, n) = generators::parse_spec(&g.spec)?;
                let count = generators::primitive_count(&info, n);
                let limit = raybench_core::limits::MAX_PRIMITIVES as u64;
                if b.primitive_count() as u64 + count > limit {
                    return Err(LoadError::Scene {
                        context: format!("{}: {what}", ctx.file.display()),
                        cause: SceneError::TooLarge(format!(
                            "generator '{}' would take the scene past {limit} primitives",
                            g.spec
                        )),
                    });
                }
                let xf = g.transform.checked().map_err(&err)?;
                budget.reserve(
                    generators::holds(&info, n),
                    &format!("{}: {what}", ctx.file.display()),
                )?;
                let generated =
                    generators::generate(&g.spec, g.seed.unwrap_or(generators::DEFAULT_SEED))?;
                let m = material(&g.material)?.unwrap_or(0);
                let a = xf.affine();
                match generated {
                    Generated::Mesh(mut mesh) => {
                        if !xf.is_identity() {
                            mesh.transform(|v| a.transform_point3(v));
                        }
                        b.add_mesh(g.spec.as_str(), &mesh, m).map_err(err)?;
                    }
                    Generated::Spheres(spheres) => {
                        let s_max = xf.scale.abs().max_element();
                        for s in spheres {
                            let s = Sphere::new(a.transform_point3(s.center), s.radius * s_max);
                            b.add_sphere(s, m).map_err(&err)?;
                        }
                    }
                    Generated::HeightField { n, heights } => {
                        // The placement as the tessellated terrain applies it: none for
                        // the identity, else `transform_point3` on every vertex.
                        let field =
                            HeightField::new(n, n, heights, (!xf.is_identity()).then_some(a))
                                .map_err(&err)?;
                        b.add_height_field(g.spec.as_str(), Arc::new(field), m)
                            .map_err(err)?;
                    }
                }
            }
            ObjectDesc::HeightField(h) => {
                let m = material(&h.material)?.unwrap_or(0);
                let field = height_field(h, ctx, &what, &mut budget)?;
                b.add_height_field("height field", Arc::new(field), m)
                    .map_err(err)?;
            }
            ObjectDesc::Csg(c) => {
                let m = material(&c.material)?.unwrap_or(0);
                let tree = csg_node(&c.tree, 1).map_err(&err)?;
                let csg = Csg::new(&tree).map_err(&err)?;
                b.add_csg("csg", Arc::new(csg), m).map_err(err)?;
            }
            ObjectDesc::Torus(t) => {
                let m = material(&t.material)?.unwrap_or(0);
                add_solid(&mut b, "torus", t.solid(), t.transform.as_ref(), m).map_err(err)?;
            }
            ObjectDesc::Ellipsoid(e) => {
                let m = material(&e.material)?.unwrap_or(0);
                add_solid(&mut b, "ellipsoid", e.solid(), e.transform.as_ref(), m).map_err(err)?;
            }
            ObjectDesc::Cylinder(r) | ObjectDesc::Cone(r) | ObjectDesc::Paraboloid(r) => {
                let name = match o {
                    ObjectDesc::Cylinder(_) => "cylinder",
                    ObjectDesc::Cone(_) => "cone",
                    _ => "paraboloid",
                };
                let m = material(&r.material)?.unwrap_or(0);
                add_solid(&mut b, name, r.solid(name), r.transform.as_ref(), m).map_err(err)?;
            }
            ObjectDesc::Bezier(bd) => {
                let m = material(&bd.material)?.unwrap_or(0);
                bezier(&mut b, bd, ctx, &what, m, &mut budget)?;
            }
            ObjectDesc::Sdf(d) => {
                let m = material(&d.material)?.unwrap_or(0);
                let model = d.build().map_err(&err)?;
                b.add_sdf("sdf", Arc::new(model), m).map_err(err)?;
            }
        }
    }
    for (index, table) in file.volumes.into_iter().enumerate() {
        let (v, what): (VolumeDesc, _) = table_item(text, "volume", index, table, ctx)?;
        let volume = volume(&v, ctx, &what, &mut budget)?;
        b.add_volume(Arc::new(volume))
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

/// Adds the patches of a `kind = "bezier"` object: one primitive per patch, or with
/// `tessellate = N` one mesh of `2 N^2` triangles per patch.
fn bezier(
    b: &mut SceneBuilder,
    d: &BezierDesc,
    ctx: &Context,
    what: &str,
    material: u32,
    budget: &mut Reservation,
) -> Result<(), LoadError> {
    let path = ctx.resolve(&d.file)?;
    let patches = load_bpt_file(&path)?;
    let scene_err = |context: String| {
        move |cause| LoadError::Scene {
            context: format!("{}: {what}: {context}", ctx.file.display()),
            cause,
        }
    };
    if let Some(n) = d.tessellate
        && !(1..=MAX_TESSELLATE).contains(&n)
    {
        return Err(scene_err(d.file.clone())(SceneError::Invalid(format!(
            "tessellate = {n}: between 1 and {MAX_TESSELLATE} quads per patch side are accepted"
        ))));
    }
    let a = d
        .transform
        .checked()
        .map_err(scene_err(d.file.clone()))?
        .affine();
    let primitives = match d.tessellate {
        None => patches.len() as u64,
        Some(n) => 2 * u64::from(n) * u64::from(n) * patches.len() as u64,
    };
    budget.reserve(
        Holds::Primitives(primitives),
        &format!("{}: {what}: {}", ctx.file.display(), d.file),
    )?;
    let mut built = Vec::with_capacity(patches.len());
    for p in &patches {
        let patch = BezierPatch::new(p.points.map(|q| a.transform_point3(q)))
            .map_err(scene_err(format!("{} line {}", d.file, p.line)))?;
        built.push(Arc::new(patch));
    }
    match d.tessellate {
        None => b
            .add_bezier_patches(d.file.as_str(), built, material)
            .map_err(scene_err(d.file.clone()))?,
        Some(n) => {
            let triangles = 2 * u64::from(n) * u64::from(n) * built.len() as u64;
            let limit = raybench_core::limits::MAX_PRIMITIVES as u64;
            if b.primitive_count() as u64 + triangles > limit {
                return Err(scene_err(d.file.clone())(SceneError::TooLarge(format!(
                    "tessellate = {n} would take the scene past {limit} primitives"
                ))));
            }
            let mut mesh = TriangleMesh::default();
            for p in &built {
                let part = p.tessellate(n);
                let base = mesh.positions.len() as u32;
                mesh.positions.extend(part.positions);
                mesh.indices
                    .extend(part.indices.iter().map(|t| t.map(|i| i + base)));
            }
            b.add_mesh(d.file.as_str(), &mesh, material)
                .map_err(scene_err(d.file.clone()))?
        }
    };
    Ok(())
}

/// Builds the volume a `[[volume]]` table describes.
fn volume(
    v: &VolumeDesc,
    ctx: &Context,
    what: &str,
    budget: &mut Reservation,
) -> Result<Volume, LoadError> {
    let context = format!("{}: {what}", ctx.file.display());
    let parse = |message: String| LoadError::Parse {
        path: ctx.file.clone(),
        message: format!("{what}: {message}"),
    };
    let scene_err = |cause| LoadError::Scene {
        context: format!("{}: {what}", ctx.file.display()),
        cause,
    };
    let (dims, data, default_spacing) = match (&v.source, &v.raw) {
        (Some(spec), None) => {
            if v.dims.is_some() || v.format.is_some() {
                return Err(parse("dims and format belong to raw volumes".into()));
            }
            let n = volumes::parse_volume_spec(spec)?;
            budget.reserve(Holds::Voxels(u64::from(n).pow(3)), &context)?;
            let data = volumes::rasterize(&volumes::shepp_logan_ellipsoids(), n);
            // Generated volumes span [-1, 1]^3.
            ([n; 3], VolumeData::F32(data), Vec3::splat(2.0 / n as f32))
        }
        (None, Some(raw)) => {
            let dims = v
                .dims
                .ok_or_else(|| parse("a raw volume needs dims = [x, y, z]".into()))?;
            let count = check_volume_dims(dims).map_err(scene_err)?;
            budget.reserve(Holds::Voxels(count), &context)?;
            let samples = read_raw(
                &ctx.resolve(raw)?,
                count,
                v.format.unwrap_or(SampleFormat::U16),
                MAX_VOLUME_VOXELS,
            )?;
            (dims, VolumeData::from(samples), Vec3::ONE)
        }
        _ => {
            return Err(parse("a volume needs exactly one of source and raw".into()));
        }
    };
    let spacing = match v.spacing {
        None => default_spacing,
        Some(ScaleDesc::Uniform(s)) => Vec3::splat(s),
        Some(ScaleDesc::PerAxis(s)) => Vec3::from(s),
    };
    let transfer = match &v.transfer {
        None => TransferFunction::ramp(10.0),
        Some(points) => TransferFunction::new(
            points
                .iter()
                .map(|p| TransferPoint {
                    value: p.value,
                    color: Vec3::from(p.color),
                    sigma: p.sigma,
                })
                .collect(),
        )
        .map_err(scene_err)?,
    };
    let defaults = VolumeParams::default();
    let params = VolumeParams {
        sampling: match v.sampling.unwrap_or(SamplingDesc::Nearest) {
            SamplingDesc::Nearest => Sampling::Nearest,
            SamplingDesc::Trilinear => Sampling::Trilinear,
        },
        skip_empty: v.skip_empty.unwrap_or(defaults.skip_empty),
        window: v.window.unwrap_or(defaults.window),
    };
    Volume::new(
        dims,
        spacing,
        data,
        v.transform.checked().map_err(scene_err)?.affine(),
        transfer,
        params,
    )
    .map_err(scene_err)
}

/// Builds the height field an object describes, from exactly one source.
fn height_field(
    h: &HeightFieldDesc,
    ctx: &Context,
    what: &str,
    budget: &mut Reservation,
) -> Result<HeightField, LoadError> {
    let context = format!("{}: {what}", ctx.file.display());
    let parse = |message: String| LoadError::Parse {
        path: ctx.file.clone(),
        message: format!("{what}: {message}"),
    };
    let sources = [
        h.source.is_some(),
        h.png.is_some(),
        h.raw.is_some(),
        h.heights.is_some(),
    ];
    if sources.iter().filter(|&&s| s).count() != 1 {
        return Err(parse(
            "a height field needs exactly one of source, png, raw and heights".into(),
        ));
    }
    if h.raw.is_none() && (h.size.is_some() || h.format.is_some()) {
        return Err(parse("size and format belong to raw height fields".into()));
    }
    let (cols, rows, heights) = if let Some(spec) = &h.source {
        let (info, n) = generators::parse_spec(spec)?;
        if info.name != "terrain" {
            return Err(parse(format!(
                "source '{spec}' is not a height generator (expected terrain:N)"
            )));
        }
        budget.reserve(Holds::Vertices((n + 1) * (n + 1)), &context)?;
        let n = n as u32;
        (n + 1, n + 1, generators::terrain_heights(n))
    } else if let Some(png) = &h.png {
        // The header's size is checked against the vertex limit before decoding; the
        // budget counts the decoded heights.
        let (cols, rows, heights) = read_png_gray(&ctx.resolve(png)?, MAX_HEIGHT_FIELD_VERTICES)?;
        budget.reserve(Holds::Vertices(heights.len() as u64), &context)?;
        (cols, rows, heights)
    } else if let Some(raw) = &h.raw {
        let [cols, rows] = h
            .size
            .ok_or_else(|| parse("a raw height field needs size = [columns, rows]".into()))?;
        let count = u64::from(cols) * u64::from(rows);
        // Beyond the vertex limit, `read_raw` says so (before reading).
        if count <= MAX_HEIGHT_FIELD_VERTICES {
            budget.reserve(Holds::Vertices(count), &context)?;
        }
        let samples = read_raw(
            &ctx.resolve(raw)?,
            count,
            h.format.unwrap_or(SampleFormat::U16),
            MAX_HEIGHT_FIELD_VERTICES,
        )?;
        (cols, rows, samples.to_unit_f32())
    } else {
        let grid = h.heights.as_deref().unwrap_or_default();
        let rows = grid.len();
        let cols = grid.first().map_or(0, Vec::len);
        if grid.iter().any(|r| r.len() != cols) {
            return Err(parse("every row of heights needs the same length".into()));
        }
        (
            u32::try_from(cols).unwrap_or(u32::MAX),
            u32::try_from(rows).unwrap_or(u32::MAX),
            grid.concat(),
        )
    };
    if cols < 2 || rows < 2 {
        return Err(parse(format!(
            "a height field needs at least 2 x 2 vertices, got {cols} x {rows}"
        )));
    }
    let scene_err = |cause| LoadError::Scene {
        context: format!("{}: {what}", ctx.file.display()),
        cause,
    };
    let xf = h.transform.checked().map_err(scene_err)?;
    let field = HeightField::new(
        cols - 1,
        rows - 1,
        heights,
        (!xf.is_identity()).then(|| xf.affine()),
    )
    .map_err(scene_err)?;
    Ok(field
        .with_traversal(match h.traversal.unwrap_or(TraversalDesc::Tree) {
            TraversalDesc::Tree => HeightFieldTraversal::MinMaxTree,
            TraversalDesc::Dda => HeightFieldTraversal::Dda,
        })
        .with_surface(match h.cells.unwrap_or(CellsDesc::Triangles) {
            CellsDesc::Triangles => CellSurface::Triangles,
            CellsDesc::Bilinear => CellSurface::Bilinear,
        })
        .with_smooth_normals(h.smooth.unwrap_or(true)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(text: &str) -> Result<Scene, LoadError> {
        load_scene_str(text, "t", None, Path::new("/nonexistent"))
    }

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

    #[test]
    fn height_fields_and_volumes_from_files_and_inline() {
        let dir = std::env::temp_dir().join(format!("raybench-format-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // A 3 x 2-pixel 16-bit PNG and a 2 x 3 x 4 raw u16 volume.
        let png = dir.join("h.png");
        image::ImageBuffer::<image::Luma<u16>, _>::from_raw(
            3,
            2,
            vec![0u16, 100, 200, 300, 400, 65535],
        )
        .unwrap()
        .save(&png)
        .unwrap();
        let raw = dir.join("v.raw");
        let voxels: Vec<u8> = (0..24u16).flat_map(|v| (v * 1000).to_le_bytes()).collect();
        std::fs::write(&raw, voxels).unwrap();
        let text = format!(
            "[[object]]\nkind = \"height_field\"\npng = \"{}\"\ntraversal = \"dda\"\n\
             [[object]]\nkind = \"height_field\"\nheights = [[0, 1, 0], [1, 0.5, 1]]\n\
             smooth = false\n\
             [[volume]]\nraw = \"{}\"\ndims = [2, 3, 4]\nformat = \"u16\"\n\
             spacing = [1, 1, 2.5]\nsampling = \"trilinear\"\n",
            png.display(),
            raw.display()
        );
        let s = load(&text).unwrap();
        assert_eq!(s.geometry.len(), 2);
        for id in 0..2 {
            let raybench_core::Shape::HeightField(h) = s.geometry.shape(id) else {
                panic!("not a height field")
            };
            assert_eq!(h.cells(), (2, 1));
        }
        assert_eq!(s.volumes.len(), 1);
        assert_eq!(s.volumes[0].dims(), [2, 3, 4]);
        // Spacing 2.5 in z: the volume spans 10 units along z, centred.
        let b = s.volumes[0].bounds();
        assert_eq!((b.min.z, b.max.z), (-5.0, 5.0));
        assert_eq!(s.volumes[0].voxel([1, 0, 0]), 1000.0 / 65535.0);
        std::fs::remove_dir_all(dir).ok();
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

    /// Issue 18: an error in the second object names it, its kind and its line, and an
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
}
