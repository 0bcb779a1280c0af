//! `petrel check`, and the checks `petrel run` makes before starting anything: the config
//! itself, the files it names, context rules and mission bindings — every problem at once,
//! each located in the file it comes from.

use std::path::PathBuf;
use std::process::ExitCode;

use petrel_actors::{
    ConfigError, ConfigErrors, ConfigFile, FilePath, Module, ModuleRegistry, PropertyKind, Registry,
};

use super::stdout::sayln;
use super::{bad_input, load};

/// `petrel check CONFIG... [--overlay ...]`.
pub(crate) fn check(
    registry: &ModuleRegistry,
    configs: &[PathBuf],
    overlays: &[PathBuf],
) -> ExitCode {
    if configs.len() > 1 && !overlays.is_empty() {
        eprintln!("error: --overlay takes one config; check each overlaid agent on its own");
        return ExitCode::from(super::EXIT_BAD_INPUT);
    }
    let mut files = Vec::new();
    let mut errors = Vec::new();
    for config in configs {
        match load(config, overlays).and_then(|f| check_all(&f, registry).map(|a| (f, a))) {
            Ok(checked) => files.push(checked),
            Err(e) => errors.extend(e.0),
        }
    }
    if errors.is_empty() {
        let loaded: Vec<ConfigFile> = files.iter().map(|(f, _)| f.clone()).collect();
        if let Err(e) = check_team(&loaded, registry) {
            errors.extend(e.0);
        }
    }
    if !errors.is_empty() {
        return bad_input(&ConfigErrors(errors));
    }
    for (file, agent) in files {
        let links = file
            .config
            .modules
            .iter()
            .map(|m| m.links.len())
            .sum::<usize>();
        let s = |n: usize| if n == 1 { "" } else { "s" };
        sayln!(
            "{}: ok: agent `{}`, {} module{}, {links} link{}",
            file.path().display(),
            agent.name,
            agent.modules,
            s(agent.modules),
            s(links)
        );
    }
    ExitCode::SUCCESS
}

/// Checks agents that run together: unique names, and each link from one of them to another
/// names a property that exists there, of the same kind (queue or value) and type.
pub(crate) fn check_team(
    files: &[ConfigFile],
    registry: &ModuleRegistry,
) -> Result<(), ConfigErrors> {
    let mut errors = Vec::new();
    let mut built = Vec::new();
    for file in files {
        if let Some((first, _)) = built
            .iter()
            .find(|(f, _): &&(&ConfigFile, Registry)| f.config.name == file.config.name)
        {
            errors.push(ConfigError::in_file(
                file.path(),
                format!(
                    "agent name `{}` is also the name of the agent in {}: each agent of a team needs its own name",
                    file.config.name,
                    first.path().display()
                ),
            ));
            continue;
        }
        built.push((file, file.build(registry)?));
    }
    for (file, reader) in &built {
        for link in reader.remote_links().links() {
            let Some((owner_file, owner)) = built
                .iter()
                .find(|(f, _)| Some(f.config.name.as_str()) == link.source.agent())
            else {
                continue;
            };
            let team = |f: &ConfigFile| f.config.team.as_ref().map(|t| t.name.clone());
            let problem = match (team(file), team(owner_file)) {
                (Some(mine), Some(theirs)) if mine != theirs => Some(format!(
                    "but agent `{}` is in team `{theirs}` and this agent in team `{mine}`: links reach only agents of the same team",
                    owner_file.config.name
                )),
                _ => remote_link_problem(owner, &link),
            };
            if let Some(problem) = problem {
                let (module, path) = link.input.split_once('/').unwrap_or_default();
                let message = format!(
                    "module `{module}`, `{path}`: links to `{}`, {problem}",
                    link.source
                );
                errors.push(file.error(module, Some(path), message));
            }
        }
    }
    match errors.is_empty() {
        true => Ok(()),
        false => Err(ConfigErrors(errors)),
    }
}

/// What is wrong with `link` given the agent that owns its source, if anything.
fn remote_link_problem(owner: &Registry, link: &petrel_actors::team::RemoteLink) -> Option<String> {
    let source = &link.source;
    if let Err(e) = owner.key_of(&source.key()) {
        return Some(format!("but {e}"));
    }
    let decl = owner
        .declarations(source.module())
        .into_iter()
        .find(|d| d.path == source.path())?;
    let wants_queue = matches!(link.feed, petrel_actors::team::RemoteFeed::Queue(_));
    if decl.kind == PropertyKind::QueueIn {
        return Some("which is a queue input: link to the queue it reads instead".into());
    }
    if decl.kind.is_queue() != wants_queue {
        let kind = decl.kind.to_string();
        let article = match kind.starts_with(['a', 'e', 'i', 'o', 'u']) {
            true => "an",
            false => "a",
        };
        return Some(format!(
            "which is {article} {kind}: a queue input links to a queue, a value to a value"
        ));
    }
    let (theirs, ours) = (decl.type_info.name(), link.feed.type_info().name());
    (theirs != ours).then(|| format!("which is a {theirs}, but the input is a {ours}"))
}

