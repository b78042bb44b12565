//! Runs that share their beginning. Strategies whose settings differ only in the early stop
//! (`layout`, `layout-es` and `layout-aes`; `layout-gaps` and `layout-gaps-es`; the oracle's
//! two) see the same candidates and, until one of their rules stops or drops what another
//! keeps, make the same choices: the runs are identical up to that decision. On the paper's
//! grid a `layout-es` run follows its `layout` twin for 96-100 % of its progress curve (median
//! 99.98 %). [`explore_shared`] runs them as one [`Episode`]: the first configuration leads,
//! every other's rule is asked alongside at each of its decisions, and a run whose reply first
//! differs goes on alone from the last copy of the episode taken at a decision before (one every
//! [`CHECKPOINT_DECISIONS`] decisions); a run that never differs is the leader's up to its end.
//! Each result is bit-identical to the run made alone (tested).

use crate::building::Building;
use crate::explore::config::ExploreConfig;
use crate::explore::drive::{drive_to_end, explore};
use crate::explore::episode::{Episode, Event, Phase, Robot, RobotId};
use crate::explore::explorer::deciding::Deciding;
use crate::explore::explorer::{built_in_needs, Explorer};
use crate::explore::policy::{Needs, Policy, Reply};
use crate::explore::run::{ProgressSample, RunResult};
use crate::explore::strategy::BuiltInPolicy;
use crate::geom::Pose;
use std::sync::Arc;

use std::rc::Rc;

/// Decisions between two copies of the leading run's state: the most a run that parts from
/// it repeats. A copy costs about as much as a few decisions.
pub(super) const CHECKPOINT_DECISIONS: usize = 20;

/// One run following the leader.
struct Member {
    index: usize,
    cfg: ExploreConfig,
    policy: BuiltInPolicy,
    needs: Needs,
    /// Its policy at the last checkpoint.
    policy_at_checkpoint: BuiltInPolicy,
    /// Once its reply differed from the leader's: the checkpoint before that decision, its
    /// policy then, and the clock then.
    parted: Option<(Rc<Episode>, BuiltInPolicy, f64)>,
}

/// What runs that share their beginning have in common: the configuration without the
/// strategy's early stop. Runs of equal shared parts (and the same building, start and seed) can
/// be made together by [`explore_shared`].
pub fn shared_part(cfg: &ExploreConfig) -> ExploreConfig {
    ExploreConfig {
        strategy: cfg.strategy.without_early_stop(),
        ..cfg.clone()
    }
}

/// Whether the runs of `cfgs` can be made by [`explore_shared`] (at least two, all with the same
/// settings but for the strategy's early stop).
pub fn can_share(cfgs: &[ExploreConfig]) -> bool {
    cfgs.len() >= 2 && cfgs.iter().all(|c| shared_part(c) == shared_part(&cfgs[0]))
}

/// One exploration of `building` from `start` with `seed` per configuration of `cfgs`, each
/// bit-identical to [`explore`]'s, made together where they agree (see the module doc; when
/// [`can_share`] does not hold, one after the other). Put the configuration expected to run
/// longest (no early stop) first: it leads. `clock` returns the seconds since the call began
/// (the caller reads the clock); each run comes with the seconds it took: its own part, and the
/// shared part up to where it went alone. `on_progress` sees the leader's progress.
pub fn explore_shared(
    building: &Building,
    start: Pose,
    cfgs: &[ExploreConfig],
    seed: u64,
    on_progress: &mut dyn FnMut(&ProgressSample),
    clock: &mut dyn FnMut() -> f64,
) -> Vec<(RunResult, f64)> {
    if !can_share(cfgs) {
        let mut out = Vec::new();
        for cfg in cfgs {
            let t0 = clock();
            let r = explore(building, start, cfg, seed, on_progress);
            out.push((r, clock() - t0));
        }
        return out;
    }
    let mut leader = Episode::new(building, start, cfgs[0].clone(), seed);
    let mut policy = BuiltInPolicy::new(&cfgs[0].strategy, seed);
    let mut together = Together {
        members: cfgs[1..]
            .iter()
            .enumerate()
            .map(|(k, cfg)| Member::new(k + 1, cfg, seed))
            .collect(),
        checkpoint: None,
        checkpoint_decisions: 0,
    };
    let mut out: Vec<Option<(RunResult, f64)>> = (0..cfgs.len()).map(|_| None).collect();
    // The clock when the leader's exploration ended, and when its own ending began.
    let (mut shared_s, mut own_s) = (0.0, 0.0);
    loop {
        match leader.advance() {
            Event::Decide(robot) => {
                together.checkpoint_if_due(&leader, &cfgs[0], clock);
                let (reply, charged_s) = match leader.view(robot) {
                    Some(view) => policy.decide(&view),
                    None => unreachable!("a decision is pending"),
                };
                together.ask_members(&mut leader, robot, &reply);
                let answered = leader.answer_charged(robot, reply, charged_s);
                debug_assert!(answered.is_ok());
            }
            Event::Progress(_, s) => on_progress(&s),
            Event::Ended(..) => {
                // The members that never parted: the leader's run up to its end, then their
                // own ending.
                shared_s = clock();
                for m in together.following() {
                    let t0 = clock();
                    let r = finish_alone(leader.fork(&m.cfg), &mut m.policy);
                    out[m.index] = Some((r, shared_s + clock() - t0));
                }
                own_s = clock();
            }
            Event::Finished => break,
        }
    }
    let r = leader.into_result().expect("a finished run has a result");
    out[0] = Some((r, shared_s + clock() - own_s));
    // The others from the copy made before they parted.
    for m in together.members {
        if let Some((from, mut policy, at_s)) = m.parted {
            let t0 = clock();
            let r = finish_alone(from.fork(&m.cfg), &mut policy);
            out[m.index] = Some((r, at_s + clock() - t0));
        }
    }
    out.into_iter()
        .map(|r| r.expect("every run made"))
        .collect()
}

