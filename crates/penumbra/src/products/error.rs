//! The error of writing a batch's files.

use std::path::PathBuf;

use crate::image_error::ImageError;

/// A file of a batch that could not be made or written; the message names the file asked
/// for, never the temporary file it was staged under.
#[derive(Debug, thiserror::Error)]
pub enum ProductError {
    /// Staging, renaming or encoding a file failed (an [`ImageError::Write`] names it).
    #[error(transparent)]
    Image(#[from] ImageError),
    /// Any other file-system failure on `path`.
    #[error("{}: {message}", path.display())]
    Io {
        /// The file asked for.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// No memory for the values of a pass.
    #[error("not enough memory for the {0} pass")]
    Memory(&'static str),
    /// Values that cannot be written in the file's format (an array of another type, a
    /// file too large for a ZIP without ZIP64).
    #[error("{}: {message}", path.display())]
    Invalid {
        /// The file asked for.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

impl ProductError {
    /// An [`Io`](ProductError::Io) error on `path`.
    pub(crate) fn io(path: &std::path::Path, message: impl std::fmt::Display) -> ProductError {
        ProductError::Io {
            path: path.to_owned(),
            message: message.to_string(),
        }
    }
}
