//! Environment maps (`background = { map = ... }`): the first byte chooses OpenEXR or
//! Radiance HDR, the rest is the file. Any input either decodes into a map within the
//! texel limit and the memory budget, with finite non-negative texels that make a valid
//! `Environment`, or is an error.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raybench_core::{Environment, Vec3};
use raybench_scene::fuzzing::{ENVIRONMENT_TEXEL_BYTES, MAX_ENVIRONMENT_TEXELS};
use std::path::Path;

/// The memory budget: large enough for any map a few kilobytes can describe, small enough
/// that a map the budget admits stays under the fuzzer's allocation limits.
const BUDGET: u64 = 256 << 20;

fuzz_target!(|data: &[u8]| {
    let Some((&kind, file)) = data.split_first() else {
        return;
    };
    let path = Path::new(if kind & 1 == 0 {
        "fuzz.exr"
    } else {
        "fuzz.hdr"
    });
    let Ok((w, h, texels, _negative)) =
        raybench_scene::fuzzing::read_environment_map(file, path, BUDGET)
    else {
        return;
    };
    let n = u64::from(w) * u64::from(h);
    assert!(n > 0 && n <= MAX_ENVIRONMENT_TEXELS);
    assert!(n * ENVIRONMENT_TEXEL_BYTES <= BUDGET);
    assert_eq!(texels.len() as u64, n);
    assert!(
        texels
            .iter()
            .all(|t| t.is_finite() && t.min_element() >= 0.0)
    );
    // As the scene uses it (scale 1 cannot overflow).
    let env = Environment::new(w, h, texels, 1.0, 30.0).expect("a decoded map is valid");
    for d in [Vec3::X, Vec3::Y, -Vec3::Y, Vec3::new(0.3, -0.2, -0.9)] {
        let r = env.radiance(d);
        assert!(r.is_finite() && r.min_element() >= 0.0);
        let p = env.pdf(d);
        assert!(p.is_finite() && p >= 0.0);
    }
    for (u0, u1) in [(0.1, 0.7), (0.5, 0.5), (0.99, 0.01)] {
        if let Some((d, r, pdf)) = env.sample(u0, u1) {
            assert!(d.is_finite() && r.is_finite() && pdf.is_finite() && pdf > 0.0);
        }
    }
});
