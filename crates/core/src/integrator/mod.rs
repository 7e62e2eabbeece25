//! Per-pixel integrators, run tile by tile. The render crate decides how tiles are spread
//! over threads; a tile's output depends only on the tile, so frames are identical on any
//! thread count.

use crate::Hit;
use crate::Ray;
use crate::camera::CameraRays;
use crate::frame::{Frame, FrameStats, NO_HIT};
use crate::material::{Light, MaterialKind};
use crate::renderer::{Mode, RenderSettings};
use crate::scene::Scene;
use crate::{Accel, Counters};
use glam::Vec3;

mod mip_composite;
mod path;
mod wavefront;
mod whitted;

pub use mip_composite::shade_volumes;
pub use path::{DIMENSIONS_PER_BOUNCE, ROULETTE_DEPTH, SHADOW_SHORTEN};
use wavefront::Wavefront;
pub use whitted::AMBIENT;

/// A rectangle of pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    /// Left column.
    pub x0: u32,
    /// Top row.
    pub y0: u32,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
}

/// Splits a `width x height` image into `size x size` tiles (smaller at the right and
/// bottom edges), row by row.
#[must_use]
pub fn tiles(width: u32, height: u32, size: u32) -> Vec<Tile> {
    let size = size.max(1);
    let mut out = Vec::new();
    for y0 in (0..height).step_by(size as usize) {
        for x0 in (0..width).step_by(size as usize) {
            out.push(Tile {
                x0,
                y0,
                width: size.min(width - x0),
                height: size.min(height - y0),
            });
        }
    }
    out
}

/// The pixels of one tile, in [`tile_pixels`] order.
#[derive(Clone, Debug)]
pub struct TileOutput<C> {
    /// Which tile.
    pub tile: Tile,
    /// Linear colour.
    pub color: Vec<Vec3>,
    /// Centre-ray primitive ids.
    pub ids: Vec<u32>,
    /// Centre-ray distances.
    pub t: Vec<f32>,
    /// Rays traced.
    pub rays: u64,
    /// Work counters.
    pub counters: C,
}

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
        Mode::Cast => cast_tile(scene, st, shade_cast),
        Mode::Mip | Mode::Composite => {
            let composite = settings.mode == Mode::Composite;
            cast_tile(scene, st, |s, l, r, h| shade_volumes(s, l, r, h, composite))
        }
        Mode::Whitted => whitted::whitted_tile(scene, st),
        Mode::Path => path::path_tile(scene, st),
    }
}

/// Side of the square pixel blocks a tile is ordered in.
pub const PIXEL_BLOCK: u32 = 4;

/// A tile's pixels `(x, y, y * width + x)` in the order every integrator traces them:
/// [`PIXEL_BLOCK`] x [`PIXEL_BLOCK`] blocks row by row, each block row by row (smaller
/// blocks at the tile's right and bottom edges). Consecutive rays then cover compact
/// squares of the image, which is what packet backends group (Embree's 4 x 4 packets); the
/// order changes no pixel's value, since each pixel's work depends only on the pixel.
pub fn tile_pixels(tile: Tile, width: u32) -> impl Iterator<Item = (u32, u32, u32)> {
    // Plain loops into a vector: nested `flat_map`s cost a fifth of a packet-traced frame.
    let mut out = Vec::with_capacity((tile.width * tile.height) as usize);
    let b = PIXEL_BLOCK;
    for by in (tile.y0..tile.y0 + tile.height).step_by(b as usize) {
        let y_end = (by + b).min(tile.y0 + tile.height);
        for bx in (tile.x0..tile.x0 + tile.width).step_by(b as usize) {
            let x_end = (bx + b).min(tile.x0 + tile.width);
            for y in by..y_end {
                for x in bx..x_end {
                    out.push((x, y, y * width + x));
                }
            }
        }
    }
    out.into_iter()
}

/// The id and `t` buffers from the centre rays' hits.
fn id_t_buffers(hits: &[Option<Hit>]) -> (Vec<u32>, Vec<f32>) {
    (
        hits.iter().map(|h| h.map_or(NO_HIT, |h| h.prim)).collect(),
        hits.iter()
            .map(|h| h.map_or(f32::INFINITY, |h| h.t))
            .collect(),
    )
}

