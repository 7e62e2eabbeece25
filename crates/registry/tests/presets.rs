use raybench_core::{RenderSettings, Scene};
use raybench_registry::Roles;
use raybench_registry::presets::*;
use std::sync::Arc;

fn scene(spec: &str) -> Arc<Scene> {
    raybench_scene::load(spec, std::path::Path::new("."))
        .unwrap()
        .into()
}

/// Names are `BACKEND:PRESET` of a registered backend, unique, and each backend has
/// exactly one default preset.
#[test]
fn presets_are_well_formed() {
    let mut names: Vec<&str> = PRESETS.iter().map(|p| p.entry.name).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), PRESETS.len());
    for p in PRESETS {
        assert_eq!(p.entry.name, format!("{}:{}", p.backend, p.preset));
        let base = raybench_registry::backend(p.backend).unwrap();
        assert!(p.entry.is(Roles::PINNED), "{}", p.entry.name);
        assert_eq!(p.entry.exact(), base.exact(), "{}", p.entry.name);
        assert_eq!(
            presets_of(p.backend).filter(|q| q.default).count(),
            1,
            "{}",
            p.backend
        );
        assert_eq!(
            raybench_registry::backend(p.entry.name).unwrap().name,
            p.entry.name,
            "resolves"
        );
    }
}

/// Unknown presets and backends without presets get one line naming the known ones.
#[test]
fn bad_presets_list_the_known_ones() {
    let e = raybench_registry::backend("bvh:nope").unwrap_err();
    assert_eq!(
        e,
        "unknown preset 'nope' of backend 'bvh' (known: fast, medium, quality, presplit, \
         ploc_fastest_build, ploc_very_fast_build, ploc_fast_build, ploc_medium_build, \
         ploc_slow_build, ploc_very_slow_build)"
    );
    let e = raybench_registry::backend("naive:fast").unwrap_err();
    assert!(
        e.starts_with("backend 'naive' has no build presets (backends with presets: bvh, obvhs"),
        "{e}"
    );
    let e = raybench_registry::backend("nothing:fast").unwrap_err();
    assert!(e.starts_with("unknown backend 'nothing'"), "{e}");
    assert!(preset_backend("bvh").is_none());
}

/// The default preset builds the backend's default structure: the same statistics
/// (nodes, leaves, bytes) on a mesh.
#[test]
fn default_presets_build_the_default_structure() {
    let scene = scene("soup:2000");
    for p in PRESETS.iter().filter(|p| p.default) {
        let base = raybench_registry::backend(p.backend).unwrap();
        let mut a = (base.make)();
        let mut b = (p.entry.make)();
        if a.availability().is_err() {
            continue;
        }
        a.prepare(&scene).unwrap();
        b.prepare(&scene).unwrap();
        let (sa, sb) = (a.structure().unwrap(), b.structure().unwrap());
        assert_eq!(sa.memory_bytes, sb.memory_bytes, "{}", p.entry.name);
        assert_eq!(sa.counts, sb.counts, "{}", p.entry.name);
    }
}

/// Every preset of an exact backend renders the oracle's ids and `t`, bit for bit, and
/// the presets of one backend build different structures.
#[test]
fn exact_presets_match_the_oracle() {
    let scene = scene("soup:3000");
    let settings = RenderSettings {
        width: 48,
        height: 48,
        ..RenderSettings::default()
    };
    let mut oracle = (raybench_registry::BACKENDS[0].make)();
    oracle.prepare(&scene).unwrap();
    let reference = oracle.render(&settings).unwrap();
    for p in PRESETS.iter().filter(|p| p.entry.exact()) {
        let mut r = (p.entry.make)();
        r.prepare(&scene).unwrap();
        let f = r.render(&settings).unwrap();
        assert!(
            raybench_registry::compare_frames(&reference, &f).is_exact(),
            "{}",
            p.entry.name
        );
    }
    let bytes = |name: &str| {
        let mut r = (raybench_registry::backend(name).unwrap().make)();
        r.prepare(&scene).unwrap();
        r.structure().unwrap().memory_bytes
    };
    assert_ne!(bytes("bvh:fast"), bytes("bvh:quality"));
    assert_ne!(bytes("grid:coarse"), bytes("grid:fine"));
}
