//! The drivers of a run over an [`Episode`]: [`explore`], [`explore_charged`], [`explore_with`];
//! of a team's: [`explore_team`], [`drive_team_to_end`].

use crate::explore::policy::Policy;

use crate::explore::strategy::BuiltInPolicy;

use crate::building::Building;
use crate::explore::config::ExploreConfig;
use crate::explore::episode::{Episode, Event, RobotId, TeamMap};
use crate::explore::explorer::LayoutCost;
use crate::explore::run::{ProgressSample, RunResult};
use crate::explore::team::TeamResult;
use crate::geom::Pose;

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
            built_in = BuiltInPolicy::new(&cfg.strategy, seed);
            (&mut built_in, None)
        }
    };
    let episode = Episode::build(
        building,
        &[start],
        cfg.clone(),
        seed,
        caller,
        layout_cost,
        TeamMap::Separate,
    );
    drive_to_end(episode, policy, on_progress)
}

/// Drives `episode` to its end, its decisions answered by `policy` (told how the run ended),
/// its progress samples shown to `on_progress`. `policy` must be the one the episode was made
/// for (its needs: [`Episode::with_policy`]; the strategy's own rule for [`Episode::new`]).
pub fn drive_to_end(
    mut episode: Episode,
    policy: &mut dyn Policy,
    on_progress: &mut dyn FnMut(&ProgressSample),
) -> RunResult {
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
            Event::Progress(_, sample) => on_progress(&sample),
            Event::Ended(_, end) => policy.end(&end),
            Event::Finished => return episode.into_result().expect("a finished run has a result"),
        }
    }
}

/// A team's run: one robot at each of `starts` mapping as `map` says, each robot's decisions
/// answered by its own instance of the strategy's built-in rule. `on_progress` sees each
/// robot's progress samples (the team's explored area when the map is shared). A team of one
/// is [`explore`]'s run, bit for bit.
pub fn explore_team(
    building: &Building,
    starts: &[Pose],
    cfg: &ExploreConfig,
    seed: u64,
    map: TeamMap,
    on_progress: &mut dyn FnMut(RobotId, &ProgressSample),
) -> TeamResult {
    let mut rules: Vec<BuiltInPolicy> = starts
        .iter()
        .map(|_| BuiltInPolicy::new(&cfg.strategy, seed))
        .collect();
    let mut policies: Vec<&mut dyn Policy> =
        rules.iter_mut().map(|r| r as &mut dyn Policy).collect();
    let episode = Episode::team(building, starts, cfg.clone(), seed, None, map);
    drive_team_to_end(episode, &mut policies, on_progress).expect("a team has robots")
}

/// Drives a team's `episode` to its end, robot `k`'s decisions answered by `policies[k]` (told
/// how its run ended), the progress samples shown to `on_progress`. `None` for an episode
/// without robots. Panics when `policies` has fewer entries than the episode has robots.
pub fn drive_team_to_end(
    mut episode: Episode,
    policies: &mut [&mut dyn Policy],
    on_progress: &mut dyn FnMut(RobotId, &ProgressSample),
) -> Option<TeamResult> {
    loop {
        match episode.advance() {
            Event::Decide(robot) => {
                let policy = &mut policies[robot.0];
                let (reply, charged_s) = match episode.view(robot) {
                    Some(view) => policy.decide(&view),
                    None => unreachable!("a decision is pending"),
                };
                let answered = episode.answer_charged(robot, reply, charged_s);
                debug_assert!(answered.is_ok());
            }
            Event::Progress(robot, sample) => on_progress(robot, &sample),
            Event::Ended(robot, end) => policies[robot.0].end(&end),
            Event::Finished => return episode.into_team_result(),
        }
    }
}
