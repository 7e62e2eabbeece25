//! Before and after: runs of the peer benchmark set side by side (`--diff BEFORE AFTER`, or
//! several alternating pairs `--diff B1,B2 A1,A2`), the way a change to a backend is judged
//! on a shared machine.
//!
//! Absolute Mrays/s of two runs minutes apart move with the neighbours' use of the shared
//! cache (see docs/benchmarks.md), so each figure is first made relative to a reference
//! timed in the same rounds of the same run (by default the figure's first ratio
//! reference, else the one its builds are compared with: an Embree variant): per round,
//! the contestant's time over the reference's. The change is the
//! median of those relative times before over the median after (above 1: faster), with the
//! report's seeded bootstrap interval of that ratio of medians
//! ([`raybench_report::stats::ratio_interval`]) and its verdict
//! ([`raybench_report::stats::judge`]: faster or slower only where the interval excludes 1
//! and the change reaches [`raybench_report::stats::MIN_EFFECT`]). A figure without a
//! reference in both runs is compared on its raw times, which include the machine's drift,
//! and says so. One pair's interval covers the noise within its two runs, not the drift
//! between them, so several pairs are taken together ([`pooled`]): the geometric mean of
//! their changes, with an interval from their spread.

use raybench_report::stats::{self, Change};
use serde_json::Value;
use std::fmt::Write as _;

/// The workload's fields that decide the rays, which both runs must share (the rounds and
/// thread counts may differ).
pub const SAME_RAYS: [&str; 6] = [
    "primary_size",
    "tile",
    "incoherent_rays",
    "seed",
    "chunk",
    "shadow_fraction",
];

/// One figure measured in both runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    /// The mesh's name.
    pub mesh: String,
    /// The contestant's name.
    pub contestant: String,
    /// `build`, or the ray set, the query and the thread count (`ao closest, 1 thread`).
    pub what: String,
    /// The contestant timed in the same rounds that the times are taken relative to;
    /// `None` for raw times.
    pub reference: Option<String>,
    /// Speed relative to the reference before (the reference's time over the contestant's,
    /// median over the rounds), or Mrays/s-proportional `1 / time` for raw times.
    pub before: f64,
    /// The same after.
    pub after: f64,
    /// `after / before` as a speed: above 1 is faster.
    pub change: f64,
    /// The interval of [`Figure::change`] (`None` with fewer than two rounds on a side).
    pub interval: Option<[f64; 2]>,
    /// What the interval says.
    pub verdict: Change,
}

