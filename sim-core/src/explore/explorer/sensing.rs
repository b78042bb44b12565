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
        // In a team, a beam that ended on a teammate (its marker) is dropped: neither mapped nor
        // matched (a robot is not a wall).
        let (mut scan, on_robot) = world.scan_marked(self.robot);
        if self.team_size > 1 {
            for (r, _) in scan.ranges_m.iter_mut().zip(&on_robot).filter(|(_, m)| **m) {
                *r = f64::NAN;
            }
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
}
