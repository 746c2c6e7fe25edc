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
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use crate::error::{Error, Result};

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

/// An advisory lock on an output target: `.NAME.lock` beside it, held with `flock`
/// while the output is written, deleted on release.
///
/// Deleting a lock file races with a second run that opened it before the deletion and
/// locks it after: that run would hold a lock on an unlinked file. So a run that got
/// the lock checks that the path still names the file it locked, and retries if not.
struct Lock {
    path: PathBuf,
    _file: File,
}

impl Lock {
    fn acquire(target: &Path) -> std::result::Result<Lock, String> {
        let path = sibling(target, "", ".lock");
        for _ in 0..16 {
            let file = match create_registered(&path, Kind::Lock, || {
                OpenOptions::new()
                    .read(true)
                    .write(true)
                    .create(true)
                    .truncate(false)
                    .open(&path)
            }) {
                Ok(f) => f,
                Err(e) => {
                    return Err(format!(
                        "cannot create the lock file {}: {}",
                        path.display(),
                        describe_io(&e)
                    ));
                }
            };
            match file.try_lock() {
                Ok(()) => {}
                Err(fs::TryLockError::WouldBlock) => {
                    unregister(&path);
                    return Err(format!(
                        "another run is writing this file (lock {} is held); wait for it or choose another name",
                        path.display()
                    ));
                }
                Err(fs::TryLockError::Error(e)) => {
                    unregister(&path);
                    return Err(format!(
                        "cannot lock {}: {}",
                        path.display(),
                        describe_io(&e)
                    ));
                }
            }
            let same = match (file.metadata(), fs::metadata(&path)) {
                (Ok(a), Ok(b)) => (a.dev(), a.ino()) == (b.dev(), b.ino()),
                _ => false,
            };
            if same {
                return Ok(Lock { path, _file: file });
            }
        }
        unregister(&path);
        Err(format!("cannot take the lock {}", path.display()))
    }
}

impl Drop for Lock {
    fn drop(&mut self) {
        // deleted while still held, so that no other run locks a file about to vanish
        let _ = fs::remove_file(&self.path);
        unregister(&self.path);
    }
}

/// The temporary name a file is written under before it is renamed to `target`:
/// `.NAME.partial-PID-SEQ` in the same directory (SEQ keeps two writers of one process
/// apart).
fn partial_path(target: &Path) -> PathBuf {
    static SEQ: AtomicU64 = AtomicU64::new(0);
    let seq = SEQ.fetch_add(1, Ordering::Relaxed);
    sibling(
        target,
        "",
        &format!(".partial-{}-{seq}", std::process::id()),
    )
}

/// `.NAME<suffix>` beside `target`.
fn sibling(target: &Path, prefix: &str, suffix: &str) -> PathBuf {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    target.with_file_name(format!(".{prefix}{name}{suffix}"))
}

/// (device, inode, path) of each of `inputs` that exists, links followed.
fn identify<'a>(inputs: impl IntoIterator<Item = &'a Path>) -> Vec<(u64, u64, PathBuf)> {
    inputs
        .into_iter()
        .filter_map(|p| fs::metadata(p).ok().map(|m| (m.dev(), m.ino(), p.into())))
        .collect()
}

/// Follows symbolic links at the end of `path` (not in its directories, which the OS
/// resolves), up to 40 deep like the kernel; a dangling link gives its target.
fn follow_links(path: &Path) -> io::Result<PathBuf> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let t = fs::read_link(&p)?;
                p = if t.is_absolute() {
                    t
                } else {
                    parent_dir(&p).join(t)
                };
            }
            _ => return Ok(p),
        }
    }
    Err(io::Error::other("too many levels of symbolic links"))
}

/// The directory holding `path` (`.` for a bare file name).
pub fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

pub use crate::input_file::describe_file_type;

pub use crate::error::describe_io;

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
        Some(n) => describe_io(&io::Error::from_raw_os_error(n)),
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

/// An intermediate file of a command (e.g. the raw file an SCC export is made from):
/// hidden beside an output, deleted when dropped and if a signal ends the process.
pub struct ScratchFile {
    path: PathBuf,
}

