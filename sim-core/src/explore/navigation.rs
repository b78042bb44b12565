//! Navigation: the `Navigator`, which owns the planning and distance grids and keeps them up
//! to date with the map's changes (`map_updated`, the cells travelled), the plans on them
//! (`Plan`: path costs from the robot to every candidate on the distance grid, the path to the
//! chosen one on the planning grid) and the ladder of plans with less clearance (`Planning`);
//! and the explorer's goal kept, re-planned or given up while driving (`needs_decision`), and
//! driving itself. The navigator reads the map it is given (`Seen`) and holds none of it.

use crate::explore::follow::PathFollower;
use crate::explore::map_state::{MapChanges, MapState};
use crate::explore::policy::CandidateView;
use crate::geom::Vec2;
use crate::grid::{Bitmap, Cell, GridFrame, Occupancy, OccupancyGrid};
use crate::mapping::distance_field::ObstacleDistance;
use crate::mapping::log_odds::LogOddsMap;
use crate::mapping::ray::{grid_from_world, walk_segment};
use crate::plan::coarse::CoarseCosts;
use crate::plan::dijkstra::{
    dijkstra_padded_bounded, dijkstra_padded_within, padded_index, AStar, CostField,
};
use crate::plan::inflate::{nearest_by, Traversability};
use crate::plan::waypoints::waypoints_by;
use std::sync::Arc;

/// What the navigator reads of the robot's map: the map (its frame, cell states and observed
/// box) and its obstacle distances.
#[derive(Clone, Copy)]
pub(super) struct Seen<'m> {
    pub(super) map: &'m LogOddsMap,
    pub(super) obstacles: &'m ObstacleDistance,
}

/// Path planning: the planning and distance grids of the planning level in use and of those used
/// before, brought up to date before each plan from the map cells changed since, and the path
/// search's state kept between searches.
pub(super) struct Navigator {
    /// The robot's radius, and the clearance added to it when planning with the margin.
    radius_m: f64,
    safety_margin_m: f64,
    /// The planning grid, brought up to date before each plan from the planning cells whose
    /// map cells changed (occupancy or obstacle distance) since the last one.
    coarse: CoarseCosts,
    coarse_dirty: Vec<u32>,
    coarse_dirty_mark: Vec<bool>,
    /// Per cell of `far`: listed among the cells to recompute (all false between updates).
    far_dirty_mark: Vec<bool>,
    /// How permissive path planning is (see the decision's last resorts, `Explorer::chosen`).
    planning: Planning,
    /// Map cells the robot's estimated centre passed through (the segments between its poses at
    /// map updates): its body fitted there, whatever the map shows now.
    travelled: Bitmap,
    /// The coarser grid the candidates' distances are searched on, updated with `coarse`. Shared
    /// with the plans made on it (a plan lasts while the map stands still; the grid is copied
    /// only when it changes while a plan, a parked level or a snapshot still holds it).
    far: Arc<CoarseCosts>,
    /// The planning and distance grids of the planning levels used before and not in use now,
    /// with the planning cells to recompute before one is used again (marked with every map
    /// update, as `coarse_dirty`): a relaxed plan lasts one decision, and recomputing every
    /// planning cell at each change of level was most of the grids' upkeep on maps with
    /// passages narrow for the robot.
    parked: Vec<ParkedGrids>,
    /// Whether a cell became or stopped being occupied since the path was last checked.
    walls_changed: bool,
    /// The path search on `coarse`, and per cell of `far` whether it is in the corridor the
    /// search is confined to first (all false between searches).
    astar: AStar,
    corridor: Vec<bool>,
    /// Bumped whenever the planning grid (`coarse`) changes.
    planning_generation: u64,
    /// The planning cells reachable from a start, as a search of the whole planning grid that
    /// failed found them, with the grid's generation and the start: a goal not among them has
    /// no path either (a decision whose best candidates lie beyond a gap too narrow for the
    /// planning grid asks for many).
    unreachable_memo: Option<UnreachableMemo>,
    /// The last search of everything reachable made for plans bounded by distance
    /// ([`Navigator::plan`] with a bound), whose distances the candidates beyond the bound take.
    stale: Option<StaleField>,
    /// Whether the last decision headed for a goal beyond the bound of a bounded plan: the next
    /// then searches everything at once (late in a run every candidate is far, and a bounded
    /// search would only be made again).
    chose_beyond: bool,
}

/// A robot's own part of a navigator that a team's robots share (`Episode::lend`): the level
/// it plans at, whether walls changed since it last checked its path, and the bounded search's
/// memory. The grids are the team's: they depend on the map alone (and at the `Travelled`
/// level on the cells any robot travelled: a teammate's body, the same, fitted there too).
#[derive(Debug, Clone)]
pub(super) struct OwnNav {
    planning: Planning,
    walls_changed: bool,
    chose_beyond: bool,
    stale: Option<StaleField>,
}

impl Default for OwnNav {
    fn default() -> Self {
        OwnNav {
            planning: Planning::WithMargin,
            walls_changed: false,
            chose_beyond: false,
            stale: None,
        }
    }
}

impl OwnNav {
    /// A wall appeared or went on the map: the robot checks its path again.
    pub(super) fn walls_changed(&mut self) {
        self.walls_changed = true;
    }
}

/// See [`Navigator::stale`].
#[derive(Debug, Clone)]
struct StaleField {
    field: Arc<CostField>,
    /// Where the robot stood (world) and the planning level then.
    from: Vec2,
    planning: Planning,
}

/// Where a search from the robot starts, on grids brought up to date ([`Navigator::origin`]).
struct Origin {
    /// The distance grid.
    far: Arc<CoarseCosts>,
    /// The robot's cell on it, and the window of its cells that can be passable.
    start: Cell,
    window: (Cell, Cell),
    /// The robot's cell on the planning grid.
    near_start: Cell,
}

