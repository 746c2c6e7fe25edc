//! Bad inputs and hostile outputs, as a new user (or an unlucky script) would give them:
//! every case must be refused with one clear line on stderr (exit status 2) or succeed
//! as asked, with no panic, no abort, no hang, no file left behind and nothing outside
//! the output destroyed.
//!
//! Each case runs the `lidarsim` binary in a scratch directory of its own, with stdin
//! closed; the directory's entries (names, types, sizes, contents) are compared before
//! and after. Device nodes are made in the scratch directory with `mknod` (skipped where
//! that is not permitted), never `/dev/null` itself.
//!
//! `docs/hostile-inputs.md` is the before/after table of these cases; it is regenerated
//! with (the "before" binary built from an older commit):
//!
//! ```text
//! LIDARSIM_BIN=path/to/lidarsim LIDARSIM_HOSTILE_TABLE=table.md \
//!     cargo test --release --test hostile_inputs -- --ignored table
//! ```

mod common;

// Cases by topic (issue 18 and later): each module adds its own cases and preparations,
// so that topics grow without touching one another.
#[path = "hostile/crafted.rs"]
mod crafted;
#[path = "hostile/inputs.rs"]
mod inputs;
#[path = "hostile/integrity.rs"]
mod integrity;
#[path = "hostile/resources.rs"]
mod resources;
#[path = "hostile/values.rs"]
mod values;

use std::collections::BTreeMap;
use std::fs;
use std::os::unix::fs::{FileTypeExt, MetadataExt};
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// How long a case may run before it counts as a hang.
const TIMEOUT: Duration = Duration::from_secs(30);

/// What a case must do with the fixed binary.
#[derive(Clone, Copy)]
enum Want {
    /// Exit status 2, one line on stderr containing this text (case-insensitive).
    Refused(&'static str),
    /// Exit status 0, output on stdout, no file created but these.
    Stdout(&'static [&'static str]),
    /// Ended by the signal: status 128 + signal, nothing left.
    Interrupted(i32),
}

/// How a case is run.
enum Run {
    /// One invocation with these arguments.
    Args(Vec<String>),
    /// A long `simulate` writing `out.h5`, sent `signal` once its temporary file exists.
    Signal(i32),
    /// A second `simulate` to the same path while a first one runs.
    SecondWriter,
    /// `simulate` with the file size limited (RLIMIT_FSIZE) to this many bytes.
    FileSizeLimit(u64),
    /// One invocation with these arguments, its address space limited (RLIMIT_AS, as
    /// `ulimit -v`) to this many bytes.
    AddressSpaceLimit(u64, Vec<String>),
    /// A long `simulate` into a tmpfs of this many bytes, which fills up while it writes
    /// (skipped where mounting is not permitted).
    FullDisk(u64),
}

struct Case {
    name: &'static str,
    want: Want,
    env: Vec<(&'static str, &'static str)>,
    run: Run,
}

/// The scratch directory of one case.
struct Scratch(PathBuf);

