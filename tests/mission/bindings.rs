//! Bindings: condition expressions and defaults, parameterized actions, bad bindings.

use crate::support::{agent_with_mission, finished, start, stop, Plans};

#[tokio::test(start_paused = true)]
async fn conditions_bound_to_expressions_choose_the_branch() {
    let plans = Plans::new(&[("choose.plan", "<far ? a : near ? b>")]);
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true,
           "params/conditions": {{"far": "c3/params/increment > 5", "near": "not (c3/params/increment > 5)"}},
           "params/actions": {{
            "a": (enable: ["c1"], finished: "c1/out/value >= 1"),
            "b": (enable: ["c2"], finished: "c2/out/value >= 1"),
        }}"#,
        plans.path("choose.plan")
    )))
    .await;
    assert_eq!(finished(&agent).await.code, 0);
    let bb = agent.blackboard();
    assert_eq!(
        *bb.get::<f64>("c1/out/value").await.unwrap(),
        0.0,
        "a did not run"
    );
    assert_eq!(
        *bb.get::<f64>("c2/out/value").await.unwrap(),
        1.0,
        "near: b ran"
    );
    stop(agent).await;
}

#[tokio::test(start_paused = true)]
async fn parameterized_actions_substitute_their_parameters_and_restore_values() {
    let plans = Plans::new(&[("params.plan", "count_4_1; r1#count_10_3")]);
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true, "params/actions": {{
            "count": (enable: ["c1"], set: {{"c1/params/increment": "$2"}},
                      finished: "c1/out/value >= $1"),
        }}"#,
        plans.path("params.plan")
    )))
    .await;
    assert_eq!(finished(&agent).await.code, 0);
    let bb = agent.blackboard();
    assert_eq!(
        *bb.get::<f64>("c1/out/value").await.unwrap(),
        15.0,
        "4 counts of 1, then the 5th count times 3"
    );
    assert_eq!(
        *bb.get::<f64>("c1/params/increment").await.unwrap(),
        1.0,
        "restored"
    );
    stop(agent).await;
}

#[tokio::test(start_paused = true)]
async fn unbound_actions_may_be_allowed_to_finish_at_once() {
    let plans = Plans::new(&[("u.plan", "say_hello; a")]);
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true, "params/allow_unbound": true,
           "params/actions": {{"a": (finished: "true")}}"#,
        plans.path("u.plan")
    )))
    .await;
    assert_eq!(finished(&agent).await.code, 0);
    stop(agent).await;
}

#[tokio::test(start_paused = true)]
async fn bad_bindings_are_all_refused_at_init_with_positions() {
    let plans = Plans::new(&[("bad.plan", "a; b; c; d; e_1; e_2; wait_x; wramup")]);
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true,
           "params/conditions": {{"unused": "true"}},
           "params/actions": {{
            "a": (finished: "c1/out/value >= 3 and\n c1/out/valu > 0"),
            "b": (finished: "c1/out/value and true"),
            "c": (enable: ["nope"], set: {{"c1/params/period_ms": "fast"}}),
            "e": (failed: "c1/out/value > $1 +"),
            "warmup": (finished: "true"),
        }}"#,
        plans.path("bad.plan")
    )))
    .await;
    let exit = finished(&agent).await;
    assert_eq!(exit.code, 2, "{}", exit.reason);
    let summary = stop(agent).await;
    let m = summary.module("m").unwrap();
    assert_eq!(m.status, "failed");
    let err = m.last_error.clone().unwrap_or_default();
    for want in [
        "init failed: plan ",
        r#"m/params/actions["a"].finished: 2:2: unknown property `c1/out/valu` (in `c1/out/value >= 3 and"#,
        r#"m/params/actions["b"].finished: 1:1: the left operand of `and` must be a boolean, found a number"#,
        r#"m/params/actions["c"].enable (action `c`): no module `nope` in this agent"#,
        r#"bad.plan:1): `c1/params/period_ms` takes a value like 10, found "fast""#,
        r#"m/params/actions["e"].failed: 1:19: expected a value, found the end (in `c1/out/value > 1 +`)"#,
        "m/params/actions: no binding for actions `d` at ",
        "`wramup` at ",
        "bad.plan:1 (is the binding `warmup` it, misspelt?) (bound: a, b, c, e, warmup); bind them, or set params/allow_unbound to let them finish at once; `wait_x` is not the built-in wait: `wait_N` takes a number of seconds",
    ] {
        assert!(err.contains(want), "missing `{want}` in:\n{err}");
    }
    // `e_1` and `e_2` share the binding and its mistake: said once.
    assert_eq!(
        err.matches(r#"m/params/actions["e"].failed:"#).count(),
        1,
        "{err}"
    );
    assert!(
        exit.reason.contains("mission `m` could not start"),
        "{}",
        exit.reason
    );
}

#[tokio::test(start_paused = true)]
async fn a_missing_plan_file_is_reported_with_its_path() {
    let agent = start(&agent_with_mission(
        r#""params/plan": "/nonexistent/p.plan", "params/is_mission": true"#,
    ))
    .await;
    let exit = finished(&agent).await;
    assert_eq!(exit.code, 2);
    assert!(
        exit.reason.contains("m/params/plan") && exit.reason.contains("/nonexistent/p.plan"),
        "{}",
        exit.reason
    );
    stop(agent).await;
}

