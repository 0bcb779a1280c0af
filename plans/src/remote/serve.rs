//! A robot's side of a team plan: carrying out the calls a coordinator sends.

use std::collections::{BTreeMap, BTreeSet};

use serde::{Deserialize, Serialize};

use super::protocol::{parse_call, Outgoing, TeamMsg};
use crate::label::CallKind;

/// An action started by a coordinator and not yet ended by it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Run {
    /// Who started it (`agent/module`): the answer goes there.
    from: String,
    run: u64,
    /// The answer was sent: an action answers once per run.
    answered: bool,
}

/// Who watches which conditions, and what they were last sent.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
struct Watcher {
    conditions: Vec<String>,
    /// Not kept across a restart: the new instance sends every value again.
    #[serde(skip)]
    sent: BTreeMap<String, bool>,
    /// Its agent is not in the team now: nothing is sent until it is back.
    away: bool,
}

/// A robot's executor core (see the module docs): which actions run for whom, and what to
/// send back.
///
/// Two agents need not see a departure alike: under load one side's lease can lapse and come
/// back while the other never noticed. So an agent seen leaving keeps its watches (paused,
/// and sent every value again when it is back: it missed the changes), and the runs it had
/// started here, which stopped when it left, are answered as failed when it is back: its plan
/// may still wait for them.
///
/// It is kept in the mission's `state/memory` (without the messages not yet sent and what
/// watchers were last sent), so that a restarted mission still answers the runs its
/// predecessor accepted and sends its watchers their values again.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Serve {
    runs: BTreeMap<String, Run>,
    watchers: BTreeMap<String, Watcher>,
    /// Runs stopped because their coordinator left, by action: answered when it is back.
    orphans: Vec<(String, Run)>,
    #[serde(skip)]
    outgoing: Vec<Outgoing>,
}

impl Serve {
    /// An executor with nothing running.
    pub fn new() -> Self {
        Self::default()
    }

    /// A message from `from` (`agent/module`): the call to carry out on a local action, if it
    /// is one (`Ok(None)` for a `Watch`, whose values go out at the next [`Serve::poll`]).
    pub fn receive(
        &mut self,
        from: &str,
        body: &str,
    ) -> Result<Option<(String, CallKind)>, String> {
        match TeamMsg::decode(body)? {
            TeamMsg::Call { action, call, run } => {
                let kind = parse_call(&call)?;
                match kind {
                    CallKind::Start | CallKind::Resume => {
                        let same = |r: &&mut Run| r.run == run && r.from == from;
                        if let Some(r) = self.runs.get_mut(&action).filter(same) {
                            // Messages arrive at least once: a start repeated (a restarted
                            // coordinator asking again) is not carried out twice, but its
                            // answer, if one was sent, goes again.
                            r.answered = false;
                            return Ok(None);
                        }
                        let r = Run {
                            from: from.to_string(),
                            run,
                            answered: false,
                        };
                        self.runs.insert(action.clone(), r);
                    }
                    CallKind::End | CallKind::Interrupt | CallKind::Fail => {
                        self.runs.remove(&action);
                    }
                }
                Ok(Some((action, kind)))
            }
            TeamMsg::Watch { conditions } => {
                let w = Watcher {
                    conditions,
                    ..Watcher::default()
                };
                self.watchers.insert(from.to_string(), w);
                Ok(None)
            }
            other => Err(format!(
                "`{from}` sent {}, which only a robot's executor sends",
                other.encode()
            )),
        }
    }

    /// Whether some agent in the team watches conditions of this one.
    pub fn has_watchers(&self) -> bool {
        self.watchers.values().any(|w| !w.away)
    }

    /// The actions running now, for whom.
    pub fn running(&self) -> impl Iterator<Item = (&str, &str)> {
        self.runs.iter().map(|(a, r)| (a.as_str(), r.from.as_str()))
    }

    /// Looks at what the actions and conditions say now: `status(action)` is
    /// `(finished, failed)`, `condition(name)` a value (`None` counts as false). A running
    /// action that finished or failed is answered once; a watched condition is sent when it
    /// differs from what its watcher was last sent.
    pub fn poll(
        &mut self,
        mut status: impl FnMut(&str) -> (bool, bool),
        mut condition: impl FnMut(&str) -> Option<bool>,
    ) {
        for (action, r) in self.runs.iter_mut().filter(|(_, r)| !r.answered) {
            let (finished, failed) = status(action);
            if finished || failed {
                r.answered = true;
                let done = TeamMsg::Done {
                    action: action.clone(),
                    run: r.run,
                    failed,
                };
                let (to, body) = (r.from.clone(), done.encode());
                self.outgoing.push(Outgoing { to, body });
            }
        }
        for (to, w) in self.watchers.iter_mut().filter(|(_, w)| !w.away) {
            let mut values = BTreeMap::new();
            for c in &w.conditions {
                let v = condition(c).unwrap_or(false);
                if w.sent.get(c) != Some(&v) {
                    w.sent.insert(c.clone(), v);
                    values.insert(c.clone(), v);
                }
            }
            if !values.is_empty() {
                let body = TeamMsg::Conditions { values }.encode();
                self.outgoing.push(Outgoing {
                    to: to.clone(),
                    body,
                });
            }
        }
    }

    /// The team's members changed: actions started by an agent no longer present are
    /// dropped and returned (to be stopped: nobody will end them), and its watches pause.
    /// An agent back in the team gets every value it watches, and a failed answer for each
    /// run that stopped while it was away.
    pub fn members<'a>(&mut self, present: impl IntoIterator<Item = &'a str>) -> Vec<String> {
        let present: BTreeSet<&str> = present.into_iter().collect();
        let gone = |from: &str| !present.contains(from.split('/').next().unwrap_or(from));
        for (from, w) in &mut self.watchers {
            match (gone(from), w.away) {
                (true, false) => w.away = true,
                (false, true) => {
                    w.away = false;
                    w.sent.clear();
                }
                _ => {}
            }
        }
        let (back, away): (Vec<_>, Vec<_>) = std::mem::take(&mut self.orphans)
            .into_iter()
            .partition(|(_, r)| !gone(&r.from));
        self.orphans = away;
        for (action, r) in back {
            let done = TeamMsg::Done {
                action,
                run: r.run,
                failed: true,
            };
            self.outgoing.push(Outgoing {
                to: r.from,
                body: done.encode(),
            });
        }
        let stopped: Vec<String> = self
            .runs
            .iter()
            .filter(|(_, r)| gone(&r.from))
            .map(|(a, _)| a.clone())
            .collect();
        for a in &stopped {
            if let Some(r) = self.runs.remove(a) {
                if !r.answered {
                    // One answer per action and coordinator: an older run of it is moot.
                    self.orphans
                        .retain(|(o, run)| !(o == a && run.from == r.from));
                    self.orphans.push((a.clone(), r));
                }
            }
        }
        stopped
    }

    /// The messages to send, in order.
    pub fn take_outgoing(&mut self) -> Vec<Outgoing> {
        std::mem::take(&mut self.outgoing)
    }
}
