//! Vision: victim detection in camera images and victim mapping, pure cores.
//!
//! The module shells are in [`crate::robot`] (`vision.victim_detector`,
//! `vision.victim_mapper`).

#![warn(missing_docs)]

pub mod detector;
pub mod team_victims;
pub mod victim_map;

pub use detector::{detect, Detection, Detections, DetectorOutput, DetectorParams};
pub use team_victims::{Report, TeamVictim, TeamVictims};
pub use victim_map::{sighting_weight, VictimMap, VictimMapParams};
