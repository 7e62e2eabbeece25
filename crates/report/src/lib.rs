//! `raybench report`: renders a matrix of scenes, workloads and backends, times them, checks
//! that the images agree, runs the scaling experiments, and writes `REPORT.md`, charts,
//! images, `REPORT.html` (the same report as a page with an image viewer) and `results.json`
//! into one folder. `raybench merge` joins the results of
//! shards (parts of the matrix run on several machines or at several times).

pub mod baseline;
pub mod cache_probe;
pub mod charts;
mod ctx;
pub mod diff;
mod experiments;
mod fmt;
mod html;
pub mod images;
pub mod machine;
mod markdown;
pub mod results;
pub mod rounds;
pub mod stats;
mod verdict;

pub use ctx::{Options, matrix_scenes};

use anyhow::{Context, Result, bail};
use ctx::{Ctx, NAIVE_BUDGET_FULL, NAIVE_BUDGET_QUICK, skip};
use experiments::{Experiment, Planned};
use raybench_core::Mode;
use raybench_registry::interference;
use raybench_registry::progress::Progress;
use raybench_registry::{BACKENDS, Backend, Roles, backend};
use results::{Results, Shard};
use rounds::Repeat;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The shortest timed sample of `--quick` (seconds): a workload shorter than this is run
/// several times within one sample.
pub const MIN_SAMPLE_QUICK: f64 = 0.015;
/// The shortest timed sample of the full run (seconds).
pub const MIN_SAMPLE_FULL: f64 = 0.1;
/// Seconds of samples a backend may spend on one workload of `--quick` beyond the minimum
/// repetitions, looking for a narrow interval ([`Repeat::Auto`]).
pub const BUDGET_QUICK: f64 = 0.1;
/// [`BUDGET_QUICK`] for the full run.
pub const BUDGET_FULL: f64 = 1.0;

/// How long the last-level cache's walk is timed before and after a run
/// ([`Shard::cache`]).
const CACHE_PROBE_TIME: std::time::Duration = std::time::Duration::from_millis(250);

/// A stable hash (FNV-1a, 64 bits) of `bytes`: a preset's colour for presets this build
/// does not know, and the executable's fingerprint in a shard's [`results::Plan`].
pub(crate) fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325_u64, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
    })
}

/// What identifies the running binary in a shard's plan: its version and a hash of its
/// executable file (two builds of one version are told apart).
fn binary_id() -> String {
    let version = env!("CARGO_PKG_VERSION");
    match std::env::current_exe().and_then(std::fs::read) {
        Ok(bytes) => format!("raybench {version}, executable {:016x}", fnv1a(&bytes)),
        Err(_) => format!("raybench {version}, executable unreadable"),
    }
}

/// The names of the scaling experiments, in the order they run (`--experiments`).
#[must_use]
pub fn experiments() -> Vec<&'static str> {
    experiments::SCALING.iter().map(|e| e.name()).collect()
}

