//! The quality metrics against trace time with the traversal kernel held fixed, as Aila,
//! Karras and Laine ("On Quality Metrics of Bounding Volume Hierarchies", HPG 2013) measured
//! them: the trees of experiment `presets` grouped by the kernel that traces them (the part
//! of `BACKEND:PRESET` before the `:`: `bvh` traces its binned-SAH trees and obvhs's PLOC
//! topologies, `obvhs` its CWBVH presets, `packet` its BVH8s), and per scene and ray set the
//! correlation of each figure with the measured trace time across that kernel's trees. A
//! grid's resolutions (`grid:*`) form sweeps of their own, read by their cell count and
//! measured work (cells visited plus primitive tests per ray), since the SAH and EPO
//! describe trees.
//!
//! Figures: the SAH cost (`C_t` per interior node, which the kernel visits as one node of
//! the arity stated beside it, `C_i` per primitive test), the EPO where it was measured
//! ([`Quality::measured_epo`]; never read as 0), and the combined predictor
//! `(1 - a) SAH + a EPO` with the weight `a` in [0, 1] that correlates best (the paper's
//! form; a weight chosen on the same data overstates how well it predicts, which the text
//! says). Correlations are Pearson's r over the kernel's trees with a 95 % interval from
//! Fisher's z transform (`tanh(atanh r ± 1.96 / sqrt(n - 3))`, n >= 4 trees).

use super::{Chart, Plot};
use crate::charts::Series;
use crate::fmt::file_safe;
use crate::results::{Quality, Results, ScalingPoint};
use std::fmt::Write as _;

/// The experiment whose points carry the trees.
const EXPERIMENT: &str = "presets";

/// One tree of a kernel's sweep: its preset, SAH, EPO (`None`: not measured), mean
/// children per interior node, the trace time's median and interval, the kernel's node
/// visits plus primitive tests per ray, and the leaves entered per ray (mean, standard
/// deviation) over the traced rays.
#[derive(Clone, Debug, PartialEq)]
struct Tree {
    preset: String,
    sah: f64,
    epo: Option<f64>,
    arity: f64,
    seconds: f64,
    interval: Option<[f64; 2]>,
    work: Option<f64>,
    leaves: Option<(f64, f64)>,
}

/// One resolution of a grid kernel's sweep: its preset, cells and references per
/// primitive, the trace time's median and interval, and the kernel's cell visits and
/// primitive tests per ray. The SAH and EPO describe trees; a grid is read by its work.
#[derive(Clone, Debug, PartialEq)]
struct Resolution {
    preset: String,
    cells: u64,
    references_per_primitive: f64,
    seconds: f64,
    interval: Option<[f64; 2]>,
    visits: Option<f64>,
    tests: Option<f64>,
}

impl Resolution {
    /// Cell visits plus primitive tests per ray, where both were counted.
    fn work(&self) -> Option<f64> {
        Some(self.visits? + self.tests?)
    }
}

/// A kernel's sweep on one scene and ray set: its trees ([`Tree`]) or its grid resolutions
/// ([`Resolution`]).
#[derive(Clone, Debug, PartialEq)]
struct Sweep<T = Tree> {
    scene: String,
    set: String,
    kernel: String,
    members: Vec<T>,
}

/// The tree of a point of experiment `presets`, when it has tree figures.
fn tree_of(p: &ScalingPoint) -> Option<Tree> {
    let q = p.quality.as_ref()?;
    let Quality::Tree {
        sah,
        interior_nodes,
        leaves,
        leaves_per_ray,
        leaf_count_std_dev,
        ..
    } = q
    else {
        return None;
    };
    let children = (interior_nodes + leaves).saturating_sub(1);
    Some(Tree {
        preset: p.backend.clone(),
        sah: *sah,
        epo: q.measured_epo(),
        arity: if *interior_nodes == 0 {
            0.0
        } else {
            children as f64 / *interior_nodes as f64
        },
        seconds: p.seconds,
        interval: p.timing.as_ref().and_then(|t| t.interval),
        work: match (p.visits_per_ray, p.tests_per_ray) {
            (Some(v), Some(t)) => Some(v + t),
            _ => None,
        },
        leaves: leaves_per_ray.zip(*leaf_count_std_dev),
    })
}

