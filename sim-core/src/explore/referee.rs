//! The referee: what only the simulation knows and the robot does not. It credits the explored
//! area against the building's ground truth (`credit_explored`, through `MapToWorld`, the pose
//! error of the moment), records the progress curve, judges how a run ended (`classify_end`),
//! scores the finished run (`finish`: map quality, rooms entered) and makes the oracle's true
//! layout (`true_layout`). Strategies see none of it.

use super::*;

/// What only the simulation knows: the building's ground truth on the map grid, and the
/// explored area credited against it.
#[derive(Clone)]
pub(super) struct Referee {
    /// Explorable free space of the building on the map grid (ground truth for the explored
    /// area and the rooms left unexplored).
    pub(super) truth: Bitmap,
    /// Free space connected to the start (ground truth for the map's quality).
    pub(super) free: Bitmap,
    pub(super) truth_cells: usize,
    /// Truth-free cells observed, kept incrementally. Observed means free or occupied in the
    /// map: a cell whose centre is free but which a wall surface crosses is rightly mapped
    /// occupied, and the boundary rows of every room would otherwise cap the fraction near 97 %.
    /// Building cells are credited through the map cells they were observed in: the map is drawn
    /// at the estimated pose, so a heading error made early (e.g. turning where the laser sees no
    /// wall) rotates everything mapped after it, and comparing map and building cell by cell
    /// would count a consistent but rotated map as unexplored far from the start. See
    /// [`Explorer::credit_explored`].
    pub(super) explored_cells: usize,
    /// Building cells credited as observed (world frame).
    pub(super) explored: Bitmap,
    /// Building cells found not creditable in the current update (all false between updates),
    /// and the list of them (see [`Explorer::credit_explored`]).
    pub(super) untestable: Bitmap,
    pub(super) untestable_list: Vec<usize>,
    /// Ground-truth room polygons (for the "rooms never entered" report, and the layout of the
    /// `layout-truth` oracle, its one door to the decision).
    pub(super) rooms: Vec<crate::geom::Polygon>,
    /// Ground-truth doors (world frame): the `layout-truth` oracle's layout is open there.
    pub(super) doors: Vec<(Vec2, Vec2)>,
}