/// What a config that checks describes.
pub(crate) struct CheckedAgent {
    pub name: String,
    pub modules: usize,
    /// The files the agent's run uses: its config and overlays, and every file its modules'
    /// parameters name (worlds, rules, plans). No output of the run may be one of them.
    pub files: Vec<PathBuf>,
}

/// Builds the agent's registry and checks what a module would find wrong only at init: the files
/// the config names, the rules of every `context.manager`, the bindings of every mission.
pub(crate) fn check_all(
    file: &ConfigFile,
    registry: &ModuleRegistry,
) -> Result<CheckedAgent, ConfigErrors> {
    let built = file.build(registry)?;
    let (mut errors, missing) = check_files(file, &built);
    let used = files_used(file, &built);
    if let Some(section) = &file.config.record {
        // The file may come from `--record`: only the rest of the section is checked here.
        let path = std::path::Path::new("petrel-check.mcap");
        if let Err(e) = petrel_record::RecordOptions::from_section(section, Some(path), None, None)
        {
            let field = e.split(':').nth(1).map(str::trim).unwrap_or("record");
            let needle = match file.config.record.as_ref().map(|_| field) {
                Some(f) if !f.is_empty() && !f.contains(' ') => format!("{f}:"),
                _ => "record:".to_string(),
            };
            errors.push(file.locate(&needle, e));
        }
        if let Some(path) = &section.file {
            let inputs: Vec<&std::path::Path> = used.iter().map(PathBuf::as_path).collect();
            if let Some(problem) =
                petrel_record::target::target_problem(std::path::Path::new(path), &inputs)
            {
                errors.push(file.locate("file:", format!("record: file: {problem}")));
            }
        }
    }
    let without_missing_files = |module: &str| !missing.iter().any(|m| m == module);
    // What each module type checks itself (a world file that must parse, ...).
    for module in built.modules().iter().filter(|m| without_missing_files(m)) {
        let Some(module_type) = built.module_type(module).and_then(|t| registry.get(t)) else {
            continue;
        };
        for problem in module_type.check(&built, module) {
            let message = format!("module `{module}`: `{}`: {}", problem.path, problem.message);
            errors.push(file.error(module, Some(&problem.path), message));
        }
    }
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
        match petrel_contexts::check_rules(rules.as_path(), &built, &m.name) {
            Ok(warnings) => {
                for warning in warnings {
                    eprintln!("{}", warning.as_warning());
                }
            }
            Err(rule_errors) => errors.extend(rule_errors),
        }
    }
    for (module, input, output) in self_feeding_links(&built) {
        let message = format!(
            "module `{module}`: `{input}` reads its own `{output}`: every step that changes it wakes the next, a loop that runs as fast as the CPU allows unless the module stops changing it"
        );
        eprintln!(
            "{}",
            file.error(&module, Some(&input), message).as_warning()
        );
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
        files: used,
    };
    errors.extend(check_missions(file, built, &missions));
    match errors.is_empty() {
        true => Ok(agent),
        false => Err(ConfigErrors(errors)),
    }
}

/// Inputs linked to an output or state of their own module, as (module, input, output) paths.
fn self_feeding_links(built: &Registry) -> Vec<(String, String, String)> {
    let mut found = Vec::new();
    for module in built.modules() {
        let prefix = format!("{module}/");
        for decl in built.declarations(module) {
            let key = format!("{prefix}{}", decl.path);
            let Some(target) = built.link_of(&key) else {
                continue;
            };
            if let Some(own) = target.strip_prefix(&prefix) {
                found.push((module.clone(), decl.path.clone(), own.to_string()));
            }
        }
    }
    found
}

/// The files an agent's run uses: its config files, then each non-empty file parameter.
fn files_used(file: &ConfigFile, built: &Registry) -> Vec<PathBuf> {
    let mut used: Vec<PathBuf> = file.files().map(Into::into).collect();
    for module in built.modules() {
        for decl in built.declarations(module) {
            if let Some(path) = file_param(built, module, &decl.path).filter(|p| !p.is_empty()) {
                used.push(path.0);
            }
        }
    }
    used
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
            if path.is_empty() {
                continue;
            }
            let Err(problem) = petrel_actors::files::regular_file(path.as_path()) else {
                continue;
            };
            let message = format!(
                "module `{module}`: `{}` names {path}, but {problem} (relative paths are taken from the config file's directory)",
                decl.path
            );
            let mut error = file.error(module, Some(&decl.path), message);
            // The context manager the agent's `contexts:` field adds is written nowhere: the
            // error is the field's.
            if error.line == 0
                && module == super::load::CONTEXTS_MODULE
                && file.config.contexts.is_some()
            {
                error = file.locate(
                    "contexts:",
                    format!("`contexts:` names {path}, but {problem} (relative paths are taken from the config file's directory)"),
                );
            }
            errors.push(error);
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
            match petrel_plans::mission::check_mission(&bb, module).await {
                Ok(warnings) => {
                    for w in warnings {
                        eprintln!(
                            "{}",
                            file.error(module, Some(&w.needle), w.message).as_warning()
                        );
                    }
                }
                Err(problems) => errors.extend(
                    problems
                        .into_iter()
                        .map(|p| file.error(module, Some(&p.needle), p.message)),
                ),
            }
        }
        errors
    })
}