/// See [`Navigator::unreachable_memo`].
#[derive(Debug, Clone)]
struct UnreachableMemo {
    generation: u64,
    start: Cell,
    /// One bit per cell of the padded planning grid: reachable from `start`.
    reached: Vec<u64>,
}

impl Navigator {
    /// Grids on the map's `frame` with every cell blocked (nothing seen yet), for a robot of
    /// `radius_m` planned with `safety_margin_m` of clearance.
    pub(super) fn new(frame: GridFrame, radius_m: f64, safety_margin_m: f64) -> Self {
        Self {
            radius_m,
            safety_margin_m,
            coarse: CoarseCosts::blocked(frame, PLAN_FACTOR),
            coarse_dirty: Vec::new(),
            coarse_dirty_mark: vec![false; CoarseCosts::blocked(frame, PLAN_FACTOR).len()],
            far_dirty_mark: vec![false; CoarseCosts::blocked(frame, DISTANCE_FACTOR).len()],
            planning: Planning::WithMargin,
            travelled: Bitmap::filled(frame, false),
            far: Arc::new(CoarseCosts::blocked(frame, DISTANCE_FACTOR)),
            parked: Vec::new(),
            walls_changed: false,
            astar: AStar::default(),
            corridor: vec![false; CoarseCosts::blocked(frame, DISTANCE_FACTOR).len()],
            planning_generation: 0,
            unreachable_memo: None,
            stale: None,
            chose_beyond: false,
        }
    }

    /// A copy to go on with (every field; the buffer of distance changes left empty).
    pub(super) fn fork(&self) -> Self {
        Self {
            radius_m: self.radius_m,
            safety_margin_m: self.safety_margin_m,
            coarse: self.coarse.clone(),
            coarse_dirty: self.coarse_dirty.clone(),
            coarse_dirty_mark: self.coarse_dirty_mark.clone(),
            far_dirty_mark: self.far_dirty_mark.clone(),
            planning: self.planning,
            travelled: self.travelled.clone(),
            far: self.far.clone(),
            parked: self.parked.clone(),
            walls_changed: self.walls_changed,
            astar: self.astar.clone(),
            corridor: self.corridor.clone(),
            planning_generation: self.planning_generation,
            unreachable_memo: self.unreachable_memo.clone(),
            stale: self.stale.clone(),
            chose_beyond: self.chose_beyond,
        }
    }

    /// Takes on a robot's own part (see [`OwnNav`]): its planning level (the grids of the level
    /// left are kept), its walls flag and its bounded search's memory.
    pub(super) fn put_own(&mut self, own: OwnNav) {
        self.set_planning(own.planning);
        self.walls_changed = own.walls_changed;
        self.chose_beyond = own.chose_beyond;
        self.stale = own.stale;
    }

    /// The robot's own part, to keep until its next step (see [`Navigator::put_own`]).
    pub(super) fn take_own(&mut self) -> OwnNav {
        OwnNav {
            planning: self.planning,
            walls_changed: std::mem::take(&mut self.walls_changed),
            chose_beyond: std::mem::take(&mut self.chose_beyond),
            stale: self.stale.take(),
        }
    }

    /// The planning level in use.
    pub(super) fn planning(&self) -> Planning {
        self.planning
    }

    /// The planning grid (up to date with the map as of the last plan).
    pub(super) fn coarse(&self) -> &CoarseCosts {
        &self.coarse
    }

    /// Whether a cell became or stopped being occupied since this was last asked.
    pub(super) fn take_walls_changed(&mut self) -> bool {
        std::mem::take(&mut self.walls_changed)
    }

    /// A map update (`map` after `changes`): marks the planning cells the `changes` may have
    /// changed, in the grids of every planning level: those of the cells whose state or
    /// obstacle distance changed (which decides traversability and the wall cost). A planning cell's cost depends on its map
    /// cells' states, obstacle distances and travelled marks only.
    pub(super) fn map_updated(&mut self, map: &MapState, changes: &MapChanges) {
        let (flips, free) = (&changes.flips, &changes.free_changes);
        self.cells_changed(map.grid.frame, flips, map.distance_changes(), free);
    }

    /// [`Navigator::map_updated`] with the changes listed: the cells of `frame` in `flips`
    /// became or stopped being occupied, those in `distance_changes` changed their obstacle
    /// distance, those in `free_changes` changed otherwise.
    fn cells_changed(
        &mut self,
        frame: GridFrame,
        flips: &[u32],
        distance_changes: &[u32],
        free_changes: &[(u32, bool)],
    ) {
        self.walls_changed |= !flips.is_empty();
        let cells = flips
            .iter()
            .chain(distance_changes)
            .chain(free_changes.iter().map(|(i, _)| i));
        self.mark_planning_cells_at(frame, cells.copied(), |_| true);
    }

    /// Marks the map cells (of `frame`) on the segment `from`-`to` (world) travelled. They
    /// count only when planning the way the robot came (`Planning::Travelled`), so only that
    /// level's grids (in use or kept) have the new ones' planning cells marked for recomputing.
    pub(super) fn mark_travelled(&mut self, frame: GridFrame, from: Vec2, to: Vec2) {
        let mut new = Vec::new();
        let travelled = &mut self.travelled.data;
        walk_segment(
            grid_from_world(&frame, from),
            grid_from_world(&frame, to),
            |c| {
                if let Some(i) = frame.index(c) {
                    if !travelled[i] {
                        travelled[i] = true;
                        new.push((i as u32, true));
                    }
                }
                true
            },
        );
        if !new.is_empty() {
            self.mark_planning_cells_at(frame, new.iter().map(|&(i, _)| i), |level| {
                level == Planning::Travelled
            });
        }
    }

