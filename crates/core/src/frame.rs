//! The result of rendering one frame.

use crate::RayCounters;
use glam::Vec3;

/// The id buffer's value for pixels whose centre ray hit nothing.
pub const NO_HIT: u32 = u32::MAX;

/// Named durations in seconds (`build`, `upload`, `render`, `readback`, ...), in the order
/// they happened.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Timings(pub Vec<(String, f64)>);

impl Timings {
    /// Appends a phase.
    pub fn push(&mut self, name: impl Into<String>, seconds: f64) {
        self.0.push((name.into(), seconds));
    }

    /// The duration of phase `name`, if recorded.
    #[must_use]
    pub fn get(&self, name: &str) -> Option<f64> {
        self.0.iter().find(|(n, _)| n == name).map(|&(_, s)| s)
    }
}

/// What a frame cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameStats {
    /// Every ray traced (primary and secondary, closest-hit and any-hit).
    pub rays: u64,
    /// Ray/primitive tests and node or cell visits, when counting was on and the backend
    /// can count.
    pub counters: Option<RayCounters>,
}

/// A rendered frame: linear colour, and the primitive id and `t` of each pixel's centre ray.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGB per pixel, row by row from the top.
    pub color: Vec<Vec3>,
    /// Primitive id hit by each pixel's centre ray, [`NO_HIT`] for misses.
    pub ids: Vec<u32>,
    /// `t` of each pixel's centre-ray hit, `f32::INFINITY` for misses.
    pub t: Vec<f32>,
    /// Work done.
    pub stats: FrameStats,
    /// Named timing phases.
    pub timings: Timings,
}
