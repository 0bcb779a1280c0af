//! The `mission.pnp` module: declare, bind at init, step the plan on events.

use std::time::Duration;

use petrel_actors::expr::Clock;
use petrel_actors::team::Message;
use petrel_actors::{
    Context, FilePath, Input, Module, Output, Param, Ports, QueueReader, QueueWriter, Range,
    Schedule, State,
};

use super::bind::plan_names;
use super::bound::Relink;
use super::config::{ActionBindings, ConditionBindings, Flags, Places};
use super::memory::{MissionMemory, PlanFiring};
use super::prepare::{prepare, Problems, Setup};
use super::run::{Run, StepTime, MAX_ROUNDS};
use super::shown::{marking, Shown};
use super::team::{is_serve, TeamIo, RUN, SERVE};
use super::timer::Timer;
use crate::exec::{PlanState, PlanStatus};
use crate::remote::Dispatch;

/// `mission.pnp`: see the [module docs](super).
pub struct Mission {
    plan_path: Param<FilePath>,
    rules: Param<FilePath>,
    is_mission: Param<bool>,
    tick_ms: Param<i64>,
    allow_unbound: Param<bool>,
    actions: Param<ActionBindings>,
    conditions: Param<ConditionBindings>,
    places: Param<Places>,
    mode: Param<String>,
    executor: Param<String>,
    flags: Input<Flags>,
    outbox: QueueWriter<Message>,
    firings: QueueWriter<PlanFiring>,
    inbox: QueueReader<Message>,
    /// Declared so configs can link it; read through a handle once linked (see `Clock`).
    _clock: Input<f64>,
    marking: Output<String>,
    running: Output<String>,
    robot_conditions: Output<String>,
    result: Output<String>,
    fired: Output<i64>,
    wake: State<i64>,
    memory: State<MissionMemory>,
    run: Option<Run>,
}

impl Module for Mission {
    const TYPE: &'static str = "mission.pnp";
    const DESCRIPTION: &'static str =
        "Runs a Petri Net Plan: actions bound to modules, conditions to property expressions.";

    fn declare(ports: &mut Ports) -> Self {
        let module = Mission {
            plan_path: ports.param("params/plan", FilePath::default(), "plan file (.pnml or text plan), relative to the config file"),
            rules: ports.param("params/rules", FilePath::default(), "execution rules file for a text plan (empty = none), relative to the config file"),
            is_mission: ports.param("params/is_mission", false, "goal stops the agent with exit code 0, fail with 1"),
            tick_ms: ports.param_in("params/tick_ms", 0, Range::new(0.0, 3.6e6), "also step every this many ms (0 = only on events)"),
            allow_unbound: ports.param("params/allow_unbound", false, "let actions without a binding finish at once instead of refusing to start"),
            actions: ports.param("params/actions", ActionBindings::default(), "action name (or prefix of `name_p1_p2`) -> (enable, set, restore, finished, failed)"),
            conditions: ports.param("params/conditions", ConditionBindings::default(), "condition atom -> boolean expression over properties"),
            places: ports.param("params/places", Places::default(), "named values action parameters may name: `goto_kitchen` with {\"kitchen\": (x: 2.0, y: 1.0)}"),
            mode: ports.param_one_of("params/mode", RUN, &[RUN, SERVE], "run: run the plan, sending other robots' `robot#` actions to their agents; serve: run no plan, carry out this agent's `agent#` actions for the plan a coordinator runs"),
            executor: ports.param("params/executor", "mission".to_string(), "the module (a mission.pnp in serve mode) that carries out `robot#` actions on each robot's agent"),
            outbox: ports.queue_out("out/outbox", 256, "team plan messages to robots or to the coordinator"),
            firings: ports.queue_out("out/firings", 64, "what each step fired, in order, and the marking it left (not pushed while the plan fires in a circle: the loop report names it)"),
            inbox: ports.queue_in("in/inbox", "team plan messages from the coordinator or from robots"),
            flags: ports.input("in/conditions", Flags::default(), "values of condition atoms that params/conditions does not bind"),
            _clock: ports.input("in/clock", 0.0, "the agent's clock in seconds (link it to a simulator's out/simTime); unlinked: wall time"),
            marking: ports.output("out/marking", String::new(), "marked places, `label` or `label*n`, comma-separated"),
            running: ports.output("out/running", String::new(), "running actions, comma-separated"),
            robot_conditions: ports.output("out/robot_conditions", String::new(), "other robots' conditions as the plan last heard them: `robot#cond=true`, `=false`, or `=?` (not heard yet, or the robot left), comma-separated"),
            result: ports.output("out/result", "running".to_string(), "running, goal or fail"),
            fired: ports.output("out/fired", 0, "transitions fired so far"),
            wake: ports.state("state/wake", 0, "bumped to make the mission step again: a held/age deadline passed, or many steps fired in a row"),
            memory: ports.state("state/memory", MissionMemory::default(), "the plan's marking, running actions with their start times, and what each action did: a restarted mission goes on from here"),
            run: None,
        };
        // Read only by `init`: a running agent refuses new values for these.
        ports.read_at_start(&[
            "params/plan",
            "params/rules",
            "params/actions",
            "params/conditions",
            "params/places",
            "params/mode",
            "params/executor",
            "params/allow_unbound",
        ]);
        module
    }

