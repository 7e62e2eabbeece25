//! `raybench rays export`: a ray set of a scene written to a ray file.

use crate::args::{CameraArgs, load_scene, parse_ray_set};
use anyhow::Result;
use clap::{Args, Subcommand};
use raybench_core::ray_sets::{DEFAULT_AO_RAYS, DerivedParams};
use raybench_core::{RaySet, RenderSettings};
use raybench_registry::measure::{explicit_rays, primary_rays};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Subcommand)]
pub(crate) enum RaysCmd {
    /// Write a ray set of a scene to a ray file (`--rays-file` replays it).
    Export(ExportCmd),
}

#[derive(Args)]
pub(crate) struct ExportCmd {
    /// Scene (as for render).
    pub(crate) scene: String,
    /// Ray set: primary (in the renderer's tile order), incoherent, shadow, ao or diffuse.
    #[arg(long, default_value = "primary", value_parser = parse_ray_set)]
    pub(crate) rays: RaySet,
    /// The ray file to write (replaced).
    #[arg(long, value_name = "FILE")]
    pub(crate) out: PathBuf,
    /// Image width (primary rays; width x height incoherent rays).
    #[arg(long, default_value_t = 512)]
    pub(crate) width: u32,
    /// Image height.
    #[arg(long, default_value_t = 512)]
    pub(crate) height: u32,
    /// Seed of the derived sets' random numbers.
    #[arg(long, default_value_t = 0)]
    pub(crate) seed: u32,
    /// Ambient-occlusion rays per primary hit (--rays ao).
    #[arg(long, default_value_t = DEFAULT_AO_RAYS, value_name = "N")]
    pub(crate) ao_rays: u32,
    #[command(flatten)]
    pub(crate) camera: CameraArgs,
}

/// `raybench rays export`: the rays of a set written to a ray file.
pub(crate) fn export_rays(cmd: &ExportCmd, assets: &Path) -> Result<ExitCode> {
    let settings = RenderSettings {
        width: cmd.width,
        height: cmd.height,
        seed: cmd.seed,
        ..RenderSettings::default()
    };
    settings.validate()?;
    let scene = load_scene(&cmd.scene, assets, &cmd.camera, false)?;
    let params = DerivedParams {
        ao_rays: cmd.ao_rays,
        seed: cmd.seed,
        ..DerivedParams::default()
    };
    let rays = match explicit_rays(cmd.rays, &scene, &settings, &params)? {
        Some(batch) => batch.rays,
        None => primary_rays(&scene, &settings)?,
    };
    raybench_registry::rays_file::write(&cmd.out, &rays, cmd.rays.any_hit())?;
    eprintln!(
        "wrote {} {} rays ({}) of {} to {}",
        rays.len(),
        cmd.rays.name(),
        if cmd.rays.any_hit() {
            "any hit"
        } else {
            "closest hit"
        },
        scene.name,
        cmd.out.display()
    );
    Ok(ExitCode::SUCCESS)
}
