//! The registry's tests: one test binary, a module per subject (the files beside this one),
//! against the public API only. The library's own test harness is off (`test = false` in
//! Cargo.toml): it would compile every backend's renderers a second time, with `cfg(test)`,
//! for tests that need none of the crate's private items. Run one subject with a filter on
//! the module path: `cargo test -p raybench-registry --test registry progress::`.

mod frames;
mod interference;
mod measure;
mod presets;
mod progress;
mod rays_file;
mod registry;
mod timed;
