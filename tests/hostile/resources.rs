//! Memory limits (RLIMIT_AS, cgroups) and signals during the commit (issue 18, items 4 and 5).
//!
//! The memory cases run under an address-space limit (`ulimit -v`, set with
//! `setrlimit(RLIMIT_AS)` before exec): each must be refused up front with the estimate
//! and the limit it meets, one line, exit 2, an existing output untouched. Sizes: the
//! scenario 1 window (0-100 km) with `instrument.bin_width_s = 1e-10` is 6,671,282 bins
//! (refused at the model, 1,100 B per bin), with `1e-9` 667,129 bins (the model fits under
//! the limits below; the command's own estimate does not). The limits sit inside the
//! window where only the case's own check refuses, as measured with one malloc heap
//! (`resources::one_heap_under_an_address_space_limit`): validate's sums refuse from the
//! model's fit (~720,000 KiB) to ~1,100,000 KiB, the onboard draw from there to
//! ~1,400,000 KiB.
//!
//! [`a_signal_at_the_end_of_a_run_leaves_old_or_new_outputs`] sends signals around the
//! end of short `simulate` and `onboard` runs, across the commit.

use std::collections::BTreeMap;
use std::fs;
use std::os::unix::process::ExitStatusExt;
use std::path::Path;
use std::time::Instant;

use super::{Case, Run, Scratch, Want, spawn, wait};

const KIB: u64 = 1024;

/// `args` under an address-space limit of `kib` KiB (`ulimit -v kib`).
fn limited(kib: u64, v: &[&str]) -> Run {
    Run::AddressSpaceLimit(kib * KIB, v.iter().map(|s| s.to_string()).collect())
}

/// This topic's cases, run after the older ones.
pub fn cases() -> Vec<Case> {
    use Want::*;
    let c = |name, want, run| Case {
        name,
        want,
        env: vec![],
        run,
    };
    let huge = ["--set", "instrument.bin_width_s=1e-10"];
    let large = ["--set", "instrument.bin_width_s=1e-9"];
    let with = |a: &[&'static str], b: &[&'static str]| -> Vec<&'static str> {
        a.iter().chain(b).copied().collect()
    };
    vec![
        c(
            "validate of 6.7e6 bins under ulimit -v 4000000",
            Refused("ulimit -v"),
            limited(
                4_000_000,
                &with(&["validate", "@S1", "--realizations", "100"], &huge),
            ),
        ),
        c(
            "simulate of 6.7e6 bins under ulimit -v 4000000",
            Refused("ulimit -v"),
            limited(
                4_000_000,
                &with(
                    &["simulate", "@S1", "-o", "@D/out.h5", "--profiles", "3"],
                    &huge,
                ),
            ),
        ),
        c(
            "validate of 6.7e5 bins: model fits, sums do not",
            Refused("validating 667129 bins"),
            limited(
                900_000,
                &with(&["validate", "@S1", "--realizations", "100"], &large),
            ),
        ),
        c(
            "simulate of 6.7e5 bins: model fits, draw does not",
            Refused("simulating 20 profiles"),
            limited(
                1_270_000,
                &with(
                    &["simulate", "@S1", "-o", "@D/out.h5", "--profiles", "20"],
                    &large,
                ),
            ),
        ),
        c(
            "onboard of 6.7e5 bins under ulimit -v",
            Refused("onboard draw"),
            limited(
                1_200_000,
                &with(
                    &[
                        "onboard",
                        "@S1",
                        "--scheme",
                        "uniform:10",
                        "-o",
                        "@D/out.h5",
                        "--raw",
                        "@D/raw.h5",
                    ],
                    &large,
                ),
            ),
        ),
        c(
            "sweep of 6.7e5 bins under ulimit -v",
            Refused("sweeping 3 points"),
            limited(
                1_050_000,
                &with(
                    &[
                        "sweep",
                        "@S1",
                        "--vary",
                        "instrument.pulse_energy_j=0.1..1:3",
                        "--metric",
                        "snr_at:5km",
                        "--csv",
                        "@D/out.csv",
                    ],
                    &large,
                ),
            ),
        ),
    ]
}

/// Prepares the scratch directory of one of this topic's cases: `None` when the case
/// is not this topic's, `Some(false)` when its preparation is not possible here.
pub fn prepare(name: &str, dir: &Scratch) -> Option<bool> {
    let old = |rel: &str| fs::write(dir.0.join(rel), "old output, must survive").unwrap();
    match name {
        "simulate of 6.7e6 bins under ulimit -v 4000000"
        | "simulate of 6.7e5 bins: model fits, draw does not" => old("out.h5"),
        "onboard of 6.7e5 bins under ulimit -v" => {
            old("out.h5");
            old("raw.h5");
        }
        "sweep of 6.7e5 bins under ulimit -v" => old("out.csv"),
        "validate of 6.7e6 bins under ulimit -v 4000000"
        | "validate of 6.7e5 bins: model fits, sums do not" => {}
        _ => return None,
    }
    Some(true)
}

/// The files of a directory (names and contents), the captured stdout/stderr aside.
fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fs::read_dir(dir)
        .unwrap()
        .flatten()
        .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
        .map(|e| {
            (
                e.file_name().to_string_lossy().into_owned(),
                fs::read(e.path()).unwrap(),
            )
        })
        .collect()
}

