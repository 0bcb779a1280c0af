//! Members, departures and rejoins: links to a departed agent go stale and resume by
//! themselves when it comes back.

use petrel::actors::team::{LinkStatus, Tap, TeamMembers};

use crate::support::*;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn three_agents_see_each_other_and_a_departure_makes_links_stale_until_rejoin() {
    let team = team_name("members");
    let (pa, pb, pc) = (free_port(), free_port(), free_port());
    let counter = r#"(name: "count", type: "demo.counter", values: {"params/period_ms": 5}),"#;
    let a = start(&agent_config("a", &team, pa, &[], "", counter)).await;
    let b = start(&agent_config(
        "b",
        &team,
        pb,
        &[pa],
        "",
        r#"
        (name: "scale", type: "demo.scale", links: {"in/value": "petrel://c/count/out/value"}),"#,
    ))
    .await;
    let c = start(&agent_config("c", &team, pc, &[pa], "", counter)).await;
    for m in [&a, &b, &c] {
        let members = m.handle::<TeamMembers>("_team/members").await;
        let list = wait_for(&members, "three members with their modules", |l| {
            names(l) == ["a", "b", "c"] && l.0.iter().all(|m| !m.modules.is_empty())
        })
        .await;
        assert_eq!(list.0[1].modules, ["scale"]);
    }
    let status = b.handle::<LinkStatus>("scale/stats/links/in/value").await;
    wait_for(&status, "a live link to c", |s| s.state == "live").await;
    // The first sample may be c's initial 0: wait for a count, so "kept" below means something.
    let input = b.handle::<f64>("scale/in/value").await;
    wait_for(&input, "a count from c", |v| *v > 0.0).await;
    let Ok(Tap::Queue(mut events)) = a.agent.blackboard().tap("_team/events").await else {
        panic!("_team/events is a queue");
    };

    c.stop().await;
    let s = wait_for(&status, "a stale link once c left", |s| s.state == "stale").await;
    assert!(input.value() > 0.0, "the last value is kept: {s:?}");
    let members = a.handle::<TeamMembers>("_team/members").await;
    wait_for(&members, "c gone from a's members", |l| {
        names(l) == ["a", "b"]
    })
    .await;
    events_until(&mut events, |e| e.agent == "c" && e.kind == "left").await;

    // The same agent comes back (a restarted process): links resume with no manual step. (On
    // a fresh port: between the stop and the restart, a test running in parallel may have
    // been given the old one; the processes test restarts on the same port.)
    let before = input.value();
    let c = start(&agent_config("c", &team, free_port(), &[pa], "", counter)).await;
    wait_for(&status, "the link live again", |s| s.state == "live").await;
    wait_for(&members, "c back in a's members", |l| {
        names(l) == ["a", "b", "c"]
    })
    .await;
    let seen = events_until(&mut events, |e| e.agent == "c" && e.kind == "rejoined").await;
    assert!(
        !seen.iter().any(|e| e.kind == "joined"),
        "c was seen before: {seen:?}"
    );
    // The new c counts from 0 again: values move on from what it sends now.
    wait_for(&input, "values from the new c", |v| *v != before).await;
    for m in [c, b, a] {
        m.stop().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_second_run_of_an_agent_is_refused_while_the_first_answers() {
    let team = team_name("claim");
    let pa = free_port();
    let counter = r#"(name: "count", type: "demo.counter", values: {"params/period_ms": 5}),"#;
    let a = start(&agent_config("a", &team, pa, &[], "", counter)).await;
    let b = start(&agent_config("b", &team, free_port(), &[pa], "", counter)).await;
    let members = b.handle::<TeamMembers>("_team/members").await;
    wait_for(&members, "a and b", |l| names(l) == ["a", "b"]).await;

    let Ok(Tap::Queue(mut events)) = b.agent.blackboard().tap("_team/events").await else {
        panic!("_team/events is a queue");
    };

    // A second run of a: refused at start, naming the run that holds the name.
    let again = agent_config("a", &team, free_port(), &[pa], "", counter);
    let refused = start_refused(&again).await;
    assert!(
        matches!(refused, petrel::team::TeamError::NameTaken { .. }),
        "{refused}"
    );
    let text = refused.to_string();
    assert!(
        text.contains(&format!("team `{team}` already has an agent `a`"))
            && text.contains(&format!("process {}", std::process::id()))
            && text.contains(a.team.zid()),
        "{text}"
    );

    // A holder of a name that does not answer (a stopped or killed run whose lease is not over;
    // here a bare session with a token) leaves the name to be taken over: c joins, and the
    // others take it once the silent token goes.
    let rogue = zenoh::open(
        petrel::team::zenoh_config(&petrel::actors::team::TeamConfig {
            name: team.clone(),
            mode: Default::default(),
            listen: vec![],
            connect: vec![format!("tcp/127.0.0.1:{pa}")],
            lease_ms: 1000,
            remote_write: vec![],
            scouting: false,
        })
        .unwrap(),
    )
    .await
    .unwrap();
    let token = rogue
        .liveliness()
        .declare_token(format!("petrel/{team}/@alive/c/0badc0de"))
        .await
        .unwrap();
    wait_for(&members, "the silent c among the members", |l| {
        names(l) == ["a", "b", "c"]
    })
    .await;
    let c = start(&agent_config("c", &team, free_port(), &[pa], "", counter)).await;
    drop(token);
    rogue.close().await.unwrap();
    wait_for(&members, "the running c with its modules", |l| {
        names(l) == ["a", "b", "c"] && l.0[2].modules == ["count"]
    })
    .await;
    // The refused run of a declared no token: the team saw c's claims, never a second a.
    let seen = events_until(&mut events, |e| e.agent == "c" && e.kind == "rejoined").await;
    assert!(
        !seen.iter().any(|e| e.agent == "a"),
        "the refused run never reached the team: {seen:?}"
    );
    for m in [c, b, a] {
        m.stop().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn teams_with_different_names_never_see_each_other() {
    let (pa, pb) = (free_port(), free_port());
    let a = start(&agent_config("a", &team_name("red"), pa, &[], "", "")).await;
    let b = start(&agent_config("b", &team_name("blue"), pb, &[pa], "", "")).await;
    let c = start(&agent_config(
        "c",
        &team_name("red"),
        free_port(),
        &[pa],
        "",
        "",
    ))
    .await;
    let members = a.handle::<TeamMembers>("_team/members").await;
    wait_for(&members, "a and c in red", |l| names(l) == ["a", "c"]).await;
    let blue = b.handle::<TeamMembers>("_team/members").await;
    wait_for(&blue, "b alone in blue", |l| names(l) == ["b"]).await;
    assert_eq!(names(&members.get()), ["a", "c"], "b never joined red");
    for m in [c, b, a] {
        m.stop().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn members_see_modules_added_and_removed_while_an_agent_runs() {
    let (a, b) = pair(
        "modules",
        ("", r#"(name: "count", type: "demo.counter"),"#),
        ("", r#"(name: "scale", type: "demo.scale"),"#),
    )
    .await;
    let members = b.handle::<TeamMembers>("_team/members").await;
    let modules_of_a = |l: &TeamMembers| {
        l.0.iter()
            .find(|m| m.agent == "a")
            .map(|m| m.modules.clone())
            .unwrap_or_default()
    };
    wait_for(&members, "a with its module", |l| {
        modules_of_a(l) == ["count"]
    })
    .await;
    let extra = petrel::actors::ModuleConfig {
        name: "extra".into(),
        type_name: "demo.signal".into(),
        ..Default::default()
    };
    let control = a.agent.modules();
    control.add(extra).await.expect("the module is added");
    wait_for(&members, "a's new module", |l| {
        modules_of_a(l) == ["count", "extra"]
    })
    .await;
    control
        .remove("extra")
        .await
        .expect("the module is removed");
    wait_for(&members, "a without it", |l| modules_of_a(l) == ["count"]).await;
    b.stop().await;
    a.stop().await;
}
