use super::*;
use crate::sim::camera::{render, CameraConfig, CameraMotion};
use crate::sim::features::Rect;
use crate::sim::{Grid, WorldFeatures};
use petrel_actors::{Point2, Pose2, Twist2};
use rand::SeedableRng;

/// A 10 m x 5 m hall; the robot at (1, 2.5) facing +x; victims where asked.
fn image(
    victims: &[(f64, f64)],
    dark: bool,
    motion: CameraMotion,
    cfg: &CameraConfig,
    seed: u64,
) -> Vec<u8> {
    let mut grid = Grid::new(100, 50, 0.1, 0.0, 0.0).unwrap();
    for c in 0..100 {
        grid.set(c, 0, true);
        grid.set(c, 49, true);
    }
    for r in 0..50 {
        grid.set(0, r, true);
        grid.set(99, r, true);
    }
    let features = WorldFeatures {
        victims: victims.iter().map(|&(x, y)| Point2::new(x, y)).collect(),
        dark: if dark {
            vec![Rect::from_corners([0.0, 0.0, 10.0, 5.0]).unwrap()]
        } else {
            Vec::new()
        },
        ..WorldFeatures::default()
    };
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    render(
        &grid,
        &features,
        Pose2::new(1.0, 2.5, 0.0),
        motion,
        cfg,
        &mut rng,
    )
}

/// The shipped rescue world (configs/rescue/rescue.txt).
pub(super) fn rescue_world() -> crate::sim::WorldMap {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../configs/rescue/rescue.txt");
    crate::sim::load_world(std::path::Path::new(path)).unwrap()
}

/// A frame of `w` from `pose`, the camera still.
pub(super) fn still_frame(
    w: &crate::sim::WorldMap,
    pose: Pose2,
    cfg: &CameraConfig,
    rng: &mut rand::rngs::StdRng,
) -> Vec<u8> {
    render(
        &w.grid,
        &w.features,
        pose,
        CameraMotion::default(),
        cfg,
        rng,
    )
}

pub(super) fn run(img: &[u8], p: &DetectorParams) -> DetectorOutput {
    detect(img, 160, 120, p).unwrap()
}

#[test]
fn a_victim_ahead_and_one_to_the_left_are_found_with_bearing_and_range() {
    let cfg = CameraConfig::default();
    let p = DetectorParams::default();
    let out = run(
        &image(
            &[(3.0, 2.5), (4.0, 3.6)],
            false,
            CameraMotion::default(),
            &cfg,
            1,
        ),
        &p,
    );
    assert_eq!(out.detections.len(), 2, "{out:?}");
    let mut d = out.detections.clone();
    d.sort_by(|a, b| a.bearing.total_cmp(&b.bearing));
    let ahead = d[0];
    assert!(
        ahead.bearing.abs() < 0.05 && (ahead.range - 2.0).abs() < 0.3,
        "{ahead:?}"
    );
    let left = d[1];
    let (bearing, range) = ((1.1f64).atan2(3.0), (1.1f64).hypot(3.0));
    assert!(
        (left.bearing - bearing).abs() < 0.05 && (left.range - range).abs() < 0.5,
        "{left:?} vs {bearing} {range}"
    );
    assert!(out.brightness > 0.2 && ahead.confidence > 0.2);
    // An empty hall gives nothing.
    assert!(
        run(&image(&[], false, CameraMotion::default(), &cfg, 1), &p)
            .detections
            .is_empty()
    );
}

