//! Voxel volumes and direct volume rendering: a 3D grid of scalar densities walked voxel by
//! voxel with the 3D-DDA of Amanatides and Woo ("A Fast Voxel Traversal Algorithm for Ray
//! Tracing", Eurographics 1987), integrated as a maximum-intensity projection or by
//! front-to-back emission-absorption compositing through a transfer function.
//!
//! Volumes are not primitives: they have no ids and acceleration structures never see
//! them. The integrators of [`crate::Mode::Mip`] and [`crate::Mode::Composite`] trace each
//! camera ray through the backend first and integrate every volume from where the ray
//! enters it to where it leaves or meets that surface, whichever is first.
//!
//! Voxel `(i, j, k)` is the box `[i, i + 1] x [j, j + 1] x [k, k + 1]` in grid units,
//! `spacing` world units per grid unit, the grid centred on the object-space origin; the
//! placement maps object to world space. The ray is carried into object space (the ray
//! parameter `t` stays the world ray's).

use crate::Aabb;
use crate::Ray;
use crate::SceneError;
use glam::{Affine3A, Vec3};
use std::ops::ControlFlow;

pub use crate::limits::MAX_VOLUME_VOXELS;

/// Side of the blocks of the coarse min-max grid used for empty-space skipping. Measured on
/// the phantom (bench `volume/phantom/*/skip`, 2-vCPU AMD EPYC Zen 5, one run per size):
/// 4 gives MIP 19.8 ms and compositing 51.6 ms, 8 gives 24.0 and 52.2 ms, 16 gives 38.3 and
/// 62.7 ms. Smaller blocks skip closer to the head's outline; the coarse grid costs 8 bytes
/// per block (1/8 of the voxel bytes of an f32 volume at 4).
pub const SKIP_BLOCK: u32 = 4;

/// Opacity at which front-to-back compositing stops (transmittance below 1/256: the rest
/// cannot change an 8-bit pixel by more than one level).
pub const EARLY_TERMINATION: f32 = 1.0 - 1.0 / 256.0;

/// Voxel values in their stored type.
#[derive(Clone, Debug, PartialEq)]
pub enum VolumeData {
    /// 8-bit, read as `value / 255`.
    U8(Vec<u8>),
    /// 16-bit, read as `value / 65535`.
    U16(Vec<u16>),
    /// Floats, read as they are.
    F32(Vec<f32>),
}

impl VolumeData {
    fn len(&self) -> usize {
        match self {
            Self::U8(v) => v.len(),
            Self::U16(v) => v.len(),
            Self::F32(v) => v.len(),
        }
    }

    fn bytes(&self) -> usize {
        match self {
            Self::U8(v) => v.len(),
            Self::U16(v) => v.len() * 2,
            Self::F32(v) => v.len() * 4,
        }
    }

    #[inline]
    fn get(&self, i: usize) -> f32 {
        match self {
            Self::U8(v) => f32::from(v[i]) / 255.0,
            Self::U16(v) => f32::from(v[i]) / 65_535.0,
            Self::F32(v) => v[i],
        }
    }
}

/// How values are read along a ray.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Sampling {
    /// The value of the voxel the segment lies in.
    #[default]
    Nearest,
    /// Trilinear interpolation between voxel centres, at the middle of each voxel segment.
    Trilinear,
}

/// One control point of a [`TransferFunction`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TransferPoint {
    /// The (normalised) voxel value.
    pub value: f32,
    /// Emitted colour (linear RGB).
    pub color: Vec3,
    /// Extinction per world unit: a segment of length `l` has opacity `1 - exp(-sigma l)`.
    pub sigma: f32,
}

/// A piecewise-linear map from value to colour and extinction, constant beyond its first
/// and last points.
#[derive(Clone, Debug, PartialEq)]
pub struct TransferFunction {
    points: Vec<TransferPoint>,
}

