//! The episode: one run as a state machine driven from outside (as quinn-proto's `Connection`
//! is). [`Episode::advance`] runs the simulation until something needs the outside and returns
//! an [`Event`]: a decision to make ([`Episode::view`] shows it, [`Episode::answer`] gives the
//! reply), a point of the progress curve, the end of exploration, or the finished run. Whoever
//! answers (the strategy's built-in rule, an external program, a learned policy in Python) is
//! outside the episode; the episode owns everything else and is `Send + 'static`, so a driver
//! may keep it anywhere, move it between threads between steps, or hold many.
//!
//! The run loop's states: sense (and record progress), then either decide or drive one step;
//! a decision is a question put to the policy and its answers until a goal is set or none is
//! left (`decision`: the retries, last resorts and re-decisions are explicit states there);
//! when none is left the goals given up get one more chance (`Explorer::forgive`), then
//! exploration ends, the policy is told, the robot returns home if asked to, and the run is
//! scored.
//!
//! A run has one robot today, [`RobotId`] 0; the events and answers name their robot so that a
//! team needs no other interface.

use crate::building::Building;
use crate::explore::config::ExploreConfig;
use crate::explore::explorer::deciding::{Deciding, Step};
use crate::explore::explorer::{new_explorer, Explorer, LayoutCost};
use crate::explore::policy::{DecisionView, Needs, Reply, RunEnd};
use crate::explore::run::{EndReason, ProgressSample, RunResult};
use crate::geom::Pose;
pub use crate::sim::RobotId;
use crate::sim::World;
use std::sync::Arc;

/// What [`Episode::advance`] stopped for.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// The robot needs a decision: [`Episode::view`] shows it, [`Episode::answer`] replies.
    /// Until it is answered, `advance` returns this again and the simulation does not move.
    Decide(RobotId),
    /// A point of the progress curve (every `progress_period_s` of simulated time, and the
    /// last at the end of the run).
    Progress(ProgressSample),
    /// Exploration ended: the policy's last message (not sent when the policy failed). The
    /// robot then returns home if the settings ask for it, and the run is scored.
    Ended(RunEnd),
    /// The run is over: [`Episode::result`] holds it. `advance` returns this from now on.
    Finished,
}

/// A call an episode cannot take in its state.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum EpisodeError {
    /// The episode has no such robot.
    NoSuchRobot(RobotId),
    /// No decision of this robot is pending (`advance` has not returned [`Event::Decide`] for
    /// it, or it was answered).
    NotDeciding(RobotId),
}

impl std::fmt::Display for EpisodeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EpisodeError::NoSuchRobot(r) => {
                write!(f, "the episode has no robot {} (it has robot 0 only)", r.0)
            }
            EpisodeError::NotDeciding(r) => write!(
                f,
                "robot {} has no decision pending: answer only after advance() returned Decide",
                r.0
            ),
        }
    }
}

impl std::error::Error for EpisodeError {}

/// Where the run loop stands.
#[derive(Clone)]
pub(super) enum Phase {
    /// At the top of the loop: sense, record progress, then decide or drive.
    Sense,
    /// A question to the policy is pending.
    Deciding(Box<Deciding>),
    /// Wait for charged compute time (standing still, sensing, one period at a time), then
    /// drive one period.
    Drive,
    /// Exploration ended for this reason (the policy is told next).
    Ending(EndReason),
    /// The policy told: return home if asked, close the progress curve. The exploration time
    /// (s).
    Concluding(EndReason, f64),
    /// On the way home (one period at a time).
    Home(EndReason, f64),
    /// Score the run (the last progress sample handed out).
    Scoring(EndReason, f64),
    /// Scored.
    Finished,
}

/// One run (a building, settings, a seed and its robot), stepped from outside: see the module
/// documentation. Bit-identical to [`explore`] when every decision is answered as the
/// strategy's built-in rule ([`super::strategy::BuiltInPolicy`]) answers it.
pub struct Episode {
    /// The walls, the physics, the clock and the robots' bodies and sensors.
    pub(super) world: World,
    /// The robot's exploration: its estimate, map, goal and record.
    pub(super) ex: Box<Explorer>,
    pub(super) phase: Phase,
    /// Progress samples handed out so far.
    pub(super) progress_sent: usize,
    pub(super) result: Option<RunResult>,
}

