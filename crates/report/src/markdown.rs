//! `REPORT.md` and the charts it shows, drawn from [`Results`] alone (so that a merge of
//! shards produces the same kind of report as one run). Each experiment draws and writes
//! its own part ([`crate::experiments`]); this file holds the frame around them.

use crate::charts;
use crate::ctx::{PEER_MAX_FLIP, PEER_MIN_ID_MATCH};
use crate::experiments;
use crate::fmt::{opt, section};
use crate::results::Results;
use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::Path;

/// A chart written: its title and its SVG's path relative to the report (`charts/STEM.svg`).
pub struct Drawn {
    pub title: String,
    pub svg: String,
}

/// The charts drawn, and the first error met writing one (the others are still drawn).
pub struct Charts {
    pub drawn: Vec<Drawn>,
    pub problem: Option<String>,
}

/// Draws every experiment's charts into `dir` as SVG, in the order of [`experiments::ALL`].
pub fn charts(results: &Results, dir: &Path) -> Charts {
    let mut out = Charts {
        drawn: Vec::new(),
        problem: None,
    };
    for chart in experiments::ALL.iter().flat_map(|e| e.charts(results)) {
        match charts::draw(dir, &chart) {
            Ok(svg) => out.drawn.push(Drawn {
                title: chart.title,
                svg: format!("charts/{svg}"),
            }),
            Err(e) => {
                out.problem.get_or_insert(e);
            }
        }
    }
    out
}

/// The note a report merged from shards on different CPU models carries (`merge
/// --allow-mixed-machines`): its tables set their timings side by side, but they compare
/// only within a shard. `None` when every shard ran on one CPU model.
fn mixed_machines(results: &Results) -> Option<String> {
    let models: BTreeSet<&str> = results
        .shards
        .iter()
        .map(|sh| sh.machine.cpu.as_str())
        .collect();
    (models.len() > 1).then(|| {
        let list: Vec<String> = models.iter().map(|m| format!("`{m}`")).collect();
        format!(
            "**Mixed machines**: the shards ran on different CPU models ({}), merged with \
             `--allow-mixed-machines`; the timings of different shards share the tables but \
             compare only within a shard.",
            list.join(", ")
        )
    })
}