#[tokio::test(start_paused = true)]
async fn named_places_are_parameters_of_one_binding() {
    // `goto_far` and `goto_near` bind to `goto`: the place's value is set with the target's type
    // and its field is read in the condition.
    let plans = Plans::new(&[("places.plan", "goto_far; goto_near")]);
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true,
           "params/places": {{"far": (increment: 5.0, until: 20.0), "near": (increment: 1.0, until: 23.0)}},
           "params/actions": {{
            "goto": (enable: ["c1"], set: {{"c1/params/increment": "$1.increment"}},
                     finished: "c1/out/value >= $1.until"),
        }}"#,
        plans.path("places.plan")
    )))
    .await;
    let exit = finished(&agent).await;
    assert_eq!(exit.code, 0, "{}", exit.reason);
    let bb = agent.blackboard();
    assert_eq!(
        *bb.get::<f64>("c1/out/value").await.unwrap(),
        23.0,
        "4 x 5, then 3 x 1"
    );
    stop(agent).await;
}

#[tokio::test(start_paused = true)]
async fn wrong_arity_and_wrong_place_values_are_refused_naming_the_plan_line() {
    let plans = Plans::new(&[("bad.plan", "# patrol\ngoto_kitchen; count_1_2")]);
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true,
           "params/places": {{"kitchen": (x: 1.0, y: 2.0)}},
           "params/actions": {{
            "goto": (set: {{"c1/params/increment": "$1"}}, finished: "true"),
            "count": (finished: "c1/out/value >= $1"),
        }}"#,
        plans.path("bad.plan")
    )))
    .await;
    let exit = finished(&agent).await;
    assert_eq!(exit.code, 2);
    let summary = stop(agent).await;
    let err = summary
        .module("m")
        .unwrap()
        .last_error
        .clone()
        .unwrap_or_default();
    for want in [
        "action `count_1_2` at ",
        "bad.plan:2 has 2 parameters, but the binding uses up to $1; write the action as `count_P1`",
        "`c1/params/increment` takes a value like 1.0, found (x: 1.0, y: 2.0)",
    ] {
        assert!(err.contains(want), "missing `{want}` in:\n{err}");
    }
    assert!(
        !err.contains("Expected") && !err.contains("f64"),
        "no type names from the code: {err}"
    );
}

#[tokio::test(start_paused = true)]
async fn expressions_read_the_latest_item_of_a_queue() {
    // The producer pushes 0, 1, 2... every 10 ms; `a` ends when the latest item reaches 20,
    // read from the queue itself and through a consumer's linked queue input.
    let plans = Plans::new(&[("q.plan", "a; b")]);
    let config = agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true, "params/actions": {{
            "a": (finished: "producer/out/items >= 20"),
            "b": (finished: "consumer/in/items >= 30"),
        }}"#,
        plans.path("q.plan")
    ))
    .replace(
        r#"(name: "m", type: "mission.pnp""#,
        r#"(name: "producer", type: "demo.producer", values: {"params/period_ms": 10}),
           (name: "consumer", type: "demo.consumer", links: {"in/items": "producer/out/items"}),
           (name: "m", type: "mission.pnp""#,
    );
    let agent = start(&config).await;
    let exit = finished(&agent).await;
    assert_eq!(exit.code, 0, "{}", exit.reason);
    let memory = agent
        .blackboard()
        .get::<petrel::plans::mission::MissionMemory>("m/state/memory")
        .await
        .unwrap();
    assert!(
        (memory.actions["a"].time_s - 0.2).abs() < 0.015,
        "{memory:?}"
    );
    assert!(
        (memory.actions["b"].time_s - 0.1).abs() < 0.015,
        "{memory:?}"
    );
    stop(agent).await;
}

#[tokio::test(start_paused = true)]
async fn linked_inputs_follow_the_action_and_get_their_link_back() {
    // `b` links c1's increment to c2's value (2 after `a`) while it runs: c1 counts in twos.
    let plans = Plans::new(&[("link.plan", "a; b")]);
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true, "params/actions": {{
            "a": (enable: ["c2"], finished: "c2/out/value >= 2"),
            "b": (enable: ["c1"], link: {{"c1/params/increment": "c2/out/value"}},
                  finished: "c1/out/value >= 4"),
        }}"#,
        plans.path("link.plan")
    )))
    .await;
    assert_eq!(finished(&agent).await.code, 0);
    let bb = agent.blackboard();
    assert_eq!(
        *bb.get::<f64>("c1/out/value").await.unwrap(),
        4.0,
        "two steps of 2"
    );
    assert_eq!(
        bb.link_of("c1/params/increment").await.unwrap(),
        None,
        "link restored"
    );
    assert_eq!(*bb.get::<f64>("c1/params/increment").await.unwrap(), 1.0);
    stop(agent).await;
}

#[tokio::test(start_paused = true)]
async fn links_of_the_wrong_type_or_to_outputs_are_refused_at_init() {
    let plans = Plans::new(&[("badlink.plan", "a; b")]);
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true, "params/actions": {{
            "a": (link: {{"c1/params/increment": "m/out/result"}}, finished: "true"),
            "b": (link: {{"c1/out/value": "c2/out/value"}}, finished: "true"),
        }}"#,
        plans.path("badlink.plan")
    )))
    .await;
    let exit = finished(&agent).await;
    assert_eq!(exit.code, 2, "{}", exit.reason);
    let summary = stop(agent).await;
    let err = summary
        .module("m")
        .unwrap()
        .last_error
        .clone()
        .unwrap_or_default();
    for want in [
        r#"m/params/actions["a"].link["c1/params/increment"] (action `a`): `c1/params/increment` is a "#,
        "but `m/out/result` is a ",
        r#"m/params/actions["b"].link["c1/out/value"] (action `b`): `c1/out/value` is not an input or parameter"#,
    ] {
        assert!(err.contains(want), "missing `{want}` in:\n{err}");
    }
}
