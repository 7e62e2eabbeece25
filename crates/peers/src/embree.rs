//! Intel Embree 3 behind raybench's [`Accel`] (feature `embree`): backends `embree` (single
//! rays) and `embree-packet` (packets of 16 rays).
//!
//! The `embree` crate's safe wrappers tie scenes to a borrowed device by lifetime, which an
//! accelerator that owns its scene cannot express, so this module speaks to the C API
//! through the crate's raw bindings (`embree::sys`). Every `unsafe` block is an FFI call
//! (or a view of a buffer Embree handed out) and says why it is sound.
//!
//! One Embree device serves the whole process (created on first use, never released):
//! creating a device starts Embree's task system, which no timed build should pay for.

// The workspace denies `unsafe_code`; this module is the FFI boundary.
#![allow(unsafe_code)]

use embree::sys::{
    RTCBufferType, RTCBuildQuality, RTCDevice, RTCDeviceProperty, RTCError, RTCFormat,
    RTCGeometryType, RTCHit, RTCIntersectContext, RTCIntersectContextFlags, RTCRay, RTCRayHit,
    RTCScene, RTCSceneFlags, rtcAttachGeometry, rtcCommitGeometry, rtcCommitScene,
    rtcGetDeviceError, rtcGetDeviceProperty, rtcIntersect1, rtcNewDevice, rtcNewGeometry,
    rtcNewScene, rtcOccluded1, rtcReleaseGeometry, rtcReleaseScene, rtcSetGeometryBuildQuality,
    rtcSetNewGeometryBuffer, rtcSetSceneBuildQuality, rtcSetSceneFlags,
};
use raybench_geometry::{
    Accel, AccelStats, Counters, Geometry, Hit, PrimHit, PrimitiveKind, QualityParams, Ray, Shape,
    StructureQuality, keep_closer,
};
use std::sync::{Arc, OnceLock};

/// Embree's "no geometry" id (`RTC_INVALID_GEOMETRY_ID`).
const INVALID_ID: u32 = u32::MAX;

/// The most bounded primitives other than triangles (spheres) a scene may hold for the
/// Embree backends ([`supports`]): Embree knows only the triangles, and the others are
/// tested by every ray beside its structure, like planes, which is fine for a handful and
/// a brute-force loop beyond.
pub const MAX_SIDE_PRIMITIVES: usize = 64;

/// Rays per packet of [`EmbreePacketAccel`] by default: 16 (`rtcIntersect16` /
/// `rtcOccluded16`), Embree's widest packet; it runs on every CPU (Embree splits it where
/// the CPU's vectors are narrower) and is native with AVX-512.
pub const DEFAULT_PACKET_WIDTH: usize = 16;

/// Embree's scene mode: the scene flags its BVH is built and traversed with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EmbreeMode {
    /// `RTC_SCENE_FLAG_ROBUST`, what the registered backends `embree` and `embree-packet`
    /// use: Embree's watertight triangle test and conservative traversal. Its default
    /// mode lets rays aimed at shared edges and vertices of a closed mesh escape
    /// (tests/tests/watertight.rs: 4,165 of 61,440 from inside an icosphere).
    Robust,
    /// No scene flags: Embree's default mode, faster and not watertight; the figure peers
    /// usually quote (`tests/benches/peers.rs` measures both).
    Default,
}

impl EmbreeMode {
    /// Both modes, robust first.
    pub const ALL: [Self; 2] = [Self::Robust, Self::Default];

    /// `"robust"` or `"default"`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Robust => "robust",
            Self::Default => "default",
        }
    }

    fn flags(self) -> RTCSceneFlags {
        match self {
            Self::Robust => RTCSceneFlags::ROBUST,
            Self::Default => RTCSceneFlags::NONE,
        }
    }
}

/// Embree's build quality (`rtcSetSceneBuildQuality`, and the mesh's
/// `rtcSetGeometryBuildQuality`): the builder presets `embree:low`, `embree:medium`,
/// `embree:high` of the registry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EmbreeQuality {
    /// `RTC_BUILD_QUALITY_LOW`: Embree's fastest, lower-quality build (meant for dynamic
    /// scenes).
    Low,
    /// `RTC_BUILD_QUALITY_MEDIUM`: Embree's default (binned SAH), what the backends use.
    Medium,
    /// `RTC_BUILD_QUALITY_HIGH`: higher-quality trees (spatial splits for triangles), the
    /// slowest build.
    High,
}

