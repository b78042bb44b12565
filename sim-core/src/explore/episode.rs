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
//! An episode holds one robot or a team ([`Episode::team`]): the robots share the [`World`]
//! (their bodies and lasers see each other) and its clock, which moves one period once every
//! robot has its command for it (a robot deciding holds the world until it is answered); each
//! robot has its own exploration (estimate, map, goal, record) and result. The events and
//! answers name their robot. One robot's episode is today's run, bit for bit.

use crate::building::Building;
use crate::explore::config::ExploreConfig;
use crate::explore::explorer::deciding::{Deciding, Step};
use crate::explore::explorer::{new_explorer, Explorer, LayoutCost};
use crate::explore::map_state::{MapChanges, MapState};
use crate::explore::navigation::{Navigator, OwnNav};
use crate::explore::policy::{DecisionView, Mate, Needs, Reply, RunEnd};
use crate::explore::referee::Referee;
use crate::explore::run::{EndReason, ProgressSample, RunResult};
use crate::explore::team::{overlap, team_run, Coverage, RobotFigures, TeamResult};
use crate::geom::Pose;
pub use crate::sim::RobotId;
use crate::sim::World;
use std::sync::{Arc, Mutex};

/// The largest team.
pub const MAX_ROBOTS: usize = 8;

/// What [`Episode::advance`] stopped for.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// The robot needs a decision: [`Episode::view`] shows it, [`Episode::answer`] replies.
    /// Until it is answered, `advance` returns this again and the simulation does not move.
    Decide(RobotId),
    /// A point of the robot's progress curve (every `progress_period_s` of simulated time, and
    /// the last at the end of its run).
    Progress(RobotId, ProgressSample),
    /// The robot's exploration ended: its policy's last message (not sent when the policy
    /// failed). The robot then returns home if the settings ask for it, and its run is scored.
    Ended(RobotId, RunEnd),
    /// Every robot's run is over: [`Episode::result_of`] holds each. `advance` returns this
    /// from now on.
    Finished,
}

/// A call an episode cannot take in its state.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum EpisodeError {
    /// The episode has no such robot.
    NoSuchRobot(RobotId, usize),
    /// No decision of this robot is pending (`advance` has not returned [`Event::Decide`] for
    /// it, or it was answered).
    NotDeciding(RobotId),
}

impl std::fmt::Display for EpisodeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EpisodeError::NoSuchRobot(r, 0) => {
                write!(f, "the episode has no robot {} (it has no robots)", r.0)
            }
            EpisodeError::NoSuchRobot(r, n) => write!(
                f,
                "the episode has no robot {} (its robots are 0 to {})",
                r.0,
                n - 1
            ),
            EpisodeError::NotDeciding(r) => write!(
                f,
                "robot {} has no decision pending: answer only after advance() returned Decide",
                r.0
            ),
        }
    }
}

impl std::error::Error for EpisodeError {}

/// Where a robot's run loop stands.
#[derive(Clone)]
pub(super) enum Phase {
    /// At the top of the loop: sense, record progress, then decide or drive.
    Sense,
    /// A question to the policy is pending.
    Deciding(Box<Deciding>),
    /// Wait for charged compute time (standing still, sensing, one period at a time), then
    /// drive one period.
    Drive,
    /// The robot has its command for the period: the world moves once every robot has one,
    /// then `After` is done.
    Moving((f64, f64), After),
    /// Exploration ended for this reason (the policy is told next).
    Ending(EndReason),
    /// The policy told: return home if asked, close the progress curve. The exploration time
    /// (s).
    Concluding(EndReason, f64),
    /// On the way home (one period at a time).
    Home(EndReason, f64),
    /// Score the run (the last progress sample handed out).
    Scoring(EndReason, f64),
    /// Scored: the robot stands still while the others run.
    Finished,
}

/// What a robot does once the world has moved.
#[derive(Clone, Copy)]
pub(super) enum After {
    /// It stood still for charged compute from this time (s): sense, record progress, and wait
    /// on or drive.
    Waited(f64),
    /// It drove: sense at the top of the loop.
    Drove,
    /// It drove on its way home: sense, and go on home.
    Home(EndReason, f64),
}

