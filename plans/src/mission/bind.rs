//! Resolving bindings against the blackboard at init: every action of the plan gets its
//! handles and expressions (its own binding, or a built-in), every condition atom its
//! expression; every problem is collected.

use std::collections::{BTreeSet, HashMap, HashSet};

use petrel_actors::expr::{parse, properties, ExprId, ExprSet, Ty, TypeEnv};
use petrel_actors::{AnyHandle, Blackboard};

use super::builtin::{builtin, not_a_wait, Builtin};
use super::config::{
    config_form, match_action, max_param, substitute, substitute_value, ActionBindings, ActionName,
    ConditionBindings, Places,
};
use super::hints::{nearest, place_hint, unused_bindings};
use crate::model::Plan;

use super::bound::{Bound, BoundAction, Positions};

/// Actions (sub-plans' included) and external conditions of a plan, each once, sorted.
pub(crate) fn plan_names(plan: &Plan) -> (BTreeSet<String>, BTreeSet<String>) {
    let (mut actions, mut conds) = (BTreeSet::new(), BTreeSet::new());
    fn walk(p: &Plan, a: &mut BTreeSet<String>, c: &mut BTreeSet<String>) {
        c.extend(p.conditions().iter().cloned());
        for e in p.executables() {
            match &e.subplan {
                Some(sp) => walk(sp, a, c),
                None => {
                    a.insert(e.name.clone());
                }
            }
        }
    }
    walk(plan, &mut actions, &mut conds);
    (actions, conds)
}

/// A binding that cannot be resolved, or looks wrong: what it is, and the text of the config
/// it is about (an action or condition key, a module or property name), to locate it in the
/// config file.
#[derive(Debug, Clone, PartialEq)]
pub struct BindingProblem {
    /// Config text the problem is about, as written between quotes.
    pub needle: String,
    /// What is wrong and what was expected.
    pub message: String,
}

/// Which of a team plan's names a mission binds: its own agent's.
#[derive(Clone, Copy)]
pub(crate) struct Scope<'a> {
    /// The agent the mission runs in.
    pub agent: &'a str,
    /// `serve` mode: only `agent#...` names (the rest belong to whoever runs the plan);
    /// otherwise every name but other robots' (`robot#...`, carried out by those robots).
    pub serve: bool,
    /// The agent is in a team: every condition of `params/conditions` is bound, used by the
    /// plan or not, since other agents' plans may watch it (`agent#cond`).
    pub team: bool,
}

impl Scope<'_> {
    /// Whether name `full` (an action or condition) is bound here.
    pub fn owns(&self, full: &str) -> bool {
        match crate::remote::robot_of(full) {
            Some((robot, _)) => robot == self.agent,
            None => !self.serve,
        }
    }
}

/// What `bind` reads from the mission's parameters.
pub(crate) struct Params<'a> {
    pub module: &'a str,
    pub scope: Scope<'a>,
    pub actions: &'a ActionBindings,
    pub conditions: &'a ConditionBindings,
    pub places: &'a Places,
    pub allow_unbound: bool,
}

/// What binding gives: the bound plan, or every error; warnings either way.
pub(crate) struct Binding {
    pub bound: Result<Bound, Vec<BindingProblem>>,
    pub warnings: Vec<BindingProblem>,
}

struct Binder<'a> {
    bb: &'a Blackboard,
    plan: &'a Plan,
    module: &'a str,
    handles: HashMap<String, Option<AnyHandle>>,
    exprs: ExprSet,
    errors: Vec<BindingProblem>,
    /// Expression errors reported (needle, field, error): a binding used by several actions
    /// (`count_5`, `count_1000`) has its mistake reported once, not once per action.
    reported: HashSet<(String, String, String)>,
}

