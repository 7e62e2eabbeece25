//! `raybench report`, `merge` and `compare-results`: the harness's front end.

use crate::args::{parse_mode, parse_ray_set};
use anyhow::Result;
use clap::Args;
use raybench_core::ray_sets::DEFAULT_AO_RAYS;
use raybench_core::{Mode, RaySet};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Args)]
pub(crate) struct ReportCmd {
    /// The small matrix: under 5 minutes on a 2-core machine (what the README's main
    /// command runs). Without --backends it leaves the GPU backends out when their adapter
    /// is a software one (lavapipe), saying so.
    #[arg(long)]
    pub(crate) quick: bool,
    /// Comma-separated scenes (default: the built-in scenes of the matrix; `raybench scenes` lists them).
    #[arg(long, value_delimiter = ',')]
    pub(crate) scenes: Option<Vec<String>>,
    /// Comma-separated backends, or build presets as BACKEND:PRESET (default: every backend
    /// but the pinned variants).
    #[arg(long, value_delimiter = ',')]
    pub(crate) backends: Option<Vec<String>>,
    /// Comma-separated modes (cast, whitted, path, mip, composite; default: all).
    #[arg(long, value_delimiter = ',', value_parser = parse_mode)]
    pub(crate) modes: Option<Vec<Mode>>,
    /// Output folder (created; files in it are replaced).
    #[arg(long, default_value = "target/raybench-report", value_name = "DIR")]
    pub(crate) out: PathBuf,
    /// Run part I of N of the matrix (1-based), split by scene: `--shard 2/4`.
    #[arg(long, value_parser = parse_shard, default_value = "1/1", value_name = "I/N")]
    pub(crate) shard: (u32, u32),
    /// Image side of the main matrix (default 256 with --quick, else 512).
    #[arg(long)]
    pub(crate) size: Option<u32>,
    /// Timed repetitions per backend and workload, taken in rounds that rotate the
    /// backends: `auto` (the default) repeats from 6 to 30 times until the median's 95 %
    /// interval is within 3 % or the workload's time budget is spent; N takes exactly N.
    #[arg(long, value_parser = parse_repeat, value_name = "auto|N")]
    pub(crate) repeat: Option<raybench_report::rounds::Repeat>,
    /// Milliseconds a timed repetition lasts at least: a shorter workload is run several
    /// times within it, and its time per run reported (default 15 with --quick, else 100).
    #[arg(long, value_name = "MS")]
    pub(crate) min_sample: Option<f64>,
    /// Leave out the scaling experiments.
    #[arg(long)]
    pub(crate) no_scaling: bool,
    /// Run only these scaling experiments (primitives, pixels, spp, heightfield, bezier,
    /// presets, instancing, motion).
    #[arg(long, value_delimiter = ',', value_name = "A,B")]
    pub(crate) experiments: Option<Vec<String>>,
    /// Worker threads (default: all cores; at most 1024).
    #[arg(long)]
    pub(crate) threads: Option<usize>,
    /// Pin each worker thread to a core (recorded in the report): steadier timings where
    /// the scheduler would move threads between cores; no help against other processes on
    /// the same cores (docs/report.md).
    #[arg(long)]
    pub(crate) pin: bool,
    /// Rank a backend on another device (the GPU) by its device time (the kernels'
    /// execution) rather than by the wall-clock time of the whole call.
    #[arg(long)]
    pub(crate) device_time: bool,
    /// An earlier report (its folder or its results.json) to set this run beside: REPORT.md
    /// gains a "Before and after" section (as `compare-results` prints).
    #[arg(long, value_name = "DIR")]
    pub(crate) baseline: Option<PathBuf>,
    /// Comma-separated ray sets of the ray-casting workloads (primary, incoherent, shadow,
    /// ao, diffuse; default: all).
    #[arg(long, value_delimiter = ',', value_parser = parse_ray_set, value_name = "SET,...")]
    pub(crate) rays: Option<Vec<RaySet>>,
    /// Ambient-occlusion rays per primary hit of the `ao` workloads.
    #[arg(long, default_value_t = DEFAULT_AO_RAYS, value_name = "N")]
    pub(crate) ao_rays: u32,
    /// Replay a ray file (`raybench rays export`, docs/rays-format.md) on every scene as
    /// the workload `cast-file` (the only ray-casting workload unless --rays names sets).
    #[arg(long, value_name = "FILE")]
    pub(crate) rays_file: Option<PathBuf>,
}

pub(crate) fn parse_repeat(s: &str) -> Result<raybench_report::rounds::Repeat, String> {
    use raybench_report::rounds::Repeat;
    match s.trim() {
        "auto" => Ok(Repeat::Auto),
        n => match n.parse::<u32>() {
            Ok(n @ 1..=100) => Ok(Repeat::Fixed(n)),
            _ => Err(format!("'{s}' is neither auto nor a count in 1..=100")),
        },
    }
}

