//! What shapes a run besides the building, the start and the seed: [`ExploreConfig`], and the
//! grid its map is drawn on.

use crate::explore::follow::FollowConfig;
use crate::explore::layout_state::LayoutUse;
use crate::explore::strategy::Strategy;
use crate::grid::GridFrame;
use crate::mapping::log_odds::LogOddsConfig;
use crate::mapping::scan_match::ScanMatchConfig;
use crate::sim::SimConfig;
use crate::utility::UtilityDistance;

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
