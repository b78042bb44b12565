//! The layout kept for the decisions: rebuilt when the map has grown enough, or the oracle's true rooms.

use crate::explore::layout_state::LayoutState;

use crate::explore::explorer::Explorer;
use crate::explore::explorer::LayoutCost;
use crate::explore::layout_state::room_view;
use crate::explore::referee::{
    open_true_doors, open_unseen_walls, open_where_free, true_layout, MapToWorld,
};
use crate::explore::strategy::GainModel;
use crate::grid::Occupancy;
use crate::grid::OccupancyGrid;
use crate::layout::{reconstruct_layout, Layout, LayoutConfig};
use crate::layout_gain::LayoutRaster;
use std::sync::Mutex;

impl Explorer {
    /// Recomputes the layout when the strategy uses it and the map has grown enough since the
    /// last one. Returns whether gains should use the layout now.
    pub(crate) fn refresh_layout(&mut self) -> bool {
        let (st, layout_use) = (&self.cfg.strategy, &self.cfg.layout_use);
        let needs = self.policy_needs;
        if !st.uses_layout() && !needs.layout_gain && !needs.layout {
            return false;
        }
        let cell_area = self.map.grid.frame.cell_area_m2();
        let grown_m2 = self.map.layout.as_ref().map_or(f64::INFINITY, |l| {
            (self.map.known_cells.saturating_sub(l.known_cells_at)) as f64 * cell_area
        });
        let known_m2 = self.map.known_cells as f64 * cell_area;
        if grown_m2 >= layout_use.update_m2 && grown_m2 >= layout_use.update_fraction * known_m2 {
            let grid = &self.map.grid.occupancy;
            // Judge the previous layout by what was revealed since (for the switch strategy).
            if let (
                Some(prev),
                GainModel::Switch {
                    agreement,
                    min_area_m2,
                },
            ) = (&self.map.layout, st.gain)
            {
                let (mut known, mut free) = (0usize, 0usize);
                for &i in &prev.predicted_unknown {
                    match grid.data[i as usize] {
                        Occupancy::Free => {
                            known += 1;
                            free += 1;
                        }
                        Occupancy::Occupied => known += 1,
                        Occupancy::Unknown => {}
                    }
                }
                if known as f64 * cell_area >= min_area_m2
                    && free as f64 >= agreement * known as f64
                {
                    self.layout_trusted = true;
                }
            }
            // (Dropped before the next is made: two rasters of a large map are tens of MB.)
            self.map.layout = None;
            // The rooms a policy is shown: only a layout predicted from the map.
            let mut rooms = Vec::new();
            let mut raster = if st.layout_from_truth() {
                // The oracle: nothing to compute (and nothing to charge).
                let to_map = MapToWorld::new(&self.localizer.estimate(), &self.true_pose);
                let layout = true_layout(&self.referee.rooms, &to_map);
                let mut raster = LayoutRaster::exact(&layout, grid);
                open_true_doors(&mut raster.walls, &self.referee.doors, &to_map);
                open_where_free(&mut raster.walls, &layout, &self.referee.free, &to_map);
                open_unseen_walls(&mut raster.walls, &layout, grid);
                raster
            } else {
                let (layout, charged_s) =
                    charged_layout(self.layout_cost.as_deref(), grid, &self.cfg.layout);
                if charged_s.is_finite() && charged_s > 0.0 {
                    self.compute_debt_s += charged_s;
                    self.layout_compute_s += charged_s;
                }
                if needs.layout {
                    rooms = layout.rooms.iter().map(room_view).collect();
                }
                LayoutRaster::new(&layout, grid, layout_use.max_wall_gap_m)
            };
            raster.through_openings = layout_use.through_openings;
            // Only the switch judges a layout by what it predicted (a scan of the whole map).
            let predicted_unknown = if matches!(st.gain, GainModel::Switch { .. }) {
                grid.data
                    .iter()
                    .enumerate()
                    .filter(|(i, s)| {
                        **s == Occupancy::Unknown
                            && raster.inside(self.map.grid.frame.cell_of_index(*i))
                    })
                    .map(|(i, _)| i as u32)
                    .collect()
            } else {
                Vec::new()
            };
            self.layouts_computed += 1;
            self.map.layout = Some(LayoutState {
                raster,
                known_cells_at: self.map.known_cells,
                predicted_unknown,
                rooms,
                number: self.layouts_computed,
            });
            // Cached layout gains were computed with the previous layout.
            self.map.gains.clear_layout_gains();
        }
        match st.gain {
            GainModel::Baseline => false,
            GainModel::PredictedRooms(_) | GainModel::ClosedGaps(_) => true,
            GainModel::Switch { .. } => self.layout_trusted,
        }
    }
}

/// The layout reconstructed from `grid`, and the seconds `cost` charges for it (0 without one).
fn charged_layout(
    cost: Option<&Mutex<LayoutCost>>,
    grid: &OccupancyGrid,
    cfg: &LayoutConfig,
) -> (Layout, f64) {
    let mut made = None;
    let charged_s = match cost {
        Some(cost) => {
            let mut cost = cost.lock().unwrap_or_else(|e| e.into_inner());
            cost(&mut || made = Some(reconstruct_layout(grid, cfg)))
        }
        None => 0.0,
    };
    (
        made.unwrap_or_else(|| reconstruct_layout(grid, cfg)),
        charged_s,
    )
}
