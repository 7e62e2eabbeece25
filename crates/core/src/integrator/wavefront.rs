//! The wavefront frame every integrator works in: a tile's centre rays (whose hits are the
//! id and `t` buffers), its colour and counts, the jittered camera rays of a sample, one
//! bounce traced as a batch, the surface each of its rays hit, and one batch of shadow
//! rays. Integrators never trace one ray at a time (ARCHITECTURE.md), so that packet
//! backends speed up secondary rays too.

use super::tile::{Tile, TileOutput, id_t_buffers, tile_pixels};
use crate::camera::CameraRays;
use crate::material::Material;
use crate::renderer::RenderSettings;
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::{Accel, Counters, Hit, Ray};
use glam::Vec3;

/// A ray in flight and what its radiance is worth to its pixel.
#[derive(Clone, Copy)]
pub(super) struct Segment {
    /// Index of the pixel in the tile.
    pub pixel: u32,
    /// Product of the weights along the way.
    pub weight: Vec3,
    /// The ray.
    pub ray: Ray,
}

/// The surface a bounce's ray hit, ready to shade.
pub(super) struct Surface<'s> {
    /// The primitive hit.
    pub prim: u32,
    /// Its material.
    pub m: &'s Material,
    /// The hit point.
    pub p: Vec3,
    /// The unit geometric normal, facing the incoming ray: it decides sides and offsets
    /// ray origins.
    pub nf: Vec3,
    /// The unit shading normal ([`Scene::shading`]), flipped with the geometric one to
    /// face the incoming ray's side: Lambert and Blinn-Phong terms, reflection, refraction
    /// and sampled directions use it.
    pub ns: Vec3,
    /// The diffuse colour at the hit (textures applied).
    pub albedo: Vec3,
    /// The emitted radiance at the hit (textures applied).
    pub emission: Vec3,
    /// Whether the ray arrived on the side the geometric normal points to.
    pub front: bool,
    /// The ray's unit direction.
    pub d: Vec3,
}

/// The normals of a hit facing a ray of unit direction `d`: the geometric normal `ng` and
/// the shading normal `ns` (on `ng`'s side) flipped together to the side the ray comes
/// from, and whether that is the side `ng` points to. Where the shading normal faces away
/// from the ray (a grazing view of a strongly bent normal), the geometric normal shades.
#[inline]
pub(super) fn facing(ng: Vec3, ns: Vec3, d: Vec3) -> (Vec3, Vec3, bool) {
    let front = ng.dot(d) < 0.0;
    let (nf, ns) = if front { (ng, ns) } else { (-ng, -ns) };
    (nf, if ns.dot(d) < 0.0 { ns } else { nf }, front)
}

/// One tile in flight: what it traces through and with, its centre rays and hits, its
/// colour accumulator and its counts of rays and work.
pub(super) struct Wavefront<'a, A, C> {
    /// The accelerator every batch goes through.
    accel: &'a A,
    /// The camera.
    pub camera: &'a CameraRays,
    /// Image size, samples, depth and seed.
    pub settings: &'a RenderSettings,
    /// Which tile.
    pub tile: Tile,
    /// The centre ray of every pixel, in [`tile_pixels`] order.
    pub centre_rays: Vec<Ray>,
    /// Their closest hits (the id and `t` buffers).
    pub centre_hits: Vec<Option<Hit>>,
    /// Linear colour per pixel; starts at zero.
    pub color: Vec<Vec3>,
    /// Rays traced so far.
    traced: u64,
    /// Work counters.
    counters: C,
}

