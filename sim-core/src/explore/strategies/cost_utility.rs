//! `cost-utility`: the largest `I - beta_m2_per_m * L` (Burgard, Moors, Stachniss and
//! Schneider, "Coordinated multi-robot exploration", IEEE T-RO 21(3), 2005, with one robot).

use super::shared::{best_of, plain, BuiltIn, NO_FRONTIER};
use crate::explore::strategy::{Choosing, Memory, Rule};

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "cost-utility",
    gain: "as `baseline`; the largest `I(p) - beta * L(p)`, `L` the path length, beta `cost_utility_beta_m2_per_m` (1 m² per m)",
    stops: NO_FRONTIER,
    citation: "Burgard, Moors, Stachniss and Schneider, IEEE T-RO 2005, one robot",
    settings: &["cost_utility_beta_m2_per_m"],
    make: |p| {
        plain(CostUtility {
            beta_m2_per_m: p.cost_utility_beta_m2_per_m,
        })
    },
};

/// The largest `I - beta_m2_per_m * L`, `L` the path's length.
#[derive(Debug)]
struct CostUtility {
    beta_m2_per_m: f64,
}

impl Rule for CostUtility {
    fn name(&self) -> &'static str {
        "cost-utility"
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("cost_utility_beta_m2_per_m", self.beta_m2_per_m)]
    }

    fn choose(&self, at: &Choosing<'_, '_>, _: &mut Memory) -> Option<usize> {
        best_of(at.shown, |c| c.gain_m2 - self.beta_m2_per_m * c.path_m)
    }
}
