//! Every input is an input: scheme, curtain, profile, partial and raw files are protected from every output and refused at once when special (issue 18, items 1 and 3).
//!
//! Each case is `KIND: VARIANT`. The kind says which input the case is about and which
//! command reads it; its preparation makes that input in the scratch directory (`in/`)
//! so that the harness sees whether it changed. The variants:
//!
//! * `OPTION onto it`, `... onto a link to it` (`D/link`, a symbolic link),
//!   `... onto a hard link to it` (`D/hard`): an output named onto the input, refused
//!   with "input" and the input unchanged;
//! * `a FIFO` (`D/fifo`, made with `mkfifo`), `a directory` (`D/dir`),
//!   `a character device` (`D/null`, `mknod c 1 3`), `a socket` (`D/sock`): the input
//!   given as that, refused at once (a FIFO opened for reading would block forever).

use std::fs;
use std::path::Path;
use std::process::{Command, Stdio};

use super::{Case, Scratch, Want, args, bin, cfg, s1};

/// The inputs: (name prefix of its cases, what its preparation makes).
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    /// `in/cfg.toml`, scenario 1.
    Config,
    /// `in/profile.txt`, named by the ground config `in/cfg.toml`.
    Profile,
    /// `in/scheme.toml`, an onboard scheme file for scenario 1.
    Scheme,
    /// `in/curtain.h5`, named by `[scene] curtain` of `in/cfg.toml`.
    Curtain,
    /// `in/part.json`, a partial of `validate --shard 0/1` of `in/cfg.toml` (the ground
    /// config with its profile file `in/profile.txt`).
    ValidatePartial,
    /// `in/part.json`, a partial of `onboard --shard 0/1` of `in/cfg.toml` (the ground
    /// config with its profile file `in/profile.txt`).
    OnboardPartial,
    /// `in/raw.h5`, a raw file of a ground run, for `export-scc`.
    SccRaw,
    /// `in/raw.h5`, a raw file of scenario 1, for `curtain`.
    CurtainRaw,
    /// `in/shard.h5`, shard 0/1 of a run of `in/cfg.toml` (the ground config with its
    /// profile file `in/profile.txt`), for `merge`.
    Shard,
}

const KINDS: [(&str, Kind); 9] = [
    ("config", Kind::Config),
    ("profile file", Kind::Profile),
    ("scheme file", Kind::Scheme),
    ("curtain file", Kind::Curtain),
    ("validate partial", Kind::ValidatePartial),
    ("onboard partial", Kind::OnboardPartial),
    ("export-scc raw file", Kind::SccRaw),
    ("curtain raw file", Kind::CurtainRaw),
    ("merge shard", Kind::Shard),
];

/// A scheme file for scenario 1's window (100 to 0 km, 300 m bins).
const SCHEME: &str = "[[regions]]\ntop_km = 100.0\nbottom_km = 20.0\n\
                      vertical_resolution_m = 600.0\nshots_averaged = 2\n\n\
                      [[regions]]\ntop_km = 20.0\nbottom_km = 0.0\n\
                      vertical_resolution_m = 300.0\nshots_averaged = 1\n";