impl TransferFunction {
    /// A transfer function from control points in increasing `value` order.
    ///
    /// # Errors
    /// No points, values not strictly increasing, non-finite numbers, negative `sigma` or
    /// colour.
    pub fn new(points: Vec<TransferPoint>) -> Result<Self, SceneError> {
        if points.is_empty() {
            return Err(SceneError::Invalid(
                "a transfer function needs at least one point".into(),
            ));
        }
        for p in &points {
            if !(p.value.is_finite() && p.color.is_finite() && p.sigma.is_finite()) {
                return Err(SceneError::NonFinite("transfer function point".into()));
            }
            if p.sigma < 0.0 || p.color.min_element() < 0.0 {
                return Err(SceneError::Invalid(
                    "transfer function colours and sigma must not be negative".into(),
                ));
            }
        }
        if points.windows(2).any(|w| w[0].value >= w[1].value) {
            return Err(SceneError::Invalid(
                "transfer function values must be strictly increasing".into(),
            ));
        }
        Ok(Self { points })
    }

    /// A grey ramp: colour = value, `sigma = value * density` (a simple default).
    #[must_use]
    pub fn ramp(density: f32) -> Self {
        Self {
            points: vec![
                TransferPoint {
                    value: 0.0,
                    color: Vec3::ZERO,
                    sigma: 0.0,
                },
                TransferPoint {
                    value: 1.0,
                    color: Vec3::ONE,
                    sigma: density,
                },
            ],
        }
    }

    /// Colour and extinction at `value`.
    #[must_use]
    pub fn eval(&self, value: f32) -> (Vec3, f32) {
        let p = &self.points;
        let first = p[0];
        // NaN values read as the first point.
        if value <= first.value || value.is_nan() {
            return (first.color, first.sigma);
        }
        for w in p.windows(2) {
            if value <= w[1].value {
                let f = (value - w[0].value) / (w[1].value - w[0].value);
                return (
                    w[0].color.lerp(w[1].color, f),
                    w[0].sigma + (w[1].sigma - w[0].sigma) * f,
                );
            }
        }
        let last = p[p.len() - 1];
        (last.color, last.sigma)
    }

    /// The control points, in increasing `value` order (for ports of [`Self::eval`]).
    #[must_use]
    pub fn points(&self) -> &[TransferPoint] {
        &self.points
    }

    /// The largest extinction over values in `[lo, hi]` (exact for a piecewise-linear map:
    /// the ends and the points between).
    #[must_use]
    pub fn max_sigma(&self, lo: f32, hi: f32) -> f32 {
        let mut m = self.eval(lo).1.max(self.eval(hi).1);
        for p in &self.points {
            if p.value > lo && p.value < hi {
                m = m.max(p.sigma);
            }
        }
        m
    }
}

/// Options of a volume's integration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeParams {
    /// Nearest voxel or trilinear.
    pub sampling: Sampling,
    /// Skip blocks of the coarse min-max grid that cannot contribute.
    pub skip_empty: bool,
    /// Values mapped to black and white by the maximum-intensity projection.
    pub window: [f32; 2],
}

impl Default for VolumeParams {
    fn default() -> Self {
        Self {
            sampling: Sampling::Nearest,
            skip_empty: true,
            window: [0.0, 1.0],
        }
    }
}

/// A placed voxel volume with its transfer function.
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    dims: [u32; 3],
    spacing: Vec3,
    data: VolumeData,
    /// Object to world.
    transform: Affine3A,
    /// World to object.
    inverse: Affine3A,
    /// Dimensions of the coarse grid (blocks of [`SKIP_BLOCK`]^3 voxels).
    coarse_dims: [u32; 3],
    /// `[min, max]` of the values that sampling inside each block can return (the block
    /// and a one-voxel apron, which trilinear interpolation reaches into).
    coarse: Vec<[f32; 2]>,
    transfer: TransferFunction,
    params: VolumeParams,
}

/// The result of integrating one ray through the volumes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeSample {
    /// Whether the ray crossed any voxel (before the surface).
    pub crossed: bool,
    /// Maximum value met (maximum-intensity projection).
    pub max: f32,
    /// Colour accumulated front to back (premultiplied by opacity).
    pub color: Vec3,
    /// Transmittance left (1: nothing absorbed).
    pub transmittance: f32,
}

