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
//! No actors and no I/O besides reading the files asked for.
#![warn(missing_docs)]

mod analysis;
mod condition;
mod dot;
mod error;
mod exec;
mod label;
mod load;
mod model;
mod pnml;
mod simulate;
mod text;

pub use analysis::{check, CheckReport, Finding};
pub use condition::{parse_condition, Cond, CondError};
pub use dot::to_dot;
pub use error::PlanError;
pub use exec::{step, CallRecord, Environment, PlanState, PlanStatus, StepReport};
pub use label::{split_label, CallKind};
pub use load::{compile_to_pnml, load_plan, LoadedPlan};
pub use model::{
    Atom, Call, Comment, Condition, Edge, Executable, Place, Plan, Position, Transition,
};
pub use pnml::{parse_pnml, write_pnml};
pub use simulate::{simulate, Script, ScriptedEnv};
pub use text::compile_text;
