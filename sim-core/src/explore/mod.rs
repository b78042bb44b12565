//! The exploration loop: sense, map (with the chosen localization), decide among frontier
//! candidates with the paper's utility, drive, until no candidate is left.
//!
//! Decisions are re-taken when the goal is reached, when the goal's frontier has (mostly)
//! disappeared, and after `redecide_period_s` once the map has grown by
//! `redecide_min_growth_m2`; a path the map shows blocked is planned again to the same goal.
//! Unreachable goals are blacklisted with a radius; a goal along whose path the robot makes no
//! progress for `progress_timeout_s` (or near which it stands still for three times that) is
//! given up, blacklisted until the run would otherwise end: those goals then get another chance
//! (once per square metre of new map), so a run never hangs and a moment of bad luck does not
//! end it early.
//!
//! Planning uses two grids, both stored padded by one blocked cell and searched in place
//! (`plan::coarse`): the distances to every candidate come from one Dijkstra on the 0.2 m grid,
//! the path to the chosen candidate from A* on the 0.1 m grid inside a corridor around the coarse
//! path. A planning cell is passable when any of its map cells is traversable; only the cells whose
//! map cells or obstacle distances changed since the last plan are recomputed. A candidate with no
//! fine path is passed over for that decision. When no frontier's candidate can be reached, the
//! candidates move to their frontiers' nearest reachable cells (`Explorer::reachable_candidates`;
//! at every decision with `candidate_from_reachable_part`), and if none of those can be reached
//! either, the decision is made again with paths planned without the safety margin, and then
//! once more through the free map cells the robot has travelled as well (`Planning`, set with
//! `Explorer::set_planning` for that decision only; every planning cell is recomputed when it
//! switches). Every run ends in one [`EndReason`] (`Explorer::classify_end`).
//!
//! The explored area credits, whenever cells become known, the building cells around where the
//! sensor saw them whose centres, moved into the map by the pose error of that moment, fall in a
//! known map cell (the map is drawn at the estimated pose), so a consistent but rotated map is not
//! counted as unexplored; with ground-truth poses this is the plain cell-by-cell comparison.
//! [`explore_charged`] takes a caller's cost hook that times each layout computation
//! (`--charge-compute`): the clock stays outside sim-core, and only such runs depend on the
//! machine. The `layout-truth` oracle's layout is the building's true rooms moved into the map
//! frame by the current pose error (`true_layout`), rasterised by `LayoutRaster::exact`; it is the
//! only strategy whose decisions read ground truth.
//!
//! These incremental structures (frontier tracker, gain cache, planning cells) change no result:
//! runs are bit-identical to full recomputation.

mod calibration;
mod follow;
mod gain_cache;
pub mod policy;
pub mod strategy;

pub use crate::utility::UtilityDistance;
pub use follow::{Command, FollowConfig, PathFollower};
pub use policy::{
    CandidateView, DecisionView, Needs, Policy, Reply, RunEnd, MAX_UNREACHABLE_GOALS,
};
pub use strategy::{EarlyStop, GainModel, Strategy};

use self::calibration::OdometryCalibration;
use self::gain_cache::GainCache;
use crate::building::Building;
use crate::frontier::blacklist::Blacklist;
use crate::frontier::detect::{
    frontiers_where, is_frontier_cell, Frontier, FrontierConfig, FrontierTracker,
};
use crate::gain::information_gain;
use crate::geom::{Pose, Vec2};
use crate::grid::{Bitmap, Cell, GridFrame, Occupancy, OccupancyGrid};
use crate::layout::reconstruct_layout;
use crate::layout_gain::{gap_closed_information_gain, layout_information_gain, LayoutRaster};
use crate::mapping::distance_field::ObstacleDistance;
use crate::mapping::log_odds::{LogOddsConfig, LogOddsMap};
use crate::mapping::ray::{grid_from_world, walk_segment};
use crate::mapping::scan_match::{match_scan, ScanMatchConfig};
use crate::plan::coarse::CoarseCosts;
use crate::plan::dijkstra::{dijkstra_padded, AStar, CostField};
use crate::plan::inflate::{nearest_by, Traversability};
use crate::plan::waypoints::waypoints_by;
use crate::sim::{SimConfig, Simulator};
use crate::utility::CandidateScore;

/// Where the map's poses come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Localization {
    /// The simulator's true pose (an upper bound on map quality).
    GroundTruth,
    /// Dead reckoning with the run's odometry error (drifts).
    Odometry,
    /// Odometry corrected by scan-to-map matching (the default).
    Slam,
}

impl Localization {
    pub fn as_str(self) -> &'static str {
        match self {
            Localization::GroundTruth => "ground-truth",
            Localization::Odometry => "odometry",
            Localization::Slam => "slam",
        }
    }
}

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

    /// Whether the run ended because it had explored everything it could see (complete) or
    /// by the strategy's own choice (early stop), as opposed to being cut short.
    pub fn is_normal(self) -> bool {
        matches!(self, EndReason::Complete | EndReason::EarlyStop)
    }
}

/// Everything that shapes a run besides the building, the start and the seed.
#[derive(Debug, Clone, PartialEq)]
pub struct ExploreConfig {
    pub sim: SimConfig,
    /// How candidates are scored and when to stop early.
    pub strategy: Strategy,
    /// Parameters of the layout reconstruction (for layout-informed strategies).
    pub layout: crate::layout::LayoutConfig,
    pub localization: Localization,
    pub map_resolution_m: f64,
    pub log_odds: LogOddsConfig,
    pub scan_match: ScanMatchConfig,
    /// With SLAM: learn the odometry's proportional error from the scan matches and correct it.
    pub calibrate_odometry: bool,
    /// Weight of distance against information gain in the utility (paper: 0.5).
    pub alpha: f64,
    /// In the utility, a candidate's gain counts as at least this much (m2); 0 = the paper's
    /// utility. See [`crate::utility::with_gain_floor`].
    pub gain_floor_m2: f64,
    /// What the utility's `D(p)` measures: the planned path's length (default) or, as in the
    /// paper, the straight line from the robot to the candidate.
    pub utility_distance: UtilityDistance,
    /// Frontiers shorter than this are ignored.
    pub min_frontier_m: f64,
    /// Frontier cells closer than this to an observed obstacle are ignored (m; 0 = none, the
    /// default). ROS explorers commonly look for frontiers in the inflated map the planner uses,
    /// where cells near walls are not free (nav2d, the navigator of the paper's authors' later
    /// exploration code, calls a cell free at more than 0.4 m from a wall with that code's
    /// settings: inflation radius 1 m, lethal cost 60 %): they never see the small unknown wedges along walls that a 180° laser leaves
    /// beside every door, which take much of a run's last stage here. A clearance beyond the
    /// reach of the obstacle distance field (robot radius + safety margin + 0.2 m, 0.45 m by
    /// default) widens that field, which the scan matcher also reads.
    pub frontier_clearance_m: f64,
    /// When a frontier's candidate (its middle cell, or a traversable cell within 0.5 m of it)
    /// cannot be reached, use the reachable traversable cell of the frontier nearest to it
    /// instead of passing the frontier over (false = the paper's rule). A frontier seen through
    /// a door at a slant reaches into the room along a strip too narrow to drive, so its middle
    /// can lie where the robot cannot go while its other end is at the door.
    pub candidate_from_reachable_part: bool,
    /// Frontiers the robot stands in are resolved as real explorers do (on by default since
    /// 0.4; off: the paper's rule, setting `paper_frontiers`): a frontier whose middle cell was blacklisted
    /// (reached and looked at with the frontier still there, given up, or unreachable) keeps its
    /// other cells, its candidate moving to the nearest of them outside every blacklisted
    /// radius; and at a goal whose unknown side surrounds the robot (the first scan's boundary,
    /// one chain through the robot whose unknown lies right behind it), the robot turns to face
    /// the frontier's outward side instead of taking the goal as seen; and before an early stop
    /// ends the run, frontiers whose goal cannot be reached get their reachable part and the plan
    /// without the safety margin, so that they weigh in the rule.
    pub robust_frontiers: bool,
    /// Re-decide this often while driving to a goal, once the map has grown by at least
    /// `redecide_min_growth_m2` since the last decision.
    pub redecide_period_s: f64,
    /// Without new information a periodic re-decision picks the same goal: on the 2000 m2
    /// bench building (seeds 1 and 3) 552 of 667 periodic re-decisions came after less than
    /// 0.5 m2 of new map and 30 of those 552 changed the goal. Skipping them saves the work of
    /// 40 % of all decisions, and lets the progress timeout run (re-deciding restarts it).
    pub redecide_min_growth_m2: f64,
    /// Clearance added to the robot radius when planning.
    pub safety_margin_m: f64,
    /// Radius around an unreachable or abandoned goal within which candidates are skipped.
    pub blacklist_radius_m: f64,
    /// A goal toward which the robot gets no closer for this long is abandoned.
    pub progress_timeout_s: f64,
    /// The run stops here if exploration has not finished.
    pub time_limit_s: f64,
    /// Drive back to the start after exploring (time counted).
    pub return_home: bool,
    /// A map update happens after this much motion, or `map_update_period_s`, whichever first.
    /// 0.25 m / 0.25 rad (Hector SLAM's defaults are 0.4 m / 0.9 rad, GMapping's 1 m / 0.5 rad):
    /// on the 2000 m2 bench building, updating every 0.1 m / 0.1 rad instead took 1.45x the
    /// time and gave no better maps. Every 0.5 m / 0.5 rad was 1.4x faster on the 22 school-map
    /// runs (11 maps x seeds 1-2, `baseline`) and explored as much, but drew worse maps (aligned
    /// wall precision 0.906 against 0.937 on average, lower on 17 of 22 runs).
    pub map_update_distance_m: f64,
    pub map_update_angle_rad: f64,
    pub map_update_period_s: f64,
    /// Period of the progress curve.
    pub progress_period_s: f64,
    pub follow: FollowConfig,
    /// Keep a copy of the map when the explored fraction first reaches each of these values
    /// (ascending), e.g. to draw the layout at 20, 40, 60, 80 and 90 % as the paper's Fig. 3.
    pub snapshot_fractions: Vec<f64>,
}