    fn schedule(&self) -> Schedule {
        let mut s = Schedule::new()
            .on_change(&self.flags)
            .on_change(&self.wake)
            .on_items(&self.inbox);
        if let Some(run) = &self.run {
            if let Some(members) = &run.team.members {
                s = s.on_change(members);
            }
            for (_, h, _) in &run.bound.watched {
                s = s.on_change(h);
            }
            if let Some(clock) = run.clock.handle() {
                s = s.on_change(clock);
            }
        }
        match self.tick_ms.value() {
            ms if ms > 0 => s.period(Duration::from_millis(ms as u64)),
            _ => s,
        }
    }

    async fn init(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let result = self.start(ctx).await;
        if let Err(e) = &result {
            if self.is_mission.value() {
                // The run exists for this mission: end it rather than idle forever.
                ctx.stop_agent(
                    2,
                    format!("mission `{}` could not start: {e:#}", ctx.module()),
                );
            }
        }
        result
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let Some(run) = self.run.as_mut() else {
            return Ok(());
        };
        if run.done {
            return Ok(());
        }
        let (mut fired, mut sub_fired) = (0, 0);
        let stamp = ctx.now();
        let (now, secs) = (run.clock.now(stamp), run.clock.secs(stamp));
        let t = StepTime { now, secs, stamp };
        if run.team.serve_mode {
            if run.serve_round(t, &self.flags, &self.inbox) {
                run.save(&self.memory);
            }
            run.team.send(&self.outbox);
            if run.clock.is_wall() {
                run.timer.set(run.bound.exprs.next_deadline());
            }
            return Ok(());
        }
        // Items wake the mission (ITEMS), and its first step reads what a predecessor left.
        let cause = ctx.cause();
        let may_step = run
            .team
            .take_news(&self.inbox, cause.items() || cause.first());
        if run.team.dispatch.has_conditions() {
            publish(
                &self.robot_conditions,
                &run.team.dispatch.conditions_shown(),
            );
        }
        if !may_step {
            // Waiting for robots' conditions: the watches must still go out (and be answered).
            run.answer_watches(t, &self.flags);
            run.team.send(&self.outbox);
            return Ok(());
        }
        // PNP needs repeated steps: transitions enabled by a step's firings wait for the next
        // one. Step again at once while something fires (bounded, so a cycle of plain
        // transitions cannot starve the agent: past the bound, `state/wake` asks for a new step).
        run.fired.clear();
        // Whether a round called an action (which may have enabled a module or written its
        // input), and whether this step already let such modules answer.
        let (mut called, mut settled) = (false, false);
        // Whether the watched properties must be looked at again (see `Run::round`).
        let mut fresh = true;
        for round in 1.. {
            let report = run.round(t, &self.flags, fresh || ctx.changes_pending());
            fresh = !run.bound.relinks.is_empty();
            if fresh {
                relink(ctx, &mut run.bound.relinks).await;
            }
            fired += report.fired;
            sub_fired += report.sub_fired;
            called |= report.called;
            let running = run.state.status(&run.plan) == PlanStatus::Running;
            // A firing inside a sub-plan is progress too: the next round may end the action
            // it started (one whose `finished` already holds), and nothing else would wake
            // the mission for it.
            if report.fired + report.sub_fired == 0 || !running {
                // Nothing more fires now. A module an action has just switched on may answer
                // at once (a quick action): let it, once per step, and go on with its answer
                // in this step rather than stepping again for it (see `settle`).
                if called && running && !settled {
                    settled = true;
                    if settle(ctx, &self.wake, run).await {
                        // The changes it took are this step's to read.
                        fresh = true;
                        continue;
                    }
                }
                break;
            }
            if round == MAX_ROUNDS {
                self.wake.set(self.wake.value() + 1);
                break;
            }
        }
        run.answer_watches(t, &self.flags);
        run.team.send(&self.outbox);
        if run.clock.is_wall() {
            run.timer.set(run.bound.exprs.next_deadline());
        }
        if fired + sub_fired > 0 {
            // Once per step, however many rounds fired: what the plan left (a call counted in
            // the actions' records, so the memory changed).
            run.save_changed(&self.memory, called);
            let news = run.shown.news(&run.plan, &run.state, &run.memory.marking);
            if news.running {
                self.running.set(news.texts.running.to_string());
            }
            // Before the marking: a reader following the marking reads the count with it.
            self.fired.set(self.fired.value() + fired as i64);
            if !run.fired.is_empty() {
                let (shown, fired) = (&run.shown, &run.fired);
                self.firings.push_with(|| PlanFiring {
                    time_s: secs,
                    transitions: shown.labels(fired),
                    marking: news.texts.marking.clone(),
                });
            }
            if news.marking {
                self.marking.set(news.texts.marking.to_string());
            }
        }
        let status = run.state.status(&run.plan);
        let runaway = if fired > 0 { run.runaway() } else { None };
        if status != PlanStatus::Running || runaway.is_some() {
            run.done = true;
            for a in run.bound.actions.values_mut().filter(|a| a.active()) {
                a.deactivate(&mut run.bound.relinks, stamp);
            }
            relink(ctx, &mut run.bound.relinks).await;
            let mut reason = format!("mission `{}` ended: {}", run.plan.name(), status.as_str());
            let failed = status == PlanStatus::Fail || runaway.is_some();
            if let Some(why) = &runaway {
                reason = format!("mission `{}` stopped: {why}", run.plan.name());
                tracing::error!("{reason}");
            } else if let Some(action) = run.state.unhandled_failure(&run.plan) {
                let why = run
                    .bound
                    .actions
                    .get(&action)
                    .map_or(String::new(), |a| format!(" (`failed`: {})", a.failed_text));
                reason = format!(
                    "{reason}: action `{action}` failed{why} and no execution rule handles its failure"
                );
                tracing::error!(action = %action, "{reason}");
                run.memory.count_unhandled_failure(&action, secs);
                run.memory.failed_action = Some(action);
            } else {
                tracing::info!(result = status.as_str(), "{reason}");
            }
            run.save(&self.memory);
            let result = if failed { PlanStatus::Fail } else { status };
            self.result.set(result.as_str().to_string());
            if self.is_mission.value() {
                ctx.stop_agent(u8::from(failed), reason);
            }
        }
        Ok(())
    }

