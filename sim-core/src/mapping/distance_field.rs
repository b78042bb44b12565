//! Capped Euclidean distance to the nearest `Occupied` cell, kept up to date incrementally.
//!
//! Used by the scan matcher (smooth residual with a gradient) and by obstacle inflation for the
//! planner. Distances are in cells and capped at `cap_cells`: anything farther reads as the cap.
//! Adding an obstacle stamps a disc of radius `cap_cells`; removing one recomputes the disc from
//! the obstacles around it. The result always equals the capped exact transform.

use crate::geom::{floor_f64, Vec2};
use crate::grid::{Cell, GridFrame, Occupancy, OccupancyGrid};

/// Capped distance (in cells) from every cell to the nearest occupied cell.
#[derive(Debug, Clone, PartialEq)]
pub struct ObstacleDistance {
    pub frame: GridFrame,
    pub cap_cells: u32,
    /// Row-major, in cells, in `[0, cap_cells]`.
    pub data: Vec<f32>,
    /// The disc of radius `cap_cells` (cells with `dx^2 + dy^2 < cap^2`) by rows:
    /// `(dy, first dx, distances)`, for stamping a row at a time.
    disc_rows: Vec<(i32, i32, Vec<f32>)>,
    /// Working memory of the updates.
    scratch: Scratch,
}

/// Working memory of [`ObstacleDistance::update`] and [`ObstacleDistance::update_reporting`],
/// kept between calls so that an update allocates nothing once its lists have grown (made for
/// each update, the report's two lists alone were 224 000 allocations of 420 MB in a run of the
/// generated office). Not part of the field's value: a clone starts empty, and equality ignores
/// it.
#[derive(Debug, Default)]
struct Scratch {
    removed: Vec<Cell>,
    col2: Vec<i32>,
    last: Vec<i32>,
    spans: Vec<(usize, usize)>,
    before: Vec<f32>,
}

impl Clone for Scratch {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl PartialEq for Scratch {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl ObstacleDistance {
    /// An obstacle-free field (every cell at the cap).
    pub fn new(frame: GridFrame, cap_cells: u32) -> Self {
        let cap = cap_cells.max(1) as i32;
        let half_widths: Vec<i32> = (-cap..=cap)
            .map(|ry| {
                (0..=cap)
                    .take_while(|r| r * r + ry * ry < cap * cap)
                    .last()
                    .unwrap_or(-1)
            })
            .collect();
        let disc_rows = (-cap..=cap)
            .zip(&half_widths)
            .filter(|(_, &hw)| hw >= 0)
            .map(|(dy, &hw)| {
                let d = (-hw..=hw)
                    .map(|dx| ((dx * dx + dy * dy) as f32).sqrt())
                    .collect();
                (dy, -hw, d)
            })
            .collect();
        Self {
            frame,
            cap_cells: cap as u32,
            data: vec![cap as f32; frame.len()],
            disc_rows,
            scratch: Scratch::default(),
        }
    }

    /// The field of a whole grid.
    pub fn from_grid(grid: &OccupancyGrid, cap_cells: u32) -> Self {
        let mut f = Self::new(grid.frame, cap_cells);
        for (i, s) in grid.data.iter().enumerate() {
            if *s == Occupancy::Occupied {
                f.stamp(grid.frame.cell_of_index(i));
            }
        }
        f
    }

    fn stamp(&mut self, c: Cell) {
        let w = self.frame.width as i32;
        stamp_rows(&mut self.data, w, &self.disc_rows, c, |_| (0, w));
    }

    /// Brings the field up to date after the cells at `flips` (row-major indices into `grid`,
    /// which must share this frame) became or stopped being occupied.
    pub fn update(&mut self, grid: &OccupancyGrid, flips: &[u32]) {
        if grid.frame != self.frame {
            *self = Self::from_grid(grid, self.cap_cells);
            return;
        }
        let mut scratch = std::mem::take(&mut self.scratch);
        self.remove_and_stamp(grid, flips, &mut scratch);
        self.scratch = scratch;
    }

