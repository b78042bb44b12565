//! A coarse planning grid: `factor` x `factor` map cells per planning cell, so that path searches
//! over a large building touch a fraction of the cells.
//!
//! A planning cell is passable when any map cell it covers is traversable, so the coarse grid
//! connects whatever the map connects (a conservative "all cells" rule closes narrow doors and
//! the gaps between diverging laser beams); a path through it keeps the clearance of the map
//! up to half a planning cell (the inflation's safety margin covers that). Its extra cost is the
//! largest of its traversable cells'.

use crate::grid::{Cell, GridFrame};
use crate::plan::inflate::nearest_by;

/// Per planning cell: 0 = blocked, otherwise 1 + the extra cost of entering it.
///
/// Stored on the frame padded by one blocked cell on every side (`frame.width + 2` wide), the
/// layout [`dijkstra_padded`](crate::plan::dijkstra::dijkstra_padded) searches directly, so a
/// path search copies nothing.
#[derive(Debug, Clone, PartialEq)]
pub struct CoarseCosts {
    pub frame: GridFrame,
    pub factor: u32,
    padded: Vec<u8>,
}

impl CoarseCosts {
    pub(crate) fn passable(&self, c: Cell) -> bool {
        self.frame.contains(c) && self.padded[self.padded_index(c)] > 0
    }

    /// The cost grid on the padded frame (see the type's doc).
    pub(crate) fn padded(&self) -> &[u8] {
        &self.padded
    }

    /// The costs row-major over `frame` (unpadded).
    #[cfg(test)]
    pub fn costs(&self) -> Vec<u8> {
        let (w, h) = (self.frame.width as i32, self.frame.height as i32);
        (0..h)
            .flat_map(|y| (0..w).map(move |x| Cell::new(x, y)))
            .map(|c| self.padded[self.padded_index(c)])
            .collect()
    }

    /// Number of planning cells.
    pub fn len(&self) -> usize {
        self.frame.len()
    }

    pub fn is_empty(&self) -> bool {
        self.frame.is_empty()
    }

    fn padded_index(&self, c: Cell) -> usize {
        (c.y as usize + 1) * (self.frame.width as usize + 2) + c.x as usize + 1
    }

    /// The planning cell covering map cell `c`.
    pub(crate) fn coarse_of(&self, c: Cell) -> Cell {
        let f = self.factor as i32;
        Cell::new(c.x.div_euclid(f), c.y.div_euclid(f))
    }

    /// The planning cell of map cell `c` if passable, else the nearest passable one within
    /// `radius_cells` planning cells.
    pub(crate) fn passable_near(&self, c: Cell, radius_cells: i32) -> Option<Cell> {
        let cc = self.coarse_of(c);
        if self.passable(cc) {
            Some(cc)
        } else {
            nearest_by(cc, radius_cells, |n| self.passable(n))
        }
    }
}

/// Builds the planning grid of a map grid `fine`, looking only at map cells within `lo..=hi`
/// (inclusive; everything else is blocked). `traversable` and `extra` take row-major map
/// indices; `extra` is clamped to 254.
pub fn coarse_costs(
    fine: GridFrame,
    factor: u32,
    lo: Cell,
    hi: Cell,
    traversable: impl Fn(usize) -> bool,
    extra: impl Fn(usize) -> u32,
) -> CoarseCosts {
    let mut c = CoarseCosts::blocked(fine, factor);
    if c.frame.is_empty() {
        return c;
    }
    let fi = c.factor as i32;
    let cx0 = (lo.x.div_euclid(fi)).clamp(0, c.frame.width as i32 - 1);
    let cy0 = (lo.y.div_euclid(fi)).clamp(0, c.frame.height as i32 - 1);
    let cx1 = (hi.x.div_euclid(fi)).clamp(0, c.frame.width as i32 - 1);
    let cy1 = (hi.y.div_euclid(fi)).clamp(0, c.frame.height as i32 - 1);
    for cy in cy0..=cy1 {
        for cx in cx0..=cx1 {
            let i = c.padded_index(Cell::new(cx, cy));
            c.padded[i] = cell_cost(fine, c.factor, cx, cy, &traversable, &extra);
        }
    }
    c
}

