//! Errors of scene construction.

use std::fmt;

/// Why a scene could not be built.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SceneError {
    /// A coordinate or parameter is NaN or infinite.
    NonFinite(String),
    /// A face refers to a vertex that does not exist.
    IndexOutOfRange {
        /// The offending index.
        index: usize,
        /// Number of vertices.
        len: usize,
    },
    /// A value is outside its allowed range.
    Invalid(String),
    /// The scene exceeds a limit of [`crate::limits`].
    TooLarge(String),
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NonFinite(what) => write!(f, "{what} is not finite (NaN or infinite)"),
            Self::IndexOutOfRange { index, len } => write!(
                f,
                "face index {index} is out of range (the mesh has {len} vertices)"
            ),
            Self::Invalid(what) => write!(f, "{what}"),
            Self::TooLarge(what) => write!(f, "{what}"),
        }
    }
}

impl std::error::Error for SceneError {}
