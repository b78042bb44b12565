//! The decision: the frontiers and their candidates, their scores (the gains a strategy needs),
//! the policy asked to choose (the built-in strategy's rule or the caller's, answering from
//! outside the run: see `episode`), the last resorts before a run ends with frontiers left (their
//! reachable parts, plans with less clearance, a closer look: `approach`), and the goal set for
//! the choice. A decision is a state machine: `begin_decision` puts a question ([`Step::Ask`],
//! its state a [`Deciding`]) or decides at once; `reply` takes the answer and puts the next
//! question or decides.

use crate::explore::explorer::Goal;
use crate::explore::map_state::MapState;
use crate::explore::policy::{LayoutView, TeamView};
use crate::explore::run::Decision;

use crate::explore::explorer::Explorer;
use crate::explore::follow::PathFollower;
use crate::explore::gain_cache::{GainCache, GainKind};
use crate::explore::navigation::{Plan, Planning, MAX_EXTRA};
use crate::explore::policy::{CandidateView, DecisionView, Needs, Reply, MAX_UNREACHABLE_GOALS};
use crate::frontier::blacklist::Blacklist;
use crate::frontier::detect::{frontiers_where, is_frontier_cell, Frontier, FrontierConfig};
use crate::gain::{information_count_read, information_gain};
use crate::geom::Vec2;
use crate::grid::{Cell, GridFrame, Occupancy, OccupancyGrid};
use crate::layout_gain::{
    gap_closed_information_gain_read, layout_information_gain_read, LayoutRaster,
};
use crate::plan::dijkstra::dijkstra_padded;
use crate::plan::inflate::nearest_by;
use crate::plan::waypoints::waypoints_by;
use crate::utility::{CandidateScore, UtilityDistance};
use std::sync::Arc;

impl Explorer {
    /// Moves the candidate of every frontier whose goal is unreachable in `plan` to the
    /// reachable traversable cell of the frontier nearest to it (the first in row-major order
    /// among equals), if there is one. Returns the plan to score with: a full search when
    /// `plan`, which stops once its targets are settled, may not cover the new goals.
    pub(crate) fn reachable_candidates(
        &mut self,
        frontiers: &mut [Frontier],
        goals: &mut [Option<Cell>],
        plan: Plan,
    ) -> Plan {
        let moved: Vec<usize> = (0..frontiers.len())
            .filter(|&k| goals[k].and_then(|c| plan.distance_m(c)).is_none())
            .collect();
        if moved.is_empty() {
            return plan;
        }
        // The new goals need distances that are final: search everything if the search stopped
        // at its targets.
        let plan = if plan.is_complete() {
            plan
        } else {
            self.plan(&[])
        };
        let trav = self.traversability();
        let frame = self.map.grid.frame;
        for k in moved {
            let f = &mut frontiers[k];
            let from = f.candidate;
            let d2 = |c: &Cell| {
                let (dx, dy) = ((c.x - from.x) as i64, (c.y - from.y) as i64);
                dx * dx + dy * dy
            };
            // (Not where a goal was given up: the robot would come back for ever.)
            let best = f
                .cells
                .iter()
                .filter(|c| {
                    trav.at(**c)
                        && plan.distance_m(**c).is_some()
                        && !self.blacklist.contains(frame.world_from_cell(**c))
                })
                .min_by_key(|c| d2(c));
            if let Some(&c) = best {
                f.candidate = c;
                goals[k] = Some(c);
            }
        }
        plan
    }

    /// Scores every frontier for the utility: distance to its goal (`None` if unreachable in
    /// `plan`; the path's length, or the straight line to the candidate with
    /// [`UtilityDistance::Euclidean`]) and information gain (as the strategy's gain model
    /// defines it).
    pub(crate) fn score(
        &mut self,
        frontiers: &[Frontier],
        goals: &[Option<Cell>],
        plan: &Plan,
        use_layout: bool,
    ) -> Vec<CandidateScore> {
        let cfg = Arc::clone(&self.cfg);
        let mut scores = Vec::with_capacity(frontiers.len());
        let (frame, robot) = (self.map.grid.frame, self.localizer.estimate().position());
        for (f, goal_cell) in frontiers.iter().zip(goals) {
            let distance_m = goal_cell.and_then(|c| plan.distance_m(c)).map(|path_m| {
                match cfg.utility_distance {
                    UtilityDistance::Path => path_m,
                    UtilityDistance::Euclidean => {
                        (frame.world_from_cell(f.candidate) - robot).norm()
                    }
                }
            });
            let gain_m2 = if distance_m.is_some() {
                let (grid, range_m) = (&self.map.grid.occupancy, cfg.sim.laser.max_range_m);
                let (c, now) = (f.candidate, self.map.updates());
                match (&self.map.layout, use_layout) {
                    (Some(l), true) if cfg.strategy.gain.ranks_by_predicted_rooms() => {
                        layout_gain_cached(&mut self.map.gains, grid, &l.raster, c, range_m, now)
                    }
                    (Some(l), true) => {
                        self.map
                            .gains
                            .gain(GainKind::GapClosed, c, range_m, now, || {
                                gap_closed_information_gain_read(grid, &l.raster, c, range_m)
                            })
                    }
                    _ => self
                        .map
                        .gains
                        .plain_gain(c, range_m, now, || information_count_read(grid, c, range_m)),
                }
            } else {
                0.0
            };
            scores.push(CandidateScore {
                distance_m,
                gain_m2,
            });
        }
        scores
    }

