//! Sizes checked before work starts (docs/outputs.md: "Sizes ... are checked before work
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

/// Address space kept free for what a run maps besides its estimated data (HDF5's and
/// the allocator's small mappings, the output's buffers). glibc's per-thread arenas
/// reserve 64 MiB each; under such a limit there are none
/// ([`one_heap_under_an_address_space_limit`]), so they are not counted: a 334-bin
/// `simulate` runs under `ulimit -v 50000` (measured).
pub const ADDRESS_SPACE_MARGIN_BYTES: f64 = 16.0 * 1048576.0;
/// Address space per thread of the process (rayon's pool, the signal watcher, the
/// writer): its stack (2 MiB by default) and guard page, rounded up, bytes.
pub const ADDRESS_SPACE_PER_THREAD_BYTES: f64 = 4.0 * 1048576.0;

/// Under an address-space limit (`RLIMIT_AS`, `ulimit -v`), makes every thread allocate
/// from glibc's main heap (`mallopt(M_ARENA_MAX, 1)`), so that the up-front memory
/// check holds: a worker thread's own arena reserves 64 MiB of address space when it is
/// first used, after the check (measured: `expect` of 133,426 bins, estimated 175 MB,
/// refused or run at will under `ulimit -v 350000` until then, sometimes dying "out of
/// memory" partway). Without such a limit nothing changes. Call it once, first thing
/// in `main`, before any thread is started.
pub fn one_heap_under_an_address_space_limit() {
    let limited = std::fs::read_to_string("/proc/self/limits")
        .ok()
        .and_then(|t| parse_address_space_limit(&t))
        .is_some();
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    if limited {
        // SAFETY: mallopt only sets an allocator parameter; no thread runs yet.
        unsafe {
            libc::mallopt(libc::M_ARENA_MAX, 1);
        }
    }
    let _ = limited;
}

/// The limits on the memory this process may still take, bytes (`None`: no such limit
/// or not known).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MemoryLimits {
    /// `MemAvailable` of `/proc/meminfo`: what the system can give without swapping.
    pub system: Option<f64>,
    /// The address-space limit (`RLIMIT_AS`, `ulimit -v`) less the address space already
    /// mapped (`VmSize`) and [`ADDRESS_SPACE_MARGIN_BYTES`] plus a thread stack per
    /// worker thread.
    pub address_space: Option<f64>,
    /// The tightest control group on the way to the root: its limit less its usage
    /// (cgroup v2 `memory.max` − `memory.current`, v1 `memory.limit_in_bytes` −
    /// `memory.usage_in_bytes`).
    pub cgroup: Option<f64>,
}

impl MemoryLimits {
    /// The limits of this process now.
    pub fn of_this_process() -> MemoryLimits {
        let read = |p: &str| std::fs::read_to_string(p).ok();
        let address_space = read("/proc/self/limits")
            .and_then(|t| parse_address_space_limit(&t))
            .and_then(|limit| {
                let mapped = read("/proc/self/status").and_then(|t| parse_vm_size(&t))?;
                let threads = rayon::current_num_threads() as f64 + 2.0;
                let margin = ADDRESS_SPACE_MARGIN_BYTES + threads * ADDRESS_SPACE_PER_THREAD_BYTES;
                Some((limit - mapped - margin).max(0.0))
            });
        MemoryLimits {
            system: read("/proc/meminfo").and_then(|t| parse_mem_available(&t)),
            address_space,
            cgroup: cgroup_memory_left(),
        }
    }

    /// The memory that can be had: the least of the known limits.
    pub fn usable(&self) -> Option<f64> {
        [self.system, self.address_space, self.cgroup]
            .into_iter()
            .flatten()
            .reduce(f64::min)
    }

    /// Which limit [`usable`](Self::usable) is, for messages: "available", "left under
    /// the address-space limit (ulimit -v)", "left in the control group's memory limit".
    fn binding(&self) -> &'static str {
        let u = self.usable();
        if u.is_some() && u == self.address_space {
            "left under the address-space limit (ulimit -v)"
        } else if u.is_some() && u == self.cgroup {
            "left under the control group's memory limit"
        } else {
            "available"
        }
    }
}

/// Memory this process can still take, bytes: the least of `MemAvailable`, the
/// address-space limit less the address space already mapped, and the control group's
/// limit less its usage ([`MemoryLimits`]); `None` where none is known (then memory is
/// not checked up front).
pub fn available_memory_bytes() -> Option<f64> {
    MemoryLimits::of_this_process().usable()
}

