//! Log-odds occupancy mapping with a ternary view kept in sync incrementally.
//!
//! Every beam is traced with an exact cell walk ([`walk_segment`]): the cells before the end
//! get a miss, the end cell a hit (or a miss for a max-range beam, which marks free up to max
//! range). The ternary state of a cell changes with hysteresis: it becomes `Occupied` when its
//! log-odds rises above `occupied_above_l`, `Free` when it falls below `free_below_l`, and keeps
//! its previous state in between (a cell never observed stays `Unknown`).
//!
//! Consecutive hits closer than `hit_gap_fill_m` lie on one surface: the cells between them get
//! a hit too. A wall seen from afar is otherwise a dotted line of cells (1 degree between beams
//! is 9 cm at 5 m), and a scan matched against dots slides along the wall toward them: a small
//! rotation per scan that bends the map.

use crate::geom::{floor_i32, Pose, Vec2};
use crate::grid::{Cell, Grid, GridFrame, Occupancy, OccupancyGrid};
use crate::mapping::ray::{grid_from_world, walk_segment, SegmentCells};
use crate::scan::Scan;

/// Increments and thresholds of the log-odds update (natural log of the odds).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogOddsConfig {
    /// Added to the cell where a beam ends on an obstacle (0.85 ~ p = 0.7).
    pub hit_l: f32,
    /// Added to the cells a beam crosses (-0.4 ~ p = 0.4).
    pub miss_l: f32,
    /// Lower clamp (-2.0 ~ p = 0.12), so that a cell can become occupied again quickly.
    pub min_l: f32,
    /// Upper clamp (3.5 ~ p = 0.97).
    pub max_l: f32,
    /// A cell becomes `Occupied` when its log-odds exceeds this (0.5; one hit suffices).
    pub occupied_above_l: f32,
    /// A cell becomes `Free` when its log-odds falls below this (-0.3; one miss suffices).
    pub free_below_l: f32,
    /// Cells whose centre is closer than this (in cells) to a hit point get no miss from that
    /// beam (1.0): keeps walls seen at grazing angles from being eroded by their own beams.
    pub hit_guard_cells: f64,
    /// Consecutive hit points closer than this are joined by hits on the cells between them
    /// (0 = off).
    pub hit_gap_fill_m: f64,
}

impl Default for LogOddsConfig {
    fn default() -> Self {
        Self {
            hit_l: 0.85,
            miss_l: -0.4,
            min_l: -2.0,
            max_l: 3.5,
            occupied_above_l: 0.5,
            free_below_l: -0.3,
            hit_guard_cells: 1.0,
            hit_gap_fill_m: 0.2,
        }
    }
}

/// What one [`LogOddsMap::insert_scan`] changed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct InsertStats {
    /// Cells whose ternary state changed.
    pub cells_changed: usize,
    /// Cells that were `Unknown` and became known.
    pub cells_discovered: usize,
    /// Beams whose end cell was outside the map frame (their in-frame part was still used).
    pub beams_clipped: usize,
}

/// A log-odds occupancy map over a fixed frame, with its ternary view.
#[derive(Debug, Clone, PartialEq)]
pub struct LogOddsMap {
    pub frame: GridFrame,
    /// Log-odds per cell, row-major; 0 = never observed (or exactly undecided).
    pub data: Vec<f32>,
    /// The ternary view, always in sync with `data`.
    pub occupancy: OccupancyGrid,
    /// Indices of cells that became or stopped being `Occupied` since the last
    /// [`LogOddsMap::take_occupied_flips`] (may repeat a cell); feeds incremental consumers such
    /// as [`crate::mapping::distance_field::ObstacleDistance`].
    pub occupied_flips: Vec<u32>,
    /// Cells that became (`true`) or stopped being (`false`) `Free` since the last
    /// [`LogOddsMap::take_free_changes`], in order (a cell may appear more than once).
    pub free_changes: Vec<(u32, bool)>,
    /// Bounding box (inclusive cells) of everything observed so far; `None` before any scan.
    pub known_bounds: Option<(Cell, Cell)>,
    /// Total ternary changes since construction.
    pub total_cells_changed: u64,
    /// Per cell, the mean of the hit points that fell in it, with their count: where in the
    /// cell the surface is, for sub-cell scan matching.
    surface: SurfacePoints,
}

