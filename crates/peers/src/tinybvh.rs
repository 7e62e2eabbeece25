//! Jacco Bikker's tinybvh behind raybench's [`Accel`] (feature `tinybvh`): its `BVH4_CPU`
//! and `BVH8_CPU` layouts, each built by tinybvh's own builder and traced with its own
//! single-ray kernels.
//!
//! tinybvh is a single C++ header. The `tinybvh-rs` crate's Rust API does not match the
//! header's structure layouts, so it is not used: `build.rs` compiles `tinybvh_shim.cpp`, a
//! small C interface of our own, against the header that crate ships (tinybvh 1.6.8), and
//! this module calls that interface with plain floats and integers, never a tinybvh type.
//! Every `unsafe` block is such a call and says why it is sound.
//!
//! The kernels are compiled for AVX2 and FMA: [`availability`] refuses a CPU without them
//! (or another architecture), and nothing calls into tinybvh then.

// The workspace denies `unsafe_code`; this module is the FFI boundary.
#![allow(unsafe_code)]

use raybench_geometry::{
    Accel, AccelStats, Counters, Geometry, Hit, PrimHit, PrimitiveKind, QualityParams, Ray, Shape,
    StructureQuality, keep_closer,
};
use std::sync::Arc;

/// The tinybvh release compiled in.
pub const VERSION: &str = "tinybvh 1.6.8";

/// Which of tinybvh's CPU layouts a [`TinyBvhAccel`] traces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TinyBvhLayout {
    /// `BVH4_CPU`: 4-wide nodes, SSE box tests over four children and four triangles per
    /// leaf.
    Bvh4,
    /// `BVH8_CPU`: 8-wide nodes tested with AVX2, four triangles per leaf.
    Bvh8,
}

impl TinyBvhLayout {
    /// Both layouts, the narrower first.
    pub const ALL: [Self; 2] = [Self::Bvh4, Self::Bvh8];

    /// tinybvh's name of the layout: `"BVH4_CPU"` or `"BVH8_CPU"`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Bvh4 => "BVH4_CPU",
            Self::Bvh8 => "BVH8_CPU",
        }
    }

    /// Children per node: 4 or 8.
    #[must_use]
    pub fn width(self) -> u32 {
        match self {
            Self::Bvh4 => 4,
            Self::Bvh8 => 8,
        }
    }
}

/// The shim's C interface (`tinybvh_shim.cpp`).
#[cfg(target_arch = "x86_64")]
mod ffi {
    use std::ffi::c_void;

    unsafe extern "C" {
        pub fn raybench_tinybvh_build(width: u32, triangles: *const f32, count: u32)
        -> *mut c_void;
        pub fn raybench_tinybvh_free(accel: *mut c_void);
        pub fn raybench_tinybvh_bytes(accel: *const c_void) -> u64;
        pub fn raybench_tinybvh_intersect(
            accel: *const c_void,
            origin: *const f32,
            dir: *const f32,
            t_max: f32,
            t: *mut f32,
            u: *mut f32,
            v: *mut f32,
            prim: *mut u32,
        ) -> i32;
        pub fn raybench_tinybvh_occluded(
            accel: *const c_void,
            origin: *const f32,
            dir: *const f32,
            t_max: f32,
        ) -> i32;
    }
}

/// Whether tinybvh's kernels run on a CPU with these features: AVX2 and FMA both.
///
/// # Errors
/// Which feature is missing, and why it matters.
pub fn availability_with(avx2: bool, fma: bool) -> Result<(), String> {
    let missing: Vec<&str> = [("AVX2", avx2), ("FMA", fma)]
        .into_iter()
        .filter(|&(_, has)| !has)
        .map(|(name, _)| name)
        .collect();
    if missing.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "this CPU lacks {}: raybench compiles tinybvh's BVH4_CPU and BVH8_CPU kernels for \
             AVX2 and FMA",
            missing.join(" and ")
        ))
    }
}

/// Whether tinybvh runs here: an x86-64 CPU with AVX2 and FMA ([`availability_with`]), or
/// why not. Nothing calls into tinybvh when this is an error.
///
/// # Errors
/// The reason tinybvh cannot run.
pub fn availability() -> Result<(), String> {
    #[cfg(target_arch = "x86_64")]
    {
        availability_with(
            std::arch::is_x86_feature_detected!("avx2"),
            std::arch::is_x86_feature_detected!("fma"),
        )
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        Err(format!(
            "tinybvh's BVH4_CPU and BVH8_CPU kernels are x86-64 code (AVX2 and FMA); this is {}",
            std::env::consts::ARCH
        ))
    }
}

