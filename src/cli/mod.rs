//! The `petrel` command line: `run`, `check`, `modules`, `plan`, and the tools that attach to
//! running agents (`ls`, `get`, `set`).

mod attach;
mod check;
pub(crate) use check::check_all;
mod chrome;
pub mod console;
mod console_log;
mod exits;
mod follow;
mod foxglove;
mod graph;
mod hangup;
mod interrupt;
mod listing;
mod load;
pub(crate) use load::{bad_input, load};
mod logging;
mod modules;
mod outputs;
mod plan;
mod rate;
mod reach;
mod record;
mod record_log;
mod remote;
mod run;
mod runtime;
pub(crate) mod stdout;
mod stop_guard;
mod team_agent;
mod top;
mod trace;

use std::ffi::OsString;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::{Parser, Subcommand, ValueEnum};
use petrel_actors::ModuleRegistry;

// Exit codes: one table, documented in docs/missions.md ("Exit codes").
/// Exit code when a mission or plan failed, a module failed, or a check found errors.
pub(crate) const EXIT_FAILED: u8 = 1;
/// Exit code for bad input (config errors, unknown names).
pub(crate) const EXIT_BAD_INPUT: u8 = 2;
// 3: the supervisor gave up (`petrel_actors::EXIT_GAVE_UP`), passed on from the agent.
/// Exit code when time ran out (`run --for`, `plan simulate --steps`) with a mission still running.
pub(crate) const EXIT_STILL_RUNNING: u8 = 4;

#[derive(Parser)]
#[command(
    name = "petrel",
    version,
    about = "An async, actor-based, context-aware mission runtime for robots."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Runs agents from RON configs (several: a team in one process) until Ctrl-C or --for.
    Run(RunArgs),
    /// Checks configs (and overlays) without running anything; prints every error found.
    /// Several configs are also checked together: unique agent names, links between them.
    Check {
        /// The agent configs (RON).
        #[arg(required = true)]
        configs: Vec<PathBuf>,
        /// Configs or snapshots laid over CONFIG, in order.
        #[arg(long)]
        overlay: Vec<PathBuf>,
    },
    /// Prints an agent's modules and links as a Graphviz DOT graph (`| dot -Tsvg > g.svg`):
    /// a box per module, an edge per link; queues bold, links to other agents dashed.
    Graph {
        /// The agent config (RON).
        config: PathBuf,
        /// Configs or snapshots laid over CONFIG, in order.
        #[arg(long)]
        overlay: Vec<PathBuf>,
    },
    /// Lists module types, or describes one with `modules describe TYPE`.
    Modules {
        #[command(subcommand)]
        command: Option<ModulesCommand>,
    },
    /// Lists the agents running on this machine, or with AGENT, its modules and properties
    /// (kind, type, link).
    Ls {
        /// The agent to describe.
        agent: Option<String>,
        #[command(flatten)]
        reach: remote::Reach,
    },
    /// Prints a property of a running agent (its JSON and type).
    Get {
        /// The property, `petrel://agent/module/path` (or `agent/module/path`).
        url: String,
        #[command(flatten)]
        reach: remote::Reach,
    },
    /// Sets a `params/` or `control/` property of a running agent, where its owner allows it
    /// (an agent in a team: its `remote_write` patterns; an agent without a `team:` section:
    /// any). The value is RON, as in a config (`2.5`, `(x: 1.0, y: 2.0, theta: 0.0)`).
    Set {
        /// The property, `petrel://agent/module/path` (or `agent/module/path`).
        url: String,
        /// The new value (RON); one that starts with `-` is taken as it is (`-0.5`, `-inf`).
        #[arg(allow_hyphen_values = true)]
        value: String,
        #[command(flatten)]
        reach: remote::Reach,
    },
    /// Prints a property's values (the current one first) or a queue's items as they come,
    /// until Ctrl-C or `--count`.
    Echo {
        /// The property, `petrel://agent/module/path` (or `agent/module/path`).
        url: String,
        /// Stop after this many.
        #[arg(short = 'n', long)]
        count: Option<u64>,
        /// One JSON object per line: `{"seq", "stamp_ns", "type", "value"}`.
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        reach: remote::Reach,
    },
    /// Measures how often a property changes (rate, interval mean/min/max, jitter), from its
    /// owner's write stamps: once a second until Ctrl-C, or once after `--count` changes.
    Hz {
        /// The property, `petrel://agent/module/path` (or `agent/module/path`).
        url: String,
        /// Figures over the last this many changes (2 or more: a rate needs an interval).
        #[arg(short, long, default_value_t = follow::DEFAULT_WINDOW, value_parser = clap::value_parser!(u64).range(2..=1_000_000))]
        window: u64,
        /// Report once after this many changes, and exit (2 or more: a rate needs an interval).
        #[arg(short = 'n', long, value_parser = clap::value_parser!(u64).range(2..))]
        count: Option<u64>,
        #[command(flatten)]
        reach: remote::Reach,
    },
    /// Every module of every agent running here (or of AGENT): status, steps, steps/s, step
    /// times, restarts, failures, queue drops; refreshed each second until Ctrl-C.
    Top {
        /// Only this agent.
        agent: Option<String>,
        /// Print once and exit (for scripts); STEPS/S is then the steps seen in one second.
        #[arg(long)]
        once: bool,
        #[command(flatten)]
        reach: remote::Reach,
    },
    /// Prints supervisor, team, context and plan events of every agent running here (or of
    /// AGENT) as they happen, until Ctrl-C or `--count`.
    Events {
        /// Only this agent.
        agent: Option<String>,
        /// Stop after this many.
        #[arg(short = 'n', long)]
        count: Option<u64>,
        #[command(flatten)]
        reach: remote::Reach,
    },
    /// Serves the web console for agents already running (every `petrel run` on this machine,
    /// or those of `--team`), attached over their teams; agents are shown as they come and go.
    Console(attach::ConsoleArgs),
    /// Recordings (MCAP): `record info FILE` shows channels, types, counts, rates, duration
    /// and drops.
    Record {
        #[command(subcommand)]
        command: RecordCommand,
    },
    /// Runs CONFIG with the recorded outputs of the `--replace`d modules published in their
    /// place (those modules are not started), with the recorded timing scaled by `--rate`.
    Replay(ReplayArgs),
    /// Petri Net Plans: check, draw, compile and simulate PNML or text plans.
    Plan {
        #[command(subcommand)]
        command: plan::PlanCommand,
    },
}

