//! `record.replay`: OpenRDK's playback module. Publishes the recorded outputs of the modules
//! it names (`params/modules`) in their place, with the recorded timing scaled by
//! `params/rate`, one recorded instant at a time, each taken by the modules downstream before
//! the next (`Context::settle_agent`). Those modules must not run: `petrel replay --replace`
//! does not start them; in a config of your own, set their `enabled` to false.

use std::time::Duration;

use anyhow::{bail, Context as _};
use petrel_actors::team::RemoteFeed;
use petrel_actors::{
    AgentView, CheckProblem, Context, FilePath, Input, Module, Output, Ports, Range, Schedule,
};
use tokio::time::Instant;

use crate::read::Recording;
use crate::replay::{plan, Rate, ReplayPlan};

/// Recorded instants published per step at most, and the longest a step goes on publishing
/// (on a clock that moves): then the module waits for its next wake-up, so the agent's timers
/// and its stop path get their turns however far behind the replay is.
const MAX_INSTANTS: usize = 512;
const SLICE: Duration = Duration::from_millis(5);

/// The `record.replay` module.
pub struct Playback {
    file: Input<FilePath>,
    modules: Input<String>,
    rate: Input<f64>,
    salvage: Input<bool>,
    stop_at_end: Input<bool>,
    published: Output<i64>,
    done: Output<bool>,
    run: Option<Run>,
}

struct Run {
    recording: Recording,
    plan: ReplayPlan,
    feeds: Vec<RemoteFeed>,
    rate: Rate,
    next: usize,
    start: Option<Instant>,
    first_ns: u64,
}

impl Run {
    fn due(&self, i: usize) -> Option<Instant> {
        let (ns, _, _) = *self.plan.schedule.get(i)?;
        Some(self.start? + self.rate.due(ns.saturating_sub(self.first_ns)))
    }
}

impl Module for Playback {
    const TYPE: &'static str = "record.replay";
    const DESCRIPTION: &'static str =
        "Replays the recorded outputs of other modules from an MCAP file, in their place.";

    fn declare(ports: &mut Ports) -> Self {
        Playback {
            file: ports.param("params/file", FilePath::default(), "the recording (`.mcap`, relative to the config file)"),
            modules: ports.param("params/modules", String::new(), "the modules whose recorded outputs are replayed, comma separated (they must not run)"),
            rate: ports.param_in("params/rate", 1.0, Range::new(0.0, 1000.0), "recorded time scale: 2 = twice as fast; 0 = as fast as possible"),
            salvage: ports.param("params/salvage", false, "replay what is readable of a damaged file instead of failing"),
            stop_at_end: ports.param("params/stop_at_end", false, "end the run when the recording is replayed"),
            published: ports.output("out/published", 0, "messages published so far"),
            done: ports.output("out/done", false, "true once every message is published"),
            run: None,
        }
    }

    fn schedule(&self) -> Schedule {
        let Some(run) = &self.run else {
            return Schedule::new();
        };
        match (run.due(run.next), run.start) {
            (Some(due), Some(_)) => {
                let now = Instant::now();
                Schedule::new().timeout(
                    due.saturating_duration_since(now)
                        .max(Duration::from_micros(1)),
                )
            }
            _ => Schedule::new(),
        }
    }

    /// What `prepare` would refuse without reading the recording (past its first bytes, which
    /// say whether it is an MCAP file at all): `petrel check` says it at the property's line.
    /// (Whether the recording fits the config is known only once it is read, at the start of
    /// the run.)
    fn check(&self, agent: &AgentView) -> Vec<CheckProblem> {
        let mut problems = Vec::new();
        if let Err(e) = Rate::from_param(self.rate.value()) {
            problems.push(CheckProblem::new("params/rate", e));
        }
        let replayed = self.replayed();
        let names: Vec<&str> = replayed.iter().map(String::as_str).collect();
        let modules = match names.is_empty() {
            true => Some(NO_MODULES.to_string()),
            false => agent.names_problem(&names, None),
        };
        if let Some(problem) = modules {
            problems.push(CheckProblem::new("params/modules", problem));
        }
        // A file that is missing or not a regular file is refused for every file parameter.
        let file = self.file.get();
        if file.is_empty() {
            problems.push(CheckProblem::new("params/file", NO_FILE));
        } else if let Some(problem) = Recording::not_mcap(file.as_path()) {
            problems.push(CheckProblem::new("params/file", problem));
        }
        problems
    }

