use proptest::prelude::*;

use super::*;

const R0: RobotId = RobotId(0);
use crate::building::Geometry;
use crate::geom::{Polygon, Vec2};

/// A 12 x 8 m building: two rooms, a wall with a 1 m door, a pillar.
fn building() -> Building {
    let outline = Polygon::rect(Vec2::new(0.0, 0.0), Vec2::new(12.0, 8.0));
    let w = |a: (f64, f64), b: (f64, f64)| {
        Polygon::thick_segment(Vec2::new(a.0, a.1), Vec2::new(b.0, b.1), 0.2)
    };
    let solids = vec![
        w((0.0, 0.0), (12.0, 0.0)),
        w((12.0, 0.0), (12.0, 8.0)),
        w((12.0, 8.0), (0.0, 8.0)),
        w((0.0, 8.0), (0.0, 0.0)),
        w((6.0, 0.0), (6.0, 3.5)),
        w((6.0, 4.5), (6.0, 8.0)),
        Polygon::rect(Vec2::new(2.5, 2.5), Vec2::new(3.0, 3.0)),
    ];
    Building {
        name: "sim-test".into(),
        geometry: Geometry::Vector { outline, solids },
        rooms: vec![],
        doors: vec![],
        start: Some(Pose::new(1.5, 4.0, 0.0)),
    }
}

fn min_wall_distance(b: &Building, p: Vec2) -> f64 {
    b.boundary_segments()
        .iter()
        .map(|s| s.distance_to(p))
        .fold(f64::INFINITY, f64::min)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn beams_stay_in_range_and_stop_at_walls(
        x in 0.3f64..11.7, y in 0.3f64..7.7, theta in -3.2f64..3.2, seed in 0u64..1000
    ) {
        let b = building();
        prop_assume!(b.is_free(Vec2::new(x, y)));
        let mut sim = World::with_robot(&b, Pose::new(x, y, theta), &SimConfig::default(), seed);
        let scan = sim.scan(R0);
        prop_assert_eq!(scan.ranges_m.len(), 181);
        for (i, &r) in scan.ranges_m.iter().enumerate() {
            prop_assert!((0.0..=scan.max_range_m).contains(&r));
            let a = theta + scan.beam_angle_rad(i);
            let dir = Vec2::new(a.cos(), a.sin());
            // Every point of the beam before its end (minus the noise margin) is free.
            let end = (r - 0.05).max(0.0);
            let mut t = 0.0;
            while t < end {
                prop_assert!(b.is_free(Vec2::new(x, y) + dir * t), "beam {i} passes a wall at {t}");
                t += 0.02;
            }
            if scan.is_hit(i) {
                // A hit lies on a wall (within noise).
                let hit = Vec2::new(x, y) + dir * r;
                prop_assert!(min_wall_distance(&b, hit) < 0.06, "beam {i} hit nothing at {r}");
            }
        }
    }

    #[test]
    fn robot_never_overlaps_a_wall(
        commands in proptest::collection::vec((-0.5f64..0.5, -1.0f64..1.0, 1usize..30), 1..20),
        seed in 0u64..1000,
    ) {
        let b = building();
        let cfg = SimConfig::default();
        let mut sim = World::with_robot(&b, b.start.unwrap(), &cfg, seed);
        for (v, w, n) in commands {
            for _ in 0..n {
                sim.step(&[(v, w)]);
                let p = sim.true_pose(R0).position();
                let d = min_wall_distance(&b, p);
                prop_assert!(d >= cfg.robot.radius_m - 0.02, "robot at {p:?} is {d} m from a wall");
                prop_assert!(b.is_free(p));
            }
        }
    }
}

#[test]
fn same_seed_same_trajectory_and_scans() {
    let b = building();
    let run = |seed| {
        let mut sim = World::with_robot(&b, b.start.unwrap(), &SimConfig::default(), seed);
        let mut log = Vec::new();
        for k in 0..300 {
            let w = if (k / 40) % 2 == 0 { 0.3 } else { -0.6 };
            sim.step(&[(0.5, w)]);
            if k % 5 == 0 {
                log.push((sim.true_pose(R0), sim.odometry(R0), sim.scan(R0).ranges_m));
            }
        }
        log
    };
    let a = run(7);
    assert_eq!(a, run(7));
    assert_ne!(a, run(8));
}