#[derive(Subcommand)]
enum RecordCommand {
    /// What a recording holds: channels, schemas, counts, rates, duration, drops; whether it
    /// was finished or cut.
    Info {
        /// The recording (`.mcap`).
        file: PathBuf,
        /// Show what is readable of a damaged file instead of failing.
        #[arg(long)]
        salvage: bool,
    },
}

/// Arguments of `petrel replay`.
#[derive(clap::Args)]
struct ReplayArgs {
    /// The recording (`.mcap`).
    file: PathBuf,
    #[command(flatten)]
    run: RunArgs,
    /// A module whose recorded outputs are replayed in its place (repeat, or separate with
    /// commas, for several).
    #[arg(long, required = true, value_delimiter = ',')]
    replace: Vec<String>,
    /// Recorded time scale: `2` twice as fast, `max` as fast as the agent takes it.
    #[arg(long, default_value = "1", value_parser = record::parse_rate)]
    rate: f64,
    /// Replay what is readable of a damaged recording instead of failing.
    #[arg(long)]
    salvage: bool,
}

#[derive(Subcommand)]
enum ModulesCommand {
    /// Prints every property of a module type: path, kind, type, default and doc.
    Describe {
        /// The module type, e.g. `demo.scale`.
        type_name: String,
    },
}

