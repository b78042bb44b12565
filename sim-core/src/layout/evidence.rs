//! Wall evidence: occupied cells on the boundary of free space, each with the orientation of the
//! local boundary, plus a mask of the cells near any occupied cell.

use super::LayoutConfig;
use crate::geom::Vec2;
use crate::grid::{Bitmap, Cell, Occupancy, OccupancyGrid};

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
    pub near_wall: Bitmap,
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
pub fn wall_evidence_in(
    grid: &OccupancyGrid,
    config: &LayoutConfig,
    (known_box, known_cells): (Option<(Cell, Cell)>, usize),
) -> WallEvidence {
    let f = grid.frame;
    let (w, h) = (f.width as usize, f.height as usize);
    let at = |x: isize, y: isize| -> Occupancy {
        if x < 0 || y < 0 || x >= w as isize || y >= h as isize {
            Occupancy::Unknown
        } else {
            grid.data[y as usize * w + x as usize]
        }
    };
    let is_free = |x: usize, y: usize| grid.data[y * w + x] == Occupancy::Free;
    let mut cells = Vec::new();
    let (bx0, by0, bx1, by1) = known_box.map_or((1, 1, 0, 0), |(a, b)| {
        (a.x as usize, a.y as usize, b.x as usize, b.y as usize)
    });
    for y in by0..=by1 {
        for x in bx0..=bx1 {
            if grid.data[y * w + x] != Occupancy::Occupied {
                continue;
            }
            let touches_free = (x > 0 && is_free(x - 1, y))
                || (x + 1 < w && is_free(x + 1, y))
                || (y > 0 && is_free(x, y - 1))
                || (y + 1 < h && is_free(x, y + 1));
            if !touches_free {
                continue;
            }
            // In a 5x5 window: the first moment of the free cells (points to the free side of a
            // wall edge) and the second moments of the occupied cells (the axis of a thin wall,
            // which has free space on both sides and no free moment).
            let (xi, yi) = (x as isize, y as isize);
            let (mut gx, mut gy) = (0i32, 0i32);
            let (mut n, mut sx, mut sy, mut sxx, mut syy, mut sxy) =
                (0i32, 0i32, 0i32, 0i32, 0i32, 0i32);
            for dy in -2..=2isize {
                for dx in -2..=2isize {
                    match at(xi + dx, yi + dy) {
                        Occupancy::Free => {
                            gx += dx as i32;
                            gy += dy as i32;
                        }
                        Occupancy::Occupied => {
                            let (dx, dy) = (dx as i32, dy as i32);
                            n += 1;
                            sx += dx;
                            sy += dy;
                            sxx += dx * dx;
                            syy += dy * dy;
                            sxy += dx * dy;
                        }
                        Occupancy::Unknown => {}
                    }
                }
            }
            let a = if gx * gx + gy * gy >= 25 {
                (gy as f64).atan2(gx as f64)
            } else {
                let nf = n as f64;
                let cxx = sxx as f64 - (sx * sx) as f64 / nf;
                let cyy = syy as f64 - (sy * sy) as f64 / nf;
                let cxy = sxy as f64 - (sx * sy) as f64 / nf;
                if cxx == cyy && cxy == 0.0 {
                    continue;
                }
                // Major axis of the occupied cells, turned to its normal.
                0.5 * (2.0 * cxy).atan2(cxx - cyy) + std::f64::consts::FRAC_PI_2
            };
            let a = a.rem_euclid(std::f64::consts::PI);
            cells.push(BoundaryCell {
                p: f.world_from_cell(Cell::new(x as i32, y as i32)),
                normal_rad: if a >= std::f64::consts::PI { 0.0 } else { a },
            });
        }
    }
    let radius = (config.wall_tolerance_m / f.resolution_m).round().max(0.0) as usize;
    let near_wall = dilate_occupied(grid, known_box, radius);
    WallEvidence {
        cells,
        near_wall,
        known_box,
        known_cells,
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

/// The cells of `grid` in the window, mapped by `pred`, row-major.
fn window_mask(
    grid: &OccupancyGrid,
    (x0, y0, ww, wh): (usize, usize, usize, usize),
    pred: impl Fn(Occupancy) -> bool,
) -> Vec<bool> {
    let w = grid.frame.width as usize;
    let mut out = Vec::with_capacity(ww * wh);
    for y in y0..y0 + wh {
        out.extend(
            grid.data[y * w + x0..y * w + x0 + ww]
                .iter()
                .map(|s| pred(*s)),
        );
    }
    out
}

/// Occupied cells dilated by a square of half-side `radius` cells. Occupied cells are known, so
/// only the known box (grown by the radius) is computed.
fn dilate_occupied(grid: &OccupancyGrid, bbox: Option<(Cell, Cell)>, radius: usize) -> Bitmap {
    let f = grid.frame;
    let mut out = Bitmap::filled(f, false);
    let Some(bbox) = bbox else {
        return out;
    };
    let win = window(grid, bbox, radius);
    let (x0, y0, ww, wh) = win;
    let src = window_mask(grid, win, |s| s == Occupancy::Occupied);
    let d = dilate(&src, ww, wh, radius);
    let w = f.width as usize;
    for (y, row) in d.chunks_exact(ww.max(1)).enumerate() {
        out.data[(y0 + y) * w + x0..(y0 + y) * w + x0 + ww].copy_from_slice(row);
    }
    out
}

/// A row-major `w` x `h` mask dilated by a square of half-side `radius` cells (cells outside the
/// mask are false). Separable; each axis is a few passes of shifted ORs over whole slices
/// (radii 1, 2, 4...: a dilation by `R` followed by one by `{-s, 0, s}`, `s <= R + 1`, is one
/// by `R + s`, also where the mask's edge clips it), which the compiler vectorises.
pub fn dilate(src: &[bool], w: usize, h: usize, radius: usize) -> Vec<bool> {
    let mut a = src.to_vec();
    if radius == 0 || w == 0 || h == 0 {
        return a;
    }
    let mut b = vec![false; a.len()];
    // Rows.
    let mut r = 0;
    while r < radius {
        let s = (r + 1).min(radius - r);
        if s < w {
            for (ra, rb) in a.chunks_exact(w).zip(b.chunks_exact_mut(w)) {
                rb.copy_from_slice(ra);
                or_shifted(rb, ra, s);
            }
            std::mem::swap(&mut a, &mut b);
        } else {
            for ra in a.chunks_exact_mut(w) {
                let any = ra.iter().any(|v| *v);
                ra.fill(any);
            }
        }
        r += s;
    }
    // Columns: the same on the whole array with a shift of `s` rows.
    let mut r = 0;
    while r < radius {
        let s = (r + 1).min(radius - r);
        if s < h {
            b.copy_from_slice(&a);
            or_shifted(&mut b, &a, s * w);
            std::mem::swap(&mut a, &mut b);
        } else {
            let mut any = vec![false; w];
            for ra in a.chunks_exact(w) {
                for (x, v) in any.iter_mut().zip(ra) {
                    *x |= *v;
                }
            }
            for ra in a.chunks_exact_mut(w) {
                ra.copy_from_slice(&any);
            }
        }
        r += s;
    }
    a
}

/// `dst[i] |= src[i - s] | src[i + s]` where those exist (`s < len`).
fn or_shifted(dst: &mut [bool], src: &[bool], s: usize) {
    let n = src.len();
    for (d, v) in dst[s..].iter_mut().zip(&src[..n - s]) {
        *d |= *v;
    }
    for (d, v) in dst[..n - s].iter_mut().zip(&src[s..]) {
        *d |= *v;
    }
}

/// The reference dilation (per cell, the last true cell before and after in each row, then in
/// each column, over the whole mask): what [`dilate`] replaced; kept to check and benchmark it.
pub fn dilate_reference(src: &[bool], w: usize, h: usize, radius: usize) -> Vec<bool> {
    let mut rows = vec![false; w * h];
    let mut line = Vec::new();
    for y in 0..h {
        dilate_1d(&src[y * w..(y + 1) * w], radius, &mut line);
        rows[y * w..(y + 1) * w].copy_from_slice(&line);
    }
    let mut out = rows.clone();
    let mut last = vec![usize::MAX; w];
    for y in 0..h {
        let row = &rows[y * w..(y + 1) * w];
        for x in 0..w {
            if row[x] {
                last[x] = y;
            }
            if last[x] != usize::MAX && y - last[x] <= radius {
                out[y * w + x] = true;
            }
        }
    }
    last.fill(usize::MAX);
    for y in (0..h).rev() {
        let row = &rows[y * w..(y + 1) * w];
        for x in 0..w {
            if row[x] {
                last[x] = y;
            }
            if last[x] != usize::MAX && last[x] - y <= radius {
                out[y * w + x] = true;
            }
        }
    }
    out
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
    let known = window_mask(grid, win, |s| s != Occupancy::Unknown);
    let mut eroded = dilate(&known, ww, wh, r);
    eroded.iter_mut().for_each(|k| *k = !*k);
    let opened = dilate(&eroded, ww, wh, r);
    let w = grid.frame.width as usize;
    let mut changed = 0;
    for (y, row) in opened.chunks_exact(ww).enumerate() {
        let start = (y0 + y) * w + x0;
        for (s, o) in out.data[start..start + ww].iter_mut().zip(row) {
            if *s == Occupancy::Unknown && !o {
                *s = Occupancy::Occupied;
                changed += 1;
            }
        }
        if let (Some(first), Some(last)) =
            (row.iter().position(|o| !o), row.iter().rposition(|o| !o))
        {
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

/// `out[i]` is true when some `src[j]` with `|i - j| <= radius` is.
fn dilate_1d(src: &[bool], radius: usize, out: &mut Vec<bool>) {
    let n = src.len();
    out.clear();
    out.resize(n, false);
    // Distance to the last true on the left, then on the right.
    let mut last: Option<usize> = None;
    for i in 0..n {
        if src[i] {
            last = Some(i);
        }
        if last.is_some_and(|j| i - j <= radius) {
            out[i] = true;
        }
    }
    last = None;
    for i in (0..n).rev() {
        if src[i] {
            last = Some(i);
        }
        if last.is_some_and(|j| j - i <= radius) {
            out[i] = true;
        }
    }
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
    fn fast_dilation_matches_the_reference() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for (w, h) in [(1, 1), (7, 3), (40, 33), (5, 60)] {
            let src: Vec<bool> = (0..w * h).map(|_| rng.random_bool(0.03)).collect();
            for radius in [0, 1, 2, 3, 4, 6, 7, 13, 80] {
                assert_eq!(
                    dilate(&src, w, h, radius),
                    dilate_reference(&src, w, h, radius),
                    "{w}x{h} r {radius}"
                );
            }
        }
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

    #[test]
    fn dilation_is_square() {
        let mut out = Vec::new();
        dilate_1d(&[false, false, true, false, false, false], 2, &mut out);
        assert_eq!(out, vec![true, true, true, true, true, false]);
    }
}