impl Default for ExploreConfig {
    fn default() -> Self {
        Self {
            sim: SimConfig::default(),
            localization: Localization::Slam,
            map_resolution_m: 0.05,
            log_odds: LogOddsConfig::default(),
            scan_match: ScanMatchConfig::default(),
            calibrate_odometry: true,
            strategy: Strategy::baseline(),
            layout: crate::layout::LayoutConfig::default(),
            alpha: 0.5,
            gain_floor_m2: 0.0,
            utility_distance: UtilityDistance::Path,
            min_frontier_m: 0.5,
            frontier_clearance_m: 0.0,
            candidate_from_reachable_part: false,
            robust_frontiers: true,
            redecide_period_s: 10.0,
            redecide_min_growth_m2: 0.5,
            safety_margin_m: 0.05,
            blacklist_radius_m: 0.5,
            progress_timeout_s: 20.0,
            time_limit_s: 4.0 * 3600.0,
            return_home: false,
            map_update_distance_m: 0.25,
            map_update_angle_rad: 0.25,
            map_update_period_s: 1.0,
            progress_period_s: 1.0,
            follow: FollowConfig::default(),
            snapshot_fractions: Vec::new(),
        }
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

/// Heading prior of a scan match (standard deviation, rad) for any update, on top of the part
/// proportional to the turn since the last one. 0.001 until 0.3.0: on the paper set (300 runs)
/// the median aligned wall precision was 0.89 and the worst run's map 0.31, the heading having
/// random-walked by up to 7 degrees; with 0.0002 and [`PRIOR_SIGMA_THETA_PER_RAD_CALIBRATED`]
/// the median is 0.94 and the worst 0.79 (README, "Map quality").
const PRIOR_SIGMA_THETA_BASE_RAD: f64 = 0.0002;

/// Heading prior per radian turned once the odometry's heading scale is calibrated (0.01 until
/// 0.3.0).
const PRIOR_SIGMA_THETA_PER_RAD_CALIBRATED: f64 = 0.003;

/// The mutable state of one exploration.
struct Explorer<'a> {
    cfg: &'a ExploreConfig,
    seed: u64,
    sim: Simulator,
    map: LogOddsMap,
    obstacles: ObstacleDistance,
    /// Explorable free space of the building on the map grid (ground truth for the explored
    /// area and the rooms left unexplored).
    truth: Bitmap,
    /// Free space connected to the start (ground truth for the map's quality).
    free: Bitmap,
    truth_cells: usize,
    /// Truth-free cells observed, kept incrementally. Observed means free or occupied in the
    /// map: a cell whose centre is free but which a wall surface crosses is rightly mapped
    /// occupied, and the boundary rows of every room would otherwise cap the fraction near 97 %.
    /// Building cells are credited through the map cells they were observed in: the map is drawn
    /// at the estimated pose, so a heading error made early (e.g. turning where the laser sees no
    /// wall) rotates everything mapped after it, and comparing map and building cell by cell
    /// would count a consistent but rotated map as unexplored far from the start. See
    /// [`Explorer::credit_explored`].
    explored_cells: usize,
    /// Map cells observed (free or occupied) so far.
    known: Bitmap,
    /// Building cells credited as observed (world frame).
    explored: Bitmap,
    estimate: Pose,
    last_odometry: Pose,
    /// Odometry reading at the last map update.
    update_odometry: Pose,
    calibration: OdometryCalibration,
    last_update_pose: Pose,
    last_update_time_s: f64,
    blacklist: Blacklist,
    /// The goal reached (and looked at) just before the current decision.
    last_reached: Option<Vec2>,
    follower: PathFollower,
    goal: Option<Goal>,
    decisions: Vec<Decision>,
    progress: Vec<ProgressSample>,
    trajectory: Vec<Pose>,
    estimated_trajectory: Vec<Pose>,
    scans: u64,
    matches_accepted: u64,
    plans: u64,
    gains: GainCache,
    /// The paper's room-bounded `I(p)` of candidates, for early stopping.
    room_gains: GainCache,
    next_progress_s: f64,
    /// Cells of the map that are known (free or occupied), counted from the map's own changes.
    known_cells: usize,
    layout: Option<LayoutState>,
    layouts_computed: u64,
    layout_cost: Option<LayoutCost<'a>>,
    /// Charged layout compute time the robot still has to wait for (s).
    compute_debt_s: f64,
    /// Layout compute time charged so far (s).
    layout_compute_s: f64,
    /// The decision rule in place of the strategy's own, if any, what it needs, how often it
    /// was asked, whether it said stop or failed, and its compute time charged so far (s).
    policy: PolicySlot<'a>,
    policy_needs: Needs,
    policy_decisions: usize,
    policy_failed: bool,
    strategy_compute_s: f64,
    /// Where the robot has stayed (within `STILL_RADIUS_M`) since `still_since_s`.
    still_at: Vec2,
    still_since_s: f64,
    /// For the switch strategy: the layout has been judged reliable.
    layout_trusted: bool,
    stopped_early: bool,
    start: Pose,
    snapshots: Vec<MapSnapshot>,
    /// Ground-truth room polygons (for the "rooms never entered" report, and the layout of the
    /// `layout-truth` oracle).
    rooms: Vec<crate::geom::Polygon>,
    /// The map's frontier cells, updated with each map update.
    frontiers: FrontierTracker,
    /// The planning grid, brought up to date before each plan from the planning cells whose
    /// map cells changed (occupancy or obstacle distance) since the last one.
    coarse: CoarseCosts,
    coarse_dirty: Vec<u32>,
    coarse_dirty_mark: Vec<bool>,
    /// How permissive path planning is (see `decide_planned`'s last resorts).
    planning: Planning,
    /// Map cells the robot's estimated centre passed through (the segments between its poses at
    /// map updates): its body fitted there, whatever the map shows now.
    travelled: Bitmap,
    /// The coarser grid the candidates' distances are searched on, updated with `coarse`.
    far: CoarseCosts,
    /// Whether a cell became or stopped being occupied since the path was last checked.
    walls_changed: bool,
    /// `known_cells` when goals given up were last given another chance (see `forgive`).
    forgiven_at: Option<usize>,
    /// Frontier cells left at the end that the robot had not looked into (see `classify_end`).
    frontier_cells_left: usize,
    /// The path search on `coarse`, and per cell of `far` whether it is in the corridor the
    /// search is confined to first (all false between searches).
    astar: AStar,
    corridor: Vec<bool>,
}

/// The last layout and what is needed to judge it.
struct LayoutState {
    raster: LayoutRaster,
    known_cells_at: usize,
    /// Cells unknown when the layout was made that it predicted inside a room.
    predicted_unknown: Vec<u32>,
}

struct Goal {
    /// Where the robot drives: the candidate, or the nearest traversable cell to it.
    cell: Cell,
    /// The frontier's candidate (its middle cell). Blacklisting applies to candidates, so it
    /// is recorded here: the goal cell may lie farther from it than the blacklist radius, and
    /// blacklisting the goal cell would then leave the candidate to be chosen again forever.
    candidate: Cell,
    /// Where the unknown space behind the frontier is: the robot faces it on arrival, so that its
    /// forward-looking laser sees it.
    look_at: Vec2,
    /// The frontier's outward side (unit vector from its cells to their unknown neighbours, on
    /// average): faced instead when `look_at` is where the robot stands (`robust_frontiers`).
    look_dir: Option<Vec2>,
    arrived: bool,
    /// Cells of the frontier it was chosen for.
    frontier: Vec<Cell>,
    decided_at_s: f64,
    /// `Explorer::known_cells` when decided.
    known_cells_at: usize,
    /// Shortest path length left seen so far, and when.
    best_distance_m: f64,
    best_distance_at_s: f64,
}

/// Runs one exploration. `on_progress` sees every progress sample as it is made (for a
/// progress bar); it must not affect the run. Layouts are computed "in the background" (no delay
/// to the robot), as in the paper; see [`explore_charged`] to charge their cost.
pub fn explore(
    building: &Building,
    start: Pose,
    cfg: &ExploreConfig,
    seed: u64,
    on_progress: &mut dyn FnMut(&ProgressSample),
) -> RunResult {
    explore_charged(building, start, cfg, seed, on_progress, None)
}

/// The margin (m) the map grid adds around a building's bounds on every side: 15 % of the
/// longer side, at least 1 m and at most 8 m. A map that turns as a whole (a heading error
/// made in a large room, before any wall came into view) reaches beyond the building's
/// bounds by about the turn times the distance from the start; cut at the grid's edge, it
/// would leave frontiers there that no path reaches.
pub fn map_margin_m(bounds: &crate::geom::Aabb) -> f64 {
    (0.15 * bounds.width_m().max(bounds.height_m())).clamp(1.0, 8.0)
}

/// The grid of a run's map and ground truth: the building's bounds plus [`map_margin_m`].
pub fn map_frame(bounds: &crate::geom::Aabb, resolution_m: f64) -> GridFrame {
    GridFrame::covering(bounds, resolution_m, map_margin_m(bounds))
}

/// A caller's measure of the layout's compute cost: it is given the computation, must run it
/// once, and returns the seconds to charge (e.g. the wall time it took).
pub type LayoutCost<'a> = &'a mut dyn FnMut(&mut dyn FnMut()) -> f64;

/// [`explore`], with the cost of every layout computation charged to simulated time when
/// `layout_cost` is given: the robot stands still (sensing) for the seconds it returns, right
/// after the decision that needed the layout. The core has no clock, so the caller measures;
/// a run charged with measured wall time depends on the machine and is no longer reproducible.
pub fn explore_charged<'a>(
    building: &Building,
    start: Pose,
    cfg: &'a ExploreConfig,
    seed: u64,
    on_progress: &mut dyn FnMut(&ProgressSample),
    layout_cost: Option<LayoutCost<'a>>,
) -> RunResult {
    let hooks = Hooks {
        layout_cost,
        policy: None,
    };
    explore_with(building, start, cfg, seed, on_progress, hooks)
}

/// What a caller can plug into a run besides its settings.
#[derive(Default)]
pub struct Hooks<'a> {
    /// Measures each layout computation, to charge its cost (see [`explore_charged`]).
    pub layout_cost: Option<LayoutCost<'a>>,
    /// Chooses the candidates in place of the configured strategy (whose gain model and early
    /// stop still apply: give it [`Strategy::baseline`] for the plain gains and no early stop).
    pub policy: Option<&'a mut dyn Policy>,
}

impl std::fmt::Debug for Hooks<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Hooks")
            .field("layout_cost", &self.layout_cost.is_some())
            .field("policy", &self.policy.as_ref().map(|p| p.needs()))
            .finish()
    }
}

