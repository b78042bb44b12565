//! Frontiers: chains of free cells that touch unknown space, and their middle cells.
//!
//! A *frontier cell* is a `Free` cell with at least one `Unknown` **4-neighbour** (cells outside
//! the grid are not unknown). A *frontier* is an **8-connected** component of frontier cells.
//! Its candidate location is its middle cell: from any cell, a BFS (8-connected, unit steps)
//! inside the chain finds the farthest cell `a`; a second BFS from `a` finds the farthest `b` at
//! depth `L`; the candidate is the cell at depth `L / 2` on the BFS path from `b` back to `a`.
//!
//! [`FrontierTracker`] keeps the frontier cells and their chains up to date from each map
//! update's list of changed cells, so a decision labels again only the chains that changed, and
//! reuses the middle cell of every chain unchanged since the last decision; it is property-tested
//! equal to a full detection ([`detect_frontiers`]). [`frontiers_where`] (for `frontier_clearance_m`) drops the cells that
//! fail a predicate and splits each frontier into the chains left, each with its own middle cell;
//! both share one component search.

use crate::grid::{Cell, Occupancy, OccupancyGrid};
use std::collections::{BTreeMap, VecDeque};

/// A hash map that is looked up only, never iterated, so its order cannot reach a result (the
/// kernel's clippy configuration forbids hash maps elsewhere).
#[allow(clippy::disallowed_types)]
type LookupMap<K, V> = std::collections::HashMap<K, V>;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrontierConfig {
    /// Frontiers with fewer cells are dropped.
    pub min_cells: usize,
}

impl Default for FrontierConfig {
    fn default() -> Self {
        Self { min_cells: 5 }
    }
}

