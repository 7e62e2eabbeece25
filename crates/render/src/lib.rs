//! # raybench-render
//!
//! The CPU side of the renderer interface: [`CpuRenderer`], one generic [`Renderer`] over any
//! [`Accel`], which spreads the core's tile integrators over threads with rayon; image
//! output ([`write_color`]: PNG, OpenEXR, PFM; [`write_ids_png`]) and input
//! ([`read_linear`], for `raybench diff`).
//!
//! **Architecture invariant:** the hot loop is generic over the accelerator
//! (`render_frame::<A, C>`); dynamic dispatch happens once per frame, at the `Renderer`
//! boundary. Tiles are reduced in tile order, so frames and counters are identical on any
//! number of threads. A scene with instances is rendered through the two-level form of the
//! backend's structure ([`TwoLevel`]), chosen once in `prepare`: the match between the two
//! forms happens once per frame or batch, so flat scenes keep their direct path.

mod output;
mod read;

pub use output::{
    ImageFormat, OutputError, check_image_path, check_png_path, id_color, partial_path, pfm_bytes,
    srgb8, write_atomically, write_color, write_color_png, write_file, write_ids_png, write_rgb,
};
pub use read::{LinearImage, ReadError, parse_pfm, read_linear};

use raybench_core::integrator::{assemble, render_tile, tiles};
use raybench_core::{
    Accel, AccelStats, BatchTracer, Counters, Frame, Geometry, Hit, NoCounters, QualityParams, Ray,
    RayCounters, RenderError, RenderSettings, Renderer, Scene, StructureQuality, Timings, TwoLevel,
    UpdatePolicy,
};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// Tile edge in pixels: 16 x 16 = 256 rays per batch, small enough to balance 2 to 64
/// threads on a 512 x 512 frame (1024 tiles).
pub const TILE_SIZE: u32 = 16;

/// Renders one frame of `scene` through `accel` on the current rayon pool.
///
/// # Errors
/// When the settings are out of range.
pub fn render_frame<A: Accel>(
    scene: &Scene,
    accel: &A,
    settings: &RenderSettings,
) -> Result<Frame, RenderError> {
    settings.validate()?;
    let view = scene.view(settings)?;
    let start = Instant::now();
    let mut frame = if settings.count {
        render_counted::<A, RayCounters>(scene, view, accel, settings)
    } else {
        render_counted::<A, NoCounters>(scene, view, accel, settings)
    };
    frame.timings.push("render", start.elapsed().as_secs_f64());
    Ok(frame)
}

fn render_counted<A: Accel, C: Counters>(
    scene: &Scene,
    view: &raybench_core::Camera,
    accel: &A,
    settings: &RenderSettings,
) -> Frame {
    let camera = view.rays(settings.width, settings.height);
    let outputs: Vec<_> = tiles(settings.width, settings.height, TILE_SIZE)
        .into_par_iter()
        .map(|tile| render_tile::<A, C>(scene, accel, &camera, settings, tile))
        .collect();
    assemble(settings.width, settings.height, outputs)
}

/// The builder of an accelerator: a function so that backends can pass their parameters.
pub type BuildFn<A> = Box<dyn Fn(Arc<Geometry>) -> A + Send + Sync>;

/// The structure `prepare` built: the backend's own for a flat scene (or for a backend
/// that tests instances itself, [`Accel::TESTS_INSTANCES`]: naive), its two-level form for a
/// scene with instances.
enum Built<A: Accel> {
    Flat(A),
    TwoLevel(TwoLevel<A>),
}

/// `$body` with `$a` bound to the built structure, whichever form it has: the one match per
/// frame or batch, outside the per-ray path.
macro_rules! with_built {
    ($built:expr, $a:ident => $body:expr) => {
        match $built {
            Built::Flat($a) => $body,
            Built::TwoLevel($a) => $body,
        }
    };
}

/// The one CPU [`Renderer`]: builds an [`Accel`] in `prepare` (its [`TwoLevel`] form for a
/// scene with instances), renders tiles in parallel.
pub struct CpuRenderer<A: Accel> {
    name: String,
    description: String,
    build: BuildFn<A>,
    availability: fn() -> Result<(), String>,
    support: fn(&Geometry) -> Result<(), String>,
    counts_tests: bool,
    prepared: Option<(Arc<Scene>, Built<A>)>,
}

