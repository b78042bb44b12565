//! `frontier-tsp`: the first candidate of a short open travelling-salesman path from the robot
//! through every candidate ([`crate::tsp::open_path`], by the planned path lengths between
//! their goals), instead of the greedy nearest (Kulich, Faigl and Přeučil, "On distance utility
//! in the exploration task", ICRA 2011).

use super::shared::{nearest_of, plain, BuiltIn, NO_FRONTIER};
use crate::explore::policy::CandidateView;
use crate::explore::strategy::{Choosing, Memory, Rule};

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "frontier-tsp",
    gain: "not used: the first goal of a short travelling-salesman path from the robot through every candidate, by planned path lengths (nearest neighbour, 2-opt, Or-opt)",
    stops: NO_FRONTIER,
    citation: "Kulich, Faigl and Přeučil, ICRA 2011",
    settings: &[],
    make: |_| plain(FrontierTsp),
};

/// The first goal of the tour; the nearest when the lengths between candidates are missing.
#[derive(Debug)]
struct FrontierTsp;

impl Rule for FrontierTsp {
    fn name(&self) -> &'static str {
        "frontier-tsp"
    }

    fn needs_paths_between(&self) -> bool {
        true
    }

    fn choose(&self, at: &Choosing<'_, '_>, _: &mut Memory) -> Option<usize> {
        match at.view.between_m {
            Some(between) => first_of_tour(at.view.candidates, at.kept, between),
            None => nearest_of(at.shown),
        }
    }
}

/// The index among the `kept` candidates (in the order of `all`) of the first goal of a short
/// open tour from the robot through them all; `between` holds the path lengths between all
/// of `all` (row-major).
fn first_of_tour(all: &[CandidateView], kept: &[usize], between: &[f64]) -> Option<usize> {
    let n = all.len();
    let idx: Vec<usize> = (0..n).filter(|&k| kept.contains(&all[k].id)).collect();
    let from: Vec<f64> = idx.iter().map(|&k| all[k].path_m).collect();
    let mut sub = Vec::with_capacity(idx.len() * idx.len());
    for &a in &idx {
        for &b in &idx {
            sub.push(between.get(a * n + b).copied().unwrap_or(f64::INFINITY));
        }
    }
    crate::tsp::open_path(&from, &sub, TOUR_PASSES)
        .first()
        .copied()
}

/// Rounds of improving moves of the tour at most.
const TOUR_PASSES: usize = 50;
