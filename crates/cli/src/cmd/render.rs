//! `raybench render`: one scene to an image, or a sequence of frames.

use crate::args::{CameraArgs, Exposure, FrameArgs, check_mode_fits, load_scene, phase_line};
use anyhow::{Result, bail};
use clap::Args;
use raybench_core::{Mode, RenderSettings, Scene, UpdatePolicy};
use raybench_registry::measure::{device_seconds, prepare, timed_seconds};
use raybench_registry::progress::Progress;
use raybench_registry::{backend, default_backend};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

#[derive(Args)]
pub(crate) struct RenderCmd {
    /// Scene: a file (.toml, .obj, .gltf, .glb, .ply), a built-in name or a generator (soup:1000).
    pub(crate) scene: String,
    /// Backend, or a build preset as BACKEND:PRESET (default: the fastest available).
    #[arg(long)]
    pub(crate) backend: Option<String>,
    #[command(flatten)]
    pub(crate) frame: FrameArgs,
    #[command(flatten)]
    pub(crate) camera: CameraArgs,
    /// Output image (default: SCENE.png): `.png` is 8-bit sRGB clamped to [0, 1]; `.exr`
    /// (OpenEXR, 32-bit float) and `.pfm` hold the unclamped linear radiance.
    #[arg(long, value_name = "FILE")]
    pub(crate) out: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) exposure: Exposure,
    /// Flatten the scene's instances first: every instanced primitive carried to world
    /// space and stored flat, ids unchanged (to compare a two-level structure with one over
    /// the flattened scene; refused over the memory budget).
    #[arg(long)]
    pub(crate) flatten: bool,
    /// Also write a false-colour image of primitive ids.
    #[arg(long, value_name = "FILE.png")]
    pub(crate) ids: Option<PathBuf>,
    /// Renders frames 0..N-1 of a moving scene (instance `keys` and `motion`, object
    /// `deform`), each image named after --out (and --ids) with the frame number:
    /// moving.png becomes moving-0000.png, moving-0001.png, ... A scene that does not move
    /// refuses N > 1 (its frames would be the same image).
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub(crate) frames: u32,
    /// How the structure follows the frames: `refit` (boxes recomputed bottom up, the
    /// tree's topology kept; a two-level form rebuilds its top level) or `rebuild`.
    /// Backends that cannot refit rebuild.
    #[arg(long, default_value = "refit", value_parser = parse_update)]
    pub(crate) update: UpdatePolicy,
}

pub(crate) fn parse_update(s: &str) -> Result<UpdatePolicy, String> {
    UpdatePolicy::from_name(s)
        .ok_or_else(|| format!("unknown update policy '{s}' (known: refit, rebuild)"))
}

