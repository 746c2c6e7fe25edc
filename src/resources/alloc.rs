//! Allocation that never aborts: fallible vectors sized by user input ([`try_vec`]) and
//! the binary's allocator, which ends a refused allocation like any refusal.

use super::human::human_bytes;
use crate::error::{Error, Result};

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
/// system refuses (the memory limits of [`MemoryLimits`](super::limits::MemoryLimits)
/// reached although the estimate checked before the work fitted) ends the run like any
/// refusal, with one line on stderr, its temporary and lock files deleted and exit
/// status 2, instead of Rust's allocation abort (signal 6, files left behind).
/// Allocations made through [`try_vec`] still fail back to their caller.
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
    crate::tell!(
        "lidarsim: error: out of memory: {size} more bytes could not be had (the run needs \
         more than its estimate, a limit such as ulimit -v or a control group's was reached); \
         make the run smaller{what}"
    );
    signal_hook::low_level::exit(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_fallible_allocation_is_returned_not_fatal() {
        // far beyond any machine but not an overflow of the layout: the allocator is asked
        assert!(try_vec("test", 1 << 46, 0u8).is_err());
        assert!(!FALLIBLE.with(|f| f.get()));
    }
}
