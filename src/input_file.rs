//! The one rule by which every input file is opened (config, molecular profile, curtain,
//! scheme, partial JSON, raw file, shard): it must be a regular file, checked from its
//! metadata (after following links) *before* it is opened.
//!
//! Opening a FIFO for reading blocks until a writer comes, and reading a character device
//! (`/dev/zero`, a terminal) may never end; a directory or a socket cannot be read at
//! all. So every reader calls [`check`] (or reads through [`read`], [`read_to_string`])
//! and such an input is refused at once with one line naming the option or config key,
//! the path and what it is: `--scheme D/fifo: is a FIFO, not a regular file`.
//!
//! Which files a command reads, so that no output replaces one, is the other half of
//! the rule: `LoadedConfig::files_read` (`src/loaded.rs`) for a config and the files it
//! names, and the inputs each command passes to `Outputs` (`src/safe_file/`):
//! both read through this module, which names neither.

use std::fs;
use std::os::unix::fs::FileTypeExt;
use std::path::Path;

use crate::error::{Error, Result, describe_io};

/// "a directory", "a character device", ... for messages.
pub fn describe_file_type(t: &fs::FileType) -> &'static str {
    if t.is_dir() {
        "a directory"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

/// The error of input `what` (an option such as `--scheme`, or a config key) at `path`.
fn refuse(what: &str, path: &Path, reason: impl std::fmt::Display) -> Error {
    let shown = if what.is_empty() {
        path.display().to_string()
    } else {
        format!("{what} {}", path.display())
    };
    Error::output(shown, reason)
}

/// Refuses input `what` at `path` unless it is an existing regular file (links followed),
/// without opening it: a missing or unreadable path gives the OS reason, a directory,
/// device, FIFO or socket its kind. `what` names the option or config key in the message
/// (`--scheme`, `scene.curtain`; empty for none).
pub fn check(what: &str, path: &Path) -> Result<()> {
    let meta = fs::metadata(path).map_err(|e| refuse(what, path, describe_io(&e)))?;
    if meta.is_file() {
        Ok(())
    } else {
        Err(refuse(
            what,
            path,
            format!(
                "is {}, not a regular file",
                describe_file_type(&meta.file_type())
            ),
        ))
    }
}

/// The bytes of input `what` at `path`, after [`check`].
pub fn read(what: &str, path: &Path) -> Result<Vec<u8>> {
    check(what, path)?;
    fs::read(path).map_err(|e| refuse(what, path, describe_io(&e)))
}

/// The text of input `what` at `path`, after [`check`]; `not UTF-8 text` otherwise.
pub fn read_to_string(what: &str, path: &Path) -> Result<String> {
    String::from_utf8(read(what, path)?).map_err(|_| refuse(what, path, "is not UTF-8 text"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_files_are_refused_without_opening_them() {
        let d = std::env::temp_dir().join(format!("lidarsim-input-file-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        let fifo = d.join("fifo");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success());
        assert!(made, "mkfifo is needed for this test");
        // a FIFO opened for reading would block this test forever: check must not open it
        let e = read_to_string("--scheme", &fifo).unwrap_err().to_string();
        assert_eq!(
            e,
            format!("--scheme {}: is a FIFO, not a regular file", fifo.display())
        );
        let e = check("scene.curtain", &d).unwrap_err().to_string();
        assert!(e.ends_with("is a directory, not a regular file"), "{e}");
        let e = check("", Path::new("/dev/null")).unwrap_err().to_string();
        assert_eq!(e, "/dev/null: is a character device, not a regular file");
        let e = check("CONFIG", &d.join("none")).unwrap_err().to_string();
        assert!(e.ends_with("none: no such file or directory"), "{e}");
        // a link to a regular file is that file
        fs::write(d.join("a.txt"), "text").unwrap();
        std::os::unix::fs::symlink(d.join("a.txt"), d.join("link")).unwrap();
        assert_eq!(read_to_string("x", &d.join("link")).unwrap(), "text");
        fs::write(d.join("bin"), [0xff, 0xfe]).unwrap();
        let e = read_to_string("x", &d.join("bin")).unwrap_err().to_string();
        assert!(e.ends_with("is not UTF-8 text"), "{e}");
        let _ = fs::remove_dir_all(&d);
    }
}
