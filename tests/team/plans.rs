//! Team plans over real zenoh sessions: a coordinator runs the plan, each robot's
//! `mission.pnp` in serve mode carries out its `robot#` actions and reports its conditions.

use petrel::actors::team::TeamMembers;
use petrel::plans::mission::MissionMemory;

use crate::support::*;

/// A coordinator `boss` and robots `r1`, `r2` on a fresh team, all running `plan` (written
/// to a temp dir); each robot has a `test.probe` whose `in/value` its bindings read and set.
struct TeamPlan {
    boss: Member,
    r1: Member,
    r2: Member,
    _dir: tempfile::TempDir,
}

/// Robot bindings: `search_west` and `search_east` run until the probe reads 1 or more,
/// `enter` sets it to 42 and is done, `knock` is done at once; `doorOpen` is probe > 5.
const ROBOT_BINDINGS: &str = r#""params/actions": {
        "search_west": (finished: "probe/in/value >= 1"),
        "search_east": (finished: "probe/in/value >= 1"),
        "enter": (set: {"probe/in/value": 42.0}, restore: false, finished: "probe/in/value == 42"),
        "knock": (finished: "true"),
    },
    "params/conditions": {"doorOpen": "probe/in/value > 5"}"#;

async fn team_plan(test: &str, plan: &str) -> TeamPlan {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("team.plan");
    std::fs::write(&path, plan).unwrap();
    let plan_path = path.display().to_string();
    let team = team_name(test);
    let (pb, p1, p2) = (free_port(), free_port(), free_port());
    // Every robot gets every binding: those its part of the plan does not use are warnings.
    let robot = format!(
        r#"(name: "probe", type: "test.probe"),
           (name: "mission", type: "mission.pnp", values: {{"params/plan": "{plan_path}",
              "params/mode": "serve", {ROBOT_BINDINGS}}}),"#
    );
    let boss = start(&agent_config(
        "boss",
        &team,
        pb,
        &[],
        "",
        &format!(
            r#"(name: "mission", type: "mission.pnp", values: {{"params/plan": "{plan_path}"}}),"#
        ),
    ))
    .await;
    let r1 = start(&agent_config("r1", &team, p1, &[pb], "", &robot)).await;
    let r2 = start(&agent_config("r2", &team, p2, &[pb], "", &robot)).await;
    TeamPlan {
        boss,
        r1,
        r2,
        _dir: dir,
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_coordinator_dispatches_robot_actions_and_reads_robot_conditions() {
    let t = team_plan(
        "plan-dispatch",
        "r1#search_west; < r2#doorOpen ? r2#enter : (not r2#doorOpen) ? r2#knock >\n",
    )
    .await;
    let running = t.boss.handle::<String>("mission/out/running").await;
    wait_for(&running, "r1's search running", |r| r == "r1#search_west").await;
    // r2 reports its door open before r1 is done: the plan takes the `enter` branch. The
    // report and r1's end travel from different agents, so wait until the coordinator heard it.
    t.r2.agent
        .blackboard()
        .set("probe/in/value", 9.0)
        .await
        .unwrap();
    let heard = t
        .boss
        .handle::<String>("mission/out/robot_conditions")
        .await;
    wait_for(&heard, "r2's door open at the coordinator", |c| {
        c == "r2#doorOpen=true"
    })
    .await;
    t.r1.agent
        .blackboard()
        .set("probe/in/value", 1.0)
        .await
        .unwrap();
    let result = t.boss.handle::<String>("mission/out/result").await;
    wait_for(&result, "the plan's goal", |r| r == "goal").await;
    // `enter` ran on r2 (it set r2's probe), not on the coordinator.
    assert_eq!(t.r2.handle::<f64>("probe/in/value").await.value(), 42.0);
    let memory = t
        .boss
        .handle::<MissionMemory>("mission/state/memory")
        .await
        .get();
    let ends = |a: &str| memory.actions.get(a).map_or(0, |s| s.ends);
    assert_eq!(
        (ends("r1#search_west"), ends("r2#enter"), ends("r2#knock")),
        (1, 1, 0)
    );
    let served =
        t.r2.handle::<MissionMemory>("mission/state/memory")
            .await
            .get();
    assert_eq!(
        served.actions.get("r2#enter").map(|s| s.starts),
        Some(1),
        "{served:?}"
    );
    for m in [t.r2, t.r1, t.boss] {
        m.stop().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_robot_leaving_the_team_fails_its_action_and_the_plan_recovers() {
    let t = team_plan(
        "plan-departure",
        "{ r1#search_west ! *if* action_failed *do* r2#search_west; skip_action ! } || { r2#search_east }\n",
    )
    .await;
    let running = t.boss.handle::<String>("mission/out/running").await;
    wait_for(&running, "both searches running", |r| {
        r.contains("r1#search_west") && r.contains("r2#search_east")
    })
    .await;
    let members = t.boss.handle::<TeamMembers>("_team/members").await;
    t.r1.stop().await;
    wait_for(&members, "r1 gone", |m| !names(m).contains(&"r1")).await;
    // r1's area goes to r2.
    wait_for(&running, "r2 searching the west too", |r| {
        r.contains("r2#search_west")
    })
    .await;
    t.r2.agent
        .blackboard()
        .set("probe/in/value", 1.0)
        .await
        .unwrap();
    let result = t.boss.handle::<String>("mission/out/result").await;
    wait_for(&result, "the plan's goal", |r| r == "goal").await;
    let memory = t
        .boss
        .handle::<MissionMemory>("mission/state/memory")
        .await
        .get();
    let stats = |a: &str| memory.actions.get(a).cloned().unwrap_or_default();
    assert_eq!(stats("r1#search_west").failures, 1);
    assert_eq!(stats("r2#search_west").ends, 1);
    for m in [t.r2, t.boss] {
        m.stop().await;
    }
}

/// A robot's mission restarted while it carries out a coordinator's action (a crash, or a move
/// off its agent's thread) still answers that run when the action finishes: what it serves is
/// kept in its `state/memory`.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_robot_mission_restarted_mid_action_still_answers_the_coordinator() {
    let t = team_plan("plan-restart", "r1#search_west\n").await;
    let running = t.boss.handle::<String>("mission/out/running").await;
    wait_for(&running, "r1's search running", |r| r == "r1#search_west").await;
    let served = t.r1.handle::<MissionMemory>("mission/state/memory").await;
    wait_for(&served, "the run kept in r1's memory", |m| {
        m.serve
            .running()
            .any(|(a, from)| a == "search_west" && from.starts_with("boss/"))
    })
    .await;
    t.r1.agent.modules().restart("mission").await.unwrap();
    finish_r1s_search(&t).await;
    for m in [t.r2, t.r1, t.boss] {
        m.stop().await;
    }
}

/// A coordinator's mission restarted while a robot carries out its action (a crash, or a move
/// off its agent's thread) still hears that run's answer: the runs it started are kept in its
/// `state/memory`, and the running ones are asked again.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_coordinator_mission_restarted_mid_action_still_hears_the_robot_finish() {
    let t = team_plan("plan-boss-restart", "r1#search_west\n").await;
    let running = t.boss.handle::<String>("mission/out/running").await;
    wait_for(&running, "r1's search running", |r| r == "r1#search_west").await;
    let memory = t.boss.handle::<MissionMemory>("mission/state/memory").await;
    wait_for(&memory, "the run kept in the boss's memory", |m| {
        m.running.contains_key("r1#search_west")
    })
    .await;
    t.boss.agent.modules().restart("mission").await.unwrap();
    finish_r1s_search(&t).await;
    let memory = t
        .boss
        .handle::<MissionMemory>("mission/state/memory")
        .await
        .get();
    let search = &memory.actions["r1#search_west"];
    assert_eq!((search.starts, search.ends), (1, 1), "{memory:?}");
    for m in [t.r2, t.r1, t.boss] {
        m.stop().await;
    }
}

/// Makes r1's `search_west` finish (its probe reads 1) and waits for the boss's plan goal.
async fn finish_r1s_search(t: &TeamPlan) {
    t.r1.agent
        .blackboard()
        .set("probe/in/value", 1.0)
        .await
        .unwrap();
    let result = t.boss.handle::<String>("mission/out/result").await;
    wait_for(&result, "the plan's goal", |r| r == "goal").await;
}

/// Bindings of a robot running its own plan: `goto_door` until the probe reads 1 or more,
/// `enter` sets it to 42; `atDoor` (watched by the other robot) is probe >= 1.
const OWN_PLAN_BINDINGS: &str = r#""params/actions": {
        "goto_door": (finished: "probe/in/value >= 1"),
        "enter": (set: {"probe/in/value": 42.0}, restore: false, finished: "probe/in/value == 42"),
    },
    "params/conditions": {"atDoor": "probe/in/value >= 1"}"#;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn robots_running_their_own_plans_wait_for_each_other_at_the_door() {
    let dir = tempfile::tempdir().unwrap();
    let team = team_name("plan-distributed");
    let (p1, p2) = (free_port(), free_port());
    let robot = |me: &str, other: &str| {
        let path = dir.path().join(format!("{me}.plan"));
        std::fs::write(&path, format!("goto_door; < {other}#atDoor ? enter >\n")).unwrap();
        format!(
            r#"(name: "probe", type: "test.probe"),
               (name: "mission", type: "mission.pnp", values: {{"params/plan": "{}", {OWN_PLAN_BINDINGS}}}),"#,
            path.display()
        )
    };
    let r1 = start(&agent_config("r1", &team, p1, &[], "", &robot("r1", "r2"))).await;
    let r2 = start(&agent_config(
        "r2",
        &team,
        p2,
        &[p1],
        "",
        &robot("r2", "r1"),
    ))
    .await;
    let memory = r1.handle::<MissionMemory>("mission/state/memory").await;
    // r1 reaches the door first: its plan goes on only when r2 says it is there too.
    r1.agent
        .blackboard()
        .set("probe/in/value", 1.0)
        .await
        .unwrap();
    wait_for(&memory, "r1 at the door", |m| {
        m.actions.get("goto_door").is_some_and(|s| s.ends == 1)
    })
    .await;
    let marking = r1.handle::<String>("mission/out/marking").await.get();
    assert_eq!(
        r1.handle::<f64>("probe/in/value").await.value(),
        1.0,
        "r1 waits: {marking}"
    );
    assert_eq!(
        *r1.handle::<String>("mission/out/result").await.get(),
        "running"
    );
    r2.agent
        .blackboard()
        .set("probe/in/value", 1.0)
        .await
        .unwrap();
    for m in [&r1, &r2] {
        let result = m.handle::<String>("mission/out/result").await;
        wait_for(&result, "both through the door", |r| r == "goal").await;
        assert_eq!(m.handle::<f64>("probe/in/value").await.value(), 42.0);
    }
    for m in [r2, r1] {
        m.stop().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_robot_given_two_actions_on_the_same_modules_runs_them_one_after_the_other() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("team.plan");
    std::fs::write(&path, "{ r1#search_west } || { r1#search_east }\n").unwrap();
    let team = team_name("plan-queue");
    let (pb, p1) = (free_port(), free_port());
    let boss = start(&agent_config(
        "boss",
        &team,
        pb,
        &[],
        "",
        &format!(
            r#"(name: "mission", type: "mission.pnp", values: {{"params/plan": "{}"}}),"#,
            path.display()
        ),
    ))
    .await;
    // Both searches drive the same module; each is done once the probe has been written
    // since it started.
    let r1 = start(&agent_config(
        "r1",
        &team,
        p1,
        &[pb],
        "",
        &format!(
            r#"(name: "probe", type: "test.probe"),
               (name: "mission", type: "mission.pnp", values: {{"params/plan": "{}", "params/mode": "serve",
                  "params/actions": {{"search": (enable: ["probe"], finished: "probe/in/value >= 1 and age(probe/in/value) < elapsed()")}}}}),"#,
            path.display()
        ),
    ))
    .await;
    let memory = r1.handle::<MissionMemory>("mission/state/memory").await;
    let starts = |m: &MissionMemory, a: &str| m.actions.get(a).map_or(0, |s| s.starts);
    let first = wait_for(&memory, "one search started", |m| {
        starts(m, "r1#search_west") + starts(m, "r1#search_east") == 1
    })
    .await;
    let running = first.running.keys().next().cloned().unwrap();
    // The memory can say "started" a moment before the action switched its module on and
    // began counting `elapsed()`: a write before that would not count as written since.
    let enabled = r1.handle::<bool>("probe/enabled").await;
    let probe = |value: f64, search: &'static str| {
        let (enabled, bb) = (&enabled, r1.agent.blackboard().clone());
        async move {
            wait_for(enabled, search, |on| *on).await;
            bb.set("probe/in/value", value).await.unwrap();
        }
    };
    probe(1.0, "the first search switching the probe on").await;
    wait_for(
        &memory,
        "the other search started after the first ended",
        |m| starts(m, "r1#search_west") == 1 && starts(m, "r1#search_east") == 1,
    )
    .await;
    let m = memory.get();
    assert_eq!(m.actions[&running].ends, 1, "{m:?}");
    // The first search's end switched the probe off; the second switches it on again.
    probe(2.0, "the second search switching the probe on").await;
    let result = boss.handle::<String>("mission/out/result").await;
    wait_for(&result, "the plan's goal", |r| r == "goal").await;
    for m in [r1, boss] {
        m.stop().await;
    }
}

#[test]
fn petrel_check_refuses_a_team_plan_without_a_team_and_an_unknown_mode() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("t.plan"), "r1#go; r2#go\n").unwrap();
    let check = |values: &str| {
        let config = dir.path().join("boss.ron");
        let text = format!(
            r#"Agent(name: "boss", modules: [
  (name: "mission", type: "mission.pnp", values: {{"params/plan": "t.plan", {values}}}),
])"#
        );
        std::fs::write(&config, text).unwrap();
        let out = crate::bounded::output_within_deadline(
            std::process::Command::new(env!("CARGO_BIN_EXE_petrel"))
                .arg("check")
                .arg(&config),
        );
        assert_eq!(out.status.code(), Some(2), "{values}");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let err = check(r#""params/is_mission": true"#);
    assert!(
        err.contains("boss.ron:2:")
            && err.contains("the plan names other robots (r1, r2), which needs a team: agent `boss` has no `team:` section"),
        "{err}"
    );
    let err = check(r#""params/mode": "boss""#);
    assert!(
        err.contains("boss.ron:2:")
            && err.contains("`mission/params/mode` = \"boss\": expected one of \"run\", \"serve\" (run: run the plan"),
        "{err}"
    );
}