impl Binder<'_> {
    fn problem(&mut self, needle: &str, message: String) {
        self.errors.push(BindingProblem {
            needle: needle.to_string(),
            message,
        });
    }

    async fn handle(&mut self, path: &str) -> Result<AnyHandle, String> {
        if !self.handles.contains_key(path) {
            let h = self.bb.any_handle(path).await.ok();
            self.handles.insert(path.to_string(), h);
        }
        self.handles[path]
            .clone()
            .ok_or_else(|| format!("unknown property `{path}`"))
    }

    /// A property an expression reads: a value, or a queue's latest item.
    async fn read_handle(&mut self, path: &str) -> Result<AnyHandle, String> {
        if self.handle(path).await.is_err() {
            let h = self.bb.expr_handle(path).await.ok();
            self.handles.insert(path.to_string(), h);
        }
        self.handles[path]
            .clone()
            .ok_or_else(|| format!("unknown property `{path}`"))
    }

    /// Checks that `input` can be linked to `source` (an input or parameter, a source of the
    /// same type); returns the link `input` has now, which `restore` puts back.
    async fn link(&mut self, input: &str, source: &str) -> Result<Option<String>, String> {
        let to = self.handle(input).await?;
        if !matches!(input.split('/').nth(1), Some("in" | "params")) {
            return Err(format!(
                "`{input}` is not an input or parameter; only those can be linked"
            ));
        }
        let from = self.handle(source).await?;
        let (want, have) = (to.type_info().name(), from.type_info().name());
        if want != have {
            return Err(format!("`{input}` is a {want}, but `{source}` is a {have}"));
        }
        // A link onto itself or around a loop of links, refused when made: the action went
        // on as if linked.
        self.bb
            .check_link(input, source)
            .await
            .map_err(|e| e.to_string())?;
        self.bb.link_of(input).await.map_err(|e| e.to_string())
    }

    /// Checks boolean expression `src`, reporting errors as `what: line:col: message`, located
    /// at `needle`.
    async fn expr(&mut self, src: &str, what: &str, needle: &str) -> Option<ExprId> {
        let ast = match parse(src) {
            Ok(a) => a,
            Err(e) => {
                self.expr_problem(src, what, needle, e.to_string());
                return None;
            }
        };
        let mut env = TypeEnv::new();
        for p in properties(&ast) {
            // An unknown property is left out: the checker reports it with its position.
            if let Ok(h) = self.read_handle(&p).await {
                env.insert_property(&p, h.type_info(), &h.value());
            }
        }
        match self.exprs.add(src, &env, Some(&Ty::Bool)) {
            Ok(id) => Some(id),
            Err(e) => {
                self.expr_problem(src, what, needle, e.to_string());
                None
            }
        }
    }

    /// Reports error `e` of expression `src`, unless the same error of the same field was
    /// reported already (the same binding, written for another action's parameters).
    fn expr_problem(&mut self, src: &str, what: &str, needle: &str, e: String) {
        let key = (needle.to_string(), what.to_string(), e.clone());
        if self.reported.insert(key) {
            let message = format!("{what}: {e} (in `{}`)", petrel_actors::expr::quoted(src));
            self.problem(needle, message);
        }
    }

    /// Where action `full` is written, for messages: ` at plan.plan:3`.
    fn at(&self, full: &str) -> String {
        self.plan
            .action_line(full)
            .map_or(String::new(), |l| format!(" at {l}"))
    }

    async fn action(&mut self, full: &str, p: &Params<'_>) -> Option<BoundAction> {
        let name = ActionName::parse(full);
        let mut a = BoundAction {
            enable: Vec::new(),
            set: Vec::new(),
            saved: None,
            links: Vec::new(),
            restore: true,
            finished: None,
            failed: None,
            failed_text: String::new(),
            log: None,
            unbound: false,
            unbound_said: false,
            said_in_loop: false,
        };
        let Some((key, params)) = match_action(p.actions.0.keys().map(|k| k.as_str()), &name.local)
        else {
            match builtin(&name.local) {
                Some(Builtin::Wait(secs)) => {
                    let src = format!("elapsed() >= {secs}");
                    a.finished = self.expr(&src, full, full).await;
                }
                Some(Builtin::Log(text)) => {
                    a.log = Some(text);
                    a.finished = self.expr("true", full, full).await;
                }
                None => {
                    a.unbound = true;
                    return p.allow_unbound.then_some(a);
                }
            }
            return Some(a);
        };
        let b = &p.actions.0[key];
        let what = format!("{}/params/actions[\"{key}\"]", self.module);
        let uses = max_param(b);
        if uses > 0 && params.len() != uses {
            let message = format!(
                "{what}: action `{full}`{} has {} parameter{}, but the binding uses up to ${uses}; write the action as `{key}{}`",
                self.at(full),
                params.len(),
                if params.len() == 1 { "" } else { "s" },
                (1..=uses).map(|i| format!("_P{i}")).collect::<String>()
            );
            self.problem(key, message);
            return Some(a);
        }
        for m in &b.enable {
            match self.handle(&format!("{m}/enabled")).await {
                Ok(h) => a.enable.push(h),
                Err(_) => self.problem(
                    m,
                    format!("{what}.enable (action `{full}`): no module `{m}` in this agent"),
                ),
            }
        }
        for (path, value) in &b.set {
            if *path == format!("{}/enabled", self.module) {
                let message = format!("{what}.set: `{path}` is this mission's own switch: turned off from its own action, it would never step again to end the action or the plan");
                self.problem(path, message);
                continue;
            }
            let h = match self.handle(path).await {
                Ok(h) if !path.contains("/stats/") => h,
                Ok(_) => {
                    let message =
                        format!("{what}.set: `{path}` is runtime-owned (stats) and cannot be set");
                    self.problem(path, message);
                    continue;
                }
                Err(e) => {
                    self.problem(path, format!("{what}.set (action `{full}`): {e}"));
                    continue;
                }
            };
            let given = substitute_value(value, &params, p.places);
            match h.type_info().from_ron(given.clone()) {
                // What `petrel set` and a config would refuse: a parameter out of its range.
                Ok(v) => match h.check(&v) {
                    Ok(()) => a.set.push((h, v)),
                    Err(e) => {
                        let message = format!(
                            "{what}.set[\"{path}\"] (action `{full}`{}): {e}{}",
                            self.at(full),
                            place_hint(value, &params, p.places),
                        );
                        self.problem(path, message);
                    }
                },
                Err(_) => {
                    let expected = h.type_info().to_ron(&h.value()).map_or_else(
                        |_| "a value of its type".to_string(),
                        |v| petrel_actors::spaced_ron(&v),
                    );
                    let message = format!(
                        "{what}.set[\"{path}\"] (action `{full}`{}): `{path}` takes a value like {expected}, found {}{}",
                        self.at(full),
                        config_form(&given),
                        place_hint(value, &params, p.places),
                    );
                    self.problem(path, message);
                }
            }
        }
        for (input, source) in &b.link {
            match self.link(input, source).await {
                Ok(original) => a.links.push((input.clone(), source.clone(), original)),
                Err(e) => self.problem(
                    input,
                    format!("{what}.link[\"{input}\"] (action `{full}`): {e}"),
                ),
            }
        }
        a.restore = b.restore;
        for (text, is_failed) in [(&b.finished, false), (&b.failed, true)] {
            if text.trim().is_empty() {
                continue;
            }
            let field = if is_failed { "failed" } else { "finished" };
            let src = match substitute(text, &params, p.places) {
                Ok(src) => src,
                Err(e) => {
                    let at = self.at(full);
                    self.problem(key, format!("{what}.{field} (action `{full}`{at}): {e}"));
                    continue;
                }
            };
            let id = self.expr(&src, &format!("{what}.{field}"), key).await;
            if is_failed {
                a.failed = id;
                a.failed_text = src;
            } else {
                a.finished = id;
            }
        }
        Some(a)
    }
}

