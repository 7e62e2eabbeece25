//! Animations: the frames of a moving scene (`raybench render --frames N`, the report's
//! `motion` experiment). A prepared renderer follows the scene from frame to frame through
//! [`Renderer::update`] (refit or rebuild, [`UpdatePolicy`]); every frame's scene comes from
//! [`Scene::at_frame`], so frames are deterministic and independent of the order they are
//! rendered in.

use raybench_core::{Renderer, Scene, Timings, UpdatePolicy};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Most frames one `--frames` renders.
pub const MAX_FRAMES: u32 = 100_000;

/// The image path of frame `frame` of `frames`: `path`'s stem, a dash, the frame number
/// zero-padded to four digits (more when `frames` needs them), and `path`'s extension
/// (`moving.png` -> `moving-0000.png`, `moving-0001.png`, ...). One frame keeps `path`.
#[must_use]
pub fn numbered(path: &Path, frame: u32, frames: u32) -> PathBuf {
    if frames <= 1 {
        return path.to_owned();
    }
    let digits = (frames - 1).to_string().len().max(4);
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("frame");
    let name = match path.extension().and_then(|e| e.to_str()) {
        Some(ext) => format!("{stem}-{frame:0digits$}.{ext}"),
        None => format!("{stem}-{frame:0digits$}"),
    };
    path.with_file_name(name)
}

/// Checks `--frames` alone, before a scene is loaded: between 1 and [`MAX_FRAMES`].
///
/// # Errors
/// The message saying so.
pub fn check_frame_count(frames: u32) -> Result<(), String> {
    if frames == 0 || frames > MAX_FRAMES {
        return Err(format!(
            "--frames {frames}: between 1 and {MAX_FRAMES} frames are rendered"
        ));
    }
    Ok(())
}

/// Whether `frames` frames of `scene` can be rendered: 1 to [`MAX_FRAMES`], and more than
/// one only for a scene that moves (a still scene's frames would be identical images: the
/// command refuses rather than render the same picture N times).
///
/// # Errors
/// Why not, in one sentence.
pub fn check_frames(scene: &Scene, frames: u32) -> Result<(), String> {
    check_frame_count(frames)?;
    if frames > 1 && !scene.is_moving() {
        return Err(format!(
            "--frames {frames}: scene '{}' does not move (no instance `keys` or `motion`, no \
             object `deform`: docs/scene-format.md), so its {frames} frames would be the \
             same image; render it once without --frames",
            scene.name
        ));
    }
    Ok(())
}

/// Brings `renderer`, prepared for a frame of `scene`, to frame `frame` by `policy`;
/// returns that frame's scene and the update's phases (`refit`, `build`, `top`).
///
/// # Errors
/// The scene's state at `frame` cannot be built, or the renderer fails to update.
pub fn advance(
    renderer: &mut dyn Renderer,
    scene: &Scene,
    frame: u32,
    policy: UpdatePolicy,
) -> Result<(Arc<Scene>, Timings), String> {
    let at = Arc::new(
        scene
            .at_frame(frame)
            .map_err(|e| format!("scene '{}' at frame {frame}: {e}", scene.name))?,
    );
    let timings = renderer.update(&at, policy).map_err(|e| e.to_string())?;
    Ok((at, timings))
}

/// `refit 0.182 ms, top 0.004 ms` (the phases of an update, in order).
#[must_use]
pub fn describe(timings: &Timings) -> String {
    timings
        .0
        .iter()
        .map(|(name, s)| format!("{name} {:.3} ms", s * 1e3))
        .collect::<Vec<_>>()
        .join(", ")
}
