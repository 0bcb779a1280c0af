//! What one plan reaction costs in module steps (the `pnp_reaction` bench's reaction): a
//! condition changes → `[go]` and `work.start` fire and enable the work module → it steps and
//! answers → `work.end` and the jump back fire and disable it. Counted on the paused clock,
//! where one thread runs every module in a fixed order.

use petrel::actors::Agent;

use crate::support::{start, stop, Plans};

const REACTIONS: i64 = 10;

fn config(plan: &str) -> String {
    format!(
        r#"Agent(name: "r1", modules: [
            (name: "w", type: "demo.scale", values: {{"enabled": false}}),
            (name: "m", type: "mission.pnp", values: {{
                "params/plan": "{plan}",
                "params/conditions": {{"go": "w/in/value > w/out/value", "quit": "w/in/value < 0"}},
                "params/actions": {{"work": (enable: ["w"], finished: "w/out/value >= w/in/value")}},
            }}),
        ])"#
    )
}

/// Makes `REACTIONS` requests, each answered when the mission has fired its four transitions.
async fn react(agent: &Agent) {
    let bb = agent.blackboard();
    let request = bb.handle::<f64>("w/in/value").await.unwrap();
    let fired = bb.handle::<i64>("m/out/fired").await.unwrap();
    for k in 1..=REACTIONS {
        request.set(k as f64);
        let deadline = tokio::time::sleep(std::time::Duration::from_secs(10));
        tokio::pin!(deadline);
        while *fired.get() < 4 * k {
            tokio::select! {
                _ = fired.changed() => {}
                _ = &mut deadline => panic!("reaction {k}: the mission fired {} transitions", fired.get()),
            }
        }
    }
}

#[tokio::test(start_paused = true)]
async fn a_reaction_is_one_mission_step_when_its_action_answers_at_once() {
    let plans = Plans::new(&[(
        "loop.plan",
        "LABEL_top; < go ? work; GOTO_LABEL_top : quit ? work >\n",
    )]);
    let agent = start(&config(&plans.path("loop.plan"))).await;
    let status = agent
        .blackboard()
        .handle::<String>("w/stats/status")
        .await
        .unwrap();
    let status_before = status.read().version;
    react(&agent).await;
    let status_writes = status.read().version - status_before;
    let firings = agent
        .blackboard()
        .handle::<i64>("m/out/fired")
        .await
        .unwrap();
    assert_eq!(*firings.get(), 4 * REACTIONS);
    let summary = stop(agent).await;
    let steps = |name: &str| summary.module(name).unwrap().steps as i64;
    // The mission's first step (every module steps once after init), then one per reaction:
    // the step that fires `[go]` and `work.start` lets the work module it enabled answer and
    // fires `work.end` and the jump back in the same step.
    assert_eq!(steps("m"), 1 + REACTIONS, "mission steps");
    // The work module steps once per reaction (its first step waits for it to be enabled).
    assert_eq!(steps("w"), REACTIONS, "work module steps");
    // Its status goes running and disabled once per reaction (besides its last stop).
    assert_eq!(
        status_writes as i64,
        2 * REACTIONS,
        "work module status writes"
    );
}
