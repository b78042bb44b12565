//! Information gains of frontier candidates, reused between decisions while the map around a
//! candidate has not changed where its rays went.
//!
//! Every ternary change of a cell stamps the cell, its square block and the block's group with
//! the current map-update number. A gain computed at update `k` for cell `p` stays valid while
//! no cell it read has a later stamp: the gain only depends on the cells it read. The cells
//! read are those of the rays up to where each stopped, at a wall or at the range
//! ([`CellsRead`]): the changed cells to look up among them are found through the blocks that
//! changed within the laser range of `p` (plus two cells, for the cells a ray crosses at its
//! very end) and the boxes of the cells read, a group's or a block's stamp sparing the cells of
//! those unchanged. A gain found valid at update `n` is then the gain computed at `n` (the same
//! cells, unchanged, read again), and later lookups look at the changes after `n` only.
//!
//! A plain gain (the unknown cells visible from `p`, [`crate::gain::information_count_read`])
//! is also kept as a number of cells, and brought up to date without its rays when no cell it
//! read changed whether it blocks (is occupied): the same cells are then visible, and the count
//! falls by one for each visible cell within range that stopped being unknown since. A cell's
//! changes are one from unknown to free, or none, and then changes between free and occupied
//! (it never becomes unknown again), so a cell's last change tells whether it blocked or
//! unblocked since any earlier update: each cell's stamp carries whether its last change was
//! of whether it is occupied ([`BLOCKING`]).
//!
//! Gains of different kinds are kept apart ([`GainKind`]): a new layout makes the gains computed
//! with the previous one stale, but not the plain gains, which read only the map (the paper's
//! `I(p)` falls back to them for most candidates, those in rooms with an open frontier).

use std::collections::btree_map::Entry;
use std::collections::BTreeMap;

use crate::gain::{CellBox, CellsRead};
use crate::grid::{Cell, GridFrame};

/// What a cached gain was computed with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum GainKind {
    /// [`crate::gain::information_gain`]: the map only.
    Plain = 0,
    /// [`crate::layout_gain::gap_closed_information_gain`] with the current layout.
    GapClosed = 1,
    /// [`crate::layout_gain::layout_information_gain`] with the current layout, for a candidate
    /// that does not fall back to the plain gain.
    Rooms = 2,
}

/// Side of a block in cells.
const BLOCK_CELLS: i32 = 8;
/// Side of a group of blocks in blocks: a group's stamp is the latest of its blocks', so that
/// the blocks of a group unchanged since a gain need not be read.
const GROUP_BLOCKS: i32 = 8;

/// The flag of a cell's stamp: its last change was of whether it is occupied. The stamp
/// itself is the rest (at most [`STAMP_MAX`]).
const BLOCKING: u32 = 1 << 31;
const STAMP_MAX: u32 = BLOCKING - 1;

/// A gain kept: its value, the update at which it was computed, where the cells it read lie,
/// and for a plain gain the number of cells it counts.
#[derive(Debug, Clone)]
struct Cached {
    gain: f64,
    at: u64,
    read: CellsRead,
    count: Option<usize>,
}

/// What changed since a gain was computed among the cells it may have read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Since {
    /// Nothing: the gain is the same.
    Nothing,
    /// No cell that may have been read changed whether it blocks; `n` cells visible within
    /// range stopped being unknown (a plain count is lower by `n`).
    Unblocked(usize),
    /// Anything else: the gain is computed again.
    Changed,
}

#[derive(Debug, Clone)]
pub(crate) struct GainCache {
    frame: GridFrame,
    blocks_w: i32,
    blocks_h: i32,
    groups_w: i32,
    /// Map update that last changed each block.
    stamps: Vec<u64>,
    /// Map update that last changed each group of blocks.
    group_stamps: Vec<u64>,
    /// Map update that last changed each cell (at most [`STAMP_MAX`]), with [`BLOCKING`] when
    /// that change was of whether the cell is occupied.
    cell_stamps: Vec<u32>,
    /// Per [`GainKind`]: candidate cell -> its gain.
    gains: [BTreeMap<(i32, i32), Cached>; 3],
}