    async fn cleanup(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        if let Some(run) = self.run.as_mut() {
            run.timer.set(None);
            // At a restart or a move the plan goes on from `state/memory`: no summary yet.
            if self.is_mission.value() && !run.memory.actions.is_empty() && !ctx.restarting() {
                // The run summary of a plan-driven mission: the plan's result and what each
                // action did (printed as the run stops, like the recorder's summary).
                petrel_actors::outln!(
                    "\n── plan `{}`: {} ─────────────────────\n{}",
                    run.plan.name(),
                    match run.runaway() {
                        Some(_) => PlanStatus::Fail.as_str(),
                        None => run.state.status(&run.plan).as_str(),
                    },
                    run.memory.report()
                );
            }
        }
        Ok(())
    }
}

impl Mission {
    /// Loads the plan and binds it (the body of `init`).
    async fn start(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let serve = is_serve(&self.mode.get()).map_err(|e| {
            petrel_actors::Unrecoverable(format!("invalid parameter `params/mode`: {e}"))
        })?;
        let setup = Setup {
            plan: self.plan_path.get(),
            rules: self.rules.get(),
            actions: self.actions.get(),
            conditions: self.conditions.get(),
            places: self.places.get(),
            allow_unbound: self.allow_unbound.value(),
            agent: ctx.agent().to_string(),
            serve,
            team: ctx.blackboard().any_handle("_team/members").await.is_ok(),
        };
        let (plan, bound) = prepare(ctx.blackboard(), ctx.module(), &setup)
            .await
            .map_err(|problems| anyhow::anyhow!("{}", Problems(&problems, &setup.plan)))?;
        let clock = Clock::of_module(ctx.blackboard(), ctx.module()).await;
        if !bound.defaults.is_empty() {
            tracing::info!(atoms = ?bound.defaults, "conditions read from in/conditions");
        }
        let wake = ctx
            .blackboard()
            .any_handle(&format!("{}/state/wake", ctx.module()))
            .await?;
        let timer = Timer::start(wake);
        tracing::info!(
            plan = plan.name(),
            actions = bound.actions.len(),
            conditions = bound.conditions.len(),
            "mission bound"
        );
        let dispatch = match serve {
            true => Dispatch::new(ctx.agent(), "", [], []),
            false => {
                let (actions, conditions) = plan_names(&plan);
                let executor = self.executor.get();
                Dispatch::new(
                    ctx.agent(),
                    &executor,
                    actions.iter().map(String::as_str),
                    conditions.iter().map(String::as_str),
                )
            }
        };
        let team = TeamIo::connect(ctx, dispatch, serve).await?;
        let state = PlanState::new(&plan);
        let shown = Shown::new(&plan);
        let mut run = Run {
            team,
            state,
            plan,
            bound,
            timer,
            done: false,
            changed: Vec::new(),
            clock,
            memory: MissionMemory::default(),
            loops: Default::default(),
            shown,
            spare: None,
            report: Default::default(),
            fired: Vec::new(),
            flags: Default::default(),
            keys: Vec::new(),
        };
        let memory = self.memory.get();
        if memory.plan != run.plan.name() && !memory.marking.is_empty() {
            tracing::warn!(
                kept = %memory.plan,
                plan = %run.plan.name(),
                "state/memory is of another plan: not used; the plan starts over"
            );
        }
        if memory.plan == run.plan.name() && !memory.marking.is_empty() {
            match run.resume(&memory) {
                Ok(()) => tracing::info!(
                    marking = %marking(&run.plan, &run.state),
                    running = ?memory.running.keys().collect::<Vec<_>>(),
                    "mission resumed from state/memory"
                ),
                Err(e) => tracing::warn!("state/memory not used: {e}; the plan starts over"),
            }
        }
        run.done = run.state.status(&run.plan) != PlanStatus::Running;
        publish(&self.marking, &marking(&run.plan, &run.state));
        self.run = Some(run);
        Ok(())
    }
}

