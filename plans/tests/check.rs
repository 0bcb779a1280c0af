//! Static analysis.
mod common;

use common::*;
use petrel_plans::{
    check, check_with, compile_text, load_plan, simulate, to_dot, CheckOptions, PlanStatus, Script,
};

fn codes(r: &petrel_plans::CheckReport) -> (Vec<&str>, Vec<&str>) {
    (
        r.errors.iter().map(|f| f.code).collect(),
        r.warnings.iter().map(|f| f.code).collect(),
    )
}

#[test]
fn a_good_plan_is_clean() {
    let l = load_plan(&fixture("editor_patrol.pnml"), None).unwrap();
    let r = check(&l.plan);
    assert_eq!(codes(&r), (vec![], vec![]), "{r}");
    assert!(r.is_ok() && r.complete);
    assert_eq!(r.actions, ["patrol"]);
    assert_eq!(r.conditions, ["battery_low"]);
    let text = r.to_string();
    assert!(
        text.starts_with("plan 'patrol_demo': 0 errors, 0 warnings ("),
        "{text}"
    );
    assert!(
        text.contains("actions: patrol\n") && text.contains("conditions: battery_low\n"),
        "{text}"
    );
}

#[test]
fn missing_goal_is_an_error() {
    let p = net(
        &[("P", 1), ("a.ex", 0)],
        &["a.start"],
        &[("n0", "t0", 1), ("t0", "n1", 1)],
    );
    let r = check(&p);
    assert!(!r.is_ok());
    assert_eq!(codes(&r).0, ["no-goal"]);
    assert!(
        r.to_string()
            .contains("error[no-goal]: the plan has no goal place"),
        "{r}"
    );
}

#[test]
fn dead_transitions_dead_ends_and_multiple_tokens() {
    let p = net(
        &[("P", 1), ("Q", 0), ("goal", 0), ("never", 0), ("stuck", 0)],
        &["[]", "[]", "[]", "[x]"],
        &[
            ("n0", "t0", 1),
            ("t0", "n1", 1),
            ("t0", "n1", 1),
            ("n1", "t1", 2),
            ("t1", "n2", 1),
            ("n3", "t2", 1),
            ("t2", "n2", 1),
            ("n1", "t3", 1),
            ("t3", "n4", 1),
        ],
    );
    let r = check(&p);
    let (errors, warnings) = codes(&r);
    assert!(errors.is_empty(), "{r}");
    // t3 is token-enabled with Q, but t1 comes first and takes both tokens.
    assert_eq!(
        warnings,
        [
            "dead-end-place",
            "multiple-tokens",
            "dead-transition",
            "dead-transition"
        ],
        "{r}"
    );
    assert_eq!(
        r.warnings[0].message,
        "place 'n4' ('stuck') is neither a goal nor a fail place and has no outgoing transition"
    );
    assert_eq!(r.warnings[1].message, "place 'n1' ('Q') can hold 2 tokens");
    assert_eq!(
        r.warnings[2].message,
        "transition 't2' ('[]') can never fire"
    );
    assert_eq!(
        r.warnings[3].message,
        "transition 't3' ('[x]') can never fire"
    );
}

#[test]
fn structural_errors() {
    let p = net(&[("P", 0), ("goal", 0)], &["[]"], &[("t0", "n1", 1)]);
    assert_eq!(
        codes(&check(&p)).0,
        ["no-initial-marking", "source-transition"]
    );
}

#[test]
fn an_action_that_looks_like_a_wait_but_is_not_one_is_a_warning() {
    let p = compile_text("wait_abc; wait_2; r1#wait_-1", "t.plan", "t", None).unwrap();
    let r = check(&p);
    assert_eq!(codes(&r), (vec![], vec!["not-a-wait", "not-a-wait"]), "{r}");
    assert!(
        r.warnings[0]
            .message
            .starts_with("`wait_abc` is not the built-in wait: `wait_N` takes a number of seconds"),
        "{r}"
    );
    assert!(r.warnings[1].message.contains("`wait_-1`"), "{r}");
}

