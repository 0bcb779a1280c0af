//! Petri Net Plans for petrel: the pure library.
//!
//! * [`Plan`]: the immutable net model, read from PNML ([`parse_pnml`],
//!   [`load_plan`]) or compiled from the PNPgen-style text language
//!   ([`compile_text`]), written back with [`write_pnml`].
//! * [`PlanState`] + [`step`]: the exact PNP step semantics, against an
//!   [`Environment`] that answers conditions and runs actions.
//! * [`check`]: static analysis; [`to_dot`]: Graphviz; [`simulate`]: a
//!   deterministic scripted simulator.
//!
//! No actors and no I/O besides reading the files asked for, except in [`mission`]: the
//! `mission.pnp` module running a plan inside an agent ([`mission::register`]).
//!
//! # For the `petrel plan` CLI
//! * load: [`load_plan`]`(path, rules)` (`.pnml`, or a text plan with any
//!   other extension; sub-plans resolved next to the file);
//! * check: [`check`]`(&loaded.plan)`, print the [`CheckReport`], exit
//!   non-zero when [`CheckReport::is_ok`] is false;
//! * dot: [`to_dot`]; compile: [`compile_to_pnml`]`(path, rules)`;
//! * simulate: [`Script::parse`] then [`simulate`]`(&plan, &script, max_steps, &mut stdout)`.
//!
//! # For the mission module
//! Keep an `Arc<Plan>` and a [`PlanState`]; implement [`Environment`] over
//! the blackboard and call [`step`] once per tick; stop when
//! [`PlanState::status`] is not [`PlanStatus::Running`].
//!
//! # Choices where the reference semantics is silent
//! * The environment only sees actions; sub-plans are run inside [`step`].
//!   [`StepReport::calls`] lists every call, sub-plans' own (`child.start`)
//!   and their actions' included. `resume` passes on to a sub-plan's running
//!   executables like `interrupt` does.
//! * Executables are stepped once per step each, in order of first mention
//!   in the plan.
//! * A transition with several `end`/`fail` calls and no guard waits for
//!   all of them (conjunction of the default guards).
//! * Parallel arcs between the same place and transition add their weights.
//! * Place label words other than execution / goal / fail words are
//!   ignored; a malformed `goal(x)` and two different executables in one
//!   place label are errors. A guard glued to a call (`A.end[x]`) is accepted.
//! * `check`: a missing goal place, no initial token and a transition
//!   without inputs are errors; dead transitions, dead-end places, places
//!   that may hold several tokens, deadlocks, livelocks (markings from which
//!   neither goal nor fail can be reached) and an unreachable goal marking
//!   are warnings.
//! * Execution rules only apply to text plans (an error with a `.pnml`).
//! * An action that failed where no transition asks about its failure fails the
//!   plan ([`StepReport::unhandled_failure`]); `check` leaves such failures out
//!   of its exploration (any action may fail, which would hide livelocks).
//! * Timed actions `A|N` join when both the action and its timer end in the
//!   same step, so they cannot deadlock; `{ ... } * N` writes a block N times.
#![warn(missing_docs)]

mod analysis;
mod build;
mod condition;
mod dot;
mod error;
mod exec;
mod hot;
mod label;
mod load;
pub mod mission;
mod model;
mod pnml;
pub mod remote;
mod simulate;
mod text;

pub use analysis::{check, check_with, CheckOptions, CheckReport, Finding, DEFAULT_MAX_STATES};
pub use condition::{parse_condition, Cond, CondError};
pub use dot::to_dot;
pub use error::{PlanError, MAX_DEPTH};
pub use exec::{
    step, step_with, CallRecord, Environment, PlanState, PlanStatus, StepReport, MAX_PLACE_TOKENS,
};
pub use label::{split_label, CallKind};
pub use load::{compile_to_pnml, load_plan, LoadedPlan};
pub use mission::register;
pub use model::{
    Atom, Call, Comment, Condition, Edge, Executable, Place, Plan, Position, Transition,
};
pub use pnml::{parse_pnml, write_pnml};
pub use simulate::{simulate, Script, ScriptedEnv, DEFAULT_MAX_STEPS};
pub use text::compile_text;