/// Direction light travels in ray-casting mode: the scene's first directional light, else a
/// fixed light from above-front-right.
#[must_use]
pub fn cast_light(scene: &Scene) -> Vec3 {
    scene
        .lights
        .iter()
        .find_map(|l| match *l {
            Light::Directional { direction, .. } => Some(direction),
            Light::Point { .. } => None,
        })
        .unwrap_or_else(|| Vec3::new(-0.4, -1.0, -0.6).normalize())
}

/// Ray-casting shading: base colour times a mix of `|cos|` to the viewer and a directional
/// light (no shadows), plus emission. Deliberately simple: this mode measures visibility.
#[inline]
#[must_use]
pub fn shade_cast(scene: &Scene, light_dir: Vec3, ray: &Ray, hit: Option<&Hit>) -> Vec3 {
    let Some(hit) = hit else {
        return scene.background_along(ray.dir);
    };
    let m = scene.material_of(hit.prim);
    let view = -ray.dir.normalize_or_zero();
    let cos_view = hit.normal.dot(view);
    // Face the normal towards the viewer.
    let n = if cos_view < 0.0 {
        -hit.normal
    } else {
        hit.normal
    };
    let diffuse = n.dot(-light_dir).max(0.0);
    let albedo = match m.kind {
        MaterialKind::Diffuse => m.base_color,
        MaterialKind::Mirror => m.specular.max(Vec3::splat(0.2)),
        MaterialKind::Glass => Vec3::new(0.75, 0.85, 0.9),
    };
    albedo * (0.35 * cos_view.abs() + 0.65 * diffuse) + m.emission
}

/// Camera rays only, shaded by `shade` (ray casting, and the volume modes, which integrate
/// the volumes along the camera ray up to its surface hit).
fn cast_tile<A: Accel, C: Counters>(
    scene: &Scene,
    mut st: Wavefront<A, C>,
    shade: impl Fn(&Scene, Vec3, &Ray, Option<&Hit>) -> Vec3,
) -> TileOutput<C> {
    let light_dir = cast_light(scene);
    let spp = st.settings.spp;
    if spp <= 1 {
        for ((c, r), h) in st
            .color
            .iter_mut()
            .zip(&st.centre_rays)
            .zip(&st.centre_hits)
        {
            *c = shade(scene, light_dir, r, h.as_ref());
        }
    } else {
        // Jittered samples for colour; ids and t stay those of the centre ray.
        for s in 0..spp {
            let rays: Vec<Ray> = st.camera_rays(s).map(|(_, ray, _)| ray).collect();
            let hits = st.trace(&rays);
            for ((acc, r), h) in st.color.iter_mut().zip(&rays).zip(&hits) {
                *acc += shade(scene, light_dir, r, h.as_ref());
            }
        }
        let inv = 1.0 / spp as f32;
        for c in &mut st.color {
            *c *= inv;
        }
    }
    st.finish()
}

/// Assembles tile outputs (in any order) into a frame, summing rays and counters.
#[must_use]
pub fn assemble<C: Counters>(width: u32, height: u32, outputs: Vec<TileOutput<C>>) -> Frame {
    let n = width as usize * height as usize;
    let mut frame = Frame {
        width,
        height,
        color: vec![Vec3::ZERO; n],
        ids: vec![NO_HIT; n],
        t: vec![f32::INFINITY; n],
        stats: FrameStats::default(),
        timings: Default::default(),
    };
    let mut counters = C::default();
    for out in outputs {
        for (i, (_, _, pixel)) in tile_pixels(out.tile, width).enumerate() {
            let pixel = pixel as usize;
            frame.color[pixel] = out.color[i];
            frame.ids[pixel] = out.ids[i];
            frame.t[pixel] = out.t[i];
        }
        frame.stats.rays += out.rays;
        counters.merge(&out.counters);
    }
    frame.stats.counters = counters.counts();
    frame
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_the_image_once() {
        let ts = tiles(37, 20, 16);
        let area: u32 = ts.iter().map(|t| t.width * t.height).sum();
        assert_eq!(area, 37 * 20);
        assert_eq!(ts.len(), 3 * 2);
        assert!(tiles(0, 5, 16).is_empty());
    }
}