#[test]
fn timed_actions_cannot_deadlock_whichever_ends_first() {
    let p = compile_text("a|5", "t.plan", "t", None).unwrap();
    let r = check(&p);
    assert_eq!(codes(&r), (vec![], vec![]), "{r}");
    // The action, its timer, or both in the same step: each way reaches the goal.
    for script in [
        "finish a 1\nfinish wait_5 5",
        "finish a 5\nfinish wait_5 1",
        "finish a 3\nfinish wait_5 3",
    ] {
        let mut out = Vec::new();
        let script = Script::parse(script, "s").unwrap();
        assert_eq!(
            simulate(&p, &script, 20, &mut out).unwrap(),
            PlanStatus::Goal,
            "{}",
            String::from_utf8_lossy(&out)
        );
    }
}

#[test]
fn subplans_are_checked_too() {
    let l = load_plan(&fixture("parent.pnml"), None).unwrap();
    let r = check(&l.plan);
    assert!(r.is_ok(), "{r}");
    assert_eq!(r.subplans, ["child"]);
    assert_eq!(r.actions, ["report"]);
}

#[test]
fn dot_output() {
    let l = load_plan(&fixture("editor_three.pnml"), None).unwrap();
    let d = to_dot(&l.plan);
    assert!(
        d.starts_with("digraph \"editor_three\" {\n  rankdir=LR;\n"),
        "{d}"
    );
    assert!(
        d.contains("p1 [shape=doublecircle, label=\"goal\", tooltip=\"p2\"];"),
        "{d}"
    );
    assert!(
        d.contains("p2 [shape=circle, label=\"P (1)\", tooltip=\"p3\"];"),
        "{d}"
    );
    assert!(
        d.contains("t0 [shape=box, height=0.2, label=\"azione1.start\", tooltip=\"t1\"];"),
        "{d}"
    );
    assert!(d.contains("  p2 -> t0;\n  t0 -> p0;\n"), "{d}");
    assert!(d.ends_with("}\n"));
}

#[test]
fn livelocks_are_reported_with_a_witness() {
    // The y branch loops on b forever: from there neither goal nor fail can be reached.
    let p = compile_text(
        "a; <x ? c : y ? LABEL_l; b; GOTO_LABEL_l>",
        "t.plan",
        "t",
        None,
    )
    .unwrap();
    let r = check(&p);
    assert!(r.complete && r.is_ok(), "{r}");
    let live: Vec<&str> = r
        .warnings
        .iter()
        .filter(|w| w.code == "livelock")
        .map(|w| w.message.as_str())
        .collect();
    assert_eq!(live.len(), 1, "{r}");
    assert!(
        live[0].starts_with("from {'X6': 1} the plan can never reach its goal or fail: it stays among 3 markings forever; reached by step 1: 'a.start'; step 2: 'a.end'; step 3: '[y]'"),
        "{}",
        live[0]
    );
    // Without the loop there is none.
    let p = compile_text("a; <x ? c : y ? b>", "t.plan", "t", None).unwrap();
    assert!(!check(&p).warnings.iter().any(|w| w.code == "livelock"));
}

#[test]
fn a_linear_plan_has_one_marking_per_place() {
    let n = 20_000;
    let src: Vec<String> = (0..n).map(|i| format!("a{i}")).collect();
    let p = compile_text(&src.join("; "), "l.plan", "l", None).unwrap();
    let r = check(&p);
    assert_eq!(codes(&r), (vec![], vec![]), "{r}");
    assert!(r.complete);
    assert_eq!(r.states, 2 * n + 1);
}

#[test]
fn the_budget_stops_wide_plans_with_a_message() {
    let branches: Vec<String> = (0..12).map(|i| format!("{{ a{i}; b{i} }}")).collect();
    let p = compile_text(&branches.join(" || "), "w.plan", "w", None).unwrap();
    let r = check_with(&p, &CheckOptions { max_states: 5_000 });
    assert!(!r.complete);
    assert_eq!(r.states, 5_000);
    assert_eq!(r.warnings[0].code, "incomplete", "{r}");
    assert_eq!(
        r.warnings[0].message,
        "stopped after exploring 5000 markings (the limit); raise --max-states to explore further; the findings below may be partial"
    );
    assert!(
        r.to_string()
            .contains("(5000 markings explored, incomplete)"),
        "{r}"
    );
    // Findings that need the whole graph are not given.
    assert!(!r
        .warnings
        .iter()
        .any(|w| w.code == "dead-transition" || w.code == "livelock"));
}