    /// Before the run ends for want of candidates: gives the goals given up (by the progress
    /// timeout or standing still) another chance, if the map has grown by at least 1 m2 since
    /// they last had one (or never had one). A goal given up for a moment of bad luck (a robot
    /// stuck on clutter, a pose estimate briefly off) would otherwise end the run with
    /// frontiers left. Returns whether any were forgiven.
    ///
    /// In a team, goals are mostly given up (or looked at in vain) because a teammate's body was
    /// in the way: while a teammate still explores (and moves), they also get another chance once
    /// [`TEAM_RETRY_S`] has passed since the last, at most [`TEAM_RETRIES`] times between two
    /// chances the map's growth gave.
    pub(crate) fn forgive(&mut self) -> bool {
        if self.stopped_early || self.policy_failed {
            return false;
        }
        let grown = self.forgiven_at.is_none_or(|at| {
            self.map.known_cells.saturating_sub(at) as f64 * self.map.grid.frame.cell_area_m2()
                >= 1.0
        });
        let retry = !grown
            && self.mates.iter().any(|m| m.exploring)
            && self.team_retries < TEAM_RETRIES
            && self.now_s - self.team_forgiven_s >= TEAM_RETRY_S;
        if !(grown || retry) || self.blacklist.forgive() == 0 {
            return false;
        }
        if grown {
            self.forgiven_at = Some(self.map.known_cells);
            self.team_retries = 0;
        } else {
            self.team_retries += 1;
        }
        self.team_forgiven_s = self.now_s;
        true
    }

    /// Begins a decision (the goals given up already given another chance before it when
    /// `forgiven`): the question to the policy, or at once the decision's result when nothing
    /// is to be asked. A relaxed plan (see `chosen`) holds for one decision.
    pub(crate) fn begin_decision(&mut self, forgiven: bool) -> Step {
        self.set_planning(Planning::WithMargin);
        self.begin_level(forgiven)
    }

    /// The decision at the planning level in use: the frontiers, their goals and the plan to
    /// them, then the first round of asking (`begin_round`).
    fn begin_level(&mut self, forgiven: bool) -> Step {
        if self.map.grid.known_bounds.is_none() {
            // Nothing seen yet: wait for the first scan.
            return Step::Done(true);
        }
        self.blacklist_reached_again();
        let mut frontiers = self.candidate_frontiers();
        self.goal = None;
        self.follower = PathFollower::default();
        if frontiers.is_empty() {
            return Step::Done(false);
        }
        let mut goals = self.goal_cells(&frontiers);
        let use_layout = self.refresh_layout();
        let targets: Vec<Cell> = goals.iter().flatten().copied().collect();
        self.plans += 1;
        let mut plan = self.plan_bounded(&targets);
        // The frontiers' own middle cells first (the paper's rule), unless the settings ask
        // for the reachable part of every frontier from the start; as a last resort, before
        // ending the run with frontiers left, their reachable parts: exploration does not end
        // while a frontier can be reached.
        let moved_to_reachable = self.cfg.candidate_from_reachable_part;
        if moved_to_reachable {
            plan = self.reachable_candidates(&mut frontiers, &mut goals, plan);
        }
        self.begin_round(Box::new(Deciding {
            forgiven,
            frontiers,
            goals,
            use_layout,
            plan: Some(plan),
            moved_to_reachable,
            scores: Vec::new(),
            counted: 0,
            attempt: 0,
            unreachable_goals: 0,
            asked: Asked::default(),
            views: Vec::new(),
            between: None,
            mate_paths: None,
        }))
    }

    /// A round of asking: the candidates scored, then the policy asked until it chooses a
    /// candidate with a path on the planning grid, passes, or says stop. The distance grid is
    /// coarser and may connect what the planning grid does not (yet: a door seen at a slant
    /// opens as the robot comes closer), so a candidate without a path is passed over for
    /// this decision (the policy is asked again without it), not blacklisted.
    fn begin_round(&mut self, mut d: Box<Deciding>) -> Step {
        d.scores = self.score(&d.frontiers, &d.goals, d.plan(), d.use_layout);
        // (A round asked again with every distance searched counts once: see `chosen`.)
        d.counted = self.policy_decisions;
        d.attempt = 0;
        d.unreachable_goals = 0;
        self.ask(d, None)
    }