impl ScratchFile {
    /// A scratch path `.NAME.SUFFIX-PID` beside `output` (nothing is created).
    pub fn beside(output: &Path, suffix: &str) -> ScratchFile {
        let name = output
            .file_name()
            .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
        let path = parent_dir(output).join(format!(".{name}.{suffix}-{}", std::process::id()));
        register(&path, Kind::Scratch);
        ScratchFile { path }
    }

    /// Its path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for ScratchFile {
    fn drop(&mut self) {
        let _ = fs::remove_file(&self.path);
        unregister(&self.path);
    }
}

/// What a file of the registry is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// The temporary stand-in of an output not yet committed.
    Temp,
    /// The lock file of an output.
    Lock,
    /// An intermediate file of the command ([`ScratchFile`]).
    Scratch,
}

/// The files this process deletes if a signal ends it (temporary outputs, lock files,
/// scratch files), and whether a commit renamed outputs into place.
///
/// Every creation of a registered file and every commit's renames happen while this
/// state is locked; the signal watcher locks it before it deletes anything and never
/// unlocks it (the process ends). So a signal either comes before a creation or rename
/// (which then never happens) or after it (and sees its result).
struct FileState {
    files: Vec<(PathBuf, Kind)>,
    committed: bool,
}

static FILE_STATE: Mutex<FileState> = Mutex::new(FileState {
    files: Vec::new(),
    committed: false,
});

fn file_state() -> std::sync::MutexGuard<'static, FileState> {
    FILE_STATE.lock().unwrap_or_else(|e| e.into_inner())
}

fn register(path: &Path, kind: Kind) {
    file_state().files.push((path.to_path_buf(), kind));
}

/// Registers `path` and runs `create` (which makes the file) under the registry's lock,
/// so that a signal cannot fall between the two; unregisters it when `create` fails.
fn create_registered<T>(
    path: &Path,
    kind: Kind,
    create: impl FnOnce() -> io::Result<T>,
) -> io::Result<T> {
    let mut state = file_state();
    state.files.push((path.to_path_buf(), kind));
    let made = create();
    if made.is_err() {
        state.files.retain(|(p, _)| p != path);
    }
    made
}

fn unregister(path: &Path) {
    file_state().files.retain(|(p, _)| p != path);
}

fn is_registered(path: &Path) -> bool {
    file_state().files.iter().any(|(p, _)| p == path)
}

/// Set by the signal watcher as it starts ending the process.
static SIGNALLED: AtomicBool = AtomicBool::new(false);

/// Blocks for good when a signal is ending the process: its watcher deletes the
/// temporary files, so an error from one (a reopen that finds it gone) is no error of
/// the run, and a writer about to open one by path must not recreate it.
fn wait_if_signalled() {
    if SIGNALLED.load(Ordering::SeqCst) {
        loop {
            std::thread::park();
        }
    }
}

/// How the process ends: what its outputs are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ending {
    /// Temporary outputs were deleted: every old output is as it was.
    PartialRemoved,
    /// A commit renamed the outputs into place and none is pending: they are complete.
    Complete,
    /// No output was under way.
    NoOutput,
}

/// Deletes every registered file and keeps the registry locked for good (no file is
/// created or renamed after); for a process about to end. `wait`: wait for the
/// registry (a commit's renames), else give up (`None`, nothing deleted) when it is
/// busy. `paths` receives the deleted paths (for a second pass: a writer that opened
/// its file by path, as HDF5 does, may recreate it before the process ends).
fn clean_for_exit(wait: bool, paths: Option<&mut Vec<PathBuf>>) -> Option<Ending> {
    let state = if wait {
        file_state()
    } else {
        match FILE_STATE.try_lock() {
            Ok(s) => s,
            Err(std::sync::TryLockError::Poisoned(e)) => e.into_inner(),
            Err(std::sync::TryLockError::WouldBlock) => return None,
        }
    };
    for (f, _) in &state.files {
        let _ = fs::remove_file(f);
    }
    if let Some(paths) = paths {
        paths.extend(state.files.iter().map(|(p, _)| p.clone()));
    }
    let ending = if state.files.iter().any(|(_, k)| *k == Kind::Temp) {
        Ending::PartialRemoved
    } else if state.committed {
        Ending::Complete
    } else {
        Ending::NoOutput
    };
    std::mem::forget(state);
    Some(ending)
}

