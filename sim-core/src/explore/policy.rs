//! The decision seen from outside the explorer: a [`Policy`] is asked, at every decision, which
//! of the reachable frontier candidates to drive to, given what a strategy may know (the robot's
//! estimated pose, the candidates with their distances and gains, the map). Every strategy
//! decides through one: the built-in ones through [`super::strategy::BuiltInPolicy`] (their
//! early stop and the paper's utility), an external program speaking floorcast's strategy
//! protocol through its own (in the `floorcast-worker` crate: sim-core does no IO). The explorer
//! keeps everything else: mapping, frontiers, planning, the gains, the last resorts before a run
//! ends, scoring the run.
//!
//! A policy never sees ground truth: only what the explorer derives from the laser and the
//! odometry.

use crate::geom::{Pose, Vec2};
use crate::grid::{Cell, OccupancyGrid};

/// What a policy asks the explorer to compute for it besides the baseline gains.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Needs {
    /// The paper's `I(p)` inside the rooms of the layout predicted from the map
    /// ([`CandidateView::layout_gain_m2`]); the layout is rebuilt as for the layout strategies.
    pub layout_gain: bool,
    /// The rooms of the layout predicted from the map ([`DecisionView::layout`]) and each
    /// candidate's room ([`CandidateView::room`]); the layout is rebuilt as for the layout
    /// strategies.
    pub layout: bool,
    /// The planned path lengths between the candidates' goals
    /// ([`DecisionView::between_m`]): one search of the distance grid per candidate.
    pub paths_between: bool,
    /// In a team: the planned path lengths from each teammate to each candidate's goal
    /// ([`TeamView::mate_paths_m`]): one search of the distance grid per teammate.
    pub mate_paths: bool,
}

/// One reachable frontier candidate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CandidateView {
    /// The candidate's number at this decision (stable across the attempts of one decision).
    pub id: usize,
    /// The frontier's candidate cell (its middle cell) and that cell's centre.
    pub cell: Cell,
    pub point: Vec2,
    /// Where the robot would drive: the candidate, or the nearest traversable cell to it.
    pub goal: Vec2,
    /// Cells of the frontier.
    pub frontier_cells: usize,
    /// The utility's `D(p)` as the run's `utility_distance` defines it (m).
    pub distance_m: f64,
    /// Planned path length to the goal on the distance grid (m).
    pub path_m: f64,
    /// Straight line from the robot's estimated position to `point` (m).
    pub straight_m: f64,
    /// The baseline information gain `I(p)` (m2).
    pub gain_m2: f64,
    /// The paper's `I(p)` inside the predicted rooms (m2), when the policy needs it and a
    /// layout exists.
    pub layout_gain_m2: Option<f64>,
    /// The index into [`LayoutView::rooms`] of the predicted room holding the candidate, when
    /// the policy needs the layout and a room holds it.
    pub room: Option<usize>,
}

/// One room of the layout predicted from the map (never the building's true rooms).
#[derive(Debug, Clone, PartialEq)]
pub struct RoomView {
    /// The room's shape, prediction included (map frame, m, counter-clockwise).
    pub polygon: Vec<Vec2>,
    /// What the map shows of it: completely observed (no frontier in it), partially observed
    /// and closed by wall lines, or open (its prediction reaches the known map's edge).
    pub state: RoomState,
    /// Whether the prediction added to what was observed.
    pub predicted: bool,
    /// Area (m2): the whole room, its observed part, and its cells still unknown.
    pub area_m2: f64,
    pub observed_area_m2: f64,
    pub unknown_area_m2: f64,
}

/// How much of a room the map shows (the layout method's room label).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RoomState {
    Full,
    Partial,
    Open,
}

impl RoomState {
    pub fn as_str(self) -> &'static str {
        match self {
            RoomState::Full => "full",
            RoomState::Partial => "partial",
            RoomState::Open => "open",
        }
    }
}

/// The current layout as a policy sees it.
#[derive(Debug, Clone, Copy)]
pub struct LayoutView<'a> {
    /// Which layout this is: 1 for the run's first, counting up as it is rebuilt while the map
    /// grows (a policy can keep what it derived from a layout until the number changes).
    pub number: u64,
    pub rooms: &'a [RoomView],
}

impl LayoutView<'_> {
    /// The index of the first room whose polygon holds `p`.
    pub fn room_holding(&self, p: Vec2) -> Option<usize> {
        self.rooms.iter().position(|r| {
            crate::geom::Polygon {
                vertices: r.polygon.clone(),
            }
            .contains(p)
        })
    }
}