impl<T> Sweep<T> {
    /// The first cells of its table rows: `| scene | rays | kernel |`.
    fn row_start(&self) -> String {
        format!("| {} | {} | {} |", self.scene, self.set, self.kernel)
    }
}

/// The grid resolution of a point of experiment `presets`, when it has grid figures.
fn resolution_of(p: &ScalingPoint) -> Option<Resolution> {
    let Some(Quality::Grid {
        cells,
        references,
        primitives,
        ..
    }) = p.quality
    else {
        return None;
    };
    Some(Resolution {
        preset: p.backend.clone(),
        cells,
        references_per_primitive: references as f64 / primitives.max(1) as f64,
        seconds: p.seconds,
        interval: p.timing.as_ref().and_then(|t| t.interval),
        visits: p.visits_per_ray,
        tests: p.tests_per_ray,
    })
}

/// Every kernel's sweep with at least two trees, in the order the points ran.
fn sweeps(results: &Results) -> Vec<Sweep> {
    sweeps_of(results, tree_of)
}

/// Every kernel's sweep with at least two members that `member` reads from the points of
/// experiment `presets` (the part of the preset's name before the `:` is the kernel), in
/// the order the points ran.
fn sweeps_of<T>(results: &Results, member: fn(&ScalingPoint) -> Option<T>) -> Vec<Sweep<T>> {
    let mut out: Vec<Sweep<T>> = Vec::new();
    for p in results
        .scaling
        .iter()
        .filter(|p| p.experiment == EXPERIMENT)
    {
        let (Some(found), Some((scene, set))) = (member(p), p.series.rsplit_once(' ')) else {
            continue;
        };
        let kernel = p.backend.split(':').next().unwrap_or_default();
        match out
            .iter_mut()
            .find(|s| s.scene == scene && s.set == set && s.kernel == kernel)
        {
            Some(s) => s.members.push(found),
            None => out.push(Sweep {
                scene: scene.into(),
                set: set.into(),
                kernel: kernel.into(),
                members: vec![found],
            }),
        }
    }
    out.retain(|s| s.members.len() >= 2);
    out
}

/// Pearson's correlation of the pairs; `None` with fewer than 3 pairs or a constant side.
fn pearson(pairs: &[(f64, f64)]) -> Option<f64> {
    let n = pairs.len();
    if n < 3 {
        return None;
    }
    let mean = |f: fn(&(f64, f64)) -> f64| pairs.iter().map(f).sum::<f64>() / n as f64;
    let (mx, my) = (mean(|p| p.0), mean(|p| p.1));
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (x, y) in pairs {
        sxy += (x - mx) * (y - my);
        sxx += (x - mx) * (x - mx);
        syy += (y - my) * (y - my);
    }
    (sxx > 0.0 && syy > 0.0).then(|| (sxy / (sxx * syy).sqrt()).clamp(-1.0, 1.0))
}

/// The 95 % interval of a correlation `r` over `n` pairs by Fisher's z transform; `None`
/// below 4 pairs (the interval needs `n - 3 > 0`).
fn fisher_interval(r: f64, n: usize) -> Option<[f64; 2]> {
    if n < 4 {
        return None;
    }
    let z = r.clamp(-0.999_999, 0.999_999).atanh();
    let half = 1.96 / ((n - 3) as f64).sqrt();
    Some([(z - half).tanh(), (z + half).tanh()])
}

/// The weight `a` (in steps of 0.01) whose `(1 - a) SAH + a EPO` correlates best with the
/// time, and that correlation; `None` unless at least 3 trees have a measured EPO.
fn best_combination(trees: &[Tree]) -> Option<(f64, f64)> {
    let with: Vec<&Tree> = trees.iter().filter(|t| t.epo.is_some()).collect();
    let mut best: Option<(f64, f64)> = None;
    for step in 0..=100 {
        let a = f64::from(step) / 100.0;
        let pairs: Vec<(f64, f64)> = with
            .iter()
            .map(|t| ((1.0 - a) * t.sah + a * t.epo.unwrap_or(0.0), t.seconds))
            .collect();
        if let Some(r) = pearson(&pairs)
            && best.is_none_or(|b| r > b.1)
        {
            best = Some((a, r));
        }
    }
    best
}

