//! Goal sequencing: hands out goals one at a time and tracks progress.

use petrel_actors::Pose2;

use crate::sim::error::{positive, ParamError};

/// Progress report of a [`GoalSequencer`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SequencerOutput {
    /// The goal to pursue now; `None` once all goals are reached.
    pub goal: Option<Pose2>,
    /// Index of the current goal (equals `total` when done).
    pub index: usize,
    /// Goals reached so far.
    pub reached: usize,
    /// Number of goals in the list.
    pub total: usize,
    /// All goals reached.
    pub done: bool,
}

/// Feeds a list of goals one at a time, advancing when the current one is reached.
///
/// A goal counts as reached when the planner says `arrived` *and* the robot is within
/// `tolerance` of that goal. The second check makes the sequencer immune to a stale `arrived`
/// flag that still refers to the previous goal (as can happen when modules run concurrently).
#[derive(Clone, Debug)]
pub struct GoalSequencer {
    goals: Vec<Pose2>,
    index: usize,
    tolerance: f64,
}

impl GoalSequencer {
    /// A sequencer over `goals`; `tolerance` (metres) should be at least the planner's goal
    /// tolerance.
    pub fn new(goals: Vec<Pose2>, tolerance: f64) -> Result<Self, ParamError> {
        positive("tolerance", tolerance)?;
        Ok(GoalSequencer {
            goals,
            index: 0,
            tolerance,
        })
    }

    /// Current progress without advancing.
    pub fn progress(&self) -> SequencerOutput {
        let done = self.index >= self.goals.len();
        SequencerOutput {
            goal: self.goals.get(self.index).copied(),
            index: self.index,
            reached: self.index,
            total: self.goals.len(),
            done,
        }
    }

    /// Advances past the current goal if `arrived` and `robot` is at it; returns the progress.
    pub fn step(&mut self, robot: Pose2, arrived: bool) -> SequencerOutput {
        if let Some(goal) = self.goals.get(self.index) {
            let d = (goal.0.translation.vector - robot.0.translation.vector).norm();
            if arrived && d <= self.tolerance {
                self.index += 1;
            }
        }
        self.progress()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn advances_one_goal_at_a_time_and_ignores_stale_arrivals() {
        let goals = vec![Pose2::new(1.0, 0.0, 0.0), Pose2::new(2.0, 0.0, 0.0)];
        let mut s = GoalSequencer::new(goals.clone(), 0.3).unwrap();
        assert_eq!(s.progress().goal, Some(goals[0]));
        assert_eq!(
            s.step(Pose2::new(0.0, 0.0, 0.0), true).index,
            0,
            "arrived elsewhere: stale flag"
        );
        assert_eq!(s.step(Pose2::new(1.1, 0.0, 0.0), false).index, 0);
        let out = s.step(Pose2::new(1.1, 0.0, 0.0), true);
        assert_eq!(
            (out.index, out.reached, out.goal, out.done),
            (1, 1, Some(goals[1]), false)
        );
        // Still "arrived" from goal 0 on the next tick: does not skip goal 1.
        assert_eq!(s.step(Pose2::new(1.1, 0.0, 0.0), true).index, 1);
        let out = s.step(Pose2::new(2.0, 0.1, 0.0), true);
        assert_eq!(
            (out.reached, out.total, out.goal, out.done),
            (2, 2, None, true)
        );
        assert!(s.step(Pose2::new(2.0, 0.1, 0.0), true).done);
        assert!(GoalSequencer::new(vec![], 0.0).is_err());
        assert!(GoalSequencer::new(vec![], 1.0).unwrap().progress().done);
    }
}
