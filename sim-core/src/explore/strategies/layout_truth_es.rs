//! `layout-truth-es`: the oracle with the paper's early stop.

use super::shared::{by_utility, es, BuiltIn, FLOORCAST, TRUTH};

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "layout-truth-es",
    gain: "as `layout-truth`",
    stops: "as `layout-es`",
    citation: FLOORCAST,
    settings: &[
        "alpha",
        "gain_floor_m2",
        "es_threshold_m2",
        "layout_update_m2",
        "layout_update_fraction",
    ],
    make: |p| by_utility(TRUTH, es(p), p),
};
