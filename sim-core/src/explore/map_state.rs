//! The map as one component: the occupancy grid, the obstacle distances, the known cells, the
//! frontiers, the gain cache and the layout kept for the gains. [`MapState::integrate`] inserts
//! a scan taken from a pose and returns what changed ([`MapChanges`]), which the navigator (its
//! planning cells) and the referee (the explored area) consume. It knows nothing of the robot
//! that took the scan: several robots can share one map or keep their own.

use crate::explore::gain_cache::GainCache;
use crate::explore::layout_state::LayoutState;
use crate::frontier::detect::FrontierTracker;
use crate::geom::Pose;
use crate::grid::{Bitmap, GridFrame, Occupancy};
use crate::mapping::distance_field::ObstacleDistance;
use crate::mapping::log_odds::{LogOddsConfig, LogOddsMap};
use crate::scan::Scan;

/// The map built from the scans (see the module documentation).
#[derive(Clone)]
pub(crate) struct MapState {
    /// The log-odds occupancy grid.
    pub(crate) grid: LogOddsMap,
    pub(crate) obstacles: ObstacleDistance,
    /// Map cells observed (free or occupied) so far.
    pub(crate) known: Bitmap,
    /// Cells of the map that are known (free or occupied), counted from the map's own changes.
    pub(crate) known_cells: usize,
    /// The map's frontier cells, updated with each map update.
    pub(crate) frontiers: FrontierTracker,
    /// Candidates' gains of every kind, kept while the cells they read are unchanged.
    pub(crate) gains: GainCache,
    /// The last layout (for the layout strategies' gains), when one was made.
    pub(crate) layout: Option<LayoutState>,
    /// Scans integrated so far (the gain cache's clock).
    updates: u64,
    /// Buffers of the last update's changes, kept between updates.
    fresh_known: Vec<usize>,
    distance_changes: Vec<u32>,
}

/// What one [`MapState::integrate`] changed (row-major cell indices of the map's frame; the
/// cells that became known and those whose obstacle distance changed are kept in the map:
/// [`MapState::fresh_known`], [`MapState::distance_changes`]).
#[derive(Debug)]
pub(crate) struct MapChanges {
    /// Cells that became occupied or stopped being so.
    pub(crate) flips: Vec<u32>,
    /// Cells that changed toward free (whether each was unknown before).
    pub(crate) free_changes: Vec<(u32, bool)>,
}

impl MapState {
    /// An empty map over `frame`; obstacle distances are kept up to `cap_cells`.
    pub(crate) fn new(frame: GridFrame, cap_cells: u32) -> MapState {
        MapState {
            grid: LogOddsMap::new(frame),
            obstacles: ObstacleDistance::new(frame, cap_cells),
            known: Bitmap::filled(frame, false),
            known_cells: 0,
            frontiers: FrontierTracker::default(),
            gains: GainCache::new(frame),
            layout: None,
            updates: 0,
            fresh_known: Vec::new(),
            distance_changes: Vec::new(),
        }
    }

    /// Map updates so far (the clock the gain cache's entries are stamped with).
    pub(crate) fn updates(&self) -> u64 {
        self.updates
    }

    /// The cells the last update made known (free or occupied).
    pub(crate) fn fresh_known(&self) -> &[usize] {
        &self.fresh_known
    }

    /// The cells whose obstacle distance the last update changed.
    pub(crate) fn distance_changes(&self) -> &[u32] {
        &self.distance_changes
    }

