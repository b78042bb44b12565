//! The simulated robot in a building: a rapier2d body that cannot pass through walls, a 2D laser
//! cast against the wall segments (the nearest crossing in `f64`), and odometry with Stage's
//! proportional error model.
//!
//! A [`World`] holds the walls, the physics and the clock; each robot in it is reached by its
//! [`RobotId`] and has its own body, odometry and laser. All randomness comes from the seed
//! given to [`World::new`]; separate streams feed each robot's odometry error and laser noise,
//! so changing the beam count does not change the odometry, and adding a robot does not change
//! the first robot's draws.

mod laser;
mod odometry;
mod robot;

pub use laser::{cast_exhaustive, LaserConfig, Walls};
pub use odometry::{Odometry, OdometryConfig};
pub use robot::RobotConfig;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::building::Building;
use crate::geom::Pose;
use crate::scan::Scan;

/// Everything about the simulated robot.
#[derive(Debug, Clone, PartialEq)]
pub struct SimConfig {
    pub robot: RobotConfig,
    pub laser: LaserConfig,
    pub odometry: OdometryConfig,
    /// Physics and control period.
    pub step_s: f64,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            robot: RobotConfig::default(),
            laser: LaserConfig::default(),
            odometry: OdometryConfig::default(),
            step_s: 0.1,
        }
    }
}

/// RNG stream numbers (ChaCha streams of the run's seed) of the first robot; robot `k` uses
/// these plus `2 * k`.
const STREAM_ODOMETRY: u64 = 1;
const STREAM_LASER: u64 = 2;

/// A robot of a [`World`] (and of an [`crate::explore::Episode`]): its index in the order the
/// robots were added. A world of one robot has `RobotId(0)` only.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct RobotId(pub usize);

/// One robot's sensors and its record of motion (its body is in [`World`]'s physics).
#[derive(Debug, Clone)]
struct Robot {
    odometry: Odometry,
    laser_rng: ChaCha8Rng,
    /// Ground-truth path length.
    path_length_m: f64,
}

/// The simulated world: the building's walls, the physics of the robots' bodies (which cannot
/// pass through walls or each other) and the clock. Add robots with [`World::add_robot`],
/// advance every robot one period with [`World::step`]; read a robot's laser with
/// [`World::scan`] and its odometry with [`World::odometry`].
#[derive(Debug, Clone)]
pub struct World {
    config: SimConfig,
    seed: u64,
    walls: Walls,
    bodies: robot::Bodies,
    robots: Vec<Robot>,
    time_s: f64,
}

impl World {
    /// The walls of `building`, no robot yet; randomness from `seed`.
    pub fn new(building: &Building, config: &SimConfig, seed: u64) -> Self {
        let walls = Walls::new(&building.boundary_segments());
        let bodies = robot::Bodies::new(&walls);
        Self {
            config: config.clone(),
            seed,
            walls,
            bodies,
            robots: Vec::new(),
            time_s: 0.0,
        }
    }

    /// A world of one robot at `start` (see [`World::new`]).
    pub fn with_robot(building: &Building, start: Pose, config: &SimConfig, seed: u64) -> Self {
        let mut world = World::new(building, config, seed);
        world.add_robot(start);
        world
    }

    /// Adds a robot at `start`: its body, and its odometry error drawn from the seed.
    pub fn add_robot(&mut self, start: Pose) -> RobotId {
        let k = self.robots.len() as u64;
        let mut odo_rng = ChaCha8Rng::seed_from_u64(self.seed);
        odo_rng.set_stream(STREAM_ODOMETRY + 2 * k);
        let odometry = Odometry::new(start, &self.config.odometry, &mut odo_rng);
        let mut laser_rng = ChaCha8Rng::seed_from_u64(self.seed);
        laser_rng.set_stream(STREAM_LASER + 2 * k);
        self.bodies.add(start, &self.config.robot);
        self.robots.push(Robot {
            odometry,
            laser_rng,
            path_length_m: 0.0,
        });
        RobotId(self.robots.len() - 1)
    }

    /// The robots, in the order they were added.
    pub fn robots(&self) -> impl Iterator<Item = RobotId> {
        (0..self.robots.len()).map(RobotId)
    }

    /// Whether `robot` is in this world.
    pub fn has(&self, robot: RobotId) -> bool {
        robot.0 < self.robots.len()
    }

    pub fn config(&self) -> &SimConfig {
        &self.config
    }

    /// Simulated time since the start.
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// Ground-truth distance `robot` travelled.
    pub fn path_length_m(&self, robot: RobotId) -> f64 {
        self.robots[robot.0].path_length_m
    }

    /// The robot's true pose (for evaluation and drawing only: strategies must use the estimate).
    pub fn true_pose(&self, robot: RobotId) -> Pose {
        self.bodies.pose(robot.0)
    }

    /// The odometry pose (true motion with this robot's proportional error).
    pub fn odometry(&self, robot: RobotId) -> Pose {
        self.robots[robot.0].odometry.pose()
    }

    pub fn odometry_model(&self, robot: RobotId) -> &Odometry {
        &self.robots[robot.0].odometry
    }

    pub fn walls(&self) -> &Walls {
        &self.walls
    }

    /// Drives every robot for one period, robot `k` with the commanded forward speed and turn
    /// rate `commands[k]` (clamped to the robot's limits; a robot without a command stands
    /// still). Walls and other robots stop a robot.
    pub fn step(&mut self, commands: &[(f64, f64)]) {
        let robot = &self.config.robot;
        let clamped: Vec<(f64, f64)> = (0..self.robots.len())
            .map(|k| {
                let (v, w) = commands.get(k).copied().unwrap_or((0.0, 0.0));
                (
                    v.clamp(-robot.max_speed_mps, robot.max_speed_mps),
                    w.clamp(-robot.max_turn_rate_radps, robot.max_turn_rate_radps),
                )
            })
            .collect();
        let before: Vec<Pose> = (0..self.robots.len())
            .map(|k| self.bodies.pose(k))
            .collect();
        self.bodies.step(&clamped, self.config.step_s);
        for (k, r) in self.robots.iter_mut().enumerate() {
            let after = self.bodies.pose(k);
            r.path_length_m += (after.position() - before[k].position()).norm();
            r.odometry.advance(&before[k], &after);
        }
        self.time_s += self.config.step_s;
    }

    /// Every robot waits one period without moving.
    pub fn idle(&mut self) {
        self.step(&[]);
    }

    /// A laser scan of `robot` from its true pose, with range noise: the walls and the other
    /// robots' bodies stop its beams.
    pub fn scan(&mut self, robot: RobotId) -> Scan {
        self.scan_marked(robot).0
    }

    /// [`World::scan`], and per beam whether it ended on another robot's body: the robots carry
    /// retro-reflective markers that a laser tells by its return's intensity, as real teams tag
    /// each other. The same scan (the same noise) as [`World::scan`].
    pub fn scan_marked(&mut self, robot: RobotId) -> (Scan, Vec<bool>) {
        let pose = self.bodies.pose(robot.0);
        let radius_m = self.config.robot.radius_m;
        let others: Vec<(crate::geom::Vec2, f64)> = (0..self.robots.len())
            .filter(|&k| k != robot.0)
            .map(|k| (self.bodies.pose(k).position(), radius_m))
            .collect();
        let rng = &mut self.robots[robot.0].laser_rng;
        self.config
            .laser
            .scan_marked(&self.walls, &others, &pose, rng)
    }
}

#[cfg(test)]
mod tests;
