//! The matrix's "Structure quality" section and its charts: every structure's figures
//! (`Run::quality`, computed once per backend and scene after the build) tabulated per scene,
//! and the SAH cost and the EPO set against the measured time of ray casting.

use super::{Chart, Plot};
use crate::charts::Series;
use crate::fmt::{backends_in, section};
use crate::results::{GRID_COLUMNS, Quality, Results, Run, TREE_COLUMNS};
use std::fmt::Write as _;

/// The workloads (mode, ray set) whose times the charts set against SAH and EPO.
const TIMED: [(&str, &str); 2] = [("cast", "primary"), ("cast", "incoherent")];

/// The first run of every (scene, backend) that has quality figures, in run order.
fn structures(results: &Results) -> Vec<&Run> {
    let mut out: Vec<&Run> = Vec::new();
    for r in &results.runs {
        if r.quality.is_some()
            && !out
                .iter()
                .any(|o| o.scene == r.scene && o.backend == r.backend)
        {
            out.push(r);
        }
    }
    out
}

/// A timed tree: its run, SAH cost, EPO (`None` where not measured: [`Quality::measured_epo`])
/// and the mean median seconds of its backend's runs of a workload on its scene.
type TimedTree<'a> = (&'a Run, f64, Option<f64>, f64);

/// Each tree's SAH cost, EPO and the mean median seconds of its backend's runs of workload
/// `(mode, set)` on its scene (several runs: one per camera), per structure that has them.
fn timed_trees<'a>(results: &'a Results, mode: &str, set: &str) -> Vec<TimedTree<'a>> {
    structures(results)
        .into_iter()
        .filter_map(|s| {
            let q = s.quality.as_ref()?;
            let sah = q.sah()?;
            let epo = q.measured_epo();
            let times: Vec<f64> = results
                .runs
                .iter()
                .filter(|r| {
                    r.scene == s.scene
                        && r.backend == s.backend
                        && r.mode == mode
                        && r.ray_set == set
                })
                .filter_map(|r| r.seconds.as_ref().map(|t| t.median))
                .collect();
            (!times.is_empty())
                .then(|| (s, sah, epo, times.iter().sum::<f64>() / times.len() as f64))
        })
        .collect()
}

/// SAH cost and EPO against the time of ray casting (camera rays, incoherent rays): one
/// series per backend, one point per scene; points that are not positive (an EPO of 0)
/// cannot sit on log axes and are left out.
pub(super) fn charts(results: &Results) -> Vec<Chart> {
    let mut out = Vec::new();
    for (mode, set) in TIMED {
        let points = timed_trees(results, mode, set);
        let runs: Vec<&Run> = points.iter().map(|p| p.0).collect();
        for (metric, stem, pick) in [("SAH cost", "sah", 0usize), ("EPO", "epo", 1)] {
            let series: Vec<Series> = backends_in(&runs)
                .into_iter()
                .map(|b| Series {
                    points: points
                        .iter()
                        .filter(|p| p.0.backend == b)
                        .filter_map(|p| Some(([Some(p.1), p.2][pick]?, p.3)))
                        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
                        .collect(),
                    label: b,
                    fit: None,
                })
                .filter(|s| !s.points.is_empty())
                .collect();
            if series.is_empty() {
                continue;
            }
            out.push(Chart {
                title: format!("{metric} against time, {mode} ({set} rays)"),
                stem: format!("quality-{stem}-{mode}-{set}"),
                x_label: format!("{metric} (C_t = C_i = 1)"),
                y_label: format!("time to cast the {set} rays (s, median)"),
                plot: Plot::Scatter(series),
            });
        }
    }
    out
}

/// How often one figure's lowest tree was the fastest: over `scenes` scenes with two or more
/// timed trees that the figure tells apart, `picked` times; `tied` more scenes had two or more
/// trees share the lowest figure (no pick), `unmeasured` more lacked the figure.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Picks {
    scenes: usize,
    picked: usize,
    tied: usize,
    unmeasured: usize,
}

