//! Exploration strategies as values. A [`Strategy`] is a gain model (how the information gain
//! `I(p)` of a candidate is estimated, and from which layout), an early-stopping rule and a
//! choice (how the candidates the stop rule keeps are weighed: a [`Rule`] with the values of
//! the settings it reads); the combinations that mean nothing (an oracle layout without a
//! layout gain, the switch's thresholds on another model) cannot be written. The built-in
//! strategies are registered in `super::strategies`, one file each: its name, what it does in
//! words, the settings it reads, the function that makes its value from the user's settings
//! and, when its way of choosing is its own, its rule. Their choice is made by a [`Policy`]
//! ([`BuiltInPolicy`]), as an external strategy's is.

use std::sync::Arc;

use super::policy::{CandidateView, DecisionView, Needs, Policy, Reply};

/// Where a layout comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LayoutSource {
    /// Predicted from the map as it is explored (the paper's method).
    Predicted,
    /// The building's ground-truth rooms, brought into the map's frame by the current pose
    /// error: an oracle, so that the paper's gain can be judged apart from the errors of the
    /// layout prediction. Needs a building with rooms.
    Truth,
}

/// How `I(p)` is estimated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GainModel {
    /// Unknown cells within laser range visible from `p`, unknown counted as free ("no L").
    Baseline,
    /// "With L", the paper's `I(p)`: the unknown area inside the predicted rooms visible in
    /// `M^L` (rooms with an open frontier fall back to the baseline).
    PredictedRooms(LayoutSource),
    /// The baseline gain through the map with the layout's wall lines closing short gaps in
    /// observed walls (`layout-gaps`); an early stop still judges the paper's `I(p)`. See
    /// `layout_gain` for why this ranking does not use the predicted room shapes.
    ClosedGaps(LayoutSource),
    /// The baseline until the predicted layout is judged reliable, then the paper's `I(p)`: the
    /// dynamic switch of the paper's conclusion. The layout is trusted once at least
    /// `agreement` of the cells it predicted inside rooms, and that were observed since, turned
    /// out free, measured over at least `min_area_m2`.
    Switch { agreement: f64, min_area_m2: f64 },
}

impl GainModel {
    /// Where its layout comes from (`None`: it uses none).
    pub fn layout_source(self) -> Option<LayoutSource> {
        match self {
            GainModel::Baseline => None,
            GainModel::PredictedRooms(s) | GainModel::ClosedGaps(s) => Some(s),
            GainModel::Switch { .. } => Some(LayoutSource::Predicted),
        }
    }

    /// Whether candidates are ranked by the paper's `I(p)` while the layout is in use.
    pub fn ranks_by_predicted_rooms(self) -> bool {
        matches!(
            self,
            GainModel::PredictedRooms(_) | GainModel::Switch { .. }
        )
    }
}

/// When to stop early.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EarlyStop {
    /// Explore until no frontier is left.
    Never,
    /// The paper's ES: stop when the sum of `I(p)` over all candidates is below the threshold (m2).
    TotalGainBelow(f64),
    /// The more aggressive ES of the paper's discussion: candidates whose `I(p)` is below the
    /// threshold (m2) are dropped; stop when none is left.
    DropCandidatesBelow(f64),
}

/// A way of choosing among the candidates a built-in strategy's early stop keeps: the value a
/// strategy file supplies. `L` below is the planned path's length to the candidate's goal
/// ([`CandidateView::path_m`]), `I` its gain as the gain model estimates it; ties go to the
/// candidate listed first.
pub(crate) trait Rule: std::fmt::Debug + Send + Sync {
    /// Its name (two choices are the same when their names and parameters are).
    fn name(&self) -> &'static str;
    /// The settings it reads, by their names, with its values of them.
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        Vec::new()
    }
    /// Whether it needs the rooms of the layout predicted from the map ([`Needs::layout`]).
    fn needs_layout(&self) -> bool {
        false
    }
    /// Whether it needs the path lengths between the candidates ([`Needs::paths_between`]).
    fn needs_paths_between(&self) -> bool {
        false
    }
    /// Whether it needs the path lengths from the teammates to the candidates
    /// ([`Needs::mate_paths`]).
    fn needs_mate_paths(&self) -> bool {
        false
    }
    /// The index in `at.shown` of the candidate chosen (`None`: none is).
    fn choose(&self, at: &Choosing<'_, '_>, memory: &mut Memory) -> Option<usize>;
}