impl<A: Accel> CpuRenderer<A> {
    /// A renderer named `name` whose structure is built by `build`.
    #[must_use]
    pub fn new(name: impl Into<String>, description: impl Into<String>, build: BuildFn<A>) -> Self {
        Self {
            name: name.into(),
            description: description.into(),
            build,
            availability: || Ok(()),
            support: |_| Ok(()),
            counts_tests: true,
            prepared: None,
        }
    }

    /// The same renderer, reporting itself unavailable when `check` fails (a backend that
    /// needs an instruction set this CPU may lack).
    #[must_use]
    pub fn with_availability(mut self, check: fn() -> Result<(), String>) -> Self {
        self.availability = check;
        self
    }

    /// The same renderer, refusing scenes whose geometry `check` refuses (a backend that
    /// supports only some primitive kinds: a CPU structure sees the geometry and nothing
    /// else of a scene): [`Renderer::supports`] reports it and `prepare` fails with
    /// [`RenderError::Unsupported`].
    #[must_use]
    pub fn with_support_check(mut self, check: fn(&Geometry) -> Result<(), String>) -> Self {
        self.support = check;
        self
    }

    /// The same renderer, saying that its accelerator does not count ray/primitive tests
    /// (a peer library that tests primitives itself): [`Renderer::counts_tests`] is false.
    #[must_use]
    pub fn without_test_counts(mut self) -> Self {
        self.counts_tests = false;
        self
    }

    /// A renderer that builds with [`Accel::build`].
    #[must_use]
    pub fn with_default_build(name: impl Into<String>, description: impl Into<String>) -> Self {
        Self::new(name, description, Box::new(A::build))
    }

    /// The built structure, after `prepare` of a flat scene (`None` before, and for a
    /// scene with instances, whose structure is the [`TwoLevel`] form of `A`).
    #[must_use]
    pub fn accel(&self) -> Option<&A> {
        match self.prepared.as_ref() {
            Some((_, Built::Flat(a))) => Some(a),
            _ => None,
        }
    }
}

impl<A: Accel> Renderer for CpuRenderer<A> {
    fn name(&self) -> &str {
        &self.name
    }

    fn description(&self) -> &str {
        &self.description
    }

    fn availability(&self) -> Result<(), String> {
        (self.availability)()
    }

    /// The support check on the flat primitives and on every instanced mesh.
    fn supports(&self, scene: &Scene) -> Result<(), String> {
        (self.support)(&scene.geometry)?;
        scene
            .geometry
            .meshes()
            .iter()
            .try_for_each(|m| (self.support)(m))
    }

    fn counts_tests(&self) -> bool {
        self.counts_tests
    }

    fn prepare(&mut self, scene: &Arc<Scene>) -> Result<Timings, RenderError> {
        // Drop the previous structure first so that two never coexist in memory.
        self.prepared = None;
        self.supports(scene).map_err(RenderError::Unsupported)?;
        let start = Instant::now();
        let geometry = Arc::clone(&scene.geometry);
        let accel = if geometry.has_instances() && !A::TESTS_INSTANCES {
            Built::TwoLevel(TwoLevel::build_with(geometry, &self.build))
        } else {
            Built::Flat((self.build)(geometry))
        };
        let mut timings = Timings::default();
        timings.push("build", start.elapsed().as_secs_f64());
        self.prepared = Some((Arc::clone(scene), accel));
        Ok(timings)
    }

