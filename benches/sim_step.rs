//! Simulation step cost: one robot with a 181-ray laser in a 400 x 400 cell world.
//!
//! `raycast_only` (the scan alone) and `step_no_laser` (kinematics and swept collision
//! checks alone) run in the same process as baselines, so the ratio to `step_400` stays
//! meaningful on a noisy machine.
//!
//! `camera/render` (one 160 x 120 frame of the rescue world: a ray per column, shading,
//! noise) is measured against `camera/rays_only` (its 160 ray casts alone), and
//! `camera/detect` and `camera/detect_deblur` (the victim detector without and with
//! sharpening) against `camera/pixel_pass` (one pass summing the frame's pixels).

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use petrel_actors::{Pose2, Twist2};
use petrel_modules::sim::raycast::cast_ray;
use petrel_modules::sim::{load_world, Grid, RobotConfig, World};

fn warehouse() -> Grid {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/worlds/warehouse.yaml");
    let world = load_world(&path).expect("shipped warehouse world loads");
    assert_eq!((world.grid.width(), world.grid.height()), (400, 400));
    world.grid
}

/// A world with one robot circling (radius 0.3 m) at the warehouse's central crossing.
fn circling(config: RobotConfig) -> World {
    let mut world = World::new(warehouse(), 1);
    let id = world
        .add_robot(config, Pose2::new(9.75, 8.5, 0.0))
        .expect("free start");
    world
        .set_command(id, Twist2::new(0.3, 1.0))
        .expect("robot exists");
    world
}

fn sim_step(c: &mut Criterion) {
    let mut g = c.benchmark_group("sim_step");

    let mut world = circling(RobotConfig::default());
    g.bench_function("step_400", |b| {
        b.iter(|| black_box(world.step(black_box(0.01)).unwrap().len()))
    });

    let mut world = circling(RobotConfig {
        laser: None,
        ..RobotConfig::default()
    });
    g.bench_function("step_no_laser", |b| {
        b.iter(|| black_box(world.step(black_box(0.01)).unwrap().len()))
    });

    // The scans `step_400` casts: the same robot's 181 rays, from the poses it passes through
    // while circling (recorded without a laser, replayed in order), relative to its heading.
    let mut recorder = circling(RobotConfig {
        laser: None,
        ..RobotConfig::default()
    });
    let poses: Vec<Pose2> = (0..1000)
        .map(|_| {
            recorder.step(0.01).unwrap();
            recorder.pose(0).expect("the only robot, id 0")
        })
        .collect();
    let laser = RobotConfig::default()
        .laser
        .expect("the default robot has a laser");
    let grid = warehouse();
    let mut at = 0;
    g.bench_function("raycast_only", |b| {
        b.iter(|| {
            let pose = poses[at % poses.len()];
            at += 1;
            let mut sum = 0.0;
            for i in 0..laser.rays {
                let a =
                    pose.theta() - laser.fov / 2.0 + laser.fov * i as f64 / (laser.rays - 1) as f64;
                sum += cast_ray(
                    &grid,
                    black_box(pose.x()),
                    black_box(pose.y()),
                    a,
                    laser.range_max,
                );
            }
            black_box(sum)
        })
    });
    g.finish();
}

fn camera(c: &mut Criterion) {
    use petrel_modules::sim::camera::{render, CameraConfig, CameraMotion};
    use petrel_modules::vision::{detect, DetectorParams};
    use rand::SeedableRng;

    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/rescue/rescue.txt");
    let world = load_world(&path).expect("shipped rescue world loads");
    // At the start, facing the first victim.
    let pose = Pose2::new(1.1, 1.1, 1.3);
    let cfg = CameraConfig::default();
    let motion = CameraMotion {
        speed: Twist2::new(0.3, 0.2),
        rough: false,
    };
    let mut rng = rand::rngs::StdRng::seed_from_u64(1);
    let mut g = c.benchmark_group("camera");
    g.bench_function("render", |b| {
        b.iter(|| {
            black_box(render(
                &world.grid,
                &world.features,
                black_box(pose),
                motion,
                &cfg,
                &mut rng,
            ))
        })
    });
    g.bench_function("rays_only", |b| {
        b.iter(|| {
            let mut sum = 0.0;
            for col in 0..160 {
                let a = pose.theta() + cfg.bearing(col as f64 + 0.5);
                sum += cast_ray(&world.grid, black_box(pose.x()), pose.y(), a, cfg.range_max);
            }
            black_box(sum)
        })
    });
    let frame = render(
        &world.grid,
        &world.features,
        pose,
        CameraMotion::default(),
        &cfg,
        &mut rng,
    );
    let plain = DetectorParams::default();
    assert_eq!(
        detect(&frame, 160, 120, &plain).unwrap().detections.len(),
        1
    );
    g.bench_function("detect", |b| {
        b.iter(|| black_box(detect(black_box(&frame), 160, 120, &plain)))
    });
    let sharpen = DetectorParams {
        deblur: 1.0,
        ..DetectorParams::default()
    };
    g.bench_function("detect_deblur", |b| {
        b.iter(|| black_box(detect(black_box(&frame), 160, 120, &sharpen)))
    });
    g.bench_function("pixel_pass", |b| {
        b.iter(|| black_box(black_box(&frame).iter().map(|&v| v as u64).sum::<u64>()))
    });
    g.finish();
}

criterion_group!(benches, sim_step, camera);
criterion_main!(benches);