    /// Puts the question of attempt `d.attempt` (`unreachable_goal`: the previous attempt's
    /// goal point without a path): the candidates the policy is shown and the paths between
    /// them when it needs them. With no candidate to show, the answer is `Answer::Nothing`.
    fn ask(&mut self, mut d: Box<Deciding>, unreachable_goal: Option<Vec2>) -> Step {
        d.asked = Asked {
            attempt: d.attempt,
            use_layout: d.use_layout,
            unreachable_goal,
        };
        // A built-in strategy's rule weighs the layout's gain only while it uses the layout.
        let needs = self.policy_needs;
        let use_layout = d.use_layout || self.caller_decides;
        d.views = self.candidate_views(
            &d.frontiers,
            &d.goals,
            d.plan(),
            &d.scores,
            needs,
            use_layout,
        );
        if d.views.is_empty() {
            return self.answered(d, Answer::Nothing);
        }
        if d.attempt == 0 {
            self.policy_decisions += 1;
        }
        d.between = needs.paths_between.then(|| self.paths_between(&d.views));
        d.mate_paths =
            (needs.mate_paths && !self.mates.is_empty()).then(|| self.mate_paths(&d.views));
        Step::Ask(d)
    }

    /// The policy's `reply` to the question in `d`, and its compute time to charge (s). A reply
    /// naming no candidate shown (or a candidate twice, or an empty list, or a point that is not
    /// finite) is a failure of the policy (`policy_failed`), as [`Reply::Fail`] is.
    pub(crate) fn reply(&mut self, d: Box<Deciding>, reply: Reply, charged_s: f64) -> Step {
        if charged_s.is_finite() && charged_s > 0.0 {
            self.compute_debt_s += charged_s;
            self.strategy_compute_s += charged_s;
        }
        let views = &d.views;
        let shown = |id: &usize| views.iter().any(|v| v.id == *id);
        // Candidates shown, each once.
        let listed = |ids: &[usize]| {
            !ids.is_empty()
                && ids.iter().all(shown)
                && ids.iter().collect::<std::collections::BTreeSet<_>>().len() == ids.len()
        };
        let answer = match reply {
            Reply::Choose(id) if shown(&id) => Answer::One(id),
            Reply::Rank(ids) if listed(&ids) => Answer::Ranked(ids),
            Reply::Goal(p) if p.x.is_finite() && p.y.is_finite() => Answer::Point(p),
            Reply::Drop(ids) if listed(&ids) => Answer::Drop(ids),
            Reply::Pass => Answer::Nothing,
            Reply::Stop => Answer::Stop,
            _ => {
                self.policy_failed = true;
                Answer::Nothing
            }
        };
        self.answered(d, answer)
    }

    /// What an answer leads to: the round's choice (`chosen`), or the next attempt's question.
    fn answered(&mut self, mut d: Box<Deciding>, answer: Answer) -> Step {
        // An answer from a bounded search stands when it heads for a goal within the bound;
        // a stop, a pass or a goal beyond is asked again with every distance searched.
        let plan = d.plan();
        let inexact = match &answer {
            Answer::Stop | Answer::Nothing => !plan.is_exact(),
            Answer::One(best) => d.goals[*best].is_some_and(|c| !plan.is_exact_at(c)),
            Answer::Ranked(ids) => ids
                .first()
                .and_then(|&id| d.goals[id])
                .is_some_and(|c| !plan.is_exact_at(c)),
            Answer::Drop(_) | Answer::Point(_) => false,
        };
        if inexact {
            return self.chosen(d, Choice::Inexact);
        }
        match answer {
            Answer::Stop => self.chosen(d, Choice::Stop),
            Answer::Nothing => self.chosen(d, Choice::Nothing),
            Answer::Drop(ids) => {
                let frame = self.map.grid.frame;
                for id in ids {
                    let at = frame.world_from_cell(d.frontiers[id].candidate);
                    self.blacklist.add(at, self.cfg.blacklist_radius_m);
                    // Not offered again in this decision, nor by its last resorts where the
                    // blacklist holds.
                    d.scores[id].distance_m = None;
                    d.goals[id] = None;
                }
                d.attempt += 1;
                self.ask(d, None)
            }
            Answer::Point(p) => {
                if let Some((goal_cell, wps)) = self.point_goal(p) {
                    let n = d.frontiers.len();
                    let done = self.set_point_goal(n, p, goal_cell, wps);
                    return self.chosen(d, Choice::Decided(done));
                }
                d.unreachable_goals += 1;
                if d.unreachable_goals >= MAX_UNREACHABLE_GOALS {
                    return self.chosen(d, Choice::Nothing);
                }
                d.attempt += 1;
                self.ask(d, Some(p))
            }
            Answer::One(best) => {
                let goal_cell = d.goals[best].expect("best candidate is reachable");
                match self.waypoints_to(d.plan(), goal_cell) {
                    Some(wps) => return self.chosen(d, Choice::Found(best, wps)),
                    None => d.scores[best].distance_m = None,
                }
                d.attempt += 1;
                self.ask(d, None)
            }
            Answer::Ranked(ids) => {
                let mut found = None;
                for id in ids {
                    let goal_cell = d.goals[id].expect("ranked candidate is reachable");
                    if let Some(wps) = self.waypoints_to(d.plan(), goal_cell) {
                        found = Some((id, wps));
                        break;
                    }
                }
                match found {
                    Some((id, wps)) => self.chosen(d, Choice::Found(id, wps)),
                    None => self.chosen(d, Choice::Nothing),
                }
            }
        }
    }

