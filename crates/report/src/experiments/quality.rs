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

/// A tree's SAH cost, EPO and the mean median seconds of its backend's runs of workload
/// `(mode, set)` on its scene (several runs: one per camera), per structure that has them.
fn timed_trees<'a>(results: &'a Results, mode: &str, set: &str) -> Vec<(&'a Run, f64, f64, f64)> {
    structures(results)
        .into_iter()
        .filter_map(|s| {
            let (sah, epo) = s.quality.as_ref()?.sah_epo()?;
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
                        .map(|p| ([p.1, p.2][pick], p.3))
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

/// In how many scenes the tree with the lowest SAH cost (and the lowest EPO) was the fastest
/// tree on `(mode, set)`, over the scenes where at least two trees were timed.
fn lowest_is_fastest(results: &Results, mode: &str, set: &str) -> (usize, usize, usize) {
    let points = timed_trees(results, mode, set);
    let mut scenes: Vec<&str> = Vec::new();
    for p in &points {
        if !scenes.contains(&p.0.scene.as_str()) {
            scenes.push(&p.0.scene);
        }
    }
    let (mut sah, mut epo, mut counted) = (0, 0, 0);
    for sc in scenes {
        let here: Vec<_> = points.iter().filter(|p| p.0.scene == sc).collect();
        if here.len() < 2 {
            continue;
        }
        counted += 1;
        let argmin = |f: fn(&&&(&Run, f64, f64, f64)) -> f64| {
            here.iter()
                .min_by(|a, b| f(a).total_cmp(&f(b)))
                .map(|p| p.0.backend.as_str())
        };
        let fastest = argmin(|p| p.3);
        sah += usize::from(argmin(|p| p.1) == fastest);
        epo += usize::from(argmin(|p| p.2) == fastest);
    }
    (sah, epo, counted)
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
         scene. An EPO of 0 (no overlap) cannot sit on log axes and is left out of its chart.\n"
    );
    for (mode, set) in TIMED {
        let (sah, epo, counted) = lowest_is_fastest(results, mode, set);
        if counted > 0 {
            let _ = writeln!(
                s,
                "On {mode} ({set} rays), of the {counted} scenes where two or more trees were \
                 timed, the tree with the lowest SAH cost was the fastest in {sah} and the tree \
                 with the lowest EPO in {epo}.\n"
            );
        }
    }
}
