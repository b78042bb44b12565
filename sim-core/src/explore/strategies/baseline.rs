//! `baseline`: the paper's "no L", choosing by the paper's utility.

use super::shared::{by_utility, BuiltIn, NO_FRONTIER, PAPER};
use crate::explore::strategy::{EarlyStop, GainModel, Strategy, StrategyParams};

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "baseline",
    gain: "unknown cells within laser range visible from `p`, unknown counted as free (the paper's \"no L\")",
    stops: NO_FRONTIER,
    citation: PAPER,
    settings: &["alpha", "gain_floor_m2"],
    make,
};

/// Its value with the settings `p` (also [`Strategy::baseline_with`]).
pub(crate) fn make(p: &StrategyParams) -> Strategy {
    by_utility(GainModel::Baseline, EarlyStop::Never, p)
}