impl EmbreeQuality {
    /// The three qualities, fastest build first.
    pub const ALL: [Self; 3] = [Self::Low, Self::Medium, Self::High];

    /// `"low"`, `"medium"` or `"high"`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Low => "low",
            Self::Medium => "medium",
            Self::High => "high",
        }
    }

    fn rtc(self) -> RTCBuildQuality {
        match self {
            Self::Low => RTCBuildQuality::LOW,
            Self::Medium => RTCBuildQuality::MEDIUM,
            Self::High => RTCBuildQuality::HIGH,
        }
    }
}

/// The process's Embree device.
struct Device(RTCDevice);

// SAFETY: an Embree device is a thread-safe object: Embree's API documents that scenes and
// geometries may be created on one device from several threads at once and that its
// reference counting is atomic; this handle is never released.
unsafe impl Send for Device {}
// SAFETY: as above; the handle itself is an immutable pointer.
unsafe impl Sync for Device {}

/// The shared device, or why Embree cannot run.
fn device() -> Result<RTCDevice, String> {
    static DEVICE: OnceLock<Result<Device, String>> = OnceLock::new();
    DEVICE
        .get_or_init(|| {
            // SAFETY: a null configuration string asks for Embree's defaults; the result is
            // checked for null before use.
            let d = unsafe { rtcNewDevice(std::ptr::null()) };
            if d.is_null() {
                // SAFETY: with a null device, rtcGetDeviceError returns the error of the
                // failed rtcNewDevice call on this thread.
                let e = unsafe { rtcGetDeviceError(std::ptr::null_mut()) };
                return Err(format!("Embree cannot create a device ({e:?})"));
            }
            // SAFETY: `d` is a valid device; property queries have no other precondition.
            let culling =
                unsafe { rtcGetDeviceProperty(d, RTCDeviceProperty::BACKFACE_CULLING_ENABLED) };
            if culling != 0 {
                return Err(
                    "this Embree library culls back faces; raybench needs both sides".into(),
                );
            }
            Ok(Device(d))
        })
        .as_ref()
        .map(|d| d.0)
        .map_err(Clone::clone)
}

/// Whether Embree runs here (the library loads and makes a device), or why not.
///
/// # Errors
/// The reason Embree cannot run.
pub fn availability() -> Result<(), String> {
    device().map(|_| ())
}

/// Embree's version and the packet widths this CPU runs natively, such as
/// `"Embree 3.13.5, native packets 4/8/16"`.
///
/// # Errors
/// When Embree cannot run ([`availability`]).
pub fn version() -> Result<String, String> {
    let d = device()?;
    // SAFETY: `d` is a valid device; property queries have no other precondition.
    let prop = |p| unsafe { rtcGetDeviceProperty(d, p) };
    let native: Vec<&str> = [
        (RTCDeviceProperty::NATIVE_RAY4_SUPPORTED, "4"),
        (RTCDeviceProperty::NATIVE_RAY8_SUPPORTED, "8"),
        (RTCDeviceProperty::NATIVE_RAY16_SUPPORTED, "16"),
    ]
    .into_iter()
    .filter(|&(p, _)| prop(p) != 0)
    .map(|(_, w)| w)
    .collect();
    Ok(format!(
        "Embree {}.{}.{}, native packets {}",
        prop(RTCDeviceProperty::VERSION_MAJOR),
        prop(RTCDeviceProperty::VERSION_MINOR),
        prop(RTCDeviceProperty::VERSION_PATCH),
        if native.is_empty() {
            "none".to_string()
        } else {
            native.join("/")
        }
    ))
}

