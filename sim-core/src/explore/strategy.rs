//! Exploration strategies as values. A [`Strategy`] is a gain model (how the information gain
//! `I(p)` of a candidate is estimated, and from which layout), an early-stopping rule and a
//! choice rule (how the candidates the stop rule keeps are weighed); the combinations that mean
//! nothing (an oracle layout without a layout gain, the switch's thresholds on another model)
//! cannot be written. The built-in strategies are the rows of [`BUILT_IN`]: a name, what it
//! does in words and the function that makes its value from the user's settings. Their choice
//! is made by a [`Policy`] ([`BuiltInPolicy`]), as an external strategy's is.
//!
//! Adding a strategy: a row of [`BUILT_IN`] (and, for a new way of choosing, a variant of
//! [`Choice`] with its arm in [`BuiltInPolicy::decide`]), plus its test (ARCHITECTURE.md).

use super::policy::{CandidateView, DecisionView, Needs, Policy, Reply};
use crate::utility::{best_candidate, with_gain_floor, CandidateScore};

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

/// How a built-in strategy chooses among the candidates its early stop keeps. `L` below is the
/// planned path's length to the candidate's goal ([`CandidateView::path_m`]), `I` its gain as
/// the gain model estimates it; ties go to the candidate listed first.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Choice {
    /// The paper's utility `alpha * (1 - D/D_max) + (1 - alpha) * I/I_max`
    /// ([`crate::utility`]; `D` as the setting `utility_distance` defines it), each candidate's
    /// gain counted as at least `gain_floor_m2`.
    Utility { alpha: f64, gain_floor_m2: f64 },
    /// The nearest candidate by path: Yamauchi, "A frontier-based approach for autonomous
    /// exploration", CIRA 1997.
    Nearest,
    /// The largest `I * exp(-lambda_per_m * L)`: González-Baños and Latombe, "Navigation
    /// strategies for exploring indoor environments", IJRR 21(10-11), 2002.
    UtilityExp { lambda_per_m: f64 },
    /// The largest `I - beta_m2_per_m * L`: Burgard, Moors, Stachniss and Schneider,
    /// "Coordinated multi-robot exploration", IEEE T-RO 21(3), 2005, with one robot.
    CostUtility { beta_m2_per_m: f64 },
    /// The nearest candidate by path in the robot's room, while one is left there; then the
    /// nearest: Holz, Basilico, Amigoni and Behnke, "Evaluating the efficiency of
    /// frontier-based exploration strategies", ISR/ROBOTIK 2010. Rooms are those of the layout
    /// predicted from the map (never the building's true rooms); a candidate is in the room
    /// that holds its cell, the robot in the room whose polygon holds its estimated position.
    RoomFirst,
    /// The first candidate of a short open travelling-salesman path from the robot through every
    /// candidate ([`crate::tsp::open_path`], by the planned path lengths between their goals),
    /// instead of the greedy nearest: Kulich, Faigl and Přeučil, "On distance utility in the
    /// exploration task", ICRA 2011.
    FrontierTsp,
    /// A candidate drawn at random (uniformly, from the run's seed and the decision), driven
    /// to until it is reached or gone (a random walk over the frontiers, each goal kept as a
    /// frontier strategy keeps its goal): the floor every strategy must beat.
    Random,
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

/// A built-in strategy: its name, what it does in words (the README's table), and its value.
#[derive(Debug, Clone, Copy)]
pub struct BuiltIn {
    pub name: &'static str,
    /// How `I(p)` is estimated, in words.
    pub gain: &'static str,
    /// When it stops, in words.
    pub stops: &'static str,
    /// Where it comes from ([`PAPER`]: the paper floorcast first studies).
    pub citation: &'static str,
    pub make: fn(&StrategyParams) -> Strategy,
}

/// The paper whose strategies floorcast first studied.
pub const PAPER: &str = "Luperto, Fochetta and Amigoni, \"Exploration of indoor environments through predicting the layout of partially observed rooms\"";
/// floorcast's own variants of the paper's strategies.
const FLOORCAST: &str = "floorcast, after Luperto, Fochetta and Amigoni";

impl BuiltIn {
    /// How `I(p)` is estimated, with the citation unless it is the paper's or floorcast's.
    pub fn gain_cited(&self) -> String {
        if self.citation == PAPER || self.citation.starts_with("floorcast") {
            self.gain.to_string()
        } else {
            format!("{} ({})", self.gain, self.citation)
        }
    }
}