    /// How far from obstacles the robot's centre must stay on planned paths: its radius and
    /// the safety margin, or its radius alone while planning is relaxed (`Planning`).
    pub(super) fn inflation_m(&self) -> f64 {
        match self.planning {
            Planning::WithMargin => self.radius_m + self.safety_margin_m,
            Planning::NoMargin | Planning::Travelled => self.radius_m,
        }
    }

    /// Where the robot's centre may be on the map `seen` at the planning level in use.
    pub(super) fn traversability<'m>(&self, seen: Seen<'m>) -> Traversability<'m> {
        Traversability::new(&seen.map.occupancy, seen.obstacles, self.inflation_m())
    }

    /// Plans at `level` from now on: with its grids as last used, brought up to date with the
    /// map cells changed since (or, the first time, every planning cell recomputed); the grids
    /// of the level left are kept for its next use.
    pub(super) fn set_planning(&mut self, level: Planning) {
        if self.planning == level {
            return;
        }
        let left = self.planning;
        self.planning = level;
        self.planning_generation += 1;
        let restored = match self.parked.iter().position(|p| p.level == level) {
            Some(k) => self.parked.swap_remove(k),
            // (Every planning cell to recompute: the order does not matter.)
            None => ParkedGrids {
                level,
                coarse: self.coarse.clone(),
                far: self.far.clone(),
                dirty: (0..self.coarse_dirty_mark.len() as u32).collect(),
                dirty_mark: vec![true; self.coarse_dirty_mark.len()],
            },
        };
        let parked = ParkedGrids {
            level: left,
            coarse: std::mem::replace(&mut self.coarse, restored.coarse),
            far: std::mem::replace(&mut self.far, restored.far),
            dirty: std::mem::replace(&mut self.coarse_dirty, restored.dirty),
            dirty_mark: std::mem::replace(&mut self.coarse_dirty_mark, restored.dirty_mark),
        };
        self.parked.push(parked);
    }

    /// Marks the planning cells of the map cells `cells` (row-major indices of `frame`) in the
    /// grids of the planning levels `at` accepts.
    fn mark_planning_cells_at(
        &mut self,
        frame: GridFrame,
        cells: impl Iterator<Item = u32>,
        at: impl Fn(Planning) -> bool,
    ) {
        // (The constant, not the grid's field: a division by 2 is a shift, by a field a
        // division per cell.)
        debug_assert_eq!(self.coarse.factor, PLAN_FACTOR);
        let f = PLAN_FACTOR as i32;
        let (cw, ch) = (
            self.coarse.frame.width as i32,
            self.coarse.frame.height as i32,
        );
        let mark = |marks: &mut [bool], dirty: &mut Vec<u32>, i: usize| {
            if !marks[i] {
                marks[i] = true;
                dirty.push(i as u32);
            }
        };
        let current = at(self.planning);
        for i in cells {
            let c = frame.cell_of_index(i as usize);
            let (cx, cy) = (c.x.div_euclid(f), c.y.div_euclid(f));
            if cx < 0 || cy < 0 || cx >= cw || cy >= ch {
                continue;
            }
            let i = (cy * cw + cx) as usize;
            if current {
                mark(&mut self.coarse_dirty_mark, &mut self.coarse_dirty, i);
            }
            for p in self.parked.iter_mut().filter(|p| at(p.level)) {
                mark(&mut p.dirty_mark, &mut p.dirty, i);
            }
        }
    }

    /// Path costs from the robot (metres, plus a penalty for passing close to walls, so paths
    /// keep to the middle of corridors and doors) on the distance grid, stopping once every
    /// target (map cells) is settled; the path to the chosen one is then searched on the finer
    /// planning grid ([`Plan::waypoints_to`]). A robot closer to a wall than the inflation
    /// radius starts from the nearest passable cell (it then first drives out). The robot
    /// stands at `robot` (world) on the map `seen`.
    ///
    /// With `bound_m > 0` (an approximation, not the paper's: `ExploreConfig::distance_bound_m`)
    /// the search is bounded to paths of `bound_m`, and the targets beyond take their distances
    /// from the last search of everything reachable, made from where the robot stood at most
    /// `bound_m / 4` away; a target neither search reaches reads as unreachable. A robot farther
    /// away, another planning level, no target reached, or a last decision that headed beyond
    /// the bound ([`Self::chose`]) makes a new search of everything.
    pub(super) fn plan(
        &mut self,
        seen: Seen,
        robot_m: Vec2,
        targets: &[Cell],
        bound_m: f64,
    ) -> Plan {
        let origin = self.origin(seen, robot_m);
        #[cfg(test)]
        self.check_planning_grids(seen);
        let far_targets: Vec<Cell> = targets
            .iter()
            .filter_map(|c| origin.far.passable_near(*c, far_search_cells()))
            .collect();
        if bound_m > 0.0 && !targets.is_empty() {
            if self.chose_beyond {
                return self.plan_all_from(origin, robot_m);
            }
            let planning = self.planning;
            let stale = self
                .stale
                .as_ref()
                .filter(|s| s.planning == planning && (s.from - robot_m).norm() <= bound_m / 4.0)
                .map(|s| Arc::clone(&s.field));
            if let Some(stale) = stale {
                let field = dijkstra_padded_bounded(
                    origin.far.frame,
                    origin.start,
                    origin.far.padded(),
                    MAX_EXTRA,
                    origin.window,
                    bound_m,
                );
                let covered = far_targets
                    .iter()
                    .any(|c| field.distance_m(*c).is_some() || stale.distance_m(*c).is_some());
                if covered {
                    return Plan {
                        far: origin.far,
                        field: Arc::new(field),
                        stale: Some(stale),
                        near_start: origin.near_start,
                    };
                }
            }
            return self.plan_all_from(origin, robot_m);
        }
        let Origin {
            far,
            start,
            window,
            near_start,
        } = origin;
        let field = dijkstra_padded_within(
            far.frame,
            start,
            far.padded(),
            MAX_EXTRA,
            &far_targets,
            window,
        );
        Plan {
            far,
            field: Arc::new(field),
            stale: None,
            near_start,
        }
    }

    /// Path costs from the robot (at `robot_m`, world) to every reachable cell, kept for the
    /// bounded plans that follow (see [`Self::plan`]).
    pub(super) fn plan_all(&mut self, seen: Seen, robot_m: Vec2) -> Plan {
        let origin = self.origin(seen, robot_m);
        self.plan_all_from(origin, robot_m)
    }

    /// The grids brought up to date with the map `seen`, and where a search from the robot (at
    /// `robot_m`, world) starts on them.
    fn origin(&mut self, seen: Seen, robot_m: Vec2) -> Origin {
        self.refresh(seen);
        let radius_m = self.inflation_m();
        let robot = seen.map.frame.cell_from_world(robot_m);
        let far = Arc::clone(&self.far);
        Origin {
            start: start_cell(&far, robot, radius_m),
            far,
            window: self.far_window(seen.map),
            near_start: start_cell(&self.coarse, robot, radius_m),
        }
    }

    /// [`Self::plan_all`] from the robot's `origin` on the grids.
    fn plan_all_from(&mut self, origin: Origin, robot_m: Vec2) -> Plan {
        let Origin {
            far,
            start,
            window,
            near_start,
        } = origin;
        let field = Arc::new(dijkstra_padded_within(
            far.frame,
            start,
            far.padded(),
            MAX_EXTRA,
            &[],
            window,
        ));
        self.stale = Some(StaleField {
            field: Arc::clone(&field),
            from: robot_m,
            planning: self.planning,
        });
        Plan {
            far,
            field,
            stale: None,
            near_start,
        }
    }

    /// Notes the path length (m) of the goal a decision chose, for the next bounded plan
    /// (`bound_m`, 0 = none: see [`Self::plan`]).
    pub(super) fn chose(&mut self, distance_m: Option<f64>, bound_m: f64) {
        self.chose_beyond = bound_m > 0.0 && distance_m.is_some_and(|d| d > bound_m);
    }

    /// The planned path lengths (m) on the distance grid between the goals of `views`,
    /// row-major (`n * n`; 0 on the diagonal, infinite where no path leads): one search from each
    /// goal to the goals after it, its lengths used both ways. Call after [`Self::plan`] at the
    /// same decision on `map` (the grids are then up to date).
    pub(super) fn paths_between(&self, map: &LogOddsMap, views: &[CandidateView]) -> Vec<f64> {
        let (far, frame) = (&self.far, map.frame);
        let on_far: Vec<Option<Cell>> = views
            .iter()
            .map(|v| far.passable_near(frame.cell_from_world(v.goal), far_search_cells()))
            .collect();
        let window = self.far_window(map);
        crate::plan::dijkstra::lengths_between(&on_far, |from, to| {
            dijkstra_padded_within(far.frame, from, far.padded(), MAX_EXTRA, to, window)
        })
    }

    /// The planned path lengths (m) on the distance grid from each point of `from` (world) to
    /// the goal of each of `views`, row-major (`from.len() * views.len()`; infinite where no
    /// path leads): one search per point. Call after [`Self::plan`] at the same decision on
    /// `map` (the grids are then up to date).
    pub(super) fn paths_from(
        &self,
        map: &LogOddsMap,
        from: &[Vec2],
        views: &[CandidateView],
    ) -> Vec<f64> {
        let (far, frame) = (&self.far, map.frame);
        let targets: Vec<Option<Cell>> = views
            .iter()
            .map(|v| far.passable_near(frame.cell_from_world(v.goal), far_search_cells()))
            .collect();
        let wanted: Vec<Cell> = targets.iter().flatten().copied().collect();
        let window = self.far_window(map);
        let mut out = vec![f64::INFINITY; from.len() * views.len()];
        for (i, &p) in from.iter().enumerate() {
            let start = start_cell(far, frame.cell_from_world(p), self.inflation_m());
            if !far.passable(start) || wanted.is_empty() {
                continue;
            }
            let field =
                dijkstra_padded_within(far.frame, start, far.padded(), MAX_EXTRA, &wanted, window);
            for (j, t) in targets.iter().enumerate() {
                if let Some(d) = t.and_then(|c| field.distance_m(c)) {
                    out[i * views.len() + j] = d;
                }
            }
        }
        out
    }

    /// The distance grid's cells that can be passable: those under the box of the map's cells
    /// observed so far (a passable cell covers a traversable map cell, which is free, or one
    /// travelled and free) of `map`. The whole grid before the first scan.
    fn far_window(&self, map: &LogOddsMap) -> (Cell, Cell) {
        let f = DISTANCE_FACTOR as i32;
        match map.known_bounds {
            Some((lo, hi)) => (
                Cell::new(lo.x.div_euclid(f), lo.y.div_euclid(f)),
                Cell::new(hi.x.div_euclid(f), hi.y.div_euclid(f)),
            ),
            None => (
                Cell::new(0, 0),
                Cell::new(
                    self.far.frame.width as i32 - 1,
                    self.far.frame.height as i32 - 1,
                ),
            ),
        }
    }

    /// What the planning cells' costs are computed from on the map `seen` at the current
    /// planning level.
    fn planning_costs<'s>(&'s self, seen: Seen<'s>) -> PlanningCosts<'s> {
        let travelled = (self.planning == Planning::Travelled).then_some(&self.travelled.data[..]);
        PlanningCosts::new(
            &seen.map.occupancy,
            seen.obstacles,
            travelled,
            self.inflation_m(),
        )
    }

    /// With [`PLANNING_CHECKS`] on, asserts that the planning and distance grids in use are
    /// those computed from the whole map `seen`, and counts it for the level.
    #[cfg(test)]
    fn check_planning_grids(&self, seen: Seen) {
        if PLANNING_CHECKS.with(|c| c.get()).is_none() {
            return;
        }
        use crate::plan::coarse::coarse_costs;
        let costs = self.planning_costs(seen);
        let frame = seen.map.frame;
        let last = Cell::new(frame.width as i32 - 1, frame.height as i32 - 1);
        let whole = |factor| {
            coarse_costs(
                frame,
                factor,
                Cell::new(0, 0),
                last,
                |i| costs.traversable(i),
                |j| costs.extra(j),
            )
        };
        assert_eq!(self.coarse, whole(PLAN_FACTOR), "{:?}", self.planning);
        assert_eq!(*self.far, whole(DISTANCE_FACTOR), "{:?}", self.planning);
        // Every passable cell of the distance grid lies in the window its searches take.
        let (lo, hi) = self.far_window(seen.map);
        for y in 0..self.far.frame.height as i32 {
            for x in 0..self.far.frame.width as i32 {
                let c = Cell::new(x, y);
                let inside = x >= lo.x && y >= lo.y && x <= hi.x && y <= hi.y;
                assert!(
                    inside || !self.far.passable(c),
                    "{c:?} outside {lo:?}-{hi:?}"
                );
            }
        }
        PLANNING_CHECKS.with(|c| {
            let mut n = c.get().expect("on");
            n[self.planning as usize] += 1;
            c.set(Some(n));
        });
    }

    /// Brings the planning and distance grids up to date with the map `seen`.
    pub(super) fn refresh(&mut self, seen: Seen) {
        if self.coarse_dirty.is_empty() {
            return;
        }
        // (The grid taken out while the costs read the rest.)
        let empty = GridFrame::new(seen.map.frame.origin_m, 1.0, 0, 0);
        let mut coarse = std::mem::replace(&mut self.coarse, CoarseCosts::blocked(empty, 1));
        let costs = self.planning_costs(seen);
        coarse.recompute(
            seen.map.frame,
            &self.coarse_dirty,
            |i| costs.traversable(i),
            |j| costs.extra(j),
        );
        self.coarse = coarse;
        self.planning_generation += 1;
        // The distance grid's cells covering the changed planning cells.
        let k = (DISTANCE_FACTOR / PLAN_FACTOR) as usize;
        let (cw, fw, fh) = (
            self.coarse.frame.width as usize,
            self.far.frame.width as usize,
            self.far.frame.height as usize,
        );
        // (Each once: the planning cells under a distance cell are usually dirty together, and
        // recomputing it once per planning cell did the work four times. The order does not
        // matter: each cell's cost depends on the planning grid only.)
        let mut far_dirty: Vec<u32> = Vec::new();
        for (x, y) in self
            .coarse_dirty
            .iter()
            .map(|&i| ((i as usize % cw) / k, (i as usize / cw) / k))
            .filter(|&(x, y)| x < fw && y < fh)
        {
            let f = y * fw + x;
            if !self.far_dirty_mark[f] {
                self.far_dirty_mark[f] = true;
                far_dirty.push(f as u32);
            }
        }
        for &f in &far_dirty {
            self.far_dirty_mark[f as usize] = false;
        }
        // (From the planning grid, just brought up to date: 4 of its cells per distance cell
        // rather than 16 map cells, each a traversability test.)
        Arc::make_mut(&mut self.far).recompute_from(&self.coarse, &far_dirty);
        for &i in &self.coarse_dirty {
            self.coarse_dirty_mark[i as usize] = false;
        }
        self.coarse_dirty.clear();
    }

    /// Whether the rest of the path being followed (from the start of the segment the robot is
    /// on) crosses a planning cell that the map now shows impassable; the cells within one
    /// planning cell of the robot (at `robot`, world) are not tested (a robot close to a wall
    /// stands in one). The path is `follower`'s, the map `seen`.
    pub(super) fn path_blocked(
        &mut self,
        seen: Seen,
        follower: &PathFollower,
        robot: Vec2,
    ) -> bool {
        self.refresh(seen);
        let Some((start, rest)) = follower.current_segment() else {
            return false;
        };
        let grid = &self.coarse;
        let to_grid = |p: Vec2| grid_from_world(&grid.frame, p);
        let robot = grid.frame.cell_from_world(robot);
        let mut from = to_grid(start);
        let mut blocked = false;
        for &w in rest {
            let to = to_grid(w);
            walk_segment(from, to, |c| {
                let near_robot = (c.x - robot.x).abs() <= 1 && (c.y - robot.y).abs() <= 1;
                blocked = !near_robot && !grid.passable(c);
                !blocked
            });
            if blocked {
                return true;
            }
            from = to;
        }
        false
    }

    /// Waypoints (world) of the path to map cell `c`, searched on the planning grid from the
    /// robot's cell when `plan` was made (the grid has not changed since): first within a
    /// corridor three cells of the distance grid wide around the path `plan` found there, which
    /// touches few cells; over the whole grid if no path lies inside it.
    pub(super) fn waypoints_to(&mut self, plan: &Plan, c: Cell) -> Option<Vec<Vec2>> {
        let near = &self.coarse;
        let goal = near.passable_near(c, TARGET_SEARCH_CELLS)?;
        let start = plan.near_start;
        // A goal that a failed search of the whole grid from this start did not reach.
        let generation = self.planning_generation;
        if let Some(m) = self
            .unreachable_memo
            .as_ref()
            .filter(|m| m.generation == generation && m.start == start)
        {
            let i = padded_index(&near.frame, goal);
            if m.reached
                .get(i / 64)
                .is_none_or(|w| w & (1 << (i % 64)) == 0)
            {
                return None;
            }
        }
        let mut found = None;
        if let Some(far_path) = plan.far_path(c) {
            let frame = plan.far.frame;
            let mut marked = Vec::with_capacity(far_path.len() * 3);
            for p in &far_path {
                for n in std::iter::once(*p).chain(p.neighbours8()) {
                    if let Some(i) = frame.index(n) {
                        if !self.corridor[i] {
                            self.corridor[i] = true;
                            marked.push(i);
                        }
                    }
                }
            }
            let corridor = &self.corridor;
            found =
                self.astar
                    .path_within(near.frame, start, near.padded(), MAX_EXTRA, goal, |n| {
                        frame
                            .index(Cell::new(n.x >> FAR_SHIFT, n.y >> FAR_SHIFT))
                            .is_some_and(|i| corridor[i])
                    });
            for i in marked {
                self.corridor[i] = false;
            }
        }
        let (path, _) = match found {
            Some(p) => p,
            None => {
                let mut reached = Vec::new();
                let found = self.astar.path_or_reached(
                    near.frame,
                    start,
                    near.padded(),
                    MAX_EXTRA,
                    goal,
                    &mut reached,
                );
                if found.is_none() && !reached.is_empty() {
                    let mut bits = vec![0u64; near.padded().len().div_ceil(64)];
                    for i in reached {
                        bits[i as usize / 64] |= 1 << (i % 64);
                    }
                    self.unreachable_memo = Some(UnreachableMemo {
                        generation,
                        start,
                        reached: bits,
                    });
                }
                found?
            }
        };
        Some(waypoints_by(&path, &near.frame, |n| near.passable(n)))
    }

    /// Waypoints of a path from the robot (at `robot`, world) to map cell `c` on the map
    /// `seen`: as for a decision, a distance search (stopping at `c`) on the distance grid, then
    /// the planning grid's search within a corridor around its path ([`Self::waypoints_to`]).
    /// A search of the whole planning grid, guided by the straight-line distance only, took 6 %
    /// of a run (its wall penalty leaves the heuristic far below the true cost).
    pub(super) fn path_to(&mut self, seen: Seen, robot: Vec2, c: Cell) -> Option<Vec<Vec2>> {
        let plan = self.plan(seen, robot, &[c], 0.0);
        self.waypoints_to(&plan, c)
    }
}

