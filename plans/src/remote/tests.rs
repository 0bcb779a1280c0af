use super::*;
use crate::label::CallKind;

fn bodies(out: &[Outgoing]) -> Vec<(String, TeamMsg)> {
    out.iter()
        .map(|o| (o.to.clone(), TeamMsg::decode(&o.body).unwrap()))
        .collect()
}

fn call(action: &str, call: &str, run: u64) -> TeamMsg {
    TeamMsg::Call {
        action: action.into(),
        call: call.into(),
        run,
    }
}

#[test]
fn calls_wait_for_their_robot_then_go_in_order_with_a_watch_first() {
    let mut d = Dispatch::new(
        "boss",
        "executor",
        ["r1#goto_a", "r2#search", "boss#log_x", "local"],
        ["r1#seen", "r1#atDoor", "other"],
    );
    assert_eq!(d.robots().collect::<Vec<_>>(), ["r1", "r2"]);
    assert!(d.has_action("r1#goto_a") && !d.has_action("boss#log_x") && !d.has_action("local"));
    assert!(d.has_condition("r1#seen") && !d.has_condition("other"));
    d.call("r1#goto_a", CallKind::Start);
    assert!(d.take_outgoing().is_empty(), "r1 is not in the team yet");
    assert!(!d.failed("r1#goto_a") && !d.finished("r1#goto_a"));
    assert!(d.members(["boss", "r1"]).is_empty());
    assert_eq!(
        bodies(&d.take_outgoing()),
        [
            (
                "r1/executor".to_string(),
                TeamMsg::Watch {
                    conditions: vec!["atDoor".into(), "seen".into()]
                }
            ),
            ("r1/executor".to_string(), call("goto_a", "start", 1)),
        ]
    );
    d.call("r1#goto_a", CallKind::Interrupt);
    assert_eq!(
        bodies(&d.take_outgoing()),
        [("r1/executor".to_string(), call("goto_a", "interrupt", 1))]
    );
}

#[test]
fn answers_finish_or_fail_the_run_they_name_and_stale_ones_are_dropped() {
    let mut d = Dispatch::new("boss", "ex", ["r1#go"], []);
    d.members(["r1"]);
    d.call("r1#go", CallKind::Start);
    d.call("r1#go", CallKind::Interrupt);
    d.call("r1#go", CallKind::Start);
    let done = |run, failed| {
        TeamMsg::Done {
            action: "go".into(),
            run,
            failed,
        }
        .encode()
    };
    // The answer to the first run crosses the second start: it is not about this run.
    d.receive("r1/ex", &done(1, false)).unwrap();
    assert!(!d.finished("r1#go"));
    // Another robot answering for r1's action is not r1.
    d.receive("r2/ex", &done(2, false)).unwrap();
    assert!(!d.finished("r1#go"));
    d.receive("r1/ex", &done(2, true)).unwrap();
    assert!(d.failed("r1#go") && !d.finished("r1#go"));
    d.call("r1#go", CallKind::Fail);
    assert!(!d.failed("r1#go"), "the plan took the failure");
    assert!(d
        .receive("r1/ex", "Hello")
        .unwrap_err()
        .contains("expected Call(..)"));
    let err = d
        .receive("r1/ex", &call("go", "start", 1).encode())
        .unwrap_err();
    assert!(err.contains("only a coordinator sends"), "{err}");
}

