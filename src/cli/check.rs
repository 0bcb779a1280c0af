//! `petrel check`, and the checks `petrel run` makes before starting anything: the config
//! itself, the files it names, context rules and mission bindings — every problem at once,
//! each located in the file it comes from.

use std::path::PathBuf;
use std::process::ExitCode;

use petrel_actors::{
    ConfigError, ConfigErrors, ConfigFile, FilePath, Module, ModuleRegistry, Registry,
};

use super::{bad_input, load};

/// `petrel check CONFIG [--overlay ...]`.
pub(crate) fn check(registry: &ModuleRegistry, config: &PathBuf, overlays: &[PathBuf]) -> ExitCode {
    let result = load(config, overlays)
        .and_then(|file| check_all(&file, registry).map(|agent| (file, agent)));
    match result {
        Ok((file, agent)) => {
            let links = file
                .config
                .modules
                .iter()
                .map(|m| m.links.len())
                .sum::<usize>();
            println!(
                "{}: ok: agent `{}`, {} modules, {links} links",
                config.display(),
                agent.name,
                agent.modules
            );
            ExitCode::SUCCESS
        }
        Err(errors) => bad_input(&errors),
    }
}

/// What a config that checks describes.
pub(crate) struct CheckedAgent {
    pub name: String,
    pub modules: usize,
}

/// Builds the agent's registry and checks what a module would find wrong only at init: the files
/// the config names, the rules of every `context.manager`, the bindings of every mission.
pub(crate) fn check_all(
    file: &ConfigFile,
    registry: &ModuleRegistry,
) -> Result<CheckedAgent, ConfigErrors> {
    let built = file.build(registry)?;
    let (mut errors, missing) = check_files(file, &built);
    let without_missing_files = |module: &str| !missing.iter().any(|m| m == module);
    for m in file
        .config
        .modules
        .iter()
        .filter(|m| m.type_name == petrel_contexts::ContextManager::TYPE)
        .filter(|m| without_missing_files(&m.name))
    {
        let Some(rules) = file_param(&built, &m.name, "params/rules") else {
            continue;
        };
        if let Err(rule_errors) = petrel_contexts::check_rules(rules.as_path(), &built) {
            errors.extend(rule_errors);
        }
    }
    let missions: Vec<&str> = file
        .config
        .modules
        .iter()
        .filter(|m| m.type_name == petrel_plans::mission::Mission::TYPE)
        .map(|m| m.name.as_str())
        .filter(|m| without_missing_files(m))
        .collect();
    let agent = CheckedAgent {
        name: built.agent().to_string(),
        modules: built.modules().len(),
    };
    errors.extend(check_missions(file, built, &missions));
    match errors.is_empty() {
        true => Ok(agent),
        false => Err(ConfigErrors(errors)),
    }
}

/// The value of `module`'s file parameter `path`, if it has one.
fn file_param(built: &Registry, module: &str, path: &str) -> Option<FilePath> {
    let (_, value) = built.get(&format!("{module}/{path}")).ok()?;
    value.downcast_ref::<FilePath>().cloned()
}

/// Every file parameter ([`FilePath`]) that names a file must name one that exists. Returns the
/// errors and the modules they concern.
fn check_files(file: &ConfigFile, built: &Registry) -> (Vec<ConfigError>, Vec<String>) {
    let (mut errors, mut modules) = (Vec::new(), Vec::new());
    for module in built.modules() {
        let params = built
            .declarations(module)
            .into_iter()
            .filter(|d| d.type_info.is::<FilePath>());
        for decl in params {
            let Some(path) = file_param(built, module, &decl.path) else {
                continue;
            };
            if path.is_empty() || path.as_path().is_file() {
                continue;
            }
            let problem = match path.as_path().exists() {
                true => "is not a file",
                false => "does not exist",
            };
            let message = format!(
                "module `{module}`: `{}` names {path}, which {problem} (relative paths are taken from the config file's directory)",
                decl.path
            );
            errors.push(file.error(module, Some(&decl.path), message));
            modules.push(module.clone());
        }
    }
    (errors, modules)
}

/// Loads each mission's plan and binds it as its init would, against a blackboard holding the
/// config's values (`built`; nothing runs), so bad bindings are found before the robot moves.
fn check_missions(file: &ConfigFile, built: Registry, missions: &[&str]) -> Vec<ConfigError> {
    if missions.is_empty() {
        return Vec::new();
    }
    let runtime = match tokio::runtime::Builder::new_current_thread().build() {
        Ok(rt) => rt,
        Err(e) => {
            let message = format!("cannot check missions: no async runtime: {e}");
            return vec![ConfigError::in_file(file.path(), message)];
        }
    };
    runtime.block_on(async {
        let (bb, _join) = match petrel_actors::Blackboard::spawn(built).await {
            Ok(bb) => bb,
            Err(e) => {
                let message = format!("cannot check missions: {e}");
                return vec![ConfigError::in_file(file.path(), message)];
            }
        };
        let mut errors = Vec::new();
        for &module in missions {
            if let Err(problems) = petrel_plans::mission::check_mission(&bb, module).await {
                errors.extend(
                    problems
                        .into_iter()
                        .map(|p| file.error(module, Some(&p.needle), p.message)),
                );
            }
        }
        errors
    })
}
