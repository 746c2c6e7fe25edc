//! Sizes checked before work starts (interface.md: "Sizes ... are checked before work
//! starts: an impossible run is refused with its estimate, a long one announces its
//! estimate").
//!
//! Each command estimates the memory it will hold, the disk its files will take and the
//! time it will run, from its sizes (profiles, bins, realizations) and measured costs,
//! and calls [`require_memory`], [`require_disk`] and [`announce_duration`] before it
//! allocates or writes anything. Allocations sized by user input go through
//! [`try_vec`], so that an estimate that was too low still ends in a clear error, never
//! an allocation abort.

use std::path::Path;

use crate::error::{Error, Result};

/// Fraction of the available memory a run may plan to use.
pub const MEMORY_FRACTION: f64 = 0.8;
/// A run expected to take longer than this (s) says so before it starts.
pub const ANNOUNCE_AFTER_S: f64 = 60.0;

/// Memory the system can give without swapping (`MemAvailable` of `/proc/meminfo`), bytes;
/// `None` where that is unknown (then memory is not checked up front).
pub fn available_memory_bytes() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0)
}

/// Refuses a run that would need more than [`MEMORY_FRACTION`] of the available memory:
/// "`what` needs about 12 GB of memory, 3.1 GB is available".
pub fn require_memory(what: &str, bytes: f64) -> Result<()> {
    let Some(avail) = available_memory_bytes() else {
        return Ok(());
    };
    if !bytes.is_finite() || bytes > MEMORY_FRACTION * avail {
        return Err(Error::Unsupported(format!(
            "{what} needs about {} of memory, {} is available; make the run smaller",
            human_bytes(bytes),
            human_bytes(avail)
        )));
    }
    Ok(())
}

/// Refuses to write `bytes` (an estimate) into the directory of `target` when its file
/// system has less free space: "OUT.h5: needs about 536 GB, 80 GB free on its file system".
pub fn require_disk(option: &str, target: &Path, bytes: f64) -> Result<()> {
    let dir = crate::output::safe_file::parent_dir(target);
    let Ok(free) = fs4::available_space(dir) else {
        return Ok(());
    };
    let free = free as f64;
    if !bytes.is_finite() || bytes > free {
        return Err(Error::output(
            format!("{option} {}", target.display()),
            format!(
                "the file needs about {}, only {} is free on its file system; \
                 write fewer profiles or elsewhere",
                human_bytes(bytes),
                human_bytes(free)
            ),
        ));
    }
    Ok(())
}

/// Says on stderr how long a run is expected to take when that is more than a minute.
pub fn announce_duration(what: &str, seconds: f64) {
    if seconds > ANNOUNCE_AFTER_S {
        eprintln!(
            "lidarsim: {what}: expected to take about {} (estimate)",
            human_duration(seconds)
        );
    }
}

/// A vector of `n` copies of `value`, or a clear error naming `what` where the memory
/// cannot be had (never an allocation abort).
pub fn try_vec<T: Clone>(what: &str, n: usize, value: T) -> Result<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| {
        Error::Unsupported(format!(
            "{what} needs about {} of memory, which cannot be allocated",
            human_bytes(n as f64 * std::mem::size_of::<T>() as f64)
        ))
    })?;
    v.resize(n, value);
    Ok(v)
}

/// Bytes for a person: "512 B", "3.4 kB", "12 GB", "1.2e6 TB" (SI prefixes).
pub fn human_bytes(bytes: f64) -> String {
    if !bytes.is_finite() {
        return "an unbounded amount".into();
    }
    const UNITS: [&str; 5] = ["B", "kB", "MB", "GB", "TB"];
    let mut v = bytes;
    let mut u = 0;
    while v >= 1000.0 && u + 1 < UNITS.len() {
        v /= 1000.0;
        u += 1;
    }
    if v >= 1e4 {
        format!("{v:.1e} {}", UNITS[u])
    } else if u == 0 || v >= 100.0 {
        format!("{v:.0} {}", UNITS[u])
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

/// A duration for a person: "45 s", "12 min", "3.5 h", "41 days", "2.3e4 years".
pub fn human_duration(seconds: f64) -> String {
    if !seconds.is_finite() {
        return "forever".into();
    }
    let s = seconds.max(0.0);
    if s < 90.0 {
        format!("{s:.0} s")
    } else if s < 5400.0 {
        format!("{:.0} min", s / 60.0)
    } else if s < 2.0 * 86400.0 {
        format!("{:.1} h", s / 3600.0)
    } else if s < 365.25 * 86400.0 {
        format!("{:.0} days", s / 86400.0)
    } else {
        let y = s / (365.25 * 86400.0);
        if y < 1e4 {
            format!("{y:.0} years")
        } else {
            format!("{y:.1e} years")
        }
    }
}

/// Entropy of a Poisson(μ) count, bits: exact sum over the PMF below μ = 50, the
/// normal-limit `½·log2(2πeμ)` with its `1/(12μ)`-order correction above.
pub fn poisson_entropy_bits(mu: f64) -> f64 {
    if mu.is_nan() || mu <= 0.0 {
        return 0.0;
    }
    if mu >= 50.0 {
        let e = std::f64::consts::E;
        return 0.5 * (2.0 * std::f64::consts::PI * e * mu).log2()
            - 1.0 / (12.0 * mu * std::f64::consts::LN_2);
    }
    let mut p = (-mu).exp();
    let mut h = 0.0;
    let kmax = (mu + 12.0 * mu.sqrt() + 30.0) as u64;
    for k in 0..=kmax {
        if p > 0.0 {
            h -= p * p.log2();
        }
        p *= mu / (k + 1) as f64;
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_durations_read_at_a_glance() {
        assert_eq!(human_bytes(512.0), "512 B");
        assert_eq!(human_bytes(3.4e9), "3.4 GB");
        assert_eq!(human_bytes(5.36e11), "536 GB");
        assert_eq!(human_bytes(1e20), "1.0e8 TB");
        assert_eq!(human_duration(30.0), "30 s");
        assert_eq!(human_duration(720.0), "12 min");
        assert_eq!(human_duration(3.5 * 3600.0), "3.5 h");
        assert_eq!(human_duration(1e12), "3.2e4 years");
    }

    #[test]
    fn poisson_entropy_matches_known_values() {
        // H(Poisson(1)) = 1.8825 bits (direct sum); continuity at the switch
        assert!((poisson_entropy_bits(1.0) - 1.882_5).abs() < 1e-3);
        let (a, b) = (poisson_entropy_bits(49.999), poisson_entropy_bits(50.0));
        assert!((a - b).abs() < 1e-3, "{a} {b}");
        assert_eq!(poisson_entropy_bits(0.0), 0.0);
        assert!(poisson_entropy_bits(1e15).is_finite());
    }

    #[test]
    fn impossible_requests_are_errors_not_aborts() {
        assert!(try_vec("test", usize::MAX / 2, 0u64).is_err());
        assert!(require_memory("test", 1e30).is_err());
        assert!(require_memory("test", f64::INFINITY).is_err());
        let e = require_disk("-o", Path::new("/tmp/x.h5"), 1e30).unwrap_err();
        assert!(e.to_string().contains("free"), "{e}");
    }
}