/// One robot of an episode: its exploration and where its loop stands.
pub(super) struct Robot {
    pub(super) ex: Box<Explorer>,
    pub(super) phase: Phase,
    /// Progress samples handed out so far.
    pub(super) progress_sent: usize,
    /// In a team sharing its planning grids: the robot's own part of the navigator.
    pub(super) own_nav: OwnNav,
    pub(super) result: Option<RunResult>,
}

impl Robot {
    /// Whether the robot is still exploring (its exploration has not ended).
    fn is_exploring(&self) -> bool {
        matches!(
            self.phase,
            Phase::Sense
                | Phase::Deciding(_)
                | Phase::Drive
                | Phase::Moving(_, After::Waited(_) | After::Drove)
        )
    }
}

/// What one step of a robot's loop came to.
enum Poll {
    /// Something for the outside.
    Event(Event),
    /// The robot waits for the world to move (it has its command, or has finished).
    Wait,
    /// Go on stepping it.
    Again,
}

/// One run (a building, settings, a seed and its robots), stepped from outside: see the module
/// documentation. Bit-identical to [`explore`] when every decision is answered as the
/// strategy's built-in rule ([`super::strategy::BuiltInPolicy`]) answers it.
pub struct Episode {
    /// The walls, the physics, the clock and the robots' bodies and sensors.
    pub(super) world: World,
    /// Each robot's exploration, by [`RobotId`].
    pub(super) robots: Vec<Robot>,
    /// The settings of the run (every robot's).
    pub(super) cfg: Arc<ExploreConfig>,
    /// A team's shared map and what goes with it (`None`: one robot, or robots with maps of
    /// their own).
    pub(super) shared: Option<Box<Shared>>,
}

/// How a team's robots map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TeamMap {
    /// One map that every robot's scans go into and every robot plans on: the robots' relative
    /// starts are known (their estimates begin in one frame) and every map update reaches every
    /// robot at once (full communication). Their poses and goals are known to each other.
    Shared,
    /// Each robot its own map; nothing is exchanged (each explores as if alone, but among the
    /// others' bodies).
    Separate,
}

/// What the robots of a team with a shared map share: the map (with its frontiers, gains and
/// layout), the referee's record of the explored area, and which robots' scans changed each
/// map cell. Lent to a robot's explorer for each of its steps (`Episode::lend`).
pub(super) struct Shared {
    map: MapState,
    referee: Referee,
    /// The planning grids (each robot's own part kept with it: `Robot::own_nav`).
    nav: Navigator,
    /// Map updates passed on to teammates (one per update and teammate).
    exchanges: u64,
    /// The smallest distance between two robots' centres so far (m).
    min_separation_m: f64,
}

impl std::fmt::Debug for Episode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let phases: Vec<&str> = self
            .robots
            .iter()
            .map(|r| match &r.phase {
                Phase::Sense | Phase::Drive | Phase::Moving(..) => "running",
                Phase::Deciding(_) => "deciding",
                Phase::Ending(_) | Phase::Concluding(..) | Phase::Home(..) => "ending",
                Phase::Scoring(..) => "ending",
                Phase::Finished => "finished",
            })
            .collect();
        f.debug_struct("Episode")
            .field("time_s", &self.world.time_s())
            .field("robots", &phases)
            .finish()
    }
}

impl Episode {
    /// A run of `building` from `start` with the settings `cfg` and `seed`, whose decisions the
    /// strategy's own rule is to answer (the episode computes what that rule needs: the
    /// layout's gains, its rooms, the paths between candidates).
    pub fn new(building: &Building, start: Pose, cfg: ExploreConfig, seed: u64) -> Episode {
        Episode::build(building, &[start], cfg, seed, None, None, TeamMap::Separate)
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
        Episode::build(
            building,
            &[start],
            cfg,
            seed,
            Some(needs),
            None,
            TeamMap::Separate,
        )
    }

