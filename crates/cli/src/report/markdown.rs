//! `REPORT.md` and the charts it shows, drawn from [`Results`] alone (so that a merge of
//! shards produces the same kind of report as one run).

use super::HEIGHTFIELD_BACKEND;
use super::charts::{self, Series};
use super::results::{Results, Run};
use super::{PEER_MAX_FLIP, PEER_MIN_ID_MATCH};
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::Path;

/// The charts drawn: `(title, svg, png)`, or why none could be.
pub struct Charts {
    pub drawn: Vec<(String, String, String)>,
    pub problem: Option<String>,
}

fn backends_in(runs: &[&Run]) -> Vec<String> {
    let mut seen = Vec::new();
    for r in runs {
        if !seen.contains(&r.backend) {
            seen.push(r.backend.clone());
        }
    }
    seen
}

/// Draws every chart into `dir`.
pub fn charts(results: &Results, dir: &Path) -> Charts {
    let mut out = Charts {
        drawn: Vec::new(),
        problem: None,
    };
    if let Err(e) = charts::font() {
        out.problem = Some(e);
        return out;
    }
    let mut add = |title: &str, r: Result<[String; 2], String>| match r {
        Ok([svg, png]) => out.drawn.push((
            title.to_string(),
            format!("charts/{svg}"),
            format!("charts/{png}"),
        )),
        Err(e) => {
            out.problem.get_or_insert(e);
        }
    };

    // Throughput per scene, one chart per workload kind.
    let mut kinds: Vec<(String, String)> = Vec::new();
    for r in &results.runs {
        let k = (r.mode.clone(), r.ray_set.clone());
        if !kinds.contains(&k) {
            kinds.push(k);
        }
    }
    for (mode, set) in &kinds {
        let runs: Vec<&Run> = results
            .runs
            .iter()
            .filter(|r| &r.mode == mode && &r.ray_set == set)
            .collect();
        let mut scenes: Vec<String> = Vec::new();
        for r in &runs {
            if !scenes.contains(&r.scene) {
                scenes.push(r.scene.clone());
            }
        }
        let series: Vec<(String, Vec<Option<f64>>)> = backends_in(&runs)
            .into_iter()
            .map(|b| {
                let v = scenes
                    .iter()
                    .map(|s| {
                        runs.iter()
                            .find(|r| &r.scene == s && r.backend == b)
                            .and_then(|r| r.mrays_per_s)
                    })
                    .collect();
                (b, v)
            })
            .collect();
        let title = format!("Throughput, {mode} ({set} rays)");
        add(
            &title,
            charts::categories(
                &dir.join(format!("throughput-{mode}-{set}")),
                &title,
                "Mrays/s",
                &scenes,
                &series,
            ),
        );
    }

    // Scaling: one chart per experiment, series and quantity.
    let mut groups: BTreeMap<(String, String), BTreeSet<String>> = BTreeMap::new();
    for p in &results.scaling {
        groups
            .entry((p.experiment.clone(), p.series.clone()))
            .or_default()
            .insert(p.backend.clone());
    }
    for ((experiment, series_name), backends) in &groups {
        if experiment == "bezier" {
            // Drawn below: direct and tessellated on one chart, and the image difference.
            continue;
        }
        let x_label = match experiment.as_str() {
            "primitives" => "primitives M",
            "pixels" => "pixels N^2",
            "heightfield" => "height-field cells N^2",
            _ => "samples per pixel K",
        };
        for (quantity, y_label) in [
            ("seconds", "render seconds"),
            ("tests_per_ray", "ray/primitive tests per ray"),
        ] {
            let series: Vec<Series> = backends
                .iter()
                .map(|b| {
                    let mut points: Vec<(f64, f64)> = results
                        .scaling
                        .iter()
                        .filter(|p| {
                            &p.experiment == experiment
                                && &p.series == series_name
                                && &p.backend == b
                        })
                        .filter_map(|p| match quantity {
                            "seconds" => Some((p.x, p.seconds)),
                            _ => p.tests_per_ray.map(|t| (p.x, t)),
                        })
                        .collect();
                    points.sort_by(|a, b| a.0.total_cmp(&b.0));
                    let slope = results.slope(experiment, series_name, b, quantity);
                    Series {
                        label: match slope {
                            Some(s) => format!("{b} (slope {s:.2})"),
                            None => b.clone(),
                        },
                        points,
                    }
                })
                .filter(|s| !s.points.is_empty())
                .collect();
            if series.is_empty() || (quantity == "tests_per_ray" && experiment != "primitives") {
                continue;
            }
            let title = format!("{y_label} vs {x_label} ({series_name})");
            add(
                &title,
                charts::log_log(
                    &dir.join(format!("scaling-{experiment}-{series_name}-{quantity}")),
                    &title,
                    x_label,
                    y_label,
                    &series,
                ),
            );
        }
        // Speed-up over naive where naive ran.
        if experiment == "primitives" && backends.contains("naive") {
            let naive: BTreeMap<u64, f64> = results
                .scaling
                .iter()
                .filter(|p| {
                    &p.experiment == experiment && &p.series == series_name && p.backend == "naive"
                })
                .map(|p| (p.x as u64, p.seconds))
                .collect();
            let series: Vec<Series> = backends
                .iter()
                .filter(|b| *b != "naive")
                .map(|b| Series {
                    label: b.clone(),
                    points: results
                        .scaling
                        .iter()
                        .filter(|p| {
                            &p.experiment == experiment
                                && &p.series == series_name
                                && &p.backend == b
                        })
                        .filter_map(|p| {
                            naive
                                .get(&(p.x as u64))
                                .map(|n| (p.x, n / p.seconds.max(1e-12)))
                        })
                        .collect(),
                })
                .filter(|s| !s.points.is_empty())
                .collect();
            if !series.is_empty() {
                let title = format!("speed-up over naive vs primitives M ({series_name})");
                add(
                    &title,
                    charts::log_log(
                        &dir.join(format!("speedup-{series_name}")),
                        &title,
                        "primitives M",
                        "naive time / backend time",
                        &series,
                    ),
                );
            }
        }
    }
    for (title, stem, x_label, y_label, series) in bezier_charts(results) {
        add(
            &title,
            charts::log_log(&dir.join(stem), &title, x_label, y_label, &series),
        );
    }
    out
}

