//! Wall evidence: occupied cells on the boundary of free space, each with the orientation of the
//! local boundary, plus a mask of the cells near any occupied cell.

#[cfg(any(test, feature = "test-support"))]
use super::morphology::dilate_reference;
use super::morphology::{BitRows, WindowMask};
use super::LayoutConfig;
use crate::geom::Vec2;
use crate::grid::{Cell, Occupancy, OccupancyGrid};

/// An occupied cell next to free space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundaryCell {
    /// Centre of the cell, world metres.
    pub p: Vec2,
    /// Orientation of the boundary normal, in `[0, pi)`.
    pub normal_rad: f64,
}

/// What the later stages read from the grid.
#[derive(Debug, Clone, PartialEq)]
pub struct WallEvidence {
    pub cells: Vec<BoundaryCell>,
    /// Cells within [`LayoutConfig::wall_tolerance_m`] (square neighbourhood) of an occupied cell.
    pub near_wall: WindowMask,
    /// Inclusive cell box of the known (free or occupied) cells; `None` when there are none.
    pub known_box: Option<(Cell, Cell)>,
    pub known_cells: usize,
}

/// Extracts the wall evidence of `grid`.
pub fn wall_evidence(grid: &OccupancyGrid, config: &LayoutConfig) -> WallEvidence {
    wall_evidence_in(grid, config, known_box(grid))
}

/// [`wall_evidence`] with the known box and the number of known cells of `grid` given (from
/// [`known_box`]).
pub(crate) fn wall_evidence_in(
    grid: &OccupancyGrid,
    config: &LayoutConfig,
    (known_box, known_cells): (Option<(Cell, Cell)>, usize),
) -> WallEvidence {
    let f = grid.frame;
    let radius = (config.wall_tolerance_m / f.resolution_m).round().max(0.0) as usize;
    let Some(bbox) = known_box else {
        return WallEvidence {
            cells: Vec::new(),
            near_wall: WindowMask::empty(f),
            known_box,
            known_cells,
        };
    };
    // The box grown by the 5x5 window and by the dilation (cells past the grid are unknown).
    let win = window(grid, bbox, radius.max(2));
    let occupied = BitRows::from_grid(grid, win, |s| s == Occupancy::Occupied);
    let free = BitRows::from_grid(grid, win, |s| s == Occupancy::Free);
    let cells = boundary_cells(grid, bbox, win, &occupied, &free);
    let near_wall = WindowMask::new(f, win.0, win.1, occupied.dilate(radius));
    WallEvidence {
        cells,
        near_wall,
        known_box,
        known_cells,
    }
}

/// Per 5-bit row of a 5x5 window (bit `i` at `dx = i - 2`): the number of cells, and the sums of
/// their `dx` and `dx^2`.
const WINDOW_ROW: [(i32, i32, i32); 32] = {
    let mut t = [(0, 0, 0); 32];
    let mut m = 0;
    while m < 32 {
        let mut i = 0;
        while i < 5 {
            if m >> i & 1 == 1 {
                let dx = i - 2;
                t[m].0 += 1;
                t[m].1 += dx;
                t[m].2 += dx * dx;
            }
            i += 1;
        }
        m += 1;
    }
    t
};

/// The five cells of row `y` of a mask starting `start` cells into the row (cells before the row
/// or past it read false), bit `i` for cell `start + i`.
fn five_at(bits: &BitRows, y: isize, start: isize) -> usize {
    if y < 0 || y >= bits.height() as isize {
        return 0;
    }
    let row = bits.row(y as usize);
    let word = |k: usize| row.get(k).copied().unwrap_or(0);
    let field = if start < 0 {
        // (Only at the grid's first column.)
        word(0) << (-start) as u32
    } else {
        let (k, o) = (start as usize / 64, start as u32 % 64);
        let hi = if o > 59 { word(k + 1) << (64 - o) } else { 0 };
        word(k) >> o | hi
    };
    (field & 31) as usize
}

