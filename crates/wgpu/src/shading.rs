//! What the kernels' shading reads beyond materials and point lights, appended to the `geo`
//! buffer (`kernels/lights.wgsl` reads it back): the emitter table, the environment map with
//! its sampling distribution, image textures, and the meshes' shading attributes (vertex
//! normals and texture coordinates).
//!
//! Layout (indices into `geo`'s 16-byte entries unless said otherwise):
//!
//! - emitter table, at [`ShadingBlock::emitter_table`]: two entries per entry of the scene's
//!   `Emitters::ids` (the order of the emitter list in `prims`): the bounding sphere
//!   `(centre, radius)` (`Shape::bounding_sphere`: a sphere's own; unused for triangles),
//!   then `(cdf, choice, area, 0)`: the cumulative choice weight (`Emitters::cdf`, rounded to
//!   f32), the probability of choosing the emitter (its weight over the total of every
//!   light, the environment's included, divided in f64 as `Emitters::probability` does) and
//!   the area where it is known (`Shape::area`, 0 otherwise; the kernels read a triangle's);
//! - environment, at [`ShadingBlock::env_first`]: `width x height` texels `(r, g, b,
//!   pdf_uv)`, rows from the top, where `pdf_uv` is the texel's density over the map's
//!   `(u, v)` square (`Environment::texel_pdf` before its division by `2π² sin θ`, computed
//!   in f64 and rounded once); then, as f32s packed four to an entry from float index
//!   [`ShadingBlock::env_cdf`], the marginal table (`height` values) and the conditional
//!   tables (`width` per row), the f64 tables of `Environment` rounded to f32;
//! - textures: one entry per texture at [`ShadingBlock::tex_table`], `(first texel, width,
//!   height, wrap)` as bits (`wrap`: the `u` mode in bits 0-7, the `v` mode in bits 8-15,
//!   [`wrap_code`]), the texels `(r, g, b, 0)` row by row from the first texel on;
//! - attributes: from float index [`ShadingBlock::attr_table`], one u32 per flat primitive
//!   id: 0, or the index of the triangle's four-entry record `(n0, uv0.x) (n1, uv0.y)
//!   (n2, uv1.x) (uv1.y, uv2.x, uv2.y, flags)` (flags: 1 vertex normals, 2 texture
//!   coordinates). Each distinct instanced mesh with attributes has a table of its own, by
//!   the mesh's primitive index ([`mesh_attribute_tables`]; the instance record says where).
//!   The vertices' values are read back through the public
//!   `ShadingAttributes::at` at the triangle's corners: texture coordinates exactly (the
//!   other weights are 0), unit normals within an ulp of the stored ones (renormalised).
//!
//! The f32 formulation: every table the CPU keeps in f64 is rounded to f32 once, so the
//! GPU's choices of a light, a row and a texel agree with the CPU's except where the
//! uniform number falls within a relative 2^-24 of a boundary; the densities themselves are
//! computed in f64 here and rounded once, then divided on the GPU by f32 quantities (`sin θ`
//! from the GPU's `sin`, `acos`, `atan2`, whose absolute errors are about 1e-6).

use crate::records::{Geo, NONE, ShadingBlock};
use raybench_core::{Scene, ShadingAttributes, Shape, Vec3, Wrap};

/// The kernels' number of a wrap mode.
#[must_use]
pub fn wrap_code(w: Wrap) -> u32 {
    match w {
        Wrap::Repeat => 0,
        Wrap::ClampToEdge => 1,
        Wrap::MirroredRepeat => 2,
    }
}

fn index(geo: &Geo) -> Result<u32, String> {
    u32::try_from(geo.len()).map_err(|_| "the GPU's shading data exceeds 2^32 entries".into())
}

fn bits(x: u32) -> f32 {
    f32::from_bits(x)
}

/// Appends `floats` to `geo`, four to an entry (the last padded with zeros), and returns
/// the float index of the first.
fn push_floats(geo: &mut Geo, floats: &[f32]) -> Result<u32, String> {
    let first = index(geo)?
        .checked_mul(4)
        .ok_or("the GPU's shading data exceeds 2^32 floats")?;
    for c in floats.chunks(4) {
        let mut e = [0.0; 4];
        e[..c.len()].copy_from_slice(c);
        geo.push(e);
    }
    Ok(first)
}