/// The map as the navigator reads it.
pub(super) fn seen<'m>(map: &'m LogOddsMap, obstacles: &'m ObstacleDistance) -> Seen<'m> {
    Seen { map, obstacles }
}

/// A robot that stays within this radius...
pub(super) const STILL_RADIUS_M: f64 = 0.5;

/// ...for this many progress timeouts is stuck.
pub(super) const STILL_FACTOR: f64 = 3.0;

/// Map cells per side of a planning cell (0.05 m map: 0.1 m planning grid), on which the
/// robot's paths are searched.
pub(super) const PLAN_FACTOR: u32 = 2;

/// Map cells per side of a cell of the grid on which the distances to all candidates are
/// searched (0.05 m map: 0.2 m), a multiple of `PLAN_FACTOR`. That search covers most of the
/// known building at every decision; on the coarser grid it touches a quarter of the cells.
/// The grid connects whatever the planning grid connects (a cell is passable when any of its
/// map cells is traversable), so no candidate reachable by a path is lost.
pub(super) const DISTANCE_FACTOR: u32 = 4;

/// Planning cells per side of a distance cell, as a shift: a planning cell's distance cell is
/// its coordinates shifted right (arithmetically: `div_euclid` by the power of two, without
/// the division's fix-ups for negative values, in A*'s test of every neighbour).
const FAR_SHIFT: u32 = (DISTANCE_FACTOR / PLAN_FACTOR).trailing_zeros();
const _: () = assert!(
    DISTANCE_FACTOR.is_multiple_of(PLAN_FACTOR)
        && (DISTANCE_FACTOR / PLAN_FACTOR).is_power_of_two()
);