/// `MemAvailable` of a `/proc/meminfo` text, bytes.
pub fn parse_mem_available(meminfo: &str) -> Option<f64> {
    kib_field(meminfo, "MemAvailable:")
}

/// `VmSize` (address space mapped) of a `/proc/self/status` text, bytes.
pub fn parse_vm_size(status: &str) -> Option<f64> {
    kib_field(status, "VmSize:")
}

fn kib_field(text: &str, key: &str) -> Option<f64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0)
}

/// The soft address-space limit of a `/proc/self/limits` text (the row
/// `Max address space  SOFT  HARD  bytes`), bytes; `None` when unlimited.
pub fn parse_address_space_limit(limits: &str) -> Option<f64> {
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    let soft = line["Max address space".len()..]
        .split_whitespace()
        .next()?;
    parse_limit_value(soft)
}

/// A limit as the kernel writes it: a number of bytes, or `max` / `unlimited` (none);
/// cgroup v1 writes "no limit" as a huge number (`9223372036854771712`), also none.
pub fn parse_limit_value(text: &str) -> Option<f64> {
    let t = text.trim();
    if t == "max" || t == "unlimited" {
        return None;
    }
    let v: u64 = t.parse().ok()?;
    // v1's "no limit" is PAGE_COUNTER_MAX × page size, near i64::MAX
    (v < 1 << 62).then_some(v as f64)
}

/// The memory control group of a `/proc/self/cgroup` text: the path of the v1 `memory`
/// hierarchy if there is one, else the v2 path (`0::PATH`); with whether it is v2.
pub fn parse_memory_cgroup(proc_cgroup: &str) -> Option<(String, bool)> {
    let mut v2 = None;
    for line in proc_cgroup.lines() {
        let mut parts = line.splitn(3, ':');
        let (id, controllers, path) = (parts.next()?, parts.next()?, parts.next()?);
        if controllers.split(',').any(|c| c == "memory") {
            return Some((path.to_string(), false));
        }
        if id == "0" && controllers.is_empty() {
            v2 = Some((path.to_string(), true));
        }
    }
    v2
}

/// Where a cgroup file system is mounted, from `/proc/self/mountinfo`: (mount point,
/// root of the mount within the hierarchy) of the v2 file system (`v2`) or of the v1
/// hierarchy holding the `memory` controller.
pub fn parse_cgroup_mount(mountinfo: &str, v2: bool) -> Option<(String, String)> {
    mountinfo.lines().find_map(|line| {
        let (left, right) = line.split_once(" - ")?;
        let f: Vec<&str> = left.split_whitespace().collect();
        let r: Vec<&str> = right.split_whitespace().collect();
        let (root, point) = (*f.get(3)?, *f.get(4)?);
        let ok = match (v2, *r.first()?) {
            (true, "cgroup2") => true,
            (false, "cgroup") => r.get(2)?.split(',').any(|o| o == "memory"),
            _ => false,
        };
        ok.then(|| (point.to_string(), root.to_string()))
    })
}

/// Memory left in this process's control group and every group above it (the least
/// of limit − usage), bytes; `None` when no group on the way has a limit.
fn cgroup_memory_left() -> Option<f64> {
    let (path, v2) = parse_memory_cgroup(&std::fs::read_to_string("/proc/self/cgroup").ok()?)?;
    let (point, root) =
        parse_cgroup_mount(&std::fs::read_to_string("/proc/self/mountinfo").ok()?, v2)?;
    cgroup_memory_left_at(Path::new(&point), &root, &path, v2)
}

/// [`cgroup_memory_left`] for the group `path` of a hierarchy mounted at `point` from
/// its `root`: the least of limit − usage over the group and its parents up to `point`.
fn cgroup_memory_left_at(point: &Path, root: &str, path: &str, v2: bool) -> Option<f64> {
    // the path is relative to the hierarchy's root; the mount shows it from `root`
    let rel = path
        .strip_prefix(root.trim_end_matches('/'))
        .unwrap_or(path);
    let mut dir = point.join(rel.trim_start_matches('/'));
    let (limit_file, usage_file) = if v2 {
        ("memory.max", "memory.current")
    } else {
        ("memory.limit_in_bytes", "memory.usage_in_bytes")
    };
    let mut least: Option<f64> = None;
    loop {
        let read = |f: &str| std::fs::read_to_string(dir.join(f)).ok();
        if let Some(left) = read(limit_file).and_then(|l| {
            let limit = parse_limit_value(&l)?;
            let used = read(usage_file).and_then(|u| u.trim().parse::<f64>().ok())?;
            Some((limit - used).max(0.0))
        }) {
            least = Some(least.map_or(left, |l| l.min(left)));
        }
        if dir == point || !dir.pop() || !dir.starts_with(point) {
            break;
        }
    }
    least
}

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