/// The utility of the settings.
fn utility(p: &StrategyParams) -> Choice {
    Choice::Utility {
        alpha: p.alpha,
        gain_floor_m2: p.gain_floor_m2,
    }
}

/// A strategy choosing by the utility of the settings.
fn by_utility(gain: GainModel, early_stop: EarlyStop, p: &StrategyParams) -> Strategy {
    Strategy {
        gain,
        early_stop,
        choice: utility(p),
    }
}

const PREDICTED: GainModel = GainModel::PredictedRooms(LayoutSource::Predicted);
const TRUTH: GainModel = GainModel::PredictedRooms(LayoutSource::Truth);
const GAPS: GainModel = GainModel::ClosedGaps(LayoutSource::Predicted);
const NO_FRONTIER: &str = "when no frontier is left";
const PAPER_ES: &str = "also when the summed `I(p)` of all candidates is below `es_threshold_m2` (1 m², the paper's ES)";

fn es(p: &StrategyParams) -> EarlyStop {
    EarlyStop::TotalGainBelow(p.es_threshold_m2)
}

/// The built-in strategies, in the order of the README's table: `baseline`; the paper's
/// `layout` and `layout-es`; `layout-aes` (aggressive ES) and `layout-switch` (dynamic switch)
/// from its discussion; floorcast's `layout-gaps` and `layout-gaps-es`; the oracle's
/// `layout-truth` and `layout-truth-es` (the most a perfect layout prediction could give the
/// paper's method).
pub const BUILT_IN: &[BuiltIn] = &[
    BuiltIn {
        name: "baseline",
        gain: "unknown cells within laser range visible from `p`, unknown counted as free (the paper's \"no L\")",
        stops: NO_FRONTIER,
        citation: PAPER,
        make: Strategy::baseline_with,
    },
    BuiltIn {
        name: "layout",
        gain: "the layout's room walls drawn into a copy of the map as obstacles; unknown cells in range, inside the predicted rooms and visible in that copy (\"with L\"); rooms with an open frontier use the baseline",
        stops: NO_FRONTIER,
        citation: PAPER,
        make: |p| by_utility(PREDICTED, EarlyStop::Never, p),
    },
    BuiltIn {
        name: "layout-es",
        gain: "as `layout`",
        stops: PAPER_ES,
        citation: PAPER,
        make: |p| by_utility(PREDICTED, es(p), p),
    },
    BuiltIn {
        name: "layout-aes",
        gain: "as `layout`",
        stops: "candidates with `I(p)` below `aes_min_gain_m2` (2 m²) are dropped; stops when none is left (the paper's \"more aggressive ES\")",
        citation: PAPER,
        make: |p| by_utility(PREDICTED, EarlyStop::DropCandidatesBelow(p.aes_min_gain_m2), p),
    },
    BuiltIn {
        name: "layout-switch",
        gain: "baseline until the layout's predictions prove right (90 % of 5 m² seen since), then `layout` (the paper's \"dynamic switch\")",
        stops: NO_FRONTIER,
        citation: PAPER,
        make: |p| {
            let switch = GainModel::Switch {
                agreement: 0.9,
                min_area_m2: 5.0,
            };
            by_utility(switch, EarlyStop::Never, p)
        },
    },
    BuiltIn {
        name: "layout-gaps",
        gain: "the baseline gain through the map with gaps of up to `max_wall_gap_m` (1 m) in observed walls closed by the layout's wall lines",
        stops: NO_FRONTIER,
        citation: FLOORCAST,
        make: |p| by_utility(GAPS, EarlyStop::Never, p),
    },
    BuiltIn {
        name: "layout-gaps-es",
        gain: "as `layout-gaps`; the stop judges the paper's `I(p)`",
        stops: "as `layout-es`",
        citation: FLOORCAST,
        make: |p| by_utility(GAPS, es(p), p),
    },
    BuiltIn {
        name: "layout-truth",
        gain: "as `layout`, with the building's true rooms for a layout (an oracle: needs a building with rooms)",
        stops: NO_FRONTIER,
        citation: FLOORCAST,
        make: |p| by_utility(TRUTH, EarlyStop::Never, p),
    },
    BuiltIn {
        name: "layout-truth-es",
        gain: "as `layout-truth`",
        stops: "as `layout-es`",
        citation: FLOORCAST,
        make: |p| by_utility(TRUTH, es(p), p),
    },
    BuiltIn {
        name: "nearest",
        gain: "not used: the nearest candidate by path",
        stops: NO_FRONTIER,
        citation: "Yamauchi, CIRA 1997",
        make: |_| plain(Choice::Nearest),
    },
    BuiltIn {
        name: "utility-exp",
        gain: "as `baseline`; the largest `I(p) * exp(-lambda * L(p))`, `L` the path length, lambda `utility_exp_lambda_per_m` (0.2 per m)",
        stops: NO_FRONTIER,
        citation: "González-Baños and Latombe, IJRR 2002",
        make: |p| {
            plain(Choice::UtilityExp {
                lambda_per_m: p.utility_exp_lambda_per_m,
            })
        },
    },
    BuiltIn {
        name: "cost-utility",
        gain: "as `baseline`; the largest `I(p) - beta * L(p)`, `L` the path length, beta `cost_utility_beta_m2_per_m` (1 m² per m)",
        stops: NO_FRONTIER,
        citation: "Burgard, Moors, Stachniss and Schneider, IEEE T-RO 2005, one robot",
        make: |p| {
            plain(Choice::CostUtility {
                beta_m2_per_m: p.cost_utility_beta_m2_per_m,
            })
        },
    },
    BuiltIn {
        name: "frontier-tsp",
        gain: "not used: the first goal of a short travelling-salesman path from the robot through every candidate, by planned path lengths (nearest neighbour, 2-opt, Or-opt)",
        stops: NO_FRONTIER,
        citation: "Kulich, Faigl and Přeučil, ICRA 2011",
        make: |_| plain(Choice::FrontierTsp),
    },
    BuiltIn {
        name: "room-first",
        gain: "not used: the nearest candidate by path in the robot's room while one is left there, then the nearest; rooms from the layout predicted from the map",
        stops: NO_FRONTIER,
        citation: "Holz, Basilico, Amigoni and Behnke, ISR/ROBOTIK 2010",
        make: |_| plain(Choice::RoomFirst),
    },
    BuiltIn {
        name: "random-frontier",
        gain: "not used: a reachable candidate drawn at random from the run's seed, kept until reached or gone (the floor every strategy must beat)",
        stops: NO_FRONTIER,
        citation: "floorcast",
        make: |_| plain(Choice::Random),
    },
];