/// One table row per member of each sweep, sorted by `order`: the scene and ray set, then
/// `cells` of the member.
fn member_rows<T: Clone>(
    sweeps: &[Sweep<T>],
    order: impl Fn(&T, &T) -> std::cmp::Ordering,
    cells: impl Fn(&T) -> String,
    s: &mut String,
) {
    for sw in sweeps {
        let mut members = sw.members.clone();
        members.sort_by(&order);
        for m in &members {
            let _ = writeln!(s, "| {} | {} | {} |", sw.scene, sw.set, cells(m));
        }
    }
}

/// A trace time cell: `0.08524 [0.08324, 0.08836]` (median [interval]).
fn time_cell(seconds: f64, interval: Option<[f64; 2]>) -> String {
    let interval = interval.map_or(String::new(), |[lo, hi]| format!(" [{lo:.5}, {hi:.5}]"));
    format!("{seconds:.5}{interval}")
}

/// `0.91 [0.62, 0.98]`; `-` without a correlation, no interval below 4 pairs.
fn describe(r: Option<f64>, n: usize) -> String {
    match r {
        None => "-".into(),
        Some(r) => match fisher_interval(r, n) {
            Some([lo, hi]) => format!("{r:.2} [{lo:.2}, {hi:.2}]"),
            None => format!("{r:.2}"),
        },
    }
}

/// SAH cost against trace time per scene and ray set, one series per kernel.
pub(super) fn charts(results: &Results) -> Vec<Chart> {
    let all = sweeps(results);
    let mut keys: Vec<(&str, &str)> = Vec::new();
    for s in &all {
        if !keys.contains(&(s.scene.as_str(), s.set.as_str())) {
            keys.push((&s.scene, &s.set));
        }
    }
    keys.into_iter()
        .map(|(scene, set)| Chart {
            title: format!("SAH cost against trace time, kernel held fixed ({scene}, {set} rays)"),
            stem: format!("fixed-kernel-sah-{}-{set}", file_safe(scene)),
            x_label: "SAH cost (C_t = C_i = 1)".into(),
            y_label: format!("time to trace the {set} rays (s, median)"),
            plot: Plot::Scatter(
                all.iter()
                    .filter(|s| s.scene == scene && s.set == set)
                    .map(|s| Series {
                        label: format!("{} kernel", s.kernel),
                        points: s.members.iter().map(|t| (t.sah, t.seconds)).collect(),
                        fit: None,
                    })
                    .collect(),
            ),
        })
        .collect()
}

/// The section's introduction.
const INTRO: &str = "The quality figures against the measured trace time with the traversal \
    kernel held fixed (Aila, Karras and Laine 2013): the trees of every build preset, grouped \
    by the kernel that traces them (`bvh` traces its binned-SAH trees and, as `bvh:ploc_*`, \
    obvhs's PLOC trees copied into its layout; `obvhs` and `packet` trace their own presets), \
    and per scene and ray set Pearson's r of each figure with the median trace time over that \
    kernel's trees, with a 95 % interval from Fisher's z transform (4 trees or more). SAH: C_t \
    = 1 per interior node visited (its arity, the mean children per interior node, is stated: \
    a wide node is one visit testing that many boxes), C_i = 1 per primitive test. EPO: where \
    measured (trees over primitives it cannot sample show none, never 0). SAH+EPO: the paper's \
    combined predictor (1 - a) SAH + a EPO with the weight a that correlates best here; a \
    weight chosen on the same trees overstates how well it would predict new ones. LCV, \
    leaf-count variability (the paper's third figure, which matters where SIMD lanes wait for \
    the ray with the most leaves): the standard deviation over the traced rays of the leaves \
    whose box a ray's segment up to its closest hit enters (every exact closest-hit traversal \
    opens at least those), with their mean beside it in the trees' table. Work: r of the SAH \
    with the kernel's measured node visits plus primitive tests per ray, which the SAH models. \
    With a few trees per kernel the intervals are wide: read a correlation only where its \
    interval excludes 0. The grid's resolutions follow the trees, read by their work.";

/// Writes the section (nothing without a sweep of two trees or two grid resolutions).
pub(super) fn write(results: &Results, s: &mut String) {
    let all = sweeps(results);
    let grids = sweeps_of(results, resolution_of);
    if all.is_empty() && grids.is_empty() {
        return;
    }
    crate::fmt::section(
        s,
        "Tree quality against trace time, kernel held fixed",
        INTRO,
    );
    if !all.is_empty() {
        write_trees(&all, s);
    }
    write_grids(&grids, s);
}

