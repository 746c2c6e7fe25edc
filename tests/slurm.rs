//! The real Slurm test: `tests/slurm/run_cluster_test.sh` starts a one-node Slurm
//! cluster (munged, slurmctld, slurmd from the distribution's packages), submits
//! `deploy/slurm/submit.sh`'s 4-task array jobs with their dependent merge and combine,
//! and checks the merged file and the combined verdict against single runs (docs/scale.md).
//!
//! It runs where `slurmctld` is installed and this is root; elsewhere it says plainly
//! that it is skipped (`common::skip`: recorded where `.ci/run` prints it) and passes,
//! unless `LIDARSIM_REQUIRE_SLURM=1` or `CI=true` (`.ci/run` installs Slurm there) makes
//! a skip a failure.

mod common;

use std::io::Write;
use std::path::Path;
use std::process::Command;

/// Whether `cmd` is an executable on PATH.
fn on_path(cmd: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join(cmd).is_file()))
}

/// Says why the test does not run, past the test harness's capture; fails instead when
/// the environment requires Slurm.
fn skip(why: &str) {
    let required = std::env::var("LIDARSIM_REQUIRE_SLURM").is_ok_and(|v| v == "1");
    assert!(
        !required,
        "slurm test cannot run ({why}) but LIDARSIM_REQUIRE_SLURM=1"
    );
    common::skip("slurm cluster test", why);
}

#[test]
fn array_jobs_and_their_dependent_merge_run_on_a_real_slurm_cluster() {
    if !on_path("slurmctld") {
        return skip(
            "slurmctld not installed (Debian: apt-get install slurmctld slurmd slurm-client munge)",
        );
    }
    let uid = Command::new("id").arg("-u").output().map(|o| o.stdout);
    if !uid.is_ok_and(|u| u == b"0\n") {
        return skip("not root (the test cluster's daemons run as root)");
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/slurm/run_cluster_test.sh");
    let o = Command::new("bash")
        .arg(&script)
        .arg(env!("CARGO_BIN_EXE_lidarsim"))
        .env_remove("SLURM_CONF")
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "the Slurm cluster test failed:\n{log}");
    assert!(log.contains("slurm cluster test: PASSED"), "{log}");
    // what ran, in the test's output
    let ran: String = log
        .lines()
        .filter(|l| l.starts_with("slurm cluster test:"))
        .map(|l| format!("{l}\n"))
        .collect();
    let _ = std::io::stderr().write_all(ran.as_bytes());
}