/// A strategy of the baseline's gains choosing by `choice`, without an early stop.
fn plain(choice: Choice) -> Strategy {
    Strategy {
        gain: GainModel::Baseline,
        early_stop: EarlyStop::Never,
        choice,
    }
}

impl Strategy {
    /// The settings this strategy reads, by their names, with its values of them: those of
    /// its choice, its early stop and, when it uses the layout, how the layout is used
    /// (`layout_update_m2`, `layout_update_fraction`, `max_wall_gap_m` for closed gaps; their
    /// values are the run's, not the strategy's, so only their names are listed there).
    pub fn parameters(&self) -> Vec<(&'static str, Option<f64>)> {
        let mut out = Vec::new();
        match self.choice {
            Choice::Utility {
                alpha,
                gain_floor_m2,
            } => {
                out.push(("alpha", Some(alpha)));
                out.push(("gain_floor_m2", Some(gain_floor_m2)));
            }
            Choice::UtilityExp { lambda_per_m } => {
                out.push(("utility_exp_lambda_per_m", Some(lambda_per_m)));
            }
            Choice::CostUtility { beta_m2_per_m } => {
                out.push(("cost_utility_beta_m2_per_m", Some(beta_m2_per_m)));
            }
            Choice::Nearest | Choice::RoomFirst | Choice::FrontierTsp | Choice::Random => {}
        }
        match self.early_stop {
            EarlyStop::Never => {}
            EarlyStop::TotalGainBelow(t) => out.push(("es_threshold_m2", Some(t))),
            EarlyStop::DropCandidatesBelow(t) => out.push(("aes_min_gain_m2", Some(t))),
        }
        if self.gain.layout_source().is_some() || self.choice == Choice::RoomFirst {
            out.push(("layout_update_m2", None));
            out.push(("layout_update_fraction", None));
        }
        if matches!(self.gain, GainModel::ClosedGaps(_)) {
            out.push(("max_wall_gap_m", None));
        }
        out
    }

    /// The paper's baseline with the default settings.
    pub fn baseline() -> Self {
        Self::baseline_with(&StrategyParams::default())
    }

    /// The paper's baseline with the settings `params`.
    pub fn baseline_with(params: &StrategyParams) -> Self {
        by_utility(GainModel::Baseline, EarlyStop::Never, params)
    }

    /// The built-in strategy `name` ([`BUILT_IN`]) with the settings `params`.
    pub fn by_name(name: &str, params: &StrategyParams) -> Option<Self> {
        BUILT_IN
            .iter()
            .find(|b| b.name == name)
            .map(|b| (b.make)(params))
    }

