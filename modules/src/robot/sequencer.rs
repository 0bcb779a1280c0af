//! `nav.goal_sequencer`: the mission. Hands out goals, reports progress, ends the run.

use std::time::Duration;

use anyhow::bail;
use petrel_actors::types::Path2;
use petrel_actors::{Context, Input, Module, Output, Ports, Pose2, Range, Schedule};
use tokio::time::Instant;

use super::check_params;
use crate::nav::GoalSequencer;
use crate::sim::error::positive;

/// Exit code of `petrel run` when the mission fails (timeout, or no path for too long).
pub const MISSION_FAILED: u8 = 1;

const NO_GOALS: &str =
    "params/goals is empty; expected at least one goal, `[(x: 1.0, y: 2.0), ...]`";

/// `nav.goal_sequencer`: wraps [`GoalSequencer`].
pub struct GoalSequencerModule {
    goals: Input<Path2>,
    tolerance: Input<f64>,
    timeout_s: Input<f64>,
    give_up_s: Input<f64>,
    report_every_s: Input<f64>,
    robot: Input<Pose2>,
    arrived: Input<bool>,
    failed: Input<bool>,
    sim_time: Input<f64>,
    target: Output<Pose2>,
    index: Output<i64>,
    reached: Output<i64>,
    done: Output<bool>,
    run: Option<Run>,
}

/// Mission state, from init on.
struct Run {
    core: GoalSequencer,
    started: Instant,
    next_report: f64,
    failing_since: Option<f64>,
    over: bool,
}

impl Module for GoalSequencerModule {
    const TYPE: &'static str = "nav.goal_sequencer";
    const DESCRIPTION: &'static str =
        "Feeds goals one at a time, prints progress, and ends the run: exit 0 when all are reached.";

    fn declare(ports: &mut Ports) -> Self {
        let module = GoalSequencerModule {
            goals: ports.param("params/goals", Path2::default(), "goals in visiting order, `[(x: 1.0, y: 2.0), ...]` (world frame)"),
            tolerance: ports.param_in("params/tolerance", 0.4, Range::new(0.01, 100.0), "distance within which an arrival at a goal counts, m (>= the planner's goal_tolerance)"),
            timeout_s: ports.param_in("params/timeout_s", 600.0, Range::new(0.1, 1e7), "mission time after which the mission fails, s"),
            give_up_s: ports.param_in("params/give_up_s", 10.0, Range::new(0.1, 1e7), "continuous planning failure after which the mission fails, s"),
            report_every_s: ports.param_in("params/report_every_s", 10.0, Range::new(0.0, 1e7), "mission time between progress lines, s (0 = only at goals)"),
            robot: ports.input("in/robotPose", Pose2::default(), "robot pose, world frame"),
            arrived: ports.input("in/arrived", false, "the planner is at the current target"),
            failed: ports.input("in/failed", false, "the planner finds no path to the current target"),
            sim_time: ports.input("in/simTime", 0.0, "mission clock, s (when never written: wall time since start)"),
            target: ports.output("out/targetPose", Pose2::default(), "the current goal"),
            index: ports.output("out/index", 0, "index of the current goal (= goal count when done)"),
            reached: ports.output("out/reached", 0, "goals reached so far"),
            done: ports.output("out/done", false, "every goal reached"),
            run: None,
        };
        // Read only by `init`: a running agent refuses new values for these.
        ports.read_at_start(&["params/goals", "params/tolerance"]);
        module
    }

    fn schedule(&self) -> Schedule {
        Schedule::new()
            .on_change(&self.robot)
            .on_change(&self.arrived)
            .on_change(&self.failed)
            // Keeps the mission clock checked when nothing moves (a stalled robot or sim).
            .timeout(Duration::from_secs(1))
    }

    /// No goal at all: `petrel check` says so, as `init` would.
    fn check(&self, _agent: &petrel_actors::AgentView) -> Vec<petrel_actors::CheckProblem> {
        match self.goals.get().points().is_empty() {
            true => vec![petrel_actors::CheckProblem::new("params/goals", NO_GOALS)],
            false => Vec::new(),
        }
    }

