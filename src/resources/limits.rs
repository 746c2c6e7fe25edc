//! The memory this process may still take (the system's, the address-space limit's and the
//! control group's, read from `/proc` and the cgroup files), and one malloc heap under an
//! address-space limit.

use std::path::Path;

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
    pub(super) fn binding(&self) -> &'static str {
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

#[cfg(test)]
mod tests {
    use super::*;

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
    fn this_process_limits_are_read_where_proc_exists() {
        if !Path::new("/proc/self/status").exists() {
            crate::tell!("no /proc here: the limits of this process are not read");
            return;
        }
        let l = MemoryLimits::of_this_process();
        assert!(l.system.is_some_and(|b| b > 0.0), "{l:?}");
        assert!(l.usable().is_some());
    }
}
