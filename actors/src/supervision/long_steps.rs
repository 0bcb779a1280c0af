//! When a module's steps are too long for its agent's thread (`scheduler: agent_thread`): the
//! pure rule behind moving it to the shared runtime (the agent's `step_budget`).
//!
//! Steps are watched in windows of `steps` timed steps; a window whose mean step exceeds the
//! budget asks for a move, once. Windows rather than a mean since the start: a module that
//! turns slow after a long fast stretch is seen within one window.
//!
//! What counts is the time a step ran or blocked, not the time its thread waited for a CPU:
//! on a loaded machine the OS preempts the agent's thread inside a step, and in wall time that
//! step looks long (in one CI run every robot's detector was moved). Knowing that wait costs a
//! read of the thread's scheduler statistics (`run_queue.rs`, about 0.7 µs) at both ends of a
//! step, so the watch only asks for it when wall time says the module may be over: a window
//! over the budget in wall time is not a verdict but starts a checked window, whose steps are
//! counted without their run-queue wait; only a checked window over the budget moves the
//! module. A module that is fast in wall time never pays for the reads; a module really over
//! the budget moves one window later. Where the wait cannot be known, wall time decides.

use std::time::Duration;

use crate::config::StepBudget;

/// The time a step ran or blocked: its wall time less the time its thread waited on the run
/// queue meanwhile (`None`: not known, the wall time counts).
pub(crate) fn step_cost(wall: Duration, run_queue_wait: Option<Duration>) -> Duration {
    wall.saturating_sub(run_queue_wait.unwrap_or(Duration::ZERO))
}

/// Watches one module instance's step durations against its agent's budget.
#[derive(Debug, Clone)]
pub(crate) struct LongStepWatch {
    budget: Duration,
    steps: u32,
    total: Duration,
    count: u32,
    /// Whether the thread's run-queue wait can be read here at all.
    wait_known: bool,
    /// The current window counts steps without their run-queue wait.
    checking: bool,
    asked: bool,
}

impl LongStepWatch {
    /// A watch for `budget`; `None` when the budget never moves anything (`mean_us: 0`).
    /// `wait_known`: whether the step's thread can tell its run-queue wait.
    pub fn new(budget: StepBudget, wait_known: bool) -> Option<LongStepWatch> {
        (budget.mean_us > 0).then(|| LongStepWatch {
            budget: Duration::from_micros(budget.mean_us),
            steps: budget.steps.max(1),
            total: Duration::ZERO,
            count: 0,
            wait_known,
            checking: false,
            asked: false,
        })
    }

    /// Whether the next timed step should be observed with its run-queue wait.
    pub fn wants_run_queue_wait(&self) -> bool {
        self.checking
    }

