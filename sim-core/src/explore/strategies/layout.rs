//! `layout`: the paper's "with L", the gain inside the predicted rooms.

use super::shared::{by_utility, BuiltIn, NO_FRONTIER, PAPER, PREDICTED};
use crate::explore::strategy::EarlyStop;

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "layout",
    gain: "the layout's room walls drawn into a copy of the map as obstacles; unknown cells in range, inside the predicted rooms and visible in that copy (\"with L\"); rooms with an open frontier use the baseline",
    stops: NO_FRONTIER,
    citation: PAPER,
    settings: &["alpha", "gain_floor_m2", "layout_update_m2", "layout_update_fraction"],
    make: |p| by_utility(PREDICTED, EarlyStop::Never, p),
};