/// [`explore`] with the caller's [`Hooks`].
pub fn explore_with<'a>(
    building: &Building,
    start: Pose,
    cfg: &'a ExploreConfig,
    seed: u64,
    on_progress: &mut dyn FnMut(&ProgressSample),
    hooks: Hooks<'a>,
) -> RunResult {
    let Hooks {
        layout_cost,
        policy,
    } = hooks;
    let policy = match policy {
        Some(p) => PolicySlot::External(p),
        None => PolicySlot::BuiltIn(strategy::BuiltInPolicy::new(
            cfg.strategy.early_stop,
            cfg.alpha,
            cfg.gain_floor_m2,
        )),
    };
    let policy_needs = match &policy {
        PolicySlot::External(p) => p.needs(),
        // The rule judges the paper's I(p) only when the strategy uses the layout.
        PolicySlot::BuiltIn(b) => Needs {
            layout_gain: b.needs().layout_gain && cfg.strategy.uses_layout(),
        },
    };
    let frame = map_frame(&building.bounds(), cfg.map_resolution_m);
    let free = building.reachable_free(frame, start.position());
    let truth = crate::building::explorable_free(
        &free,
        start.position(),
        cfg.sim.robot.radius_m + cfg.safety_margin_m,
        cfg.sim.laser.max_range_m,
    );
    let truth_cells = truth.count_true();
    let cap_cells =
        (((cfg.sim.robot.radius_m + cfg.safety_margin_m) / cfg.map_resolution_m).ceil() as u32 + 4)
            .max(8)
            .max((cfg.frontier_clearance_m / cfg.map_resolution_m).ceil() as u32 + 1);
    let sim = Simulator::new(building, start, &cfg.sim, seed);
    let ex = Explorer {
        cfg,
        seed,
        last_odometry: sim.odometry(),
        update_odometry: sim.odometry(),
        calibration: OdometryCalibration::new(
            cfg.sim.odometry.max_translation_error * 1.5,
            cfg.sim.odometry.max_rotation_error * 1.5,
        ),
        sim,
        map: LogOddsMap::new(frame),
        obstacles: ObstacleDistance::new(frame, cap_cells),
        truth,
        free,
        truth_cells,
        explored_cells: 0,
        known: Bitmap::filled(frame, false),
        explored: Bitmap::filled(frame, false),
        estimate: start,
        last_update_pose: start,
        last_update_time_s: f64::NEG_INFINITY,
        blacklist: Blacklist::new(),
        last_reached: None,
        follower: PathFollower::default(),
        goal: None,
        decisions: Vec::new(),
        progress: Vec::new(),
        trajectory: Vec::new(),
        estimated_trajectory: Vec::new(),
        scans: 0,
        matches_accepted: 0,
        plans: 0,
        gains: GainCache::new(frame),
        room_gains: GainCache::new(frame),
        next_progress_s: 0.0,
        known_cells: 0,
        layout: None,
        layouts_computed: 0,
        still_at: start.position(),
        still_since_s: 0.0,
        layout_cost,
        compute_debt_s: 0.0,
        layout_compute_s: 0.0,
        policy,
        policy_needs,
        policy_decisions: 0,
        policy_failed: false,
        strategy_compute_s: 0.0,
        layout_trusted: false,
        stopped_early: false,
        start,
        snapshots: Vec::new(),
        rooms: building.rooms.iter().map(|r| r.polygon.clone()).collect(),
        frontiers: FrontierTracker::default(),
        coarse: CoarseCosts::blocked(frame, PLAN_FACTOR),
        coarse_dirty: Vec::new(),
        coarse_dirty_mark: vec![false; CoarseCosts::blocked(frame, PLAN_FACTOR).len()],
        planning: Planning::WithMargin,
        travelled: Bitmap::filled(frame, false),
        far: CoarseCosts::blocked(frame, DISTANCE_FACTOR),
        walls_changed: false,
        forgiven_at: None,
        frontier_cells_left: 0,
        astar: AStar::default(),
        corridor: vec![false; CoarseCosts::blocked(frame, DISTANCE_FACTOR).len()],
    };
    ex.run(on_progress)
}