    /// [`ObstacleDistance::update`] within the frame, with the working memory `scratch`.
    fn remove_and_stamp(&mut self, grid: &OccupancyGrid, flips: &[u32], scratch: &mut Scratch) {
        let Scratch {
            removed,
            col2,
            last,
            ..
        } = scratch;
        removed.clear();
        for &i in flips {
            let i = i as usize;
            if i >= grid.data.len() {
                continue;
            }
            let c = self.frame.cell_of_index(i);
            if grid.data[i] == Occupancy::Occupied {
                self.stamp(c);
            } else {
                removed.push(c);
            }
        }
        if removed.is_empty() {
            return;
        }
        removed.sort_unstable();
        removed.dedup();
        let cap = self.cap_cells as i32;
        let (w, h) = (self.frame.width as i32, self.frame.height as i32);
        // Every cell of a removed obstacle's disc gets the distance to its nearest obstacle
        // within the cap, computed afresh from the grid: an obstacle within the cap of a cell
        // lies within `reach` cells of it on each axis (dx^2 < cap^2), so within twice that of
        // the removed one. First, per column near it, the vertical distance from each row of
        // the disc to the column's nearest obstacle (`col2`, squared; `cap2` for none within
        // reach); then per cell the least squared distance over the columns within reach. Its
        // square root is what stamping every obstacle would have left, bit for bit (the square
        // root and the conversion to `f32` are monotonic), and the cells outside the discs keep
        // their values: no obstacle they are within the cap of has gone. Removed cells close
        // together (consecutive in their order, within a box of `2 reach` cells) are done at
        // once: per row, the cells from the leftmost to the rightmost of their discs' rows
        // (more than the discs, maybe: a cell computed afresh gets the value it has). A cell in
        // discs of several groups is computed more than once, to the same value.
        let reach = cap - 1;
        let mut next = 0;
        while next < removed.len() {
            let (end, lo, hi) = group_end(removed, next, reach);
            let group = &removed[next..end];
            next = end;
            let (x0, x1) = ((lo.x - 2 * reach).max(0), (hi.x + 2 * reach).min(w - 1));
            let (y0, y1) = ((lo.y - reach).max(0), (hi.y + reach).min(h - 1));
            if x0 > x1 || y0 > y1 {
                continue;
            }
            let b = Recompute {
                x0,
                x1,
                y0,
                y1,
                reach,
                cap,
            };
            b.column_distances(grid, (w, h), col2, last);
            self.recompute(group, &b, col2);
        }
    }

    /// Sets the distance of the cells of the discs of the removed cells `group` within the box
    /// `b`, from the columns' squared vertical distances `col2`.
    fn recompute(&mut self, group: &[Cell], b: &Recompute, col2: &[i32]) {
        let w = self.frame.width as i32;
        let Recompute {
            x0,
            x1,
            y0,
            y1,
            reach,
            cap,
        } = *b;
        let (nx, cap2) = (b.nx(), cap * cap);
        let half_width = |dy: i32| -self.disc_rows[(dy + reach) as usize].1;
        for y in y0..=y1 {
            let (mut x_from, mut x_to) = (w, 0);
            for r in group.iter().filter(|r| (y - r.y).abs() <= reach) {
                let hw = half_width(y - r.y);
                (x_from, x_to) = (x_from.min(r.x - hw), x_to.max(r.x + hw + 1));
            }
            let (x_from, x_to) = (x_from.max(0), x_to.min(w));
            if x_from >= x_to {
                continue;
            }
            let cols = &col2[(y - y0) as usize * nx..(y - y0 + 1) as usize * nx];
            for x in x_from..x_to {
                let (c0, c1) = ((x - reach).max(x0), (x + reach).min(x1));
                let mut best = cap2;
                for (k, &v) in cols[(c0 - x0) as usize..=(c1 - x0) as usize]
                    .iter()
                    .enumerate()
                {
                    let dx = c0 + k as i32 - x;
                    best = best.min(v + dx * dx);
                }
                self.data[(y * w + x) as usize] = if best < cap2 {
                    (best as f32).sqrt()
                } else {
                    cap as f32
                };
            }
        }
    }

