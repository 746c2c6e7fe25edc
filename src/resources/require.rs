//! The refusals before work starts: a run's memory against what the process can have
//! ([`MemoryLimits`]), a file's size against the free space of its file system.

use std::path::Path;

use super::human::human_bytes;
use super::limits::MemoryLimits;
use crate::error::{Error, Result};

/// Fraction of the available memory a run may plan to use.
pub const MEMORY_FRACTION: f64 = 0.8;

/// Refuses a run that would need more than [`MEMORY_FRACTION`] of the memory it can
/// have ([`MemoryLimits`]): "`what` needs about 12 GB of memory, 3.1 GB is available"
/// (or "is left under the address-space limit (ulimit -v)", "... the control group's
/// memory limit").
pub fn require_memory(what: &str, bytes: f64) -> Result<()> {
    check_memory(what, bytes, &MemoryLimits::of_this_process())
}

/// [`require_memory`] against given limits.
pub fn check_memory(what: &str, bytes: f64, limits: &MemoryLimits) -> Result<()> {
    let Some(avail) = limits.usable() else {
        return Ok(());
    };
    if !bytes.is_finite() || bytes > MEMORY_FRACTION * avail {
        let share = if bytes <= avail {
            format!(
                " (a run plans on at most {:.0} % of it)",
                MEMORY_FRACTION * 100.0
            )
        } else {
            String::new()
        };
        return Err(Error::Unsupported(format!(
            "{what} needs about {} of memory, {} is {}{share}; make the run smaller",
            human_bytes(bytes),
            human_bytes(avail),
            limits.binding()
        )));
    }
    Ok(())
}

/// Refuses to write `bytes` (an estimate) into the directory of `target` when its file
/// system has less free space: "OUT.h5: needs about 536 GB, 80 GB free on its file system".
pub fn require_disk(option: &str, target: &Path, bytes: f64) -> Result<()> {
    let dir = crate::safe_file::parent_dir(target);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::resources::alloc::try_vec;

    #[test]
    fn the_usable_memory_is_the_least_limit_and_the_message_names_it() {
        let gb = 1e9;
        let limits = MemoryLimits {
            system: Some(20.0 * gb),
            address_space: Some(3.0 * gb),
            cgroup: Some(5.0 * gb),
        };
        assert_eq!(limits.usable(), Some(3.0 * gb));
        // 0.8 × 3 GB = 2.4 GB may be planned
        assert!(check_memory("test", 2.39 * gb, &limits).is_ok());
        let e = check_memory("test", 2.41 * gb, &limits).unwrap_err();
        assert!(e.to_string().contains("ulimit -v"), "{e}");
        let cg = MemoryLimits {
            cgroup: Some(1.0 * gb),
            ..limits
        };
        let e = check_memory("test", 0.81 * gb, &cg).unwrap_err();
        assert!(e.to_string().contains("control group"), "{e}");
        let none = MemoryLimits::default();
        assert_eq!(none.usable(), None);
        assert!(check_memory("test", 1e30, &none).is_ok());
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
