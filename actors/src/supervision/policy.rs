//! The pure part of supervision: restart windows, backoff delays, and which modules a failure
//! restarts. No actors, no clocks of its own: times are passed in.

use std::collections::VecDeque;
use std::time::Duration;

use tokio::time::Instant;

use super::{BackoffConfig, RestartPolicy, Strategy};

/// Counts restarts in a sliding window: at most `max` within `within`.
#[derive(Debug, Clone)]
pub struct Intensity {
    max: u32,
    within: Duration,
    restarts: VecDeque<Instant>,
}

impl Intensity {
    /// A window allowing `max` restarts within `within`.
    pub fn new(max: u32, within: Duration) -> Self {
        Intensity {
            max,
            within,
            restarts: VecDeque::new(),
        }
    }

    /// Records a restart at `now`; false when that exceeds the intensity.
    pub fn allow(&mut self, now: Instant) -> bool {
        while self
            .restarts
            .front()
            .is_some_and(|t| now.duration_since(*t) >= self.within)
        {
            self.restarts.pop_front();
        }
        self.restarts.push_back(now);
        self.restarts.len() <= self.max as usize
    }
}

/// Exponential backoff with jitter and reset, for one module.
#[derive(Debug, Clone)]
pub struct Backoff {
    config: BackoffConfig,
    attempt: u32,
    last_start: Option<Instant>,
}

impl Backoff {
    /// A backoff following `config`.
    pub fn new(config: BackoffConfig) -> Self {
        Backoff {
            config,
            attempt: 0,
            last_start: None,
        }
    }

    /// Notes that the module (re)started at `now`.
    pub fn started(&mut self, now: Instant) {
        self.last_start = Some(now);
    }

    /// The delay before restarting after a failure at `now`; `unit` in `[0, 1)` draws the jitter.
    pub fn next_delay(&mut self, now: Instant, unit: f64) -> Duration {
        let quiet = Duration::from_millis(self.config.reset_after_ms);
        if self
            .last_start
            .is_some_and(|t| now.duration_since(t) >= quiet)
        {
            self.attempt = 0;
        }
        let (min, max) = (
            self.config.min_ms as f64,
            self.config.max_ms.max(self.config.min_ms) as f64,
        );
        let base = (min * 2f64.powi(self.attempt.min(30) as i32)).min(max);
        self.attempt += 1;
        let jitter = self.config.jitter.clamp(0.0, 1.0);
        let spread = base * jitter * (2.0 * unit.clamp(0.0, 1.0) - 1.0);
        Duration::from_secs_f64(((base + spread).max(0.0)) / 1000.0)
    }
}

/// A supervised module as the policy sees it.
#[derive(Debug, Clone)]
pub(crate) struct Member {
    /// Index of the group, or `None` for a top-level module.
    pub group: Option<usize>,
    pub policy: RestartPolicy,
}

/// What to do about one module ending.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum RestartPlan {
    /// Leave it stopped (its policy says so).
    Leave,
    /// Stop `stop` (indices, in reverse start order; they are still running) and start
    /// `restart` (in start order; includes the module that ended).
    Restart {
        stop: Vec<usize>,
        restart: Vec<usize>,
    },
}

/// Which modules to restart when module `failed` ends (abnormally if `failure`), given every
/// member and the strategy that applies: the group's, or the agent's for top-level modules and
/// for a whole group that failed to the agent (`whole_group`).
pub(crate) fn plan_restart(
    members: &[Member],
    failed: usize,
    failure: bool,
    strategy: Strategy,
    whole_group: bool,
) -> RestartPlan {
    let restart_it = match members[failed].policy {
        RestartPolicy::Permanent => true,
        RestartPolicy::Transient => failure,
        RestartPolicy::Temporary => false,
    };
    if !restart_it && !whole_group {
        return RestartPlan::Leave;
    }
    let group = members[failed].group;
    // The unit the strategy works on: the group's members, or (at the agent level) every module,
    // where a failed group counts as one child placed at its first member.
    let in_scope = |i: usize| {
        whole_group || members[i].group == group || group.is_none() && members[i].group.is_none()
    };
    let scope: Vec<usize> = (0..members.len())
        .filter(|&i| match (group, whole_group) {
            (_, true) | (None, false) => true,
            (Some(_), false) => in_scope(i),
        })
        .collect();
    let unit_of = |i: usize| {
        if whole_group && members[i].group == group {
            failed
        } else {
            i
        }
    };
    let mut restart: Vec<usize> = match strategy {
        Strategy::OneForOne => scope
            .iter()
            .copied()
            .filter(|&i| unit_of(i) == failed && (i == failed || whole_group))
            .collect(),
        Strategy::OneForAll => scope.clone(),
        Strategy::RestForOne => {
            let first = scope
                .iter()
                .position(|&i| unit_of(i) == failed)
                .unwrap_or(0);
            scope[first..].to_vec()
        }
    };
    // A temporary module that did not fail is not restarted with its siblings, as in OTP.
    restart.retain(|&i| {
        i == failed
            || members[i].policy != RestartPolicy::Temporary
            || whole_group && members[i].group == group
    });
    let mut stop: Vec<usize> = restart.iter().copied().filter(|&i| i != failed).collect();
    stop.reverse();
    RestartPlan::Restart { stop, restart }
}

