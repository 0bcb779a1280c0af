//! `nav.explorer`: frontier-based exploration; hands the path planner one frontier at a time.

use petrel_actors::types::Path2;
use petrel_actors::{
    Context, Input, Module, OccupancyGrid, Output, Point2, Ports, Pose2, Range, Schedule,
};

use super::{count, param_error, MISSION_FAILED};
use crate::nav::{explore_searched, known_area, Exploration, FrontierParams};

/// Simulated seconds a new target gets before the planner's flags are taken to be about it
/// (the planner answers a new target at its next step; older flags are about the last one).
const FLAG_GRACE_S: f64 = 0.5;

/// Simulated seconds without a step after which the explorer was paused (disabled, e.g. by a
/// mission that sent the robot elsewhere): its target then starts afresh, without blame.
const PAUSE_S: f64 = 1.0;

/// `nav.explorer`: wraps the frontier search
/// ([`explore_searched`](crate::nav::frontier::explore_searched)).
pub struct ExplorerModule {
    map: Input<OccupancyGrid>,
    searched: Input<OccupancyGrid>,
    robot: Input<Pose2>,
    arrived: Input<bool>,
    failed: Input<bool>,
    sim_time: Input<f64>,
    clearance: Input<f64>,
    min_frontier_cells: Input<i64>,
    gain_weight: Input<f64>,
    blacklist_radius: Input<f64>,
    replan_s: Input<f64>,
    keep_radius: Input<f64>,
    give_up_s: Input<f64>,
    end_run: Input<bool>,
    timeout_s: Input<f64>,
    area: Input<Vec<f64>>,
    team: Input<bool>,
    assigned: Input<Vec<f64>>,
    team_done: Input<bool>,
    target: Output<Pose2>,
    given_up: Output<Path2>,
    done: Output<bool>,
    frontiers: Output<i64>,
    explored: Output<f64>,
    state: Option<State>,
}

/// What exists after a successful init.
struct State {
    params: FrontierParams,
    /// Current target and the simulated time it was handed out.
    current: Option<(Point2, f64)>,
    blacklist: Vec<Point2>,
    last_plan: f64,
    /// Simulated time of the last step.
    last_step: f64,
    over: bool,
}

impl Module for ExplorerModule {
    const TYPE: &'static str = "nav.explorer";
    const DESCRIPTION: &'static str =
        "Explores the map being built: sends the path planner to the best reachable frontier until none is left.";

    fn declare(ports: &mut Ports) -> Self {
        let module = ExplorerModule {
            map: ports.input("in/map", OccupancyGrid::default(), "the map being built"),
            searched: ports.input("in/searched", OccupancyGrid::default(), "optional: the floor a camera searched (nav.searched's out/searched); reachable free cells not searched are frontiers too, so exploring ends only when the camera looked everywhere"),
            robot: ports.input("in/robotPose", Pose2::default(), "estimated robot pose"),
            arrived: ports.input("in/arrived", false, "the planner reached the target"),
            failed: ports.input("in/failed", false, "the planner finds no path to the target"),
            sim_time: ports.input("in/simTime", 0.0, "simulated time, s"),
            clearance: ports.param_in("params/clearance", 0.3, Range::new(0.0, 5.0), "distance the robot's centre keeps from walls, m (frontiers closer are unreachable)"),
            min_frontier_cells: ports.param_in("params/min_frontier_cells", 4, Range::new(1.0, 1e6), "smaller frontiers are ignored, cells"),
            gain_weight: ports.param_in("params/gain_weight", 0.05, Range::new(0.0, 100.0), "metres of travel one frontier cell is worth"),
            blacklist_radius: ports.param_in("params/blacklist_radius", 0.6, Range::new(0.01, 100.0), "frontiers this close to a target reached or failed before are skipped, m"),
            replan_s: ports.param_in("params/replan_s", 2.0, Range::new(0.05, 1e4), "re-evaluate frontiers at least this often, simulated s"),
            keep_radius: ports.param_in("params/keep_radius", 1.0, Range::new(0.0, 100.0), "keep the current target while a frontier stays this close to it, m"),
            give_up_s: ports.param_in("params/give_up_s", 60.0, Range::new(0.1, 1e7), "a target not reached within this many simulated seconds is given up (and skipped from then on)"),
            end_run: ports.param("params/end_run", false, "end the run when exploration is done (exit 0) or times out (exit 1)"),
            timeout_s: ports.param_in("params/timeout_s", 0.0, Range::new(0.0, 1e7), "simulated time after which exploration fails, s (0 = none)"),
            area: {
                let area = ports.param("params/area", Vec::new(), "explore only frontiers in `[x0, y0, x1, y1]` (a robot's share of a team's search); empty = everywhere. Read at every step: a new area starts exploring again");
                ports.accept_last(area_fits, "`[]` or `[x0, y0, x1, y1]` with x0 < x1 and y0 < y1");
                area
            },
            team: ports.param("params/team", false, "follow a team's search: go to the frontier `in/assigned` names (a coordinator's nav.team_search allocates it on the team's merged map) instead of choosing one on this robot's map; done when `in/teamDone` is"),
            assigned: ports.input("in/assigned", Vec::new(), "with params/team: the frontier to explore, `[x, y]`; empty = none for now"),
            team_done: ports.input("in/teamDone", false, "with params/team: the team's search is over"),
            given_up: ports.output("out/givenUp", Path2::default(), "targets reached or given up (never chosen again; a team's search reads them)"),
            target: ports.output("out/targetPose", Pose2::default(), "the frontier to explore next"),
            done: ports.output("out/done", false, "no reachable frontier is left"),
            frontiers: ports.output("out/frontiers", 0, "reachable frontiers at the last evaluation"),
            explored: ports.output("out/explored", 0.0, "known area of the map, m²"),
            state: None,
        };
        // Read only by `init`: a running agent refuses new values for these.
        ports.read_at_start(&[
            "params/clearance",
            "params/min_frontier_cells",
            "params/gain_weight",
            "params/blacklist_radius",
        ]);
        module
    }

