//! `layout-switch`: the "dynamic switch" of the paper's conclusion, the baseline's gain until
//! the predicted layout proves right, then `layout`'s.

use super::shared::{by_utility, BuiltIn, NO_FRONTIER, PAPER};
use crate::explore::strategy::{EarlyStop, GainModel};

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "layout-switch",
    gain: "baseline until the layout's predictions prove right (90 % of 5 m² seen since), then `layout` (the paper's \"dynamic switch\")",
    stops: NO_FRONTIER,
    citation: PAPER,
    settings: &[
        "alpha",
        "gain_floor_m2",
        "layout_update_m2",
        "layout_update_fraction",
    ],
    make: |p| {
        let switch = GainModel::Switch {
            agreement: 0.9,
            min_area_m2: 5.0,
        };
        by_utility(switch, EarlyStop::Never, p)
    },
};