#[test]
fn too_dark_images_miss_victims_until_exposure_and_gain_rise() {
    let p = DetectorParams::default();
    let victim = [(3.0, 2.5)];
    let plain = CameraConfig::default();
    let dark = run(
        &image(&victim, true, CameraMotion::default(), &plain, 2),
        &p,
    );
    assert!(
        dark.detections.is_empty() && dark.brightness < 0.05,
        "{dark:?}"
    );
    let adapted = CameraConfig {
        exposure_ms: 40.0,
        gain: 4.0,
        ..plain
    };
    let seen = run(
        &image(&victim, true, CameraMotion::default(), &adapted, 2),
        &p,
    );
    assert_eq!(seen.detections.len(), 1, "{seen:?}");
    // No false victims out of amplified noise, sharpened or not.
    let sharpening = DetectorParams {
        deblur: 1.0,
        ..p.clone()
    };
    for seed in 0..20 {
        let img = image(&[], true, CameraMotion::default(), &adapted, seed);
        let empty = run(&img, &p);
        assert!(empty.detections.is_empty(), "seed {seed}: {empty:?}");
        let sharpened = run(&img, &sharpening);
        assert!(
            sharpened.detections.is_empty(),
            "seed {seed}, deblur: {sharpened:?}"
        );
    }
}

#[test]
fn blurred_images_miss_victims_and_lose_sharpness_deblur_costs_and_helps_a_little() {
    let p = DetectorParams::default();
    let victim = [(3.0, 2.5)];
    let cfg = CameraConfig {
        exposure_ms: 30.0,
        ..CameraConfig::default()
    };
    let still = run(&image(&victim, false, CameraMotion::default(), &cfg, 3), &p);
    let turn = CameraMotion {
        speed: Twist2::new(0.3, 1.5),
        rough: false,
    };
    let blurred = run(&image(&victim, false, turn, &cfg, 3), &p);
    assert_eq!(still.detections.len(), 1, "{still:?}");
    assert!(blurred.detections.is_empty(), "{blurred:?}");
    assert!(
        blurred.sharpness < 0.85 * still.sharpness,
        "{} vs {}",
        blurred.sharpness,
        still.sharpness
    );
    let sharpened = run(
        &image(&victim, false, turn, &cfg, 3),
        &DetectorParams {
            deblur: 2.0,
            ..p.clone()
        },
    );
    assert!(sharpened.sharpness > blurred.sharpness);
    assert!(detect(&[0; 10], 160, 120, &p).is_none());
    assert!(DetectorParams {
        roi: [0.5, 0.0, 0.2, 1.0],
        ..p
    }
    .validate()
    .unwrap_err()
    .contains("params/roi"));
}

#[test]
fn no_false_victims_in_the_dark_room_of_the_rescue_world() {
    // Looking around the dark storeroom with exposure and gain raised: walls lit through the
    // door saturate beside dark, amplified, noisy ones. Noise is not a victim.
    let w = rescue_world();
    let cfg = CameraConfig {
        exposure_ms: 30.0,
        gain: 4.0,
        ..CameraConfig::default()
    };
    let mut rng = rand::rngs::StdRng::seed_from_u64(1);
    let (mut false_victims, mut frames) = (0, 0);
    for deblur in [0.0, 1.0] {
        let p = DetectorParams {
            deblur,
            ..DetectorParams::default()
        };
        for k in 0..96 {
            let (xi, yi, hi) = (k % 3, (k / 3) % 4, k / 12);
            let pose = Pose2::new(
                12.2 + xi as f64 * 1.2,
                6.8 + yi as f64 * 1.2,
                hi as f64 * 0.785,
            );
            if w.grid.disc_collides(pose.x(), pose.y(), 0.25) {
                continue;
            }
            let img = still_frame(&w, pose, &cfg, &mut rng);
            frames += 1;
            for d in run(&img, &p).detections {
                let a = pose.theta() + d.bearing;
                let (x, y) = (pose.x() + d.range * a.cos(), pose.y() + d.range * a.sin());
                if !w
                    .features
                    .victims
                    .iter()
                    .any(|v| (v.0.x - x).hypot(v.0.y - y) < 1.0)
                {
                    false_victims += 1;
                }
            }
        }
    }
    assert!(frames > 100);
    assert_eq!(false_victims, 0, "in {frames} frames");
}