/// Binds every action and condition of `plan`; all problems at once in the error.
pub(crate) async fn bind(bb: &Blackboard, plan: &Plan, p: Params<'_>) -> Binding {
    let (mut action_names, mut cond_names) = plan_names(plan);
    action_names.retain(|n| p.scope.owns(n));
    cond_names.retain(|n| p.scope.owns(n));
    if p.scope.team {
        for key in p.conditions.0.keys().filter(|k| !k.contains('#')) {
            if !cond_names.contains(&format!("{}#{key}", p.scope.agent)) {
                cond_names.insert(key.clone());
            }
        }
    }
    let mut b = Binder {
        bb,
        plan,
        module: p.module,
        handles: HashMap::new(),
        exprs: ExprSet::new(),
        errors: Vec::new(),
        reported: HashSet::new(),
    };
    let mut actions = foldhash::HashMap::default();
    let mut unbound = Vec::new();
    for full in &action_names {
        match b.action(full, &p).await {
            Some(a) => {
                actions.insert(full.clone(), a);
            }
            None => unbound.push(full.as_str()),
        }
    }
    if !unbound.is_empty() {
        let keys: Vec<&str> = p.actions.0.keys().map(|k| k.as_str()).collect();
        let message = format!(
            "{}/params/actions: no binding for action{} {} (bound: {}); bind them, or set params/allow_unbound to let them finish at once",
            p.module,
            if unbound.len() == 1 { "" } else { "s" },
            unbound
                .iter()
                .map(|u| format!("`{u}`{}{}", b.at(u), super::hints::misspelt_binding(u, &keys)))
                .collect::<Vec<_>>()
                .join(", "),
            if keys.is_empty() { "none".to_string() } else { keys.join(", ") }
        );
        let almost: Vec<String> = unbound
            .iter()
            .filter_map(|u| not_a_wait(crate::remote::robot_of(u).map_or(u, |(_, l)| l)))
            .collect();
        let message = match almost.is_empty() {
            true => message,
            false => format!("{message}; {}", almost.join("; ")),
        };
        b.problem("params/actions", message);
    }
    let warnings = unused_bindings(p.module, p.actions, &action_names);
    let mut conditions = foldhash::HashMap::default();
    let mut defaults = Vec::new();
    for atom in &cond_names {
        // This agent's own `me#cond` may be bound as `cond`, so robot configs need not name
        // their agent.
        let local = crate::remote::robot_of(atom).map_or(atom.as_str(), |(_, l)| l);
        match p
            .conditions
            .0
            .get(atom)
            .or_else(|| p.conditions.0.get(local))
        {
            Some(src) => {
                let what = format!("{}/params/conditions[\"{atom}\"]", p.module);
                if let Some(id) = b.expr(src, &what, atom).await {
                    conditions.insert(atom.clone(), id);
                }
            }
            None => defaults.push(atom.clone()),
        }
    }
    let mut warnings = warnings;
    // Legal (a tool, a context or a link may set `in/conditions`), but a plan waiting on a
    // condition nothing binds waits for ever if nothing does: worth a word.
    for atom in defaults
        .iter()
        .filter(|a| crate::remote::robot_of(a).is_none())
    {
        warnings.push(BindingProblem {
            needle: "params/plan".into(),
            message: format!(
                "{m}/params/conditions: the plan's condition `{atom}` is not bound; it is read from `{m}/in/conditions` (false until a tool, a context rule or a link sets it){}",
                nearest(atom, p.conditions.0.keys().map(String::as_str)),
                m = p.module,
            ),
        });
    }
    let used = |k: &String| {
        cond_names.contains(k) || cond_names.contains(&format!("{}#{k}", p.scope.agent))
    };
    for extra in p.conditions.0.keys().filter(|k| !used(k)) {
        warnings.push(BindingProblem {
            needle: extra.clone(),
            message: format!(
                "{}/params/conditions[\"{extra}\"]: the plan uses no condition `{extra}`{}",
                p.module,
                nearest(extra, cond_names.iter().map(String::as_str))
            ),
        });
    }
    if !b.errors.is_empty() {
        return Binding {
            bound: Err(b.errors),
            warnings,
        };
    }
    let watched = b
        .exprs
        .properties()
        .map(|(id, path)| {
            (
                id,
                b.handles[path]
                    .clone()
                    .expect("checked expressions only read known properties"),
                None,
            )
        })
        .collect();
    let at = Positions::of(plan, &conditions, &actions);
    Binding {
        bound: Ok(Bound {
            exprs: b.exprs,
            watched,
            conditions,
            defaults,
            actions,
            relinks: Vec::new(),
            at,
        }),
        warnings,
    }
}