/// Block side (cells) of [`SurfacePoints`], a power of two.
const SURFACE_BLOCK: usize = 16;

/// The mean hit point per cell (grid coordinates, cell units) and the number of hits averaged,
/// stored by blocks of `SURFACE_BLOCK`² cells made at the block's first hit: a map's walls cross
/// a small part of its blocks, and ten bytes per cell of a large map are tens of MB.
#[derive(Debug, Clone, PartialEq)]
struct SurfacePoints {
    blocks_w: usize,
    /// Per block: 1 + its index in `blocks`, or 0 before its first hit.
    slot: Vec<u32>,
    /// The blocks made, each `SURFACE_BLOCK`² cells in row-major order: (mean, hits).
    blocks: Vec<([f32; 2], u16)>,
}

impl SurfacePoints {
    fn new(frame: GridFrame) -> Self {
        let (w, h) = (frame.width as usize, frame.height as usize);
        let blocks_w = w.div_ceil(SURFACE_BLOCK);
        Self {
            blocks_w,
            slot: vec![0; blocks_w * h.div_ceil(SURFACE_BLOCK)],
            blocks: Vec::new(),
        }
    }

    /// The block of cell `c` (in the frame) and the cell's place in it.
    #[inline]
    fn locate(&self, c: Cell) -> (usize, usize) {
        let (x, y) = (c.x as usize, c.y as usize);
        let b = (y / SURFACE_BLOCK) * self.blocks_w + x / SURFACE_BLOCK;
        (b, (y % SURFACE_BLOCK) * SURFACE_BLOCK + x % SURFACE_BLOCK)
    }

    /// The mean hit point of cell `c` (in the frame), if it has hits.
    #[inline]
    fn get(&self, c: Cell) -> Option<[f32; 2]> {
        let (b, k) = self.locate(c);
        let slot = self.slot[b] as usize;
        if slot == 0 {
            return None;
        }
        let (p, n) = self.blocks[(slot - 1) * SURFACE_BLOCK * SURFACE_BLOCK + k];
        (n > 0).then_some(p)
    }

    /// Adds a hit point `q` (grid coordinates) to the running mean of cell `c` (in the frame).
    // (Always inlined, as profile-guided optimisation chose: BENCHMARKS.md.)
    #[inline(always)]
    fn add(&mut self, c: Cell, q: [f64; 2]) {
        let (b, k) = self.locate(c);
        if self.slot[b] == 0 {
            let n = SURFACE_BLOCK * SURFACE_BLOCK;
            self.blocks
                .resize(self.blocks.len() + n, ([f32::NAN; 2], 0));
            self.slot[b] = (self.blocks.len() / n) as u32;
        }
        let at = (self.slot[b] as usize - 1) * SURFACE_BLOCK * SURFACE_BLOCK + k;
        let (s, n) = &mut self.blocks[at];
        if *n == 0 {
            *s = [q[0] as f32, q[1] as f32];
        } else {
            let k = 1.0 / (*n as f32 + 1.0);
            s[0] += (q[0] as f32 - s[0]) * k;
            s[1] += (q[1] as f32 - s[1]) * k;
        }
        *n = n.saturating_add(1).min(1000);
    }
}

/// A beam of [`LogOddsMap::insert_scan`]: whether it hit, its end point, and the guard around
/// the end (cells, and squared cells) within which no miss is recorded.
struct Beam {
    hit: bool,
    end: [f64; 2],
    guard_cells: u32,
    guard2: f64,
}

impl LogOddsMap {
    /// An all-unknown map over `frame`.
    pub fn new(frame: GridFrame) -> Self {
        Self {
            frame,
            data: vec![0.0; frame.len()],
            occupancy: Grid::filled(frame, Occupancy::Unknown),
            occupied_flips: Vec::new(),
            free_changes: Vec::new(),
            known_bounds: None,
            total_cells_changed: 0,
            surface: SurfacePoints::new(frame),
        }
    }