/// How far (planning cells) a goal may be moved to reach a passable planning cell.
pub(super) const TARGET_SEARCH_CELLS: i32 = 4;

/// Largest extra cost of entering a cell near a wall (cost units, 10 per straight step).
pub(super) const MAX_EXTRA: u32 = 10;

pub(super) fn far_search_cells() -> i32 {
    let (cells, f) = (
        TARGET_SEARCH_CELLS * PLAN_FACTOR as i32,
        DISTANCE_FACTOR as i32,
    );
    (cells + f - 1) / f
}

/// What a planning cell's cost is computed from, per map cell (row-major index): whether the
/// robot's centre may be there at the planning level, and the extra cost of passing close to
/// walls.
struct PlanningCosts<'a> {
    trav: Traversability<'a>,
    /// The cells travelled, when they count as traversable (free ones).
    travelled: Option<&'a [bool]>,
    occupancy: &'a [Occupancy],
    obstacles: &'a [f32],
    /// The extra cost by obstacle distance, in steps of 1/8 cell (the field is capped, so the
    /// table is small) instead of evaluated per cell.
    table: Vec<u32>,
}

impl<'a> PlanningCosts<'a> {
    const STEPS_PER_CELL: f32 = 8.0;

    fn new(
        grid: &'a OccupancyGrid,
        obstacles: &'a ObstacleDistance,
        travelled: Option<&'a [bool]>,
        radius_m: f64,
    ) -> Self {
        const WALL_BAND_M: f64 = 0.3;
        let res = grid.frame.resolution_m;
        let table = (0..=(obstacles.cap_cells as usize * 8 + 1))
            .map(|k| {
                let d_cells = k as f64 / Self::STEPS_PER_CELL as f64;
                let beyond = (d_cells * res - radius_m) / WALL_BAND_M;
                if beyond >= 1.0 {
                    0
                } else {
                    (MAX_EXTRA as f64 * (1.0 - beyond.max(0.0))).round() as u32
                }
            })
            .collect();
        Self {
            trav: Traversability::new(grid, obstacles, radius_m),
            travelled,
            occupancy: &grid.data,
            obstacles: &obstacles.data,
            table,
        }
    }

