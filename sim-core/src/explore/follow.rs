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
    /// Where the path starts, if known.
    start: Option<Vec2>,
}

/// What the follower asks of the robot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    Drive { v_mps: f64, w_radps: f64 },
    Arrived,
}

impl PathFollower {
    pub fn new(waypoints: Vec<Vec2>) -> Self {
        Self {
            waypoints,
            next: 0,
            start: None,
        }
    }

    /// A path from `start` (where the robot stands) through `waypoints`.
    pub fn from(start: Vec2, waypoints: Vec<Vec2>) -> Self {
        Self {
            waypoints,
            next: 0,
            start: Some(start),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.waypoints.is_empty()
    }

    pub fn waypoints(&self) -> &[Vec2] {
        &self.waypoints
    }

    /// Remaining waypoints, from the next one.
    /// The start of the segment being followed (the waypoint passed last, or the start given to
    /// [`PathFollower::from`]) and the waypoints left.
    pub fn current_segment(&self) -> Option<(Vec2, &[Vec2])> {
        let rest = self.remaining();
        (!rest.is_empty()).then_some((self.passed()?, rest))
    }

    /// The waypoint passed last, or the start given to [`PathFollower::from`] before the first.
    fn passed(&self) -> Option<Vec2> {
        match self.next {
            0 => self.start,
            k => self.waypoints.get(k - 1).copied(),
        }
    }

    pub fn remaining(&self) -> &[Vec2] {
        &self.waypoints[self.next.min(self.waypoints.len())..]
    }

    /// Length (m) of the path left from `p`: to the waypoint being approached, then along the
    /// rest (0 for an empty path).
    pub fn remaining_length_m(&self, p: Vec2) -> f64 {
        let rest = self.remaining();
        let Some(first) = rest.first() else {
            return 0.0;
        };
        (first - p).norm() + rest.windows(2).map(|w| (w[1] - w[0]).norm()).sum::<f64>()
    }

    pub fn goal(&self) -> Option<Vec2> {
        self.waypoints.last().copied()
    }

    /// Start of the segment being followed (the robot itself before the first waypoint when
    /// the path has no known start).
    fn segment_start(&self, p: Vec2) -> Vec2 {
        self.passed().unwrap_or(p)
    }

    /// The point `lookahead_m` along the path from the robot's projection on the segment being
    /// followed. Aiming at a point on the path, rather than at the next waypoint once within
    /// reach of the one before, cuts corners by little: a robot that turned early toward the
    /// waypoint after a corner could run into the wall end at the corner and push against it.
    fn carrot(&self, p: Vec2, lookahead_m: f64) -> Vec2 {
        let k = self.next.min(self.waypoints.len() - 1);
        let (from, to) = (self.segment_start(p), self.waypoints[k]);
        let mut at = from + (to - from) * projection(p, from, to);
        let mut left = lookahead_m;
        for &w in &self.waypoints[k..] {
            let seg = (w - at).norm();
            if seg >= left {
                return at + (w - at) * (left / seg);
            }
            left -= seg;
            at = w;
        }
        at
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
        // Move on to the next segment once past the end of this one (or close to its end).
        while self.next + 1 < self.waypoints.len() {
            let (from, to) = (self.segment_start(p), self.waypoints[self.next]);
            if (to - p).norm() < cfg.lookahead_m / 2.0 || projection(p, from, to) >= 1.0 {
                self.next += 1;
            } else {
                break;
            }
        }
        let target = self.carrot(p, cfg.lookahead_m);
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

/// Where the projection of `p` falls on the segment `a`-`b`, as a fraction of it in [0, 1].
fn projection(p: Vec2, a: Vec2, b: Vec2) -> f64 {
    let d = b - a;
    let len2 = d.norm_squared();
    if len2 > 0.0 {
        ((p - a).dot(&d) / len2).clamp(0.0, 1.0)
    } else {
        1.0
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
    fn the_path_left_is_measured_from_the_robot_along_the_waypoints() {
        let wps = vec![Vec2::new(3.0, 0.0), Vec2::new(3.0, 4.0)];
        let mut f = PathFollower::from(Vec2::new(0.0, 0.0), wps.clone());
        // 3 m to the first waypoint, 4 m on.
        assert!((f.remaining_length_m(Vec2::new(0.0, 0.0)) - 7.0).abs() < 1e-12);
        assert_eq!(f.current_segment(), Some((Vec2::new(0.0, 0.0), &wps[..])));
        // Past the first waypoint (within the lookahead), on the second segment.
        let _ = f.command(
            &Pose::new(2.9, 0.0, 0.0),
            &FollowConfig::default(),
            0.5,
            1.0,
        );
        assert_eq!(f.current_segment(), Some((wps[0], &wps[1..])));
        assert!((f.remaining_length_m(Vec2::new(3.0, 1.0)) - 3.0).abs() < 1e-12);
        // Without a known start the first segment has none; an empty path has nothing left.
        assert_eq!(PathFollower::new(wps).current_segment(), None);
        assert_eq!(
            PathFollower::default().remaining_length_m(Vec2::zeros()),
            0.0
        );
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

    #[test]
    fn does_not_cut_a_corner_next_to_the_robot() {
        // The robot stands 0.33 m east of a corner of its path, facing north: the path goes
        // west to the corner, then north. Aiming at the waypoint after the corner (the old rule,
        // once within the look-ahead of the corner) would drive it north, into the end of the
        // wall that the path goes around; it must first turn west.
        let p = Vec2::new(0.33, 0.0);
        let mut f = PathFollower::from(p, vec![Vec2::new(0.0, 0.0), Vec2::new(0.0, 3.0)]);
        let c = f.command(
            &Pose::new(p.x, p.y, std::f64::consts::FRAC_PI_2),
            &FollowConfig::default(),
            0.5,
            1.0,
        );
        match c {
            Command::Drive { v_mps, w_radps } => {
                assert_eq!(v_mps, 0.0, "drives on toward the wall");
                assert!(w_radps > 0.5, "turns left, toward the corner: {w_radps}");
            }
            Command::Arrived => panic!("not arrived"),
        }
        // Near the corner it aims up the second segment.
        let c = f.command(
            &Pose::new(0.02, 0.0, std::f64::consts::FRAC_PI_2),
            &FollowConfig::default(),
            0.5,
            1.0,
        );
        assert!(
            matches!(c, Command::Drive { v_mps, .. } if v_mps > 0.0),
            "{c:?}"
        );
    }
}