impl Explorer<'_> {
    fn run(mut self, on_progress: &mut dyn FnMut(&ProgressSample)) -> RunResult {
        let cfg = self.cfg;
        let end_reason;
        loop {
            self.sense();
            self.record_progress(on_progress);
            if self.sim.time_s() >= cfg.time_limit_s {
                end_reason = EndReason::TimeLimit;
                break;
            }
            if self.needs_decision() && !self.decide() && !(self.forgive() && self.decide()) {
                end_reason = if self.stopped_early {
                    EndReason::EarlyStop
                } else {
                    self.classify_end()
                };
                break;
            }
            self.wait_for_compute(on_progress);
            self.drive();
        }
        let exploration_time_s = self.sim.time_s();
        let end = RunEnd {
            reason: end_reason,
            exploration_time_s,
            explored_fraction: self.explored_fraction(),
            decisions: self.decisions.len(),
        };
        if !self.policy_failed {
            self.policy.get().end(&end);
        }
        if cfg.return_home && end_reason != EndReason::TimeLimit && !self.policy_failed {
            self.return_home();
        }
        self.finish(end_reason, exploration_time_s, on_progress)
    }

    /// Stands still, sensing, while charged layout compute time is due.
    fn wait_for_compute(&mut self, on_progress: &mut dyn FnMut(&ProgressSample)) {
        while self.compute_debt_s > 0.0 && self.sim.time_s() < self.cfg.time_limit_s {
            let t0 = self.sim.time_s();
            self.sim.idle();
            self.compute_debt_s -= self.sim.time_s() - t0;
            self.sense();
            self.record_progress(on_progress);
        }
        self.compute_debt_s = 0.0;
    }

    /// A map update when the robot has moved or turned enough, or the period has passed.
    fn sense(&mut self) {
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
            Localization::Slam => {
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
                let m = match_scan(&self.obstacles, &self.map, &prior, &scan, &mc);
                if m.accepted {
                    self.matches_accepted += 1;
                    self.calibration.observe(
                        &self.update_odometry.between(&odo_pose),
                        &self.last_update_pose.between(&m.pose),
                    );
                    m.pose
                } else {
                    prior
                }
            }
        };
        let stats = self.map.insert_scan(&self.estimate, &scan, &cfg.log_odds);
        self.known_cells += stats.cells_discovered;
        let flips = self.map.take_occupied_flips();
        self.walls_changed |= !flips.is_empty();
        self.obstacles.update(&self.map.occupancy, &flips);
        let free_changes = self.map.take_free_changes();
        // (The room-bounded gains too: the layout they are computed with changes less often
        // than the map, and clears them when it does.)
        for &i in flips.iter().chain(free_changes.iter().map(|(i, _)| i)) {
            self.gains.touch(i, self.scans);
            self.room_gains.touch(i, self.scans);
        }
        self.frontiers.update(
            &self.map.occupancy,
            flips
                .iter()
                .chain(free_changes.iter().map(|(i, _)| i))
                .copied(),
        );
        self.mark_planning_cells(&flips, &free_changes);
        // A cell never goes back to unknown, and every change from unknown is in one of the
        // two lists.
        let map_to_world = MapToWorld::new(&self.estimate, &self.sim.true_pose());
        for &i in flips.iter().chain(free_changes.iter().map(|(i, _)| i)) {
            let i = i as usize;
            if !self.known.data[i] && self.map.occupancy.data[i] != Occupancy::Unknown {
                self.known.data[i] = true;
                self.credit_explored(i, &map_to_world);
            }
        }
        self.mark_travelled(self.last_update_pose.position(), self.estimate.position());
        self.last_update_pose = self.estimate;
        self.update_odometry = odo_pose;
        self.last_update_time_s = self.sim.time_s();
        self.trajectory.push(self.sim.true_pose());
        self.estimated_trajectory.push(self.estimate);
    }

    /// Marks the map cells on the segment `from`-`to` (world) travelled. They count only while
    /// planning the way the robot came (`Planning::Travelled`, which recomputes every planning
    /// cell when it is set), so only then are the new ones' planning cells marked for recomputing.
    fn mark_travelled(&mut self, from: Vec2, to: Vec2) {
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
        if self.planning == Planning::Travelled && !new.is_empty() {
            self.mark_planning_cells(&[], &new);
        }
    }

    /// Credits the building cells observed through map cell `i`, just observed from the current
    /// scan: the building cells near where the sensor saw it whose centres, brought into the map
    /// frame by the current pose error, fall in a known map cell. With ground-truth poses that is
    /// exactly the known cells. Under a rotation every building cell still corresponds to one map
    /// cell (mapping cell centres forward instead would leave lines of holes), and testing every
    /// known map cell rather than only `i` credits the cells that a pose error jittering by a
    /// cell between updates would otherwise skip.
    fn credit_explored(&mut self, i: usize, map_to_world: &MapToWorld) {
        const REACH: i32 = 2;
        let frame = self.map.frame;
        for (j, n) in map_to_world.cells_near(&frame, frame.cell_of_index(i), REACH) {
            // Most neighbours are credited already: test that before transforming back.
            if !self.explored.data[j]
                && map_to_world
                    .map_index_of(&frame, n)
                    .is_some_and(|k| self.known.data[k])
            {
                self.explored.data[j] = true;
                self.explored_cells += self.truth.data[j] as usize;
            }
        }
    }

    fn explored_area_m2(&self) -> f64 {
        self.explored_cells as f64 * self.map.frame.cell_area_m2()
    }

    fn explored_fraction(&self) -> f64 {
        if self.truth_cells == 0 {
            0.0
        } else {
            self.explored_cells as f64 / self.truth_cells as f64
        }
    }

    fn record_progress(&mut self, on_progress: &mut dyn FnMut(&ProgressSample)) {
        if self.sim.time_s() + 1e-9 < self.next_progress_s {
            return;
        }
        let s = ProgressSample {
            time_s: self.sim.time_s(),
            explored_area_m2: self.explored_area_m2(),
            explored_fraction: self.explored_fraction(),
        };
        self.progress.push(s);
        on_progress(&s);
        while let Some(&f) = self.cfg.snapshot_fractions.get(self.snapshots.len()) {
            if s.explored_fraction + 1e-12 < f {
                break;
            }
            self.snapshots.push(MapSnapshot {
                fraction: f,
                time_s: s.time_s,
                map: self.map.occupancy.clone(),
            });
        }
        self.next_progress_s += self.cfg.progress_period_s;
    }

    fn needs_decision(&mut self) -> bool {
        let cfg = self.cfg;
        let now = self.sim.time_s();
        let Some(goal) = &mut self.goal else {
            return true;
        };
        // Whatever the goals, a robot that has not moved for long is stuck (e.g. alternating
        // between goals it cannot approach, each new one restarting the progress timeout):
        // abandon the current goal.
        let position = self.estimate.position();
        if (position - self.still_at).norm() > STILL_RADIUS_M {
            self.still_at = position;
            self.still_since_s = now;
        } else if now - self.still_since_s > STILL_FACTOR * cfg.progress_timeout_s {
            self.blacklist.give_up(
                self.map.frame.world_from_cell(goal.candidate),
                cfg.blacklist_radius_m,
            );
            self.goal = None;
            self.still_since_s = now;
            return true;
        }
        if goal.arrived {
            // Turning toward the frontier; done when facing it.
            let to = look_vector(goal, &self.estimate, cfg.robust_frontiers);
            let err = crate::geom::wrap_angle(to.y.atan2(to.x) - self.estimate.theta_rad);
            if err.abs() > 0.15 && to.norm() > 0.05 && now - goal.best_distance_at_s < 10.0 {
                return false;
            }
            self.last_reached = Some(self.map.frame.world_from_cell(goal.candidate));
            return true;
        }
        // Periodically, once the map shows something new: without new information the choice
        // would be the same (see `redecide_min_growth_m2`).
        let grown_m2 = self.known_cells.saturating_sub(goal.known_cells_at) as f64
            * self.map.frame.cell_area_m2();
        if now - goal.decided_at_s >= cfg.redecide_period_s
            && grown_m2 >= cfg.redecide_min_growth_m2
        {
            return true;
        }
        // The goal's frontier has (mostly) disappeared: nothing left to see there.
        let still = goal
            .frontier
            .iter()
            .filter(|c| is_frontier_cell(&self.map.occupancy, **c))
            .count();
        if still * 5 < goal.frontier.len() {
            return true;
        }
        // No progress along the path for too long: abandon the goal. (The length of the path
        // left, not the straight line to the goal: a path around a wall first leads away.)
        let d = self.follower.remaining_length_m(self.estimate.position());
        if d < goal.best_distance_m - 0.1 {
            goal.best_distance_m = d;
            goal.best_distance_at_s = now;
        } else if now - goal.best_distance_at_s > cfg.progress_timeout_s {
            let p = self.map.frame.world_from_cell(goal.candidate);
            self.blacklist.give_up(p, cfg.blacklist_radius_m);
            self.goal = None;
            return true;
        }
        // The map now shows an obstacle on the path: plan the path again (the goal is kept, and
        // so is the time of the last progress), or choose another goal if it cannot be reached.
        let to = goal.cell;
        if std::mem::take(&mut self.walls_changed) && self.path_blocked() {
            let Some(wps) = self.path_to(to) else {
                return true;
            };
            self.follower = PathFollower::from(self.estimate.position(), wps);
            let d = self.follower.remaining_length_m(self.estimate.position());
            if let Some(goal) = &mut self.goal {
                goal.best_distance_m = d;
            }
        }
        false
    }

    /// Waypoints of a path from the robot to map cell `c`: as for a decision, a distance search
    /// (stopping at `c`) on the distance grid, then the planning grid's search within a corridor
    /// around its path ([`Self::waypoints_to`]). A search of the whole planning grid, guided by
    /// the straight-line distance only, took 6 % of a run (its wall penalty leaves the
    /// heuristic far below the true cost).
    fn path_to(&mut self, c: Cell) -> Option<Vec<Vec2>> {
        let plan = self.plan(&[c]);
        self.waypoints_to(&plan, c)
    }

    /// How far from obstacles the robot's centre must stay on planned paths: its radius and
    /// the safety margin, or its radius alone while planning is relaxed (`Planning`).
    fn inflation_m(&self) -> f64 {
        match self.planning {
            Planning::WithMargin => self.cfg.sim.robot.radius_m + self.cfg.safety_margin_m,
            Planning::NoMargin | Planning::Travelled => self.cfg.sim.robot.radius_m,
        }
    }

    /// Plans at `level` from now on (every planning cell is recomputed when it changes).
    fn set_planning(&mut self, level: Planning) {
        if self.planning == level {
            return;
        }
        self.planning = level;
        for (i, m) in self.coarse_dirty_mark.iter_mut().enumerate() {
            if !*m {
                *m = true;
                self.coarse_dirty.push(i as u32);
            }
        }
    }

    /// Marks the planning cells that a map update may have changed: those of cells whose state
    /// changed and, around cells that became or stopped being occupied, those within the reach
    /// of the obstacle distance field (which decides traversability and the wall cost).
    fn mark_planning_cells(&mut self, flips: &[u32], free_changes: &[(u32, bool)]) {
        let frame = self.map.frame;
        let f = self.coarse.factor as i32;
        let (cw, ch) = (
            self.coarse.frame.width as i32,
            self.coarse.frame.height as i32,
        );
        let mut mark = |x0: i32, y0: i32, x1: i32, y1: i32| {
            for cy in y0.div_euclid(f).max(0)..=y1.div_euclid(f).min(ch - 1) {
                for cx in x0.div_euclid(f).max(0)..=x1.div_euclid(f).min(cw - 1) {
                    let i = (cy * cw + cx) as usize;
                    if !self.coarse_dirty_mark[i] {
                        self.coarse_dirty_mark[i] = true;
                        self.coarse_dirty.push(i as u32);
                    }
                }
            }
        };
        let reach = self.obstacles.cap_cells as i32 + 1;
        for &i in flips {
            let c = frame.cell_of_index(i as usize);
            mark(c.x - reach, c.y - reach, c.x + reach, c.y + reach);
        }
        for &(i, _) in free_changes {
            let c = frame.cell_of_index(i as usize);
            mark(c.x, c.y, c.x, c.y);
        }
    }

    fn traversability(&self) -> Traversability<'_> {
        Traversability::new(&self.map.occupancy, &self.obstacles, self.inflation_m())
    }

    /// Path costs from the robot (metres, plus a penalty for passing close to walls, so paths
    /// keep to the middle of corridors and doors) on the distance grid, stopping once every
    /// target (map cells) is settled; the path to the chosen one is then searched on the finer
    /// planning grid ([`Plan::waypoints_to`]). A robot closer to a wall than the inflation
    /// radius starts from the nearest passable cell (it then first drives out).
    fn plan(&mut self, targets: &[Cell]) -> Plan {
        self.refresh_planning_grids();
        let radius_m = self.inflation_m();
        let robot = self.map.frame.cell_from_world(self.estimate.position());
        let start_on = |grid: &CoarseCosts| start_cell(grid, robot, radius_m);
        let far = self.far.clone();
        let start = start_on(&far);
        let far_targets: Vec<Cell> = targets
            .iter()
            .filter_map(|c| far.passable_near(*c, far_search_cells()))
            .collect();
        let field = dijkstra_padded(far.frame, start, far.padded(), MAX_EXTRA, &far_targets);
        Plan {
            far,
            field,
            near_start: start_on(&self.coarse),
        }
    }

    /// Brings the planning and distance grids up to date with the map.
    fn refresh_planning_grids(&mut self) {
        if self.coarse_dirty.is_empty() {
            return;
        }
        const WALL_BAND_M: f64 = 0.3;
        let radius_m = self.inflation_m();
        // Not `self.traversability()`: the planning grid below is updated while this borrows
        // only the map and the obstacle field.
        let trav = Traversability::new(&self.map.occupancy, &self.obstacles, radius_m);
        let travelled = (self.planning == Planning::Travelled).then_some(&self.travelled.data);
        let occupancy = &self.map.occupancy.data;
        let traversable = |i: usize| {
            trav.at_index(i) || travelled.is_some_and(|t| t[i] && occupancy[i] == Occupancy::Free)
        };
        let res = self.map.frame.resolution_m;
        let obstacles = &self.obstacles.data;
        // The extra cost by obstacle distance, tabulated in steps of 1/8 cell (the field is
        // capped, so the table is small) instead of evaluated per cell.
        const STEPS_PER_CELL: f32 = 8.0;
        let table: Vec<u32> = (0..=(self.obstacles.cap_cells as usize * 8 + 1))
            .map(|k| {
                let d_cells = k as f64 / STEPS_PER_CELL as f64;
                let beyond = (d_cells * res - radius_m) / WALL_BAND_M;
                if beyond >= 1.0 {
                    0
                } else {
                    (MAX_EXTRA as f64 * (1.0 - beyond.max(0.0))).round() as u32
                }
            })
            .collect();
        let last = table.len() - 1;
        let extra = |j: usize| table[((obstacles[j] * STEPS_PER_CELL) as usize).min(last)];
        self.coarse
            .recompute(self.map.frame, &self.coarse_dirty, traversable, extra);
        // The distance grid's cells covering the changed planning cells.
        let k = (DISTANCE_FACTOR / PLAN_FACTOR) as usize;
        let (cw, fw, fh) = (
            self.coarse.frame.width as usize,
            self.far.frame.width as usize,
            self.far.frame.height as usize,
        );
        let mut far_dirty: Vec<u32> = self
            .coarse_dirty
            .iter()
            .map(|&i| ((i as usize % cw) / k, (i as usize / cw) / k))
            .filter(|&(x, y)| x < fw && y < fh)
            .map(|(x, y)| (y * fw + x) as u32)
            .collect();
        far_dirty.sort_unstable();
        far_dirty.dedup();
        self.far
            .recompute(self.map.frame, &far_dirty, traversable, extra);
        for &i in &self.coarse_dirty {
            self.coarse_dirty_mark[i as usize] = false;
        }
        self.coarse_dirty.clear();
    }

    /// Whether the rest of the path being followed (from the start of the segment the robot is
    /// on) crosses a planning cell that the map now shows impassable; the cells within one
    /// planning cell of the robot are not tested (a robot close to a wall stands in one).
    fn path_blocked(&mut self) -> bool {
        self.refresh_planning_grids();
        let Some((start, rest)) = self.follower.current_segment() else {
            return false;
        };
        let grid = &self.coarse;
        let to_grid = |p: Vec2| grid_from_world(&grid.frame, p);
        let robot = grid.frame.cell_from_world(self.estimate.position());
        let mut from = to_grid(start);
        let mut blocked = false;
        for &w in rest {
            let to = to_grid(w);
            walk_segment(from, to, |c| {
                let near_robot = (c.x - robot.x).abs() <= 1 && (c.y - robot.y).abs() <= 1;
                blocked = !near_robot && !grid.passable(c);
                !blocked
            });
            if blocked {
                return true;
            }
            from = to;
        }
        false
    }

    /// Waypoints (world) of the path to map cell `c`, searched on the planning grid from the
    /// robot's cell when `plan` was made (the grid has not changed since): first within a
    /// corridor three cells of the distance grid wide around the path `plan` found there, which
    /// touches few cells; over the whole grid if no path lies inside it.
    fn waypoints_to(&mut self, plan: &Plan, c: Cell) -> Option<Vec<Vec2>> {
        let near = &self.coarse;
        let goal = near.passable_near(c, TARGET_SEARCH_CELLS)?;
        let (start, k) = (plan.near_start, (DISTANCE_FACTOR / PLAN_FACTOR) as i32);
        let mut found = None;
        if let Some(far_path) = plan.far_path(c) {
            let frame = plan.far.frame;
            let mut marked = Vec::with_capacity(far_path.len() * 3);
            for p in &far_path {
                for n in std::iter::once(*p).chain(p.neighbours8()) {
                    if let Some(i) = frame.index(n) {
                        if !self.corridor[i] {
                            self.corridor[i] = true;
                            marked.push(i);
                        }
                    }
                }
            }
            let corridor = &self.corridor;
            found =
                self.astar
                    .path_within(near.frame, start, near.padded(), MAX_EXTRA, goal, |n| {
                        frame
                            .index(Cell::new(n.x.div_euclid(k), n.y.div_euclid(k)))
                            .is_some_and(|i| corridor[i])
                    });
            for i in marked {
                self.corridor[i] = false;
            }
        }
        let (path, _) = match found {
            Some(p) => p,
            None => self
                .astar
                .path(near.frame, start, near.padded(), MAX_EXTRA, goal)?,
        };
        Some(waypoints_by(&path, &near.frame, |n| near.passable(n)))
    }

    /// Recomputes the layout when the strategy uses it and the map has grown enough since the
    /// last one. Returns whether gains should use the layout now.
    fn refresh_layout(&mut self) -> bool {
        let st = &self.cfg.strategy;
        if !st.uses_layout() && !self.policy_needs.layout_gain {
            return false;
        }
        let cell_area = self.map.frame.cell_area_m2();
        let grown_m2 = self.layout.as_ref().map_or(f64::INFINITY, |l| {
            (self.known_cells.saturating_sub(l.known_cells_at)) as f64 * cell_area
        });
        if grown_m2 >= st.layout_update_m2 {
            let grid = &self.map.occupancy;
            // Judge the previous layout by what was revealed since (for the switch strategy).
            if let Some(prev) = &self.layout {
                let (mut known, mut free) = (0usize, 0usize);
                for &i in &prev.predicted_unknown {
                    match grid.data[i as usize] {
                        Occupancy::Free => {
                            known += 1;
                            free += 1;
                        }
                        Occupancy::Occupied => known += 1,
                        Occupancy::Unknown => {}
                    }
                }
                if known as f64 * cell_area >= st.switch_min_area_m2
                    && free as f64 >= st.switch_agreement * known as f64
                {
                    self.layout_trusted = true;
                }
            }
            let mut raster = if st.layout_from_truth {
                // The oracle: nothing to compute (and nothing to charge).
                let to_map = MapToWorld::new(&self.estimate, &self.sim.true_pose());
                LayoutRaster::exact(&true_layout(&self.rooms, &to_map), grid)
            } else {
                let mut made = None;
                let layout_cfg = &self.cfg.layout;
                let charged_s = match self.layout_cost.as_mut() {
                    Some(cost) => cost(&mut || made = Some(reconstruct_layout(grid, layout_cfg))),
                    None => 0.0,
                };
                let layout = made.unwrap_or_else(|| reconstruct_layout(grid, layout_cfg));
                if charged_s.is_finite() && charged_s > 0.0 {
                    self.compute_debt_s += charged_s;
                    self.layout_compute_s += charged_s;
                }
                LayoutRaster::new(&layout, grid, st.max_wall_gap_m)
            };
            raster.through_openings = st.gain_through_openings;
            let predicted_unknown = grid
                .data
                .iter()
                .enumerate()
                .filter(|(i, s)| {
                    **s == Occupancy::Unknown && raster.inside(self.map.frame.cell_of_index(*i))
                })
                .map(|(i, _)| i as u32)
                .collect();
            self.layout = Some(LayoutState {
                raster,
                known_cells_at: self.known_cells,
                predicted_unknown,
            });
            self.layouts_computed += 1;
            // Cached gains were computed with the previous layout.
            self.gains.clear();
            self.room_gains.clear();
        }
        match st.gain {
            GainModel::Baseline => false,
            GainModel::Layout => true,
            GainModel::Switch => self.layout_trusted,
        }
    }

    /// Moves the candidate of every frontier whose goal is unreachable in `plan` to the
    /// reachable traversable cell of the frontier nearest to it (the first in row-major order
    /// among equals), if there is one. Returns the plan to score with: a full search when
    /// `plan`, which stops once its targets are settled, may not cover the new goals.
    fn reachable_candidates(
        &mut self,
        frontiers: &mut [Frontier],
        goals: &mut [Option<Cell>],
        plan: Plan,
    ) -> Plan {
        let moved: Vec<usize> = (0..frontiers.len())
            .filter(|&k| goals[k].and_then(|c| plan.distance_m(c)).is_none())
            .collect();
        if moved.is_empty() {
            return plan;
        }
        // The new goals need distances that are final: search everything if the search stopped
        // at its targets.
        let plan = if plan.field.is_complete() {
            plan
        } else {
            self.plan(&[])
        };
        let trav = self.traversability();
        let frame = self.map.frame;
        for k in moved {
            let f = &mut frontiers[k];
            let from = f.candidate;
            let d2 = |c: &Cell| {
                let (dx, dy) = ((c.x - from.x) as i64, (c.y - from.y) as i64);
                dx * dx + dy * dy
            };
            // (Not where a goal was given up: the robot would come back for ever.)
            let best = f
                .cells
                .iter()
                .filter(|c| {
                    trav.at(**c)
                        && plan.distance_m(**c).is_some()
                        && !self.blacklist.contains(frame.world_from_cell(**c))
                })
                .min_by_key(|c| d2(c));
            if let Some(&c) = best {
                f.candidate = c;
                goals[k] = Some(c);
            }
        }
        plan
    }

    /// Scores every frontier for the utility: distance to its goal (`None` if unreachable in
    /// `plan`; the path's length, or the straight line to the candidate with
    /// [`UtilityDistance::Euclidean`]) and information gain (as the strategy's gain model
    /// defines it).
    fn score(
        &mut self,
        frontiers: &[Frontier],
        goals: &[Option<Cell>],
        plan: &Plan,
        use_layout: bool,
    ) -> Vec<CandidateScore> {
        let cfg = self.cfg;
        let mut scores = Vec::with_capacity(frontiers.len());
        let (frame, robot) = (self.map.frame, self.estimate.position());
        for (f, goal_cell) in frontiers.iter().zip(goals) {
            let distance_m = goal_cell.and_then(|c| plan.distance_m(c)).map(|path_m| {
                match cfg.utility_distance {
                    UtilityDistance::Path => path_m,
                    UtilityDistance::Euclidean => {
                        (frame.world_from_cell(f.candidate) - robot).norm()
                    }
                }
            });
            let gain_m2 = if distance_m.is_some() {
                let (grid, range_m) = (&self.map.occupancy, cfg.sim.laser.max_range_m);
                match (&self.layout, use_layout) {
                    (Some(l), true) if cfg.strategy.rank_by_predicted_rooms => {
                        self.room_gains.gain(f.candidate, range_m, self.scans, || {
                            layout_information_gain(grid, &l.raster, f.candidate, range_m)
                        })
                    }
                    (Some(l), true) => self.gains.gain(f.candidate, range_m, self.scans, || {
                        gap_closed_information_gain(grid, &l.raster, f.candidate, range_m)
                    }),
                    _ => self.gains.gain(f.candidate, range_m, self.scans, || {
                        information_gain(grid, f.candidate, range_m)
                    }),
                }
            } else {
                0.0
            };
            scores.push(CandidateScore {
                distance_m,
                gain_m2,
            });
        }
        scores
    }

    /// Before the run ends for want of candidates: gives the goals given up (by the progress
    /// timeout or standing still) another chance, if the map has grown by at least 1 m2 since
    /// they last had one (or never had one). A goal given up for a moment of bad luck (a robot
    /// stuck on clutter, a pose estimate briefly off) would otherwise end the run with
    /// frontiers left. Returns whether any were forgiven.
    fn forgive(&mut self) -> bool {
        if self.stopped_early || self.policy_failed {
            return false;
        }
        let grown = self.forgiven_at.is_none_or(|at| {
            self.known_cells.saturating_sub(at) as f64 * self.map.frame.cell_area_m2() >= 1.0
        });
        if !grown || self.blacklist.forgive() == 0 {
            return false;
        }
        self.forgiven_at = Some(self.known_cells);
        true
    }

    /// Chooses the next goal. Returns false when no reachable candidate is left.
    fn decide(&mut self) -> bool {
        // A relaxed plan (see below) holds for one decision.
        self.set_planning(Planning::WithMargin);
        self.decide_planned()
    }

    fn decide_planned(&mut self) -> bool {
        let cfg = self.cfg;
        let frame = self.map.frame;
        if self.map.known_bounds.is_none() {
            // Nothing seen yet: wait for the first scan.
            return true;
        }
        // A goal just reached and looked at whose frontier is still there cannot be resolved by
        // going there again: blacklist it.
        if let Some(p) = self.last_reached.take() {
            let again = self.goal.as_ref().is_some_and(|g| {
                g.frontier
                    .iter()
                    .filter(|c| is_frontier_cell(&self.map.occupancy, **c))
                    .count()
                    * 2
                    > g.frontier.len()
            });
            if again {
                self.blacklist.looked(p, cfg.blacklist_radius_m);
            }
        }
        let fcfg = FrontierConfig::with_min_length_m(cfg.min_frontier_m, frame.resolution_m);
        let mut frontiers = self.frontiers.detect(&self.map.occupancy, &fcfg);
        if cfg.frontier_clearance_m > 0.0 {
            let clearance_cells = cfg.frontier_clearance_m / frame.resolution_m;
            let obstacles = &self.obstacles;
            frontiers = frontiers_where(frontiers, &fcfg, |c| {
                f64::from(obstacles.get(c)) >= clearance_cells
            });
        }
        let blacklist = &self.blacklist;
        let mut frontiers: Vec<Frontier> = frontiers
            .into_iter()
            .filter_map(|f| {
                if !blacklist.contains(frame.world_from_cell(f.candidate)) {
                    Some(f)
                } else if cfg.robust_frontiers {
                    outside_blacklist(f, blacklist, &frame)
                } else {
                    None
                }
            })
            .collect();
        self.goal = None;
        self.follower = PathFollower::default();
        if frontiers.is_empty() {
            return false;
        }
        let search = (0.5 / frame.resolution_m).ceil() as i32;
        let mut goals: Vec<Option<Cell>> = {
            let trav = self.traversability();
            frontiers
                .iter()
                .map(|f| {
                    if trav.at(f.candidate) {
                        Some(f.candidate)
                    } else {
                        nearest_by(f.candidate, search, |c| trav.at(c))
                    }
                })
                .collect()
        };
        let use_layout = self.refresh_layout();
        let targets: Vec<Cell> = goals.iter().flatten().copied().collect();
        self.plans += 1;
        let mut plan = self.plan(&targets);
        // The frontiers' own middle cells first (the paper's rule), unless the settings ask
        // for the reachable part of every frontier from the start; as a last resort, before
        // ending the run with frontiers left, their reachable parts: exploration does not end
        // while a frontier can be reached.
        let mut moved_to_reachable = cfg.candidate_from_reachable_part;
        if moved_to_reachable {
            plan = self.reachable_candidates(&mut frontiers, &mut goals, plan);
        }
        let (scores, best, wps) = loop {
            // `None` when the strategy says stop.
            let mut scores = self.score(&frontiers, &goals, &plan, use_layout);
            // The best candidate with a path on the planning grid: the distance grid is coarser
            // and may connect what the planning grid does not (yet: a door seen at a slant opens
            // as the robot comes closer), so a candidate without a path is passed over for this
            // decision (the strategy is asked again without it), not blacklisted.
            let mut attempt = 0;
            // A goal point of the policy's own without a path (`Reply::Goal`), and how many.
            let (mut unreachable_goal, mut unreachable_goals) = (None, 0);
            let chosen = loop {
                let asked = Asked {
                    attempt,
                    use_layout,
                    unreachable_goal: unreachable_goal.take(),
                };
                match self.ask_policy(&frontiers, &goals, &plan, &scores, asked) {
                    Answer::Stop => break None,
                    Answer::Nothing => break Some(None),
                    Answer::Point(p) => {
                        if let Some((goal_cell, wps)) = self.point_goal(p) {
                            return self.set_point_goal(frontiers.len(), p, goal_cell, wps);
                        }
                        unreachable_goals += 1;
                        if unreachable_goals >= MAX_UNREACHABLE_GOALS {
                            break Some(None);
                        }
                        unreachable_goal = Some(p);
                        attempt += 1;
                    }
                    Answer::One(best) => {
                        let goal_cell = goals[best].expect("best candidate is reachable");
                        match self.waypoints_to(&plan, goal_cell) {
                            Some(wps) => {
                                break Some(Some((std::mem::take(&mut scores), best, wps)))
                            }
                            None => scores[best].distance_m = None,
                        }
                        attempt += 1;
                    }
                    Answer::Ranked(ids) => {
                        let mut found = None;
                        for id in ids {
                            let goal_cell = goals[id].expect("ranked candidate is reachable");
                            if let Some(wps) = self.waypoints_to(&plan, goal_cell) {
                                found = Some((id, wps));
                                break;
                            }
                        }
                        break Some(found.map(|(id, wps)| (std::mem::take(&mut scores), id, wps)));
                    }
                }
            };
            // A policy that failed ends the run at once.
            if self.policy_failed {
                return false;
            }
            let early_stop = match chosen {
                Some(Some(found)) => break found,
                Some(None) => false,
                None => true,
            };
            // Frontiers exist but none can be reached as they stand, or the early stop would end
            // the run. The last resorts first, in order. The early stop weighs the reachable
            // candidates only, so it gets them too (not under the paper's frontier rule): a
            // doorway seen at a slant leaves a wedge of free cells beyond it too thin to drive,
            // whose frontier is reachable only at the doorway, and the room behind must weigh in
            // the rule (modern-office, layout-es from a random start, stopped at 96.7 % with a
            // room never entered).
            let last_resorts = !early_stop || cfg.robust_frontiers;
            // 1. Each frontier's reachable part.
            if last_resorts && !moved_to_reachable {
                moved_to_reachable = true;
                plan = self.reachable_candidates(&mut frontiers, &mut goals, plan);
                continue;
            }
            // 2. The plan without the safety margin. Where the map shows a passage (often the
            // one the robot came in by) a little narrower than the robot's diameter plus twice
            // the margin, the robot would otherwise end the run with frontiers it can reach
            // (Lamuniere1, seed 2, with updates every 0.5 m / 0.25 rad: 86 % explored).
            // 3. The plan through the cells the robot has travelled as well: where the map,
            // sharpened by later scans, shows the passage it came in by narrower than its body
            // (a crowded room, a narrow corridor), the robot is in a pocket of the planning grid
            // and reaches nothing (freiburg_building101 and intel_map from random starts,
            // stuck at 95 % explored). Its body fitted there: it leaves the way it came.
            if let Some(looser) = self.planning.looser().filter(|_| last_resorts) {
                self.set_planning(looser);
                return self.decide_planned();
            }
            // 4. A closer look (see `approach`).
            if !early_stop {
                if let Some((i, goal_cell, wps)) = self.approach(&frontiers, &goals, &plan) {
                    return self.set_goal(&frontiers, i, goal_cell, wps, None);
                }
            }
            if early_stop {
                self.stopped_early = true;
            } else {
                // Frontiers exist but none is reachable: blacklist them all so the run can end.
                for f in &frontiers {
                    self.blacklist
                        .add(frame.world_from_cell(f.candidate), cfg.blacklist_radius_m);
                }
            }
            return false;
        };
        let goal_cell = goals[best].expect("best candidate is reachable");
        let score = scores[best];
        self.set_goal(&frontiers, best, goal_cell, wps, Some(score))
    }

    /// Heads for frontier `i` of `frontiers` through `goal_cell` (a map cell) along `wps`,
    /// recording the decision (`score`: its gain and path length; `None` for a closer look).
    /// Returns true.
    fn set_goal(
        &mut self,
        frontiers: &[Frontier],
        i: usize,
        goal_cell: Cell,
        wps: Vec<Vec2>,
        score: Option<CandidateScore>,
    ) -> bool {
        let cfg = self.cfg;
        let frame = self.map.frame;
        let now = self.sim.time_s();
        self.follower = PathFollower::from(self.estimate.position(), wps);
        let dist = self.follower.remaining_length_m(self.estimate.position());
        self.decisions.push(Decision {
            time_s: now,
            pose: self.estimate,
            goal: frame.world_from_cell(goal_cell),
            candidates: frontiers.len(),
            gain_m2: score.map_or(0.0, |s| s.gain_m2),
            distance_m: score.map_or(dist, |s| s.distance_m.unwrap_or(0.0)),
        });
        let look_at = unknown_centroid(&self.map.occupancy, &frontiers[i].cells)
            .unwrap_or_else(|| frame.world_from_cell(frontiers[i].candidate));
        let look_dir = cfg
            .robust_frontiers
            .then(|| unknown_side(&self.map.occupancy, &frontiers[i].cells))
            .flatten();
        self.goal = Some(Goal {
            cell: goal_cell,
            candidate: frontiers[i].candidate,
            look_at,
            look_dir,
            arrived: false,
            frontier: frontiers[i].cells.clone(),
            decided_at_s: now,
            known_cells_at: self.known_cells,
            best_distance_m: dist,
            best_distance_at_s: now,
        });
        true
    }

    /// The goal cell and path for a policy's own goal point `p` (`Reply::Goal`): the nearest
    /// traversable map cell within 0.5 m of it, and a path there on the planning grid. `None`
    /// when `p` is off the map or no path leads there.
    fn point_goal(&mut self, p: Vec2) -> Option<(Cell, Vec<Vec2>)> {
        let frame = self.map.frame;
        let c = frame.cell_from_world(p);
        frame.index(c)?;
        let search = (0.5 / frame.resolution_m).ceil() as i32;
        let goal = {
            let trav = self.traversability();
            if trav.at(c) {
                Some(c)
            } else {
                nearest_by(c, search, |n| trav.at(n))
            }
        }?;
        let plan = self.plan(&[goal]);
        plan.distance_m(goal)?;
        let wps = self.waypoints_to(&plan, goal)?;
        Some((goal, wps))
    }

    /// Heads for a policy's own goal point `p` through `goal_cell` along `wps` (no frontier:
    /// the goal ends on arrival, and is given up, as any, when the robot makes no progress).
    /// `candidates`: how many were shown. Returns true.
    fn set_point_goal(
        &mut self,
        candidates: usize,
        p: Vec2,
        goal_cell: Cell,
        wps: Vec<Vec2>,
    ) -> bool {
        let now = self.sim.time_s();
        self.follower = PathFollower::from(self.estimate.position(), wps);
        let dist = self.follower.remaining_length_m(self.estimate.position());
        self.decisions.push(Decision {
            time_s: now,
            pose: self.estimate,
            goal: p,
            candidates,
            gain_m2: 0.0,
            distance_m: dist,
        });
        self.goal = Some(Goal {
            cell: goal_cell,
            candidate: goal_cell,
            look_at: p,
            look_dir: None,
            arrived: false,
            frontier: Vec::new(),
            decided_at_s: now,
            known_cells_at: self.known_cells,
            best_distance_m: dist,
            best_distance_at_s: now,
        });
        true
    }

    /// Asks the strategy's policy to choose among the reachable candidates (`scores` with a
    /// distance). [`Answer::Nothing`] when there is none, when the policy passes, or when it
    /// failed (`policy_failed`, also for a reply naming no candidate shown).
    fn ask_policy(
        &mut self,
        frontiers: &[Frontier],
        goals: &[Option<Cell>],
        plan: &Plan,
        scores: &[CandidateScore],
        asked: Asked,
    ) -> Answer {
        let Asked {
            attempt,
            use_layout,
            unreachable_goal,
        } = asked;
        // A built-in strategy's rule weighs the layout's gain only while it uses the layout.
        let layout_gain = self.policy_needs.layout_gain
            && (use_layout || matches!(self.policy, PolicySlot::External(_)));
        let frame = self.map.frame;
        let robot = self.estimate.position();
        let range_m = self.cfg.sim.laser.max_range_m;
        let mut views = Vec::new();
        for (i, s) in scores.iter().enumerate() {
            let (Some(distance_m), Some(goal)) = (s.distance_m, goals[i]) else {
                continue;
            };
            let f = &frontiers[i];
            let point = frame.world_from_cell(f.candidate);
            let layout_gain_m2 = match (&self.layout, layout_gain) {
                (Some(l), true) => {
                    let grid = &self.map.occupancy;
                    Some(self.room_gains.gain(f.candidate, range_m, self.scans, || {
                        layout_information_gain(grid, &l.raster, f.candidate, range_m)
                    }))
                }
                _ => None,
            };
            views.push(CandidateView {
                id: i,
                cell: f.candidate,
                point,
                goal: frame.world_from_cell(goal),
                frontier_cells: f.size,
                distance_m,
                path_m: plan.distance_m(goal).unwrap_or(distance_m),
                straight_m: (point - robot).norm(),
                gain_m2: s.gain_m2,
                layout_gain_m2,
            });
        }
        if views.is_empty() {
            return Answer::Nothing;
        }
        if attempt == 0 {
            self.policy_decisions += 1;
        }
        let view = DecisionView {
            decision: self.policy_decisions - 1,
            attempt,
            time_s: self.sim.time_s(),
            pose: self.estimate,
            candidates: &views,
            unreachable_goal,
            map: &self.map.occupancy,
        };
        let (reply, charged_s) = self.policy.get().decide(&view);
        if charged_s.is_finite() && charged_s > 0.0 {
            self.compute_debt_s += charged_s;
            self.strategy_compute_s += charged_s;
        }
        let shown = |id: &usize| views.iter().any(|v| v.id == *id);
        match reply {
            Reply::Choose(id) if shown(&id) => Answer::One(id),
            Reply::Rank(ids)
                if !ids.is_empty()
                    && ids.iter().all(shown)
                    && ids.iter().collect::<std::collections::BTreeSet<_>>().len() == ids.len() =>
            {
                Answer::Ranked(ids)
            }
            Reply::Goal(p) if p.x.is_finite() && p.y.is_finite() => Answer::Point(p),
            Reply::Pass => Answer::Nothing,
            Reply::Stop => Answer::Stop,
            _ => {
                self.policy_failed = true;
                Answer::Nothing
            }
        }
    }

    /// The last rung of `decide_planned`'s ladder: a closer look at a frontier that the distance
    /// grid reaches but no path on the planning grid does (a doorway seen from afar at a grazing
    /// angle, drawn narrower than the robot by the noise of its edges: intel_map from a random
    /// start never entered the building's middle and ended at 79 % explored). The goal is the
    /// planning cell reachable from the robot nearest to such a frontier's goal `goals[i]`, within
    /// the laser's range of it and at least 1 m nearer to it than the robot stands; the frontier
    /// whose gap left is smallest wins (the first among equals). Scans from there often open the
    /// doorway; if not, the frontier is looked into from there and given up as any other.
    /// Returns the frontier's index, the goal (map cell) and the path's waypoints.
    fn approach(
        &mut self,
        frontiers: &[Frontier],
        goals: &[Option<Cell>],
        plan: &Plan,
    ) -> Option<(usize, Cell, Vec<Vec2>)> {
        let frame = self.map.frame;
        let near = &self.coarse;
        let field = dijkstra_padded(near.frame, plan.near_start, near.padded(), MAX_EXTRA, &[]);
        let robot = self.estimate.position();
        let range_m = self.cfg.sim.laser.max_range_m;
        let r = (range_m / near.frame.resolution_m).ceil() as i32;
        let mut best: Option<(f64, usize, Cell)> = None;
        for (i, g) in goals.iter().enumerate() {
            let Some(g) = *g else { continue };
            if plan.distance_m(g).is_none() {
                continue;
            }
            // Slivers behind a wall and corners seen at a slant are not worth the drive; a
            // doorway opens onto a room. The baseline's gain (not the strategy's: a layout's
            // wall line may close the very doorway; not cached: the caches hold the strategy's).
            let (grid, candidate) = (&self.map.occupancy, frontiers[i].candidate);
            if information_gain(grid, candidate, range_m) < CLOSER_LOOK_MIN_GAIN_M2 {
                continue;
            }
            let target = frame.world_from_cell(g);
            let gc = near.coarse_of(g);
            let mut nearest: Option<(f64, Cell)> = None;
            for y in gc.y - r..=gc.y + r {
                for x in gc.x - r..=gc.x + r {
                    let c = Cell::new(x, y);
                    if field.distance_m(c).is_none() {
                        continue;
                    }
                    let d = (near.frame.world_from_cell(c) - target).norm();
                    if d <= range_m && nearest.is_none_or(|(nd, _)| d < nd) {
                        nearest = Some((d, c));
                    }
                }
            }
            let Some((gap_m, c)) = nearest else { continue };
            if (robot - target).norm() - gap_m >= 1.0 && best.is_none_or(|(bd, ..)| gap_m < bd) {
                best = Some((gap_m, i, c));
            }
        }
        let (_, i, c) = best?;
        let path = field.path_to(c)?;
        let wps = waypoints_by(&path, &near.frame, |n| near.passable(n));
        let f = near.factor as i32;
        Some((i, Cell::new(c.x * f + f / 2, c.y * f + f / 2), wps))
    }

    /// Why a run that ran out of goals ended. Frontier cells the robot looked into (stood at a
    /// goal near them facing the unknown space, and they stayed frontier) are resolved as far as
    /// the sensor allows. Complete when no other frontier cell is left on the map (frontiers of
    /// the configured length, wherever they are); stuck when a path leads to one of the cells
    /// left (every goal toward them was given up); unreachable otherwise.
    fn classify_end(&mut self) -> EndReason {
        let frame = self.map.frame;
        let fcfg = FrontierConfig::with_min_length_m(self.cfg.min_frontier_m, frame.resolution_m);
        let mut frontiers = self.frontiers.detect(&self.map.occupancy, &fcfg);
        if self.cfg.frontier_clearance_m > 0.0 {
            let clearance_cells = self.cfg.frontier_clearance_m / frame.resolution_m;
            let obstacles = &self.obstacles;
            frontiers = frontiers_where(frontiers, &fcfg, |c| {
                f64::from(obstacles.get(c)) >= clearance_cells
            });
        }
        let left: Vec<Cell> = frontiers
            .iter()
            .flat_map(|f| f.cells.iter().copied())
            .filter(|&c| !self.blacklist.looked_at(frame.world_from_cell(c)))
            .collect();
        self.frontier_cells_left = left.len();
        if left.is_empty() {
            return EndReason::Complete;
        }
        if left
            .iter()
            .any(|&c| self.blacklist.given_up_at(frame.world_from_cell(c)))
        {
            return EndReason::Stuck;
        }
        let search = (0.5 / frame.resolution_m).ceil() as i32;
        let targets: Vec<Cell> = {
            let trav = self.traversability();
            left.iter()
                .filter_map(|&c| {
                    if trav.at(c) {
                        Some(c)
                    } else {
                        nearest_by(c, search, |n| trav.at(n))
                    }
                })
                .collect()
        };
        self.set_planning(Planning::Travelled);
        let plan = self.plan(&targets);
        let reachable = targets.iter().any(|&c| plan.distance_m(c).is_some());
        self.set_planning(Planning::WithMargin);
        if reachable {
            EndReason::Stuck
        } else {
            EndReason::Unreachable
        }
    }

    fn drive(&mut self) {
        let cfg = self.cfg;
        if let Some(goal) = self.goal.as_ref().filter(|g| g.arrived) {
            let to = look_vector(goal, &self.estimate, cfg.robust_frontiers);
            let err = crate::geom::wrap_angle(to.y.atan2(to.x) - self.estimate.theta_rad);
            let w = (cfg.follow.heading_gain * err).clamp(
                -cfg.sim.robot.max_turn_rate_radps,
                cfg.sim.robot.max_turn_rate_radps,
            );
            self.sim.step(0.0, w);
            return;
        }
        match self.follower.command(
            &self.estimate,
            &cfg.follow,
            cfg.sim.robot.max_speed_mps,
            cfg.sim.robot.max_turn_rate_radps,
        ) {
            Command::Drive { v_mps, w_radps } => self.sim.step(v_mps, w_radps),
            Command::Arrived => {
                // Goal reached: turn toward the unknown space behind the frontier.
                if let Some(goal) = &mut self.goal {
                    goal.arrived = true;
                    goal.best_distance_at_s = self.sim.time_s();
                }
                self.sim.idle();
            }
        }
    }

    fn return_home(&mut self) {
        let cfg = self.cfg;
        let frame = self.map.frame;
        let start = self.trajectory.first().copied().unwrap_or(self.estimate);
        let home = frame.cell_from_world(start.position());
        let plan = self.plan(&[home]);
        let Some(wps) = self.waypoints_to(&plan, home) else {
            return;
        };
        self.follower = PathFollower::new(wps);
        while self.sim.time_s() < cfg.time_limit_s {
            match self.follower.command(
                &self.estimate,
                &cfg.follow,
                cfg.sim.robot.max_speed_mps,
                cfg.sim.robot.max_turn_rate_radps,
            ) {
                Command::Arrived => break,
                Command::Drive { v_mps, w_radps } => self.sim.step(v_mps, w_radps),
            }
            self.sense();
        }
    }

    fn finish(
        mut self,
        end_reason: EndReason,
        exploration_time_s: f64,
        on_progress: &mut dyn FnMut(&ProgressSample),
    ) -> RunResult {
        // Always close the curve with the final state.
        self.next_progress_s = f64::NEG_INFINITY;
        self.record_progress(on_progress);
        let mut map_quality = map_quality(&self.map.occupancy, &self.free);
        // The map as a whole may sit rotated about the start (a heading error made before any
        // wall was in view); the best fit of the estimated trajectory onto the true one undoes
        // that, and the search around it takes out what remains of a rigid misplacement, so
        // that only inconsistencies (doubled or bent walls) lower the score.
        let positions = |t: &[Pose]| t.iter().map(|p| p.position()).collect::<Vec<_>>();
        let prior = crate::mapping::alignment::fit_rigid(
            &positions(&self.estimated_trajectory),
            &positions(&self.trajectory),
        );
        map_quality.occupied_precision_aligned =
            crate::mapping::alignment::aligned_occupied_precision(
                &self.map.occupancy,
                &self.free,
                &prior,
                prior
                    .compose(&Pose::new(self.start.x_m, self.start.y_m, 0.0))
                    .position(),
                &Default::default(),
            )
            .0;
        RunResult {
            seed: self.seed,
            start: self.start,
            stopped_early: end_reason == EndReason::EarlyStop,
            layouts_computed: self.layouts_computed,
            layout_compute_s: self.layout_compute_s,
            strategy_compute_s: self.strategy_compute_s,
            rooms_never_entered: (!self.rooms.is_empty()).then(|| {
                self.rooms
                    .iter()
                    .filter(|r| !self.trajectory.iter().any(|p| r.contains(p.position())))
                    .count()
            }),
            rooms_unexplored: (!self.rooms.is_empty()).then(|| {
                self.rooms
                    .iter()
                    .filter(|r| {
                        let (mut free, mut explored) = (0usize, 0usize);
                        crate::building::for_cells_in_polygon(self.map.frame, r, |i| {
                            if self.truth.data[i] {
                                free += 1;
                                explored += self.explored.data[i] as usize;
                            }
                        });
                        free > 0 && 2 * explored < free
                    })
                    .count()
            }),
            end_reason,
            frontier_cells_left: self.frontier_cells_left,
            exploration_time_s,
            total_time_s: self.sim.time_s(),
            explored_area_m2: self.explored_area_m2(),
            free_area_m2: self.truth_cells as f64 * self.map.frame.cell_area_m2(),
            unexplorable_free_m2: (self.free.count_true() - self.truth_cells) as f64
                * self.map.frame.cell_area_m2(),
            explored_fraction: self.explored_fraction(),
            path_length_m: self.sim.path_length_m(),
            blacklisted_goals: self.blacklist.added(),
            decisions: self.decisions,
            progress: self.progress,
            trajectory: self.trajectory,
            estimated_trajectory: self.estimated_trajectory,
            map: self.map.occupancy,
            map_quality,
            scans: self.scans,
            scan_matches_accepted: self.matches_accepted,
            plans: self.plans,
            snapshots: self.snapshots,
        }
    }
}

