//! Runs that share their beginning. Strategies whose settings differ only in the early stop
//! (`layout`, `layout-es` and `layout-aes`; `layout-gaps` and `layout-gaps-es`; the oracle's
//! two) see the same candidates and, until one of their rules stops or drops what another
//! keeps, make the same choices: the runs are identical up to that decision. On the paper's
//! grid a `layout-es` run follows its `layout` twin for 96-100 % of its progress curve (median
//! 99.98 %). [`explore_shared`] runs them as one: the first configuration leads, every other's
//! rule is asked alongside at each of its decisions, and a run whose reply first differs goes on
//! alone from the last copy of the state taken before that decision (one every
//! [`CHECKPOINT_DECISIONS`] decisions); a run that never differs is the leader's up to its end.
//! Each result is bit-identical to the run made alone (tested).

use std::rc::Rc;

use super::strategy::BuiltInPolicy;
use super::*;

/// Decisions between two copies of the leading run's state: the most a run that parts from
/// it repeats. A copy costs about as much as a few decisions.
pub(super) const CHECKPOINT_DECISIONS: usize = 20;

/// The runs sharing the leading run's beginning, held by the leader.
pub(super) struct Shared<'a> {
    members: Vec<Member<'a>>,
    /// Seconds since the shared run began, read by the caller (the core reads no clock).
    clock: &'a mut dyn FnMut() -> f64,
    /// The leader's state at the top of its run loop when last copied, and the clock then.
    checkpoint: Option<(Rc<Explorer<'a>>, f64)>,
    /// The leader's `policy_decisions` at that copy.
    checkpoint_decisions: usize,
}

/// One run following the leader.
struct Member<'a> {
    index: usize,
    cfg: &'a ExploreConfig,
    policy: BuiltInPolicy,
    needs: Needs,
    /// Its policy at the last checkpoint.
    policy_at_checkpoint: BuiltInPolicy,
    /// Once its reply differed from the leader's: the checkpoint before that decision, its
    /// policy then, and the clock then.
    parted: Option<(Rc<Explorer<'a>>, BuiltInPolicy, f64)>,
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
pub fn explore_shared<'a>(
    building: &Building,
    start: Pose,
    cfgs: &'a [ExploreConfig],
    seed: u64,
    on_progress: &mut dyn FnMut(&ProgressSample),
    clock: &'a mut dyn FnMut() -> f64,
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
    let mut leader = new_explorer(building, start, &cfgs[0], seed, Hooks::default());
    let members = cfgs[1..]
        .iter()
        .enumerate()
        .map(|(k, cfg)| {
            let policy = BuiltInPolicy::new(&cfg.strategy, seed);
            Member {
                index: k + 1,
                cfg,
                needs: built_in_needs(&policy, cfg),
                policy_at_checkpoint: policy.clone(),
                policy,
                parted: None,
            }
        })
        .collect();
    leader.shared = Some(Box::new(Shared {
        members,
        clock,
        checkpoint: None,
        checkpoint_decisions: 0,
    }));
    let end_reason = leader.explore_until_end(on_progress);
    let shared = *leader.shared.take().expect("the leader keeps its members");
    let Shared { members, clock, .. } = shared;
    let mut out: Vec<Option<(RunResult, f64)>> = (0..cfgs.len()).map(|_| None).collect();
    // The members that never parted: the leader's run up to its end, then their own ending.
    let shared_s = clock();
    let mut parted = Vec::new();
    for m in members {
        match m.parted {
            None => {
                let t0 = clock();
                let r = leader
                    .fork(m.cfg, m.policy)
                    .conclude(end_reason, &mut |_| {});
                out[m.index] = Some((r, shared_s + clock() - t0));
            }
            Some(p) => parted.push((m.index, m.cfg, p)),
        }
    }
    let t0 = clock();
    let r = leader.conclude(end_reason, on_progress);
    out[0] = Some((r, shared_s + clock() - t0));
    // The others from the copy made before they parted.
    for (index, cfg, (from, policy, at_s)) in parted {
        let t0 = clock();
        let r = from.fork(cfg, policy).run(&mut |_| {});
        out[index] = Some((r, at_s + clock() - t0));
    }
    out.into_iter()
        .map(|r| r.expect("every run made"))
        .collect()
}

