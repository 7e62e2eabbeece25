//! The `raybench` command. Stdout carries data (tables, JSON); progress, timings and
//! warnings go to stderr.

/// `println!` that returns the write's `io::Result` instead of panicking, so that a reader
/// that closes the pipe early (`raybench compare-results A B --json | head`) ends the
/// command quietly ([`main`]) rather than with a panic.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)
    }};
}

/// `print!` likewise ([`outln`]).
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout().lock(), $($arg)*)
    }};
}

mod args;
mod cmd;

use anyhow::Result;
use args::{with_pool, with_threads};
use clap::{Parser, Subcommand};
use cmd::{backends, compare, diff, info, rays, render, report, scenes};
use raybench_scene::assets_dir;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Renders scenes with interchangeable acceleration strategies and compares them.
#[derive(Parser)]
#[command(name = "raybench", version = raybench_registry::VERSION, about, long_about = None)]
struct Cli {
    /// Folder holding the shared meshes (default: $RAYBENCH_ASSETS, else assets/ at the
    /// workspace root).
    #[arg(long, global = true, value_name = "DIR")]
    assets: Option<PathBuf>,
    /// Largest memory a scene may take, estimated from its declared sizes before loading
    /// (8G, 512M, or none; default: $RAYBENCH_MEMORY_LIMIT, else half the available
    /// memory).
    #[arg(long, global = true, value_name = "SIZE", value_parser = parse_memory_limit)]
    memory_limit: Option<MemoryLimit>,
    #[command(subcommand)]
    command: Command,
}

/// `--memory-limit`: bytes, or `None` for no limit.
#[derive(Clone, Copy)]
struct MemoryLimit(Option<u64>);

fn parse_memory_limit(s: &str) -> Result<MemoryLimit, String> {
    raybench_scene::parse_size(s).map(MemoryLimit)
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to an image (PNG, OpenEXR or PFM).
    Render(render::RenderCmd),
    /// Render a scene with several backends, time them and check that they agree.
    Compare(compare::CompareCmd),
    /// List the built-in scenes and generators.
    Scenes,
    /// List the backends, their build presets (BACKEND:PRESET) and whether they are
    /// available here.
    Backends {
        /// One JSON array on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Show a scene's primitives and each backend's structure.
    Info(info::InfoCmd),
    /// Run the benchmark matrix and write a report (REPORT.md, charts, images,
    /// results.json).
    Report(report::ReportCmd),
    /// Join the results of report shards into one report.
    Merge(report::MergeCmd),
    /// Set a report's results beside an earlier one's: per workload the speed ratio and
    /// whether it exceeds the noise of both runs.
    CompareResults(report::CompareResultsCmd),
    /// Measure how far image B is from the reference A (PNG, EXR or PFM).
    Diff(diff::DiffCmd),
    /// Ray files (docs/rays-format.md): write a ray set for other tools to replay.
    #[command(subcommand)]
    Rays(rays::RaysCmd),
}

/// Lets every option that takes a value take a negative number (`--fov -5`), so that its
/// own check refuses it, rather than clap's tip to write `-- -5` (which would make it the
/// scene).
fn negative_numbers(cmd: clap::Command) -> clap::Command {
    cmd.mut_args(|a| {
        if a.get_action().takes_values() {
            a.allow_negative_numbers(true)
        } else {
            a
        }
    })
    .mut_subcommands(negative_numbers)
}

fn main() -> ExitCode {
    quiet_wayland_probe();
    let cli = {
        use clap::{CommandFactory as _, FromArgMatches as _};
        let cmd = negative_numbers(Cli::command()).mut_subcommand("diff", |c| {
            c.mut_arg("ev", |a| {
                a.help(
                    "Exposure in stops: both images are scaled by 2^EV before PSNR and FLIP, \
                     which compare them as displayed",
                )
            })
        });
        let matches = cmd.get_matches();
        Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit())
    };
    match run(cli) {
        Ok(code) => code,
        // The reader of standard output went away (`| head`): what it wanted was written.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Whether `e` comes from writing to a pipe whose reader has closed it.
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Gives the process a private, empty `XDG_RUNTIME_DIR` when it has none (or a relative
/// one): `raybench-runtime-UID` in the temporary folder, made once per user with mode 0700
/// and kept (so that nothing is left behind per run); not used if someone else owns it.
///
/// Mesa's Vulkan device-selection layer (`VK_LAYER_MESA_device_select`) asks Wayland for
/// the compositor's GPU whenever wgpu lists the adapters, and libwayland-client then prints
/// `error: XDG_RUNTIME_DIR is invalid or not set in the environment.`, twice per command,
/// on servers, in containers and over ssh, where the variable is unset. In an empty folder
/// the layer finds no compositor, as it would not have anyway, and nothing is printed; the
/// adapters and their order are unchanged. wgpu offers no switch for this: the layer reads
/// only the environment.
#[cfg(target_os = "linux")]
#[allow(unsafe_code)]
fn quiet_wayland_probe() {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt};
    let set = std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| Path::new(&d).is_absolute());
    if set {
        return;
    }
    // The process's user owns its /proc entry.
    let Ok(uid) = std::fs::metadata("/proc/self").map(|m| m.uid()) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("raybench-runtime-{uid}"));
    let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
    let private = std::fs::symlink_metadata(&dir)
        .is_ok_and(|m| m.is_dir() && m.uid() == uid && m.mode() & 0o777 == 0o700);
    if private {
        // SAFETY: this runs first in `main`, before any other thread exists, so no thread
        // can read the environment while it changes (the condition of `set_var`).
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
    }
}

