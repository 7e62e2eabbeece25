//! How a report states its timings: every timing carries its median, interval, minimum,
//! repetition count and contended count in `results.json`, the Markdown and the HTML; one
//! repetition says its noise is unknown; the verdict names ties or a winner by the
//! intervals.

use crate::common::{assert_clean_error, read, results};
use crate::{markdown, report, tmp_dir};
use serde_json::Value;
use std::path::Path;

/// A report of two backends on a small generated mesh (a performance scene, as every
/// generated one: the verdict judges it), cast only, 16 x 16, with `repeat` repetitions of
/// at least 2 ms each.
fn tiny(dir: &Path, repeat: &str) -> Value {
    #[rustfmt::skip]
    let out = report(dir, &[
        "--scenes", "icosphere:1", "--backends", "naive,bvh", "--modes", "cast",
        "--rays", "primary,incoherent", "--size", "16", "--repeat", repeat,
        "--min-sample", "2", "--no-scaling",
    ]);
    crate::common::assert_success(&out);
    results(dir)
}

#[test]
fn every_timing_carries_its_interval_and_counts() {
    let dir = tmp_dir("intervals");
    let r = tiny(&dir, "6");
    let shard = &r["shards"][0];
    assert_eq!(shard["repeat"], "6");
    assert_eq!(shard["min_sample"], 0.002);
    // The last-level cache's walk, before and after, in the JSON and the machine's line.
    for walk in [&shard["cache"][0], &shard["cache"][1]] {
        let (fastest, median) = (walk["fastest_ns"].as_f64(), walk["median_ns"].as_f64());
        assert!(
            fastest.is_some_and(|f| f > 0.0 && f <= median.unwrap()),
            "{walk}"
        );
        assert!(walk["samples"].as_u64().is_some_and(|n| n > 0), "{walk}");
    }
    assert!(
        markdown(&dir).contains("a random walk through"),
        "no cache walk in REPORT.md"
    );
    let runs = r["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 4);
    for run in runs {
        let t = &run["seconds"];
        let samples = t["samples"].as_array().unwrap();
        assert_eq!(samples.len(), 6, "{run}");
        let (median, min) = (t["median"].as_f64().unwrap(), t["min"].as_f64().unwrap());
        let [lo, hi] = [0, 1].map(|i| t["interval"][i].as_f64().unwrap());
        assert!(min <= lo && lo <= median && median <= hi, "{t}");
        assert!(t["confidence"].as_f64().unwrap() >= 0.95, "{t}");
        // A 16 x 16 frame lasts well under 2 ms: several runs fill a repetition.
        assert!(t["per_sample"].as_u64().unwrap() > 1, "{t}");
        for count in ["redone", "contended"] {
            assert!(t[count].as_u64().is_some(), "{count}: {t}");
        }
        // Camera rays also as a batch, timed the same way; the other sets are batches.
        let trace = &run["trace"];
        if run["ray_set"] == "primary" {
            assert_eq!(
                trace["seconds"]["samples"].as_array().unwrap().len(),
                6,
                "{run}"
            );
            assert!(trace["seconds"]["interval"].is_array(), "{run}");
            assert_eq!(trace["rays"], 256, "{run}");
            assert!(trace["mrays_per_s"].as_f64().unwrap() > 0.0, "{run}");
        } else {
            assert!(trace.is_null(), "{run}");
        }
    }
    // The Markdown: the shard's header states the rule, every row its interval, minimum
    // and repetitions; the verdict names a winner or a tie.
    let md = markdown(&dir);
    assert!(md.contains("repetitions 6, each at least 2 ms"), "{md}");
    assert!(
        md.contains("| render s [interval] | min s | repetitions |"),
        "{md}"
    );
    for run in runs {
        let t = &run["seconds"];
        let backend = run["backend"].as_str().unwrap();
        // The workload tables' rows (repetitions in the sixth column); the batch trace's
        // table has them in the third.
        let rows_with = |column: usize| -> Vec<&str> {
            md.lines()
                .filter(|l| {
                    l.starts_with(&format!("| {backend} | "))
                        && l.split(" | ")
                            .nth(column)
                            .is_some_and(|c| c.starts_with("6 ("))
                })
                .collect()
        };
        let scene_rows = rows_with(5);
        assert_eq!(scene_rows.len(), 2, "{backend}: {md}");
        assert_eq!(rows_with(2).len(), 1, "{backend}'s batch trace: {md}");
        // `median [lo-hi]`, then the minimum, then the repetitions.
        let cells: Vec<&str> = scene_rows[0].split(" | ").collect();
        let (median, interval) = cells[3].split_once(" [").unwrap();
        let (lo, hi) = interval
            .trim_end_matches(['†', ' ', ']'])
            .split_once('-')
            .unwrap();
        let [median, lo, hi, min]: [f64; 4] =
            [median, lo, hi, cells[4]].map(|v| v.trim().parse().unwrap());
        assert!(
            min <= lo && lo <= median && median <= hi,
            "{}",
            scene_rows[0]
        );
        assert!(
            cells[5].starts_with("6 (") && cells[5].contains("runs each"),
            "{}",
            scene_rows[0]
        );
        assert!(t["per_sample"].as_u64() > Some(1));
    }
    let verdict = &md[md.find("## Verdict").unwrap()..md.find("## How to read").unwrap()];
    assert!(
        verdict.contains("tie: ") || verdict.contains("x ["),
        "a winner with the interval of its lead, or a tie: {verdict}"
    );
    // The page: the same rows, and the viewer's figures name the repetitions.
    let html = read(&dir, "REPORT.html");
    assert!(
        html.contains("[interval]") && html.contains("runs each"),
        "{html}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn one_repetition_has_unknown_noise() {
    let dir = tmp_dir("one-repetition");
    let r = tiny(&dir, "1");
    for run in r["runs"].as_array().unwrap() {
        let t = &run["seconds"];
        assert!(t["interval"].is_null() && t["confidence"].is_null(), "{t}");
    }
    let md = markdown(&dir);
    assert!(md.contains("[?] ?"), "a table row of unknown noise: {md}");
    assert!(md.contains("noise unknown"), "{md}");
    assert!(!md.contains("spread by at most"), "{md}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn repetition_options_are_checked() {
    let dir = tmp_dir("bad-repeat");
    for (args, needle) in [
        (&["--repeat", "0"][..], "neither auto nor a count"),
        (&["--repeat", "often"][..], "neither auto nor a count"),
        (&["--min-sample", "20000"][..], "--min-sample"),
    ] {
        let mut all = vec!["--scenes", "spheres", "--no-scaling"];
        all.extend_from_slice(args);
        assert_clean_error(&report(&dir, &all), needle);
    }
}