impl GainCache {
    pub(crate) fn new(frame: GridFrame) -> Self {
        let blocks_w = (frame.width as i32 + BLOCK_CELLS - 1) / BLOCK_CELLS;
        let blocks_h = (frame.height as i32 + BLOCK_CELLS - 1) / BLOCK_CELLS;
        let groups_w = (blocks_w + GROUP_BLOCKS - 1) / GROUP_BLOCKS;
        let groups_h = (blocks_h + GROUP_BLOCKS - 1) / GROUP_BLOCKS;
        Self {
            frame,
            blocks_w,
            blocks_h,
            groups_w,
            stamps: vec![0; (blocks_w.max(0) * blocks_h.max(0)) as usize],
            group_stamps: vec![0; (groups_w.max(0) * groups_h.max(0)) as usize],
            cell_stamps: vec![0; frame.len()],
            gains: Default::default(),
        }
    }

    /// Records that the cell with row-major index `i` changed at update `now`, and whether the
    /// change was of whether it is occupied (`blocking`). Of the changes of one update, those
    /// of whether cells are occupied are recorded last.
    pub(crate) fn touch(&mut self, i: u32, now: u64, blocking: bool) {
        let w = self.frame.width as usize;
        if w == 0 {
            return;
        }
        if let Some(s) = self.cell_stamps.get_mut(i as usize) {
            *s = now.min(STAMP_MAX as u64) as u32 | if blocking { BLOCKING } else { 0 };
        }
        let (x, y) = ((i as usize % w) as i32, (i as usize / w) as i32);
        let (bx, by) = (x / BLOCK_CELLS, y / BLOCK_CELLS);
        if let Some(s) = self.stamps.get_mut((by * self.blocks_w + bx) as usize) {
            *s = now;
        }
        let g = (by / GROUP_BLOCKS) * self.groups_w + bx / GROUP_BLOCKS;
        if let Some(s) = self.group_stamps.get_mut(g as usize) {
            *s = now;
        }
    }

    /// Forgets the gains computed with a layout (when the layout changed); the plain gains stay.
    pub(crate) fn clear_layout_gains(&mut self) {
        self.gains[GainKind::GapClosed as usize].clear();
        self.gains[GainKind::Rooms as usize].clear();
    }

    /// The gain of `p` of the given kind, computed by `compute` (the gain, and where the cells
    /// it read lie) unless a still valid one is cached.
    pub(crate) fn gain(
        &mut self,
        kind: GainKind,
        p: Cell,
        range_m: f64,
        now: u64,
        compute: impl FnOnce() -> (f64, CellsRead),
    ) -> f64 {
        // (The kind's map is taken out for the call, so that the entry is found once and the
        // cache's stamps read while it is held; taking a map allocates nothing. Should `compute`
        // panic, the kind's gains are forgotten: computed again, they are the same.)
        let mut gains = std::mem::take(&mut self.gains[kind as usize]);
        let g = match gains.entry((p.x, p.y)) {
            // Computed now, the gain would read the same cells, unchanged: the same value and
            // cells read. Later lookups need only look at the changes after this one.
            Entry::Occupied(mut e)
                if self.changed_since(p, range_m, &e.get().read, e.get().at, false)
                    == Since::Nothing =>
            {
                e.get_mut().at = now;
                e.get().gain
            }
            entry => {
                let (gain, read) = compute();
                let cached = Cached {
                    gain,
                    at: now,
                    read,
                    count: None,
                };
                match entry {
                    Entry::Occupied(mut e) => *e.get_mut() = cached,
                    Entry::Vacant(e) => {
                        e.insert(cached);
                    }
                }
                gain
            }
        };
        self.gains[kind as usize] = gains;
        g
    }

