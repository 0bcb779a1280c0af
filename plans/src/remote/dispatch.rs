//! The coordinator's side of a team plan: other robots' actions and conditions.

use std::collections::{BTreeMap, BTreeSet};

use serde::{Deserialize, Serialize};

use super::protocol::{call_name, Outgoing, TeamMsg};
use super::robot_of;
use crate::label::CallKind;

/// Where one remote action stands, as the coordinator knows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
enum State {
    /// Not started, or ended / interrupted / failed by the plan.
    Idle,
    /// Started; no answer yet.
    Running,
    Finished,
    Failed,
}

#[derive(Debug, Clone)]
struct RemoteAction {
    robot: String,
    local: String,
    /// Starts so far: the run answers must name.
    run: u64,
    state: State,
}

/// What a restarted coordinator needs to go on (kept in the mission's `state/memory`): per
/// remote action, its last run and where it stands. Without it, a restarted mission would
/// number its runs from 0 again and drop the answer to the run its predecessor started.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DispatchMemory {
    runs: BTreeMap<String, (u64, State)>,
}

#[derive(Debug, Clone, Default)]
struct Robot {
    /// In the team now.
    present: bool,
    /// Was in the team at some point: a robot that was never seen is waited for, one that
    /// left is gone.
    seen: bool,
    /// Calls made before the robot first joined, sent when it does.
    held: Vec<TeamMsg>,
}

/// A robot that left the team, and the running actions that failed with it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Departure {
    /// The robot (agent) name.
    pub robot: String,
    /// Its actions that were running (full names, `robot#action`).
    pub failed: Vec<String>,
}

/// The coordinator's view of the other robots' actions and conditions (see the module docs).
///
/// Calls on a robot's action become [`TeamMsg::Call`]s to `robot/<executor>`; its
/// [`TeamMsg::Done`] answers make the action finished or failed; its conditions arrive as
/// [`TeamMsg::Conditions`] after a [`TeamMsg::Watch`]. A robot not yet in the team is waited
/// for (calls are held); a robot that left fails its running actions at once, and its
/// conditions become unknown (false), so the plan's failure branches run instead of waiting.
#[derive(Debug, Clone)]
pub struct Dispatch {
    executor: String,
    actions: BTreeMap<String, RemoteAction>,
    /// Full name → (robot, local name, last value received).
    conditions: BTreeMap<String, (String, String, Option<bool>)>,
    robots: BTreeMap<String, Robot>,
    /// Robots that sent their conditions at least once.
    answered: BTreeSet<String>,
    outgoing: Vec<Outgoing>,
}

