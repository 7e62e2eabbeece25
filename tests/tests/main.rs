//! raybench's integration tests: one test binary, a module per subject (the files beside
//! this one, and `gpu/`). One binary links wgpu, naga, image, gltf and every backend once,
//! not once per subject, and its tests share one GPU device and its pipeline caches.
//!
//! Run one subject or one test with a filter on the module path:
//! `cargo test -p raybench-tests --test integration equivalence::` or
//! `... --test integration gpu::rays::`. The tree's own checks are the `tidy` binary
//! (`tidy/main.rs`), which links none of the backends.

/// A test per built-in scene, each calling `$check(name)`, in a module `builtin` of the
/// module that invokes it (so the harness spreads the scenes over its threads, and a filter
/// such as `equivalence::builtin::dabrovic_sponza` runs one); and
/// `builtin::every_builtin_scene_has_a_test`, which compares the list with
/// `raybench_scene::BUILTIN_SCENES` (found from `bench-scenes/`), so a new scene file fails
/// until it is listed here. `$check` is a path as seen from the invoking module.
macro_rules! builtin_scene_tests {
    ($check:path) => {
        builtin_scene_tests!(@list $check;
            bunny_field => "bunny-field",
            bunny_lowres => "bunny-lowres",
            bunny => "bunny",
            cornell_box => "cornell-box",
            csg => "csg",
            heightfield => "heightfield",
            instance_grid => "instance-grid",
            instances => "instances",
            moving => "moving",
            phantom => "phantom",
            quadrics => "quadrics",
            sdf => "sdf",
            spheres => "spheres",
            dabrovic_sponza => "dabrovic-sponza",
            suzanne => "suzanne",
            teapot_bezier => "teapot-bezier",
            teapot_stadium => "teapot-stadium",
            teapot => "teapot",
            whitted => "whitted",
        );
    };
    (@list $check:path; $($test:ident => $scene:literal,)*) => {
        /// One test per built-in scene (`builtin_scene_tests!` in `tests/main.rs`).
        mod builtin {
            $(
                #[test]
                fn $test() {
                    $check($scene);
                }
            )*

            /// Every built-in scene has its test above, and every test a scene.
            #[test]
            fn every_builtin_scene_has_a_test() {
                let mut tested = vec![$($scene),*];
                let mut builtin: Vec<&str> =
                    raybench_scene::BUILTIN_SCENES.iter().map(|b| b.name).collect();
                tested.sort_unstable();
                builtin.sort_unstable();
                assert_eq!(
                    tested, builtin,
                    "builtin_scene_tests! in tests/main.rs against bench-scenes/"
                );
            }
        }
    };
}

// Equivalence with the naive oracle, and hostile rays.
mod adversarial;
mod determinism;
mod edge_cases;
mod equivalence;
mod grid_cases;
mod meshes;
mod properties;
mod watertight;

// Known answers.
mod furnace;
mod integrators;
mod lights;
mod volumes;

// Primitives, scene kinds and scene features.
mod bezier;
mod csg;
mod heightfield;
mod instances;
mod motion;
mod quadrics;
mod sdf;
mod textures;

// Structures, the GPU and the peer benchmark.
mod gpu;
mod peer_bench;
mod quality;