impl CoarseCosts {
    /// The planning grid of a map grid `fine` with every planning cell blocked.
    pub(crate) fn blocked(fine: GridFrame, factor: u32) -> Self {
        let f = factor.max(1);
        let frame = GridFrame::new(
            fine.origin_m,
            fine.resolution_m * f as f64,
            fine.width / f,
            fine.height / f,
        );
        Self {
            frame,
            factor: f,
            padded: vec![0; (frame.width as usize + 2) * (frame.height as usize + 2)],
        }
    }

    /// Recomputes the planning cells at `cells` (row-major indices of this grid; out-of-range
    /// ones are ignored) from the map, as [`coarse_costs`] computes them. Updating every
    /// planning cell whose map cells changed keeps the grid equal to a full rebuild.
    pub(crate) fn recompute(
        &mut self,
        fine: GridFrame,
        cells: &[u32],
        traversable: impl Fn(usize) -> bool,
        extra: impl Fn(usize) -> u32,
    ) {
        let factor = self.factor;
        self.set_cells(cells, |cx, cy| {
            cell_cost(fine, factor, cx, cy, &traversable, &extra)
        });
    }

    /// [`CoarseCosts::recompute`] of the cells at `cells` from `finer`, a grid of the same map
    /// with a factor dividing this one's that is up to date: a cell's map cells are exactly those
    /// of the `k x k` cells of `finer` under it (`k` the ratio of the factors), so it is blocked
    /// when they all are, else their largest cost (1 + the largest extra cost of a traversable
    /// map cell, clamped alike). Reads `k^2` cells instead of `factor^2` map cells.
    pub(crate) fn recompute_from(&mut self, finer: &CoarseCosts, cells: &[u32]) {
        assert!(
            self.factor.is_multiple_of(finer.factor) && self.frame.origin_m == finer.frame.origin_m,
            "a finer grid of the same map"
        );
        let k = (self.factor / finer.factor) as i32;
        self.set_cells(cells, |cx, cy| {
            let under = (0..k).flat_map(|dy| (0..k).map(move |dx| (dx, dy)));
            under
                .map(|(dx, dy)| {
                    finer.padded[finer.padded_index(Cell::new(cx * k + dx, cy * k + dy))]
                })
                .max()
                .unwrap_or(0)
        });
    }

    /// Sets the cells at `cells` (row-major indices; out-of-range ones are ignored) to `cost` of
    /// their column and row.
    fn set_cells(&mut self, cells: &[u32], cost: impl Fn(i32, i32) -> u8) {
        let w = self.frame.width as usize;
        for &i in cells {
            let i = i as usize;
            if i >= self.frame.len() {
                continue;
            }
            let (cx, cy) = ((i % w) as i32, (i / w) as i32);
            let p = self.padded_index(Cell::new(cx, cy));
            self.padded[p] = cost(cx, cy);
        }
    }
}