/// A robot that stays within this radius...
const STILL_RADIUS_M: f64 = 0.5;
/// ...for this many progress timeouts is stuck.
const STILL_FACTOR: f64 = 3.0;

/// Map cells per side of a planning cell (0.05 m map: 0.1 m planning grid), on which the
/// robot's paths are searched.
const PLAN_FACTOR: u32 = 2;
/// Map cells per side of a cell of the grid on which the distances to all candidates are
/// searched (0.05 m map: 0.2 m), a multiple of `PLAN_FACTOR`. That search covers most of the
/// known building at every decision; on the coarser grid it touches a quarter of the cells.
/// The grid connects whatever the planning grid connects (a cell is passable when any of its
/// map cells is traversable), so no candidate reachable by a path is lost.
const DISTANCE_FACTOR: u32 = 4;
/// How far (planning cells) a goal may be moved to reach a passable planning cell.
const TARGET_SEARCH_CELLS: i32 = 4;
/// Largest extra cost of entering a cell near a wall (cost units, 10 per straight step).
const MAX_EXTRA: u32 = 10;
/// Least baseline gain (m2) of a frontier worth a closer look (see `Explorer::approach`): two
/// square metres, about what a doorway's view adds at once; slivers and corners add less.
const CLOSER_LOOK_MIN_GAIN_M2: f64 = 2.0;