/// Whether the Embree backends support `geometry`: triangles and planes in any number, other
/// bounded primitives (spheres, height fields, CSG trees, SDF models, Bezier patches) up to
/// [`MAX_SIDE_PRIMITIVES`]. A height
/// field is one such primitive: it stays beside Embree's scene and every ray meets it
/// through the core's own routine (its cells are not handed to Embree), so its hits are
/// raybench's exactly. A CSG tree and an SDF model are likewise one side primitive each, and
/// so is each Bezier patch.
///
/// # Errors
/// Why not.
pub fn supports(geometry: &Geometry) -> Result<(), String> {
    let side = geometry
        .bounded()
        .iter()
        .filter(|&&id| geometry.shape(id).kind() != PrimitiveKind::Triangle)
        .count();
    if side > MAX_SIDE_PRIMITIVES {
        // Every bounded kind but the triangle, by name, so a new kind joins the message.
        let kinds: Vec<&str> = PrimitiveKind::ALL
            .iter()
            .filter(|&&k| !matches!(k, PrimitiveKind::Triangle | PrimitiveKind::Plane))
            .map(|k| k.name())
            .collect();
        return Err(format!(
            "{side} bounded primitives that are not triangles ({}): the Embree backends trace \
             triangles in Embree and test other bounded primitives beside it by every ray, at \
             most {MAX_SIDE_PRIMITIVES}",
            kinds.join(", ")
        ));
    }
    Ok(())
}

/// A committed Embree scene.
struct SceneHandle(RTCScene);

// SAFETY: the scene is committed before the handle is wrapped and never modified after;
// Embree's API allows rtcIntersect*/rtcOccluded* on a committed scene from any number of
// threads at once, and rtcReleaseScene (atomic reference counting) from any thread.
unsafe impl Send for SceneHandle {}
// SAFETY: as above.
unsafe impl Sync for SceneHandle {}

impl Drop for SceneHandle {
    fn drop(&mut self) {
        // SAFETY: the handle holds one reference, released exactly once here.
        unsafe { rtcReleaseScene(self.0) };
    }
}

/// The structure both Embree backends share.
struct Inner {
    geometry: Arc<Geometry>,
    /// Embree's scene over the triangles; `None` when there are none.
    scene: Option<SceneHandle>,
    /// Raybench id of each Embree `primID` (the triangles in id order).
    ids: Vec<u32>,
    /// Bounded primitives Embree does not hold (spheres), tested by every ray.
    side: Vec<u32>,
    /// The scene mode Embree's scene was built with.
    mode: EmbreeMode,
    /// The build quality it was built with.
    quality: EmbreeQuality,
}

/// Panics with Embree's last error on this thread, if any, naming what was being done.
fn check(device: RTCDevice, what: &str) {
    // SAFETY: `device` is the valid process device.
    let e = unsafe { rtcGetDeviceError(device) };
    assert!(e == RTCError::NONE, "Embree failed to {what}: {e:?}");
}

impl Inner {
    fn build(geometry: Arc<Geometry>, mode: EmbreeMode, quality: EmbreeQuality) -> Self {
        let mut ids = Vec::new();
        let mut side = Vec::new();
        for &id in geometry.bounded() {
            match geometry.shape(id) {
                Shape::Triangle(_) => ids.push(id),
                _ => side.push(id),
            }
        }
        let scene = (!ids.is_empty()).then(|| Self::embree_scene(&geometry, &ids, mode, quality));
        Self {
            geometry,
            scene,
            ids,
            side,
            mode,
            quality,
        }
    }