pub(crate) fn parse_shard(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("'{s}' is not I/N with 1 <= I <= N (for example 2/4)");
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let (i, n): (u32, u32) = (
        i.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if i == 0 || n == 0 || i > n {
        return Err(bad());
    }
    Ok((i, n))
}

#[derive(Args)]
pub(crate) struct MergeCmd {
    /// Report folders (each with a results.json).
    #[arg(required = true)]
    pub(crate) dirs: Vec<PathBuf>,
    /// Output folder of the merged report (not one of the merged folders).
    #[arg(long, value_name = "DIR")]
    pub(crate) out: PathBuf,
    /// Merge a set that lacks some shards of its plan, listing the missing ones (and the
    /// scenes and experiments they hold) under Skipped.
    #[arg(long)]
    pub(crate) allow_partial: bool,
    /// Merge shards that ran on different CPU models (their timings share the tables but
    /// compare only within a shard; the report says so).
    #[arg(long)]
    pub(crate) allow_mixed_machines: bool,
}

#[derive(Args)]
pub(crate) struct CompareResultsCmd {
    /// The earlier run: a report folder or its results.json.
    pub(crate) before: PathBuf,
    /// The newer run.
    pub(crate) after: PathBuf,
    /// Print the comparison as JSON instead of markdown.
    #[arg(long)]
    pub(crate) json: bool,
}

pub(crate) fn report(cmd: &ReportCmd, assets: &Path) -> Result<ExitCode> {
    let opts = raybench_report::Options {
        quick: cmd.quick,
        scenes: cmd.scenes.clone(),
        backends: cmd.backends.clone(),
        modes: cmd.modes.clone(),
        out: cmd.out.clone(),
        shard: cmd.shard,
        size: cmd.size,
        repeat: cmd.repeat,
        min_sample: cmd.min_sample.map(|ms| ms / 1000.0),
        scaling: !cmd.no_scaling,
        experiments: cmd.experiments.clone(),
        ray_sets: cmd.rays.clone(),
        ao_rays: cmd.ao_rays,
        rays_file: cmd.rays_file.clone(),
        assets: assets.to_path_buf(),
        threads: rayon::current_num_threads(),
        command: std::env::args().collect::<Vec<_>>().join(" "),
        baseline: cmd.baseline.clone(),
        device_time: cmd.device_time,
        pin: cmd.pin,
    };
    let results = raybench_report::run(&opts)?;
    // The empty scene's fixed cost alone is a shard's whole part of a sharded plan, but no
    // report on its own.
    let sharded = results.shards.first().is_some_and(|s| s.count > 1);
    if results.runs.is_empty()
        && results.scaling.is_empty()
        && (results.empty_scene.is_empty() || !sharded)
    {
        let why: Vec<String> = results
            .skipped
            .iter()
            .map(|k| format!("{} {}: {}", k.kind, k.name, k.reason))
            .collect();
        if why.is_empty() {
            eprintln!("error: nothing ran: the options leave no workload to run");
        } else {
            eprintln!(
                "error: nothing ran ({}); REPORT.md lists what was skipped",
                why.join("; ")
            );
        }
        return Ok(ExitCode::FAILURE);
    }
    let failed: Vec<String> = results
        .runs
        .iter()
        .filter(|r| r.exact && r.equality.as_ref().is_some_and(|e| !e.pass))
        .map(|r| format!("{} on {} ({}, {})", r.backend, r.scene, r.mode, r.ray_set))
        .collect();
    if !failed.is_empty() {
        eprintln!(
            "error: raybench CPU backends disagree with the reference: {}",
            failed.join("; ")
        );
        return Ok(ExitCode::from(3));
    }
    Ok(ExitCode::SUCCESS)
}

/// `raybench merge`: the shards' results joined into one report.
pub(crate) fn merge(cmd: &MergeCmd) -> Result<ExitCode> {
    let allow = raybench_report::Allow {
        partial: cmd.allow_partial,
        mixed_machines: cmd.allow_mixed_machines,
    };
    raybench_report::merge(&cmd.dirs, &cmd.out, allow)?;
    Ok(ExitCode::SUCCESS)
}

/// `raybench compare-results`: per workload the speed ratio of two reports, as Markdown or
/// JSON on stdout.
pub(crate) fn compare_results(cmd: &CompareResultsCmd) -> Result<ExitCode> {
    use raybench_report::baseline;
    let before = baseline::read(&cmd.before)?;
    let after = baseline::read(&cmd.after)?;
    let c = baseline::compare(&before, &after);
    if cmd.json {
        outln!("{}", serde_json::to_string_pretty(&c)?)?;
    } else {
        out!(
            "{}",
            baseline::markdown(
                &c,
                &cmd.before.display().to_string(),
                &cmd.after.display().to_string()
            )
        )?;
    }
    Ok(ExitCode::SUCCESS)
}
