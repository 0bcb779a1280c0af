//! Loading an agent's config as the CLI does (overlays, the context manager its `contexts:`
//! field adds, missions on their simulator's clock), and reporting config errors.

use std::path::PathBuf;
use std::process::ExitCode;

use petrel_actors::{ConfigErrors, ConfigFile, ModuleConfig};

use super::EXIT_BAD_INPUT;

/// Loads a config with its overlays, and adds the `contexts` module its `contexts:` field asks for
/// (on the clock of the agent's mission, when its `in/clock` is linked).
pub(crate) fn load(config: &PathBuf, overlays: &[PathBuf]) -> Result<ConfigFile, ConfigErrors> {
    let mut file = ConfigFile::load(config)?;
    for overlay in overlays {
        let before = file.config.name.clone();
        file.overlay(ConfigFile::load(overlay)?);
        // A deliberate rename (one base config, an overlay per robot) and a snapshot of another
        // robot laid over by mistake look the same here: said, so neither passes unseen.
        if file.config.name != before {
            eprintln!(
                "note: {}: renames the agent `{before}` to `{}`",
                overlay.display(),
                file.config.name
            );
        }
    }
    link_mission_clocks(&mut file);
    if let Some(rules) = file.config.contexts.clone() {
        // Relative to the config file, like every file path in it (resolved when built).
        let taken = file
            .config
            .modules
            .iter()
            .find(|m| m.name == CONTEXTS_MODULE);
        // A snapshot lists the manager itself; any other module of that name would silently
        // replace it, and the rules would never run.
        if let Some(m) = taken.filter(|m| m.type_name != "context.manager") {
            let message = format!(
                "the name `{CONTEXTS_MODULE}` is taken by the context manager that the agent's `contexts:` field adds; rename this `{}` module",
                m.type_name
            );
            return Err(ConfigErrors(vec![file.error(
                CONTEXTS_MODULE,
                None,
                message,
            )]));
        }
        if taken.is_none() {
            // Contexts run on the same clock as the agent's mission (`in/clock`), if it has one.
            let clock = file
                .config
                .modules
                .iter()
                .filter(|m| m.type_name == "mission.pnp")
                .find_map(|m| m.links.get("in/clock").cloned());
            file.config.modules.push(ModuleConfig {
                name: CONTEXTS_MODULE.into(),
                type_name: "context.manager".into(),
                values: [("params/rules".to_string(), ron::Value::String(rules))].into(),
                links: clock
                    .map(|c| [("in/clock".to_string(), c)].into())
                    .unwrap_or_default(),
                ..Default::default()
            });
        }
    }
    Ok(file)
}

/// The agent's clock is its simulator's when one drives it: a mission whose `in/clock` the
/// config leaves unlinked, in an agent with exactly one `sim.world`, runs on that world's
/// `out/simTime` (so `held(x, 2s)` is two simulated seconds, as the robot lives them).
fn link_mission_clocks(file: &mut ConfigFile) {
    let mut worlds = file
        .config
        .modules
        .iter()
        .filter(|m| m.type_name == "sim.world");
    let (Some(world), None) = (worlds.next(), worlds.next()) else {
        return;
    };
    let sim_time = format!("{}/out/simTime", world.name);
    for m in file
        .config
        .modules
        .iter_mut()
        .filter(|m| m.type_name == "mission.pnp")
    {
        m.links
            .entry("in/clock".to_string())
            .or_insert_with(|| sim_time.as_str().into());
    }
}

/// The name of the context manager that an agent's `contexts:` field adds.
pub(crate) const CONTEXTS_MODULE: &str = "contexts";

/// The most config errors printed: beyond, a count (a generated config with a typo in a
/// module type repeated 100,000 times printed 11 MB).
const MAX_SHOWN_ERRORS: usize = 200;

/// Prints config errors, one per line (the first [`MAX_SHOWN_ERRORS`]), and returns the
/// bad-input exit code.
pub(crate) fn bad_input(errors: &ConfigErrors) -> ExitCode {
    for e in errors.0.iter().take(MAX_SHOWN_ERRORS) {
        eprintln!("{e}");
    }
    let n = errors.0.len();
    if n > MAX_SHOWN_ERRORS {
        eprintln!(
            "... and {} more errors, not shown (fix the first ones: often one mistake repeated)",
            n - MAX_SHOWN_ERRORS
        );
    }
    eprintln!(
        "{n} error{} found; nothing was started",
        if n == 1 { "" } else { "s" }
    );
    ExitCode::from(EXIT_BAD_INPUT)
}
