//! The `[[volume]]` tables of the scene format: a voxel volume from a generated phantom or
//! a raw sample file, with its spacing, placement, sampling and transfer function.

use super::{Context, ScaleDesc, TransformDesc, V3};
use crate::budget::{Holds, Reservation};
use crate::error::LoadError;
use crate::phantom;
use crate::samples::{SampleFormat, read_raw};
use raybench_core::voxels::{MAX_VOLUME_VOXELS, check_volume_dims};
use raybench_core::{
    Sampling, TransferFunction, TransferPoint, Vec3, Volume, VolumeData, VolumeParams,
};
use serde::Deserialize;

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

/// A `[[volume]]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct VolumeDesc {
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

/// Builds the volume a `[[volume]]` table describes.
pub(super) fn volume(
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
            let n = phantom::parse_volume_spec(spec).map_err(ctx.within(what))?;
            budget.reserve(Holds::Voxels(u64::from(n).pow(3)), &context)?;
            let data = phantom::rasterize(&phantom::shepp_logan_ellipsoids(), n);
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
                &ctx.resolve("raw", raw, what)?,
                count,
                v.format.unwrap_or(SampleFormat::U16),
                MAX_VOLUME_VOXELS,
            )
            .map_err(ctx.within(what))?;
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

#[cfg(test)]
mod tests {
    use super::super::load_test_scene as load;

    #[test]
    fn volumes_from_raw_files() {
        let dir = std::env::temp_dir().join(format!("raybench-volume-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // A 2 x 3 x 4 raw u16 volume.
        let raw = dir.join("v.raw");
        let voxels: Vec<u8> = (0..24u16).flat_map(|v| (v * 1000).to_le_bytes()).collect();
        std::fs::write(&raw, voxels).unwrap();
        let text = format!(
            "[[volume]]\nraw = \"{}\"\ndims = [2, 3, 4]\nformat = \"u16\"\n\
             spacing = [1, 1, 2.5]\nsampling = \"trilinear\"\n",
            raw.display()
        );
        let s = load(&text).unwrap();
        assert_eq!(s.volumes.len(), 1);
        assert_eq!(s.volumes[0].dims(), [2, 3, 4]);
        // Spacing 2.5 in z: the volume spans 10 units along z, centred.
        let b = s.volumes[0].bounds();
        assert_eq!((b.min.z, b.max.z), (-5.0, 5.0));
        assert_eq!(s.volumes[0].voxel([1, 0, 0]), 1000.0 / 65535.0);
        std::fs::remove_dir_all(dir).ok();
    }
}