/// The report text.
pub fn report(results: &Results, charts: &Charts) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# raybench report\n");
    for sh in &results.shards {
        let m = &sh.machine;
        let _ = writeln!(
            s,
            "**Shard {}/{}**{}{}: {}, {} logical cores ({} worker threads{}); {}; GPU: {}; {}; {}. Started {} UTC, took {:.0} s{}{}{}.\n\n`{}`\n",
            sh.index,
            sh.count,
            if sh.quick { " (quick)" } else { "" },
            if m.host.is_empty() {
                String::new()
            } else {
                format!(" on `{}`", m.host)
            },
            m.cpu,
            m.cores,
            m.threads,
            if sh.pinned { ", pinned to cores" } else { "" },
            m.isa,
            m.gpu,
            m.os,
            m.version,
            sh.started.trim_end_matches('Z').replace('T', " "),
            sh.wall_seconds,
            sh.load.map_or_else(String::new, |[before, after]| format!(
                "; load average {:.2} before, {:.2} after (1 minute)",
                before[0], after[0]
            )),
            sh.others.map_or_else(String::new, |[share, steal]| format!(
                "; other processes took {:.1}% of the CPUs' time meanwhile ({:.1}% stolen by the hypervisor)",
                share * 100.0,
                steal * 100.0
            )),
            if sh.repeat.is_empty() {
                String::new()
            } else {
                format!(
                    "; repetitions {}, each at least {:.0} ms",
                    sh.repeat,
                    sh.min_sample * 1e3
                )
            },
            sh.command
        );
    }
    if let Some(note) = mixed_machines(results) {
        let _ = writeln!(s, "> {note}\n");
    }
    crate::verdict::write(results, &mut s);
    section(
        &mut s,
        "How to read this report",
        &format!(
            "Every backend renders the same scenes with the same settings. Times are the median of \
             the timed repetitions after a counted warm-up; the repetitions of a workload run in \
             rounds, every backend once per round in a rotated order, each repetition lasting \
             at least the minimum sample (a shorter workload runs several times within it, \
             and the time per run is reported); one the machine interfered with is redone. \
             `[lo-hi]` is the median's {:.0}% interval. Build time is separate. **Mrays/s** counts every ray traced (camera, secondary, shadow) over the \
             median time; **tests/ray** and **visits/ray** are ray/primitive tests and node or \
             cell visits per ray, counted in the warm-up. Ray casting runs on several ray sets: \
             `primary` (camera rays, as frames), `incoherent` (seeded random rays in the scene's \
             box), and, derived from the primary hits and the same for every backend, `shadow` \
             (any hit, to every light and one sampled emitter point), `ao` (any hit, cosine rays a \
             tenth of the scene's diagonal long) and `diffuse` (one cosine bounce, closest hit); \
             any-hit sets are compared on whether each ray is blocked. **Equality** compares each \
             backend with the reference backend of its scene (naive where it fits its time budget, \
             else bvh, which the test suite checks against naive on every built-in scene of up to \
             2^21 primitives flattened, and the other exact backends against on the larger ones). \
             **Pass**: a raybench CPU backend (bound by the equivalence contract) must be \
             bit-identical (ids, `t`, colours); other backends must match at least {:.1}% of the \
             ids, counting **ties** (a different primitive at the same distance, within 1e-4 \
             relative: coincident surfaces, where each library breaks the tie its own way) as \
             matches, with a mean FLIP error of at most {PEER_MAX_FLIP}. PSNR is of the 8-bit sRGB \
             images (`inf`: identical); FLIP is NVIDIA's perceptual difference (0 = \
             indistinguishable). **†** marks a noisy time: its median's interval is wider than \
             ±{:.0}%; **?** a single repetition (noise unknown); compare such figures with \
             care. A scene with \
             several cameras renders every one of them in each repetition: its time is that of all \
             its cameras, its Mrays/s their rays over it (so the average over the cameras, \
             weighted by time), and a table per workload gives each camera's own figure.",
            crate::stats::CONFIDENCE * 100.0,
            PEER_MIN_ID_MATCH * 100.0,
            crate::results::NOISY_HALF_WIDTH * 100.0
        ),
    );
    if let Some(p) = &charts.problem {
        let _ = writeln!(s, "> Charts: {p}\n");
    }

    if !results.skipped.is_empty() {
        section(
            &mut s,
            "Skipped",
            "Parts of the matrix that did not run (or ran in part), so the tables below lack \
             them.",
        );
        let _ = writeln!(s, "| shard | what | status | reason |");
        let _ = writeln!(s, "|---|---|---|---|");
        for k in &results.skipped {
            let shard = results
                .shards
                .get(k.shard)
                .map_or_else(|| "?".into(), |sh| format!("{}/{}", sh.index, sh.count));
            let _ = writeln!(
                s,
                "| {shard} | {} `{}` | {} | {} |",
                k.kind,
                k.name,
                k.status,
                k.reason.replace('|', "\\|")
            );
        }
        let _ = writeln!(s);
    }

    // The main matrix, then the scaling fits and each scaling experiment's own section.
    let (matrix, scaling) = experiments::ALL.split_first().expect("the matrix is first");
    matrix.write(results, &mut s);
    if !results.scaling.is_empty() {
        let _ = writeln!(s, "## Scaling\n");
        let _ = writeln!(s, "{}", experiments::fits_intro());
        let _ = writeln!(
            s,
            "| experiment | series | backend | time slope | tests/ray slope | points |"
        );
        let _ = writeln!(s, "|---|---|---|---:|---:|---:|");
        let mut seen = BTreeSet::new();
        for f in &results.fits {
            if !seen.insert((f.experiment.clone(), f.series.clone(), f.backend.clone())) {
                continue;
            }
            let t = results.slope(&f.experiment, &f.series, &f.backend, "seconds");
            let k = results.slope(&f.experiment, &f.series, &f.backend, "tests_per_ray");
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} |",
                f.experiment,
                f.series,
                f.backend,
                opt(t, |v| format!("{v:.2}")),
                opt(k, |v| format!("{v:.2}")),
                f.points
            );
        }
        let _ = writeln!(s);
    }

    for e in scaling {
        e.write(results, &mut s);
    }

    if !charts.drawn.is_empty() {
        let _ = writeln!(s, "## Charts\n");
        for Drawn { title, svg } in &charts.drawn {
            let _ = writeln!(s, "**{title}**\n\n![{title}]({svg})\n");
        }
    }
    s
}