/// What a [`Rule`] chooses from.
#[derive(Debug)]
pub(crate) struct Choosing<'v, 'a> {
    pub view: &'v DecisionView<'a>,
    /// The candidates the early stop kept, in the order of `view.candidates`.
    pub shown: &'v [&'v CandidateView],
    /// Their ids.
    pub kept: &'v [usize],
}

/// What a [`BuiltInPolicy`] keeps for its rule from one decision to the next.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Memory {
    /// The run's seed.
    pub seed: u64,
    /// The point of the candidate chosen last, for a rule that keeps its goal (map frame, m).
    pub goal: Option<crate::geom::Vec2>,
}

/// How a built-in strategy chooses among the candidates its early stop keeps: a [`Rule`] of a
/// strategy file with the values of the settings it reads.
#[derive(Clone)]
pub struct Choice(Arc<dyn Rule>);

impl Choice {
    /// The choice by `rule`.
    pub(crate) fn new(rule: impl Rule + 'static) -> Self {
        Self(Arc::new(rule))
    }

    /// Its rule's name.
    pub fn name(&self) -> &'static str {
        self.0.name()
    }

    /// The settings it reads, by their names, with its values of them.
    pub fn parameters(&self) -> Vec<(&'static str, f64)> {
        self.0.parameters()
    }
}

impl PartialEq for Choice {
    fn eq(&self, other: &Self) -> bool {
        self.name() == other.name() && self.parameters() == other.parameters()
    }
}

impl std::fmt::Debug for Choice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Choice({} {:?})", self.name(), self.parameters())
    }
}

/// A strategy: how gains are estimated, when to stop early, how to choose.
#[derive(Debug, Clone, PartialEq)]
pub struct Strategy {
    pub gain: GainModel,
    pub early_stop: EarlyStop,
    pub choice: Choice,
}

/// The user's settings a strategy's definition reads.
#[derive(Debug, Clone, PartialEq)]
pub struct StrategyParams {
    /// The utility's weight of distance (the paper's alpha).
    pub alpha: f64,
    /// The utility's floor on a candidate's gain (m2).
    pub gain_floor_m2: f64,
    /// The paper's ES threshold (m2).
    pub es_threshold_m2: f64,
    /// The aggressive ES's least gain of a candidate (m2).
    pub aes_min_gain_m2: f64,
    /// `utility-exp`'s weight of path length (per m).
    pub utility_exp_lambda_per_m: f64,
    /// `cost-utility`'s price of path length (m2 per m).
    pub cost_utility_beta_m2_per_m: f64,
}

impl Default for StrategyParams {
    fn default() -> Self {
        Self {
            alpha: 0.5,
            gain_floor_m2: 0.0,
            es_threshold_m2: 1.0,
            aes_min_gain_m2: 2.0,
            utility_exp_lambda_per_m: 0.2,
            cost_utility_beta_m2_per_m: 1.0,
        }
    }
}

