//! `raybench compare`: one scene with several backends, timed and checked against the
//! reference.

use crate::args::{
    CameraArgs, FrameArgs, RaysArgs, check_mode_fits, fmt_opt, load_scene, phase_line,
};
use anyhow::{Result, bail};
use clap::Args;
use raybench_registry::measure::{
    Measured, Prepared, measure, median, median_phases, prepare_for_mode,
};
use raybench_registry::progress::Progress;
use raybench_registry::{chosen_backends, compare_hits};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::ExitCode;

#[derive(Args)]
pub(crate) struct CompareCmd {
    /// Scene (as for render).
    pub(crate) scene: String,
    /// Comma-separated backends or BACKEND:PRESET build presets, the first being the
    /// reference (default: every available backend, naive first when it finishes in
    /// reasonable time).
    #[arg(long, value_delimiter = ',')]
    pub(crate) backends: Option<Vec<String>>,
    #[command(flatten)]
    pub(crate) frame: FrameArgs,
    #[command(flatten)]
    pub(crate) camera: CameraArgs,
    #[command(flatten)]
    pub(crate) rays: RaysArgs,
    /// Timed repetitions after one warm-up; the median is reported.
    #[arg(long, default_value_t = 3)]
    pub(crate) repeat: u32,
    /// Print exactly one JSON array on stdout.
    #[arg(long)]
    pub(crate) json: bool,
    /// Flatten the scene's instances first: every instanced primitive carried to world
    /// space and stored flat, ids unchanged (to compare a two-level structure with one over
    /// the flattened scene; refused over the memory budget).
    #[arg(long)]
    pub(crate) flatten: bool,
}

/// One row of `raybench compare --json`; the key set is documented in docs/cli.md.
#[derive(Serialize)]
pub(crate) struct CompareRow {
    pub(crate) backend: String,
    pub(crate) reference: bool,
    pub(crate) available: bool,
    pub(crate) reason: Option<String>,
    pub(crate) scene: String,
    pub(crate) mode: &'static str,
    pub(crate) ray_set: String,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) spp: u32,
    pub(crate) build_seconds: Option<f64>,
    pub(crate) render_seconds: Option<f64>,
    pub(crate) rays: Option<u64>,
    pub(crate) mrays_per_s: Option<f64>,
    pub(crate) tests_per_ray: Option<f64>,
    pub(crate) id_match: Option<f64>,
    pub(crate) hit_mismatch: Option<u64>,
    pub(crate) max_abs_dt: Option<f64>,
    /// Seconds per phase: `prepare.build`, `prepare.upload`, and the medians of the timed
    /// frames' phases (`render`; `upload`, `gpu`, `readback` on the GPU).
    pub(crate) phases: BTreeMap<String, f64>,
}

