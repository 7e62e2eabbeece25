//! The peer benchmark (`benches/peers.rs`, [`raybench_tests::peers`]) on a tiny workload, so
//! that it cannot rot unnoticed: every contestant runs or says why not, exact backends answer
//! exactly as `bvh`, peers nearly so, every figure is present and the JSON reads back; and
//! its command line, defaults (the workload of `../shared/PEERS.md`) and ray sets.

use raybench_core::RaySet;
use raybench_tests::peers::contestants::{self, Kind};
use raybench_tests::peers::{self, Command, Options};

fn parse(args: &[&str]) -> Result<Command, String> {
    Options::parse(args.iter().map(|s| (*s).to_string()))
}

fn options(args: &[&str]) -> Options {
    match parse(args) {
        Ok(Command::Run(o)) => o,
        other => panic!("{args:?}: {other:?}"),
    }
}

#[test]
fn defaults_are_the_peers_workload() {
    let o = options(&["--bench"]);
    let meshes: Vec<_> = o
        .meshes
        .iter()
        .map(|(n, s)| (n.as_str(), s.as_str()))
        .collect();
    assert_eq!(
        meshes,
        [
            ("sphere", "icosphere:6"),
            ("soup", "soup:100000"),
            ("terrain", "terrain:708"),
            ("dabrovic-sponza", "dabrovic-sponza"),
            ("bunny", "bunny"),
            ("bunny-field", "flat:bunny-field")
        ]
    );
    assert_eq!(
        (o.primary_size, o.incoherent_rays, o.seed),
        (1024, 1 << 20, 1)
    );
    assert_eq!((o.chunk, o.contestants.as_ref()), (1024, None));
    let q = options(&["--quick", "--repeat", "5", "--meshes", "soup,icosphere:3"]);
    assert_eq!(
        (q.primary_size, q.incoherent_rays, q.repeat),
        (256, 65_536, 5)
    );
    assert_eq!(q.meshes[0], ("soup".into(), "soup:100000".into()));
    assert_eq!(q.meshes[1], ("icosphere:3".into(), "icosphere:3".into()));
    // --size and --rays win over --quick in any order.
    let s = options(&["--size", "64", "--quick", "--rays", "100"]);
    assert_eq!((s.primary_size, s.incoherent_rays), (64, 100));
    assert_eq!(parse(&["--help"]), Ok(Command::Help));
    assert_eq!(parse(&["--list"]), Ok(Command::List));
    assert_eq!(
        parse(&["--cache-probe"]),
        Ok(Command::CacheProbe(std::time::Duration::from_secs(10)))
    );
    assert_eq!(
        parse(&[
            "--diff",
            "a.json,c.json",
            "b.json,d.json",
            "--reference",
            "embree1-robust"
        ]),
        Ok(Command::Diff(
            vec!["a.json".into(), "c.json".into()],
            vec!["b.json".into(), "d.json".into()],
            Some("embree1-robust".into())
        ))
    );
    assert_eq!(o.sets, RaySet::ALL);
    let d = options(&[
        "--sets",
        "ao,primary",
        "--ao-rays",
        "2",
        "--rays-file",
        "x.rays",
    ]);
    assert_eq!(d.sets, [RaySet::Ao, RaySet::Primary]);
    assert_eq!(d.ao_rays, 2);
    assert_eq!(d.rays_file.as_deref(), Some(std::path::Path::new("x.rays")));
    assert_eq!(options(&["--threads", "1"]).thread_counts(), [1]);
    assert_eq!(options(&["--threads", "3"]).thread_counts(), [1, 3]);
}

