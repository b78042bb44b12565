//! The layout state: the layout predicted from the map, rebuilt when the map has grown enough and
//! a strategy needs it (`refresh_layout`), or the oracle's true rooms.

use crate::explore::policy::{RoomState, RoomView};
use crate::layout_gain::LayoutRaster;

/// How the explorer keeps the layout and draws it for the gains (for a layout strategy, or a
/// policy that needs the layout).
#[derive(Debug, Clone, PartialEq)]
pub struct LayoutUse {
    /// The layout is recomputed at a decision when the known area changed by at least this much
    /// since the last layout (m2), so it follows the map without being rebuilt at every step.
    pub update_m2: f64,
    /// And by at least this fraction of the known area (0.1 by default since 0.7; 0: off, the
    /// paper's): on a large building the layout, whose every rebuild reads the whole known map,
    /// is then rebuilt a number of times that does not grow with the building (every 400 m² at
    /// 4000 m² known; below 200 m² known `update_m2` decides alone; docs/scale.md).
    pub update_fraction: f64,
    /// Layout walls close gaps of unknown cells up to this long in an observed wall (m).
    pub max_wall_gap_m: f64,
    /// The paper's `I(p)` sees through openings of the layout's wall lines (see
    /// [`crate::layout_gain::LayoutRaster::through_openings`]): an early stop then drops only
    /// what the layout predicts, never a room beyond a doorway the robot has seen. On by default
    /// since 0.4 (off: the paper's rule, setting `paper_layout_gain`).
    pub through_openings: bool,
}

impl Default for LayoutUse {
    fn default() -> Self {
        Self {
            update_m2: 20.0,
            update_fraction: 0.1,
            max_wall_gap_m: 1.0,
            through_openings: true,
        }
    }
}

/// The last layout and what is needed to judge it.
#[derive(Clone)]
pub(super) struct LayoutState {
    pub(super) raster: LayoutRaster,
    pub(super) known_cells_at: usize,
    /// Cells unknown when the layout was made that it predicted inside a room (for the switch;
    /// empty for other gains).
    pub(super) predicted_unknown: Vec<u32>,
    /// Its rooms as a policy that needs them sees them (else empty).
    pub(super) rooms: Vec<RoomView>,
    /// Layouts made in the run up to this one.
    pub(super) number: u64,
}

/// A predicted room as a policy sees it.
pub(super) fn room_view(r: &crate::layout::LayoutRoom) -> RoomView {
    RoomView {
        polygon: r.polygon.vertices.clone(),
        state: match r.label {
            crate::layout::RoomLabel::Full => RoomState::Full,
            crate::layout::RoomLabel::Partial => RoomState::Partial,
            crate::layout::RoomLabel::Open => RoomState::Open,
        },
        predicted: r.predicted,
        area_m2: r.area_m2,
        observed_area_m2: r.observed_area_m2,
        unknown_area_m2: r.unknown_area_m2,
    }
}
