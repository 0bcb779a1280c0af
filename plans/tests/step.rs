//! The step semantics.
mod common;

use common::*;
use petrel_plans::{load_plan, step, PlanState, PlanStatus, Script, ScriptedEnv};

#[test]
fn enabled_set_is_computed_once_per_step() {
    let p = net(
        &[("A", 1), ("B", 0), ("C", 0)],
        &["[]", "[]"],
        &[
            ("n0", "t0", 1),
            ("t0", "n1", 1),
            ("n1", "t1", 1),
            ("t1", "n2", 1),
        ],
    );
    let mut st = PlanState::new(&p);
    let mut env = TestEnv::default();
    assert_eq!(step(&p, &mut st, &mut env).fired, [0]);
    assert_eq!(marking(&p, &st), [("B".into(), 1)]);
    assert_eq!(step(&p, &mut st, &mut env).fired, [1]);
    assert_eq!(marking(&p, &st), [("C".into(), 1)]);
}

#[test]
fn conflicts_go_to_the_first_transition_in_document_order() {
    let arcs = [
        ("n0", "t0", 1),
        ("t0", "n1", 1),
        ("n0", "t1", 1),
        ("t1", "n2", 1),
    ];
    let p = net(&[("P", 1), ("left", 0), ("right", 0)], &["[]", "[]"], &arcs);
    let mut st = PlanState::new(&p);
    assert_eq!(step(&p, &mut st, &mut TestEnv::default()).fired, [0]);
    assert_eq!(marking(&p, &st), [("left".into(), 1)]);
    // With two tokens both fire in the same step.
    let p = net(&[("P", 2), ("left", 0), ("right", 0)], &["[]", "[]"], &arcs);
    let mut st = PlanState::new(&p);
    assert_eq!(step(&p, &mut st, &mut TestEnv::default()).fired, [0, 1]);
    // The first one is skipped when its guard is false.
    let p = net(
        &[("P", 1), ("left", 0), ("right", 0)],
        &["[c]", "[]"],
        &arcs,
    );
    let mut st = PlanState::new(&p);
    assert_eq!(
        step(&p, &mut st, &mut TestEnv::default().cond("c", false)).fired,
        [1]
    );
}

#[test]
fn arc_weights_count() {
    let p = net(
        &[("P", 1), ("Q", 0)],
        &["[]"],
        &[("n0", "t0", 2), ("t0", "n1", 3)],
    );
    let mut st = PlanState::new(&p);
    assert!(step(&p, &mut st, &mut TestEnv::default()).fired.is_empty());
    let p = net(
        &[("P", 2), ("Q", 0)],
        &["[]"],
        &[("n0", "t0", 2), ("t0", "n1", 3)],
    );
    let mut st = PlanState::new(&p);
    step(&p, &mut st, &mut TestEnv::default());
    assert_eq!(marking(&p, &st), [("Q".into(), 3)]);
}

fn sense_net() -> petrel_plans::Plan {
    net(
        &[("sense.exec", 1), ("seen", 0), ("done", 0)],
        &["sense.end [obstacle]", "sense.end"],
        &[
            ("n0", "t0", 1),
            ("t0", "n1", 1),
            ("n0", "t1", 1),
            ("t1", "n2", 1),
        ],
    )
}

#[test]
fn explicit_guard_replaces_the_default() {
    let p = sense_net();
    // Finished but no obstacle: the default-guarded transition fires.
    let mut st = PlanState::new(&p);
    let mut env = TestEnv::default().cond("obstacle", false);
    env.finished.insert("sense".into());
    assert_eq!(run(&p, &mut st, &mut env), ["sense.end"]);
    assert_eq!(marking(&p, &st), [("done".into(), 1)]);
    // Obstacle while not finished: the explicit guard fires anyway.
    let mut st = PlanState::new(&p);
    let mut env = TestEnv::default().cond("obstacle", true);
    assert_eq!(run(&p, &mut st, &mut env), ["sense.end"]);
    assert_eq!(marking(&p, &st), [("seen".into(), 1)]);
    assert_eq!(env.stepped, ["sense"]);
    assert_eq!(env.calls, ["sense.end"]);
    // Neither: nothing.
    let mut st = PlanState::new(&p);
    assert!(run(&p, &mut st, &mut TestEnv::default().cond("obstacle", false)).is_empty());
}

