//! Navigation algorithms: localization, mapping, planning, obstacle avoidance, goal sequencing.
//!
//! Each is a plain struct with a `step`-style method from inputs to outputs, using the
//! built-in property types, so a module actor only has to read, call and publish.

#![warn(missing_docs)]

pub mod allocate;
pub mod astar;
pub mod avoidance;
pub mod costmap;
pub mod frontier;
pub mod headless;
pub mod localizer;
pub mod mapper;
pub mod planner;
pub mod pose_history;
pub mod publish_gate;
pub mod scan_matcher;
pub mod searched;
pub mod sequencer;
pub mod stall;
pub mod team_log;
pub mod team_map;
#[cfg(test)]
mod text_map;

pub use allocate::{Allocator, Change};
pub use avoidance::{Avoidance, AvoidanceParams};
pub use costmap::CostParams;
pub use frontier::{explore, explore_searched, known_area, Exploration, Frontier, FrontierParams};
pub use headless::{run_mission, MissionParams, MissionSummary};
pub use localizer::{Localizer, LocalizerOutput, LocalizerParams};
pub use mapper::{Mapper, MapperParams};
pub use planner::{Planner, PlannerOutput, PlannerParams};
pub use pose_history::PoseHistory;
pub use publish_gate::PublishGate;
pub use scan_matcher::{ScanLocalizer, ScanMatcher, ScanMatcherParams, ScanOutcome};
pub use searched::{heading_change, SearchParams, SearchedMap};
pub use sequencer::{GoalSequencer, SequencerOutput};
pub use stall::StallWatch;
pub use team_log::{Reassignment, TeamLog};
pub use team_map::{merge_maps, merge_searched};
