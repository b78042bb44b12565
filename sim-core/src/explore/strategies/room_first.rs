//! `room-first`: the nearest candidate by path in the robot's room, while one is left there;
//! then the nearest (Holz, Basilico, Amigoni and Behnke, "Evaluating the efficiency of
//! frontier-based exploration strategies", ISR/ROBOTIK 2010). Rooms are those of the layout
//! predicted from the map (never the building's true rooms); a candidate is in the room that
//! holds its cell, the robot in the room whose polygon holds its estimated position.

use super::shared::{best_of, nearest_of, plain, BuiltIn, NO_FRONTIER};
use crate::explore::policy::CandidateView;
use crate::explore::strategy::{Choosing, Memory, Rule};

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "room-first",
    gain: "not used: the nearest candidate by path in the robot's room while one is left there, then the nearest; rooms from the layout predicted from the map",
    stops: NO_FRONTIER,
    citation: "Holz, Basilico, Amigoni and Behnke, ISR/ROBOTIK 2010",
    settings: &["layout_update_m2", "layout_update_fraction"],
    make: |_| plain(RoomFirst),
};

/// The nearest in the robot's room, then the nearest.
#[derive(Debug)]
struct RoomFirst;

impl Rule for RoomFirst {
    fn name(&self) -> &'static str {
        "room-first"
    }

    fn needs_layout(&self) -> bool {
        true
    }

    fn choose(&self, at: &Choosing<'_, '_>, _: &mut Memory) -> Option<usize> {
        let view = at.view;
        let here = view
            .layout
            .and_then(|l| l.room_holding(view.pose.position()));
        let in_here = |c: &CandidateView| here.is_some() && c.room == here;
        if at.shown.iter().any(|c| in_here(c)) {
            best_of(at.shown, |c| if in_here(c) { -c.path_m } else { f64::NAN })
        } else {
            nearest_of(at.shown)
        }
    }
}