/// One command of the signal storm: its arguments and output files (in the scratch dir).
struct Storm {
    name: &'static str,
    args: &'static [&'static str],
    outputs: &'static [&'static str],
    tries: usize,
}

/// How one try ended.
#[derive(Debug, Default)]
struct Tally {
    completed: usize,
    interrupted_old: usize,
    interrupted_new: usize,
    before_handlers: usize,
}

/// Same seed and date, same bytes (the storm compares outputs with a reference run).
const ENV: &[(&str, &str)] = &[("SOURCE_DATE_EPOCH", "1700000000")];

/// Runs `storm` once to completion in `dir` (the reference outputs and the run's wall
/// time), then `storm.tries` times with the old outputs in place and SIGINT, SIGTERM or
/// SIGHUP sent after a delay spread from 40 % to 110 % of that time (the commit is at
/// the end). Every try must end in one of: exit 0 and every output new; exit 128 + sig,
/// every output old (byte for byte) and a last line saying it was interrupted (not that
/// the outputs are complete); exit 128 + sig, every output new and a last line saying
/// they are complete; or, for a signal before the handlers are installed, killed by it
/// with every output old. Never any other file in the directory.
fn storm(s: &Storm, tally: &mut Tally) -> Vec<String> {
    let dir = Scratch::new("storm", 0);
    let args: Vec<String> = s.args.iter().map(|a| a.to_string()).collect();
    let start = Instant::now();
    let (mut child, out, err) = spawn(&dir, &args, ENV, None);
    let (st, hung) = wait(&mut child);
    let took = start.elapsed();
    let _ = (fs::remove_file(&out), fs::remove_file(&err));
    assert!(
        !hung && st.is_some_and(|s| s.success()),
        "{}: the reference run failed",
        s.name
    );
    let new = files(&dir.0);
    let names: Vec<&str> = new.keys().map(String::as_str).collect();
    assert_eq!(names, s.outputs, "{}: the reference run's files", s.name);
    let old: BTreeMap<String, Vec<u8>> = s
        .outputs
        .iter()
        .map(|n| (n.to_string(), format!("old {n}\n").into_bytes()))
        .collect();
    let mut failures = Vec::new();
    for i in 0..s.tries {
        for (n, b) in &old {
            fs::write(dir.0.join(n), b).unwrap();
        }
        let sig = [libc::SIGINT, libc::SIGTERM, libc::SIGHUP][i % 3];
        let delay = took.mul_f64(0.4 + 0.7 * i as f64 / (s.tries - 1) as f64);
        let (mut child, out, err) = spawn(&dir, &args, ENV, None);
        std::thread::sleep(delay);
        // SAFETY: a signal to our own child, not yet reaped (its pid is not reused)
        unsafe { libc::kill(child.id() as i32, sig) };
        let (st, hung) = wait(&mut child);
        let stderr = fs::read_to_string(&err).unwrap_or_default();
        let _ = (fs::remove_file(&out), fs::remove_file(&err));
        let last = stderr.lines().rev().find(|l| !l.trim().is_empty());
        let last = last.unwrap_or("").to_string();
        let now = files(&dir.0);
        let what = format!(
            "{} try {i} (signal {sig} after {delay:?}): {st:?}, `{last}`, files {:?}",
            s.name,
            now.keys().collect::<Vec<_>>()
        );
        let (is_old, is_new) = (now == old, now == new);
        let code = st.and_then(|s| s.code());
        let ok = if hung || stderr.contains("panicked") {
            false
        } else if code == Some(0) {
            tally.completed += 1;
            is_new && !stderr.contains("interrupted")
        } else if code == Some(128 + sig) && last.contains("interrupted") {
            if last.contains("complete") {
                tally.interrupted_new += 1;
                is_new
            } else {
                tally.interrupted_old += 1;
                is_old
            }
        } else if st.and_then(|s| s.signal()) == Some(sig) {
            tally.before_handlers += 1;
            is_old
        } else {
            false
        };
        if !ok {
            failures.push(what);
        }
    }
    failures
}

#[test]
fn a_signal_at_the_end_of_a_run_leaves_old_or_new_outputs() {
    // one at a time with the case tables: the machine's two cores and HDF5's locks
    let _one = crate::ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let runs = [
        Storm {
            name: "simulate",
            args: &["simulate", "@S1", "-o", "@D/out.h5", "--profiles", "100"],
            outputs: &["out.h5"],
            tries: 30,
        },
        Storm {
            name: "onboard",
            args: &[
                "onboard",
                "@S1",
                "--scheme",
                "uniform:10",
                "-o",
                "@D/product.h5",
                "--raw",
                "@D/raw.h5",
                "--report",
                "@D/report.csv",
            ],
            outputs: &["product.h5", "raw.h5", "report.csv"],
            tries: 30,
        },
    ];
    let mut failures = Vec::new();
    let mut tally = Tally::default();
    for s in &runs {
        failures.extend(storm(s, &mut tally));
    }
    eprintln!("signal storm: {tally:?}");
    assert!(
        failures.is_empty(),
        "{} tries went wrong:\n{}",
        failures.len(),
        failures.join("\n")
    );
    // the storm must have interrupted runs, else it tested nothing
    assert!(
        tally.interrupted_old + tally.interrupted_new > 0,
        "no try was interrupted: {tally:?}"
    );
}