#[test]
fn a_robot_leaving_fails_its_running_actions_and_forgets_its_conditions() {
    let mut d = Dispatch::new("boss", "ex", ["r1#go", "r1#look", "r2#go"], ["r1#seen"]);
    d.members(["r1", "r2"]);
    assert_eq!(d.conditions_shown(), "r1#seen=?");
    d.call("r1#go", CallKind::Start);
    d.call("r2#go", CallKind::Start);
    let values = TeamMsg::Conditions {
        values: [("seen".to_string(), true)].into(),
    };
    d.receive("r1/ex", &values.encode()).unwrap();
    assert_eq!(d.condition("r1#seen"), Some(true));
    assert_eq!(d.conditions_shown(), "r1#seen=true");
    let gone = d.members(["r2"]);
    assert_eq!(
        gone,
        [Departure {
            robot: "r1".into(),
            failed: vec!["r1#go".into()]
        }]
    );
    assert!(d.failed("r1#go") && !d.failed("r1#look") && !d.failed("r2#go"));
    assert_eq!(d.condition("r1#seen"), None);
    assert_eq!(d.conditions_shown(), "r1#seen=?");
    // Starting an action of a robot that is gone fails it at once; nothing is sent.
    d.take_outgoing();
    d.call("r1#look", CallKind::Start);
    assert!(d.failed("r1#look") && d.take_outgoing().is_empty());
    // Back in the team: watched again, and new starts go out.
    d.members(["r1", "r2"]);
    let sent = bodies(&d.take_outgoing());
    assert!(
        matches!(&sent[..], [(_, TeamMsg::Watch { .. })]),
        "{sent:?}"
    );
}

#[test]
fn an_executor_answers_each_run_once_and_sends_watched_conditions_when_they_change() {
    let mut s = Serve::new();
    let got = s
        .receive("boss/m", &call("go", "start", 3).encode())
        .unwrap();
    assert_eq!(got, Some(("go".to_string(), CallKind::Start)));
    let watch = TeamMsg::Watch {
        conditions: vec!["seen".into()],
    };
    assert_eq!(s.receive("boss/m", &watch.encode()).unwrap(), None);
    let mut seen = false;
    let mut done = (false, false);
    for _ in 0..2 {
        s.poll(|_| done, |_| Some(seen));
    }
    assert_eq!(
        bodies(&s.take_outgoing()),
        [(
            "boss/m".to_string(),
            TeamMsg::Conditions {
                values: [("seen".to_string(), false)].into()
            }
        )]
    );
    seen = true;
    done = (true, false);
    for _ in 0..2 {
        s.poll(|_| done, |_| Some(seen));
    }
    let sent = bodies(&s.take_outgoing());
    assert_eq!(
        sent,
        [
            (
                "boss/m".to_string(),
                TeamMsg::Done {
                    action: "go".into(),
                    run: 3,
                    failed: false
                }
            ),
            (
                "boss/m".to_string(),
                TeamMsg::Conditions {
                    values: [("seen".to_string(), true)].into()
                }
            ),
        ]
    );
    assert_eq!(
        s.receive("boss/m", &call("go", "end", 3).encode()).unwrap(),
        Some(("go".to_string(), CallKind::End))
    );
    assert_eq!(s.running().count(), 0);
    let err = s
        .receive("boss/m", &call("go", "jump", 3).encode())
        .unwrap_err();
    assert!(err.contains("unknown call `jump`"), "{err}");
}

/// What `state/memory` keeps of an executor: a restarted mission still answers the run its
/// predecessor accepted, to the coordinator that started it, and sends its watcher every
/// value again.
#[test]
fn an_executor_restored_from_its_memory_answers_the_runs_it_had_and_resends_watched_values() {
    let mut s = Serve::new();
    s.receive("boss/m", &call("go", "start", 7).encode())
        .unwrap();
    let watch = TeamMsg::Watch {
        conditions: vec!["seen".into()],
    };
    s.receive("boss/m", &watch.encode()).unwrap();
    s.poll(|_| (false, false), |_| Some(true));
    assert_eq!(s.take_outgoing().len(), 1, "the watched value went out");
    let text = ron::to_string(&s).unwrap();
    let mut restored: Serve = ron::from_str(&text).unwrap();
    assert_eq!(restored.running().collect::<Vec<_>>(), [("go", "boss/m")]);
    restored.poll(|_| (true, false), |_| Some(true));
    assert_eq!(
        bodies(&restored.take_outgoing()),
        [
            (
                "boss/m".to_string(),
                TeamMsg::Done {
                    action: "go".into(),
                    run: 7,
                    failed: false
                }
            ),
            (
                "boss/m".to_string(),
                TeamMsg::Conditions {
                    values: [("seen".to_string(), true)].into()
                }
            ),
        ]
    );
}

