//! Memory: the peak resident memory of this process, as the kernel counts it (what a user's
//! `time -v` would say of a whole command), and the heap's peak over one piece of work (what one
//! experiment among several in a process added).
//!
//! On Linux the resident peak is `VmHWM` in `/proc/self/status`; elsewhere it is `None` and the
//! figures read "unknown". The heap's peak needs the counting allocator installed by the binary
//! (`#[global_allocator] static A: &PeakMemAlloc<System> = &INSTRUMENTED_SYSTEM;`); without it
//! [`heap_peak_of`] says `None`.

use std::fs;

use peakmem_alloc::{INSTRUMENTED_SYSTEM, PeakMemAllocTrait};

/// Runs `work` and returns what it gave with the most heap bytes it held at once above what was
/// held when it started (other threads' allocations meanwhile count too); `None` when the
/// counting allocator is not installed.
pub fn heap_peak_of<T>(work: impl FnOnce() -> T) -> (T, Option<u64>) {
    INSTRUMENTED_SYSTEM.reset_peak_memory();
    let out = work();
    let peak = INSTRUMENTED_SYSTEM.get_peak_memory() as u64;
    // Any real work allocates: a peak of 0 means the counter never saw an allocation.
    (out, (peak > 0).then_some(peak))
}

/// The peak resident memory of this process so far, in bytes; `None` where the system does not
/// say.
#[must_use]
pub fn peak_bytes() -> Option<u64> {
    status_kib("VmHWM:").map(|kib| kib * 1024)
}

/// A `kB` figure of `/proc/self/status`.
fn status_kib(key: &str) -> Option<u64> {
    let status = fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(key))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// While 64 MiB are held and touched, the peak is at least that (other tests in this
    /// process may hold more, never less).
    #[test]
    fn a_peak_counts_what_is_held() {
        if peak_bytes().is_none() {
            return; // not Linux: nothing to measure
        }
        let held: Vec<u8> = vec![1; 64 << 20];
        let during = peak_bytes().unwrap();
        assert!(during >= 64 << 20, "{during}");
        assert_eq!(held.iter().map(|&b| u64::from(b)).sum::<u64>(), 64 << 20);
    }
}