impl Strategy {
    /// The settings this strategy reads, by their names, with its values of them: those of
    /// its choice, its early stop and, when it uses the layout, how the layout is used
    /// (`layout_update_m2`, `layout_update_fraction`, `max_wall_gap_m` for closed gaps; their
    /// values are the run's, not the strategy's, so only their names are listed there).
    pub fn parameters(&self) -> Vec<(&'static str, Option<f64>)> {
        let mut out: Vec<(&'static str, Option<f64>)> = self
            .choice
            .parameters()
            .into_iter()
            .map(|(name, v)| (name, Some(v)))
            .collect();
        match self.early_stop {
            EarlyStop::Never => {}
            EarlyStop::TotalGainBelow(t) => out.push(("es_threshold_m2", Some(t))),
            EarlyStop::DropCandidatesBelow(t) => out.push(("aes_min_gain_m2", Some(t))),
        }
        if self.gain.layout_source().is_some() || self.choice.0.needs_layout() {
            out.push(("layout_update_m2", None));
            out.push(("layout_update_fraction", None));
        }
        if matches!(self.gain, GainModel::ClosedGaps(_)) {
            out.push(("max_wall_gap_m", None));
        }
        out
    }

    /// Whether this strategy needs the layout at all.
    pub fn uses_layout(&self) -> bool {
        self.gain.layout_source().is_some()
    }

    /// Whether its layout is the building's true rooms (an oracle).
    pub fn layout_from_truth(&self) -> bool {
        self.gain.layout_source() == Some(LayoutSource::Truth)
    }

    /// The same strategy without its early stop: runs of strategies whose plain forms are equal
    /// share their beginning ([`super::can_share`]).
    pub fn without_early_stop(&self) -> Self {
        Self {
            early_stop: EarlyStop::Never,
            ..self.clone()
        }
    }
}

/// Applies the early-stopping rule to the candidates' gains: returns which candidates stay and
/// whether exploration should stop now.
pub(crate) fn early_stop(rule: EarlyStop, gains_m2: &[f64]) -> (Vec<bool>, bool) {
    match rule {
        EarlyStop::Never => (vec![true; gains_m2.len()], false),
        EarlyStop::TotalGainBelow(t) => {
            let total: f64 = gains_m2.iter().sum();
            (
                vec![true; gains_m2.len()],
                !gains_m2.is_empty() && total < t,
            )
        }
        EarlyStop::DropCandidatesBelow(t) => {
            let keep: Vec<bool> = gains_m2.iter().map(|g| *g >= t).collect();
            let stop = !gains_m2.is_empty() && !keep.iter().any(|k| *k);
            (keep, stop)
        }
    }
}

/// A built-in strategy's decision rule as a [`Policy`]: its early-stopping rule on the
/// candidates' gains (the paper's `I(p)` inside the predicted rooms when the layout is in use,
/// [`CandidateView::layout_gain_m2`], else the ranking gain), then its [`Choice`] over the
/// candidates the rule keeps. The explorer computes the gains the strategy's gain model defines
/// ([`CandidateView::gain_m2`]).
#[derive(Debug, Clone, PartialEq)]
pub struct BuiltInPolicy {
    pub early_stop: EarlyStop,
    pub choice: Choice,
    /// The candidates the rule kept at this decision's first attempt.
    kept: Vec<usize>,
    /// What its rule keeps between decisions (the run's seed, the goal drawn last).
    memory: Memory,
}

impl BuiltInPolicy {
    /// The rule of `strategy` in a run of `seed`.
    pub fn new(strategy: &Strategy, seed: u64) -> Self {
        Self {
            early_stop: strategy.early_stop,
            choice: strategy.choice.clone(),
            kept: Vec::new(),
            memory: Memory { seed, goal: None },
        }
    }
}

impl Policy for BuiltInPolicy {
    fn needs(&self) -> Needs {
        Needs {
            layout_gain: self.early_stop != EarlyStop::Never,
            layout: self.choice.0.needs_layout(),
            paths_between: self.choice.0.needs_paths_between(),
            mate_paths: self.choice.0.needs_mate_paths(),
        }
    }

