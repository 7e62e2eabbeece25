//! Loading errors.

use raybench_core::SceneError;
use std::path::PathBuf;

/// Why a scene could not be loaded. Every variant names the file or scene and the problem.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file could not be read.
    #[error("{}: {cause}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause (in the message; not a separate `source`, which would print it twice
        /// in a chain of causes).
        cause: std::io::Error,
    },
    /// The file does not exist.
    #[error("{}: file not found", path.display())]
    NotFound {
        /// The file.
        path: PathBuf,
    },
    /// The file is malformed.
    #[error("{}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong, with a position where the parser gives one.
        message: String,
    },
    /// A mesh file that a scene needs is absent.
    #[error(
        "scene '{scene}' needs {}, which does not exist; point --assets or RAYBENCH_ASSETS at \
         the folder holding the shared scenes",
        path.display()
    )]
    MissingAsset {
        /// The scene.
        scene: String,
        /// The file looked for.
        path: PathBuf,
    },
    /// The name is no file, built-in scene or generator.
    #[error(
        "unknown scene '{0}': not a file, a built-in scene or a generator (see `raybench scenes`)"
    )]
    UnknownScene(String),
    /// A generator spec is malformed or out of range.
    #[error("generator '{spec}': {message}")]
    Generator {
        /// The spec.
        spec: String,
        /// What is wrong.
        message: String,
    },
    /// The scene would need more memory than the budget allows (`crate::MemoryBudget`).
    #[error("{context}: {message}")]
    OverBudget {
        /// The scene and the part of it.
        context: String,
        /// The estimate, the budget and how to raise it.
        message: String,
    },
    /// The content is well-formed but invalid (NaN coordinates, bad indices, ...).
    #[error("{context}: {cause}")]
    Scene {
        /// The file or object.
        context: String,
        /// The problem (in the message, not a separate `source`).
        cause: SceneError,
    },
}

impl LoadError {
    /// True when the error is a missing asset (harnesses skip such scenes).
    #[must_use]
    pub fn is_missing_asset(&self) -> bool {
        matches!(self, Self::MissingAsset { .. })
    }

    /// True when the scene would not fit in this machine's memory budget (harnesses skip
    /// such scenes, saying so: the same run fits on a larger machine).
    #[must_use]
    pub fn is_over_budget(&self) -> bool {
        matches!(self, Self::OverBudget { .. })
    }
}
