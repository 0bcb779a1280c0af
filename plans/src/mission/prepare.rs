//! Loading a mission's plan and binding it, as the module's init does and as `petrel check`
//! does from a config (every problem at once, located by the config text it is about).

use std::sync::Arc;

use anyhow::Context as _;
use petrel_actors::{Blackboard, BlackboardError, FilePath};

use super::bind::{bind, BindingProblem, Params, Scope};
use super::bound::Bound;
use super::config::{ActionBindings, ConditionBindings, Places};
use crate::load::load_plan;
use crate::model::Plan;

/// A mission's parameters, as its init reads them (or `petrel check`, from the config).
pub(crate) struct Setup {
    pub(crate) plan: Arc<FilePath>,
    pub(crate) rules: Arc<FilePath>,
    pub(crate) actions: Arc<ActionBindings>,
    pub(crate) conditions: Arc<ConditionBindings>,
    pub(crate) places: Arc<Places>,
    pub(crate) allow_unbound: bool,
    /// The agent the mission runs in, and whether it serves a team plan run elsewhere.
    pub(crate) agent: String,
    pub(crate) serve: bool,
    /// The agent has a `team:` section.
    pub(crate) team: bool,
}

/// Loads the plan and binds its actions and conditions; every problem at once (warnings are
/// logged).
pub(crate) async fn prepare(
    bb: &Blackboard,
    module: &str,
    setup: &Setup,
) -> Result<(Arc<Plan>, Bound), Vec<BindingProblem>> {
    let (bound, warnings) = prepare_all(bb, module, setup).await;
    for w in &warnings {
        tracing::warn!("{}", w.message);
    }
    bound
}

/// [`prepare`], with the warnings returned rather than logged.
async fn prepare_all(
    bb: &Blackboard,
    module: &str,
    setup: &Setup,
) -> (
    Result<(Arc<Plan>, Bound), Vec<BindingProblem>>,
    Vec<BindingProblem>,
) {
    let plan_problem = |message| {
        vec![BindingProblem {
            needle: "params/plan".into(),
            message,
        }]
    };
    if setup.plan.is_empty() {
        let message = format!("{module}/params/plan is empty; expected a plan file");
        return (Err(plan_problem(message)), Vec::new());
    }
    let rules = (!setup.rules.is_empty()).then(|| setup.rules.as_path());
    let loaded = match load_plan(setup.plan.as_path(), rules)
        .with_context(|| format!("{module}/params/plan"))
    {
        Ok(loaded) => loaded,
        Err(e) => return (Err(plan_problem(format!("{e:#}"))), Vec::new()),
    };
    // `plan check` refuses it too; a robot serving a team plan runs no plan of its own.
    if loaded.plan.goal_places().is_empty() && !setup.serve {
        let message = format!(
            "{module}/params/plan: {}: the plan has no goal place, so it can never succeed (`petrel plan check` lists what it can reach)",
            setup.plan
        );
        return (Err(plan_problem(message)), Vec::new());
    }
    // What `petrel plan check` finds: its errors refuse the plan, its warnings are shown by
    // `petrel check` and logged by the run. A robot serving a team plan leaves it to the
    // coordinator.
    let mut warnings = Vec::new();
    if !setup.serve {
        let report = crate::analysis::check(&loaded.plan);
        let shown = |kind: &str, f: &crate::analysis::Finding| {
            format!(
                "{module}/params/plan: {}: {kind}[{}]: {}",
                setup.plan, f.code, f.message
            )
        };
        let problem = |kind, f| BindingProblem {
            needle: "params/plan".into(),
            message: shown(kind, f),
        };
        if !report.errors.is_empty() {
            let errors = report.errors.iter().map(|f| problem("error", f)).collect();
            return (Err(errors), Vec::new());
        }
        warnings.extend(report.warnings.iter().map(|f| problem("warning", f)));
    }
    let params = Params {
        module,
        scope: Scope {
            agent: &setup.agent,
            serve: setup.serve,
            team: setup.team,
        },
        actions: &setup.actions,
        conditions: &setup.conditions,
        places: &setup.places,
        allow_unbound: setup.allow_unbound,
    };
    let binding = bind(bb, &loaded.plan, params).await;
    warnings.extend(binding.warnings);
    (binding.bound.map(|bound| (loaded.plan, bound)), warnings)
}

/// Problems of [`prepare`] as the module's init error.
pub(crate) struct Problems<'a>(pub &'a [BindingProblem], pub &'a FilePath);

impl std::fmt::Display for Problems<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let Problems(problems, plan) = self;
        if let [only] = problems {
            if only.needle == "params/plan" {
                return write!(f, "{}", only.message);
            }
        }
        write!(f, "plan {plan}: bad bindings:")?;
        problems
            .iter()
            .try_for_each(|p| write!(f, "\n{}", p.message))
    }
}

/// Checks mission module `module` as its init would, without running anything: loads the plan
/// its parameters name and binds every action and condition against `bb`, an agent's
/// blackboard holding the config's values. What `petrel check` runs for each mission.
/// `Ok` holds the warnings (a binding no action uses, with the nearest action name).
pub async fn check_mission(
    bb: &Blackboard,
    module: &str,
) -> Result<Vec<BindingProblem>, Vec<BindingProblem>> {
    let param = |name: &str| format!("{module}/params/{name}");
    let read = async {
        Ok::<_, BlackboardError>(Setup {
            plan: bb.get::<FilePath>(&param("plan")).await?,
            rules: bb.get::<FilePath>(&param("rules")).await?,
            actions: bb.get::<ActionBindings>(&param("actions")).await?,
            conditions: bb.get::<ConditionBindings>(&param("conditions")).await?,
            places: bb.get::<Places>(&param("places")).await?,
            allow_unbound: *bb.get::<bool>(&param("allow_unbound")).await?,
            agent: bb.agent().to_string(),
            serve: false,
            team: bb.any_handle("_team/members").await.is_ok(),
        })
    };
    let mut setup = read.await.map_err(|e| {
        vec![BindingProblem {
            needle: module.to_string(),
            message: format!("module `{module}` is not a mission.pnp: {e}"),
        }]
    })?;
    let mode = bb.get::<String>(&param("mode")).await.unwrap_or_default();
    setup.serve = super::team::is_serve(&mode).map_err(|message| {
        vec![BindingProblem {
            needle: "params/mode".into(),
            message: format!("{}: {message}", param("mode")),
        }]
    })?;
    let (bound, warnings) = prepare_all(bb, module, &setup).await;
    let (plan, _) = bound?;
    // A snapshot's memory the mission cannot go on from: refused here, where a restart in a
    // run (whose memory the mission wrote itself) would warn and start the plan over.
    if let Ok(memory) = bb
        .get::<super::MissionMemory>(&format!("{module}/state/memory"))
        .await
    {
        if let Some(problem) = super::memory::memory_problem(&plan, &memory) {
            return Err(vec![BindingProblem {
                needle: "state/memory".into(),
                message: format!(
                    "{module}/state/memory: {problem}; remove it to start the plan over"
                ),
            }]);
        }
    }
    if !setup.team {
        let (actions, conditions) = super::bind::plan_names(&plan);
        let dispatch = crate::remote::Dispatch::new(
            &setup.agent,
            "",
            actions.iter().map(String::as_str),
            conditions.iter().map(String::as_str),
        );
        if setup.serve || !dispatch.is_empty() {
            return Err(vec![BindingProblem {
                needle: "params/plan".into(),
                message: format!(
                    "{module}: {}",
                    super::team::needs_team(&dispatch, setup.serve, &setup.agent)
                ),
            }]);
        }
    }
    Ok(warnings)
}
