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
//! `Explorer::set_planning` for that decision only; each level's planning grids are kept while
//! another is in use and brought up to date when it is used again). Every run ends in one
//! [`EndReason`] (`Explorer::classify_end`).
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
//!
//! The explorer's work is split over files: `localization` (the `Localizer`, which owns the pose
//! estimate, and the explorer's sensing and map), `navigation` (the `Navigator`, which owns the
//! planning grids and plans on the map it is given; driving, the goal while driving),
//! `layout_state`, `decision` (frontiers, scores, the policy, the last resorts) and `referee`
//! (what reads ground truth: the explored area, how the run ended, its scores); the last three
//! are `impl Explorer` blocks.

mod calibration;
mod decision;
mod episode;
mod follow;
mod gain_cache;
mod layout_state;
mod localization;
mod navigation;
pub mod policy;
mod referee;
mod shared;
pub mod strategy;

pub use crate::utility::UtilityDistance;
pub use episode::{Episode, EpisodeError, Event, RobotId};
pub use follow::{Command, FollowConfig, PathFollower};
pub use layout_state::LayoutUse;
pub use policy::{
    CandidateView, DecisionView, LayoutView, Needs, Policy, Reply, RoomState, RoomView, RunEnd,
    MAX_UNREACHABLE_GOALS,
};
pub use strategy::{
    BuiltIn, Choice, EarlyStop, GainModel, LayoutSource, Strategy, StrategyParams, BUILT_IN,
};

use self::calibration::OdometryCalibration;
use self::gain_cache::{GainCache, GainKind};
use self::layout_state::*;
use self::localization::*;
use self::navigation::*;
use self::referee::*;
pub use self::shared::{can_share, explore_shared, shared_part};
use crate::building::Building;
use crate::frontier::blacklist::Blacklist;
use crate::frontier::detect::{
    frontiers_where, is_frontier_cell, Frontier, FrontierConfig, FrontierTracker,
};
use crate::gain::{information_count_read, information_gain};
use crate::geom::{Pose, Vec2};
use crate::grid::{Bitmap, Cell, GridFrame, Occupancy, OccupancyGrid};
use crate::layout::reconstruct_layout;
use crate::layout_gain::{
    gap_closed_information_gain_read, layout_information_gain_read, LayoutRaster,
};
use crate::mapping::distance_field::ObstacleDistance;
use crate::mapping::log_odds::{LogOddsConfig, LogOddsMap};
use crate::mapping::ray::{grid_from_world, walk_segment};
use crate::mapping::scan_match::{match_scan, ScanMatchConfig};
use crate::plan::coarse::CoarseCosts;
use crate::plan::dijkstra::{
    dijkstra_padded, dijkstra_padded_bounded, dijkstra_padded_within, padded_index, AStar,
    CostField,
};
use crate::plan::inflate::{nearest_by, Traversability};
use crate::plan::waypoints::waypoints_by;
use crate::sim::{SimConfig, Simulator};
use crate::utility::CandidateScore;
use std::sync::Arc;

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