    fn decide(&mut self, view: &DecisionView<'_>) -> (Reply, f64) {
        if view.attempt == 0 {
            let gains: Vec<f64> = view
                .candidates
                .iter()
                .map(|c| c.layout_gain_m2.unwrap_or(c.gain_m2))
                .collect();
            let (keep, stop) = early_stop(self.early_stop, &gains);
            if stop {
                return (Reply::Stop, 0.0);
            }
            self.kept = view
                .candidates
                .iter()
                .zip(keep)
                .filter(|(_, k)| *k)
                .map(|(c, _)| c.id)
                .collect();
        }
        let shown: Vec<&CandidateView> = view
            .candidates
            .iter()
            .filter(|c| self.kept.contains(&c.id))
            .collect();
        let at = Choosing {
            view,
            shown: &shown,
            kept: &self.kept,
        };
        let chosen = self.choice.0.choose(&at, &mut self.memory);
        let reply = match chosen {
            Some(i) => Reply::Choose(shown[i].id),
            None => Reply::Pass,
        };
        (reply, 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::super::policy::RoomView;
    use super::super::strategies::{strategies_markdown, BUILT_IN};
    use super::*;

    /// Each name makes the value it stands for, with the settings' thresholds.
    #[test]
    #[allow(clippy::too_many_lines)] // a table of cases
    fn names_make_their_strategies() {
        let p = StrategyParams {
            alpha: 0.3,
            gain_floor_m2: 0.5,
            es_threshold_m2: 1.5,
            aes_min_gain_m2: 2.5,
            utility_exp_lambda_per_m: 0.7,
            cost_utility_beta_m2_per_m: 3.0,
        };
        let utility: &[(&str, f64)] = &[("alpha", 0.3), ("gain_floor_m2", 0.5)];
        let never = EarlyStop::Never;
        let predicted = GainModel::PredictedRooms(LayoutSource::Predicted);
        let truth = GainModel::PredictedRooms(LayoutSource::Truth);
        let gaps = GainModel::ClosedGaps(LayoutSource::Predicted);
        let es = EarlyStop::TotalGainBelow(1.5);
        let switch = GainModel::Switch {
            agreement: 0.9,
            min_area_m2: 5.0,
        };
        // (name, gain, stop, the choice's rule and parameters)
        type Case<'a> = (&'a str, GainModel, EarlyStop, &'a str, &'a [(&'a str, f64)]);
        let cases: &[Case] = &[
            ("baseline", GainModel::Baseline, never, "utility", utility),
            ("layout", predicted, never, "utility", utility),
            ("layout-es", predicted, es, "utility", utility),
            (
                "layout-aes",
                predicted,
                EarlyStop::DropCandidatesBelow(2.5),
                "utility",
                utility,
            ),
            ("layout-switch", switch, never, "utility", utility),
            ("layout-gaps", gaps, never, "utility", utility),
            ("layout-gaps-es", gaps, es, "utility", utility),
            ("layout-truth", truth, never, "utility", utility),
            ("layout-truth-es", truth, es, "utility", utility),
            ("nearest", GainModel::Baseline, never, "nearest", &[]),
            (
                "utility-exp",
                GainModel::Baseline,
                never,
                "utility-exp",
                &[("utility_exp_lambda_per_m", 0.7)],
            ),
            (
                "cost-utility",
                GainModel::Baseline,
                never,
                "cost-utility",
                &[("cost_utility_beta_m2_per_m", 3.0)],
            ),
            (
                "frontier-tsp",
                GainModel::Baseline,
                never,
                "frontier-tsp",
                &[],
            ),
            ("room-first", GainModel::Baseline, never, "room-first", &[]),
            ("random-frontier", GainModel::Baseline, never, "random", &[]),
            (
                "team-nearest",
                GainModel::Baseline,
                never,
                "team-nearest",
                &[],
            ),
            (
                "team-greedy",
                GainModel::Baseline,
                never,
                "team-greedy",
                utility,
            ),
            (
                "team-burgard",
                GainModel::Baseline,
                never,
                "team-burgard",
                utility,
            ),
            (
                "team-hungarian",
                GainModel::Baseline,
                never,
                "team-hungarian",
                utility,
            ),
            (
                "team-minpos",
                GainModel::Baseline,
                never,
                "team-minpos",
                &[],
            ),
        ];
        assert_eq!(
            Strategy::names(),
            cases.iter().map(|c| c.0).collect::<Vec<_>>()
        );
        for &(name, gain, stop, rule, parameters) in cases {
            let s = Strategy::by_name(name, &p).unwrap();
            assert_eq!((s.gain, s.early_stop), (gain, stop), "{name}");
            assert_eq!(s.choice.name(), rule, "{name}");
            assert_eq!(s.choice.parameters(), parameters, "{name}");
            assert_eq!(s.uses_layout(), name.starts_with("layout"), "{name}");
            assert_eq!(s.layout_from_truth(), name.contains("truth"), "{name}");
        }
        assert!(Strategy::by_name("nope", &p).is_none());
        assert_eq!(
            Strategy::by_name("baseline", &StrategyParams::default()),
            Some(Strategy::baseline())
        );
        // Choices are equal by their rule and its values.
        let (a, b) = (
            Strategy::by_name("utility-exp", &p).unwrap(),
            Strategy::by_name("utility-exp", &StrategyParams::default()).unwrap(),
        );
        assert_ne!(a, b);
        assert_eq!(a, a.clone());
        assert_ne!(
            Strategy::by_name("nearest", &p).unwrap(),
            Strategy::by_name("frontier-tsp", &p).unwrap()
        );
    }

    #[test]
    fn names_are_unique_and_tabled() {
        let mut names = Strategy::names();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), BUILT_IN.len());
        let table = strategies_markdown();
        for b in BUILT_IN {
            assert!(table.contains(&format!("| `{}` |", b.name)), "{}", b.name);
        }
    }

    /// Two reachable candidates: `near` (2 m of path, 1 m2 of gain) and `far` (20 m, 30 m2).
    fn two_candidates() -> [CandidateView; 2] {
        let c = |id, path_m, gain_m2| CandidateView {
            id,
            cell: crate::grid::Cell::new(0, 0),
            point: crate::geom::Vec2::zeros(),
            goal: crate::geom::Vec2::zeros(),
            frontier_cells: 10,
            distance_m: path_m,
            path_m,
            straight_m: path_m,
            gain_m2,
            layout_gain_m2: None,
            room: None,
        };
        [c(3, 2.0, 1.0), c(7, 20.0, 30.0)]
    }

    /// The choice of `strategy` (with the settings `p`) among `candidates`, at `decision`.
    fn choice_of(
        strategy: &str,
        p: &StrategyParams,
        seed: u64,
        decision: usize,
        candidates: &[CandidateView],
    ) -> Reply {
        let map = crate::grid::OccupancyGrid::filled(
            crate::grid::GridFrame::new(crate::geom::Vec2::zeros(), 0.05, 4, 4),
            crate::grid::Occupancy::Unknown,
        );
        let view = DecisionView {
            decision,
            attempt: 0,
            time_s: 1.0,
            pose: crate::geom::Pose::new(0.0, 0.0, 0.0),
            candidates,
            unreachable_goal: None,
            layout: None,
            map: &map,
            between_m: None,
            team: None,
        };
        let s = Strategy::by_name(strategy, p).unwrap();
        BuiltInPolicy::new(&s, seed).decide(&view).0
    }

    /// What distinguishes each literature strategy: the nearest goes near whatever the gains;
    /// the exponential utility and the cost utility go far for a large gain when path is cheap
    /// (small lambda, small beta) and near when it is dear.
    #[test]
    fn the_literature_strategies_weigh_path_and_gain_as_their_papers_do() {
        let two = two_candidates();
        let (near, far) = (Reply::Choose(3), Reply::Choose(7));
        let with = |lambda: f64, beta: f64| StrategyParams {
            utility_exp_lambda_per_m: lambda,
            cost_utility_beta_m2_per_m: beta,
            ..StrategyParams::default()
        };
        // (strategy, lambda, beta, the choice): 30 e^(-20 l) against e^(-2 l) turns at
        // l = ln(30) / 18 = 0.189 per m; 30 - 20 b against 1 - 2 b at b = 29 / 18 = 1.61.
        let cases = [
            ("nearest", 0.0, 0.0, &near),
            ("utility-exp", 0.1, 1.0, &far),
            ("utility-exp", 0.2, 1.0, &near),
            ("cost-utility", 0.2, 1.5, &far),
            ("cost-utility", 0.2, 1.7, &near),
            ("baseline", 0.2, 1.0, &far),
        ];
        for (name, lambda, beta, expected) in cases {
            let got = choice_of(name, &with(lambda, beta), 1, 0, &two);
            assert_eq!(&got, expected, "{name} lambda {lambda} beta {beta}");
        }
    }

    /// `frontier-tsp` goes where a short tour through every candidate starts, not to the
    /// nearest: candidates on a line at 1, -1.2, 3, -2 and 6 m from the robot; the nearest
    /// (1 m) leaves -1.2 and -2 to come back for (12 m in all), the tour takes them first (10 m,
    /// either of them first). Without the lengths between the candidates it takes the nearest.
    #[test]
    fn frontier_tsp_starts_the_shortest_tour() {
        let xs = [1.0, -1.2, 3.0, -2.0, 6.0_f64];
        let candidates: Vec<CandidateView> = xs
            .iter()
            .enumerate()
            .map(|(i, x)| CandidateView {
                id: 10 + i,
                distance_m: x.abs(),
                path_m: x.abs(),
                straight_m: x.abs(),
                ..two_candidates()[0]
            })
            .collect();
        let between: Vec<f64> = xs
            .iter()
            .flat_map(|a| xs.iter().map(move |b| (a - b).abs()))
            .collect();
        let map = crate::grid::OccupancyGrid::filled(
            crate::grid::GridFrame::new(crate::geom::Vec2::zeros(), 0.05, 4, 4),
            crate::grid::Occupancy::Unknown,
        );
        let s = Strategy::by_name("frontier-tsp", &StrategyParams::default()).unwrap();
        assert!(BuiltInPolicy::new(&s, 1).needs().paths_between);
        for (given, expected) in [(Some(&between[..]), [11, 13]), (None, [10, 10])] {
            let view = DecisionView {
                decision: 0,
                attempt: 0,
                time_s: 1.0,
                pose: crate::geom::Pose::new(0.0, 0.0, 0.0),
                candidates: &candidates,
                unreachable_goal: None,
                layout: None,
                map: &map,
                between_m: given,
                team: None,
            };
            let got = BuiltInPolicy::new(&s, 1).decide(&view).0;
            let chosen = match got {
                Reply::Choose(id) => id,
                other => panic!("{other:?}"),
            };
            assert!(expected.contains(&chosen), "{chosen} {:?}", given.is_some());
        }
    }

    /// `room-first` finishes the robot's room: a far candidate there goes before a near one
    /// elsewhere; with none left in its room (or outside every room) it takes the nearest. It
    /// asks for the layout; the others of its kind do not.
    #[test]
    fn room_first_finishes_the_robots_room() {
        use crate::geom::Vec2;
        let room = |x0: f64, x1: f64| RoomView {
            polygon: vec![
                Vec2::new(x0, 0.0),
                Vec2::new(x1, 0.0),
                Vec2::new(x1, 10.0),
                Vec2::new(x0, 10.0),
            ],
            state: super::super::policy::RoomState::Partial,
            predicted: false,
            area_m2: 100.0,
            observed_area_m2: 50.0,
            unknown_area_m2: 50.0,
        };
        let rooms = [room(0.0, 10.0), room(10.0, 20.0)];
        let [mut near, mut far] = two_candidates();
        let map = crate::grid::OccupancyGrid::filled(
            crate::grid::GridFrame::new(crate::geom::Vec2::zeros(), 0.05, 4, 4),
            crate::grid::Occupancy::Unknown,
        );
        let s = Strategy::by_name("room-first", &StrategyParams::default()).unwrap();
        assert!(BuiltInPolicy::new(&s, 1).needs().layout);
        assert!(!BuiltInPolicy::new(&Strategy::baseline(), 1).needs().layout);
        // (robot's x, near's room, far's room, the choice)
        let cases = [
            (5.0, Some(1), Some(0), 7),
            (15.0, Some(1), Some(0), 3),
            (5.0, Some(1), None, 3),
            (25.0, Some(1), Some(0), 3),
        ];
        for (x, near_room, far_room, expected) in cases {
            (near.room, far.room) = (near_room, far_room);
            let candidates = [near, far];
            let view = DecisionView {
                decision: 0,
                attempt: 0,
                time_s: 1.0,
                pose: crate::geom::Pose::new(x, 5.0, 0.0),
                candidates: &candidates,
                unreachable_goal: None,
                layout: Some(super::super::policy::LayoutView {
                    number: 1,
                    rooms: &rooms,
                }),
                map: &map,
                between_m: None,
                team: None,
            };
            let got = BuiltInPolicy::new(&s, 1).decide(&view).0;
            assert_eq!(got, Reply::Choose(expected), "robot at x = {x}");
        }
    }

    /// The random choice is the run's: the same seed and decision give the same candidate,
    /// every candidate is drawn over the decisions, and other seeds draw otherwise.
    #[test]
    fn the_random_frontier_is_drawn_from_the_seed() {
        let two = two_candidates();
        let p = StrategyParams::default();
        let draws = |seed| -> Vec<Reply> {
            (0..64)
                .map(|d| choice_of("random-frontier", &p, seed, d, &two))
                .collect()
        };
        let a = draws(1);
        assert_eq!(a, draws(1));
        assert_ne!(a, draws(2));
        for id in [3, 7] {
            let n = a.iter().filter(|r| **r == Reply::Choose(id)).count();
            assert!(
                (16..=48).contains(&n),
                "candidate {id} drawn {n} times of 64"
            );
        }
    }

    /// The random walk keeps its goal: while the frontier drawn stands (its candidate moved by
    /// at most 3 m) and the robot is not there, every decision goes to it; once the robot
    /// is there, or the goal was refused (a second attempt), it draws again.
    #[test]
    fn the_random_frontier_keeps_its_goal_until_reached() {
        use crate::geom::{Pose, Vec2};
        let mut cands = two_candidates();
        cands[0].point = Vec2::new(10.0, 0.0);
        cands[0].goal = cands[0].point;
        cands[1].point = Vec2::new(0.0, 10.0);
        cands[1].goal = cands[1].point;
        let map = crate::grid::OccupancyGrid::filled(
            crate::grid::GridFrame::new(Vec2::zeros(), 0.05, 4, 4),
            crate::grid::Occupancy::Unknown,
        );
        let s = Strategy::by_name("random-frontier", &StrategyParams::default()).unwrap();
        let ask = |policy: &mut BuiltInPolicy, decision, attempt, at: Vec2, c: &[CandidateView]| {
            let view = DecisionView {
                decision,
                attempt,
                time_s: 1.0,
                pose: Pose::new(at.x, at.y, 0.0),
                candidates: c,
                unreachable_goal: None,
                layout: None,
                map: &map,
                between_m: None,
                team: None,
            };
            policy.decide(&view).0
        };
        for seed in 1..=8 {
            let mut policy = BuiltInPolicy::new(&s, seed);
            let first = ask(&mut policy, 0, 0, Vec2::zeros(), &cands);
            let Reply::Choose(id) = first else {
                panic!("seed {seed}: {first:?}")
            };
            let k = usize::from(id == 7);
            // (decision, robot, how far the chosen frontier moved, whether it is kept)
            let cases = [
                (1, Vec2::new(1.0, 1.0), 0.0, true),
                (2, Vec2::new(2.0, 2.0), 1.0, true),
                (3, Vec2::new(2.0, 2.0), 1.0, true),
            ];
            let mut moved = cands;
            for (decision, robot, shift, kept) in cases {
                moved[k].point += Vec2::new(shift, 0.0);
                moved[k].goal = moved[k].point;
                let got = ask(&mut policy, decision, 0, robot, &moved);
                assert_eq!(
                    got == Reply::Choose(id),
                    kept,
                    "seed {seed}, decision {decision}"
                );
            }
            // The goal's frontier moved by 4 m at once: gone, so 64 later decisions of a
            // policy that goes on from here draw both candidates. Likewise with the robot at
            // the goal, and for a refused goal.
            for (robot, shift, attempt) in [
                (Vec2::zeros(), 4.0, 0),
                (moved[k].goal, 0.0, 0),
                (Vec2::zeros(), 0.0, 1),
            ] {
                let mut gone = moved;
                gone[k].point += Vec2::new(shift, 0.0);
                gone[k].goal = gone[k].point;
                let mut drawn = [0usize; 2];
                for decision in 10..74 {
                    let mut p = policy.clone();
                    let got = ask(&mut p, decision, attempt, robot, &gone);
                    drawn[usize::from(got == Reply::Choose(7))] += 1;
                }
                assert!(
                    drawn.iter().all(|n| (16..=48).contains(n)),
                    "seed {seed}, robot {robot:?}, shift {shift}, attempt {attempt}: {drawn:?}"
                );
            }
        }
    }

    #[test]
    fn early_stop_rules() {
        assert_eq!(
            early_stop(EarlyStop::Never, &[0.0, 0.1]),
            (vec![true, true], false)
        );
        assert!(early_stop(EarlyStop::TotalGainBelow(1.0), &[0.3, 0.5]).1);
        assert!(!early_stop(EarlyStop::TotalGainBelow(1.0), &[0.3, 0.8]).1);
        assert!(!early_stop(EarlyStop::TotalGainBelow(1.0), &[]).1);
        assert_eq!(
            early_stop(EarlyStop::DropCandidatesBelow(2.0), &[1.0, 3.0]),
            (vec![false, true], false)
        );
        assert!(early_stop(EarlyStop::DropCandidatesBelow(2.0), &[1.0, 1.5]).1);
    }
}