/// Whether the tree with the lowest SAH cost (and the lowest EPO) was the fastest tree on
/// `(mode, set)`, over the scenes where at least two trees were timed. A scene where the
/// lowest figure is shared is a tie, not a pick (where the first tree listed would win);
/// trees without a measured EPO take no part in the EPO's count.
fn lowest_is_fastest(results: &Results, mode: &str, set: &str) -> (Picks, Picks) {
    let points = timed_trees(results, mode, set);
    let mut scenes: Vec<&str> = Vec::new();
    for p in &points {
        if !scenes.contains(&p.0.scene.as_str()) {
            scenes.push(&p.0.scene);
        }
    }
    let (mut sah, mut epo) = (Picks::default(), Picks::default());
    for sc in scenes {
        let here: Vec<&TimedTree> = points.iter().filter(|p| p.0.scene == sc).collect();
        if here.len() < 2 {
            continue;
        }
        let fastest = here
            .iter()
            .min_by(|a, b| a.3.total_cmp(&b.3))
            .map(|p| p.0.backend.as_str());
        for (picks, figure) in [
            (
                &mut sah,
                (|p: &TimedTree| Some(p.1)) as fn(&TimedTree) -> Option<f64>,
            ),
            (&mut epo, |p: &TimedTree| p.2),
        ] {
            let figures: Vec<(f64, &str)> = here
                .iter()
                .filter_map(|p| Some((figure(p)?, p.0.backend.as_str())))
                .collect();
            if figures.len() < 2 {
                picks.unmeasured += 1;
                continue;
            }
            let lowest = figures.iter().map(|f| f.0).fold(f64::INFINITY, f64::min);
            let at_lowest: Vec<&str> = figures
                .iter()
                .filter(|f| f.0 == lowest)
                .map(|f| f.1)
                .collect();
            if at_lowest.len() > 1 {
                picks.tied += 1;
                continue;
            }
            picks.scenes += 1;
            picks.picked += usize::from(Some(at_lowest[0]) == fastest);
        }
    }
    (sah, epo)
}

/// `the tree with the lowest SAH cost was the fastest in 3 of 5 scenes (2 more tied at the
/// lowest figure)`.
fn describe_picks(figure: &str, p: Picks) -> String {
    let mut out = format!(
        "the tree with the lowest {figure} was the fastest in {} of {} scenes",
        p.picked, p.scenes
    );
    let mut extra = Vec::new();
    if p.tied > 0 {
        extra.push(format!(
            "{} more had trees tied at the lowest {figure}",
            p.tied
        ));
    }
    if p.unmeasured > 0 {
        extra.push(format!(
            "{} more had fewer than two trees with it measured",
            p.unmeasured
        ));
    }
    if !extra.is_empty() {
        let _ = write!(out, " ({})", extra.join("; "));
    }
    out
}

