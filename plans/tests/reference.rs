//! Loads, checks, draws and simulates every reference plan of `../shared/pnp/` (beside the
//! workspace; `PETREL_PNP_REFERENCE` overrides the directory). The files are read in place,
//! never copied (they are GPL). Without them the test says so and passes, unless
//! `PETREL_REQUIRE_REFERENCE` is set (CI sets it): then their absence fails it.

use std::path::PathBuf;

use petrel_plans::{check, load_plan, parse_pnml, simulate, to_dot, write_pnml, Script};

fn reference_dir() -> Option<PathBuf> {
    let dir = match std::env::var_os("PETREL_PNP_REFERENCE") {
        Some(d) => PathBuf::from(d),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/pnp"),
    };
    dir.is_dir().then_some(dir)
}

/// What each reference plan is known to be: the codes of its `check` errors and where an
/// empty script leads it within 100 steps. A plan that checks or runs differently fails.
const EXPECTED: &[(&str, &[&str], &str)] = &[
    ("MultiRobot.pnml", &["no-goal"], "running"),
    ("enabledTransitions.pnml", &[], "running"),
    ("enabledTransitions2.pnml", &[], "goal"),
    ("ending_plan.pnml", &[], "goal"),
    ("env1.pnml", &[], "running"),
    ("fetch_box_plan.pnml", &["no-goal"], "running"),
    ("fork_join.pnml", &[], "running"),
    ("interrupt.pnml", &[], "running"),
    ("name.pnml", &["no-goal", "no-initial-marking"], "running"),
    ("parallel.pnml", &[], "running"),
    ("plan2.pnml", &[], "running"),
    ("sensing.pnml", &[], "running"),
    ("sequence_loop.pnml", &[], "running"),
    ("simple.pnml", &[], "running"),
    ("subplan.pnml", &[], "goal"),
    ("superplan.pnml", &["no-goal"], "running"),
    ("test1.pnml", &[], "goal"),
    ("test2.pnml", &[], "goal"),
    ("test3.pnml", &[], "fail"),
    ("test4.pnml", &[], "goal"),
    ("text/DIAG_printer.plan", &[], "running"),
    ("text/test2.plan", &[], "goal"),
];

#[test]
fn every_reference_plan_loads_checks_draws_and_simulates_as_known() {
    let Some(dir) = reference_dir() else {
        assert!(
            std::env::var_os("PETREL_REQUIRE_REFERENCE").is_none(),
            "PETREL_REQUIRE_REFERENCE is set but the reference plans are missing (shared/pnp beside the workspace, or PETREL_PNP_REFERENCE)"
        );
        eprintln!("SKIPPED: no reference plans beside the workspace (shared/pnp)");
        return;
    };
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .chain(
            std::fs::read_dir(dir.join("text"))
                .into_iter()
                .flatten()
                .map(|e| format!("text/{}", e.unwrap().file_name().to_string_lossy())),
        )
        .filter(|p| p.ends_with(".pnml") || p.ends_with(".plan"))
        .collect();
    files.sort();
    let known: Vec<&str> = EXPECTED.iter().map(|(f, ..)| *f).collect();
    assert_eq!(files, known, "the reference set changed: update EXPECTED");
    let script = Script::parse("", "empty").unwrap();
    for (name, errors, result) in EXPECTED {
        let f = dir.join(name);
        let rules = f.with_extension("er");
        let rules = rules.is_file().then_some(rules);
        let l = load_plan(&f, rules.as_deref()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let report = check(&l.plan);
        let codes: Vec<&str> = report.errors.iter().map(|e| e.code).collect();
        assert_eq!(&codes, errors, "{name}: {:?}", report.errors);

        let dot = to_dot(&l.plan);
        assert!(dot.starts_with("digraph"), "{name}: {dot}");
        for place in l.plan.places() {
            assert!(
                dot.contains(&place.label),
                "{name}: place {} not drawn",
                place.label
            );
        }

        let again = parse_pnml(&write_pnml(&l.plan), "again", "again").unwrap();
        assert_eq!(
            again.transitions().len(),
            l.plan.transitions().len(),
            "{name}"
        );
        assert_eq!(again.places().len(), l.plan.places().len(), "{name}");

        let mut out = Vec::new();
        simulate(&l.plan, &script, 100, &mut out).unwrap();
        let lines = String::from_utf8(out).unwrap();
        let last = lines.lines().last().unwrap_or_default();
        assert!(
            last.contains(&format!("\"result\":\"{result}\"")),
            "{name}: ends {last}"
        );
    }
}