    /// One Embree triangle mesh with the triangles `ids` of `geometry` (three vertices of
    /// their own each: raybench stores triangles, not indexed meshes), committed in `mode`
    /// at build quality `quality`.
    fn embree_scene(
        geometry: &Geometry,
        ids: &[u32],
        mode: EmbreeMode,
        quality: EmbreeQuality,
    ) -> SceneHandle {
        let device = device().unwrap_or_else(|e| panic!("Embree is unavailable: {e}"));
        let n = ids.len();
        // SAFETY: `device` is valid; a failure (null scene) is caught by `check` before use.
        let scene = unsafe { rtcNewScene(device) };
        check(device, "create a scene");
        // SAFETY: `scene` is a valid, uncommitted scene.
        unsafe {
            rtcSetSceneFlags(scene, mode.flags());
            rtcSetSceneBuildQuality(scene, quality.rtc());
        }
        let scene = SceneHandle(scene);
        // SAFETY: as above.
        let mesh = unsafe { rtcNewGeometry(device, RTCGeometryType::TRIANGLE) };
        check(device, "create a triangle mesh");
        // SAFETY: `mesh` is a valid, uncommitted triangle geometry.
        unsafe { rtcSetGeometryBuildQuality(mesh, quality.rtc()) };
        // SAFETY: `mesh` is a valid triangle geometry; Embree allocates the buffers (padded
        // for its vector loads) with the given stride and count and returns their data.
        let (vertices, indices) = unsafe {
            (
                rtcSetNewGeometryBuffer(
                    mesh,
                    RTCBufferType::VERTEX,
                    0,
                    RTCFormat::FLOAT3,
                    12,
                    3 * n,
                ),
                rtcSetNewGeometryBuffer(mesh, RTCBufferType::INDEX, 0, RTCFormat::UINT3, 12, n),
            )
        };
        check(device, "allocate the mesh buffers");
        assert!(!vertices.is_null() && !indices.is_null());
        // SAFETY: Embree returned a buffer of `3 n` FLOAT3 items (12 bytes each, aligned to
        // at least 16 bytes) and one of `n` UINT3 items, ours to fill until the commit; no
        // other reference to them exists.
        let (vertices, indices) = unsafe {
            (
                std::slice::from_raw_parts_mut(vertices.cast::<[f32; 3]>(), 3 * n),
                std::slice::from_raw_parts_mut(indices.cast::<[u32; 3]>(), n),
            )
        };
        for (k, &id) in ids.iter().enumerate() {
            let Shape::Triangle(tri) = geometry.shape(id) else {
                unreachable!("only triangles go to Embree")
            };
            for (j, v) in tri.v.iter().enumerate() {
                vertices[3 * k + j] = v.to_array();
            }
            let base = u32::try_from(3 * k).expect("at most 2^26 primitives");
            indices[k] = [base, base + 1, base + 2];
        }
        // SAFETY: `mesh` and `scene.0` are valid; the scene takes its own reference to the
        // mesh, so ours is released after attaching; committing builds the BVH.
        unsafe {
            rtcCommitGeometry(mesh);
            let geom_id = rtcAttachGeometry(scene.0, mesh);
            debug_assert_eq!(geom_id, 0);
            rtcReleaseGeometry(mesh);
            rtcCommitScene(scene.0);
        }
        check(device, "build its BVH");
        scene
    }

    /// Planes ([`Geometry::closest_unbounded`]) and side primitives: the best hit Embree
    /// must improve on.
    fn closest_beside<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<(u32, PrimHit)> {
        crate::closest_beside(&self.geometry, &self.side, ray, counters)
    }