/// The figures of `after` that `before` has too, in `after`'s order, with the reference
/// `reference` where given (otherwise each figure's first ratio reference in both runs,
/// else the builds' reference).
///
/// # Errors
/// When either document is not a peer benchmark's JSON (`raybench-peers/*`), or the two
/// traced other rays ([`SAME_RAYS`], or a mesh's ray sets hold other counts of rays) or ran
/// on different CPU models.
pub fn diff(before: &Value, after: &Value, reference: Option<&str>) -> Result<Vec<Figure>, String> {
    for (name, doc) in [("before", before), ("after", after)] {
        let schema = doc["schema"].as_str().unwrap_or("");
        if !schema.starts_with("raybench-peers/") {
            return Err(format!(
                "{name}: not a peer benchmark's JSON (schema '{schema}')"
            ));
        }
    }
    for key in SAME_RAYS {
        let (b, a) = (&before["workload"][key], &after["workload"][key]);
        if b != a {
            return Err(format!(
                "the runs traced different rays: workload {key} {b} before, {a} after"
            ));
        }
    }
    let (b, a) = (&before["machine"]["cpu"], &after["machine"]["cpu"]);
    if b != a {
        return Err(format!(
            "the runs ran on different CPUs: {b} before, {a} after"
        ));
    }
    let mut out = Vec::new();
    for mesh_after in meshes(after) {
        let name = mesh_after["name"].as_str().unwrap_or_default();
        let Some(mesh_before) = meshes(before).find(|m| m["name"] == name) else {
            continue;
        };
        // The ray counts catch what the workload does not name (`--ao-rays`, a ray file).
        for set in mesh_after["ray_sets"].as_array().into_iter().flatten() {
            let rays = |m: &Value| {
                let sets = m["ray_sets"].as_array()?;
                sets.iter()
                    .find(|s| s["name"] == set["name"])
                    .map(|s| s["rays"].clone())
            };
            if let Some(b) = rays(mesh_before).filter(|b| *b != set["rays"]) {
                return Err(format!(
                    "mesh {name}: the runs traced different rays: ray set {} of {b} rays \
                     before, {} after",
                    set["name"], set["rays"]
                ));
            }
        }
        for c in contestants(mesh_after) {
            let cname = c["name"].as_str().unwrap_or_default();
            let Some(c_before) = contestant(mesh_before, cname) else {
                continue;
            };
            let runs = [mesh_before, mesh_after];
            let build_reference = c["build_ratio"]["reference"].as_str();
            // Builds: rounds of every contestant of the mesh, interleaved.
            out.extend(compare(
                [name, cname, "build"],
                pick(reference, build_reference, cname, runs, false),
                runs,
                [c_before, c],
                |c| floats(&c["build_rounds_s"]),
            ));
            for set in c["ray_sets"].as_array().into_iter().flatten() {
                let sname = set["name"].as_str().unwrap_or_default();
                for query in ["closest", "any"] {
                    for run in set[query]["runs"].as_array().into_iter().flatten() {
                        let threads = run["threads"].as_u64().unwrap_or(0);
                        // The figure's first ratio reference, else the builds' (any-hit
                        // figures have ratios only to Embree's robust single rays).
                        let default = set[query]["ratios"]
                            .as_array()
                            .into_iter()
                            .flatten()
                            .filter(|x| x["threads"].as_u64() == Some(threads))
                            .filter_map(|x| x["reference"].as_str())
                            .find(|r| pick(None, Some(r), cname, runs, true).is_some())
                            .or(build_reference);
                        let plural = if threads == 1 { "" } else { "s" };
                        let what = format!("{sname} {query}, {threads} thread{plural}");
                        out.extend(compare(
                            [name, cname, &what],
                            pick(reference, default, cname, runs, true),
                            runs,
                            [c_before, c],
                            |c| {
                                ray_set(c, sname)
                                    .and_then(|s| s[query]["runs"].as_array())
                                    .and_then(|runs| {
                                        runs.iter().find(|x| x["threads"].as_u64() == Some(threads))
                                    })
                                    .map(|x| floats(&x["samples_s"]))
                                    .unwrap_or_default()
                            },
                        ));
                    }
                }
            }
        }
    }
    Ok(out)
}

/// Figure `[mesh, contestant, what]` of `contestants` (before, after) in `meshes`, its
/// `times` relative to `reference`'s in both runs, or raw where the reference has no
/// times of it in either run; `None` where the contestant has none.
fn compare(
    [mesh, contestant_name, what]: [&str; 3],
    reference: Option<&str>,
    meshes: [&Value; 2],
    contestants: [&Value; 2],
    times: impl Fn(&Value) -> Vec<f64>,
) -> Option<Figure> {
    let relative = |side: usize| {
        let own = times(contestants[side]);
        let r = reference.and_then(|r| contestant(meshes[side], r))?;
        let theirs = times(r);
        (!own.is_empty() && theirs.len() == own.len()).then(|| {
            own.iter()
                .zip(theirs)
                .map(|(t, r)| t / r)
                .collect::<Vec<_>>()
        })
    };
    let (reference, before, after) = match (relative(0), relative(1)) {
        (Some(b), Some(a)) => (reference, b, a),
        _ => (None, times(contestants[0]), times(contestants[1])),
    };
    let (b, a) = (stats::median(&before)?, stats::median(&after)?);
    // Times: after over before below 1 is faster; shown inverted, as speeds.
    let (ratio, interval) = stats::ratio_interval(&after, &before);
    Some(Figure {
        mesh: mesh.into(),
        contestant: contestant_name.into(),
        what: what.into(),
        reference: reference.map(String::from),
        before: 1.0 / b,
        after: 1.0 / a,
        change: 1.0 / ratio,
        interval: interval.map(|i| [1.0 / i.hi, 1.0 / i.lo]),
        verdict: stats::judge(ratio, interval, stats::MIN_EFFECT),
    })
}