impl Scratch {
    fn new(tag: &str, n: usize) -> Scratch {
        let d =
            std::env::temp_dir().join(format!("lidarsim-hostile-{tag}-{}-{n}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(d.join("in")).unwrap();
        Scratch(d)
    }
    fn p(&self, name: &str) -> String {
        self.0.join(name).to_string_lossy().into_owned()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = Command::new("umount")
            .arg(self.0.join("small"))
            .stderr(Stdio::null())
            .status();
        let _ = fs::remove_dir_all(&self.0);
    }
}

fn cfg(rel: &str) -> String {
    common::config_path(rel).to_string_lossy().into_owned()
}

fn s1() -> String {
    cfg("paper/scenario1.toml")
}

/// Scenario 1 with one line replaced (`key = ...` lines start with `key =`).
fn s1_with(line_start: &str, replacement: &str) -> String {
    let text = fs::read_to_string(s1()).unwrap();
    let mut found = false;
    let out: Vec<String> = text
        .lines()
        .map(|l| {
            if !found && l.trim_start().starts_with(line_start) {
                found = true;
                replacement.to_string()
            } else {
                l.to_string()
            }
        })
        .collect();
    assert!(found, "no line starts with {line_start}");
    out.join("\n")
}

fn args(v: &[&str]) -> Run {
    Run::Args(v.iter().map(|s| s.to_string()).collect())
}

/// Placeholders in arguments: `@S1` scenario 1, `@GROUND` the profile-file ground config,
/// `@D/name` a path in the scratch directory, `@IN` the case's own config `in/cfg.toml`.
fn expand(arg: &str, dir: &Scratch) -> String {
    arg.replace("@S1", &s1())
        .replace("@GROUND", &cfg("ground/profile_file_example.toml"))
        .replace("@PROFILE", &cfg("atmospheres/us76_1km.txt"))
        .replace("@IN", &dir.p("in/cfg.toml"))
        .replace("@D/", &format!("{}/", dir.0.display()))
}

/// Files a case prepares in its scratch directory before it runs.
fn prepare(name: &str, dir: &Scratch) -> bool {
    for topic in [
        inputs::prepare,
        crafted::prepare,
        resources::prepare,
        values::prepare,
        integrity::prepare,
    ] {
        if let Some(ok) = topic(name, dir) {
            return ok;
        }
    }
    let d = &dir.0;
    let write = |rel: &str, text: &str| fs::write(d.join(rel), text).unwrap();
    match name {
        "config is empty" => write("in/cfg.toml", ""),
        "config is not UTF-8" => {
            fs::write(d.join("in/cfg.toml"), [0xff, 0xfe, 0x00, 0x9c, 0x80]).unwrap()
        }
        "TOML syntax error" => write(
            "in/cfg.toml",
            &s1_with("pulse_energy_j", "pulse_energy_j = [1.0"),
        ),
        "unknown key" => write(
            "in/cfg.toml",
            &s1_with(
                "pulse_energy_j",
                "pulse_energy_j = 1.0\nlaser_colour = \"green\"",
            ),
        ),
        "string for a number" => write(
            "in/cfg.toml",
            &s1_with("pulse_energy_j", "pulse_energy_j = \"one\""),
        ),
        "nan energy" => write(
            "in/cfg.toml",
            &s1_with("pulse_energy_j", "pulse_energy_j = nan"),
        ),
        "infinite energy" => write(
            "in/cfg.toml",
            &s1_with("pulse_energy_j", "pulse_energy_j = inf"),
        ),
        "missing section" => write(
            "in/cfg.toml",
            &s1_with("[background]", "[unused_background]"),
        ),
        "molecular file is garbage" => {
            write("in/garbage.txt", "this is not a profile\n1 2\n");
            write(
                "in/cfg.toml",
                &s1_with("model = \"us76\"", "model = { file = \"garbage.txt\" }"),
            );
        }
        "molecular file is a directory" => {
            fs::create_dir(d.join("in/dir")).unwrap();
            write(
                "in/cfg.toml",
                &s1_with("model = \"us76\"", "model = { file = \"dir\" }"),
            );
        }
        "molecular file missing" => write(
            "in/cfg.toml",
            &s1_with("model = \"us76\"", "model = { file = \"nope.txt\" }"),
        ),
        "-o is a FIFO" => {
            let ok = Command::new("mkfifo")
                .arg(d.join("out.h5"))
                .status()
                .is_ok_and(|s| s.success());
            if !ok {
                return false;
            }
        }
        "-o is a socket" => {
            let _l = std::os::unix::net::UnixListener::bind(d.join("out.h5")).unwrap();
        }
        "-o is a character device"
        | "--png is a character device"
        | "--csv is a character device"
        | "--json is a character device" => {
            let ok = Command::new("mknod")
                .arg(d.join("null"))
                .args(["c", "1", "3"])
                .status()
                .is_ok_and(|s| s.success());
            if !ok {
                return false;
            }
        }
        "-o is a directory" => fs::create_dir(d.join("out.h5")).unwrap(),
        "-o is the config"
        | "-o is a link to the config"
        | "--csv is the config"
        | "--png is the config" => {
            fs::copy(s1(), d.join("in/cfg.toml")).unwrap();
            std::os::unix::fs::symlink(d.join("in/cfg.toml"), d.join("link")).unwrap();
        }
        "--csv is the profile file" => {
            fs::copy(
                cfg("ground/profile_file_example.toml"),
                d.join("in/cfg.toml"),
            )
            .unwrap();
            fs::copy(
                cfg("atmospheres/us76_1km.txt"),
                d.join("atmospheres_us76_1km.txt"),
            )
            .unwrap();
            let text = fs::read_to_string(d.join("in/cfg.toml")).unwrap();
            let text = text.replace("../atmospheres/us76_1km.txt", "../atmospheres_us76_1km.txt");
            fs::write(d.join("in/cfg.toml"), text).unwrap();
        }
        "existing output survives a failed run" => write("out.h5", "precious"),
        _ => {}
    }
    true
}

fn cases() -> Vec<Case> {
    use Want::*;
    let c = |name, want, run| Case {
        name,
        want,
        env: vec![],
        run,
    };
    let mut v = vec![
        // --- the config file ---
        c(
            "config missing",
            Refused("no such file"),
            args(&["expect", "@D/none.toml"]),
        ),
        c(
            "config is a directory",
            Refused("directory"),
            args(&["expect", "@D/in"]),
        ),
        c("config is empty", Refused("name"), args(&["expect", "@IN"])),
        c(
            "config is not UTF-8",
            Refused("UTF-8"),
            args(&["expect", "@IN"]),
        ),
        c(
            "TOML syntax error",
            Refused("line"),
            args(&["expect", "@IN"]),
        ),
        c(
            "unknown key",
            Refused("laser_colour"),
            args(&["expect", "@IN"]),
        ),
        c(
            "string for a number",
            Refused("pulse_energy_j"),
            args(&["expect", "@IN"]),
        ),
        c(
            "nan energy",
            Refused("pulse_energy_j"),
            args(&["expect", "@IN"]),
        ),
        c(
            "infinite energy",
            Refused("pulse_energy_j"),
            args(&["expect", "@IN"]),
        ),
        c(
            "number for a table",
            Refused("platform"),
            args(&["expect", "@S1", "--set", "platform=3"]),
        ),
        c(
            "missing section",
            Refused("background"),
            args(&["expect", "@IN"]),
        ),
        c(
            "molecular file is garbage",
            Refused("garbage.txt"),
            args(&["expect", "@IN"]),
        ),
        c(
            "molecular file is a directory",
            Refused("dir"),
            args(&["expect", "@IN"]),
        ),
        c(
            "molecular file missing",
            Refused("nope.txt"),
            args(&["expect", "@IN"]),
        ),
        // --- values through --set ---
        c(
            "negative energy",
            Refused("pulse_energy_j"),
            args(&["expect", "@S1", "--set", "instrument.pulse_energy_j=-1"]),
        ),
        c(
            "energy 1e308",
            Refused("1e308"),
            args(&["expect", "@S1", "--set", "instrument.pulse_energy_j=1e308"]),
        ),
        c(
            "nan via --set",
            Refused("pulse_energy_j"),
            args(&["expect", "@S1", "--set", "instrument.pulse_energy_j=nan"]),
        ),
        c(
            "rep rate 0",
            Refused("rep_rate_hz"),
            args(&["expect", "@S1", "--set", "instrument.rep_rate_hz=0"]),
        ),
        c(
            "efficiency above 1",
            Refused("quantum_efficiency"),
            args(&[
                "expect",
                "@S1",
                "--set",
                "instrument.quantum_efficiency=1.5",
            ]),
        ),
        c(
            "bins beyond the limit",
            Refused("bins"),
            args(&[
                "expect",
                "@S1",
                "--set",
                "instrument.bin_width_s=1e-10",
                "--set",
                "acquisition.top_altitude_km=1000",
                "--set",
                "platform.altitude_km=2000",
            ]),
        ),
        c(
            "zero accumulation time",
            Refused("accumulation_time_s"),
            args(&[
                "expect",
                "@S1",
                "--set",
                "acquisition.accumulation_time_s=0",
            ]),
        ),
        c(
            "window upside down",
            Refused("bottom_altitude_km"),
            args(&[
                "expect",
                "@S1",
                "--set",
                "acquisition.bottom_altitude_km=150",
            ]),
        ),
        c(
            "window above the platform",
            Refused("top_altitude_km"),
            args(&["expect", "@S1", "--set", "acquisition.top_altitude_km=700"]),
        ),
        c(
            "off nadir 90 degrees",
            Refused("off_nadir_deg"),
            args(&["expect", "@S1", "--set", "platform.off_nadir_deg=90"]),
        ),
        c(
            "unknown molecular model",
            Refused("model"),
            args(&["expect", "@S1", "--set", "atmosphere.molecular.model=msis"]),
        ),
        c(
            "layer top below base",
            Refused("top_km"),
            args(&["expect", "@S1", "--set", "atmosphere.layers.0.top_km=5"]),
        ),
        c(
            "depolarization 2",
            Refused("depolarization"),
            args(&[
                "expect",
                "@S1",
                "--set",
                "atmosphere.layers.0.depolarization=2",
            ]),
        ),
        c(
            "jitter 0.5",
            Refused("pulse_energy_jitter"),
            args(&[
                "expect",
                "@S1",
                "--set",
                "instrument.pulse_energy_jitter=0.5",
            ]),
        ),
        c(
            "--set without =",
            Refused("--set"),
            args(&["expect", "@S1", "--set", "instrument.pulse_energy_j"]),
        ),
        c(
            "--set empty key part",
            Refused("--set"),
            args(&["expect", "@S1", "--set", "instrument..pulse_energy_j=1"]),
        ),
        c(
            "--set index out of range",
            Refused("layers"),
            args(&["expect", "@S1", "--set", "atmosphere.layers.7.top_km=5"]),
        ),
        c(
            "--set unknown key",
            Refused("laser_colour"),
            args(&["expect", "@S1", "--set", "instrument.laser_colour=1"]),
        ),
        c(
            "--set wrong type",
            Refused("--set"),
            args(&["expect", "@S1", "--set", "instrument.pulse_energy_j=true"]),
        ),
        // --- command-line values ---
        c(
            "--profiles -1",
            Refused("--profiles"),
            args(&["simulate", "@S1", "-o", "@D/out.h5", "--profiles", "-1"]),
        ),
        c(
            "--profiles 0",
            Refused("--profiles"),
            args(&["simulate", "@S1", "-o", "@D/out.h5", "--profiles", "0"]),
        ),
        c(
            "--profiles abc",
            Refused("--profiles"),
            args(&["simulate", "@S1", "-o", "@D/out.h5", "--profiles", "abc"]),
        ),
        c(
            "--profiles 1e11 (memory, disk)",
            Refused("profiles"),
            args(&[
                "simulate",
                "@S1",
                "-o",
                "@D/out.h5",
                "--profiles",
                "100000000000",
            ]),
        ),
        c(
            "--profiles 1e9 (disk)",
            Refused("free"),
            args(&[
                "simulate",
                "@S1",
                "-o",
                "@D/out.h5",
                "--profiles",
                "1000000000",
                "--set",
                "instrument.bin_width_s=2e-7",
            ]),
        ),
        c(
            "--seed -1",
            Refused("--seed"),
            args(&["simulate", "@S1", "-o", "@D/out.h5", "--seed", "-1"]),
        ),
        c(
            "--seed 1e30",
            Refused("--seed"),
            args(&[
                "simulate",
                "@S1",
                "-o",
                "@D/out.h5",
                "--seed",
                "1000000000000000000000000000000",
            ]),
        ),
        c(
            "--threads 0",
            Refused("--threads"),
            args(&["simulate", "@S1", "-o", "@D/out.h5", "--threads", "0"]),
        ),
        c(
            "--threads 100000",
            Refused("--threads"),
            args(&["simulate", "@S1", "-o", "@D/out.h5", "--threads", "100000"]),
        ),
        c(
            "--tolerance NaN",
            Refused("--tolerance"),
            args(&["simulate", "@S1", "-o", "@D/out.h5", "--tolerance", "NaN"]),
        ),
        c(
            "--tolerance -1",
            Refused("--tolerance"),
            args(&["simulate", "@S1", "-o", "@D/out.h5", "--tolerance", "-1"]),
        ),
        c(
            "--tolerance inf",
            Refused("--tolerance"),
            args(&["simulate", "@S1", "-o", "@D/out.h5", "--tolerance", "inf"]),
        ),
        c(
            "--tolerance 2",
            Refused("--tolerance"),
            args(&["simulate", "@S1", "-o", "@D/out.h5", "--tolerance", "2"]),
        ),
        c(
            "--tolerance with --method shot",
            Refused("--tolerance"),
            args(&[
                "simulate",
                "@S1",
                "-o",
                "@D/out.h5",
                "--tolerance",
                "1e-3",
                "--method",
                "shot",
            ]),
        ),
        c(
            "--method aggregate with dead time",
            Refused("aggregate"),
            args(&[
                "simulate",
                "@S1",
                "-o",
                "@D/out.h5",
                "--method",
                "aggregate",
                "--set",
                "instrument.detector.dead_time_s=3.5e-9",
            ]),
        ),
        c(
            "--method bogus",
            Refused("--method"),
            args(&["simulate", "@S1", "-o", "@D/out.h5", "--method", "bogus"]),
        ),
        c(
            "--realizations 0",
            Refused("--realizations"),
            args(&["validate", "@S1", "--realizations", "0"]),
        ),
        c(
            "--realizations 5",
            Refused("--realizations"),
            args(&["validate", "@S1", "--realizations", "5"]),
        ),
        c(
            "--realizations 1e12",
            Refused("realizations"),
            args(&["validate", "@S1", "--realizations", "1000000000000"]),
        ),
        c(
            "background_bins 1e12",
            Refused("background_bins"),
            args(&[
                "validate",
                "@S1",
                "--set",
                "acquisition.background_bins=1000000000000",
            ]),
        ),
        // --- outputs ---
        c(
            "-o is a character device",
            Refused("character device"),
            args(&["simulate", "@S1", "-o", "@D/null", "--profiles", "2"]),
        ),
        c(
            "--png is a character device",
            Refused("character device"),
            args(&["snr-map", "@S1", "--png", "@D/null"]),
        ),
        c(
            "--csv is a character device",
            Refused("character device"),
            args(&["expect", "@S1", "--csv", "@D/null"]),
        ),
        c(
            "--json is a character device",
            Refused("character device"),
            args(&[
                "validate",
                "@S1",
                "--realizations",
                "100",
                "--json",
                "@D/null",
            ]),
        ),
        c(
            "-o is a FIFO",
            Refused("FIFO"),
            args(&["simulate", "@S1", "-o", "@D/out.h5", "--profiles", "2"]),
        ),
        c(
            "-o is a socket",
            Refused("socket"),
            args(&["simulate", "@S1", "-o", "@D/out.h5", "--profiles", "2"]),
        ),
        c(
            "-o is a directory",
            Refused("directory"),
            args(&["simulate", "@S1", "-o", "@D/out.h5", "--profiles", "2"]),
        ),
        c(
            "-o names a directory with /",
            Refused("-o"),
            args(&["simulate", "@S1", "-o", "@D/in/", "--profiles", "2"]),
        ),
        c(
            "-o is empty",
            Refused("-o"),
            args(&["simulate", "@S1", "-o", "", "--profiles", "2"]),
        ),
        c(
            "-o in a missing directory",
            Refused("no such"),
            args(&[
                "simulate",
                "@S1",
                "-o",
                "@D/no/such/out.h5",
                "--profiles",
                "2",
            ]),
        ),
        c(
            "-o under a regular file",
            Refused("-o"),
            args(&["simulate", "@S1", "-o", "@S1/out.h5", "--profiles", "2"]),
        ),
        c(
            "-o file name too long",
            Refused("-o"),
            Run::Args(vec![
                "simulate".into(),
                "@S1".into(),
                "-o".into(),
                format!("@D/{}.h5", "x".repeat(300)),
                "--profiles".into(),
                "2".into(),
            ]),
        ),
        c(
            "-o is the config",
            Refused("input"),
            args(&["simulate", "@IN", "-o", "@IN", "--profiles", "2"]),
        ),
        c(
            "-o is a link to the config",
            Refused("input"),
            args(&["simulate", "@IN", "-o", "@D/link", "--profiles", "2"]),
        ),
        c(
            "--csv is the config",
            Refused("input"),
            args(&["expect", "@IN", "--csv", "@IN"]),
        ),
        c(
            "--png is the config",
            Refused("input"),
            args(&["snr-map", "@IN", "--png", "@IN"]),
        ),
        c(
            "--csv is the profile file",
            Refused("input"),
            args(&["expect", "@IN", "--csv", "@D/atmospheres_us76_1km.txt"]),
        ),
        c(
            "-o - (binary to stdout)",
            Refused("standard output"),
            args(&["simulate", "@S1", "-o", "-", "--profiles", "2"]),
        ),
        c(
            "--png - (binary to stdout)",
            Refused("standard output"),
            args(&["snr-map", "@S1", "--png", "-"]),
        ),
        c(
            "snr-map --csv -",
            Stdout(&["map.png"]),
            args(&["snr-map", "@S1", "--png", "@D/map.png", "--csv", "-"]),
        ),
        c(
            "validate --json -",
            Stdout(&[]),
            args(&["validate", "@S1", "--realizations", "100", "--json", "-"]),
        ),
        c(
            "expect --csv -",
            Stdout(&[]),
            args(&["expect", "@S1", "--csv", "-"]),
        ),
        c(
            "--png and --csv the same file",
            Refused("also the output"),
            args(&["snr-map", "@S1", "--png", "@D/x", "--csv", "@D/x"]),
        ),
        c(
            "failed --png leaves no --csv",
            Refused("--png"),
            args(&[
                "snr-map",
                "@S1",
                "--csv",
                "@D/map.csv",
                "--png",
                "@D/no/such/map.png",
            ]),
        ),
        c(
            "existing output survives a failed run",
            Refused("pulse_energy_j"),
            args(&[
                "simulate",
                "@S1",
                "-o",
                "@D/out.h5",
                "--set",
                "instrument.pulse_energy_j=-1",
            ]),
        ),
        c("SIGINT during a run", Interrupted(2), Run::Signal(2)),
        c("SIGTERM during a run", Interrupted(15), Run::Signal(15)),
        c("SIGHUP during a run", Interrupted(1), Run::Signal(1)),
        c(
            "second run writing the same file",
            Refused("another run"),
            Run::SecondWriter,
        ),
        c(
            "file size limit reached mid-run",
            Refused("file too large"),
            Run::FileSizeLimit(200_000),
        ),
        c(
            "disk full mid-run",
            Refused("no space left"),
            Run::FullDisk(512 << 20),
        ),
    ];
    v.push(Case {
        name: "malformed SOURCE_DATE_EPOCH",
        want: Refused("SOURCE_DATE_EPOCH"),
        env: vec![("SOURCE_DATE_EPOCH", "yesterday")],
        run: args(&["simulate", "@S1", "-o", "@D/out.h5", "--profiles", "2"]),
    });
    v.extend(inputs::cases());
    v.extend(crafted::cases());
    v.extend(resources::cases());
    v.extend(values::cases());
    v
}

/// One entry of a directory snapshot: type and content.
#[derive(Debug, PartialEq)]
enum Entry {
    File(Vec<u8>),
    Dir,
    Other(String),
}

fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Entry> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(rd) = fs::read_dir(&d) else { continue };
        for e in rd.flatten() {
            let p = e.path();
            let Ok(m) = fs::symlink_metadata(&p) else {
                continue;
            };
            let t = m.file_type();
            let entry = if t.is_symlink() {
                Entry::Other(format!("link -> {:?}", fs::read_link(&p).ok()))
            } else if t.is_dir() {
                stack.push(p.clone());
                Entry::Dir
            } else if t.is_file() {
                Entry::File(fs::read(&p).unwrap_or_default())
            } else if t.is_char_device() || t.is_block_device() {
                Entry::Other(format!("device {}", m.rdev()))
            } else {
                Entry::Other(format!("{t:?}"))
            };
            out.insert(p.strip_prefix(dir).unwrap().to_path_buf(), entry);
        }
    }
    out
}