impl<'a, A: Accel, C: Counters> Wavefront<'a, A, C> {
    /// Starts a tile by tracing its centre rays.
    pub(super) fn new(
        accel: &'a A,
        camera: &'a CameraRays,
        settings: &'a RenderSettings,
        tile: Tile,
    ) -> Self {
        let centre_rays: Vec<Ray> = tile_pixels(tile, 0)
            .map(|(x, y, _)| camera.center_ray(x, y))
            .collect();
        let n = centre_rays.len();
        let mut st = Self {
            accel,
            camera,
            settings,
            tile,
            centre_rays: Vec::new(),
            centre_hits: Vec::new(),
            color: vec![Vec3::ZERO; n],
            traced: 0,
            counters: C::default(),
        };
        st.centre_hits = st.trace(&centre_rays);
        st.centre_rays = centre_rays;
        st
    }

    /// The jittered camera rays of sample `s`, in [`tile_pixels`] order: the pixel's index
    /// in the tile, its ray, and its sampler after the two jitter dimensions.
    pub(super) fn camera_rays(&self, s: u32) -> impl Iterator<Item = (u32, Ray, Sampler)> {
        let (camera, seed) = (self.camera, self.settings.seed);
        tile_pixels(self.tile, self.settings.width)
            .enumerate()
            .map(move |(i, (x, y, pixel))| {
                let mut sampler = Sampler::new(pixel, s, seed);
                let (jx, jy) = sampler.next_2d();
                (i as u32, camera.ray(x as f32 + jx, y as f32 + jy), sampler)
            })
    }

    /// Traces one bounce as a batch: the closest hit of every ray, counted.
    pub(super) fn trace(&mut self, rays: &[Ray]) -> Vec<Option<Hit>> {
        let mut hits = vec![None; rays.len()];
        self.accel
            .intersect_batch(rays, &mut hits, &mut self.counters);
        self.traced += rays.len() as u64;
        hits
    }

    /// The surface `seg` hit (`hit`, from [`Self::trace`]), ready to shade; on a miss, adds
    /// the background (or environment map) seen along the ray, weighted, to the segment's
    /// pixel and returns `None`.
    pub(super) fn surface<'s>(
        &mut self,
        scene: &'s Scene,
        seg: &Segment,
        hit: Option<&Hit>,
    ) -> Option<Surface<'s>> {
        let Some(hit) = hit else {
            self.color[seg.pixel as usize] += seg.weight * scene.background_along(seg.ray.dir);
            return None;
        };
        let p = seg.ray.at(hit.t);
        let d = seg.ray.dir.normalize();
        let shading = scene.shading(hit, p);
        let (nf, ns, front) = facing(hit.normal, shading.normal, d);
        Some(Surface {
            prim: hit.prim,
            m: scene.material_of(hit.prim),
            p,
            nf,
            ns,
            albedo: shading.albedo,
            emission: shading.emission,
            front,
            d,
        })
    }

    /// Traces a batch of shadow rays and adds to each unblocked ray's pixel what it brings.
    pub(super) fn add_unshadowed(&mut self, shadows: &ShadowBatch) {
        if shadows.rays.is_empty() {
            return;
        }
        let mut occluded = vec![false; shadows.rays.len()];
        self.accel
            .occluded_batch(&shadows.rays, &mut occluded, &mut self.counters);
        for (&(px, value), &blocked) in shadows.light.iter().zip(&occluded) {
            if !blocked {
                self.color[px] += value;
            }
        }
        self.traced += shadows.rays.len() as u64;
    }

    /// The tile's output.
    pub(super) fn finish(self) -> TileOutput<C> {
        let (ids, t) = id_t_buffers(&self.centre_hits);
        TileOutput {
            tile: self.tile,
            color: self.color,
            ids,
            t,
            rays: self.traced,
            counters: self.counters,
        }
    }
}

/// The shadow rays of one bounce, each with its pixel and the light it brings there when
/// nothing blocks it.
#[derive(Default)]
pub(super) struct ShadowBatch {
    rays: Vec<Ray>,
    light: Vec<(usize, Vec3)>,
}

impl ShadowBatch {
    /// Adds shadow ray `ray`, worth `value` to pixel `px` when unblocked.
    pub(super) fn push(&mut self, ray: Ray, px: usize, value: Vec3) {
        self.rays.push(ray);
        self.light.push((px, value));
    }
}