#[test]
fn bad_options_are_refused_with_a_reason() {
    for (args, expected) in [
        (
            &["--repeat", "0"][..],
            "--repeat: '0' is not a positive integer",
        ),
        (&["--chunk", "x"], "--chunk: 'x' is not a positive integer"),
        (&["--size"], "--size needs a value"),
        (&["--size", "20000"], "--size: 20000 is above 16384"),
        (&["--meshes", ","], "--meshes: empty list"),
        (&["--sets", ","], "--sets: empty list"),
        (&["--sets", "primary,up"], "--sets: unknown ray set 'up'"),
        (&["--ao-rays", "5000"], "--ao-rays: 5000 is above 1024"),
        (&["--diff", "a.json"], "--diff needs a value"),
        (
            &["--diff", "a.json,c.json", "b.json"],
            "--diff: 2 runs before and 1 after; give as many of each, paired in order",
        ),
        (
            &["--reference", "bvh"],
            "--reference is an option of --diff",
        ),
        (
            &["--frobnicate"],
            "unknown option '--frobnicate' (see --help)",
        ),
    ] {
        assert_eq!(parse(args), Err(expected.to_string()), "{args:?}");
    }
    let e = parse(&["--contestants", "bvh,nope"]).unwrap_err();
    assert!(
        e.starts_with("--contestants: unknown contestant 'nope' (known: bvh,"),
        "{e}"
    );
}

#[test]
fn contestants_are_the_exact_registry_backends_then_the_peers() {
    let all = contestants::all();
    let mut raybench: Vec<_> = all
        .iter()
        .filter(|c| c.kind == Kind::Raybench)
        .map(|c| c.name)
        .collect();
    // Every exact backend but the oracle, the brute force one (compared as sets).
    let mut exact = raybench_tests::ACCELERATED_BACKENDS.to_vec();
    raybench.sort_unstable();
    exact.sort_unstable();
    assert_eq!(raybench, exact);
    let peers: Vec<_> = all
        .iter()
        .filter(|c| c.kind == Kind::Peer)
        .map(|c| c.name)
        .collect();
    assert!(
        peers.starts_with(&["bvh-crate", "obvhs-bvh2", "obvhs-cwbvh"]),
        "{peers:?}"
    );
    let embree = if cfg!(feature = "embree") { 4 } else { 0 };
    let tinybvh = if cfg!(feature = "tinybvh") { 2 } else { 0 };
    assert_eq!(peers.len(), 3 + embree + tinybvh);
    let picked = contestants::select(&["obvhs-bvh2".into(), "bvh".into()]).unwrap();
    let names: Vec<_> = picked.iter().map(|c| c.name).collect();
    assert_eq!(names, ["bvh", "obvhs-bvh2"]);
}

#[test]
fn ray_sets_are_deterministic_and_shadow_rays_end_at_half_the_hit() {
    let o = options(&["--size", "16", "--rays", "500"]);
    let scene = raybench_scene::load("icosphere:2", &raybench_scene::assets_dir(None)).unwrap();
    let set = |s| peers::ray_set(&scene, s, &o, &[]).unwrap();
    let primary = set(RaySet::Primary);
    let incoherent = set(RaySet::Incoherent);
    assert_eq!((primary.len(), incoherent.len()), (256, 500));
    assert_eq!(primary, set(RaySet::Primary));
    assert_eq!(incoherent, set(RaySet::Incoherent));
    let hit = raybench_core::Hit {
        t: 3.0,
        prim: 0,
        sub: 0,
        u: 0.0,
        v: 0.0,
        normal: raybench_core::Vec3::Z,
    };
    let shadow = peers::shadow_rays(&primary[..2], &[Some(hit), None]);
    assert_eq!(shadow[0].t_max, 1.5);
    assert_eq!(shadow[0].origin, primary[0].origin);
    assert_eq!(shadow[1], primary[1]);
}