    /// What the round's choice leads to: the goal set, the decision's end, or its last resorts
    /// in order (another round, another planning level).
    fn chosen(&mut self, mut d: Box<Deciding>, choice: Choice) -> Step {
        let cfg = Arc::clone(&self.cfg);
        // `None` when the strategy says stop.
        let chosen = match choice {
            Choice::Inexact => {
                // (The same decision asked again: counted once.)
                self.policy_decisions = d.counted;
                d.plan = Some(self.plan_all());
                return self.begin_round(d);
            }
            Choice::Decided(result) => return Step::Done(result),
            Choice::Stop => None,
            Choice::Nothing => Some(None),
            Choice::Found(best, wps) => Some(Some((best, wps))),
        };
        // A policy that failed ends the run at once.
        if self.policy_failed {
            return Step::Done(false);
        }
        let early_stop = match chosen {
            Some(Some((best, wps))) => {
                let goal_cell = d.goals[best].expect("best candidate is reachable");
                let score = d.scores[best];
                self.nav
                    .chose(d.plan().distance_m(goal_cell), cfg.distance_bound_m);
                return Step::Done(self.set_goal(&d.frontiers, best, goal_cell, wps, Some(score)));
            }
            Some(None) => false,
            None => true,
        };
        // Frontiers exist but none can be reached as they stand, or the early stop would end
        // the run. The last resorts first, in order. The early stop weighs the reachable
        // candidates only, so it gets them too (not under the paper's frontier rule): a
        // doorway seen at a slant leaves a wedge of free cells beyond it too thin to drive,
        // whose frontier is reachable only at the doorway, and the room behind must weigh in
        // the rule (modern-office, layout-es from a random start, stopped at 96.7 % with a
        // room never entered).
        let last_resorts = !early_stop || cfg.robust_frontiers;
        // 1. Each frontier's reachable part.
        if last_resorts && !d.moved_to_reachable {
            d.moved_to_reachable = true;
            let plan = d.plan.take().expect("a decision has a plan");
            let plan = self.reachable_candidates(&mut d.frontiers, &mut d.goals, plan);
            d.plan = Some(plan);
            return self.begin_round(d);
        }
        // 2. The plan without the safety margin. Where the map shows a passage (often the
        // one the robot came in by) a little narrower than the robot's diameter plus twice
        // the margin, the robot would otherwise end the run with frontiers it can reach
        // (Lamuniere1, seed 2, with updates every 0.5 m / 0.25 rad: 86 % explored).
        // 3. The plan through the cells the robot has travelled as well: where the map,
        // sharpened by later scans, shows the passage it came in by narrower than its body
        // (a crowded room, a narrow corridor), the robot is in a pocket of the planning grid
        // and reaches nothing (freiburg_building101 and intel_map from random starts,
        // stuck at 95 % explored). Its body fitted there: it leaves the way it came.
        if let Some(looser) = self.nav.planning().looser().filter(|_| last_resorts) {
            self.set_planning(looser);
            return self.begin_level(d.forgiven);
        }
        // 4. A closer look (see `approach`).
        if !early_stop {
            if let Some((i, goal_cell, wps)) = self.approach(&d.frontiers, &d.goals, d.plan()) {
                return Step::Done(self.set_goal(&d.frontiers, i, goal_cell, wps, None));
            }
        }
        if early_stop {
            self.stopped_early = true;
        } else {
            // Frontiers exist but none is reachable: blacklist them all so the run can end.
            for f in &d.frontiers {
                self.blacklist.add(
                    self.map.grid.frame.world_from_cell(f.candidate),
                    cfg.blacklist_radius_m,
                );
            }
        }
        Step::Done(false)
    }

    /// Blacklists the goal just reached (and looked at) if most of its frontier is still there.
    fn blacklist_reached_again(&mut self) {
        // A goal just reached and looked at whose frontier is still there cannot be resolved by
        // going there again: blacklist it.
        if let Some(p) = self.last_reached.take() {
            let again = self.goal.as_ref().is_some_and(|g| {
                g.frontier
                    .iter()
                    .filter(|c| is_frontier_cell(&self.map.grid.occupancy, **c))
                    .count()
                    * 2
                    > g.frontier.len()
            });
            if again && self.team_size > 1 {
                // (A teammate may have stood in the view: another chance later, see `forgive`.)
                self.blacklist
                    .looked_for_now(p, self.cfg.blacklist_radius_m);
            } else if again {
                self.blacklist.looked(p, self.cfg.blacklist_radius_m);
            }
        }
    }

