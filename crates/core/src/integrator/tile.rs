//! Tiles: the pieces of an image that integrators render independently, the order of a
//! tile's pixels, and the assembly of tiles into a frame.

use crate::Counters;
use crate::Hit;
use crate::frame::{Frame, FrameStats, NO_HIT};
use glam::Vec3;

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
pub(super) fn id_t_buffers(hits: &[Option<Hit>]) -> (Vec<u32>, Vec<f32>) {
    (
        hits.iter().map(|h| h.map_or(NO_HIT, |h| h.prim)).collect(),
        hits.iter()
            .map(|h| h.map_or(f32::INFINITY, |h| h.t))
            .collect(),
    )
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
