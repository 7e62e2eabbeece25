//! Loading errors.

use raybench_core::SceneError;
use std::path::PathBuf;

/// Why a scene could not be loaded. Every variant names the file or scene and the problem.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file could not be read.
    #[error("{}: {}", path.display(), crate::io::os_error(cause))]
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
    /// A file that a scene names (a mesh, an environment map, a patch, height or volume
    /// file) is in none of the places looked in.
    #[error(
        "{context}: {key} '{name}' names no readable file: {}{}",
        looked_in(looked),
        if *assets {
            "; point --assets or RAYBENCH_ASSETS at the folder holding the shared scenes"
        } else {
            ""
        }
    )]
    MissingAsset {
        /// The scene file (or built-in scene), the line and the table that name the file.
        context: String,
        /// The key that names it (`path`, `map`, `raw`, ...).
        key: String,
        /// The name as written in the scene.
        name: String,
        /// Each place looked in, with what was found there (`missing`, `a folder`, ...).
        looked: Vec<(PathBuf, String)>,
        /// Whether the assets folder was among the places (the message then says how to
        /// point at another).
        assets: bool,
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
    /// A file that a scene names could not be loaded: the scene file, line and table that
    /// name it, then the file's own error.
    #[error("{context}: {error}")]
    Within {
        /// The scene file (or built-in scene), the line and the table.
        context: String,
        /// The named file's error (in the message, not a separate `source`).
        error: Box<LoadError>,
    },
}

/// The places of [`LoadError::MissingAsset`], each with what was found there.
fn looked_in(looked: &[(PathBuf, String)]) -> String {
    let places: Vec<String> = looked
        .iter()
        .map(|(path, found)| format!("{} ({found})", path.display()))
        .collect();
    format!("looked at {}", places.join(" and "))
}

impl LoadError {
    /// True when the error is a missing asset (harnesses skip such scenes).
    #[must_use]
    pub fn is_missing_asset(&self) -> bool {
        match self {
            Self::MissingAsset { .. } => true,
            Self::Within { error, .. } => error.is_missing_asset(),
            _ => false,
        }
    }

    /// True when the scene would not fit in this machine's memory budget (harnesses skip
    /// such scenes, saying so: the same run fits on a larger machine).
    #[must_use]
    pub fn is_over_budget(&self) -> bool {
        match self {
            Self::OverBudget { .. } => true,
            Self::Within { error, .. } => error.is_over_budget(),
            _ => false,
        }
    }

    /// This error of a file that a scene names, prefixed with `context` (the scene file,
    /// line and table). Errors that already name the scene's place (a missing file, the
    /// memory budget's refusal) pass unchanged.
    #[must_use]
    pub(crate) fn within(self, context: &str) -> Self {
        match self {
            Self::MissingAsset { .. } | Self::OverBudget { .. } | Self::Within { .. } => self,
            error => Self::Within {
                context: context.to_owned(),
                error: Box::new(error),
            },
        }
    }
}
