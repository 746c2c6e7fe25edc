//! Running `lidarsim` in a scratch directory, as the shard tests do: reproducible bytes
//! (`SOURCE_DATE_EPOCH`), no array-job variables, one-line refusals.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// SOURCE_DATE_EPOCH of every run here: reproducible bytes.
pub const EPOCH: &str = "1700000000";

pub fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lidarsim-shard-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `lidarsim ARGS` in `dir` with SOURCE_DATE_EPOCH and `env` set, no array-job variables.
pub fn lidarsim(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_lidarsim"));
    // A file this test process opened with the hdf5 crate (to rewrite it) may stay
    // locked by a child another test thread forked meanwhile: HDF5 opens files without
    // close-on-exec, and the child inherits the descriptor and its lock. The child run
    // here then cannot open the file; without HDF5's advisory locking it can.
    cmd.current_dir(dir)
        .args(args)
        .env("SOURCE_DATE_EPOCH", EPOCH)
        .env("HDF5_USE_FILE_LOCKING", "FALSE");
    for v in [
        "SLURM_ARRAY_TASK_ID",
        "SLURM_ARRAY_TASK_COUNT",
        "SLURM_ARRAY_TASK_MIN",
        "SLURM_ARRAY_TASK_STEP",
        "JOB_COMPLETION_INDEX",
        "AWS_BATCH_JOB_ARRAY_INDEX",
        "LIDARSIM_SHARD_COUNT",
    ] {
        cmd.env_remove(v);
    }
    cmd.envs(env.iter().copied());
    cmd.output().unwrap()
}

pub fn ok(o: Output) -> Output {
    assert!(
        o.status.success(),
        "exit {:?}: {}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// `simulate CONFIG --profiles N --method shot -o raw.h5 --photons ph.h5 MORE` in `dir`
/// (`config` a shipped config's path under `configs/`), which must succeed.
pub fn simulate_with_photons(dir: &Path, config: &str, profiles: &str, more: &[&str]) {
    let cfg = super::config_path(config);
    let mut args = vec![
        "simulate",
        cfg.to_str().unwrap(),
        "-o",
        "raw.h5",
        "--profiles",
        profiles,
        "--method",
        "shot",
        "--photons",
        "ph.h5",
    ];
    args.extend_from_slice(more);
    ok(lidarsim(dir, &args, &[]));
}

/// Runs `python3 ARGS` in `dir` (`["-c", script, …]` or a script's path and its
/// arguments), which must succeed; its standard output.
pub fn python_in(dir: &Path, args: &[&str]) -> String {
    let o = std::process::Command::new("python3")
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Expects `args` to fail with one line containing every one of `words`, leaving no
/// `out` behind.
pub fn refused(dir: &Path, args: &[&str], words: &[&str], out: &str) {
    let o = lidarsim(dir, args, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    for w in words {
        assert!(err.contains(w), "{args:?}: {err} lacks {w:?}");
    }
    assert!(!dir.join(out).exists(), "{args:?} left {out}");
    assert!(
        std::fs::read_dir(dir).unwrap().all(|e| !e
            .unwrap()
            .file_name()
            .to_string_lossy()
            .starts_with('.')),
        "{args:?} left a temporary file"
    );
}

/// The first line `lidarsim ARGS` writes to stderr, the process killed then (and after
/// 30 s at the latest).
pub fn first_stderr_line(dir: &Path, args: &[&str]) -> String {
    use std::io::BufRead;
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_lidarsim"))
        .current_dir(dir)
        .args(args)
        .stderr(std::process::Stdio::piped())
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let pid = child.id().to_string();
    let child = std::sync::Arc::new(std::sync::Mutex::new(child));
    let stderr = child.lock().unwrap().stderr.take().unwrap();
    // the watchdog kills through the same handle (never a pid reused after the wait)
    let watched = std::sync::Arc::clone(&child);
    std::thread::spawn(move || {
        std::thread::sleep(std::time::Duration::from_secs(30));
        let mut c = watched.lock().unwrap();
        if c.try_wait().ok().flatten().is_none() {
            eprintln!("killing lidarsim {pid} after 30 s");
            c.kill().ok();
        }
    });
    let mut line = String::new();
    std::io::BufReader::new(stderr).read_line(&mut line).ok();
    let mut c = child.lock().unwrap();
    c.kill().ok();
    c.wait().ok();
    line
}