/// Whether the tinybvh backends support `geometry`: triangles, and planes (kept beside the
/// structure and tested by every ray). tinybvh is a triangle BVH; raybench gives it no
/// other primitive.
///
/// # Errors
/// How many bounded primitives are not triangles.
pub fn supports(geometry: &Geometry) -> Result<(), String> {
    let others = geometry
        .bounded()
        .iter()
        .filter(|&&id| geometry.shape(id).kind() != PrimitiveKind::Triangle)
        .count();
    if others > 0 {
        // Every bounded kind but the triangle, by name, so a new kind joins the message.
        let kinds: Vec<&str> = PrimitiveKind::ALL
            .iter()
            .filter(|&&k| !matches!(k, PrimitiveKind::Triangle | PrimitiveKind::Plane))
            .map(|k| k.name())
            .collect();
        return Err(format!(
            "{others} bounded primitives that are not triangles ({}): the tinybvh backends \
             trace triangles only (and planes beside them)",
            kinds.join(", ")
        ));
    }
    Ok(())
}

/// A structure the shim built, freed on drop.
struct Handle(std::ptr::NonNull<std::ffi::c_void>);

// SAFETY: the structure is never modified after its build; tinybvh's Intersect and
// IsOccluded are const methods that keep their state (stack, ray) on the caller's stack,
// so any number of threads may trace through it at once, and it may be freed from any
// thread.
unsafe impl Send for Handle {}
// SAFETY: as above.
unsafe impl Sync for Handle {}

impl Drop for Handle {
    fn drop(&mut self) {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the pointer came from raybench_tinybvh_build and is freed exactly once.
        unsafe {
            ffi::raybench_tinybvh_free(self.0.as_ptr());
        }
    }
}

/// One of tinybvh's CPU layouts ([`TinyBvhLayout`]) over the scene's triangles: the peers
/// `tinybvh4` and `tinybvh8` of the peer benchmark.
///
/// **Build.** The triangles go to tinybvh in id order (three vertices of their own each,
/// padded to four floats as tinybvh wants), and its `BVH4_CPU::Build` / `BVH8_CPU::Build`
/// makes the tree: tinybvh's binned SAH builder (`BuildAVX`) makes a binary BVH, which
/// tinybvh collapses into a 4- or 8-wide one and converts into the traversal layout; the
/// whole of it is the build (timed as such). tinybvh builds meshes of 50,000 triangles or
/// more on a thread pool of its own, one thread per core, and raybench serialises tinybvh
/// builds (tinybvh creates that pool lazily without a lock).
///
/// **Tracing.** `Intersect` / `IsOccluded` per ray (a batch is a loop over its rays).
/// tinybvh's rays keep raybench's direction unnormalised, so its `t` is raybench's.
/// tinybvh's rays have no `t_min`: they accept hits with `0 < t < t_max`. A ray with
/// `t_min > 0` is handed to tinybvh from `origin + t_min dir` with `t_max - t_min`, and its
/// hit's `t` shifted back by `t_min` (rounded twice, so a hit at the interval's ends may
/// come or go); a negative `t_min` counts as 0, and hits at exactly `t_min` or `t_max` are
/// not reported. Rays that can hit nothing (NaN, infinite or zero direction or origin,
/// empty interval) never reach tinybvh, which stops the process on a NaN ray.
///
/// Planes are tested first ([`Geometry::closest_unbounded`]) and tinybvh's `t_max`
/// clipped to their hit; bounded primitives that are not triangles ([`supports`] refuses
/// them for the renderer) are tested beside tinybvh by every ray. tinybvh's hit (`t`, its
/// barycentrics `u`, `v` of vertices 1 and 2, the triangle mapped back to the raybench id)
/// is completed with [`Geometry::complete`], so normals are raybench's.
///
/// Not bound by the equivalence contract: tinybvh tests triangles with its own
/// Moeller-Trumbore routine (with an approximate reciprocal of the determinant), not
/// watertight, and its traversal keeps the first of equal hits, so its `t` differs from
/// raybench's in the last bits, a ray through an edge may report the neighbouring triangle
/// or slip through, and the peer benchmark counts the rays that differ from `bvh`.
/// tinybvh counts no tests: the counters see only the planes and side primitives.
pub struct TinyBvhAccel {
    geometry: Arc<Geometry>,
    layout: TinyBvhLayout,
    /// tinybvh's structure over the triangles; `None` when there are none.
    handle: Option<Handle>,
    /// Raybench id of each triangle tinybvh holds (tinybvh's `prim`).
    ids: Vec<u32>,
    /// Bounded primitives tinybvh does not hold, tested by every ray.
    side: Vec<u32>,
    /// Bytes of tinybvh's traversal layout.
    tree_bytes: u64,
}