#[test]
fn tiny_run_measures_every_contestant_and_writes_json() {
    let mut o = options(&[
        "--size",
        "24",
        "--rays",
        "2000",
        "--repeat",
        "2",
        "--chunk",
        "100",
        "--threads",
        "2",
        "--meshes",
        "icosphere:2,soup:300",
    ]);
    let dir = std::env::temp_dir().join(format!("raybench-peer-bench-{}", std::process::id()));
    o.json = dir.join("out").join("peers.json");
    let mut calls = 0;
    let report = peers::run(&o, |partial| {
        calls += 1;
        assert_eq!(partial.meshes.len(), calls);
        Ok(())
    })
    .unwrap();
    assert_eq!(calls, 2);
    assert_eq!(report.meshes.len(), 2);
    // The last-level cache's walk, before and after, in the header and the tables.
    let [Some(before), Some(after)] = report.cache else {
        panic!("no cache walk: {:?}", report.cache)
    };
    assert!(
        before.samples > 0 && after.fastest_ns > 0.0,
        "{before:?} {after:?}"
    );
    assert!(
        report
            .header()
            .contains("Last-level cache before the run: a random walk")
    );
    assert!(
        report
            .tables()
            .contains("Last-level cache after the run: a random walk")
    );
    let all = contestants::all();
    for m in &report.meshes {
        let ran: Vec<_> = m.contestants.iter().map(|c| c.name.as_str()).collect();
        for c in &all {
            let skipped = m.skipped.iter().find(|s| s.name == c.name);
            assert!(
                ran.contains(&c.name) != skipped.is_some(),
                "{} on {}: ran or skipped, once",
                c.name,
                m.name
            );
            if let Some(s) = skipped {
                assert!(!s.reason.is_empty());
                assert_ne!(c.kind, Kind::Peer, "{}: {}", c.name, s.reason);
            }
        }
        let names: Vec<_> = m.ray_sets.iter().map(|s| s.name).collect();
        assert_eq!(names, ["primary", "incoherent", "shadow", "ao", "diffuse"]);
        assert_eq!((m.ray_sets[0].rays, m.ray_sets[1].rays), (576, 2000));
        // The derived sets: one diffuse ray per primary hit, four ambient-occlusion rays, and
        // one shadow ray (the generators' directional light) per hit that faces the light
        // (the others are blocked by their own surface, not traced).
        let primary_hits = m.ray_sets[0].hits;
        let derived: Vec<_> = m.ray_sets[2..].iter().map(|s| s.rays).collect();
        assert_eq!(derived[1..], [4 * primary_hits, primary_hits]);
        assert!(
            derived[0] > 0 && derived[0] <= primary_hits,
            "{}: {} shadow rays from {primary_hits} hits",
            m.name,
            derived[0]
        );
        assert!(m.ray_sets[..2].iter().all(|s| s.hits > 0), "{}", m.name);
        // Embree runs wherever the feature is on (CI installs it).
        let embree = ran.contains(&"embree1-default") && ran.contains(&"embree1-robust");
        assert_eq!(embree, cfg!(feature = "embree"));
        for c in &m.contestants {
            for s in &c.ray_sets {
                let n = m.ray_sets.iter().find(|i| i.name == s.name).unwrap().rays;
                for q in [&s.closest, &s.any] {
                    let threads: Vec<_> = q.runs.iter().map(|r| r.threads).collect();
                    assert_eq!(threads, [1, 2]);
                    assert!(q.runs.iter().all(|r| r.mrays.is_finite() && r.mrays > 0.0));
                    // Two kept rounds each, the median between the best and the slowest.
                    for r in &q.runs {
                        assert_eq!(r.samples_s.len(), 2, "{}", c.name);
                        let slowest = r.samples_s.iter().copied().fold(0.0, f64::max);
                        assert!(r.best_s <= r.median_s && r.median_s <= slowest);
                    }
                    match c.kind {
                        Kind::Raybench => {
                            assert_eq!(q.differ, 0, "{} {} {}", c.name, m.name, s.name);
                            assert!(q.node_visits_per_ray.is_some());
                            assert!(q.prim_tests_per_ray.is_some());
                        }
                        // Peers differ on edge rays only.
                        Kind::Peer => assert!(q.differ * 100 <= n, "{} {}", c.name, q.differ),
                    }
                    // One ratio per Embree reference and thread count, each with the
                    // interval of two paired rounds.
                    assert_eq!(q.ratios.is_empty(), !embree, "{}", c.name);
                    assert_eq!(q.ratios.len() % 2, 0);
                    for r in &q.ratios {
                        let [lo, hi] = r.interval.unwrap();
                        assert!(lo <= r.value && r.value <= hi, "{r:?}");
                        assert_eq!(r.confidence, Some(0.5));
                    }
                }
            }
            assert_eq!(c.build_vs_embree.is_some(), embree);
            // The interleaved rounds' builds, paired with Embree's for the build ratio's
            // interval; the build traced with is not among them, yet among the best.
            assert_eq!(c.build_rounds_s.len() + 1, c.builds, "{}", c.name);
            assert!(c.build_rounds_s.iter().all(|&b| b >= c.build_s));
            // The machine's memory events during the builds are read wherever the system
            // tells them.
            assert_eq!(
                c.build_memory.is_some(),
                raybench_registry::interference::MemoryEvents::now().is_some(),
                "{}",
                c.name
            );
            assert_eq!(c.build_ratio.is_some(), embree, "{}", c.name);
            if let Some(r) = &c.build_ratio {
                let [lo, hi] = r.interval.unwrap();
                assert!(lo <= r.value && r.value <= hi, "{r:?}");
            }
        }
        // Builds in interleaved rounds: every contestant as many, and tiny meshes (builds
        // of microseconds) more than `--repeat` asks for, at most 20 rounds and the one
        // traced with.
        let builds: Vec<_> = m.contestants.iter().map(|c| c.builds).collect();
        assert!(
            builds.iter().all(|&b| b == builds[0]),
            "{}: {builds:?}",
            m.name
        );
        assert!((2..=21).contains(&builds[0]), "{}: {builds:?}", m.name);
        // Every contestant that ran was timed in some group, in table order.
        let grouped: Vec<_> = m.groups.concat();
        assert_eq!(grouped, ran, "{}", m.name);
    }
    let tables = report.tables();
    for c in &report.meshes[0].contestants {
        assert!(tables.contains(&format!("| {} |", c.name)), "{}", c.name);
    }
    // The goals' tables, against every Embree variant (with the builds) and against its
    // robust mode: a row per mesh in each, a ratio or `-` per ray set and query, where
    // Embree ran.
    let summary = report.summary();
    assert_eq!(summary.is_empty(), !cfg!(feature = "embree"), "{summary}");
    for m in &report.meshes {
        let rows: Vec<_> = summary
            .lines()
            .filter(|l| l.starts_with(&format!("| {} |", m.name)))
            .map(|l| l.matches(" / ").count())
            .collect();
        if cfg!(feature = "embree") {
            let sets = m.ray_sets.len();
            assert_eq!(rows, [sets + 1, sets], "{summary}");
        }
    }
    peers::write_json(&report, &o.json).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&o.json).unwrap()).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(json["schema"], "raybench-peers/2");
    assert_eq!(json["workload"]["threads"], serde_json::json!([1, 2]));
    let first = &json["meshes"][0]["contestants"][0];
    assert_eq!(first["name"], "bvh");
    assert_eq!(first["kind"], "raybench");
    assert!(first["builds"].as_u64().unwrap() >= 2);
    assert_eq!(first["ray_sets"][1]["name"], "incoherent");
    let run = &first["ray_sets"][0]["any"]["runs"][1];
    assert!(run["mrays"].as_f64().unwrap() > 0.0);
    assert_eq!(run["samples_s"].as_array().unwrap().len(), 2);
    assert!(run["redone"].is_u64() && run["contended"].is_u64());
    assert!(tables.contains("2 rounds per figure"), "{tables}");
    assert!(json["machine"]["cpu"].is_string());
    assert!(
        json["cache"][1]["median_ns"]
            .as_f64()
            .is_some_and(|ns| ns > 0.0)
    );
    // A run set beside itself: every figure of every contestant (the build and, per ray
    // set, query and thread count), each unchanged.
    let figures = peers::diff::diff(&json, &json, None).unwrap();
    let expected: usize = json["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            let contestants = m["contestants"].as_array().unwrap().len();
            contestants * (1 + m["ray_sets"].as_array().unwrap().len() * 2 * 2)
        })
        .sum();
    assert_eq!(figures.len(), expected);
    assert!(figures.iter().all(|f| f.change == 1.0), "{figures:?}");
    if cfg!(feature = "embree") {
        let packet = figures
            .iter()
            .find(|f| f.contestant == "packet" && f.what == "incoherent any, 2 threads")
            .unwrap();
        assert!(
            packet
                .reference
                .as_deref()
                .is_some_and(|r| r.starts_with("embree"))
        );
    }
}