/// Says how long a run is expected to take when that is more than a minute: on stderr,
/// or kept for the caller once [`keep_duration_notices`] was called (the Python module,
/// which prints nothing and gives them as warnings, [`take_duration_notices`]).
pub fn announce_duration(what: &str, seconds: f64) {
    if let Some(notice) = duration_notice(what, seconds) {
        match KEPT_NOTICES.lock().as_deref_mut() {
            Ok(Some(kept)) => kept.push(notice),
            _ => eprintln!("{notice}"),
        }
    }
}

/// The line [`announce_duration`] gives for a run of `what` expected to take `seconds`:
/// "lidarsim: WHAT: expected to take about 7 min (estimate)"; none at a minute or less.
pub fn duration_notice(what: &str, seconds: f64) -> Option<String> {
    (seconds > ANNOUNCE_AFTER_S).then(|| {
        format!(
            "lidarsim: {what}: expected to take about {} (estimate)",
            human_duration(seconds)
        )
    })
}

/// Duration notices kept for the caller instead of printed (`None`: printed on stderr).
static KEPT_NOTICES: std::sync::Mutex<Option<Vec<String>>> = std::sync::Mutex::new(None);

/// From now on this process keeps its duration notices for [`take_duration_notices`]
/// instead of printing them (a library that prints nothing: the Python module).
pub fn keep_duration_notices() {
    if let Ok(mut kept) = KEPT_NOTICES.lock() {
        kept.get_or_insert_with(Vec::new);
    }
}

/// The duration notices kept since the last call (empty when they are printed).
pub fn take_duration_notices() -> Vec<String> {
    KEPT_NOTICES
        .lock()
        .ok()
        .and_then(|mut kept| kept.as_mut().map(std::mem::take))
        .unwrap_or_default()
}

/// Cost of one afterpulse drawn (`detector::afterpulse`: its component, delay and bin),
/// ns, for the duration a run announces. Measured on 2026-12-01 (one thread, the machine
/// shared with two builds): `lidarsim simulate configs/ground/mpl_like.toml --profiles 1
/// --threads 1 --set instrument.detector.afterpulsing.probability=P`: drawing 14.0 s at
/// P = 5e-3 and 20.75 s at P = 0.5, whose 2.25e7 more counts are afterpulses: 300 ns each.
pub const AFTERPULSE_NS: f64 = 300.0;

/// Cost of drawing the afterpulses of one shot whose recorded counts sum to
/// `recorded_per_shot`, with afterpulse probability `probability`, ns: `p·R` afterpulses
/// at [`AFTERPULSE_NS`] each.
pub fn afterpulse_ns_per_shot(probability: f64, recorded_per_shot: f64) -> f64 {
    probability * recorded_per_shot * AFTERPULSE_NS
}

/// A vector of `n` copies of `value`, or a clear error naming `what` where the memory
/// cannot be had (never an allocation abort).
pub fn try_vec<T: Clone>(what: &str, n: usize, value: T) -> Result<Vec<T>> {
    let mut v = try_with_capacity(what, n)?;
    v.resize(n, value);
    Ok(v)
}

/// An empty vector with room for `n` elements (none written yet: its pages are touched
/// as it fills), or a clear error naming `what` where the memory cannot be had.
pub fn try_with_capacity<T>(what: &str, n: usize) -> Result<Vec<T>> {
    let mut v = Vec::new();
    let reserved = {
        let _fallible = FallibleAllocation::begin();
        v.try_reserve_exact(n)
    };
    reserved.map_err(|_| {
        Error::Unsupported(format!(
            "{what} needs about {} of memory, which cannot be allocated",
            human_bytes(n as f64 * std::mem::size_of::<T>() as f64)
        ))
    })?;
    Ok(v)
}