/// Makes and prepares a renderer, or says why it cannot run this scene.
pub(crate) fn render(cmd: &RenderCmd, assets: &Path) -> Result<ExitCode> {
    let settings = cmd.frame.settings(false);
    settings.validate()?;
    let b = match &cmd.backend {
        Some(name) => backend(name).map_err(anyhow::Error::msg)?,
        None => default_backend(),
    };
    let out = cmd.out.clone().unwrap_or_else(|| {
        let stem = Path::new(&cmd.scene)
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("scene")
            .replace(':', "-");
        PathBuf::from(format!("{stem}.png"))
    });
    // Before loading and rendering: a long render must not be lost to a bad path.
    raybench_render::check_image_path(&out, &raybench_render::ImageFormat::ALL)?;
    let exposure = cmd.exposure.checked()?;
    if let Some(ids) = &cmd.ids {
        raybench_render::check_png_path(ids)?;
        // One file for both would keep only the image written last.
        if std::path::absolute(ids)? == std::path::absolute(&out)? {
            bail!(
                "--ids {} and --out {} name the same file: give the id image a name of its own",
                ids.display(),
                out.display()
            );
        }
    }
    raybench_registry::frames::check_frame_count(cmd.frames).map_err(anyhow::Error::msg)?;
    let scene = load_scene(&cmd.scene, assets, &cmd.camera, cmd.flatten)?;
    check_mode_fits(&scene, settings.mode)?;
    raybench_registry::frames::check_frames(&scene, cmd.frames).map_err(anyhow::Error::msg)?;
    if !scene.volumes.is_empty() && !matches!(settings.mode, Mode::Mip | Mode::Composite) {
        eprintln!(
            "note: the scene's {} volume(s) show only with --mode mip or --mode composite",
            scene.volumes.len()
        );
    }
    if cmd.frames > 1 {
        return render_frames(cmd, b, &scene, &settings, &out, exposure);
    }
    let progress = Progress::new(1);
    progress.begin(format!("{}: build", b.name));
    let p = prepare(b, &scene).map_err(|e| anyhow::anyhow!("backend '{}': {e}", b.name))?;
    progress.begin(format!(
        "{}: render {} {}x{}, {} spp",
        b.name,
        settings.mode.name(),
        settings.width,
        settings.height,
        settings.spp
    ));
    let frame = p.renderer.render(&settings)?;
    progress.done();
    drop(progress);
    let secs = timed_seconds(&frame.timings);
    eprintln!(
        "{}: build {:.3} s, render {:.3} s{}, {} rays, {:.2} Mrays/s",
        b.name,
        p.build,
        secs,
        device_seconds(&frame.timings).map_or_else(String::new, |g| format!(" (device {g:.3} s)")),
        frame.stats.rays,
        frame.stats.rays as f64 / secs.max(1e-12) / 1e6
    );
    if let Some(line) = phase_line(&p.phases, &frame.timings) {
        eprintln!("{}: {line}", b.name);
    }
    raybench_render::write_color(&frame, &out, exposure)?;
    eprintln!("wrote {}", out.display());
    if let Some(ids) = &cmd.ids {
        raybench_render::write_ids_png(&frame, ids)?;
        eprintln!("wrote {}", ids.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// `render --frames N`: frame 0 prepared, every later one updated by `--update`; per frame
/// the update's and the render's times, and the images numbered
/// ([`raybench_registry::frames::numbered`]).
pub(crate) fn render_frames(
    cmd: &RenderCmd,
    b: &raybench_registry::Backend,
    scene: &Arc<Scene>,
    settings: &RenderSettings,
    out: &Path,
    exposure: f32,
) -> Result<ExitCode> {
    use raybench_registry::frames::{advance, describe, numbered};
    let progress = Progress::new(cmd.frames as usize);
    progress.begin(format!("{}: build", b.name));
    let mut p = prepare(b, scene).map_err(|e| anyhow::anyhow!("backend '{}': {e}", b.name))?;
    let (mut update, mut trace) = (0.0, 0.0);
    for f in 0..cmd.frames {
        let phases = if f == 0 {
            p.phases.clone()
        } else {
            progress.begin(format!("{}: frame {f}: {}", b.name, cmd.update.name()));
            let (_, phases) = advance(p.renderer.as_mut(), scene, f, cmd.update)
                .map_err(|e| anyhow::anyhow!("backend '{}': {e}", b.name))?;
            update += phases.0.iter().map(|(_, s)| s).sum::<f64>();
            phases
        };
        progress.begin(format!("{}: frame {f}: render", b.name));
        let frame = p.renderer.render(settings)?;
        let secs = timed_seconds(&frame.timings);
        trace += secs;
        progress.done();
        progress.note(&format!(
            "frame {f}: {}; render {:.3} ms, {:.2} Mrays/s",
            describe(&phases),
            secs * 1e3,
            frame.stats.rays as f64 / secs.max(1e-12) / 1e6
        ));
        let path = numbered(out, f, cmd.frames);
        raybench_render::write_color(&frame, &path, exposure)?;
        if let Some(ids) = &cmd.ids {
            raybench_render::write_ids_png(&frame, &numbered(ids, f, cmd.frames))?;
        }
    }
    drop(progress);
    let n = f64::from(cmd.frames - 1);
    eprintln!(
        "{}: {} frames: build {:.3} ms, then update {:.3} ms per frame (mean, --update {}), \
         render {:.3} ms per frame (mean)",
        b.name,
        cmd.frames,
        p.build * 1e3,
        update / n * 1e3,
        cmd.update.name(),
        trace / f64::from(cmd.frames) * 1e3
    );
    eprintln!(
        "wrote {} .. {}",
        numbered(out, 0, cmd.frames).display(),
        numbered(out, cmd.frames - 1, cmd.frames).display()
    );
    Ok(ExitCode::SUCCESS)
}
