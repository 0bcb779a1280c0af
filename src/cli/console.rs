//! `petrel run --console ADDR`: serves the web console (petrel-console) for the run's agents,
//! with the plans their missions run (read here with petrel-plans: the console crate reads
//! no plan files) and the log tail. [`plan_graph`] is public for tests and embedders.

use std::net::SocketAddr;
use std::sync::RwLock;

use petrel_actors::{outln, Agent, FilePath};
use petrel_console::{
    AgentSource, Console, ConsoleOptions, LogTail, PlaceView, PlanGraph, TransitionView,
};
use petrel_plans::Plan;

static LOG_TAIL: RwLock<Option<LogTail>> = RwLock::new(None);

/// The log tail the console shows, while one runs (fed by `console_log`'s layer).
pub(crate) fn log_tail() -> Option<LogTail> {
    LOG_TAIL.read().unwrap_or_else(|e| e.into_inner()).clone()
}

/// Starts the console on `addr` for `agents`, printing where it is (and a generated token).
pub(crate) async fn start(
    addr: SocketAddr,
    token: Option<String>,
    agents: &[Agent],
) -> Result<Console, String> {
    let mut sources = Vec::new();
    for agent in agents {
        let mut source = AgentSource::new(agent.name(), agent.blackboard().clone());
        source.plans = plans_of(agent).await;
        sources.push(source);
    }
    serve(addr, token, sources).await
}

/// Starts the console on `addr` for `sources`, printing where it is (and a generated token).
pub(crate) async fn serve(
    addr: SocketAddr,
    token: Option<String>,
    sources: Vec<AgentSource>,
) -> Result<Console, String> {
    let logs = LogTail::default();
    *LOG_TAIL.write().unwrap_or_else(|e| e.into_inner()) = Some(logs.clone());
    let console = Console::start(ConsoleOptions { addr, token }, sources, logs)
        .await
        .map_err(|e| e.to_string())?;
    outln!("console: {}", console.url());
    if console.token_generated() {
        eprintln!(
            "console: {} is not loopback, so requests need this token (generated; give your own with --console-token): {}",
            console.local_addr().ip(),
            console.token().unwrap_or_default()
        );
    }
    Ok(console)
}

/// Stops the console and its log tail.
pub(crate) async fn stop(console: Console) {
    console.stop().await;
    *LOG_TAIL.write().unwrap_or_else(|e| e.into_inner()) = None;
}

/// What a run serves to watch it: the web console (`--console`), the Foxglove live view
/// (`--foxglove`).
#[derive(Default)]
pub(crate) struct Views {
    console: Option<Console>,
    foxglove: Option<petrel_console::FoxgloveServer>,
}

/// Starts the views `args` ask for.
pub(crate) async fn start_views(args: &super::RunArgs, agents: &[Agent]) -> Result<Views, String> {
    let mut views = Views::default();
    if let Some(addr) = args.console {
        views.console = Some(start(addr, args.console_token.clone(), agents).await?);
    }
    if let Some(addr) = args.foxglove {
        let format = args.record_format.map(Into::into);
        match super::foxglove::start(addr, format, agents).await {
            Ok(server) => views.foxglove = Some(server),
            Err(e) => {
                stop_views(views).await;
                return Err(e);
            }
        }
    }
    Ok(views)
}

/// Stops the views.
pub(crate) async fn stop_views(views: Views) {
    if let Some(console) = views.console {
        stop(console).await;
    }
    if let Some(server) = views.foxglove {
        super::record_log::install_live(None);
        server.stop().await;
    }
}

/// The plans of `agent`'s `mission.pnp` modules, from the files their parameters name (a plan
/// that does not load is left out: the mission module reports why).
async fn plans_of(agent: &Agent) -> Vec<PlanGraph> {
    let Ok(listing) = agent.blackboard().listing().await else {
        return Vec::new();
    };
    let mut files = Vec::new();
    for m in listing
        .modules
        .iter()
        .filter(|m| m.type_name == "mission.pnp")
    {
        let bb = agent.blackboard();
        let Ok(path) = bb.get::<FilePath>(&format!("{}/params/plan", m.name)).await else {
            continue;
        };
        let rules = bb
            .get::<FilePath>(&format!("{}/params/rules", m.name))
            .await
            .ok();
        files.push((m.name.clone(), (*path).clone(), rules.map(|r| (*r).clone())));
    }
    plans_from(files)
}

/// The plans of mission modules, from (module, plan file, rules file) (a plan that does not
/// load is left out: the mission module reports why).
pub(crate) fn plans_from(files: Vec<(String, FilePath, Option<FilePath>)>) -> Vec<PlanGraph> {
    let mut plans = Vec::new();
    for (module, path, rules) in files {
        let rules = rules.filter(|r| !r.0.as_os_str().is_empty());
        match petrel_plans::load_plan(&path.0, rules.as_ref().map(|r| r.0.as_path())) {
            Ok(loaded) => plans.push(plan_graph(&module, &loaded.plan)),
            Err(e) => {
                tracing::warn!(%module, error = %e, "the console cannot draw this plan")
            }
        }
    }
    plans
}

/// A plan's structure as the console draws it.
pub fn plan_graph(module: &str, plan: &Plan) -> PlanGraph {
    PlanGraph {
        module: module.to_string(),
        places: plan
            .places()
            .iter()
            .map(|p| PlaceView {
                label: p.label.clone(),
                role: match () {
                    _ if p.goal > 0 => "goal",
                    _ if p.fail > 0 => "fail",
                    _ if p.initial > 0 => "init",
                    _ if p.exec.is_some() => "exec",
                    _ => "",
                }
                .to_string(),
            })
            .collect(),
        transitions: plan
            .transitions()
            .iter()
            .map(|t| TransitionView {
                label: t.label.clone(),
                inputs: t.inputs.iter().map(|e| e.place).collect(),
                outputs: t.outputs.iter().map(|e| e.place).collect(),
            })
            .collect(),
    }
}