/// What `state/memory` keeps of a coordinator: a restarted mission hears the answer to the run
/// its predecessor started, and asks the robot again once it sees it (an answer sent while no
/// mission read the inbox is not lost); finished and idle actions are not asked.
#[test]
fn a_dispatch_restored_from_its_memory_hears_its_runs_and_asks_the_running_ones_again() {
    let actions = ["r1#go", "r1#look", "r2#wait"];
    let mut d = Dispatch::new("boss", "ex", actions, []);
    d.members(["r1", "r2"]);
    d.call("r1#go", CallKind::Start);
    d.call("r1#go", CallKind::Interrupt);
    d.call("r1#go", CallKind::Start);
    d.call("r1#look", CallKind::Start);
    let done = |action: &str, run| TeamMsg::Done {
        action: action.into(),
        run,
        failed: false,
    };
    d.receive("r1/ex", &done("look", 1).encode()).unwrap();
    let text = ron::to_string(&d.memory()).unwrap();
    let memory: DispatchMemory = ron::from_str(&text).unwrap();
    let mut restored = Dispatch::new("boss", "ex", actions, []);
    restored.restore(&memory);
    assert!(restored.finished("r1#look") && !restored.finished("r1#go"));
    assert!(restored.take_outgoing().is_empty(), "r1 is not seen yet");
    restored.members(["r1", "r2"]);
    assert_eq!(
        bodies(&restored.take_outgoing()),
        [("r1/ex".to_string(), call("go", "start", 2))],
        "only the running run is asked again, with its number"
    );
    restored.receive("r1/ex", &done("go", 2).encode()).unwrap();
    assert!(restored.finished("r1#go"));
    // A fresh dispatch (no memory) drops that answer: the run is not one it started.
    let mut fresh = Dispatch::new("boss", "ex", actions, []);
    fresh.members(["r1", "r2"]);
    fresh.receive("r1/ex", &done("go", 2).encode()).unwrap();
    assert!(!fresh.finished("r1#go"));
}

/// Messages arrive at least once: a start repeated for the run being carried out is not
/// carried out again, and the answer already sent for it goes again.
#[test]
fn an_executor_repeats_its_answer_to_a_repeated_start_and_starts_nothing() {
    let mut s = Serve::new();
    let start = call("go", "start", 3).encode();
    assert_eq!(
        s.receive("boss/m", &start).unwrap(),
        Some(("go".to_string(), CallKind::Start))
    );
    s.poll(|_| (true, false), |_| None);
    assert_eq!(s.take_outgoing().len(), 1, "the answer went out");
    s.poll(|_| (true, false), |_| None);
    assert!(s.take_outgoing().is_empty(), "once per run");
    assert_eq!(
        s.receive("boss/m", &start).unwrap(),
        None,
        "not started again"
    );
    s.poll(|_| (true, false), |_| None);
    let again = TeamMsg::Done {
        action: "go".into(),
        run: 3,
        failed: false,
    };
    assert_eq!(bodies(&s.take_outgoing()), [("boss/m".to_string(), again)]);
    // A new run of it is a start.
    assert_eq!(
        s.receive("boss/m", &call("go", "start", 4).encode())
            .unwrap(),
        Some(("go".to_string(), CallKind::Start))
    );
}

#[test]
fn an_executor_drops_the_actions_of_a_coordinator_that_left() {
    let mut s = Serve::new();
    s.receive("boss/m", &call("go", "start", 1).encode())
        .unwrap();
    s.receive("boss2/m", &call("look", "start", 1).encode())
        .unwrap();
    assert_eq!(s.members(["r1", "boss2"]), ["go"]);
    assert_eq!(s.running().collect::<Vec<_>>(), [("look", "boss2/m")]);
}

