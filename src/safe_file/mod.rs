//! The one rule by which every output is written (`-o`, `--csv`, `--png`, `--json`,
//! `--report`): a regular file, complete or absent.
//!
//! A command declares all its outputs up front in one [`Outputs`] set, before any work
//! starts, so that every refusal comes before the run:
//!
//! * an existing target that is not a regular file (directory, device, FIFO, socket) is
//!   refused: `--png /dev/null` never replaces a device node;
//! * a symbolic link is followed (to any depth, dangling or not): the file is written at
//!   its target and the link stays a link;
//! * a target that is the same file as an input or as another output of the same command
//!   is refused: the same device and inode after following links, so neither a symbolic
//!   nor a hard link to an input passes. The inputs are every file the command reads
//!   (config and the files it names, scheme files, partials, raw files and shards:
//!   [`crate::input_file`]), given to [`Outputs::new`] or, when a command learns of them
//!   only after declaring its outputs, to [`Outputs::protect`];
//! * `-` means standard output for text outputs (CSV, JSON); a binary output (HDF5, PNG)
//!   refuses it;
//! * each target is locked (`.NAME.lock` beside it, an advisory `flock`): a second run
//!   writing the same path fails at once instead of racing the first to the rename;
//! * each file is written under a temporary name in its target's directory
//!   (`.NAME.partial-PID-SEQ`) and only [`Outputs::commit`] renames the temporary files
//!   over their targets, after every output was written and synced. A set dropped
//!   without `commit` (an error, a panic) deletes its temporary and lock files, so a
//!   failure leaves none of the command's outputs; text for standard output is spooled
//!   and printed only at commit, after the files are in place;
//! * SIGINT, SIGTERM and SIGHUP (after [`install_signal_handlers`]) delete every
//!   temporary and lock file of the process and end it with one line on stderr and the
//!   conventional status 128 + signal number (130, 143, 129).
//!
//! **The commit under signals.** [`Outputs::commit`] syncs every temporary file, then
//! renames them over their targets in the order they were declared (`simulate`: `-o`;
//! `onboard`: `-o`, `--raw`, `--report`) while it holds the lock of the process's file
//! registry. The signal watcher takes the same lock before it deletes anything and never
//! gives it back (the process ends), and every creation of a temporary or lock file
//! happens under it too. So a signal lands either before the first rename (the
//! temporaries are deleted: every old output stays as it was, "interrupted by SIGINT;
//! partial output removed") or after the last (every new output is complete and in
//! place: "interrupted by SIGINT after its outputs were written; they are complete"),
//! never between two renames; either way the status is 128 + signal and no
//! `.NAME.partial-*` or `.NAME.lock` file stays. A reopen of a temporary file that a
//! signal's cleanup deleted is not reported as an error of the run: the thread waits
//! for the watcher to end the process.
//!
//! Renames are atomic one by one, not as a set, against anything but a signal: if the
//! second of two renames failed (the directory vanished, say), the first output would
//! stay. Every rename happens after all writing and syncing, where nothing but such an
//! outside change (or a crash of the machine, or SIGKILL) can fail.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Seek, Write};
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result, describe_io};
use crate::input_file::describe_file_type;

mod lock;
mod paths;
mod registry;
mod signals;

use lock::Lock;
pub use paths::parent_dir;
use paths::{follow_links, identify, partial_path};
pub use registry::ScratchFile;
use registry::{Kind, create_registered, file_state, is_registered, unregister};
use signals::wait_if_signalled;
pub use signals::{install_signal_handlers, remove_files_for_exit};

/// Whether an output may go to standard output.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stream {
    /// Text (CSV, JSON): `-` means standard output.
    Text,
    /// Binary (HDF5, PNG): always a file.
    Binary,
}

/// Handle of one output of an [`Outputs`] set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OutputId(usize);

/// Where one output goes until commit.
enum Sink {
    /// Standard output, spooled in an anonymous temporary file until commit.
    Stdout { spool: Option<File> },
    /// A file written under a temporary name.
    File(Staged),
}

/// A file output in progress: its target, its temporary stand-in and its lock.
struct Staged {
    /// The path as the user gave it (for messages).
    shown: PathBuf,
    /// The target after following symbolic links.
    target: PathBuf,
    /// The temporary file, renamed over `target` at commit.
    temp: PathBuf,
    /// Held until the set is committed or dropped.
    _lock: Lock,
}

/// One output, with the option that named it (for messages).
struct Output {
    option: String,
    sink: Sink,
}

