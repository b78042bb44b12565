//! `layout-gaps`: floorcast's baseline gain with the layout's wall lines closing gaps in observed walls.

use super::shared::{by_utility, BuiltIn, FLOORCAST, GAPS, NO_FRONTIER};
use crate::explore::strategy::EarlyStop;

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "layout-gaps",
    gain: "the baseline gain through the map with gaps of up to `max_wall_gap_m` (1 m) in observed walls closed by the layout's wall lines",
    stops: NO_FRONTIER,
    citation: FLOORCAST,
    settings: &["alpha", "gain_floor_m2", "layout_update_m2", "layout_update_fraction", "max_wall_gap_m"],
    make: |p| by_utility(GAPS, EarlyStop::Never, p),
};
