//! The `.bpt` Bezier patch parser: any text either gives finite patches or is an error.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(patches) = raybench_scene::parse_bpt(text, Path::new("fuzz.bpt")) {
        assert!(!patches.is_empty());
        assert!(patches.len() <= raybench_core::limits::MAX_BEZIER_PATCHES);
        for p in &patches {
            assert!(p.points.iter().all(|q| q.is_finite()));
            // The patch itself must be accepted by the core type.
            let _ = raybench_core::BezierPatch::new(p.points);
        }
    }
});