#[test]
fn failed_default_guard() {
    let p = net(
        &[("a.ex", 1), ("ko", 0)],
        &["a.fail"],
        &[("n0", "t0", 1), ("t0", "n1", 1)],
    );
    let mut st = PlanState::new(&p);
    let mut env = TestEnv::default();
    assert!(run(&p, &mut st, &mut env).is_empty());
    env.failed.insert("a".into());
    assert_eq!(run(&p, &mut st, &mut env), ["a.fail"]);
}

#[test]
fn calls_follow_label_order() {
    let p = net(
        &[("x.ex", 1), ("y.ex", 0)],
        &["[] x.interrupt y.start x.end"],
        &[("n0", "t0", 1), ("t0", "n1", 1)],
    );
    let mut st = PlanState::new(&p);
    assert_eq!(
        run(&p, &mut st, &mut TestEnv::default()),
        ["x.interrupt", "y.start", "x.end"]
    );
}

#[test]
fn interrupt_and_resume() {
    let p = load_plan(&fixture("editor_patrol.pnml"), None)
        .unwrap()
        .plan;
    let mut st = PlanState::new(&p);
    let mut env = TestEnv::default().cond("battery_low", false);
    assert_eq!(run(&p, &mut st, &mut env), ["patrol.start"]);
    assert!(run(&p, &mut st, &mut env).is_empty());
    env.conditions.insert("battery_low".into(), true);
    assert_eq!(run(&p, &mut st, &mut env), ["patrol.interrupt"]);
    assert_eq!(marking(&p, &st), [("paused".into(), 1)]);
    let stepped = env.stepped.len();
    assert!(run(&p, &mut st, &mut env).is_empty());
    assert_eq!(
        env.stepped.len(),
        stepped,
        "an interrupted action is not stepped"
    );
    env.conditions.insert("battery_low".into(), false);
    assert_eq!(run(&p, &mut st, &mut env), ["patrol.resume"]);
    env.finished.insert("patrol".into());
    assert_eq!(run(&p, &mut st, &mut env), ["patrol.end"]);
    assert_eq!(st.status(&p), PlanStatus::Goal);
    assert_eq!(
        env.calls,
        [
            "patrol.start",
            "patrol.interrupt",
            "patrol.resume",
            "patrol.end"
        ]
    );
}

#[test]
fn fork_and_join() {
    let p = net(
        &[
            ("P", 1),
            ("a.ex", 0),
            ("b.ex", 0),
            ("Ea", 0),
            ("Eb", 0),
            ("goal", 0),
        ],
        &["Fork start", "a.end", "b.end", "join"],
        &[
            ("n0", "t0", 1),
            ("t0", "n1", 1),
            ("t0", "n2", 1),
            ("n1", "t1", 1),
            ("t1", "n3", 1),
            ("n2", "t2", 1),
            ("t2", "n4", 1),
            ("n3", "t3", 1),
            ("n4", "t3", 1),
            ("t3", "n5", 1),
        ],
    );
    let mut st = PlanState::new(&p);
    let mut env = TestEnv::default();
    assert_eq!(run(&p, &mut st, &mut env), ["a.start", "b.start"]);
    assert!(run(&p, &mut st, &mut env).is_empty());
    assert_eq!(env.stepped, ["a", "b"]);
    env.finished.insert("a".into());
    assert_eq!(run(&p, &mut st, &mut env), ["a.end"]);
    assert!(
        run(&p, &mut st, &mut env).is_empty(),
        "the join waits for both branches"
    );
    env.finished.insert("b".into());
    assert_eq!(run(&p, &mut st, &mut env), ["b.end"]);
    assert_eq!(st.status(&p), PlanStatus::Running);
    run(&p, &mut st, &mut env);
    assert_eq!(st.status(&p), PlanStatus::Goal);
}

#[test]
fn places_of_one_name_share_one_executable() {
    let p = net(&[("x.ex", 1), ("x.exec", 1)], &[], &[]);
    assert_eq!(p.executables().len(), 1);
    let mut st = PlanState::new(&p);
    let mut env = TestEnv::default();
    step(&p, &mut st, &mut env);
    assert_eq!(env.stepped, ["x"]);
}

