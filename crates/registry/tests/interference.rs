use raybench_registry::interference::*;

#[test]
fn shares_and_the_threshold() {
    let quiet = Interference {
        cpu_seconds: 1.0,
        wait_seconds: 0.01,
    };
    let hogged = Interference {
        cpu_seconds: 1.0,
        wait_seconds: 0.5,
    };
    // A millisecond's repetition whose threads waited 0.3 ms to wake: a large share,
    // but no other process's time slice.
    let woken = Interference {
        cpu_seconds: 0.001,
        wait_seconds: 0.0003,
    };
    assert!(!quiet.contended() && hogged.contended() && !woken.contended());
    assert!((hogged.wait_share() - 1.0 / 3.0).abs() < 1e-12);
    assert_eq!(Interference::default().wait_share(), 0.0);
}

#[test]
fn a_busy_call_is_seen_by_the_scheduler() {
    // Tens of milliseconds of work the optimiser cannot fold (a fixed count, not a clock):
    // several scheduler ticks.
    let busy = || {
        let mut a = 0u64;
        for i in 0..50_000_000u64 {
            a = std::hint::black_box(a.wrapping_mul(31) ^ i);
        }
        a
    };
    let (_, i) = during(busy);
    if std::path::Path::new("/proc/self/task").is_dir() {
        let i = i.expect("schedstat on Linux");
        assert!(i.cpu_seconds > 0.0 && i.wait_seconds >= 0.0, "{i:?}");
    }
    let load = load_average();
    assert!(load.is_none_or(|l| l.iter().all(|x| *x >= 0.0)));
    if let Some(before) = MachineUse::now() {
        busy();
        let after = MachineUse::now().expect("readable twice");
        assert!(after.own >= before.own && after.total >= before.total);
        assert!(before.steal <= before.busy && before.busy <= before.total);
        if let Some(o) = after.others_since(&before) {
            assert!(
                (0.0..=1.0).contains(&o.share) && o.steal <= o.share + 1e-12,
                "{o:?}"
            );
        }
    }
}

/// Other processes' share is the busy ticks not this process's, over every CPU's ticks.
#[test]
fn others_share_from_the_counters() {
    let at = |busy, steal, total, own| MachineUse {
        busy,
        steal,
        total,
        own,
    };
    let before = at(1_000, 10, 4_000, 300);
    // 200 ticks pass on two CPUs: 150 busy, 100 of them ours, 20 stolen.
    let after = at(1_150, 30, 4_200, 400);
    let o = after.others_since(&before).expect("ticks passed");
    assert!((o.share - 50.0 / 200.0).abs() < 1e-12, "{o:?}");
    assert!((o.steal - 20.0 / 200.0).abs() < 1e-12, "{o:?}");
    // No tick between the readings: nothing to say.
    assert_eq!(before.others_since(&before), None);
    // Our ticks beyond the machine's busy ones (counters read at different moments) are
    // not a negative share.
    assert_eq!(
        at(1_050, 10, 4_100, 500)
            .others_since(&before)
            .unwrap()
            .share,
        0.0
    );
}