    /// The frontiers of the map with enough clearance, those whose candidate is blacklisted
    /// dropped (or, with robust frontiers, their candidate moved outside the blacklist).
    fn candidate_frontiers(&mut self) -> Vec<Frontier> {
        let cfg = Arc::clone(&self.cfg);
        let frame = self.map.grid.frame;
        let fcfg = FrontierConfig::with_min_length_m(cfg.min_frontier_m, frame.resolution_m);
        let mut frontiers = self.map.frontiers.detect(&self.map.grid.occupancy, &fcfg);
        if cfg.frontier_clearance_m > 0.0 {
            let clearance_cells = cfg.frontier_clearance_m / frame.resolution_m;
            let obstacles = &self.map.obstacles;
            frontiers = frontiers_where(frontiers, &fcfg, |c| {
                f64::from(obstacles.get(c)) >= clearance_cells
            });
        }
        let blacklist = &self.blacklist;
        frontiers
            .into_iter()
            .filter_map(|f| {
                if !blacklist.contains(frame.world_from_cell(f.candidate)) {
                    Some(f)
                } else if cfg.robust_frontiers {
                    outside_blacklist(f, blacklist, &frame)
                } else {
                    None
                }
            })
            .collect()
    }

    /// The goal cell of each frontier: its candidate if traversable, else the nearest
    /// traversable cell within half a metre (`None` if there is none).
    fn goal_cells(&self, frontiers: &[Frontier]) -> Vec<Option<Cell>> {
        let search = (0.5 / self.map.grid.frame.resolution_m).ceil() as i32;
        let trav = self.traversability();
        frontiers
            .iter()
            .map(|f| {
                if trav.at(f.candidate) {
                    Some(f.candidate)
                } else {
                    nearest_by(f.candidate, search, |c| trav.at(c))
                }
            })
            .collect()
    }

    /// Heads for frontier `i` of `frontiers` through `goal_cell` (a map cell) along `wps`,
    /// recording the decision (`score`: its gain and path length; `None` for a closer look).
    /// Returns true.
    pub(crate) fn set_goal(
        &mut self,
        frontiers: &[Frontier],
        i: usize,
        goal_cell: Cell,
        wps: Vec<Vec2>,
        score: Option<CandidateScore>,
    ) -> bool {
        let frame = self.map.grid.frame;
        let f = &frontiers[i];
        let look_at = unknown_centroid(&self.map.grid.occupancy, &f.cells)
            .unwrap_or_else(|| frame.world_from_cell(f.candidate));
        let look_dir = self
            .cfg
            .robust_frontiers
            .then(|| unknown_side(&self.map.grid.occupancy, &f.cells))
            .flatten();
        let target = Target {
            cell: goal_cell,
            candidate: f.candidate,
            look_at,
            look_dir,
            frontier: f.cells.clone(),
        };
        let recorded = Recorded {
            goal: frame.world_from_cell(goal_cell),
            candidates: frontiers.len(),
            gain_m2: score.map_or(0.0, |s| s.gain_m2),
            distance_m: score.map(|s| s.distance_m.unwrap_or(0.0)),
        };
        self.head_for(target, recorded, wps)
    }

    /// The goal cell and path for a policy's own goal point `p` (`Reply::Goal`): the nearest
    /// traversable map cell within 0.5 m of it, and a path there on the planning grid. `None`
    /// when `p` is off the map or no path leads there.
    pub(crate) fn point_goal(&mut self, p: Vec2) -> Option<(Cell, Vec<Vec2>)> {
        let frame = self.map.grid.frame;
        let c = frame.cell_from_world(p);
        frame.index(c)?;
        let search = (0.5 / frame.resolution_m).ceil() as i32;
        let goal = {
            let trav = self.traversability();
            if trav.at(c) {
                Some(c)
            } else {
                nearest_by(c, search, |n| trav.at(n))
            }
        }?;
        let plan = self.plan(&[goal]);
        plan.distance_m(goal)?;
        let wps = self.waypoints_to(&plan, goal)?;
        Some((goal, wps))
    }

    /// Heads for a policy's own goal point `p` through `goal_cell` along `wps` (no frontier:
    /// the goal ends on arrival, and is given up, as any, when the robot makes no progress).
    /// `candidates`: how many were shown. Returns true.
    pub(crate) fn set_point_goal(
        &mut self,
        candidates: usize,
        p: Vec2,
        goal_cell: Cell,
        wps: Vec<Vec2>,
    ) -> bool {
        let target = Target {
            cell: goal_cell,
            candidate: goal_cell,
            look_at: p,
            look_dir: None,
            frontier: Vec::new(),
        };
        let recorded = Recorded {
            goal: p,
            candidates,
            gain_m2: 0.0,
            distance_m: None,
        };
        self.head_for(target, recorded, wps)
    }

