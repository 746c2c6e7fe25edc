//! The crate's error type: every failure names what it concerns (file, key, reason).

use std::path::PathBuf;

/// Every error lidarsim reports. Displayed as one line for the user.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A configuration value (file or `--set` override) is missing, malformed or out of range.
    /// Shown as `FILE: key `KEY`: REASON`, or `--set KEY=VALUE: REASON` for an override,
    /// or `FILE: REASON` when no key applies (a TOML syntax error).
    #[error("{}", config_message(file, key, reason))]
    Config {
        /// The config file (or `--set` for an override).
        file: String,
        /// Dotted key, e.g. `instrument.pulse_energy_j`.
        key: String,
        /// What is wrong and what is expected.
        reason: String,
    },
    /// Reading or writing a file failed; shown with the OS reason in plain words.
    #[error("{}: {}", path.display(), describe_io(source))]
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
    /// The caller stopped the run (the run options' cancel flag: the Python module's
    /// Ctrl-C); its temporary output was removed.
    #[error("interrupted; partial output removed")]
    Interrupted,
}

fn config_message(file: &str, key: &str, reason: &str) -> String {
    if file.starts_with("--set ") || key.is_empty() {
        format!("{file}: {reason}")
    } else {
        format!("{file}: key `{key}`: {reason}")
    }
}

/// A shape for a message: `3 × 1 × 334`.
pub fn shape_text(shape: &[usize]) -> String {
    let v: Vec<String> = shape.iter().map(usize::to_string).collect();
    if v.is_empty() {
        "a scalar".into()
    } else {
        v.join(" × ")
    }
}

/// A number for a message, in compact form: `1000`, `0.25`, `1e308`, `2.5e-10` (the
/// shortest representation that reads back to the same value).
pub fn compact(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || !x.is_finite() || (1e-4..1e6).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// A short, user-facing description of an I/O error: the OS reason in plain words
/// ("no space left on device"), without the "(os error 28)" tail.
pub fn describe_io(err: &std::io::Error) -> String {
    use std::io::ErrorKind as K;
    match err.kind() {
        K::PermissionDenied => "permission denied".into(),
        K::NotFound => "no such file or directory".into(),
        K::ReadOnlyFilesystem => "read-only file system".into(),
        K::StorageFull => "no space left on device".into(),
        K::QuotaExceeded => "disk quota exceeded".into(),
        K::NotADirectory => "a component of the path is not a directory".into(),
        K::IsADirectory => "is a directory".into(),
        K::FileTooLarge => "file too large".into(),
        K::InvalidData => "not UTF-8 text".into(),
        K::InvalidFilename => "file name too long or invalid".into(),
        _ => {
            let s = err.to_string();
            let s = s.split(" (os error").next().unwrap_or(&s).to_string();
            let mut c = s.chars();
            c.next()
                .map(|f| f.to_lowercase().chain(c).collect())
                .unwrap_or(s)
        }
    }
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

/// The OS reason inside an HDF5 error message, in plain words: HDF5 reports a failed
/// system call as `... errno = 28, error message = 'No space left on device' ...`;
/// any other message is returned as it is.
pub fn describe_hdf5_error(message: &str) -> String {
    let errno = message
        .split("errno = ")
        .nth(1)
        .and_then(|rest| rest.split(|c: char| !c.is_ascii_digit()).next())
        .and_then(|digits| digits.parse::<i32>().ok());
    match errno {
        Some(n) => describe_io(&std::io::Error::from_raw_os_error(n)),
        // no errno: the library's words without its function names and trace details
        None => {
            let core = message
                .split(", time =")
                .next()
                .unwrap_or(message)
                .split(" time = ")
                .next()
                .unwrap_or(message);
            let words: Vec<&str> = core
                .split(": ")
                .filter(|part| !(part.starts_with("H5") && part.ends_with("()")))
                .collect();
            words
                .join(": ")
                .trim_end_matches([':', ',', ' '])
                .to_string()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_in_messages_are_compact() {
        assert_eq!(compact(1e308), "1e308");
        assert_eq!(compact(1000.0), "1000");
        assert_eq!(compact(-1.0), "-1");
        assert_eq!(compact(0.25), "0.25");
        assert_eq!(compact(2.5e-10), "2.5e-10");
        assert_eq!(compact(f64::NAN), "NaN");
    }

    #[test]
    fn io_reasons_are_plain_words() {
        let e = std::io::Error::from_raw_os_error(28);
        assert_eq!(describe_io(&e), "no space left on device");
        let e = std::io::Error::from_raw_os_error(5);
        assert_eq!(describe_io(&e), "input/output error");
        let e = std::io::Error::from_raw_os_error(36);
        assert_eq!(describe_io(&e), "file name too long or invalid");
    }

    #[test]
    fn hdf5_errors_read_as_their_os_reason() {
        let m = "H5Dwrite(): can't write data: file write failed: time = Sun Nov 22, \
                 filename = 'x.h5', file descriptor = 5, errno = 28, error message = \
                 'No space left on device', buf = 0x1, total write size = 4096";
        assert_eq!(describe_hdf5_error(m), "no space left on device");
        assert_eq!(describe_hdf5_error("bad chunk"), "bad chunk");
        // no errno: the library's words, without its function names or trace details
        assert_eq!(
            describe_hdf5_error(
                "H5Dcreate2(): unable to create dataset: H5D__create(): chunk size too large, \
                 time = Sun Nov 22"
            ),
            "unable to create dataset: chunk size too large"
        );
    }
}
