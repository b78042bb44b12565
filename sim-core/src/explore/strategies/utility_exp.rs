//! `utility-exp`: the largest `I * exp(-lambda_per_m * L)` (González-Baños and Latombe,
//! "Navigation strategies for exploring indoor environments", IJRR 21(10-11), 2002).

use super::shared::{best_of, plain, BuiltIn, NO_FRONTIER};
use crate::explore::strategy::{Choosing, Memory, Rule};

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "utility-exp",
    gain: "as `baseline`; the largest `I(p) * exp(-lambda * L(p))`, `L` the path length, lambda `utility_exp_lambda_per_m` (0.2 per m)",
    stops: NO_FRONTIER,
    citation: "González-Baños and Latombe, IJRR 2002",
    settings: &["utility_exp_lambda_per_m"],
    make: |p| {
        plain(UtilityExp {
            lambda_per_m: p.utility_exp_lambda_per_m,
        })
    },
};

/// The largest `I * exp(-lambda_per_m * L)`, `L` the path's length.
#[derive(Debug)]
struct UtilityExp {
    lambda_per_m: f64,
}

impl Rule for UtilityExp {
    fn name(&self) -> &'static str {
        "utility-exp"
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("utility_exp_lambda_per_m", self.lambda_per_m)]
    }

    fn choose(&self, at: &Choosing<'_, '_>, _: &mut Memory) -> Option<usize> {
        best_of(at.shown, |c| {
            c.gain_m2 * (-self.lambda_per_m * c.path_m).exp()
        })
    }
}