/// What a policy is shown at a decision.
#[derive(Debug, Clone, Copy)]
pub struct DecisionView<'a> {
    /// Decisions asked before this one.
    pub decision: usize,
    /// 0, then 1, 2, ... when the chosen candidate had no drivable path and the policy is asked
    /// again within the same decision (without that candidate).
    pub attempt: usize,
    /// Simulated time (s).
    pub time_s: f64,
    /// The robot's estimated pose in the map frame.
    pub pose: Pose,
    /// The reachable candidates (never empty).
    pub candidates: &'a [CandidateView],
    /// The point of the previous attempt's [`Reply::Goal`] when no drivable path led there.
    pub unreachable_goal: Option<Vec2>,
    /// The layout predicted from the map, when the policy needs it and one exists.
    pub layout: Option<LayoutView<'a>>,
    /// The map as the robot has built it.
    pub map: &'a OccupancyGrid,
    /// When the policy needs them: the planned path lengths (m) between the candidates' goals,
    /// row-major in the order of `candidates` (`n * n` values; infinite where no path leads).
    pub between_m: Option<&'a [f64]>,
    /// In a team of more than one robot: the teammates as the deciding robot knows them.
    pub team: Option<TeamView<'a>>,
}

/// A teammate as the deciding robot knows it (from the team's communication: its estimated pose
/// and its goal as last exchanged).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mate {
    /// Its number in the team (0 to N - 1).
    pub robot: usize,
    /// Its estimated pose (map frame).
    pub pose: Pose,
    /// The goal it drives to (map frame, m): the point of the candidate it chose, `None` while
    /// it has none.
    pub goal: Option<Vec2>,
    /// Whether it is still exploring (its exploration has not ended).
    pub exploring: bool,
    /// When this was last heard from it (simulated time, s).
    pub heard_s: f64,
}

/// The team as the deciding robot sees it.
#[derive(Debug, Clone, Copy)]
pub struct TeamView<'a> {
    /// The deciding robot's number in the team.
    pub robot: usize,
    /// The team's size (the deciding robot included).
    pub size: usize,
    /// The other robots, in the order of their numbers.
    pub mates: &'a [Mate],
    /// When the policy needs them ([`Needs::mate_paths`]): the planned path lengths (m) from
    /// each mate's estimated position to each candidate's goal on the deciding robot's map,
    /// row-major mates by candidates (`mates.len() * candidates.len()` values; infinite where
    /// no path leads).
    pub mate_paths_m: Option<&'a [f64]>,
}

impl TeamView<'_> {
    /// The path length (m) from mate `m` (an index into `mates`) to candidate `c` (an index into
    /// the view's candidates), when computed.
    pub fn mate_path_m(&self, m: usize, c: usize, candidates: usize) -> Option<f64> {
        self.mate_paths_m.map(|p| p[m * candidates + c])
    }
}

/// How many [`Reply::Goal`] points without a drivable path one decision takes: the last of them
/// counts as [`Reply::Pass`].
pub const MAX_UNREACHABLE_GOALS: usize = 8;

/// A policy's answer.
#[derive(Debug, Clone, PartialEq)]
pub enum Reply {
    /// Drive to the candidate with this id.
    Choose(usize),
    /// Try these candidates in this order and take the first with a drivable path; the others
    /// are not tried at this decision.
    Rank(Vec<usize>),
    /// Drive to this point (map frame, m), or to the nearest traversable cell within 0.5 m of
    /// it: a goal of the policy's own, not a frontier's. When no drivable path leads there the
    /// policy is asked again (the next attempt, with the point in
    /// [`DecisionView::unreachable_goal`]); the [`MAX_UNREACHABLE_GOALS`]th such point in a
    /// decision counts as [`Reply::Pass`]. A point that is not finite is a failure.
    Goal(Vec2),
    /// Give these candidates up (each frontier blacklisted within `blacklist_radius_m` of its
    /// candidate cell for the rest of the run, as one that cannot be reached: the rest of a long
    /// frontier may be offered again, with another candidate cell) and ask again without them
    /// (the next attempt; when none is left, as [`Reply::Pass`]). An empty list, a repeated id
    /// or one not shown is a failure.
    Drop(Vec<usize>),
    /// None of these candidates: the decision goes on as when no candidate has a path (the
    /// explorer's last resorts, else the run ends).
    Pass,
    /// End the exploration (an early stop). Before it ends a run with frontiers left, the
    /// explorer asks again with the candidates of its last resorts (frontiers' reachable
    /// parts, plans with less clearance), if any: a stop stands when the policy says it again.
    Stop,
    /// The policy failed (it says why to its caller): the run ends at once, its result is not
    /// to be used.
    Fail,
}

/// How a run ended, for the policy's last message.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunEnd {
    pub reason: super::EndReason,
    pub exploration_time_s: f64,
    pub explored_fraction: f64,
    pub decisions: usize,
}

/// A decision rule the explorer consults instead of its built-in strategy's.
pub trait Policy {
    /// What the explorer must compute for the policy.
    fn needs(&self) -> Needs;
    /// The choice at one decision, and the compute time to charge to simulated time for it
    /// (s; 0 when nothing is charged). A reply naming no candidate of the view is a failure
    /// of the policy; the explorer treats it as [`Reply::Fail`].
    fn decide(&mut self, view: &DecisionView<'_>) -> (Reply, f64);
    /// The run ended (no reply).
    fn end(&mut self, _end: &RunEnd) {}
}