    fn traversable(&self, i: usize) -> bool {
        self.trav.at_index(i)
            || self
                .travelled
                .is_some_and(|t| t[i] && self.occupancy[i] == Occupancy::Free)
    }

    fn extra(&self, j: usize) -> u32 {
        let last = self.table.len() - 1;
        self.table[((self.obstacles[j] * Self::STEPS_PER_CELL) as usize).min(last)]
    }
}

#[cfg(test)]
thread_local! {
    /// When on (`Some`), every plan asserts that the grids it uses are those computed from the
    /// whole map, counted per planning level.
    pub(super) static PLANNING_CHECKS: std::cell::Cell<Option<[u64; 3]>> =
        const { std::cell::Cell::new(None) };
}

/// The grids of a planning level not in use (see `Navigator::parked`).
#[derive(Debug, Clone)]
pub(super) struct ParkedGrids {
    pub(super) level: Planning,
    coarse: CoarseCosts,
    far: Arc<CoarseCosts>,
    /// The planning cells to recompute before the grids are used again, each marked.
    dirty: Vec<u32>,
    dirty_mark: Vec<bool>,
}

/// How permissive path planning is: the rungs of the decision's last resorts (`Explorer::chosen`), in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Planning {
    /// Paths keep the robot's radius and the safety margin from the map's obstacles.
    WithMargin,
    /// The robot's radius only.
    NoMargin,
    /// The robot's radius, or any free map cell the robot has travelled.
    Travelled,
}