    fn schedule(&self) -> Schedule {
        // Simulated time too: a robot that arrived within the grace period, before a static map,
        // must still get its next target (a step that decides nothing returns at once).
        Schedule::new()
            .on_change(&self.map)
            .on_change(&self.arrived)
            .on_change(&self.failed)
            .on_change(&self.sim_time)
            .on_change(&self.area)
            .on_change(&self.assigned)
            .on_change(&self.team_done)
    }

    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let params = FrontierParams {
            area: self.area()?,
            clearance: self.clearance.value(),
            min_frontier_cells: count("min_frontier_cells", self.min_frontier_cells.value())?,
            gain_weight: self.gain_weight.value(),
            blacklist_radius: self.blacklist_radius.value(),
            ..FrontierParams::default()
        };
        params.validate().map_err(|e| param_error(e, &[]))?;
        for (name, v) in [
            ("replan_s", self.replan_s.value()),
            ("keep_radius", self.keep_radius.value()),
            ("timeout_s", self.timeout_s.value()),
            ("give_up_s", self.give_up_s.value()),
        ] {
            crate::sim::error::non_negative(name, v).map_err(|e| param_error(e, &[]))?;
        }
        self.state = Some(State {
            params,
            current: None,
            blacklist: Vec::new(),
            last_plan: f64::NEG_INFINITY,
            last_step: f64::NEG_INFINITY,
            over: false,
        });
        Ok(())
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        if self.team.value() {
            return self.step_team(ctx);
        }
        let t = self.sim_time.value();
        let area = self.area()?;
        let state = super::initialized(&mut self.state);
        if area != state.params.area {
            // A new share of the search (a team reassigning areas): explore again.
            state.params.area = area;
            state.over = false;
            state.current = None;
            state.last_plan = f64::NEG_INFINITY;
            self.done.set(false);
        }
        if state.over {
            return Ok(());
        }
        if t - state.last_step > PAUSE_S && state.current.is_some() {
            // Back from a pause: the robot is elsewhere, the planner's flags are about another
            // target, and the time away says nothing about this one. Choose again.
            state.current = None;
        }
        state.last_step = t;
        let timeout = self.timeout_s.value();
        if timeout > 0.0 && t > timeout && self.end_run.value() {
            state.over = true;
            ctx.stop_agent(
                MISSION_FAILED,
                format!("exploration failed: timeout after {t:.1} s"),
            );
            return Ok(());
        }
        let settled = state
            .current
            .is_some_and(|(_, since)| t - since >= FLAG_GRACE_S);
        let overdue = state
            .current
            .is_some_and(|(_, since)| t - since > self.give_up_s.value());
        let mut force = state.current.is_none();
        if settled && (self.failed.value() || overdue) {
            // No path to this frontier, or no way to get there in time (blocked, circling): do
            // not pick it (or its neighbours) again.
            let (p, _) = state.current.take().expect("settled");
            state.blacklist.push(p);
            self.given_up.set(state.blacklist.clone().into());
            force = true;
        } else if settled && self.arrived.value() {
            // Arrived and a frontier is still here: the laser cannot see it from this pose
            // (behind the robot, under a table); going there again would change nothing.
            let (p, _) = state.current.take().expect("settled");
            state.blacklist.push(p);
            self.given_up.set(state.blacklist.clone().into());
            force = true;
        }
        if !force && t - state.last_plan < self.replan_s.value() {
            return Ok(());
        }
        let map = self.map.get();
        self.explored.set(known_area(&map));
        let searched = self.searched.get();
        let decision = explore_searched(
            &map,
            Some(&searched),
            self.robot.value(),
            &state.blacklist,
            &state.params,
        );
        state.last_plan = t;
        match decision {
            Exploration::Waiting => {}
            Exploration::Done => {
                self.frontiers.set(0);
                self.done.set(true);
                state.over = true;
                petrel_actors::outln!(
                    "[{}] t = {t:6.1} s  exploration done: {:.0} m² known",
                    ctx.module(),
                    self.explored.value()
                );
                if self.end_run.value() {
                    ctx.stop_agent(0, format!("exploration complete in {t:.1} s"));
                }
            }
            Exploration::Frontiers(list) => {
                self.frontiers.set(list.len() as i64);
                let keep = self.keep_radius.value();
                let kept = state.current.filter(|(p, _)| {
                    !force && list.iter().any(|f| (f.target.0 - p.0).norm() <= keep)
                });
                if kept.is_none() {
                    let next = list[0].target;
                    state.current = Some((next, t));
                    self.target.set(Pose2::new(next.0.x, next.0.y, 0.0));
                }
            }
        }
        Ok(())
    }
}