    /// The plain gain of `p` (the unknown area visible from it), from `compute` (the number of
    /// unknown cells visible, [`crate::gain::information_count_read`], and where the cells it
    /// read lie) unless a kept one is still valid or can be brought up to date without it (no
    /// cell it read changed whether it blocks: see the module's doc).
    pub(crate) fn plain_gain(
        &mut self,
        p: Cell,
        range_m: f64,
        now: u64,
        compute: impl FnOnce() -> (usize, CellsRead),
    ) -> f64 {
        let area = self.frame.cell_area_m2();
        let mut gains = std::mem::take(&mut self.gains[GainKind::Plain as usize]);
        let g = match gains.entry((p.x, p.y)) {
            Entry::Occupied(mut e) => {
                let kept = e.get();
                match (
                    kept.count,
                    self.changed_since(p, range_m, &kept.read, kept.at, true),
                ) {
                    (_, Since::Nothing) => {
                        e.get_mut().at = now;
                        e.get().gain
                    }
                    (Some(count), Since::Unblocked(n)) if n <= count => {
                        // (As `compute` would give it: the count's cells times their area.)
                        let count = count - n;
                        let gain = count as f64 * area;
                        let kept = e.get_mut();
                        (kept.at, kept.count, kept.gain) = (now, Some(count), gain);
                        gain
                    }
                    _ => {
                        let (count, read) = compute();
                        let gain = count as f64 * area;
                        *e.get_mut() = Cached {
                            gain,
                            at: now,
                            read,
                            count: Some(count),
                        };
                        gain
                    }
                }
            }
            Entry::Vacant(e) => {
                let (count, read) = compute();
                let gain = count as f64 * area;
                e.insert(Cached {
                    gain,
                    at: now,
                    read,
                    count: Some(count),
                });
                gain
            }
        };
        self.gains[GainKind::Plain as usize] = gains;
        g
    }

    /// What changed after update `at` among the cells that `read` may have read
    /// ([`CellsRead::may_have_read`]), in the boxes read and within the range of `p` (and two
    /// cells): with `count`, how many visible cells stopped being unknown if no cell read
    /// changed whether it blocks; without, only whether anything changed (the first change
    /// found ends the search).
    fn changed_since(
        &self,
        p: Cell,
        range_m: f64,
        read: &CellsRead,
        at: u64,
        count: bool,
    ) -> Since {
        let r = (range_m / self.frame.resolution_m).ceil() as i32 + 2;
        let mut boxes = read.boxes.iter();
        let first = *boxes.next().expect("four boxes");
        let all = boxes.fold(first, |a, b| CellBox {
            min: Cell::new(a.min.x.min(b.min.x), a.min.y.min(b.min.y)),
            max: Cell::new(a.max.x.max(b.max.x), a.max.y.max(b.max.y)),
        });
        let (x0, x1) = ((p.x - r).max(all.min.x), (p.x + r).min(all.max.x));
        let (y0, y1) = ((p.y - r).max(all.min.y), (p.y + r).min(all.max.y));
        if x0 > x1 || y0 > y1 {
            return Since::Nothing;
        }
        let bx0 = x0.div_euclid(BLOCK_CELLS).max(0);
        let by0 = y0.div_euclid(BLOCK_CELLS).max(0);
        let bx1 = x1.div_euclid(BLOCK_CELLS).min(self.blocks_w - 1);
        let by1 = y1.div_euclid(BLOCK_CELLS).min(self.blocks_h - 1);
        if bx0 > bx1 || by0 > by1 {
            return Since::Nothing; // (outside the frame, whose cells never change)
        }
        // Distance (cells) from `p` to the nearest cell of the range `lo..lo + side`.
        let gap = |v: i32, lo: i32, side: i32| (lo - v).max(v - (lo + side - 1)).max(0) as i64;
        let r2 = r as i64 * r as i64;
        let group = BLOCK_CELLS * GROUP_BLOCKS;
        let mut since = Since::Nothing;
        for gy in by0 / GROUP_BLOCKS..=by1 / GROUP_BLOCKS {
            let gdy = gap(p.y, gy * group, group);
            for gx in bx0 / GROUP_BLOCKS..=bx1 / GROUP_BLOCKS {
                let gdx = gap(p.x, gx * group, group);
                if self.group_stamps[(gy * self.groups_w + gx) as usize] <= at
                    || gdx * gdx + gdy * gdy > r2
                {
                    continue;
                }
                let (ys, xs) = (gy * GROUP_BLOCKS, gx * GROUP_BLOCKS);
                for by in by0.max(ys)..=by1.min(ys + GROUP_BLOCKS - 1) {
                    let dy = gap(p.y, by * BLOCK_CELLS, BLOCK_CELLS);
                    for bx in bx0.max(xs)..=bx1.min(xs + GROUP_BLOCKS - 1) {
                        let dx = gap(p.x, bx * BLOCK_CELLS, BLOCK_CELLS);
                        if dx * dx + dy * dy > r2
                            || self.stamps[(by * self.blocks_w + bx) as usize] <= at
                        {
                            continue;
                        }
                        let block = (bx, by);
                        match self.read_changed_cells(p, read, block, (x0, x1, y0, y1), at, count) {
                            Since::Nothing => {}
                            Since::Changed => return Since::Changed,
                            Since::Unblocked(n) => {
                                since = match since {
                                    Since::Unblocked(m) => Since::Unblocked(m + n),
                                    _ => Since::Unblocked(n),
                                }
                            }
                        }
                    }
                }
            }
        }
        since
    }

