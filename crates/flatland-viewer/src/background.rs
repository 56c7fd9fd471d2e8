//! Learning in the background of the window: in a window the learner's threads ask the OS for
//! the lowest priority, so the window and its (possibly software) renderer get a core whenever
//! they want one and the learner everything they leave.
//!
//! On 2 cores under Mesa's software rasterizer, `floorplan-1000` with the visibility network
//! growing flat out drew 26–44 frames/s (33 on average over 40 s) at equal priority, the
//! learner resting a third of its time to leave room; at the lowest priority without the rest,
//! 50–61 (55): the rasterizer's threads no longer wait for the learner's time slice. Only
//! Linux is handled (its nice value is per thread, and threads inherit it); other
//! systems keep the learner at normal priority.

/// Who the learner's threads give way to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Priority {
    /// The OS's default: tests and headless use, where nothing waits for frames.
    #[default]
    Normal,
    /// The lowest priority: the window's frames come first.
    Background,
}

impl Priority {
    /// Applies the priority to the calling thread (and so to the threads it starts later).
    /// Returns whether the OS took it (`Normal` changes nothing and returns true).
    pub fn apply_to_this_thread(self) -> bool {
        match self {
            Priority::Normal => true,
            Priority::Background => lower_this_thread(),
        }
    }
}

/// The least favourable nice value on Linux.
#[cfg(target_os = "linux")]
const LOWEST_NICE: i32 = 19;

#[cfg(target_os = "linux")]
fn lower_this_thread() -> bool {
    // On Linux `setpriority(PRIO_PROCESS, tid)` sets one thread's nice value, not the process's.
    rustix::process::setpriority_process(Some(rustix::thread::gettid()), LOWEST_NICE).is_ok()
}

#[cfg(not(target_os = "linux"))]
fn lower_this_thread() -> bool {
    false
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    fn nice_of_this_thread() -> i32 {
        rustix::process::getpriority_process(Some(rustix::thread::gettid())).unwrap()
    }

    #[test]
    fn background_lowers_only_the_calling_thread_and_the_threads_it_starts() {
        let before = nice_of_this_thread();
        let (own, child) = std::thread::spawn(|| {
            assert!(Priority::Background.apply_to_this_thread());
            let child = std::thread::spawn(nice_of_this_thread).join().unwrap();
            (nice_of_this_thread(), child)
        })
        .join()
        .unwrap();
        assert_eq!((own, child), (LOWEST_NICE, LOWEST_NICE));
        assert_eq!(
            nice_of_this_thread(),
            before,
            "the test's own thread is untouched"
        );
        let normal = std::thread::spawn(|| {
            assert!(Priority::Normal.apply_to_this_thread());
            nice_of_this_thread()
        })
        .join()
        .unwrap();
        assert_eq!(normal, before);
    }
}