impl ExplorerModule {
    /// A step following a team's search: the target is the frontier the coordinator
    /// assigned; reaching it, failing to or running out of time gives it up (`out/givenUp`,
    /// which the coordinator reads), and the search is done when the team's is.
    fn step_team(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let t = self.sim_time.value();
        let assigned = match self.assigned.get().as_slice() {
            [] => None,
            &[x, y] if x.is_finite() && y.is_finite() => Some(Point2::new(x, y)),
            other => anyhow::bail!(
                "invalid input `in/assigned`: expected `[x, y]` or `[]`, got {other:?}"
            ),
        };
        let state = super::initialized(&mut self.state);
        if state.over {
            return Ok(());
        }
        if self.team_done.value() {
            state.over = true;
            self.done.set(true);
            petrel_actors::outln!(
                "[{}] t = {t:6.1} s  the team's search is done",
                ctx.module()
            );
            return Ok(());
        }
        if t - state.last_step > PAUSE_S {
            // Back from a pause (or the first step): whatever flags the planner shows are old.
            state.current = None;
        }
        state.last_step = t;
        if let Some((p, since)) = state.current {
            let settled = t - since >= FLAG_GRACE_S;
            let overdue = t - since > self.give_up_s.value();
            if settled && (self.failed.value() || self.arrived.value() || overdue) {
                state.current = None;
                state.blacklist.push(p);
                self.given_up.set(state.blacklist.clone().into());
            }
        }
        let radius = state.params.blacklist_radius;
        let fresh =
            assigned.filter(|p| state.blacklist.iter().all(|b| (b.0 - p.0).norm() > radius));
        match (fresh, state.current) {
            (Some(p), Some((q, _))) if p == q => {}
            (Some(p), _) => {
                state.current = Some((p, t));
                self.target.set(Pose2::new(p.0.x, p.0.y, 0.0));
            }
            (None, _) => state.current = None,
        }
        if t - state.last_plan >= self.replan_s.value() {
            state.last_plan = t;
            self.explored.set(known_area(&self.map.get()));
        }
        Ok(())
    }

    /// `params/area` as the core takes it (refused before it is set when it does not fit:
    /// [`area_fits`]).
    fn area(&self) -> anyhow::Result<Option<[f64; 4]>> {
        let area = match self.area.get().as_slice() {
            [] => None,
            &[x0, y0, x1, y1] => Some([x0, y0, x1, y1]),
            other => anyhow::bail!(
                "invalid parameter `params/area`: expected `[x0, y0, x1, y1]` or `[]`, got {other:?}"
            ),
        };
        let check = FrontierParams {
            area,
            ..FrontierParams::default()
        };
        check.validate().map_err(|e| param_error(e, &[]))?;
        Ok(area)
    }
}

/// Whether `area` is one `params/area` takes: empty, or a box the frontier search accepts.
#[allow(clippy::ptr_arg)] // the parameter is a `Vec<f64>`: a rule on it takes one
fn area_fits(area: &Vec<f64>) -> bool {
    match area.as_slice() {
        [] => true,
        &[x0, y0, x1, y1] => FrontierParams {
            area: Some([x0, y0, x1, y1]),
            ..FrontierParams::default()
        }
        .validate()
        .is_ok(),
        _ => false,
    }
}
