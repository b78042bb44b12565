//! `team-minpos`: MinPos (Bautin, Simonin and Charpillet, "MinPos: a novel frontier allocation
//! algorithm for multi-robot exploration", ICIRA 2012). For each candidate the robot counts the
//! exploring teammates nearer to it by path than itself (its rank for the candidate); it takes
//! a candidate where its rank is lowest, the nearest of those. A robot thus leaves to a teammate
//! the frontiers that teammate is closer to, and spreads away from the team. Alone, it is
//! `nearest`.

use super::shared::{plain, BuiltIn, NO_FRONTIER};
use crate::explore::strategy::{Choosing, Memory, Rule};

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "team-minpos",
    gain: "not used: where the fewest teammates are nearer by path than the robot, the nearest",
    stops: NO_FRONTIER,
    citation: "Bautin, Simonin and Charpillet, ICIRA 2012",
    settings: &[],
    make: |_| plain(TeamMinPos),
};

/// The candidate of the lowest rank, the nearest of those.
#[derive(Debug)]
struct TeamMinPos;

impl Rule for TeamMinPos {
    fn name(&self) -> &'static str {
        "team-minpos"
    }

    fn needs_mate_paths(&self) -> bool {
        true
    }

    fn choose(&self, at: &Choosing<'_, '_>, _: &mut Memory) -> Option<usize> {
        let view = at.view;
        let n = view.candidates.len();
        let mut best: Option<(usize, (usize, f64))> = None;
        for (i, c) in at.shown.iter().enumerate() {
            if !c.path_m.is_finite() {
                continue;
            }
            // (`c.id` indexes the view's candidates, which the mates' paths follow.)
            let k = view.candidates.iter().position(|v| v.id == c.id);
            let rank = match (view.team, k) {
                (Some(t), Some(k)) => t
                    .mates
                    .iter()
                    .enumerate()
                    .filter(|(m, mate)| {
                        mate.exploring && t.mate_path_m(*m, k, n).is_some_and(|d| d < c.path_m)
                    })
                    .count(),
                _ => 0,
            };
            let key = (rank, c.path_m);
            if best.is_none_or(|(_, b)| key < b) {
                best = Some((i, key));
            }
        }
        best.map(|(i, _)| i)
    }
}
