//! `layout-es`: `layout` with the paper's early stop (ES).

use super::shared::{by_utility, es, BuiltIn, PAPER, PAPER_ES, PREDICTED};

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "layout-es",
    gain: "as `layout`",
    stops: PAPER_ES,
    citation: PAPER,
    settings: &[
        "alpha",
        "gain_floor_m2",
        "es_threshold_m2",
        "layout_update_m2",
        "layout_update_fraction",
    ],
    make: |p| by_utility(PREDICTED, es(p), p),
};