    /// Refits where `A` can ([`Accel::REFITS`]) under [`UpdatePolicy::Refit`]; a two-level
    /// form updates its bottom level (phase `refit` or `build`: the flat part and the meshes
    /// that deformed) and rebuilds its top level (phase `top`); anything else, and a scene
    /// of another topology, goes through [`Renderer::prepare`].
    fn update(&mut self, scene: &Arc<Scene>, policy: UpdatePolicy) -> Result<Timings, RenderError> {
        let refit = policy == UpdatePolicy::Refit && A::REFITS;
        let geometry = Arc::clone(&scene.geometry);
        let mut timings = Timings::default();
        let done = match self.prepared.as_mut() {
            Some((_, Built::Flat(a))) if refit => {
                let start = Instant::now();
                let ok = a.refit(geometry);
                timings.push("refit", start.elapsed().as_secs_f64());
                ok
            }
            Some((_, Built::TwoLevel(two))) => {
                let start = Instant::now();
                let ok = if refit {
                    two.refit_bottom(geometry)
                } else {
                    two.rebuild_bottom(geometry, &self.build)
                };
                timings.push(
                    if refit { "refit" } else { "build" },
                    start.elapsed().as_secs_f64(),
                );
                if ok {
                    let start = Instant::now();
                    two.rebuild_top();
                    timings.push("top", start.elapsed().as_secs_f64());
                }
                ok
            }
            _ => false,
        };
        if !done {
            return self.prepare(scene);
        }
        if let Some(prepared) = self.prepared.as_mut() {
            prepared.0 = Arc::clone(scene);
        }
        Ok(timings)
    }

    fn render(&self, settings: &RenderSettings) -> Result<Frame, RenderError> {
        let (scene, built) = self.prepared.as_ref().ok_or(RenderError::NotPrepared)?;
        with_built!(built, a => render_frame(scene, a, settings))
    }

    /// The structure's figures; a two-level form counts each distinct mesh's structure
    /// once.
    fn structure(&self) -> Option<AccelStats> {
        let (_, built) = self.prepared.as_ref()?;
        Some(with_built!(built, a => a.stats()))
    }

    fn batch_tracer(&self) -> Option<&dyn BatchTracer> {
        let (_, built) = self.prepared.as_ref()?;
        Some(with_built!(built, a => a as &dyn BatchTracer))
    }

    /// The structure's quality; `None` for a two-level form (not defined for it in this
    /// version).
    fn quality(&self, params: &QualityParams) -> Option<StructureQuality> {
        let (_, built) = self.prepared.as_ref()?;
        with_built!(built, a => a.quality(params))
    }

    /// The structure's quality for a flat scene; the flat part's structure's for a
    /// two-level form.
    fn flat_quality(&self, params: &QualityParams) -> Option<StructureQuality> {
        match self.prepared.as_ref()? {
            (_, Built::Flat(a)) => a.quality(params),
            (_, Built::TwoLevel(two)) => two.flat().quality(params),
        }
    }

    fn trace_rays(
        &self,
        rays: &[Ray],
        count: bool,
    ) -> Result<(Vec<Option<Hit>>, Option<RayCounters>), RenderError> {
        let (_, built) = self.prepared.as_ref().ok_or(RenderError::NotPrepared)?;
        Ok(with_built!(built, a => counted_if(
            count,
            || trace_counted(a, rays),
            || trace_counted(a, rays),
        )))
    }

    /// Any hits through the structure's `occluded_batch`, in parallel chunks like
    /// [`Renderer::trace_rays`].
    fn occlude_rays(
        &self,
        rays: &[Ray],
        count: bool,
    ) -> Result<(Vec<bool>, Option<RayCounters>), RenderError> {
        let (_, built) = self.prepared.as_ref().ok_or(RenderError::NotPrepared)?;
        Ok(with_built!(built, a => counted_if(
            count,
            || occlude_counted(a, rays),
            || occlude_counted(a, rays),
        )))
    }
}

/// The answers of `counted` with its counters when `count` is set, else those of `plain`
/// (the same work, instantiated with [`NoCounters`], which count nothing for free).
fn counted_if<T>(
    count: bool,
    counted: impl FnOnce() -> (T, RayCounters),
    plain: impl FnOnce() -> (T, NoCounters),
) -> (T, Option<RayCounters>) {
    if count {
        let (answers, c) = counted();
        (answers, Some(c))
    } else {
        (plain().0, None)
    }
}

/// Rays per batch in [`trace_counted`].
const RAY_CHUNK: usize = 256;