/// The trees' correlations and each kernel's trees.
fn write_trees(all: &[Sweep], s: &mut String) {
    let _ = writeln!(
        s,
        "| scene | rays | kernel | arity | trees | r(SAH, time) | r(EPO, time) | a | r(SAH+EPO, time) | r(LCV, time) | r(SAH, work) |"
    );
    let _ = writeln!(s, "|---|---|---|---:|---:|---|---|---:|---|---|---|");
    for sw in all {
        let n = sw.members.len();
        let sah: Vec<(f64, f64)> = sw.members.iter().map(|t| (t.sah, t.seconds)).collect();
        let epo: Vec<(f64, f64)> = sw
            .members
            .iter()
            .filter_map(|t| Some((t.epo?, t.seconds)))
            .collect();
        let work: Vec<(f64, f64)> = sw
            .members
            .iter()
            .filter_map(|t| Some((t.sah, t.work?)))
            .collect();
        let lcv: Vec<(f64, f64)> = sw
            .members
            .iter()
            .filter_map(|t| Some((t.leaves?.1, t.seconds)))
            .collect();
        let combined = best_combination(&sw.members);
        let arity = sw.members.iter().map(|t| t.arity).sum::<f64>() / n as f64;
        let _ = writeln!(
            s,
            "{} {arity:.1} | {n} | {} | {} | {} | {} | {} | {} |",
            sw.row_start(),
            describe(pearson(&sah), n),
            if epo.is_empty() {
                "not measured".into()
            } else {
                describe(pearson(&epo), epo.len())
            },
            combined.map_or("-".into(), |c| format!("{:.2}", c.0)),
            describe(combined.map(|c| c.1), epo.len()),
            describe(pearson(&lcv), lcv.len()),
            describe(pearson(&work), work.len()),
        );
    }
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "Each kernel's trees, lowest SAH first (trace time: median [interval]):\n"
    );
    let _ = writeln!(
        s,
        "| scene | rays | preset | SAH | EPO | leaves/ray | LCV | trace s | work/ray |"
    );
    let _ = writeln!(s, "|---|---|---|---:|---:|---:|---:|---|---:|");
    member_rows(
        all,
        |a, b| a.sah.total_cmp(&b.sah),
        |t| {
            format!(
                "{} | {:.2} | {} | {} | {} | {} | {}",
                t.preset,
                t.sah,
                t.epo.map_or("not measured".into(), |e| format!("{e:.2}")),
                t.leaves.map_or("-".into(), |l| format!("{:.2}", l.0)),
                t.leaves.map_or("-".into(), |l| format!("{:.2}", l.1)),
                time_cell(t.seconds, t.interval),
                t.work.map_or("-".into(), |w| format!("{w:.1}")),
            )
        },
        s,
    );
    let _ = writeln!(s);
}