/// A policy's answer as a decision uses it: one candidate (the next best is asked for when it
/// has no path), a ranking (the first with a path), a point of its own, none, or stop.
enum Answer {
    One(usize),
    Ranked(Vec<usize>),
    Point(Vec2),
    Nothing,
    Stop,
}

/// How a policy is asked within one decision: the attempt, whether a built-in strategy uses the
/// layout now, and the goal point of the previous attempt that had no path.
struct Asked {
    attempt: usize,
    use_layout: bool,
    unreachable_goal: Option<Vec2>,
}

/// The run's policy: the built-in strategy's rule, or the caller's.
enum PolicySlot<'a> {
    BuiltIn(strategy::BuiltInPolicy),
    External(&'a mut dyn Policy),
}

impl PolicySlot<'_> {
    fn get(&mut self) -> &mut dyn Policy {
        match self {
            PolicySlot::BuiltIn(b) => b,
            PolicySlot::External(p) => &mut **p,
        }
    }
}

fn far_search_cells() -> i32 {
    let (cells, f) = (
        TARGET_SEARCH_CELLS * PLAN_FACTOR as i32,
        DISTANCE_FACTOR as i32,
    );
    (cells + f - 1) / f
}

/// How permissive path planning is: the rungs of `decide_planned`'s last resorts, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Planning {
    /// Paths keep the robot's radius and the safety margin from the map's obstacles.
    WithMargin,
    /// The robot's radius only.
    NoMargin,
    /// The robot's radius, or any free map cell the robot has travelled.
    Travelled,
}

