//! The `kind = "height_field"` object of the scene format: a grid of vertex heights from a
//! terrain generator, a PNG height map, a raw sample file or inline rows.

use super::{Context, ObjectCx, TransformDesc};
use crate::budget::{Holds, Reservation};
use crate::error::LoadError;
use crate::generators;
use crate::samples::{SampleFormat, read_png_gray, read_raw};
use raybench_core::{CellSurface, HeightField, HeightFieldTraversal, MAX_HEIGHT_FIELD_VERTICES};
use serde::Deserialize;
use std::sync::Arc;

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

/// `kind = "height_field"`: from exactly one of a terrain generator, a PNG, a raw file and
/// inline heights.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct HeightFieldDesc {
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

impl HeightFieldDesc {
    /// Builds the height field and adds it.
    pub(super) fn add(&self, cx: &mut ObjectCx) -> Result<(), LoadError> {
        let err = cx.err();
        let m = cx.material(self.material.as_ref())?.unwrap_or(0);
        let field = height_field(self, cx.ctx, cx.what, cx.budget)?;
        cx.b.add_shapes(
            "height field",
            vec![raybench_core::Shape::HeightField(Arc::new(field))],
            m,
        )
        .map_err(err)?;
        Ok(())
    }
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
        let (info, n) = generators::parse_spec(spec).map_err(ctx.within(what))?;
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
        let (cols, rows, heights) =
            read_png_gray(&ctx.resolve("png", png, what)?, MAX_HEIGHT_FIELD_VERTICES)
                .map_err(ctx.within(what))?;
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
            &ctx.resolve("raw", raw, what)?,
            count,
            h.format.unwrap_or(SampleFormat::U16),
            MAX_HEIGHT_FIELD_VERTICES,
        )
        .map_err(ctx.within(what))?;
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
    use super::super::load_test_scene as load;

    #[test]
    fn height_fields_from_a_png_and_inline() {
        let dir = std::env::temp_dir().join(format!("raybench-heightfield-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // A 3 x 2-pixel 16-bit PNG.
        let png = dir.join("h.png");
        image::ImageBuffer::<image::Luma<u16>, _>::from_raw(
            3,
            2,
            vec![0u16, 100, 200, 300, 400, 65535],
        )
        .unwrap()
        .save(&png)
        .unwrap();
        let text = format!(
            "[[object]]\nkind = \"height_field\"\npng = \"{}\"\ntraversal = \"dda\"\n\
             [[object]]\nkind = \"height_field\"\nheights = [[0, 1, 0], [1, 0.5, 1]]\n\
             smooth = false\n",
            png.display(),
        );
        let s = load(&text).unwrap();
        assert_eq!(s.geometry.len(), 2);
        for id in 0..2 {
            let raybench_core::Shape::HeightField(h) = s.geometry.shape(id) else {
                panic!("not a height field")
            };
            assert_eq!(h.cells(), (2, 1));
        }
        std::fs::remove_dir_all(dir).ok();
    }
}
