//! petrel runtime core: property types and URLs, the blackboard actor, links and queues,
//! the module trait and module actors, supervision, agent assembly and RON configuration.
//!
//! See `ARCHITECTURE.md` at the repository root for a map of the code.
//!
//! # Snapshots
//! [`Agent::snapshot`] writes the whole blackboard as a RON agent config; see the `snapshot`
//! module docs for what it holds.
#![warn(missing_docs)]

mod agent;
mod agent_thread;
mod blackboard;
mod cell;
pub mod config;
pub mod expr;
pub mod files;
mod fine_timer;
mod handle;
mod long_step_threads;
mod loop_watch;
mod module;
mod module_actor;
mod module_types;
mod panic_report;
mod park_spin;
mod ports;
mod property_kind;
mod queue;
mod range;
mod realtime;
pub mod run_queue;
mod settle;
mod snapshot;
pub mod stdout;
mod step_clock;
mod step_probe;
mod summary;
pub mod supervision;
mod supervisor;
pub mod team;
mod text_position;
mod thread_hold;
pub mod types;
pub mod url;
mod value;

pub use agent::{
    Agent, AgentExit, ModuleControl, PreparedAgent, StartError, DEFAULT_STOP_TIMEOUT, EXIT_DIED,
};
pub use blackboard::{
    parse_set_text, AgentListing, Blackboard, BlackboardError, GraphLink, GraphNode, ModuleGraph,
    ModuleListing, PropertyListing, Registry, WatchedTap,
};
pub use config::{AgentConfig, ConfigError, ConfigErrors, ConfigFile, ModuleConfig};
pub use handle::{
    AnyHandle, Input, Item, Output, Param, PropertyHandle, QueueReader, QueueWriter, Sample, State,
};
pub use module::{
    module_names_problem, AgentView, Cause, CheckProblem, Context, Module, Schedule, Unrecoverable,
    Watchable,
};
pub use module_actor::status;
pub use module_types::{ModuleRegistry, ModuleType};
pub use ports::{Ports, PropertyDecl, PropertyKind};
pub use queue::DEFAULT_CAPACITY;
pub use range::{short_number, Numeric, Range};
pub use step_probe::{StepProbe, StepSample};
pub use summary::{ModuleReport, RunSummary};
pub use supervision::SupervisorEvent;
pub use supervisor::EXIT_GAVE_UP;
pub use text_position::{line_column, LineIndex};
pub use types::{
    cell_to_world, world_to_cell, FilePath, Image, LaserScan, OccupancyGrid, Point2, Pose2,
    PropertyType, Twist2,
};
pub use url::PropertyUrl;
pub use value::{config_form, config_value_error, spaced_ron, AnyValue, TypeInfo};