/// The cost of one planning cell: 0 if none of its map cells is traversable, else 1 + the
/// largest extra cost of its traversable cells (clamped to 254).
fn cell_cost(
    fine: GridFrame,
    factor: u32,
    cx: i32,
    cy: i32,
    traversable: &impl Fn(usize) -> bool,
    extra: &impl Fn(usize) -> u32,
) -> u8 {
    let fi = factor as i32;
    let fw = fine.width as usize;
    let mut worst = 0u32;
    let mut any = false;
    for dy in 0..fi {
        let row = (cy * fi + dy) as usize * fw;
        for dx in 0..fi {
            let i = row + (cx * fi + dx) as usize;
            if traversable(i) {
                any = true;
                worst = worst.max(extra(i));
            }
        }
    }
    if any {
        1 + worst.min(254) as u8
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec2;

    proptest::proptest! {
        /// A coarser grid recomputed from an up-to-date finer one equals one recomputed from the
        /// map, on maps of any size (not a multiple of either factor) after any changes.
        #[test]
        fn recomputed_from_a_finer_grid_is_recomputed_from_the_map(
            (w, h) in (1u32..40, 1u32..30),
            trav in proptest::collection::vec(proptest::bool::weighted(0.6), 40 * 30),
            extra in proptest::collection::vec(0u32..300, 40 * 30),
            changed in proptest::collection::vec(0u32..1200, 0..60),
        ) {
            let fine = GridFrame::new(Vec2::new(0.3, -0.2), 0.05, w, h);
            let n = fine.len();
            let before = |i: usize| trav[i] && !i.is_multiple_of(3);
            let after = |i: usize| trav[i];
            let cost = |i: usize| extra[i];
            let all = (Cell::new(0, 0), Cell::new(w as i32 - 1, h as i32 - 1));
            let mut plan = coarse_costs(fine, 2, all.0, all.1, before, cost);
            let mut far = coarse_costs(fine, 4, all.0, all.1, before, cost);
            // The planning cells over the changed map cells (all of them: `before` and `after`
            // differ on every third), and the distance cells over those.
            let changed: Vec<u32> = changed.iter().map(|c| c % n as u32).collect();
            let dirty = |g: &CoarseCosts| {
                let mut d: Vec<u32> = (0..n as u32)
                    .filter(|i| i.is_multiple_of(3) || changed.contains(i))
                    .map(|i| {
                        let c = g.coarse_of(fine.cell_of_index(i as usize));
                        g.frame.index(c).map_or(u32::MAX, |k| k as u32)
                    })
                    .collect();
                d.sort_unstable();
                d.dedup();
                d
            };
            let (plan_dirty, far_dirty) = (dirty(&plan), dirty(&far));
            plan.recompute(fine, &plan_dirty, after, cost);
            let mut want = far.clone();
            want.recompute(fine, &far_dirty, after, cost);
            far.recompute_from(&plan, &far_dirty);
            proptest::prop_assert_eq!(far, want);
        }
    }

    #[test]
    fn a_planning_cell_is_passable_when_any_of_its_cells_is() {
        let fine = GridFrame::new(Vec2::zeros(), 0.05, 8, 4);
        let idx = |x, y| fine.index(Cell::new(x, y)).unwrap();
        // Coarse (2, 0) has no traversable cell; coarse (3, 1) one, with extra cost 3.
        let blocked = [
            idx(4, 0),
            idx(5, 0),
            idx(4, 1),
            idx(5, 1),
            idx(6, 2),
            idx(7, 2),
            idx(6, 3),
        ];
        let costly = idx(7, 3);
        let c = coarse_costs(
            fine,
            2,
            Cell::new(0, 0),
            Cell::new(7, 3),
            |i| !blocked.contains(&i),
            |i| if i == costly { 3 } else { 0 },
        );
        assert_eq!((c.frame.width, c.frame.height), (4, 2));
        assert_eq!(c.frame.resolution_m, 0.1);
        assert_eq!(c.costs(), vec![1, 1, 0, 1, 1, 1, 1, 4]);
        assert_eq!(c.coarse_of(Cell::new(5, 1)), Cell::new(2, 0));
        assert!(!c.passable(Cell::new(2, 0)) && c.passable(Cell::new(3, 1)));
        assert_eq!(c.passable_near(Cell::new(4, 0), 1), Some(Cell::new(1, 0)));
        // Outside the bounds everything is blocked.
        let c = coarse_costs(fine, 2, Cell::new(0, 0), Cell::new(1, 1), |_| true, |_| 0);
        assert_eq!(c.costs(), vec![1, 0, 0, 0, 0, 0, 0, 0]);
        // Recomputing some cells from another map changes exactly those.
        let mut d = c.clone();
        d.recompute(fine, &[1, 7, 99], |i| i == costly, |_| 5);
        assert_eq!(d.costs(), vec![1, 0, 0, 0, 0, 0, 0, 6]);
    }

    #[test]
    fn searching_the_padded_grid_equals_searching_its_costs() {
        use crate::plan::dijkstra::{dijkstra_by, dijkstra_padded};
        let fine = GridFrame::new(Vec2::zeros(), 0.05, 40, 30);
        // A wall with a door, and extra costs near it.
        let blocked = |i: usize| {
            let (x, y) = (i % 40, i / 40);
            x == 20 && !(12..16).contains(&y)
        };
        let extra = |i: usize| {
            let x = (i % 40) as i32;
            (4 - (x - 20).abs()).max(0) as u32
        };
        let c = coarse_costs(
            fine,
            2,
            Cell::new(0, 0),
            Cell::new(39, 29),
            |i| !blocked(i),
            extra,
        );
        let costs = c.costs();
        let start = Cell::new(2, 3);
        let targets = [Cell::new(17, 12), Cell::new(15, 1)];
        let direct = dijkstra_padded(c.frame, start, c.padded(), 4, &targets);
        let by = dijkstra_by(
            c.frame,
            start,
            |i| costs[i] > 0,
            |i| costs[i].saturating_sub(1) as u32,
            4,
            &targets,
        );
        assert_eq!(direct, by);
        assert!(direct.distance_m(Cell::new(17, 12)).is_some());
    }
}