/// Everything that shapes a run besides the building, the start and the seed.
#[derive(Debug, Clone, PartialEq)]
pub struct ExploreConfig {
    pub sim: SimConfig,
    /// How candidates' gains are estimated, when to stop early and how to choose.
    pub strategy: Strategy,
    /// Parameters of the layout reconstruction (for layout-informed strategies).
    pub layout: crate::layout::LayoutConfig,
    /// How the layout is kept and drawn for the gains, whoever asks for it (a layout strategy or
    /// a policy that needs the layout).
    pub layout_use: LayoutUse,
    pub localization: Localization,
    pub map_resolution_m: f64,
    pub log_odds: LogOddsConfig,
    pub scan_match: ScanMatchConfig,
    /// With SLAM: learn the odometry's proportional error from the scan matches and correct it.
    pub calibrate_odometry: bool,
    /// What the utility's `D(p)` measures: the planned path's length (default) or, as in the
    /// paper, the straight line from the robot to the candidate.
    pub utility_distance: UtilityDistance,
    /// Bound the distance search of a decision to paths of this length (m; 0 = off, the
    /// paper's: every candidate's path searched at every decision, which on a large building is
    /// most of the known map each time). With a bound, candidates beyond it take their path
    /// lengths from the last search of everything reachable, made within `bound / 4` of where
    /// the robot stands (an approximation of `Dmax` and of far candidates' `D(p)`), and a
    /// choice of a candidate beyond the bound, a pass or a stop is made again with every
    /// distance searched: the robot heads only for goals whose distance is exact. Built-in
    /// strategies only (a strategy of the caller's is asked once per decision). docs/scale.md.
    pub distance_bound_m: f64,
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
            layout_use: LayoutUse::default(),
            utility_distance: UtilityDistance::Path,
            distance_bound_m: 0.0,
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

/// The mutable state of one exploration (driven by an [`Episode`]).
struct Explorer {
    cfg: Arc<ExploreConfig>,
    seed: u64,
    sim: Simulator,
    map: LogOddsMap,
    obstacles: ObstacleDistance,
    /// Ground truth and the run's score (see `referee`).
    referee: Referee,
    /// Map cells observed (free or occupied) so far.
    known: Bitmap,
    /// The map cells the last update made known (a buffer kept between updates).
    fresh_known: Vec<usize>,
    /// The pose estimate (see `localization`).
    localizer: Localizer,
    blacklist: Blacklist,
    /// The goal reached (and looked at) just before the current decision.
    last_reached: Option<Vec2>,
    follower: PathFollower,
    goal: Option<Goal>,
    decisions: Vec<Decision>,
    progress: Vec<ProgressSample>,
    trajectory: Vec<Pose>,
    plans: u64,
    /// Candidates' gains of every kind (the paper's room-bounded `I(p)` for ranking and early
    /// stopping among them).
    gains: GainCache,
    next_progress_s: f64,
    /// Cells of the map that are known (free or occupied), counted from the map's own changes.
    known_cells: usize,
    layout: Option<LayoutState>,
    layouts_computed: u64,
    layout_cost: Option<LayoutCost>,
    /// Charged layout compute time the robot still has to wait for (s).
    compute_debt_s: f64,
    /// Layout compute time charged so far (s).
    layout_compute_s: f64,
    /// What the policy needs computed, whether it is the caller's (not the strategy's rule: it is
    /// then shown the layout's gains whenever it needs them), how often it was asked, whether it
    /// failed, and its compute time charged so far (s).
    policy_needs: Needs,
    caller_decides: bool,
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
    /// The map's frontier cells, updated with each map update.
    frontiers: FrontierTracker,
    /// The planning grids and path search (see `navigation`).
    nav: Navigator,
    /// `known_cells` when goals given up were last given another chance (see `forgive`).
    forgiven_at: Option<usize>,
    /// Frontier cells left at the end that the robot had not looked into (see `classify_end`).
    frontier_cells_left: usize,
}

#[derive(Clone)]
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
pub type LayoutCost = Box<dyn FnMut(&mut dyn FnMut()) -> f64 + Send>;

/// [`explore`], with the cost of every layout computation charged to simulated time when
/// `layout_cost` is given: the robot stands still (sensing) for the seconds it returns, right
/// after the decision that needed the layout. The core has no clock, so the caller measures;
/// a run charged with measured wall time depends on the machine and is no longer reproducible.
pub fn explore_charged(
    building: &Building,
    start: Pose,
    cfg: &ExploreConfig,
    seed: u64,
    on_progress: &mut dyn FnMut(&ProgressSample),
    layout_cost: Option<LayoutCost>,
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
    pub layout_cost: Option<LayoutCost>,
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

/// [`explore`] with the caller's [`Hooks`]: an [`Episode`] driven to its end, its decisions
/// answered by the caller's policy or the strategy's built-in rule.
pub fn explore_with(
    building: &Building,
    start: Pose,
    cfg: &ExploreConfig,
    seed: u64,
    on_progress: &mut dyn FnMut(&ProgressSample),
    hooks: Hooks<'_>,
) -> RunResult {
    let Hooks {
        layout_cost,
        policy,
    } = hooks;
    let mut built_in;
    let (policy, caller): (&mut dyn Policy, _) = match policy {
        Some(p) => {
            let needs = p.needs();
            (p, Some(needs))
        }
        None => {
            built_in = strategy::BuiltInPolicy::new(&cfg.strategy, seed);
            (&mut built_in, None)
        }
    };
    let mut episode = Episode::build(building, start, cfg.clone(), seed, caller, layout_cost);
    loop {
        match episode.advance() {
            Event::Decide(robot) => {
                let (reply, charged_s) = match episode.view(robot) {
                    Some(view) => policy.decide(&view),
                    None => unreachable!("a decision is pending"),
                };
                let answered = episode.answer_charged(robot, reply, charged_s);
                debug_assert!(answered.is_ok());
            }
            Event::Progress(sample) => on_progress(&sample),
            Event::Ended(end) => policy.end(&end),
            Event::Finished => return episode.into_result().expect("a finished run has a result"),
        }
    }
}

/// The state of a run at its start: `caller` holds the needs of the caller's policy (`None`:
/// the strategy's rule decides).
fn new_explorer(
    building: &Building,
    start: Pose,
    cfg: Arc<ExploreConfig>,
    seed: u64,
    caller: Option<Needs>,
    layout_cost: Option<LayoutCost>,
) -> Explorer {
    let policy_needs = match caller {
        Some(needs) => needs,
        None => built_in_needs(&strategy::BuiltInPolicy::new(&cfg.strategy, seed), &cfg),
    };
    let frame = map_frame(&building.bounds(), cfg.map_resolution_m);
    let referee = new_referee(building, frame, start, &cfg);
    let cap_cells =
        (((cfg.sim.robot.radius_m + cfg.safety_margin_m) / cfg.map_resolution_m).ceil() as u32 + 4)
            .max(8)
            .max((cfg.frontier_clearance_m / cfg.map_resolution_m).ceil() as u32 + 1);
    let sim = Simulator::new(building, start, &cfg.sim, seed);
    Explorer {
        seed,
        localizer: Localizer::new(start, sim.odometry(), &cfg),
        sim,
        map: LogOddsMap::new(frame),
        obstacles: ObstacleDistance::new(frame, cap_cells),
        referee,
        known: Bitmap::filled(frame, false),
        fresh_known: Vec::new(),
        blacklist: Blacklist::new(),
        last_reached: None,
        follower: PathFollower::default(),
        goal: None,
        decisions: Vec::new(),
        progress: Vec::new(),
        trajectory: Vec::new(),
        plans: 0,
        gains: GainCache::new(frame),
        next_progress_s: 0.0,
        known_cells: 0,
        layout: None,
        layouts_computed: 0,
        still_at: start.position(),
        still_since_s: 0.0,
        layout_cost,
        compute_debt_s: 0.0,
        layout_compute_s: 0.0,
        policy_needs,
        caller_decides: caller.is_some(),
        policy_decisions: 0,
        policy_failed: false,
        strategy_compute_s: 0.0,
        layout_trusted: false,
        stopped_early: false,
        start,
        snapshots: Vec::new(),
        frontiers: FrontierTracker::default(),
        nav: Navigator::new(frame, cfg.sim.robot.radius_m, cfg.safety_margin_m),
        forgiven_at: None,
        frontier_cells_left: 0,
        cfg,
    }
}

/// The referee of a run from `start` in `building` on the map's `frame`: the free space the
/// robot can reach and the part of it it can explore, nothing explored yet.
fn new_referee(building: &Building, frame: GridFrame, start: Pose, cfg: &ExploreConfig) -> Referee {
    let free = building.reachable_free(frame, start.position());
    let truth = crate::building::explorable_free(
        &free,
        start.position(),
        cfg.sim.robot.radius_m + cfg.safety_margin_m,
        cfg.sim.laser.max_range_m,
    );
    let truth_cells = truth.count_true();
    Referee {
        truth,
        free,
        truth_cells,
        explored_cells: 0,
        explored: Bitmap::filled(frame, false),
        untestable: Bitmap::filled(frame, false),
        untestable_list: Vec::new(),
        rooms: building.rooms.iter().map(|r| r.polygon.clone()).collect(),
        doors: building.doors.iter().map(|d| (d.a, d.b)).collect(),
    }
}

/// What a built-in strategy's rule needs: the paper's I(p) only when the strategy uses the
/// layout; the layout's rooms when its choice asks for them (`room-first`).
fn built_in_needs(policy: &strategy::BuiltInPolicy, cfg: &ExploreConfig) -> Needs {
    Needs {
        layout_gain: policy.needs().layout_gain && cfg.strategy.uses_layout(),
        layout: policy.needs().layout,
        paths_between: policy.needs().paths_between,
    }
}

#[cfg(test)]
pub(crate) mod tests;
