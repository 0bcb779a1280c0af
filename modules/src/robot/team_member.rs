//! `nav.team_member`: one robot of a team's shared search, as the coordinator sees it.
//!
//! Passive, as `sim.body` is for a world: it only declares what the coordinator knows of one
//! robot (its map, searched floor, pose and given-up targets, linked to the robot's agent) and what it tells
//! it (`out/target`, which the robot's explorer links to). The `nav.team_search` module that
//! names it in `params/members` reads and writes these ports, so each robot's share is one
//! `agent/module` with fixed paths, whatever the size of the team.

use petrel_actors::types::Path2;
use petrel_actors::{Context, Input, Module, OccupancyGrid, Output, Ports, Pose2, Schedule};

/// `params/members` of `nav.team_search`: its `nav.team_member` modules, one per robot.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
pub struct MemberNames(pub Vec<String>);

impl petrel_actors::PropertyType for MemberNames {
    const TYPE_NAME: &'static str = "nav.members";
}

/// `nav.team_member`: one robot of a `nav.team_search` (see the module docs).
pub struct TeamMember {
    _map: Input<OccupancyGrid>,
    _searched: Input<OccupancyGrid>,
    _pose: Input<Pose2>,
    _given_up: Input<Path2>,
    _searching: Input<bool>,
    _target: Output<Vec<f64>>,
}

impl Module for TeamMember {
    const TYPE: &'static str = "nav.team_member";
    const DESCRIPTION: &'static str =
        "One robot of a team's shared search (named in a nav.team_search's params/members): its map, searched floor, pose, given-up targets and whether it searches in, its frontier out.";

    fn declare(ports: &mut Ports) -> Self {
        TeamMember {
            _map: ports.input("in/map", OccupancyGrid::default(), "the robot's map, world frame (link it to the robot's mapper; periodic and lossy links are fine)"),
            _searched: ports.input("in/searched", OccupancyGrid::default(), "optional: the floor the robot's camera searched (its nav.searched's out/searched; periodic and lossy links are fine); with it, the team searches until every reachable cell was looked at, not only until the laser mapped it"),
            _pose: ports.input("in/pose", Pose2::default(), "the robot's estimated pose, world frame"),
            _given_up: ports.input("in/givenUp", Path2::default(), "targets the robot reached or could not reach (its explorer's out/givenUp): never assigned again"),
            _searching: ports.input("in/searching", true, "optional: whether the robot searches now (link it to the robot's explorer's `enabled`); a robot that does not is given no frontier, such as one whose process was restarted after its search action had failed"),
            _target: ports.output("out/target", Vec::new(), "the frontier this robot is to explore, `[x, y]`; empty = none for now"),
        }
    }

    /// Never steps: the team search reads and writes its ports.
    fn schedule(&self) -> Schedule {
        Schedule::new()
    }

    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        Ok(())
    }
}