    /// Notes a timed step that took `wall`, of which its thread waited `run_queue_wait` for a
    /// CPU; returns the window's mean step the first time a window that counts decides the
    /// module is over the budget (it should move), `None` otherwise.
    pub fn observe(
        &mut self,
        wall: Duration,
        run_queue_wait: Option<Duration>,
    ) -> Option<Duration> {
        if self.asked {
            return None;
        }
        self.total += match self.checking {
            true => step_cost(wall, run_queue_wait),
            false => wall,
        };
        self.count += 1;
        if self.count < self.steps {
            return None;
        }
        let mean = self.total / self.count;
        self.total = Duration::ZERO;
        self.count = 0;
        let over = mean > self.budget;
        let decides = self.checking || !self.wait_known;
        self.checking = over && !decides;
        self.asked = over && decides;
        self.asked.then_some(mean)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn watch(mean_us: u64, steps: u32, wait_known: bool) -> LongStepWatch {
        let budget = StepBudget {
            mean_us,
            steps,
            held_ms: 0,
        };
        LongStepWatch::new(budget, wait_known).unwrap()
    }

    const MS: fn(u64) -> Duration = Duration::from_millis;
    const US: fn(u64) -> Duration = Duration::from_micros;

    /// Feeds `window` (wall, run-queue wait) samples; the verdicts of its steps.
    fn feed(w: &mut LongStepWatch, window: &[(Duration, Duration)]) -> Vec<Option<Duration>> {
        window
            .iter()
            .map(|&(wall, wait)| {
                let wait = w.wants_run_queue_wait().then_some(wait);
                w.observe(wall, wait)
            })
            .collect()
    }

    #[test]
    fn step_cost_is_wall_time_less_the_run_queue_wait() {
        assert_eq!(step_cost(MS(5), Some(MS(4))), MS(1));
        assert_eq!(step_cost(MS(5), None), MS(5), "unknown wait: wall time");
        assert_eq!(
            step_cost(MS(1), Some(MS(2))),
            Duration::ZERO,
            "never negative"
        );
    }

    #[test]
    fn a_step_that_blocks_or_computes_moves_after_a_checked_window() {
        // A step that sleeps 5 ms waits on no run queue; one that computes 5 ms on a loaded
        // machine waited 3 ms of its 8: both are over a 1 ms budget once checked.
        for (wall, wait) in [(MS(5), Duration::ZERO), (MS(8), MS(3))] {
            let mut w = watch(1000, 4, true);
            let verdicts = feed(&mut w, &[(wall, wait); 4]);
            assert!(
                verdicts.iter().all(Option::is_none),
                "wall time only checks"
            );
            assert!(w.wants_run_queue_wait());
            let verdicts = feed(&mut w, &[(wall, wait); 4]);
            assert_eq!(verdicts[..3], [None, None, None]);
            assert_eq!(verdicts[3], Some(step_cost(wall, Some(wait))));
            assert!(
                feed(&mut w, &[(MS(50), MS(0)); 100])
                    .iter()
                    .all(Option::is_none),
                "asked once"
            );
        }
    }

    #[test]
    fn a_step_preempted_by_a_loaded_machine_does_not_move() {
        // 300 µs of work that the OS kept waiting 4 ms: 4.3 ms in wall time.
        let mut w = watch(1000, 4, true);
        for _ in 0..50 {
            assert!(feed(&mut w, &[(US(4300), MS(4)); 4])
                .iter()
                .all(Option::is_none));
        }
        // When the load goes, the module stops paying for the reads.
        feed(&mut w, &[(US(300), Duration::ZERO); 4]);
        assert!(!w.wants_run_queue_wait());
    }

    #[test]
    fn where_the_wait_is_unknown_wall_time_decides() {
        let mut w = watch(1000, 4, false);
        let verdicts = feed(&mut w, &[(US(4300), MS(4)); 4]);
        assert_eq!(verdicts[3], Some(US(4300)));
        // A checked step whose wait could not be read counts its wall time.
        let mut w = watch(1000, 2, true);
        feed(&mut w, &[(MS(3), Duration::ZERO); 2]);
        assert_eq!(w.observe(MS(3), None), None);
        assert_eq!(w.observe(MS(3), None), Some(MS(3)));
    }

    #[test]
    fn short_steps_and_single_long_ones_never_ask() {
        let mut w = watch(1000, 4, true);
        for _ in 0..1000 {
            assert_eq!(w.observe(US(200), None), None);
        }
        assert!(!w.wants_run_queue_wait());
        // One long step in a window of short ones keeps its mean under the budget.
        for step in [US(3000), US(100), US(100), US(100)] {
            assert_eq!(w.observe(step, None), None);
        }
        // A window exactly at the budget is within it.
        for _ in 0..4 {
            assert_eq!(w.observe(US(1000), None), None);
        }
        assert!(!w.wants_run_queue_wait());
    }

    #[test]
    fn a_module_turning_slow_is_seen_within_two_windows() {
        let mut w = watch(1000, 10, true);
        for _ in 0..100_000 {
            w.observe(US(10), None);
        }
        let asked = (1..=30).find(|_| {
            let wait = w.wants_run_queue_wait().then_some(Duration::ZERO);
            w.observe(US(5000), wait).is_some()
        });
        assert_eq!(asked, Some(20));
    }

    #[test]
    fn a_zero_budget_watches_nothing() {
        let budget = StepBudget {
            mean_us: 0,
            steps: 20,
            held_ms: 0,
        };
        assert!(LongStepWatch::new(budget, true).is_none());
    }
}
