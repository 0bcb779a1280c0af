use super::*;
use crate::sim::features::Rect;
use petrel_actors::Point2;
use rand::SeedableRng;

/// A 10 m x 5 m hall, a victim 2 m in front of a robot at (1, 2.5) facing +x.
fn scene(dark: bool) -> (Grid, WorldFeatures) {
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
        victims: vec![Point2::new(3.0, 2.5)],
        dark: if dark {
            vec![Rect::from_corners([0.0, 0.0, 10.0, 5.0]).unwrap()]
        } else {
            Vec::new()
        },
        ..WorldFeatures::default()
    };
    (grid, features)
}

fn frame(dark: bool, motion: CameraMotion, cfg: &CameraConfig, seed: u64) -> Vec<u8> {
    let (grid, features) = scene(dark);
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

/// Mean |row-to-row difference| in a window: the checkerboard's contrast.
fn contrast(
    img: &[u8],
    cfg: &CameraConfig,
    cols: std::ops::Range<usize>,
    rows: std::ops::Range<usize>,
) -> f64 {
    let w = cfg.width as usize;
    let mut sum = 0.0;
    let mut n = 0;
    for r in rows {
        for c in cols.clone() {
            sum += (img[r * w + c] as f64 - img[(r + 1) * w + c] as f64).abs();
            n += 1;
        }
    }
    sum / n as f64
}

fn turning(omega: f64) -> CameraMotion {
    CameraMotion {
        speed: Twist2::new(0.0, omega),
        rough: false,
    }
}

#[test]
fn a_victim_straight_ahead_appears_in_the_middle_below_the_horizon() {
    let cfg = CameraConfig::default();
    let img = frame(false, CameraMotion::default(), &cfg, 1);
    assert_eq!(img.len(), 160 * 120);
    // 1.75 m to its surface, 0.3 m high from the floor up to the camera's height: rows from
    // the horizon (60) down to 60 + f * 0.3 / 1.75 = 83.8; 0.5 m wide: +-20 columns.
    let f = cfg.focal();
    let bottom = 60.0 + f * CAMERA_HEIGHT / 1.75;
    assert!((83.0..85.0).contains(&bottom), "{bottom}");
    let victim = contrast(&img, &cfg, 70..90, 62..82);
    let wall = contrast(&img, &cfg, 5..25, 62..82);
    assert!(victim > 40.0 && wall < 10.0, "victim {victim}, wall {wall}");
    // Above the horizon the victim is not there: the wall beyond is smooth.
    assert!(contrast(&img, &cfg, 70..90, 45..57) < 10.0);
    // Its bearing: straight ahead is the image centre.
    assert!(cfg.bearing(80.0).abs() < 1e-12 && cfg.bearing(0.0) > 0.5);
}

#[test]
fn blur_grows_with_turn_rate_and_exposure() {
    let cfg = CameraConfig::default();
    let long = CameraConfig {
        exposure_ms: 40.0,
        ..cfg.clone()
    };
    let c = |img: &[u8]| contrast(img, &cfg, 70..90, 62..82);
    let still = c(&frame(false, turning(0.0), &cfg, 2));
    let slow = c(&frame(false, turning(1.5), &cfg, 2));
    let fast = c(&frame(false, turning(3.0), &cfg, 2));
    assert!(still > slow && slow > fast, "{still} {slow} {fast}");
    let fast_long = contrast(&frame(false, turning(1.5), &long, 2), &long, 70..90, 62..82);
    // Four times the exposure is four times brighter (clipped) but smears the squares away.
    assert!(fast_long < 0.5 * still, "{fast_long} vs {still}");
    // Rough floor smears rows when moving.
    let rough = CameraMotion {
        speed: Twist2::new(0.5, 0.0),
        rough: true,
    };
    let smooth = CameraMotion {
        rough: false,
        ..rough
    };
    let on_rough = c(&frame(false, rough, &cfg, 3));
    let on_smooth = c(&frame(false, smooth, &cfg, 3));
    assert!(on_rough < 0.5 * on_smooth, "{on_rough} vs {on_smooth}");
}

#[test]
fn darkness_makes_images_dim_and_noisy_exposure_and_gain_bring_them_back() {
    let mean = |img: &[u8]| img.iter().map(|&v| v as f64).sum::<f64>() / img.len() as f64;
    // Relative noise on the smooth wall: std / mean over a patch, from two frames.
    let noise = |cfg: &CameraConfig, dark: bool| {
        let a = frame(dark, CameraMotion::default(), cfg, 5);
        let b = frame(dark, CameraMotion::default(), cfg, 6);
        let w = cfg.width as usize;
        let (mut d2, mut m, mut n) = (0.0, 0.0, 0.0);
        for r in 40..55 {
            for c in 5..25 {
                let (x, y) = (a[r * w + c] as f64, b[r * w + c] as f64);
                d2 += (x - y).powi(2) / 2.0;
                m += (x + y) / 2.0;
                n += 1.0;
            }
        }
        (d2 / n).sqrt() / (m / n).max(1e-9)
    };
    let cfg = CameraConfig::default();
    let bright = frame(false, CameraMotion::default(), &cfg, 4);
    let dim = frame(true, CameraMotion::default(), &cfg, 4);
    assert!(
        mean(&dim) < 0.15 * mean(&bright),
        "{} vs {}",
        mean(&dim),
        mean(&bright)
    );
    assert!(noise(&cfg, true) > 2.0 * noise(&cfg, false));
    let longer = CameraConfig {
        exposure_ms: 40.0,
        ..cfg.clone()
    };
    assert!(noise(&longer, true) < 0.7 * noise(&cfg, true));
    let gained = CameraConfig {
        gain: 8.0,
        ..cfg.clone()
    };
    let dim_gained = frame(true, CameraMotion::default(), &gained, 4);
    assert!(mean(&dim_gained) > 4.0 * mean(&dim));
    let bad = CameraConfig { gain: 0.5, ..cfg };
    assert_eq!(bad.validate().unwrap_err().param, "camera/gain");
}

/// Mean grey level in a window.
fn mean(
    img: &[u8],
    cfg: &CameraConfig,
    cols: std::ops::Range<usize>,
    rows: std::ops::Range<usize>,
) -> f64 {
    let w = cfg.width as usize;
    let (mut sum, mut n) = (0.0, 0.0);
    for r in rows {
        for c in cols.clone() {
            sum += img[r * w + c] as f64;
            n += 1.0;
        }
    }
    sum / n
}

#[test]
fn another_robot_in_view_is_a_plain_grey_body_hiding_what_is_behind_it() {
    let cfg = CameraConfig::default();
    let (grid, features) = scene(false);
    let shot = |robots: &[(f64, f64, f64)]| {
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let pose = Pose2::new(1.0, 2.5, 0.0);
        render_among(
            &grid,
            &features,
            robots,
            pose,
            CameraMotion::default(),
            &cfg,
            &mut rng,
        )
    };
    let alone = shot(&[]);
    // A robot 1 m ahead, in front of the victim: its near side is 0.8 m away.
    let blocked = shot(&[(2.0, 2.5, 0.2)]);
    // The victim's checkerboard is gone behind it; the robot itself is smooth and brighter
    // than the wall (albedo 0.45 against a far wall's 0.28).
    let victim_alone = contrast(&alone, &cfg, 75..85, 62..82);
    let victim_hidden = contrast(&blocked, &cfg, 75..85, 62..82);
    assert!(
        victim_alone > 40.0 && victim_hidden < 10.0,
        "{victim_alone} vs {victim_hidden}"
    );
    let body = mean(&blocked, &cfg, 75..85, 62..90);
    let wall = mean(&alone, &cfg, 5..15, 62..70);
    assert!(body > wall + 20.0, "robot {body}, wall {wall}");
    // It rises above the horizon (0.4 m tall against a camera at 0.3 m) and stands on the floor.
    assert!(mean(&blocked, &cfg, 75..85, 52..58) > mean(&alone, &cfg, 75..85, 52..58) + 20.0);
    // Out of view (behind the camera) it changes nothing.
    assert_eq!(shot(&[(0.5, 2.5, 0.2)]), alone);
}

/// A dark room's edge drawn along its walls' inner faces (as `configs/rescue/rescue.txt` does:
/// the storeroom's `dark:` rectangle ends where its walls begin). The light on a wall is the
/// light in front of the face the camera sees, so every column of the wall is as dark as the
/// room: taking it at the face itself, which lies on the rectangle's edge, lit columns at
/// random (rounding put the hit in or out), and with a dark room's gain they were white
/// stripes beside black ones, which sharpening turned into texture and the detector into a
/// victim beside the wall.
#[test]
fn a_wall_on_the_edge_of_a_dark_room_is_as_dark_as_the_room() {
    let (grid, _) = scene(false);
    // The inner faces of the hall's walls: x = 0.1 and 9.9, y = 0.1 and 4.9.
    let features = WorldFeatures {
        dark: vec![Rect::from_corners([0.1, 0.1, 9.9, 4.9]).unwrap()],
        ..WorldFeatures::default()
    };
    let cfg = CameraConfig {
        exposure_ms: 30.0,
        gain: 4.0,
        ..CameraConfig::default()
    };
    let w = cfg.width as usize;
    // Looking at the walls from several places and headings, some at a slant.
    for (x, y, heading) in [
        (5.0, 2.5, -90.0f64),
        (5.0, 2.5, 90.0),
        (2.0, 1.5, -60.0),
        (8.0, 3.0, 20.0),
        (6.0, 1.0, -120.0),
    ] {
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let img = render(
            &grid,
            &features,
            Pose2::new(x, y, heading.to_radians()),
            CameraMotion::default(),
            &cfg,
            &mut rng,
        );
        // The row just above the horizon is wall in every column; a lit column saturates.
        let row = cfg.height as usize / 2 - 2;
        let lit: Vec<usize> = (0..w).filter(|&c| img[row * w + c] == 255).collect();
        assert!(
            lit.is_empty(),
            "from ({x}, {y}) at {heading}°: wall columns lit as if outside the room: {lit:?}"
        );
    }
}
