//! The crate's error type: every failure names what it concerns (file, key, reason).

use std::path::PathBuf;

/// Every error lidarsim reports. Displayed as one line for the user.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A configuration value (file or `--set` override) is missing, malformed or out of range.
    #[error("{file}: key `{key}`: {reason}")]
    Config {
        /// The config file (or `--set` for an override).
        file: String,
        /// Dotted key, e.g. `instrument.pulse_energy_j`.
        key: String,
        /// What is wrong and what is expected.
        reason: String,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The underlying I/O error.
        source: std::io::Error,
    },
    /// Writing an output file (CSV, PNG, HDF5) failed.
    #[error("{}: {reason}", path.display())]
    Output {
        /// The file concerned.
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },
    /// A request that the model cannot honour for this scene (e.g. `--method aggregate`
    /// on a scene whose expectations vary per shot).
    #[error("{0}")]
    Unsupported(String),
}

/// Shorthand for results carrying [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// A configuration error for `key` in `file`.
    pub fn config(
        file: impl Into<String>,
        key: impl Into<String>,
        reason: impl Into<String>,
    ) -> Self {
        Error::Config {
            file: file.into(),
            key: key.into(),
            reason: reason.into(),
        }
    }

    /// An output error for `path`.
    pub fn output(path: impl Into<PathBuf>, reason: impl std::fmt::Display) -> Self {
        Error::Output {
            path: path.into(),
            reason: reason.to_string(),
        }
    }
}
