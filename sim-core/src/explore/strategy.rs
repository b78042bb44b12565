//! Exploration strategies: how the information gain `I(p)` of a candidate is estimated and when
//! exploration may stop before the last frontier is visited; their choice among the candidates
//! is a [`Policy`] ([`BuiltInPolicy`]), as an external strategy's is.

use super::policy::{CandidateView, DecisionView, Needs, Policy, Reply};
use crate::utility::{best_candidate, with_gain_floor, CandidateScore};

/// How `I(p)` is estimated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GainModel {
    /// Unknown cells within laser range visible from `p`, unknown counted as free ("no L").
    Baseline,
    /// "With L": candidates are ranked by the baseline gain through the map with the layout's
    /// wall lines closing short gaps in observed walls; early stopping judges the paper's `I(p)`
    /// (the unknown area inside the predicted rooms visible in `M^L`; rooms with an open frontier
    /// fall back to the baseline). See `layout_gain` for why the ranking does not use the
    /// predicted room shapes.
    Layout,
    /// Baseline until the layout is judged reliable (its predictions agree with what later scans
    /// revealed), layout afterwards: the dynamic switch of the paper's conclusion.
    Switch,
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

/// A strategy: a gain model and an early-stopping rule, plus how often the layout is rebuilt.
#[derive(Debug, Clone, PartialEq)]
pub struct Strategy {
    pub gain: GainModel,
    pub early_stop: EarlyStop,
    /// The layout is recomputed at a decision when the known area changed by at least this much
    /// since the last layout (m2), so it follows the map without being rebuilt at every step.
    pub layout_update_m2: f64,
    /// For [`GainModel::Switch`]: the layout is trusted once this fraction of the cells it
    /// predicted inside rooms, and that were observed since, turned out free...
    pub switch_agreement: f64,
    /// ...measured over at least this many square metres.
    pub switch_min_area_m2: f64,
    /// Layout walls close gaps of unknown cells up to this long in an observed wall.
    pub max_wall_gap_m: f64,
    /// With a layout gain model: rank candidates by the paper's `I(p)` (unknown area inside the
    /// predicted rooms visible in `M^L`; open rooms use the baseline) rather than by the baseline
    /// gain through the map whose short wall gaps the layout closes (`layout-gaps`).
    pub rank_by_predicted_rooms: bool,
    /// The layout is the building's ground-truth rooms (brought into the map's frame by the
    /// current pose error) instead of a prediction from the map: an oracle, so that the paper's
    /// gain can be judged apart from the errors of the layout prediction (`layout-truth`). Needs
    /// a building with rooms.
    pub layout_from_truth: bool,
    /// The paper's `I(p)` sees through openings of the layout's wall lines (see
    /// [`crate::layout_gain::LayoutRaster::through_openings`]): an early stop then drops only
    /// what the layout predicts, never a room beyond a doorway the robot has seen. On by default
    /// since 0.4 (off: the paper's rule, setting `paper_layout_gain`).
    pub gain_through_openings: bool,
}

impl Strategy {
    pub fn baseline() -> Self {
        Self {
            gain: GainModel::Baseline,
            early_stop: EarlyStop::Never,
            layout_update_m2: 20.0,
            switch_agreement: 0.9,
            switch_min_area_m2: 5.0,
            max_wall_gap_m: 1.0,
            rank_by_predicted_rooms: false,
            layout_from_truth: false,
            gain_through_openings: true,
        }
    }