/// The occupied cells of the box `bbox` that touch a free cell (4-neighbours), row by row, each
/// with the orientation of its boundary. `occupied` and `free` are the grid's cells in `win`
/// (the box grown by at least 2 cells, clamped to the grid).
fn boundary_cells(
    grid: &OccupancyGrid,
    (b0, b1): (Cell, Cell),
    (wx0, wy0, ww, _): (usize, usize, usize, usize),
    occupied: &BitRows,
    free: &BitRows,
) -> Vec<BoundaryCell> {
    let f = grid.frame;
    let n = ww.div_ceil(64);
    // The box's columns in the window, as a mask per word.
    let (cx0, cx1) = (b0.x as usize - wx0, b1.x as usize - wx0);
    let in_box = |k: usize| -> u64 {
        let lo = (k * 64).max(cx0);
        let hi = (k * 64 + 63).min(cx1);
        if lo > hi {
            0
        } else {
            let len = (hi - lo + 1) as u32;
            let ones = if len == 64 {
                u64::MAX
            } else {
                (1u64 << len) - 1
            };
            ones << (lo - k * 64)
        }
    };
    let mut cells = Vec::new();
    let mut free_side = FreeSideNormals::new();
    for y in b0.y as usize..=b1.y as usize {
        let wy = y - wy0;
        let occ = occupied.row(wy);
        let fr = free.row(wy);
        let empty: &[u64] = &[];
        let above = if wy > 0 { free.row(wy - 1) } else { empty };
        let below = if wy + 1 < free.height() {
            free.row(wy + 1)
        } else {
            empty
        };
        for k in 0..n {
            if occ[k] == 0 {
                continue;
            }
            let word = |r: &[u64], k: usize| r.get(k).copied().unwrap_or(0);
            // A free cell left, right, above or below.
            let left = fr[k] << 1 | if k > 0 { fr[k - 1] >> 63 } else { 0 };
            let right = fr[k] >> 1 | word(fr, k + 1) << 63;
            let touches = left | right | word(above, k) | word(below, k);
            let mut m = occ[k] & touches & in_box(k);
            while m != 0 {
                let cx = k * 64 + m.trailing_zeros() as usize;
                m &= m - 1;
                let mut moments = Moments::default();
                for dy in -2..=2i32 {
                    let (r, start) = (wy as isize + dy as isize, cx as isize - 2);
                    let fr5 = WINDOW_ROW[five_at(free, r, start)];
                    let oc5 = WINDOW_ROW[five_at(occupied, r, start)];
                    moments.gx += fr5.1;
                    moments.gy += dy * fr5.0;
                    moments.n += oc5.0;
                    moments.sx += oc5.1;
                    moments.sy += dy * oc5.0;
                    moments.sxx += oc5.2;
                    moments.syy += dy * dy * oc5.0;
                    moments.sxy += dy * oc5.1;
                }
                if let Some(normal_rad) = moments.normal_rad_with(&mut free_side) {
                    let c = Cell::new((wx0 + cx) as i32, y as i32);
                    cells.push(BoundaryCell {
                        p: f.world_from_cell(c),
                        normal_rad,
                    });
                }
            }
        }
    }
    cells
}

/// In a 5x5 window around a boundary cell: the first moment of the free cells (points to the
/// free side of a wall edge) and the second moments of the occupied cells (the axis of a thin
/// wall, which has free space on both sides and no free moment). Offsets in cells.
#[derive(Debug, Default, PartialEq, Eq)]
struct Moments {
    gx: i32,
    gy: i32,
    n: i32,
    sx: i32,
    sy: i32,
    sxx: i32,
    syy: i32,
    sxy: i32,
}

impl Moments {
    /// The orientation of the boundary normal in `[0, pi)`, `None` when the window has none.
    fn normal_rad(&self) -> Option<f64> {
        let Moments {
            gx,
            gy,
            n,
            sx,
            sy,
            sxx,
            syy,
            sxy,
        } = *self;
        if gx * gx + gy * gy >= 25 {
            return Some(free_side_normal(gx, gy));
        }
        let nf = n as f64;
        let cxx = sxx as f64 - (sx * sx) as f64 / nf;
        let cyy = syy as f64 - (sy * sy) as f64 / nf;
        let cxy = sxy as f64 - (sx * sy) as f64 / nf;
        if cxx == cyy && cxy == 0.0 {
            return None;
        }
        // Major axis of the occupied cells, turned to its normal.
        let a = 0.5 * (2.0 * cxy).atan2(cxx - cyy) + std::f64::consts::FRAC_PI_2;
        Some(normal_in_half_turn(a))
    }