    /// Integrates one scan taken at `pose` (the sensor sits at the robot's centre).
    pub fn insert_scan(&mut self, pose: &Pose, scan: &Scan, cfg: &LogOddsConfig) -> InsertStats {
        let mut stats = InsertStats::default();
        if self.frame.is_empty() || scan.max_range_m.is_nan() || scan.max_range_m <= 0.0 {
            return stats;
        }
        let start = grid_from_world(&self.frame, pose.position());
        let w = self.frame.width as i32;
        let h = self.frame.height as i32;
        let inv_res = 1.0 / self.frame.resolution_m;
        let start_cell = Cell::new(floor_i32(start[0]), floor_i32(start[1]));
        let mut bmin = start_cell;
        let mut bmax = bmin;
        let guard2 = cfg.hit_guard_cells * cfg.hit_guard_cells;
        // (The conversion saturates: an infinite guard is `u32::MAX` cells.)
        let guard_cells = cfg.hit_guard_cells.max(0.0).ceil() as u32;
        let fill2 = (cfg.hit_gap_fill_m * inv_res).powi(2);
        // The previous beam's end (grid coordinates) when it was a hit.
        let mut prev_hit: Option<[f64; 2]> = None;
        let inside = |c: Cell| c.x >= 0 && c.y >= 0 && c.x < w && c.y < h;
        let start_inside = inside(start_cell);
        for i in 0..scan.ranges_m.len() {
            let range_m = scan.ranges_m[i];
            if !range_m.is_finite() {
                // A beam left out (a teammate's body in a team): no gap is filled across it.
                prev_hit = None;
                continue;
            }
            let hit = scan.is_hit(i);
            let r_cells = range_m.clamp(0.0, scan.max_range_m) * inv_res;
            let a = pose.theta_rad + scan.beam_angle_rad(i);
            let end = [start[0] + a.cos() * r_cells, start[1] + a.sin() * r_cells];
            let end_cell = Cell::new(floor_i32(end[0]), floor_i32(end[1]));
            bmin = Cell::new(bmin.x.min(end_cell.x), bmin.y.min(end_cell.y));
            bmax = Cell::new(bmax.x.max(end_cell.x), bmax.y.max(end_cell.y));
            let beam = Beam {
                hit,
                end,
                guard_cells,
                guard2,
            };
            if start_inside && inside(end_cell) {
                // The usual beam, from a cell of the map to a cell of the map: no cell needs a
                // bounds test, and the end cell is the last.
                let last = SegmentCells::new(start, end).for_each_indexed(w, |c, idx, nx, ny| {
                    self.beam_cell(&beam, c, idx, (nx, ny), cfg, &mut stats)
                });
                if let Some((c, idx)) = last {
                    if hit {
                        self.update_cell(idx, cfg.hit_l, cfg, &mut stats);
                        self.surface.add(c, end);
                    } else {
                        self.update_cell(idx, cfg.miss_l, cfg, &mut stats);
                    }
                }
                self.fill_gap(hit, prev_hit, end, end_cell, fill2, cfg, &mut stats);
                prev_hit = hit.then_some(end);
                continue;
            }
            let mut was_inside = false;
            let mut clipped = false;
            // (A loop, not `walk_segment`'s closure: this body runs for every cell of every
            // beam and stays inlined here.)
            for c in SegmentCells::new(start, end) {
                if c.x < 0 || c.y < 0 || c.x >= w || c.y >= h {
                    clipped = true;
                    if was_inside {
                        break;
                    }
                    continue;
                }
                was_inside = true;
                let idx = c.y as usize * w as usize + c.x as usize;
                if hit && c == end_cell {
                    self.update_cell(idx, cfg.hit_l, cfg, &mut stats);
                    self.surface.add(c, end);
                    continue;
                }
                let from_end = (c.x.abs_diff(end_cell.x), c.y.abs_diff(end_cell.y));
                self.beam_cell(&beam, c, idx, from_end, cfg, &mut stats);
            }
            if clipped {
                stats.beams_clipped += 1;
            }
            self.fill_gap(hit, prev_hit, end, end_cell, fill2, cfg, &mut stats);
            prev_hit = hit.then_some(end);
        }
        let clamp = |c: Cell| Cell::new(c.x.clamp(0, w - 1), c.y.clamp(0, h - 1));
        let (bmin, bmax) = (clamp(bmin), clamp(bmax));
        self.known_bounds = Some(match self.known_bounds {
            None => (bmin, bmax),
            Some((lo, hi)) => (
                Cell::new(lo.x.min(bmin.x), lo.y.min(bmin.y)),
                Cell::new(hi.x.max(bmax.x), hi.y.max(bmax.y)),
            ),
        });
        self.total_cells_changed += stats.cells_changed as u64;
        stats
    }

