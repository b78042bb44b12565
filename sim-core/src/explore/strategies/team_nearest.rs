//! `team-nearest`: every robot of a team its own nearest candidate by path, no coordination
//! (Yamauchi, "Frontier-based exploration using multiple robots", Agents 1998): the team
//! baseline the coordinated strategies are measured against. Alone, it is `nearest`.

use super::shared::{nearest_of, plain, BuiltIn, NO_FRONTIER};
use crate::explore::strategy::{Choosing, Memory, Rule};

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "team-nearest",
    gain: "not used: each robot its own nearest candidate by path, teammates ignored",
    stops: NO_FRONTIER,
    citation: "Yamauchi, Agents 1998",
    settings: &[],
    make: |_| plain(TeamNearest),
};

/// The nearest candidate by path, teammates ignored.
#[derive(Debug)]
struct TeamNearest;

impl Rule for TeamNearest {
    fn name(&self) -> &'static str {
        "team-nearest"
    }

    fn choose(&self, at: &Choosing<'_, '_>, _: &mut Memory) -> Option<usize> {
        nearest_of(at.shown)
    }
}