impl Default for VolumeSample {
    fn default() -> Self {
        Self {
            crossed: false,
            max: f32::NEG_INFINITY,
            color: Vec3::ZERO,
            transmittance: 1.0,
        }
    }
}

/// Checks volume dimensions before anything is allocated.
///
/// # Errors
/// Zero dimensions or more than [`MAX_VOLUME_VOXELS`] voxels.
pub fn check_volume_dims(dims: [u32; 3]) -> Result<u64, SceneError> {
    if dims.contains(&0) {
        return Err(SceneError::Invalid(format!(
            "volume of {} x {} x {} voxels is empty",
            dims[0], dims[1], dims[2]
        )));
    }
    // In u128: three u32 sides multiply to at most 2^96, which u64 would wrap (a wrapped
    // product could pass the limit).
    let n = dims.iter().map(|&d| u128::from(d)).product::<u128>();
    if n > u128::from(MAX_VOLUME_VOXELS) {
        return Err(SceneError::TooLarge(format!(
            "volume of {} x {} x {} = {n} voxels exceeds the limit of {MAX_VOLUME_VOXELS}",
            dims[0], dims[1], dims[2]
        )));
    }
    Ok(n as u64)
}

impl Volume {
    /// A volume of `dims` voxels (x fastest, then y, then z), each `spacing` object units
    /// wide, placed by `transform`.
    ///
    /// # Errors
    /// Bad dimensions ([`check_volume_dims`]), a data length that does not match, NaN or
    /// infinite values, a spacing that is not positive and finite, a singular or
    /// non-finite transform.
    pub fn new(
        dims: [u32; 3],
        spacing: Vec3,
        data: VolumeData,
        transform: Affine3A,
        transfer: TransferFunction,
        params: VolumeParams,
    ) -> Result<Self, SceneError> {
        let n = check_volume_dims(dims)?;
        if data.len() as u64 != n {
            return Err(SceneError::Invalid(format!(
                "volume of {} x {} x {} voxels needs {n} values, got {}",
                dims[0],
                dims[1],
                dims[2],
                data.len()
            )));
        }
        if let VolumeData::F32(v) = &data
            && let Some(i) = v.iter().position(|x| !x.is_finite())
        {
            return Err(SceneError::NonFinite(format!("voxel {}", i + 1)));
        }
        if !(spacing.is_finite() && spacing.min_element() > 0.0) {
            return Err(SceneError::Invalid(format!(
                "voxel spacing {spacing} must be positive and finite"
            )));
        }
        let det = transform.matrix3.determinant();
        if !(transform.matrix3.is_finite() && transform.translation.is_finite())
            || det == 0.0
            || !det.is_finite()
        {
            return Err(SceneError::Invalid(
                "volume transform must be finite and invertible".into(),
            ));
        }
        if !(params.window[0].is_finite()
            && params.window[1].is_finite()
            && params.window[0] < params.window[1])
        {
            return Err(SceneError::Invalid(
                "volume window must be two finite increasing values".into(),
            ));
        }
        let coarse_dims = dims.map(|d| d.div_ceil(SKIP_BLOCK));
        let mut v = Self {
            dims,
            spacing,
            data,
            transform,
            inverse: transform.inverse(),
            coarse_dims,
            coarse: Vec::new(),
            transfer,
            params,
        };
        v.build_coarse();
        Ok(v)
    }

    /// The same volume with other options.
    #[must_use]
    pub fn with_params(mut self, params: VolumeParams) -> Self {
        self.params = params;
        self
    }

    /// The options.
    #[must_use]
    pub fn params(&self) -> VolumeParams {
        self.params
    }

    /// Voxels along x, y and z.
    #[must_use]
    pub fn dims(&self) -> [u32; 3] {
        self.dims
    }