    /// The names of the built-in strategies, in [`BUILT_IN`]'s order.
    pub fn names() -> Vec<&'static str> {
        BUILT_IN.iter().map(|b| b.name).collect()
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

/// The README's table of the built-in strategies (name, `I(p)`, stops), from [`BUILT_IN`].
pub fn strategies_markdown() -> String {
    let mut s = String::from("| name | information gain `I(p)` | stops |\n|---|---|---|\n");
    for b in BUILT_IN {
        s.push_str(&format!(
            "| `{}` | {} | {} |\n",
            b.name,
            b.gain_cited(),
            b.stops
        ));
    }
    s
}

/// Applies the early-stopping rule to the candidates' gains: returns which candidates stay and
/// whether exploration should stop now.
pub fn early_stop(rule: EarlyStop, gains_m2: &[f64]) -> (Vec<bool>, bool) {
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
    /// The run's seed (for [`Choice::Random`]).
    seed: u64,
    /// The candidates the rule kept at this decision's first attempt.
    kept: Vec<usize>,
    /// [`Choice::Random`]'s goal: the point of the candidate drawn last (map frame, m).
    drawn: Option<crate::geom::Vec2>,
}

/// [`Choice::Random`] keeps its goal while a candidate lies this close to the point drawn
/// (the frontier, moved a little as the map grows) and the robot is farther than this from it
/// (m).
const RANDOM_KEEP_M: f64 = 3.0;

impl BuiltInPolicy {
    /// The rule of `strategy` in a run of `seed`.
    pub fn new(strategy: &Strategy, seed: u64) -> Self {
        Self {
            early_stop: strategy.early_stop,
            choice: strategy.choice,
            seed,
            kept: Vec::new(),
            drawn: None,
        }
    }
}

impl Policy for BuiltInPolicy {
    fn needs(&self) -> Needs {
        Needs {
            layout_gain: self.early_stop != EarlyStop::Never,
            layout: self.choice == Choice::RoomFirst,
            paths_between: self.choice == Choice::FrontierTsp,
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
        let chosen = match self.choice {
            Choice::Utility {
                alpha,
                gain_floor_m2,
            } => by_utility_of(&shown, alpha, gain_floor_m2),
            Choice::Nearest => best_of(&shown, |c| -c.path_m),
            Choice::FrontierTsp => match view.between_m {
                Some(between) => first_of_tour(view.candidates, &self.kept, between),
                None => best_of(&shown, |c| -c.path_m),
            },
            Choice::RoomFirst => {
                let here = view
                    .layout
                    .and_then(|l| l.room_holding(view.pose.position()));
                let in_here = |c: &CandidateView| here.is_some() && c.room == here;
                if shown.iter().any(|c| in_here(c)) {
                    best_of(&shown, |c| if in_here(c) { -c.path_m } else { f64::NAN })
                } else {
                    best_of(&shown, |c| -c.path_m)
                }
            }
            Choice::UtilityExp { lambda_per_m } => {
                best_of(&shown, |c| c.gain_m2 * (-lambda_per_m * c.path_m).exp())
            }
            Choice::CostUtility { beta_m2_per_m } => {
                best_of(&shown, |c| c.gain_m2 - beta_m2_per_m * c.path_m)
            }
            Choice::Random => {
                // The goal drawn before while it stands (a refused goal, attempt > 0, does
                // not); else a new draw.
                let robot = view.pose.position();
                let standing = self.drawn.filter(|_| view.attempt == 0).and_then(|at| {
                    best_of(&shown, |c| {
                        let off = (c.point - at).norm();
                        if off <= RANDOM_KEEP_M && (c.goal - robot).norm() > RANDOM_KEEP_M {
                            -off
                        } else {
                            f64::NAN
                        }
                    })
                });
                let chosen = standing.or_else(|| {
                    let draw = random_draw(self.seed, view.decision, view.attempt);
                    (!shown.is_empty()).then(|| (draw % shown.len() as u64) as usize)
                });
                self.drawn = chosen.map(|i| shown[i].point);
                chosen
            }
        };
        let reply = match chosen {
            Some(i) => Reply::Choose(shown[i].id),
            None => Reply::Pass,
        };
        (reply, 0.0)
    }
}

/// The index in `shown` of the candidate of the largest finite `score` (the first of equals).
fn best_of(shown: &[&CandidateView], score: impl Fn(&CandidateView) -> f64) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, c) in shown.iter().enumerate() {
        let v = score(c);
        if v.is_finite() && best.is_none_or(|(_, b)| v > b) {
            best = Some((i, v));
        }
    }
    best.map(|(i, _)| i)
}