std::thread_local! {
    /// Whether this thread is in a fallible allocation ([`try_vec`]), where a failure is
    /// returned to the caller instead of ending the run.
    static FALLIBLE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Marks the current thread's allocations as fallible while it lives.
struct FallibleAllocation(bool);

impl FallibleAllocation {
    fn begin() -> FallibleAllocation {
        FallibleAllocation(FALLIBLE.with(|f| f.replace(true)))
    }
}

impl Drop for FallibleAllocation {
    fn drop(&mut self) {
        FALLIBLE.with(|f| f.set(self.0));
    }
}

/// The allocator of the `lidarsim` binary: the system's, except that an allocation the
/// system refuses (the memory limits of [`MemoryLimits`] reached although the estimate
/// checked before the work fitted) ends the run like any refusal, with one line on
/// stderr, its temporary and lock files deleted and exit status 2, instead of Rust's
/// allocation abort (signal 6, files left behind). Allocations made through
/// [`try_vec`] still fail back to their caller.
pub struct NoAbortAllocator;

// SAFETY: every call is forwarded to `System` unchanged; only a null result is acted on.
unsafe impl std::alloc::GlobalAlloc for NoAbortAllocator {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: forwarded with the caller's guarantees.
        checked(unsafe { std::alloc::System.alloc(layout) }, layout.size())
    }
    unsafe fn alloc_zeroed(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: forwarded with the caller's guarantees.
        checked(
            unsafe { std::alloc::System.alloc_zeroed(layout) },
            layout.size(),
        )
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        // SAFETY: forwarded with the caller's guarantees.
        unsafe { std::alloc::System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, new_size: usize) -> *mut u8 {
        // SAFETY: forwarded with the caller's guarantees.
        checked(
            unsafe { std::alloc::System.realloc(ptr, layout, new_size) },
            new_size,
        )
    }
}

/// `ptr`, unless it is null outside a fallible allocation: then the run ends (exit 2).
fn checked(ptr: *mut u8, size: usize) -> *mut u8 {
    if ptr.is_null() && !FALLIBLE.with(|f| f.get()) {
        out_of_memory(size);
    }
    ptr
}

/// Ends the run after an allocation of `size` bytes failed: one line (formatted without
/// allocating), the process's temporary and lock files deleted, exit status 2 without
/// exit handlers (as a signal ends it).
fn out_of_memory(size: usize) -> ! {
    let removed = crate::safe_file::remove_files_for_exit();
    let what = if removed {
        "; partial output removed"
    } else {
        ""
    };
    eprintln!(
        "lidarsim: error: out of memory: {size} more bytes could not be had (the run needs \
         more than its estimate, a limit such as ulimit -v or a control group's was reached); \
         make the run smaller{what}"
    );
    signal_hook::low_level::exit(2)
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

    /// The afterpulse cost model against the measurement it was made from (the constants
    /// of [`AFTERPULSE_NS`]'s comment): MPL-like at p = 0.5, 150,000 shots of 304 recorded
    /// counts (4.56e7 a profile at p = 5e-3) took 6.74 s more to draw: within 10 %, and a
    /// 10-profile run on two threads is announced (over a minute with the 14 s a profile
    /// of the rest of the draw).
    #[test]
    fn the_afterpulse_cost_model_matches_its_measurement() {
        let per_shot = 4.5624e7 / 150_000.0;
        let s = afterpulse_ns_per_shot(0.5, per_shot) * 150_000.0 * 1e-9;
        assert!((s / 6.74 - 1.0).abs() < 0.1, "{s} s");
        let run_s = 10.0 * (14.0 + s) / 2.0;
        assert!(duration_notice("run", run_s).is_some());
        assert!(duration_notice("run", 59.0).is_none());
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

    const LIMITS: &str = "\
Limit                     Soft Limit           Hard Limit           Units
Max cpu time              unlimited            unlimited            seconds
Max address space         4096000000           unlimited            bytes
Max file locks            unlimited            unlimited            locks
";

    #[test]
    fn the_address_space_limit_is_read_from_proc_limits() {
        assert_eq!(parse_address_space_limit(LIMITS), Some(4_096_000_000.0));
        let unlimited = LIMITS.replace("4096000000          ", "unlimited           ");
        assert_eq!(parse_address_space_limit(&unlimited), None);
        let status = "Name:\tlidarsim\nVmPeak:\t  282044 kB\nVmSize:\t  150000 kB\n";
        assert_eq!(parse_vm_size(status), Some(150_000.0 * 1024.0));
        let meminfo = "MemTotal:       32000000 kB\nMemAvailable:   22683992 kB\n";
        assert_eq!(parse_mem_available(meminfo), Some(22_683_992.0 * 1024.0));
    }

    #[test]
    fn limit_values_max_unlimited_and_v1_no_limit_are_none() {
        assert_eq!(parse_limit_value("max\n"), None);
        assert_eq!(parse_limit_value("unlimited"), None);
        // cgroup v1 writes "no limit" as PAGE_COUNTER_MAX pages of 4 KiB
        assert_eq!(parse_limit_value("9223372036854771712\n"), None);
        assert_eq!(parse_limit_value("536870912\n"), Some(536_870_912.0));
        assert_eq!(parse_limit_value("garbage"), None);
    }

    #[test]
    fn the_memory_cgroup_is_found_in_v1_and_v2_formats() {
        // v2 only (unified hierarchy)
        let v2 = "0::/user.slice/user-1000.slice/session-2.scope\n";
        assert_eq!(
            parse_memory_cgroup(v2),
            Some(("/user.slice/user-1000.slice/session-2.scope".into(), true))
        );
        // v1 with the memory controller (and a v2 line, as hybrid systems write)
        let hybrid = "9:name=systemd:/\n4:memory:/process_api/02cb\n2:cpu,cpuacct:/\n0::/\n";
        assert_eq!(
            parse_memory_cgroup(hybrid),
            Some(("/process_api/02cb".into(), false))
        );
        let joined = "5:cpuacct,memory:/docker/abc\n";
        assert_eq!(
            parse_memory_cgroup(joined),
            Some(("/docker/abc".into(), false))
        );
        assert_eq!(parse_memory_cgroup("3:cpu:/\n"), None);
        let mountinfo = "\
31 23 0:28 / /sys/fs/cgroup rw,relatime - tmpfs tmpfs rw,mode=755
32 31 0:29 / /sys/fs/cgroup/cpu rw,relatime - cgroup cgroup rw,cpu
35 31 0:32 /docker/abc /sys/fs/cgroup/memory rw,relatime - cgroup cgroup rw,memory
41 31 0:38 / /sys/fs/cgroup/unified rw,relatime - cgroup2 cgroup2 rw
";
        assert_eq!(
            parse_cgroup_mount(mountinfo, false),
            Some(("/sys/fs/cgroup/memory".into(), "/docker/abc".into()))
        );
        assert_eq!(
            parse_cgroup_mount(mountinfo, true),
            Some(("/sys/fs/cgroup/unified".into(), "/".into()))
        );
    }

    #[test]
    fn the_tightest_group_on_the_way_to_the_root_counts() {
        let top = std::env::temp_dir().join(format!("lidarsim-cgroup-{}", std::process::id()));
        let leaf = top.join("a/b");
        std::fs::create_dir_all(&leaf).unwrap();
        let put = |dir: &Path, f: &str, v: &str| std::fs::write(dir.join(f), v).unwrap();
        // v2: the leaf has no limit, its parent 1 GiB with 400 MiB used, the root none
        put(&leaf, "memory.max", "max\n");
        put(&leaf, "memory.current", "100\n");
        put(&top.join("a"), "memory.max", "1073741824\n");
        put(&top.join("a"), "memory.current", "419430400\n");
        let left = cgroup_memory_left_at(&top, "/", "/a/b", true);
        assert_eq!(left, Some((1024.0 - 400.0) * 1048576.0));
        // the mount's root is the group's parent (a cgroup namespace): same files
        let left = cgroup_memory_left_at(&top.join("a"), "/a", "/a/b", true);
        assert_eq!(left, Some((1024.0 - 400.0) * 1048576.0));
        // v1: the leaf's own limit is tighter; "no limit" elsewhere
        put(&leaf, "memory.limit_in_bytes", "209715200\n");
        put(&leaf, "memory.usage_in_bytes", "104857600\n");
        put(
            &top.join("a"),
            "memory.limit_in_bytes",
            "9223372036854771712\n",
        );
        let left = cgroup_memory_left_at(&top, "/", "/a/b", false);
        assert_eq!(left, Some(100.0 * 1048576.0));
        assert_eq!(cgroup_memory_left_at(&top, "/", "/none", false), None);
        std::fs::remove_dir_all(&top).unwrap();
    }

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
    fn this_process_limits_are_read_where_proc_exists() {
        if !Path::new("/proc/self/status").exists() {
            eprintln!("no /proc here: the limits of this process are not read");
            return;
        }
        let l = MemoryLimits::of_this_process();
        assert!(l.system.is_some_and(|b| b > 0.0), "{l:?}");
        assert!(l.usable().is_some());
    }

    #[test]
    fn a_failed_fallible_allocation_is_returned_not_fatal() {
        // far beyond any machine but not an overflow of the layout: the allocator is asked
        assert!(try_vec("test", 1 << 46, 0u8).is_err());
        assert!(!FALLIBLE.with(|f| f.get()));
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
