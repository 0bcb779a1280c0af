//! The figures behind a module's `stats/...`: step durations and intervals, kept locally and
//! published now and then.
//!
//! A busy module is timed on a sample of its steps: timing a step costs two clock reads, which
//! is a fifth of a module-to-module hop. A module stepping less often than every
//! [`FAST_STEP`] is timed at every step; a faster one at one step in [`STRIDE`]. Means are
//! over the timed steps, intervals between their starts divided by the steps in between.

use std::time::Duration;

use tokio::time::Instant;

/// Stats are published at most this often (and at every status change), to keep steps cheap.
const STATS_INTERVAL: Duration = Duration::from_millis(100);
/// Modules whose steps come faster than this are timed on a sample.
const FAST_STEP: Duration = Duration::from_micros(100);
/// One step in this many is timed for fast modules.
const STRIDE: u64 = 16;

#[derive(Debug)]
pub(crate) struct StepStats {
    /// Steps until the next timed one.
    skip: u64,
    stride: u64,
    timed: u64,
    total: Duration,
    pub last: Duration,
    /// Start and step number of the first and of the last timed step.
    first: Option<(Instant, u64)>,
    latest: Option<(Instant, u64)>,
    pub published: Option<Instant>,
}

impl Default for StepStats {
    fn default() -> Self {
        StepStats {
            skip: 0,
            stride: 1,
            timed: 0,
            total: Duration::ZERO,
            last: Duration::ZERO,
            first: None,
            latest: None,
            published: None,
        }
    }
}

impl StepStats {
    /// Whether to time the next step.
    pub fn wants_timing(&mut self) -> bool {
        match self.skip {
            0 => {
                self.skip = self.stride - 1;
                true
            }
            _ => {
                self.skip -= 1;
                false
            }
        }
    }

    /// Records timed step number `step` (counting from 1), which started at `started` and took
    /// `took`; true when the stats are due for publishing.
    pub fn record(&mut self, step: u64, started: Instant, took: Duration) -> bool {
        self.timed += 1;
        self.total += took;
        self.last = took;
        if let Some((before, n)) = self.latest {
            let per_step = started.saturating_duration_since(before) / (step - n).max(1) as u32;
            self.stride = if per_step < FAST_STEP { STRIDE } else { 1 };
            self.skip = self.skip.min(self.stride - 1);
        }
        self.first.get_or_insert((started, step));
        self.latest = Some((started, step));
        self.due(started)
    }

    /// Whether stats not published since [`STATS_INTERVAL`] before `now` (or never) are due.
    fn due(&self, now: Instant) -> bool {
        self.published
            .is_none_or(|p| now.duration_since(p) >= STATS_INTERVAL)
    }

    pub fn mean_step_us(&self) -> f64 {
        match self.timed {
            0 => 0.0,
            n => self.total.as_secs_f64() * 1e6 / n as f64,
        }
    }

    pub fn mean_interval_ms(&self) -> f64 {
        match (self.first, self.latest) {
            (Some((a, i)), Some((b, j))) if j > i => {
                b.duration_since(a).as_secs_f64() * 1e3 / (j - i) as f64
            }
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs `steps` steps `interval` apart, each taking `took`; returns how many were timed.
    fn run(stats: &mut StepStats, start: Instant, steps: u64, interval: Duration) -> u64 {
        let mut timed = 0;
        for k in 1..=steps {
            if stats.wants_timing() {
                timed += 1;
                let at = start + interval * k as u32;
                stats.record(k, at, Duration::from_micros(3));
            }
        }
        timed
    }

    #[test]
    fn slow_modules_are_timed_at_every_step_fast_ones_on_a_sample() {
        let t0 = Instant::now();
        let mut slow = StepStats::default();
        assert_eq!(run(&mut slow, t0, 100, Duration::from_millis(10)), 100);
        assert!((slow.mean_interval_ms() - 10.0).abs() < 1e-9);
        assert!((slow.mean_step_us() - 3.0).abs() < 1e-9);

        let mut fast = StepStats::default();
        let timed = run(&mut fast, t0, 1600, Duration::from_micros(10));
        assert!((100..=102).contains(&timed), "{timed}");
        assert!(
            (fast.mean_interval_ms() - 0.01).abs() < 1e-9,
            "{}",
            fast.mean_interval_ms()
        );
        assert!((fast.mean_step_us() - 3.0).abs() < 1e-9);
    }
}