    /// [`ObstacleDistance::update`], pushing to `changed` the row-major indices of the cells
    /// whose distance it changed (some possibly more than once): only cells within the cap of a
    /// flipped cell can change (the others are at least the cap from it), so their values
    /// are kept before the update and compared after. Every cell if the frame changed.
    pub(crate) fn update_reporting(
        &mut self,
        grid: &OccupancyGrid,
        flips: &[u32],
        changed: &mut Vec<u32>,
    ) {
        if grid.frame != self.frame {
            self.update(grid, flips);
            changed.extend(0..self.data.len() as u32);
            return;
        }
        let (w, h) = (self.frame.width as i32, self.frame.height as i32);
        let mut scratch = std::mem::take(&mut self.scratch);
        // The discs' rows in the grid, as (first index, length), and their values before.
        let (spans, before) = (&mut scratch.spans, &mut scratch.before);
        spans.clear();
        for &i in flips {
            if i as usize >= self.data.len() {
                continue;
            }
            let c = self.frame.cell_of_index(i as usize);
            for (dy, dx0, ds) in &self.disc_rows {
                let (y, x0) = (c.y + dy, c.x + dx0);
                let (x_from, x_to) = (x0.max(0), (x0 + ds.len() as i32).min(w));
                if y >= 0 && y < h && x_from < x_to {
                    spans.push(((y * w + x_from) as usize, (x_to - x_from) as usize));
                }
            }
        }
        before.clear();
        for &(at, n) in spans.iter() {
            before.extend_from_slice(&self.data[at..at + n]);
        }
        self.remove_and_stamp(grid, flips, &mut scratch);
        let mut old = scratch.before.iter();
        for &(at, n) in &scratch.spans {
            for (k, (&new, &was)) in self.data[at..at + n].iter().zip(old.by_ref()).enumerate() {
                if new != was {
                    changed.push((at + k) as u32);
                }
            }
        }
        self.scratch = scratch;
    }

    /// Distance (cells) of a cell; the cap outside the grid.
    pub fn get(&self, c: Cell) -> f32 {
        self.frame
            .index(c)
            .map_or(self.cap_cells as f32, |i| self.data[i])
    }

    /// Bilinearly interpolated distance (cells) at a world point and its gradient (cells per
    /// metre... i.e. d(distance_cells)/d(world metre)). Cell values sit at cell centres.
    // (Always inlined, as profile-guided optimisation chose: BENCHMARKS.md.)
    #[inline(always)]
    pub fn sample(&self, p: Vec2) -> (f64, Vec2) {
        let inv_res = 1.0 / self.frame.resolution_m;
        let q = (p - self.frame.origin_m) * inv_res - Vec2::new(0.5, 0.5);
        let (x0, y0) = (floor_f64(q.x), floor_f64(q.y));
        let (fx, fy) = (q.x - x0, q.y - y0);
        let (x0, y0) = (x0 as i32, y0 as i32);
        let v = |x: i32, y: i32| self.get(Cell::new(x, y)) as f64;
        let (v00, v10, v01, v11) = (v(x0, y0), v(x0 + 1, y0), v(x0, y0 + 1), v(x0 + 1, y0 + 1));
        let d = v00 * (1.0 - fx) * (1.0 - fy)
            + v10 * fx * (1.0 - fy)
            + v01 * (1.0 - fx) * fy
            + v11 * fx * fy;
        let gx = ((v10 - v00) * (1.0 - fy) + (v11 - v01) * fy) * inv_res;
        let gy = ((v01 - v00) * (1.0 - fx) + (v11 - v10) * fx) * inv_res;
        (d, Vec2::new(gx, gy))
    }
}

/// The end (exclusive) of the group of removed cells starting at `next` (consecutive cells
/// within a box of `2 reach` cells), and the group's box (least and greatest corner).
fn group_end(removed: &[Cell], next: usize, reach: i32) -> (usize, Cell, Cell) {
    let first = removed[next];
    let (mut lo, mut hi) = (first, first);
    let mut end = next + 1;
    while let Some(&c) = removed.get(end) {
        let (l, u) = (
            Cell::new(lo.x.min(c.x), lo.y.min(c.y)),
            Cell::new(hi.x.max(c.x), hi.y.max(c.y)),
        );
        if u.x - l.x > 2 * reach || u.y - l.y > 2 * reach {
            break;
        }
        (lo, hi, end) = (l, u, end + 1);
    }
    (end, lo, hi)
}

/// The box of cells (inclusive) recomputed for a group of removed cells, the reach and the cap
/// (see `ObstacleDistance::remove_and_stamp`).
#[derive(Debug, Clone, Copy)]
struct Recompute {
    x0: i32,
    x1: i32,
    y0: i32,
    y1: i32,
    reach: i32,
    cap: i32,
}

impl Recompute {
    /// The box's width in cells.
    fn nx(&self) -> usize {
        (self.x1 - self.x0 + 1) as usize
    }