/// The outputs of one command: declared and checked before the work, written into
/// temporary files, renamed into place together by [`commit`](Outputs::commit).
pub struct Outputs {
    /// (device, inode) of every input file.
    inputs: Vec<(u64, u64, PathBuf)>,
    outputs: Vec<Output>,
}

impl Outputs {
    /// A new set; `inputs` are the files the command reads (config and the files it names,
    /// scheme files, partials, raw files), which no output may overwrite. Inputs that
    /// cannot be inspected are skipped (reading them fails with its own message).
    pub fn new<'a>(inputs: impl IntoIterator<Item = &'a Path>) -> Self {
        Outputs {
            inputs: identify(inputs),
            outputs: Vec::new(),
        }
    }

    /// Adds inputs the command learnt of after declaring its outputs (the files a stored
    /// config names, read while combining partials), refusing one that is the target of
    /// an output already declared: the same device and inode, links followed.
    pub fn protect<'a>(&mut self, inputs: impl IntoIterator<Item = &'a Path>) -> Result<()> {
        for (dev, ino, input) in identify(inputs) {
            for out in &self.outputs {
                if let Sink::File(s) = &out.sink
                    && fs::metadata(&s.target).is_ok_and(|m| (m.dev(), m.ino()) == (dev, ino))
                {
                    return Err(Error::output(
                        format!("{} {}", out.option, s.shown.display()),
                        format!("is the input {}; refusing to overwrite it", input.display()),
                    ));
                }
            }
            self.inputs.push((dev, ino, input));
        }
        Ok(())
    }

    /// Declares the output named by command-line `option` (e.g. `--csv`) at `path`,
    /// checks it against the rules of the module docs, locks it and creates its
    /// temporary file. Errors name the path, the option and the reason.
    pub fn add(&mut self, option: &str, path: &Path, stream: Stream) -> Result<OutputId> {
        let sink = if path == Path::new("-") {
            if stream == Stream::Binary {
                return Err(Error::output(
                    format!("{option} -"),
                    "a binary file cannot go to standard output; give a file name",
                ));
            }
            if self
                .outputs
                .iter()
                .any(|o| matches!(o.sink, Sink::Stdout { .. }))
            {
                return Err(Error::output(
                    format!("{option} -"),
                    "standard output is already taken by another output",
                ));
            }
            let spool = tempfile::tempfile().map_err(|e| {
                Error::output(
                    format!("{option} -"),
                    format!("cannot spool standard output: {e}"),
                )
            })?;
            Sink::Stdout { spool: Some(spool) }
        } else {
            Sink::File(self.stage(option, path)?)
        };
        self.outputs.push(Output {
            option: option.to_string(),
            sink,
        });
        Ok(OutputId(self.outputs.len() - 1))
    }

    /// Resolves, checks, locks and creates the temporary file of a file output.
    fn stage(&self, option: &str, path: &Path) -> Result<Staged> {
        let fail = |reason: String| Error::output(format!("{option} {}", path.display()), reason);
        if path.as_os_str().is_empty() {
            return Err(fail("an empty path is not a file name".into()));
        }
        let target = follow_links(path).map_err(|e| fail(describe_io(&e)))?;
        if target.file_name().is_none() {
            return Err(fail("does not name a file".into()));
        }
        let dir = parent_dir(&target);
        match fs::metadata(dir) {
            Ok(m) if m.is_dir() => {}
            Ok(_) => return Err(fail(format!("{} is not a directory", dir.display()))),
            Err(e) => return Err(fail(format!("{}: {}", dir.display(), describe_io(&e)))),
        }
        if let Ok(meta) = fs::metadata(&target) {
            if !meta.is_file() {
                return Err(fail(format!(
                    "is {}, not a regular file; refusing to replace it",
                    describe_file_type(&meta.file_type())
                )));
            }
            let id = (meta.dev(), meta.ino());
            if let Some((_, _, input)) = self.inputs.iter().find(|i| (i.0, i.1) == id) {
                return Err(fail(format!(
                    "is the input {}; refusing to overwrite it",
                    input.display()
                )));
            }
        }
        if let Some(other) = self.outputs.iter().find_map(|o| match &o.sink {
            Sink::File(s) if s.target == target => Some(o.option.as_str()),
            _ => None,
        }) {
            return Err(fail(format!("is also the output of {other}")));
        }
        let lock = Lock::acquire(&target).map_err(fail)?;
        let temp = partial_path(&target);
        if let Err(e) = create_registered(&temp, Kind::Temp, || {
            OpenOptions::new().write(true).create_new(true).open(&temp)
        }) {
            return Err(fail(format!(
                "cannot create a file in {}: {}",
                dir.display(),
                describe_io(&e)
            )));
        }
        Ok(Staged {
            shown: path.to_path_buf(),
            target,
            temp,
            _lock: lock,
        })
    }

    /// The temporary file of a file output, for writers that open files by path (HDF5).
    /// Errors for an output going to standard output.
    pub fn temp_path(&self, id: OutputId) -> Result<&Path> {
        wait_if_signalled();
        match &self.outputs[id.0].sink {
            Sink::File(s) => Ok(&s.temp),
            Sink::Stdout { .. } => Err(Error::Unsupported(format!(
                "{} cannot write to standard output",
                self.outputs[id.0].option
            ))),
        }
    }

    /// The path of an output as the user gave it (`-` for standard output).
    pub fn shown_path(&self, id: OutputId) -> &Path {
        match &self.outputs[id.0].sink {
            Sink::File(s) => &s.shown,
            Sink::Stdout { .. } => Path::new("-"),
        }
    }

    /// Writes the whole content of an output through `fill` (a buffered writer over its
    /// temporary file or its standard-output spool).
    pub fn write(
        &mut self,
        id: OutputId,
        fill: impl FnOnce(&mut dyn Write) -> io::Result<()>,
    ) -> Result<()> {
        let out = &mut self.outputs[id.0];
        let (file, shown) = match &mut out.sink {
            Sink::File(s) => (
                OpenOptions::new().write(true).truncate(true).open(&s.temp),
                s.shown.clone(),
            ),
            Sink::Stdout { spool } => (
                spool
                    .as_ref()
                    .ok_or_else(|| io::Error::other("spool closed"))
                    .and_then(|f| f.try_clone()),
                PathBuf::from("<stdout>"),
            ),
        };
        let fail = |e: io::Error| {
            wait_if_signalled();
            Error::output(&shown, describe_io(&e))
        };
        let mut w = BufWriter::new(file.map_err(fail)?);
        fill(&mut w).map_err(fail)?;
        w.flush().map_err(fail)
    }

    /// Syncs every temporary file, renames each over its target, makes the renames
    /// durable, then prints the spooled standard output. A closed standard output
    /// (`| head`) is not an error.
    pub fn commit(mut self) -> Result<()> {
        for out in &self.outputs {
            if let Sink::File(s) = &out.sink {
                let fail = |what: &str, e: io::Error| {
                    wait_if_signalled();
                    Error::output(&s.shown, format!("{what}: {}", describe_io(&e)))
                };
                let f = File::open(&s.temp).map_err(|e| fail("cannot reopen", e))?;
                f.sync_all().map_err(|e| fail("cannot sync", e))?;
                if let Ok(old) = fs::metadata(&s.target) {
                    let _ = fs::set_permissions(&s.temp, old.permissions());
                }
            }
        }
        // Every rename under the lock of the file registry: a signal's cleanup waits
        // for the last rename (then reports the outputs complete) or, having come
        // first, ends the process before the first one (the old outputs stay).
        {
            let mut state = file_state();
            for out in &self.outputs {
                if let Sink::File(s) = &out.sink {
                    fs::rename(&s.temp, &s.target).map_err(|e| {
                        Error::output(&s.shown, format!("cannot rename: {}", describe_io(&e)))
                    })?;
                    state.files.retain(|(p, _)| *p != s.temp);
                    state.committed = true;
                }
            }
        }
        for out in &self.outputs {
            if let Sink::File(s) = &out.sink
                && let Ok(dir) = File::open(parent_dir(&s.target))
            {
                let _ = dir.sync_all();
            }
        }
        for out in &mut self.outputs {
            if let Sink::Stdout { spool } = &mut out.sink
                && let Some(mut f) = spool.take()
            {
                copy_to_stdout(&mut f)?;
            }
        }
        Ok(())
    }
}

impl Drop for Outputs {
    /// Deletes the temporary files not yet renamed (an error or a panic before commit).
    fn drop(&mut self) {
        for out in &self.outputs {
            if let Sink::File(s) = &out.sink
                && is_registered(&s.temp)
            {
                let _ = fs::remove_file(&s.temp);
                unregister(&s.temp);
            }
        }
    }
}

/// Copies a spool to standard output; a closed pipe ends the copy quietly.
fn copy_to_stdout(spool: &mut File) -> Result<()> {
    let fail = |e: io::Error| Error::output("<stdout>", describe_io(&e));
    spool.rewind().map_err(fail)?;
    let stdout = io::stdout();
    let mut lock = stdout.lock();
    match io::copy(spool, &mut lock).and_then(|_| lock.flush()) {
        Err(e) if e.kind() != io::ErrorKind::BrokenPipe => Err(fail(e)),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests;
