//! The scene's voxel volumes as the volume kernels (`kernels/volume.wgsl`: `mip_kernel`,
//! `composite_kernel`) read them: appended to the `geo` buffer after the primitives' data.
//!
//! The kernels port `raybench_core::voxels` and `integrator::mip_composite` operation for
//! operation: the ray carried into grid units (`Volume::grid_ray`), the 3D-DDA of Amanatides
//! and Woo (`raybench_core::dda`), empty-space skipping over the coarse min-max grid of
//! [`raybench_core::voxels::SKIP_BLOCK`]^3-voxel blocks (MIP enters a block only when its maximum exceeds the
//! maximum so far, compositing only when the transfer function has extinction in the
//! block's value range, `TransferFunction::max_sigma`), nearest or trilinear sampling,
//! the transfer function (`TransferFunction::eval`), Beer-Lambert opacity
//! `1 - exp(-sigma l)` per voxel segment and front-to-back compositing with early
//! termination at [`raybench_core::voxels::EARLY_TERMINATION`], the volumes taken in the
//! order the ray enters them.
//!
//! # Layout in `geo` (16-byte entries)
//!
//! - The table: one entry per volume, `x` the bits of the index of its header.
//! - The header, [`HEADER_ENTRIES`] entries: the world-to-object matrix's columns (0-2), its
//!   translation with the sampling in `w` (3: 0 nearest, 1 trilinear), the object-space
//!   box's minimum with the skip flag in `w` (4), `1 / spacing` with the transfer
//!   function's point count in `w` (5), the dimensions with the index of the points in `w`
//!   (6), the coarse grid's dimensions with the index of the coarse grid in `w` (7), the
//!   MIP window `lo, hi` and the index of the voxels (8).
//! - The transfer function: two entries per point, `(value, sigma, 0, 0)` and
//!   `(r, g, b, 0)`.
//! - The coarse grid: `[min, max]` per block, two blocks per entry, x fastest.
//! - The voxels: the values `Volume::voxel` reads (8- and 16-bit samples already divided by
//!   255 or 65,535, so the GPU reads the same f32), four per entry, x fastest. Four bytes
//!   per voxel whatever the stored type: a volume whose entries exceed the device's
//!   storage-binding limit is refused ([`fit`]) and the volume modes with it; the other
//!   modes, which ignore volumes, still render the scene.
//!
//! # Precision
//!
//! Everything is f32 on both sides (the CPU integrates in f32 too), so the GPU differs only
//! where it rounds differently: WGSL division (2.5 ULP on Vulkan) in the DDA's crossing
//! distances and the transfer function's interpolation weight, `exp` (3 + 2|x| ULP), and
//! fused multiply-adds in the trilinear lerps and the grid transform. A segment length
//! then differs by a few ULP of the ray's `t`, a sample by a few ULP of its value; each
//! segment's opacity by about `sigma l` times that, and the composite sum accumulates one
//! such error per segment (a 3D-DDA crosses at most 3 x 128 - 2 = 382 voxels of the
//! phantom): relative errors of order 1e-5, well under the tests' 1e-3 per channel. A
//! sample that lands on the other side of a voxel border or of a sharp step of the
//! transfer function, a ray that grazes a block edge, or early termination one segment
//! earlier can change a pixel more; the tests allow a small fraction of such pixels.
//! Measured on lavapipe against naive (`tests/tests/gpu/shading.rs`), largest relative colour
//! difference at 32 x 32 (64 x 64): MIP 1.2e-5 (1.4e-5) and compositing 4.7e-5 (8.6e-5) on
//! `phantom`, 9e-6 (8e-6) and 1.9e-5 (3.1e-5) on the tests' scene with surfaces and
//! overlapping volumes; no pixel beyond 1e-3, ids all equal, `t` within 5e-7.

use crate::records::{Geo, next_index};
use raybench_core::voxels::{Sampling, Volume};
use raybench_core::{Scene, Vec3};

/// Entries of a volume's header in `geo` (see the module's layout).
pub(crate) const HEADER_ENTRIES: usize = 9;

/// Where the volumes start in `geo`: the index of the table and the number of volumes, or
/// why the volume modes cannot run on the GPU.
pub(crate) type GpuVolumes = Result<(u32, u32), String>;

/// Entries of `geo` one volume takes (header, transfer function, coarse grid, voxels; the
/// table's entry not included).
fn entries(v: &Volume) -> u64 {
    let [x, y, z] = v.dims();
    let voxels = u64::from(x) * u64::from(y) * u64::from(z);
    let blocks = v.coarse().1.len() as u64;
    HEADER_ENTRIES as u64
        + 2 * v.transfer().points().len() as u64
        + blocks.div_ceil(2)
        + voxels.div_ceil(4)
}