/// Elsewhere there is no Wayland probe to quiet.
#[cfg(not(target_os = "linux"))]
fn quiet_wayland_probe() {}

fn run(cli: Cli) -> Result<ExitCode> {
    // The global scene options mean nothing to the commands that load no scene: refused
    // rather than silently ignored.
    let loads_no_scene = match &cli.command {
        Command::Backends { .. } => Some("backends"),
        Command::Merge(_) => Some("merge"),
        Command::CompareResults(_) => Some("compare-results"),
        Command::Diff(_) => Some("diff"),
        _ => None,
    };
    if let Some(name) = loads_no_scene {
        for (given, option) in [
            (cli.assets.is_some(), "--assets"),
            (cli.memory_limit.is_some(), "--memory-limit"),
        ] {
            if given {
                anyhow::bail!(
                    "{option} applies to the commands that load scenes; `{name}` loads none"
                );
            }
        }
    }
    let assets = assets_dir(cli.assets.as_deref());
    if let Some(MemoryLimit(limit)) = cli.memory_limit {
        raybench_scene::set_memory_limit(limit);
    }
    match cli.command {
        Command::Render(cmd) => with_threads(cmd.frame.threads, || render::render(&cmd, &assets)),
        Command::Compare(cmd) => {
            with_threads(cmd.frame.threads, || compare::compare(&cmd, &assets))
        }
        Command::Scenes => scenes::scenes(&assets),
        Command::Backends { json } => backends::backends(json),
        Command::Info(cmd) => with_threads(cmd.threads, || info::info(&cmd, &assets)),
        Command::Report(cmd) => {
            // On a pool of its own, so that the thread that times is one of the workers: on
            // the global pool, the calling thread and every worker compete for the cores.
            let threads = cmd.threads.unwrap_or_else(rayon::current_num_threads);
            with_pool(Some(threads), cmd.pin, || report::report(&cmd, &assets))
        }
        Command::Merge(cmd) => report::merge(&cmd),
        Command::CompareResults(cmd) => report::compare_results(&cmd),
        Command::Diff(cmd) => diff::diff_images(&cmd),
        Command::Rays(rays::RaysCmd::Export(cmd)) => rays::export_rays(&cmd, &assets),
    }
}