    /// [`Moments::normal_rad`], the angles of the free cells' moments (a few hundred possible
    /// ones, most cells of a wall sharing a few) looked up in `free_side` once computed.
    fn normal_rad_with(&self, free_side: &mut FreeSideNormals) -> Option<f64> {
        if self.gx * self.gx + self.gy * self.gy < 25 {
            return self.normal_rad();
        }
        Some(free_side.get(self.gx, self.gy))
    }
}

/// The normal of a boundary given by the first moment `(gx, gy)` of the free cells, in `[0, pi)`.
fn free_side_normal(gx: i32, gy: i32) -> f64 {
    normal_in_half_turn((gy as f64).atan2(gx as f64))
}

/// An angle taken to `[0, pi)`.
fn normal_in_half_turn(a: f64) -> f64 {
    let a = crate::geom::rem_pi(a);
    if a >= std::f64::consts::PI {
        0.0
    } else {
        a
    }
}

/// [`free_side_normal`] of every first moment of a 5x5 window (each coordinate within
/// `-MOMENT..=MOMENT`), computed when first asked for.
struct FreeSideNormals {
    /// NaN: not computed yet (a normal is never NaN).
    table: Vec<f64>,
}

/// The largest first moment of a 5x5 window: 5 rows of offsets 1 and 2.
const MOMENT: i32 = 15;

impl FreeSideNormals {
    fn new() -> Self {
        let side = (2 * MOMENT + 1) as usize;
        Self {
            table: vec![f64::NAN; side * side],
        }
    }

    fn get(&mut self, gx: i32, gy: i32) -> f64 {
        let side = 2 * MOMENT + 1;
        let i = ((gy + MOMENT) * side + gx + MOMENT) as usize;
        let v = &mut self.table[i];
        if v.is_nan() {
            *v = free_side_normal(gx, gy);
        }
        *v
    }
}

/// The inclusive cell box of the known (free or occupied) cells and their number.
pub fn known_box(grid: &OccupancyGrid) -> (Option<(Cell, Cell)>, usize) {
    let w = grid.frame.width as usize;
    let mut known_cells = 0usize;
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0usize, 0usize);
    if w == 0 {
        return (None, 0);
    }
    // (Rows are read in blocks of `K` cells with no early exit, which the compiler turns into
    // vector instructions; most of a map is unknown.)
    const K: usize = 64;
    let known_in = |cells: &[Occupancy]| {
        // (At most `K` cells: the count fits a byte, so byte lanes add it.)
        cells
            .iter()
            .fold(0u8, |n, s| n + (*s != Occupancy::Unknown) as u8) as usize
    };
    for (y, row) in grid.data.chunks_exact(w).enumerate() {
        let n = row.chunks(K).map(known_in).sum::<usize>();
        if n == 0 {
            continue;
        }
        let known = |s: &Occupancy| *s != Occupancy::Unknown;
        let first = row
            .chunks(K)
            .position(|c| known_in(c) > 0)
            .expect("a known block");
        let last = row
            .chunks(K)
            .rposition(|c| known_in(c) > 0)
            .expect("a known block");
        let block = |b: usize| &row[b * K..(b * K + K).min(row.len())];
        let fx = first * K + block(first).iter().position(known).expect("a known cell");
        let lx = last * K + block(last).iter().rposition(known).expect("a known cell");
        known_cells += n;
        x0 = x0.min(fx);
        x1 = x1.max(lx);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let b = (known_cells > 0).then(|| {
        (
            Cell::new(x0 as i32, y0 as i32),
            Cell::new(x1 as i32, y1 as i32),
        )
    });
    (b, known_cells)
}