impl std::fmt::Debug for Episode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let phase = match &self.phase {
            Phase::Sense | Phase::Drive => "running",
            Phase::Deciding(_) => "deciding",
            Phase::Ending(_) | Phase::Concluding(..) | Phase::Home(..) | Phase::Scoring(..) => {
                "ending"
            }
            Phase::Finished => "finished",
        };
        f.debug_struct("Episode")
            .field("time_s", &self.world.time_s())
            .field("phase", &phase)
            .field("decisions", &self.ex.decisions.len())
            .finish()
    }
}

impl Episode {
    /// A run of `building` from `start` with the settings `cfg` and `seed`, whose decisions the
    /// strategy's own rule is to answer (the episode computes what that rule needs: the
    /// layout's gains, its rooms, the paths between candidates).
    pub fn new(building: &Building, start: Pose, cfg: ExploreConfig, seed: u64) -> Episode {
        Episode::build(building, start, cfg, seed, None, None)
    }

    /// [`Episode::new`], its decisions answered by a policy of the caller's that needs
    /// `needs` computed (the strategy's gain model and early stop still apply to what it is
    /// shown).
    pub fn with_policy(
        building: &Building,
        start: Pose,
        cfg: ExploreConfig,
        seed: u64,
        needs: Needs,
    ) -> Episode {
        Episode::build(building, start, cfg, seed, Some(needs), None)
    }

    pub(super) fn build(
        building: &Building,
        start: Pose,
        cfg: ExploreConfig,
        seed: u64,
        caller: Option<Needs>,
        layout_cost: Option<LayoutCost>,
    ) -> Episode {
        let world = World::with_robot(building, start, &cfg.sim, seed);
        let cfg = Arc::new(cfg);
        let robot = RobotId(0);
        let ex = new_explorer(
            building,
            &world,
            robot,
            start,
            cfg,
            seed,
            caller,
            layout_cost,
        );
        Episode {
            world,
            ex: Box::new(ex),
            phase: Phase::Sense,
            progress_sent: 0,
            result: None,
        }
    }

    /// Charges each layout computation the seconds `cost` returns (see
    /// [`super::explore_charged`]).
    pub fn charge_layouts(&mut self, cost: LayoutCost) {
        self.ex.layout_cost = Some(cost);
    }

    /// The robots of the episode.
    pub fn robots(&self) -> Vec<RobotId> {
        self.world.robots().collect()
    }

    /// The simulated world (its walls, and each robot's true pose and odometry: for evaluation
    /// and drawing, not for a policy, which sees what [`Episode::view`] shows).
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The settings of the run.
    pub fn config(&self) -> &ExploreConfig {
        &self.ex.cfg
    }

    /// Simulated time (s).
    pub fn time_s(&self) -> f64 {
        self.world.time_s()
    }

    /// Runs the simulation until something needs the outside: see [`Event`].
    pub fn advance(&mut self) -> Event {
        loop {
            if let Some(&s) = self.ex.progress.get(self.progress_sent) {
                self.progress_sent += 1;
                return Event::Progress(s);
            }
            match std::mem::replace(&mut self.phase, Phase::Finished) {
                Phase::Sense => self.sense(),
                Phase::Deciding(d) => {
                    self.phase = Phase::Deciding(d);
                    return Event::Decide(RobotId(0));
                }
                Phase::Drive => self.drive(),
                Phase::Ending(reason) => {
                    let ex = &mut self.ex;
                    let exploration_time_s = self.world.time_s();
                    self.phase = Phase::Concluding(reason, exploration_time_s);
                    if !ex.policy_failed {
                        return Event::Ended(RunEnd {
                            reason,
                            exploration_time_s,
                            explored_fraction: ex.explored_fraction(),
                            decisions: ex.decisions.len(),
                        });
                    }
                }
                Phase::Concluding(reason, exploration_time_s) => {
                    let ex = &mut self.ex;
                    let home = ex.cfg.return_home
                        && reason != EndReason::TimeLimit
                        && !ex.policy_failed
                        && ex.head_home();
                    self.phase = Phase::Home(reason, exploration_time_s);
                    if !home {
                        self.arrived_home(reason, exploration_time_s);
                    }
                }
                Phase::Home(reason, exploration_time_s) => {
                    self.home(reason, exploration_time_s);
                }
                Phase::Scoring(reason, exploration_time_s) => {
                    let result = self.ex.finish(reason, exploration_time_s, &self.world);
                    self.result = Some(result);
                    self.phase = Phase::Finished;
                }
                Phase::Finished => {
                    self.phase = Phase::Finished;
                    return Event::Finished;
                }
            }
        }
    }

