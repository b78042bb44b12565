//! Information gains of frontier candidates, reused between decisions while the map around a
//! candidate has not changed.
//!
//! The map is divided into square blocks; every ternary change of a cell stamps its block with
//! the current map-update number. A gain computed at update `k` for cell `p` stays valid while
//! no block that holds a cell of the boxes of the cells it read ([`CellsRead`]: the rays' cells
//! up to where they stopped, at a wall or at the range, one box per quadrant) and comes within
//! the laser range of `p` (plus two cells, for the cells a ray crosses at its very end) has a
//! later stamp: the gain only depends on the cells it read. (Boxes, not the blocks the rays
//! crossed: those would be kept at every cell of the fan, which made runs slower.)
//!
//! Gains of different kinds are kept apart ([`GainKind`]): a new layout makes the gains computed
//! with the previous one stale, but not the plain gains, which read only the map (the paper's
//! `I(p)` falls back to them for most candidates, those in rooms with an open frontier).

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

/// A gain kept: its value, the update at which it was computed, and where the cells it read lie.
#[derive(Debug, Clone, Copy)]
struct Cached {
    gain: f64,
    at: u64,
    read: CellsRead,
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
            gains: Default::default(),
        }
    }

    /// Records that the cell with row-major index `i` changed at update `now`.
    pub(crate) fn touch(&mut self, i: u32, now: u64) {
        let w = self.frame.width as usize;
        if w == 0 {
            return;
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
        let gains = &self.gains[kind as usize];
        if let Some(&Cached { gain: g, at, read }) = gains.get(&(p.x, p.y)) {
            if !read
                .boxes
                .iter()
                .any(|b| self.changed_since(p, range_m, *b, at))
            {
                return g;
            }
        }
        let (g, read) = compute();
        let cached = Cached {
            gain: g,
            at: now,
            read,
        };
        self.gains[kind as usize].insert((p.x, p.y), cached);
        g
    }

    /// Whether a block holding a cell of `read` within the range of `p` (and two cells) changed
    /// after update `at`.
    fn changed_since(&self, p: Cell, range_m: f64, read: CellBox, at: u64) -> bool {
        let r = (range_m / self.frame.resolution_m).ceil() as i32 + 2;
        let (x0, x1) = ((p.x - r).max(read.min.x), (p.x + r).min(read.max.x));
        let (y0, y1) = ((p.y - r).max(read.min.y), (p.y + r).min(read.max.y));
        if x0 > x1 || y0 > y1 {
            return false;
        }
        let bx0 = x0.div_euclid(BLOCK_CELLS).max(0);
        let by0 = y0.div_euclid(BLOCK_CELLS).max(0);
        let bx1 = x1.div_euclid(BLOCK_CELLS).min(self.blocks_w - 1);
        let by1 = y1.div_euclid(BLOCK_CELLS).min(self.blocks_h - 1);
        if bx0 > bx1 || by0 > by1 {
            return false; // (outside the frame, whose cells never change)
        }
        // Distance (cells) from `p` to the nearest cell of the range `lo..lo + side`.
        let gap = |v: i32, lo: i32, side: i32| (lo - v).max(v - (lo + side - 1)).max(0) as i64;
        let r2 = r as i64 * r as i64;
        let group = BLOCK_CELLS * GROUP_BLOCKS;
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
                        if dx * dx + dy * dy <= r2
                            && self.stamps[(by * self.blocks_w + bx) as usize] > at
                        {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec2;

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
            (value, CellsRead { boxes: [whole; 4] })
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
        cache.touch(frame.index(Cell::new(300, 20)).unwrap() as u32, 3);
        assert_eq!(near(&mut cache, GainKind::Plain, p, 1.0, 3, 7.0), 5.0);
        // A change within range invalidates it.
        cache.touch(frame.index(Cell::new(30, 25)).unwrap() as u32, 4);
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
        cache.touch(frame.index(Cell::new(49, 49)).unwrap() as u32, 2);
        assert_eq!(near(&mut cache, GainKind::Plain, p, 2.0, 2, 7.0), 5.0);
        // (48, 8), in the same row of blocks, is 40 cells away: within range.
        cache.touch(frame.index(Cell::new(48, 8)).unwrap() as u32, 3);
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
            assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 1, || (3.0, far)), 3.0);
            cache.touch(0, 2);
            assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 2, || (9.0, far)), 3.0);
            let near = CellsRead::of(Cell::new(0, 0));
            assert_eq!(cache.gain(GainKind::Rooms, p, 2.0, 2, || (4.0, near)), 4.0);
            cache.touch(0, 3);
            let expected = if frame.is_empty() { 4.0 } else { 5.0 };
            assert_eq!(
                cache.gain(GainKind::Rooms, p, 2.0, 3, || (5.0, near)),
                expected
            );
        }
    }

    #[test]
    fn a_change_within_range_outside_the_cells_read_keeps_the_gain() {
        let frame = GridFrame::new(Vec2::zeros(), 0.05, 200, 200);
        let mut cache = GainCache::new(frame);
        // Range 2 m = 40 cells around (100, 100); the gain read a room east of it (the cells
        // up to x = 120) and nothing west of x = 96.
        let p = Cell::new(100, 100);
        let room = CellBox {
            min: Cell::new(96, 90),
            max: Cell::new(120, 110),
        };
        let read = CellsRead { boxes: [room; 4] };
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 1, || (5.0, read)), 5.0);
        // Within range, west of the room's block (x 88..96): kept.
        cache.touch(frame.index(Cell::new(80, 100)).unwrap() as u32, 2);
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 2, || (7.0, read)), 5.0);
        // North of the room, in a block the room does not reach: kept.
        cache.touch(frame.index(Cell::new(110, 125)).unwrap() as u32, 3);
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 3, || (7.0, read)), 5.0);
        // In a block the room reaches (x 120..128), though the cell itself is not in the room.
        cache.touch(frame.index(Cell::new(126, 100)).unwrap() as u32, 4);
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 4, || (7.0, read)), 7.0);
        // Any one of the boxes read counts.
        let mut cache = GainCache::new(frame);
        let mut one = CellsRead::of(p);
        one.boxes[3] = room;
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 1, || (5.0, one)), 5.0);
        cache.touch(frame.index(Cell::new(80, 100)).unwrap() as u32, 2);
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 2, || (7.0, one)), 5.0);
        cache.touch(frame.index(Cell::new(97, 91)).unwrap() as u32, 3);
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 3, || (9.0, one)), 9.0);
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
        cache.touch(frame.index(Cell::new(52, 50)).unwrap() as u32, 4);
        assert_eq!(near(&mut cache, GainKind::Plain, p, 1.0, 4, 7.0), 7.0);
        assert_eq!(near(&mut cache, GainKind::Rooms, p, 1.0, 4, 6.0), 6.0);
    }
}