/// A window of the grid: the box grown by `margin` cells, clamped to the grid, as
/// `(x0, y0, width, height)`.
fn window(grid: &OccupancyGrid, bbox: (Cell, Cell), margin: usize) -> (usize, usize, usize, usize) {
    let m = margin as i64;
    let (w, h) = (grid.frame.width as i64, grid.frame.height as i64);
    let x0 = (bbox.0.x as i64 - m).max(0);
    let y0 = (bbox.0.y as i64 - m).max(0);
    let x1 = (bbox.1.x as i64 + m).min(w - 1);
    let y1 = (bbox.1.y as i64 + m).min(h - 1);
    (
        x0 as usize,
        y0 as usize,
        (x1 - x0 + 1).max(0) as usize,
        (y1 - y0 + 1).max(0) as usize,
    )
}

/// The cell radius of the opening of [`fill_thin_unknown`]; `None` when it is off.
fn thin_radius(grid: &OccupancyGrid, max_thickness_m: f64) -> Option<usize> {
    let r = ((max_thickness_m / grid.frame.resolution_m - 1.0) / 2.0).ceil();
    (!r.is_nan() && r >= 1.0 && !grid.frame.is_empty()).then_some(r as usize)
}

/// `grid` with its thin unknown regions (no square of side `max_thickness_m` fits in them)
/// made occupied. Maps made by SLAM from floor plans draw walls as never-observed grey bands
/// edged by sparse occupied cells: such a band is a wall, not a frontier, while the unknown
/// space beyond a frontier is wide. Returns the number of cells changed.
///
/// Only the known box grown by twice the radius is computed: farther unknown cells are more
/// than the radius from any known cell, so the opening keeps them, and cannot reach back to
/// the cells within the radius of the known ones.
pub fn fill_thin_unknown(grid: &OccupancyGrid, max_thickness_m: f64) -> (OccupancyGrid, usize) {
    let (out, changed, _) = fill_thin_unknown_in(grid, max_thickness_m, known_box(grid).0);
    (out, changed)
}

/// [`fill_thin_unknown`] with the known box of `grid` given (from [`known_box`]); also returns
/// the known box of the result (filled cells can lie outside the first one, in a thin band
/// between it and the edge of the grid).
pub fn fill_thin_unknown_in(
    grid: &OccupancyGrid,
    max_thickness_m: f64,
    known_box: Option<(Cell, Cell)>,
) -> (OccupancyGrid, usize, Option<(Cell, Cell)>) {
    let mut out = grid.clone();
    let Some(r) = thin_radius(grid, max_thickness_m) else {
        return (out, 0, known_box);
    };
    let Some(bbox) = known_box else {
        return (out, 0, None);
    };
    let (mut b0, mut b1) = bbox;
    let win = window(grid, bbox, 2 * r + 2);
    let (x0, y0, ww, wh) = win;
    // Opening of the unknown cells: erode (dilate the complement), then dilate.
    let known = BitRows::from_grid(grid, win, |s| s != Occupancy::Unknown);
    let mut eroded = known.dilate(r);
    eroded.invert();
    let opened = eroded.dilate(r);
    let w = grid.frame.width as usize;
    let mut changed = 0;
    for y in 0..wh {
        let start = (y0 + y) * w + x0;
        let cells = &mut out.data[start..start + ww];
        let (mut first, mut last) = (None, None);
        for (k, (o, kn)) in opened.row(y).iter().zip(known.row(y)).enumerate() {
            let outside = !o & opened.valid_bits(k);
            if outside != 0 {
                first.get_or_insert(k * 64 + outside.trailing_zeros() as usize);
                last = Some(k * 64 + 63 - outside.leading_zeros() as usize);
            }
            // Unknown cells not in the opening are filled.
            let mut fill = outside & !kn;
            while fill != 0 {
                cells[k * 64 + fill.trailing_zeros() as usize] = Occupancy::Occupied;
                fill &= fill - 1;
                changed += 1;
            }
        }
        if let (Some(first), Some(last)) = (first, last) {
            // Cells not in the opening are known now (or were).
            let yy = (y0 + y) as i32;
            b0 = Cell::new(b0.x.min((x0 + first) as i32), b0.y.min(yy));
            b1 = Cell::new(b1.x.max((x0 + last) as i32), b1.y.max(yy));
        }
    }
    (out, changed, Some((b0, b1)))
}