/// Writes "Structure quality": the trees' and grids' tables, the unreadable structures, and
/// what the charts show (nothing when no run has quality figures).
pub(super) fn write(results: &Results, s: &mut String) {
    let all = structures(results);
    if all.is_empty() {
        return;
    }
    let (c_t, c_i) = all
        .iter()
        .find_map(|r| match r.quality {
            Some(Quality::Tree { c_t, c_i, .. }) => Some((c_t, c_i)),
            _ => None,
        })
        .unwrap_or((1.0, 1.0));
    section(
        s,
        "Structure quality",
        &format!(
            "Figures of the structure each backend built, read from the structure itself once per \
             scene. Trees: the SAH cost with C_t = {c_t} per interior node and C_i = {c_i} per \
             primitive test (the expected work of a ray that hits the root box: every node's cost \
             weighted by its box's surface area over the root's); the EPO, end-point overlap \
             (Aila, Karras and Laine 2013), the cost of the nodes whose box holds a point of a \
             surface that their subtree does not hold, averaged over the surface area and \
             estimated from points sampled by area on the triangles and spheres, with its standard \
             error; depth counts nodes from the root (depth 1) to a leaf; bytes per bounded \
             primitive. Grids: the cells whose lists rays test, the fraction that is not empty, \
             references per primitive and the lengths of the non-empty lists."
        ),
    );
    let table = |s: &mut String, headers: [&str; 7], f: fn(&Quality) -> Option<[String; 7]>| {
        let rows: Vec<(&Run, [String; 7])> = all
            .iter()
            .filter_map(|r| Some((*r, f(r.quality.as_ref()?)?)))
            .collect();
        if rows.is_empty() {
            return;
        }
        let _ = writeln!(s, "| scene | backend | {} |", headers.join(" | "));
        let _ = writeln!(s, "|---|---|{}---|", "---:|".repeat(headers.len() - 1));
        for (r, cells) in rows {
            let _ = writeln!(s, "| {} | {} | {} |", r.scene, r.backend, cells.join(" | "));
        }
        let _ = writeln!(s);
    };
    table(s, TREE_COLUMNS, Quality::tree_columns);
    table(s, GRID_COLUMNS, Quality::grid_columns);
    let mut unreadable: Vec<String> = Vec::new();
    for r in &all {
        if let Some(Quality::NotReadable { reason }) = &r.quality {
            let line = format!("`{}` ({reason})", r.backend);
            if !unreadable.contains(&line) {
                unreadable.push(line);
            }
        }
    }
    if !unreadable.is_empty() {
        let _ = writeln!(s, "Not readable: {}.\n", unreadable.join(", "));
    }
    let excluded = all.iter().find_map(|r| match r.quality {
        Some(Quality::Tree {
            epo_excluded_primitives: n @ 1..,
            ..
        }) => Some((r.scene.as_str(), n)),
        _ => None,
    });
    if let Some((scene, n)) = excluded {
        let _ = writeln!(
            s,
            "The EPO leaves out primitives that are neither triangles nor spheres ({n} in \
             {scene}, and likewise in other such scenes).\n"
        );
    }
    let _ = writeln!(
        s,
        "The charts \"SAH cost against time\" and \"EPO against time\" set each tree's figure \
         against the median time of its backend on ray casting (camera rays, and incoherent \
         rays), one colour per backend and one point per scene. Aila, Karras and Laine found \
         that the SAH cost alone predicts measured speed poorly and that EPO explains much of \
         the rest; here the backends also differ in their traversal (SIMD, wide nodes), which \
         neither figure sees, and the scenes differ in size, so points are comparable within a \
         scene. An EPO of 0 (no overlap) cannot sit on log axes and is left out of its chart; \
         a tree whose scene holds only kinds the EPO leaves out has no EPO (\"not measured\"), \
         not an EPO of 0. The trees compared below differ in arity and traversal kernel as well \
         as in build, so these counts are not the fixed-kernel test of the 2013 paper.\n"
    );
    for (mode, set) in TIMED {
        let (sah, epo) = lowest_is_fastest(results, mode, set);
        if sah.scenes + sah.tied + sah.unmeasured > 0 {
            let _ = writeln!(
                s,
                "On {mode} ({set} rays), over the scenes where two or more trees were timed, {} \
                 and {}.\n",
                describe_picks("SAH cost", sah),
                describe_picks("EPO", epo)
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::verdict::tests::run;

    /// A tree with SAH cost `sah` and EPO `epo` (`None`: no point sampled).
    fn tree(sah: f64, epo: Option<f64>) -> Quality {
        Quality::Tree {
            c_t: 1.0,
            c_i: 1.0,
            sah,
            epo: epo.unwrap_or(0.0),
            epo_std_error: 0.0,
            epo_samples: if epo.is_some() { 4096 } else { 0 },
            epo_excluded_primitives: if epo.is_some() { 0 } else { 10 },
            interior_nodes: 1,
            leaves: 2,
            leaf_sizes: [2, 0, 0, 0, 0, 0, 0],
            max_depth: 2,
            mean_leaf_depth: 2.0,
            references: 2,
            bytes_per_primitive: 32.0,
            leaves_per_ray: None,
            leaf_count_std_dev: None,
        }
    }

    /// The run of `backend` on `scene` (camera rays) at `ms` with its tree.
    fn timed(scene: &str, backend: &str, ms: f64, q: Quality) -> Run {
        Run {
            quality: Some(q),
            ..run(scene, backend, &[ms, ms, ms])
        }
    }

    /// A tie at the lowest figure is no pick (the first tree listed would win it), and a tree
    /// without a measured EPO takes no part in the EPO's count.
    #[test]
    fn ties_and_unmeasured_epo_are_not_picks() {
        let results = Results {
            runs: vec![
                // a: the lowest SAH and EPO picks the fastest tree.
                timed("a", "x", 1.0, tree(10.0, Some(1.0))),
                timed("a", "y", 2.0, tree(20.0, Some(2.0))),
                // b: both trees at EPO 0.5 (a tie); the lowest SAH is the slower tree.
                timed("b", "x", 2.0, tree(10.0, Some(0.5))),
                timed("b", "y", 1.0, tree(20.0, Some(0.5))),
                // c: nothing the EPO samples (quadrics, say): not measured, not 0.
                timed("c", "x", 1.0, tree(10.0, None)),
                timed("c", "y", 2.0, tree(10.0, None)),
            ],
            ..Results::default()
        };
        let (sah, epo) = lowest_is_fastest(&results, "cast", "primary");
        assert_eq!(
            sah,
            Picks {
                scenes: 2,
                picked: 1,
                tied: 1,
                unmeasured: 0
            }
        );
        assert_eq!(
            epo,
            Picks {
                scenes: 1,
                picked: 1,
                tied: 1,
                unmeasured: 1
            }
        );
        assert_eq!(
            describe_picks("EPO", epo),
            "the tree with the lowest EPO was the fastest in 1 of 1 scenes (1 more had trees \
             tied at the lowest EPO; 1 more had fewer than two trees with it measured)"
        );
        assert_eq!(tree(1.0, None).tree_columns().unwrap()[1], "not measured");
        assert_eq!(
            tree(1.0, Some(0.25)).tree_columns().unwrap()[1],
            "0.25 ± 0.00"
        );
    }
}
