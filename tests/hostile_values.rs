//! Hostile values: every numeric parameter of every module in the shipped configs is set to NaN,
//! infinities, zero, negative, tiny and huge values. Each value is refused by `petrel check`
//! (`petrel::check`), or the agent starts and runs with it: no module fails, panics or hangs.
//! A case that hangs ends the test binary with the case named.

use std::time::Duration;

use petrel::actors::{Agent, ConfigFile, PropertyKind, DEFAULT_STOP_TIMEOUT};

/// The configs whose modules the table runs: together they hold every module type but
/// `record.replay` (it needs a recording; its one number, `params/rate`, has a declared range).
const CONFIGS: &[&str] = &[
    "configs/navigate.ron",
    "configs/rescue/robot.ron",
    "configs/pipeline.ron",
    "configs/chaos.ron",
    "configs/contexts-demo.ron",
    "configs/mission-demo.ron",
    "configs/examples/patrol.ron",
    "configs/rescue/team/world.ron",
    "configs/rescue/team/coordinator.ron",
    // A team robot, with the fault scenario's sim.fault.
    "configs/rescue/team/fault/robot_1.ron",
];

/// Wall-clock time a case may take before the test binary is ended with the case named.
const CASE_DEADLINE: Duration = Duration::from_secs(60);

/// Virtual time each accepted case runs.
const RUN: Duration = Duration::from_millis(500);

fn float(x: f64) -> ron::Value {
    ron::Value::Number(ron::value::Number::F64(x.into()))
}

fn hostile_floats() -> Vec<(String, ron::Value)> {
    [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        0.0,
        -1.0,
        1e-300,
        1e300,
        -1e300,
    ]
    .into_iter()
    .map(|x| (format!("{x:e}"), float(x)))
    .collect()
}

fn hostile_integers() -> Vec<(String, ron::Value)> {
    [i64::MIN, -1, 0, i64::MAX]
        .into_iter()
        .map(|n| {
            (
                n.to_string(),
                ron::Value::Number(ron::value::Number::I64(n)),
            )
        })
        .collect()
}

/// Runs every hostile case of `config` (a shipped config) and returns what went wrong.
fn cases_of(config: &str) -> Vec<String> {
    let types = petrel::Petrel::new().registry().clone();
    let mut base = petrel::load(config).unwrap_or_else(|e| panic!("{config}: {e}"));
    // No pictures: they would land in the repository's out/.
    for m in &mut base.config.modules {
        if let Some(png) = m.values.get_mut("params/png") {
            *png = ron::Value::String(String::new());
        }
    }
    let mut problems = Vec::new();
    for module in &base.config.modules {
        let Some(module_type) = types.get(&module.type_name) else {
            continue;
        };
        for decl in module_type.properties() {
            if decl.kind != PropertyKind::Param || module.links.contains_key(&decl.path) {
                continue;
            }
            let values = match decl.type_info.name() {
                "f64" => hostile_floats(),
                "i64" => hostile_integers(),
                _ => continue,
            };
            for (shown, value) in values {
                let case = format!("{config}: {}/{} = {shown}", module.name, decl.path);
                // To look at one case: PETREL_HOSTILE_ONLY="wave/params/amplitude = 0".
                if std::env::var("PETREL_HOSTILE_ONLY").is_ok_and(|only| !case.contains(&only)) {
                    continue;
                }
                let mut file = base.clone();
                let m = file
                    .config
                    .modules
                    .iter_mut()
                    .find(|m| m.name == module.name)
                    .unwrap();
                m.values.insert(decl.path.clone(), value);
                if let Some(problem) = run_case(&case, &file, &types) {
                    problems.push(problem);
                }
            }
        }
    }
    problems
}

/// Starts the agent on a paused clock and runs it for [`RUN`]; a refusal at build time is
/// fine, a failure afterwards is the problem returned.
fn run_case(
    case: &str,
    file: &ConfigFile,
    types: &petrel::actors::ModuleRegistry,
) -> Option<String> {
    // `check` runs its own runtime: outside the case's.
    if petrel::check(file, types).is_err() {
        return None;
    }
    // Dropped (sent) when the case ends, also by a panic.
    let (done, finished) = std::sync::mpsc::channel::<()>();
    let named = case.to_string();
    std::thread::spawn(move || {
        if let Err(std::sync::mpsc::RecvTimeoutError::Timeout) =
            finished.recv_timeout(CASE_DEADLINE)
        {
            // Straight to the process's stderr: the test harness's capture dies with the abort.
            use std::io::Write;
            let _ = writeln!(std::io::stderr(), "hostile value case hung: {named}");
            std::process::abort();
        }
    });
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .start_paused(true)
        .build()
        .unwrap();
    let outcome = runtime.block_on(async {
        let agent = match Agent::start(file, types).await {
            Ok(agent) => agent,
            Err(e) => return Some(format!("{case}: checked, then could not start: {e}")),
        };
        tokio::time::sleep(RUN).await;
        let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
        // Failures a chaos module injects on purpose (panics, errors, hangs its watchdog
        // catches) are not the value's doing: with one, only the chaos module itself counts.
        let chaos: Vec<&str> = file
            .config
            .modules
            .iter()
            .filter(|m| m.type_name == "demo.chaos")
            .map(|m| m.name.as_str())
            .collect();
        let failed = |m: &&petrel::actors::ModuleReport| {
            m.failures > 0 && (chaos.is_empty() || chaos.contains(&m.name.as_str()))
        };
        summary.modules.iter().find(failed).map(|m| {
            format!(
                "{case}: checked, then `{}` failed: {}",
                m.name,
                m.last_error.as_deref().unwrap_or("?")
            )
        })
    });
    drop(done);
    outcome
}

fn assert_none(problems: Vec<String>) {
    assert!(
        problems.is_empty(),
        "{} hostile values got through:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn navigation_modules_refuse_or_survive_hostile_values() {
    assert_none(cases_of("configs/navigate.ron"));
}

#[test]
fn rescue_modules_refuse_or_survive_hostile_values() {
    assert_none(cases_of("configs/rescue/robot.ron"));
}

#[test]
fn demo_and_mission_modules_refuse_or_survive_hostile_values() {
    let mut problems = Vec::new();
    for config in &CONFIGS[2..7] {
        problems.extend(cases_of(config));
    }
    assert_none(problems);
}

#[test]
fn team_world_coordinator_and_robot_refuse_or_survive_hostile_values() {
    let mut problems = Vec::new();
    for config in &CONFIGS[7..] {
        problems.extend(cases_of(config));
    }
    assert_none(problems);
}

#[test]
fn the_table_covers_every_module_type() {
    let mut covered = std::collections::BTreeSet::new();
    for config in CONFIGS {
        let file = petrel::load(config).unwrap();
        covered.extend(file.config.modules.iter().map(|m| m.type_name.clone()));
    }
    let missing: Vec<&str> = petrel::Petrel::new()
        .registry()
        .types()
        .map(|t| t.name())
        .filter(|t| !covered.contains(*t) && *t != "record.replay")
        .collect();
    assert!(
        missing.is_empty(),
        "no config of the table runs {missing:?}"
    );
}