    async fn init(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        // A recording that does not fit the config is bad input, not a fault a restart
        // mends: the run ends, saying why.
        let result = self.prepare(ctx).await;
        if let Err(e) = &result {
            ctx.stop_agent(2, format!("{}: cannot replay: {e:#}", ctx.module()));
        }
        result
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        self.publish_due(ctx).await
    }
}

const NO_FILE: &str = "empty; expected the path of an MCAP recording";
const NO_MODULES: &str = "empty; expected the modules to replay, e.g. \"robot\"";

impl Playback {
    /// `params/modules`, split at commas.
    fn replayed(&self) -> Vec<String> {
        (self.modules.get().split(','))
            .map(str::trim)
            .filter(|m| !m.is_empty())
            .map(String::from)
            .collect()
    }

    /// Publishes the instants that are due, one at a time: after each, the agent's modules
    /// downstream take it (`settle_agent`) before the next is published, as they did live
    /// when the replayed module wrote one step's outputs and then waited for its next period.
    /// Without that, a fast replay wrote several steps' values over one another before their
    /// readers ran: a localizer saw only the last odometry of a batch, and a mapper put
    /// scans at the wrong poses.
    async fn publish_due(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let Some(run) = self.run.as_mut() else {
            return Ok(());
        };
        run.start.get_or_insert(ctx.now());
        let began = Instant::now();
        let mut instants = 0;
        while let Some(due) = run.due(run.next) {
            let now = Instant::now();
            if due > now || instants == MAX_INSTANTS || now.duration_since(began) >= SLICE {
                break;
            }
            let end = run.plan.instant_end(run.next);
            for &(_, track, index) in &run.plan.schedule[run.next..end] {
                let t = &run.plan.tracks[track];
                let feed = &run.feeds[track];
                let data = &run.recording.messages[index].data;
                match t.codec.decode(&feed.type_info(), data) {
                    Ok(value) => match feed {
                        RemoteFeed::Value(v) => v.write(value, now),
                        RemoteFeed::Queue(q) => q.push(value, now),
                    },
                    Err(e) => bail!("message {index} of channel `{}`: {e}", t.topic),
                }
            }
            run.next = end;
            instants += 1;
            ctx.settle_agent().await;
        }
        self.published.set(run.next as i64);
        if run.next == run.plan.schedule.len() {
            self.done.set(true);
            if self.stop_at_end.value() {
                ctx.stop_agent(0, "the recording is replayed");
            }
        }
        ctx.reschedule();
        Ok(())
    }

    async fn prepare(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let file = self.file.get();
        if file.is_empty() {
            bail!("params/file: {NO_FILE}");
        }
        let rate = (Rate::from_param(self.rate.value()))
            .map_err(|e| anyhow::anyhow!("invalid parameter `params/rate`: {e}"))?;
        let modules = self.replayed();
        if modules.is_empty() {
            bail!("params/modules: {NO_MODULES}");
        }
        let recording =
            Recording::open(file.as_path(), self.salvage.value()).map_err(anyhow::Error::msg)?;
        if let Some(p) = &recording.problem {
            tracing::warn!(module = ctx.module(), file = %file, "salvaging a damaged recording: {p}; replaying the {} messages before it", recording.messages.len());
        }
        let bb = ctx.blackboard();
        for m in &modules {
            // Both would write its outputs: the module must be off (`petrel replay --replace`
            // does not start it and turns it off).
            if let Ok(enabled) = bb.get::<bool>(&format!("{m}/enabled")).await {
                if *enabled {
                    bail!("module `{m}` is enabled: set its `enabled` to false in the config (or use `petrel replay --replace {m}`), so only the recording writes its outputs");
                }
            }
        }
        let listing = bb.listing().await?;
        let plan = plan(&recording, &modules, &listing).map_err(anyhow::Error::msg)?;
        let mut feeds = Vec::new();
        for t in &plan.tracks {
            feeds.push(
                bb.feed(&t.key)
                    .await
                    .with_context(|| format!("replaying into `{}`", t.key))?,
            );
        }
        tracing::info!(module = ctx.module(), file = %file, tracks = plan.tracks.len(), messages = plan.schedule.len(), "replaying");
        let first_ns = plan.schedule.first().map_or(0, |s| s.0);
        self.run = Some(Run {
            recording,
            plan,
            feeds,
            rate,
            next: 0,
            start: None,
            first_ns,
        });
        Ok(())
    }
}