impl Planning {
    /// The next rung, `None` on the last.
    pub(super) fn looser(self) -> Option<Self> {
        match self {
            Self::WithMargin => Some(Self::NoMargin),
            Self::NoMargin => Some(Self::Travelled),
            Self::Travelled => None,
        }
    }
}

/// The distances to the candidates, and what is needed to find the path to one of them.
#[derive(Clone)]
pub(super) struct Plan {
    /// The distance grid and the search over it.
    pub(super) far: Arc<CoarseCosts>,
    pub(super) field: Arc<CostField>,
    /// With a bounded search (see [`Navigator::plan`]), the earlier search the cells beyond
    /// its bound take their distances from.
    stale: Option<Arc<CostField>>,
    /// The robot's cell on the planning grid.
    pub(super) near_start: Cell,
}

impl Plan {
    /// Path length (with the wall penalty) to the map cell `c`, `None` if unreachable.
    pub(super) fn distance_m(&self, c: Cell) -> Option<f64> {
        let c = self.far.passable_near(c, far_search_cells())?;
        self.field
            .distance_m(c)
            .or_else(|| self.stale.as_ref()?.distance_m(c))
    }

    /// Whether every distance is final for every cell (a search of everything reachable).
    pub(super) fn is_complete(&self) -> bool {
        self.field.is_complete()
    }

    /// Whether every distance is searched from where the robot stands (no bound, or nothing
    /// reachable beyond it).
    pub(super) fn is_exact(&self) -> bool {
        self.stale.is_none() || self.field.is_complete()
    }

    /// Whether the distance to map cell `c` is searched from where the robot stands: within
    /// the bound of a bounded search (the path to it is then found there too).
    pub(super) fn is_exact_at(&self, c: Cell) -> bool {
        self.is_exact()
            || self
                .far
                .passable_near(c, far_search_cells())
                .is_some_and(|c| self.field.distance_m(c).is_some())
    }

    /// The path to the map cell `c` on the distance grid.
    pub(super) fn far_path(&self, c: Cell) -> Option<Vec<Cell>> {
        self.field
            .path_to(self.far.passable_near(c, far_search_cells())?)
    }
}

