//! Peak resident memory of this process, as the kernel counts it, and its reset between
//! experiments run one after another in one process.
//!
//! On Linux the peak is `VmHWM` in `/proc/self/status`, and writing `5` to
//! `/proc/self/clear_refs` resets it to the memory held now, so each experiment's peak is its
//! own. Elsewhere both say `None` / do nothing, and the figures read "unknown".

use std::fs;

/// The peak resident memory of this process so far (since the last [`reset_peak`]), in bytes;
/// `None` where the system does not say.
#[must_use]
pub fn peak_bytes() -> Option<u64> {
    let status = fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Starts a new peak at the memory held now; whether the system could.
pub fn reset_peak() -> bool {
    fs::write("/proc/self/clear_refs", "5").is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// While 64 MiB are held and touched, the peak is at least that (other tests in this
    /// process may hold more, never less); a reset leaves a figure to read.
    #[test]
    fn a_peak_counts_what_is_held() {
        if peak_bytes().is_none() {
            return; // not Linux: nothing to measure
        }
        let held: Vec<u8> = vec![1; 64 << 20];
        let during = peak_bytes().unwrap();
        assert!(during >= 64 << 20, "{during}");
        assert_eq!(held.iter().map(|&b| u64::from(b)).sum::<u64>(), 64 << 20);
        drop(held);
        if reset_peak() {
            assert!(peak_bytes().unwrap() > 0);
        }
    }
}
