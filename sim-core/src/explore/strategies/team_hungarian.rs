//! `team-hungarian`: an optimal assignment of the exploring robots to the candidates (the
//! Hungarian method, Kuhn 1955; in multi-robot exploration e.g. Stachniss's thesis, 2006, and
//! Faigl et al. 2012). The cost of robot `r` going to candidate `c` is its path cost minus the
//! candidate's gain, each normalised as in the paper's utility: `alpha · D(r, c) / D_max - (1 -
//! alpha) · I(c) / I_max` (unreachable: never chosen while another is possible); the deciding
//! robot takes the candidate the assignment of least total cost gives it. With more robots than
//! candidates a robot may be left without one: it then takes its own best. Alone, it is
//! `baseline`'s choice.

use super::shared::{plain, BuiltIn, NO_FRONTIER};
use crate::explore::strategy::{Choosing, Memory, Rule, StrategyParams};

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "team-hungarian",
    gain: "as `baseline`; the robots assigned to candidates by least total path cost minus gain",
    stops: NO_FRONTIER,
    citation: "Kuhn 1955; Stachniss 2006",
    settings: &["alpha", "gain_floor_m2"],
    make: |p: &StrategyParams| {
        plain(TeamHungarian {
            alpha: p.alpha,
            gain_floor_m2: p.gain_floor_m2,
        })
    },
};

/// The deciding robot's candidate in the least-cost assignment.
#[derive(Debug)]
struct TeamHungarian {
    alpha: f64,
    gain_floor_m2: f64,
}

/// The cost given to a robot-candidate pair without a path (normalised costs are within
/// [-1, 1]).
const UNREACHABLE_COST: f64 = 10.0;

/// Costs are rounded to integers in these units for the assignment (exact integer sums).
const COST_SCALE: f64 = 1e6;

impl Rule for TeamHungarian {
    fn name(&self) -> &'static str {
        "team-hungarian"
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("alpha", self.alpha), ("gain_floor_m2", self.gain_floor_m2)]
    }

    fn needs_mate_paths(&self) -> bool {
        true
    }

    fn choose(&self, at: &Choosing<'_, '_>, _: &mut Memory) -> Option<usize> {
        let view = at.view;
        let n = view.candidates.len();
        let shown = at.shown;
        if shown.is_empty() {
            return None;
        }
        // Rows: the deciding robot, then the exploring mates; columns: the candidates shown.
        let mut rows: Vec<Vec<f64>> = vec![shown.iter().map(|c| c.distance_m).collect()];
        if let Some(t) = view.team.filter(|t| t.mate_paths_m.is_some()) {
            for (m, mate) in t.mates.iter().enumerate() {
                if !mate.exploring {
                    continue;
                }
                rows.push(
                    shown
                        .iter()
                        .map(|c| {
                            let k = view.candidates.iter().position(|v| v.id == c.id);
                            k.and_then(|k| t.mate_path_m(m, k, n))
                                .unwrap_or(f64::INFINITY)
                        })
                        .collect(),
                );
            }
        }
        let gain = |c: &crate::explore::policy::CandidateView| c.gain_m2.max(self.gain_floor_m2);
        let d_max = rows
            .iter()
            .flatten()
            .copied()
            .filter(|d| d.is_finite())
            .fold(0.0f64, f64::max);
        let i_max = shown.iter().map(|c| gain(c)).fold(0.0f64, f64::max);
        let cost = |d: f64, c: &crate::explore::policy::CandidateView| {
            if !d.is_finite() {
                return UNREACHABLE_COST;
            }
            let dn = if d_max > 0.0 { d / d_max } else { 0.0 };
            let gn = if i_max > 0.0 { gain(c) / i_max } else { 0.0 };
            self.alpha * dn - (1.0 - self.alpha) * gn
        };
        let own_best = || {
            let mut best: Option<(usize, f64)> = None;
            for (i, c) in shown.iter().enumerate() {
                let v = cost(c.distance_m, c);
                if c.distance_m.is_finite() && best.is_none_or(|(_, b)| v < b) {
                    best = Some((i, v));
                }
            }
            best.map(|(i, _)| i)
        };
        if rows.len() == 1 {
            return own_best();
        }
        // At least as many columns as rows: with more robots than candidates, columns meaning
        // "none" at the cost of an unreachable candidate (a robot left with one takes its own
        // best); with more candidates than robots, some are left unassigned.
        let cols = shown.len().max(rows.len());
        let weights: Vec<i64> = rows
            .iter()
            .flat_map(|row| {
                (0..cols).map(move |j| match row.get(j) {
                    Some(&d) => (cost(d, shown[j]) * COST_SCALE).round() as i64,
                    None => (UNREACHABLE_COST * COST_SCALE) as i64,
                })
            })
            .collect();
        let matrix = pathfinding::matrix::Matrix::from_vec(rows.len(), cols, weights)
            .expect("rows times columns weights");
        let (_, assignment) = pathfinding::kuhn_munkres::kuhn_munkres_min(&matrix);
        match assignment[0] {
            j if j < shown.len() && shown[j].distance_m.is_finite() => Some(j),
            _ => own_best(),
        }
    }
}