impl FrontierConfig {
    /// A minimal size given in metres of chain (cells = metres / resolution, at least 1).
    pub fn with_min_length_m(min_length_m: f64, resolution_m: f64) -> Self {
        Self {
            min_cells: ((min_length_m / resolution_m).ceil().max(1.0)) as usize,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frontier {
    /// The chain's cells, in row-major order.
    pub cells: Vec<Cell>,
    /// The middle cell of the chain.
    pub candidate: Cell,
    /// Number of cells.
    pub size: usize,
}

/// Detects all frontiers of `grid`, in row-major order of their first cell.
pub fn detect_frontiers(grid: &OccupancyGrid, cfg: &FrontierConfig) -> Vec<Frontier> {
    if grid.frame.is_empty() {
        return Vec::new();
    }
    let max = Cell::new(grid.width() as i32 - 1, grid.height() as i32 - 1);
    detect_frontiers_in(grid, Cell::new(0, 0), max, cfg)
}

/// Like [`detect_frontiers`], looking only at cells inside the inclusive box `[lo, hi]` (e.g. the
/// map's known bounds: outside it there is no free cell). The box is clipped to the grid.
pub fn detect_frontiers_in(
    grid: &OccupancyGrid,
    lo: Cell,
    hi: Cell,
    cfg: &FrontierConfig,
) -> Vec<Frontier> {
    let gw = grid.width() as i32;
    let gh = grid.height() as i32;
    if gw == 0 || gh == 0 {
        return Vec::new();
    }
    let x0 = lo.x.clamp(0, gw - 1);
    let y0 = lo.y.clamp(0, gh - 1);
    let x1 = hi.x.clamp(0, gw - 1);
    let y1 = hi.y.clamp(0, gh - 1);
    if x1 < x0 || y1 < y0 {
        return Vec::new();
    }
    let bw = (x1 - x0 + 1) as usize;
    let bh = (y1 - y0 + 1) as usize;
    let data = &grid.data;
    let gwu = gw as usize;
    let unknown = |x: i32, y: i32| -> bool {
        x >= 0
            && y >= 0
            && x < gw
            && y < gh
            && data[y as usize * gwu + x as usize] == Occupancy::Unknown
    };
    // 0 = not a frontier cell, 1 = frontier cell not yet labelled, 2 = labelled.
    let mut mark = vec![0u8; bw * bh];
    for by in 0..bh {
        let y = y0 + by as i32;
        let row = y as usize * gwu;
        for bx in 0..bw {
            let x = x0 + bx as i32;
            if data[row + x as usize] == Occupancy::Free
                && (unknown(x + 1, y)
                    || unknown(x - 1, y)
                    || unknown(x, y + 1)
                    || unknown(x, y - 1))
            {
                mark[by * bw + bx] = 1;
            }
        }
    }
    let mut frontiers = Vec::new();
    chains(
        &mut mark,
        bw,
        bh,
        Cell::new(x0, y0),
        cfg.min_cells,
        &mut frontiers,
    );
    frontiers
}

/// Appends to `out` the 8-connected chains of the cells marked 1 in `mark` (a `bw` x `bh` box
/// whose cell (0, 0) is `origin`), in row-major order of their first cell, dropping chains of
/// fewer than `min_cells`; marks them 2.
fn chains(
    mark: &mut [u8],
    bw: usize,
    bh: usize,
    origin: Cell,
    min_cells: usize,
    out: &mut Vec<Frontier>,
) {
    let (x0, y0) = (origin.x, origin.y);
    let mut queue = VecDeque::new();
    for start in 0..mark.len() {
        if mark[start] != 1 {
            continue;
        }
        // Collect the component.
        let mut comp: Vec<usize> = vec![start];
        mark[start] = 2;
        queue.clear();
        queue.push_back(start);
        while let Some(i) = queue.pop_front() {
            let (bx, by) = ((i % bw) as i32, (i / bw) as i32);
            for (dx, dy) in NEIGHBOURS8 {
                let (nx, ny) = (bx + dx, by + dy);
                if nx < 0 || ny < 0 || nx >= bw as i32 || ny >= bh as i32 {
                    continue;
                }
                let j = ny as usize * bw + nx as usize;
                if mark[j] == 1 {
                    mark[j] = 2;
                    comp.push(j);
                    queue.push_back(j);
                }
            }
        }
        if comp.len() < min_cells.max(1) {
            continue;
        }
        comp.sort_unstable();
        let middle = middle_cell(&comp, bw);
        let to_cell = |i: usize| Cell::new(x0 + (i % bw) as i32, y0 + (i / bw) as i32);
        out.push(Frontier {
            size: comp.len(),
            candidate: to_cell(middle),
            cells: comp.into_iter().map(to_cell).collect(),
        });
    }
}

/// The parts of `frontiers` made of cells that satisfy `keep`: the kept cells of each frontier
/// split into 8-connected chains, those of fewer than `cfg.min_cells` dropped, each with its own
/// middle cell (e.g. frontier cells too close to a wall for the robot, as explorers that look
/// for frontiers in an inflated costmap see them). A frontier whose cells are all kept is
/// returned as it is.
pub(crate) fn frontiers_where(
    frontiers: Vec<Frontier>,
    cfg: &FrontierConfig,
    keep: impl Fn(Cell) -> bool,
) -> Vec<Frontier> {
    let mut out = Vec::with_capacity(frontiers.len());
    for f in frontiers {
        let kept: Vec<Cell> = f.cells.iter().copied().filter(|c| keep(*c)).collect();
        if kept.len() == f.cells.len() {
            out.push(f);
            continue;
        }
        let Some(first) = kept.first() else {
            continue;
        };
        let (mut lo, mut hi) = (*first, *first);
        for c in &kept {
            lo = Cell::new(lo.x.min(c.x), lo.y.min(c.y));
            hi = Cell::new(hi.x.max(c.x), hi.y.max(c.y));
        }
        let bw = (hi.x - lo.x + 1) as usize;
        let bh = (hi.y - lo.y + 1) as usize;
        let mut mark = vec![0u8; bw * bh];
        for c in &kept {
            mark[(c.y - lo.y) as usize * bw + (c.x - lo.x) as usize] = 1;
        }
        chains(&mut mark, bw, bh, lo, cfg.min_cells, &mut out);
    }
    out
}

/// Frontiers kept up to date as the map changes, so that detecting the frontiers of a decision
/// touches only what changed near the robot instead of the whole map. Gives exactly the result
/// of [`detect_frontiers`] on the same grid.
///
/// Every frontier cell belongs to a tracked *component* (an 8-connected chain, kept whatever
/// its size) with its cells and, once asked for, its middle cell. A map update marks the
/// components that lost a cell, and lists the cells that became frontier cells; a detection
/// dissolves the marked components and those next to a new cell, labels the chains of their
/// cells and the new ones again, and lists every component in row-major order of its first
/// cell. The components far from the changes, most of a large building's, are not looked at
/// beyond copying them into the list.
#[derive(Debug, Clone, Default)]
pub(crate) struct FrontierTracker {
    /// Per cell: [`FRONTIER`] when it is a frontier cell, plus [`LABELLED`] while the component
    /// search has reached it (never between calls).
    state: Vec<u8>,
    /// Per cell: the slot in `comps` of the component holding it, or [`NO_COMPONENT`] (not a
    /// frontier cell at the last detection, or one that became a frontier cell since).
    owner: Vec<u32>,
    /// The components of the last detection, by slot (`None`: a free slot, listed in `free`).
    comps: Vec<Option<Component>>,
    free: Vec<u32>,
    /// Slot of each component by the row-major index of its first cell: the order of the
    /// frontiers.
    order: BTreeMap<u32, u32>,
    /// Slots of components that lost a cell since the last detection (repeats allowed).
    dirty: Vec<u32>,
    /// Cells that became frontier cells since the last detection (repeats allowed, and cells
    /// that stopped being one again).
    fresh: Vec<u32>,
    /// The width of the grid the cells' indices are for.
    width: u32,
}

/// A frontier chain kept by [`FrontierTracker`].
#[derive(Debug, Clone)]
struct Component {
    /// Its cells in row-major order.
    cells: Vec<Cell>,
    /// Its middle cell, once computed.
    middle: Option<Cell>,
    /// Listed in [`FrontierTracker::dirty`] since the last detection.
    dirty: bool,
}

/// [`FrontierTracker::state`]: a frontier cell.
const FRONTIER: u8 = 1;
/// [`FrontierTracker::state`]: reached by the component search.
const LABELLED: u8 = 2;
/// [`FrontierTracker::owner`]: no component.
const NO_COMPONENT: u32 = u32::MAX;

impl FrontierTracker {
    /// A tracker of `grid`'s frontier cells, from a full scan of the grid.
    pub(crate) fn new(grid: &OccupancyGrid) -> Self {
        let n = grid.data.len();
        let mut t = Self {
            state: vec![0; n],
            owner: vec![NO_COMPONENT; n],
            width: grid.width(),
            ..Default::default()
        };
        // (Row by row, as `update` of every cell would find them, without its five tests per
        // cell: the first update of a run scans a map that is nearly all unknown.)
        let w = grid.width() as usize;
        let mut row = vec![false; w];
        for y in (0..grid.height() as usize).filter(|_| w > 0) {
            frontier_row(grid, y, 0, w - 1, &mut row);
            for (x, &f) in row.iter().enumerate() {
                if f {
                    t.state[y * w + x] = FRONTIER;
                    t.fresh.push((y * w + x) as u32);
                }
            }
        }
        t
    }

    /// Brings the frontier cells up to date after the cells at `changed` (row-major indices of
    /// `grid`, in any order, repeats allowed) changed state. A grid of another size starts over.
    pub(crate) fn update(&mut self, grid: &OccupancyGrid, changed: impl IntoIterator<Item = u32>) {
        if !self.is_for(grid) {
            *self = Self::new(grid);
            return;
        }
        let w = grid.width() as i64;
        let h = grid.height() as i64;
        let (data, wu) = (&grid.data[..], w as usize);
        let unknown = |j: usize| data[j] == Occupancy::Unknown;
        // (In u32: a row-major index fits, as does the width.)
        let w32 = (w as u32).max(1);
        for i in changed {
            let (x, y) = ((i % w32) as i64, (i / w32) as i64);
            // Two cells or more from the map's edge, the five cells and their 4-neighbours all
            // lie in the map: read by their indices, without bounds tests.
            let interior = x >= 2 && y >= 2 && x < w - 2 && y < h - 2;
            for (dx, dy) in [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)] {
                let (nx, ny) = (x + dx, y + dy);
                if !interior && (nx < 0 || ny < 0 || nx >= w || ny >= h) {
                    continue;
                }
                let j = (ny * w + nx) as usize;
                let now = if interior {
                    data[j] == Occupancy::Free
                        && (unknown(j + 1) || unknown(j - 1) || unknown(j + wu) || unknown(j - wu))
                } else {
                    is_frontier_cell(grid, Cell::new(nx as i32, ny as i32))
                };
                let was = self.state[j] & FRONTIER != 0;
                if now == was {
                    continue;
                }
                if now {
                    self.state[j] |= FRONTIER;
                    self.fresh.push(j as u32);
                } else {
                    self.state[j] &= !FRONTIER;
                    self.mark_dirty(self.owner[j]);
                }
            }
        }
    }

    /// Whether the tracker's cells are those of `grid` (a grid of another size starts over).
    fn is_for(&self, grid: &OccupancyGrid) -> bool {
        grid.data.len() == self.state.len() && grid.width() == self.width
    }

    /// Lists the component in `slot` (if any) as changed.
    fn mark_dirty(&mut self, slot: u32) {
        if let Some(Some(c)) = self.comps.get_mut(slot as usize) {
            if !c.dirty {
                c.dirty = true;
                self.dirty.push(slot);
            }
        }
    }

    /// The frontiers of `grid` (which must be the grid of the last update), as
    /// [`detect_frontiers`] finds them.
    pub(crate) fn detect(&mut self, grid: &OccupancyGrid, cfg: &FrontierConfig) -> Vec<Frontier> {
        if !self.is_for(grid) {
            *self = Self::new(grid);
        }
        let w = grid.width() as usize;
        let index_of = |c: Cell| c.y as usize * w + c.x as usize;
        let (seeds, mut dissolved) = self.dissolve_changed(grid);
        self.label(grid, &seeds, &mut dissolved);
        // Every component of enough cells, in order, with its middle cell.
        let mut frontiers = Vec::new();
        let mut indices: Vec<usize> = Vec::new();
        for &slot in self.order.values() {
            let Some(comp) = self.comps[slot as usize].as_mut() else {
                continue;
            };
            if comp.cells.len() < cfg.min_cells.max(1) {
                continue;
            }
            let middle = *comp.middle.get_or_insert_with(|| {
                // (A cell's place in the component from a table over the component's box, not
                // over the whole map; by binary search when the box is much larger than the
                // component, a long diagonal chain.)
                indices.clear();
                indices.extend(comp.cells.iter().map(|c| index_of(*c)));
                grid.frame.cell_of_index(middle_cell_boxed(&indices, w))
            });
            frontiers.push(Frontier {
                size: comp.cells.len(),
                candidate: middle,
                cells: comp.cells.clone(),
            });
        }
        frontiers
    }

    /// Dissolves the components that changed since the last detection (lost a cell, or have a
    /// new frontier cell next to them): returns the cells to label again (their cells still
    /// frontier cells, and the new ones) and the dissolved components by first cell.
    fn dissolve_changed(
        &mut self,
        grid: &OccupancyGrid,
    ) -> (Vec<usize>, LookupMap<u32, Component>) {
        let w = grid.width() as i64;
        let h = grid.height() as i64;
        let index_of = |c: Cell| c.y as usize * w as usize + c.x as usize;
        // A new frontier cell next to a component's cell joins it: the component changed.
        let fresh = std::mem::take(&mut self.fresh);
        for &i in &fresh {
            let i = i as usize;
            if self.state[i] & FRONTIER == 0 || self.owner[i] != NO_COMPONENT {
                continue;
            }
            let (x, y) = (i as i64 % w, i as i64 / w);
            for (dx, dy) in NEIGHBOURS8 {
                let (nx, ny) = (x + dx as i64, y + dy as i64);
                if nx >= 0 && ny >= 0 && nx < w && ny < h {
                    self.mark_dirty(self.owner[(ny * w + nx) as usize]);
                }
            }
        }
        // The changed components dissolved: their cells still frontier cells, and the new
        // ones, are labelled again. (The dissolved ones kept by first cell: a chain found again
        // with the same cells keeps its middle cell.)
        let mut seeds: Vec<usize> = Vec::new();
        let mut dissolved: LookupMap<u32, Component> = LookupMap::new();
        for slot in std::mem::take(&mut self.dirty) {
            let Some(comp) = self.comps[slot as usize].take() else {
                continue;
            };
            self.free.push(slot);
            let first = index_of(comp.cells[0]) as u32;
            self.order.remove(&first);
            for c in &comp.cells {
                let i = index_of(*c);
                self.owner[i] = NO_COMPONENT;
                if self.state[i] & FRONTIER != 0 {
                    seeds.push(i);
                }
            }
            dissolved.insert(first, comp);
        }
        seeds.extend(
            fresh
                .iter()
                .map(|&i| i as usize)
                .filter(|&i| self.state[i] & FRONTIER != 0 && self.owner[i] == NO_COMPONENT),
        );
        (seeds, dissolved)
    }

    /// Labels the chains of `seeds` (frontier cells of no component) as components, each
    /// keeping the middle cell of a dissolved one with the same cells.
    fn label(
        &mut self,
        grid: &OccupancyGrid,
        seeds: &[usize],
        dissolved: &mut LookupMap<u32, Component>,
    ) {
        let w = grid.width() as i64;
        let h = grid.height() as i64;
        let mut queue = VecDeque::new();
        let mut comp: Vec<usize> = Vec::new();
        for &start in seeds {
            if self.state[start] & LABELLED != 0 {
                continue;
            }
            comp.clear();
            comp.push(start);
            self.state[start] |= LABELLED;
            queue.clear();
            // (Each cell queued with its column and row: no division per cell.)
            queue.push_back((start as i64 % w, start as i64 / w));
            while let Some((x, y)) = queue.pop_front() {
                // (A cell off the map's edge has all eight neighbours in the map: no bounds
                // tests for them.)
                let interior = x > 0 && y > 0 && x < w - 1 && y < h - 1;
                for (dx, dy) in NEIGHBOURS8 {
                    let (nx, ny) = (x + dx as i64, y + dy as i64);
                    if !interior && (nx < 0 || ny < 0 || nx >= w || ny >= h) {
                        continue;
                    }
                    let j = (ny * w + nx) as usize;
                    if self.state[j] == FRONTIER {
                        // (A component next to a new cell or a labelled one was dissolved.)
                        debug_assert_eq!(self.owner[j], NO_COMPONENT);
                        self.state[j] |= LABELLED;
                        comp.push(j);
                        queue.push_back((nx, ny));
                    }
                }
            }
            comp.sort_unstable();
            let first = comp[0] as u32;
            let cells: Vec<Cell> = comp.iter().map(|&i| grid.frame.cell_of_index(i)).collect();
            let middle = dissolved
                .remove(&first)
                .filter(|old| old.cells == cells)
                .and_then(|old| old.middle);
            let slot = match self.free.pop() {
                Some(s) => s,
                None => {
                    self.comps.push(None);
                    (self.comps.len() - 1) as u32
                }
            };
            for &i in &comp {
                self.owner[i] = slot;
            }
            self.comps[slot as usize] = Some(Component {
                cells,
                middle,
                dirty: false,
            });
            self.order.insert(first, slot);
        }
        for &i in seeds {
            self.state[i] &= !LABELLED;
        }
    }
}

/// Whether `c` is a frontier cell: free, with an unknown 4-neighbour (outside the grid is not
/// unknown).
pub(crate) fn is_frontier_cell(grid: &OccupancyGrid, c: Cell) -> bool {
    grid.is(c, Occupancy::Free)
        && c.neighbours4()
            .iter()
            .any(|n| grid.is(*n, Occupancy::Unknown))
}

/// [`is_frontier_cell`] for the cells `xa..=xb` of row `y` (all in the grid), into `out` (one
/// flag per cell, `out[0]` for `xa`). The cells whose both row neighbours are in the grid are
/// read as whole slices, which the compiler turns into vector instructions; a map's first and
/// last columns one by one.
pub(crate) fn frontier_row(grid: &OccupancyGrid, y: usize, xa: usize, xb: usize, out: &mut [bool]) {
    let (w, h) = (grid.width() as usize, grid.height() as usize);
    debug_assert!(xa <= xb && xb < w && y < h && out.len() > xb - xa);
    let (ia, ib) = (xa.max(1), xb.min(w.saturating_sub(2)));
    // (The cells before `ia` and after `ib`: at most a map's first and last columns, or the
    // whole span when the map is one or two columns wide. Counted from the ends, not found by
    // testing every column of the span.)
    let edges = (xa..=xb.min(ia - 1)).chain(xa.max(ib + 1)..=xb);
    for x in edges {
        out[x - xa] = is_frontier_cell(grid, Cell::new(x as i32, y as i32));
    }
    if ia > ib {
        return;
    }
    let n = ib - ia + 1;
    let at = |row: usize, x: usize| &grid.data[row * w + x..][..n];
    // (A missing row above or below reads the row itself: a free cell is not unknown.)
    let (up, down) = (y.saturating_sub(1), (y + 1).min(h - 1));
    let (cell, left, right) = (at(y, ia), at(y, ia - 1), at(y, ia + 1));
    let (above, below) = (at(up, ia), at(down, ia));
    let unknown = |o: &Occupancy| *o == Occupancy::Unknown;
    for (k, f) in out[ia - xa..][..n].iter_mut().enumerate() {
        *f = (cell[k] == Occupancy::Free)
            & (unknown(&left[k]) | unknown(&right[k]) | unknown(&above[k]) | unknown(&below[k]));
    }
}

const NEIGHBOURS8: [(i32, i32); 8] = [
    (1, 0),
    (-1, 0),
    (0, 1),
    (0, -1),
    (1, 1),
    (-1, 1),
    (1, -1),
    (-1, -1),
];

/// The middle of a chain given as sorted box indices (row width `bw`).
fn middle_cell(comp: &[usize], bw: usize) -> usize {
    middle_cell_by(comp, bw, |i, _, _| comp.binary_search(&i).ok())
}

/// [`middle_cell`], finding cells in `comp` through a table of positions over its bounding box
/// when that box is at most a few times larger than the component.
fn middle_cell_boxed(comp: &[usize], bw: usize) -> usize {
    let (mut x0, mut x1) = (usize::MAX, 0);
    let (y0, y1) = (comp[0] / bw, comp[comp.len() - 1] / bw);
    for &i in comp {
        x0 = x0.min(i % bw);
        x1 = x1.max(i % bw);
    }
    let (w, h) = (x1 - x0 + 1, y1 - y0 + 1);
    if w * h > 64 * comp.len() + 4096 {
        return middle_cell(comp, bw);
    }
    let mut slot = vec![u32::MAX; w * h];
    let local = |x: usize, y: usize| {
        (x >= x0 && x <= x1 && y >= y0 && y <= y1).then(|| (y - y0) * w + x - x0)
    };
    for (k, &i) in comp.iter().enumerate() {
        if let Some(j) = local(i % bw, i / bw) {
            slot[j] = k as u32;
        }
    }
    middle_cell_by(comp, bw, |_, x, y| {
        local(x as usize, y as usize)
            .map(|j| slot[j])
            .filter(|k| *k != u32::MAX)
            .map(|k| k as usize)
    })
}

/// [`middle_cell`] with `pos` giving the position in `comp` of a cell, given by its index, column
/// and row (`None` if absent).
fn middle_cell_by(
    comp: &[usize],
    bw: usize,
    pos: impl Fn(usize, i64, i64) -> Option<usize>,
) -> usize {
    let n = comp.len();
    // BFS inside the component; returns (depth, parent) per member and the farthest member
    // (first in BFS order among the deepest).
    let bfs = |from: usize| -> (Vec<u32>, Vec<u32>, usize) {
        let mut depth = vec![u32::MAX; n];
        let mut parent = vec![u32::MAX; n];
        let mut q = VecDeque::new();
        depth[from] = 0;
        q.push_back(from);
        let mut last = from;
        while let Some(k) = q.pop_front() {
            if depth[k] > depth[last] {
                last = k;
            }
            let i = comp[k];
            let (x, y) = ((i % bw) as i64, (i / bw) as i64);
            for (dx, dy) in NEIGHBOURS8 {
                let (nx, ny) = (x + dx as i64, y + dy as i64);
                if nx < 0 || ny < 0 || nx >= bw as i64 {
                    continue;
                }
                if let Some(m) = pos(ny as usize * bw + nx as usize, nx, ny) {
                    if depth[m] == u32::MAX {
                        depth[m] = depth[k] + 1;
                        parent[m] = k as u32;
                        q.push_back(m);
                    }
                }
            }
        }
        (depth, parent, last)
    };
    let (_, _, a) = bfs(0);
    let (depth, parent, b) = bfs(a);
    let half = depth[b] / 2;
    let mut k = b;
    while depth[k] > depth[b] - half {
        k = parent[k] as usize;
    }
    comp[k]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn grid(s: &str) -> OccupancyGrid {
        OccupancyGrid::from_ascii(s, 0.1)
    }

    proptest! {
        /// A row's frontier flags are `is_frontier_cell`'s, on grids of any size (one or two
        /// columns, one row), for any span of any row.
        #[test]
        fn frontier_row_is_is_frontier_cell(
            width in 1usize..90,
            height in 1usize..5,
            cells in proptest::collection::vec(0u8..3, 90 * 5),
            y in 0usize..5,
            span in (0usize..90, 0usize..90),
        ) {
            let frame = crate::grid::GridFrame::new(
                crate::geom::Vec2::zeros(),
                0.1,
                width as u32,
                height as u32,
            );
            let mut g = OccupancyGrid::filled(frame, Occupancy::Unknown);
            for (d, v) in g.data.iter_mut().zip(&cells) {
                *d = [Occupancy::Unknown, Occupancy::Free, Occupancy::Occupied][*v as usize];
            }
            let y = y % height;
            let (a, b) = (span.0 % width, span.1 % width);
            let (xa, xb) = (a.min(b), a.max(b));
            let mut out = vec![false; xb - xa + 1];
            frontier_row(&g, y, xa, xb, &mut out);
            let expected: Vec<bool> = (xa..=xb)
                .map(|x| is_frontier_cell(&g, Cell::new(x as i32, y as i32)))
                .collect();
            prop_assert_eq!(out, expected);
        }
    }

    #[test]
    fn one_straight_frontier_with_its_middle() {
        let g = grid(
            "
            ?????????
            .........
            .........
            #########",
        );
        let f = detect_frontiers(&g, &FrontierConfig { min_cells: 1 });
        assert_eq!(f.len(), 1);
        assert_eq!(f[0].size, 9);
        assert_eq!(f[0].candidate, Cell::new(4, 2));
        assert!(f[0].cells.iter().all(|c| c.y == 2));
    }

    #[test]
    fn cells_left_out_split_a_frontier_into_chains_with_their_own_middles() {
        let g = grid(
            "
            ?????????????
            .............
            .............
            #############",
        );
        let cfg = FrontierConfig { min_cells: 3 };
        let all = detect_frontiers(&g, &cfg);
        assert_eq!(all.len(), 1);
        // Everything kept: the same frontier.
        assert_eq!(frontiers_where(all.clone(), &cfg, |_| true), all);
        // Cells 4 and 5 left out: two chains, 0-3 and 6-12, each with its own middle cell.
        let split = frontiers_where(all.clone(), &cfg, |c| c.x != 4 && c.x != 5);
        assert_eq!(split.len(), 2);
        assert_eq!((split[0].size, split[1].size), (4, 7));
        assert!(split[0].cells.iter().all(|c| c.x <= 3 && c.y == 2));
        assert_eq!(split[1].candidate, Cell::new(9, 2));
        // A piece shorter than the minimum is dropped; nothing kept, nothing left.
        let short = frontiers_where(all.clone(), &cfg, |c| c.x < 2 || c.x > 5);
        assert_eq!(short.len(), 1);
        assert_eq!(short[0].size, 7);
        assert!(frontiers_where(all, &cfg, |_| false).is_empty());
    }

    #[test]
    fn separate_chains_min_size_and_order() {
        let g = grid(
            "
            ??##?????
            ..##.....
            ..##.....
            #########",
        );
        let all = detect_frontiers(&g, &FrontierConfig { min_cells: 1 });
        assert_eq!(all.len(), 2);
        assert_eq!((all[0].size, all[1].size), (2, 5));
        assert!(all[0].cells[0] < all[1].cells[0]);
        assert_eq!(all[1].candidate, Cell::new(6, 2));
        let big = detect_frontiers(&g, &FrontierConfig { min_cells: 3 });
        assert_eq!(big.len(), 1);
        assert_eq!(big[0].size, 5);
        assert_eq!(FrontierConfig::with_min_length_m(0.25, 0.1).min_cells, 3);
    }

    #[test]
    fn l_shaped_chain_middle_is_near_the_corner() {
        // Unknown above and to the right of the free region: the chain runs along the top row
        // and down the right column (8-connected), 4 + 1 + 4 cells.
        let g = grid(
            "
            ??????
            .....?
            .....?
            .....?
            .....?
            #####?",
        );
        let f = detect_frontiers(&g, &FrontierConfig { min_cells: 1 });
        assert_eq!(f.len(), 1);
        assert_eq!(f[0].size, 8);
        // 8-connected BFS cuts the corner: (0,4)..(3,4),(4,3)..(4,1) is 6 steps; half is (3,4).
        assert_eq!(f[0].candidate, Cell::new(3, 4));
    }

    #[test]
    fn diagonal_unknown_is_not_enough_and_empty_grid_is_fine() {
        let g = grid(
            "
            ?#
            #.",
        );
        assert!(detect_frontiers(&g, &FrontierConfig { min_cells: 1 }).is_empty());
        assert!(detect_frontiers(&grid(""), &FrontierConfig::default()).is_empty());
        let g = grid("..\n?.");
        let f = detect_frontiers_in(
            &g,
            Cell::new(1, 0),
            Cell::new(5, 5),
            &FrontierConfig { min_cells: 1 },
        );
        assert_eq!(f.len(), 1);
        assert_eq!(f[0].cells, vec![Cell::new(1, 0)]);
    }

    #[test]
    fn a_frontier_of_other_cells_from_the_same_first_cell_is_found_again() {
        // Each map after the first changes one frontier so that it keeps its first cell and
        // its number of cells but not all its cells (or keeps them all): the tracker, which
        // reuses the cells of a frontier found the same, finds what a full detection finds.
        let maps = [
            "
            ??????
            ....##
            ......",
            // The chain's last cell moves: (3, 1) stops being a frontier cell, (4, 1) is one.
            "
            ???.??
            ...###
            ......",
            // Unchanged.
            "
            ???.??
            ...###
            ......",
            // The same number of cells, one of them moved a row down.
            "
            ?.?.??
            ..?###
            ......",
        ];
        let cfg = FrontierConfig { min_cells: 1 };
        let first = grid(maps[0]);
        let mut t = FrontierTracker::new(&first);
        assert_eq!(t.detect(&first, &cfg), detect_frontiers(&first, &cfg));
        for text in &maps[1..] {
            let g = grid(text);
            t.update(&g, 0..g.data.len() as u32);
            assert_eq!(t.detect(&g, &cfg), detect_frontiers(&g, &cfg), "{text}");
        }
    }

    proptest! {
        #[test]
        fn frontier_cells_are_free_touch_unknown_and_are_disjoint(
            cells in proptest::collection::vec(0u8..3, 12 * 10)
        ) {
            let frame = crate::grid::GridFrame::new(crate::geom::Vec2::zeros(), 0.1, 12, 10);
            let g = OccupancyGrid {
                frame,
                data: cells.iter().map(|v| [Occupancy::Unknown, Occupancy::Free, Occupancy::Occupied][*v as usize]).collect(),
            };
            let fs = detect_frontiers(&g, &FrontierConfig { min_cells: 1 });
            let mut seen = std::collections::BTreeSet::new();
            for f in &fs {
                prop_assert!(f.cells.contains(&f.candidate));
                prop_assert_eq!(f.size, f.cells.len());
                for c in &f.cells {
                    prop_assert!(g.is(*c, Occupancy::Free));
                    prop_assert!(c.neighbours4().iter().any(|n| g.is(*n, Occupancy::Unknown)));
                    prop_assert!(seen.insert(*c));
                }
            }
            // Every frontier cell belongs to some frontier.
            let n_frontier = g.iter().filter(|(c, s)| **s == Occupancy::Free
                && c.neighbours4().iter().any(|n| g.is(*n, Occupancy::Unknown))).count();
            prop_assert_eq!(n_frontier, seen.len());
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// `new` (row by row) marks what updating every cell of a blank tracker marks.
        #[test]
        fn new_equals_updating_every_cell(
            w in 1usize..40,
            h in 1usize..12,
            init in proptest::collection::vec(0u8..3, 480),
        ) {
            let state = |k: u8| match k { 0 => Occupancy::Unknown, 1 => Occupancy::Free, _ => Occupancy::Occupied };
            let mut g = OccupancyGrid::filled(crate::grid::GridFrame::new(crate::geom::Vec2::zeros(), 0.1, w as u32, h as u32), Occupancy::Unknown);
            for (i, s) in g.data.iter_mut().enumerate() {
                *s = state(init[i]);
            }
            let n = w * h;
            let mut old = FrontierTracker {
                state: vec![0; n],
                owner: vec![NO_COMPONENT; n],
                width: w as u32,
                ..Default::default()
            };
            old.update(&g, 0..n as u32);
            let new = FrontierTracker::new(&g);
            prop_assert_eq!(&new.state, &old.state);
            let mut cells = old.fresh.clone();
            cells.sort_unstable();
            cells.dedup();
            prop_assert_eq!(&new.fresh, &cells);
        }

        #[test]
        fn tracker_equals_full_detection(
            w in 1usize..14,
            h in 1usize..14,
            init in proptest::collection::vec(0u8..3, 196),
            edits in proptest::collection::vec((0usize..196, 0u8..3), 0..40),
            min_cells in 1usize..4,
        ) {
            let state = |k: u8| match k { 0 => Occupancy::Unknown, 1 => Occupancy::Free, _ => Occupancy::Occupied };
            let mut g = OccupancyGrid::filled(crate::grid::GridFrame::new(crate::geom::Vec2::zeros(), 0.1, w as u32, h as u32), Occupancy::Unknown);
            for (i, s) in g.data.iter_mut().enumerate() {
                *s = state(init[i]);
            }
            let cfg = FrontierConfig { min_cells };
            let mut t = FrontierTracker::new(&g);
            prop_assert_eq!(t.detect(&g, &cfg), detect_frontiers(&g, &cfg));
            for chunk in edits.chunks(5) {
                let mut changed = Vec::new();
                for &(i, k) in chunk {
                    let i = i % (w * h);
                    g.data[i] = state(k);
                    changed.push(i as u32);
                }
                t.update(&g, changed);
                prop_assert_eq!(t.detect(&g, &cfg), detect_frontiers(&g, &cfg));
            }
        }

        /// Chains that grow, merge, split and vanish over many updates of a larger map, with
        /// the minimal size changing between detections and some detections repeated without
        /// an update: the components kept from one detection to the next are the full
        /// detection's.
        #[test]
        fn tracker_equals_full_detection_over_many_updates(
            init in proptest::collection::vec(0u8..3, 30 * 24),
            edits in proptest::collection::vec((0usize..30 * 24, 0u8..3, 1usize..6), 0..200),
            chunk in 1usize..12,
        ) {
            let state = |k: u8| match k { 0 => Occupancy::Unknown, 1 => Occupancy::Free, _ => Occupancy::Occupied };
            let mut g = OccupancyGrid::filled(crate::grid::GridFrame::new(crate::geom::Vec2::zeros(), 0.1, 30, 24), Occupancy::Unknown);
            for (i, s) in g.data.iter_mut().enumerate() {
                *s = state(init[i]);
            }
            let mut t = FrontierTracker::new(&g);
            for edits in edits.chunks(chunk) {
                let mut changed = Vec::new();
                for &(i, k, _) in edits {
                    g.data[i] = state(k);
                    changed.push(i as u32);
                }
                t.update(&g, changed);
                let cfg = FrontierConfig { min_cells: edits[0].2 };
                prop_assert_eq!(t.detect(&g, &cfg), detect_frontiers(&g, &cfg));
                if edits[0].2 == 1 {
                    let cfg = FrontierConfig { min_cells: 3 };
                    prop_assert_eq!(t.detect(&g, &cfg), detect_frontiers(&g, &cfg));
                }
            }
        }
    }
}