/// The members of a shared run, and the leader's last checkpoint.
struct Together {
    members: Vec<Member>,
    /// The leader's state at a decision when last copied, and the clock then.
    checkpoint: Option<(Rc<Episode>, f64)>,
    /// The leader's decisions asked at that copy.
    checkpoint_decisions: usize,
}

impl Together {
    /// The members still following the leader.
    fn following(&mut self) -> impl Iterator<Item = &mut Member> {
        self.members.iter_mut().filter(|m| m.parted.is_none())
    }

    /// At a decision of the `leader` (settings `cfg`): a copy of its state for the members
    /// still following, every [`CHECKPOINT_DECISIONS`] decisions (and at the first).
    fn checkpoint_if_due(
        &mut self,
        leader: &Episode,
        cfg: &ExploreConfig,
        clock: &mut dyn FnMut() -> f64,
    ) {
        let asked = leader.robots[0].ex.policy_decisions;
        let due =
            self.checkpoint.is_none() || asked >= self.checkpoint_decisions + CHECKPOINT_DECISIONS;
        if !due || self.following().next().is_none() {
            return;
        }
        // (The previous copy dropped first, unless a member that parted holds it: two copies
        // of a large map at once are a lot.)
        drop(self.checkpoint.take());
        self.checkpoint = Some((Rc::new(leader.fork(cfg)), clock()));
        self.checkpoint_decisions = asked;
        for m in self.following() {
            m.policy_at_checkpoint = m.policy.clone();
        }
    }

    /// Every member still following is asked the decision pending with the candidates as it
    /// sees them; those whose reply differs from the leader's `reply` part.
    fn ask_members(&mut self, leader: &mut Episode, robot: RobotId, reply: &Reply) {
        let checkpoint = self.checkpoint.clone();
        for m in self.following() {
            if leader.ask_alongside(robot, &mut m.policy, m.needs) != *reply {
                let (from, at_s) = checkpoint
                    .clone()
                    .expect("a checkpoint is taken at the first decision");
                m.parted = Some((from, m.policy_at_checkpoint.clone(), at_s));
            }
        }
    }
}

impl Member {
    /// Member `index` of the shared run, with settings `cfg`.
    fn new(index: usize, cfg: &ExploreConfig, seed: u64) -> Member {
        let policy = BuiltInPolicy::new(&cfg.strategy, seed);
        Member {
            index,
            cfg: cfg.clone(),
            needs: built_in_needs(&policy, cfg),
            policy_at_checkpoint: policy.clone(),
            policy,
            parted: None,
        }
    }
}

/// Drives `episode` to its end, its decisions answered by `policy`.
fn finish_alone(episode: Episode, policy: &mut BuiltInPolicy) -> RunResult {
    drive_to_end(episode, policy, &mut |_| {})
}

impl Episode {
    /// This episode's state, to go on with `cfg` (whose settings may differ from this run's in
    /// the early stop only) answered by its built-in rule. A decision pending is shown anew as
    /// that rule sees it. Hooks are not copied (shared runs have none).
    pub(super) fn fork(&self, cfg: &ExploreConfig) -> Episode {
        let cfg = Arc::new(cfg.clone());
        let robots = self.robots.iter().map(|r| {
            let needs = built_in_needs(&BuiltInPolicy::new(&cfg.strategy, r.ex.seed), &cfg);
            let mut ex = Box::new(r.ex.fork(Arc::clone(&cfg), needs));
            let phase = match &r.phase {
                Phase::Deciding(d) => {
                    let mut d: Box<Deciding> = d.clone();
                    let (views, between) = d.show(&mut ex, needs);
                    d.views = views;
                    d.between = between;
                    Phase::Deciding(d)
                }
                other => other.clone(),
            };
            Robot {
                ex,
                phase,
                progress_sent: r.progress_sent,
                own_nav: r.own_nav.clone(),
                result: None,
            }
        });
        Episode {
            world: self.world.clone(),
            robots: robots.collect(),
            cfg,
            shared: None,
        }
    }

