//! `team-burgard`: coordinated multi-robot exploration (Burgard, Moors, Stachniss and
//! Schneider, IEEE T-RO 2005). A candidate's utility is discounted by the probability that a
//! teammate's target already covers it: `U(c) = I(c) · Π (1 - P(|c - g|))` over the exploring
//! teammates' goals `g`, with `P(d) = max(0, 1 - d / R)` falling linearly to 0 at the sensor
//! range `R` ([`DISCOUNT_RANGE_M`], the default laser's); the robot takes the best of the paper's
//! utility with `U` as the gain (the trade-off between utility and path cost of the paper's
//! equation, its `β`, is the utility's `alpha`). Unlike `team-greedy`, a candidate near a
//! teammate's target is not excluded but worth less, the more the nearer. Alone, it is
//! `baseline`'s choice.

use super::shared::{plain, utility_of, BuiltIn, NO_FRONTIER};
use crate::explore::strategy::{Choosing, Memory, Rule, StrategyParams};

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "team-burgard",
    gain: "as `baseline`, discounted around teammates' targets (linearly to 6 m); the best paper utility",
    stops: NO_FRONTIER,
    citation: "Burgard, Moors, Stachniss and Schneider, IEEE T-RO 2005",
    settings: &["alpha", "gain_floor_m2"],
    make: |p: &StrategyParams| {
        plain(TeamBurgard {
            alpha: p.alpha,
            gain_floor_m2: p.gain_floor_m2,
        })
    },
};

/// The range over which a teammate's target discounts a candidate (m): the default laser's.
pub(super) const DISCOUNT_RANGE_M: f64 = 6.0;

/// The best candidate by the paper's utility of the discounted gain.
#[derive(Debug)]
struct TeamBurgard {
    alpha: f64,
    gain_floor_m2: f64,
}

impl Rule for TeamBurgard {
    fn name(&self) -> &'static str {
        "team-burgard"
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("alpha", self.alpha), ("gain_floor_m2", self.gain_floor_m2)]
    }

    fn choose(&self, at: &Choosing<'_, '_>, _: &mut Memory) -> Option<usize> {
        let goals: Vec<crate::geom::Vec2> = at
            .view
            .team
            .map(|t| {
                t.mates
                    .iter()
                    .filter(|m| m.exploring)
                    .filter_map(|m| m.goal)
                    .collect()
            })
            .unwrap_or_default();
        let u = utility_of(at.shown, self.alpha, self.gain_floor_m2, |c, gain| {
            goals.iter().fold(gain, |g, &goal| {
                let p = (1.0 - (c.point - goal).norm() / DISCOUNT_RANGE_M).max(0.0);
                g * (1.0 - p)
            })
        });
        let mut best: Option<(usize, f64)> = None;
        for (i, v) in u.iter().enumerate() {
            if let Some(v) = *v {
                if best.is_none_or(|(_, b)| v > b) {
                    best = Some((i, v));
                }
            }
        }
        best.map(|(i, _)| i)
    }
}