/// What a case did.
struct Outcome {
    status: Option<i32>,
    signal: Option<i32>,
    hung: bool,
    stdout_len: usize,
    stderr: String,
    /// Entries added, removed or changed in the scratch directory.
    changes: Vec<String>,
}

impl Outcome {
    fn summary(&self) -> String {
        let mut s = if self.hung {
            "hang (killed after 30 s)".to_string()
        } else if let Some(sig) = self.signal {
            format!(
                "killed by signal {sig}{}",
                if sig == 6 { " (abort)" } else { "" }
            )
        } else {
            format!("exit {}", self.status.unwrap_or(-1))
        };
        let lines: Vec<&str> = self
            .stderr
            .lines()
            .filter(|l| !l.trim().is_empty())
            .collect();
        // an interrupted run's last line is the one that matters
        let shown = match lines.last() {
            Some(l) if l.contains("interrupted") => Some(l),
            _ => lines.first(),
        };
        if let Some(first) = shown {
            let first: String = shorten(first).chars().take(160).collect();
            s += &format!(": `{}`", first.replace('|', "\\|").replace('`', "'"));
            if lines.len() > 1 {
                s += &format!(" (+{} lines)", lines.len() - 1);
            }
        }
        if self.stdout_len > 0 {
            s += &format!("; {} bytes on stdout", self.stdout_len);
        }
        if !self.changes.is_empty() {
            s += &format!("; files: {}", self.changes.join(", "));
        }
        s
    }
}