/// A hierarchy 30 levels deep where every level runs the next one twice (`L0` → `L1; L1` →
/// ...): 2^30 paths through the sub-plans, 31 distinct files.
fn shared_subplan_dag(dir: &std::path::Path, levels: usize) {
    for i in 0..levels {
        let text = format!("L{0}; L{0}\n", i + 1);
        let plan = compile_text(&text, "dag.plan", &format!("L{i}"), None).unwrap();
        std::fs::write(
            dir.join(format!("L{i}.pnml")),
            petrel_plans::write_pnml(&plan),
        )
        .unwrap();
    }
    let leaf = compile_text("leaf\n", "leaf.plan", &format!("L{levels}"), None).unwrap();
    std::fs::write(
        dir.join(format!("L{levels}.pnml")),
        petrel_plans::write_pnml(&leaf),
    )
    .unwrap();
}

#[test]
fn a_shared_subplan_is_loaded_and_checked_once_however_many_paths_reach_it() {
    let dir = tempfile::tempdir().unwrap();
    shared_subplan_dag(dir.path(), 30);
    let l = load_plan(&dir.path().join("L0.pnml"), None).unwrap();
    let r = check(&l.plan);
    assert!(r.complete && r.is_ok(), "{r}");
    // Each plan is explored with its sub-plan as one action: a handful of markings, not the
    // 2^30 of every nested state (which the budget would cut short as "incomplete").
    assert!(r.states < 10, "{r}");
    assert_eq!(r.subplans, ["L1"]);

    // A leaf that can never reach its goal (its only place waits forever) makes every
    // parent's goal unreachable, level after level: the outcome travels up, checked once.
    std::fs::write(
        dir.path().join("L30.pnml"),
        r#"<pnml><net id="n"><place id="p"><name><value>stuck</value></name>
<initialMarking><value>1</value></initialMarking></place>
<place id="g"><name><value>goal</value></name></place></net></pnml>"#,
    )
    .unwrap();
    let l = load_plan(&dir.path().join("L0.pnml"), None).unwrap();
    let r = check(&l.plan);
    assert!(r.complete, "{r}");
    assert!(
        r.warnings
            .iter()
            .any(|w| w.code == "goal-unreachable" && !w.message.starts_with("sub-plan")),
        "L0 itself can never reach its goal: {r}"
    );
}

#[test]
fn a_rule_that_never_applies_is_named_by_its_file_and_line() {
    let p = compile_text(
        "goto_dock",
        "d.plan",
        "d",
        Some((
            "*if* action_failed *during* goto *do* skip_action\n*if* action_failed *during* goto_dock *do* fail_plan\n",
            "d.er",
        )),
    )
    .unwrap();
    let r = check(&p);
    let dead: Vec<&str> = r
        .warnings
        .iter()
        .filter(|w| w.code == "dead-transition")
        .map(|w| w.message.as_str())
        .collect();
    assert_eq!(
        dead,
        ["the rule at d.er:2 (`*if* action_failed *during* goto_dock *do* fail_plan`) for `goto_dock` never applies (`goto_dock.fail` can never fire): the rule at d.er:1 (`*if* action_failed *during* goto *do* skip_action`) for `goto_dock` already handles it"],
        "{r}"
    );
    assert!(!r.to_string().contains("'t"), "no internal ids: {r}");
}

#[test]
fn an_action_that_can_never_run_is_named_by_its_line() {
    let p = compile_text(
        "a;\nGOTO_LABEL_end;\nLABEL_skipped;\nb;\nLABEL_end;\nc",
        "j.plan",
        "j",
        None,
    )
    .unwrap();
    let r = check(&p);
    let dead: Vec<&str> = r
        .warnings
        .iter()
        .filter(|w| w.code == "dead-transition")
        .map(|w| w.message.as_str())
        .collect();
    assert_eq!(
        dead,
        ["action `b` at j.plan:4: `b.start` can never fire"],
        "{r}"
    );
}
