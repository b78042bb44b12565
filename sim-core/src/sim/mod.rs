//! The simulated robot in a building: a rapier2d body that cannot pass through walls, a 2D laser
//! cast against the wall segments (the nearest crossing in `f64`), and odometry with Stage's
//! proportional error model.
//!
//! All randomness comes from the seed given to [`Simulator::new`]; separate streams feed the
//! odometry error and the laser noise, so changing the beam count does not change the odometry.

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

/// RNG stream numbers (ChaCha streams of the run's seed).
const STREAM_ODOMETRY: u64 = 1;
const STREAM_LASER: u64 = 2;

/// The simulated world and robot. Advance it with [`Simulator::step`]; read the laser with
/// [`Simulator::scan`] and the odometry with [`Simulator::odometry`].
#[derive(Debug, Clone)]
pub struct Simulator {
    config: SimConfig,
    walls: Walls,
    robot: robot::RobotBody,
    odometry: Odometry,
    laser_rng: ChaCha8Rng,
    time_s: f64,
    /// Ground-truth path length.
    path_length_m: f64,
}

impl Simulator {
    /// A robot at `start` in `building`. The odometry error of the run is drawn here from `seed`.
    pub fn new(building: &Building, start: Pose, config: &SimConfig, seed: u64) -> Self {
        let segments = building.boundary_segments();
        let walls = Walls::new(&segments);
        let robot = robot::RobotBody::new(&walls, start, &config.robot);
        let mut odo_rng = ChaCha8Rng::seed_from_u64(seed);
        odo_rng.set_stream(STREAM_ODOMETRY);
        let odometry = Odometry::new(start, &config.odometry, &mut odo_rng);
        let mut laser_rng = ChaCha8Rng::seed_from_u64(seed);
        laser_rng.set_stream(STREAM_LASER);
        Self {
            config: config.clone(),
            walls,
            robot,
            odometry,
            laser_rng,
            time_s: 0.0,
            path_length_m: 0.0,
        }
    }

    pub fn config(&self) -> &SimConfig {
        &self.config
    }

    /// Simulated time since the start.
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// Ground-truth distance travelled.
    pub fn path_length_m(&self) -> f64 {
        self.path_length_m
    }

    /// The robot's true pose (for evaluation and drawing only: strategies must use the estimate).
    pub fn true_pose(&self) -> Pose {
        self.robot.pose()
    }

    /// The odometry pose (true motion with this run's proportional error).
    pub fn odometry(&self) -> Pose {
        self.odometry.pose()
    }

    pub fn odometry_model(&self) -> &Odometry {
        &self.odometry
    }

    pub fn walls(&self) -> &Walls {
        &self.walls
    }

    /// Drives for one period with the commanded forward speed and turn rate (clamped to the
    /// robot's limits). Walls stop the robot.
    pub fn step(&mut self, v_mps: f64, w_radps: f64) {
        let before = self.robot.pose();
        let v = v_mps.clamp(
            -self.config.robot.max_speed_mps,
            self.config.robot.max_speed_mps,
        );
        let w = w_radps.clamp(
            -self.config.robot.max_turn_rate_radps,
            self.config.robot.max_turn_rate_radps,
        );
        self.robot.step(v, w, self.config.step_s);
        let after = self.robot.pose();
        self.path_length_m += (after.position() - before.position()).norm();
        self.odometry.advance(&before, &after);
        self.time_s += self.config.step_s;
    }

    /// Waits one period without moving.
    pub fn idle(&mut self) {
        self.step(0.0, 0.0);
    }

    /// A laser scan from the true pose, with range noise.
    pub fn scan(&mut self) -> Scan {
        self.config
            .laser
            .scan(&self.walls, &self.robot.pose(), &mut self.laser_rng)
    }
}

#[cfg(test)]
mod tests;