/// The reference asked for, else `default`, where it is another contestant of both runs'
/// mesh than `name`, and, for traced figures (`grouped`), one timed in the same group of
/// rounds (builds are interleaved across every contestant of a mesh).
fn pick<'a>(
    asked: Option<&'a str>,
    default: Option<&'a str>,
    name: &str,
    runs: [&Value; 2],
    grouped: bool,
) -> Option<&'a str> {
    asked.or(default).filter(|r| {
        *r != name
            && runs
                .iter()
                .all(|m| contestant(m, r).is_some() && (!grouped || paired(m, name, r)))
    })
}

/// The meshes of a run.
fn meshes(doc: &Value) -> impl Iterator<Item = &Value> {
    doc["meshes"].as_array().into_iter().flatten()
}

/// The contestants of a mesh.
fn contestants(mesh: &Value) -> impl Iterator<Item = &Value> {
    mesh["contestants"].as_array().into_iter().flatten()
}

/// Contestant `name` of a mesh.
fn contestant<'a>(mesh: &'a Value, name: &str) -> Option<&'a Value> {
    contestants(mesh).find(|c| c["name"] == name)
}

/// Ray set `name` of a contestant.
fn ray_set<'a>(c: &'a Value, name: &str) -> Option<&'a Value> {
    c["ray_sets"].as_array()?.iter().find(|s| s["name"] == name)
}

/// Whether contestants `a` and `b` of a mesh were timed in the same rounds (one group).
fn paired(mesh: &Value, a: &str, b: &str) -> bool {
    contestant(mesh, b).is_some()
        && mesh["groups"].as_array().into_iter().flatten().any(|g| {
            let has = |n: &str| g.as_array().is_some_and(|g| g.iter().any(|x| x == n));
            has(a) && has(b)
        })
}

/// A JSON array of numbers.
fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .into_iter()
        .flatten()
        .filter_map(Value::as_f64)
        .collect()
}

/// The figures as Markdown tables, one per mesh.
#[must_use]
pub fn markdown(figures: &[Figure], before: &str, after: &str) -> String {
    let mut s = format!(
        "# raybench peers: {after} over {before}\n\n\
         Per figure, the contestant's speed relative to a reference timed in the same \
         rounds (its time over the contestant's, median over the rounds; where no reference \
         is in both runs, raw times with before as 1, the machine's drift included), before \
         and after, \
         and after over before with its {:.0} % bootstrap interval: faster or slower only \
         where the interval excludes 1 and the change is at least {:.0} %.\n",
        stats::CONFIDENCE * 100.0,
        stats::MIN_EFFECT * 100.0
    );
    let mut mesh = None;
    for f in figures {
        if mesh != Some(&f.mesh) {
            mesh = Some(&f.mesh);
            let _ = write!(
                s,
                "\n## {}\n\n| contestant | figure | reference | before | after | after / before \
                 [interval] | verdict |\n|---|---|---|---:|---:|---:|---|\n",
                f.mesh
            );
        }
        let interval = bracketed(f.interval);
        let (reference, scale) = match &f.reference {
            Some(r) => (r.as_str(), 1.0),
            None => ("(raw times)", f.before),
        };
        let verdict = f.verdict.label();
        let _ = writeln!(
            s,
            "| {} | {} | {reference} | {:.3} | {:.3} | {:.3}{interval} | {verdict} |",
            f.contestant,
            f.what,
            f.before / scale,
            f.after / scale,
            f.change
        );
    }
    s
}

/// An interval as the tables write it (` [lo-hi]`), or nothing.
fn bracketed(interval: Option<[f64; 2]>) -> String {
    interval.map_or_else(String::new, |[lo, hi]| format!(" [{lo:.2}-{hi:.2}]"))
}

