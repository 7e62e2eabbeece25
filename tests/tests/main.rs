//! raybench's integration tests: one test binary, a module per subject (the files beside
//! this one, and `gpu/`). One binary links wgpu, naga, image, gltf and every backend once,
//! not once per subject, and its tests share one GPU device and its pipeline caches.
//!
//! Run one subject or one test with a filter on the module path:
//! `cargo test -p raybench-tests --test integration equivalence::` or
//! `... --test integration gpu::rays::`. The tree's own checks are the `tidy` binary
//! (`tidy/main.rs`), which links none of the backends.

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