/// This topic's cases, run after the older ones.
pub fn cases() -> Vec<Case> {
    use Want::Refused;
    let c = |name, want, run| Case {
        name,
        want,
        env: vec![],
        run,
    };
    let onboard = |extra: &[&'static str]| {
        let mut v = vec![
            "onboard",
            "@S1",
            "--set",
            "acquisition.profiles=2",
            "--scheme",
            "@D/in/scheme.toml",
        ];
        v.extend_from_slice(extra);
        args(&v)
    };
    vec![
        // --- the config ---
        c(
            "config: --json onto it",
            Refused("input"),
            args(&["validate", "@IN", "--realizations", "100", "--json", "@IN"]),
        ),
        c(
            "config: --report onto a link to it",
            Refused("input"),
            args(&[
                "onboard", "@IN", "--scheme", "none", "-o", "@D/p.h5", "--report", "@D/link",
            ]),
        ),
        c(
            "config: --raw onto a hard link to it",
            Refused("input"),
            args(&[
                "onboard", "@IN", "--scheme", "none", "-o", "@D/p.h5", "--raw", "@D/hard",
            ]),
        ),
        c(
            "config: a FIFO",
            Refused("is a FIFO"),
            args(&["expect", "@D/fifo"]),
        ),
        c(
            "config: a character device",
            Refused("is a character device"),
            args(&["expect", "@D/null"]),
        ),
        c(
            "config: a socket",
            Refused("is a socket"),
            args(&["validate", "@D/sock"]),
        ),
        // --- the molecular profile file ---
        c(
            "profile file: -o onto it",
            Refused("input"),
            args(&[
                "simulate",
                "@IN",
                "-o",
                "@D/in/profile.txt",
                "--profiles",
                "2",
            ]),
        ),
        c(
            "profile file: --png onto a link to it",
            Refused("input"),
            args(&["snr-map", "@IN", "--png", "@D/link"]),
        ),
        c(
            "profile file: --csv onto a hard link to it",
            Refused("input"),
            args(&["expect", "@IN", "--csv", "@D/hard"]),
        ),
        c(
            "profile file: a FIFO",
            Refused("is a FIFO"),
            args(&["expect", "@IN"]),
        ),
        c(
            "profile file: a directory",
            Refused("is a directory"),
            args(&["expect", "@IN"]),
        ),
        c(
            "profile file: a character device",
            Refused("is a character device"),
            args(&["expect", "@IN"]),
        ),
        // --- the onboard scheme file ---
        c(
            "scheme file: --report onto it",
            Refused("input"),
            onboard(&["-o", "@D/p.h5", "--report", "@D/in/scheme.toml"]),
        ),
        c(
            "scheme file: -o onto a link to it",
            Refused("input"),
            onboard(&["-o", "@D/link"]),
        ),
        c(
            "scheme file: --raw onto a hard link to it",
            Refused("input"),
            onboard(&["-o", "@D/p.h5", "--raw", "@D/hard"]),
        ),
        c(
            "scheme file: --partial onto it",
            Refused("input"),
            onboard(&[
                "-o",
                "@D/p.h5",
                "--shard",
                "0/1",
                "--partial",
                "@D/in/scheme.toml",
            ]),
        ),
        c(
            "scheme file: a FIFO",
            Refused("is a FIFO"),
            args(&["onboard", "@S1", "--scheme", "@D/fifo", "-o", "@D/p.h5"]),
        ),
        c(
            "scheme file: a directory",
            Refused("is a directory"),
            args(&["onboard", "@S1", "--scheme", "@D/dir", "-o", "@D/p.h5"]),
        ),
        c(
            "scheme file: a character device",
            Refused("is a character device"),
            args(&["onboard", "@S1", "--scheme", "@D/null", "-o", "@D/p.h5"]),
        ),
        // --- the scene's curtain file ---
        c(
            "curtain file: -o onto it",
            Refused("input"),
            args(&[
                "simulate",
                "@IN",
                "--profiles",
                "2",
                "-o",
                "@D/in/curtain.h5",
            ]),
        ),
        c(
            "curtain file: -o onto a link to it",
            Refused("input"),
            args(&["simulate", "@IN", "--profiles", "2", "-o", "@D/link"]),
        ),
        c(
            "curtain file: -o onto a hard link to it",
            Refused("input"),
            args(&["simulate", "@IN", "--profiles", "2", "-o", "@D/hard"]),
        ),
        c(
            "curtain file: --csv onto it",
            Refused("input"),
            args(&["expect", "@IN", "--csv", "@D/in/curtain.h5"]),
        ),
        c(
            "curtain file: a FIFO",
            Refused("is a FIFO"),
            args(&["simulate", "@IN", "--profiles", "2", "-o", "@D/out.h5"]),
        ),
        c(
            "curtain file: a directory",
            Refused("is a directory"),
            args(&["simulate", "@IN", "--profiles", "2", "-o", "@D/out.h5"]),
        ),
        c(
            "curtain file: a character device",
            Refused("is a character device"),
            args(&["simulate", "@IN", "--profiles", "2", "-o", "@D/out.h5"]),
        ),
        // --- validate --combine's partials ---
        c(
            "validate partial: --json onto it",
            Refused("input"),
            args(&[
                "validate",
                "--combine",
                "@D/in/part.json",
                "--json",
                "@D/in/part.json",
            ]),
        ),
        c(
            "validate partial: --json onto a link to it",
            Refused("input"),
            args(&[
                "validate",
                "--combine",
                "@D/in/part.json",
                "--json",
                "@D/link",
            ]),
        ),
        c(
            "validate partial: --json onto its config's profile file",
            Refused("input"),
            args(&[
                "validate",
                "--combine",
                "@D/in/part.json",
                "--json",
                "@D/in/profile.txt",
            ]),
        ),
        c(
            "validate partial: a FIFO",
            Refused("is a FIFO"),
            args(&["validate", "--combine", "@D/fifo"]),
        ),
        c(
            "validate partial: a directory",
            Refused("is a directory"),
            args(&["validate", "--combine", "@D/dir"]),
        ),
        c(
            "validate partial: a character device",
            Refused("is a character device"),
            args(&["validate", "--combine", "@D/null"]),
        ),
        // --- onboard --combine's partials ---
        c(
            "onboard partial: --report onto it",
            Refused("input"),
            args(&[
                "onboard",
                "--combine",
                "@D/in/part.json",
                "--report",
                "@D/in/part.json",
            ]),
        ),
        c(
            "onboard partial: --report onto a hard link to it",
            Refused("input"),
            args(&[
                "onboard",
                "--combine",
                "@D/in/part.json",
                "--report",
                "@D/hard",
            ]),
        ),
        c(
            "onboard partial: --report onto its config's profile file",
            Refused("input"),
            args(&[
                "onboard",
                "--combine",
                "@D/in/part.json",
                "--report",
                "@D/in/profile.txt",
            ]),
        ),
        c(
            "onboard partial: a FIFO",
            Refused("is a FIFO"),
            args(&["onboard", "--combine", "@D/fifo"]),
        ),
        c(
            "onboard partial: a directory",
            Refused("is a directory"),
            args(&["onboard", "--combine", "@D/dir"]),
        ),
        c(
            "onboard partial: a character device",
            Refused("is a character device"),
            args(&["onboard", "--combine", "@D/null"]),
        ),
        // --- export-scc's raw file ---
        c(
            "export-scc raw file: OUT.nc onto it",
            Refused("input"),
            args(&["export-scc", "@D/in/raw.h5", "@D/in/raw.h5"]),
        ),
        c(
            "export-scc raw file: OUT.nc onto a link to it",
            Refused("input"),
            args(&["export-scc", "@D/in/raw.h5", "@D/link"]),
        ),
        c(
            "export-scc raw file: a FIFO",
            Refused("is a FIFO"),
            args(&["export-scc", "@D/fifo", "@D/out.nc"]),
        ),
        c(
            "export-scc raw file: a directory",
            Refused("is a directory"),
            args(&["export-scc", "@D/dir", "@D/out.nc"]),
        ),
        c(
            "export-scc raw file: a character device",
            Refused("is a character device"),
            args(&["export-scc", "@D/null", "@D/out.nc"]),
        ),
        // --- curtain's raw file ---
        c(
            "curtain raw file: --png onto it",
            Refused("input"),
            args(&["curtain", "@D/in/raw.h5", "--png", "@D/in/raw.h5"]),
        ),
        c(
            "curtain raw file: --png onto a hard link to it",
            Refused("input"),
            args(&["curtain", "@D/in/raw.h5", "--png", "@D/hard"]),
        ),
        c(
            "curtain raw file: a FIFO",
            Refused("is a FIFO"),
            args(&["curtain", "@D/fifo", "--png", "@D/c.png"]),
        ),
        c(
            "curtain raw file: a directory",
            Refused("is a directory"),
            args(&["curtain", "@D/dir", "--png", "@D/c.png"]),
        ),
        c(
            "curtain raw file: a character device",
            Refused("is a character device"),
            args(&["curtain", "@D/null", "--png", "@D/c.png"]),
        ),
        // --- merge's shards ---
        c(
            "merge shard: OUT.h5 onto a link to it",
            Refused("input"),
            args(&["merge", "@D/link", "@D/in/shard.h5"]),
        ),
        c(
            "merge shard: OUT.h5 onto its config's profile file",
            Refused("input"),
            args(&["merge", "@D/in/profile.txt", "@D/in/shard.h5"]),
        ),
        c(
            "merge shard: a FIFO",
            Refused("is a FIFO"),
            args(&["merge", "@D/out.h5", "@D/fifo"]),
        ),
        c(
            "merge shard: a character device",
            Refused("is a character device"),
            args(&["merge", "@D/out.h5", "@D/null"]),
        ),
    ]
}

