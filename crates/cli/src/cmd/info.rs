//! `raybench info`: a scene's primitives and each backend's structure quality.

use crate::args::{CameraArgs, RaysArgs, check_mode_fits, load_scene, parse_mode};
use anyhow::Result;
use clap::Args;
use raybench_core::{Mode, QualityParams, RenderSettings};
use raybench_registry::chosen_backends;
use raybench_registry::measure::{Prepared, measure, prepare_for_mode};
use raybench_report::results::{GRID_COLUMNS, Quality, TREE_COLUMNS};
use std::path::Path;
use std::process::ExitCode;

#[derive(Args)]
pub(crate) struct InfoCmd {
    /// Scene (as for render).
    pub(crate) scene: String,
    /// Comma-separated backends or BACKEND:PRESET build presets (default: all available).
    #[arg(long, value_delimiter = ',')]
    pub(crate) backends: Option<Vec<String>>,
    /// The probe's rays, whose work per ray is shown.
    #[command(flatten)]
    pub(crate) rays: RaysArgs,
    /// Width of the probe image (or width x height incoherent rays).
    #[arg(long, default_value_t = 128)]
    pub(crate) width: u32,
    /// Height of the probe image.
    #[arg(long, default_value_t = 128)]
    pub(crate) height: u32,
    /// Integrator of the probe: cast, whitted, path, mip or composite.
    #[arg(long, default_value = "cast", value_parser = parse_mode)]
    pub(crate) mode: Mode,
    /// Samples per pixel of the probe.
    #[arg(long, default_value_t = 1)]
    pub(crate) spp: u32,
    /// Maximum bounces of the probe.
    #[arg(long, default_value_t = 5)]
    pub(crate) max_depth: u32,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub(crate) threads: Option<usize>,
    /// Points sampled for each structure's EPO (end-point overlap), at most 1048576.
    #[arg(
        long,
        default_value_t = raybench_core::quality::DEFAULT_EPO_SAMPLES,
        value_parser = clap::value_parser!(u32)
            .range(1..=i64::from(raybench_core::quality::MAX_EPO_SAMPLES))
    )]
    pub(crate) epo_samples: u32,
    /// Flatten the scene's instances first: every instanced primitive carried to world
    /// space and stored flat, ids unchanged (to compare a two-level structure with one over
    /// the flattened scene; refused over the memory budget).
    #[arg(long)]
    pub(crate) flatten: bool,
    #[command(flatten)]
    pub(crate) camera: CameraArgs,
}

