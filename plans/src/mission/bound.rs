//! What binding a plan to the blackboard gives a mission: each action's handles and
//! expressions, each condition's expression, and the same looked up by the plan's positions.

use petrel_actors::expr::{ExprId, ExprSet, PropId};
use petrel_actors::{AnyHandle, AnyValue};

use crate::model::Plan;

/// One plan action bound to modules and properties.
pub(crate) struct BoundAction {
    /// `enabled` of each module to switch on while the action runs.
    pub enable: Vec<AnyHandle>,
    /// Property and value written at start.
    pub set: Vec<(AnyHandle, AnyValue)>,
    /// What `set` replaced, while the action is active.
    pub saved: Option<Vec<AnyValue>>,
    /// Input, the source it is linked to while the action runs, and its link when the mission
    /// was bound (what `restore` puts back).
    pub links: Vec<(String, String, Option<String>)>,
    pub restore: bool,
    pub finished: Option<ExprId>,
    pub failed: Option<ExprId>,
    /// The `failed` expression as bound (parameters substituted), for the failure message.
    pub failed_text: String,
    /// Text a built-in `log_...` / `say_...` action logs when it starts.
    pub log: Option<String>,
    /// No binding and `params/allow_unbound`: finishes as soon as it is checked.
    pub unbound: bool,
    /// The warning about an unbound action is said once, not at every call.
    pub unbound_said: bool,
    /// Its `log` text was said while the plan fires in a circle: not again until it waits.
    pub said_in_loop: bool,
}

impl BoundAction {
    /// The expressions whose time counts from the action's start.
    pub fn exprs(&self) -> impl Iterator<Item = ExprId> {
        self.finished.into_iter().chain(self.failed)
    }
}

/// Everything the mission needs at run time, resolved once.
pub(crate) struct Bound {
    pub exprs: ExprSet,
    /// Every property an expression reads, with the version last fed to `exprs`.
    pub watched: Vec<(PropId, AnyHandle, Option<u64>)>,
    /// Looked up by name at every plan round: a fast hasher (names come from the plan file).
    pub conditions: foldhash::HashMap<String, ExprId>,
    /// Atoms with no expression: read from the mission's `in/conditions`.
    pub defaults: Vec<String>,
    pub actions: foldhash::HashMap<String, BoundAction>,
    /// Relinks that actions' calls asked for, in order, carried out after the plan step
    /// (linking is a blackboard request, which a plan step cannot wait for).
    pub relinks: Vec<Relink>,
    /// The top plan's conditions and actions by position, as bound here.
    pub at: Positions,
}

/// What a guard asks of the top plan, by position ([`crate::Environment::condition_at`]):
/// resolved once, so a plan round looks no name up.
#[derive(Default)]
pub(crate) struct Positions {
    /// Per condition of the plan: its expression, if bound to one here.
    pub conditions: Vec<Option<ExprId>>,
    /// Per executable of the plan: the action bound here, if any (sub-plans and other
    /// robots' actions have none).
    pub actions: Vec<Option<ActionExprs>>,
}

/// An action's `finished` and `failed` expressions.
#[derive(Clone, Copy)]
pub(crate) struct ActionExprs {
    pub finished: Option<ExprId>,
    pub failed: Option<ExprId>,
    /// No binding and `params/allow_unbound`: finished as soon as asked.
    pub unbound: bool,
}

impl Positions {
    /// The positions of `plan`'s names among `conditions` and `actions`.
    pub fn of(
        plan: &Plan,
        conditions: &foldhash::HashMap<String, ExprId>,
        actions: &foldhash::HashMap<String, BoundAction>,
    ) -> Positions {
        Positions {
            conditions: (plan.conditions().iter())
                .map(|c| conditions.get(c).copied())
                .collect(),
            actions: (plan.executables().iter())
                .map(|e| match e.subplan {
                    Some(_) => None,
                    None => actions.get(&e.name).map(|a| ActionExprs {
                        finished: a.finished,
                        failed: a.failed,
                        unbound: a.unbound,
                    }),
                })
                .collect(),
        }
    }
}

/// One relink an action call asked for: `input` to `source`, or unlinked.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Relink {
    pub input: String,
    pub source: Option<String>,
}