    /// A team: one robot at each of `starts` (robot `k` at `starts[k]`, at most 8), in one
    /// world, each with its own body, odometry, estimate, goal and record, mapping as `map`
    /// says, with the settings `cfg`; their decisions answered by a policy needing `needs`
    /// (`None`: the strategy's own rule; each robot needs its own, as it keeps memory). Robot
    /// 0's random streams are those of a run alone; robot `k`'s are its own. A team of one is
    /// [`Episode::new`]'s run, bit for bit. More than 8 robots panics (the caller checks).
    pub fn team(
        building: &Building,
        starts: &[Pose],
        cfg: ExploreConfig,
        seed: u64,
        needs: Option<Needs>,
        map: TeamMap,
    ) -> Episode {
        assert!(starts.len() <= MAX_ROBOTS, "at most {MAX_ROBOTS} robots");
        let mut episode = Episode::build(building, starts, cfg, seed, needs, None, map);
        if starts.len() > 1 {
            let n = starts.len();
            for r in &mut episode.robots {
                r.ex.coverage = Some(Coverage::new(r.ex.map.grid.frame));
                r.ex.team_size = n;
            }
            if map == TeamMap::Shared {
                episode.share_map();
            }
        }
        episode
    }

    /// Makes robot 0's map and referee the team's (the others' maps dropped: each robot is lent
    /// the shared one for its steps).
    fn share_map(&mut self) {
        let frame = self.robots[0].ex.map.grid.frame;
        let tiny = crate::grid::GridFrame::new(frame.origin_m, frame.resolution_m, 1, 1);
        let (radius_m, margin_m) = (self.cfg.sim.robot.radius_m, self.cfg.safety_margin_m);
        let mut map = None;
        let mut nav = None;
        for (k, r) in self.robots.iter_mut().enumerate() {
            let own = std::mem::replace(&mut r.ex.map, MapState::new(tiny, 1));
            let own_nav =
                std::mem::replace(&mut r.ex.nav, Navigator::new(tiny, radius_m, margin_m));
            // (Robot 0's map and planning grids become the team's.)
            if k == 0 {
                map = Some(own);
                nav = Some(own_nav);
            }
            r.ex.shares_map = true;
        }
        let referee = self.robots[0].ex.referee.clone();
        self.shared = Some(Box::new(Shared {
            map: map.expect("a team has robots"),
            nav: nav.expect("a team has robots"),
            referee,
            exchanges: 0,
            min_separation_m: self.separation(),
        }));
    }

    /// The smallest distance between two robots' centres now (m; infinite for one robot).
    fn separation(&self) -> f64 {
        let n = self.robots.len();
        let mut min = f64::INFINITY;
        for i in 0..n {
            for j in i + 1..n {
                let (a, b) = (
                    self.world.true_pose(RobotId(i)),
                    self.world.true_pose(RobotId(j)),
                );
                min = min.min((a.position() - b.position()).norm());
            }
        }
        min
    }

    /// Lends the team's shared map (and referee) to robot `k`'s explorer and tells it its
    /// mates, for one of its steps; [`Episode::take_back`] returns them. Nothing for a robot
    /// alone or with a map of its own.
    fn lend(&mut self, k: usize) {
        let Some(shared) = self.shared.as_mut() else {
            return;
        };
        let frame = shared.map.grid.frame;
        let mates: Vec<Mate> = (0..self.robots.len())
            .filter(|&j| j != k)
            .map(|j| {
                let r = &self.robots[j];
                Mate {
                    robot: j,
                    pose: r.ex.localizer.estimate(),
                    goal: r
                        .ex
                        .goal
                        .as_ref()
                        .map(|g| frame.world_from_cell(g.candidate)),
                    exploring: r.is_exploring(),
                    heard_s: self.world.time_s(),
                }
            })
            .collect();
        let r = &mut self.robots[k];
        r.ex.mates = mates;
        std::mem::swap(&mut shared.map, &mut r.ex.map);
        std::mem::swap(&mut shared.referee, &mut r.ex.referee);
        std::mem::swap(&mut shared.nav, &mut r.ex.nav);
        r.ex.nav.put_own(std::mem::take(&mut r.own_nav));
    }

