//! Per-pixel integrators, run tile by tile. The render crate decides how tiles are spread
//! over threads; a tile's output depends only on the tile, so frames are identical on any
//! thread count.

use crate::camera::{Camera, CameraRays};
use crate::renderer::{Mode, RenderError, RenderSettings};
use crate::scene::Scene;
use crate::{Accel, Counters};

mod cast;
mod mip_composite;
mod path;
mod tile;
mod wavefront;
mod whitted;

pub use cast::{cast_light, shade_cast};
pub use mip_composite::shade_volumes;
pub use path::{DIMENSIONS_PER_BOUNCE, ROULETTE_DEPTH, SHADOW_SHORTEN};
pub use tile::{PIXEL_BLOCK, Tile, TileOutput, assemble, tile_pixels, tiles};
use wavefront::Wavefront;
pub use whitted::{AMBIENT, HEADLIGHT_NOTE, headlight};

/// Renders one tile with the integrator of `settings.mode`, tracing the tile's rays through
/// `accel`'s batch entry point.
#[must_use]
pub fn render_tile<A: Accel, C: Counters>(
    scene: &Scene,
    accel: &A,
    camera: &CameraRays,
    settings: &RenderSettings,
    tile: Tile,
) -> TileOutput<C> {
    let st = Wavefront::new(accel, camera, settings, tile);
    match settings.mode {
        Mode::Cast => cast::cast_tile(scene, st, shade_cast),
        Mode::Mip | Mode::Composite => {
            let composite = settings.mode == Mode::Composite;
            cast::cast_tile(scene, st, |s, l, r, h| shade_volumes(s, l, r, h, composite))
        }
        Mode::Whitted => whitted::whitted_tile(scene, st),
        Mode::Path => path::path_tile(scene, st),
    }
}

impl Scene {
    /// The camera that renders a frame with `settings`: [`Scene::cameras`]`[i]` for
    /// `settings.camera == Some(i)`, else [`Scene::camera`].
    ///
    /// # Errors
    /// [`RenderError::InvalidSettings`] when the scene has no camera of that index.
    pub fn view(&self, settings: &RenderSettings) -> Result<&Camera, RenderError> {
        match settings.camera {
            None => Ok(&self.camera),
            Some(i) => self
                .cameras
                .get(i as usize)
                .map(|c| &c.camera)
                .ok_or_else(|| {
                    RenderError::InvalidSettings(format!(
                        "camera index {i} is out of range: scene '{}' has {} camera(s)",
                        self.name,
                        self.cameras.len()
                    ))
                }),
        }
    }
}