/// Arguments of `petrel run`.
#[derive(clap::Args)]
pub(crate) struct RunArgs {
    /// The agent configs (RON); several run as a team in one process, each agent with its own
    /// team session.
    #[arg(required = true)]
    configs: Vec<PathBuf>,
    /// Stop after this long (e.g. `10s`, `1m30s`); default: run until Ctrl-C.
    #[arg(long = "for", value_parser = bounded_duration)]
    duration: Option<Duration>,
    /// Configs or snapshots laid over CONFIG, in order.
    #[arg(long)]
    overlay: Vec<PathBuf>,
    /// Write a snapshot of the whole blackboard here when stopping.
    #[arg(long)]
    snapshot_out: Option<PathBuf>,
    /// How long each module gets to stop before it is killed (default: each module's
    /// `shutdown_timeout_ms`, else the agent's `supervision.shutdown_timeout_ms`, 5 s). If a
    /// step holds its thread for good, the process ends at the longest timeout + 0.5 s.
    #[arg(long, value_parser = bounded_duration)]
    stop_timeout: Option<std::time::Duration>,
    /// Log format on standard error (filter with RUST_LOG, default `info`).
    #[arg(long, value_enum, default_value_t = LogFormat::Pretty)]
    log_format: LogFormat,
    /// Threads of the shared runtime (default: one per core): where modules with long steps,
    /// agents with `scheduler: shared`, teams, the console and tools run. Each agent's other
    /// modules run on the agent's own thread.
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..=MAX_WORKERS as i64))]
    workers: Option<u16>,
    /// Do not join the teams the configs name (links to other agents stay `waiting`), and
    /// do not answer tools (`petrel ls|get|set|echo|hz|top|events`).
    #[arg(long)]
    no_remote: bool,
    /// Write a timeline of the run here (Chrome trace JSON, for Perfetto or chrome://tracing):
    /// each module a track, each step a span, restarts, context switches and plan steps as
    /// instants.
    #[arg(long)]
    trace_out: Option<PathBuf>,
    /// Record the run to this MCAP file: every property and queue, supervisor events, context
    /// switches, plan firings and the log (or what the config's `record:` section selects).
    #[arg(long)]
    record: Option<PathBuf>,
    /// How the standard types are written (default `foxglove`: protobuf for grids, scans, poses
    /// and images, JSON for the rest; `foxglove-json`: all JSON; `ros2`: ROS 2 messages, CDR).
    #[arg(long, value_enum)]
    record_format: Option<record::RecordFormat>,
    /// How the recording's chunks are compressed: zstd (default: less CPU and smaller files on
    /// petrel's recordings) or lz4 (faster to read back).
    #[arg(long, value_enum)]
    record_compression: Option<record::RecordCompression>,
    /// Serve the web console here (`127.0.0.1:8080`; port 0: any free port, printed): modules,
    /// live properties and parameter editing, links, plan, contexts, events, log, map.
    #[arg(long, value_name = "ADDR")]
    console: Option<std::net::SocketAddr>,
    /// The token every console request must carry (`?token=` or `Authorization: Bearer`);
    /// required beyond loopback, where one is generated and printed if not given.
    #[arg(long, value_name = "TOKEN", requires = "console")]
    console_token: Option<String>,
    /// Serve the Foxglove live view here (`127.0.0.1:8765`): the Foxglove WebSocket protocol
    /// with the channels and schemas of `--record` (its `--record-format`).
    #[arg(long, value_name = "ADDR")]
    foxglove: Option<std::net::SocketAddr>,
    /// Set by `petrel replay`.
    #[arg(skip)]
    replay: Option<record::ReplaySpec>,
}

/// The most worker threads `--workers` takes (more threads than this only cost memory on any
/// machine a robot carries).
const MAX_WORKERS: u16 = 256;

/// How logs are written.
#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum LogFormat {
    /// Human-readable lines.
    Pretty,
    /// One JSON object per line, for tools.
    Json,
}

/// Runs the command line given by `args` (including the program name) with module types `registry`.
pub fn main(registry: ModuleRegistry, args: impl IntoIterator<Item = OsString>) -> ExitCode {
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() {
                ExitCode::from(EXIT_BAD_INPUT)
            } else {
                ExitCode::SUCCESS
            };
        }
    };
    // A run (`run`, `replay`, the console) goes on when its standard output fails (`outln!`).
    let ends = !matches!(
        cli.command,
        Command::Run(_) | Command::Replay(_) | Command::Console(_)
    );
    if !matches!(cli.command, Command::Run(_)) {
        stop_quietly_on_a_closed_pipe();
    }
    let code = dispatch(registry, cli.command);
    match ends {
        true => stdout::finish(code),
        false => code,
    }
}