    /// Takes the shared map back from robot `k` (see [`Episode::lend`]).
    fn take_back(&mut self, k: usize) {
        if let Some(shared) = self.shared.as_mut() {
            let r = &mut self.robots[k];
            r.own_nav = r.ex.nav.take_own();
            std::mem::swap(&mut shared.map, &mut r.ex.map);
            std::mem::swap(&mut shared.referee, &mut r.ex.referee);
            std::mem::swap(&mut shared.nav, &mut r.ex.nav);
        }
    }

    /// Robot `k` updated the map (lent to it) with `changes`: its teammates are told (they
    /// check their paths again when walls changed).
    fn shared_update(&mut self, k: usize, changes: Option<MapChanges>) {
        let (Some(shared), Some(changes)) = (self.shared.as_mut(), changes) else {
            return;
        };
        // (The planning grids, the team's, took in the changes as the robot mapped.)
        let walls = !changes.flips.is_empty();
        for (j, other) in self.robots.iter_mut().enumerate() {
            if j != k {
                if walls {
                    other.own_nav.walls_changed();
                }
                shared.exchanges += 1;
            }
        }
    }

    pub(super) fn build(
        building: &Building,
        starts: &[Pose],
        cfg: ExploreConfig,
        seed: u64,
        caller: Option<Needs>,
        layout_cost: Option<LayoutCost>,
        map: TeamMap,
    ) -> Episode {
        let mut world = World::new(building, &cfg.sim, seed);
        let cfg = Arc::new(cfg);
        let mut robots: Vec<Robot> = Vec::new();
        for &start in starts {
            let robot = world.add_robot(start);
            // (On a shared map robot 0's ground truth is the team's.)
            let referee = robots
                .first()
                .filter(|_| map == TeamMap::Shared)
                .map(|r| &r.ex.referee);
            let ex = new_explorer(
                building,
                &world,
                robot,
                start,
                Arc::clone(&cfg),
                seed,
                caller,
                referee,
            );
            robots.push(Robot {
                ex: Box::new(ex),
                phase: Phase::Sense,
                progress_sent: 0,
                own_nav: OwnNav::default(),
                result: None,
            });
        }
        let mut episode = Episode {
            world,
            robots,
            cfg,
            shared: None,
        };
        if let Some(cost) = layout_cost {
            episode.charge_layouts(cost);
        }
        episode
    }

    /// Charges each layout computation the seconds `cost` returns (see
    /// [`super::explore_charged`]); a team's robots share it.
    pub fn charge_layouts(&mut self, cost: LayoutCost) {
        let cost = Arc::new(Mutex::new(cost));
        for r in &mut self.robots {
            r.ex.layout_cost = Some(Arc::clone(&cost));
        }
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
        &self.cfg
    }

    /// Simulated time (s).
    pub fn time_s(&self) -> f64 {
        self.world.time_s()
    }

    /// Runs the simulation until something needs the outside: see [`Event`].
    pub fn advance(&mut self) -> Event {
        loop {
            for k in 0..self.robots.len() {
                let r = &mut self.robots[k];
                if let Some(&s) = r.ex.progress.get(r.progress_sent) {
                    r.progress_sent += 1;
                    return Event::Progress(RobotId(k), s);
                }
            }
            // One step of the first robot that has one to take (then its progress first, as
            // each step may record some); the world moves once none has.
            let mut stepped = false;
            for k in 0..self.robots.len() {
                // (A robot waiting for the world, or finished, has nothing to do with the map.)
                if matches!(self.robots[k].phase, Phase::Moving(..) | Phase::Finished) {
                    continue;
                }
                self.lend(k);
                let poll = self.poll(k);
                self.take_back(k);
                match poll {
                    Poll::Event(e) => return e,
                    Poll::Wait => {}
                    Poll::Again => {
                        stepped = true;
                        break;
                    }
                }
            }
            if stepped {
                continue;
            }
            if self
                .robots
                .iter()
                .all(|r| matches!(r.phase, Phase::Finished))
            {
                return Event::Finished;
            }
            self.step_world();
        }
    }

