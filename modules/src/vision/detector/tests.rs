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
fn rescue_world() -> crate::sim::WorldMap {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../configs/rescue/rescue.txt");
    crate::sim::load_world(std::path::Path::new(path)).unwrap()
}

/// A frame of `w` from `pose`, the camera still.
fn still_frame(
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

fn run(img: &[u8], p: &DetectorParams) -> DetectorOutput {
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

/// Another robot at the edge of the rescue world's dark storeroom, seen from inside with the
/// dark context's exposure and gain: frames found by a search over 3,000 random poses, where
/// the detector reported the robot as a weak victim (confidence 0.12 to 0.18). In the rescue
/// team such frames, seen again and again while two robots stood still, made a false victim
/// where a robot stood. Real victims are reported with confidence 0.9 or more in 99 % of the
/// sightings of a team's runs, so a victim mapper ignores sightings below 0.7 by default;
/// one near a dark-room victim still passes it.
#[test]
fn a_robot_in_the_dark_is_at_most_a_weak_sighting_that_the_victim_mapper_ignores() {
    let w = rescue_world();
    let dark = CameraConfig {
        exposure_ms: 30.0,
        gain: 4.0,
        ..CameraConfig::default()
    };
    let min = crate::vision::VictimMapParams::default().min_confidence;
    for (seed, me, other) in [
        (393, Pose2::new(14.060, 8.991, -3.100), (11.923, 8.919)),
        (1095, Pose2::new(13.651, 9.337, -3.102), (11.599, 8.805)),
        (1821, Pose2::new(12.651, 7.133, 1.626), (12.034, 8.782)),
        (2623, Pose2::new(13.929, 10.067, -2.872), (12.139, 9.793)),
    ] {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let img = crate::sim::camera::render_among(
            &w.grid,
            &w.features,
            &[(other.0, other.1, 0.2)],
            me,
            CameraMotion::default(),
            &dark,
            &mut rng,
        );
        let out = run(&img, &DetectorParams::default());
        assert!(
            out.detections.iter().all(|d| d.confidence < min),
            "seed {seed}: {:?}",
            out.detections
        );
    }
    // The storeroom's victim (13.7, 8.1), 2.5 m ahead, is seen well above it.
    let me = Pose2::new(13.7, 10.6, -std::f64::consts::FRAC_PI_2);
    let confident = (0..10)
        .filter(|&seed| {
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
            let img = still_frame(&w, me, &dark, &mut rng);
            run(&img, &DetectorParams::default())
                .detections
                .iter()
                .any(|d| d.confidence >= min && (d.range - 2.5).abs() < 0.5)
        })
        .count();
    assert!(confident >= 9, "{confident} of 10 frames");
}

/// The searched map counts a cell only where the detector sees a victim standing there: lit
/// frames of the rescue world's victims from 1 to 3.5 m, at bearings near the edge of what the
/// map counts (10° to 27° off the heading, where a fixed 50° view had counted floor on which
/// a victim 1.0 to 1.5 m away was seen in 2 of 343 frames). Measured with this model over 6,000
/// frames: 90 % or more seen in each band of distance and bearing it counts.
#[test]
fn the_searched_map_counts_only_floor_where_a_victim_would_be_seen() {
    use crate::nav::{SearchParams, SearchedMap};
    use rand::{Rng, SeedableRng};
    let w = rescue_world();
    let cfg = CameraConfig::default();
    let min = crate::vision::VictimMapParams::default().min_confidence;
    // An open 16 m x 12 m map of 0.1 m cells: the line of sight is checked on the world here.
    let open = petrel_actors::OccupancyGrid {
        width: 160,
        height: 120,
        resolution: 0.1,
        origin: Pose2::default(),
        data: vec![0i8; 160 * 120].into(),
    };
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let (mut counted, mut seen, mut tried) = (0, 0, 0);
    while counted < 150 && tried < 5_000 {
        tried += 1;
        let v = w.features.victims[rng.random_range(0..w.features.victims.len())];
        let d: f64 = rng.random_range(1.0..3.5);
        let b = rng.random_range(10f64..27.0).to_radians()
            * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let a: f64 = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        let (x, y) = (v.0.x - d * a.cos(), v.0.y - d * a.sin());
        let solid = |x: f64, y: f64| {
            w.grid
                .is_solid((x / 0.2).floor() as i64, (y / 0.2).floor() as i64)
        };
        let dark = w.features.dark.iter().any(|r| r.contains(x, y));
        // In the world, on lit floor, with nothing between the camera and the victim.
        if !(0.3..15.7).contains(&x)
            || !(0.3..11.7).contains(&y)
            || dark
            || solid(x, y)
            || (1..40).any(|k| {
                let t = k as f64 / 40.0 * (d - 0.3);
                solid(x + t * a.cos(), y + t * a.sin())
            })
        {
            continue;
        }
        let camera = Pose2::new(x, y, a - b);
        let mut map = SearchedMap::new(SearchParams {
            min_views: 1,
            ..SearchParams::default()
        })
        .unwrap();
        map.look(camera, &open);
        let (c, r) = ((v.0.x / 0.1).floor() as i64, (v.0.y / 0.1).floor() as i64);
        if !map.is_searched(c, r) {
            continue;
        }
        counted += 1;
        let mut frame_rng = rand::rngs::StdRng::seed_from_u64(tried);
        let img = still_frame(&w, camera, &cfg, &mut frame_rng);
        if run(&img, &DetectorParams::default())
            .detections
            .iter()
            .any(|det| (det.bearing - b).abs() < 0.15 && det.confidence >= min)
        {
            seen += 1;
        }
    }
    assert!(
        counted >= 150,
        "only {counted} counted cells in {tried} tries"
    );
    assert!(
        seen * 100 >= counted * 90,
        "a victim was seen on {seen} of {counted} counted cells"
    );
}
