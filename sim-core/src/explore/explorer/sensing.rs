//! Sensing: the laser and odometry read, the pose estimated, the map updated.

use crate::explore::explorer::Explorer;
use crate::explore::map_state::MapChanges;
use crate::explore::referee::MapToWorld;
use crate::sim::World;

impl Explorer {
    /// Takes in the world's clock and the robot's true pose (after the world moved).
    pub(crate) fn observe(&mut self, world: &World) {
        self.now_s = world.time_s();
        self.true_pose = world.true_pose(self.robot);
    }

    /// Observes the world ([`Explorer::observe`]), and updates the map when the robot has moved
    /// or turned enough, or the period has passed: what the update changed (`None`: no update).
    pub(crate) fn sense(&mut self, world: &mut World) -> Option<MapChanges> {
        self.observe(world);
        let cfg = &*self.cfg;
        let due = self
            .localizer
            .advance(world.odometry(self.robot), self.now_s, cfg)?;
        let mut scan = world.scan(self.robot);
        if !self.mates.is_empty() {
            self.drop_teammates(&mut scan);
        }
        let seen = (&self.map.grid, &self.map.obstacles);
        let estimate = self
            .localizer
            .localize(&due, &scan, seen, self.true_pose, cfg);
        let changes = self.map.integrate(&estimate, &scan, &cfg.log_odds);
        if let Some(coverage) = self.coverage.as_mut() {
            coverage.add_scan(&estimate, &scan);
        }
        // (The planning cells of every change, and the explored area.)
        self.nav.map_updated(&self.map, &changes);
        let map_to_world = MapToWorld::new(&estimate, &self.true_pose);
        self.credit_explored(&map_to_world);
        let (from, to) = self.localizer.close_update(due, self.now_s);
        self.mark_travelled(from, to);
        self.trajectory.push(self.true_pose);
        Some(changes)
    }

    /// Drops (makes not finite: neither mapped nor matched) the beams of `scan` that end on a
    /// teammate: within its radius and [`TEAMMATE_FILTER_M`] of its estimated position, as its
    /// teammates tell it, measured from the robot's own estimate (a robot is not a wall to map).
    fn drop_teammates(&self, scan: &mut crate::scan::Scan) {
        let pose = self.localizer.estimate();
        let reach = self.cfg.sim.robot.radius_m + TEAMMATE_FILTER_M;
        for i in 0..scan.ranges_m.len() {
            if !scan.is_hit(i) {
                continue;
            }
            let a = pose.theta_rad + scan.beam_angle_rad(i);
            let end = pose.position() + crate::geom::Vec2::new(a.cos(), a.sin()) * scan.ranges_m[i];
            if self
                .mates
                .iter()
                .any(|m| (m.pose.position() - end).norm() <= reach)
            {
                scan.ranges_m[i] = f64::NAN;
            }
        }
    }
}

/// How far beyond a teammate's body (its estimated position plus its radius) a beam's end is
/// taken for the teammate, not a wall (m): the estimates' errors.
pub(crate) const TEAMMATE_FILTER_M: f64 = 0.15;