impl Explorer {
    /// Credits the building cells observed through the map cells `fresh`, just made known by
    /// the current scan (every one of them already marked in `known`): the building cells near
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
    pub(super) fn credit_explored(&mut self, fresh: &[usize], map_to_world: &MapToWorld) {
        const REACH: i32 = 2;
        let frame = self.map.frame;
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
                        .is_some_and(|k| self.known.data[k])
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

    pub(super) fn explored_area_m2(&self) -> f64 {
        self.referee.explored_cells as f64 * self.map.frame.cell_area_m2()
    }

    pub(super) fn explored_fraction(&self) -> f64 {
        if self.referee.truth_cells == 0 {
            0.0
        } else {
            self.referee.explored_cells as f64 / self.referee.truth_cells as f64
        }
    }

    pub(super) fn record_progress(&mut self) {
        if self.sim.time_s() + 1e-9 < self.next_progress_s {
            return;
        }
        let s = ProgressSample {
            time_s: self.sim.time_s(),
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
                map: self.map.occupancy.clone(),
            });
        }
        self.next_progress_s += self.cfg.progress_period_s;
    }

    /// Why a run that ran out of goals ended. Frontier cells the robot looked into (stood at a
    /// goal near them facing the unknown space, and they stayed frontier) are resolved as far as
    /// the sensor allows. Complete when no other frontier cell is left on the map (frontiers of
    /// the configured length, wherever they are); stuck when a path leads to one of the cells
    /// left (every goal toward them was given up); unreachable otherwise.
    pub(super) fn classify_end(&mut self) -> EndReason {
        let frame = self.map.frame;
        let fcfg = FrontierConfig::with_min_length_m(self.cfg.min_frontier_m, frame.resolution_m);
        let mut frontiers = self.frontiers.detect(&self.map.occupancy, &fcfg);
        if self.cfg.frontier_clearance_m > 0.0 {
            let clearance_cells = self.cfg.frontier_clearance_m / frame.resolution_m;
            let obstacles = &self.obstacles;
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
    pub(super) fn close_curve(&mut self) {
        self.next_progress_s = f64::NEG_INFINITY;
        self.record_progress();
    }

    /// The run's result (`close_curve` called before), its map, curve and trajectories taken out
    /// of the state.
    pub(super) fn finish(&mut self, end_reason: EndReason, exploration_time_s: f64) -> RunResult {
        let mut map_quality = map_quality(&self.map.occupancy, &self.referee.free);
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
                &self.map.occupancy,
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
                        crate::building::for_cells_in_polygon(self.map.frame, r, |i| {
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
            total_time_s: self.sim.time_s(),
            explored_area_m2: self.explored_area_m2(),
            free_area_m2: self.referee.truth_cells as f64 * self.map.frame.cell_area_m2(),
            unexplorable_free_m2: (self.referee.free.count_true() - self.referee.truth_cells)
                as f64
                * self.map.frame.cell_area_m2(),
            explored_fraction: self.explored_fraction(),
            path_length_m: self.sim.path_length_m(),
            blacklisted_goals: self.blacklist.added(),
            decisions: std::mem::take(&mut self.decisions),
            progress: std::mem::take(&mut self.progress),
            trajectory: std::mem::take(&mut self.trajectory),
            scans: self.localizer.scans(),
            scan_matches_accepted: self.localizer.matches_accepted(),
            estimated_trajectory: self.localizer.take_estimated_trajectory(),
            map: self.map.occupancy.clone(),
            map_quality,
            plans: self.plans,
            snapshots: std::mem::take(&mut self.snapshots),
        }
    }
}

/// The rigid motion taking a point of the map (drawn at the estimated pose) to where the sensor
/// observed it in the building (the true pose): `true ∘ estimate⁻¹`.
pub(super) struct MapToWorld {
    pub(super) motion: Pose,
    pub(super) inverse: Pose,
    /// `sin_cos` of the two motions' angles, computed once: the arithmetic is then exactly
    /// `Pose::compose`'s.
    pub(super) motion_sc: (f64, f64),
    pub(super) inverse_sc: (f64, f64),
}

impl MapToWorld {
    pub(super) fn new(estimate: &Pose, truth: &Pose) -> Self {
        let origin = Pose::new(0.0, 0.0, 0.0);
        let motion = truth.compose(&estimate.between(&origin));
        let inverse = estimate.compose(&truth.between(&origin));
        Self {
            motion_sc: motion.theta_rad.sin_cos(),
            inverse_sc: inverse.theta_rad.sin_cos(),
            motion,
            inverse,
        }
    }

    /// `pose.compose(p)`'s position, with `(s, c)` = `pose.theta_rad.sin_cos()`.
    pub(super) fn apply(pose: &Pose, (s, c): (f64, f64), p: Vec2) -> Vec2 {
        Vec2::new(pose.x_m + c * p.x - s * p.y, pose.y_m + s * p.x + c * p.y)
    }

    pub(super) fn forward(&self, p: Vec2) -> Vec2 {
        Self::apply(&self.motion, self.motion_sc, p)
    }

    pub(super) fn backward(&self, p: Vec2) -> Vec2 {
        Self::apply(&self.inverse, self.inverse_sc, p)
    }

    /// The building cells (index, cell; same frame) within `reach` cells of where map cell `c`
    /// lies in the building. [`Self::map_index_of`] gives the map cell each corresponds to.
    /// (`credit_explored` walks the same box row by row.)
    #[cfg(test)]
    pub(super) fn cells_near<'a>(
        &'a self,
        frame: &'a GridFrame,
        c: Cell,
        reach: i32,
    ) -> impl Iterator<Item = (usize, Cell)> + 'a {
        let w = self.building_cell_of(frame, c);
        (-reach..=reach)
            .flat_map(move |dy| (-reach..=reach).map(move |dx| Cell::new(w.x + dx, w.y + dy)))
            .filter_map(move |n| Some((frame.index(n)?, n)))
    }

    /// The building cell where map cell `c` lies.
    pub(super) fn building_cell_of(&self, frame: &GridFrame, c: Cell) -> Cell {
        frame.cell_from_world(self.forward(frame.world_from_cell(c)))
    }

    /// The map cell (index) the centre of building cell `n` falls in, `None` off the frame.
    pub(super) fn map_index_of(&self, frame: &GridFrame, n: Cell) -> Option<usize> {
        frame.index(frame.cell_from_world(self.backward(frame.world_from_cell(n))))
    }
}