#[test]
fn an_agent_seen_leaving_and_back_gets_its_watched_values_again_and_its_stopped_runs_failed() {
    let mut s = Serve::new();
    s.receive("boss/m", &call("go", "start", 4).encode())
        .unwrap();
    let watch = TeamMsg::Watch {
        conditions: vec!["seen".into()],
    };
    s.receive("boss/m", &watch.encode()).unwrap();
    s.poll(|_| (false, false), |_| Some(false));
    s.take_outgoing();
    // Only this side saw boss go (its lease lapsed under load): the run stops here, and the
    // change of `seen` while boss is away is sent to nobody.
    assert_eq!(s.members(["r1"]), ["go"]);
    s.poll(|_| (false, false), |_| Some(true));
    assert!(s.take_outgoing().is_empty() && !s.has_watchers());
    // boss never saw itself leave, so it sends no new watch: it is sent what it missed.
    assert!(s.members(["r1", "boss"]).is_empty());
    s.poll(|_| (false, false), |_| Some(true));
    assert_eq!(
        bodies(&s.take_outgoing()),
        [
            (
                "boss/m".to_string(),
                TeamMsg::Done {
                    action: "go".into(),
                    run: 4,
                    failed: true
                }
            ),
            (
                "boss/m".to_string(),
                TeamMsg::Conditions {
                    values: [("seen".to_string(), true)].into()
                }
            ),
        ]
    );
    // Answered once: another flap sends only the values again.
    s.members(["r1"]);
    s.members(["r1", "boss"]);
    s.poll(|_| (false, false), |_| Some(true));
    assert_eq!(bodies(&s.take_outgoing()).len(), 1);
}

/// A team plan stepped against a [`Dispatch`], with robots whose executors are [`Serve`]s
/// and whose actions finish when the test says: the whole exchange, without a network.
mod plan_over_a_team {
    use std::collections::{BTreeMap, BTreeSet};

    use super::*;
    use crate::exec::{step, Environment, PlanState, PlanStatus};
    use crate::model::Plan;

