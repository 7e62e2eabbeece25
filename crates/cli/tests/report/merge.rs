//! Sharding by scene and merging back: every shard's runs and images in the merged report,
//! a shard given twice refused, shards of different CPU models refused unless told, and bad
//! `report` and `merge` options refused cleanly.

use crate::common::{assert_clean_error, assert_success, merge, raybench, results};
use crate::{markdown, small_report, tmp_dir};
use std::path::Path;

#[test]
fn shards_split_by_scene_and_merge_back() {
    let (a, b, m) = (tmp_dir("shard1"), tmp_dir("shard2"), tmp_dir("merged"));
    for (dir, shard) in [(&a, "1/2"), (&b, "2/2")] {
        small_report(dir, &["--shard", shard]);
    }
    let scenes = |dir: &Path| -> Vec<String> {
        let mut s: Vec<String> = results(dir)["runs"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r["scene"].as_str().unwrap().to_string())
            .collect();
        s.dedup();
        s
    };
    assert_eq!(scenes(&a), ["spheres"]);
    assert_eq!(scenes(&b), ["cornell-box"]);
    assert_success(&merge(&[&a, &b], &m));
    let r = results(&m);
    assert_eq!(r["shards"].as_array().unwrap().len(), 2);
    assert_eq!(r["shards"][1]["index"], 2);
    let runs = r["runs"].as_array().unwrap();
    assert_eq!(runs.len(), (6 + 7) * 3);
    assert!(
        runs.iter()
            .any(|r| r["scene"] == "cornell-box" && r["shard"] == 1)
    );
    for run in runs {
        if let Some(img) = run["images"]["color"].as_str() {
            assert!(m.join(img).is_file(), "{img} not copied");
        }
    }
    assert!(markdown(&m).contains("Shard 2/2"));
    // A shard given twice, as the same folder or inside a merged report, is refused: it
    // would double its rows.
    let again = tmp_dir("merged-again");
    for pair in [[&a, &a], [&m, &b]] {
        assert_clean_error(&merge(&[pair[0], pair[1]], &again), "same shard");
        assert!(!again.join("results.json").exists());
    }
    // A copy of a shard (another run of the same part) measures the same runs.
    let rerun = tmp_dir("shard1-rerun");
    small_report(&rerun, &["--shard", "1/2"]);
    assert_clean_error(&merge(&[&a, &rerun], &again), "both measure spheres");
    // The merged report is not written over one of its inputs.
    assert_clean_error(&merge(&[&a, &b], &a), "is the merged folder");
    assert!(a.join("results.json").is_file());
    for d in [a, b, m, again, rerun] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// A set of shards that is not one whole plan is refused with the reason (a shard missing,
/// another shard count, other settings), and a missing shard is listed under Skipped when
/// a partial merge is asked for; a shard that would hold nothing is refused up front.
#[test]
fn merge_checks_the_shards_form_one_plan() {
    let dirs: Vec<_> = ["one", "two-of-three", "other-settings", "merged", "partial"]
        .into_iter()
        .map(|n| tmp_dir(&format!("plan-{n}")))
        .collect();
    let [one, two_of_three, other, merged, partial] = [0, 1, 2, 3, 4].map(|i| &dirs[i]);
    small_report(one, &["--shard", "1/2"]);
    assert_clean_error(
        &merge(&[one], merged),
        "shards missing from the merge: 2/2 (matrix cornell-box)",
    );
    small_report(two_of_three, &["--shard", "2/3"]);
    assert_clean_error(
        &merge(&[one, two_of_three], merged),
        "the shard counts differ (1/2 against 2/3)",
    );
    small_report(other, &["--shard", "2/2", "--ao-rays", "3"]);
    assert_clean_error(
        &merge(&[one, other], merged),
        "the settings differ (ao-rays=4 against ao-rays=3)",
    );
    assert!(!merged.join("results.json").exists());
    // Asked for, a partial merge lists the missing shard and what it holds.
    let d = |p: &Path| p.to_str().unwrap().to_string();
    let o = raybench(&["merge", &d(one), "--out", &d(partial), "--allow-partial"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = results(partial);
    let skipped = r["skipped"].as_array().unwrap();
    assert!(
        skipped.iter().any(|k| k["kind"] == "shard"
            && k["name"] == "2/2"
            && k["status"] == "missing"
            && k["reason"].as_str().unwrap().contains("matrix cornell-box")),
        "{skipped:?}"
    );
    assert!(markdown(partial).contains("shard `2/2` (missing)"));
    // Two scenes and the empty scene's fixed cost make three units: a fourth shard would
    // hold none.
    let out = raybench(&[
        "report",
        "--scenes",
        "spheres,cornell-box",
        "--no-scaling",
        "--shard",
        "4/4",
        "--out",
        &d(merged),
    ]);
    assert_clean_error(&out, "shard 4 holds none; split it into at most 3 shards");
    for d in &dirs {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// Shards that ran on different CPU models are refused, naming both folders and models,
/// unless `--allow-mixed-machines` is given; then the merge proceeds and the report says
/// its timings compare only within a shard. Each shard records its host name.
#[test]
fn merge_refuses_mixed_cpu_models_unless_told() {
    let (a, b, m) = (
        tmp_dir("mixed1"),
        tmp_dir("mixed2"),
        tmp_dir("mixed-merged"),
    );
    for (dir, shard) in [(&a, "1/2"), (&b, "2/2")] {
        small_report(dir, &["--shard", shard]);
    }
    let host = &results(&a)["shards"][0]["machine"]["host"];
    assert!(host.as_str().is_some_and(|h| !h.is_empty()), "{host}");
    let ours = results(&a)["shards"][0]["machine"]["cpu"]
        .as_str()
        .unwrap()
        .to_string();
    let mut edited = results(&b);
    edited["shards"][0]["machine"]["cpu"] = "Imaginary CPU 9000".into();
    std::fs::write(
        b.join("results.json"),
        serde_json::to_string(&edited).unwrap(),
    )
    .unwrap();
    assert_clean_error(
        &merge(&[&a, &b], &m),
        &format!(
            "{} ({ours}) and {} (Imaginary CPU 9000) ran on different CPU models",
            a.display(),
            b.display()
        ),
    );
    assert!(!m.join("results.json").exists());
    let d = |p: &Path| p.to_str().unwrap().to_string();
    let o = raybench(&[
        "merge",
        &d(&a),
        &d(&b),
        "--out",
        &d(&m),
        "--allow-mixed-machines",
    ]);
    assert_success(&o);
    let text = markdown(&m);
    assert!(text.contains("**Mixed machines**"), "{text}");
    assert!(text.contains("`Imaginary CPU 9000`"));
    assert_eq!(results(&m)["shards"].as_array().unwrap().len(), 2);
    for d in [a, b, m] {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn bad_report_options_are_refused_cleanly() {
    let dir = tmp_dir("bad");
    let d = dir.to_str().unwrap();
    for args in [
        vec!["report", "--shard", "3/2", "--out", d],
        vec!["report", "--shard", "0/2", "--out", d],
        vec!["report", "--shard", "x", "--out", d],
        vec!["report", "--backends", "nope", "--out", d],
        vec![
            "report",
            "--scenes",
            "no-such-scene",
            "--no-scaling",
            "--out",
            d,
        ],
        vec!["report", "--size", "5", "--out", d],
        vec!["report", "--modes", "raster", "--out", d],
        vec!["report", "--rays", "sideways", "--out", d],
        vec!["report", "--ao-rays", "0", "--out", d],
        // Checked whether the experiments run or not.
        vec![
            "report",
            "--no-scaling",
            "--experiments",
            "bogus",
            "--scenes",
            "spheres",
            "--out",
            d,
        ],
        vec!["merge", "/nonexistent-raybench-dir", "--out", d],
    ] {
        let out = raybench(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert_ne!(out.status.code(), Some(101), "{args:?} panicked: {stderr}");
        assert!(stderr.contains("error"), "{args:?}: {stderr}");
    }
    // A results file of another schema is refused.
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("results.json"), r#"{"schema": "other/9"}"#).unwrap();
    let out = raybench(&["merge", d, "--out", &format!("{d}-out")]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("schema"));
    let _ = std::fs::remove_dir_all(&dir);
}
