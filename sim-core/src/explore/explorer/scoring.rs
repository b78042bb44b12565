//! What reads ground truth: the explored area, the progress curve, how the run ended, its result.

use crate::explore::run::{MapSnapshot, ProgressSample};
use crate::sim::World;

use crate::explore::explorer::Explorer;
use crate::explore::navigation::Planning;
use crate::explore::referee::{map_quality, MapToWorld};
use crate::explore::run::{EndReason, RunResult};
use crate::frontier::detect::{frontiers_where, FrontierConfig};
use crate::geom::Pose;
use crate::grid::Cell;
use crate::plan::inflate::nearest_by;

impl Explorer {
    /// Credits the building cells observed through the map cells `fresh`
    /// ([`MapState::fresh_known`]), just made known by the current scan (every one of them already marked in `known`): the building cells near
    /// where the sensor saw each whose centres, brought into the map frame by the current pose
    /// error, fall in a known map cell. With ground-truth poses that is exactly the known cells.
    /// Under a rotation every building cell still corresponds to one map cell (mapping cell
    /// centres forward instead would leave lines of holes), and testing every known map cell
    /// rather than only the fresh ones credits the cells that a pose error jittering by a cell
    /// between updates would otherwise skip.
    ///
    /// The cells credited do not depend on the order of `fresh`, nor on whether `known` was
    /// brought up to date before or during the crediting: a building cell `n` whose map cell `k`
    /// is fresh lies within a cell of where `k` lies in the building, so within the reach of `k`
    /// itself. Hence a building cell found not creditable once in an update stays so for the rest
    /// of it, and is tested once (about a sixth of the tests of testing it for every fresh cell
    /// near it, on the bench building).
    pub(crate) fn credit_explored(&mut self, map_to_world: &MapToWorld) {
        const REACH: i32 = 2;
        let frame = self.map.grid.frame;
        let fresh = self.map.fresh_known();
        let referee = &mut self.referee;
        let (w, h) = (frame.width as i32, frame.height as i32);
        // The previous fresh cell's square of building cells (clipped to the frame): every cell
        // of it has been tested in this update, so that it is credited or found untestable, and
        // a test again would change nothing. Consecutive fresh cells are mostly neighbours (a
        // beam's cells), whose squares share 20 of their 25 cells (16 for diagonal neighbours).
        let mut done: Option<(i32, i32, i32, i32)> = None;
        for &i in fresh {
            let b = map_to_world.building_cell_of(&frame, frame.cell_of_index(i));
            let (x0, x1) = (
                b.x.saturating_sub(REACH).max(0),
                b.x.saturating_add(REACH).min(w - 1),
            );
            let (y0, y1) = (
                b.y.saturating_sub(REACH).max(0),
                b.y.saturating_add(REACH).min(h - 1),
            );
            for y in y0..=y1 {
                let row = y as usize * w as usize;
                // The row's columns outside the previous square: those left and right of its
                // columns when the row is one of its rows, else all of them (none skipped).
                let (skip0, skip1) = match done {
                    Some((dx0, dx1, dy0, dy1)) if (dy0..=dy1).contains(&y) => (dx0, dx1),
                    _ => (x1 + 1, x1),
                };
                for x in (x0..=x1.min(skip0 - 1)).chain(x0.max(skip1 + 1)..=x1) {
                    let j = row + x as usize;
                    // Most neighbours are credited already: test that before transforming back.
                    if referee.explored.data[j] || referee.untestable.data[j] {
                        continue;
                    }
                    if map_to_world
                        .map_index_of(&frame, Cell::new(x, y))
                        .is_some_and(|k| self.map.known.data[k])
                    {
                        referee.explored.data[j] = true;
                        referee.explored_cells += referee.truth.data[j] as usize;
                    } else {
                        referee.untestable.data[j] = true;
                        referee.untestable_list.push(j);
                    }
                }
            }
            done = (x0 <= x1 && y0 <= y1).then_some((x0, x1, y0, y1));
        }
        for j in referee.untestable_list.drain(..) {
            referee.untestable.data[j] = false;
        }
    }

    pub(crate) fn explored_area_m2(&self) -> f64 {
        self.referee.explored_area_m2()
    }

    pub(crate) fn explored_fraction(&self) -> f64 {
        self.referee.explored_fraction()
    }

    pub(crate) fn record_progress(&mut self) {
        if self.now_s + 1e-9 < self.next_progress_s {
            return;
        }
        let s = ProgressSample {
            time_s: self.now_s,
            explored_area_m2: self.explored_area_m2(),
            explored_fraction: self.explored_fraction(),
        };
        self.progress.push(s);
        while let Some(&f) = self.cfg.snapshot_fractions.get(self.snapshots.len()) {
            if s.explored_fraction + 1e-12 < f {
                break;
            }
            self.snapshots.push(MapSnapshot {
                fraction: f,
                time_s: s.time_s,
                map: self.map.grid.occupancy.clone(),
            });
        }
        self.next_progress_s += self.cfg.progress_period_s;
    }

