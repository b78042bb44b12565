//! `nearest`: the nearest candidate by path (Yamauchi, "A frontier-based approach for
//! autonomous exploration", CIRA 1997).

use super::shared::{nearest_of, plain, BuiltIn, NO_FRONTIER};
use crate::explore::strategy::{Choosing, Memory, Rule};

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "nearest",
    gain: "not used: the nearest candidate by path",
    stops: NO_FRONTIER,
    citation: "Yamauchi, CIRA 1997",
    settings: &[],
    make: |_| plain(Nearest),
};

/// The nearest candidate by path.
#[derive(Debug)]
struct Nearest;

impl Rule for Nearest {
    fn name(&self) -> &'static str {
        "nearest"
    }

    fn choose(&self, at: &Choosing<'_, '_>, _: &mut Memory) -> Option<usize> {
        nearest_of(at.shown)
    }
}