    struct Env<'a>(&'a mut Dispatch);

    impl Environment for Env<'_> {
        fn condition(&mut self, name: &str) -> Option<bool> {
            Some(self.0.condition(name).unwrap_or(false))
        }
        fn step_action(&mut self, _: &str) {}
        fn action_finished(&mut self, name: &str) -> bool {
            self.0.finished(name)
        }
        fn action_failed(&mut self, name: &str) -> bool {
            self.0.failed(name)
        }
        fn call(&mut self, name: &str, kind: CallKind) {
            self.0.call(name, kind)
        }
    }

    #[derive(Default)]
    struct Robot {
        serve: Serve,
        /// Calls received, as `action.call`.
        log: Vec<String>,
        finished: BTreeSet<String>,
        conditions: BTreeMap<String, bool>,
    }

    struct Team {
        plan: Plan,
        state: PlanState,
        dispatch: Dispatch,
        robots: BTreeMap<String, Robot>,
        present: Vec<String>,
    }

    impl Team {
        fn new(text: &str) -> Team {
            let plan = crate::compile_text(text, "team.plan", "team", None).unwrap();
            let actions: Vec<String> = plan.executables().iter().map(|e| e.name.clone()).collect();
            let dispatch = Dispatch::new(
                "boss",
                "ex",
                actions.iter().map(String::as_str),
                plan.conditions().iter().map(String::as_str),
            );
            let robots = dispatch
                .robots()
                .map(|r| (r.to_string(), Robot::default()))
                .collect();
            Team {
                state: PlanState::new(&plan),
                plan,
                dispatch,
                robots,
                present: vec!["boss".into(), "r1".into(), "r2".into()],
            }
        }

        /// Plan steps and message exchanges until nothing moves (bounded).
        fn settle(&mut self) -> PlanStatus {
            for _ in 0..50 {
                self.dispatch
                    .members(self.present.iter().map(String::as_str));
                if self.dispatch.waiting_for().is_empty() {
                    step(&self.plan, &mut self.state, &mut Env(&mut self.dispatch));
                }
                for o in self.dispatch.take_outgoing() {
                    let (robot, _) = o.to.split_once('/').unwrap();
                    let r = self.robots.get_mut(robot).unwrap();
                    if let Some((action, kind)) = r.serve.receive("boss/m", &o.body).unwrap() {
                        r.log.push(format!("{action}.{kind}"));
                    }
                }
                for (name, r) in &mut self.robots {
                    if !self.present.contains(name) {
                        continue;
                    }
                    let (finished, conditions) = (&r.finished, &r.conditions);
                    r.serve.poll(
                        |a| (finished.contains(a), false),
                        |c| conditions.get(c).copied(),
                    );
                    for o in r.serve.take_outgoing() {
                        self.dispatch
                            .receive(&format!("{name}/ex"), &o.body)
                            .unwrap();
                    }
                }
            }
            self.state.status(&self.plan)
        }
    }

    #[test]
    fn each_robot_carries_out_its_own_actions_and_the_plan_reaches_its_goal() {
        let mut t = Team::new("{ r1#search_west } || { r2#search_east }; r1#report");
        assert_eq!(t.settle(), PlanStatus::Running);
        assert_eq!(t.robots["r1"].log, ["search_west.start"]);
        assert_eq!(t.robots["r2"].log, ["search_east.start"]);
        t.robots
            .get_mut("r1")
            .unwrap()
            .finished
            .insert("search_west".into());
        t.robots
            .get_mut("r2")
            .unwrap()
            .finished
            .insert("search_east".into());
        t.robots
            .get_mut("r1")
            .unwrap()
            .finished
            .insert("report".into());
        assert_eq!(t.settle(), PlanStatus::Goal);
        assert_eq!(
            t.robots["r1"].log,
            [
                "search_west.start",
                "search_west.end",
                "report.start",
                "report.end"
            ]
        );
        assert_eq!(t.robots["r2"].log, ["search_east.start", "search_east.end"]);
    }

    #[test]
    fn a_condition_named_with_a_robot_is_read_from_that_robot() {
        let mut t = Team::new("< r1#doorOpen ? r2#enter : (not r1#doorOpen) ? r2#knock >");
        // Before r1 says anything the door is unknown: neither branch may be taken on a guess.
        t.present = vec!["boss".into(), "r2".into()];
        assert_eq!(t.settle(), PlanStatus::Running);
        assert_eq!(t.dispatch.waiting_for(), ["r1"]);
        assert!(t.robots["r2"].log.is_empty(), "{:?}", t.robots["r2"].log);
        t.robots
            .get_mut("r1")
            .unwrap()
            .conditions
            .insert("doorOpen".into(), true);
        t.present.push("r1".into());
        t.settle();
        assert_eq!(t.robots["r2"].log, ["enter.start"]);
        // r1 leaving makes the door unknown, which never makes the plan wait again.
        t.present.retain(|r| r != "r1");
        t.settle();
        assert!(
            t.dispatch.waiting_for().is_empty() && t.dispatch.condition("r1#doorOpen").is_none()
        );
    }

    #[test]
    fn a_robot_leaving_fails_its_action_and_the_recovery_hands_its_area_to_another() {
        let mut t = Team::new(
            "{ r1#search_west ! *if* action_failed *do* r2#search_west; skip_action ! } || { r2#search_east }",
        );
        t.settle();
        t.present.retain(|r| r != "r1");
        t.settle();
        assert_eq!(
            t.robots["r2"].log,
            ["search_east.start", "search_west.start"]
        );
        for a in ["search_east", "search_west"] {
            t.robots.get_mut("r2").unwrap().finished.insert(a.into());
        }
        assert_eq!(t.settle(), PlanStatus::Goal);
    }
}
