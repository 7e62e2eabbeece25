//! The `kind = "generator"` object of the scene format: a seeded generator's output
//! (a mesh, spheres or a height field), placed.

use super::{ObjectCx, TransformDesc};
use crate::error::LoadError;
use crate::generators::{self, Generated};
use raybench_core::{HeightField, SceneError, Sphere};
use serde::Deserialize;
use std::sync::Arc;

/// `kind = "generator"`: `spec` as on the command line (`spheres:1000`), with a seed.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct GeneratorDesc {
    spec: String,
    seed: Option<u32>,
    material: Option<String>,
    #[serde(default)]
    transform: TransformDesc,
}

impl GeneratorDesc {
    /// Checks the primitive count and the budget from the spec, then generates, places and
    /// adds the output.
    pub(super) fn add(&self, cx: &mut ObjectCx) -> Result<(), LoadError> {
        let err = cx.err();
        // Refuse before generating: a one-line spec can ask for 2e7 primitives.
        let within = cx.ctx.within(cx.what);
        let (info, n) = generators::parse_spec(&self.spec).map_err(&within)?;
        let count = generators::primitive_count(&info, n);
        let limit = raybench_core::limits::MAX_PRIMITIVES as u64;
        if cx.b.primitive_count() as u64 + count > limit {
            return Err(LoadError::Scene {
                context: format!("{}: {}", cx.ctx.file.display(), cx.what),
                cause: SceneError::TooLarge(format!(
                    "generator '{}' would take the scene past {limit} primitives",
                    self.spec
                )),
            });
        }
        let xf = self.transform.checked().map_err(&err)?;
        cx.budget.reserve(
            generators::holds(&info, n),
            &format!("{}: {}", cx.ctx.file.display(), cx.what),
        )?;
        let generated =
            generators::generate(&self.spec, self.seed.unwrap_or(generators::DEFAULT_SEED))
                .map_err(within)?;
        let m = cx.material(self.material.as_ref())?.unwrap_or(0);
        let a = xf.affine();
        match generated {
            Generated::Mesh(mut mesh) => {
                if !xf.is_identity() {
                    mesh.transform(|v| a.transform_point3(v));
                }
                cx.b.add_mesh(self.spec.as_str(), &mesh, m).map_err(err)?;
            }
            Generated::Spheres(spheres) => {
                let s_max = xf.scale.abs().max_element();
                for s in spheres {
                    let s = Sphere::new(a.transform_point3(s.center), s.radius * s_max);
                    cx.b.add_sphere(s, m).map_err(&err)?;
                }
            }
            Generated::HeightField { n, heights } => {
                // The placement as the tessellated terrain applies it: none for the
                // identity, else `transform_point3` on every vertex.
                let field = HeightField::new(n, n, heights, (!xf.is_identity()).then_some(a))
                    .map_err(&err)?;
                cx.b.add_shapes(
                    self.spec.as_str(),
                    vec![raybench_core::Shape::HeightField(Arc::new(field))],
                    m,
                )
                .map_err(err)?;
            }
        }
        Ok(())
    }
}