impl Planning {
    /// The next rung, `None` on the last.
    fn looser(self) -> Option<Self> {
        match self {
            Self::WithMargin => Some(Self::NoMargin),
            Self::NoMargin => Some(Self::Travelled),
            Self::Travelled => None,
        }
    }
}

/// The distances to the candidates, and what is needed to find the path to one of them.
struct Plan {
    /// The distance grid and the search over it.
    far: CoarseCosts,
    field: CostField,
    /// The robot's cell on the planning grid.
    near_start: Cell,
}

impl Plan {
    /// Path length (with the wall penalty) to the map cell `c`, `None` if unreachable.
    fn distance_m(&self, c: Cell) -> Option<f64> {
        self.field
            .distance_m(self.far.passable_near(c, far_search_cells())?)
    }

    /// The path to the map cell `c` on the distance grid.
    fn far_path(&self, c: Cell) -> Option<Vec<Cell>> {
        self.field
            .path_to(self.far.passable_near(c, far_search_cells())?)
    }
}

/// The cell of `grid` a path from the robot (in map cell `robot`) starts from: its own, or the
/// nearest passable one when it stands closer to a wall than the inflation radius `radius_m`
/// (it then first drives out).
fn start_cell(grid: &CoarseCosts, robot: Cell, radius_m: f64) -> Cell {
    let c = grid.coarse_of(robot);
    let r = ((2.0 * radius_m) / grid.frame.resolution_m).ceil() as i32 + 1;
    if grid.passable(c) {
        c
    } else {
        nearest_by(c, r, |n| grid.passable(n)).unwrap_or(c)
    }
}