    /// Per row of the box and column, the squared vertical distance to the column's nearest
    /// obstacle within reach (the cap squared for none), into `col2`; `last` is scratch. The
    /// grid is `w` x `h` cells.
    fn column_distances(
        &self,
        grid: &OccupancyGrid,
        (w, h): (i32, i32),
        col2: &mut Vec<i32>,
        last: &mut Vec<i32>,
    ) {
        let Recompute {
            x0,
            x1,
            y0,
            y1,
            reach,
            cap,
        } = *self;
        let (nx, cap2) = (self.nx(), cap * cap);
        col2.clear();
        col2.resize((y1 - y0 + 1) as usize * nx, cap2);
        // Downwards (the nearest obstacle at or above), then upwards (at or below).
        let (top, bottom) = ((y0 - reach).max(0), (y1 + reach).min(h - 1));
        for down in [true, false] {
            last.clear();
            last.resize(nx, if down { i32::MIN / 2 } else { i32::MAX / 2 });
            for k in 0..=(if down { y1 - top } else { bottom - y0 }) {
                let y = if down { top + k } else { bottom - k };
                let row = &grid.data[(y * w + x0) as usize..(y * w + x1) as usize + 1];
                for (l, s) in last.iter_mut().zip(row) {
                    if *s == Occupancy::Occupied {
                        *l = y;
                    }
                }
                if y < y0 || y > y1 {
                    continue;
                }
                let out = &mut col2[(y - y0) as usize * nx..(y - y0 + 1) as usize * nx];
                for (o, &l) in out.iter_mut().zip(last.iter()) {
                    let d = (y - l).abs();
                    if d <= reach {
                        *o = (*o).min(d * d);
                    }
                }
            }
        }
    }
}

/// Lowers `data` (a grid `w` cells wide) to the distances of the disc `rows` centred at `o`,
/// in each row `y` only for `x` in `bounds(y)` (half-open) and inside the grid. Row by row: a
/// loop the compiler vectorises.
fn stamp_rows(
    data: &mut [f32],
    w: i32,
    rows: &[(i32, i32, Vec<f32>)],
    o: Cell,
    bounds: impl Fn(i32) -> (i32, i32),
) {
    let h = data.len() as i32 / w.max(1);
    for (dy, dx0, ds) in rows {
        let y = o.y + dy;
        if y < 0 || y >= h {
            continue;
        }
        let (lo, hi) = bounds(y);
        let x0 = o.x + dx0;
        let (x_from, x_to) = (x0.max(lo).max(0), (x0 + ds.len() as i32).min(hi).min(w));
        if x_from >= x_to {
            continue;
        }
        let row = (y * w) as usize;
        let dst = &mut data[row + x_from as usize..row + x_to as usize];
        let src = &ds[(x_from - x0) as usize..(x_to - x0) as usize];
        for (v, &d) in dst.iter_mut().zip(src) {
            *v = if d < *v { d } else { *v };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distance::distance_to;
    use crate::grid::Grid;
    use proptest::prelude::*;

    fn exact(grid: &OccupancyGrid, cap: u32) -> Vec<f32> {
        let mask = Grid {
            frame: grid.frame,
            data: grid
                .data
                .iter()
                .map(|s| *s == Occupancy::Occupied)
                .collect(),
        };
        distance_to(&mask)
            .data
            .into_iter()
            .map(|d| d.min(cap as f32))
            .collect()
    }

    proptest! {
        #[test]
        fn incremental_equals_exact(ops in proptest::collection::vec((0u32..30, 0u32..20, any::<bool>()), 1..60)) {
            let frame = GridFrame::new(Vec2::zeros(), 0.1, 30, 20);
            let mut grid = Grid::filled(frame, Occupancy::Free);
            let mut field = ObstacleDistance::new(frame, 4);
            for (x, y, occ) in ops {
                let c = Cell::new(x as i32, y as i32);
                let before = grid.is(c, Occupancy::Occupied);
                grid.set(c, if occ { Occupancy::Occupied } else { Occupancy::Free });
                if before != occ {
                    field.update(&grid, &[frame.index(c).unwrap() as u32]);
                }
            }
            let want = exact(&grid, 4);
            for (i, (a, b)) in field.data.iter().zip(&want).enumerate() {
                prop_assert!((a - b).abs() < 1e-4, "cell {:?}: {} vs {}", frame.cell_of_index(i), a, b);
            }
        }
    }

    /// [`ObstacleDistance::update`] as first written: each removed obstacle's disc reset and
    /// restamped, cut to that disc, from every obstacle within twice the cap of it.
    fn update_reference(f: &mut ObstacleDistance, grid: &OccupancyGrid, flips: &[u32]) {
        let mut removed = Vec::new();
        for &i in flips {
            let i = i as usize;
            if i >= grid.data.len() {
                continue;
            }
            let c = f.frame.cell_of_index(i);
            if grid.data[i] == Occupancy::Occupied {
                f.stamp(c);
            } else {
                removed.push(c);
            }
        }
        removed.sort_unstable();
        removed.dedup();
        let cap = f.cap_cells as i32;
        let (w, h) = (f.frame.width as i32, f.frame.height as i32);
        for &c in &removed {
            for (dy, dx0, ds) in &f.disc_rows {
                let y = c.y + dy;
                let x0 = c.x + dx0;
                let (x_from, x_to) = (x0.max(0), (x0 + ds.len() as i32).min(w));
                if y >= 0 && y < h && x_from < x_to {
                    let row = (y * w) as usize;
                    f.data[row + x_from as usize..row + x_to as usize].fill(cap as f32);
                }
            }
            for oy in (c.y - 2 * cap).max(0)..=(c.y + 2 * cap).min(h - 1) {
                for ox in (c.x - 2 * cap).max(0)..=(c.x + 2 * cap).min(w - 1) {
                    if grid.data[(oy * w + ox) as usize] != Occupancy::Occupied {
                        continue;
                    }
                    // (The disc of `c`'s row `y`: its half width is minus its first dx.)
                    let half_of =
                        |y: i32| f.disc_rows.iter().find(|r| r.0 == y - c.y).map(|r| -r.1);
                    stamp_rows(
                        &mut f.data,
                        w,
                        &f.disc_rows,
                        Cell::new(ox, oy),
                        |y| match half_of(y) {
                            Some(half) => (c.x - half, c.x + half + 1),
                            None => (0, 0),
                        },
                    );
                }
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]
        /// Batches of flips (walls appearing and vanishing together, as a scan's do) leave the
        /// same bits as the removals handled one by one, and report the cells they changed.
        #[test]
        fn batched_removals_equal_one_by_one(
            w in 1i32..48, h in 1i32..40, cap in 1u32..7,
            density in prop_oneof![Just(0.01), Just(0.04), Just(0.15)],
            seed in any::<u64>(),
            batches in proptest::collection::vec(
                proptest::collection::vec((0i32..48, 0i32..40, proptest::bool::weighted(0.3)), 0..40), 1..5),
        ) {
            let frame = GridFrame::new(Vec2::zeros(), 0.1, w as u32, h as u32);
            let mut grid = Grid::filled(frame, Occupancy::Free);
            // Sparse obstacles too, so that the farthest obstacle that reaches a reset cell is
            // often its nearest.
            let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(seed);
            for s in grid.data.iter_mut() {
                if rand::Rng::random_bool(&mut rng, density) { *s = Occupancy::Occupied; }
            }
            let mut new = ObstacleDistance::from_grid(&grid, cap);
            let mut old = new.clone();
            for batch in batches {
                let mut flips = Vec::new();
                for (x, y, occ) in batch {
                    let c = Cell::new(x % w, y % h);
                    let s = if occ { Occupancy::Occupied } else { Occupancy::Free };
                    if grid.get(c) != Some(&s) {
                        grid.set(c, s);
                        flips.push(frame.index(c).unwrap() as u32);
                    }
                }
                let before = new.data.clone();
                let mut changed = Vec::new();
                new.update_reporting(&grid, &flips, &mut changed);
                update_reference(&mut old, &grid, &flips);
                prop_assert_eq!(&new.data, &old.data);
                // The cells reported are those whose distance changed.
                changed.sort_unstable();
                changed.dedup();
                let differ: Vec<u32> = (0..before.len() as u32)
                    .filter(|&i| before[i as usize] != new.data[i as usize])
                    .collect();
                prop_assert_eq!(changed, differ);
            }
        }
    }

    #[test]
    fn walls_removed_at_once_equal_the_reference() {
        // Removed cells in lines and clusters (done together, in groups of nearby cells),
        // among other walls, near the frame's edges and inside it: the same bits as the first
        // update and as the exact transform.
        let frame = GridFrame::new(Vec2::zeros(), 0.1, 40, 30);
        let shapes: [(&str, Vec<(i32, i32)>); 6] = [
            ("row", (3..25).map(|x| (x, 12)).collect()),
            ("column", (0..30).map(|y| (17, y)).collect()),
            ("diagonal", (0..20).map(|k| (5 + k, 4 + k)).collect()),
            (
                "L",
                (10..30)
                    .map(|x| (x, 2))
                    .chain((2..20).map(|y| (10, y)))
                    .collect(),
            ),
            ("far apart in a column", vec![(20, 0), (20, 29), (21, 15)]),
            (
                "block at a corner",
                (0..6).flat_map(|x| (0..5).map(move |y| (x, y))).collect(),
            ),
        ];
        for cap in [1, 2, 4, 7] {
            for (name, cells) in &shapes {
                let mut grid = Grid::filled(frame, Occupancy::Free);
                for y in (0..30).step_by(7) {
                    for x in 0..40 {
                        grid.set(Cell::new(x, y), Occupancy::Occupied);
                    }
                }
                for &(x, y) in cells {
                    grid.set(Cell::new(x, y), Occupancy::Occupied);
                }
                let mut new = ObstacleDistance::from_grid(&grid, cap);
                let mut old = new.clone();
                let mut flips = Vec::new();
                for &(x, y) in cells {
                    grid.set(Cell::new(x, y), Occupancy::Free);
                    flips.push(frame.index(Cell::new(x, y)).unwrap() as u32);
                }
                new.update(&grid, &flips);
                update_reference(&mut old, &grid, &flips);
                assert!(new.data == old.data, "{name}, cap {cap}");
                let want = exact(&grid, cap);
                for (i, (a, b)) in new.data.iter().zip(&want).enumerate() {
                    let c = frame.cell_of_index(i);
                    assert!((a - b).abs() < 1e-4, "{name}, cap {cap}, {c:?}: {a} vs {b}");
                }
            }
        }
    }

    #[test]
    fn gradient_points_away_from_obstacle() {
        let frame = GridFrame::new(Vec2::zeros(), 0.1, 20, 20);
        let mut grid = Grid::filled(frame, Occupancy::Free);
        grid.set(Cell::new(10, 10), Occupancy::Occupied);
        let f = ObstacleDistance::from_grid(&grid, 6);
        let (d, g) = f.sample(Vec2::new(1.33, 1.05));
        assert!(d > 2.0 && d < 3.0, "{d}");
        assert!(g.x > 5.0 && g.y.abs() < 3.0, "{g:?}");
    }
}
