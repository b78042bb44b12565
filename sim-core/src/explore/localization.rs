//! Localization and mapping: each scan, the pose estimate from odometry (calibrated) and scan
//! matching, the map updated at that estimate, the frontier tracker and planning cells told
//! which cells changed, and the cells the robot travelled.

use super::*;

impl Explorer<'_> {
    /// A map update when the robot has moved or turned enough, or the period has passed.
    pub(super) fn sense(&mut self) {
        let cfg = self.cfg;
        let odo_pose = self.sim.odometry();
        let raw = self.last_odometry.between(&odo_pose);
        self.last_odometry = odo_pose;
        let delta = if cfg.localization == Localization::Slam && cfg.calibrate_odometry {
            self.calibration.apply(&raw)
        } else {
            raw
        };
        let prior = self.estimate.compose(&delta);
        self.estimate = prior;
        let moved = self.last_update_pose.between(&prior);
        let due = moved.position().norm() >= cfg.map_update_distance_m
            || moved.theta_rad.abs() >= cfg.map_update_angle_rad
            || self.sim.time_s() - self.last_update_time_s >= cfg.map_update_period_s;
        if !due {
            return;
        }
        let scan = self.sim.scan();
        self.scans += 1;
        self.estimate = match cfg.localization {
            Localization::GroundTruth => self.sim.true_pose(),
            Localization::Odometry => prior,
            Localization::Slam => self.slam_pose(&prior, &moved, &odo_pose, &scan),
        };
        let stats = self.map.insert_scan(&self.estimate, &scan, &cfg.log_odds);
        self.known_cells += stats.cells_discovered;
        let flips = self.map.take_occupied_flips();
        self.walls_changed |= !flips.is_empty();
        let mut distance_changes = std::mem::take(&mut self.distance_changes);
        distance_changes.clear();
        self.obstacles
            .update_reporting(&self.map.occupancy, &flips, &mut distance_changes);
        let free_changes = self.map.take_free_changes();
        // (The layout gains too: the layout they are computed with changes less often than the
        // map, and clears them when it does.)
        for &i in flips.iter().chain(free_changes.iter().map(|(i, _)| i)) {
            self.gains.touch(i, self.scans);
        }
        self.frontiers.update(
            &self.map.occupancy,
            flips
                .iter()
                .chain(free_changes.iter().map(|(i, _)| i))
                .copied(),
        );
        self.mark_planning_cells(&flips, &distance_changes, &free_changes);
        self.distance_changes = distance_changes;
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
        let map_to_world = MapToWorld::new(&self.estimate, &self.sim.true_pose());
        self.credit_explored(&fresh, &map_to_world);
        self.fresh_known = fresh;
        self.mark_travelled(self.last_update_pose.position(), self.estimate.position());
        self.last_update_pose = self.estimate;
        self.update_odometry = odo_pose;
        self.last_update_time_s = self.sim.time_s();
        self.trajectory.push(self.sim.true_pose());
        self.estimated_trajectory.push(self.estimate);
    }

    /// The pose estimate from scan matching `scan` at the `prior`, trusting odometry in
    /// proportion to the motion `moved` since the last map update; `odo_pose` is the raw
    /// odometry now (for the calibration). The prior when the match is not accepted.
    fn slam_pose(
        &mut self,
        prior: &Pose,
        moved: &Pose,
        odo_pose: &Pose,
        scan: &crate::scan::Scan,
    ) -> Pose {
        let cfg = self.cfg;
        // Trust odometry in proportion to the motion since the last match: its error is
        // proportional (at most ~1 % and 2 deg/rad, and much less once calibrated), so
        // only small corrections are plausible and large ones are mismatches (e.g. along
        // a featureless corridor). A prior as tight as the odometry's error matters: each
        // match is made against a map built from the previous few scans, so a matcher
        // noisier than odometry makes the estimate random-walk (0.3 m after 15 m, bent
        // maps and doubled walls). Driving straight does not change the odometry's
        // heading at all, so the heading is then nearly fixed. Once calibrated, the
        // odometry's heading is off by the residual scale error times the turn (the
        // calibrated heading scale is within ~0.03 % of the true one on the bench), far
        // less than a match's own heading noise: a looser heading prior let that noise
        // random-walk the heading by degrees around the ring corridors of the paper set
        // (maps bent until walls doubled; see PRIOR_SIGMA_THETA_*).
        let d = moved.position().norm();
        let a = moved.theta_rad.abs();
        let base = &cfg.scan_match;
        let odo = &cfg.sim.odometry;
        let calibrated = self.calibration.calibrated();
        let (k_xy, k_theta) = if cfg.calibrate_odometry {
            (
                if calibrated[0] {
                    0.005
                } else {
                    odo.max_translation_error
                },
                if calibrated[2] {
                    PRIOR_SIGMA_THETA_PER_RAD_CALIBRATED
                } else {
                    odo.max_rotation_error
                },
            )
        } else {
            (odo.max_translation_error, odo.max_rotation_error)
        };
        let mc = ScanMatchConfig {
            prior_sigma_xy_m: base.prior_sigma_xy_m.min(0.001 + k_xy * d),
            prior_sigma_theta_rad: base
                .prior_sigma_theta_rad
                .min(PRIOR_SIGMA_THETA_BASE_RAD + k_theta * a),
            max_correction_m: base.max_correction_m.min(0.05 + 0.1 * d),
            max_correction_rad: base.max_correction_rad.min(0.005 + 0.05 * a),
            search_xy_m: base.search_xy_m.min(0.05),
            search_theta_rad: base.search_theta_rad.min(1.5f64.to_radians()),
            // Few points near the map (facing unknown space) constrain the heading
            // poorly: odometry is better then.
            min_points: base.min_points.max(80),
            ..*base
        };
        let m = match_scan(&self.obstacles, &self.map, prior, scan, &mc);
        if m.accepted {
            self.matches_accepted += 1;
            self.calibration.observe(
                &self.update_odometry.between(odo_pose),
                &self.last_update_pose.between(&m.pose),
            );
            m.pose
        } else {
            *prior
        }
    }

    /// Marks the map cells on the segment `from`-`to` (world) travelled. They count only when
    /// planning the way the robot came (`Planning::Travelled`), so only that level's grids
    /// (in use or kept) have the new ones' planning cells marked for recomputing.
    pub(super) fn mark_travelled(&mut self, from: Vec2, to: Vec2) {
        let frame = self.map.frame;
        let mut new = Vec::new();
        let travelled = &mut self.travelled.data;
        walk_segment(
            grid_from_world(&frame, from),
            grid_from_world(&frame, to),
            |c| {
                if let Some(i) = frame.index(c) {
                    if !travelled[i] {
                        travelled[i] = true;
                        new.push((i as u32, true));
                    }
                }
                true
            },
        );
        if !new.is_empty() {
            self.mark_planning_cells_at(new.iter().map(|&(i, _)| i), |level| {
                level == Planning::Travelled
            });
        }
    }
}
