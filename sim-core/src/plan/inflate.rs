//! Where the robot's centre may go: known free cells farther than its radius from obstacles.

use crate::grid::{Bitmap, Cell, Grid, GridFrame, Occupancy, OccupancyGrid};
use crate::mapping::distance_field::ObstacleDistance;

/// `Free` cells whose distance to the nearest `Occupied` cell exceeds `radius_m`. `Unknown`
/// cells are not traversable. `obstacles` must be the field of `grid` and its cap must exceed the
/// radius (a cell at the cap counts as far enough).
pub fn traversable(grid: &OccupancyGrid, obstacles: &ObstacleDistance, radius_m: f64) -> Bitmap {
    let radius_cells = (radius_m / grid.frame.resolution_m) as f32;
    let same = obstacles.frame == grid.frame;
    let data = grid
        .data
        .iter()
        .enumerate()
        .map(|(i, s)| {
            *s == Occupancy::Free
                && same
                && (obstacles.data[i] > radius_cells
                    || obstacles.data[i] >= obstacles.cap_cells as f32)
        })
        .collect();
    Grid {
        frame: grid.frame,
        data,
    }
}

/// Traversability read on demand from a map and its obstacle field (same rule as
/// [`traversable`]), for planners that touch only part of a large grid.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Traversability<'a> {
    pub grid: &'a OccupancyGrid,
    pub obstacles: &'a ObstacleDistance,
    radius_cells: f32,
}

impl<'a> Traversability<'a> {
    pub(crate) fn new(
        grid: &'a OccupancyGrid,
        obstacles: &'a ObstacleDistance,
        radius_m: f64,
    ) -> Self {
        debug_assert!(grid.frame == obstacles.frame);
        Self {
            grid,
            obstacles,
            radius_cells: (radius_m / grid.frame.resolution_m) as f32,
        }
    }

    /// Whether the cell with row-major index `i` is traversable.
    #[inline]
    pub(crate) fn at_index(&self, i: usize) -> bool {
        self.grid.data[i] == Occupancy::Free
            && (self.obstacles.data[i] > self.radius_cells
                || self.obstacles.data[i] >= self.obstacles.cap_cells as f32)
    }

    pub(crate) fn at(&self, c: Cell) -> bool {
        self.grid.frame.index(c).is_some_and(|i| self.at_index(i))
    }
}

/// Like [`traversable`], building the obstacle field itself (for one-off use and tests).
pub fn traversable_from_grid(grid: &OccupancyGrid, radius_m: f64) -> Bitmap {
    let cap = (radius_m / grid.frame.resolution_m).ceil() as u32 + 2;
    traversable(grid, &ObstacleDistance::from_grid(grid, cap), radius_m)
}

/// A coarser traversability map: a coarse cell is traversable when all the fine cells it covers
/// are (conservative). `factor` 2 turns 0.05 m into 0.1 m cells.
pub fn downsample(trav: &Bitmap, factor: u32) -> Bitmap {
    let f = factor.max(1);
    let fr = trav.frame;
    let frame = GridFrame::new(
        fr.origin_m,
        fr.resolution_m * f as f64,
        fr.width / f,
        fr.height / f,
    );
    let mut out = Grid::filled(frame, false);
    let fw = fr.width as usize;
    for cy in 0..frame.height as usize {
        for cx in 0..frame.width as usize {
            let mut all = true;
            'o: for dy in 0..f as usize {
                let row = (cy * f as usize + dy) * fw;
                for dx in 0..f as usize {
                    if !trav.data[row + cx * f as usize + dx] {
                        all = false;
                        break 'o;
                    }
                }
            }
            out.data[cy * frame.width as usize + cx] = all;
        }
    }
    out
}

/// The traversable cell nearest to `c` within `radius_cells` (Chebyshev box, Euclidean order,
/// ties broken by row-major order), e.g. "a reachable free cell near the candidate".
pub fn nearest_traversable(trav: &Bitmap, c: Cell, radius_cells: i32) -> Option<Cell> {
    nearest_by(c, radius_cells, |n| trav.get(n) == Some(&true))
}

/// [`nearest_traversable`] with any traversability test (which must be pure: the cells are
/// tested nearest first, and the search stops at the first traversable one).
pub(crate) fn nearest_by(
    c: Cell,
    radius_cells: i32,
    traversable: impl Fn(Cell) -> bool,
) -> Option<Cell> {
    if !(0..=MAX_ORDERED_RADIUS).contains(&radius_cells) {
        return nearest_by_scan(c, radius_cells, traversable);
    }
    let at = |&(dx, dy): &(i32, i32)| Cell::new(c.x + dx, c.y + dy);
    NEAREST_FIRST.with(|tables| match tables.try_borrow_mut() {
        Ok(mut tables) => {
            let k = match tables.iter().position(|(r, _)| *r == radius_cells) {
                Some(k) => k,
                None => {
                    tables.push((radius_cells, offsets_nearest_first(radius_cells)));
                    tables.len() - 1
                }
            };
            tables[k].1.iter().map(at).find(|&n| traversable(n))
        }
        // Only reachable if the test itself searches for a nearest cell.
        Err(_) => nearest_by_scan(c, radius_cells, traversable),
    })
}