impl Dispatch {
    /// The dispatch of the `robot#...` names among `actions` and `conditions` whose robot is
    /// not `me`; `executor` is the module that carries them out on every robot's agent.
    pub fn new<'a>(
        me: &str,
        executor: &str,
        actions: impl IntoIterator<Item = &'a str>,
        conditions: impl IntoIterator<Item = &'a str>,
    ) -> Self {
        let mut d = Dispatch {
            executor: executor.to_string(),
            actions: BTreeMap::new(),
            conditions: BTreeMap::new(),
            robots: BTreeMap::new(),
            answered: BTreeSet::new(),
            outgoing: Vec::new(),
        };
        for full in actions {
            if let Some((robot, local)) = robot_of(full).filter(|(r, _)| *r != me) {
                d.robots.entry(robot.to_string()).or_default();
                let a = RemoteAction {
                    robot: robot.to_string(),
                    local: local.to_string(),
                    run: 0,
                    state: State::Idle,
                };
                d.actions.insert(full.to_string(), a);
            }
        }
        for full in conditions {
            if let Some((robot, local)) = robot_of(full).filter(|(r, _)| *r != me) {
                d.robots.entry(robot.to_string()).or_default();
                let c = (robot.to_string(), local.to_string(), None);
                d.conditions.insert(full.to_string(), c);
            }
        }
        d
    }

    /// The robots the plan names (other than this agent), sorted.
    pub fn robots(&self) -> impl Iterator<Item = &str> {
        self.robots.keys().map(String::as_str)
    }

    /// Whether nothing is dispatched (the plan names no other robot).
    pub fn is_empty(&self) -> bool {
        self.robots.is_empty()
    }

    /// Whether `full` is another robot's action.
    pub fn has_action(&self, full: &str) -> bool {
        self.actions.contains_key(full)
    }

    /// Whether the plan reads other robots' conditions at all.
    pub fn has_conditions(&self) -> bool {
        !self.conditions.is_empty()
    }

    /// Whether `full` is another robot's condition.
    pub fn has_condition(&self, full: &str) -> bool {
        self.conditions.contains_key(full)
    }

    /// The plan called `kind` on remote action `full`.
    pub fn call(&mut self, full: &str, kind: CallKind) {
        let Some(a) = self.actions.get_mut(full) else {
            return;
        };
        if kind == CallKind::Start {
            a.run += 1;
        }
        a.state = match kind {
            CallKind::Start | CallKind::Resume => State::Running,
            CallKind::End | CallKind::Interrupt | CallKind::Fail => State::Idle,
        };
        let msg = TeamMsg::Call {
            action: a.local.clone(),
            call: call_name(kind).to_string(),
            run: a.run,
        };
        let robot = self.robots.entry(a.robot.clone()).or_default();
        match (robot.present, robot.seen) {
            (true, _) => self.outgoing.push(Outgoing {
                to: format!("{}/{}", a.robot, self.executor),
                body: msg.encode(),
            }),
            (false, false) => robot.held.push(msg),
            // Gone: starting it fails at once; stopping it has nothing left to stop.
            (false, true) => {
                if a.state == State::Running {
                    a.state = State::Failed;
                }
            }
        }
    }

    /// What [`Dispatch::restore`] needs after a restart.
    pub fn memory(&self) -> DispatchMemory {
        let runs = self
            .actions
            .iter()
            .filter(|(_, a)| a.run > 0)
            .map(|(full, a)| (full.clone(), (a.run, a.state)))
            .collect();
        DispatchMemory { runs }
    }

    /// Goes on from a predecessor's [`Dispatch::memory`]: its runs keep their numbers, so
    /// their answers are heard. Each action still running is asked again (its start repeated
    /// with the same run, sent when its robot is seen): an answer that came while no mission
    /// read the inbox is sent again, and a robot ignores a start it already carries out.
    pub fn restore(&mut self, memory: &DispatchMemory) {
        for (full, &(run, state)) in &memory.runs {
            let Some(a) = self.actions.get_mut(full) else {
                continue;
            };
            (a.run, a.state) = (run, state);
            if state == State::Running {
                let msg = TeamMsg::Call {
                    action: a.local.clone(),
                    call: call_name(CallKind::Start).to_string(),
                    run,
                };
                let robot = self.robots.entry(a.robot.clone()).or_default();
                match robot.present {
                    true => self.outgoing.push(Outgoing {
                        to: format!("{}/{}", a.robot, self.executor),
                        body: msg.encode(),
                    }),
                    false => robot.held.push(msg),
                }
            }
        }
    }

    /// Whether remote action `full` reported it finished (this run).
    pub fn finished(&self, full: &str) -> bool {
        self.actions
            .get(full)
            .is_some_and(|a| a.state == State::Finished)
    }

    /// Whether remote action `full` failed: it said so, or its robot left while it ran.
    pub fn failed(&self, full: &str) -> bool {
        self.actions
            .get(full)
            .is_some_and(|a| a.state == State::Failed)
    }

    /// The robots whose conditions the plan reads and that have not sent them yet: a team
    /// plan should not step before (an unknown condition counts as false, so `(not c)` would
    /// be taken on a guess). A robot that answered once never makes the plan wait again; when
    /// it leaves, its conditions read false.
    pub fn waiting_for(&self) -> Vec<&str> {
        let mut waiting: Vec<&str> = self
            .conditions
            .iter()
            .filter(|(_, (robot, _, value))| {
                value.is_none() && !self.answered.contains(robot.as_str())
            })
            .map(|(_, (robot, _, _))| robot.as_str())
            .collect();
        waiting.dedup();
        waiting
    }

    /// The last value robot sent for condition `full`; `None` before the first value and
    /// after the robot left.
    pub fn condition(&self, full: &str) -> Option<bool> {
        self.conditions.get(full).and_then(|c| c.2)
    }

    /// The other robots' conditions as this plan sees them, `robot#cond=true`, `=false`,
    /// or `=?` before the first value and after the robot left; comma-separated, sorted.
    pub fn conditions_shown(&self) -> String {
        let shown: Vec<String> = self
            .conditions
            .iter()
            .map(|(full, (_, _, v))| match v {
                Some(v) => format!("{full}={v}"),
                None => format!("{full}=?"),
            })
            .collect();
        shown.join(", ")
    }

    /// A message from `from` (`agent/module`). Answers from robots the plan does not name, or
    /// about runs that are over, are ignored; a body that is not a team message is an error.
    pub fn receive(&mut self, from: &str, body: &str) -> Result<(), String> {
        let robot = from.split('/').next().unwrap_or(from);
        match TeamMsg::decode(body)? {
            TeamMsg::Done {
                action,
                run,
                failed,
            } => {
                let hit = self
                    .actions
                    .values_mut()
                    .find(|a| a.robot == robot && a.local == action && a.run == run);
                if let Some(a) = hit.filter(|a| a.state == State::Running) {
                    a.state = if failed {
                        State::Failed
                    } else {
                        State::Finished
                    };
                }
                Ok(())
            }
            TeamMsg::Conditions { values } => {
                if self.robots.contains_key(robot) {
                    self.answered.insert(robot.to_string());
                }
                for (r, local, value) in self.conditions.values_mut() {
                    if r == robot {
                        if let Some(v) = values.get(local.as_str()) {
                            *value = Some(*v);
                        }
                    }
                }
                Ok(())
            }
            other => Err(format!(
                "`{from}` sent {}, which only a coordinator sends",
                other.encode()
            )),
        }
    }

    /// The team's members now (agent names). Robots that joined get the calls held for them
    /// and a `Watch` of their conditions; robots that left fail their running actions.
    pub fn members<'a>(&mut self, present: impl IntoIterator<Item = &'a str>) -> Vec<Departure> {
        let present: BTreeSet<&str> = present.into_iter().collect();
        let mut departures = Vec::new();
        for (name, robot) in &mut self.robots {
            let here = present.contains(name.as_str());
            if here && !robot.present {
                robot.present = true;
                robot.seen = true;
                let to = format!("{name}/{}", self.executor);
                let conditions: Vec<String> = self
                    .conditions
                    .values()
                    .filter(|(r, _, _)| r == name)
                    .map(|(_, local, _)| local.clone())
                    .collect();
                if !conditions.is_empty() {
                    let body = TeamMsg::Watch { conditions }.encode();
                    self.outgoing.push(Outgoing {
                        to: to.clone(),
                        body,
                    });
                }
                for msg in robot.held.drain(..) {
                    let body = msg.encode();
                    self.outgoing.push(Outgoing {
                        to: to.clone(),
                        body,
                    });
                }
            } else if !here && robot.present {
                robot.present = false;
                let mut failed = Vec::new();
                for (full, a) in &mut self.actions {
                    if &a.robot == name && a.state == State::Running {
                        a.state = State::Failed;
                        failed.push(full.clone());
                    }
                }
                for (r, _, value) in self.conditions.values_mut() {
                    if r == name {
                        *value = None;
                    }
                }
                departures.push(Departure {
                    robot: name.clone(),
                    failed,
                });
            }
        }
        departures
    }

    /// The messages to send, in order.
    pub fn take_outgoing(&mut self) -> Vec<Outgoing> {
        std::mem::take(&mut self.outgoing)
    }
}
