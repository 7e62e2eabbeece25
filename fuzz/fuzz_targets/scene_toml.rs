//! The TOML scene parser: any text either loads into a valid scene or is an error.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    // No folder and an assets folder that does not exist: files named by the scene are
    // missing assets (absolute paths to real files are still read, within the limits).
    if let Ok(scene) =
        raybench_scene::load_scene_str(text, "fuzz", None, Path::new("/nonexistent-assets"))
    {
        assert!(scene.geometry.len() <= raybench_core::limits::MAX_PRIMITIVES);
    }
});
