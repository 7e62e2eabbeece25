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

/// The reproducibility block: per shard, what decides its timings besides the source
/// (the revision, the compiler and its settings, the CPU, its frequency policy, SMT, the
/// threads), and a note when the shards differ in any of them.
fn reproducibility(results: &Results, s: &mut String) {
    if results.shards.is_empty() {
        return;
    }
    section(
        s,
        "Reproducibility",
        "What each shard's timings depend on besides the scenes and settings: the code \
         (revision), the compiler and its settings, the CPU and how its frequency and \
         threads were managed. `-`: not recorded (a file written before it was).",
    );
    let _ = writeln!(
        s,
        "| shard | revision | compiler and settings | CPU | frequency policy | SMT | cores / worker threads | OS |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    let or_dash = |v: &str| {
        if v.is_empty() {
            "-".to_string()
        } else {
            v.replace('|', "\\|")
        }
    };
    for sh in &results.shards {
        let m = &sh.machine;
        let _ = writeln!(
            s,
            "| {}/{} | {} | {} | {} | {} | {} | {} / {}{} | {} |",
            sh.index,
            sh.count,
            or_dash(&m.version),
            or_dash(&m.build),
            or_dash(&m.cpu),
            or_dash(&m.frequency),
            or_dash(&m.smt),
            m.cores,
            m.threads,
            if sh.pinned { ", pinned" } else { "" },
            or_dash(&m.os)
        );
    }
    let _ = writeln!(s);
    let distinct = |f: fn(&crate::results::Machine) -> &str| {
        results
            .shards
            .iter()
            .map(|sh| f(&sh.machine))
            .collect::<BTreeSet<_>>()
            .len()
            > 1
    };
    let differing: Vec<&str> = [
        ("revisions", distinct(|m| &m.version)),
        ("compilers or settings", distinct(|m| &m.build)),
        ("CPU models", distinct(|m| &m.cpu)),
    ]
    .into_iter()
    .filter_map(|(what, differs)| differs.then_some(what))
    .collect();
    if !differing.is_empty() {
        let _ = writeln!(
            s,
            "> **The shards differ in their {}**: their timings share the tables below but \
             compare only within a shard.\n",
            differing.join(" and ")
        );
    }
}