    /// Whether a plane or a side primitive is hit.
    fn occluded_beside<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        crate::occluded_beside(&self.geometry, &self.side, ray, counters)
    }

    /// Takes Embree's hit on `prim_id` when it beats `best` under raybench's tie rule.
    #[inline]
    fn merge(&self, best: &mut Option<(u32, PrimHit)>, prim_id: u32, t: f32, u: f32, v: f32) {
        let id = self.ids[prim_id as usize];
        keep_closer(best, id, PrimHit { t, sub: 0, u, v });
    }

    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        let mut best = self.closest_beside(ray, counters);
        if let Some(scene) = &self.scene
            && let Some((tnear, tfar)) = interval(ray, best.map_or(ray.t_max, |(_, h)| h.t))
        {
            let mut rh = RTCRayHit {
                ray: rtc_ray(ray, tnear, tfar),
                hit: RTCHit {
                    Ng_x: 0.0,
                    Ng_y: 0.0,
                    Ng_z: 0.0,
                    u: 0.0,
                    v: 0.0,
                    primID: INVALID_ID,
                    geomID: INVALID_ID,
                    instID: [INVALID_ID],
                },
            };
            let mut ctx = context(RTCIntersectContextFlags::INCOHERENT);
            // SAFETY: the scene is committed; `ctx` and `rh` are initialised as Embree
            // requires (valid ray, geomID and instID invalid) and live for the call.
            unsafe { rtcIntersect1(scene.0, &raw mut ctx, &raw mut rh) };
            if rh.hit.geomID != INVALID_ID {
                self.merge(&mut best, rh.hit.primID, rh.ray.tfar, rh.hit.u, rh.hit.v);
            }
        }
        self.geometry.complete(ray, best)
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        if self.occluded_beside(ray, counters) {
            return true;
        }
        let Some(scene) = &self.scene else {
            return false;
        };
        let Some((tnear, tfar)) = interval(ray, ray.t_max) else {
            return false;
        };
        let mut r = rtc_ray(ray, tnear, tfar);
        let mut ctx = context(RTCIntersectContextFlags::INCOHERENT);
        // SAFETY: the scene is committed; `ctx` and `r` are initialised and live for the call.
        unsafe { rtcOccluded1(scene.0, &raw mut ctx, &raw mut r) };
        // Embree marks an occluded ray by setting tfar to -inf.
        r.tfar == f32::NEG_INFINITY
    }

    fn stats(&self) -> AccelStats {
        // Embree's own BVH is allocated inside the library and not counted here.
        let n = self.ids.len();
        AccelStats {
            memory_bytes: n * (3 * 12 + 12) + std::mem::size_of_val(self.ids.as_slice()),
            counts: vec![
                ("embree triangles", n as u64),
                ("side primitives", self.side.len() as u64),
                ("robust mode", u64::from(self.mode == EmbreeMode::Robust)),
                (
                    "build quality (0 low, 1 medium, 2 high)",
                    self.quality as u64,
                ),
            ],
        }
    }
}

/// Embree's `[tnear, tfar]` for `ray` clipped to `t_max`, or `None` when the ray can hit
/// nothing: a NaN, infinite or zero direction or origin (Embree's results for such rays are
/// undefined), a NaN bound, or an empty interval. Embree allows no negative `tnear`: a
/// negative `t_min` is raised to 0.
#[inline]
fn interval(ray: &Ray, t_max: f32) -> Option<(f32, f32)> {
    if !ray.is_valid() || ray.t_min.is_nan() {
        return None;
    }
    let tnear = ray.t_min.max(0.0);
    // False for a NaN `t_max` too.
    (tnear <= t_max).then_some((tnear, t_max))
}

