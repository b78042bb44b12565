//! A simple path follower for a differential-drive robot: turn toward a look-ahead point on the
//! path, drive when roughly facing it.

use crate::geom::{wrap_angle, Pose, Vec2};

#[derive(Debug, Clone, PartialEq)]
pub struct FollowConfig {
    /// How far ahead along the path the robot aims.
    pub lookahead_m: f64,
    /// Heading error above which the robot turns in place.
    pub turn_in_place_rad: f64,
    /// Proportional gain from heading error to turn rate.
    pub heading_gain: f64,
    /// Distance at which the last waypoint counts as reached.
    pub goal_tolerance_m: f64,
}

impl Default for FollowConfig {
    fn default() -> Self {
        Self {
            lookahead_m: 0.4,
            turn_in_place_rad: 0.8,
            heading_gain: 2.0,
            goal_tolerance_m: 0.25,
        }
    }
}

/// Follows a polyline of waypoints.
#[derive(Debug, Clone, Default)]
pub struct PathFollower {
    waypoints: Vec<Vec2>,
    /// Index of the first waypoint not yet passed.
    next: usize,
}

/// What the follower asks of the robot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    Drive { v_mps: f64, w_radps: f64 },
    Arrived,
}

impl PathFollower {
    pub fn new(waypoints: Vec<Vec2>) -> Self {
        Self { waypoints, next: 0 }
    }

    pub fn is_empty(&self) -> bool {
        self.waypoints.is_empty()
    }

    pub fn waypoints(&self) -> &[Vec2] {
        &self.waypoints
    }

    /// Remaining waypoints, from the next one.
    pub fn remaining(&self) -> &[Vec2] {
        &self.waypoints[self.next.min(self.waypoints.len())..]
    }

    pub fn goal(&self) -> Option<Vec2> {
        self.waypoints.last().copied()
    }

    /// The command for the robot at `pose`, with speed limits.
    pub fn command(&mut self, pose: &Pose, cfg: &FollowConfig, max_v: f64, max_w: f64) -> Command {
        let Some(goal) = self.goal() else {
            return Command::Arrived;
        };
        let p = pose.position();
        if (goal - p).norm() <= cfg.goal_tolerance_m {
            return Command::Arrived;
        }
        // Skip waypoints already within the look-ahead distance.
        while self.next + 1 < self.waypoints.len()
            && (self.waypoints[self.next] - p).norm() < cfg.lookahead_m
        {
            self.next += 1;
        }
        let target = self.waypoints[self.next.min(self.waypoints.len() - 1)];
        let to = target - p;
        let err = wrap_angle(to.y.atan2(to.x) - pose.theta_rad);
        let w = (cfg.heading_gain * err).clamp(-max_w, max_w);
        let v = if err.abs() > cfg.turn_in_place_rad {
            0.0
        } else {
            // Slow down in sharp turns and for the final approach.
            let dist_left = (goal - p).norm();
            (max_v * err.cos()).min(max_v * (dist_left / 0.5).clamp(0.3, 1.0))
        };
        Command::Drive {
            v_mps: v.max(0.0),
            w_radps: w,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reaches_the_end_of_an_l_path() {
        let mut f = PathFollower::new(vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(3.0, 0.0),
            Vec2::new(3.0, 3.0),
        ]);
        let cfg = FollowConfig::default();
        let mut pose = Pose::new(0.0, 0.0, 0.0);
        let dt = 0.1;
        for _ in 0..400 {
            match f.command(&pose, &cfg, 0.5, 1.0) {
                Command::Arrived => {
                    assert!((pose.position() - Vec2::new(3.0, 3.0)).norm() <= 0.25);
                    return;
                }
                Command::Drive { v_mps, w_radps } => {
                    let th = pose.theta_rad + w_radps * dt / 2.0;
                    pose = Pose::new(
                        pose.x_m + v_mps * dt * th.cos(),
                        pose.y_m + v_mps * dt * th.sin(),
                        wrap_angle(pose.theta_rad + w_radps * dt),
                    );
                }
            }
        }
        panic!("did not arrive; at {pose:?}");
    }

    #[test]
    fn turns_in_place_when_facing_away() {
        let mut f = PathFollower::new(vec![Vec2::new(0.0, 0.0), Vec2::new(-2.0, 0.0)]);
        let c = f.command(
            &Pose::new(0.0, 0.0, 0.0),
            &FollowConfig::default(),
            0.5,
            1.0,
        );
        match c {
            Command::Drive { v_mps, w_radps } => {
                assert_eq!(v_mps, 0.0);
                assert!(w_radps.abs() > 0.9);
            }
            Command::Arrived => panic!("not arrived"),
        }
    }
}
