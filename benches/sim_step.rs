//! Simulation step cost: one robot with a 181-ray laser in a 400 x 400 cell world.
//!
//! `raycast_only` (the scan alone) and `step_no_laser` (kinematics and swept collision
//! checks alone) run in the same process as baselines, so the ratio to `step_400` stays
//! meaningful on a noisy machine.

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

    let grid = warehouse();
    g.bench_function("raycast_only", |b| {
        b.iter(|| {
            let mut sum = 0.0;
            for i in 0..181 {
                let a = -std::f64::consts::FRAC_PI_2 + std::f64::consts::PI * i as f64 / 180.0;
                sum += cast_ray(&grid, black_box(9.75), black_box(8.8), a, 8.0);
            }
            black_box(sum)
        })
    });
    g.finish();
}

criterion_group!(benches, sim_step);
criterion_main!(benches);
