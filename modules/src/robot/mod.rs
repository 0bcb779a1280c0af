//! Robot modules: thin runtime wrappers around the pure [`crate::sim`] and [`crate::nav`] cores.
//!
//! Each module reads its input properties, calls one core, and publishes the result; the
//! modules never name each other and are wired only by config links:
//!
//! ```text
//! sim.world ──odometry──▶ nav.localizer ──estimatedPose──▶ nav.mapper ──map──┐
//!     ▲   └──laserScan──▶ nav.mapper, nav.obstacle_avoidance                 ▼
//!     │                  nav.goal_sequencer ──targetPose──▶ nav.path_planner
//!     └──controlSpeed── nav.obstacle_avoidance ◀──localTargetPose──┘
//! ```
//!
//! `sim.recorder` watches the run and writes the summary and a PNG at the end. A real robot's
//! driver replaces `sim.world` by publishing the same properties.

mod avoidance;
mod body;
mod explorer;
mod fault;
mod localizer;
mod mapper;
mod path_planner;
mod pose_trail;
mod recorder;
mod searched;
mod sequencer;
mod team_member;
mod team_search;
mod team_victims;
mod victim_detector;
mod victim_mapper;
mod world;
mod world_body;
mod world_tracks;

pub use avoidance::ObstacleAvoidance;
pub use body::SimBody;
pub use explorer::ExplorerModule;
pub use fault::SimFault;
pub use localizer::LocalizerModule;
pub use mapper::MapperModule;
pub use path_planner::PathPlanner;
pub use recorder::Recorder;
pub use searched::SearchedModule;
pub use sequencer::{GoalSequencerModule, MISSION_FAILED};
pub use team_member::{MemberNames, TeamMember};
pub use team_search::TeamSearch;
pub use team_victims::TeamVictimsModule;
pub use victim_detector::VictimDetector;
pub use victim_mapper::{MapperMemory, VictimMapper};
pub use world::SimWorld;
pub use world_body::BodyNames;

use petrel_actors::ModuleRegistry;

use crate::sim::ParamError;

/// Registers every robot module type.
pub fn register(registry: &mut ModuleRegistry) {
    registry
        .register::<SimWorld>()
        .register::<SimBody>()
        .register::<SimFault>()
        .register::<LocalizerModule>()
        .register::<MapperModule>()
        .register::<PathPlanner>()
        .register::<ObstacleAvoidance>()
        .register::<GoalSequencerModule>()
        .register::<ExplorerModule>()
        .register::<SearchedModule>()
        .register::<VictimDetector>()
        .register::<VictimMapper>()
        .register::<TeamVictimsModule>()
        .register::<TeamMember>()
        .register::<TeamSearch>()
        .register::<Recorder>();
}

/// A core parameter error, renamed to the property a user sets: `renames` maps core names to
/// property paths under `params/` where they differ.
fn param_error(e: ParamError, renames: &[(&str, &str)]) -> anyhow::Error {
    let name = renames
        .iter()
        .find(|(core, _)| *core == e.param)
        .map_or(e.param.as_str(), |(_, prop)| prop);
    anyhow::anyhow!("invalid parameter `params/{name}`: {}", e.message)
}

/// Checks module parameters `(name, value)` with a core check ([`positive`](crate::sim::error::positive),
/// [`non_negative`](crate::sim::error::non_negative)); the first failure names its property.
fn check_params(
    check: fn(&str, f64) -> Result<(), ParamError>,
    params: &[(&str, f64)],
) -> anyhow::Result<()> {
    for &(name, value) in params {
        check(name, value).map_err(|e| param_error(e, &[]))?;
    }
    Ok(())
}

/// What a module built in `init` (its core, its state): a module steps only after an `init`
/// that succeeded.
fn initialized<T>(built: &mut Option<T>) -> &mut T {
    built
        .as_mut()
        .expect("stepping only after a successful init")
}

/// The cells (columns, rows) of a grid of extent `size` (m) at `res` m a cell: at least one
/// each way, at most [`crate::sim::Grid::MAX_CELLS`] in all; an error naming both parameters.
fn grid_cells(res: f64, size: petrel_actors::Point2) -> anyhow::Result<(u32, u32)> {
    let cells = |m: f64| (m / res).ceil();
    let (w, h) = (cells(size.0.x), cells(size.0.y));
    if !(res > 0.0 && w >= 1.0 && h >= 1.0 && w * h <= crate::sim::Grid::MAX_CELLS as f64) {
        let n = petrel_actors::short_number;
        anyhow::bail!(
            "invalid parameters `params/size` and `params/resolution`: expected a positive extent of at most {} cells, got {} x {} m at {} m per cell",
            crate::sim::Grid::MAX_CELLS, n(size.0.x), n(size.0.y), n(res)
        );
    }
    Ok((w as u32, h as u32))
}

/// `check`'s answer for a module whose `init` builds a core from its parameters: nothing, or
/// why the core cannot be built.
fn check_built<T>(built: anyhow::Result<T>) -> Vec<petrel_actors::CheckProblem> {
    built.err().iter().map(check_problem).collect()
}

/// An init error as a problem `petrel check` reports, at the first `params/...` it names.
fn check_problem(e: &anyhow::Error) -> petrel_actors::CheckProblem {
    let message = e.to_string();
    let path = message
        .split('`')
        .find(|part| part.starts_with("params/"))
        .unwrap_or("params")
        .to_string();
    petrel_actors::CheckProblem::new(&path, message)
}

/// Makes the folder of `params/png` (a picture written when the run stops), in `init`: so
/// that a run does not go its whole length to find it cannot write it. A folder that cannot
/// be made will not be made by a restart either.
fn png_folder(png: &str) -> Result<(), petrel_actors::Unrecoverable> {
    let Some(dir) = std::path::Path::new(png)
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
    else {
        return Ok(());
    };
    std::fs::create_dir_all(dir).map_err(|e| {
        petrel_actors::Unrecoverable(format!(
            "params/png is `{png}`, but its folder {} cannot be created: {e}",
            dir.display()
        ))
    })
}

/// An `i64` parameter as a count, or an error naming it when it is negative.
fn count(name: &str, value: i64) -> anyhow::Result<usize> {
    usize::try_from(value).map_err(|_| {
        anyhow::anyhow!("invalid parameter `params/{name}`: expected a count >= 0, got {value}")
    })
}

#[cfg(test)]
mod body_tests;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_mapper;
#[cfg(test)]
mod tests_vision;