/// `--rays-file` replaces the ray sets with a file's rays: one set named `file`, its any
/// hits on the file's own rays when its flag says so.
#[test]
fn a_ray_file_replays_in_place_of_the_sets() {
    let dir = std::env::temp_dir().join(format!("raybench-peer-file-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("primary.rays");
    let mut o = options(&["--size", "8", "--repeat", "1", "--threads", "1"]);
    let scene = raybench_scene::load("icosphere:2", &raybench_scene::assets_dir(None)).unwrap();
    let rays = peers::ray_set(&scene, RaySet::Primary, &o, &[]).unwrap();
    raybench_registry::rays_file::write(&path, &rays, true).unwrap();
    o.rays_file = Some(path);
    o.meshes = vec![("ico".into(), "icosphere:2".into())];
    o.contestants = Some(vec!["bvh".into()]);
    o.json = dir.join("peers.json");
    let report = peers::run(&o, |_| Ok(())).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let m = &report.meshes[0];
    let sets: Vec<_> = m.ray_sets.iter().map(|s| (s.name, s.rays)).collect();
    assert_eq!(sets, [("file", 64)]);
    let bvh = &m.contestants[0];
    assert_eq!(
        (bvh.ray_sets[0].closest.differ, bvh.ray_sets[0].any.differ),
        (0, 0)
    );
}

/// `flat:SCENE` traces an instanced scene flattened (every contestant, the peers too, sees
/// plain triangles), a mesh whose files are missing is skipped with its reason while the
/// others run, and a ray set that holds no ray (shadow rays without lights) is skipped with
/// its reason instead of printed as 0 Mrays/s.
#[test]
fn flattened_meshes_run_and_missing_meshes_and_empty_sets_are_skipped() {
    let dir = std::env::temp_dir().join(format!("raybench-peer-flat-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let missing = dir.join("missing.toml");
    std::fs::write(
        &missing,
        "[[object]]\nkind = \"mesh\"\npath = \"nowhere.obj\"\n",
    )
    .unwrap();
    let mut o = options(&[
        "--size",
        "16",
        "--rays",
        "500",
        "--repeat",
        "1",
        "--threads",
        "1",
        "--sets",
        "primary,incoherent",
    ]);
    let spec = missing.display().to_string();
    o.meshes = vec![
        ("gone".into(), spec),
        ("grid".into(), "flat:instance-grid".into()),
    ];
    o.contestants = Some(vec!["bvh".into(), "packet".into()]);
    o.json = dir.join("peers.json");
    // A scene without lights: its shadow set holds no ray and is skipped, saying why.
    let dark = dir.join("dark.toml");
    std::fs::write(
        &dark,
        "[[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1.0\n",
    )
    .unwrap();
    let mut d = o.clone();
    d.sets = vec![RaySet::Primary, RaySet::Shadow];
    d.meshes = vec![("dark".into(), dark.display().to_string())];
    d.contestants = Some(vec!["bvh".into()]);
    let dark_report = peers::run(&d, |_| Ok(())).unwrap();
    let report = peers::run(&o, |_| Ok(())).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let m = &dark_report.meshes[0];
    let sets: Vec<_> = m.ray_sets.iter().map(|s| s.name).collect();
    assert_eq!(sets, ["primary"]);
    assert_eq!(m.skipped_sets.len(), 1);
    assert_eq!(m.skipped_sets[0].name, "shadow");
    assert!(
        m.skipped_sets[0].reason.contains("no light"),
        "{}",
        m.skipped_sets[0].reason
    );
    assert!(
        dark_report
            .tables()
            .contains("skipped ray set shadow: no shadow rays")
    );
    assert_eq!(report.skipped_meshes.len(), 1);
    assert_eq!(report.skipped_meshes[0].name, "gone");
    assert!(
        report.skipped_meshes[0].reason.contains("nowhere.obj"),
        "{}",
        report.skipped_meshes[0].reason
    );
    assert!(report.tables().contains("Skipped meshes:\n- gone: "));
    let m = &report.meshes[0];
    let instanced =
        raybench_scene::load("instance-grid", &raybench_scene::assets_dir(None)).unwrap();
    assert!(instanced.geometry.has_instances());
    assert_eq!(m.triangles, instanced.geometry.total_len());
    assert!(m.skipped.is_empty(), "{:?}", m.skipped);
    for c in &m.contestants {
        for s in &c.ray_sets {
            assert_eq!(s.closest.differ, 0, "{} {}", c.name, s.name);
        }
    }
}