    /// One step of robot `k`'s loop.
    fn poll(&mut self, k: usize) -> Poll {
        let robot = RobotId(k);
        let r = &mut self.robots[k];
        match std::mem::replace(&mut r.phase, Phase::Finished) {
            Phase::Sense => self.sense(k),
            Phase::Deciding(d) => {
                r.phase = Phase::Deciding(d);
                return Poll::Event(Event::Decide(robot));
            }
            Phase::Drive => self.drive(k),
            moving @ Phase::Moving(..) => {
                r.phase = moving;
                return Poll::Wait;
            }
            Phase::Ending(reason) => {
                let exploration_time_s = self.world.time_s();
                r.phase = Phase::Concluding(reason, exploration_time_s);
                if !r.ex.policy_failed {
                    return Poll::Event(Event::Ended(
                        robot,
                        RunEnd {
                            reason,
                            exploration_time_s,
                            explored_fraction: r.ex.explored_fraction(),
                            decisions: r.ex.decisions.len(),
                        },
                    ));
                }
            }
            Phase::Concluding(reason, exploration_time_s) => {
                let ex = &mut r.ex;
                let home = ex.cfg.return_home
                    && reason != EndReason::TimeLimit
                    && !ex.policy_failed
                    && ex.head_home();
                r.phase = Phase::Home(reason, exploration_time_s);
                if !home {
                    self.arrived_home(k, reason, exploration_time_s);
                }
            }
            Phase::Home(reason, exploration_time_s) => self.home(k, reason, exploration_time_s),
            Phase::Scoring(reason, exploration_time_s) => {
                r.result = Some(r.ex.finish(reason, exploration_time_s, &self.world));
                r.phase = Phase::Finished;
            }
            Phase::Finished => return Poll::Wait,
        }
        Poll::Again
    }

    /// Moves the world one period, every robot by its command (a finished robot stands
    /// still), then lets each robot take in the move.
    fn step_world(&mut self) {
        let commands: Vec<(f64, f64)> = self
            .robots
            .iter()
            .map(|r| match r.phase {
                Phase::Moving(command, _) => command,
                _ => (0.0, 0.0),
            })
            .collect();
        self.world.step(&commands);
        if self.shared.is_some() {
            let now = self.separation();
            if let Some(shared) = self.shared.as_mut() {
                shared.min_separation_m = shared.min_separation_m.min(now);
            }
        }
        for k in 0..self.robots.len() {
            let Phase::Moving(_, after) = self.robots[k].phase else {
                continue;
            };
            if matches!(after, After::Drove) {
                self.robots[k].phase = Phase::Sense;
                continue;
            }
            self.lend(k);
            let r = &mut self.robots[k];
            let changes = match after {
                After::Waited(t0) => {
                    r.ex.compute_debt_s -= self.world.time_s() - t0;
                    let changes = r.ex.sense(&mut self.world);
                    r.ex.record_progress();
                    r.phase = Phase::Drive;
                    changes
                }
                After::Drove => None,
                After::Home(reason, exploration_time_s) => {
                    let changes = r.ex.sense(&mut self.world);
                    r.phase = Phase::Home(reason, exploration_time_s);
                    changes
                }
            };
            self.shared_update(k, changes);
            self.take_back(k);
        }
    }

    /// One period of waiting for charged compute time (standing still, sensing) while any is
    /// due; else the robot drives one period.
    fn drive(&mut self, k: usize) {
        let (r, now) = (&mut self.robots[k], self.world.time_s());
        r.phase = if r.ex.compute_debt_s > 0.0 && now < r.ex.cfg.time_limit_s {
            Phase::Moving((0.0, 0.0), After::Waited(now))
        } else {
            r.ex.compute_debt_s = 0.0;
            Phase::Moving(r.ex.drive(), After::Drove)
        };
    }

    /// One period on the way home, or arrived (or out of time).
    fn home(&mut self, k: usize, reason: EndReason, exploration_time_s: f64) {
        let (r, now) = (&mut self.robots[k], self.world.time_s());
        let command = if now < r.ex.cfg.time_limit_s {
            r.ex.drive_home()
        } else {
            None
        };
        match command {
            Some(c) => r.phase = Phase::Moving(c, After::Home(reason, exploration_time_s)),
            None => self.arrived_home(k, reason, exploration_time_s),
        }
    }

