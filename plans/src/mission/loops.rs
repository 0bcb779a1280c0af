//! Finding a plan that fires in a circle without waiting for anything.
//!
//! A plan loop whose actions finish at once (unbound actions, a `finished` condition already
//! true, a jump back to a label) fires round after round and never waits. The mission still
//! yields between steps (its rounds per step are bounded), but the plan makes no progress and
//! its log fills with firings. [`LoopFinder`] watches the rounds: after [`LOOP_ROUNDS`] rounds
//! in a row that each fired something, it looks for a marking that comes back, and names the
//! transitions fired between its two visits: the cycle. It is reported once, then at most every
//! [`REPORT_EVERY`]; while the plan loops, its firings are not logged one by one.

use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::time::{Duration, Instant};

/// Rounds in a row that fire something after which the plan counts as looping.
pub(super) const LOOP_ROUNDS: u64 = 1_000;

/// The least time between two reports of the same loop.
pub(super) const REPORT_EVERY: Duration = Duration::from_secs(10);

/// The most transitions a reported cycle lists.
const CYCLE_SHOWN: usize = 12;

/// The most rounds remembered while looking for a marking that comes back: a long plan of
/// actions that finish at once is not a loop, and must not cost memory as if it were.
const SEARCH_ROUNDS: usize = 10_000;

/// A loop to report: how many rounds fired in a row, and the transitions of one turn.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct PlanLoop {
    pub rounds: u64,
    pub cycle: Vec<String>,
}

/// See the module documentation.
#[derive(Debug, Default)]
pub(super) struct LoopFinder {
    /// Rounds in a row that fired something.
    streak: u64,
    /// While looking for the cycle: the round at which each marking was seen.
    seen: HashMap<u64, usize>,
    /// While looking for the cycle: the labels fired, round by round.
    fired: Vec<Vec<String>>,
    last_report: Option<Instant>,
}

impl LoopFinder {
    /// Whether the plan is looping now (its firings are then not worth a log line each).
    pub fn looping(&self) -> bool {
        self.streak >= LOOP_ROUNDS
    }

    /// A round fired nothing: the plan waits for something, so any streak ends.
    pub fn waited(&mut self) {
        self.streak = 0;
        self.seen.clear();
        self.fired.clear();
    }

    /// Notes a round that fired something; `round` gives, only when asked, the marking it left
    /// (a [`PlanState::save`] key) and the labels it fired. Returns a loop to report when one
    /// is due. The clock (`now`) is read only once the rounds look like a loop: a plan that
    /// waits now and then never pays for it.
    ///
    /// [`PlanState::save`]: crate::PlanState::save
    pub fn fired(
        &mut self,
        now: impl FnOnce() -> Instant,
        round: impl FnOnce() -> (Vec<u32>, Vec<String>),
    ) -> Option<PlanLoop> {
        self.streak += 1;
        if !self.looping() {
            return None;
        }
        let now = now();
        if self
            .last_report
            .is_some_and(|t| now.duration_since(t) < REPORT_EVERY)
        {
            return None;
        }
        if self.fired.len() >= SEARCH_ROUNDS {
            self.seen.clear();
            self.fired.clear();
        }
        let (marking, fired) = round();
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        marking.hash(&mut hasher);
        let key = hasher.finish();
        self.fired.push(fired);
        let round = self.fired.len();
        match self.seen.insert(key, round) {
            Some(first) => {
                let cycle: Vec<String> = self.fired[first..round].concat();
                self.seen.clear();
                self.fired.clear();
                self.last_report = Some(now);
                Some(PlanLoop {
                    rounds: self.streak,
                    cycle: cycle.into_iter().take(CYCLE_SHOWN).collect(),
                })
            }
            None => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs a cycle of three markings, firing `a`, `b`, `c` in turn, for `rounds` rounds.
    fn spin(finder: &mut LoopFinder, rounds: u64, now: Instant) -> Vec<PlanLoop> {
        (0..rounds)
            .filter_map(|r| {
                let i = (r % 3) as usize;
                finder.fired(
                    || now,
                    || (vec![i as u32], vec![["a", "b", "c"][i].to_string()]),
                )
            })
            .collect()
    }

    #[test]
    fn a_cycle_is_named_once_past_the_limit_and_again_only_after_ten_seconds() {
        let mut finder = LoopFinder::default();
        let t0 = Instant::now();
        let found = spin(&mut finder, LOOP_ROUNDS + 100, t0);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].rounds, LOOP_ROUNDS + 3);
        let mut cycle = found[0].cycle.clone();
        cycle.sort();
        assert_eq!(cycle, ["a", "b", "c"]);
        assert!(finder.looping());
        assert!(spin(&mut finder, 100, t0 + REPORT_EVERY / 2).is_empty());
        assert_eq!(spin(&mut finder, 10, t0 + REPORT_EVERY).len(), 1);
    }

    #[test]
    fn a_plan_that_waits_now_and_then_is_never_a_loop() {
        let mut finder = LoopFinder::default();
        let t0 = Instant::now();
        for _ in 0..100 {
            assert!(spin(&mut finder, LOOP_ROUNDS - 1, t0).is_empty());
            finder.waited();
        }
        assert!(!finder.looping());
    }

    #[test]
    fn a_long_run_without_a_repeated_marking_is_not_named_a_cycle() {
        let mut finder = LoopFinder::default();
        let t0 = Instant::now();
        let found: Vec<_> = (0..3 * LOOP_ROUNDS as u32)
            .filter_map(|r| finder.fired(|| t0, || (vec![r], vec!["step".to_string()])))
            .collect();
        assert!(found.is_empty());
    }
}
