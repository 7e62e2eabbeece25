use raybench_core::{Mode, RaySet, RenderSettings};
use raybench_registry::*;

fn names(list: &[&Backend]) -> Vec<&'static str> {
    list.iter().map(|b| b.name).collect()
}

#[test]
fn brute_force_backends_leave_large_default_lists() {
    // `info terrain:708 --rays incoherent --width 64 --height 64`: 4096 rays against a
    // million triangles, minutes of naive.
    let s = RenderSettings {
        width: 64,
        height: 64,
        ..RenderSettings::default()
    };
    let terrain = brute_force_tests(&s, RaySet::Incoherent, 2 * 707 * 707, 1);
    assert!(!names(&chosen_backends(None, terrain).unwrap()).contains(&"naive"));
    // Named, it runs anyway.
    let forced = chosen_backends(Some(&["naive".to_string()]), terrain).unwrap();
    assert_eq!(names(&forced), ["naive"]);
    // A small scene keeps it, and it comes first (the reference).
    let small = brute_force_tests(&s, RaySet::Primary, 100, 4);
    assert_eq!(names(&chosen_backends(None, small).unwrap())[0], "naive");
    // Secondary rays count: path tracing estimates four rays per sample.
    let path = RenderSettings {
        mode: Mode::Path,
        ..s
    };
    assert_eq!(
        brute_force_tests(&path, RaySet::Primary, 10, 1),
        4.0 * brute_force_tests(&s, RaySet::Primary, 10, 1)
    );
}

/// The roles the harness relies on: one oracle, exact and first; one exact baseline;
/// peers and devices outside the contract; the compile-time lists agree with the
/// registry.
#[test]
fn roles_are_consistent() {
    let with = |r: Roles| BACKENDS.iter().filter(|b| b.is(r)).count();
    assert_eq!(with(Roles::ORACLE), 1);
    assert!(BACKENDS[0].is(Roles::ORACLE.with(Roles::EXACT).with(Roles::BRUTE_FORCE)));
    assert_eq!(with(Roles::BASELINE), 1);
    assert!(with_role(Roles::BASELINE).is_some_and(Backend::exact));
    for b in BACKENDS {
        if b.is(Roles::PEER) || b.is(Roles::DEVICE) {
            assert!(!b.exact(), "{}", b.name);
        }
        if b.is(Roles::YARDSTICK) {
            assert!(b.is(Roles::PEER), "{}", b.name);
        }
        assert_eq!(roles_of(b.name), Some(b.roles));
        assert!(backend_is(b.name, b.roles));
    }
    const N: usize = count_with(Roles::EXACT);
    let exact: Vec<&str> = BACKENDS
        .iter()
        .filter(|b| b.exact())
        .map(|b| b.name)
        .collect();
    assert_eq!(names_with::<N>(Roles::EXACT).to_vec(), exact);
    assert_eq!(name_with(Roles::ORACLE), BACKENDS[0].name);
    assert_eq!(name_with(Roles::NONE), BACKENDS[0].name);
    assert!(!backend_is("no such backend", Roles::NONE));
    assert_eq!(
        Roles::EXACT.with(Roles::PINNED).names(),
        ["exact", "pinned"]
    );
}

#[test]
fn backends_missing_from_the_build_name_their_feature() {
    for n in NOT_BUILT {
        assert!(BACKENDS.iter().all(|b| b.name != n.name));
        let e = backend(n.name).unwrap_err();
        assert!(
            e.contains("not compiled in") && e.contains(n.feature),
            "{e}"
        );
    }
    assert_eq!(
        NOT_BUILT.iter().any(|n| n.name == "embree"),
        !cfg!(feature = "embree")
    );
}
