//! `team-greedy`: robots in turn take the best remaining candidate. Each robot, when it
//! decides, takes the candidate of the best paper utility among those no exploring teammate
//! is heading for (a teammate's goal within [`TAKEN_RADIUS_M`] of the candidate); when every
//! candidate is taken, the best of all. Decisions come one robot at a time, so the turns are
//! the order in which robots decide. Alone, it is `baseline`'s choice.

use super::shared::{plain, utility_of, BuiltIn, NO_FRONTIER};
use crate::explore::policy::CandidateView;
use crate::explore::strategy::{Choosing, Memory, Rule, StrategyParams};

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "team-greedy",
    gain: "as `baseline`; the best paper utility among the candidates no teammate heads for (all, when every one is)",
    stops: NO_FRONTIER,
    citation: "floorcast, the greedy assignment of multi-robot exploration",
    settings: &["alpha", "gain_floor_m2"],
    make: |p: &StrategyParams| {
        plain(TeamGreedy {
            alpha: p.alpha,
            gain_floor_m2: p.gain_floor_m2,
        })
    },
};

/// A candidate is taken by a teammate whose goal lies this close to its point (m).
pub(super) const TAKEN_RADIUS_M: f64 = 1.0;

/// The best candidate not taken by a teammate.
#[derive(Debug)]
struct TeamGreedy {
    alpha: f64,
    gain_floor_m2: f64,
}

/// Whether an exploring teammate of the view heads for `c`.
pub(super) fn taken(at: &Choosing<'_, '_>, c: &CandidateView) -> bool {
    at.view.team.is_some_and(|t| {
        t.mates.iter().any(|m| {
            m.exploring
                && m.goal
                    .is_some_and(|g| (g - c.point).norm() <= TAKEN_RADIUS_M)
        })
    })
}

impl Rule for TeamGreedy {
    fn name(&self) -> &'static str {
        "team-greedy"
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("alpha", self.alpha), ("gain_floor_m2", self.gain_floor_m2)]
    }

    fn choose(&self, at: &Choosing<'_, '_>, _: &mut Memory) -> Option<usize> {
        let free: Vec<bool> = at.shown.iter().map(|c| !taken(at, c)).collect();
        let u = utility_of(at.shown, self.alpha, self.gain_floor_m2, |_, g| g);
        let best = |only_free: bool| {
            let mut best: Option<(usize, f64)> = None;
            for (i, v) in u.iter().enumerate() {
                if let Some(v) = *v {
                    if (!only_free || free[i]) && best.is_none_or(|(_, b)| v > b) {
                        best = Some((i, v));
                    }
                }
            }
            best.map(|(i, _)| i)
        };
        best(true).or_else(|| best(false))
    }
}