/// Embree's ray: raybench's origin and direction (not normalised, so `t` agrees).
#[inline]
fn rtc_ray(ray: &Ray, tnear: f32, tfar: f32) -> RTCRay {
    RTCRay {
        org_x: ray.origin.x,
        org_y: ray.origin.y,
        org_z: ray.origin.z,
        tnear,
        dir_x: ray.dir.x,
        dir_y: ray.dir.y,
        dir_z: ray.dir.z,
        time: 0.0,
        tfar,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

/// `rtcInitIntersectContext` (an inline C function the bindings lack) with `flags`.
#[inline]
fn context(flags: RTCIntersectContextFlags) -> RTCIntersectContext {
    RTCIntersectContext {
        flags,
        filter: None,
        instID: [INVALID_ID],
    }
}

/// Packet kernels of one width, the methods `Inner::$ip` and `Inner::$op` in module
/// `$module`: `$w` lanes, Embree's `$RayHit`/`$Ray` structures and its
/// `$intersect`/`$occluded` calls.
macro_rules! packet_kernels {
    ($module:ident, $ip:ident, $op:ident, $w:literal, $RayHit:ident, $RayT:ident, $HitT:ident, $intersect:ident, $occluded:ident) => {
        mod $module {
            use super::{INVALID_ID, Inner, context, interval};
            use embree::sys::{$HitT, $RayHit, $RayT, $intersect, $occluded, RTCIntersectContextFlags};
            use raybench_geometry::{Counters, Hit, PrimHit, Ray};

            /// A valid mask, aligned as Embree requires (4 bytes per lane).
            #[repr(C, align(64))]
            struct Valid([i32; $w]);

            fn empty_ray() -> $RayT {
                $RayT {
                    org_x: [0.0; $w],
                    org_y: [0.0; $w],
                    org_z: [0.0; $w],
                    tnear: [0.0; $w],
                    dir_x: [0.0; $w],
                    dir_y: [0.0; $w],
                    dir_z: [0.0; $w],
                    time: [0.0; $w],
                    tfar: [f32::NEG_INFINITY; $w],
                    mask: [u32::MAX; $w],
                    id: [0; $w],
                    flags: [0; $w],
                }
            }

            /// Writes lane `i`.
            #[inline]
            fn set_lane(r: &mut $RayT, i: usize, ray: &Ray, tnear: f32, tfar: f32) {
                r.org_x[i] = ray.origin.x;
                r.org_y[i] = ray.origin.y;
                r.org_z[i] = ray.origin.z;
                r.dir_x[i] = ray.dir.x;
                r.dir_y[i] = ray.dir.y;
                r.dir_z[i] = ray.dir.z;
                r.tnear[i] = tnear;
                r.tfar[i] = tfar;
            }

            impl Inner {
                /// Closest hits, `$w` rays per Embree call.
                pub(super) fn $ip<C: Counters>(
                    &self,
                    rays: &[Ray],
                    hits: &mut [Option<Hit>],
                    counters: &mut C,
                ) {
                    assert_eq!(rays.len(), hits.len());
                    let Some(scene) = &self.scene else {
                        for (ray, hit) in rays.iter().zip(hits) {
                            let best = self.closest_beside(ray, counters);
                            *hit = self.geometry.complete(ray, best);
                        }
                        return;
                    };
                    let mut rh = $RayHit {
                        ray: empty_ray(),
                        hit: $HitT {
                            Ng_x: [0.0; $w],
                            Ng_y: [0.0; $w],
                            Ng_z: [0.0; $w],
                            u: [0.0; $w],
                            v: [0.0; $w],
                            primID: [INVALID_ID; $w],
                            geomID: [INVALID_ID; $w],
                            instID: [[INVALID_ID; $w]],
                        },
                    };
                    let mut best: [Option<(u32, PrimHit)>; $w] = [None; $w];
                    for (rays, hits) in rays.chunks($w).zip(hits.chunks_mut($w)) {
                        let mut valid = Valid([0; $w]);
                        let mut any = false;
                        for (i, ray) in rays.iter().enumerate() {
                            best[i] = self.closest_beside(ray, counters);
                            if let Some((tnear, tfar)) =
                                interval(ray, best[i].map_or(ray.t_max, |(_, h)| h.t))
                            {
                                set_lane(&mut rh.ray, i, ray, tnear, tfar);
                                rh.hit.geomID[i] = INVALID_ID;
                                rh.hit.instID[0][i] = INVALID_ID;
                                valid.0[i] = -1;
                                any = true;
                            }
                        }
                        if any {
                            let mut ctx = context(RTCIntersectContextFlags::COHERENT);
                            // SAFETY: the scene is committed; `valid` and `rh` are aligned
                            // as Embree requires (their types' alignment) and every valid
                            // lane holds a valid ray with geomID and instID invalid; all
                            // live for the call.
                            unsafe {
                                $intersect(valid.0.as_ptr(), scene.0, &raw mut ctx, &raw mut rh)
                            };
                        }
                        for (i, (ray, hit)) in rays.iter().zip(hits).enumerate() {
                            if valid.0[i] != 0 && rh.hit.geomID[i] != INVALID_ID {
                                self.merge(
                                    &mut best[i],
                                    rh.hit.primID[i],
                                    rh.ray.tfar[i],
                                    rh.hit.u[i],
                                    rh.hit.v[i],
                                );
                            }
                            *hit = self.geometry.complete(ray, best[i]);
                        }
                    }
                }

                /// Any-hit results, `$w` rays per Embree call.
                pub(super) fn $op<C: Counters>(
                    &self,
                    rays: &[Ray],
                    occluded: &mut [bool],
                    counters: &mut C,
                ) {
                    assert_eq!(rays.len(), occluded.len());
                    let Some(scene) = &self.scene else {
                        for (ray, o) in rays.iter().zip(occluded) {
                            *o = self.occluded_beside(ray, counters);
                        }
                        return;
                    };
                    let mut r = empty_ray();
                    for (rays, occluded) in rays.chunks($w).zip(occluded.chunks_mut($w)) {
                        let mut valid = Valid([0; $w]);
                        let mut any = false;
                        for (i, ray) in rays.iter().enumerate() {
                            occluded[i] = self.occluded_beside(ray, counters);
                            if !occluded[i]
                                && let Some((tnear, tfar)) = interval(ray, ray.t_max)
                            {
                                set_lane(&mut r, i, ray, tnear, tfar);
                                valid.0[i] = -1;
                                any = true;
                            }
                        }
                        if any {
                            let mut ctx = context(RTCIntersectContextFlags::COHERENT);
                            // SAFETY: the scene is committed; `valid` and `r` are aligned as
                            // Embree requires and every valid lane holds a valid ray; all
                            // live for the call.
                            unsafe { $occluded(valid.0.as_ptr(), scene.0, &raw mut ctx, &raw mut r) };
                        }
                        for (i, o) in occluded.iter_mut().enumerate() {
                            // Embree marks an occluded lane by setting its tfar to -inf.
                            if valid.0[i] != 0 && r.tfar[i] == f32::NEG_INFINITY {
                                *o = true;
                            }
                        }
                    }
                }
            }
        }
    };
}

packet_kernels!(
    packets16,
    intersect_packets16,
    occluded_packets16,
    16,
    RTCRayHit16,
    RTCRay16,
    RTCHit16,
    rtcIntersect16,
    rtcOccluded16
);
packet_kernels!(
    packets8,
    intersect_packets8,
    occluded_packets8,
    8,
    RTCRayHit8,
    RTCRay8,
    RTCHit8,
    rtcIntersect8,
    rtcOccluded8
);

/// Why [`Accel::quality`] has no figures for Embree: its BVH is built and held inside the
/// library, and Embree 3's API reads back no node (only `rtcGetSceneBounds`).
const NOT_READABLE: &str = "Embree's BVH lives inside the library; its API reads back no node";

/// Embree 3 with single rays (backend `embree`): one triangle mesh holding the scene's
/// triangles, built by `rtcCommitScene` with Embree's defaults (medium quality) in
/// [`EmbreeMode::Robust`] ([`EmbreeAccel::build_with_mode`] picks the mode), traced
/// with `rtcIntersect1` / `rtcOccluded1`. Planes are tested first
/// ([`Geometry::closest_unbounded`]) and Embree's `tfar` clipped to their hit; spheres (at
/// most [`MAX_SIDE_PRIMITIVES`] for the renderer, see [`supports`]) likewise beside it.
/// Embree's hit (`t`, barycentrics `u`, `v` of vertices 1 and 2, `primID` mapped back to
/// the raybench id) is completed with [`Geometry::complete`], so normals are raybench's.
///
/// Not bound by the equivalence contract: Embree intersects triangles with its own test
/// and traversal, so its `t` differs from raybench's in the last bits and a ray through
/// an edge may report the neighbouring triangle. Rays that cannot hit anything (NaN,
/// infinite or zero direction) never reach Embree; a negative `t_min` counts as 0. Embree
/// does not count its tests: the counters see only the planes and spheres.
pub struct EmbreeAccel(Inner);

/// Embree 3 with packets (backend `embree-packet`): the [`EmbreeAccel`] structure, with
/// [`Accel::intersect_batch`] and [`Accel::occluded_batch`] sending consecutive rays in
/// packets of [`DEFAULT_PACKET_WIDTH`] (16) through `rtcIntersect16` / `rtcOccluded16`
/// with a valid mask (lanes past the batch's end and rays that can hit nothing are
/// masked off); 8 (`rtcIntersect8`) with [`EmbreePacketAccel::build_with_width`], and
/// Embree's default mode with [`EmbreePacketAccel::build_with`]. Single rays take
/// `rtcIntersect1` / `rtcOccluded1`.
pub struct EmbreePacketAccel {
    inner: Inner,
    width: usize,
}

impl EmbreeAccel {
    /// The structure over `geometry`, built in `mode` ([`Accel::build`]: robust).
    ///
    /// # Panics
    /// As [`Accel::build`].
    #[must_use]
    pub fn build_with_mode(geometry: Arc<Geometry>, mode: EmbreeMode) -> Self {
        Self::build_with(geometry, mode, EmbreeQuality::Medium)
    }

    /// The structure over `geometry`, built in `mode` at build quality `quality` (the
    /// registry's presets `embree:low`, `embree:medium`, `embree:high`).
    ///
    /// # Panics
    /// As [`Accel::build`].
    #[must_use]
    pub fn build_with(geometry: Arc<Geometry>, mode: EmbreeMode, quality: EmbreeQuality) -> Self {
        Self(Inner::build(geometry, mode, quality))
    }

    /// The build quality.
    #[must_use]
    pub fn quality(&self) -> EmbreeQuality {
        self.0.quality
    }

    /// The scene mode.
    #[must_use]
    pub fn mode(&self) -> EmbreeMode {
        self.0.mode
    }
}

impl EmbreePacketAccel {
    /// The structure over `geometry` in robust mode, tracing batches in packets of `width`
    /// rays.
    ///
    /// # Panics
    /// When `width` is neither 8 nor 16, or as [`Accel::build`].
    #[must_use]
    pub fn build_with_width(geometry: Arc<Geometry>, width: usize) -> Self {
        Self::build_with(geometry, width, EmbreeMode::Robust)
    }

    /// The structure over `geometry` built in `mode`, tracing batches in packets of `width`
    /// rays.
    ///
    /// # Panics
    /// When `width` is neither 8 nor 16, or as [`Accel::build`].
    #[must_use]
    pub fn build_with(geometry: Arc<Geometry>, width: usize, mode: EmbreeMode) -> Self {
        assert!(
            width == 8 || width == 16,
            "Embree packets hold 8 or 16 rays"
        );
        Self {
            inner: Inner::build(geometry, mode, EmbreeQuality::Medium),
            width,
        }
    }

    /// The scene mode.
    #[must_use]
    pub fn mode(&self) -> EmbreeMode {
        self.inner.mode
    }

    /// Rays per packet.
    #[must_use]
    pub fn width(&self) -> usize {
        self.width
    }
}

impl Accel for EmbreeAccel {
    /// # Panics
    /// When Embree is unavailable ([`availability`]) or fails to build (out of memory).
    fn build(geometry: Arc<Geometry>) -> Self {
        Self::build_with_mode(geometry, EmbreeMode::Robust)
    }

    fn geometry(&self) -> &Geometry {
        &self.0.geometry
    }

    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        self.0.intersect(ray, counters)
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        self.0.occluded(ray, counters)
    }

    fn stats(&self) -> AccelStats {
        self.0.stats()
    }

    fn quality(&self, _params: &QualityParams) -> Option<StructureQuality> {
        Some(StructureQuality::NotReadable(NOT_READABLE))
    }
}

impl Accel for EmbreePacketAccel {
    /// # Panics
    /// When Embree is unavailable ([`availability`]) or fails to build (out of memory).
    fn build(geometry: Arc<Geometry>) -> Self {
        Self::build_with_width(geometry, DEFAULT_PACKET_WIDTH)
    }

    fn geometry(&self) -> &Geometry {
        &self.inner.geometry
    }

    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        self.inner.intersect(ray, counters)
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        self.inner.occluded(ray, counters)
    }

    fn intersect_batch<C: Counters>(
        &self,
        rays: &[Ray],
        hits: &mut [Option<Hit>],
        counters: &mut C,
    ) {
        if self.width == 16 {
            self.inner.intersect_packets16(rays, hits, counters);
        } else {
            self.inner.intersect_packets8(rays, hits, counters);
        }
    }

    fn occluded_batch<C: Counters>(&self, rays: &[Ray], occluded: &mut [bool], counters: &mut C) {
        if self.width == 16 {
            self.inner.occluded_packets16(rays, occluded, counters);
        } else {
            self.inner.occluded_packets8(rays, occluded, counters);
        }
    }

    fn stats(&self) -> AccelStats {
        let mut s = self.inner.stats();
        s.counts.push(("packet width", self.width as u64));
        s
    }

    fn quality(&self, _params: &QualityParams) -> Option<StructureQuality> {
        Some(StructureQuality::NotReadable(NOT_READABLE))
    }
}