#[test]
fn goal_and_fail_must_be_exact() {
    let p = net(&[("goal", 2)], &[], &[]);
    assert_eq!(PlanState::new(&p).status(&p), PlanStatus::Running);
    let p = net(&[("goal(2)", 2)], &[], &[]);
    assert_eq!(PlanState::new(&p).status(&p), PlanStatus::Goal);
    let p = net(&[("goal", 1), ("goal(2)", 1)], &[], &[]);
    assert_eq!(PlanState::new(&p).status(&p), PlanStatus::Running);
    let p = net(&[("fail", 1), ("goal", 0)], &[], &[]);
    assert_eq!(PlanState::new(&p).status(&p), PlanStatus::Fail);
    let p = net(&[("a.ex goal(1) fail(1)", 1)], &[], &[]);
    assert_eq!(PlanState::new(&p).status(&p), PlanStatus::Goal);
    let p = net(&[("GOAL", 1)], &[], &[]);
    assert!(p.goal_places().is_empty());
}

#[test]
fn a_finished_plan_does_nothing() {
    let p = net(
        &[("goal", 1), ("a.ex", 1), ("Q", 0)],
        &["[]"],
        &[("n1", "t0", 1), ("t0", "n2", 1)],
    );
    let mut st = PlanState::new(&p);
    let mut env = TestEnv::default();
    let r = step(&p, &mut st, &mut env);
    assert!(r.fired.is_empty() && env.stepped.is_empty());
}

#[test]
fn joined_branches_that_put_two_tokens_in_goal_never_reach_goal() {
    let p = net(
        &[("P", 1), ("w.ex", 0), ("w.exec", 0), ("goal", 0)],
        &["start", "end", "end"],
        &[
            ("n0", "t0", 1),
            ("t0", "n1", 1),
            ("t0", "n2", 1),
            ("n1", "t1", 1),
            ("t1", "n3", 1),
            ("n2", "t2", 1),
            ("t2", "n3", 1),
        ],
    );
    let mut st = PlanState::new(&p);
    let mut env = TestEnv::default();
    run(&p, &mut st, &mut env);
    env.finished.insert("w".into());
    assert_eq!(run(&p, &mut st, &mut env), ["w.end", "w.end"]);
    assert_eq!(marking(&p, &st), [("goal".into(), 2)]);
    assert_eq!(st.status(&p), PlanStatus::Running);
    let report = petrel_plans::check(&p);
    assert!(
        report
            .warnings
            .iter()
            .any(|w| w.code == "goal-unreachable" && w.message.contains("gets 2 tokens")),
        "{report}"
    );
}

#[test]
fn unknown_conditions_are_false_and_reported_once() {
    let p = net(
        &[("P", 1), ("Q", 0)],
        &["[mystery]"],
        &[("n0", "t0", 1), ("t0", "n1", 1)],
    );
    let mut st = PlanState::new(&p);
    let mut env = TestEnv::default();
    let r = step(&p, &mut st, &mut env);
    assert_eq!(r.unknown_conditions, ["mystery"]);
    assert!(r.fired.is_empty());
    assert!(step(&p, &mut st, &mut env).unknown_conditions.is_empty());
    assert_eq!(env.asked, ["mystery", "mystery"]);
}

#[test]
fn start_restarts_the_step_count() {
    // The restart transition comes first, so at step 3 it takes the token
    // a.end needs; a then needs two more steps.
    let p = net(
        &[("P", 1), ("a.ex", 0), ("goal", 0), ("a.exec", 0)],
        &["a.start", "[again] a.start", "a.end", "a.end"],
        &[
            ("n0", "t0", 1),
            ("t0", "n1", 1),
            ("n1", "t1", 1),
            ("t1", "n3", 1),
            ("n1", "t2", 1),
            ("t2", "n2", 1),
            ("n3", "t3", 1),
            ("t3", "n2", 1),
        ],
    );
    let script = Script::parse("cond again 3 3", "s").unwrap();
    let mut env = ScriptedEnv::new(&script);
    let mut st = PlanState::new(&p);
    let mut log = Vec::new();
    for k in 1..=5 {
        env.set_step(k);
        log.push(calls(&step(&p, &mut st, &mut env)).join(","));
    }
    assert_eq!(log, ["a.start", "", "a.start", "", "a.end"]);
    assert_eq!(st.status(&p), PlanStatus::Goal);
}

#[test]
fn subplans_step_their_own_net() {
    let l = load_plan(&fixture("parent.pnml"), None).unwrap();
    let p = &l.plan;
    let child = p.executable("child").unwrap();
    assert!(p.executables()[child].subplan.is_some());
    let mut st = PlanState::new(p);
    let mut env = TestEnv::default();
    env.finished.insert("grasp".into());
    env.finished.insert("report".into());
    let mut log = Vec::new();
    for _ in 0..6 {
        log.push(run(p, &mut st, &mut env).join(","));
    }
    // The sub-plan reaches its goal while stepped (phase 2), so the parent's
    // `child.end` is enabled in the same step.
    assert_eq!(
        log,
        [
            "child.start",
            "grasp.start",
            "grasp.end,child.end",
            "report.start",
            "report.end",
            ""
        ]
    );
    assert_eq!(st.status(p), PlanStatus::Goal);
    assert_eq!(env.stepped, ["grasp", "report"]);
    // The environment only sees actions, never the sub-plan itself.
    assert_eq!(
        env.calls,
        ["grasp.start", "grasp.end", "report.start", "report.end"]
    );
}

