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

mod alloc;
mod duration;
mod entropy;
mod human;
mod limits;
mod require;

pub use alloc::{NoAbortAllocator, try_vec, try_with_capacity};
pub use duration::{
    AFTERPULSE_NS, ANNOUNCE_AFTER_S, afterpulse_ns_per_shot, announce_duration, duration_notice,
    keep_duration_notices, take_duration_notices,
};
pub use entropy::poisson_entropy_bits;
pub use human::{human_bytes, human_duration};
pub use limits::{
    ADDRESS_SPACE_MARGIN_BYTES, ADDRESS_SPACE_PER_THREAD_BYTES, MemoryLimits,
    available_memory_bytes, one_heap_under_an_address_space_limit, parse_address_space_limit,
    parse_cgroup_mount, parse_limit_value, parse_mem_available, parse_memory_cgroup, parse_vm_size,
};
pub use require::{MEMORY_FRACTION, check_memory, require_disk, require_memory};
