//! Sensing: the laser and odometry read, the pose estimated, the map updated.

use crate::explore::explorer::Explorer;
use crate::explore::referee::MapToWorld;
use crate::grid::Occupancy;
use crate::sim::World;

impl Explorer {
    /// Takes in the world's clock and the robot's true pose (after the world moved).
    pub(crate) fn observe(&mut self, world: &World) {
        self.now_s = world.time_s();
        self.true_pose = world.true_pose(self.robot);
    }

    /// Observes the world ([`Explorer::observe`]), and updates the map when the robot has moved
    /// or turned enough, or the period has passed.
    pub(crate) fn sense(&mut self, world: &mut World) {
        self.observe(world);
        let cfg = &*self.cfg;
        let Some(due) = self
            .localizer
            .advance(world.odometry(self.robot), self.now_s, cfg)
        else {
            return;
        };
        let scan = world.scan(self.robot);
        let seen = (&self.map, &self.obstacles);
        let estimate = self
            .localizer
            .localize(&due, &scan, seen, self.true_pose, cfg);
        let stats = self.map.insert_scan(&estimate, &scan, &cfg.log_odds);
        self.known_cells += stats.cells_discovered;
        let flips = self.map.take_occupied_flips();
        let free_changes = self.map.take_free_changes();
        // (The obstacle distances too, and the planning cells of every change.)
        self.nav
            .map_updated(&self.map, &mut self.obstacles, &flips, &free_changes);
        // (The layout gains too: the layout they are computed with changes less often than the
        // map, and clears them when it does.)
        // (Changes of whether a cell is occupied recorded last: see `GainCache::touch`.)
        let now = self.localizer.scans();
        for &(i, _) in &free_changes {
            self.gains.touch(i, now, false);
        }
        for &i in &flips {
            self.gains.touch(i, now, true);
        }
        self.frontiers.update(
            &self.map.occupancy,
            flips
                .iter()
                .chain(free_changes.iter().map(|(i, _)| i))
                .copied(),
        );
        // A cell never goes back to unknown, and every change from unknown is in one of the
        // two lists.
        let mut fresh = std::mem::take(&mut self.fresh_known);
        fresh.clear();
        for &i in flips.iter().chain(free_changes.iter().map(|(i, _)| i)) {
            let i = i as usize;
            if !self.known.data[i] && self.map.occupancy.data[i] != Occupancy::Unknown {
                self.known.data[i] = true;
                fresh.push(i);
            }
        }
        let map_to_world = MapToWorld::new(&estimate, &self.true_pose);
        self.credit_explored(&fresh, &map_to_world);
        self.fresh_known = fresh;
        let (from, to) = self.localizer.close_update(due, self.now_s);
        self.mark_travelled(from, to);
        self.trajectory.push(self.true_pose);
    }
}