    /// Follows `wps` to `target`, recording the decision (its distance, when `None`, the
    /// path's length). Returns true.
    fn head_for(&mut self, target: Target, recorded: Recorded, wps: Vec<Vec2>) -> bool {
        let now = self.now_s;
        self.follower = PathFollower::from(self.localizer.estimate().position(), wps);
        let dist = self
            .follower
            .remaining_length_m(self.localizer.estimate().position());
        self.decisions.push(Decision {
            time_s: now,
            pose: self.localizer.estimate(),
            goal: recorded.goal,
            candidates: recorded.candidates,
            gain_m2: recorded.gain_m2,
            distance_m: recorded.distance_m.unwrap_or(dist),
        });
        self.goal = Some(Goal {
            cell: target.cell,
            candidate: target.candidate,
            look_at: target.look_at,
            look_dir: target.look_dir,
            arrived: false,
            frontier: target.frontier,
            decided_at_s: now,
            known_cells_at: self.map.known_cells,
            best_distance_m: dist,
            best_distance_at_s: now,
            checked_s: now,
            waited_s: 0.0,
        });
        true
    }

    /// The candidates a policy with `needs` is shown: those with a distance and a goal, with the
    /// layout's gain when it needs it and `use_layout` holds.
    pub(crate) fn candidate_views(
        &mut self,
        frontiers: &[Frontier],
        goals: &[Option<Cell>],
        plan: &Plan,
        scores: &[CandidateScore],
        needs: Needs,
        use_layout: bool,
    ) -> Vec<CandidateView> {
        let layout_gain = needs.layout_gain && use_layout;
        let frame = self.map.grid.frame;
        let robot = self.localizer.estimate().position();
        let range_m = self.cfg.sim.laser.max_range_m;
        let mut views = Vec::new();
        for (i, s) in scores.iter().enumerate() {
            let (Some(distance_m), Some(goal)) = (s.distance_m, goals[i]) else {
                continue;
            };
            let f = &frontiers[i];
            let point = frame.world_from_cell(f.candidate);
            let now = self.map.updates();
            let layout_gain_m2 = match (&self.map.layout, layout_gain) {
                (Some(l), true) => {
                    let grid = &self.map.grid.occupancy;
                    Some(layout_gain_cached(
                        &mut self.map.gains,
                        grid,
                        &l.raster,
                        f.candidate,
                        range_m,
                        now,
                    ))
                }
                _ => None,
            };
            views.push(CandidateView {
                id: i,
                cell: f.candidate,
                point,
                goal: frame.world_from_cell(goal),
                frontier_cells: f.size,
                distance_m,
                path_m: plan.distance_m(goal).unwrap_or(distance_m),
                straight_m: (point - robot).norm(),
                gain_m2: s.gain_m2,
                layout_gain_m2,
                room: match (&self.map.layout, needs.layout) {
                    (Some(l), true) => l.raster.room_index(f.candidate),
                    _ => None,
                },
            });
        }
        views
    }