    /// The strategies by name: `baseline`; the paper's `layout` and `layout-es` (ES threshold
    /// 1 m2); `layout-aes` (aggressive ES, 2 m2 per candidate) and `layout-switch` (dynamic
    /// switch) from its discussion; `layout-gaps` and `layout-gaps-es`, which rank candidates by
    /// the baseline gain through the map with short wall gaps closed by the layout's walls;
    /// `layout-truth` and `layout-truth-es`, the paper's two with the true rooms for a layout
    /// (an oracle: the most a perfect layout prediction could give the paper's method).
    pub fn by_name(name: &str) -> Option<Self> {
        let b = Self::baseline();
        let paper = Self {
            gain: GainModel::Layout,
            rank_by_predicted_rooms: true,
            ..b.clone()
        };
        Some(match name {
            "baseline" => b,
            "layout" => paper,
            "layout-es" => Self {
                early_stop: EarlyStop::TotalGainBelow(1.0),
                ..paper
            },
            "layout-aes" => Self {
                early_stop: EarlyStop::DropCandidatesBelow(2.0),
                ..paper
            },
            "layout-switch" => Self {
                gain: GainModel::Switch,
                ..paper
            },
            "layout-gaps" => Self {
                gain: GainModel::Layout,
                ..b
            },
            "layout-gaps-es" => Self {
                gain: GainModel::Layout,
                early_stop: EarlyStop::TotalGainBelow(1.0),
                ..b
            },
            "layout-truth" => Self {
                layout_from_truth: true,
                ..paper
            },
            "layout-truth-es" => Self {
                early_stop: EarlyStop::TotalGainBelow(1.0),
                layout_from_truth: true,
                ..paper
            },
            _ => return None,
        })
    }

    /// Names accepted by [`Strategy::by_name`].
    pub const NAMES: &'static [&'static str] = &[
        "baseline",
        "layout",
        "layout-es",
        "layout-aes",
        "layout-switch",
        "layout-gaps",
        "layout-gaps-es",
        "layout-truth",
        "layout-truth-es",
    ];

    /// Whether this strategy needs the layout at all.
    pub fn uses_layout(&self) -> bool {
        self.gain != GainModel::Baseline
    }
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
/// [`CandidateView::layout_gain_m2`], else the ranking gain), then the paper's utility with the
/// gain floor over the candidates the rule keeps. The explorer computes the gains the
/// strategy's gain model defines ([`CandidateView::gain_m2`]).
#[derive(Debug, Clone, PartialEq)]
pub struct BuiltInPolicy {
    pub early_stop: EarlyStop,
    pub alpha: f64,
    pub gain_floor_m2: f64,
    /// The candidates the rule kept at this decision's first attempt.
    kept: Vec<usize>,
}

impl BuiltInPolicy {
    pub fn new(early_stop: EarlyStop, alpha: f64, gain_floor_m2: f64) -> Self {
        Self {
            early_stop,
            alpha,
            gain_floor_m2,
            kept: Vec::new(),
        }
    }
}

impl Policy for BuiltInPolicy {
    fn needs(&self) -> Needs {
        Needs {
            layout_gain: self.early_stop != EarlyStop::Never,
            layout: false,
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
        let scores: Vec<CandidateScore> = shown
            .iter()
            .map(|c| CandidateScore {
                distance_m: Some(c.distance_m),
                gain_m2: c.gain_m2,
            })
            .collect();
        let reply = match best_candidate(&with_gain_floor(&scores, self.gain_floor_m2), self.alpha)
        {
            Some(i) => Reply::Choose(shown[i].id),
            None => Reply::Pass,
        };
        (reply, 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_resolve() {
        for n in Strategy::NAMES {
            assert!(Strategy::by_name(n).is_some(), "{n}");
        }
        assert!(Strategy::by_name("nope").is_none());
        assert!(!Strategy::by_name("baseline").unwrap().uses_layout());
        assert!(Strategy::by_name("layout-es").unwrap().uses_layout());
        let truth = Strategy::by_name("layout-truth-es").unwrap();
        assert!(truth.layout_from_truth && truth.rank_by_predicted_rooms);
        assert_eq!(truth.early_stop, EarlyStop::TotalGainBelow(1.0));
        assert!(!Strategy::by_name("layout-es").unwrap().layout_from_truth);
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
