//! The frame-level renderer interface that the harness talks to.

use crate::Hit;
use crate::Ray;
use crate::frame::{Frame, Timings};
use crate::limits;
use crate::scene::Scene;
use crate::{AccelStats, BatchTracer, QualityParams, RayCounters, StructureQuality};
use std::fmt;
use std::sync::Arc;

/// What to compute per pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Ray casting: one closest-hit ray per sample, simple shading, no secondary rays.
    #[default]
    Cast,
    /// Whitted ray tracing: shadow rays to point and directional lights, Lambert plus
    /// Blinn-Phong, mirror reflection, refraction with Fresnel weighting.
    Whitted,
    /// Monte Carlo path tracing: cosine-weighted diffuse bounces, next-event estimation,
    /// Russian roulette, many samples per pixel.
    Path,
    /// Maximum-intensity projection of the scene's volumes (the X-ray-like image): each
    /// camera ray shows the grey level of the largest value it meets before a surface.
    Mip,
    /// Direct volume rendering by emission-absorption compositing through each volume's
    /// transfer function, front to back, over the surface behind.
    Composite,
}

impl Mode {
    /// Every mode.
    pub const ALL: [Self; 5] = [
        Self::Cast,
        Self::Whitted,
        Self::Path,
        Self::Mip,
        Self::Composite,
    ];

    /// The name used on the command line.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Cast => "cast",
            Self::Whitted => "whitted",
            Self::Path => "path",
            Self::Mip => "mip",
            Self::Composite => "composite",
        }
    }

    /// The mode called `name`, if any.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// How `path` mode reaches light sources (`docs/sampling.md`); point and directional
/// lights are always sampled directly, as nothing else can reach them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LightSampling {
    /// Next-event estimation towards one chosen emitter (or the environment map) combined
    /// with BSDF sampling by multiple importance sampling (power heuristic).
    #[default]
    Mis,
    /// BSDF sampling only: emission counts when a path happens to hit it (the reference
    /// estimator the MIS one is compared with).
    Bsdf,
}

impl LightSampling {
    /// Both, in a fixed order.
    pub const ALL: [Self; 2] = [Self::Mis, Self::Bsdf];

    /// The name used on the command line.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Mis => "mis",
            Self::Bsdf => "bsdf",
        }
    }

    /// The estimator called `name`, if any.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// How [`Renderer::update`] brings a prepared structure to another frame of a moving scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum UpdatePolicy {
    /// Refit where the structure can ([`crate::Accel::refit`]: boxes recomputed bottom up,
    /// topology kept; a two-level form refits its bottom level and rebuilds its top level),
    /// else rebuild. Cheap per frame; the tree's quality decays as things move.
    #[default]
    Refit,
    /// Rebuild: what has moved is built anew (a two-level form rebuilds its flat part, the
    /// meshes that deformed and its top level).
    Rebuild,
}

impl UpdatePolicy {
    /// Both, in a fixed order.
    pub const ALL: [Self; 2] = [Self::Refit, Self::Rebuild];

    /// The name used on the command line.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Refit => "refit",
            Self::Rebuild => "rebuild",
        }
    }

    /// The policy called `name`, if any.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// Settings of one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderSettings {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Integrator.
    pub mode: Mode,
    /// Seed of the counter-based random numbers.
    pub seed: u32,
    /// Maximum number of bounces (modes with secondary rays).
    pub max_depth: u32,
    /// Whether to count ray/primitive tests and node visits.
    pub count: bool,
    /// How `path` mode samples emitters.
    pub light_sampling: LightSampling,
    /// Which of the scene's cameras renders the frame, by index into
    /// [`crate::Scene::cameras`]; `None`: [`crate::Scene::camera`] (the one selected when
    /// loading, overrides applied). One prepared structure serves every camera
    /// ([`crate::Scene::view`]).
    pub camera: Option<u32>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            spp: 1,
            mode: Mode::Cast,
            seed: 0,
            max_depth: 5,
            count: false,
            light_sampling: LightSampling::Mis,
            camera: None,
        }
    }
}