    /// The decision as a policy with `needs` sees it, with `views` for its candidates.
    pub(crate) fn decision_view<'v>(
        &'v self,
        map: &'v MapState,
        views: &'v [CandidateView],
        asked: &Asked,
        needs: Needs,
        between_m: Option<&'v [f64]>,
        mate_paths_m: Option<&'v [f64]>,
    ) -> DecisionView<'v> {
        DecisionView {
            decision: self.policy_decisions - 1,
            attempt: asked.attempt,
            time_s: self.now_s,
            pose: self.localizer.estimate(),
            candidates: views,
            unreachable_goal: asked.unreachable_goal,
            layout: map
                .layout
                .as_ref()
                .filter(|_| needs.layout)
                .map(|l| LayoutView {
                    number: l.number,
                    rooms: &l.rooms,
                }),
            map: &map.grid.occupancy,
            between_m,
            team: (self.team_size > 1).then_some(TeamView {
                robot: self.robot.0,
                size: self.team_size,
                mates: &self.mates,
                mate_paths_m,
            }),
        }
    }

    /// The last rung of the decision's last resorts (`chosen`): a closer look at a frontier that the distance
    /// grid reaches but no path on the planning grid does (a doorway seen from afar at a grazing
    /// angle, drawn narrower than the robot by the noise of its edges: intel_map from a random
    /// start never entered the building's middle and ended at 79 % explored). The goal is the
    /// planning cell reachable from the robot nearest to such a frontier's goal `goals[i]`, within
    /// the laser's range of it and at least 1 m nearer to it than the robot stands; the frontier
    /// whose gap left is smallest wins (the first among equals). Scans from there often open the
    /// doorway; if not, the frontier is looked into from there and given up as any other.
    /// Returns the frontier's index, the goal (map cell) and the path's waypoints.
    pub(crate) fn approach(
        &mut self,
        frontiers: &[Frontier],
        goals: &[Option<Cell>],
        plan: &Plan,
    ) -> Option<(usize, Cell, Vec<Vec2>)> {
        let frame = self.map.grid.frame;
        let near = self.nav.coarse();
        let field = dijkstra_padded(near.frame, plan.near_start, near.padded(), MAX_EXTRA, &[]);
        let robot = self.localizer.estimate().position();
        let range_m = self.cfg.sim.laser.max_range_m;
        let r = (range_m / near.frame.resolution_m).ceil() as i32;
        let mut best: Option<(f64, usize, Cell)> = None;
        for (i, g) in goals.iter().enumerate() {
            let Some(g) = *g else { continue };
            if plan.distance_m(g).is_none() {
                continue;
            }
            // Slivers behind a wall and corners seen at a slant are not worth the drive; a
            // doorway opens onto a room. The baseline's gain (not the strategy's: a layout's
            // wall line may close the very doorway; not cached: the caches hold the strategy's).
            let (grid, candidate) = (&self.map.grid.occupancy, frontiers[i].candidate);
            if information_gain(grid, candidate, range_m) < CLOSER_LOOK_MIN_GAIN_M2 {
                continue;
            }
            let target = frame.world_from_cell(g);
            let gc = near.coarse_of(g);
            let mut nearest: Option<(f64, Cell)> = None;
            for y in gc.y - r..=gc.y + r {
                for x in gc.x - r..=gc.x + r {
                    let c = Cell::new(x, y);
                    if field.distance_m(c).is_none() {
                        continue;
                    }
                    let d = (near.frame.world_from_cell(c) - target).norm();
                    if d <= range_m && nearest.is_none_or(|(nd, _)| d < nd) {
                        nearest = Some((d, c));
                    }
                }
            }
            let Some((gap_m, c)) = nearest else { continue };
            if (robot - target).norm() - gap_m >= 1.0 && best.is_none_or(|(bd, ..)| gap_m < bd) {
                best = Some((gap_m, i, c));
            }
        }
        let (_, i, c) = best?;
        let path = field.path_to(c)?;
        let wps = waypoints_by(&path, &near.frame, |n| near.passable(n));
        let f = near.factor as i32;
        Some((i, Cell::new(c.x * f + f / 2, c.y * f + f / 2), wps))
    }
}

/// Least baseline gain (m2) of a frontier worth a closer look (see `Explorer::approach`): two
/// square metres, about what a doorway's view adds at once; slivers and corners add less.
pub(crate) const CLOSER_LOOK_MIN_GAIN_M2: f64 = 2.0;

/// A policy's answer as a decision uses it: one candidate (the next best is asked for when it
/// has no path), a ranking (the first with a path), a point of its own, none, or stop.
pub(crate) enum Answer {
    One(usize),
    Ranked(Vec<usize>),
    Point(Vec2),
    Drop(Vec<usize>),
    Nothing,
    Stop,
}

/// Where a decision stands after a step: the policy is asked (the question in [`Deciding`]),
/// or the decision is made.
pub(crate) enum Step {
    /// The policy is asked: see `Explorer::reply`.
    Ask(Box<Deciding>),
    /// Decided: whether a goal was set (false: no reachable candidate is left, or the strategy
    /// stopped, or the policy failed).
    Done(bool),
}

/// A decision in progress, its retries and last resorts as explicit state: the frontiers, their
/// goal cells and the plan at the planning level in use (`Explorer::begin_level`), the round of
/// asking (`begin_round`: the scores, the attempt) and the question put (`ask`).
#[derive(Clone)]
pub(crate) struct Deciding {
    /// The goals given up had another chance before this decision (`Explorer::forgive`).
    pub(crate) forgiven: bool,
    frontiers: Vec<Frontier>,
    goals: Vec<Option<Cell>>,
    /// Whether a built-in strategy's gains use the layout now.
    use_layout: bool,
    /// (Only taken out while the last resorts move the candidates.)
    plan: Option<Plan>,
    /// The candidates already moved to their frontiers' reachable parts (the first last resort).
    moved_to_reachable: bool,
    scores: Vec<CandidateScore>,
    /// `policy_decisions` when the round began.
    counted: usize,
    attempt: usize,
    /// Goal points of the policy's own without a path in this round.
    unreachable_goals: usize,
    /// The question put: how, the candidates shown, the paths between them.
    pub(crate) asked: Asked,
    pub(crate) views: Vec<CandidateView>,
    pub(crate) between: Option<Vec<f64>>,
    /// In a team, when the policy needs them: the paths from the mates to the candidates.
    pub(crate) mate_paths: Option<Vec<f64>>,
}

impl Deciding {
    fn plan(&self) -> &Plan {
        self.plan.as_ref().expect("a decision has a plan")
    }