/// Lets the modules a mission step's calls woke run ([`Context::settle`]); true when a watched
/// property changed meanwhile, for another round to read. Time and membership are read once
/// per step, so when they changed meanwhile the mission asks for another step (`state/wake`)
/// rather than take that change as seen.
async fn settle(ctx: &mut Context, wake: &State<i64>, run: &Run) -> bool {
    let outside = || {
        let clock = run.clock.handle().map(|h| h.version());
        let members = run.team.members.as_ref().map(|h| h.version());
        (wake.version(), clock, members)
    };
    let before = outside();
    let changed = ctx.settle().await;
    if outside() != before {
        wake.set(wake.value() + 1);
    }
    changed
}

/// Carries out the relinks the plan step's calls asked for, in order; a refused one is logged
/// (they were checked when the mission was bound).
async fn relink(ctx: &Context, relinks: &mut Vec<Relink>) {
    for r in relinks.drain(..) {
        let bb = ctx.blackboard();
        let result = match &r.source {
            Some(source) => bb.link(&r.input, source).await,
            None => bb.unlink(&r.input).await,
        };
        if let Err(e) = result {
            tracing::error!(input = %r.input, source = ?r.source, error = %e, "binding relink refused");
        }
    }
}

/// Writes `v` unless the output shows it already (a write wakes every reader).
fn publish(out: &Output<String>, v: &str) {
    if *out.get() != v {
        out.set(v.to_string());
    }
}