/// The index among the `kept` candidates (in the order of `all`) of the first goal of a short
/// open tour from the robot through them all; `between` holds the path lengths between all
/// of `all` (row-major).
fn first_of_tour(all: &[CandidateView], kept: &[usize], between: &[f64]) -> Option<usize> {
    let n = all.len();
    let idx: Vec<usize> = (0..n).filter(|&k| kept.contains(&all[k].id)).collect();
    let from: Vec<f64> = idx.iter().map(|&k| all[k].path_m).collect();
    let mut sub = Vec::with_capacity(idx.len() * idx.len());
    for &a in &idx {
        for &b in &idx {
            sub.push(between.get(a * n + b).copied().unwrap_or(f64::INFINITY));
        }
    }
    crate::tsp::open_path(&from, &sub, TOUR_PASSES)
        .first()
        .copied()
}

/// Rounds of improving moves of `frontier-tsp`'s tour at most.
const TOUR_PASSES: usize = 50;

/// A number drawn from the run's seed and the decision (SplitMix64 of their mix): the same at
/// the same decision of the same run, whatever was asked before.
fn random_draw(seed: u64, decision: usize, attempt: usize) -> u64 {
    let mut z = seed
        ^ (decision as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (attempt as u64).wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The index in `shown` of the candidate of best utility, if any is reachable.
fn by_utility_of(shown: &[&CandidateView], alpha: f64, gain_floor_m2: f64) -> Option<usize> {
    let scores: Vec<CandidateScore> = shown
        .iter()
        .map(|c| CandidateScore {
            distance_m: Some(c.distance_m),
            gain_m2: c.gain_m2,
        })
        .collect();
    best_candidate(&with_gain_floor(&scores, gain_floor_m2), alpha)
}

#[cfg(test)]
mod tests {
    use super::super::policy::RoomView;
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
        let choice = Choice::Utility {
            alpha: 0.3,
            gain_floor_m2: 0.5,
        };
        let never = EarlyStop::Never;
        let cases: &[(&str, GainModel, EarlyStop, Choice)] = &[
            ("baseline", GainModel::Baseline, never, choice),
            ("layout", PREDICTED, never, choice),
            (
                "layout-es",
                PREDICTED,
                EarlyStop::TotalGainBelow(1.5),
                choice,
            ),
            (
                "layout-aes",
                PREDICTED,
                EarlyStop::DropCandidatesBelow(2.5),
                choice,
            ),
            (
                "layout-switch",
                GainModel::Switch {
                    agreement: 0.9,
                    min_area_m2: 5.0,
                },
                never,
                choice,
            ),
            ("layout-gaps", GAPS, never, choice),
            (
                "layout-gaps-es",
                GAPS,
                EarlyStop::TotalGainBelow(1.5),
                choice,
            ),
            ("layout-truth", TRUTH, never, choice),
            (
                "layout-truth-es",
                TRUTH,
                EarlyStop::TotalGainBelow(1.5),
                choice,
            ),
            ("nearest", GainModel::Baseline, never, Choice::Nearest),
            (
                "utility-exp",
                GainModel::Baseline,
                never,
                Choice::UtilityExp { lambda_per_m: 0.7 },
            ),
            (
                "cost-utility",
                GainModel::Baseline,
                never,
                Choice::CostUtility { beta_m2_per_m: 3.0 },
            ),
            (
                "frontier-tsp",
                GainModel::Baseline,
                never,
                Choice::FrontierTsp,
            ),
            ("room-first", GainModel::Baseline, never, Choice::RoomFirst),
            (
                "random-frontier",
                GainModel::Baseline,
                never,
                Choice::Random,
            ),
        ];
        assert_eq!(
            Strategy::names(),
            cases.iter().map(|c| c.0).collect::<Vec<_>>()
        );
        for &(name, gain, stop, choice) in cases {
            let s = Strategy::by_name(name, &p).unwrap();
            assert_eq!(
                s,
                Strategy {
                    gain,
                    early_stop: stop,
                    choice
                },
                "{name}"
            );
            assert_eq!(s.uses_layout(), name.starts_with("layout"), "{name}");
            assert_eq!(s.layout_from_truth(), name.contains("truth"), "{name}");
        }
        assert!(Strategy::by_name("nope", &p).is_none());
        assert_eq!(
            Strategy::by_name("baseline", &StrategyParams::default()),
            Some(Strategy::baseline())
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