    /// What changed after update `at` among the cells of block `(bx, by)` within `x0..=x1`,
    /// `y0..=y1` that may have been read ([`Self::changed_since`]).
    fn read_changed_cells(
        &self,
        p: Cell,
        read: &CellsRead,
        (bx, by): (i32, i32),
        (x0, x1, y0, y1): (i32, i32, i32, i32),
        at: u64,
        count: bool,
    ) -> Since {
        if at >= STAMP_MAX as u64 {
            return Since::Changed; // (the cells' stamps cannot tell)
        }
        let w = self.frame.width as i32;
        let x0 = (bx * BLOCK_CELLS).max(x0).max(0);
        let y0 = (by * BLOCK_CELLS).max(y0).max(0);
        let x1 = (bx * BLOCK_CELLS + BLOCK_CELLS).min(x1 + 1).min(w);
        let y1 = (by * BLOCK_CELLS + BLOCK_CELLS)
            .min(y1 + 1)
            .min(self.frame.height as i32);
        if x0 >= x1 || y0 >= y1 {
            return Since::Nothing; // (the window ends beyond the frame: no cell of it)
        }
        let at = at as u32;
        let mut opened = 0usize;
        for y in y0..y1 {
            let row = &self.cell_stamps[(y * w + x0) as usize..(y * w + x1) as usize];
            // The row's changed cells as bits, then only those looked up.
            let mut changed = row
                .iter()
                .enumerate()
                .fold(0u32, |m, (k, &s)| m | ((s & STAMP_MAX > at) as u32) << k);
            while changed != 0 {
                let k = changed.trailing_zeros();
                changed &= changed - 1;
                let c = Cell::new(x0 + k as i32, y);
                // With the rays' stops kept, a cell whose last change was not of whether it
                // blocks stopped being unknown after `at` and did not block then or since: if
                // read, it counted then when within range, and counts no more.
                let opened_cell = count && row[k as usize] & BLOCKING == 0;
                match opened_cell.then(|| read.rays.read_in_range(p, c)).flatten() {
                    Some((false, _)) => {}
                    Some((true, in_range)) => opened += in_range as usize,
                    None if read.may_have_read(p, c) => return Since::Changed,
                    None => {}
                }
            }
        }
        if opened > 0 {
            Since::Unblocked(opened)
        } else {
            Since::Nothing
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec2;
    use crate::grid::{Occupancy, OccupancyGrid};

    /// The gain `value` of `p`, unless one is kept, as computed by a fan whose cells read are
    /// anywhere near (any change within range makes it stale).
    fn near(
        cache: &mut GainCache,
        kind: GainKind,
        p: Cell,
        range_m: f64,
        now: u64,
        value: f64,
    ) -> f64 {
        let whole = CellBox {
            min: Cell::new(-1000, -1000),
            max: Cell::new(1000, 1000),
        };
        cache.gain(kind, p, range_m, now, || {
            let mut read = CellsRead::of(p);
            read.boxes = [whole; 4];
            (value, read)
        })
    }

    #[test]
    fn reuses_until_a_change_within_range() {
        let frame = GridFrame::new(Vec2::zeros(), 0.05, 400, 100);
        let mut cache = GainCache::new(frame);
        let p = Cell::new(20, 20);
        assert_eq!(near(&mut cache, GainKind::Plain, p, 1.0, 1, 5.0), 5.0);
        assert_eq!(near(&mut cache, GainKind::Plain, p, 1.0, 2, 7.0), 5.0);
        // A change far away (x = 300 cells = 15 m) keeps the cached value.
        cache.touch(frame.index(Cell::new(300, 20)).unwrap() as u32, 3, false);
        assert_eq!(near(&mut cache, GainKind::Plain, p, 1.0, 3, 7.0), 5.0);
        // A change within range invalidates it.
        cache.touch(frame.index(Cell::new(30, 25)).unwrap() as u32, 4, false);
        assert_eq!(near(&mut cache, GainKind::Plain, p, 1.0, 4, 7.0), 7.0);
        assert_eq!(near(&mut cache, GainKind::Plain, p, 1.0, 5, 9.0), 7.0);
    }

    #[test]
    fn a_change_in_the_corner_of_the_square_around_the_range_keeps_the_gain() {
        let frame = GridFrame::new(Vec2::zeros(), 0.05, 100, 100);
        let mut cache = GainCache::new(frame);
        // Range 2 m = 40 cells (42 with the margin) around (8, 8).
        let p = Cell::new(8, 8);
        assert_eq!(near(&mut cache, GainKind::Plain, p, 2.0, 1, 5.0), 5.0);
        // (49, 49) is 58 cells away, in the block (48..56)^2 that a square around the range
        // covers but the range does not reach.
        cache.touch(frame.index(Cell::new(49, 49)).unwrap() as u32, 2, false);
        assert_eq!(near(&mut cache, GainKind::Plain, p, 2.0, 2, 7.0), 5.0);
        // (48, 8), in the same row of blocks, is 40 cells away: within range.
        cache.touch(frame.index(Cell::new(48, 8)).unwrap() as u32, 3, false);
        assert_eq!(near(&mut cache, GainKind::Plain, p, 2.0, 3, 7.0), 7.0);
    }

    #[test]
    fn boxes_outside_the_frame_are_read_as_far_as_it_goes() {
        // Boxes reaching outside the frame, or lying wholly outside it, are read as far as the
        // frame goes (none of the frame, no block at all).
        for frame in [
            GridFrame::new(Vec2::zeros(), 0.05, 0, 0),
            GridFrame::new(Vec2::zeros(), 0.05, 3, 2),
        ] {
            let mut cache = GainCache::new(frame);
            let far = CellsRead::of(Cell::new(-50, 70));
            let p = Cell::new(1, 1);
            assert_eq!(
                cache.gain(GainKind::Plain, p, 2.0, 1, || (3.0, far.clone())),
                3.0
            );
            cache.touch(0, 2, false);
            assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 2, || (9.0, far)), 3.0);
            let near = CellsRead::of(Cell::new(0, 0));
            let compute = |v: f64| (v, near.clone());
            assert_eq!(cache.gain(GainKind::Rooms, p, 2.0, 2, || compute(4.0)), 4.0);
            cache.touch(0, 3, false);
            let expected = if frame.is_empty() { 4.0 } else { 5.0 };
            assert_eq!(
                cache.gain(GainKind::Rooms, p, 2.0, 3, || compute(5.0)),
                expected
            );
        }
    }