    /// Why a run that ran out of goals ended. Frontier cells the robot looked into (stood at a
    /// goal near them facing the unknown space, and they stayed frontier) are resolved as far as
    /// the sensor allows. Complete when no other frontier cell is left on the map (frontiers of
    /// the configured length, wherever they are); stuck when a path leads to one of the cells
    /// left (every goal toward them was given up); unreachable otherwise.
    pub(crate) fn classify_end(&mut self) -> EndReason {
        let frame = self.map.grid.frame;
        let fcfg = FrontierConfig::with_min_length_m(self.cfg.min_frontier_m, frame.resolution_m);
        let mut frontiers = self.map.frontiers.detect(&self.map.grid.occupancy, &fcfg);
        if self.cfg.frontier_clearance_m > 0.0 {
            let clearance_cells = self.cfg.frontier_clearance_m / frame.resolution_m;
            let obstacles = &self.map.obstacles;
            frontiers = frontiers_where(frontiers, &fcfg, |c| {
                f64::from(obstacles.get(c)) >= clearance_cells
            });
        }
        let left: Vec<Cell> = frontiers
            .iter()
            .flat_map(|f| f.cells.iter().copied())
            .filter(|&c| !self.blacklist.looked_at(frame.world_from_cell(c)))
            .collect();
        self.frontier_cells_left = left.len();
        if left.is_empty() {
            return EndReason::Complete;
        }
        if left
            .iter()
            .any(|&c| self.blacklist.given_up_at(frame.world_from_cell(c)))
        {
            return EndReason::Stuck;
        }
        let search = (0.5 / frame.resolution_m).ceil() as i32;
        let targets: Vec<Cell> = {
            let trav = self.traversability();
            left.iter()
                .filter_map(|&c| {
                    if trav.at(c) {
                        Some(c)
                    } else {
                        nearest_by(c, search, |n| trav.at(n))
                    }
                })
                .collect()
        };
        self.set_planning(Planning::Travelled);
        let plan = self.plan(&targets);
        let reachable = targets.iter().any(|&c| plan.distance_m(c).is_some());
        self.set_planning(Planning::WithMargin);
        if reachable {
            EndReason::Stuck
        } else {
            EndReason::Unreachable
        }
    }

    /// Closes the progress curve with the final state.
    pub(crate) fn close_curve(&mut self) {
        self.next_progress_s = f64::NEG_INFINITY;
        self.record_progress();
    }

    /// The run's result (`close_curve` called before), its map, curve and trajectories taken out
    /// of the state: the explorer is not used after it.
    pub(crate) fn finish(
        &mut self,
        end_reason: EndReason,
        exploration_time_s: f64,
        world: &World,
    ) -> RunResult {
        let mut map_quality = map_quality(&self.map.grid.occupancy, &self.referee.free);
        // The map as a whole may sit rotated about the start (a heading error made before any
        // wall was in view); the best fit of the estimated trajectory onto the true one undoes
        // that, and the search around it takes out what remains of a rigid misplacement, so
        // that only inconsistencies (doubled or bent walls) lower the score.
        let positions = |t: &[Pose]| t.iter().map(|p| p.position()).collect::<Vec<_>>();
        let prior = crate::mapping::alignment::fit_rigid(
            &positions(self.localizer.estimated_trajectory()),
            &positions(&self.trajectory),
        );
        map_quality.occupied_precision_aligned =
            crate::mapping::alignment::aligned_occupied_precision(
                &self.map.grid.occupancy,
                &self.referee.free,
                &prior,
                prior
                    .compose(&Pose::new(self.start.x_m, self.start.y_m, 0.0))
                    .position(),
                &Default::default(),
            )
            .0;
        RunResult {
            seed: self.seed,
            start: self.start,
            stopped_early: end_reason == EndReason::EarlyStop,
            layouts_computed: self.layouts_computed,
            layout_compute_s: self.layout_compute_s,
            strategy_compute_s: self.strategy_compute_s,
            rooms_never_entered: (!self.referee.rooms.is_empty()).then(|| {
                self.referee
                    .rooms
                    .iter()
                    .filter(|r| !self.trajectory.iter().any(|p| r.contains(p.position())))
                    .count()
            }),
            rooms_unexplored: (!self.referee.rooms.is_empty()).then(|| {
                self.referee
                    .rooms
                    .iter()
                    .filter(|r| {
                        let (mut free, mut explored) = (0usize, 0usize);
                        crate::building::for_cells_in_polygon(self.map.grid.frame, r, |i| {
                            if self.referee.truth.data[i] {
                                free += 1;
                                explored += self.referee.explored.data[i] as usize;
                            }
                        });
                        free > 0 && 2 * explored < free
                    })
                    .count()
            }),
            end_reason,
            frontier_cells_left: self.frontier_cells_left,
            exploration_time_s,
            total_time_s: self.now_s,
            explored_area_m2: self.explored_area_m2(),
            free_area_m2: self.referee.truth_cells as f64 * self.map.grid.frame.cell_area_m2(),
            unexplorable_free_m2: (self.referee.free.count_true() - self.referee.truth_cells)
                as f64
                * self.map.grid.frame.cell_area_m2(),
            explored_fraction: self.explored_fraction(),
            path_length_m: world.path_length_m(self.robot),
            blacklisted_goals: self.blacklist.added(),
            decisions: std::mem::take(&mut self.decisions),
            progress: std::mem::take(&mut self.progress),
            trajectory: std::mem::take(&mut self.trajectory),
            scans: self.localizer.scans(),
            scan_matches_accepted: self.localizer.matches_accepted(),
            estimated_trajectory: self.localizer.take_estimated_trajectory(),
            map: crate::grid::Grid {
                frame: self.map.grid.occupancy.frame,
                data: if self.shares_map {
                    self.map.grid.occupancy.data.clone()
                } else {
                    std::mem::take(&mut self.map.grid.occupancy.data)
                },
            },
            map_quality,
            plans: self.plans,
            snapshots: std::mem::take(&mut self.snapshots),
        }
    }
}