    /// The reply `policy` (a rule needing `needs`) gives to the decision pending for `robot`,
    /// shown as it would see it.
    fn ask_alongside(&mut self, robot: RobotId, policy: &mut BuiltInPolicy, needs: Needs) -> Reply {
        let r = &mut self.robots[robot.0];
        let Phase::Deciding(d) = &r.phase else {
            unreachable!("asked alongside a decision pending")
        };
        let (views, between) = d.show(&mut r.ex, needs);
        let view =
            r.ex.decision_view(&r.ex.map, &views, &d.asked, needs, between.as_deref(), None);
        policy.decide(&view).0
    }
}

impl Explorer {
    /// This run's state, to go on with `cfg` and a built-in rule needing `needs`.
    fn fork(&self, cfg: Arc<ExploreConfig>, needs: Needs) -> Explorer {
        Explorer {
            cfg,
            seed: self.seed,
            robot: self.robot,
            now_s: self.now_s,
            true_pose: self.true_pose,
            map: self.map.clone(),
            referee: self.referee.clone(),
            localizer: self.localizer.clone(),
            blacklist: self.blacklist.clone(),
            last_reached: self.last_reached,
            follower: self.follower.clone(),
            goal: self.goal.clone(),
            decisions: self.decisions.clone(),
            progress: self.progress.clone(),
            trajectory: self.trajectory.clone(),
            plans: self.plans,
            next_progress_s: self.next_progress_s,
            layouts_computed: self.layouts_computed,
            layout_cost: None,
            compute_debt_s: self.compute_debt_s,
            layout_compute_s: self.layout_compute_s,
            policy_needs: needs,
            caller_decides: false,
            policy_decisions: self.policy_decisions,
            policy_failed: self.policy_failed,
            strategy_compute_s: self.strategy_compute_s,
            still_at: self.still_at,
            still_since_s: self.still_since_s,
            layout_trusted: self.layout_trusted,
            stopped_early: self.stopped_early,
            start: self.start,
            snapshots: self.snapshots.clone(),
            nav: self.nav.fork(),
            forgiven_at: self.forgiven_at,
            frontier_cells_left: self.frontier_cells_left,
            team_size: self.team_size,
            mates: self.mates.clone(),
            shares_map: self.shares_map,
            team_forgiven_s: self.team_forgiven_s,
            team_retries: self.team_retries,
            coverage: self.coverage.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::explore::strategy::{Strategy, StrategyParams};
    use crate::generate::{generate, BuildingKind, GenerateConfig};

    fn cfg(name: &str) -> ExploreConfig {
        ExploreConfig {
            strategy: Strategy::by_name(name, &StrategyParams::default()).unwrap(),
            ..ExploreConfig::default()
        }
    }

    /// Each run made together is the run made alone, whole (every pose, decision, progress
    /// sample, map cell and measure), for groups of strategies that differ in their early stop,
    /// on generated buildings with their rooms, from their starts.
    #[test]
    fn shared_runs_are_the_runs_made_alone() {
        let groups: [&[&str]; 3] = [
            &["layout", "layout-es", "layout-aes"],
            &["layout-gaps", "layout-gaps-es"],
            &["layout-truth", "layout-truth-es"],
        ];
        let buildings = [
            generate(&GenerateConfig {
                seed: 3,
                area_m2: 400.0,
                kind: BuildingKind::Office,
                ..GenerateConfig::default()
            }),
            generate(&GenerateConfig {
                seed: 5,
                area_m2: 600.0,
                kind: BuildingKind::School,
                ..GenerateConfig::default()
            }),
        ];
        let mut parted = 0;
        for b in &buildings {
            let start = b.start.unwrap();
            for group in groups {
                let cfgs: Vec<ExploreConfig> = group.iter().map(|n| cfg(n)).collect();
                for seed in 1..=2 {
                    let mut t = 0.0;
                    let mut clock = || {
                        t += 1.0;
                        t
                    };
                    let shared = explore_shared(b, start, &cfgs, seed, &mut |_| {}, &mut clock);
                    assert_eq!(shared.len(), cfgs.len());
                    for ((r, wall_s), (c, name)) in shared.iter().zip(cfgs.iter().zip(group)) {
                        let alone = explore(b, start, c, seed, &mut |_| {});
                        assert_eq!(*r, alone, "{} {name} seed {seed}", b.name);
                        assert!(*wall_s > 0.0, "{} {name} seed {seed}", b.name);
                    }
                    parted += shared
                        .iter()
                        .skip(1)
                        .filter(|(r, _)| r.decisions.len() != shared[0].0.decisions.len())
                        .count();
                }
            }
        }
        // (Some of the runs went their own way: the checkpoints were used.)
        assert!(parted > 0);
    }
}