    /// The question as a policy with `needs` would be shown it (`views`, `between`), for a run
    /// that shares this one's state (see `shared`).
    pub(crate) fn show(
        &self,
        ex: &mut Explorer,
        needs: Needs,
    ) -> (Vec<CandidateView>, Option<Vec<f64>>) {
        let views = ex.candidate_views(
            &self.frontiers,
            &self.goals,
            self.plan(),
            &self.scores,
            needs,
            self.asked.use_layout,
        );
        let between = needs.paths_between.then(|| ex.paths_between(&views));
        (views, between)
    }
}

/// In a team: the least time between two chances for the goals given up without the map
/// growing (s), and how many such chances between two the map's growth gave (see
/// `Explorer::forgive`).
pub(crate) const TEAM_RETRY_S: f64 = 60.0;
pub(crate) const TEAM_RETRIES: u32 = 3;

/// What the policy chose within one round of a decision (see `Explorer::answered`).
enum Choice {
    /// The answer rests on distances beyond a bounded search ([`Plan::is_exact_at`]): to be
    /// asked again with every distance searched.
    Inexact,
    /// The strategy says stop.
    Stop,
    /// No candidate with a path (or the policy passed).
    Nothing,
    /// The chosen candidate and the waypoints to its goal cell.
    Found(usize, Vec<Vec2>),
    /// The decision is made (a goal point of the policy's own): its result.
    Decided(bool),
}

/// Where a goal leads (see `Goal`).
struct Target {
    cell: Cell,
    candidate: Cell,
    look_at: Vec2,
    look_dir: Option<Vec2>,
    frontier: Vec<Cell>,
}

/// What the decision record of a goal says besides its time and pose (see `Decision`).
struct Recorded {
    goal: Vec2,
    candidates: usize,
    gain_m2: f64,
    distance_m: Option<f64>,
}

/// How a policy is asked within one decision: the attempt, whether a built-in strategy uses the
/// layout now, and the goal point of the previous attempt that had no path.
#[derive(Debug, Clone, Default)]
pub(crate) struct Asked {
    pub(crate) attempt: usize,
    pub(crate) use_layout: bool,
    pub(crate) unreachable_goal: Option<Vec2>,
}

/// A frontier whose middle cell is blacklisted, with its candidate moved to the cell nearest to
/// the middle outside every blacklisted radius (the first in row-major order among equals), or
/// `None` when every cell is blacklisted.
pub(crate) fn outside_blacklist(
    mut f: Frontier,
    blacklist: &Blacklist,
    frame: &GridFrame,
) -> Option<Frontier> {
    let from = f.candidate;
    let d2 = |c: &Cell| {
        let (dx, dy) = ((c.x - from.x) as i64, (c.y - from.y) as i64);
        dx * dx + dy * dy
    };
    f.candidate = *f
        .cells
        .iter()
        .filter(|c| !blacklist.contains(frame.world_from_cell(**c)))
        .min_by_key(|c| d2(c))?;
    Some(f)
}

/// The outward side of a frontier: the mean of the unit steps from its cells to their unknown
/// 4-neighbours, normalised (`None` when they cancel out or there are none).
pub(crate) fn unknown_side(grid: &OccupancyGrid, cells: &[Cell]) -> Option<Vec2> {
    let mut sum = Vec2::zeros();
    for c in cells {
        for nb in c.neighbours4() {
            if grid.is(nb, Occupancy::Unknown) {
                sum += Vec2::new(f64::from(nb.x - c.x), f64::from(nb.y - c.y));
            }
        }
    }
    (sum.norm() > 1e-9).then(|| sum / sum.norm())
}

/// Centre of the unknown cells next to a frontier.
pub(crate) fn unknown_centroid(grid: &OccupancyGrid, cells: &[Cell]) -> Option<Vec2> {
    let mut sum = Vec2::zeros();
    let mut n = 0usize;
    for c in cells {
        for nb in c.neighbours4() {
            if grid.is(nb, Occupancy::Unknown) {
                sum += grid.frame.world_from_cell(nb);
                n += 1;
            }
        }
    }
    (n > 0).then(|| sum / n as f64)
}

/// The paper's `I(p)` ([`layout_information_gain`]) through the cache: a candidate the layout
/// leaves with the plain gain (in a room with an open frontier, or outside every room) reads the
/// plain gain, which a new layout does not make stale.
pub(crate) fn layout_gain_cached(
    gains: &mut GainCache,
    grid: &OccupancyGrid,
    raster: &LayoutRaster,
    p: Cell,
    range_m: f64,
    now: u64,
) -> f64 {
    if raster.uses_baseline(p) {
        gains.plain_gain(p, range_m, now, || information_count_read(grid, p, range_m))
    } else {
        gains.gain(GainKind::Rooms, p, range_m, now, || {
            layout_information_gain_read(grid, raster, p, range_m)
        })
    }
}