    /// The progress curve closed; the run is scored next.
    fn arrived_home(&mut self, k: usize, reason: EndReason, exploration_time_s: f64) {
        let r = &mut self.robots[k];
        r.ex.close_curve();
        r.phase = Phase::Scoring(reason, exploration_time_s);
    }

    /// The top of robot `k`'s loop: sense, record progress, end at the time limit, else decide
    /// when a decision is due, or drive.
    fn sense(&mut self, k: usize) {
        let changes = self.robots[k].ex.sense(&mut self.world);
        self.shared_update(k, changes);
        let r = &mut self.robots[k];
        r.ex.record_progress();
        r.phase = if self.world.time_s() >= r.ex.cfg.time_limit_s {
            Phase::Ending(EndReason::TimeLimit)
        } else if r.ex.needs_decision() {
            let step = r.ex.begin_decision(false);
            after_decision(&mut r.ex, step, false)
        } else {
            Phase::Drive
        };
    }

    /// The robot `robot` of this episode.
    fn robot(&self, robot: RobotId) -> Result<&Robot, EpisodeError> {
        self.robots
            .get(robot.0)
            .ok_or(EpisodeError::NoSuchRobot(robot, self.robots.len()))
    }

    /// The decision pending for `robot` as its policy sees it (`None` when none is pending).
    pub fn view(&self, robot: RobotId) -> Option<DecisionView<'_>> {
        let r = self.robot(robot).ok()?;
        match &r.phase {
            Phase::Deciding(d) => Some(r.ex.decision_view(
                self.shared.as_ref().map_or(&r.ex.map, |s| &s.map),
                &d.views,
                &d.asked,
                r.ex.policy_needs,
                d.between.as_deref(),
                d.mate_paths.as_deref(),
            )),
            _ => None,
        }
    }

    /// Answers the decision pending for `robot` (see [`Reply`]). A reply that names no
    /// candidate shown is the policy's failure and ends the robot's run, as [`Reply::Fail`]
    /// does.
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
        self.robot(robot)?;
        let r = &mut self.robots[robot.0];
        let d = match std::mem::replace(&mut r.phase, Phase::Finished) {
            Phase::Deciding(d) => d,
            other => {
                r.phase = other;
                return Err(EpisodeError::NotDeciding(robot));
            }
        };
        let forgiven = d.forgiven;
        self.lend(robot.0);
        let r = &mut self.robots[robot.0];
        let step = r.ex.reply(d, reply, compute_s);
        r.phase = after_decision(&mut r.ex, step, forgiven);
        self.take_back(robot.0);
        Ok(())
    }

    /// `robot`'s explored area so far (m2) and its share of the building's free area: the
    /// referee's figures (ground truth: for rewards and evaluation, never for a policy, which
    /// sees what [`Episode::view`] shows). `None` for a robot the episode does not have.
    pub fn explored(&self, robot: RobotId) -> Option<(f64, f64)> {
        let r = self.robot(robot).ok()?;
        // (A team's shared referee is with the episode between the robots' steps.)
        let referee = self.shared.as_ref().map_or(&r.ex.referee, |s| &s.referee);
        Some((referee.explored_area_m2(), referee.explored_fraction()))
    }

    /// Robot 0's result (the run's, for an episode of one robot), once [`Event::Finished`] was
    /// returned.
    pub fn result(&self) -> Option<&RunResult> {
        self.robots.first()?.result.as_ref()
    }

    /// `robot`'s result, once its run is over.
    pub fn result_of(&self, robot: RobotId) -> Option<&RunResult> {
        self.robot(robot).ok()?.result.as_ref()
    }

    /// Robot 0's result (the run's, for an episode of one robot), once [`Event::Finished`] was
    /// returned.
    pub fn into_result(self) -> Option<RunResult> {
        self.robots.into_iter().next()?.result
    }

    /// Every robot's result (by [`RobotId`]), once [`Event::Finished`] was returned.
    pub fn into_results(self) -> Vec<Option<RunResult>> {
        self.robots.into_iter().map(|r| r.result).collect()
    }

    /// The team's result (see [`TeamResult`]), once [`Event::Finished`] was returned (`None`
    /// before, or without robots). For robots with separate maps the team's explored area is
    /// the union of theirs, and its progress curve the best robot's at each time.
    pub fn into_team_result(self) -> Option<TeamResult> {
        if self.robots.is_empty() || self.robots.iter().any(|r| r.result.is_none()) {
            return None;
        }
        let n = self.robots.len();
        let frame = self.robots[0].ex.referee.truth.frame;
        let cell_m2 = frame.cell_area_m2();
        // The area each robot's laser swept, the overlap, the team's explored cells.
        let coverages: Vec<&Coverage> = self
            .robots
            .iter()
            .filter_map(|r| r.ex.coverage.as_ref())
            .collect();
        let (seen, overlap_m2, seen_m2) = if coverages.len() == n {
            overlap(&coverages)
        } else {
            let seen: Vec<f64> = self
                .robots
                .iter()
                .map(|r| r.ex.referee.explored_area_m2())
                .collect();
            let any = seen.iter().sum();
            (seen, 0.0, any)
        };
        let team_explored = (self.shared.is_none() && n > 1).then(|| {
            let referee = &self.robots[0].ex.referee;
            let union = (0..referee.truth.data.len())
                .filter(|&j| {
                    referee.truth.data[j]
                        && self.robots.iter().any(|r| r.ex.referee.explored.data[j])
                })
                .count();
            (union, referee.truth_cells)
        });
        let rooms = match &self.shared {
            Some(sh) => sh.referee.rooms.clone(),
            None => self.robots[0].ex.referee.rooms.clone(),
        };
        let min_separation_m = self
            .shared
            .as_ref()
            .map_or_else(|| self.separation(), |s| s.min_separation_m);
        let exchanges = self.shared.as_ref().map_or(0, |s| s.exchanges);
        let robots: Vec<RunResult> = self
            .robots
            .into_iter()
            .map(|r| r.result.expect("checked"))
            .collect();
        let last = (0..n)
            .max_by(|&a, &b| {
                robots[a]
                    .exploration_time_s
                    .total_cmp(&robots[b].exploration_time_s)
                    .then(b.cmp(&a))
            })
            .expect("a team has robots");
        let team_time_s = robots[last].exploration_time_s;
        let figures: Vec<RobotFigures> = robots
            .iter()
            .zip(&seen)
            .map(|(r, &seen_m2)| RobotFigures {
                seen_m2,
                path_length_m: r.path_length_m,
                exploration_time_s: r.exploration_time_s,
                end_reason: r.end_reason,
                idle_s: (team_time_s - r.exploration_time_s).max(0.0)
                    + r.layout_compute_s
                    + r.strategy_compute_s,
                decisions: r.decisions.len(),
            })
            .collect();
        let union = team_explored.map(|(cells, truth)| {
            let fraction = if truth == 0 {
                0.0
            } else {
                cells as f64 / truth as f64
            };
            (cells as f64 * cell_m2, fraction)
        });
        let team = team_run(&robots, last, &rooms, union);
        Some(TeamResult {
            team,
            robots,
            figures,
            overlap_m2,
            seen_m2,
            exchanges,
            min_separation_m,
        })
    }
}

/// Where a decision's step leads: the question pending, driving to the goal set, one more
/// chance for the goals given up (unless the decision had it: `forgiven`), or the end of
/// exploration.
fn after_decision(ex: &mut Explorer, step: Step, forgiven: bool) -> Phase {
    match step {
        Step::Ask(d) => Phase::Deciding(d),
        Step::Done(true) => Phase::Drive,
        Step::Done(false) if !forgiven && ex.forgive() => {
            let step = ex.begin_decision(true);
            after_decision(ex, step, true)
        }
        Step::Done(false) => Phase::Ending(if ex.stopped_early {
            EndReason::EarlyStop
        } else {
            ex.classify_end()
        }),
    }
}
