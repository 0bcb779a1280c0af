use std::sync::Arc;

use anyhow::{anyhow, bail, Context as _};
use petrel_actors::{AnyHandle, Context, Module, Output, Param, Ports, Range, Schedule};
use rand::Rng;

/// Faults `demo.chaos` knows how to inject.
const FAULTS: [&str; 3] = ["panic", "hang", "error"];

/// Chances are drawn this many times per mean interval, so intervals vary (geometrically).
const DRAWS_PER_INTERVAL: i64 = 4;

/// `demo.chaos`: makes chosen modules fail at random times, by writing a fault (`panic`,
/// `hang`, `error`) to their `control/fault` property, to show supervision at work.
pub struct Chaos {
    targets: Param<String>,
    faults: Param<String>,
    mean_interval_ms: Param<i64>,
    seed: Param<i64>,
    injected: Output<i64>,
    handles: Vec<(String, AnyHandle)>,
    kinds: Vec<&'static str>,
    rng: crate::seeded::SeededRng,
}

/// Splits a comma-separated list, trimming blanks.
const NO_TARGETS: &str = "empty; expected comma-separated module names";

/// The faults `params/faults` names, or what is wrong with it.
fn fault_kinds(faults: &str) -> Result<Vec<&'static str>, String> {
    let kinds = list(faults)
        .into_iter()
        .map(|fault| {
            FAULTS
                .iter()
                .find(|f| **f == fault)
                .copied()
                .ok_or_else(|| format!("`{fault}` is no fault; expected panic, hang or error"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    match kinds.is_empty() {
        true => Err("empty; expected panic, hang or error".into()),
        false => Ok(kinds),
    }
}

fn list(text: &str) -> Vec<&str> {
    text.split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .collect()
}

impl Module for Chaos {
    const TYPE: &'static str = "demo.chaos";
    const DESCRIPTION: &'static str =
        "Makes the modules in params/targets panic, hang or fail at random.";

    fn declare(ports: &mut Ports) -> Self {
        let module = Chaos {
            targets: ports.param(
                "params/targets",
                String::new(),
                "comma-separated module names",
            ),
            faults: ports.param(
                "params/faults",
                "panic, hang".to_string(),
                "comma-separated: panic, hang, error",
            ),
            mean_interval_ms: ports.param_in(
                "params/mean_interval_ms",
                1000,
                Range::new(1.0, 3.6e6),
                "mean time between faults, ms",
            ),
            seed: ports.param("params/seed", 1, "random seed (same seed, same faults)"),
            injected: ports.output("out/injected", 0, "faults injected so far"),
            handles: Vec::new(),
            kinds: Vec::new(),
            rng: crate::seeded::seeded(1),
        };
        // Read only by `init`: a running agent refuses new values for these.
        ports.read_at_start(&["params/targets", "params/faults", "params/seed"]);
        module
    }

    fn schedule(&self) -> Schedule {
        Schedule::every(super::period(
            self.mean_interval_ms.value() / DRAWS_PER_INTERVAL,
        ))
    }

    /// What `init` would refuse of the lists, before anything runs.
    fn check(&self, agent: &petrel_actors::AgentView) -> Vec<petrel_actors::CheckProblem> {
        let targets = self.targets.get();
        let faults = self.faults.get();
        let targets = list(&targets);
        let problems = [
            (
                "params/targets",
                match targets.is_empty() {
                    true => Some(NO_TARGETS.to_string()),
                    false => agent.names_problem(&targets, None),
                },
            ),
            ("params/faults", fault_kinds(&faults).err()),
        ];
        problems
            .into_iter()
            .filter_map(|(path, problem)| Some(petrel_actors::CheckProblem::new(path, problem?)))
            .collect()
    }

    async fn init(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let targets = self.targets.get();
        if list(&targets).is_empty() {
            bail!("params/targets: {NO_TARGETS}");
        }
        for target in list(&targets) {
            let handle = ctx
                .blackboard()
                .any_handle(&format!("{target}/control/fault"))
                .await
                .with_context(|| format!("params/targets names `{target}`"))?;
            self.handles.push((target.to_string(), handle));
        }
        self.kinds = fault_kinds(&self.faults.get()).map_err(|e| anyhow!("params/faults: {e}"))?;
        self.rng = crate::seeded::seeded(self.seed.value() as u64);
        Ok(())
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        if ctx.cause().first() || self.rng.random_range(0..DRAWS_PER_INTERVAL) != 0 {
            return Ok(());
        }
        let (target, handle) = &self.handles[self.rng.random_range(0..self.handles.len())];
        let fault = self.kinds[self.rng.random_range(0..self.kinds.len())];
        tracing::warn!(target = %target, fault, "chaos: injecting a fault");
        handle.set(Arc::new(fault.to_string()))?;
        self.injected.set(self.injected.value() + 1);
        Ok(())
    }
}