/// The figures measured in every one of several pairs of runs (each pair's [`diff`]),
/// grouped per figure in the first pair's order: one [`Figure`] per pair.
#[must_use]
pub fn across(pairs: &[Vec<Figure>]) -> Vec<Vec<Figure>> {
    let Some((first, rest)) = pairs.split_first() else {
        return Vec::new();
    };
    let same = |a: &Figure, b: &Figure| {
        (&a.mesh, &a.contestant, &a.what) == (&b.mesh, &b.contestant, &b.what)
    };
    first
        .iter()
        .filter_map(|f| {
            let mut group = vec![f.clone()];
            for pair in rest {
                group.push(pair.iter().find(|g| same(f, g))?.clone());
            }
            Some(group)
        })
        .collect()
}

/// Several pairs' changes of one figure taken together.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pooled {
    /// The geometric mean of the pairs' changes (above 1: faster).
    pub change: f64,
    /// Its interval by Student's t over the pairs ([`stats::replicate_ratio`]); `None`
    /// with fewer than two pairs.
    pub interval: Option<[f64; 2]>,
    /// What the interval says, by the rule of a single pair ([`stats::judge`]).
    pub verdict: Change,
}

/// Several pairs' figures of one figure ([`across`]) taken together: each pair gives one
/// change, and their spread bounds the drift between runs as well as the noise within
/// them, which one pair's interval leaves out.
#[must_use]
pub fn pooled(group: &[Figure]) -> Pooled {
    let changes: Vec<f64> = group.iter().map(|f| f.change).collect();
    let (change, interval) = stats::replicate_ratio(&changes);
    // `judge` reads ratios of times: after over before below 1 is faster.
    let times = interval.map(|i| stats::Interval {
        lo: 1.0 / i.hi,
        hi: 1.0 / i.lo,
        confidence: i.confidence,
    });
    Pooled {
        change,
        interval: interval.map(|i| [i.lo, i.hi]),
        verdict: stats::judge(1.0 / change, times, stats::MIN_EFFECT),
    }
}

/// Several pairs' figures ([`across`]) as Markdown tables, one per mesh: each pair's change
/// with its interval, and the pairs taken together ([`pooled`]) with their verdict.
#[must_use]
pub fn markdown_across(groups: &[Vec<Figure>], pairs: &[(String, String)]) -> String {
    let mut s = format!(
        "# raybench peers: {} pairs of runs, after over before\n\n",
        pairs.len()
    );
    for (i, (before, after)) in pairs.iter().enumerate() {
        let _ = writeln!(s, "- pair {}: {after} over {before}", i + 1);
    }
    let _ = writeln!(
        s,
        "\nPer figure and pair, the change of the contestant's speed relative to a reference \
         timed in the same rounds, with its {:.0} % bootstrap interval (`+` faster, `-` \
         slower, by that pair alone); across pairs, the geometric mean of the pairs' changes \
         with its {:.0} % Student t interval over the pairs, which holds the drift between \
         runs as well as the noise within them, and the verdict it gives.",
        stats::CONFIDENCE * 100.0,
        stats::CONFIDENCE * 100.0
    );
    let mut mesh = None;
    for group in groups {
        let f = &group[0];
        if mesh != Some(&f.mesh) {
            mesh = Some(&f.mesh);
            let _ = write!(
                s,
                "\n## {}\n\n| contestant | figure | reference | after / before per pair \
                 [interval] | across pairs [interval] | verdict |\n|---|---|---|---|---|---|\n",
                f.mesh
            );
        }
        let cells: Vec<String> = group
            .iter()
            .map(|g| {
                let mark = match g.verdict {
                    Change::Faster => " +",
                    Change::Slower => " -",
                    Change::Same | Change::Unknown => "",
                };
                let interval = bracketed(g.interval);
                format!("{:.3}{interval}{mark}", g.change)
            })
            .collect();
        let all = pooled(group);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.3}{} | {} |",
            f.contestant,
            f.what,
            f.reference.as_deref().unwrap_or("(raw times)"),
            cells.join("; "),
            all.change,
            bracketed(all.interval),
            all.verdict.label()
        );
    }
    s
}