/// Runs the report and writes it; returns the results.
///
/// # Errors
/// Bad options, an unwritable output folder, or a scene that fails to load for another
/// reason than a missing asset (those are reported and skipped, except under `CI=true`).
pub fn run(opts: &Options) -> Result<Results> {
    let (shard, shards) = opts.shard;
    if shards == 0 || shard == 0 || shard > shards {
        bail!("--shard must be I/N with 1 <= I <= N (got {shard}/{shards})");
    }
    let size = opts.size.unwrap_or(if opts.quick { 256 } else { 512 });
    if !(16..=4096).contains(&size) {
        bail!("--size must be in 16..=4096");
    }
    let policy = rounds::Policy {
        repeat: opts.repeat.unwrap_or(Repeat::Auto),
        min_sample: opts.min_sample.unwrap_or(if opts.quick {
            MIN_SAMPLE_QUICK
        } else {
            MIN_SAMPLE_FULL
        }),
        budget: if opts.quick {
            BUDGET_QUICK
        } else {
            BUDGET_FULL
        },
    };
    if let Repeat::Fixed(n) = policy.repeat
        && !(1..=100).contains(&n)
    {
        bail!("--repeat must be auto or in 1..=100");
    }
    if !(0.0..=10.0).contains(&policy.min_sample) {
        bail!("--min-sample must be in 0..=10000 milliseconds");
    }
    let repeat = policy.repeat.minimum();
    let mut chosen: Vec<&'static Backend> = match &opts.backends {
        Some(names) => names
            .iter()
            .map(|n| backend(n.trim()))
            .collect::<Result<_, _>>()
            .map_err(anyhow::Error::msg)?,
        None => BACKENDS.iter().filter(|b| !b.is(Roles::PINNED)).collect(),
    };
    // A quick run of every backend leaves the GPU backends out when their adapter is a
    // software one (lavapipe: about one CPU thread's speed, and every kind's kernels to
    // compile): on two cores they would take most of the run. Named, they run.
    let mut software = Vec::new();
    if opts.quick
        && opts.backends.is_none()
        && let Some(adapter) = raybench_registry::software_device()
    {
        chosen.retain(|b| {
            let device = b.is(Roles::DEVICE);
            if device {
                software.push((b.name, adapter.clone()));
            }
            !device
        });
    }
    if chosen.is_empty() {
        bail!("no backend to run");
    }
    if let Some(unknown) = opts
        .experiments
        .iter()
        .flatten()
        .find(|c| !experiments().contains(&c.as_str()))
    {
        bail!(
            "unknown experiment '{unknown}' (known: {})",
            experiments().join(", ")
        );
    }
    // Read the baseline first: a bad path should fail before the measuring, not after.
    let before = opts
        .baseline
        .as_deref()
        .map(|p| baseline::read(p).map(|r| (r, p.display().to_string())))
        .transpose()?;
    let max_ao = raybench_core::ray_sets::MAX_AO_RAYS;
    if !(1..=max_ao).contains(&opts.ao_rays) {
        bail!("--ao-rays {} must be in 1..={max_ao}", opts.ao_rays);
    }
    let modes = opts.modes.clone().unwrap_or_else(|| Mode::ALL.to_vec());
    // The ray file too, before any measuring.
    let replay = opts
        .rays_file
        .as_deref()
        .map(|p| {
            raybench_registry::rays_file::read(p)
                .map(raybench_registry::measure::RayBatch::from_file)
        })
        .transpose()?;
    let ctx = Ctx {
        opts,
        replay,
        chosen: &chosen,
        modes: &modes,
        size,
        repeat,
        policy,
        budget: if opts.quick {
            NAIVE_BUDGET_QUICK
        } else {
            NAIVE_BUDGET_FULL
        },
    };
    // The units of every experiment that runs: the matrix's scenes, then one per scaling
    // experiment. Whole units per shard, so that every backend of a scene runs on the same
    // machine.
    let units: Vec<(&dyn Experiment, String)> = experiments::ALL
        .iter()
        .filter(|e| {
            !e.scaling()
                || (opts.scaling
                    && opts
                        .experiments
                        .as_ref()
                        .is_none_or(|chosen| chosen.iter().any(|c| c == e.name())))
        })
        .flat_map(|e| e.units(&ctx).into_iter().map(move |u| (*e, u)))
        .collect();
    let plan = results::Plan {
        settings: settings_line(opts, &chosen, &modes, size, &policy),
        binary: binary_id(),
        units: units
            .iter()
            .map(|(e, u)| format!("{} {u}", e.name()))
            .collect(),
    };
    let mine: Vec<(&dyn Experiment, String)> = units
        .into_iter()
        .enumerate()
        .filter(|(i, _)| results::Plan::holds(*i, shard, shards))
        .map(|(_, u)| u)
        .collect();
    if mine.is_empty() {
        bail!(
            "--shard {shard}/{shards}: the plan has {} units (the matrix's scenes and the \
             scaling experiments, split whole), so shard {shard} holds none; split it into \
             at most {} shards",
            plan.units.len(),
            plan.units.len().max(1)
        );
    }

    std::fs::create_dir_all(opts.out.join("images"))
        .with_context(|| format!("cannot create {}", opts.out.display()))?;
    std::fs::create_dir_all(opts.out.join("charts"))?;
    let cache_before = cache_probe::last_level(CACHE_PROBE_TIME);
    let started = machine::now_utc();
    let wall = Instant::now();
    let load_before = interference::load_average();
    let use_before = interference::MachineUse::now();
    let mut results = Results {
        schema: results::SCHEMA.into(),
        raybench_version: env!("CARGO_PKG_VERSION").into(),
        shards: vec![Shard {
            index: shard,
            count: shards,
            machine: machine::describe(opts.threads),
            started,
            wall_seconds: 0.0,
            command: opts.command.clone(),
            quick: opts.quick,
            load: None,
            ranked_by_device: opts.device_time,
            others: None,
            cache: None,
            pinned: opts.pin,
            repeat: ctx.policy.repeat.name(),
            min_sample: ctx.policy.min_sample,
            plan: Some(plan),
        }],
        ..Results::default()
    };

    for (name, adapter) in software {
        skip(
            &mut results,
            "backend",
            name,
            "skipped",
            format!(
                "a quick run leaves the GPU backends out on a software adapter ({adapter}); \
                 name them in --backends to include them"
            ),
        );
    }

    // Plan every unit first (loading the matrix's scenes), so that the progress bar knows
    // the whole run.
    let mut plan: Vec<(&dyn Experiment, Planned)> = Vec::new();
    for (e, unit) in mine {
        if let Some(p) = e.plan(&ctx, &unit, &mut results)? {
            plan.push((e, p));
        }
    }
    let progress = Progress::new(plan.iter().map(|(_, p)| p.steps).sum());
    for (e, p) in plan {
        e.run(&ctx, p, &progress, &mut results)?;
    }
    results.shards[0].wall_seconds = wall.elapsed().as_secs_f64();
    results.shards[0].load = load_before
        .zip(interference::load_average())
        .map(|(before, after)| [before, after]);
    results.shards[0].others = use_before
        .zip(interference::MachineUse::now())
        .and_then(|(before, after)| after.others_since(&before))
        .map(|o| [o.share, o.steal]);
    results.shards[0].cache = Some([cache_before, cache_probe::last_level(CACHE_PROBE_TIME)]);
    results.fit();
    let appendix = before.as_ref().map(|(before, name)| {
        baseline::markdown(
            &baseline::compare(before, &results),
            name,
            &opts.out.display().to_string(),
        )
    });
    if let Some(section) = &appendix {
        use std::io::Write as _;
        write!(std::io::stdout().lock(), "{section}")?;
    }
    write(&results, &opts.out, appendix.as_deref())?;
    Ok(results)
}