/// Bytes of `geo` the shading data of `scene` needs (for the refusal of scenes whose data
/// exceeds a storage buffer).
#[must_use]
pub fn bytes_needed(scene: &Scene) -> u64 {
    let env = scene.environment.as_ref().map_or(0, |e| {
        let (w, h) = e.size();
        u64::from(w) * u64::from(h) * 20 + u64::from(h) * 4
    });
    let textures: u64 = scene
        .textures
        .iter()
        .map(|t| u64::from(t.width()) * u64::from(t.height()) * 16 + 16)
        .sum();
    let table = |a: &ShadingAttributes, ids: usize| {
        if a.is_empty() {
            0
        } else {
            ids as u64 * 4 + a.bytes() as u64 * 2
        }
    };
    let meshes = scene.geometry.meshes();
    let attributes = table(&scene.attributes, scene.prim_material.len())
        + scene
            .mesh_attributes
            .iter()
            .zip(meshes)
            .map(|(a, m)| table(a, m.len()))
            .sum::<u64>();
    env + textures + attributes + scene.emitters.ids.len() as u64 * 32
}

/// Appends the shading data of `scene` to `geo` and returns where it is.
///
/// # Errors
/// When `geo` outgrows 32-bit indices.
pub fn encode(scene: &Scene, geo: &mut Geo) -> Result<ShadingBlock, String> {
    let e = &scene.emitters;
    let emitter_total = e.cdf.last().copied().unwrap_or(0.0);
    let total = emitter_total + e.environment;
    let mut block = ShadingBlock {
        light_total: total as f32,
        env_choice: if total > 0.0 {
            (e.environment / total) as f32
        } else {
            0.0
        },
        env_first: 0,
        env_width: 0,
        env_height: 0,
        env_cdf: 0,
        env_cos: 1.0,
        env_sin: 0.0,
        emitter_table: index(geo)?,
        attr_table: NONE,
        attr_count: 0,
        tex_table: 0,
    };
    // Emitter table.
    let mut previous = 0.0f64;
    for (&id, &cdf) in e.ids.iter().zip(&e.cdf) {
        let shape = scene.geometry.shape(id);
        let (center, radius) = shape.bounding_sphere().unwrap_or((Vec3::ZERO, 0.0));
        let area = shape.area().map_or(0.0, |a| a as f32);
        let choice = if total > 0.0 {
            ((cdf - previous) / total) as f32
        } else {
            0.0
        };
        previous = cdf;
        geo.push([center.x, center.y, center.z, radius]);
        geo.push([cdf as f32, choice, area, 0.0]);
    }
    // Environment.
    if let Some(env) = scene.environment.as_deref() {
        let (w, h) = env.size();
        let wu = w as usize;
        let (marginal, conditional) = env.tables();
        let total = marginal.last().copied().unwrap_or(0.0);
        block.env_first = index(geo)?;
        block.env_width = w;
        block.env_height = h;
        for (i, t) in env.texels().iter().enumerate() {
            let (x, y) = (i % wu, i / wu);
            // `Environment::texel_pdf` before its division by 2π² sin θ.
            let row = &conditional[y * wu..(y + 1) * wu];
            let texel = row[x] - if x == 0 { 0.0 } else { row[x - 1] };
            let row_sin = f64::from(((y as f32 + 0.5) / h as f32 * std::f32::consts::PI).sin());
            let pdf_uv = if total > 0.0 {
                texel * row_sin / total * f64::from(w) * f64::from(h)
            } else {
                0.0
            };
            geo.push([t.x, t.y, t.z, pdf_uv as f32]);
        }
        let tables: Vec<f32> = marginal
            .iter()
            .chain(conditional)
            .map(|&c| c as f32)
            .collect();
        block.env_cdf = push_floats(geo, &tables)?;
        (block.env_cos, block.env_sin) = env.rotation();
    }
    // Textures.
    if !scene.textures.is_empty() {
        let mut firsts = Vec::with_capacity(scene.textures.len());
        let table_len = scene.textures.len();
        block.tex_table = index(geo)?;
        geo.resize(geo.len() + table_len, [0.0; 4]);
        for t in &scene.textures {
            firsts.push(index(geo)?);
            for j in 0..t.height() {
                for i in 0..t.width() {
                    let c = t.texel(i64::from(i), i64::from(j));
                    geo.push([c.x, c.y, c.z, 0.0]);
                }
            }
        }
        for (k, (t, first)) in scene.textures.iter().zip(firsts).enumerate() {
            let wrap = wrap_code(t.wrap[0]) | (wrap_code(t.wrap[1]) << 8);
            geo[block.tex_table as usize + k] =
                [bits(first), bits(t.width()), bits(t.height()), bits(wrap)];
        }
    }
    // Shading attributes of the flat primitives.
    if !scene.attributes.is_empty() {
        let n = scene.prim_material.len();
        block.attr_table = attribute_table(&scene.attributes, n, geo, |id| {
            matches!(scene.geometry.shape(id), Shape::Triangle(_))
        })?;
        block.attr_count = n as u32;
    }
    Ok(block)
}

