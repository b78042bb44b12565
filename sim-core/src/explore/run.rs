//! What a run produces: its end, its progress curve, its decisions, its map's quality, its
//! [`RunResult`].

use crate::geom::{Pose, Vec2};
use crate::grid::OccupancyGrid;

/// Why a run ended. Every end is one of these classes, so that a report never averages a run
/// that stopped short as if it were complete.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EndReason {
    /// No frontier left on the map: exploration complete.
    Complete,
    /// The strategy's early-stopping rule ended exploration with frontiers left.
    EarlyStop,
    /// The simulated time limit was reached first.
    TimeLimit,
    /// Frontiers are left that the robot could plan a path to, but every goal toward them was
    /// given up for want of progress (the robot could not get there, or got there without
    /// seeing into them).
    Stuck,
    /// Frontiers are left, but no path leads to any of them (seen through a gap the robot
    /// cannot pass, or beyond the map's edge).
    Unreachable,
}

impl EndReason {
    /// Every class, in the order reports list them.
    pub const ALL: [EndReason; 5] = [
        EndReason::Complete,
        EndReason::EarlyStop,
        EndReason::TimeLimit,
        EndReason::Stuck,
        EndReason::Unreachable,
    ];

    /// The name in summaries and reports.
    pub fn as_str(self) -> &'static str {
        match self {
            EndReason::Complete => "complete",
            EndReason::EarlyStop => "early stop",
            EndReason::TimeLimit => "time limit",
            EndReason::Stuck => "stuck",
            EndReason::Unreachable => "frontiers unreachable",
        }
    }

    /// The class of a name [`EndReason::as_str`] gives (`None`: not a class's name).
    pub fn from_name(name: &str) -> Option<EndReason> {
        EndReason::ALL.into_iter().find(|r| r.as_str() == name)
    }

    /// Whether the run ended because it had explored everything it could see (complete) or
    /// by the strategy's own choice (early stop), as opposed to being cut short.
    pub fn is_normal(self) -> bool {
        matches!(self, EndReason::Complete | EndReason::EarlyStop)
    }
}

impl std::fmt::Display for EndReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One point of the exploration curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProgressSample {
    pub time_s: f64,
    pub explored_area_m2: f64,
    pub explored_fraction: f64,
}

/// The map when the explored fraction first reached `fraction`.
#[derive(Debug, Clone, PartialEq)]
pub struct MapSnapshot {
    pub fraction: f64,
    pub time_s: f64,
    pub map: OccupancyGrid,
}

/// One decision of the strategy.
#[derive(Debug, Clone, PartialEq)]
pub struct Decision {
    pub time_s: f64,
    /// The robot's estimated pose when deciding.
    pub pose: Pose,
    /// The chosen candidate's world position.
    pub goal: Vec2,
    pub candidates: usize,
    pub gain_m2: f64,
    pub distance_m: f64,
}

/// How well the final map matches the building (cells of the map grid).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapQuality {
    /// Map-free cells that are free in the building.
    pub free_precision: f64,
    /// Map-occupied cells within one cell of solid space in the building (doubled walls and
    /// drift lower this).
    pub occupied_precision: f64,
    /// The same after the best small rigid motion of the map (rotation about the start):
    /// a map that is consistent but turned as a whole by an early heading error scores high
    /// here, a doubled or bent one does not.
    pub occupied_precision_aligned: f64,
}

/// Everything a run produced.
#[derive(Debug, Clone, PartialEq)]
pub struct RunResult {
    pub seed: u64,
    pub start: Pose,
    /// Ended by the strategy's early-stopping rule.
    pub stopped_early: bool,
    /// Layouts reconstructed during the run.
    pub layouts_computed: u64,
    /// Layout compute time charged to simulated time (s; 0 unless charged).
    pub layout_compute_s: f64,
    /// A [`Policy`]'s compute time charged to simulated time (s; 0 unless charged).
    pub strategy_compute_s: f64,
    /// Ground-truth rooms the robot never entered (when the building has rooms).
    pub rooms_never_entered: Option<usize>,
    /// Ground-truth rooms of which less than half the reachable free area was explored (`None`
    /// without rooms): the rooms an early stop left out, as the paper's "missing one room". A
    /// room seen from its door counts as explored although it was never entered.
    pub rooms_unexplored: Option<usize>,
    pub end_reason: EndReason,
    /// Frontier cells left on the map at the end that the robot had not looked into (0 when
    /// complete; counted only for runs that ran out of goals, else 0).
    pub frontier_cells_left: usize,
    /// Simulated time at the end of exploration (before any return home).
    pub exploration_time_s: f64,
    /// Simulated time at the very end.
    pub total_time_s: f64,
    pub explored_area_m2: f64,
    /// The explorable free area: free space connected to the start that the laser can see
    /// from where the robot's body fits (the denominator of the explored fraction; see
    /// [`crate::building::explorable_free`]).
    pub free_area_m2: f64,
    /// Free area connected to the start (through gaps of any width) that is not explorable:
    /// behind openings narrower than the robot, out of the laser's sight.
    pub unexplorable_free_m2: f64,
    pub explored_fraction: f64,
    pub path_length_m: f64,
    pub decisions: Vec<Decision>,
    pub blacklisted_goals: usize,
    pub progress: Vec<ProgressSample>,
    /// True poses, one per map update.
    pub trajectory: Vec<Pose>,
    /// Estimated poses, one per map update.
    pub estimated_trajectory: Vec<Pose>,
    pub map: OccupancyGrid,
    pub map_quality: MapQuality,
    pub scans: u64,
    pub scan_matches_accepted: u64,
    /// Path searches (Dijkstra runs) made while deciding.
    pub plans: u64,
    /// Maps kept at the configured explored fractions.
    pub snapshots: Vec<MapSnapshot>,
}

impl RunResult {
    /// A fingerprint of the whole run (SHA-256 of every true and estimated pose, decision,
    /// progress sample, the final map's cells and its quality; first 8 bytes, hex): equal for
    /// bit-identical runs. A change made only for speed must leave it unchanged
    /// (`tests/fingerprints.rs` checks a few reference runs on every CI run).
    pub fn fingerprint(&self) -> String {
        use sha2::{Digest, Sha256};
        let mut h = Sha256::new();
        let mut eat = |vs: &[f64]| vs.iter().for_each(|v| h.update(v.to_le_bytes()));
        for p in self.trajectory.iter().chain(&self.estimated_trajectory) {
            eat(&[p.x_m, p.y_m, p.theta_rad]);
        }
        for d in &self.decisions {
            let (g, p) = (d.goal, d.pose);
            eat(&[
                d.time_s,
                p.x_m,
                p.y_m,
                p.theta_rad,
                g.x,
                g.y,
                d.gain_m2,
                d.distance_m,
            ]);
            eat(&[d.candidates as f64]);
        }
        for s in &self.progress {
            eat(&[s.time_s, s.explored_area_m2]);
        }
        eat(&[
            self.explored_fraction,
            self.path_length_m,
            self.map_quality.occupied_precision,
            self.map_quality.occupied_precision_aligned,
            self.map_quality.free_precision,
        ]);
        h.update(self.map.data.iter().map(|c| *c as u8).collect::<Vec<u8>>());
        h.finalize()[..8]
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect()
    }
}