#[test]
fn another_robot_in_view_is_not_a_victim() {
    let cfg = CameraConfig::default();
    let mut grid = Grid::new(100, 50, 0.1, 0.0, 0.0).unwrap();
    for c in 0..100 {
        grid.set(c, 0, true);
        grid.set(c, 49, true);
    }
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    let img = crate::sim::camera::render_among(
        &grid,
        &WorldFeatures::default(),
        &[(2.5, 2.5, 0.2)],
        Pose2::new(1.0, 2.5, 0.0),
        CameraMotion::default(),
        &cfg,
        &mut rng,
    );
    assert!(run(&img, &DetectorParams::default()).detections.is_empty());
}

/// Near a victim its squares are many rows high, so the band from the horizon down is
/// textured only every so many rows: the foot is still found at the bottom, not at the first
/// gap (a rescue mission confirms a victim as it approaches it; following the band with gaps
/// judged by the depth reached alone, it dismissed one).
/// Near victims, lit and in the dark with the dark context's exposure and gain: there the
/// shot noise of the bright squares is amplified, and a near victim's tall squares leave few
/// edges, so against a noise floor taken from its own columns it went unseen from closer than
/// about 1.8 m (a warehouse run's victim in the dark office, passed at 1.3 m, was never found).
#[test]
fn a_near_victim_is_found_at_its_range() {
    let lit = CameraConfig::default();
    let dark = CameraConfig {
        exposure_ms: 30.0,
        gain: 4.0,
        ..CameraConfig::default()
    };
    for (cfg, in_dark) in [(lit, false), (dark, true)] {
        for deblur in [0.0, 1.0] {
            let p = DetectorParams {
                deblur,
                ..DetectorParams::default()
            };
            for distance in [1.25, 1.4, 1.5, 1.75] {
                let img = image(
                    &[(1.0 + distance, 2.5)],
                    in_dark,
                    CameraMotion::default(),
                    &cfg,
                    3,
                );
                let out = run(&img, &p);
                assert!(
                    out.detections.len() == 1 && (out.detections[0].range - distance).abs() < 0.25,
                    "dark {in_dark}, deblur {deblur}, victim {distance} m ahead: {:?}",
                    out.detections
                );
            }
        }
    }
}

/// The foot is where the victim's textured band ends, not the lowest row that happens to be
/// textured: sharpened noise on the floor in front of a far victim was taken for its foot in
/// about one frame in ten from this doorway of the rescue world, placing the victim at
/// (8.3, 10.5) three metres short (two such frames made a seventh, false victim in a rescue
/// team's run). Every sighting placed from these poses must land on a victim.
#[test]
fn a_far_victim_is_not_placed_short_by_a_noisy_row_of_floor() {
    let w = rescue_world();
    let cfg = CameraConfig::default();
    let p = DetectorParams {
        deblur: 1.0,
        ..DetectorParams::default()
    };
    let (mut sightings, mut off) = (0, Vec::new());
    for (x, y, heading) in [
        (10.48, 5.5, 128.0f64),
        (10.46, 5.53, 125.0),
        (10.5, 5.45, 131.0),
    ] {
        let pose = Pose2::new(x, y, heading.to_radians());
        for seed in 0..40 {
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
            let img = still_frame(&w, pose, &cfg, &mut rng);
            for d in run(&img, &p).detections {
                sightings += 1;
                let a = pose.theta() + d.bearing;
                let at = (x + d.range * a.cos(), y + d.range * a.sin());
                let nearest = w
                    .features
                    .victims
                    .iter()
                    .map(|v| (v.0.x - at.0).hypot(v.0.y - at.1))
                    .fold(f64::INFINITY, f64::min);
                if nearest > 1.5 {
                    off.push((heading, seed, d.range, at));
                }
            }
        }
    }
    assert!(sightings > 80, "most frames see the victim: {sightings}");
    assert!(
        off.is_empty(),
        "placed away from every victim (heading, seed, range, at): {off:?}"
    );
}
