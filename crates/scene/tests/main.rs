//! The scene crate's integration tests: one test binary, a module per subject (the files
//! beside this one), so the loaders, image and glTF are linked once. Run one subject with a
//! filter on the module path: `cargo test -p raybench-scene --test scene ply::`.

// The PLY writer that `ply` and `loaders_proptest` share.
#[path = "support/ply_writer.rs"]
mod ply_writer;

mod cameras;
mod declared_limits;
mod fuzz_regressions;
mod loaders_proptest;
mod ply;
mod referenced_files;
