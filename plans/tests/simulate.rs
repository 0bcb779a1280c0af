//! The scripted simulator.
mod common;

use common::*;
use petrel_plans::{load_plan, simulate, PlanStatus, Script};

fn lines(plan: &petrel_plans::Plan, script: &str, max: u64) -> (Vec<String>, PlanStatus) {
    let script = Script::parse(script, "script.txt").unwrap();
    let mut out = Vec::new();
    let status = simulate(plan, &script, max, &mut out).unwrap();
    (
        String::from_utf8(out)
            .unwrap()
            .lines()
            .map(str::to_string)
            .collect(),
        status,
    )
}

#[test]
fn worked_example() {
    let p = load_plan(&fixture("editor_three.pnml"), None).unwrap().plan;
    let (out, status) = lines(&p, "", 100);
    assert_eq!(
        out,
        [
            r#"{"step":0,"marking":{"P":1}}"#,
            r#"{"step":1,"calls":["azione1.start"],"marking":{"azione1.ex":1}}"#,
            r#"{"step":2,"calls":[],"marking":{"azione1.ex":1}}"#,
            r#"{"step":3,"calls":["azione1.end"],"marking":{"goal":1}}"#,
            r#"{"result":"goal","step":3}"#,
        ]
    );
    assert_eq!(status, PlanStatus::Goal);
}

