//! Driving: the goal while driving, the plans, the way home, waiting for charged compute.

use crate::explore::explorer::{Explorer, Goal};
use crate::explore::follow::{Command, PathFollower};
use crate::explore::navigation::{seen, Plan, Planning, STILL_FACTOR, STILL_RADIUS_M};
use crate::explore::policy::CandidateView;
use crate::frontier::detect::is_frontier_cell;
use crate::geom::{Pose, Vec2};
use crate::grid::Cell;
use crate::plan::inflate::Traversability;

/// In a team: a teammate whose estimated centre is within two radii and this much of the
/// robot's holds it up (m), and the most a robot waits so per goal (s).
pub(crate) const TEAM_BESIDE_M: f64 = 0.6;
pub(crate) const TEAM_WAIT_MAX_S: f64 = 60.0;

impl Explorer {
    pub(crate) fn needs_decision(&mut self) -> bool {
        let cfg = &*self.cfg;
        let now = self.now_s;
        let Some(goal) = &mut self.goal else {
            return true;
        };
        // Whatever the goals, a robot that has not moved for long is stuck (e.g. alternating
        // between goals it cannot approach, each new one restarting the progress timeout):
        // abandon the current goal.
        let position = self.localizer.estimate().position();
        // In a team, a teammate's body beside the robot holds it up: its progress clocks wait
        // (for at most `TEAM_WAIT_MAX_S` per goal, so that two robots holding each other up in
        // a doorway give up in the end).
        let dt = now - goal.checked_s;
        goal.checked_s = now;
        let beside = cfg.sim.robot.radius_m * 2.0 + TEAM_BESIDE_M;
        if goal.waited_s < TEAM_WAIT_MAX_S
            && self
                .mates
                .iter()
                .any(|m| (m.pose.position() - position).norm() <= beside)
        {
            goal.waited_s += dt;
            goal.best_distance_at_s += dt;
            self.still_since_s += dt;
        }
        if (position - self.still_at).norm() > STILL_RADIUS_M {
            self.still_at = position;
            self.still_since_s = now;
        } else if now - self.still_since_s > STILL_FACTOR * cfg.progress_timeout_s {
            self.blacklist.give_up(
                self.map.grid.frame.world_from_cell(goal.candidate),
                cfg.blacklist_radius_m,
            );
            self.goal = None;
            self.still_since_s = now;
            return true;
        }
        if goal.arrived {
            // Turning toward the frontier; done when facing it.
            let to = look_vector(goal, &self.localizer.estimate(), cfg.robust_frontiers);
            let err =
                crate::geom::wrap_angle(to.y.atan2(to.x) - self.localizer.estimate().theta_rad);
            if err.abs() > 0.15 && to.norm() > 0.05 && now - goal.best_distance_at_s < 10.0 {
                return false;
            }
            self.last_reached = Some(self.map.grid.frame.world_from_cell(goal.candidate));
            return true;
        }
        // Periodically, once the map shows something new: without new information the choice
        // would be the same (see `redecide_min_growth_m2`).
        let grown_m2 = self.map.known_cells.saturating_sub(goal.known_cells_at) as f64
            * self.map.grid.frame.cell_area_m2();
        if now - goal.decided_at_s >= cfg.redecide_period_s
            && grown_m2 >= cfg.redecide_min_growth_m2
        {
            return true;
        }
        // The goal's frontier has (mostly) disappeared: nothing left to see there.
        let still = goal
            .frontier
            .iter()
            .filter(|c| is_frontier_cell(&self.map.grid.occupancy, **c))
            .count();
        if still * 5 < goal.frontier.len() {
            return true;
        }
        // No progress along the path for too long: abandon the goal. (The length of the path
        // left, not the straight line to the goal: a path around a wall first leads away.)
        let d = self
            .follower
            .remaining_length_m(self.localizer.estimate().position());
        if d < goal.best_distance_m - 0.1 {
            goal.best_distance_m = d;
            goal.best_distance_at_s = now;
        } else if now - goal.best_distance_at_s > cfg.progress_timeout_s {
            let p = self.map.grid.frame.world_from_cell(goal.candidate);
            self.blacklist.give_up(p, cfg.blacklist_radius_m);
            self.goal = None;
            return true;
        }
        // The map now shows an obstacle on the path: plan the path again (the goal is kept, and
        // so is the time of the last progress), or choose another goal if it cannot be reached.
        let to = goal.cell;
        if self.nav.take_walls_changed() && self.path_blocked() {
            let Some(wps) = self.path_to(to) else {
                return true;
            };
            self.follower = PathFollower::from(self.localizer.estimate().position(), wps);
            let d = self
                .follower
                .remaining_length_m(self.localizer.estimate().position());
            if let Some(goal) = &mut self.goal {
                goal.best_distance_m = d;
            }
        }
        false
    }

    /// Whether the path being followed crosses a planning cell the map now shows impassable
    /// ([`Navigator::path_blocked`]).
    fn path_blocked(&mut self) -> bool {
        let robot = self.localizer.estimate().position();
        let seen = seen(&self.map.grid, &self.map.obstacles);
        self.nav.path_blocked(seen, &self.follower, robot)
    }

    /// Waypoints of a path from the robot to map cell `c` ([`Navigator::path_to`]).
    pub(crate) fn path_to(&mut self, c: Cell) -> Option<Vec<Vec2>> {
        let robot = self.localizer.estimate().position();
        self.nav
            .path_to(seen(&self.map.grid, &self.map.obstacles), robot, c)
    }

