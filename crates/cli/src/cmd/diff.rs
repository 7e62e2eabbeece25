//! `raybench diff A B`: how far image B is from the reference A.

use crate::args::Exposure;
use anyhow::{Context, Result, bail};
use clap::Args;
use raybench_report::diff::{Metric, diff};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub(crate) struct DiffCmd {
    /// The reference image (.png, .exr or .pfm).
    pub(crate) a: PathBuf,
    /// The image compared with it.
    pub(crate) b: PathBuf,
    /// Write the error map (error.png) and the FLIP map (flip.png) into this folder.
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) exposure: Exposure,
    /// Exit with status 2 when the metric of --metric exceeds this value (errors exit
    /// with 1).
    #[arg(long, value_name = "X")]
    pub(crate) fail_above: Option<f64>,
    /// The metric --fail-above tests: flip, mae, max, mse or relmse.
    #[arg(long, default_value = "flip", value_parser = parse_metric)]
    pub(crate) metric: Metric,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub(crate) json: bool,
}

pub(crate) fn parse_metric(s: &str) -> Result<Metric, String> {
    Metric::from_name(s).ok_or_else(|| {
        let names: Vec<_> = Metric::ALL.iter().map(|(_, n)| *n).collect();
        format!("unknown metric '{s}' (known: {})", names.join(", "))
    })
}

/// `raybench diff`: the measures on stdout, the maps on request, and status 2 when
/// `--fail-above` is exceeded (errors are 1).
pub(crate) fn diff_images(cmd: &DiffCmd) -> Result<ExitCode> {
    let exposure = cmd.exposure.checked()?;
    if let Some(x) = cmd.fail_above
        && !(x.is_finite() && x >= 0.0)
    {
        bail!("--fail-above {x} is not a finite number of at least 0 (every metric is)");
    }
    let maps = cmd
        .out
        .as_ref()
        .map(|d| (d.join("error.png"), d.join("flip.png")));
    if let Some((e, f)) = &maps {
        if let Some(dir) = &cmd.out {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create the folder {}", dir.display()))?;
        }
        raybench_render::check_png_path(e)?;
        raybench_render::check_png_path(f)?;
    }
    let a = raybench_render::read_linear(&cmd.a)?;
    let b = raybench_render::read_linear(&cmd.b)?;
    let (stats, error_map, flip_map) = diff(&a, &b, exposure)
        .map_err(|e| anyhow::anyhow!("{} and {}: {e}", cmd.a.display(), cmd.b.display()))?;
    if cmd.json {
        outln!("{}", serde_json::to_string(&stats)?)?;
    } else {
        outln!("size            {} x {}", stats.width, stats.height)?;
        outln!(
            "mean            {:.6} (A)  {:.6} (B)",
            stats.mean_a,
            stats.mean_b
        )?;
        outln!("mean abs error  {:.6}", stats.mean_abs_error)?;
        outln!("max abs error   {:.6}", stats.max_abs_error)?;
        outln!("MSE             {:.6e}", stats.mse)?;
        outln!("relative MSE    {:.6e}", stats.rel_mse)?;
        outln!(
            "PSNR            {}",
            stats
                .psnr
                .map_or("inf (identical as displayed)".into(), |p| format!(
                    "{p:.2} dB"
                ))
        )?;
        outln!("mean FLIP       {:.6}", stats.flip)?;
        if stats.has_non_finite() {
            outln!(
                "non-finite      {} (A)  {} (B) pixels, left out of the figures above",
                stats.non_finite_a,
                stats.non_finite_b
            )?;
        }
    }
    if let Some((e, f)) = &maps {
        error_map.save(e)?;
        flip_map.save(f)?;
        eprintln!("wrote {} and {}", e.display(), f.display());
    }
    if let Some(limit) = cmd.fail_above {
        // A pixel that is not a number passes no gate, whatever the metric says of the
        // others.
        if stats.has_non_finite() {
            eprintln!(
                "{} pixels of A and {} of B are not finite (NaN or infinite): above any limit",
                stats.non_finite_a, stats.non_finite_b
            );
            return Ok(ExitCode::from(2));
        }
        let value = cmd.metric.of(&stats);
        if value > limit {
            let name = Metric::ALL
                .iter()
                .find(|(m, _)| *m == cmd.metric)
                .map_or("", |(_, n)| n);
            eprintln!("{name} {value:.6} is above {limit}");
            return Ok(ExitCode::from(2));
        }
    }
    Ok(ExitCode::SUCCESS)
}