    #[test]
    fn a_change_within_range_outside_the_cells_read_keeps_the_gain() {
        let frame = GridFrame::new(Vec2::zeros(), 0.05, 200, 200);
        // Range 2 m = 40 cells around (100, 100); the gain read a room east of it (the cells
        // up to x = 120) and nothing west of x = 96 (its boxes; no rays kept).
        let p = Cell::new(100, 100);
        let room = CellBox {
            min: Cell::new(96, 90),
            max: Cell::new(120, 110),
        };
        let mut read = CellsRead::of(p);
        read.boxes = [room; 4];
        let compute = |v: f64| (v, read.clone());
        let mut cache = GainCache::new(frame);
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 1, || compute(5.0)), 5.0);
        // Within range, west of the room: kept.
        cache.touch(frame.index(Cell::new(80, 100)).unwrap() as u32, 2, false);
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 2, || compute(7.0)), 5.0);
        // North of the room: kept.
        cache.touch(frame.index(Cell::new(110, 125)).unwrap() as u32, 3, false);
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 3, || compute(7.0)), 5.0);
        // Next to the room, in the same block as its east wall (x 120..128): kept.
        cache.touch(frame.index(Cell::new(121, 100)).unwrap() as u32, 4, false);
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 4, || compute(7.0)), 5.0);
        // On the room's east wall: computed again.
        cache.touch(frame.index(Cell::new(120, 100)).unwrap() as u32, 5, false);
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 5, || compute(7.0)), 7.0);
        // Any one of the boxes read counts.
        let mut cache = GainCache::new(frame);
        let mut one = CellsRead::of(p);
        one.boxes[3] = room;
        let compute = |v: f64| (v, one.clone());
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 1, || compute(5.0)), 5.0);
        cache.touch(frame.index(Cell::new(80, 100)).unwrap() as u32, 2, false);
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 2, || compute(7.0)), 5.0);
        cache.touch(frame.index(Cell::new(97, 91)).unwrap() as u32, 3, false);
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 3, || compute(9.0)), 9.0);
    }

    #[test]
    fn a_gain_is_kept_until_a_cell_its_rays_read_changes() {
        // A room of cells x 10..=40, y 10..=20 (its walls included) at 5 cm in unknown, open to
        // the east through a door (x 40, y 14..=16); the candidate at its west end. Cells
        // changed behind the room's walls (in blocks its rays reach) keep the gain; a cell on
        // the rays' way, or one the door lets them reach, does not.
        let frame = GridFrame::new(Vec2::zeros(), 0.05, 90, 40);
        let mut grid = OccupancyGrid::filled(frame, Occupancy::Unknown);
        for y in 10..=20 {
            for x in 10..=40 {
                let wall = (y == 10 || y == 20 || x == 10 || x == 40)
                    && !(x == 40 && (14..=16).contains(&y));
                grid.set(
                    Cell::new(x, y),
                    if wall {
                        Occupancy::Occupied
                    } else {
                        Occupancy::Free
                    },
                );
            }
        }
        let p = Cell::new(12, 15);
        let range_m = 2.0;
        let mut cache = GainCache::new(grid.frame);
        let mut now = 1;
        let exact = |grid: &OccupancyGrid| crate::gain::information_gain_read(grid, p, range_m);
        let first = cache.gain(GainKind::Plain, p, range_m, now, || exact(&grid));
        assert!(first > 0.0, "the door lets the rays out");
        // (cell, whether the gain is computed again): each change is made and undone in turn.
        let cases = [
            (Cell::new(20, 9), false),  // north of the wall, behind it
            (Cell::new(9, 15), false),  // west of the wall, behind it
            (Cell::new(30, 21), false), // south of the wall, behind it
            // Beyond the door, within the boxes of the cells read but off every ray.
            (Cell::new(50, 19), false),
            (Cell::new(45, 11), false),
            (Cell::new(25, 15), true), // in the room, in the rays' way
            (Cell::new(20, 10), true), // the wall itself, where rays stop
            (Cell::new(45, 15), true), // beyond the door, in the rays' way
        ];
        for (cell, recomputed) in cases {
            for state in [Occupancy::Occupied, *grid.get(cell).expect("in the map")] {
                now += 1;
                grid.set(cell, state);
                cache.touch(grid.frame.index(cell).unwrap() as u32, now, true);
                let mut computed = false;
                let g = cache.gain(GainKind::Plain, p, range_m, now, || {
                    computed = true;
                    exact(&grid)
                });
                assert_eq!(computed, recomputed, "{cell:?} set {state:?}");
                assert_eq!(g, exact(&grid).0, "{cell:?} set {state:?}");
            }
        }
    }

    #[test]
    fn a_new_layout_forgets_the_layout_gains_only() {
        let frame = GridFrame::new(Vec2::zeros(), 0.05, 100, 100);
        let mut cache = GainCache::new(frame);
        let p = Cell::new(50, 50);
        for (k, kind) in [GainKind::Plain, GainKind::GapClosed, GainKind::Rooms]
            .into_iter()
            .enumerate()
        {
            assert_eq!(near(&mut cache, kind, p, 1.0, 1, k as f64), k as f64);
        }
        // Kinds do not share values.
        assert_eq!(near(&mut cache, GainKind::Rooms, p, 1.0, 2, 9.0), 2.0);
        cache.clear_layout_gains();
        assert_eq!(near(&mut cache, GainKind::Plain, p, 1.0, 3, 9.0), 0.0);
        assert_eq!(near(&mut cache, GainKind::GapClosed, p, 1.0, 3, 9.0), 9.0);
        assert_eq!(near(&mut cache, GainKind::Rooms, p, 1.0, 3, 8.0), 8.0);
        // A change within range invalidates every kind.
        cache.touch(frame.index(Cell::new(52, 50)).unwrap() as u32, 4, false);
        assert_eq!(near(&mut cache, GainKind::Plain, p, 1.0, 4, 7.0), 7.0);
        assert_eq!(near(&mut cache, GainKind::Rooms, p, 1.0, 4, 6.0), 6.0);
    }

    /// A map changed as a log-odds map changes (a cell goes from unknown to free or occupied,
    /// then between free and occupied, never back to unknown), each update's changes recorded
    /// as the run records them (changes of whether a cell is free, then of whether it is
    /// occupied): after every update, each candidate's plain gain from the cache, computed
    /// again or brought up to date, equals the gain computed afresh, to the bit. The cases
    /// bring gains up to date without their rays (cells only opened where they were read) and
    /// compute them again (a wall appears or goes), both many times.
    #[test]
    fn plain_gains_brought_up_to_date_equal_gains_computed_afresh() {
        use crate::gain::{information_count_read, information_gain_read};
        use rand::{Rng, SeedableRng};
        let (mut updated, mut recomputed) = (0usize, 0usize);
        for seed in 0..40u64 {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let frame = GridFrame::new(Vec2::new(-1.0, 2.0), 0.05, 70, 56);
            let mut grid = OccupancyGrid::filled(frame, Occupancy::Unknown);
            // A few walls and free patches to start from.
            for _ in 0..rng.random_range(0..6) {
                let (x, y) = (rng.random_range(0..70), rng.random_range(0..56));
                let (horizontal, len) = (rng.random_bool(0.5), rng.random_range(3..30));
                for k in 0..len {
                    let c = if horizontal {
                        Cell::new(x + k, y)
                    } else {
                        Cell::new(x, y + k)
                    };
                    if frame.contains(c) {
                        grid.set(c, Occupancy::Occupied);
                    }
                }
            }
            let range_m = rng.random_range(0.4..1.6);
            let candidates: Vec<Cell> = (0..6)
                .map(|_| Cell::new(rng.random_range(-2..72), rng.random_range(-2..58)))
                .collect();
            let mut cache = GainCache::new(frame);
            for now in 1..60u64 {
                // An update: cells near a candidate (or anywhere) change, some more than once.
                let (mut free_changes, mut flips) = (Vec::new(), Vec::new());
                for _ in 0..rng.random_range(0..40) {
                    let near = candidates[rng.random_range(0..candidates.len())];
                    let c = if rng.random_bool(0.8) {
                        Cell::new(
                            near.x + rng.random_range(-25..=25),
                            near.y + rng.random_range(-25..=25),
                        )
                    } else {
                        Cell::new(rng.random_range(0..70), rng.random_range(0..56))
                    };
                    let Some(i) = frame.index(c) else { continue };
                    let old = grid.data[i];
                    let new = match old {
                        Occupancy::Unknown if rng.random_bool(0.85) => Occupancy::Free,
                        Occupancy::Unknown | Occupancy::Free => Occupancy::Occupied,
                        Occupancy::Occupied => Occupancy::Free,
                    };
                    grid.data[i] = new;
                    if (old == Occupancy::Free) != (new == Occupancy::Free) {
                        free_changes.push(i as u32);
                    }
                    if (old == Occupancy::Occupied) != (new == Occupancy::Occupied) {
                        flips.push(i as u32);
                    }
                }
                for &i in &free_changes {
                    cache.touch(i, now, false);
                }
                for &i in &flips {
                    cache.touch(i, now, true);
                }
                for &p in &candidates {
                    let mut computed = false;
                    let before = cache.gains[GainKind::Plain as usize]
                        .get(&(p.x, p.y))
                        .map(|k| k.gain);
                    let g = cache.plain_gain(p, range_m, now, || {
                        computed = true;
                        information_count_read(&grid, p, range_m)
                    });
                    let fresh = information_gain_read(&grid, p, range_m).0;
                    assert_eq!(
                        g.to_bits(),
                        fresh.to_bits(),
                        "seed {seed}, update {now}, {p:?}: kept {g}, afresh {fresh}"
                    );
                    if computed {
                        recomputed += 1;
                    } else if before.is_some_and(|b| b != g) {
                        updated += 1;
                    }
                }
            }
        }
        assert!(
            updated > 500,
            "brought up to date without rays {updated} times"
        );
        assert!(recomputed > 500, "computed again {recomputed} times");
    }
}
