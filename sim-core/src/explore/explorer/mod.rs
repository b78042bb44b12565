//! The state of one exploration ([`Explorer`]), driven by an [`super::Episode`]; its behaviour in
//! the child modules: `sensing`, `deciding`, `driving`, `layout`, `scoring`.

use crate::explore::policy::Policy;
use crate::explore::strategy::BuiltInPolicy;

use crate::building::Building;
use crate::explore::config::{map_frame, ExploreConfig};
use crate::explore::follow::PathFollower;
use crate::explore::localization::Localizer;
use crate::explore::map_state::MapState;
use crate::explore::navigation::Navigator;
use crate::explore::policy::Needs;
use crate::explore::referee::Referee;
use crate::explore::run::{Decision, MapSnapshot, ProgressSample};
use crate::frontier::blacklist::Blacklist;
use crate::geom::{Pose, Vec2};
use crate::grid::{Bitmap, Cell, GridFrame};
use crate::sim::{RobotId, World};
use std::sync::{Arc, Mutex};

pub(crate) mod deciding;
pub(crate) mod driving;
mod layout;
mod scoring;
mod sensing;

/// A caller's measure of the layout's compute cost: it is given the computation, must run it
/// once, and returns the seconds to charge (e.g. the wall time it took).
pub type LayoutCost = Box<dyn FnMut(&mut dyn FnMut()) -> f64 + Send>;

/// The mutable state of one exploration (driven by an [`Episode`]).
pub(crate) struct Explorer {
    pub(crate) cfg: Arc<ExploreConfig>,
    pub(crate) seed: u64,
    /// The robot this state explores with (its body, odometry and laser are in the [`World`]).
    pub(crate) robot: RobotId,
    /// The world's clock (s) and the robot's true pose when it last sensed
    /// ([`Explorer::observe`]: the world moves only between two sensings).
    pub(crate) now_s: f64,
    pub(crate) true_pose: Pose,
    /// The map built from the scans, its frontiers, gains and layout (see `map_state`).
    pub(crate) map: MapState,
    /// Ground truth and the run's score (see `referee`).
    pub(crate) referee: Referee,
    /// The pose estimate (see `localization`).
    pub(crate) localizer: Localizer,
    pub(crate) blacklist: Blacklist,
    /// The goal reached (and looked at) just before the current decision.
    pub(crate) last_reached: Option<Vec2>,
    pub(crate) follower: PathFollower,
    pub(crate) goal: Option<Goal>,
    pub(crate) decisions: Vec<Decision>,
    pub(crate) progress: Vec<ProgressSample>,
    pub(crate) trajectory: Vec<Pose>,
    pub(crate) plans: u64,
    pub(crate) next_progress_s: f64,
    pub(crate) layouts_computed: u64,
    /// The caller's measure of a layout's compute cost, shared by a team's robots.
    pub(crate) layout_cost: Option<Arc<Mutex<LayoutCost>>>,
    /// Charged layout compute time the robot still has to wait for (s).
    pub(crate) compute_debt_s: f64,
    /// Layout compute time charged so far (s).
    pub(crate) layout_compute_s: f64,
    /// What the policy needs computed, whether it is the caller's (not the strategy's rule: it is
    /// then shown the layout's gains whenever it needs them), how often it was asked, whether it
    /// failed, and its compute time charged so far (s).
    pub(crate) policy_needs: Needs,
    pub(crate) caller_decides: bool,
    pub(crate) policy_decisions: usize,
    pub(crate) policy_failed: bool,
    pub(crate) strategy_compute_s: f64,
    /// Where the robot has stayed (within `STILL_RADIUS_M`) since `still_since_s`.
    pub(crate) still_at: Vec2,
    pub(crate) still_since_s: f64,
    /// For the switch strategy: the layout has been judged reliable.
    pub(crate) layout_trusted: bool,
    pub(crate) stopped_early: bool,
    pub(crate) start: Pose,
    pub(crate) snapshots: Vec<MapSnapshot>,
    /// The planning grids and path search (see `navigation`).
    pub(crate) nav: Navigator,
    /// `known_cells` when goals given up were last given another chance (see `forgive`).
    pub(crate) forgiven_at: Option<usize>,
    /// Frontier cells left at the end that the robot had not looked into (see `classify_end`).
    pub(crate) frontier_cells_left: usize,
    /// In a team: the team's size, and the robot's teammates as it knows them (set by the
    /// episode before each of its steps; empty alone).
    pub(crate) team_size: usize,
    pub(crate) mates: Vec<crate::explore::policy::Mate>,
    /// The map is a team's, lent to this robot: its end copies the map rather than taking it.
    pub(crate) shares_map: bool,
    /// In a team: when the goals given up last had another chance, and how many chances they
    /// had since the map last grew by 1 m2 (see `forgive`).
    pub(crate) team_forgiven_s: f64,
    pub(crate) team_retries: u32,
    /// In a team: the area its laser swept (for the team's overlap).
    pub(crate) coverage: Option<crate::explore::team::Coverage>,
}