/// Radii (cells) up to which [`nearest_by`] keeps the offsets in the order it tests them.
const MAX_ORDERED_RADIUS: i32 = 64;

/// Per radius used, the offsets within it nearest first (see [`offsets_nearest_first`]).
type NearestFirst = Vec<(i32, Vec<(i32, i32)>)>;

thread_local! {
    static NEAREST_FIRST: std::cell::RefCell<NearestFirst> =
        const { std::cell::RefCell::new(Vec::new()) };
}

/// The offsets within `radius_cells` (Euclidean), nearest first, ties in row-major order: the
/// first traversable one is the cell [`nearest_by_scan`] finds.
fn offsets_nearest_first(radius_cells: i32) -> Vec<(i32, i32)> {
    let r = radius_cells;
    let mut offsets: Vec<(i32, i32)> = (-r..=r)
        .flat_map(|dy| (-r..=r).map(move |dx| (dx, dy)))
        .filter(|&(dx, dy)| dx * dx + dy * dy <= r * r)
        .collect();
    offsets.sort_by_key(|&(dx, dy)| (dx * dx + dy * dy, dy, dx));
    offsets
}

/// [`nearest_by`] by testing every cell of the box around `c`, in row-major order, keeping the
/// first of the least distance.
fn nearest_by_scan(c: Cell, radius_cells: i32, traversable: impl Fn(Cell) -> bool) -> Option<Cell> {
    let mut best: Option<(i32, Cell)> = None;
    for dy in -radius_cells..=radius_cells {
        for dx in -radius_cells..=radius_cells {
            let n = Cell::new(c.x + dx, c.y + dy);
            let d2 = dx * dx + dy * dy;
            if d2 > radius_cells * radius_cells || !traversable(n) {
                continue;
            }
            if best.is_none_or(|(bd, _)| d2 < bd) {
                best = Some((d2, n));
            }
        }
    }
    best.map(|(_, n)| n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inflation_keeps_the_centre_away_from_walls_and_unknown() {
        let g = OccupancyGrid::from_ascii(
            "
            #########
            #.......#
            #.......?
            #.......#
            #########",
            0.1,
        );
        let t = traversable_from_grid(&g, 0.15);
        // Cells two away from walls: only the middle row, x = 2..=6.
        let cells: Vec<Cell> = t.iter().filter(|(_, v)| **v).map(|(c, _)| c).collect();
        assert_eq!(cells, (2..=6).map(|x| Cell::new(x, 2)).collect::<Vec<_>>());
        assert_eq!(
            nearest_traversable(&t, Cell::new(8, 2), 3),
            Some(Cell::new(6, 2))
        );
        assert_eq!(nearest_traversable(&t, Cell::new(8, 2), 1), None);
        let d = downsample(&traversable_from_grid(&g, 0.0), 2);
        assert_eq!((d.width(), d.height()), (4, 2));
        // Coarse row 1 covers fine rows 2-3: free at fine x = 1..=7, so coarse x = 1, 2, 3.
        assert_eq!(d.count_true(), 3);
    }

    proptest::proptest! {
        /// Nearest first is the scan of the whole box: the same cell (ties in row-major order),
        /// or none; on sparse grids (8 % of the cells traversable: the nearest is often far, or
        /// out of reach), from cells inside, on the edge of and outside the grid, with radii
        /// below and above the table's limit.
        #[test]
        fn nearest_first_is_the_scan(
            bits in proptest::collection::vec(proptest::bool::weighted(0.08), 30 * 20),
            x in -5i32..35, y in -5i32..25, r in -1i32..16, wide in proptest::bool::ANY,
        ) {
            let r = if wide { r + MAX_ORDERED_RADIUS - 8 } else { r };
            let test = |n: Cell| {
                (0..30).contains(&n.x) && (0..20).contains(&n.y) && bits[(n.y * 30 + n.x) as usize]
            };
            let c = Cell::new(x, y);
            proptest::prop_assert_eq!(nearest_by(c, r, test), nearest_by_scan(c, r, test));
        }
    }

    #[test]
    fn ties_go_to_the_first_in_row_major_order() {
        // Four cells at distance 2 (up, left, right, down): the lowest row's, then the left.
        let on = [(5, 3), (3, 5), (7, 5), (5, 7)];
        let test = |n: Cell| on.contains(&(n.x, n.y));
        assert_eq!(nearest_by(Cell::new(5, 5), 3, test), Some(Cell::new(5, 3)));
        let test = |n: Cell| on[1..].contains(&(n.x, n.y));
        assert_eq!(nearest_by(Cell::new(5, 5), 3, test), Some(Cell::new(3, 5)));
        assert_eq!(nearest_by(Cell::new(5, 5), 1, test), None);
    }
}
