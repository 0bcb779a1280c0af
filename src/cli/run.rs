//! `petrel run`: start one agent or several (a team in one process), wait for Ctrl-C, `--for`
//! or an agent asking to end, stop cleanly, summarise.

use std::process::ExitCode;

use petrel_actors::{
    files, outln, status, Agent, ConfigFile, ModuleRegistry, StartError, EXIT_DIED,
};
use petrel_record::Recorder;
use petrel_team::discovery::Registration;
use petrel_team::Team;

use super::check::{check_all, check_team};
use super::exits::{die, first_exit};
use super::hangup::{reload_on_hangup, Hangups};
use super::stop_guard::StopGuard;
use super::{bad_input, load, logging, RunArgs, EXIT_BAD_INPUT, EXIT_FAILED, EXIT_STILL_RUNNING};

pub(crate) fn run(registry: &ModuleRegistry, args: RunArgs) -> ExitCode {
    if args.configs.len() > 1 && (!args.overlay.is_empty() || args.snapshot_out.is_some()) {
        eprintln!("error: --overlay and --snapshot-out take one agent; run each agent with its own `petrel run` to use them");
        return ExitCode::from(EXIT_BAD_INPUT);
    }
    if let Some(addr) = args.console {
        // The token rules are checked before anything starts (binding comes later).
        let given = args.console_token.as_deref();
        if let Err(e) = petrel_console::core::access::Access::for_bind(addr, given, String::new) {
            eprintln!("error: --console {addr}: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    }
    // Everything is loaded and checked before logging starts: the `--trace-out` file is made
    // only once it is known not to be a file the run uses.
    let (files, used) = match load_all(registry, &args) {
        Ok(loaded) => loaded,
        Err(code) => return code,
    };
    let used = super::outputs::borrowed(&used);
    let recording = match super::record::options(
        args.record.as_ref(),
        args.record_format,
        args.record_compression,
        &files,
        &used,
    ) {
        Ok(options) => options,
        Err(code) => return code,
    };
    let recording_path = recording.as_ref().map(|o| o.path.as_path());
    if let Some(problem) = super::outputs::problem(&args, &used, recording_path) {
        eprintln!("error: {problem}");
        return ExitCode::from(EXIT_BAD_INPUT);
    }
    let _trace = match logging::init(args.log_format, args.trace_out.as_deref()) {
        Ok(guard) => guard,
        Err(e) => {
            let path = args
                .trace_out
                .as_deref()
                .unwrap_or(std::path::Path::new(""));
            eprintln!("error: cannot write the trace to {}: {e}", path.display());
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    let runtime = match super::runtime::start(args.workers.map(Into::into)) {
        Ok(rt) => rt,
        Err(code) => return code,
    };
    let code = runtime.block_on(run_agents(registry, &args, files, recording));
    // A killed module whose step never yields still holds its worker thread: do not wait for it.
    runtime.shutdown_timeout(std::time::Duration::from_millis(100));
    code
}

/// Loads and checks every config, alone and together (links between them, unique names);
/// with the files their runs use.
fn load_all(
    registry: &ModuleRegistry,
    args: &RunArgs,
) -> Result<(Vec<ConfigFile>, Vec<std::path::PathBuf>), ExitCode> {
    let (mut files, mut used) = (Vec::new(), Vec::new());
    for config in &args.configs {
        let mut file = load(config, &args.overlay).map_err(|e| bad_input(&e))?;
        if let Some(replay) = &args.replay {
            super::record::apply_replay(&mut file, replay).map_err(|e| {
                eprintln!("error: {e}");
                ExitCode::from(EXIT_BAD_INPUT)
            })?;
        }
        let checked = check_all(&file, registry).map_err(|e| bad_input(&e))?;
        used.extend(checked.files);
        files.push(file);
    }
    check_team(&files, registry).map_err(|e| bad_input(&e))?;
    Ok((files, used))
}

async fn run_agents(
    registry: &ModuleRegistry,
    args: &RunArgs,
    files: Vec<ConfigFile>,
    recording: Option<petrel_record::RecordOptions>,
) -> ExitCode {
    // Listen before the agents start, so a SIGHUP sent as soon as the rules are loaded is a
    // reload, not the default "terminate".
    let hangups = Hangups::listen();
    let workers = tokio::runtime::Handle::current().metrics().num_workers();
    tracing::info!(workers, "modules run on {workers} worker thread(s)");
    let guard = match StopGuard::start(stop_limit(args, &files)) {
        Ok(guard) => guard,
        Err(e) => {
            eprintln!("error: cannot start the stop watchdog: {e}");
            return ExitCode::FAILURE;
        }
    };
    // Before the agents: the recorder taps each agent's properties before its modules start.
    let mut recorder = match recording {
        Some(options) => match super::record::start(options) {
            Ok(r) => Some(r),
            Err(code) => return code,
        },
        None => None,
    };
    let mut agents = Vec::new();
    let mut teams = Vec::new();
    let started = start_all(
        registry,
        args,
        &files,
        (&mut agents, &mut teams),
        recorder.as_mut(),
        &guard,
    )
    .await;
    let registration = match started {
        Ok(registration) => registration,
        Err(code) => {
            abandon(agents, teams, args, &guard, recorder).await;
            return code;
        }
    };
    let views = match super::console::start_views(args, &agents).await {
        Ok(views) => views,
        Err(e) => {
            eprintln!("error: {e}");
            drop(registration);
            abandon(agents, teams, args, &guard, recorder).await;
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    if let Some(duration) = args.duration {
        guard.run_for(duration);
    }
    let mut dead = vec![false; agents.len()];
    let mut reload = Box::pin(reload_on_hangup(hangups, &agents));
    let (mut why, mut code) = loop {
        tokio::select! {
            (i, exit) = first_exit(&agents, &dead) => {
                if exit.code != EXIT_DIED {
                    break (exit.reason, exit.code);
                }
                if dead.iter().filter(|d| !**d).count() == 1 {
                    // The last agent of the process: the process dies with it.
                    eprintln!("agent `{}` died: {}", agents[i].name(), exit.reason);
                    std::process::exit(EXIT_DIED.into());
                }
                die(&agents[i], &exit.reason, &mut teams, args).await;
                dead[i] = true;
            }
            asked = guard.requested() => break (asked.reason, asked.code),
            _ = &mut reload => unreachable!("reloading never ends"),
        }
    };
    drop(reload);
    if args.duration.is_some() && code == 0 && why.starts_with("ran for") {
        let pending = pending_missions(&agents, &files).await;
        if !pending.is_empty() {
            why = format!("{why}; mission still running: {}", pending.join(", "));
            code = EXIT_STILL_RUNNING;
        }
    }
    // Tools stop finding the run before its agents stop answering.
    drop(registration);
    super::console::stop_views(views).await;
    for agent in &agents {
        tracing::info!(agent = agent.name(), "stopping: {why}");
    }
    let summaries = stop_all(&agents, teams, args, &guard).await;
    if let Some(recorder) = recorder {
        if let Err(e) = super::record::finish(recorder).await {
            tracing::error!("{e}");
            code = code.max(EXIT_FAILED);
        }
    }
    if let (Some(path), [agent]) = (&args.snapshot_out, agents.as_slice()) {
        if !write_snapshot(agent, path).await {
            code = code.max(EXIT_FAILED);
        }
    }
    for agent in agents {
        agent.shutdown().await;
    }
    outln!("\n{why}");
    for summary in &summaries {
        outln!("{summary}");
    }
    let failed = summaries
        .iter()
        .flat_map(|s| &s.modules)
        .any(|m| m.status == status::FAILED || m.status == status::KILLED);
    if failed {
        // A log event, so `--log-format json` consumers see it too.
        tracing::error!("some modules failed or were killed: see the summary and the log");
        // A more specific reason (the supervisor gave up, a mission failed) keeps its code.
        if code == 0 {
            code = EXIT_FAILED;
        }
    }
    ExitCode::from(code)
}

/// A run refused at its start: its agents stopped and shut down, and no recording left
/// behind.
async fn abandon(
    agents: Vec<Agent>,
    teams: Vec<Team>,
    args: &RunArgs,
    guard: &StopGuard,
    recorder: Option<Recorder>,
) {
    stop_all(&agents, teams, args, guard).await;
    for agent in agents {
        agent.shutdown().await;
    }
    if let Some(recorder) = recorder {
        super::record::discard(recorder).await;
    }
}

/// `--snapshot-out`: the stopped agent's snapshot, written whole or not at all (a full disk
/// never leaves half a snapshot). Whether it was written; the error is printed.
async fn write_snapshot(agent: &Agent, path: &std::path::Path) -> bool {
    let written = agent
        .snapshot()
        .await
        .map_err(|e| e.to_string())
        .and_then(|s| files::write_atomically(path, s.as_bytes()).map_err(|e| e.to_string()));
    match written {
        Ok(()) => {
            outln!("snapshot written to {}", path.display());
            true
        }
        Err(e) => {
            eprintln!(
                "error: could not write the snapshot to {}: {e}",
                path.display()
            );
            false
        }
    }
}

/// Missions (`mission.pnp` modules with `params/is_mission`) whose plan has not ended, as
/// `agent/module`: a run stopped by `--for` before them did not do its job.
async fn pending_missions(agents: &[Agent], files: &[ConfigFile]) -> Vec<String> {
    let mut pending = Vec::new();
    for (agent, file) in agents.iter().zip(files) {
        for m in file
            .config
            .modules
            .iter()
            .filter(|m| m.type_name == "mission.pnp")
        {
            let bb = agent.blackboard();
            let is_mission = bb
                .get::<bool>(&format!("{}/params/is_mission", m.name))
                .await;
            let result = bb.get::<String>(&format!("{}/out/result", m.name)).await;
            if let (Ok(is_mission), Ok(result)) = (is_mission, result) {
                if *is_mission && result.as_str() == "running" {
                    pending.push(format!("{}/{}", agent.name(), m.name));
                }
            }
        }
    }
    pending
}

/// The longest a module of these agents may take to stop: `--stop-timeout`, else the longest
/// `shutdown_timeout_ms` their configs give.
fn stop_limit(args: &RunArgs, files: &[ConfigFile]) -> std::time::Duration {
    args.stop_timeout.unwrap_or_else(|| {
        let ms = files
            .iter()
            .flat_map(|f| {
                let agent = f.config.supervision.shutdown_timeout_ms;
                std::iter::once(agent).chain(
                    f.config
                        .modules
                        .iter()
                        .filter_map(|m| m.shutdown_timeout_ms),
                )
            })
            .max()
            .unwrap_or(0);
        std::time::Duration::from_millis(ms)
    })
}

/// Starts every agent, then joins each to its team or makes it reachable by tools (unless
/// `--no-remote`); the registration makes the run findable while it is held.
async fn start_all(
    registry: &ModuleRegistry,
    args: &RunArgs,
    files: &[ConfigFile],
    (agents, teams): (&mut Vec<Agent>, &mut Vec<Team>),
    mut recorder: Option<&mut Recorder>,
    guard: &StopGuard,
) -> Result<Option<Registration>, ExitCode> {
    let not_started = args.replay.as_ref().map_or(&[][..], |r| &r.replace[..]);
    for file in files {
        let prepared = match Agent::prepare(file, registry, not_started).await {
            Ok(prepared) => prepared,
            Err(StartError::Config(errors)) => return Err(bad_input(&errors)),
            Err(e) => {
                eprintln!("error: {e}");
                return Err(ExitCode::FAILURE);
            }
        };
        if let Some(recorder) = recorder.as_deref_mut() {
            super::record::attach(recorder, &file.config.name, prepared.blackboard()).await?;
        }
        match prepared.start().await {
            Ok(agent) => {
                guard.watch(agent.name(), agent.step_probe());
                agents.push(agent);
            }
            Err(StartError::Config(errors)) => return Err(bad_input(&errors)),
            Err(e) => {
                eprintln!("error: {e}");
                return Err(ExitCode::FAILURE);
            }
        }
    }
    if args.no_remote {
        return Ok(None);
    }
    super::reach::join_all(agents, files, teams).await
}

/// Stops every agent's modules (last started first), then leaves the teams. The `guard`, once
/// told, ends the process if the modules take longer than their stop timeout.
async fn stop_all(
    agents: &[Agent],
    teams: Vec<Team>,
    args: &RunArgs,
    guard: &StopGuard,
) -> Vec<petrel_actors::RunSummary> {
    guard.stopping();
    let mut summaries = Vec::new();
    for agent in agents.iter().rev() {
        summaries.push(agent.stop_modules(args.stop_timeout).await);
    }
    summaries.reverse();
    guard.modules_stopped();
    for team in teams {
        team.leave().await;
    }
    summaries
}