pub(crate) fn info(cmd: &InfoCmd, assets: &Path) -> Result<ExitCode> {
    // Named backends are checked before the scene loads, as in `compare`.
    if cmd.backends.is_some() {
        chosen_backends(cmd.backends.as_deref(), 0.0).map_err(anyhow::Error::msg)?;
    }
    let scene = load_scene(&cmd.scene, assets, &cmd.camera, cmd.flatten)?;
    check_mode_fits(&scene, cmd.mode)?;
    let g = &scene.geometry;
    outln!("scene       {}", scene.name)?;
    outln!("primitives  {}", g.total_len())?;
    if g.has_instances() {
        let stored: usize = g.meshes().iter().map(|m| m.len()).sum();
        outln!(
            "instances   {} of {} meshes ({} flat primitives and {stored} in the meshes \
             stored; the counts by kind below are the flat ones)",
            g.instances().len(),
            g.meshes().len(),
            g.len()
        )?;
    }
    // Counts aligned after the longest kind's name ("analytic solid / CSG tree").
    let kinds = g.count_by_kind();
    let width = kinds.iter().map(|(k, _)| k.name().len()).max().unwrap_or(0);
    for (kind, n) in kinds {
        outln!("  {:<width$} {n}", kind.name())?;
    }
    outln!("volumes     {}", scene.volumes.len())?;
    outln!("objects     {}", scene.objects.len())?;
    outln!("materials   {}", scene.materials.len())?;
    outln!("lights      {}", scene.lights.len())?;
    outln!("cameras     {}", scene.cameras.len())?;
    for (i, c) in scene.cameras.iter().enumerate() {
        let cam = c.camera;
        outln!(
            "  {i:<3} {:<20} from [{}, {}, {}] at [{}, {}, {}] fov {}",
            format!("'{}'", c.name),
            cam.position.x,
            cam.position.y,
            cam.position.z,
            cam.look_at.x,
            cam.look_at.y,
            cam.look_at.z,
            cam.vfov_degrees
        )?;
    }
    let bb = g.world_bounds();
    if bb.is_empty() {
        outln!("bounds      (none: no bounded primitives)")?;
    } else {
        outln!(
            "bounds      [{}, {}, {}] .. [{}, {}, {}]",
            bb.min.x,
            bb.min.y,
            bb.min.z,
            bb.max.x,
            bb.max.y,
            bb.max.z
        )?;
    }
    let settings = RenderSettings {
        width: cmd.width,
        height: cmd.height,
        spp: cmd.spp,
        mode: cmd.mode,
        max_depth: cmd.max_depth,
        ..RenderSettings::default()
    };
    settings.validate()?;
    let (ray_set, probe) = cmd.rays.batch(&scene, &settings)?;
    outln!(
        "probe       {} rays{}, {}x{}, mode {}, {} spp, max depth {}",
        ray_set,
        probe.as_ref().map_or(String::new(), |b| format!(
            " ({} {} rays)",
            b.rays.len(),
            if b.any_hit { "any-hit" } else { "closest-hit" }
        )),
        cmd.width,
        cmd.height,
        cmd.mode.name(),
        cmd.spp,
        cmd.max_depth
    )?;
    let work = cmd.rays.work(probe.as_ref(), &settings, g.total_len(), 1);
    let chosen = chosen_backends(cmd.backends.as_deref(), work).map_err(anyhow::Error::msg)?;
    outln!(
        "{:<16} {:>10} {:>14} {:>9} {:>10} {:>10}  structure",
        "backend",
        "build s",
        "memory bytes",
        "rays/px",
        "tests/ray",
        "visits/ray"
    )?;
    let params = QualityParams {
        epo_samples: cmd.epo_samples,
        ..QualityParams::default()
    };
    let mut qualities = Vec::new();
    for b in chosen {
        match prepare_for_mode(b, &scene, settings.mode) {
            Err(reason) => outln!("{:<16} unavailable: {reason}", b.name)?,
            Ok(Prepared {
                renderer: r, build, ..
            }) => {
                qualities.push((b.name, r.quality(&params).as_ref().map(Quality::from)));
                let s = r.structure().unwrap_or_default();
                let counts: Vec<String> =
                    s.counts.iter().map(|(k, v)| format!("{k}={v}")).collect();
                let m = measure(r.as_ref(), &settings, probe.as_ref(), true)?;
                let per_ray = |v: u64| format!("{:.2}", v as f64 / m.rays.max(1) as f64);
                let pixels = f64::from(cmd.width) * f64::from(cmd.height);
                outln!(
                    "{:<16} {:>10.4} {:>14} {:>9.2} {:>10} {:>10}  {}",
                    b.name,
                    build,
                    s.memory_bytes,
                    m.rays as f64 / pixels,
                    m.counters.map_or("-".into(), |c| per_ray(c.prim_tests)),
                    m.counters.map_or("-".into(), |c| per_ray(c.node_visits)),
                    if counts.is_empty() {
                        "(none)".into()
                    } else {
                        counts.join(" ")
                    }
                )?;
            }
        }
    }
    print_quality(&qualities, &params)?;
    Ok(ExitCode::SUCCESS)
}

/// `raybench info`'s structure quality: one table for trees, one for grids, then the
/// structures that cannot be read and the backends without one.
pub(crate) fn print_quality(
    qualities: &[(&str, Option<Quality>)],
    params: &QualityParams,
) -> std::io::Result<()> {
    outln!(
        "quality     SAH cost and EPO with C_t = {}, C_i = {}; EPO from {} points sampled by area \
         on triangles and spheres, +- its standard error",
        params.costs.traversal,
        params.costs.intersection,
        params.epo_samples
    )?;
    let table = |headers: [&str; 7], rows: Vec<(&str, [String; 7])>| -> std::io::Result<()> {
        if rows.is_empty() {
            return Ok(());
        }
        outln!(
            "{:<16} {:>10} {:>16} {:>9} {:>9} {:>14} {:>10}  {}",
            "backend",
            headers[0],
            headers[1],
            headers[2],
            headers[3],
            headers[4],
            headers[5],
            headers[6]
        )?;
        for (name, c) in rows {
            outln!(
                "{name:<16} {:>10} {:>16} {:>9} {:>9} {:>14} {:>10}  {}",
                c[0],
                c[1],
                c[2],
                c[3],
                c[4],
                c[5],
                c[6]
            )?;
        }
        Ok(())
    };
    let rows = |f: fn(&Quality) -> Option<[String; 7]>| {
        qualities
            .iter()
            .filter_map(|(name, q)| Some((*name, f(q.as_ref()?)?)))
            .collect::<Vec<_>>()
    };
    table(TREE_COLUMNS, rows(Quality::tree_columns))?;
    table(GRID_COLUMNS, rows(Quality::grid_columns))?;
    for (name, q) in qualities {
        match q {
            Some(Quality::NotReadable { reason }) => {
                outln!("{name:<16} not readable: {reason}")?;
            }
            None => outln!("{name:<16} no structure")?,
            Some(_) => {}
        }
    }
    let excluded = qualities.iter().find_map(|(_, q)| match q {
        Some(Quality::Tree {
            epo_excluded_primitives,
            ..
        }) => Some(*epo_excluded_primitives),
        _ => None,
    });
    if let Some(n @ 1..) = excluded {
        outln!(
            "            EPO leaves out {n} bounded primitives that are neither triangles nor spheres"
        )?;
    }
    Ok(())
}
