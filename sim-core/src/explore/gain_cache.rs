//! Information gains of frontier candidates, reused between decisions while the map around a
//! candidate has not changed.
//!
//! The map is divided into square blocks; every ternary change of a cell stamps its block with
//! the current map-update number. A gain computed at update `k` for cell `p` stays valid while
//! no block that comes within the laser range of `p` (plus two cells, for the cells a ray crosses
//! at its very end) has a later stamp: the gain only depends on cells within range.
//!
//! Gains of different kinds are kept apart ([`GainKind`]): a new layout makes the gains computed
//! with the previous one stale, but not the plain gains, which read only the map (the paper's
//! `I(p)` falls back to them for most candidates, those in rooms with an open frontier).

use std::collections::BTreeMap;

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
const BLOCK_CELLS: i32 = 16;

#[derive(Debug, Clone)]
pub(crate) struct GainCache {
    frame: GridFrame,
    blocks_w: i32,
    blocks_h: i32,
    /// Map update that last changed each block.
    stamps: Vec<u64>,
    /// Per [`GainKind`]: candidate cell -> (gain, update at which it was computed).
    gains: [BTreeMap<(i32, i32), (f64, u64)>; 3],
}

impl GainCache {
    pub(crate) fn new(frame: GridFrame) -> Self {
        let blocks_w = (frame.width as i32 + BLOCK_CELLS - 1) / BLOCK_CELLS;
        let blocks_h = (frame.height as i32 + BLOCK_CELLS - 1) / BLOCK_CELLS;
        Self {
            frame,
            blocks_w,
            blocks_h,
            stamps: vec![0; (blocks_w.max(0) * blocks_h.max(0)) as usize],
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
        let b = (y / BLOCK_CELLS) * self.blocks_w + x / BLOCK_CELLS;
        if let Some(s) = self.stamps.get_mut(b as usize) {
            *s = now;
        }
    }

    /// Forgets the gains computed with a layout (when the layout changed); the plain gains stay.
    pub(crate) fn clear_layout_gains(&mut self) {
        self.gains[GainKind::GapClosed as usize].clear();
        self.gains[GainKind::Rooms as usize].clear();
    }

    /// The gain of `p` of the given kind, computed by `compute` unless a still valid one is
    /// cached.
    pub(crate) fn gain(
        &mut self,
        kind: GainKind,
        p: Cell,
        range_m: f64,
        now: u64,
        compute: impl FnOnce() -> f64,
    ) -> f64 {
        let gains = &self.gains[kind as usize];
        if let Some(&(g, at)) = gains.get(&(p.x, p.y)) {
            if self.last_change_near(p, range_m) <= at {
                return g;
            }
        }
        let g = compute();
        self.gains[kind as usize].insert((p.x, p.y), (g, now));
        g
    }

    fn last_change_near(&self, p: Cell, range_m: f64) -> u64 {
        let r = (range_m / self.frame.resolution_m).ceil() as i32 + 2;
        let bx0 = (p.x - r).div_euclid(BLOCK_CELLS).max(0);
        let by0 = (p.y - r).div_euclid(BLOCK_CELLS).max(0);
        let bx1 = (p.x + r).div_euclid(BLOCK_CELLS).min(self.blocks_w - 1);
        let by1 = (p.y + r).div_euclid(BLOCK_CELLS).min(self.blocks_h - 1);
        // Distance (cells) from `p` to the nearest cell of the block range `lo..lo + BLOCK`.
        let gap = |v: i32, b: i32| {
            let lo = b * BLOCK_CELLS;
            (lo - v).max(v - (lo + BLOCK_CELLS - 1)).max(0) as i64
        };
        let r2 = r as i64 * r as i64;
        let mut last = 0;
        for by in by0..=by1 {
            let gy = gap(p.y, by);
            for bx in bx0..=bx1 {
                let gx = gap(p.x, bx);
                if gx * gx + gy * gy <= r2 {
                    last = last.max(self.stamps[(by * self.blocks_w + bx) as usize]);
                }
            }
        }
        last
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec2;

    #[test]
    fn reuses_until_a_change_within_range() {
        let frame = GridFrame::new(Vec2::zeros(), 0.05, 400, 100);
        let mut cache = GainCache::new(frame);
        let p = Cell::new(20, 20);
        assert_eq!(cache.gain(GainKind::Plain, p, 1.0, 1, || 5.0), 5.0);
        assert_eq!(cache.gain(GainKind::Plain, p, 1.0, 2, || 7.0), 5.0);
        // A change far away (x = 300 cells = 15 m) keeps the cached value.
        cache.touch(frame.index(Cell::new(300, 20)).unwrap() as u32, 3);
        assert_eq!(cache.gain(GainKind::Plain, p, 1.0, 3, || 7.0), 5.0);
        // A change within range invalidates it.
        cache.touch(frame.index(Cell::new(30, 25)).unwrap() as u32, 4);
        assert_eq!(cache.gain(GainKind::Plain, p, 1.0, 4, || 7.0), 7.0);
        assert_eq!(cache.gain(GainKind::Plain, p, 1.0, 5, || 9.0), 7.0);
    }

    #[test]
    fn a_change_in_the_corner_of_the_square_around_the_range_keeps_the_gain() {
        let frame = GridFrame::new(Vec2::zeros(), 0.05, 100, 100);
        let mut cache = GainCache::new(frame);
        // Range 2 m = 40 cells (42 with the margin) around (8, 8).
        let p = Cell::new(8, 8);
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 1, || 5.0), 5.0);
        // (49, 49) is 58 cells away, in the block (48..64)^2 that a square around the range
        // covers but the range does not reach.
        cache.touch(frame.index(Cell::new(49, 49)).unwrap() as u32, 2);
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 2, || 7.0), 5.0);
        // (48, 8), in the same row of blocks, is 40 cells away: within range.
        cache.touch(frame.index(Cell::new(48, 8)).unwrap() as u32, 3);
        assert_eq!(cache.gain(GainKind::Plain, p, 2.0, 3, || 7.0), 7.0);
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
            assert_eq!(cache.gain(kind, p, 1.0, 1, || k as f64), k as f64);
        }
        // Kinds do not share values.
        assert_eq!(cache.gain(GainKind::Rooms, p, 1.0, 2, || 9.0), 2.0);
        cache.clear_layout_gains();
        assert_eq!(cache.gain(GainKind::Plain, p, 1.0, 3, || 9.0), 0.0);
        assert_eq!(cache.gain(GainKind::GapClosed, p, 1.0, 3, || 9.0), 9.0);
        assert_eq!(cache.gain(GainKind::Rooms, p, 1.0, 3, || 8.0), 8.0);
        // A change within range invalidates every kind.
        cache.touch(frame.index(Cell::new(52, 50)).unwrap() as u32, 4);
        assert_eq!(cache.gain(GainKind::Plain, p, 1.0, 4, || 7.0), 7.0);
        assert_eq!(cache.gain(GainKind::Rooms, p, 1.0, 4, || 6.0), 6.0);
    }
}
