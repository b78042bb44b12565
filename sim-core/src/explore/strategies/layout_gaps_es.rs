//! `layout-gaps-es`: `layout-gaps` with the paper's early stop.

use super::shared::{by_utility, es, BuiltIn, FLOORCAST, GAPS};

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "layout-gaps-es",
    gain: "as `layout-gaps`; the stop judges the paper's `I(p)`",
    stops: "as `layout-es`",
    citation: FLOORCAST,
    settings: &[
        "alpha",
        "gain_floor_m2",
        "es_threshold_m2",
        "layout_update_m2",
        "layout_update_fraction",
        "max_wall_gap_m",
    ],
    make: |p| by_utility(GAPS, es(p), p),
};