/// A chart's title, file stem, axis labels and series.
type ChartSpec = (
    String,
    &'static str,
    &'static str,
    &'static str,
    Vec<Series>,
);

/// Experiment `bezier`: render time against primitives (the direct patches as one point at
/// their count, 32, and as a level line across the triangle counts for comparison), and
/// the tessellations' difference from the direct image against their triangle count (zero
/// fractions are left off the log scale; the table has them).
fn bezier_charts(results: &Results) -> Vec<ChartSpec> {
    let points = |series: &str| -> Vec<&super::results::ScalingPoint> {
        results
            .scaling
            .iter()
            .filter(|p| p.experiment == "bezier" && p.series == series)
            .collect()
    };
    let (direct, tess) = (points("direct"), points("tessellated"));
    let Some(d) = direct.first() else {
        return Vec::new();
    };
    if tess.is_empty() {
        return Vec::new();
    }
    let x_max = tess.iter().map(|p| p.x).fold(d.x, f64::max);
    let times = vec![
        Series {
            label: "tessellated (triangles)".into(),
            points: tess.iter().map(|p| (p.x, p.seconds)).collect(),
        },
        Series {
            label: "direct (32 patches; level line for comparison)".into(),
            points: vec![(d.x, d.seconds), (x_max, d.seconds)],
        },
    ];
    let diff = |label: &str, f: fn(&super::results::ImageDifference) -> f64| Series {
        label: label.into(),
        points: tess
            .iter()
            .filter_map(|p| p.difference.as_ref().map(|q| (p.x, f(q))))
            .filter(|&(_, y)| y > 0.0)
            .collect(),
    };
    let differences = vec![
        diff("mean FLIP", |q| q.mean_flip),
        diff("fraction of pixels: other patch or hit/miss", |q| {
            q.patch_mismatch
        }),
        diff("fraction of pixels: depth off by > 1%", |q| {
            q.depth_mismatch
        }),
    ]
    .into_iter()
    .filter(|s| !s.points.is_empty())
    .collect::<Vec<_>>();
    let mut out = vec![(
        "render seconds vs primitives (Bezier teapot: direct against tessellated)".to_string(),
        "scaling-bezier-seconds",
        "primitives (patches or triangles)",
        "render seconds",
        times,
    )];
    if !differences.is_empty() {
        out.push((
            "difference from the direct image vs triangles (Bezier teapot)".to_string(),
            "scaling-bezier-difference",
            "triangles 2 N^2 32",
            "difference",
            differences,
        ));
    }
    out
}

