//! Vision: victim detection in camera images and victim mapping, pure cores.
//!
//! The module shells are in [`crate::robot`] (`vision.victim_detector`,
//! `vision.victim_mapper`).

#![warn(missing_docs)]

pub mod detector;

pub use detector::{detect, Detection, DetectorOutput, DetectorParams};
