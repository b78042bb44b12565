//! The built-in strategies, one file each: its registry entry ([`BuiltIn`]: its name, what it
//! does in words, where it comes from, the settings it reads and the function that makes its
//! value from the user's settings) and, when its way of choosing is its own, its rule (a
//! `Rule` of `strategy.rs`). What they share (the entry's type, the paper's utility, the choice
//! of the best score) is in `shared.rs`; the early stops are `strategy.rs`'s.
//!
//! Adding a strategy: a file here holding its `STRATEGY` (and its rule, if new), and one line
//! in [`BUILT_IN`] (ARCHITECTURE.md, "Where to add").

pub(crate) mod baseline;
mod cost_utility;
mod frontier_tsp;
mod layout;
mod layout_aes;
mod layout_es;
mod layout_gaps;
mod layout_gaps_es;
mod layout_switch;
mod layout_truth;
mod layout_truth_es;
mod nearest;
mod random_frontier;
mod room_first;
pub(crate) mod shared;
mod team_burgard;
mod team_greedy;
mod team_hungarian;
mod team_minpos;
mod team_nearest;
mod utility_exp;

use crate::explore::strategy::{Strategy, StrategyParams};
pub use shared::BuiltIn;

/// The built-in strategies, in the order of the README's table: `baseline`; the paper's
/// `layout` and `layout-es`; `layout-aes` (aggressive ES) and `layout-switch` (dynamic switch)
/// from its discussion; floorcast's `layout-gaps` and `layout-gaps-es`; the oracle's
/// `layout-truth` and `layout-truth-es` (the most a perfect layout prediction could give the
/// paper's method); then the literature's and the random floor.
pub const BUILT_IN: &[BuiltIn] = &[
    baseline::STRATEGY,
    layout::STRATEGY,
    layout_es::STRATEGY,
    layout_aes::STRATEGY,
    layout_switch::STRATEGY,
    layout_gaps::STRATEGY,
    layout_gaps_es::STRATEGY,
    layout_truth::STRATEGY,
    layout_truth_es::STRATEGY,
    nearest::STRATEGY,
    utility_exp::STRATEGY,
    cost_utility::STRATEGY,
    frontier_tsp::STRATEGY,
    room_first::STRATEGY,
    random_frontier::STRATEGY,
    team_nearest::STRATEGY,
    team_greedy::STRATEGY,
    team_burgard::STRATEGY,
    team_hungarian::STRATEGY,
    team_minpos::STRATEGY,
];

/// The paper's baseline (the candidates and gains an external strategy chooses among).
pub const BASELINE: &BuiltIn = &baseline::STRATEGY;

impl BuiltIn {
    /// The built-in strategy named `name`.
    pub fn find(name: &str) -> Option<&'static BuiltIn> {
        BUILT_IN.iter().find(|b| b.name == name)
    }
}

impl Strategy {
    /// The paper's baseline with the default settings.
    pub fn baseline() -> Self {
        Self::baseline_with(&StrategyParams::default())
    }

    /// The paper's baseline with the settings `params`.
    pub fn baseline_with(params: &StrategyParams) -> Self {
        baseline::make(params)
    }

    /// The built-in strategy `name` ([`BUILT_IN`]) with the settings `params`.
    pub fn by_name(name: &str, params: &StrategyParams) -> Option<Self> {
        BuiltIn::find(name).map(|b| (b.make)(params))
    }

    /// The names of the built-in strategies, in [`BUILT_IN`]'s order.
    pub fn names() -> Vec<&'static str> {
        BUILT_IN.iter().map(|b| b.name).collect()
    }
}

/// The README's table of the built-in strategies (name, `I(p)`, stops), from [`BUILT_IN`].
pub fn strategies_markdown() -> String {
    let mut s = String::from("| name | information gain `I(p)` | stops |\n|---|---|---|\n");
    for b in BUILT_IN {
        s.push_str(&format!(
            "| `{}` | {} | {} |\n",
            b.name,
            b.gain_cited(),
            b.stops
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each entry lists the settings its value reads, in the order of its parameters.
    #[test]
    fn each_strategy_lists_the_settings_it_reads() {
        for p in [
            StrategyParams::default(),
            StrategyParams {
                alpha: 0.3,
                ..StrategyParams::default()
            },
        ] {
            for b in BUILT_IN {
                let read: Vec<&str> = (b.make)(&p)
                    .parameters()
                    .into_iter()
                    .map(|(n, _)| n)
                    .collect();
                assert_eq!(b.settings, read.as_slice(), "{}", b.name);
            }
        }
    }

    /// Names are registered once and found.
    #[test]
    fn each_name_is_registered_once() {
        for (i, b) in BUILT_IN.iter().enumerate() {
            assert_eq!(BuiltIn::find(b.name), Some(b));
            assert!(BUILT_IN[..i].iter().all(|a| a.name != b.name), "{}", b.name);
        }
        assert_eq!(BuiltIn::find("nope"), None);
    }
}
