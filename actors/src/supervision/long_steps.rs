//! When a module's steps are too long for its agent's thread (`scheduler: agent_thread`): the
//! pure rule behind moving it to the shared runtime (the agent's `step_budget`).
//!
//! Steps are watched in windows of `steps` timed steps; a window whose mean step exceeds the
//! budget asks for a move, once. Windows rather than a mean since the start: a module that
//! turns slow after a long fast stretch is seen within one window.

use std::time::Duration;

use crate::config::StepBudget;

/// Watches one module instance's step durations against its agent's budget.
#[derive(Debug, Clone)]
pub(crate) struct LongStepWatch {
    budget: Duration,
    steps: u32,
    total: Duration,
    count: u32,
    asked: bool,
}

impl LongStepWatch {
    /// A watch for `budget`; `None` when the budget never moves anything (`mean_us: 0`).
    pub fn new(budget: StepBudget) -> Option<LongStepWatch> {
        (budget.mean_us > 0).then(|| LongStepWatch {
            budget: Duration::from_micros(budget.mean_us),
            steps: budget.steps.max(1),
            total: Duration::ZERO,
            count: 0,
            asked: false,
        })
    }

    /// Notes a timed step that took `took`; returns the window's mean step the first time a
    /// window's mean exceeds the budget (the module should move), `None` otherwise.
    pub fn observe(&mut self, took: Duration) -> Option<Duration> {
        if self.asked {
            return None;
        }
        self.total += took;
        self.count += 1;
        if self.count < self.steps {
            return None;
        }
        let mean = self.total / self.count;
        self.total = Duration::ZERO;
        self.count = 0;
        self.asked = mean > self.budget;
        self.asked.then_some(mean)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn watch(mean_us: u64, steps: u32) -> LongStepWatch {
        LongStepWatch::new(StepBudget {
            mean_us,
            steps,
            held_ms: 0,
        })
        .unwrap()
    }

    #[test]
    fn a_window_over_the_budget_asks_once() {
        let mut w = watch(1000, 4);
        let ms = Duration::from_millis;
        assert_eq!(w.observe(ms(5)), None);
        assert_eq!(w.observe(ms(5)), None);
        assert_eq!(w.observe(ms(5)), None);
        assert_eq!(w.observe(ms(1)), Some(ms(4)), "mean of the window: 4 ms");
        assert!((0..100).all(|_| w.observe(ms(50)).is_none()), "asked once");
    }

    #[test]
    fn short_steps_and_single_long_ones_never_ask() {
        let mut w = watch(1000, 4);
        let us = Duration::from_micros;
        for _ in 0..1000 {
            assert_eq!(w.observe(us(200)), None);
        }
        // One long step in a window of short ones keeps its mean under the budget.
        for step in [us(3000), us(100), us(100), us(100)] {
            assert_eq!(w.observe(step), None);
        }
        // A window exactly at the budget is within it.
        for _ in 0..4 {
            assert_eq!(w.observe(us(1000)), None);
        }
    }

    #[test]
    fn a_module_turning_slow_is_seen_within_one_window() {
        let mut w = watch(1000, 10);
        let us = Duration::from_micros;
        for _ in 0..100_000 {
            w.observe(us(10));
        }
        let asked = (1..=20).find(|_| w.observe(us(5000)).is_some());
        assert_eq!(asked, Some(10));
    }

    #[test]
    fn a_zero_budget_watches_nothing() {
        assert!(LongStepWatch::new(StepBudget {
            mean_us: 0,
            steps: 20,
            held_ms: 0
        })
        .is_none());
    }
}