    /// Bytes held (values and the coarse grid).
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.data.bytes() + self.coarse.len() * 8
    }

    /// Object units per grid unit along each axis.
    #[must_use]
    pub fn spacing(&self) -> Vec3 {
        self.spacing
    }

    /// The world-to-object transform.
    #[must_use]
    pub fn inverse(&self) -> Affine3A {
        self.inverse
    }

    /// The transfer function.
    #[must_use]
    pub fn transfer(&self) -> &TransferFunction {
        &self.transfer
    }

    /// The coarse min-max grid of empty-space skipping: its dimensions (blocks of
    /// [`SKIP_BLOCK`]^3 voxels) and `[min, max]` per block, x fastest (for ports of
    /// [`Self::integrate`]).
    #[must_use]
    pub fn coarse(&self) -> ([u32; 3], &[[f32; 2]]) {
        (self.coarse_dims, &self.coarse)
    }

    /// The object-space box.
    #[must_use]
    pub fn object_box(&self) -> Aabb {
        let half = Vec3::new(
            self.dims[0] as f32,
            self.dims[1] as f32,
            self.dims[2] as f32,
        ) * self.spacing
            * 0.5;
        Aabb::new(-half, half)
    }

    /// The world-space bounding box.
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        let b = self.object_box();
        Aabb::from_points((0..8).map(|c| {
            let p = Vec3::new(
                if c & 1 == 0 { b.min.x } else { b.max.x },
                if c & 2 == 0 { b.min.y } else { b.max.y },
                if c & 4 == 0 { b.min.z } else { b.max.z },
            );
            self.transform.transform_point3(p)
        }))
    }

    #[inline]
    fn index(&self, c: [u32; 3]) -> usize {
        (c[2] as usize * self.dims[1] as usize + c[1] as usize) * self.dims[0] as usize
            + c[0] as usize
    }

    /// The value of voxel `c`.
    #[inline]
    #[must_use]
    pub fn voxel(&self, c: [u32; 3]) -> f32 {
        self.data.get(self.index(c))
    }

    /// Trilinear interpolation at grid point `p` (voxel centres at `i + 0.5`), clamped at
    /// the borders.
    #[must_use]
    pub fn trilinear(&self, p: Vec3) -> f32 {
        let q = p - 0.5;
        let mut i0 = [0u32; 3];
        let mut i1 = [0u32; 3];
        let mut f = [0.0f32; 3];
        for a in 0..3 {
            let max = self.dims[a] as f32 - 1.0;
            let x = q[a].clamp(0.0, max);
            let fl = x.floor();
            i0[a] = fl as u32;
            i1[a] = (i0[a] + 1).min(self.dims[a] - 1);
            f[a] = x - fl;
        }
        let v = |x: u32, y: u32, z: u32| self.voxel([x, y, z]);
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let c00 = lerp(v(i0[0], i0[1], i0[2]), v(i1[0], i0[1], i0[2]), f[0]);
        let c10 = lerp(v(i0[0], i1[1], i0[2]), v(i1[0], i1[1], i0[2]), f[0]);
        let c01 = lerp(v(i0[0], i0[1], i1[2]), v(i1[0], i0[1], i1[2]), f[0]);
        let c11 = lerp(v(i0[0], i1[1], i1[2]), v(i1[0], i1[1], i1[2]), f[0]);
        lerp(lerp(c00, c10, f[1]), lerp(c01, c11, f[1]), f[2])
    }

    fn build_coarse(&mut self) {
        let [cx, cy, cz] = self.coarse_dims;
        let b = SKIP_BLOCK;
        let mut out = Vec::with_capacity((cx * cy * cz) as usize);
        for bz in 0..cz {
            for by in 0..cy {
                for bx in 0..cx {
                    let lo = [bx, by, bz].map(|c| (c * b).saturating_sub(1));
                    let hi = [bx, by, bz]
                        .iter()
                        .zip(&self.dims)
                        .map(|(&c, &d)| ((c + 1) * b + 1).min(d))
                        .collect::<Vec<_>>();
                    let mut r = [f32::INFINITY, f32::NEG_INFINITY];
                    for z in lo[2]..hi[2] {
                        for y in lo[1]..hi[1] {
                            for x in lo[0]..hi[0] {
                                let v = self.voxel([x, y, z]);
                                r = [r[0].min(v), r[1].max(v)];
                            }
                        }
                    }
                    out.push(r);
                }
            }
        }
        self.coarse = out;
    }

    /// The ray in grid units (`o + t d`, same `t` as the world ray) and the interval
    /// `[t0, t1]` where it is inside the grid, clipped to `[ray.t_min, t_max]`.
    #[must_use]
    pub fn grid_ray(&self, ray: &Ray, t_max: f32) -> Option<(Vec3, Vec3, f32, f32)> {
        let o = self.inverse.transform_point3(ray.origin);
        let d = self.inverse.transform_vector3(ray.dir);
        let b = self.object_box();
        let inv_s = self.spacing.recip();
        let go = (o - b.min) * inv_s;
        let gd = d * inv_s;
        // NaN or infinite rays, and zero directions (which never leave), cross nothing.
        if !(go.is_finite() && gd.is_finite()) || gd == Vec3::ZERO {
            return None;
        }
        let dims = Vec3::new(
            self.dims[0] as f32,
            self.dims[1] as f32,
            self.dims[2] as f32,
        );
        let (mut t0, mut t1) = (ray.t_min, t_max);
        for a in 0..3 {
            if gd[a] == 0.0 {
                if !(go[a] >= 0.0 && go[a] <= dims[a]) {
                    return None;
                }
                continue;
            }
            let (ta, tb) = ((0.0 - go[a]) / gd[a], (dims[a] - go[a]) / gd[a]);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        (t0 < t1 && t1.is_finite()).then_some((go, gd, t0, t1))
    }

    /// Integrates `ray` through this volume over `[ray.t_min, t_max]` (`t_max`: the
    /// surface hit, or the ray's end), updating `acc`. Maximum-intensity projection and
    /// compositing are both accumulated; `composite` enables early termination.
    pub fn integrate(&self, ray: &Ray, t_max: f32, composite: bool, acc: &mut VolumeSample) {
        let Some((go, gd, t0, t1)) = self.grid_ray(ray, t_max) else {
            return;
        };
        let world_len = ray.dir.length();
        let seg = Segment {
            volume: self,
            go,
            gd,
            world_len,
            composite,
        };
        if !self.params.skip_empty {
            self.walk_voxels((go, gd, t0, t1), |c, ta, tb| seg.visit(acc, c, ta, tb));
            return;
        }
        // Empty-space skipping: walk the coarse grid; enter a block's voxels only when it
        // can contribute (compositing: some extinction in its value range; MIP: a value
        // above the maximum so far).
        let scale = 1.0 / SKIP_BLOCK as f32;
        let _ = crate::dda(
            self.coarse_dims,
            go * scale,
            gd * scale,
            t0,
            t1,
            &mut segments(|blk, ta, tb| {
                let i = (blk[2] as usize * self.coarse_dims[1] as usize + blk[1] as usize)
                    * self.coarse_dims[0] as usize
                    + blk[0] as usize;
                let [lo, hi] = self.coarse[i];
                let skip = if composite {
                    self.transfer.max_sigma(lo, hi) == 0.0
                } else {
                    hi <= acc.max
                };
                if skip {
                    acc.crossed = true;
                    return ControlFlow::Continue(());
                }
                // The voxels of this block along [ta, tb].
                let lo_c = blk.map(|c| c * SKIP_BLOCK);
                let sub = [0, 1, 2].map(|a| (self.dims[a] - lo_c[a]).min(SKIP_BLOCK));
                let origin = go - Vec3::new(lo_c[0] as f32, lo_c[1] as f32, lo_c[2] as f32);
                crate::dda(
                    sub,
                    origin,
                    gd,
                    ta,
                    tb,
                    &mut segments(|c, sa, sb| {
                        seg.visit(
                            acc,
                            [c[0] + lo_c[0], c[1] + lo_c[1], c[2] + lo_c[2]],
                            sa,
                            sb,
                        )
                    }),
                )
            }),
        );
    }

    /// Every voxel the ray crosses inside `[ray.t_min, t_max]`, in order, with its segment
    /// (the plain 3D-DDA, for tests and tools).
    #[must_use]
    pub fn voxels_crossed(&self, ray: &Ray, t_max: f32) -> Vec<([u32; 3], f32, f32)> {
        let mut out = Vec::new();
        if let Some(grid_ray) = self.grid_ray(ray, t_max) {
            self.walk_voxels(grid_ray, |c, a, b| {
                out.push((c, a, b));
                ControlFlow::Continue(())
            });
        }
        out
    }

    /// The plain 3D-DDA over every voxel along a ray in grid units (`grid_ray`'s answer),
    /// calling `visit(voxel, t_enter, t_exit)` for each segment of non-zero length.
    fn walk_voxels(
        &self,
        (go, gd, t0, t1): (Vec3, Vec3, f32, f32),
        visit: impl FnMut([u32; 3], f32, f32) -> ControlFlow<()>,
    ) {
        let _ = crate::dda(self.dims, go, gd, t0, t1, &mut segments(visit));
    }

    /// The grid coordinates of world point `p`.
    #[must_use]
    pub fn grid_point(&self, p: Vec3) -> Vec3 {
        (self.inverse.transform_point3(p) - self.object_box().min) * self.spacing.recip()
    }
}