    /// Inserts `scan` taken from `pose` (map frame) and brings the obstacle distances, the
    /// frontiers, the known cells and the gain cache up to date; returns what changed.
    pub(crate) fn integrate(
        &mut self,
        pose: &Pose,
        scan: &Scan,
        cfg: &LogOddsConfig,
    ) -> MapChanges {
        self.updates += 1;
        let stats = self.grid.insert_scan(pose, scan, cfg);
        self.known_cells += stats.cells_discovered;
        let flips = self.grid.take_occupied_flips();
        let free_changes = self.grid.take_free_changes();
        let mut distance_changes = std::mem::take(&mut self.distance_changes);
        distance_changes.clear();
        self.obstacles
            .update_reporting(&self.grid.occupancy, &flips, &mut distance_changes);
        // (The layout gains too: the layout they are computed with changes less often than the
        // map, and clears them when it does.)
        // (Changes of whether a cell is occupied recorded last: see `GainCache::touch`.)
        let now = self.updates;
        for &(i, _) in &free_changes {
            self.gains.touch(i, now, false);
        }
        for &i in &flips {
            self.gains.touch(i, now, true);
        }
        let changed = flips
            .iter()
            .chain(free_changes.iter().map(|(i, _)| i))
            .copied();
        self.frontiers.update(&self.grid.occupancy, changed.clone());
        // A cell never goes back to unknown, and every change from unknown is in one of the
        // two lists.
        let mut fresh = std::mem::take(&mut self.fresh_known);
        fresh.clear();
        for i in changed {
            let i = i as usize;
            if !self.known.data[i] && self.grid.occupancy.data[i] != Occupancy::Unknown {
                self.known.data[i] = true;
                fresh.push(i);
            }
        }
        self.fresh_known = fresh;
        self.distance_changes = distance_changes;
        MapChanges {
            flips,
            free_changes,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::building::{Building, Geometry};
    use crate::explore::config::map_frame;
    use crate::geom::{Polygon, Vec2};
    use crate::sim::{RobotId, SimConfig, World};

    /// A 10 x 6 m room with a pillar.
    fn room() -> Building {
        let w = |a: (f64, f64), b: (f64, f64)| {
            Polygon::thick_segment(Vec2::new(a.0, a.1), Vec2::new(b.0, b.1), 0.2)
        };
        Building {
            name: "map-state-test".into(),
            geometry: Geometry::Vector {
                outline: Polygon::rect(Vec2::new(0.0, 0.0), Vec2::new(10.0, 6.0)),
                solids: vec![
                    w((0.0, 0.0), (10.0, 0.0)),
                    w((10.0, 0.0), (10.0, 6.0)),
                    w((10.0, 6.0), (0.0, 6.0)),
                    w((0.0, 6.0), (0.0, 0.0)),
                    Polygon::rect(Vec2::new(4.0, 2.5), Vec2::new(4.5, 3.0)),
                ],
            },
            rooms: vec![],
            doors: vec![],
            start: None,
        }
    }

    /// Each update reports every cell whose state changed (and may report cells whose log-odds
    /// changed within a state), the fresh cells are exactly those that were unknown, the count
    /// of known cells is right; two robots' scans go into one map.
    #[test]
    fn integrate_reports_what_changed() {
        let b = room();
        let frame = map_frame(&b.bounds(), 0.05);
        let mut world = World::new(&b, &SimConfig::default(), 3);
        let poses = [Pose::new(1.5, 1.5, 0.5), Pose::new(8.5, 4.5, -2.6)];
        let robots: Vec<RobotId> = poses.iter().map(|&p| world.add_robot(p)).collect();
        let mut map = MapState::new(frame, 8);
        for (k, (&robot, pose)) in robots.iter().zip(poses).enumerate() {
            let before = map.grid.occupancy.data.clone();
            let scan = world.scan(robot);
            let changes = map.integrate(&pose, &scan, &LogOddsConfig::default());
            let mut reported: Vec<u32> = changes
                .flips
                .iter()
                .chain(changes.free_changes.iter().map(|(i, _)| i))
                .copied()
                .collect();
            reported.sort_unstable();
            reported.dedup();
            let changed: Vec<u32> = (0..before.len())
                .filter(|&i| before[i] != map.grid.occupancy.data[i])
                .map(|i| i as u32)
                .collect();
            let missed = changed
                .iter()
                .filter(|i| reported.binary_search(i).is_err());
            assert_eq!(missed.count(), 0, "update {k}: changed cells not reported");
            assert!(!changed.is_empty());
            let mut fresh = map.fresh_known().to_vec();
            fresh.sort_unstable();
            let newly: Vec<usize> = (0..before.len())
                .filter(|&i| {
                    before[i] == Occupancy::Unknown
                        && map.grid.occupancy.data[i] != Occupancy::Unknown
                })
                .collect();
            assert!(!newly.is_empty());
            assert!(fresh == newly, "update {k}: fresh cells differ");
            let known = map.grid.occupancy.data.iter();
            let known = known.filter(|&&c| c != Occupancy::Unknown).count();
            assert_eq!(map.known_cells, known);
            assert_eq!(map.known.count_true(), known);
            assert_eq!(map.updates(), k as u64 + 1);
        }
    }
}
