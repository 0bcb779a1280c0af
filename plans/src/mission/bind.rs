//! Resolving bindings against the blackboard at init: every action of the plan gets its
//! handles and expressions, every condition atom its expression; every problem is collected.

use std::collections::{BTreeSet, HashMap};

use petrel_actors::expr::{parse, properties, ExprId, ExprSet, PropId, Ty, TypeEnv};
use petrel_actors::{AnyHandle, AnyValue, Blackboard};

use super::config::{
    match_action, substitute, substitute_value, ActionBindings, ActionName, ConditionBindings,
};
use crate::model::Plan;

/// One plan action bound to modules and properties.
pub(crate) struct BoundAction {
    pub name: ActionName,
    /// `enabled` of each module to switch on while the action runs.
    pub enable: Vec<AnyHandle>,
    /// Property and value written at start.
    pub set: Vec<(AnyHandle, AnyValue)>,
    /// What `set` replaced, while the action is active.
    pub saved: Option<Vec<AnyValue>>,
    pub restore: bool,
    pub finished: Option<ExprId>,
    pub failed: Option<ExprId>,
    /// No binding and `params/allow_unbound`: finishes as soon as it is checked.
    pub unbound: bool,
}

/// Everything the mission needs at run time, resolved once.
pub(crate) struct Bound {
    pub exprs: ExprSet,
    /// Every property an expression reads, with the version last fed to `exprs`.
    pub watched: Vec<(PropId, AnyHandle, Option<u64>)>,
    pub conditions: HashMap<String, ExprId>,
    /// Atoms with no expression: read from the mission's `in/conditions`.
    pub defaults: Vec<String>,
    pub actions: HashMap<String, BoundAction>,
}

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

/// A binding that cannot be resolved: what is wrong, and the text of the config it is about
/// (an action or condition key, a module or property name), to locate it in the config file.
#[derive(Debug, Clone, PartialEq)]
pub struct BindingProblem {
    /// Config text the problem is about, as written between quotes.
    pub needle: String,
    /// What is wrong and what was expected.
    pub message: String,
}

/// What `bind` reads from the mission's parameters.
pub(crate) struct Params<'a> {
    pub module: &'a str,
    pub actions: &'a ActionBindings,
    pub conditions: &'a ConditionBindings,
    pub allow_unbound: bool,
}

struct Binder<'a> {
    bb: &'a Blackboard,
    module: &'a str,
    handles: HashMap<String, Option<AnyHandle>>,
    exprs: ExprSet,
    errors: Vec<BindingProblem>,
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

    /// Checks boolean expression `src`, reporting errors as `what: line:col: message`, located
    /// at `needle`.
    async fn expr(&mut self, src: &str, what: &str, needle: &str) -> Option<ExprId> {
        let ast = match parse(src) {
            Ok(a) => a,
            Err(e) => {
                self.problem(needle, format!("{what}: {e} (in `{src}`)"));
                return None;
            }
        };
        let mut env = TypeEnv::new();
        for p in properties(&ast) {
            // An unknown property is left out: the checker reports it with its position.
            if let Ok(h) = self.handle(&p).await {
                env.insert_property(&p, h.type_info(), &h.value());
            }
        }
        match self.exprs.add(src, &env, Some(&Ty::Bool)) {
            Ok(id) => Some(id),
            Err(e) => {
                self.problem(needle, format!("{what}: {e} (in `{src}`)"));
                None
            }
        }
    }

    async fn action(&mut self, full: &str, p: &Params<'_>) -> Option<BoundAction> {
        let name = ActionName::parse(full);
        let mut a = BoundAction {
            name: name.clone(),
            enable: Vec::new(),
            set: Vec::new(),
            saved: None,
            restore: true,
            finished: None,
            failed: None,
            unbound: false,
        };
        let Some((key, params)) = match_action(p.actions.0.keys().map(|k| k.as_str()), &name.local)
        else {
            a.unbound = true;
            return p.allow_unbound.then_some(a);
        };
        let b = &p.actions.0[key];
        let what = format!("{}/params/actions[\"{key}\"]", self.module);
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
            match h.type_info().from_ron(substitute_value(value, &params)) {
                Ok(v) => a.set.push((h, v)),
                Err(e) => {
                    let expected = h.type_info().name();
                    let message = format!(
                        "{what}.set[\"{path}\"] (action `{full}`): expected {expected}: {e}"
                    );
                    self.problem(path, message);
                }
            }
        }
        a.restore = b.restore;
        if !b.finished.trim().is_empty() {
            let src = substitute(&b.finished, &params);
            a.finished = self.expr(&src, &format!("{what}.finished"), key).await;
        }
        if !b.failed.trim().is_empty() {
            let src = substitute(&b.failed, &params);
            a.failed = self.expr(&src, &format!("{what}.failed"), key).await;
        }
        Some(a)
    }
}

/// Binds every action and condition of `plan`; all problems at once in the error.
pub(crate) async fn bind(
    bb: &Blackboard,
    plan: &Plan,
    p: Params<'_>,
) -> Result<Bound, Vec<BindingProblem>> {
    let (action_names, cond_names) = plan_names(plan);
    let mut b = Binder {
        bb,
        module: p.module,
        handles: HashMap::new(),
        exprs: ExprSet::new(),
        errors: Vec::new(),
    };
    let mut actions = HashMap::new();
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
            unbound.iter().map(|u| format!("`{u}`")).collect::<Vec<_>>().join(", "),
            if keys.is_empty() { "none".to_string() } else { keys.join(", ") }
        );
        b.problem("params/actions", message);
    }
    let mut conditions = HashMap::new();
    let mut defaults = Vec::new();
    for atom in &cond_names {
        match p.conditions.0.get(atom) {
            Some(src) => {
                let what = format!("{}/params/conditions[\"{atom}\"]", p.module);
                if let Some(id) = b.expr(src, &what, atom).await {
                    conditions.insert(atom.clone(), id);
                }
            }
            None => defaults.push(atom.clone()),
        }
    }
    for extra in p.conditions.0.keys().filter(|k| !cond_names.contains(*k)) {
        tracing::warn!(condition = %extra, "params/conditions binds a condition the plan does not use");
    }
    if !b.errors.is_empty() {
        return Err(b.errors);
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
    Ok(Bound {
        exprs: b.exprs,
        watched,
        conditions,
        defaults,
        actions,
    })
}