impl RenderSettings {
    /// Checks the settings against [`crate::limits`].
    ///
    /// # Errors
    /// [`RenderError::InvalidSettings`] naming the offending value.
    pub fn validate(&self) -> Result<(), RenderError> {
        let bad = |msg: String| Err(RenderError::InvalidSettings(msg));
        if self.width == 0 || self.height == 0 {
            return bad(format!(
                "image size {}x{} is empty: width and height must be at least 1",
                self.width, self.height
            ));
        }
        if self.width > limits::MAX_DIMENSION || self.height > limits::MAX_DIMENSION {
            return bad(format!(
                "image size {}x{} exceeds the limit of {} pixels per side",
                self.width,
                self.height,
                limits::MAX_DIMENSION
            ));
        }
        if self.spp == 0 || self.spp > limits::MAX_SPP {
            return bad(format!(
                "samples per pixel {} must be in 1..={}",
                self.spp,
                limits::MAX_SPP
            ));
        }
        let samples = u64::from(self.width) * u64::from(self.height) * u64::from(self.spp);
        if samples > limits::MAX_SAMPLES {
            return bad(format!(
                "width x height x spp = {samples} exceeds the limit of {}",
                limits::MAX_SAMPLES
            ));
        }
        if self.max_depth > limits::MAX_DEPTH {
            return bad(format!(
                "max depth {} exceeds the limit of {}",
                self.max_depth,
                limits::MAX_DEPTH
            ));
        }
        Ok(())
    }
}

/// Why a renderer could not produce a frame.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RenderError {
    /// The backend cannot run here (no adapter, no library), with the reason.
    Unavailable(String),
    /// The scene holds something the backend does not support, with the reason.
    Unsupported(String),
    /// `render` was called before `prepare`.
    NotPrepared,
    /// The settings are out of range.
    InvalidSettings(String),
    /// Anything else the backend reports.
    Backend(String),
}

impl fmt::Display for RenderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Unavailable(r) => write!(f, "backend unavailable: {r}"),
            Self::Unsupported(r) => write!(f, "scene not supported: {r}"),
            Self::NotPrepared => write!(f, "render called before prepare"),
            Self::InvalidSettings(r) => write!(f, "{r}"),
            Self::Backend(r) => write!(f, "{r}"),
        }
    }
}

impl std::error::Error for RenderError {}

/// A frame-level renderer: one backend, prepared once for a scene, then rendering any number
/// of frames. The CPU backends share one generic implementation over [`crate::Accel`].
///
/// This is what an integrator and a front end need; the clock stays outside core. A backend
/// reports the phases it alone can see ([`Timings`]: a GPU's upload, execution and readback)
/// as plain durations, and the harness's own contract (timed ray batches, the device a
/// backend runs on) is `raybench_registry::TimedRenderer`, built on this trait.
pub trait Renderer: Send + Sync {
    /// Short name (`naive`, `bvh`, ...).
    fn name(&self) -> &str;

    /// One-line description.
    fn description(&self) -> &str;

    /// Whether the backend can run on this machine, or why not.
    ///
    /// # Errors
    /// The reason it cannot run.
    fn availability(&self) -> Result<(), String> {
        Ok(())
    }

    /// Whether the backend supports every primitive kind and feature of `scene`.
    ///
    /// # Errors
    /// The reason it does not.
    fn supports(&self, _scene: &Scene) -> Result<(), String> {
        Ok(())
    }

    /// Whether the backend can render frames in `mode` (every backend of raybench can; the GPU
    /// refuses the volume modes for a prepared scene whose volumes do not fit its buffers).
    ///
    /// # Errors
    /// The reason it cannot.
    fn supports_mode(&self, _mode: Mode) -> Result<(), String> {
        Ok(())
    }

    /// Whether the backend counts ray/primitive tests.
    fn counts_tests(&self) -> bool {
        true
    }