/// Runs the binary in `dir` to make an input; panics (the case cannot be judged) if it fails.
fn make(dir: &Scratch, argv: &[&str]) {
    let out = Command::new(bin())
        .args(argv)
        .current_dir(&dir.0)
        .stdin(Stdio::null())
        .output()
        .expect("spawn lidarsim");
    assert!(
        out.status.success(),
        "making an input with lidarsim {argv:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The ground config with its profile file copied to `in/profile.txt`, written as
/// `in/cfg.toml` naming the profile as `profile_name` (relative to `in/`).
fn ground_config(dir: &Scratch, profile_name: &str) {
    let d = &dir.0;
    fs::copy(cfg("atmospheres/us76_1km.txt"), d.join("in/profile.txt")).unwrap();
    let text = fs::read_to_string(cfg("ground/profile_file_example.toml")).unwrap();
    assert!(text.contains("../atmospheres/us76_1km.txt"));
    let text = text.replace("../atmospheres/us76_1km.txt", profile_name);
    fs::write(d.join("in/cfg.toml"), text).unwrap();
}

/// Prepares the scratch directory of one of this topic's cases: `None` when the case
/// is not this topic's, `Some(false)` when its preparation is not possible here.
pub fn prepare(name: &str, dir: &Scratch) -> Option<bool> {
    let (prefix, variant) = name.split_once(": ")?;
    let kind = KINDS.iter().find(|(p, _)| *p == prefix)?.1;
    let d = &dir.0;
    // the special file given as the input, if that is the case
    let special = if variant.ends_with("a FIFO") {
        Some("fifo")
    } else if variant.ends_with("a directory") {
        Some("dir")
    } else if variant.ends_with("a character device") {
        Some("null")
    } else if variant.ends_with("a socket") {
        Some("sock")
    } else {
        None
    };
    match special {
        Some("fifo") => {
            let ok = Command::new("mkfifo")
                .arg(d.join("fifo"))
                .status()
                .is_ok_and(|s| s.success());
            if !ok {
                return Some(false);
            }
        }
        Some("dir") => fs::create_dir(d.join("dir")).unwrap(),
        Some("null") => {
            let ok = Command::new("mknod")
                .arg(d.join("null"))
                .args(["c", "1", "3"])
                .status()
                .is_ok_and(|s| s.success());
            if !ok {
                return Some(false);
            }
        }
        Some(_) => {
            let _listener = std::os::unix::net::UnixListener::bind(d.join("sock")).unwrap();
        }
        None => {}
    }
    // the input itself, and the files a config names
    let input = match kind {
        Kind::Config => {
            fs::copy(s1(), d.join("in/cfg.toml")).unwrap();
            "in/cfg.toml"
        }
        Kind::Profile => {
            let named = special.map_or("profile.txt".to_string(), |s| format!("../{s}"));
            ground_config(dir, &named);
            "in/profile.txt"
        }
        Kind::Scheme => {
            fs::write(d.join("in/scheme.toml"), SCHEME).unwrap();
            "in/scheme.toml"
        }
        Kind::Curtain => {
            fs::copy(
                cfg("atmospheres/curtain_example.h5"),
                d.join("in/curtain.h5"),
            )
            .unwrap();
            let text = fs::read_to_string(cfg("instruments/caliop_curtain.toml")).unwrap();
            assert!(text.contains("../atmospheres/curtain_example.h5"));
            let named = special.map_or("curtain.h5".to_string(), |s| format!("../{s}"));
            let text = text.replace("../atmospheres/curtain_example.h5", &named);
            fs::write(d.join("in/cfg.toml"), text).unwrap();
            "in/curtain.h5"
        }
        Kind::ValidatePartial => {
            ground_config(dir, "profile.txt");
            let c = dir.p("in/cfg.toml");
            let p = dir.p("in/part.json");
            let argv = ["validate", &c, "--realizations", "100", "--shard", "0/1"];
            make(dir, &[&argv[..], &["--partial", &p]].concat());
            "in/part.json"
        }
        Kind::OnboardPartial => {
            ground_config(dir, "profile.txt");
            let (c, o, p) = (
                dir.p("in/cfg.toml"),
                dir.p("in/p.h5"),
                dir.p("in/part.json"),
            );
            let argv = ["onboard", &c, "--set", "acquisition.profiles=2"];
            let more = [
                "--scheme",
                "none",
                "-o",
                &o,
                "--shard",
                "0/1",
                "--partial",
                &p,
            ];
            make(dir, &[&argv[..], &more[..]].concat());
            "in/part.json"
        }
        Kind::SccRaw => {
            let (c, r) = (cfg("ground/ground_532_overlap.toml"), dir.p("in/raw.h5"));
            make(dir, &["simulate", &c, "--profiles", "2", "-o", &r]);
            "in/raw.h5"
        }
        Kind::CurtainRaw => {
            let r = dir.p("in/raw.h5");
            make(dir, &["simulate", &s1(), "--profiles", "2", "-o", &r]);
            "in/raw.h5"
        }
        Kind::Shard => {
            ground_config(dir, "profile.txt");
            let (c, s) = (dir.p("in/cfg.toml"), dir.p("in/shard.h5"));
            let argv = [
                "simulate",
                &c,
                "--profiles",
                "2",
                "--shard",
                "0/1",
                "-o",
                &s,
            ];
            make(dir, &argv);
            "in/shard.h5"
        }
    };
    if variant.contains("onto a link to it") {
        std::os::unix::fs::symlink(d.join(input), d.join("link")).unwrap();
    }
    if variant.contains("onto a hard link to it") {
        fs::hard_link(d.join(input), d.join("hard")).unwrap();
    }
    assert!(Path::new(&d.join(input)).is_file(), "{name}: no {input}");
    Some(true)
}