/// A frontier whose middle cell is blacklisted, with its candidate moved to the cell nearest to
/// the middle outside every blacklisted radius (the first in row-major order among equals), or
/// `None` when every cell is blacklisted.
fn outside_blacklist(
    mut f: Frontier,
    blacklist: &Blacklist,
    frame: &GridFrame,
) -> Option<Frontier> {
    let from = f.candidate;
    let d2 = |c: &Cell| {
        let (dx, dy) = ((c.x - from.x) as i64, (c.y - from.y) as i64);
        dx * dx + dy * dy
    };
    f.candidate = *f
        .cells
        .iter()
        .filter(|c| !blacklist.contains(frame.world_from_cell(**c)))
        .min_by_key(|c| d2(c))?;
    Some(f)
}

/// What the robot faces at a goal it reached: the unknown space behind the frontier, or with
/// `robust` the frontier's outward side when that space is centred on the robot itself (within
/// 0.3 m: a frontier through the robot, whose unknown lies on both sides or right behind it).
fn look_vector(goal: &Goal, estimate: &Pose, robust: bool) -> Vec2 {
    let to = goal.look_at - estimate.position();
    match goal.look_dir {
        Some(d) if robust && to.norm() <= 0.3 => d,
        _ => to,
    }
}

/// The outward side of a frontier: the mean of the unit steps from its cells to their unknown
/// 4-neighbours, normalised (`None` when they cancel out or there are none).
fn unknown_side(grid: &OccupancyGrid, cells: &[Cell]) -> Option<Vec2> {
    let mut sum = Vec2::zeros();
    for c in cells {
        for nb in c.neighbours4() {
            if grid.is(nb, Occupancy::Unknown) {
                sum += Vec2::new(f64::from(nb.x - c.x), f64::from(nb.y - c.y));
            }
        }
    }
    (sum.norm() > 1e-9).then(|| sum / sum.norm())
}

/// Centre of the unknown cells next to a frontier.
fn unknown_centroid(grid: &OccupancyGrid, cells: &[Cell]) -> Option<Vec2> {
    let mut sum = Vec2::zeros();
    let mut n = 0usize;
    for c in cells {
        for nb in c.neighbours4() {
            if grid.is(nb, Occupancy::Unknown) {
                sum += grid.frame.world_from_cell(nb);
                n += 1;
            }
        }
    }
    (n > 0).then(|| sum / n as f64)
}

/// The rigid motion taking a point of the map (drawn at the estimated pose) to where the sensor
/// observed it in the building (the true pose): `true ∘ estimate⁻¹`.
struct MapToWorld {
    motion: Pose,
    inverse: Pose,
    /// `sin_cos` of the two motions' angles, computed once: the arithmetic is then exactly
    /// `Pose::compose`'s.
    motion_sc: (f64, f64),
    inverse_sc: (f64, f64),
}

impl MapToWorld {
    fn new(estimate: &Pose, truth: &Pose) -> Self {
        let origin = Pose::new(0.0, 0.0, 0.0);
        let motion = truth.compose(&estimate.between(&origin));
        let inverse = estimate.compose(&truth.between(&origin));
        Self {
            motion_sc: motion.theta_rad.sin_cos(),
            inverse_sc: inverse.theta_rad.sin_cos(),
            motion,
            inverse,
        }
    }

    /// `pose.compose(p)`'s position, with `(s, c)` = `pose.theta_rad.sin_cos()`.
    fn apply(pose: &Pose, (s, c): (f64, f64), p: Vec2) -> Vec2 {
        Vec2::new(pose.x_m + c * p.x - s * p.y, pose.y_m + s * p.x + c * p.y)
    }

    fn forward(&self, p: Vec2) -> Vec2 {
        Self::apply(&self.motion, self.motion_sc, p)
    }

    fn backward(&self, p: Vec2) -> Vec2 {
        Self::apply(&self.inverse, self.inverse_sc, p)
    }

    /// The building cells (index, cell; same frame) within `reach` cells of where map cell `c`
    /// lies in the building. [`Self::map_index_of`] gives the map cell each corresponds to.
    fn cells_near<'a>(
        &'a self,
        frame: &'a GridFrame,
        c: Cell,
        reach: i32,
    ) -> impl Iterator<Item = (usize, Cell)> + 'a {
        let w = self.building_cell_of(frame, c);
        (-reach..=reach)
            .flat_map(move |dy| (-reach..=reach).map(move |dx| Cell::new(w.x + dx, w.y + dy)))
            .filter_map(move |n| Some((frame.index(n)?, n)))
    }

    /// The building cell where map cell `c` lies.
    fn building_cell_of(&self, frame: &GridFrame, c: Cell) -> Cell {
        frame.cell_from_world(self.forward(frame.world_from_cell(c)))
    }

    /// The map cell (index) the centre of building cell `n` falls in, `None` off the frame.
    fn map_index_of(&self, frame: &GridFrame, n: Cell) -> Option<usize> {
        frame.index(frame.cell_from_world(self.backward(frame.world_from_cell(n))))
    }
}

/// The building's rooms as a complete layout in the map's frame (world positions brought back
/// through `to_map`, the current pose error): every room closed and fully known.
fn true_layout(rooms: &[crate::geom::Polygon], to_map: &MapToWorld) -> crate::layout::Layout {
    let rooms = rooms
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let polygon =
                crate::geom::Polygon::new(p.vertices.iter().map(|v| to_map.backward(*v)).collect());
            let area_m2 = polygon.area_m2();
            crate::layout::LayoutRoom {
                id: k as u32,
                open_edges: vec![false; polygon.vertices.len()],
                observed_polygon: polygon.clone(),
                polygon,
                label: crate::layout::RoomLabel::Partial,
                predicted: false,
                area_m2,
                observed_area_m2: area_m2,
                unknown_area_m2: 0.0,
            }
        })
        .collect();
    crate::layout::Layout {
        rooms,
        lines: Vec::new(),
        diagnostics: Default::default(),
    }
}

fn map_quality(map: &OccupancyGrid, truth_free: &Bitmap) -> MapQuality {
    let mut free = 0usize;
    let mut free_ok = 0usize;
    let mut occ = 0usize;
    let mut occ_ok = 0usize;
    for (i, s) in map.data.iter().enumerate() {
        match s {
            Occupancy::Free => {
                free += 1;
                free_ok += truth_free.data[i] as usize;
            }
            Occupancy::Occupied => {
                occ += 1;
                let c = map.frame.cell_of_index(i);
                let near_solid = std::iter::once(c)
                    .chain(c.neighbours8())
                    .any(|n| truth_free.get(n) != Some(&true));
                occ_ok += near_solid as usize;
            }
            Occupancy::Unknown => {}
        }
    }
    let ratio = |a: usize, b: usize| if b == 0 { 1.0 } else { a as f64 / b as f64 };
    MapQuality {
        free_precision: ratio(free_ok, free),
        occupied_precision: ratio(occ_ok, occ),
        occupied_precision_aligned: ratio(occ_ok, occ),
    }
}

#[cfg(test)]
pub(crate) mod tests;
