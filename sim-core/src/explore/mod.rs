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
//! frame by the current pose error (`true_layout`), rasterised by `LayoutRaster::exact`, its walls
//! opened at the true doors, where the building has no wall and where the robot has not seen
//! them at a frontier (`referee`); it is the only strategy whose decisions read ground truth.
//!
//! These incremental structures (frontier tracker, gain cache, planning cells) change no result:
//! runs are bit-identical to full recomputation.
//!
//! The modules, each using only those below it (no two use each other; tests/module_cycles.rs):
//! - `episode`: [`Episode`], the run as a state machine driven from outside; `drive`: the drivers
//!   over it ([`explore`], [`explore_with`]); `shared`: runs sharing their beginning.
//! - `explorer`: the `Explorer`, the state of one run, and its behaviour in its children:
//!   `sensing`, `deciding` (frontiers, scores, the question to the policy, the last resorts, as
//!   explicit states), `driving`, `layout`, `scoring` (what reads ground truth).
//! - The components it holds: `map_state` (the `MapState`: grid, obstacle distances, known
//!   cells, frontiers, gain cache, layout; `integrate` returns what changed), `localization` (the
//!   `Localizer`, the pose estimate), `navigation` (the `Navigator`, the planning grids),
//!   `referee` (ground truth, the explored area), `layout_state`, `gain_cache`, `follow`,
//!   `calibration`.
//! - What crosses the boundary: `config` ([`ExploreConfig`]), `run` ([`RunResult`]), `policy`
//!   (what a policy sees and replies), `strategy` (strategies as values), `strategies` (the built-in
//!   ones, one file each).

mod calibration;
mod config;
mod drive;
mod episode;
mod explorer;
mod follow;
mod gain_cache;
mod layout_state;
mod localization;
mod map_state;
mod navigation;
pub mod policy;
mod referee;
mod run;
mod shared;
pub mod strategies;
pub mod strategy;
mod team;

pub use crate::utility::UtilityDistance;
pub use config::{map_frame, map_margin_m, ExploreConfig, Localization};
pub use drive::{
    drive_team_to_end, drive_to_end, explore, explore_charged, explore_team, explore_with, Hooks,
};
pub use episode::{Episode, EpisodeError, Event, RobotId, TeamMap, MAX_ROBOTS};
pub use explorer::LayoutCost;
pub use follow::{Command, FollowConfig, PathFollower};
pub use layout_state::LayoutUse;
pub use policy::{
    CandidateView, DecisionView, LayoutView, Mate, Needs, Policy, Reply, RoomState, RoomView,
    RunEnd, TeamView, MAX_UNREACHABLE_GOALS,
};
pub use run::{Decision, EndReason, MapQuality, MapSnapshot, ProgressSample, RunResult};
pub use shared::{can_share, explore_shared, shared_part};
pub use strategies::{BuiltIn, BUILT_IN};
pub use strategy::{Choice, EarlyStop, GainModel, LayoutSource, Strategy, StrategyParams};
pub use team::{RobotFigures, TeamResult};

#[cfg(test)]
pub(crate) mod tests;