#[test]
fn odometry_error_is_proportional_and_bounded() {
    let b = building();
    let mut sim = World::with_robot(&b, b.start.unwrap(), &SimConfig::default(), 3);
    let e = sim.odometry_model(R0).error;
    assert!(e[0].abs() <= 0.01 && e[1].abs() <= 0.01 && e[2].abs() <= 2f64.to_radians());
    // Drive straight 4 m: the odometry error stays within 1 % of the distance.
    for _ in 0..80 {
        sim.step(&[(0.5, 0.0)]);
    }
    let truth = sim.true_pose(R0);
    let odo = sim.odometry(R0);
    let moved = truth.x_m - 1.5;
    assert!(moved > 3.9, "moved {moved}");
    assert!((odo.position() - truth.position()).norm() <= 0.0101 * moved * 2f64.sqrt());
}

#[test]
fn robot_is_stopped_by_a_wall() {
    let b = building();
    let mut sim = World::with_robot(
        &b,
        Pose::new(1.5, 4.0, std::f64::consts::PI),
        &SimConfig::default(),
        1,
    );
    for _ in 0..100 {
        sim.step(&[(0.5, 0.0)]);
    }
    let p = sim.true_pose(R0);
    // The outer wall's inner face is at x = 0.1.
    assert!(p.x_m >= 0.1 + 0.2 - 0.02 && p.x_m < 0.4, "{p:?}");
}

/// Two robots in the first room, facing each other 2.5 m apart.
fn two_robots(seed: u64) -> World {
    let b = building();
    let mut world = World::new(&b, &SimConfig::default(), seed);
    world.add_robot(Pose::new(1.5, 4.0, 0.0));
    world.add_robot(Pose::new(4.0, 4.0, std::f64::consts::PI));
    world
}

#[test]
fn robots_see_each_other() {
    let mut world = two_robots(5);
    assert_eq!(world.robots().count(), 2);
    let r1 = RobotId(1);
    for (robot, other) in [(R0, r1), (r1, R0)] {
        let scan = world.scan(robot);
        // The middle beam points at the other robot: it ends at the near side of its disc.
        let mid = scan.ranges_m[scan.ranges_m.len() / 2];
        let gap = (world.true_pose(robot).position() - world.true_pose(other).position()).norm()
            - SimConfig::default().robot.radius_m;
        assert!((mid - gap).abs() < 0.05, "beam {mid} m, gap {gap} m");
    }
    // Alone, the same beam reaches the wall 4.4 m ahead (the door wall at x = 5.9).
    let b = building();
    let mut alone = World::with_robot(&b, Pose::new(1.5, 4.0, 0.0), &SimConfig::default(), 5);
    let scan = alone.scan(R0);
    assert!(scan.ranges_m[scan.ranges_m.len() / 2] > 4.0);
}

#[test]
fn robots_stop_each_other() {
    let mut world = two_robots(6);
    let r = SimConfig::default().robot.radius_m;
    for _ in 0..100 {
        world.step(&[(0.5, 0.0), (0.5, 0.0)]);
        let d = (world.true_pose(R0).position() - world.true_pose(RobotId(1)).position()).norm();
        assert!(
            d >= 2.0 * r - 0.02,
            "the bodies overlap: centres {d} m apart"
        );
    }
    assert!(world.path_length_m(R0) > 0.5 && world.path_length_m(RobotId(1)) > 0.5);
}

#[test]
fn each_robot_draws_from_its_own_streams() {
    let b = building();
    let one = World::with_robot(&b, Pose::new(1.5, 4.0, 0.0), &SimConfig::default(), 9);
    let two = two_robots(9);
    // The first robot's odometry error is the same with a second robot in the world; the
    // second's is its own.
    assert_eq!(one.odometry_model(R0).error, two.odometry_model(R0).error);
    assert_ne!(
        two.odometry_model(R0).error,
        two.odometry_model(RobotId(1)).error
    );
}