/// Reads a peer benchmark's JSON.
///
/// # Errors
/// A message naming the file and the cause.
pub fn read(path: &std::path::Path) -> Result<Value, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// A run of one mesh with `packet` and `embree1-default` in one group; `packet`'s
    /// shadow any-hit rounds take `packet` seconds, Embree's `embree`.
    fn run(packet: &[f64], embree: &[f64]) -> Value {
        let contestant = |name: &str, samples: &[f64]| {
            json!({
                "name": name,
                "build_rounds_s": [0.010, 0.011, 0.012],
                "build_ratio": {"reference": "embree1-default"},
                "ray_sets": [{
                    "name": "shadow",
                    "any": {
                        "runs": [{"threads": 1, "samples_s": samples}],
                        "ratios": [{"reference": "embree1-default", "threads": 1}],
                    },
                }],
            })
        };
        json!({
            "schema": "raybench-peers/2",
            "machine": {"cpu": "AMD EPYC (family 25, model 17)"},
            "workload": {"primary_size": 1024, "tile": 16, "incoherent_rays": 1_048_576,
                         "seed": 1, "chunk": 1024, "shadow_fraction": 0.5},
            "meshes": [{
                "name": "sponza",
                "ray_sets": [{"name": "shadow", "rays": 1000}],
                "groups": [["packet", "embree1-default"]],
                "contestants": [contestant("packet", packet), contestant("embree1-default", embree)],
            }],
        })
    }

    fn shadow(figures: &[Figure]) -> &Figure {
        figures
            .iter()
            .find(|f| f.contestant == "packet" && f.what == "shadow any, 1 thread")
            .expect("the shadow figure")
    }

    /// A machine twice as slow in the second run, and `packet` 20 % faster against the
    /// same reference: the reference cancels the drift, and the change is faster.
    #[test]
    fn the_reference_cancels_the_machines_drift() {
        let before = run(
            &[1.00, 1.02, 0.99, 1.01, 1.00],
            &[0.80, 0.81, 0.79, 0.80, 0.80],
        );
        let after = run(
            &[1.67, 1.70, 1.66, 1.68, 1.67],
            &[1.60, 1.62, 1.58, 1.60, 1.60],
        );
        let figures = diff(&before, &after, None).unwrap();
        let f = shadow(&figures);
        assert_eq!(f.reference.as_deref(), Some("embree1-default"));
        assert!((f.change - 1.2).abs() < 0.01, "{}", f.change);
        assert_eq!(f.verdict, Change::Faster);
        let [lo, hi] = f.interval.unwrap();
        assert!(1.0 < lo && lo <= f.change && f.change <= hi, "{lo} {hi}");
        // On raw times the drift reads as a slowdown.
        let raw = diff(&before, &after, Some("none")).unwrap();
        let f = shadow(&raw);
        assert_eq!(f.reference, None);
        assert_eq!(f.verdict, Change::Slower);
        // Builds are paired with the reference's builds, unchanged here.
        let build = figures
            .iter()
            .find(|f| f.contestant == "packet" && f.what == "build")
            .unwrap();
        assert!((build.change - 1.0).abs() < 1e-9);
        let text = markdown(&figures, "a.json", "b.json");
        assert!(
            text.contains(
                "| packet | shadow any, 1 thread | embree1-default | 0.798 | 0.953 | 1.194"
            ),
            "{text}"
        );
        // The reference's own figure is on raw times: the drift itself.
        assert!(
            text.contains("| embree1-default | shadow any, 1 thread | (raw times) | 1.000 | 0.500")
        );
    }

    /// A change inside the rounds' spread is no verdict; the same runs read the same.
    #[test]
    fn noise_is_no_change() {
        let before = run(&[1.0, 1.3, 0.8, 1.1, 0.9], &[1.0; 5]);
        let after = run(&[0.95, 1.25, 0.85, 1.2, 0.9], &[1.0; 5]);
        assert_eq!(
            shadow(&diff(&before, &after, None).unwrap()).verdict,
            Change::Same
        );
        let same = diff(&before, &before, None).unwrap();
        assert!(
            same.iter()
                .all(|f| f.change == 1.0 && f.verdict != Change::Faster)
        );
    }

    /// Builds, interleaved across every contestant, keep their reference when the traces
    /// ran in separate groups; the traces, whose rounds were not paired, fall back to raw
    /// times.
    #[test]
    fn separate_groups_keep_the_builds_reference_only() {
        let mut split = run(&[1.0, 1.0, 1.0], &[1.0, 1.0, 1.0]);
        split["meshes"][0]["groups"] = json!([["packet"], ["embree1-default"]]);
        let figures = diff(&split, &split, None).unwrap();
        let of = |what: &str| {
            figures
                .iter()
                .find(|f| f.contestant == "packet" && f.what == what)
                .unwrap()
                .reference
                .clone()
        };
        assert_eq!(of("build").as_deref(), Some("embree1-default"));
        assert_eq!(of("shadow any, 1 thread"), None);
    }

    /// Several pairs are taken together: a change where their changes agree, whether or
    /// not each pair's own interval excludes 1, and none where they part ways.
    #[test]
    fn pairs_are_pooled() {
        let before = run(&[1.00, 1.02, 0.99, 1.01, 1.00], &[1.0; 5]);
        let faster = run(&[0.80, 0.81, 0.79, 0.80, 0.80], &[1.0; 5]);
        let slower = run(&[1.20, 1.21, 1.19, 1.20, 1.20], &[1.0; 5]);
        let d = |a: &Value| diff(&before, a, None).unwrap();
        let shadow = |groups: Vec<Vec<Figure>>| {
            groups
                .into_iter()
                .find(|g| g[0].what == "shadow any, 1 thread")
                .expect("the shadow figure")
        };
        let verdict = |pairs: &[Vec<Figure>]| pooled(&shadow(across(pairs))).verdict;
        assert_eq!(verdict(&[d(&faster), d(&faster)]), Change::Faster);
        assert_eq!(verdict(&[d(&slower), d(&slower)]), Change::Slower);
        assert_eq!(verdict(&[d(&faster), d(&slower)]), Change::Same);
        assert_eq!(verdict(&[d(&faster), d(&before)]), Change::Same);
        assert_eq!(verdict(&[d(&before), d(&before)]), Change::Same);
        // Pairs whose own intervals hold 1 but whose changes agree (Sponza's diffuse any
        // hits under the fused box test, three pairs), and pairs that part ways.
        let group = |changes: [f64; 3]| {
            let one = shadow(across(&[d(&faster)])).remove(0);
            changes.map(|change| Figure {
                change,
                interval: Some([change * 0.9, change * 1.1]),
                verdict: Change::Same,
                ..one.clone()
            })
        };
        let agree = pooled(&group([1.10, 1.12, 1.17]));
        assert_eq!(agree.verdict, Change::Faster, "{agree:?}");
        assert!((agree.change - (1.10f64 * 1.12 * 1.17).cbrt()).abs() < 1e-12);
        assert_eq!(pooled(&group([0.99, 1.135, 1.27])).verdict, Change::Same);
        let groups = across(&[d(&faster), d(&slower)]);
        let names = [
            ("b1".to_string(), "a1".to_string()),
            ("b2".into(), "a2".into()),
        ];
        let text = markdown_across(&groups, &names);
        assert!(
            text.contains("| packet | shadow any, 1 thread | embree1-default | 1.250 [1.23-1.27] +; 0.833 [0.82-0.85] - | 1.021 [0.08-13.41] | within noise |"),
            "{text}"
        );
        // A figure missing from one pair is left out.
        assert!(across(&[d(&faster), Vec::new()]).is_empty());
    }

    #[test]
    fn other_documents_are_refused() {
        let err = diff(
            &json!({"schema": "raybench-results/3"}),
            &run(&[1.0], &[1.0]),
            None,
        );
        assert!(
            err.unwrap_err()
                .contains("before: not a peer benchmark's JSON")
        );
    }
}