/// Bytes the volumes of `scene` add to the `geo` buffer.
#[must_use]
pub(crate) fn bytes(scene: &Scene) -> u64 {
    scene.volumes.iter().map(|v| (1 + entries(v)) * 16).sum()
}

/// Whether `scene`'s volumes fit a storage binding of `limit` bytes on device `device`
/// (with `other` bytes of the primitives' data before them), or why not.
///
/// # Errors
/// The reason, naming the largest volume and the bytes needed.
pub(crate) fn fit(scene: &Scene, other: u64, limit: u64, device: &str) -> Result<(), String> {
    let need = other + bytes(scene);
    if need <= limit && need / 16 <= u64::from(u32::MAX) {
        return Ok(());
    }
    let largest = scene
        .volumes
        .iter()
        .max_by_key(|v| entries(v))
        .map_or_else(String::new, |v| {
            let [x, y, z] = v.dims();
            format!(
                " (the largest, {x} x {y} x {z} voxels, takes {} bytes at 4 per voxel)",
                entries(v) * 16
            )
        });
    Err(format!(
        "the GPU's volume modes need the {} volume(s) in one storage buffer of {need} bytes{largest}, \
         more than the {limit} bytes a storage buffer may hold on {device} (render the volume \
         modes with a CPU backend)",
        scene.volumes.len()
    ))
}

/// Appends every volume of `scene` to `geo` (table, then each volume's header, transfer
/// function, coarse grid and voxels) and returns the table's index and the volume count.
/// On an error `geo` is left as it was.
///
/// # Errors
/// When `geo` would outgrow the `u32` indices of the kernels.
pub(crate) fn append(scene: &Scene, geo: &mut Geo) -> GpuVolumes {
    let start = geo.len();
    let out = append_all(scene, geo);
    if out.is_err() {
        geo.truncate(start);
    }
    out
}

/// See [`append`].
fn append_all(scene: &Scene, geo: &mut Geo) -> GpuVolumes {
    let count = u32::try_from(scene.volumes.len()).map_err(|_| "too many volumes".to_string())?;
    if count == 0 {
        return Ok((0, 0));
    }
    let total = geo.len() as u64 + bytes(scene) / 16;
    if total > u64::from(u32::MAX) {
        return Err(format!(
            "the volumes need {total} entries of the GPU's primitive data, more than 2^32"
        ));
    }
    let table = next_index(geo)?;
    geo.resize(geo.len() + count as usize, [0.0; 4]);
    for (k, v) in scene.volumes.iter().enumerate() {
        let header = next_index(geo)?;
        geo[table as usize + k] = [f32::from_bits(header), 0.0, 0.0, 0.0];
        encode(v, geo)?;
    }
    Ok((table, count))
}

/// Bits of a `u32` as the `f32` a `geo` entry holds.
fn bits(x: u32) -> f32 {
    f32::from_bits(x)
}