    /// A cell of a beam in the map other than a hit's end cell, `from_end` columns and rows from
    /// the end cell: missed, unless the beam hit and the cell lies within the guard around the
    /// end. (Both the usual beam's walk and the clipped beam's loop ask it.)
    #[inline(always)]
    fn beam_cell(
        &mut self,
        beam: &Beam,
        c: Cell,
        idx: usize,
        from_end: (u32, u32),
        cfg: &LogOddsConfig,
        stats: &mut InsertStats,
    ) {
        if beam.hit {
            // (A cell more than `guard_cells` cells from the end cell on either axis is farther
            // than the guard from the end point: no need for the distance.)
            let g = beam.guard_cells;
            let near = from_end.0 <= g && from_end.1 <= g;
            let (ddx, ddy) = (
                c.x as f64 + 0.5 - beam.end[0],
                c.y as f64 + 0.5 - beam.end[1],
            );
            if near && ddx * ddx + ddy * ddy < beam.guard2 {
                return;
            }
        }
        self.update_cell(idx, cfg.miss_l, cfg, stats);
    }

    /// Between the previous beam's end `prev_hit` and this one's (`end`, in `end_cell`), both
    /// hits closer than the fill distance (`fill2`, squared cells): marks the cells between
    /// them hit, with the segment's point nearest each cell centre as its surface point.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn fill_gap(
        &mut self,
        hit: bool,
        prev_hit: Option<[f64; 2]>,
        end: [f64; 2],
        end_cell: Cell,
        fill2: f64,
        cfg: &LogOddsConfig,
        stats: &mut InsertStats,
    ) {
        let (w, h) = (self.frame.width as i32, self.frame.height as i32);
        if let (true, Some(p)) = (hit && cfg.hit_gap_fill_m > 0.0, prev_hit) {
            let (dx, dy) = (end[0] - p[0], end[1] - p[1]);
            if dx * dx + dy * dy <= fill2 {
                let p_cell = Cell::new(floor_i32(p[0]), floor_i32(p[1]));
                let len2 = (dx * dx + dy * dy).max(1e-12);
                walk_segment(p, end, |c| {
                    if c != p_cell && c != end_cell && c.x >= 0 && c.y >= 0 && c.x < w && c.y < h {
                        let idx = c.y as usize * w as usize + c.x as usize;
                        self.update_cell(idx, cfg.hit_l, cfg, stats);
                        // The surface point: the segment's point nearest the cell centre.
                        let t = (((c.x as f64 + 0.5 - p[0]) * dx + (c.y as f64 + 0.5 - p[1]) * dy)
                            / len2)
                            .clamp(0.0, 1.0);
                        self.surface.add(c, [p[0] + t * dx, p[1] + t * dy]);
                    }
                    true
                });
            }
        }
    }

    /// The mean surface point of an occupied cell with hits, in world coordinates.
    pub(crate) fn surface_point(&self, c: Cell) -> Option<Vec2> {
        let i = self.frame.index(c)?;
        if self.occupancy.data[i] != Occupancy::Occupied {
            return None;
        }
        self.surface.get(c).map(|s| self.surface_world(s))
    }

    /// A mean hit point as kept (grid coordinates, `f32`) in world coordinates.
    #[inline]
    fn surface_world(&self, s: [f32; 2]) -> Vec2 {
        self.frame.origin_m + Vec2::new(s[0] as f64, s[1] as f64) * self.frame.resolution_m
    }

    /// The surface points ([`LogOddsMap::surface_point`]) of the 3 x 3 cells around `c0`, in row
    /// order, into `out`; returns how many. Read in place when the nine cells lie in the frame
    /// and in one block of the surface store (most cells), else cell by cell.
    // (Always inlined, as profile-guided optimisation chose: BENCHMARKS.md.)
    #[inline(always)]
    pub(crate) fn surface_points_around(&self, c0: Cell, out: &mut [Vec2; 9]) -> usize {
        const B: usize = SURFACE_BLOCK;
        let (w, h) = (self.frame.width as i32, self.frame.height as i32);
        let mut n = 0;
        if c0.x >= 1 && c0.y >= 1 && c0.x + 1 < w && c0.y + 1 < h {
            let (b, k) = self.surface.locate(c0);
            if (1..B - 1).contains(&(k % B)) && (1..B - 1).contains(&(k / B)) {
                let slot = self.surface.slot[b] as usize;
                if slot == 0 {
                    return 0; // (no hit in the block)
                }
                let block = &self.surface.blocks[(slot - 1) * B * B..slot * B * B];
                let at = c0.y as usize * w as usize + c0.x as usize;
                for dy in -1..=1isize {
                    for dx in -1..=1isize {
                        let i = (at as isize + dy * w as isize + dx) as usize;
                        if self.occupancy.data[i] != Occupancy::Occupied {
                            continue;
                        }
                        let (s, hits) = block[(k as isize + dy * B as isize + dx) as usize];
                        if hits > 0 {
                            out[n] = self.surface_world(s);
                            n += 1;
                        }
                    }
                }
                return n;
            }
        }
        for dy in -1..=1 {
            for dx in -1..=1 {
                if let Some(a) = self.surface_point(Cell::new(c0.x + dx, c0.y + dy)) {
                    out[n] = a;
                    n += 1;
                }
            }
        }
        n
    }

    #[inline(always)]
    fn update_cell(
        &mut self,
        idx: usize,
        delta: f32,
        cfg: &LogOddsConfig,
        stats: &mut InsertStats,
    ) {
        let before = self.data[idx];
        // Most cells a beam crosses are free already, at the lower clamp: a miss changes nothing
        // (the log-odds stays clamped and the ternary view, in sync, stays `Free`).
        if delta <= 0.0 && before <= cfg.min_l {
            return;
        }
        self.change_cell(idx, before, delta, cfg, stats);
    }

    /// [`Self::update_cell`] when the update may change something.
    #[inline(never)]
    fn change_cell(
        &mut self,
        idx: usize,
        before: f32,
        delta: f32,
        cfg: &LogOddsConfig,
        stats: &mut InsertStats,
    ) {
        let l = (before + delta).clamp(cfg.min_l, cfg.max_l);
        self.data[idx] = l;
        let old = self.occupancy.data[idx];
        let new = if l > cfg.occupied_above_l {
            Occupancy::Occupied
        } else if l < cfg.free_below_l {
            Occupancy::Free
        } else {
            old
        };
        if new != old {
            self.occupancy.data[idx] = new;
            stats.cells_changed += 1;
            if old == Occupancy::Unknown {
                stats.cells_discovered += 1;
            }
            if (old == Occupancy::Occupied) != (new == Occupancy::Occupied) {
                self.occupied_flips.push(idx as u32);
            }
            if (old == Occupancy::Free) != (new == Occupancy::Free) {
                self.free_changes.push((idx as u32, new == Occupancy::Free));
            }
        }
    }

    /// The ternary view (a copy; [`LogOddsMap::occupancy`] is the same, kept up to date).
    pub fn to_occupancy(&self) -> OccupancyGrid {
        self.occupancy.clone()
    }

    /// Returns and clears the list of cells whose `Occupied` status flipped.
    pub fn take_occupied_flips(&mut self) -> Vec<u32> {
        std::mem::take(&mut self.occupied_flips)
    }

    /// Returns and clears the list of `Free` transitions.
    pub(crate) fn take_free_changes(&mut self) -> Vec<(u32, bool)> {
        std::mem::take(&mut self.free_changes)
    }

    /// Probability of occupancy of a cell (0.5 outside the map).
    pub fn probability(&self, c: Cell) -> f64 {
        match self.frame.index(c) {
            Some(i) => 1.0 / (1.0 + (-(self.data[i] as f64)).exp()),
            None => 0.5,
        }
    }

    /// Log-odds at a world point (0 outside).
    pub fn log_odds_at(&self, p: Vec2) -> f32 {
        self.frame
            .index(self.frame.cell_from_world(p))
            .map_or(0.0, |i| self.data[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_beam(range_m: f64, max_range_m: f64) -> Scan {
        Scan {
            angle_min_rad: 0.0,
            angle_increment_rad: 0.0,
            max_range_m,
            ranges_m: vec![range_m],
        }
    }

    fn frame() -> GridFrame {
        GridFrame::new(Vec2::zeros(), 0.1, 40, 10)
    }

    #[test]
    fn surface_points_around_a_cell_are_those_of_its_nine_cells() {
        // A frame whose sides are not whole blocks; beams of many lengths from a few poses hit
        // cells everywhere, some blocks never. Every cell, on the frame's edges, on the blocks'
        // edges and off the frame, as each of its nine cells gives it.
        let frame = GridFrame::new(Vec2::new(-0.31, 0.17), 0.1, 45, 37);
        let mut m = LogOddsMap::new(frame);
        for (k, (x, y)) in [(0.5, 0.6), (3.9, 3.3), (2.2, 1.4)].into_iter().enumerate() {
            let scan = Scan {
                angle_min_rad: 0.1 * k as f64,
                angle_increment_rad: 0.37,
                max_range_m: 6.0,
                ranges_m: (0..40).map(|i| 0.4 + (i * 7 % 23) as f64 * 0.11).collect(),
            };
            m.insert_scan(&Pose::new(x, y, 0.0), &scan, &LogOddsConfig::default());
        }
        let mut seen = 0;
        for y in -2..frame.height as i32 + 2 {
            for x in -2..frame.width as i32 + 2 {
                let c0 = Cell::new(x, y);
                let want: Vec<Vec2> = (-1..=1)
                    .flat_map(|dy| (-1..=1).map(move |dx| Cell::new(x + dx, y + dy)))
                    .filter_map(|c| m.surface_point(c))
                    .collect();
                let mut out = [Vec2::zeros(); 9];
                let n = m.surface_points_around(c0, &mut out);
                assert_eq!(&out[..n], &want[..], "{c0:?}");
                seen += n;
            }
        }
        assert!(seen > 100, "{seen}");
    }

    #[test]
    fn surface_points_are_kept_only_in_the_blocks_hit() {
        // 200 x 200 cells: 13 x 13 blocks of 16.
        let mut m = LogOddsMap::new(GridFrame::new(Vec2::zeros(), 0.1, 200, 200));
        let pose = Pose::new(0.55, 0.55, 0.0);
        m.insert_scan(&pose, &one_beam(3.0, 6.0), &LogOddsConfig::default());
        let hit = Cell::new(35, 5);
        assert_eq!(m.occupancy.get(hit), Some(&Occupancy::Occupied));
        let p = m
            .surface_point(hit)
            .expect("a surface point where the beam hit");
        assert!(
            (p.x - 3.55).abs() < 1e-6 && (p.y - 0.55).abs() < 1e-6,
            "{p:?}"
        );
        assert_eq!(m.surface.blocks.len(), SURFACE_BLOCK * SURFACE_BLOCK);
        assert_eq!(m.surface.slot.iter().filter(|s| **s != 0).count(), 1);
        // A cell of the same block without hits, and a free cell, have none.
        assert_eq!(m.surface.get(Cell::new(34, 5)), None);
        assert_eq!(m.surface_point(Cell::new(20, 5)), None);
        // A second hit in another block makes one more block, the first keeps its point.
        let turned = Pose::new(0.55, 0.55, std::f64::consts::FRAC_PI_2);
        m.insert_scan(&turned, &one_beam(3.0, 6.0), &LogOddsConfig::default());
        assert_eq!(m.surface.blocks.len(), 2 * SURFACE_BLOCK * SURFACE_BLOCK);
        assert!(m.surface_point(Cell::new(5, 35)).is_some());
        assert_eq!(m.surface_point(hit), Some(p));
    }

    #[test]
    fn a_beam_frees_cells_and_marks_the_hit() {
        let mut m = LogOddsMap::new(frame());
        let pose = Pose::new(0.05, 0.55, 0.0);
        let stats = m.insert_scan(&pose, &one_beam(1.0, 3.0), &LogOddsConfig::default());
        let row = 5;
        for x in 0..10 {
            assert!(m.occupancy.is(Cell::new(x, row), Occupancy::Free), "x={x}");
        }
        assert!(m.occupancy.is(Cell::new(10, row), Occupancy::Occupied));
        assert!(m.occupancy.is(Cell::new(11, row), Occupancy::Unknown));
        assert!(m.occupancy.is(Cell::new(5, row + 1), Occupancy::Unknown));
        assert_eq!(stats.cells_changed, 11);
        assert_eq!(stats.cells_discovered, 11);
        assert_eq!(m.take_occupied_flips(), vec![(row * 40 + 10) as u32]);
        assert!(m.occupied_flips.is_empty());
        assert_eq!(m.known_bounds, Some((Cell::new(0, 5), Cell::new(10, 5))));
        assert!(m.probability(Cell::new(10, row)) > 0.6);
    }

    #[test]
    fn max_range_beam_frees_to_max_range_without_hit() {
        let mut m = LogOddsMap::new(frame());
        let pose = Pose::new(0.05, 0.55, 0.0);
        m.insert_scan(&pose, &one_beam(2.0, 2.0), &LogOddsConfig::default());
        for x in 0..=20 {
            assert!(m.occupancy.is(Cell::new(x, 5), Occupancy::Free), "x={x}");
        }
        assert_eq!(m.occupancy.count(Occupancy::Occupied), 0);
        assert!(m.occupancy.is(Cell::new(21, 5), Occupancy::Unknown));
    }

    #[test]
    fn beams_leaving_the_frame_are_clipped_and_hysteresis_holds() {
        let mut m = LogOddsMap::new(frame());
        let cfg = LogOddsConfig::default();
        let pose = Pose::new(3.95, 0.55, 0.0);
        let s = m.insert_scan(&pose, &one_beam(2.0, 3.0), &cfg);
        assert_eq!(s.beams_clipped, 1);
        assert_eq!(m.occupancy.count(Occupancy::Free), 1);
        // A cell hit once then crossed once stays occupied (hysteresis); a second miss frees it.
        let mut m = LogOddsMap::new(frame());
        let p = Pose::new(0.05, 0.55, 0.0);
        m.insert_scan(&p, &one_beam(1.0, 3.0), &cfg);
        m.insert_scan(&p, &one_beam(1.5, 3.0), &cfg);
        assert!(m.occupancy.is(Cell::new(10, 5), Occupancy::Occupied));
        m.insert_scan(&p, &one_beam(1.5, 3.0), &cfg);
        m.insert_scan(&p, &one_beam(1.5, 3.0), &cfg);
        assert!(m.occupancy.is(Cell::new(10, 5), Occupancy::Free));
        assert_eq!(m.take_occupied_flips().len(), 3);
    }

    #[test]
    fn a_beam_from_outside_the_frame_marks_its_cells_as_from_inside() {
        // The same beams, hits and misses, in a frame holding their start (each walked whole)
        // and in one starting 2 m further east (each clipped, its start outside): the cells
        // the two share get the same log-odds, the guard around a hit included.
        let big = GridFrame::new(Vec2::zeros(), 0.1, 60, 60);
        let small = GridFrame::new(Vec2::new(2.0, 0.0), 0.1, 40, 60);
        let cfg = LogOddsConfig {
            hit_guard_cells: 2.5,
            ..LogOddsConfig::default()
        };
        let (mut whole, mut clipped) = (LogOddsMap::new(big), LogOddsMap::new(small));
        let mut beams_clipped = 0;
        for k in 0..13 {
            let pose = Pose::new(0.55, 3.05, -0.6 + 0.1 * k as f64);
            let scan = one_beam(if k % 3 == 0 { 4.0 } else { 3.0 }, 4.0);
            assert_eq!(whole.insert_scan(&pose, &scan, &cfg).beams_clipped, 0);
            beams_clipped += clipped.insert_scan(&pose, &scan, &cfg).beams_clipped;
        }
        assert_eq!(beams_clipped, 13);
        let mut hits = 0;
        for y in 0..60 {
            for x in 0..40 {
                let (c, b) = (Cell::new(x, y), Cell::new(x + 20, y));
                let (i, j) = (small.index(c).unwrap(), big.index(b).unwrap());
                assert_eq!(clipped.data[i], whole.data[j], "{c:?}");
                hits += (whole.occupancy.data[j] == Occupancy::Occupied) as usize;
            }
        }
        assert!(hits >= 8, "{hits}");
    }

    #[test]
    fn empty_inputs_do_nothing() {
        let mut m = LogOddsMap::new(GridFrame::new(Vec2::zeros(), 0.1, 0, 0));
        let s = m.insert_scan(
            &Pose::new(0.0, 0.0, 0.0),
            &one_beam(1.0, 2.0),
            &LogOddsConfig::default(),
        );
        assert_eq!(s, InsertStats::default());
        let mut m = LogOddsMap::new(frame());
        let s = m.insert_scan(
            &Pose::new(1.0, 0.5, 0.0),
            &one_beam(f64::NAN, 2.0),
            &LogOddsConfig::default(),
        );
        assert_eq!(s.cells_changed, 0);
    }

    /// Two beams `inc_deg` apart, symmetric about the x axis, hitting the wall x = 2 m.
    fn two_beams(inc_deg: f64) -> Scan {
        let inc = inc_deg.to_radians();
        Scan {
            angle_min_rad: -inc / 2.0,
            angle_increment_rad: inc,
            max_range_m: 6.0,
            ranges_m: vec![2.0 / (inc / 2.0).cos(); 2],
        }
    }

    #[test]
    fn close_hits_are_joined_far_ones_are_not() {
        let frame = GridFrame::new(Vec2::new(-0.5, -1.0), 0.05, 80, 40);
        let pose = Pose::new(0.0, 0.0, 0.0);
        let cfg = LogOddsConfig::default();
        // The wall is the line x = 2 m: cell column 50 (x in [2.0, 2.05)).
        let col = frame.cell_from_world(Vec2::new(2.01, 0.0)).x;
        let occupied_in_col = |m: &LogOddsMap| {
            (0..40)
                .filter(|&y| m.occupancy.is(Cell::new(col, y), Occupancy::Occupied))
                .count()
        };
        let mut near = LogOddsMap::new(frame);
        near.insert_scan(&pose, &two_beams(2.0), &cfg);
        // 0.07 m apart: two adjacent end cells, nothing between.
        assert_eq!(occupied_in_col(&near), 2);
        assert_eq!(near.occupancy.count(Occupancy::Occupied), 2);
        // 0.35 m apart: not one surface.
        let mut far = LogOddsMap::new(frame);
        far.insert_scan(&pose, &two_beams(10.0), &cfg);
        assert_eq!(far.occupancy.count(Occupancy::Occupied), 2);
        let mut off = LogOddsMap::new(frame);
        off.insert_scan(
            &pose,
            &two_beams(5.0),
            &LogOddsConfig {
                hit_gap_fill_m: 0.0,
                ..cfg
            },
        );
        assert_eq!(off.occupancy.count(Occupancy::Occupied), 2);
        let mut filled = LogOddsMap::new(frame);
        filled.insert_scan(&pose, &two_beams(5.0), &cfg);
        // 0.175 m apart: the cells between are joined, on the wall's column.
        assert!(
            occupied_in_col(&filled) >= 4,
            "{}",
            occupied_in_col(&filled)
        );
        assert_eq!(
            filled.occupancy.count(Occupancy::Occupied),
            occupied_in_col(&filled)
        );
        // Every occupied cell knows where the surface is: on the line x = 2 m.
        for y in 0..40 {
            if let Some(p) = filled.surface_point(Cell::new(col, y)) {
                assert!((p.x - 2.0).abs() < 1e-4, "{p:?}");
            }
        }
        assert!(filled.surface_point(Cell::new(col - 3, 20)).is_none());
    }
}