/// Traces `rays` in parallel chunks through the batch entry point; counters are summed in
/// chunk order.
fn trace_counted<A: Accel, C: Counters>(accel: &A, rays: &[Ray]) -> (Vec<Option<Hit>>, C) {
    in_chunks(rays, None, |r, out, c| accel.intersect_batch(r, out, c))
}

/// [`trace_counted`] for any-hit queries, through the batch entry point `occluded_batch`.
fn occlude_counted<A: Accel, C: Counters>(accel: &A, rays: &[Ray]) -> (Vec<bool>, C) {
    in_chunks(rays, false, |r, out, c| accel.occluded_batch(r, out, c))
}

/// Runs `batch` over [`RAY_CHUNK`]-ray chunks of `rays` in parallel, each writing its
/// chunk of the answers (initially `empty`); the counters are summed in chunk order, so
/// they do not depend on the thread count.
fn in_chunks<T: Clone + Send, C: Counters>(
    rays: &[Ray],
    empty: T,
    batch: impl Fn(&[Ray], &mut [T], &mut C) + Sync,
) -> (Vec<T>, C) {
    let mut answers = vec![empty; rays.len()];
    let counters: Vec<C> = answers
        .par_chunks_mut(RAY_CHUNK)
        .zip(rays.par_chunks(RAY_CHUNK))
        .map(|(out, rays)| {
            let mut c = C::default();
            batch(rays, out, &mut c);
            c
        })
        .collect();
    let mut total = C::default();
    for c in &counters {
        total.merge(c);
    }
    (answers, total)
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_core::{Camera, NO_HIT, SceneBuilder, Sphere, Vec3};
    use raybench_naive::NaiveAccel;

    /// `f` on a pool of `n` threads.
    fn on_threads<T: Send>(n: usize, f: impl FnOnce() -> T + Send) -> T {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap();
        pool.install(f)
    }

    fn scene() -> Arc<Scene> {
        let mut b = SceneBuilder::new("test");
        b.add_sphere(Sphere::new(Vec3::ZERO, 1.0), 0).unwrap();
        Arc::new(b.build())
    }

    #[test]
    fn identical_on_any_thread_count_and_counts_exactly() {
        let mut r = CpuRenderer::<NaiveAccel>::with_default_build("naive", "test");
        assert_eq!(
            r.render(&RenderSettings::default()),
            Err(RenderError::NotPrepared)
        );
        r.prepare(&scene()).unwrap();
        let settings = RenderSettings {
            width: 37,
            height: 23,
            spp: 3,
            count: true,
            ..Default::default()
        };
        let frames: Vec<Frame> = [1, 2, 5]
            .iter()
            .map(|&n| on_threads(n, || r.render(&settings).unwrap()))
            .collect();
        for f in &frames[1..] {
            assert_eq!(f.color, frames[0].color);
            assert_eq!(f.ids, frames[0].ids);
            assert_eq!(f.t, frames[0].t);
            assert_eq!(f.stats, frames[0].stats);
        }
        // Centre ray plus three jittered samples per pixel, one primitive each.
        let rays = 37 * 23 * 4;
        assert_eq!(frames[0].stats.rays, rays);
        assert_eq!(frames[0].stats.counters.unwrap().prim_tests, rays);
        assert!(frames[0].ids.contains(&0) && frames[0].ids.contains(&NO_HIT));
    }

    /// `RenderSettings::camera` renders the prepared scene from another of its cameras: the
    /// same frame as a scene whose camera was that one, and an index out of range is an
    /// invalid setting.
    #[test]
    fn any_camera_of_the_prepared_scene_renders() {
        let two = |first: usize| {
            let cams = [
                Camera {
                    position: Vec3::new(0.0, 0.0, 5.0),
                    look_at: Vec3::ZERO,
                    up: Vec3::Y,
                    vfov_degrees: 40.0,
                },
                Camera {
                    position: Vec3::new(3.0, 4.0, 0.5),
                    look_at: Vec3::new(0.5, 0.0, 0.0),
                    up: Vec3::Y,
                    vfov_degrees: 50.0,
                },
            ];
            let mut b = SceneBuilder::new("two cameras");
            b.add_sphere(Sphere::new(Vec3::ZERO, 1.0), 0).unwrap();
            b.add_sphere(Sphere::new(Vec3::new(1.5, 0.0, 0.0), 0.5), 0)
                .unwrap();
            for i in [first, 1 - first] {
                b.add_camera(Some(&format!("c{i}")), cams[i]).unwrap();
            }
            Arc::new(b.build())
        };
        let settings = |camera| RenderSettings {
            width: 19,
            height: 17,
            camera,
            ..Default::default()
        };
        let mut r = CpuRenderer::<NaiveAccel>::with_default_build("naive", "test");
        r.prepare(&two(0)).unwrap();
        let mut other = CpuRenderer::<NaiveAccel>::with_default_build("naive", "test");
        other.prepare(&two(1)).unwrap();
        let from_second = r.render(&settings(Some(1))).unwrap();
        let second_first = other.render(&settings(None)).unwrap();
        assert_eq!(from_second.ids, second_first.ids);
        assert_eq!(from_second.t, second_first.t);
        assert_eq!(from_second.color, second_first.color);
        assert_ne!(from_second.ids, r.render(&settings(Some(0))).unwrap().ids);
        assert_eq!(
            r.render(&settings(None)).unwrap().ids,
            r.render(&settings(Some(0))).unwrap().ids
        );
        assert!(matches!(
            r.render(&settings(Some(2))),
            Err(RenderError::InvalidSettings(m)) if m.contains("2 camera(s)")
        ));
    }

    #[test]
    fn any_hits_agree_with_closest_hits_on_any_thread_count() {
        let mut r = CpuRenderer::<NaiveAccel>::with_default_build("naive", "test");
        assert_eq!(r.occlude_rays(&[], false), Err(RenderError::NotPrepared));
        r.prepare(&scene()).unwrap();
        // Rays through the sphere, clipped before it, and past it: 1000 of them, so that
        // the work spreads over several chunks.
        let rays: Vec<Ray> = (0..1000)
            .map(|i| {
                let x = (i % 40) as f32 * 0.07 - 1.4;
                let t_max = if i % 3 == 0 { 1.5 } else { f32::INFINITY };
                Ray::with_interval(Vec3::new(x, 0.1, 3.0), -Vec3::Z, 0.0, t_max)
            })
            .collect();
        let (hits, _) = r.trace_rays(&rays, false).unwrap();
        let expected: Vec<bool> = hits.iter().map(Option::is_some).collect();
        assert!(expected.contains(&true) && expected.contains(&false));
        let answers: Vec<_> = [1, 3]
            .iter()
            .map(|&n| on_threads(n, || r.occlude_rays(&rays, true).unwrap()))
            .collect();
        for (occluded, counters) in &answers {
            assert_eq!(occluded, &expected);
            assert_eq!(counters, &answers[0].1);
        }
        let (occluded, counters) = r.occlude_rays(&rays, false).unwrap();
        assert_eq!((occluded, counters), (expected, None));
    }

    #[test]
    fn support_check_refuses_scenes() {
        let mut r = CpuRenderer::<NaiveAccel>::with_default_build("naive", "test")
            .with_support_check(|g| {
                if g.is_empty() {
                    Ok(())
                } else {
                    Err("no primitives wanted".into())
                }
            })
            .without_test_counts();
        let scene = scene();
        assert_eq!(r.supports(&scene), Err("no primitives wanted".into()));
        assert!(matches!(
            r.prepare(&scene),
            Err(RenderError::Unsupported(_))
        ));
        assert!(!r.counts_tests());
        let plain = CpuRenderer::<NaiveAccel>::with_default_build("naive", "test");
        assert!(plain.supports(&scene).is_ok() && plain.counts_tests());
    }

    #[test]
    fn bad_sizes_are_refused() {
        let mut r = CpuRenderer::<NaiveAccel>::with_default_build("naive", "test");
        r.prepare(&scene()).unwrap();
        for (w, h) in [(0, 10), (10, 0), (100_000, 10)] {
            let s = RenderSettings {
                width: w,
                height: h,
                ..Default::default()
            };
            assert!(matches!(r.render(&s), Err(RenderError::InvalidSettings(_))));
        }
    }
}
