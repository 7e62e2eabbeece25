//! Texture images (a material's `map_Kd` or glTF texture: PNG or JPEG, the format guessed
//! from the bytes). The first byte chooses the wrap modes, the rest is the file. Any input
//! either decodes into a texture within the size limit and the memory budget, with finite
//! texels in [0, 1], or is a reason the texture cannot be used, or is over the budget.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raybench_core::{MAX_TEXTURE_SIZE, Vec2, Wrap};
use raybench_scene::fuzzing::TEXTURE_TEXEL_BYTES;

/// The memory budget: large enough for any texture a few kilobytes can describe, small
/// enough that a texture the budget admits stays under the fuzzer's allocation limits.
const BUDGET: u64 = 256 << 20;

fuzz_target!(|data: &[u8]| {
    let Some((&kind, file)) = data.split_first() else {
        return;
    };
    let modes = [Wrap::Repeat, Wrap::ClampToEdge, Wrap::MirroredRepeat];
    let wrap = [
        modes[usize::from(kind % 3)],
        modes[usize::from(kind / 3 % 3)],
    ];
    let Ok(Ok(t)) = raybench_scene::fuzzing::decode_texture(file, wrap, BUDGET) else {
        return;
    };
    let (w, h) = (t.width(), t.height());
    assert!((1..=MAX_TEXTURE_SIZE).contains(&w) && (1..=MAX_TEXTURE_SIZE).contains(&h));
    let n = u64::from(w) * u64::from(h);
    assert!(n * TEXTURE_TEXEL_BYTES <= BUDGET);
    assert_eq!(t.bytes() as u64, n * 12);
    let unit = |v: raybench_core::Vec3, slack: f32| {
        v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.0 + slack
    };
    for (i, j) in [(0, 0), (i64::from(w) - 1, i64::from(h) - 1), (-1, 7)] {
        assert!(unit(t.texel(i, j), 0.0));
    }
    // Bilinear weights may round a blend of ones a little above 1.
    for uv in [
        Vec2::new(0.5, 0.5),
        Vec2::new(-3.2, 1.7),
        Vec2::new(1e9, -1e9),
    ] {
        assert!(unit(t.sample(uv), 1e-5));
    }
});