#[test]
fn finish_counts_and_never() {
    let p = load_plan(&fixture("editor_three.pnml"), None).unwrap().plan;
    let (out, _) = lines(&p, "# slow\nfinish azione1 4\n", 100);
    assert_eq!(out.last().unwrap(), r#"{"result":"goal","step":5}"#);
    let (out, status) = lines(&p, "finish azione1 -1", 10);
    assert_eq!(out.len(), 12);
    assert_eq!(out.last().unwrap(), r#"{"result":"running","step":10}"#);
    assert_eq!(status, PlanStatus::Running);
}

#[test]
fn conditions_hold_in_their_window_and_fail_ends_the_plan() {
    let p = net(
        &[("P", 1), ("a.ex", 0), ("fail", 0), ("goal", 0)],
        &["[go] a.start", "a.fail", "a.end"],
        &[
            ("n0", "t0", 1),
            ("t0", "n1", 1),
            ("n1", "t1", 1),
            ("t1", "n2", 1),
            ("n1", "t2", 1),
            ("t2", "n3", 1),
        ],
    );
    let (out, status) = lines(&p, "cond go 3 4\nfail a 1\n", 100);
    assert_eq!(
        out,
        [
            r#"{"step":0,"marking":{"P":1}}"#,
            r#"{"step":1,"calls":[],"marking":{"P":1}}"#,
            r#"{"step":2,"calls":[],"marking":{"P":1}}"#,
            r#"{"step":3,"calls":["a.start"],"marking":{"a.ex":1}}"#,
            r#"{"step":4,"calls":["a.fail"],"marking":{"fail":1}}"#,
            r#"{"result":"fail","step":4}"#,
        ]
    );
    assert_eq!(status, PlanStatus::Fail);
}

#[test]
fn subplan_calls_are_listed() {
    let p = load_plan(&fixture("parent.pnml"), None).unwrap().plan;
    let (out, status) = lines(&p, "", 100);
    assert_eq!(status, PlanStatus::Goal);
    let all = out.join("\n");
    assert!(
        all.contains(r#""calls":["grasp.start"],"marking":{"child.exec":1}"#),
        "{all}"
    );
    assert!(
        all.contains(r#""calls":["grasp.end","child.end"],"marking":{"after":1}"#),
        "{all}"
    );
}

#[test]
fn labels_shared_by_places_add_up() {
    let p = net(&[("x", 1), ("x", 2)], &[], &[]);
    let (out, _) = lines(&p, "", 1);
    assert_eq!(out[0], r#"{"step":0,"marking":{"x":3}}"#);
}

#[test]
fn script_errors_name_the_line() {
    let e = Script::parse("finish a 2\n\nfinsh b 3\n", "s.txt")
        .unwrap_err()
        .to_string();
    assert_eq!(e, "s.txt:3: cannot read 'finsh b 3'; expected 'finish ACTION N', 'fail ACTION N' or 'cond NAME FROM TO'");
    let e = Script::parse("fail a x", "s.txt").unwrap_err().to_string();
    assert_eq!(
        e,
        "s.txt:1: 'x' is not a step count; expected a number >= 0, or -1 for never"
    );
    let e = Script::parse("cond c 1 z", "s.txt")
        .unwrap_err()
        .to_string();
    assert_eq!(e, "s.txt:1: 'z' is not a step number");
    // Nonsense that used to run: a window backwards, a name twice, names the plan lacks.
    let e = Script::parse("cond c 5 2", "s.txt")
        .unwrap_err()
        .to_string();
    assert_eq!(e, "s.txt:1: steps 5 to 2: FROM comes after TO");
    let e = Script::parse("finish a 1\nfinish a 2", "s.txt")
        .unwrap_err()
        .to_string();
    assert_eq!(e, "s.txt:2: 'finish a' is given twice; keep one");
    let e = Script::parse("finish a 3\nfail a 5", "s.txt")
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "s.txt:2: 'fail a 5' and 'finish a 3': the action ends at the first, so the other never applies; keep one"
    );
    let e = Script::parse("finish a 3\0", "s.txt")
        .unwrap_err()
        .to_string();
    assert_eq!(e, "s.txt:1: column 11: unexpected character U+0000");
    // Never finishing, failing at 5: both stand.
    assert!(Script::parse("finish a -1\nfail a 5", "s.txt").is_ok());
    let plan =
        petrel_plans::compile_text("a; < c ? b : (not c) ? d >", "p.plan", "p", None).unwrap();
    let script = Script::parse("finish a 1\ncond c 0 5\n\nfinish zzz 3", "s.txt").unwrap();
    let e = script.check(&plan, "s.txt").unwrap_err().to_string();
    assert_eq!(
        e,
        "s.txt:4: the plan has no action 'zzz' (its actions: a, b, d)"
    );
    let script = Script::parse("cond cc 0 5", "s.txt").unwrap();
    let e = script.check(&plan, "s.txt").unwrap_err().to_string();
    assert_eq!(
        e,
        "s.txt:1: the plan has no condition 'cc' (its conditions: c)"
    );
}

#[test]
fn scripts_accept_every_name_a_plan_can_contain() {
    // Multi-robot plans prefix names with `robot#`; names may also contain dots.
    let p = petrel_plans::compile_text(
        "robot_0#pathLeft; robot_1#go.to_2; <robot_0#door.open ? x : robot_1@hall ? y>",
        "m.plan",
        "m",
        None,
    )
    .unwrap();
    let script = "# two robots\nfinish robot_0#pathLeft 3   # slower than the default 2\n\
                  finish robot_1#go.to_2 1\ncond robot_1@hall 0 100 #comment\n";
    let (out, status) = lines(&p, script, 100);
    assert_eq!(status, PlanStatus::Goal);
    let step_of = |call: &str| {
        out.iter()
            .position(|l| l.contains(&format!("\"{call}\"")))
            .unwrap_or_else(|| panic!("no {call} in {out:?}"))
    };
    // Started at step 1, stepped at 2, 3, 4: finished after 3 steps.
    assert_eq!(step_of("robot_0#pathLeft.end"), 4);
    assert_eq!(step_of("robot_1#go.to_2.end"), 6);
    assert!(out.iter().any(|l| l.contains("\"y.start\"")), "{out:?}");
    assert!(!out.iter().any(|l| l.contains("\"x.start\"")), "{out:?}");
    let e = Script::parse("finish #x 2 3", "s").unwrap_err().to_string();
    assert!(e.starts_with("s:1: cannot read 'finish'"), "{e}");
}

#[test]
fn an_unhandled_failure_fails_the_plan_and_a_handled_one_does_not() {
    let p = petrel_plans::compile_text("a; b", "f.plan", "f", None).unwrap();
    let (out, status) = lines(&p, "finish a 1\nfail b 1", 20);
    assert_eq!(status, PlanStatus::Fail, "{out:?}");
    assert_eq!(out.last().unwrap(), r#"{"result":"fail","step":4}"#);
    // With a rule for b's failure, the rule runs instead.
    let p = petrel_plans::compile_text(
        "a; b",
        "f.plan",
        "f",
        Some((
            "*if* action_failed *during* b *do* fix; skip_action",
            "f.er",
        )),
    )
    .unwrap();
    let (out, status) = lines(&p, "finish a 1\nfail b 1\nfinish fix 1", 20);
    assert_eq!(status, PlanStatus::Goal, "{out:?}");
    assert!(out.iter().any(|l| l.contains("b.fail")), "{out:?}");
}

#[test]
fn an_unhandled_failure_is_reported_with_its_action() {
    let p = petrel_plans::compile_text("a; b", "f.plan", "f", None).unwrap();
    let mut state = petrel_plans::PlanState::new(&p);
    let script = Script::parse("finish a 1\nfail b 1", "s").unwrap();
    let mut env = petrel_plans::ScriptedEnv::new(&script);
    let mut failed = None;
    for _ in 0..10 {
        let r = petrel_plans::step(&p, &mut state, &mut env);
        failed = failed.or(r.unhandled_failure);
    }
    assert_eq!(failed.as_deref(), Some("b"));
    assert_eq!(state.status(&p), PlanStatus::Fail);
    assert_eq!(state.unhandled_failure(&p).as_deref(), Some("b"));
    // A saved failed state restores as failed.
    let mut again = petrel_plans::PlanState::new(&p);
    again.restore(&p, &state.save()).unwrap();
    assert_eq!(again.status(&p), PlanStatus::Fail);
    assert!(
        again.restore(&p, &[7, 1]).is_err(),
        "a key that does not fit is refused"
    );
}

#[test]
fn a_place_past_the_token_limit_fails_the_simulation_as_it_would_a_mission() {
    // `t0` keeps the token of P and adds one to Q at every step: Q grows without end.
    let p = net(
        &[("P", 1), ("Q", 0), ("goal", 0)],
        &["[]"],
        &[("n0", "t0", 1), ("t0", "n0", 1), ("t0", "n1", 1)],
    );
    let limit = u64::from(petrel_plans::MAX_PLACE_TOKENS);
    let (out, status) = lines(&p, "", limit + 100);
    assert_eq!(status, PlanStatus::Fail);
    let last = out.last().unwrap();
    assert!(
        last.starts_with(&format!("{{\"result\":\"fail\",\"step\":{},\"reason\":\"place 'Q' holds {} tokens (more than {limit})", limit + 1, limit + 1)),
        "{last}"
    );
}
