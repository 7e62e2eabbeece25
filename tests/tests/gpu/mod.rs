//! The GPU backends (`wgpu` over the BVH2, `wgpu-cwbvh` over the compressed wide BVH:
//! `raybench_tests::DEVICES`) against the CPU (the BVH, bit-identical to the naive oracle)
//! on every built-in scene, within the tolerances of `raybench_tests::gpu`, closest hits and
//! any hits. Runs on whatever adapter
//! wgpu finds: Mesa's lavapipe (software Vulkan, about one CPU thread's speed) in CI, so
//! images stay small. Skips when there is no adapter, except under `CI=true`.
//!
//! A module of the integration tests: here the built-in scenes and the generators, and what
//! the submodules share; the submodules by subject: `backend` (what the backend accepts without an adapter,
//! and the empty scene), `rays` (degenerate rays, split dispatches, the two trees' hits),
//! `shading` (textures, normals, emitters, the environment map, the volume modes),
//! `sampling` (the same frame twice, BSDF-only light sampling, the derived ray sets),
//! `heightfield`, `bezier`, `csg` and `sdf` (each kind's kernel on scenes of its own).

use raybench_core::{Hit, Ray, Renderer, Scene};
use raybench_tests::gpu::check;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The path of scene file `name` in `tests/scenes/`.
fn scene_file(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    path.to_str().unwrap().to_owned()
}

/// A test per scene file of `tests/scenes/`: [`check`] at 32 x 32, every mode (defined before
/// the modules that use it).
macro_rules! scene_file_tests {
    ($($(#[$doc:meta])* $test:ident => $file:literal,)*) => {
        $(
            $(#[$doc])*
            #[test]
            fn $test() {
                check(&scene_file($file), 32, true);
            }
        )*
    };
}

mod backend;
mod bezier;
mod csg;
mod heightfield;
mod rays;
mod sampling;
mod sdf;
mod shading;

/// Built-in scenes that [`builtin_scene`] leaves to another test, and why.
const ELSEWHERE: &[(&str, &str)] = &[(
    "phantom",
    "volumes without surfaces: phantom_volume_modes compares its modes (mip, composite)",
)];

/// Built-in scenes checked in ray casting only (the secondary modes are for the scenes
/// that are not `heavy`), and why.
const CAST_ONLY: &[(&str, &str)] = &[(
    "bunny-lowres",
    "3,674 triangles: its secondary modes on lavapipe cost minutes for \
     what the smaller triangle scenes already check",
)];

/// Ray casting at 64 x 64 (the equivalence test's size) on every built-in scene, a test each
/// (`builtin_scene_tests!`, which fails when a scene file has no test); the modes with
/// secondary rays at 32 x 32 on the scenes that are not `heavy` (their `[benchmark]` table
/// says so) nor in [`CAST_ONLY`]. The heavy scenes of millions of instanced triangles are
/// checked too: the CPU's answers come from the BVH, not the oracle. Left out: the scenes of
/// [`ELSEWHERE`].
fn builtin_scene(name: &str) {
    if let Some((_, why)) = ELSEWHERE.iter().find(|(n, _)| *n == name) {
        eprintln!("{name}: left out: {why}");
        return;
    }
    let b = raybench_scene::builtin(name).expect("a built-in scene");
    let modes = !b.benchmark.heavy && !CAST_ONLY.iter().any(|(n, _)| *n == name);
    check(name, if modes { 32 } else { 64 }, modes);
}

builtin_scene_tests!(super::builtin_scene);

/// The scenes [`ELSEWHERE`] and [`CAST_ONLY`] name are built-in scenes.
#[test]
fn the_scenes_left_out_exist() {
    for (name, why) in ELSEWHERE.iter().chain(CAST_ONLY) {
        assert!(
            raybench_scene::builtin(name).is_some(),
            "{name} is no built-in scene ({why})"
        );
    }
}

/// The generator specs, as the equivalence tests check them: ray casting at 64 x 64, the
/// modes with secondary rays at 32 x 32 on the small ones.
macro_rules! gpu_tests {
    ($($test:ident => $scene:literal, $modes:literal,)*) => {
        $(
            #[test]
            fn $test() {
                check($scene, if $modes { 32 } else { 64 }, $modes);
            }
        )*
    };
}

gpu_tests! {
    random_spheres => "spheres:2000", true,
    terrain => "terrain:32", true,
    soup => "soup:10000", false,
    icosphere => "icosphere:4", false,
    heightfield_generator => "heightfield:64", true,
}

/// The scratch folder `raybench-gpu-TOPIC-PID` for the scene files of the tests of `topic`,
/// created.
fn scratch(topic: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("raybench-gpu-{topic}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes `toml` to `dir/NAME.toml` and returns its path, for [`check`].
fn scene_toml(dir: &Path, name: &str, toml: &str) -> String {
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, toml).unwrap();
    path.to_str().unwrap().to_owned()
}

/// The closest hits of `rays` on `scene` by backend `name`.
fn closest_hits(name: &str, scene: &Arc<Scene>, rays: &[Ray]) -> Vec<Option<Hit>> {
    let (hits, _) = raybench_tests::prepared(name, scene)
        .trace_rays(rays, false)
        .unwrap();
    hits
}

/// Asserts that `gpu`'s any-hit answers for `rays` are those of the closest hits
/// `reference`: blocked exactly where a hit exists.
fn assert_same_blocked(what: &str, gpu: &dyn Renderer, rays: &[Ray], reference: &[Option<Hit>]) {
    let (blocked, _) = gpu.occlude_rays(rays, false).unwrap();
    let expected: Vec<bool> = reference.iter().map(Option::is_some).collect();
    assert_eq!(blocked, expected, "{what}: any-hit rays");
}