pub(crate) fn compare(cmd: &CompareCmd, assets: &Path) -> Result<ExitCode> {
    let settings = cmd.frame.settings(false);
    settings.validate()?;
    if cmd.repeat == 0 || cmd.repeat > 10_000 {
        bail!("--repeat must be in 1..=10000");
    }
    // Named backends are checked before the scene loads: a typo need not wait for it.
    if cmd.backends.is_some() {
        chosen_backends(cmd.backends.as_deref(), 0.0).map_err(anyhow::Error::msg)?;
    }
    let scene = load_scene(&cmd.scene, assets, &cmd.camera, cmd.flatten)?;
    check_mode_fits(&scene, settings.mode)?;
    let (ray_set, rays) = cmd.rays.batch(&scene, &settings)?;
    let work = cmd.rays.work(
        rays.as_ref(),
        &settings,
        scene.geometry.total_len(),
        cmd.repeat + 1,
    );
    let chosen = chosen_backends(cmd.backends.as_deref(), work).map_err(anyhow::Error::msg)?;
    if chosen.is_empty() {
        bail!("no backend to compare");
    }

    let mut rows = Vec::new();
    let mut reference: Option<Measured> = None;
    let mut disagree = false;
    let frames = cmd.repeat as usize + 1;
    let progress = Progress::new(chosen.len() * frames);
    for (i, b) in chosen.iter().enumerate() {
        let mut row = CompareRow {
            backend: b.name.into(),
            reference: i == 0,
            available: true,
            reason: None,
            scene: scene.name.clone(),
            mode: settings.mode.name(),
            ray_set: ray_set.clone(),
            width: settings.width,
            height: settings.height,
            spp: settings.spp,
            build_seconds: None,
            render_seconds: None,
            rays: None,
            mrays_per_s: None,
            tests_per_ray: None,
            id_match: None,
            hit_mismatch: None,
            max_abs_dt: None,
            phases: BTreeMap::new(),
        };
        progress.begin(format!("{}: build", b.name));
        let Prepared {
            renderer: r,
            build,
            phases: prepare_phases,
        } = match prepare_for_mode(b, &scene, settings.mode) {
            Ok(x) => x,
            Err(reason) => {
                progress.remove(frames);
                progress.note(&format!("skipping {}: {reason}", b.name));
                row.available = false;
                row.reason = Some(reason);
                rows.push(row);
                continue;
            }
        };
        progress.note(&format!(
            "{}: built in {build:.3} s, tracing {frames} times",
            b.name
        ));
        // The warm-up is counted and is what gets compared; timed runs count nothing.
        progress.begin(format!("{}: counted warm-up", b.name));
        let warm = measure(r.as_ref(), &settings, rays.as_ref(), true)?;
        progress.done();
        let mut times = Vec::new();
        let mut phases = Vec::new();
        for k in 1..=cmd.repeat {
            progress.begin(format!("{}: timed run {k}/{}", b.name, cmd.repeat));
            let m = measure(r.as_ref(), &settings, rays.as_ref(), false)?;
            progress.done();
            times.push(m.seconds);
            phases.push(m.phases);
        }
        let secs = median(times);
        let frame_phases = median_phases(&phases);
        if let Some(line) = phase_line(&prepare_phases, &frame_phases) {
            progress.note(&format!("{}: {line}", b.name));
        }
        row.phases = prepare_phases
            .0
            .iter()
            .map(|(n, s)| (format!("prepare.{n}"), *s))
            .chain(frame_phases.0.iter().map(|(n, s)| (n.clone(), *s)))
            .collect();
        row.build_seconds = Some(build);
        row.render_seconds = Some(secs);
        row.rays = Some(warm.rays);
        row.mrays_per_s = Some(warm.rays as f64 / secs.max(1e-12) / 1e6);
        row.tests_per_ray = warm
            .counters
            .filter(|_| r.counts_tests())
            .map(|c| c.prim_tests as f64 / warm.rays.max(1) as f64);
        match &reference {
            None => {
                row.reference = true;
                row.id_match = Some(1.0);
                row.hit_mismatch = Some(0);
                row.max_abs_dt = Some(0.0);
                reference = Some(warm);
            }
            Some(reference) => {
                let c = compare_hits(&reference.ids, &reference.t, &warm.ids, &warm.t);
                row.id_match = Some(c.id_match);
                row.hit_mismatch = Some(c.hit_mismatch);
                row.max_abs_dt = Some(c.max_abs_dt);
                if b.exact() && c.id_match < 1.0 {
                    disagree = true;
                }
            }
        }
        rows.push(row);
    }

    drop(progress);
    if cmd.json {
        outln!("{}", serde_json::to_string_pretty(&rows)?)?;
    } else {
        print_table(&rows)?;
    }
    if disagree {
        eprintln!("error: a raybench CPU backend disagrees with the reference");
        return Ok(ExitCode::from(3));
    }
    Ok(ExitCode::SUCCESS)
}

pub(crate) fn print_table(rows: &[CompareRow]) -> std::io::Result<()> {
    outln!(
        "{:<16} {:>10} {:>10} {:>10} {:>12} {:>10} {:>9} {:>8} {:>10}",
        "backend",
        "build s",
        "render s",
        "Mrays/s",
        "tests/ray",
        "id match",
        "hit diff",
        "max|dt|",
        "speed-up"
    )?;
    let base = rows.iter().find_map(|r| r.render_seconds);
    for r in rows {
        if !r.available {
            outln!(
                "{:<16} unavailable: {}",
                r.backend,
                r.reason.as_deref().unwrap_or("")
            )?;
            continue;
        }
        outln!(
            "{:<16} {:>10} {:>10} {:>10} {:>12} {:>10} {:>9} {:>8} {:>10}",
            r.backend,
            fmt_opt(r.build_seconds, |v| format!("{v:.4}")),
            fmt_opt(r.render_seconds, |v| format!("{v:.4}")),
            fmt_opt(r.mrays_per_s, |v| format!("{v:.3}")),
            fmt_opt(r.tests_per_ray, |v| format!("{v:.1}")),
            fmt_opt(r.id_match, |v| format!("{:.4}%", v * 100.0)),
            fmt_opt(r.hit_mismatch, |v| v.to_string()),
            fmt_opt(r.max_abs_dt, |v| format!("{v:.1e}")),
            fmt_opt(r.render_seconds.zip(base), |(s, b)| format!(
                "{:.1}x",
                b / s.max(1e-12)
            )),
        )?;
    }
    Ok(())
}