/// For a run ending on an allocation failure ([`crate::resources::NoAbortAllocator`]):
/// deletes every temporary, lock and scratch file of the process, unless the registry
/// is busy; `true` when a partial output was among them.
pub fn remove_files_for_exit() -> bool {
    clean_for_exit(false, None) == Some(Ending::PartialRemoved)
}

/// Installs handlers for SIGINT, SIGTERM and SIGHUP: a watcher thread waits for a commit
/// in progress to finish its renames, deletes every registered temporary and lock file,
/// prints one line saying what the outputs are and ends the process at once with status
/// 128 + signal (130, 143, 129), without running exit handlers (HDF5's could block on a
/// file another thread is writing). The line is "interrupted by SIGINT; partial output
/// removed" (every old output intact), "interrupted by SIGINT after its outputs were
/// written; they are complete", or "interrupted by SIGINT" (no output under way).
/// Call once, from `main`.
pub fn install_signal_handlers() -> Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])
        .map_err(|e| Error::Unsupported(format!("cannot install signal handlers: {e}")))?;
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            if let Some(sig) = signals.forever().next() {
                SIGNALLED.store(true, Ordering::SeqCst);
                let mut files = Vec::new();
                let ending = clean_for_exit(true, Some(&mut files)).unwrap_or(Ending::NoOutput);
                let name = match sig {
                    SIGINT => "SIGINT",
                    SIGTERM => "SIGTERM",
                    _ => "SIGHUP",
                };
                let what = match ending {
                    Ending::PartialRemoved => "; partial output removed",
                    Ending::Complete => " after its outputs were written; they are complete",
                    Ending::NoOutput => "",
                };
                eprintln!("\nlidarsim: interrupted by {name}{what}");
                for f in &files {
                    let _ = fs::remove_file(f);
                }
                signal_hook::low_level::exit(128 + sig);
            }
        })
        .map_err(|e| Error::Unsupported(format!("cannot start the signal thread: {e}")))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Dir(PathBuf);
    impl Drop for Dir {
        fn drop(&mut self) {
            let _ = fs::remove_dir_all(&self.0);
        }
    }
    fn scratch(name: &str) -> Dir {
        let d = std::env::temp_dir().join(format!("lidarsim-safe-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        Dir(d)
    }
    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn commit_renames_every_output_and_leaves_nothing_else() {
        let d = scratch("commit");
        let mut outs = Outputs::new([]);
        let a = outs.add("--csv", &d.0.join("a.csv"), Stream::Text).unwrap();
        let b = outs
            .add("--png", &d.0.join("b.png"), Stream::Binary)
            .unwrap();
        outs.write(a, |w| w.write_all(b"x,y\n")).unwrap();
        outs.write(b, |w| w.write_all(b"png")).unwrap();
        outs.commit().unwrap();
        assert_eq!(entries(&d.0), ["a.csv", "b.png"]);
        assert_eq!(fs::read(d.0.join("a.csv")).unwrap(), b"x,y\n");
    }

    #[test]
    fn a_failure_leaves_none_of_the_outputs() {
        let d = scratch("fail");
        fs::write(d.0.join("old.csv"), "old").unwrap();
        {
            let mut outs = Outputs::new([]);
            let a = outs
                .add("--csv", &d.0.join("old.csv"), Stream::Text)
                .unwrap();
            let b = outs
                .add("--png", &d.0.join("b.png"), Stream::Binary)
                .unwrap();
            outs.write(a, |w| w.write_all(b"new")).unwrap();
            let r = outs.write(b, |_| Err(io::Error::other("drawing failed")));
            assert!(r.is_err());
        }
        assert_eq!(entries(&d.0), ["old.csv"]);
        assert_eq!(fs::read_to_string(d.0.join("old.csv")).unwrap(), "old");
    }

    #[test]
    fn special_files_inputs_and_duplicates_are_refused() {
        let d = scratch("refuse");
        let input = d.0.join("cfg.toml");
        fs::write(&input, "x").unwrap();
        let mut outs = Outputs::new([input.as_path()]);
        for (p, why) in [
            (Path::new("/dev/null"), "character device"),
            (d.0.as_path(), "directory"),
            (input.as_path(), "is the input"),
            (Path::new("/no/such/dir/x.h5"), "no such file"),
        ] {
            let e = outs.add("-o", p, Stream::Binary).unwrap_err().to_string();
            assert!(e.contains(why), "{p:?}: {e}");
        }
        let e = outs.add("--png", Path::new("-"), Stream::Binary);
        assert!(e.unwrap_err().to_string().contains("standard output"));
        outs.add("--csv", &d.0.join("x"), Stream::Text).unwrap();
        let e = outs
            .add("--json", &d.0.join("x"), Stream::Text)
            .unwrap_err();
        assert!(e.to_string().contains("also the output of --csv"), "{e}");
        drop(outs);
        assert_eq!(entries(&d.0), ["cfg.toml"]);
        assert!(Path::new("/dev/null").exists());
    }

    #[test]
    fn a_symlink_is_followed_and_stays_a_link() {
        let d = scratch("link");
        let link = d.0.join("link.csv");
        std::os::unix::fs::symlink("real.csv", &link).unwrap();
        let mut outs = Outputs::new([]);
        let a = outs.add("--csv", &link, Stream::Text).unwrap();
        outs.write(a, |w| w.write_all(b"1")).unwrap();
        outs.commit().unwrap();
        assert!(
            fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(fs::read_to_string(d.0.join("real.csv")).unwrap(), "1");
        // a link to an input is the input
        let input = d.0.join("cfg.toml");
        fs::write(&input, "x").unwrap();
        std::os::unix::fs::symlink(&input, d.0.join("cfg-link")).unwrap();
        let mut outs = Outputs::new([input.as_path()]);
        assert!(
            outs.add("-o", &d.0.join("cfg-link"), Stream::Binary)
                .is_err()
        );
    }

    #[test]
    fn an_input_learnt_late_is_protected_through_any_link() {
        let d = scratch("protect");
        let input = d.0.join("profile.txt");
        fs::write(&input, "profile").unwrap();
        fs::hard_link(&input, d.0.join("hard")).unwrap();
        std::os::unix::fs::symlink(&input, d.0.join("soft")).unwrap();
        for name in ["profile.txt", "hard", "soft"] {
            let mut outs = Outputs::new([]);
            outs.add("--json", &d.0.join(name), Stream::Text).unwrap();
            let e = outs.protect([input.as_path()]).unwrap_err().to_string();
            assert!(e.contains("--json") && e.contains("is the input"), "{e}");
        }
        // an unrelated output passes, and a later output onto the input is refused
        let mut outs = Outputs::new([]);
        outs.add("--json", &d.0.join("x.json"), Stream::Text)
            .unwrap();
        outs.protect([input.as_path()]).unwrap();
        assert!(outs.add("--csv", &d.0.join("hard"), Stream::Text).is_err());
        drop(outs);
        assert_eq!(fs::read_to_string(&input).unwrap(), "profile");
        assert_eq!(entries(&d.0), ["hard", "profile.txt", "soft"]);
    }

    #[test]
    fn a_second_writer_of_the_same_path_is_refused_while_the_first_runs() {
        let d = scratch("lock");
        let target = d.0.join("x.h5");
        let mut first = Outputs::new([]);
        first.add("-o", &target, Stream::Binary).unwrap();
        let mut second = Outputs::new([]);
        let e = second.add("-o", &target, Stream::Binary).unwrap_err();
        assert!(e.to_string().contains("another run is writing"), "{e}");
        first.commit().unwrap();
        // released: a third run may write it, and no lock file stays
        let mut third = Outputs::new([]);
        third.add("-o", &target, Stream::Binary).unwrap();
        third.commit().unwrap();
        assert_eq!(entries(&d.0), ["x.h5"]);
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