#[derive(Clone)]
pub(crate) struct Goal {
    /// Where the robot drives: the candidate, or the nearest traversable cell to it.
    pub(crate) cell: Cell,
    /// The frontier's candidate (its middle cell). Blacklisting applies to candidates, so it
    /// is recorded here: the goal cell may lie farther from it than the blacklist radius, and
    /// blacklisting the goal cell would then leave the candidate to be chosen again forever.
    pub(crate) candidate: Cell,
    /// Where the unknown space behind the frontier is: the robot faces it on arrival, so that its
    /// forward-looking laser sees it.
    pub(crate) look_at: Vec2,
    /// The frontier's outward side (unit vector from its cells to their unknown neighbours, on
    /// average): faced instead when `look_at` is where the robot stands (`robust_frontiers`).
    pub(crate) look_dir: Option<Vec2>,
    pub(crate) arrived: bool,
    /// Cells of the frontier it was chosen for.
    pub(crate) frontier: Vec<Cell>,
    pub(crate) decided_at_s: f64,
    /// `MapState::known_cells` when decided.
    pub(crate) known_cells_at: usize,
    /// Shortest path length left seen so far, and when.
    pub(crate) best_distance_m: f64,
    pub(crate) best_distance_at_s: f64,
    /// In a team: when the goal's progress was last checked, and how long the robot has waited
    /// with a teammate's body beside it (its progress clocks paused: see `TEAM_WAIT_MAX_S`).
    pub(crate) checked_s: f64,
    pub(crate) waited_s: f64,
}

/// The state of `robot`'s exploration of `world` (made of `building`), starting at `start`:
/// `caller` holds the needs of the caller's policy (`None`: the strategy's rule decides);
/// `referee`, when given, is the ground truth to start from (a teammate's, on a shared map)
/// rather than one computed from `start`.
#[allow(clippy::too_many_arguments)] // each a distinct input of the state
pub(crate) fn new_explorer(
    building: &Building,
    world: &World,
    robot: RobotId,
    start: Pose,
    cfg: Arc<ExploreConfig>,
    seed: u64,
    caller: Option<Needs>,
    referee: Option<&Referee>,
) -> Explorer {
    let policy_needs = match caller {
        Some(needs) => needs,
        None => built_in_needs(&BuiltInPolicy::new(&cfg.strategy, seed), &cfg),
    };
    let frame = map_frame(&building.bounds(), cfg.map_resolution_m);
    let referee = match referee {
        Some(r) => r.clone(),
        None => new_referee(building, frame, start, &cfg),
    };
    let cap_cells =
        (((cfg.sim.robot.radius_m + cfg.safety_margin_m) / cfg.map_resolution_m).ceil() as u32 + 4)
            .max(8)
            .max((cfg.frontier_clearance_m / cfg.map_resolution_m).ceil() as u32 + 1);
    Explorer {
        seed,
        localizer: Localizer::new(start, world.odometry(robot), &cfg),
        robot,
        now_s: world.time_s(),
        true_pose: world.true_pose(robot),
        map: MapState::new(frame, cap_cells),
        referee,
        blacklist: Blacklist::new(),
        last_reached: None,
        follower: PathFollower::default(),
        goal: None,
        decisions: Vec::new(),
        progress: Vec::new(),
        trajectory: Vec::new(),
        plans: 0,
        next_progress_s: 0.0,
        layouts_computed: 0,
        still_at: start.position(),
        still_since_s: 0.0,
        layout_cost: None,
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
        nav: Navigator::new(frame, cfg.sim.robot.radius_m, cfg.safety_margin_m),
        forgiven_at: None,
        frontier_cells_left: 0,
        team_size: 1,
        mates: Vec::new(),
        shares_map: false,
        team_forgiven_s: 0.0,
        team_retries: 0,
        coverage: None,
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
pub(crate) fn built_in_needs(policy: &BuiltInPolicy, cfg: &ExploreConfig) -> Needs {
    Needs {
        layout_gain: policy.needs().layout_gain && cfg.strategy.uses_layout(),
        layout: policy.needs().layout,
        paths_between: policy.needs().paths_between,
        mate_paths: policy.needs().mate_paths,
    }
}