/// [`fill_thin_unknown`] as it was first written, on the whole grid with
/// [`dilate_reference`]: the baseline of the layout benchmark.
#[cfg(any(test, feature = "test-support"))]
pub fn fill_thin_unknown_reference(
    grid: &OccupancyGrid,
    max_thickness_m: f64,
) -> (OccupancyGrid, usize) {
    let f = grid.frame;
    let (w, h) = (f.width as usize, f.height as usize);
    let mut out = grid.clone();
    let Some(r) = thin_radius(grid, max_thickness_m) else {
        return (out, 0);
    };
    let known: Vec<bool> = grid.data.iter().map(|s| *s != Occupancy::Unknown).collect();
    let eroded: Vec<bool> = dilate_reference(&known, w, h, r)
        .iter()
        .map(|k| !k)
        .collect();
    let opened = dilate_reference(&eroded, w, h, r);
    let mut changed = 0;
    for (s, o) in out.data.iter_mut().zip(&opened) {
        if *s == Occupancy::Unknown && !o {
            *s = Occupancy::Occupied;
            changed += 1;
        }
    }
    (out, changed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The known box and count, read in blocks, are those of a cell-by-cell scan, on grids
        /// of any width (a row shorter than a block, or not a whole number of blocks) with
        /// sparse known cells.
        #[test]
        fn known_box_is_the_cell_by_cell_one(
            width in 1u32..200,
            height in 1u32..8,
            known in proptest::collection::vec((0u32..200, 0u32..8, 1u8..3), 0..6),
        ) {
            let frame = crate::grid::GridFrame::new(crate::geom::Vec2::zeros(), 0.05, width, height);
            let mut g = OccupancyGrid::filled(frame, Occupancy::Unknown);
            for (x, y, s) in known {
                let c = Cell::new((x % width) as i32, (y % height) as i32);
                let s = if s == 1 { Occupancy::Free } else { Occupancy::Occupied };
                g.set(c, s);
            }
            let cells: Vec<Cell> = (0..frame.len())
                .filter(|&i| g.data[i] != Occupancy::Unknown)
                .map(|i| frame.cell_of_index(i))
                .collect();
            let expected = (!cells.is_empty()).then(|| {
                (
                    Cell::new(cells.iter().map(|c| c.x).min().unwrap(), cells.iter().map(|c| c.y).min().unwrap()),
                    Cell::new(cells.iter().map(|c| c.x).max().unwrap(), cells.iter().map(|c| c.y).max().unwrap()),
                )
            });
            prop_assert_eq!(known_box(&g), (expected, cells.len()));
        }
    }

    /// The boundary cells as first written: a scan of every cell of the known box, reading the
    /// 5x5 window cell by cell.
    fn boundary_cells_reference(grid: &OccupancyGrid) -> Vec<BoundaryCell> {
        let f = grid.frame;
        let (w, h) = (f.width as isize, f.height as isize);
        let at = |x: isize, y: isize| -> Occupancy {
            if x < 0 || y < 0 || x >= w || y >= h {
                Occupancy::Unknown
            } else {
                grid.data[(y * w + x) as usize]
            }
        };
        let mut cells = Vec::new();
        let Some((b0, b1)) = known_box(grid).0 else {
            return cells;
        };
        for y in b0.y as isize..=b1.y as isize {
            for x in b0.x as isize..=b1.x as isize {
                if at(x, y) != Occupancy::Occupied {
                    continue;
                }
                let free = |x, y| at(x, y) == Occupancy::Free;
                if !(free(x - 1, y) || free(x + 1, y) || free(x, y - 1) || free(x, y + 1)) {
                    continue;
                }
                let mut m = Moments::default();
                for dy in -2..=2i32 {
                    for dx in -2..=2i32 {
                        match at(x + dx as isize, y + dy as isize) {
                            Occupancy::Free => {
                                m.gx += dx;
                                m.gy += dy;
                            }
                            Occupancy::Occupied => {
                                m.n += 1;
                                m.sx += dx;
                                m.sy += dy;
                                m.sxx += dx * dx;
                                m.syy += dy * dy;
                                m.sxy += dx * dy;
                            }
                            Occupancy::Unknown => {}
                        }
                    }
                }
                if let Some(normal_rad) = m.normal_rad() {
                    cells.push(BoundaryCell {
                        p: f.world_from_cell(Cell::new(x as i32, y as i32)),
                        normal_rad,
                    });
                }
            }
        }
        cells
    }

    proptest! {
        /// The boundary cells read from packed rows are the reference's, in the same order, and
        /// the cells near a wall are the occupied cells dilated, on grids of any width (a word
        /// and more), walls at the grid's edges included.
        #[test]
        fn wall_evidence_is_the_reference(
            width in 1u32..140,
            height in 1u32..12,
            cells in proptest::collection::vec(0u8..6, 140 * 12),
            tolerance_cells in 0usize..5,
        ) {
            let frame = crate::grid::GridFrame::new(Vec2::zeros(), 0.1, width, height);
            let mut g = OccupancyGrid::filled(frame, Occupancy::Unknown);
            for (s, c) in g.data.iter_mut().zip(&cells) {
                // Half unknown, walls and free space in between.
                *s = match c {
                    0 | 1 => Occupancy::Free,
                    2 => Occupancy::Occupied,
                    _ => Occupancy::Unknown,
                };
            }
            let config = LayoutConfig {
                wall_tolerance_m: tolerance_cells as f64 * 0.1,
                ..LayoutConfig::default()
            };
            let e = wall_evidence(&g, &config);
            prop_assert_eq!(&e.cells, &boundary_cells_reference(&g));
            let (w, h) = (width as usize, height as usize);
            let occupied: Vec<bool> = g.data.iter().map(|s| *s == Occupancy::Occupied).collect();
            let near = dilate_reference(&occupied, w, h, tolerance_cells);
            for (i, want) in near.iter().enumerate() {
                prop_assert_eq!(e.near_wall.get(frame.cell_of_index(i)), *want, "cell {}", i);
            }
        }
    }

    #[test]
    fn boundary_cells_face_the_free_side() {
        let g = OccupancyGrid::from_ascii(
            "
            ##########
            #........#
            #........#
            #........#
            #........#
            ##########
            ",
            0.1,
        );
        let e = wall_evidence(&g, &LayoutConfig::default());
        // Corners touch no free cell; the 8 + 8 + 4 + 4 side cells do.
        assert_eq!(e.cells.len(), 24);
        let exact = e
            .cells
            .iter()
            .filter(|c| {
                let horizontal_wall = (c.p.y < 0.1) || (c.p.y > 0.5);
                let expected = if horizontal_wall {
                    std::f64::consts::FRAC_PI_2
                } else {
                    0.0
                };
                (c.normal_rad - expected).abs() < 1e-9
            })
            .count();
        // Cells next to a corner see both walls; the others are exact.
        assert!(exact >= 8, "{exact}: {:?}", e.cells);
        assert_eq!(e.known_box, Some((Cell::new(0, 0), Cell::new(9, 5))));
        // Tolerance 0.15 m = 1 cell here: the walls and the ring of cells inside them.
        assert_eq!(e.near_wall.count_true(), 48);
    }

    #[test]
    fn windowed_thin_fill_matches_the_whole_grid() {
        // A room with a grey wall band and a wide unknown region, inside a larger grid.
        let mut text = String::new();
        for y in 0..40 {
            for x in 0..50 {
                let outside = !(5..25).contains(&y) || !(5..30).contains(&x);
                let c = if outside || x == 15 || x == 16 {
                    '?'
                } else if y == 5 || y == 24 || x == 5 || x == 29 {
                    '#'
                } else {
                    '.'
                };
                text.push(c);
            }
            text.push('\n');
        }
        let g = OccupancyGrid::from_ascii(&text, 0.1);
        let (a, na) = fill_thin_unknown(&g, 0.6);
        let (b, nb) = fill_thin_unknown_reference(&g, 0.6);
        assert_eq!(na, nb);
        assert!(na >= 2 * 18, "{na}");
        assert_eq!(a, b);
    }
}