/// A message with the scratch directory written `D/` and the repository's configs
/// `configs/`, for the table.
fn shorten(line: &str) -> String {
    let tmp = format!("{}/lidarsim-hostile-case-", std::env::temp_dir().display());
    let mut out = line.replace(
        &format!("{}/configs/", env!("CARGO_MANIFEST_DIR")),
        "configs/",
    );
    while let Some(i) = out.find(&tmp) {
        let end = out[i + tmp.len()..]
            .find('/')
            .map_or(out.len(), |j| i + tmp.len() + j + 1);
        out.replace_range(i..end, "D/");
    }
    out
}

fn bin() -> PathBuf {
    std::env::var_os("LIDARSIM_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_lidarsim")))
}

/// A resource limit set on a child before it runs.
#[derive(Clone, Copy)]
enum Limit {
    /// RLIMIT_FSIZE, bytes (SIGXFSZ ignored, so a write past it fails with EFBIG).
    FileSize(u64),
    /// RLIMIT_AS, bytes.
    AddressSpace(u64),
}

/// Starts the binary in `dir` with output captured to files beside it.
fn spawn(
    dir: &Scratch,
    args: &[String],
    env: &[(&str, &str)],
    limit: Option<Limit>,
) -> (std::process::Child, PathBuf, PathBuf) {
    static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let out = dir.0.with_extension(format!("{n}.stdout"));
    let err = dir.0.with_extension(format!("{n}.stderr"));
    let mut cmd = Command::new(bin());
    cmd.args(args.iter().map(|a| expand(a, dir)))
        .current_dir(&dir.0)
        .env_remove("SOURCE_DATE_EPOCH")
        .envs(env.iter().copied())
        .stdin(Stdio::null())
        .stdout(fs::File::create(&out).unwrap())
        .stderr(fs::File::create(&err).unwrap());
    if let Some(limit) = limit {
        let (resource, bytes) = match limit {
            Limit::FileSize(b) => (libc::RLIMIT_FSIZE, b),
            Limit::AddressSpace(b) => (libc::RLIMIT_AS, b),
        };
        // SAFETY: only async-signal-safe calls between fork and exec.
        unsafe {
            cmd.pre_exec(move || {
                libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
                let rl = libc::rlimit {
                    rlim_cur: bytes,
                    rlim_max: bytes,
                };
                if libc::setrlimit(resource, &rl) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
    }
    (cmd.spawn().expect("spawn lidarsim"), out, err)
}

/// Waits for `child` at most [`TIMEOUT`]; kills it after.
fn wait(child: &mut std::process::Child) -> (Option<std::process::ExitStatus>, bool) {
    let start = Instant::now();
    loop {
        if let Some(st) = child.try_wait().unwrap() {
            return (Some(st), false);
        }
        if start.elapsed() > TIMEOUT {
            let _ = child.kill();
            return (child.wait().ok(), true);
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Waits until a temporary output file shows in `dir` (the run is writing).
fn wait_for_partial(dir: &Path) -> bool {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(20) {
        let found = fs::read_dir(dir)
            .map(|rd| {
                rd.flatten()
                    .any(|e| e.file_name().to_string_lossy().contains("partial"))
            })
            .unwrap_or(false);
        if found {
            std::thread::sleep(Duration::from_millis(200));
            return true;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    false
}

fn long_run() -> Vec<String> {
    [
        "simulate",
        "@S1",
        "-o",
        "@D/out.h5",
        "--profiles",
        "2000000",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

/// Runs one case; `None` when its preparation is not possible here (e.g. no mknod).
fn run_case(case: &Case, n: usize) -> Option<Outcome> {
    let dir = Scratch::new("case", n);
    if !prepare(case.name, &dir) {
        return None;
    }
    let limit = match case.run {
        Run::FileSizeLimit(b) => Some(Limit::FileSize(b)),
        Run::AddressSpaceLimit(b, _) => Some(Limit::AddressSpace(b)),
        _ => None,
    };
    let args = match &case.run {
        Run::Args(a) | Run::AddressSpaceLimit(_, a) => a.clone(),
        Run::Signal(_) | Run::SecondWriter => long_run(),
        Run::FileSizeLimit(_) => ["simulate", "@S1", "-o", "@D/out.h5", "--profiles", "20000"]
            .iter()
            .map(|s| s.to_string())
            .collect(),
        Run::FullDisk(bytes) => {
            let small = dir.0.join("small");
            fs::create_dir(&small).unwrap();
            let mounted = Command::new("mount")
                .args(["-t", "tmpfs", "-o", &format!("size={bytes}"), "tmpfs"])
                .arg(&small)
                .stderr(Stdio::null())
                .status()
                .is_ok_and(|s| s.success());
            if !mounted {
                return None;
            }
            [
                "simulate",
                "@S1",
                "-o",
                "@D/small/out.h5",
                "--profiles",
                "1000000",
            ]
            .iter()
            .map(|s| s.to_string())
            .collect()
        }
    };
    let before = snapshot(&dir.0);
    let (mut child, out, err) = match &case.run {
        Run::SecondWriter => {
            let (mut first, _, _) = spawn(&dir, &args, &case.env, None);
            let writing = wait_for_partial(&dir.0);
            let second = spawn(&dir, &args, &case.env, None);
            let mut second_child = second.0;
            let (st, hung) = wait(&mut second_child);
            unsafe { libc::kill(first.id() as i32, libc::SIGTERM) };
            let _ = wait(&mut first);
            let _ = writing;
            let after = snapshot(&dir.0);
            return Some(outcome(st, hung, &second.1, &second.2, &before, &after));
        }
        _ => spawn(&dir, &args, &case.env, limit),
    };
    if let Run::Signal(sig) = case.run
        && wait_for_partial(&dir.0)
    {
        unsafe { libc::kill(child.id() as i32, sig) };
    }
    let filler = dir.0.join("small/filler");
    if let Run::FullDisk(_) = case.run
        && wait_for_partial(&dir.0.join("small"))
    {
        // fill the file system while the run writes: its next writes fail
        let mut f = fs::File::create(&filler).unwrap();
        let block = vec![1u8; 1 << 16];
        while std::io::Write::write_all(&mut f, &block).is_ok() {}
    }
    let (st, hung) = wait(&mut child);
    let _ = fs::remove_file(&filler);
    let after = snapshot(&dir.0);
    Some(outcome(st, hung, &out, &err, &before, &after))
}

fn outcome(
    st: Option<std::process::ExitStatus>,
    hung: bool,
    out: &Path,
    err: &Path,
    before: &BTreeMap<PathBuf, Entry>,
    after: &BTreeMap<PathBuf, Entry>,
) -> Outcome {
    let mut changes = Vec::new();
    for (p, e) in after {
        match before.get(p) {
            None => changes.push(format!("left {}", p.display())),
            Some(b) if b != e => changes.push(format!("changed {}", p.display())),
            _ => {}
        }
    }
    for p in before.keys().filter(|p| !after.contains_key(*p)) {
        changes.push(format!("destroyed {}", p.display()));
    }
    let stdout_len = fs::metadata(out).map(|m| m.len() as usize).unwrap_or(0);
    let stderr = fs::read_to_string(err).unwrap_or_default();
    let _ = fs::remove_file(out);
    let _ = fs::remove_file(err);
    Outcome {
        status: st.and_then(|s| s.code()),
        signal: st.and_then(|s| s.signal()),
        hung,
        stdout_len,
        stderr,
        changes,
    }
}

/// Whether the outcome is what the case wants; the reason when not.
fn judge(case: &Case, o: &Outcome) -> Result<(), String> {
    let lines: Vec<&str> = o.stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    if o.stderr.contains("panicked") || o.hung || o.signal.is_some() {
        return Err(o.summary());
    }
    let allowed: &[&str] = match case.want {
        Want::Stdout(files) => files,
        _ => &[],
    };
    if o.changes
        .iter()
        .any(|c| !allowed.iter().any(|a| *c == format!("left {a}")))
    {
        return Err(format!("changed files: {}", o.summary()));
    }
    match case.want {
        Want::Refused(needle) => {
            if o.status != Some(2) || lines.len() != 1 {
                return Err(format!("want one line and exit 2: {}", o.summary()));
            }
            if !lines[0].to_lowercase().contains(&needle.to_lowercase()) {
                return Err(format!("message lacks {needle:?}: {}", o.summary()));
            }
        }
        Want::Stdout(_) => {
            if o.status != Some(0) || o.stdout_len == 0 {
                return Err(format!("want success on stdout: {}", o.summary()));
            }
        }
        Want::Interrupted(sig) => {
            // a long run may announce its estimate first; the interruption is one line
            let last = lines.last().copied().unwrap_or("");
            if o.status != Some(128 + sig) || !last.contains("interrupted") {
                return Err(format!(
                    "want exit {} and one line: {}",
                    128 + sig,
                    o.summary()
                ));
            }
        }
    }
    Ok(())
}

/// Held by each test of this file that runs the binary: one at a time (the cases edit
/// files with this process's HDF5 while the binary under test opens others with its own,
/// and HDF5's file locks meet; the signal storms time the end of a run).
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

#[test]
fn every_hostile_case_is_refused_cleanly() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let cases = cases();
    assert!(cases.len() >= 60, "{} cases", cases.len());
    let mut failures = Vec::new();
    for (n, case) in cases.iter().enumerate() {
        match run_case(case, n) {
            None => common::skip_acceptable_in_ci(
                &format!("hostile case {}", case.name),
                "its preparation (mknod, mount or a resource limit) is not permitted here",
                "it needs a privilege an unprivileged CI container lacks; docs/hostile-inputs.md shows its outcome where permitted",
            ),
            Some(o) => {
                if let Err(why) = judge(case, &o) {
                    failures.push(format!("{}: {why}", case.name));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

/// Every class of damage that `merge` refuses, through every reader of its kind of file
/// (`tests/hostile/integrity.rs`): each refused in one line naming the variable, exit 2,
/// nothing left behind.
#[test]
fn every_damaged_file_is_refused_by_every_reader() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let cases = integrity::cases();
    let mut rows = String::from("| # | damage — reader | after |\n|---|---|---|\n");
    assert!(cases.len() >= 100, "{} cases", cases.len());
    let mut failures = Vec::new();
    for (n, case) in cases.iter().enumerate() {
        match run_case(case, 10_000 + n) {
            None => failures.push(format!("{}: its file could not be made", case.name)),
            Some(o) => {
                let name = case.name.trim_start_matches("integrity: ");
                rows += &format!("| {} | {name} | {} |\n", n + 1, o.summary());
                if let Err(why) = judge(case, &o) {
                    failures.push(format!("{}: {why}", case.name));
                }
            }
        }
    }
    // the table of docs/hostile-inputs.md, on request
    if let Some(path) = std::env::var_os("LIDARSIM_INTEGRITY_TABLE") {
        fs::write(path, rows).unwrap();
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

/// Writes the markdown rows of `docs/hostile-inputs.md` for the binary in `LIDARSIM_BIN`.
#[test]
#[ignore]
fn table() {
    let path = std::env::var_os("LIDARSIM_HOSTILE_TABLE").expect("set LIDARSIM_HOSTILE_TABLE");
    let mut rows = String::from("| # | case | outcome |\n|---|---|---|\n");
    for (n, case) in cases().iter().chain(&integrity::cases()).enumerate() {
        let what = run_case(case, n).map_or("(not possible here)".to_string(), |o| o.summary());
        rows += &format!("| {} | {} | {} |\n", n + 1, case.name, what);
    }
    fs::write(path, rows).unwrap();
}

/// A signal ends a run whose standard error is closed (`lidarsim simulate … 2>&1 | head
/// -1`, the reader gone): the signal watcher's line goes nowhere instead of panicking the
/// watcher, which then never ended the process (issue 36, item 17: a run that "ignores
/// SIGTERM"). Before the fix the run below was still drawing 10 s after its SIGTERM.
#[test]
fn a_signal_ends_a_run_whose_stderr_is_closed() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = Scratch::new("closed-stderr", 0);
    let mut child = Command::new(bin())
        .args(long_run().iter().map(|a| expand(a, &dir)))
        .current_dir(&dir.0)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn lidarsim");
    // the reader goes away: every later write to either stream fails with EPIPE
    drop(child.stdout.take());
    drop(child.stderr.take());
    assert!(wait_for_partial(&dir.0), "the run never started writing");
    unsafe { libc::kill(child.id() as i32, libc::SIGTERM) };
    let (st, hung) = wait(&mut child);
    assert!(!hung, "still running {TIMEOUT:?} after SIGTERM");
    assert_eq!(st.and_then(|s| s.code()), Some(143), "{st:?}");
    let left: Vec<String> = fs::read_dir(&dir.0)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n != "in")
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}