/// The building's rooms as a complete layout in the map's frame (world positions brought back
/// through `to_map`, the current pose error): every room closed and fully known.
pub(super) fn true_layout(
    rooms: &[crate::geom::Polygon],
    to_map: &MapToWorld,
) -> crate::layout::Layout {
    let rooms = rooms
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let polygon =
                crate::geom::Polygon::new(p.vertices.iter().map(|v| to_map.backward(*v)).collect());
            let area_m2 = polygon.area_m2();
            crate::layout::LayoutRoom {
                id: k as u32,
                open_edges: vec![false; polygon.vertices.len()],
                observed_polygon: polygon.clone(),
                polygon,
                label: crate::layout::RoomLabel::Partial,
                predicted: false,
                area_m2,
                observed_area_m2: area_m2,
                unknown_area_m2: 0.0,
            }
        })
        .collect();
    crate::layout::Layout {
        rooms,
        lines: Vec::new(),
        diagnostics: Default::default(),
    }
}

/// How far either side of a door's line the oracle's layout walls are opened: through the wall
/// (the rooms' outlines run along its faces, or its centre line).
const DOOR_REACH_M: f64 = 0.3;

/// Opens the true layout's walls (`walls`, on `frame`) at the building's doors (world frame,
/// brought into the map's through `to_map`): the layout cells within the door's width and
/// [`DOOR_REACH_M`] of its line. A perfect layout knows its doorways, as a predicted one learns
/// them from the gaps it sees in walls; without this, the oracle's gain stops at a door the
/// robot has not yet seen open, and its early stop can leave a room behind it unexplored.
pub(super) fn open_true_doors(walls: &mut Bitmap, doors: &[(Vec2, Vec2)], to_map: &MapToWorld) {
    let frame = walls.frame;
    for &(a, b) in doors {
        let (a, b) = (to_map.backward(a), to_map.backward(b));
        let len = (b - a).norm();
        if len.is_nan() || len <= 1e-9 {
            continue;
        }
        let u = (b - a) / len;
        let mid = (a + b) * 0.5;
        let r = len / 2.0 + DOOR_REACH_M;
        let lo = frame.cell_from_world(mid - Vec2::new(r, r));
        let hi = frame.cell_from_world(mid + Vec2::new(r, r));
        for y in lo.y.max(0)..=hi.y.min(frame.height as i32 - 1) {
            for x in lo.x.max(0)..=hi.x.min(frame.width as i32 - 1) {
                let c = Cell::new(x, y);
                let d = frame.world_from_cell(c) - mid;
                if d.dot(&u).abs() <= len / 2.0 && (d.x * u.y - d.y * u.x).abs() <= DOOR_REACH_M {
                    walls.set(c, false);
                }
            }
        }
    }
}

pub(super) fn map_quality(map: &OccupancyGrid, truth_free: &Bitmap) -> MapQuality {
    let mut free = 0usize;
    let mut free_ok = 0usize;
    let mut occ = 0usize;
    let mut occ_ok = 0usize;
    for (i, s) in map.data.iter().enumerate() {
        match s {
            Occupancy::Free => {
                free += 1;
                free_ok += truth_free.data[i] as usize;
            }
            Occupancy::Occupied => {
                occ += 1;
                let c = map.frame.cell_of_index(i);
                let near_solid = std::iter::once(c)
                    .chain(c.neighbours8())
                    .any(|n| truth_free.get(n) != Some(&true));
                occ_ok += near_solid as usize;
            }
            Occupancy::Unknown => {}
        }
    }
    let ratio = |a: usize, b: usize| if b == 0 { 1.0 } else { a as f64 / b as f64 };
    MapQuality {
        free_precision: ratio(free_ok, free),
        occupied_precision: ratio(occ_ok, occ),
        occupied_precision_aligned: ratio(occ_ok, occ),
    }
}
