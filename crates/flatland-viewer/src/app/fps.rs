//! The app's own frame counter: frames per second over the last second for the top bar and,
//! with `--fps-log`, a line every two seconds with the frame times (mean, 95th percentile,
//! worst), the UI thread's time per frame, the learner's speed and the frames drawn so far.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::ViewerApp;

/// How often `--fps-log` writes a line.
const LOG_EVERY: Duration = Duration::from_secs(2);

/// Frames per second over the last second, and the frame times since the last log line.
#[derive(Default)]
pub(super) struct FpsMeter {
    frames: VecDeque<Instant>,
    /// Frames per second over the last second.
    pub(super) now: f64,
    /// Whether to log (`--fps-log`).
    pub(super) log: bool,
    last_log: Option<Instant>,
    /// Seconds between frames since the last log line.
    intervals: Vec<f64>,
    /// Main-thread CPU seconds of the frames since the last log (eframe's `cpu_usage`).
    cpu: (f64, u32),
    /// Frames since the start (the log's last figure: frames between two lines, exactly).
    total: u64,
}

impl FpsMeter {
    /// A frame begins.
    pub(super) fn tick(&mut self) {
        let now = Instant::now();
        self.total += 1;
        if let Some(last) = self.frames.back() {
            self.intervals.push(now.duration_since(*last).as_secs_f64());
        }
        self.frames.push_back(now);
        while self
            .frames
            .front()
            .is_some_and(|t| now.duration_since(*t) > Duration::from_secs(1))
        {
            self.frames.pop_front();
        }
        self.now = match (self.frames.front(), self.frames.len()) {
            (Some(first), n) if n > 1 => {
                (n - 1) as f64 / now.duration_since(*first).as_secs_f64().max(1e-6)
            }
            _ => 0.0,
        };
    }

    /// The UI thread's time of the last frame (eframe's `cpu_usage`).
    pub(super) fn add_cpu(&mut self, seconds: f32) {
        self.cpu.0 += f64::from(seconds);
        self.cpu.1 += 1;
    }

    /// The log line's frame figures, when one is due.
    fn due_line(&mut self) -> Option<String> {
        if !self.log {
            return None;
        }
        let now = Instant::now();
        let last = *self.last_log.get_or_insert(now);
        if now.duration_since(last) < LOG_EVERY {
            return None;
        }
        self.last_log = Some(now);
        let (cpu, n) = std::mem::take(&mut self.cpu);
        let mut times = std::mem::take(&mut self.intervals);
        Some(format!(
            "fps {:.1}  frame ms {}  ui-thread {:.1} ms/frame",
            self.now,
            frame_times(&mut times),
            1e3 * cpu / f64::from(n.max(1)),
        ))
    }
}

/// Mean, 95th percentile and worst of frame intervals, in milliseconds.
fn frame_times(seconds: &mut [f64]) -> String {
    if seconds.is_empty() {
        return "–".into();
    }
    seconds.sort_by(f64::total_cmp);
    let mean = seconds.iter().sum::<f64>() / seconds.len() as f64;
    let p95 = seconds[((seconds.len() - 1) as f64 * 0.95).round() as usize];
    let worst = seconds[seconds.len() - 1];
    format!(
        "mean {:.1} p95 {:.1} max {:.1}",
        1e3 * mean,
        1e3 * p95,
        1e3 * worst
    )
}

impl ViewerApp {
    /// Writes the `--fps-log` line when due.
    pub(super) fn log_fps(&mut self) {
        let Some(frames) = self.fps.due_line() else {
            return;
        };
        let rate = self.status.as_ref().map_or(0.0, |s| s.steps_per_s);
        let relit = self
            .lamps
            .frame
            .as_ref()
            .map_or("relight –".to_owned(), |f| {
                format!(
                    "relight {:.2} ms/move (median, {})  moves {}  dropped {}  {}  {}",
                    f.median_ms,
                    super::lamps::answer_name(f.answer),
                    f.moves,
                    f.dropped,
                    super::lamps::relit_quality(f),
                    super::lamps::transport_note(f),
                )
            });
        eprintln!(
            "{frames}  {relit}  steps/s {rate:.0}  steps {}  cells {}  samples {}  edges {}  frames {}",
            self.steps(),
            self.cells(),
            self.status.as_ref().map_or(0, |s| s.samples.len()),
            self.scene.edges().len(),
            self.fps.total,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_times_are_mean_p95_and_worst_in_ms() {
        let mut t: Vec<f64> = (1..=100).map(|k| f64::from(k) * 1e-3).collect();
        assert_eq!(frame_times(&mut t), "mean 50.5 p95 95.0 max 100.0");
        assert_eq!(frame_times(&mut []), "–");
    }
}