#[test]
fn subplan_interrupt_passes_on_and_start_resets() {
    let dir = std::env::temp_dir().join(format!("petrel-plans-sub-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(fixture("child.pnml"), dir.join("child.pnml")).unwrap();
    let top = pnml(
        &[("init", 1), ("child.ex", 0), ("held", 0), ("goal", 0)],
        &[
            "child.start",
            "[stop] child.interrupt",
            "[again] child.start",
            "child.end",
        ],
        &[
            ("n0", "t0", 1),
            ("t0", "n1", 1),
            ("n1", "t1", 1),
            ("t1", "n2", 1),
            ("n2", "t2", 1),
            ("t2", "n1", 1),
            ("n1", "t3", 1),
            ("t3", "n3", 1),
        ],
    );
    std::fs::write(dir.join("top.pnml"), top).unwrap();
    let p = load_plan(&dir.join("top.pnml"), None).unwrap().plan;
    std::fs::remove_dir_all(&dir).unwrap();
    let mut st = PlanState::new(&p);
    let mut env = TestEnv::default().cond("stop", false).cond("again", false);
    assert_eq!(run(&p, &mut st, &mut env), ["child.start"]);
    assert_eq!(run(&p, &mut st, &mut env), ["grasp.start"]);
    assert_eq!(st.running_actions(&p), ["grasp"]);
    env.conditions.insert("stop".into(), true);
    assert_eq!(
        run(&p, &mut st, &mut env),
        ["child.interrupt", "grasp.interrupt"]
    );
    env.conditions.insert("stop".into(), false);
    env.conditions.insert("again".into(), true);
    assert_eq!(run(&p, &mut st, &mut env), ["child.start"]);
    let child = p.executable("child").unwrap();
    let sub = st.subplan_state(child).unwrap();
    assert_eq!(
        sub.marked().collect::<Vec<_>>(),
        [(0, 1)],
        "start resets the sub-plan to its initial marking"
    );
}

#[test]
fn subplan_cycles_are_errors() {
    let e = load_plan(&fixture("loop_a.pnml"), None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("sub-plan 'loop_a' includes itself (through loop_a -> loop_b -> loop_a)"),
        "{e}"
    );
}

#[test]
fn plan_and_state_can_move_between_threads() {
    fn assert<T: Send + Sync>() {}
    assert::<petrel_plans::Plan>();
    assert::<PlanState>();
    let _: &dyn petrel_plans::Environment = &TestEnv::default();
}

#[test]
fn a_reused_report_says_what_a_fresh_one_says_step_after_step() {
    // What a mission does at every round (`step_with` into one report) against a fresh report
    // per step: the same firings, calls and markings, to the goal. `stop` is unknown, so the
    // first report that asks it names it once, and a reused report must not keep that.
    let p = petrel_plans::compile_text("a; < go ? b : stop ? c >; d\n", "t.plan", "t", None)
        .expect("the plan compiles");
    let env = || {
        let mut env = TestEnv::default().cond("go", true);
        env.finished.extend(["a", "b", "c", "d"].map(String::from));
        env
    };
    let (mut fresh_env, mut reused_env) = (env(), env());
    let (mut fresh, mut reused) = (PlanState::new(&p), PlanState::new(&p));
    let mut report = petrel_plans::StepReport::default();
    let mut unknown = 0;
    for _ in 0..16 {
        let want = step(&p, &mut fresh, &mut fresh_env);
        petrel_plans::step_with(&p, &mut reused, &mut reused_env, &mut report);
        assert_eq!(report, want);
        assert_eq!(marking(&p, &reused), marking(&p, &fresh));
        unknown += report.unknown_conditions.len();
    }
    assert_eq!(unknown, 1, "`stop` is reported once");
    assert_eq!(status(&p, &reused), PlanStatus::Goal);
    assert_eq!(reused_env.calls, fresh_env.calls);
    assert!(reused_env.calls.contains(&"b.start".to_string()));
}