fn dispatch(registry: ModuleRegistry, command: Command) -> ExitCode {
    match command {
        Command::Run(args) => run::run(&registry, args),
        Command::Check { configs, overlay } => check::check(&registry, &configs, &overlay),
        Command::Graph { config, overlay } => graph::graph(&registry, &config, &overlay),
        Command::Modules { command: None } => modules::list(&registry),
        Command::Modules {
            command: Some(ModulesCommand::Describe { type_name }),
        } => modules::describe(&registry, &type_name),
        Command::Plan { command } => plan::run(command),
        Command::Record {
            command: RecordCommand::Info { file, salvage },
        } => record::info(&file, salvage),
        Command::Replay(args) => {
            let mut run = args.run;
            run.replay = Some(record::ReplaySpec {
                file: args.file,
                replace: args.replace,
                rate: args.rate,
                salvage: args.salvage,
            });
            run::run(&registry, run)
        }
        Command::Echo {
            url,
            count,
            json,
            reach,
        } => follow::echo(&reach, &url, count, json),
        Command::Hz {
            url,
            window,
            count,
            reach,
        } => follow::hz(&reach, &url, window, count),
        Command::Top { agent, once, reach } => top::run(&reach, agent.as_deref(), once),
        Command::Events {
            agent,
            count,
            reach,
        } => follow::events(&reach, agent.as_deref(), count),
        Command::Console(args) => attach::run(args),
        Command::Ls { agent, reach } => remote::list(&reach, agent.as_deref()),
        Command::Get { url, reach } => remote::property(&reach, &url, remote::Request::Get),
        Command::Set { url, value, reach } => {
            remote::property(&reach, &url, remote::Request::Set(value))
        }
    }
}

/// Lets a closed standard output (`petrel plan dot x.plan | head -1`) end the command as it
/// ends other Unix tools, by SIGPIPE (exit status 141 in a shell), instead of a panic in
/// `println!`. Not for `run`: a run keeps going and stops cleanly (cleanup, snapshot); its
/// printing goes through `outln!`, which stops printing on a closed pipe.
fn stop_quietly_on_a_closed_pipe() {
    // SAFETY: restores the default disposition of one signal before any thread that could
    // race on it exists; no handler is installed.
    #[cfg(unix)]
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// The longest `--for` or `--stop-timeout`: 10 years. Longer ones overflowed the clock
/// (`--for 18446744073709551615s` panicked the stop guard, and the run then ignored SIGTERM).
const MAX_DURATION: Duration = Duration::from_secs(10 * 365 * 24 * 3600);

/// A duration such as `10s` or `1m30s`, at most [`MAX_DURATION`].
fn bounded_duration(text: &str) -> Result<Duration, String> {
    let d = humantime::parse_duration(text).map_err(|e| e.to_string())?;
    if d > MAX_DURATION {
        return Err(format!(
            "{text} is longer than 10 years, the most a run can be given"
        ));
    }
    Ok(d)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set_value(args: &[&str]) -> Result<String, String> {
        match Cli::try_parse_from(args)
            .map_err(|e| e.to_string())?
            .command
        {
            Command::Set { value, .. } => Ok(value),
            _ => Err("not a set".into()),
        }
    }

    #[test]
    fn a_set_value_may_start_with_a_minus_and_options_still_work_around_it() {
        for value in ["-0.5", "-inf", "-1e3"] {
            assert_eq!(
                set_value(&["petrel", "set", "r/m/params/x", value]).as_deref(),
                Ok(value)
            );
        }
        let with_pid = ["petrel", "set", "--pid", "7", "r/m/params/x", "-inf"];
        assert_eq!(set_value(&with_pid).as_deref(), Ok("-inf"));
        let after = ["petrel", "set", "r/m/params/x", "-inf", "--pid", "7"];
        assert_eq!(set_value(&after).as_deref(), Ok("-inf"));
        let between = ["petrel", "set", "r/m/params/x", "--pid", "7", "-0.5"];
        assert_eq!(set_value(&between).as_deref(), Ok("-0.5"));
    }
}