/// Appends one volume's header, transfer function, coarse grid and voxels.
fn encode(v: &Volume, geo: &mut Geo) -> Result<(), String> {
    let header = geo.len();
    geo.resize(header + HEADER_ENTRIES, [0.0; 4]);
    let inv = v.inverse();
    let points = v.transfer().points();
    let (coarse_dims, coarse) = v.coarse();
    let dims = v.dims();
    let params = v.params();
    // The same operations as `Volume::grid_ray`.
    let min = v.object_box().min;
    let inv_s = v.spacing().recip();

    let points_at = next_index(geo)?;
    for p in points {
        geo.push([p.value, p.sigma, 0.0, 0.0]);
        geo.push([p.color.x, p.color.y, p.color.z, 0.0]);
    }
    let coarse_at = next_index(geo)?;
    for pair in coarse.chunks(2) {
        let b = pair.get(1).copied().unwrap_or([0.0; 2]);
        geo.push([pair[0][0], pair[0][1], b[0], b[1]]);
    }
    let voxels_at = next_index(geo)?;
    let mut quad = [0.0f32; 4];
    let mut n = 0;
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                quad[n] = v.voxel([x, y, z]);
                n += 1;
                if n == 4 {
                    geo.push(quad);
                    n = 0;
                }
            }
        }
    }
    if n > 0 {
        quad[n..].fill(0.0);
        geo.push(quad);
    }

    let col = |c: Vec3, w: f32| [c.x, c.y, c.z, w];
    let h = &mut geo[header..header + HEADER_ENTRIES];
    h[0] = col(inv.matrix3.x_axis.into(), 0.0);
    h[1] = col(inv.matrix3.y_axis.into(), 0.0);
    h[2] = col(inv.matrix3.z_axis.into(), 0.0);
    h[3] = col(
        inv.translation.into(),
        bits(u32::from(params.sampling == Sampling::Trilinear)),
    );
    h[4] = [min.x, min.y, min.z, bits(u32::from(params.skip_empty))];
    h[5] = [inv_s.x, inv_s.y, inv_s.z, bits(points.len() as u32)];
    h[6] = [bits(dims[0]), bits(dims[1]), bits(dims[2]), bits(points_at)];
    h[7] = [
        bits(coarse_dims[0]),
        bits(coarse_dims[1]),
        bits(coarse_dims[2]),
        bits(coarse_at),
    ];
    h[8] = [params.window[0], params.window[1], bits(voxels_at), 0.0];
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_core::voxels::{TransferFunction, VolumeData, VolumeParams};
    use raybench_core::{SceneBuilder, Vec3};
    use std::sync::Arc;

    /// A scene of two volumes: 5 x 3 x 7 voxels (sides not multiples of the skipping block,
    /// a voxel count not a multiple of four) and 4 x 4 x 4.
    fn scene() -> Scene {
        let mut b = SceneBuilder::new("volumes");
        for (k, dims) in [[5u32, 3, 7], [4, 4, 4]].into_iter().enumerate() {
            let n = (dims[0] * dims[1] * dims[2]) as usize;
            let data = (0..n).map(|i| ((i * 37 + k) % 101) as u8).collect();
            let v = Volume::new(
                dims,
                Vec3::new(0.5, 0.25, 1.0),
                VolumeData::U8(data),
                raybench_core::Affine3A::from_rotation_y(0.3 * k as f32),
                TransferFunction::ramp(3.0),
                VolumeParams {
                    sampling: if k == 0 {
                        Sampling::Trilinear
                    } else {
                        Sampling::Nearest
                    },
                    skip_empty: k == 0,
                    window: [0.1, 0.9],
                },
            )
            .unwrap();
            b.add_volume(Arc::new(v)).unwrap();
        }
        b.build()
    }

    #[test]
    fn volumes_are_laid_out_as_the_kernels_read_them() {
        let s = scene();
        let mut geo: Geo = vec![[1.0; 4]; 3];
        let (table, count) = append(&s, &mut geo).unwrap();
        assert_eq!((table, count), (3, 2));
        assert_eq!((geo.len() as u64 - 3) * 16, bytes(&s));
        let u = |x: f32| x.to_bits();
        for (k, v) in s.volumes.iter().enumerate() {
            let h = u(geo[table as usize + k][0]) as usize;
            let dims = v.dims();
            assert_eq!([u(geo[h + 6][0]), u(geo[h + 6][1]), u(geo[h + 6][2])], dims);
            assert_eq!(u(geo[h + 3][3]), u32::from(k == 0), "trilinear");
            assert_eq!(u(geo[h + 4][3]), u32::from(k == 0), "skip_empty");
            assert_eq!(&geo[h + 8][..2], &[0.1, 0.9]);
            // Voxels, x fastest, as `Volume::voxel` reads them.
            let at = u(geo[h + 8][2]) as usize;
            let mut i = 0;
            for z in 0..dims[2] {
                for y in 0..dims[1] {
                    for x in 0..dims[0] {
                        assert_eq!(geo[at + i / 4][i % 4], v.voxel([x, y, z]));
                        i += 1;
                    }
                }
            }
            // The coarse grid, two blocks per entry.
            let (cdims, coarse) = v.coarse();
            assert_eq!(
                [u(geo[h + 7][0]), u(geo[h + 7][1]), u(geo[h + 7][2])],
                cdims
            );
            let at = u(geo[h + 7][3]) as usize;
            for (b, r) in coarse.iter().enumerate() {
                let e = geo[at + b / 2];
                assert_eq!([e[2 * (b % 2)], e[2 * (b % 2) + 1]], *r);
            }
            // The transfer function, two entries per point.
            let points = v.transfer().points();
            assert_eq!(u(geo[h + 5][3]) as usize, points.len());
            let at = u(geo[h + 6][3]) as usize;
            for (j, p) in points.iter().enumerate() {
                assert_eq!(geo[at + 2 * j][..2], [p.value, p.sigma]);
                assert_eq!(geo[at + 2 * j + 1][..3], p.color.to_array());
            }
        }
    }

    #[test]
    fn volumes_beyond_the_binding_limit_are_refused_with_a_reason() {
        let s = scene();
        let need = bytes(&s);
        assert!(fit(&s, 0, need, "test device").is_ok());
        let why = fit(&s, 16, need, "test device").unwrap_err();
        assert!(why.contains("5 x 3 x 7 voxels"), "{why}");
        assert!(why.contains(&format!("{need} bytes")), "{why}");
        assert!(why.contains("test device"), "{why}");
        // No volumes: nothing appended.
        let mut geo = Geo::new();
        let empty = SceneBuilder::new("empty").build();
        assert_eq!(append(&empty, &mut geo), Ok((0, 0)));
        assert!(geo.is_empty());
    }
}