/// What one ray's integration through one volume needs per voxel segment.
struct Segment<'a> {
    volume: &'a Volume,
    go: Vec3,
    gd: Vec3,
    world_len: f32,
    composite: bool,
}

impl Segment<'_> {
    /// Accumulates voxel `c` over `[ta, tb]`; breaks once compositing is opaque.
    #[inline]
    fn visit(&self, acc: &mut VolumeSample, c: [u32; 3], ta: f32, tb: f32) -> ControlFlow<()> {
        let v = match self.volume.params.sampling {
            Sampling::Nearest => self.volume.voxel(c),
            Sampling::Trilinear => self.volume.trilinear(self.go + self.gd * (0.5 * (ta + tb))),
        };
        acc.crossed = true;
        acc.max = acc.max.max(v);
        if self.composite {
            let (color, sigma) = self.volume.transfer.eval(v);
            let alpha = 1.0 - (-sigma * (tb - ta) * self.world_len).exp();
            acc.color += color * (alpha * acc.transmittance);
            acc.transmittance *= 1.0 - alpha;
            if acc.transmittance < 1.0 - EARLY_TERMINATION {
                return ControlFlow::Break(());
            }
        }
        ControlFlow::Continue(())
    }
}

/// A 3D-DDA visitor ([`crate::dda()`]) that skips the cells a ray crosses for a zero length
/// (through an edge or a corner): they hold no segment to integrate.
fn segments(
    mut visit: impl FnMut([u32; 3], f32, f32) -> ControlFlow<()>,
) -> impl FnMut([u32; 3], f32, f32) -> ControlFlow<()> {
    move |c, ta, tb| {
        if tb > ta {
            visit(c, ta, tb)
        } else {
            ControlFlow::Continue(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{pcg3d, to_unit_f32};
    use std::collections::BTreeSet;

    fn random_volume(dims: [u32; 3]) -> Volume {
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        let data = (0..n as u32)
            .map(|i| to_unit_f32(pcg3d([i, 3, 3])[0]))
            .collect();
        Volume::new(
            dims,
            Vec3::new(0.5, 0.25, 0.4),
            VolumeData::F32(data),
            Affine3A::from_rotation_y(0.3),
            TransferFunction::ramp(4.0),
            VolumeParams::default(),
        )
        .unwrap()
    }

    fn random_ray(v: &Volume, k: u32) -> Ray {
        let u = |d| to_unit_f32(pcg3d([k, 9, d])[0]);
        let b = v.bounds();
        let o = b.center() + (Vec3::new(u(0), u(1), u(2)) * 2.0 - 1.0) * b.extent();
        let target = b.center() + (Vec3::new(u(3), u(4), u(5)) - 0.5) * b.extent();
        let mut dir = target - o;
        if k.is_multiple_of(5) {
            dir.y = 0.0;
        }
        Ray::new(o, dir)
    }

    #[test]
    fn dda_visits_exactly_the_cells_a_dense_sampler_finds() {
        let v = random_volume([13, 7, 9]);
        for k in 0..400 {
            let ray = random_ray(&v, k);
            let cells = v.voxels_crossed(&ray, f32::INFINITY);
            // Consecutive cells are face neighbours, segments are contiguous.
            for w in cells.windows(2) {
                let diff: u32 = (0..3).map(|a| w[0].0[a].abs_diff(w[1].0[a])).sum();
                assert_eq!(diff, 1, "ray {k}: {:?} -> {:?}", w[0], w[1]);
                assert_eq!(w[0].2, w[1].1);
            }
            let dda: BTreeSet<[u32; 3]> = cells.iter().map(|c| c.0).collect();
            let Some((go, gd, t0, t1)) = v.grid_ray(&ray, f32::INFINITY) else {
                assert!(cells.is_empty());
                continue;
            };
            // Brute force: 20,000 points along [t0, t1] in grid coordinates.
            let n = 20_000;
            let mut sampled = BTreeSet::new();
            for s in 0..n {
                let t = t0 + (t1 - t0) * (s as f32 + 0.5) / n as f32;
                let p = go + gd * t;
                let c = [0, 1, 2].map(|a| (p[a].floor().max(0.0) as u32).min(v.dims[a] - 1));
                sampled.insert(c);
            }
            // Every sampled cell is visited; every visited cell crossed for more than a
            // few sample spacings is sampled.
            assert!(
                sampled.is_subset(&dda),
                "ray {k}: {:?}",
                sampled.difference(&dda)
            );
            let spacing = (t1 - t0) / n as f32;
            for (c, a, b) in &cells {
                if b - a > 3.0 * spacing {
                    assert!(sampled.contains(c), "ray {k}: {c:?} ({a}, {b})");
                }
            }
        }
    }

    #[test]
    fn skipping_changes_nothing() {
        let plain = random_volume([20, 17, 11]).with_params(VolumeParams {
            skip_empty: false,
            ..VolumeParams::default()
        });
        // Mostly empty: zero everywhere but a few bright voxels.
        let mut data = vec![0.0f32; 20 * 17 * 11];
        for (i, x) in data.iter_mut().enumerate() {
            if i % 97 == 0 {
                *x = 0.8;
            }
        }
        for sampling in [Sampling::Nearest, Sampling::Trilinear] {
            let mk = |skip| {
                Volume::new(
                    [20, 17, 11],
                    Vec3::ONE,
                    VolumeData::F32(data.clone()),
                    Affine3A::IDENTITY,
                    TransferFunction::ramp(3.0),
                    VolumeParams {
                        sampling,
                        skip_empty: skip,
                        ..VolumeParams::default()
                    },
                )
                .unwrap()
            };
            let (a, b) = (mk(false), mk(true));
            for k in 0..500 {
                let ray = random_ray(&a, k);
                for composite in [false, true] {
                    let (mut x, mut y) = (VolumeSample::default(), VolumeSample::default());
                    a.integrate(&ray, f32::INFINITY, composite, &mut x);
                    b.integrate(&ray, f32::INFINITY, composite, &mut y);
                    // The block walk starts each block's first segment at the block border
                    // computed in coarse units, so lengths differ in the last bits.
                    assert!((x.color - y.color).abs().max_element() < 1e-5, "ray {k}");
                    assert!((x.transmittance - y.transmittance).abs() < 1e-5, "ray {k}");
                    assert_eq!(x.crossed, y.crossed, "ray {k}");
                    if !composite {
                        assert!((x.max.max(0.0) - y.max.max(0.0)).abs() < 1e-5, "ray {k}");
                    }
                }
            }
        }
        assert!(plain.memory_bytes() > 0);
    }

    #[test]
    fn beer_lambert_through_a_homogeneous_block() {
        let sigma = 2.5;
        let tf = TransferFunction::new(vec![TransferPoint {
            value: 0.0,
            color: Vec3::ONE,
            sigma,
        }])
        .unwrap();
        let v = Volume::new(
            [8, 8, 8],
            Vec3::splat(0.25),
            VolumeData::U8(vec![100; 512]),
            Affine3A::IDENTITY,
            tf,
            VolumeParams::default(),
        )
        .unwrap();
        for k in 0..200 {
            let ray = random_ray(&v, k);
            let Some((_, _, t0, t1)) = v.grid_ray(&ray, f32::INFINITY) else {
                continue;
            };
            let length = (t1 - t0) * ray.dir.length();
            let mut acc = VolumeSample::default();
            v.integrate(&ray, f32::INFINITY, true, &mut acc);
            let expected = (-sigma * length).exp();
            if expected > 1.0 - EARLY_TERMINATION {
                assert!(
                    (acc.transmittance - expected).abs() < 1e-4,
                    "ray {k}: {} vs {expected}",
                    acc.transmittance
                );
                // White emission: colour = 1 - transmittance.
                assert!((acc.color.x - (1.0 - expected)).abs() < 1e-4);
            }
        }
    }

    #[test]
    fn degenerate_rays_cross_nothing() {
        let v = random_volume([4, 4, 4]);
        for ray in [
            Ray::new(Vec3::ZERO, Vec3::ZERO),
            Ray::new(Vec3::splat(f32::NAN), Vec3::X),
            Ray::new(Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 1.0)),
            Ray::new(
                Vec3::new(0.0, 0.0, -10.0),
                Vec3::new(0.0, 0.0, f32::INFINITY),
            ),
        ] {
            let mut acc = VolumeSample::default();
            v.integrate(&ray, f32::INFINITY, true, &mut acc);
            assert_eq!(acc, VolumeSample::default(), "{ray:?}");
        }
        // A ray starting inside and going along an axis crosses to the border.
        let inside = v.voxels_crossed(&Ray::new(Vec3::ZERO, Vec3::X), f32::INFINITY);
        assert!(!inside.is_empty());
    }

    #[test]
    fn bad_volumes_are_refused() {
        let tf = || TransferFunction::ramp(1.0);
        let p = VolumeParams::default();
        let ok = |d: VolumeData, s: Vec3| {
            Volume::new([2, 2, 2], s, d, Affine3A::IDENTITY, tf(), p).is_ok()
        };
        assert!(ok(VolumeData::U8(vec![0; 8]), Vec3::ONE));
        assert!(!ok(VolumeData::U8(vec![0; 7]), Vec3::ONE));
        assert!(!ok(VolumeData::F32(vec![f32::NAN; 8]), Vec3::ONE));
        assert!(!ok(VolumeData::U8(vec![0; 8]), Vec3::new(1.0, 0.0, 1.0)));
        assert!(check_volume_dims([100_000, 100_000, 100_000]).is_err());
        assert!(check_volume_dims([0, 1, 1]).is_err());
        assert!(TransferFunction::new(vec![]).is_err());
        let pt = |value| TransferPoint {
            value,
            color: Vec3::ONE,
            sigma: 1.0,
        };
        assert!(TransferFunction::new(vec![pt(0.5), pt(0.5)]).is_err());
        assert!(TransferFunction::new(vec![pt(f32::NAN)]).is_err());
        let singular = Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0));
        assert!(
            Volume::new(
                [1, 1, 1],
                Vec3::ONE,
                VolumeData::U8(vec![0]),
                singular,
                tf(),
                p
            )
            .is_err()
        );
    }

    #[test]
    fn transfer_function_interpolates_and_bounds() {
        let tf = TransferFunction::new(vec![
            TransferPoint {
                value: 0.2,
                color: Vec3::ZERO,
                sigma: 0.0,
            },
            TransferPoint {
                value: 0.4,
                color: Vec3::ONE,
                sigma: 10.0,
            },
            TransferPoint {
                value: 0.6,
                color: Vec3::ONE,
                sigma: 0.0,
            },
        ])
        .unwrap();
        assert_eq!(tf.eval(0.0).1, 0.0);
        assert!((tf.eval(0.3).1 - 5.0).abs() < 1e-5);
        assert_eq!(tf.eval(0.9).1, 0.0);
        assert_eq!(tf.max_sigma(0.0, 0.2), 0.0);
        assert_eq!(tf.max_sigma(0.3, 0.5), 10.0);
        assert_eq!(tf.max_sigma(0.6, 1.0), 0.0);
    }
}
