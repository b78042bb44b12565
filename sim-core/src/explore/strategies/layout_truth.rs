//! `layout-truth`: the oracle, `layout` with the building's true rooms.

use super::shared::{by_utility, BuiltIn, FLOORCAST, NO_FRONTIER, TRUTH};
use crate::explore::strategy::EarlyStop;

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "layout-truth",
    gain: "as `layout`, with the building's true rooms for a layout (an oracle: needs a building with rooms)",
    stops: NO_FRONTIER,
    citation: FLOORCAST,
    settings: &["alpha", "gain_floor_m2", "layout_update_m2", "layout_update_fraction"],
    make: |p| by_utility(TRUTH, EarlyStop::Never, p),
};