#[cfg(test)]
mod tests {
    use super::*;
    use RestartPolicy::*;

    fn members(spec: &[(Option<usize>, RestartPolicy)]) -> Vec<Member> {
        spec.iter()
            .map(|&(group, policy)| Member { group, policy })
            .collect()
    }

    #[test]
    fn restart_policies_decide_whether_to_restart() {
        let m = members(&[(None, Permanent), (None, Transient), (None, Temporary)]);
        let one = |i| RestartPlan::Restart {
            stop: vec![],
            restart: vec![i],
        };
        assert_eq!(
            plan_restart(&m, 0, false, Strategy::OneForOne, false),
            one(0),
            "permanent: even after a normal stop"
        );
        assert_eq!(
            plan_restart(&m, 1, true, Strategy::OneForOne, false),
            one(1)
        );
        assert_eq!(
            plan_restart(&m, 1, false, Strategy::OneForOne, false),
            RestartPlan::Leave,
            "transient: not after a normal stop"
        );
        assert_eq!(
            plan_restart(&m, 2, true, Strategy::OneForOne, false),
            RestartPlan::Leave,
            "temporary: never"
        );
    }

    #[test]
    fn strategies_pick_the_modules_to_restart() {
        // 0 top-level; 1, 2, 3 in group 0; 4 top-level.
        let m = members(&[
            (None, Permanent),
            (Some(0), Permanent),
            (Some(0), Permanent),
            (Some(0), Permanent),
            (None, Permanent),
        ]);
        let plan = |failed, strategy| plan_restart(&m, failed, true, strategy, false);
        assert_eq!(
            plan(2, Strategy::OneForOne),
            RestartPlan::Restart {
                stop: vec![],
                restart: vec![2]
            }
        );
        assert_eq!(
            plan(2, Strategy::OneForAll),
            RestartPlan::Restart {
                stop: vec![3, 1],
                restart: vec![1, 2, 3]
            }
        );
        assert_eq!(
            plan(2, Strategy::RestForOne),
            RestartPlan::Restart {
                stop: vec![3],
                restart: vec![2, 3]
            }
        );
        assert_eq!(
            plan(0, Strategy::OneForAll),
            RestartPlan::Restart {
                stop: vec![4, 3, 2, 1],
                restart: vec![0, 1, 2, 3, 4]
            }
        );
    }

    #[test]
    fn a_group_failing_to_the_agent_restarts_as_one_child() {
        let m = members(&[
            (None, Permanent),
            (Some(0), Permanent),
            (Some(0), Permanent),
            (None, Permanent),
        ]);
        let plan = |strategy| plan_restart(&m, 2, true, strategy, true);
        assert_eq!(
            plan(Strategy::OneForOne),
            RestartPlan::Restart {
                stop: vec![1],
                restart: vec![1, 2]
            }
        );
        assert_eq!(
            plan(Strategy::RestForOne),
            RestartPlan::Restart {
                stop: vec![3, 1],
                restart: vec![1, 2, 3]
            }
        );
        assert_eq!(
            plan(Strategy::OneForAll),
            RestartPlan::Restart {
                stop: vec![3, 1, 0],
                restart: vec![0, 1, 2, 3]
            }
        );
    }

    #[test]
    fn intensity_allows_max_restarts_per_window() {
        let t0 = Instant::now();
        let mut i = Intensity::new(2, Duration::from_secs(10));
        assert!(i.allow(t0));
        assert!(i.allow(t0 + Duration::from_secs(1)));
        assert!(!i.allow(t0 + Duration::from_secs(2)), "third within 10 s");
        assert!(
            i.allow(t0 + Duration::from_secs(13)),
            "the first two left the window"
        );
    }

    #[test]
    fn backoff_doubles_up_to_max_and_resets_after_a_quiet_period() {
        let config = BackoffConfig {
            min_ms: 10,
            max_ms: 50,
            jitter: 0.0,
            reset_after_ms: 1000,
        };
        let mut b = Backoff::new(config);
        let t0 = Instant::now();
        b.started(t0);
        let ms = |d: Duration| d.as_millis();
        let delays: Vec<u128> = (0..5).map(|_| ms(b.next_delay(t0, 0.5))).collect();
        assert_eq!(delays, [10, 20, 40, 50, 50]);
        b.started(t0);
        assert_eq!(
            ms(b.next_delay(t0 + Duration::from_millis(1500), 0.5)),
            10,
            "reset after 1 s without failure"
        );
        let jittery = BackoffConfig {
            jitter: 0.5,
            ..config
        };
        let (lo, hi) = (
            Backoff::new(jittery).next_delay(t0, 0.0),
            Backoff::new(jittery).next_delay(t0, 0.999),
        );
        assert_eq!((ms(lo), ms(hi)), (5, 14));
    }
}