/// The cell of `grid` a path from the robot (in map cell `robot`) starts from: its own, or the
/// nearest passable one when it stands closer to a wall than the inflation radius `radius_m`
/// (it then first drives out).
pub(super) fn start_cell(grid: &CoarseCosts, robot: Cell, radius_m: f64) -> Cell {
    let c = grid.coarse_of(robot);
    let r = ((2.0 * radius_m) / grid.frame.resolution_m).ceil() as i32 + 1;
    if grid.passable(c) {
        c
    } else {
        nearest_by(c, r, |n| grid.passable(n)).unwrap_or(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two rooms (5 m by 3 m in all, 0.05 m cells) joined by a gap of `gap_cells` (0: none) in
    /// the wall between them (0.1 m thick: a planning cell), fully known.
    fn two_rooms(gap_cells: i32) -> LogOddsMap {
        let frame = GridFrame::new(Vec2::new(0.0, 0.0), 0.05, 100, 60);
        let mut map = LogOddsMap::new(frame);
        for y in 0..60 {
            for x in 0..100 {
                let border = x == 0 || y == 0 || x == 99 || y == 59;
                let wall = (50..52).contains(&x) && !(30..30 + gap_cells).contains(&y);
                let i = frame.index(Cell::new(x, y)).unwrap();
                map.occupancy.data[i] = if border || wall {
                    Occupancy::Occupied
                } else {
                    Occupancy::Free
                };
            }
        }
        map.known_bounds = Some((Cell::new(0, 0), Cell::new(99, 59)));
        map
    }

    /// Tells `nav` of the map update from `old` to `map`, as the explorer does.
    fn update(
        nav: &mut Navigator,
        obstacles: &mut ObstacleDistance,
        old: &LogOddsMap,
        map: &LogOddsMap,
    ) {
        let (mut flips, mut free_changes) = (Vec::new(), Vec::new());
        for (i, (a, b)) in old
            .occupancy
            .data
            .iter()
            .zip(&map.occupancy.data)
            .enumerate()
        {
            if a == b {
                continue;
            }
            if *a == Occupancy::Occupied || *b == Occupancy::Occupied {
                flips.push(i as u32);
            } else {
                free_changes.push((i as u32, true));
            }
        }
        let mut distance_changes = Vec::new();
        obstacles.update_reporting(&map.occupancy, &flips, &mut distance_changes);
        nav.cells_changed(map.frame, &flips, &distance_changes, &free_changes);
    }

    /// The navigator alone, on maps made by hand: a path through a wide gap at every level, a
    /// gap wider than the robot but not its margin only without the margin, a gap narrower
    /// than the robot only the way the robot came, none where the wall is closed; every plan
    /// made on grids brought up to date incrementally that equal those of the whole map.
    #[test]
    fn the_navigator_plans_through_the_gaps_its_levels_allow() {
        PLANNING_CHECKS.with(|c| c.set(Some([0; 3])));
        let unknown = LogOddsMap::new(two_rooms(0).frame);
        let frame = unknown.frame;
        // (A robot of radius 0.1 m, planned with 0.1 m of margin.)
        let mut nav = Navigator::new(frame, 0.1, 0.1);
        let mut obstacles = ObstacleDistance::new(frame, 8);
        let (robot, to) = (Vec2::new(1.0, 1.525), Vec2::new(4.0, 1.525));
        let goal = frame.cell_from_world(to);
        let reaches = |nav: &mut Navigator, map: &LogOddsMap, obstacles: &ObstacleDistance| {
            let plan = nav.plan(Seen { map, obstacles }, robot, &[goal], 0.0);
            let wps = nav.waypoints_to(&plan, goal);
            // (The coarser distance grid may connect what the planning grid does not.)
            assert!(wps.is_none() || plan.distance_m(goal).is_some());
            wps.inspect(|w| assert!((w[w.len() - 1] - to).norm() < 0.2, "{w:?}"))
                .is_some()
        };
        let wide = two_rooms(20);
        update(&mut nav, &mut obstacles, &unknown, &wide);
        assert!(nav.take_walls_changed() && !nav.take_walls_changed());
        assert!(reaches(&mut nav, &wide, &obstacles));
        // 0.3 m: the robot's clearance is 0.15 m at most.
        let narrow = two_rooms(6);
        update(&mut nav, &mut obstacles, &wide, &narrow);
        assert!(!reaches(&mut nav, &narrow, &obstacles));
        nav.set_planning(Planning::NoMargin);
        assert!(reaches(&mut nav, &narrow, &obstacles));
        // 0.1 m: the robot came through it (its map has narrowed since).
        let slit = two_rooms(2);
        update(&mut nav, &mut obstacles, &narrow, &slit);
        assert!(!reaches(&mut nav, &slit, &obstacles));
        nav.set_planning(Planning::Travelled);
        assert!(!reaches(&mut nav, &slit, &obstacles));
        nav.mark_travelled(frame, robot, to);
        assert!(reaches(&mut nav, &slit, &obstacles));
        nav.set_planning(Planning::WithMargin);
        assert!(!reaches(&mut nav, &slit, &obstacles));
        let closed = two_rooms(0);
        update(&mut nav, &mut obstacles, &slit, &closed);
        for level in [
            Planning::NoMargin,
            Planning::Travelled,
            Planning::WithMargin,
        ] {
            nav.set_planning(level);
            assert!(!reaches(&mut nav, &closed, &obstacles), "{level:?}");
        }
        let checks = PLANNING_CHECKS.with(|c| c.replace(None)).expect("on");
        assert_eq!(checks, [4, 3, 3]);
    }

    /// A plan bounded by distance: the first searches everything; the next, within a quarter
    /// of the bound of where that one was made, gives the targets within the bound their
    /// distances from where the robot stands and the farther ones theirs from the earlier
    /// search; farther away, everything is searched again.
    #[test]
    fn a_bounded_plan_takes_far_distances_from_the_last_whole_search() {
        let map = two_rooms(20);
        let frame = map.frame;
        let mut nav = Navigator::new(frame, 0.1, 0.1);
        let mut obstacles = ObstacleDistance::new(frame, 8);
        update(&mut nav, &mut obstacles, &LogOddsMap::new(frame), &map);
        let seen = Seen {
            map: &map,
            obstacles: &obstacles,
        };
        let (near, far) = (
            frame.cell_from_world(Vec2::new(1.6, 1.0)),
            frame.cell_from_world(Vec2::new(4.5, 1.0)),
        );
        let targets = [near, far];
        let bound_m = 2.0;
        let at = |x: f64| Vec2::new(x, 1.0);
        let exact = |nav: &mut Navigator, x: f64| nav.plan(seen, at(x), &targets, 0.0);
        // (Each case: where the robot stands, and from where the far target's distance is.)
        for (x, far_from, stale) in [(0.5, 0.5, false), (0.9, 0.5, true), (1.1, 1.1, false)] {
            let plan = nav.plan(seen, at(x), &targets, bound_m);
            let (here, then) = (exact(&mut nav, x), exact(&mut nav, far_from));
            assert_eq!(plan.distance_m(near), here.distance_m(near), "{x}");
            assert!(plan.is_exact_at(near), "{x}");
            assert_eq!(plan.distance_m(far), then.distance_m(far), "{x}");
            assert_eq!(plan.is_exact_at(far), !stale, "{x}");
            // (From where the robot stands the far target is nearer.)
            assert_eq!(plan.distance_m(far) == here.distance_m(far), !stale, "{x}");
            assert_eq!(plan.is_exact(), !stale, "{x}");
            assert!(plan.distance_m(far).unwrap() > bound_m, "{x}");
        }
    }

    #[test]
    fn a_planning_cell_shifted_is_in_its_distance_cell() {
        let k = (DISTANCE_FACTOR / PLAN_FACTOR) as i32;
        for n in [i32::MIN, -9, -5, -4, -3, -2, -1, 0, 1, 2, 3, 4, 7, i32::MAX] {
            assert_eq!(n >> FAR_SHIFT, n.div_euclid(k), "{n}");
        }
    }
}