/// The settings that decide a report's work and timings, as one line: every option but
/// the shard, the output folder and the baseline (the shards of one plan share it).
fn settings_line(
    opts: &Options,
    chosen: &[&'static Backend],
    modes: &[Mode],
    size: u32,
    policy: &rounds::Policy,
) -> String {
    let names = |v: Vec<&str>| v.join(",");
    format!(
        "quick={} backends={} modes={} size={size} repeat={} min-sample={} scaling={} \
         experiments={} rays={} ao-rays={} rays-file={} threads={} pin={} device-time={}",
        opts.quick,
        names(chosen.iter().map(|b| b.name).collect()),
        names(modes.iter().map(|m| m.name()).collect()),
        policy.repeat.name(),
        policy.min_sample,
        opts.scaling,
        opts.experiments
            .as_ref()
            .map_or("all".into(), |e| e.join(",")),
        opts.ray_sets.as_ref().map_or("all".into(), |r| {
            names(r.iter().map(|s| s.name()).collect())
        }),
        opts.ao_rays,
        opts.rays_file
            .as_ref()
            .map_or("none".into(), |p| p.display().to_string()),
        opts.threads,
        opts.pin,
        opts.device_time,
    )
}

/// Writes `results.json`, the charts, `REPORT.md` and `REPORT.html` into `out`;
/// `appendix` (Markdown: the comparison with a baseline) ends both reports.
///
/// # Errors
/// When a file cannot be written.
pub fn write(results: &Results, out: &Path, appendix: Option<&str>) -> Result<()> {
    std::fs::create_dir_all(out.join("charts"))?;
    // Compact: a full report's results run to hundreds of kilobytes, read by tools (`jq`
    // formats them for people).
    let json = serde_json::to_string(results)?;
    // Every file through a temporary name: an interrupted run leaves the previous report's
    // files whole, never a truncated one.
    write_text(&out.join("results.json"), &(json + "\n"))?;
    let charts = markdown::charts(results, &out.join("charts"));
    let mut text = markdown::report(results, &charts);
    if let Some(appendix) = appendix {
        text = text + "\n" + appendix;
    }
    write_text(&out.join("REPORT.md"), &text)?;
    write_text(&out.join("REPORT.html"), &html::page(results, &text, out))?;
    eprintln!(
        "report written to {} and {}",
        out.join("REPORT.md").display(),
        out.join("REPORT.html").display()
    );
    Ok(())
}

/// Writes `text` to `path` through [`raybench_render::write_file`].
fn write_text(path: &Path, text: &str) -> Result<()> {
    Ok(raybench_render::write_file(path, text.as_bytes())?)
}

/// What a merge accepts beyond one whole plan run on one CPU model.
#[derive(Clone, Copy, Debug, Default)]
pub struct Allow {
    /// Merge a set that lacks shards of its plan, listing the missing ones under Skipped
    /// (`--allow-partial`).
    pub partial: bool,
    /// Merge shards that ran on different CPU models into one set of tables, the report
    /// saying so (`--allow-mixed-machines`).
    pub mixed_machines: bool,
}

/// Joins the `results.json` of several report folders into one report in `out` (images are
/// copied; charts and `REPORT.md` are drawn anew).
///
/// The folders must hold the shards of one plan ([`results::Plan`]): the same shard count,
/// settings, binary and units, each shard once and every shard present, all run on one CPU
/// model; with `allow.partial` a missing shard is listed under Skipped with the units it
/// would have run, and with `allow.mixed_machines` shards of different CPU models are
/// merged and the report notes it.
///
/// # Errors
/// A folder without a readable `results.json`, shards of different plans, a shard given
/// twice, a missing shard (without `allow.partial`), shards of different CPU models
/// (without `allow.mixed_machines`), `out` being one of the folders, or an unwritable `out`.
pub fn merge(dirs: &[PathBuf], out: &Path, allow: Allow) -> Result<Results> {
    if dirs.is_empty() {
        bail!("merge needs at least one report folder");
    }
    // Writing into a folder being merged would replace its results while they are read.
    if let Ok(o) = std::fs::canonicalize(out)
        && let Some(dir) = dirs
            .iter()
            .find(|d| std::fs::canonicalize(d).is_ok_and(|d| d == o))
    {
        bail!(
            "--out {} is the merged folder {}: its report would be replaced; name another folder",
            out.display(),
            dir.display()
        );
    }
    let mut merged = Results {
        schema: results::SCHEMA.into(),
        raybench_version: env!("CARGO_PKG_VERSION").into(),
        ..Results::default()
    };
    // Every input first: a shard given twice (the same folder twice, a copy of it, or a
    // merged report with one of its parts) would double its rows.
    let mut inputs: Vec<(&PathBuf, Results)> = Vec::new();
    for dir in dirs {
        let r = Results::read(&dir.join("results.json"))?;
        for (first, earlier) in &inputs {
            if let Some(why) = earlier.overlap(&r) {
                bail!(
                    "{} and {} hold the same shard ({why}); give each shard once",
                    first.display(),
                    dir.display()
                );
            }
        }
        inputs.push((dir, r));
    }
    let missing = check_plan(&inputs, allow)?;
    std::fs::create_dir_all(out.join("images"))
        .with_context(|| format!("cannot create {}", out.display()))?;
    for (dir, r) in inputs {
        for run in &r.runs {
            for name in [
                &run.images.color,
                &run.images.ids_diff,
                &run.images.flip,
                &run.images.visits,
            ]
            .into_iter()
            .flatten()
            {
                let (from, to) = (dir.join(name), out.join(name));
                if from != to {
                    let bytes = std::fs::read(&from)
                        .with_context(|| format!("cannot copy {}", from.display()))?;
                    raybench_render::write_file(&to, &bytes)?;
                }
            }
        }
        merged.absorb(r);
    }
    merged.skipped.extend(missing);
    write(&merged, out, None)?;
    Ok(merged)
}

/// Checks that the shards of `inputs` form one plan: the same shard count, settings, binary
/// and units, each shard once, every shard present, and (unless `allow.mixed_machines`) one
/// CPU model. Returns the missing shards as skip records when `allow.partial`, else
/// refuses them.
fn check_plan(inputs: &[(&PathBuf, Results)], allow: Allow) -> Result<Vec<results::Skipped>> {
    let shards: Vec<(&PathBuf, &Shard)> = inputs
        .iter()
        .flat_map(|(dir, r)| r.shards.iter().map(move |s| (*dir, s)))
        .collect();
    let Some(&(first_dir, first)) = shards.first() else {
        bail!("{}: the results hold no shard", inputs[0].0.display());
    };
    let plan_of = |dir: &PathBuf, s: &Shard| -> Result<results::Plan> {
        s.plan.clone().ok_or_else(|| {
            anyhow::anyhow!(
                "{}: shard {}/{} records no plan (written by an older raybench), so its set \
                 cannot be checked; run it again",
                dir.display(),
                s.index,
                s.count
            )
        })
    };
    let plan = plan_of(first_dir, first)?;
    let mut seen: Vec<(u32, &PathBuf)> = Vec::new();
    for &(dir, s) in &shards {
        let other = plan_of(dir, s)?;
        let differs = |what: &str, a: &str, b: &str| {
            anyhow::anyhow!(
                "{} and {} are not shards of one plan: {what} differ ({a} against {b})",
                first_dir.display(),
                dir.display()
            )
        };
        if s.count != first.count {
            return Err(differs(
                "the shard counts",
                &format!("{}/{}", first.index, first.count),
                &format!("{}/{}", s.index, s.count),
            ));
        }
        if other.settings != plan.settings {
            let (a, b) = first_difference(&plan.settings, &other.settings);
            return Err(differs("the settings", a, b));
        }
        if other.binary != plan.binary {
            return Err(differs("the binaries", &plan.binary, &other.binary));
        }
        if other.units != plan.units {
            return Err(differs(
                "the scenes and experiments",
                &plan.units.join(", "),
                &other.units.join(", "),
            ));
        }
        if let Some((_, earlier)) = seen.iter().find(|(i, _)| *i == s.index) {
            bail!(
                "{} and {} hold the same shard {}/{}; give each shard once",
                earlier.display(),
                dir.display(),
                s.index,
                s.count
            );
        }
        seen.push((s.index, dir));
    }
    // Timings of different CPU models in one table read as a comparison they are not.
    if !allow.mixed_machines
        && let Some((dir, s)) = shards
            .iter()
            .find(|(_, s)| s.machine.cpu != first.machine.cpu)
    {
        bail!(
            "{} ({}) and {} ({}) ran on different CPU models, whose timings do not compare \
             in one table; merge the shards of one CPU model, or pass --allow-mixed-machines",
            first_dir.display(),
            first.machine.cpu,
            dir.display(),
            s.machine.cpu
        );
    }
    let missing: Vec<u32> = (1..=first.count)
        .filter(|i| !seen.iter().any(|(s, _)| s == i))
        .collect();
    let holds = |i: u32| plan.units_of(i, first.count).join(", ");
    if !missing.is_empty() && !allow.partial {
        let list: Vec<String> = missing
            .iter()
            .map(|i| format!("{i}/{} ({})", first.count, holds(*i)))
            .collect();
        bail!(
            "shards missing from the merge: {}; merge every shard of the plan, or pass \
             --allow-partial to list the missing ones under Skipped",
            list.join("; ")
        );
    }
    Ok(missing
        .into_iter()
        .map(|i| results::Skipped {
            shard: 0,
            kind: "shard".into(),
            name: format!("{i}/{}", first.count),
            status: "missing".into(),
            reason: format!(
                "not in the merge (--allow-partial): {} did not run",
                holds(i)
            ),
        })
        .collect())
}

/// The first whitespace-separated settings that differ between `a` and `b` (the whole lines
/// where they differ only in length).
fn first_difference<'a>(a: &'a str, b: &'a str) -> (&'a str, &'a str) {
    a.split_whitespace()
        .zip(b.split_whitespace())
        .find(|(x, y)| x != y)
        .unwrap_or((a, b))
}
