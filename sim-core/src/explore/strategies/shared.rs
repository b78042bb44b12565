//! What the built-in strategies share: their registry entry ([`BuiltIn`]), the paper's utility
//! (the choice of most of them), the choice of the best score, and the words and citations of
//! their table.

use crate::explore::policy::CandidateView;
use crate::explore::strategy::{
    Choice, Choosing, EarlyStop, GainModel, LayoutSource, Memory, Rule, Strategy, StrategyParams,
};
use crate::utility::{best_candidate, with_gain_floor, CandidateScore};

/// A built-in strategy's registry entry: its name, what it does in words (the README's table),
/// where it comes from, the settings it reads, and its value.
#[derive(Debug, Clone, Copy)]
pub struct BuiltIn {
    pub name: &'static str,
    /// How `I(p)` is estimated, in words.
    pub gain: &'static str,
    /// When it stops, in words.
    pub stops: &'static str,
    /// Where it comes from ([`PAPER`]: the paper floorcast first studies).
    pub citation: &'static str,
    /// The settings it reads, by their names (their defaults and ranges are the settings'
    /// declarations'): those its value lists in [`Strategy::parameters`], in that order.
    pub settings: &'static [&'static str],
    pub make: fn(&StrategyParams) -> Strategy,
}

/// Two entries are the same strategy when their names are (a name is registered once).
impl PartialEq for BuiltIn {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}

impl Eq for BuiltIn {}

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

/// The paper whose strategies floorcast first studied.
pub(super) const PAPER: &str = "Luperto, Fochetta and Amigoni, \"Exploration of indoor environments through predicting the layout of partially observed rooms\"";
/// floorcast's own variants of the paper's strategies.
pub(super) const FLOORCAST: &str = "floorcast, after Luperto, Fochetta and Amigoni";

pub(super) const PREDICTED: GainModel = GainModel::PredictedRooms(LayoutSource::Predicted);
pub(super) const TRUTH: GainModel = GainModel::PredictedRooms(LayoutSource::Truth);
pub(super) const GAPS: GainModel = GainModel::ClosedGaps(LayoutSource::Predicted);
pub(super) const NO_FRONTIER: &str = "when no frontier is left";
pub(super) const PAPER_ES: &str = "also when the summed `I(p)` of all candidates is below `es_threshold_m2` (1 m², the paper's ES)";

/// The paper's ES of the settings.
pub(super) fn es(p: &StrategyParams) -> EarlyStop {
    EarlyStop::TotalGainBelow(p.es_threshold_m2)
}

/// A strategy choosing by the utility of the settings.
pub(super) fn by_utility(gain: GainModel, early_stop: EarlyStop, p: &StrategyParams) -> Strategy {
    Strategy {
        gain,
        early_stop,
        choice: Choice::new(Utility {
            alpha: p.alpha,
            gain_floor_m2: p.gain_floor_m2,
        }),
    }
}

/// A strategy of the baseline's gains choosing by `rule`, without an early stop.
pub(super) fn plain(rule: impl Rule + 'static) -> Strategy {
    Strategy {
        gain: GainModel::Baseline,
        early_stop: EarlyStop::Never,
        choice: Choice::new(rule),
    }
}

/// The paper's utility `alpha * (1 - D/D_max) + (1 - alpha) * I/I_max` ([`crate::utility`];
/// `D` as the setting `utility_distance` defines it), each candidate's gain counted as at least
/// `gain_floor_m2`.
#[derive(Debug)]
struct Utility {
    alpha: f64,
    gain_floor_m2: f64,
}

impl Rule for Utility {
    fn name(&self) -> &'static str {
        "utility"
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("alpha", self.alpha), ("gain_floor_m2", self.gain_floor_m2)]
    }

    fn choose(&self, at: &Choosing<'_, '_>, _: &mut Memory) -> Option<usize> {
        let scores: Vec<CandidateScore> = at
            .shown
            .iter()
            .map(|c| CandidateScore {
                distance_m: Some(c.distance_m),
                gain_m2: c.gain_m2,
            })
            .collect();
        best_candidate(&with_gain_floor(&scores, self.gain_floor_m2), self.alpha)
    }
}

/// The paper's utility of each of `shown` (`None`: no path), its gain (at least
/// `gain_floor_m2`) first made `gain(candidate, gain)` (a team strategy's discount).
pub(super) fn utility_of(
    shown: &[&CandidateView],
    alpha: f64,
    gain_floor_m2: f64,
    gain: impl Fn(&CandidateView, f64) -> f64,
) -> Vec<Option<f64>> {
    let scores: Vec<CandidateScore> = with_gain_floor(
        &shown
            .iter()
            .map(|c| CandidateScore {
                distance_m: Some(c.distance_m),
                gain_m2: c.gain_m2,
            })
            .collect::<Vec<_>>(),
        gain_floor_m2,
    )
    .into_iter()
    .zip(shown)
    .map(|(s, c)| CandidateScore {
        gain_m2: gain(c, s.gain_m2),
        ..s
    })
    .collect();
    crate::utility::utilities(&scores, alpha)
}

/// The index in `shown` of the candidate of the largest finite `score` (the first of equals).
pub(super) fn best_of(
    shown: &[&CandidateView],
    score: impl Fn(&CandidateView) -> f64,
) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, c) in shown.iter().enumerate() {
        let v = score(c);
        if v.is_finite() && best.is_none_or(|(_, b)| v > b) {
            best = Some((i, v));
        }
    }
    best.map(|(i, _)| i)
}

/// The index in `shown` of the nearest candidate by path.
pub(super) fn nearest_of(shown: &[&CandidateView]) -> Option<usize> {
    best_of(shown, |c| -c.path_m)
}