    async fn init(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let goals = self.goals.get();
        if goals.points().is_empty() {
            bail!("{NO_GOALS}");
        }
        let durations = [
            ("tolerance", self.tolerance.value()),
            ("timeout_s", self.timeout_s.value()),
            ("give_up_s", self.give_up_s.value()),
        ];
        check_params(positive, &durations)?;
        let poses = goals
            .points()
            .iter()
            .map(|p| Pose2::new(p.0.x, p.0.y, 0.0))
            .collect();
        let core = GoalSequencer::new(poses, self.tolerance.value())
            .map_err(|e| super::param_error(e, &[]))?;
        self.run = Some(Run {
            core,
            started: ctx.now(),
            next_report: 0.0,
            failing_since: None,
            over: false,
        });
        Ok(())
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let clock = self.sim_time.read();
        let run = super::initialized(&mut self.run);
        if run.over {
            return Ok(());
        }
        let t = if clock.version > 0 {
            *clock.value
        } else {
            ctx.now().duration_since(run.started).as_secs_f64()
        };
        let pose = self.robot.value();
        let before = run.core.progress();
        let now = run.core.step(pose, self.arrived.value());
        let total = now.total;
        if ctx.cause().first() || now.index != before.index {
            if let Some(goal) = now.goal {
                self.target.set(goal);
            }
            self.index.set(now.index as i64);
            self.reached.set(now.reached as i64);
        }
        let line = |what: &str| {
            petrel_actors::outln!(
                "[{}] t = {t:6.1} s  pose ({:6.2}, {:6.2}, {:4.0}°)  goals {}/{total}  {what}",
                ctx.module(),
                pose.x(),
                pose.y(),
                pose.theta().to_degrees(),
                now.reached
            )
        };
        if now.reached > before.reached {
            line(&format!(
                "reached goal {} ({:.2}, {:.2})",
                now.reached,
                before.goal.map_or(0.0, |g| g.x()),
                before.goal.map_or(0.0, |g| g.y())
            ));
        } else if t >= run.next_report {
            line(&now.goal.map_or(String::new(), |g| {
                format!("heading to ({:.2}, {:.2})", g.x(), g.y())
            }));
        }
        let every = self.report_every_s.value();
        // The next multiple of `every` after `t`, computed (not counted up to: a tiny `every`
        // would take forever, and below the precision of `t` would never get there).
        if every <= 0.0 {
            run.next_report = f64::INFINITY;
        } else if run.next_report <= t {
            run.next_report = ((t / every).floor() + 1.0) * every;
            if run.next_report <= t {
                run.next_report = f64::INFINITY;
            }
        }
        if now.done {
            self.done.set(true);
            run.over = true;
            ctx.stop_agent(
                0,
                match total {
                    1 => format!("mission complete: the goal reached in {t:.1} s"),
                    _ => format!("mission complete: all {total} goals reached in {t:.1} s"),
                },
            );
            return Ok(());
        }
        run.failing_since = if self.failed.value() {
            Some(run.failing_since.unwrap_or(t))
        } else {
            None
        };
        let failure = if run
            .failing_since
            .is_some_and(|since| t - since > self.give_up_s.value())
        {
            let at = now
                .goal
                .map_or(String::new(), |g| format!(" ({:.2}, {:.2})", g.x(), g.y()));
            Some(format!(
                "no path to goal {}{at} for {:.0} s (outside the map, walled in, or blocked)",
                now.index + 1,
                self.give_up_s.value()
            ))
        } else if t > self.timeout_s.value() {
            Some(format!("timeout after {t:.1} s"))
        } else {
            None
        };
        if let Some(why) = failure {
            run.over = true;
            ctx.stop_agent(
                MISSION_FAILED,
                format!(
                    "mission failed: {why}; {} of {total} goal{} reached",
                    now.reached,
                    if total == 1 { "" } else { "s" }
                ),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::MISSION_FAILED;
    use crate::robot::tests::start;

    // A goal no planner reaches (one outside the map, say): the mission fails, naming the goal.
    #[tokio::test(start_paused = true)]
    async fn a_goal_without_a_path_fails_the_mission_naming_where_it_is() {
        let agent = start(
            r#"(name: "goals", type: "nav.goal_sequencer",
                values: {"params/goals": [(x: 400.5, y: 17.25)], "params/give_up_s": 2.0,
                         "in/failed": true})"#,
        )
        .await;
        let exit = tokio::time::timeout(Duration::from_secs(60), agent.finished())
            .await
            .expect("the mission gives up within a minute");
        assert_eq!(exit.code, MISSION_FAILED);
        assert_eq!(
            exit.reason,
            "mission failed: no path to goal 1 (400.50, 17.25) for 2 s (outside the map, walled \
             in, or blocked); 0 of 1 goal reached"
        );
        agent.stop(petrel_actors::DEFAULT_STOP_TIMEOUT).await;
    }
}
