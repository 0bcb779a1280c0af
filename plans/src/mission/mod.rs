//! `mission.pnp`: runs one Petri Net Plan inside an agent, its actions bound to modules and
//! its conditions to properties.
//!
//! ```ron
//! (name: "mission", type: "mission.pnp", values: {
//!     // Paths are relative to the config file; `.pnml`, or a text plan with optional rules.
//!     "params/plan": "plans/demo.plan",
//!     "params/rules": "plans/demo.er",
//!     "params/is_mission": true,            // goal ends the run with 0, fail with 1
//!     "params/actions": {
//!         // `count` and every `count_P1_P2...` action ($1, $2... = P1, P2...).
//!         "count": (
//!             enable: ["counter"],              // enabled while the action runs
//!             set: {"counter/state/count": 0},  // written at start, restored at the end
//!             link: {"counter/in/tick": "clock/out/tick"},  // relinked at start, restored at the end
//!             restore: true,                    // (default)
//!             finished: "counter/out/value >= $1",  // boolean expressions
//!             failed: "counter/stats/failures > 0",
//!         ),
//!     },
//!     // Condition atom -> boolean expression. Atoms not listed read `in/conditions`
//!     // (a map atom -> bool, false when absent; set it with tools or tests).
//!     "params/conditions": {"overload": "held(scale/out/value > 60, 100ms)"},
//!     // Values parameters may name: `goto_kitchen` sets "$1" to this, `$1.x` is its x.
//!     "params/places": {"kitchen": (x: 2.0, y: 1.0, theta: 0.0)},
//! }, links: {"in/clock": "robot/out/simTime"})   // mission time = simulated time
//! ```
//!
//! `wait_N` and `log_...`/`say_...` are built-in actions (a binding of the same name wins). An
//! action failure that no transition handles fails the plan, logged with the action and its
//! `failed` expression. Time in an action's `finished`/`failed` counts from its start
//! (`elapsed()`, `held` windows, `age`). The marking, the running actions (start times, what
//! `set` replaced, `held` windows) and each action's record live in `state/memory`: a
//! restarted module or a resumed snapshot goes on from there. The user guide is
//! `docs/missions.md`.
//!
//! Bindings are resolved and type-checked once, at init: an unknown module or property, a
//! value of the wrong type, an expression error (with line and column) or a plan action with
//! no binding stops the module with every problem listed (`params/allow_unbound: true` lets
//! unbound actions finish at once instead). `petrel check` (and `petrel run`, before starting
//! anything) makes the same check with [`check_mission`] and reports each problem at its place
//! in the config. Changing bindings or the plan later has no effect.
//!
//! Event-driven: the module steps the plan when a property read by a binding changes, when
//! `in/conditions` changes, or a `held`/`age` deadline passes; within one module step, plan
//! steps repeat while transitions fire (transitions enabled by a firing need the next plan
//! step). When the rounds have started or ended actions and nothing more fires, the step lets
//! the modules they switched on run once ([`Context::settle`](petrel_actors::Context::settle))
//! and, if one answered at once, goes on firing in the same step: a quick action costs one
//! mission step, not two (its marking while it ran is then not published in `out/marking`;
//! `out/firings` still lists every transition in order); `params/tick_ms` adds a periodic step (0 = none), needed only for conditions that
//! time alone changes and no deadline covers (`age(p) > 2` has one, `age(p) * 2 > 4` not). Conditions are levels: an action's `finished` must be
//! false when it starts (reset what it reads with `set`). A module enabled by two actions running
//! in parallel is disabled when the first of them ends.

mod bind;
mod bound;
pub(crate) mod builtin;
mod config;
mod env;
mod hints;
mod loops;
mod memory;
mod module;
mod prepare;
mod run;
mod serve;
mod shown;
mod team;
mod timer;

pub use bind::BindingProblem;
pub use config::{
    config_form, match_action, ActionBinding, ActionBindings, ActionName, ConditionBindings, Flags,
    Places,
};
pub use memory::{ActionStats, MissionMemory, PlanFiring, RunningAction};
pub use module::Mission;
pub use prepare::check_mission;

use petrel_actors::ModuleRegistry;

/// Registers `mission.pnp`.
pub fn register(registry: &mut ModuleRegistry) {
    registry.register::<Mission>();
}