    /// Prepares for `scene` (builds acceleration structures, uploads data) and returns the
    /// timing of each preparation phase.
    ///
    /// # Errors
    /// When the backend is unavailable or does not support the scene.
    fn prepare(&mut self, scene: &Arc<Scene>) -> Result<Timings, RenderError>;

    /// Prepares for `scene`, another frame of the prepared scene ([`Scene::at_frame`]: the
    /// same ids and topology), by `policy`, and returns the timing of each phase: `refit`
    /// (bottom-up box updates), `build` (structures built anew) and, for a two-level form,
    /// `top` (its top level, rebuilt every frame). The default rebuilds everything through
    /// [`Renderer::prepare`] (its `build` phase), whatever the policy; so does any
    /// renderer for a scene whose topology differs or before a first `prepare`.
    ///
    /// # Errors
    /// As [`Renderer::prepare`].
    fn update(
        &mut self,
        scene: &Arc<Scene>,
        _policy: UpdatePolicy,
    ) -> Result<Timings, RenderError> {
        self.prepare(scene)
    }

    /// Renders one frame of the prepared scene.
    ///
    /// # Errors
    /// When not prepared, or the settings are out of range.
    fn render(&self, settings: &RenderSettings) -> Result<Frame, RenderError>;

    /// Statistics of the prepared structure, if any.
    fn structure(&self) -> Option<AccelStats>;

    /// The prepared structure's quality figures ([`crate::Accel::quality`]): `None` before
    /// `prepare` and for backends without a readable structure. Samples points for the EPO:
    /// once per prepared scene, not per frame.
    fn quality(&self, _params: &QualityParams) -> Option<StructureQuality> {
        None
    }

    /// The quality of the prepared structure over the scene's flat primitives: for a
    /// scene with instances the bottom-level structure of its flat part (where a deformed
    /// flat mesh's tree decays), else the same as [`Renderer::quality`]. `None` as there.
    fn flat_quality(&self, _params: &QualityParams) -> Option<StructureQuality> {
        None
    }

    /// The prepared CPU structure's batch entry points, for timing ray batches without
    /// frames (`tests/benches/peers.rs`); `None` before `prepare` and for backends that are
    /// not an [`crate::Accel`] on this CPU (the GPU).
    fn batch_tracer(&self) -> Option<&dyn BatchTracer> {
        None
    }

    /// Closest hits of arbitrary rays (edge-aimed rays, incoherent ray sets) against the
    /// prepared scene, with the work counters when `count` is set and the backend counts.
    ///
    /// # Errors
    /// When not prepared, or the backend traces only whole frames.
    fn trace_rays(
        &self,
        _rays: &[Ray],
        _count: bool,
    ) -> Result<(Vec<Option<Hit>>, Option<RayCounters>), RenderError> {
        Err(RenderError::Unsupported(format!(
            "backend '{}' traces only whole frames",
            self.name()
        )))
    }

    /// Any-hit queries (shadow and ambient-occlusion rays): per ray, whether any primitive
    /// is hit within its `[t_min, t_max]`, with the work counters when `count` is set and
    /// the backend counts. The answer must equal `trace_rays(..)[i].is_some()` for every
    /// ray; only the work may differ (an any-hit walk stops at the first hit it finds).
    ///
    /// The default is exactly that: [`Renderer::trace_rays`] and `is_some()`, correct for
    /// any backend, with the closest-hit work counted. A CPU backend overrides it with its
    /// structure's `occluded_batch`, the GPU backends with their any-hit kernel.
    ///
    /// # Errors
    /// As [`Renderer::trace_rays`].
    fn occlude_rays(
        &self,
        rays: &[Ray],
        count: bool,
    ) -> Result<(Vec<bool>, Option<RayCounters>), RenderError> {
        let (hits, counters) = self.trace_rays(rays, count)?;
        Ok((hits.iter().map(Option::is_some).collect(), counters))
    }
}