impl TinyBvhAccel {
    /// The structure over `geometry` in `layout` ([`Accel::build`]: [`TinyBvhLayout::Bvh8`]).
    ///
    /// # Panics
    /// When tinybvh is unavailable ([`availability`]), the scene has `2^32` triangles or
    /// more, or tinybvh cannot allocate its structure.
    #[must_use]
    pub fn build_with(geometry: Arc<Geometry>, layout: TinyBvhLayout) -> Self {
        let mut ids = Vec::new();
        let mut side = Vec::new();
        for &id in geometry.bounded() {
            match geometry.shape(id) {
                Shape::Triangle(_) => ids.push(id),
                _ => side.push(id),
            }
        }
        let mut tree_bytes = 0;
        let handle = if ids.is_empty() {
            None
        } else {
            if let Err(e) = availability() {
                panic!("tinybvh is unavailable: {e}");
            }
            let handle = build_tree(&geometry, &ids, layout);
            tree_bytes = tree_size(&handle);
            Some(handle)
        };
        Self {
            geometry,
            layout,
            handle,
            ids,
            side,
            tree_bytes,
        }
    }

    /// The layout traced.
    #[must_use]
    pub fn layout(&self) -> TinyBvhLayout {
        self.layout
    }

    /// Planes and side primitives: the best hit tinybvh must improve on.
    fn closest_beside<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<(u32, PrimHit)> {
        crate::closest_beside(&self.geometry, &self.side, ray, counters)
    }

    /// Whether a plane or a side primitive is hit.
    fn occluded_beside<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        crate::occluded_beside(&self.geometry, &self.side, ray, counters)
    }
}

/// The ray tinybvh traces for `ray` up to `t_max`: origin, direction, tinybvh's `t_max` and
/// the offset its `t` is measured from; `None` when the ray can hit nothing (invalid, a NaN
/// bound, an empty interval, or an origin moved to infinity).
#[inline]
fn tiny_ray(ray: &Ray, t_max: f32) -> Option<([f32; 3], [f32; 3], f32, f32)> {
    if !ray.is_valid() || ray.t_min.is_nan() {
        return None;
    }
    let t_min = ray.t_min.max(0.0);
    if t_max.is_nan() || t_min > t_max {
        return None;
    }
    let origin = if t_min > 0.0 {
        ray.origin + t_min * ray.dir
    } else {
        ray.origin
    };
    if !origin.is_finite() {
        return None;
    }
    Some((origin.to_array(), ray.dir.to_array(), t_max - t_min, t_min))
}

#[cfg(target_arch = "x86_64")]
fn build_tree(geometry: &Geometry, ids: &[u32], layout: TinyBvhLayout) -> Handle {
    let count = u32::try_from(ids.len()).expect("tinybvh takes fewer than 2^32 triangles");
    let mut flat = Vec::with_capacity(9 * ids.len());
    for &id in ids {
        let Shape::Triangle(tri) = geometry.shape(id) else {
            unreachable!("only triangles go to tinybvh")
        };
        for v in &tri.v {
            flat.extend_from_slice(&v.to_array());
        }
    }
    // SAFETY: `flat` holds 9 floats per triangle for `count` triangles and outlives the
    // call (the shim copies them); the width is 4 or 8. A null result is checked.
    let ptr = unsafe { ffi::raybench_tinybvh_build(layout.width(), flat.as_ptr(), count) };
    Handle(
        std::ptr::NonNull::new(ptr)
            .unwrap_or_else(|| panic!("tinybvh failed to build its {}", layout.name())),
    )
}

#[cfg(not(target_arch = "x86_64"))]
fn build_tree(_: &Geometry, _: &[u32], _: TinyBvhLayout) -> Handle {
    unreachable!("availability() refuses every architecture but x86-64")
}