    /// One period of waiting for charged compute time (standing still, sensing) while any is
    /// due; else the robot drives one period.
    fn drive(&mut self) {
        let (ex, world) = (&mut self.ex, &mut self.world);
        if ex.compute_debt_s > 0.0 && world.time_s() < ex.cfg.time_limit_s {
            let t0 = world.time_s();
            world.idle();
            ex.compute_debt_s -= world.time_s() - t0;
            ex.sense(world);
            ex.record_progress();
            self.phase = Phase::Drive;
        } else {
            ex.compute_debt_s = 0.0;
            let command = ex.drive();
            world.step(&[command]);
            self.phase = Phase::Sense;
        }
    }

    /// One period on the way home (sensing), or arrived (or out of time).
    fn home(&mut self, reason: EndReason, exploration_time_s: f64) {
        let (ex, world) = (&mut self.ex, &mut self.world);
        let command = if world.time_s() < ex.cfg.time_limit_s {
            ex.drive_home()
        } else {
            None
        };
        match command {
            Some(command) => {
                world.step(&[command]);
                ex.sense(world);
                self.phase = Phase::Home(reason, exploration_time_s);
            }
            None => self.arrived_home(reason, exploration_time_s),
        }
    }

    /// The progress curve closed; the run is scored next.
    fn arrived_home(&mut self, reason: EndReason, exploration_time_s: f64) {
        self.ex.close_curve();
        self.phase = Phase::Scoring(reason, exploration_time_s);
    }

    /// The top of the run loop: sense, record progress, end at the time limit, else decide when
    /// a decision is due, or drive.
    fn sense(&mut self) {
        self.ex.sense(&mut self.world);
        self.ex.record_progress();
        self.phase = if self.world.time_s() >= self.ex.cfg.time_limit_s {
            Phase::Ending(EndReason::TimeLimit)
        } else if self.ex.needs_decision() {
            let step = self.ex.begin_decision(false);
            self.after_decision(step, false)
        } else {
            Phase::Drive
        };
    }

    /// Where a decision's step leads: the question pending, driving to the goal set, one more
    /// chance for the goals given up (unless the decision had it: `forgiven`), or the end of
    /// exploration.
    fn after_decision(&mut self, step: Step, forgiven: bool) -> Phase {
        match step {
            Step::Ask(d) => Phase::Deciding(d),
            Step::Done(true) => Phase::Drive,
            Step::Done(false) if !forgiven && self.ex.forgive() => {
                let step = self.ex.begin_decision(true);
                self.after_decision(step, true)
            }
            Step::Done(false) => Phase::Ending(if self.ex.stopped_early {
                EndReason::EarlyStop
            } else {
                self.ex.classify_end()
            }),
        }
    }

    /// The decision pending for `robot` as its policy sees it (`None` when none is pending).
    pub fn view(&self, robot: RobotId) -> Option<DecisionView<'_>> {
        match (&self.phase, robot) {
            (Phase::Deciding(d), RobotId(0)) => Some(self.ex.decision_view(
                &d.views,
                &d.asked,
                self.ex.policy_needs,
                d.between.as_deref(),
            )),
            _ => None,
        }
    }

    /// Answers the decision pending for `robot` (see [`Reply`]). A reply that names no
    /// candidate shown is the policy's failure and ends the run, as [`Reply::Fail`] does.
    pub fn answer(&mut self, robot: RobotId, reply: Reply) -> Result<(), EpisodeError> {
        self.answer_charged(robot, reply, 0.0)
    }

    /// [`Episode::answer`], charging the policy's compute time to simulated time (s; the robot
    /// stands still, sensing, for it before it drives on; 0 or less charges nothing).
    pub fn answer_charged(
        &mut self,
        robot: RobotId,
        reply: Reply,
        compute_s: f64,
    ) -> Result<(), EpisodeError> {
        if !self.world.has(robot) {
            return Err(EpisodeError::NoSuchRobot(robot));
        }
        let d = match std::mem::replace(&mut self.phase, Phase::Finished) {
            Phase::Deciding(d) => d,
            other => {
                self.phase = other;
                return Err(EpisodeError::NotDeciding(robot));
            }
        };
        let forgiven = d.forgiven;
        let step = self.ex.reply(d, reply, compute_s);
        self.phase = self.after_decision(step, forgiven);
        Ok(())
    }

    /// The run's result, once [`Event::Finished`] was returned.
    pub fn result(&self) -> Option<&RunResult> {
        self.result.as_ref()
    }

    /// The run's result, once [`Event::Finished`] was returned.
    pub fn into_result(self) -> Option<RunResult> {
        self.result
    }
}