impl<'a> Explorer<'a> {
    /// This run's state, to go on with `cfg` (whose settings may differ from this run's in the
    /// early stop only) and its built-in `policy`. Hooks are not copied (shared runs have none).
    pub(super) fn fork(&self, cfg: &'a ExploreConfig, policy: BuiltInPolicy) -> Explorer<'a> {
        let needs = built_in_needs(&policy, cfg);
        Explorer {
            cfg,
            seed: self.seed,
            sim: self.sim.clone(),
            map: self.map.clone(),
            obstacles: self.obstacles.clone(),
            referee: self.referee.clone(),
            known: self.known.clone(),
            fresh_known: self.fresh_known.clone(),
            localizer: self.localizer.clone(),
            blacklist: self.blacklist.clone(),
            last_reached: self.last_reached,
            follower: self.follower.clone(),
            goal: self.goal.clone(),
            decisions: self.decisions.clone(),
            progress: self.progress.clone(),
            trajectory: self.trajectory.clone(),
            plans: self.plans,
            gains: self.gains.clone(),
            next_progress_s: self.next_progress_s,
            known_cells: self.known_cells,
            layout: self.layout.clone(),
            layouts_computed: self.layouts_computed,
            layout_cost: None,
            compute_debt_s: self.compute_debt_s,
            layout_compute_s: self.layout_compute_s,
            policy: PolicySlot::BuiltIn(policy),
            policy_needs: needs,
            policy_decisions: self.policy_decisions,
            policy_failed: self.policy_failed,
            strategy_compute_s: self.strategy_compute_s,
            still_at: self.still_at,
            still_since_s: self.still_since_s,
            layout_trusted: self.layout_trusted,
            stopped_early: self.stopped_early,
            start: self.start,
            snapshots: self.snapshots.clone(),
            frontiers: self.frontiers.clone(),
            nav: self.nav.fork(),
            forgiven_at: self.forgiven_at,
            frontier_cells_left: self.frontier_cells_left,
            shared: None,
        }
    }

    /// At the top of the run loop: a copy of the state for the members still following, every
    /// [`CHECKPOINT_DECISIONS`] decisions (and at the start).
    pub(super) fn checkpoint_if_due(&mut self) {
        let Some(mut shared) = self.shared.take() else {
            return;
        };
        let following = shared.members.iter().any(|m| m.parted.is_none());
        let due = shared.checkpoint.is_none()
            || self.policy_decisions >= shared.checkpoint_decisions + CHECKPOINT_DECISIONS;
        if following && due {
            // (The previous copy dropped first, unless a member that parted holds it: two
            // copies of a large map at once are a lot.)
            shared.checkpoint = None;
            // (Its policy is never asked: a member that parts goes on with its own.)
            let policy = BuiltInPolicy::new(&self.cfg.strategy, 0);
            let copy = Rc::new(self.fork(self.cfg, policy));
            shared.checkpoint = Some((copy, (shared.clock)()));
            shared.checkpoint_decisions = self.policy_decisions;
            for m in shared.members.iter_mut().filter(|m| m.parted.is_none()) {
                m.policy_at_checkpoint = m.policy.clone();
            }
        }
        self.shared = Some(shared);
    }

    /// After the leader's policy replied `reply` to a decision (`asked`), every member still
    /// following is asked the same with the candidates as it sees them; those whose reply
    /// differs part.
    pub(super) fn ask_members(
        &mut self,
        frontiers: &[Frontier],
        goals: &[Option<Cell>],
        plan: &Plan,
        scores: &[CandidateScore],
        asked: &Asked,
        reply: &Reply,
    ) {
        let Some(mut shared) = self.shared.take() else {
            return;
        };
        for m in shared.members.iter_mut().filter(|m| m.parted.is_none()) {
            let views =
                self.candidate_views(frontiers, goals, plan, scores, m.needs, asked.use_layout);
            let between = m.needs.paths_between.then(|| self.paths_between(&views));
            let view = self.decision_view(&views, asked, m.needs, between.as_deref());
            let (theirs, _) = m.policy.decide(&view);
            if theirs != *reply {
                let (from, at_s) = shared
                    .checkpoint
                    .clone()
                    .expect("a checkpoint is taken before the first decision");
                m.parted = Some((from, m.policy_at_checkpoint.clone(), at_s));
            }
        }
        self.shared = Some(shared);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