    /// Path costs from the robot to `targets` ([`Navigator::plan`]).
    pub(crate) fn plan(&mut self, targets: &[Cell]) -> Plan {
        let robot = self.localizer.estimate().position();
        self.nav.plan(
            seen(&self.map.grid, &self.map.obstacles),
            robot,
            targets,
            0.0,
        )
    }

    /// [`Self::plan`] bounded as the settings ask (`ExploreConfig::distance_bound_m`; a
    /// built-in strategy only: a strategy of the caller's is asked once per decision).
    pub(crate) fn plan_bounded(&mut self, targets: &[Cell]) -> Plan {
        let robot = self.localizer.estimate().position();
        let bound_m = if self.caller_decides {
            0.0
        } else {
            self.cfg.distance_bound_m
        };
        self.nav.plan(
            seen(&self.map.grid, &self.map.obstacles),
            robot,
            targets,
            bound_m,
        )
    }

    /// Path costs from the robot to every reachable cell ([`Navigator::plan_all`]).
    pub(crate) fn plan_all(&mut self) -> Plan {
        let robot = self.localizer.estimate().position();
        self.nav
            .plan_all(seen(&self.map.grid, &self.map.obstacles), robot)
    }

    /// Waypoints of the path to map cell `c` found with `plan` ([`Navigator::waypoints_to`]).
    pub(crate) fn waypoints_to(&mut self, plan: &Plan, c: Cell) -> Option<Vec<Vec2>> {
        self.nav.waypoints_to(plan, c)
    }

    /// The planned path lengths between the goals of `views` ([`Navigator::paths_between`]).
    pub(crate) fn paths_between(&self, views: &[CandidateView]) -> Vec<f64> {
        self.nav.paths_between(&self.map.grid, views)
    }

    /// The planned path lengths from the mates' estimated positions to the goals of `views`
    /// ([`Navigator::paths_from`]).
    pub(crate) fn mate_paths(&self, views: &[CandidateView]) -> Vec<f64> {
        let from: Vec<crate::geom::Vec2> = self.mates.iter().map(|m| m.pose.position()).collect();
        self.nav.paths_from(&self.map.grid, &from, views)
    }

    /// Plans at `level` from now on ([`Navigator::set_planning`]).
    pub(crate) fn set_planning(&mut self, level: Planning) {
        self.nav.set_planning(level);
    }

    /// Where the robot's centre may be at the planning level in use.
    pub(crate) fn traversability(&self) -> Traversability<'_> {
        self.nav
            .traversability(seen(&self.map.grid, &self.map.obstacles))
    }

    /// Marks the map cells on the segment `from`-`to` (world) travelled
    /// ([`Navigator::mark_travelled`]).
    pub(crate) fn mark_travelled(&mut self, from: Vec2, to: Vec2) {
        self.nav.mark_travelled(self.map.grid.frame, from, to);
    }

    /// The command of the robot for the next period, `(v_mps, w_radps)`: along the path to the
    /// goal, or turning toward the unknown at the goal reached.
    pub(crate) fn drive(&mut self) -> (f64, f64) {
        let cfg = &*self.cfg;
        if let Some(goal) = self.goal.as_ref().filter(|g| g.arrived) {
            let to = look_vector(goal, &self.localizer.estimate(), cfg.robust_frontiers);
            let err =
                crate::geom::wrap_angle(to.y.atan2(to.x) - self.localizer.estimate().theta_rad);
            let w = (cfg.follow.heading_gain * err).clamp(
                -cfg.sim.robot.max_turn_rate_radps,
                cfg.sim.robot.max_turn_rate_radps,
            );
            return (0.0, w);
        }
        match self.follower.command(
            &self.localizer.estimate(),
            &cfg.follow,
            cfg.sim.robot.max_speed_mps,
            cfg.sim.robot.max_turn_rate_radps,
        ) {
            Command::Drive { v_mps, w_radps } => (v_mps, w_radps),
            Command::Arrived => {
                // Goal reached: turn toward the unknown space behind the frontier.
                if let Some(goal) = &mut self.goal {
                    goal.arrived = true;
                    goal.best_distance_at_s = self.now_s;
                }
                (0.0, 0.0)
            }
        }
    }

    /// Sets the path home (the first pose of the trajectory); false when there is none.
    pub(crate) fn head_home(&mut self) -> bool {
        let frame = self.map.grid.frame;
        let start = self
            .trajectory
            .first()
            .copied()
            .unwrap_or(self.localizer.estimate());
        let home = frame.cell_from_world(start.position());
        let plan = self.plan(&[home]);
        let Some(wps) = self.waypoints_to(&plan, home) else {
            return false;
        };
        self.follower = PathFollower::new(wps);
        true
    }

    /// The command of the robot for the next period on its way home, `None` once there.
    pub(crate) fn drive_home(&mut self) -> Option<(f64, f64)> {
        let cfg = &*self.cfg;
        match self.follower.command(
            &self.localizer.estimate(),
            &cfg.follow,
            cfg.sim.robot.max_speed_mps,
            cfg.sim.robot.max_turn_rate_radps,
        ) {
            Command::Arrived => None,
            Command::Drive { v_mps, w_radps } => Some((v_mps, w_radps)),
        }
    }
}

/// What the robot faces at a goal it reached: the unknown space behind the frontier, or with
/// `robust` the frontier's outward side when that space is centred on the robot itself (within
/// 0.3 m: a frontier through the robot, whose unknown lies on both sides or right behind it).
pub(crate) fn look_vector(goal: &Goal, estimate: &Pose, robust: bool) -> Vec2 {
    let to = goal.look_at - estimate.position();
    match goal.look_dir {
        Some(d) if robust && to.norm() <= 0.3 => d,
        _ => to,
    }
}