fn opt(v: Option<f64>, f: impl Fn(f64) -> String) -> String {
    v.map_or_else(|| "-".into(), f)
}

fn bytes(b: u64) -> String {
    if b >= 1 << 20 {
        format!("{:.1} MiB", b as f64 / f64::from(1 << 20))
    } else if b >= 1 << 10 {
        format!("{:.1} KiB", b as f64 / 1024.0)
    } else {
        format!("{b} B")
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
            "**Shard {}/{}**{}: {}, {} logical cores ({} worker threads); {}; GPU: {}; {}; {}. Started {} UTC, took {:.0} s.\n\n`{}`\n",
            sh.index,
            sh.count,
            if sh.quick { " (quick)" } else { "" },
            m.cpu,
            m.cores,
            m.threads,
            m.isa,
            m.gpu,
            m.os,
            m.version,
            sh.started.trim_end_matches('Z').replace('T', " "),
            sh.wall_seconds,
            sh.command
        );
    }
    let _ = writeln!(
        s,
        "Every backend renders the same scenes with the same settings. Times are the median of \
         the timed repetitions after one counted warm-up (min-max in brackets); build time is \
         separate. **Mrays/s** counts every ray traced (camera, secondary, shadow) over the \
         median time; **tests/ray** and **visits/ray** are ray/primitive tests and node or cell \
         visits per ray, counted in the warm-up. **Equality** compares each backend with the \
         reference backend of its scene (naive where it fits its time budget, else bvh, which \
         the test suite checks against naive on every built-in scene). **Pass**: a raybench CPU \
         backend (bound by the equivalence contract) must be bit-identical (ids, `t`, colours); \
         other backends must match at least {:.1}% of the ids, counting **ties** (a different \
         primitive at the same distance, within 1e-4 relative: coincident surfaces, where each \
         library breaks the tie its own way) as matches, with a mean FLIP error of at most \
         {PEER_MAX_FLIP}. PSNR is of the 8-bit sRGB images (`inf`: identical); FLIP is NVIDIA's \
         perceptual difference (0 = indistinguishable).\n",
        PEER_MIN_ID_MATCH * 100.0
    );
    if let Some(p) = &charts.problem {
        let _ = writeln!(s, "> Charts: {p}\n");
    }

    if !results.skipped.is_empty() {
        let _ = writeln!(s, "## Skipped\n");
        let _ = writeln!(
            s,
            "Parts of the matrix that did not run (or ran in part), so the tables below lack \
             them.\n"
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

    // Summary table: Mrays/s of every backend on every scene, camera rays, ray casting.
    let summary: Vec<&Run> = results
        .runs
        .iter()
        .filter(|r| r.mode == "cast" && r.ray_set == "primary")
        .collect();
    if !summary.is_empty() {
        let backends = backends_in(&summary);
        let mut scenes: Vec<&str> = Vec::new();
        for r in &summary {
            if !scenes.contains(&r.scene.as_str()) {
                scenes.push(&r.scene);
            }
        }
        let _ = writeln!(s, "## Summary: ray casting, camera rays, Mrays/s\n");
        let _ = writeln!(s, "| scene | primitives | {} |", backends.join(" | "));
        let _ = writeln!(s, "|---|---:|{}", "---:|".repeat(backends.len()));
        for sc in &scenes {
            let prims = summary
                .iter()
                .find(|r| r.scene == *sc)
                .map_or(0, |r| r.primitives);
            let cells: Vec<String> = backends
                .iter()
                .map(|b| {
                    summary
                        .iter()
                        .find(|r| r.scene == *sc && &r.backend == b)
                        .map_or("-".into(), |r| {
                            let fail = r.equality.as_ref().is_some_and(|e| !e.pass);
                            match r.mrays_per_s {
                                Some(v) => {
                                    format!("{v:.2}{}", if fail { " (differs)" } else { "" })
                                }
                                None => r.status.clone(),
                            }
                        })
                })
                .collect();
            let _ = writeln!(s, "| {sc} | {prims} | {} |", cells.join(" | "));
        }
        let _ = writeln!(s);
        // Ratios to Embree (single rays and packets) where it ran.
        for (base_name, what) in [("embree", "single rays"), ("embree-packet", "packets")] {
            if !backends.iter().any(|b| b == base_name) {
                continue;
            }
            let _ = writeln!(
                s,
                "Throughput relative to Embree's {what} (`{base_name}`) on the same rays, same run:\n"
            );
            let _ = writeln!(s, "| scene | {} |", backends.join(" | "));
            let _ = writeln!(s, "|---|{}", "---:|".repeat(backends.len()));
            for sc in &scenes {
                let base = summary
                    .iter()
                    .find(|r| r.scene == *sc && r.backend == base_name)
                    .and_then(|r| r.mrays_per_s);
                let cells: Vec<String> = backends
                    .iter()
                    .map(|b| {
                        let v = summary
                            .iter()
                            .find(|r| r.scene == *sc && &r.backend == b)
                            .and_then(|r| r.mrays_per_s);
                        opt(v.zip(base).map(|(v, e)| v / e), |x| format!("{x:.2}"))
                    })
                    .collect();
                let _ = writeln!(s, "| {sc} | {} |", cells.join(" | "));
            }
            let _ = writeln!(s);
        }
    }

    // Phases of backends on another device (the GPU).
    let phased: Vec<&Run> = results
        .runs
        .iter()
        .filter(|r| !r.phases.is_empty())
        .collect();
    if !phased.is_empty() {
        let _ = writeln!(s, "## GPU phases\n");
        let _ = writeln!(
            s,
            "Seconds per phase on the GPU backend (median of the timed repetitions): the \
             BVH built on the CPU and the scene uploaded once per scene; then per frame the \
             parameters uploaded, the kernels' execution on the GPU (timestamp queries when \
             the adapter has them, else wall time around submit and wait: this is the time \
             Mrays/s uses), the image read back, and the whole call.\n"
        );
        let cols = [
            "prepare.build",
            "prepare.upload",
            "upload",
            "gpu",
            "readback",
            "render",
        ];
        let _ = writeln!(
            s,
            "| scene | workload | backend | {} | Mrays/s |",
            cols.join(" | ")
        );
        let _ = writeln!(s, "|---|---|---|{}---:|", "---:|".repeat(cols.len()));
        for r in phased {
            let cells: Vec<String> = cols
                .iter()
                .map(|c| opt(r.phases.get(*c).copied(), |v| format!("{v:.4}")))
                .collect();
            let _ = writeln!(
                s,
                "| {} | {} {} {}x{} spp {} | {} | {} | {} |",
                r.scene,
                r.mode,
                r.ray_set,
                r.width,
                r.height,
                r.spp,
                r.backend,
                cells.join(" | "),
                opt(r.mrays_per_s, |v| format!("{v:.2}"))
            );
        }
        let _ = writeln!(s);
    }

    // Per scene and workload.
    let _ = writeln!(s, "## Scenes\n");
    let mut keys: Vec<(String, String, String, u32, u32, u32)> = Vec::new();
    for r in &results.runs {
        let k = (
            r.scene.clone(),
            r.mode.clone(),
            r.ray_set.clone(),
            r.width,
            r.height,
            r.spp,
        );
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    let mut last_scene = String::new();
    for (scene, mode, set, w, h, spp) in &keys {
        let runs: Vec<&Run> = results
            .runs
            .iter()
            .filter(|r| {
                &r.scene == scene
                    && &r.mode == mode
                    && &r.ray_set == set
                    && r.width == *w
                    && r.height == *h
                    && r.spp == *spp
            })
            .collect();
        if *scene != last_scene {
            let prims = runs.first().map_or(0, |r| r.primitives);
            let _ = writeln!(s, "### {scene} ({prims} primitives)\n");
            last_scene.clone_from(scene);
        }
        let what = if set == "primary" {
            format!("{w} x {h}, {spp} spp")
        } else {
            format!("{} random rays", u64::from(*w) * u64::from(*h))
        };
        let reference = runs.first().map_or("-", |r| r.reference.as_str());
        let _ = writeln!(
            s,
            "**{mode}, {set} rays** ({what}; reference `{reference}`)\n"
        );
        let _ = writeln!(
            s,
            "| backend | build s | memory | render s [min-max] | Mrays/s | tests/ray | visits/ray | id match | hit diff | ties | max abs dt | PSNR dB | FLIP | pass |"
        );
        let _ = writeln!(
            s,
            "|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"
        );
        for r in &runs {
            if r.status != "ok" {
                let _ = writeln!(
                    s,
                    "| {} | {}: {} ||||||||||||",
                    r.backend,
                    r.status,
                    r.reason.as_deref().unwrap_or("")
                );
                continue;
            }
            let e = r.equality.as_ref();
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                r.backend,
                opt(r.build_seconds, |v| format!("{v:.3}")),
                r.memory_bytes.map_or("-".into(), bytes),
                r.seconds.as_ref().map_or("-".into(), |t| format!(
                    "{:.4} [{:.4}-{:.4}]",
                    t.median, t.min, t.max
                )),
                opt(r.mrays_per_s, |v| format!("{v:.3}")),
                opt(r.tests_per_ray, |v| format!("{v:.1}")),
                opt(r.visits_per_ray, |v| format!("{v:.1}")),
                e.map_or("-".into(), |e| format!("{:.4}%", e.id_match * 100.0)),
                e.map_or("-".into(), |e| e.hit_mismatch.to_string()),
                e.map_or("-".into(), |e| e.tie_mismatch.to_string()),
                e.map_or("-".into(), |e| format!("{:.1e}", e.max_abs_dt)),
                e.map_or("-".into(), |e| {
                    match (e.psnr_db, e.identical || e.flip_mean.is_some()) {
                        (Some(p), _) => format!("{p:.1}"),
                        (None, true) if e.flip_mean.is_some() => "inf".into(),
                        _ => "-".into(),
                    }
                }),
                e.and_then(|e| e.flip_mean)
                    .map_or("-".into(), |f| format!("{f:.4}")),
                e.map_or("-", |e| if e.pass { "yes" } else { "**no**" }),
            );
        }
        let _ = writeln!(s);
        let mut pictures = Vec::new();
        for r in &runs {
            if let Some(c) = &r.images.color {
                pictures.push(format!("[{} image]({c})", r.backend));
            }
            if let Some(d) = &r.images.ids_diff {
                pictures.push(format!("[{} id differences]({d})", r.backend));
            }
            if let Some(f) = &r.images.flip {
                pictures.push(format!("[{} FLIP map]({f})", r.backend));
            }
        }
        if let Some(reference_image) = runs.first().and_then(|r| r.images.color.as_ref()) {
            let _ = writeln!(
                s,
                "<img src=\"{reference_image}\" width=\"192\" alt=\"{scene} {mode}\">\n"
            );
        }
        if !pictures.is_empty() {
            let _ = writeln!(s, "Images: {}\n", pictures.join(", "));
        }
    }

    if !results.scaling.is_empty() {
        let _ = writeln!(s, "## Scaling\n");
        let _ = writeln!(
            s,
            "Log-log fits `y ~ x^slope` of render time (and tests per ray) against the number of \
             primitives M (`soup:M`, `spheres:M` generators, 64 x 64 camera rays), the pixel \
             count N^2 (bunny), the samples per pixel K (Cornell box, path tracing, 64 x 64) and \
             the height-field cell count N^2 (direct and tessellated, see below). \
             The claims under test: naive's time grows linearly with M (slope about 1), an \
             acceleration structure's barely (slope near 0, logarithmic in theory); time grows \
             linearly with N^2 and with K for every backend.\n"
        );
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

    let hf: Vec<_> = results
        .scaling
        .iter()
        .filter(|p| p.experiment == "heightfield")
        .collect();
    if !hf.is_empty() {
        let _ = writeln!(s, "## Height fields: direct against tessellated\n");
        let _ = writeln!(
            s,
            "The `terrain:N` heights as one height-field primitive intersected directly (min-max \
             quadtree over the cells, `heightfield:N`) against the same terrain tessellated into \
             2 N^2 triangles (`terrain:N`), both in the `{}` backend; 256 x 256 camera rays. Both \
             give the same hits and `t` bit for bit. Load: generating the heights and \
             tessellating, or building the min-max levels; build: the BVH; memory: primitives \
             plus structure; a height field counts as one primitive test per ray.\n",
            HEIGHTFIELD_BACKEND
        );
        let _ = writeln!(
            s,
            "| cells | series | memory | load s | build s | render s | tests/ray |"
        );
        let _ = writeln!(s, "|---:|---|---:|---:|---:|---:|---:|");
        for p in hf {
            let _ = writeln!(
                s,
                "| {}^2 | {} | {} | {} | {} | {:.4} | {} |",
                p.x.sqrt().round(),
                p.series,
                p.memory_bytes.map_or("-".into(), bytes),
                opt(p.load_seconds, |v| format!("{v:.3}")),
                opt(p.build_seconds, |v| format!("{v:.3}")),
                p.seconds,
                opt(p.tests_per_ray, |v| format!("{v:.1}"))
            );
        }
        let _ = writeln!(s);
    }

    let bz: Vec<_> = results
        .scaling
        .iter()
        .filter(|p| p.experiment == "bezier")
        .collect();
    if !bz.is_empty() {
        let _ = writeln!(s, "## Bezier patches: direct against tessellated\n");
        let _ = writeln!(
            s,
            "The Utah teapot's 32 bicubic patches (`teapot-bezier`) intersected directly \
             (subdivision of the control-point boxes, then Newton iteration on (u, v, t)) against \
             the same patches tessellated into N x N quads (2 N^2 triangles) each, vertices on \
             the exact surface, both in the `{}` backend; 256 x 256 camera rays. Difference \
             from the direct image: mean FLIP, the fraction of pixels whose patch differs (or \
             one hits and the other misses), and the fraction hit in both whose depth differs \
             by more than 1%.\n",
            HEIGHTFIELD_BACKEND
        );
        let _ = writeln!(
            s,
            "| series | N | primitives | render s | mean FLIP | other patch | depth > 1% |"
        );
        let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|");
        for p in bz {
            let n = if p.series == "direct" {
                "-".to_string()
            } else {
                format!("{}", (p.x / 64.0).sqrt().round())
            };
            let d = p.difference;
            let _ = writeln!(
                s,
                "| {} | {n} | {} | {:.4} | {} | {} | {} |",
                p.series,
                p.x,
                p.seconds,
                opt(d.map(|d| d.mean_flip), |v| format!("{v:.4}")),
                opt(d.map(|d| d.patch_mismatch), |v| format!(
                    "{:.3}%",
                    100.0 * v
                )),
                opt(d.map(|d| d.depth_mismatch), |v| format!(
                    "{:.3}%",
                    100.0 * v
                )),
            );
        }
        let _ = writeln!(s);
    }

    if !charts.drawn.is_empty() {
        let _ = writeln!(s, "## Charts\n");
        for (title, svg, png) in &charts.drawn {
            let _ = writeln!(s, "**{title}** ([SVG]({svg}))\n\n![{title}]({png})\n");
        }
    }
    s
}
