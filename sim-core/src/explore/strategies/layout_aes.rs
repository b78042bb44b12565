//! `layout-aes`: `layout` with the "more aggressive ES" of the paper's discussion.

use super::shared::{by_utility, BuiltIn, PAPER, PREDICTED};
use crate::explore::strategy::EarlyStop;

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "layout-aes",
    gain: "as `layout`",
    stops: "candidates with `I(p)` below `aes_min_gain_m2` (2 m²) are dropped; stops when none is left (the paper's \"more aggressive ES\")",
    citation: PAPER,
    settings: &["alpha", "gain_floor_m2", "aes_min_gain_m2", "layout_update_m2", "layout_update_fraction"],
    make: |p| by_utility(PREDICTED, EarlyStop::DropCandidatesBelow(p.aes_min_gain_m2), p),
};