/// The grid's kernel over its resolutions: r of the trace time with the cell count and
/// with the measured work, and each resolution's figures (nothing without a sweep).
fn write_grids(grids: &[Sweep<Resolution>], s: &mut String) {
    if grids.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "The grid's kernel held fixed over its resolutions (the `grid:*` presets). The SAH \
         and EPO describe trees, so a grid is read by its cell count and by its measured work \
         per ray, cells visited plus primitive tests (what a grid's cost model counts): r of \
         each with the median trace time, with its 95 % interval (4 resolutions or more).\n"
    );
    let _ = writeln!(
        s,
        "| scene | rays | kernel | resolutions | r(cells, time) | r(work, time) |"
    );
    let _ = writeln!(s, "|---|---|---|---:|---|---|");
    for g in grids {
        let n = g.members.len();
        let cells: Vec<(f64, f64)> = g
            .members
            .iter()
            .map(|r| (r.cells as f64, r.seconds))
            .collect();
        let work: Vec<(f64, f64)> = g
            .members
            .iter()
            .filter_map(|r| Some((r.work()?, r.seconds)))
            .collect();
        let _ = writeln!(
            s,
            "{} {n} | {} | {} |",
            g.row_start(),
            describe(pearson(&cells), n),
            describe(pearson(&work), work.len()),
        );
    }
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "| scene | rays | preset | cells | refs/prim | cells visited/ray | tests/ray | trace s |"
    );
    let _ = writeln!(s, "|---|---|---|---:|---:|---:|---:|---|");
    let opt = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.1}"));
    member_rows(
        grids,
        |a, b| a.cells.cmp(&b.cells),
        |r| {
            format!(
                "{} | {} | {:.2} | {} | {} | {}",
                r.preset,
                r.cells,
                r.references_per_primitive,
                opt(r.visits),
                opt(r.tests),
                time_cell(r.seconds, r.interval),
            )
        },
        s,
    );
    let _ = writeln!(s);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tree(sah: f64, epo: Option<f64>, seconds: f64) -> Tree {
        Tree {
            preset: format!("bvh:{sah}"),
            sah,
            epo,
            arity: 2.0,
            seconds,
            interval: None,
            work: None,
            leaves: None,
        }
    }

    #[test]
    fn pearson_of_exact_lines_and_of_a_known_set() {
        let near = |r: Option<f64>, want: f64| (r.unwrap() - want).abs() < 1e-12;
        assert!(near(pearson(&[(1.0, 2.0), (2.0, 4.0), (3.0, 6.0)]), 1.0));
        assert!(near(pearson(&[(1.0, 6.0), (2.0, 4.0), (3.0, 2.0)]), -1.0));
        // x = 1..4, y = 1, 3, 2, 4 (both mean 2.5): sxy = 2.25 - 0.25 - 0.25 + 2.25 = 4,
        // sxx = syy = 5, r = 0.8.
        let r = pearson(&[(1.0, 1.0), (2.0, 3.0), (3.0, 2.0), (4.0, 4.0)]).unwrap();
        assert!((r - 0.8).abs() < 1e-12, "{r}");
        assert_eq!(pearson(&[(1.0, 1.0), (2.0, 1.0), (3.0, 1.0)]), None);
        assert_eq!(pearson(&[(1.0, 1.0), (2.0, 2.0)]), None);
    }

    #[test]
    fn fisher_interval_brackets_r_and_narrows_with_n() {
        assert_eq!(fisher_interval(0.5, 3), None);
        // n = 7: half-width 1.96 / 2 = 0.98 in z; atanh 0.5 = 0.549306.
        let [lo, hi] = fisher_interval(0.5, 7).unwrap();
        assert!((lo - (0.549_306_144 - 0.98f64).tanh()).abs() < 1e-9);
        assert!((hi - (0.549_306_144 + 0.98f64).tanh()).abs() < 1e-9);
        let [lo2, hi2] = fisher_interval(0.5, 28).unwrap();
        assert!(lo < lo2 && lo2 < 0.5 && 0.5 < hi2 && hi2 < hi);
    }

    #[test]
    fn the_combination_finds_the_figure_that_explains_the_time() {
        // Time follows the EPO exactly and the SAH not at all: a = 1.
        let trees = [
            tree(10.0, Some(1.0), 1.0),
            tree(9.0, Some(3.0), 3.0),
            tree(11.0, Some(2.0), 2.0),
            tree(10.0, Some(4.0), 4.0),
        ];
        let (a, r) = best_combination(&trees).unwrap();
        assert_eq!(a, 1.0);
        assert!((r - 1.0).abs() < 1e-12);
        // Without measured EPOs there is no combination.
        let none = [
            tree(1.0, None, 1.0),
            tree(2.0, None, 2.0),
            tree(3.0, None, 3.0),
        ];
        assert_eq!(best_combination(&none), None);
    }

    /// A grid's resolutions form their own sweep, read by cells and measured work; the
    /// trees' table leaves them out.
    #[test]
    fn grid_resolutions_are_read_by_cells_and_work() {
        let point = |preset: &str, cells: u64, visits: f64, seconds: f64| ScalingPoint {
            hit_fraction: None,
            shard: 0,
            experiment: EXPERIMENT.into(),
            series: "bunny incoherent".into(),
            backend: preset.into(),
            x: 1.0,
            seconds,
            timing: None,
            rays: 1,
            tests_per_ray: Some(10.0),
            load_seconds: None,
            build_seconds: Some(0.1),
            memory_bytes: None,
            difference: None,
            stored_primitives: None,
            visits_per_ray: Some(visits),
            quality: Some(Quality::Grid {
                cells,
                non_empty_cells: cells / 2,
                references: 300,
                primitives: 100,
                max_list: 9,
                list_lengths: [0; 7],
                bytes_per_primitive: 20.0,
            }),
        };
        // Time exactly linear in the work (visits + 10 tests) and falling with the cells.
        let results = Results {
            scaling: vec![
                point("grid:fine", 8000, 40.0, 0.5),
                point("grid:coarse", 1000, 10.0, 0.2),
                point("grid:medium", 4000, 20.0, 0.3),
                point("grid:fast_build", 2000, 30.0, 0.4),
            ],
            ..Results::default()
        };
        assert!(sweeps(&results).is_empty(), "a grid is no tree");
        let grids = sweeps_of(&results, resolution_of);
        assert_eq!(grids.len(), 1);
        assert_eq!(grids[0].members[1].references_per_primitive, 3.0);
        assert_eq!(grids[0].members[1].work(), Some(20.0));
        let mut text = String::new();
        write(&results, &mut text);
        assert!(!text.contains("r(SAH, time)"), "no tree sweep: {text}");
        let r_cells =
            pearson(&[(8000.0, 0.5), (1000.0, 0.2), (4000.0, 0.3), (2000.0, 0.4)]).unwrap();
        let [lo, hi] = fisher_interval(r_cells, 4).unwrap();
        assert!(
            text.contains(&format!(
                "| bunny | incoherent | grid | 4 | {r_cells:.2} [{lo:.2}, {hi:.2}] | 1.00 ["
            )),
            "{text}"
        );
        // The resolutions listed by cell count.
        let coarse = text.find("| grid:coarse | 1000 | 3.00 | 10.0 | 10.0 | 0.20000 |");
        let fine = text.find("| grid:fine | 8000 | 3.00 | 40.0 | 10.0 | 0.50000 |");
        assert!(
            coarse.is_some() && fine.is_some() && coarse < fine,
            "{text}"
        );
    }

    #[test]
    fn sweeps_group_presets_by_kernel_and_skip_lone_trees() {
        let q = |sah: f64| Quality::Tree {
            c_t: 1.0,
            c_i: 1.0,
            sah,
            epo: 0.0,
            epo_std_error: 0.0,
            epo_samples: 0,
            epo_excluded_primitives: 0,
            interior_nodes: 3,
            leaves: 4,
            leaf_sizes: [4, 0, 0, 0, 0, 0, 0],
            max_depth: 3,
            mean_leaf_depth: 3.0,
            references: 4,
            bytes_per_primitive: 32.0,
            leaves_per_ray: Some(2.0),
            leaf_count_std_dev: Some(sah / 100.0),
        };
        let point = |backend: &str, sah: f64| ScalingPoint {
            hit_fraction: None,
            shard: 0,
            experiment: EXPERIMENT.into(),
            series: "soup:100 primary".into(),
            backend: backend.into(),
            x: 1.0,
            seconds: sah / 10.0,
            timing: None,
            rays: 1,
            tests_per_ray: Some(2.0),
            load_seconds: None,
            build_seconds: Some(0.1),
            memory_bytes: None,
            difference: None,
            stored_primitives: None,
            visits_per_ray: Some(3.0),
            quality: Some(q(sah)),
        };
        let results = Results {
            scaling: vec![
                point("bvh:fast", 12.0),
                point("bvh:ploc_fast_build", 10.0),
                point("packet:medium", 5.0),
            ],
            ..Results::default()
        };
        let all = sweeps(&results);
        assert_eq!(all.len(), 1, "packet has one tree: no sweep");
        let s = &all[0];
        assert_eq!((s.scene.as_str(), s.set.as_str()), ("soup:100", "primary"));
        // The kernel is the part of the preset's name before the `:`.
        assert_eq!(format!("{}:fast", s.kernel), "bvh:fast");
        assert_eq!(s.members.len(), 2);
        // 3 interior nodes over 6 children: binary.
        assert_eq!(s.members[0].arity, 2.0);
        assert_eq!(s.members[0].epo, None, "no samples: not measured");
        assert_eq!(s.members[0].work, Some(5.0));
        assert_eq!(s.members[0].leaves, Some((2.0, 0.12)));
        let mut text = String::new();
        write(&results, &mut text);
        assert!(
            text.contains(
                "| soup:100 | primary | bvh | 2.0 | 2 | - | not measured | - | - | - | - |"
            ),
            "{text}"
        );
    }
}