#[cfg(target_arch = "x86_64")]
fn tree_size(handle: &Handle) -> u64 {
    // SAFETY: a live structure from raybench_tinybvh_build.
    unsafe { ffi::raybench_tinybvh_bytes(handle.0.as_ptr()) }
}

#[cfg(not(target_arch = "x86_64"))]
fn tree_size(_: &Handle) -> u64 {
    0
}

/// tinybvh's closest hit on the tiny ray: `t` in its own frame, `u`, `v` and the triangle.
#[cfg(target_arch = "x86_64")]
#[inline]
fn tiny_intersect(
    handle: &Handle,
    origin: &[f32; 3],
    dir: &[f32; 3],
    t_max: f32,
) -> Option<(f32, f32, f32, u32)> {
    let (mut t, mut u, mut v, mut prim) = (0.0, 0.0, 0.0, 0);
    // SAFETY: a live structure; origin and dir hold 3 finite floats each (`tiny_ray`) and
    // `t_max` is not NaN, as tinybvh requires; the out-pointers are valid for the call.
    let hit = unsafe {
        ffi::raybench_tinybvh_intersect(
            handle.0.as_ptr(),
            origin.as_ptr(),
            dir.as_ptr(),
            t_max,
            &raw mut t,
            &raw mut u,
            &raw mut v,
            &raw mut prim,
        )
    };
    (hit != 0).then_some((t, u, v, prim))
}

#[cfg(not(target_arch = "x86_64"))]
fn tiny_intersect(_: &Handle, _: &[f32; 3], _: &[f32; 3], _: f32) -> Option<(f32, f32, f32, u32)> {
    unreachable!("no tinybvh structure exists on this architecture")
}

/// Whether tinybvh finds a hit on the tiny ray.
#[cfg(target_arch = "x86_64")]
#[inline]
fn tiny_occluded(handle: &Handle, origin: &[f32; 3], dir: &[f32; 3], t_max: f32) -> bool {
    // SAFETY: as in `tiny_intersect`.
    unsafe {
        ffi::raybench_tinybvh_occluded(handle.0.as_ptr(), origin.as_ptr(), dir.as_ptr(), t_max) != 0
    }
}

#[cfg(not(target_arch = "x86_64"))]
fn tiny_occluded(_: &Handle, _: &[f32; 3], _: &[f32; 3], _: f32) -> bool {
    unreachable!("no tinybvh structure exists on this architecture")
}

/// Why [`Accel::quality`] has no figures for tinybvh: its tree lives in the C++ shim, which
/// reads back no node.
const NOT_READABLE: &str = "tinybvh's tree lives in its C++ layout; the shim reads back no node";

impl Accel for TinyBvhAccel {
    /// # Panics
    /// As [`TinyBvhAccel::build_with`].
    fn build(geometry: Arc<Geometry>) -> Self {
        Self::build_with(geometry, TinyBvhLayout::Bvh8)
    }

    fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        let mut best = self.closest_beside(ray, counters);
        if let Some(handle) = &self.handle
            && let Some((origin, dir, t_max, offset)) =
                tiny_ray(ray, best.map_or(ray.t_max, |(_, h)| h.t))
            && let Some((t, u, v, prim)) = tiny_intersect(handle, &origin, &dir, t_max)
        {
            let id = self.ids[prim as usize];
            keep_closer(
                &mut best,
                id,
                PrimHit {
                    t: t + offset,
                    sub: 0,
                    u,
                    v,
                },
            );
        }
        self.geometry.complete(ray, best)
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        if self.occluded_beside(ray, counters) {
            return true;
        }
        let Some(handle) = &self.handle else {
            return false;
        };
        tiny_ray(ray, ray.t_max)
            .is_some_and(|(origin, dir, t_max, _)| tiny_occluded(handle, &origin, &dir, t_max))
    }

    fn stats(&self) -> AccelStats {
        let n = self.ids.len();
        AccelStats {
            // The traversal layout and the id map; tinybvh also keeps the trees it converted
            // from and a copy of the vertices, not counted.
            memory_bytes: usize::try_from(self.tree_bytes).unwrap_or(usize::MAX)
                + std::mem::size_of_val(self.ids.as_slice()),
            counts: vec![
                ("tinybvh triangles", n as u64),
                ("branching factor", u64::from(self.layout.width())),
                ("side primitives", self.side.len() as u64),
            ],
        }
    }

    fn quality(&self, _params: &QualityParams) -> Option<StructureQuality> {
        Some(StructureQuality::NotReadable(NOT_READABLE))
    }
}