/// Appends the attribute table of primitive ids `0..count` (`is_triangle` says which have
/// vertices) of `attributes` to `geo`: one u32 per id, 0 or the index of its four-entry
/// record, then the records (layout above). Returns the table's float index.
fn attribute_table(
    attributes: &ShadingAttributes,
    count: usize,
    geo: &mut Geo,
    is_triangle: impl Fn(u32) -> bool,
) -> Result<u32, String> {
    let mut offsets = vec![0u32; count];
    let mut records: Vec<[f32; 4]> = Vec::new();
    let records_first = geo.len() + count.div_ceil(4);
    for (id, offset) in offsets.iter_mut().enumerate() {
        let id = id as u32;
        if !is_triangle(id) {
            continue;
        }
        let corners = [
            attributes.at(id, 0.0, 0.0),
            attributes.at(id, 1.0, 0.0),
            attributes.at(id, 0.0, 1.0),
        ];
        let normals = corners.iter().all(|c| c.normal.is_some());
        let uvs = corners.iter().all(|c| c.uv.is_some());
        if !normals && !uvs {
            continue;
        }
        let nv = corners.map(|c| c.normal.unwrap_or(Vec3::ZERO));
        let uv = corners.map(|c| c.uv.unwrap_or_default());
        let flags = u32::from(normals) | (u32::from(uvs) << 1);
        *offset = u32::try_from(records_first + records.len())
            .map_err(|_| "the GPU's shading attributes exceed 2^32 entries")?;
        records.push([nv[0].x, nv[0].y, nv[0].z, uv[0].x]);
        records.push([nv[1].x, nv[1].y, nv[1].z, uv[0].y]);
        records.push([nv[2].x, nv[2].y, nv[2].z, uv[1].x]);
        records.push([uv[1].y, uv[2].x, uv[2].y, bits(flags)]);
    }
    let words: Vec<f32> = offsets.into_iter().map(bits).collect();
    let table = push_floats(geo, &words)?;
    debug_assert_eq!(geo.len(), records_first);
    geo.extend(records);
    Ok(table)
}

/// Appends the attribute table of each distinct instanced mesh that has attributes
/// ([`Scene::mesh_attributes`], ids in the mesh) to `geo` and returns their float indices
/// in [`raybench_core::Geometry::meshes`] order ([`NONE`] for a mesh without any); the
/// instance records carry them (`crate::instances`).
///
/// # Errors
/// When `geo` outgrows 32-bit indices.
pub(crate) fn mesh_attribute_tables(scene: &Scene, geo: &mut Geo) -> Result<Vec<u32>, String> {
    let meshes = scene.geometry.meshes();
    let mut tables = vec![NONE; meshes.len()];
    for ((table, mesh), attributes) in tables.iter_mut().zip(meshes).zip(&scene.mesh_attributes) {
        if !attributes.is_empty() {
            *table = attribute_table(attributes, mesh.len(), geo, |id| {
                matches!(mesh.shape(id), Shape::Triangle(_))
            })?;
        }
    }
    Ok(tables)
}
