//! petrel runtime core: property types and URLs, the blackboard actor, links and queues,
//! the module trait and module actors, agent assembly and RON configuration.
//!
//! See `ARCHITECTURE.md` at the repository root for a map of the code.

pub mod types;

pub use types::{Image, LaserScan, OccupancyGrid, Point2, Pose2, PropertyType, Twist2};
