//! Odometry with Stage's error model: per run, a proportional error drawn once for each of
//! x, y and heading, uniformly within the configured maxima. Every motion is then scaled by it,
//! so maps differ from run to run as they do in the paper's Stage runs.

use rand::Rng;

use crate::geom::Pose;

/// Maximum proportional errors. Defaults as the paper configures Stage: translation up to
/// 0.01 m per m, rotation up to 2 degrees per radian.
#[derive(Debug, Clone, PartialEq)]
pub struct OdometryConfig {
    pub max_translation_error: f64,
    pub max_rotation_error: f64,
}

impl Default for OdometryConfig {
    fn default() -> Self {
        Self {
            max_translation_error: 0.01,
            max_rotation_error: 2f64.to_radians(),
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Odometry {
    /// The run's proportional errors `[x, y, heading]`.
    pub error: [f64; 3],
    pose: Pose,
}

impl Odometry {
    pub fn new(start: Pose, config: &OdometryConfig, rng: &mut impl Rng) -> Self {
        let mut draw = |max: f64| {
            if max > 0.0 {
                rng.random_range(-max..=max)
            } else {
                0.0
            }
        };
        let error = [
            draw(config.max_translation_error),
            draw(config.max_translation_error),
            draw(config.max_rotation_error),
        ];
        Self { error, pose: start }
    }

    pub fn pose(&self) -> Pose {
        self.pose
    }

    /// Integrates the true motion from `before` to `after`, distorted by the run's error.
    pub fn advance(&mut self, before: &Pose, after: &Pose) {
        let d = before.between(after);
        let noisy = Pose::new(
            d.x_m * (1.0 + self.error[0]),
            d.y_m * (1.0 + self.error[1]),
            d.theta_rad * (1.0 + self.error[2]),
        );
        self.pose = self.pose.compose(&noisy);
    }
}
