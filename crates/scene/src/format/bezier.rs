//! The `kind = "bezier"` object of the scene format: bicubic Bezier patches from a `.bpt`
//! file, intersected directly or tessellated.

use super::{Context, ObjectCx, TransformDesc};
use crate::bpt::load_bpt_file;
use crate::budget::{Holds, Reservation};
use crate::error::LoadError;
use raybench_core::{BezierPatch, SceneBuilder, SceneError, TriangleMesh};
use serde::Deserialize;
use std::sync::Arc;

/// Bicubic Bezier patches from a `.bpt` file, intersected directly or tessellated.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct BezierDesc {
    file: String,
    material: Option<String>,
    #[serde(default)]
    transform: TransformDesc,
    /// `N`: `N x N` quads (two triangles each) per patch instead of the direct patches.
    tessellate: Option<u32>,
}

/// Largest accepted `tessellate = N` (`2 N^2` triangles per patch).
const MAX_TESSELLATE: u32 = 1024;

impl BezierDesc {
    /// Loads the patch file and adds its patches.
    pub(super) fn add(&self, cx: &mut ObjectCx) -> Result<(), LoadError> {
        let m = cx.material(self.material.as_ref())?.unwrap_or(0);
        bezier(cx.b, self, cx.ctx, cx.what, m, cx.budget)
    }
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
    let path = ctx.resolve("file", &d.file, what)?;
    let patches = load_bpt_file(&path).map_err(ctx.within(what))?;
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
            .add_shapes(
                d.file.as_str(),
                built
                    .into_iter()
                    .map(raybench_core::Shape::Bezier)
                    .collect(),
                material,
            )
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
