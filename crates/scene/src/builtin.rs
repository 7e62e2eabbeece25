//! The built-in scenes, embedded from `bench-scenes/` so they work from any directory.
//!
//! There is no hand list: `build.rs` finds every `bench-scenes/NAME.toml` and reads its
//! `[benchmark]` table (listing order, benchmark matrix, report modes, scaling experiments),
//! so a new built-in scene is one file. The table is validated when the crate is built; the
//! TOML loader ignores it.

/// Which matrix of `raybench report` runs a built-in scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Matrix {
    /// The quick matrix (`--quick`) and the full one.
    Quick,
    /// The full matrix only.
    Full,
    /// Neither (a scene for the command line and the tests only).
    None,
}

/// What a built-in scene is for in the report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Purpose {
    /// A scene large enough that its time is the acceleration structure's (the shared
    /// meshes, the large instanced scenes): the report's verdict names winners on it.
    Performance,
    /// A small scene that checks a mode, a primitive kind or a feature (a handful of
    /// spheres, CSG trees, one height field): timed, but the verdict names no winner on it,
    /// since its time is the fixed costs of a frame, not a structure's.
    Coverage,
}

/// A built-in scene's report and test metadata: its `[benchmark]` table
/// (`docs/scene-format.md`).
#[derive(Clone, Copy, Debug)]
pub struct Benchmark {
    /// Its place in listings (`raybench scenes`, the report's matrices): ascending.
    pub order: i64,
    /// The matrix that runs it.
    pub matrix: Matrix,
    /// Whether the report's verdict judges speed on it.
    pub purpose: Purpose,
    /// The report's render modes beyond ray casting (`whitted`, `path`); the volume modes
    /// follow from the scene's volumes.
    pub modes: &'static [&'static str],
    /// The scaling experiments that use this scene (`pixels`, `spp`, `bezier`).
    pub experiments: &'static [&'static str],
    /// Too many primitives for the brute-force oracle's secondary rays: the equivalence
    /// tests check Whitted and path tracing on every other built-in scene.
    pub heavy: bool,
}

impl Benchmark {
    /// Whether the matrix `quick` (`--quick`) or the full one includes the scene.
    #[must_use]
    pub fn in_matrix(&self, quick: bool) -> bool {
        match self.matrix {
            Matrix::Quick => true,
            Matrix::Full => !quick,
            Matrix::None => false,
        }
    }
}

/// A built-in scene.
#[derive(Clone, Copy, Debug)]
pub struct BuiltinScene {
    /// Its name (the file's name, which is also the scene's `name`).
    pub name: &'static str,
    /// One line of description.
    pub description: &'static str,
    /// The files it needs from the assets directory (empty: self-contained): its objects'
    /// mesh and patch files.
    pub assets: &'static [&'static str],
    /// Its TOML source.
    pub source: &'static str,
    /// Its `[benchmark]` table.
    pub benchmark: Benchmark,
}

/// Every built-in scene, in the order `raybench scenes` lists them (their `order`).
pub const BUILTIN_SCENES: &[BuiltinScene] =
    include!(concat!(env!("OUT_DIR"), "/builtin_scenes.rs"));

/// The built-in scene called `name`.
#[must_use]
pub fn builtin(name: &str) -> Option<&'static BuiltinScene> {
    BUILTIN_SCENES.iter().find(|b| b.name == name)
}

/// The built-in scenes of a report matrix (`quick`, or the full one), in listing order.
pub fn matrix(quick: bool) -> impl Iterator<Item = &'static BuiltinScene> {
    BUILTIN_SCENES
        .iter()
        .filter(move |b| b.benchmark.in_matrix(quick))
}

/// The built-in scene that scaling experiment `experiment` uses, if one names it.
#[must_use]
pub fn for_experiment(experiment: &str) -> Option<&'static BuiltinScene> {
    BUILTIN_SCENES
        .iter()
        .find(|b| b.benchmark.experiments.contains(&experiment))
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_core::Mode;

    /// The metadata the build script cannot check: mode names, one scene per experiment,
    /// and that every scene loads (the meshes aside).
    #[test]
    fn every_builtin_scene_has_valid_metadata() {
        assert!(BUILTIN_SCENES.len() >= 15);
        for b in BUILTIN_SCENES {
            for m in b.benchmark.modes {
                assert!(
                    Mode::ALL.iter().any(|mode| mode.name() == *m)
                        && !matches!(*m, "cast" | "mip" | "composite"),
                    "bench-scenes/{}.toml: [benchmark] modes: `{m}` is not one of whitted, path",
                    b.name
                );
            }
            for e in b.benchmark.experiments {
                let users: Vec<_> = BUILTIN_SCENES
                    .iter()
                    .filter(|o| o.benchmark.experiments.contains(e))
                    .map(|o| o.name)
                    .collect();
                assert_eq!(users.len(), 1, "experiment {e} is claimed by {users:?}");
            }
            match crate::load(b.name, std::path::Path::new("/nonexistent")) {
                Ok(_) => assert!(b.assets.is_empty(), "{} loaded without its assets", b.name),
                Err(e) => assert!(
                    e.is_missing_asset() && !b.assets.is_empty(),
                    "{}: {e}",
                    b.name
                ),
            }
        }
        // The quick matrix is part of the full one, in the same order.
        let full: Vec<_> = matrix(false).map(|b| b.name).collect();
        let quick: Vec<_> = matrix(true).map(|b| b.name).collect();
        assert!(!quick.is_empty() && quick.len() < full.len());
        assert!(quick.iter().all(|q| full.contains(q)));
        assert!(
            BUILTIN_SCENES
                .windows(2)
                .all(|w| w[0].benchmark.order < w[1].benchmark.order)
        );
    }
}