/// The report text.
pub fn report(results: &Results, charts: &Charts) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# raybench report\n");
    for sh in &results.shards {
        let m = &sh.machine;
        let _ = writeln!(
            s,
            "**Shard {}/{}**{}{}: {}, {} logical cores ({} worker threads{}); {}; GPU: {}; {}; {}. Started {} UTC, took {:.0} s{}{}{}{}.\n\n`{}`\n",
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
            m.caches.as_ref().map_or_else(
                || m.isa.clone(),
                |c| format!("{}; caches {}", m.isa, c.describe())
            ),
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
            sh.cache.map_or_else(String::new, |[before, after]| format!(
                "; a random walk through {} of the last-level cache took {} before, {} after",
                before.size(),
                before.describe(),
                after.describe()
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
             `primary` (camera rays, as frames, and once more as a batch made beforehand: the \
             trace throughput the verdict judges), `incoherent` (seeded random rays in the \
             scene's box), and, derived from the primary hits and the same for every backend, \
             `shadow` (any hit, to every light and one sampled emitter point, except where the \
             light lies behind the surface, which blocks it untraced), `ao` (any hit, cosine rays a \
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
    reproducibility(results, &mut s);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::{Machine, Shard, Skipped};

    fn shard(index: u32, cpu: &str) -> Shard {
        Shard {
            index,
            count: 2,
            machine: Machine {
                host: String::new(),
                cpu: cpu.into(),
                cores: 4,
                threads: 3,
                isa: "isa".into(),
                gpu: "none".into(),
                os: "os".into(),
                version: "v".into(),
                ..Machine::default()
            },
            started: "2026-01-02T03:04:05Z".into(),
            wall_seconds: 12.4,
            command: "raybench report".into(),
            quick: false,
            load: None,
            ranked_by_device: false,
            others: None,
            cache: None,
            pinned: false,
            repeat: String::new(),
            min_sample: 0.0,
            plan: None,
        }
    }

    fn text(results: &Results) -> String {
        report(
            results,
            &Charts {
                drawn: Vec::new(),
                problem: None,
            },
        )
    }

    #[test]
    fn mixed_machines_are_noted_only_when_the_models_differ() {
        let mut results = Results {
            shards: vec![shard(1, "B"), shard(2, "B")],
            ..Results::default()
        };
        assert_eq!(mixed_machines(&results), None);
        assert!(!text(&results).contains("Mixed machines"));
        results.shards[0].machine.cpu = "C".into();
        results.shards.push(shard(2, "A"));
        let note = mixed_machines(&results).unwrap();
        // Each model once, sorted.
        assert!(note.contains("CPU models (`A`, `B`, `C`)"), "{note}");
        assert!(text(&results).contains(&format!("> {note}\n")));
    }

    #[test]
    fn each_shard_is_described_with_what_it_recorded() {
        let mut plain = shard(1, "cpu");
        plain.machine.host = String::new();
        let mut full = shard(2, "cpu");
        full.machine.host = "node7".into();
        (full.quick, full.pinned) = (true, true);
        full.load = Some([[0.5, 0.0, 0.0], [1.25, 0.0, 0.0]]);
        full.others = Some([0.123, 0.004]);
        let walk = |median_ns| crate::results::CacheWalk {
            bytes: 8 << 20,
            samples: 140,
            fastest_ns: 20.0,
            median_ns,
            p90_ns: 90.0,
            slowest_ns: 100.0,
        };
        full.cache = Some([walk(30.0), walk(70.0)]);
        (full.repeat, full.min_sample) = ("auto".into(), 0.05);
        let s = text(&Results {
            shards: vec![plain, full],
            ..Results::default()
        });
        assert!(
            s.contains(
                "**Shard 1/2**: cpu, 4 logical cores (3 worker threads); isa; GPU: none; os; v. \
                 Started 2026-01-02 03:04:05 UTC, took 12 s.\n\n`raybench report`\n"
            ),
            "{s}"
        );
        assert!(
            s.contains(
                "**Shard 2/2** (quick) on `node7`: cpu, 4 logical cores (3 worker threads, \
                 pinned to cores); isa; GPU: none; os; v. Started 2026-01-02 03:04:05 UTC, took \
                 12 s; load average 0.50 before, 1.25 after (1 minute); other processes took \
                 12.3% of the CPUs' time meanwhile (0.4% stolen by the hypervisor); a random walk \
                 through 8.0 MiB of the last-level cache took 30.0 ns per step at the median, \
                 20.0 at the fastest (1.50x) before, 70.0 ns per step at the median, 20.0 at \
                 the fastest (3.50x) after; repetitions auto, each at least 50 ms.\n"
            ),
            "{s}"
        );
    }

    #[test]
    fn the_reproducibility_block_lists_each_shard_and_notes_differences() {
        let mut one = shard(1, "cpu");
        one.machine.build = "rustc 1.0, opt-level 3".into();
        one.machine.frequency = "governor performance".into();
        one.machine.smt = "off (1 thread per core)".into();
        one.pinned = true;
        let two = shard(2, "cpu");
        let mut results = Results {
            shards: vec![one, two],
            ..Results::default()
        };
        let s = text(&results);
        assert!(
            s.contains(
                "| 1/2 | v | rustc 1.0, opt-level 3 | cpu | governor performance | off (1 thread \
                 per core) | 4 / 3, pinned | os |\n| 2/2 | v | - | cpu | - | - | 4 / 3 | os |\n"
            ),
            "{s}"
        );
        // The builds differ (one is unrecorded); the revisions and CPUs do not.
        assert!(
            s.contains("> **The shards differ in their compilers or settings**"),
            "{s}"
        );
        results.shards[1].machine.build = "rustc 1.0, opt-level 3".into();
        assert!(!text(&results).contains("The shards differ"));
        results.shards[1].machine.version = "w".into();
        results.shards[1].machine.cpu = "other".into();
        assert!(
            text(&results).contains("> **The shards differ in their revisions and CPU models**")
        );
    }

    #[test]
    fn the_skipped_table_names_the_shard_and_escapes_bars() {
        let mut results = Results {
            shards: vec![shard(1, "cpu"), shard(2, "cpu")],
            ..Results::default()
        };
        assert!(!text(&results).contains("## Skipped"));
        for (shard, reason) in [(1, "a | b"), (7, "lost")] {
            results.skipped.push(Skipped {
                shard,
                kind: "scene".into(),
                name: "x".into(),
                status: "skipped".into(),
                reason: reason.into(),
            });
        }
        let s = text(&results);
        assert!(
            s.contains(
                "| 2/2 | scene `x` | skipped | a \\| b |\n| ? | scene `x` | skipped | lost |\n"
            ),
            "{s}"
        );
    }

    #[test]
    fn the_scaling_table_gives_each_series_once_with_both_slopes() {
        let point = |backend: &str, x: f64, seconds: f64, tests: Option<f64>| {
            crate::results::ScalingPoint {
                hit_fraction: None,
                shard: 0,
                experiment: "pixels".into(),
                series: "s".into(),
                backend: backend.into(),
                x,
                seconds,
                timing: None,
                rays: 1,
                tests_per_ray: tests,
                load_seconds: None,
                build_seconds: None,
                memory_bytes: None,
                difference: None,
                stored_primitives: None,
                visits_per_ray: None,
                quality: None,
            }
        };
        // a: time 1, 4, 16 over x 1, 2, 4: slope 2; tests 3, 3, 3: slope 0. b: time 2, 2
        // over x 1, 100: slope 0, no tests.
        let mut results = Results {
            scaling: vec![
                point("a", 1.0, 1.0, Some(3.0)),
                point("a", 2.0, 4.0, Some(3.0)),
                point("a", 4.0, 16.0, Some(3.0)),
                point("b", 1.0, 2.0, None),
                point("b", 100.0, 2.0, None),
            ],
            ..Results::default()
        };
        results.fit();
        let s = text(&results);
        assert!(
            s.contains(
                "|---|---|---|---:|---:|---:|\n| pixels | s | a | 2.00 | 0.00 | 3 |\n\
                 | pixels | s | b | 0.00 | - | 2 |\n\n"
            ),
            "{s}"
        );
    }
}
