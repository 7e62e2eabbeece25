use raybench_registry::progress::*;
use std::time::Duration;

#[test]
fn status_lines() {
    assert_eq!(
        status_line(0, 4, 3.2, "render spheres"),
        "[........................] 0/4  0m03s elapsed  render spheres"
    );
    assert_eq!(
        status_line(1, 4, 30.0, "x"),
        "[######..................] 1/4  0m30s elapsed, ~1m30s left  x"
    );
    assert_eq!(clock(125.4), "2m05s");
    assert_eq!(
        record_line(3, 12, 41.0, "bvh: spheres"),
        "3/12  0m41s  bvh: spheres"
    );
    // An empty plan draws an empty bar, never a division by zero.
    assert!(status_line(0, 0, 0.0, "").starts_with("[........................] 0/0"));
}

#[test]
fn the_live_line_waits_for_the_delay() {
    let elapsed = Duration::from_secs(3);
    assert_eq!(live_line(0, 2, elapsed, None, DELAY), None, "no step runs");
    let step = |d: Duration| Some(("bvh: warm-up", d));
    assert_eq!(
        live_line(0, 2, elapsed, step(DELAY / 2), DELAY),
        None,
        "a short step shows nothing"
    );
    let line = live_line(0, 2, elapsed, step(DELAY), DELAY).expect("a long step shows a line");
    assert_eq!(
        line,
        "[........................] 0/2  0m03s elapsed  bvh: warm-up"
    );
    // Shown at once where there is no delay (`RAYBENCH_PROGRESS=always`).
    assert!(live_line(1, 2, elapsed, step(Duration::ZERO), Duration::ZERO).is_some());
}
