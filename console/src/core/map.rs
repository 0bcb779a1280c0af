//! The map view of a robot: which properties feed it (found by type and path, so any agent
//! wired like `configs/navigate.ron` gets one), and compact JSON for grids and images.

use base64::Engine as _;
use petrel_actors::{AgentListing, Image, OccupancyGrid, Pose2};
use serde::Serialize;
use serde_json::{json, Value};

/// The properties a map view reads (`module/path`), each when the agent has one.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct MapSources {
    /// The occupancy grid being built (an `OccupancyGrid` output).
    pub grid: Option<String>,
    /// The robot's estimated pose (`out/estimatedPose`, else another `Pose2` output).
    pub pose: Option<String>,
    /// The simulator's true pose (`out/pose` beside the laser).
    pub true_pose: Option<String>,
    /// The planned path (`Path2` at `out/path`).
    pub path: Option<String>,
    /// Confirmed victims (`Path2` at `out/victims`).
    pub victims: Option<String>,
    /// Goals (`Path2` at `params/goals`, not linked).
    pub goals: Option<String>,
    /// Laser scans (a `LaserScan` queue output).
    pub laser: Option<String>,
    /// Camera frames (an `Image` queue output).
    pub camera: Option<String>,
}

impl MapSources {
    /// Whether the agent has anything to draw on a map.
    pub fn any(&self) -> bool {
        self.grid.is_some() || self.pose.is_some() || self.true_pose.is_some()
    }
}

/// Finds the map view's properties among `listing`'s.
pub fn pick(listing: &AgentListing) -> MapSources {
    let find = |kind: &str, type_name: &str, suffix: &str| {
        listing
            .properties
            .iter()
            .find(|p| {
                p.kind == kind
                    && p.type_name == type_name
                    && p.key.ends_with(suffix)
                    && p.link.is_none()
            })
            .map(|p| p.key.clone())
    };
    let laser = find("queue output", "LaserScan", "");
    let true_pose = laser
        .as_deref()
        .and_then(|l| l.split('/').next())
        .map(|module| format!("{module}/out/pose"))
        .filter(|k| {
            listing
                .properties
                .iter()
                .any(|p| &p.key == k && p.type_name == "Pose2")
        });
    MapSources {
        grid: find("output", "OccupancyGrid", ""),
        pose: find("output", "Pose2", "/out/estimatedPose").or_else(|| true_pose.clone()),
        true_pose,
        path: find("output", "Path2", "/out/path"),
        victims: find("output", "Path2", "/out/victims"),
        goals: find("param", "Path2", "/params/goals"),
        laser,
        camera: find("queue output", "Image", ""),
    }
}

fn b64(bytes: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// A grid as `{width, height, resolution, origin, cells}`, cells base64 bytes row by row
/// from the origin (-1 unknown as 255, else 0..100 occupied).
pub fn grid_json(grid: &OccupancyGrid) -> Value {
    let cells: Vec<u8> = grid.data.iter().map(|&c| c as u8).collect();
    json!({
        "width": grid.width,
        "height": grid.height,
        "resolution": grid.resolution,
        "origin": pose_json(&grid.origin),
        "cells": b64(&cells),
    })
}

/// An image as `{width, height, encoding, data}`, data base64.
pub fn image_json(image: &Image) -> Value {
    json!({
        "width": image.width,
        "height": image.height,
        "encoding": image.encoding,
        "data": b64(&image.data),
    })
}

/// A pose as `{x, y, theta}`.
pub fn pose_json(pose: &Pose2) -> Value {
    json!({"x": pose.x(), "y": pose.y(), "theta": pose.theta()})
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use petrel_actors::PropertyListing;

    fn prop(key: &str, kind: &str, type_name: &str, link: Option<&str>) -> PropertyListing {
        PropertyListing {
            key: key.into(),
            kind: kind.into(),
            type_name: type_name.into(),
            link: link.map(str::to_string),
        }
    }

    #[test]
    fn a_navigation_agent_s_map_sources_are_found_by_type_and_path() {
        let listing = AgentListing {
            modules: vec![],
            properties: vec![
                prop("goals/params/goals", "param", "Path2", None),
                prop("localizer/out/estimatedPose", "output", "Pose2", None),
                prop("mapper/out/map", "output", "OccupancyGrid", None),
                prop("pathPlanner/out/path", "output", "Path2", None),
                prop(
                    "recorder/params/goals",
                    "param",
                    "Path2",
                    Some("goals/params/goals"),
                ),
                prop("robot/out/image", "queue output", "Image", None),
                prop("robot/out/laserScan", "queue output", "LaserScan", None),
                prop("robot/out/pose", "output", "Pose2", None),
            ],
        };
        let s = pick(&listing);
        assert_eq!(s.grid.as_deref(), Some("mapper/out/map"));
        assert_eq!(s.pose.as_deref(), Some("localizer/out/estimatedPose"));
        assert_eq!(s.true_pose.as_deref(), Some("robot/out/pose"));
        assert_eq!(s.goals.as_deref(), Some("goals/params/goals"));
        assert_eq!(s.laser.as_deref(), Some("robot/out/laserScan"));
        assert_eq!(s.camera.as_deref(), Some("robot/out/image"));
        assert_eq!(s.victims, None);
        assert!(s.any());
        assert!(!pick(&AgentListing {
            modules: vec![],
            properties: vec![]
        })
        .any());
    }

    #[test]
    fn grid_cells_travel_as_bytes_with_unknown_as_255() {
        let grid = OccupancyGrid {
            width: 2,
            height: 1,
            resolution: 0.5,
            origin: Pose2::new(1.0, 2.0, 0.0),
            data: Arc::from(vec![-1i8, 100]),
        };
        let j = grid_json(&grid);
        assert_eq!(j["cells"], "/2Q=");
        assert_eq!(j["origin"]["x"], 1.0);
    }
}
