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
    let f = grid.frame;
    let (w, h) = (f.width as usize, f.height as usize);
    let mut known_cells = 0usize;
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0usize, 0usize);
    for y in 0..h {
        let row = &grid.data[y * w..(y + 1) * w];
        let first = row.iter().position(|s| *s != Occupancy::Unknown);
        if let Some(fx) = first {
            let lx = row
                .iter()
                .rposition(|s| *s != Occupancy::Unknown)
                .unwrap_or(fx);
            known_cells += row.iter().filter(|s| **s != Occupancy::Unknown).count();
            x0 = x0.min(fx);
            x1 = x1.max(lx);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
    }
    let known_box = (known_cells > 0).then(|| {
        (
            Cell::new(x0 as i32, y0 as i32),
            Cell::new(x1 as i32, y1 as i32),
        )
    });
    let at = |x: isize, y: isize| -> Occupancy {
        if x < 0 || y < 0 || x >= w as isize || y >= h as isize {
            Occupancy::Unknown
        } else {
            grid.data[y as usize * w + x as usize]
        }
    };
    let is_free = |x: usize, y: usize| grid.data[y * w + x] == Occupancy::Free;
    let mut cells = Vec::new();
    for y in 0..h {
        for x in 0..w {
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
    let near_wall = dilate_occupied(grid, radius);
    WallEvidence {
        cells,
        near_wall,
        known_box,
        known_cells,
    }
}

/// Occupied cells dilated by a square of half-side `radius` cells (separable, linear time).
fn dilate_occupied(grid: &OccupancyGrid, radius: usize) -> Bitmap {
    let f = grid.frame;
    let src: Vec<bool> = grid
        .data
        .iter()
        .map(|s| *s == Occupancy::Occupied)
        .collect();
    Bitmap {
        frame: f,
        data: dilate(&src, f.width as usize, f.height as usize, radius),
    }
}

/// A row-major `w` x `h` mask dilated by a square of half-side `radius` cells (cells outside the
/// mask are false).
fn dilate(src: &[bool], w: usize, h: usize, radius: usize) -> Vec<bool> {
    let mut rows = vec![false; w * h];
    let mut line = Vec::new();
    for y in 0..h {
        dilate_1d(&src[y * w..(y + 1) * w], radius, &mut line);
        rows[y * w..(y + 1) * w].copy_from_slice(&line);
    }
    // Columns, row-major: the row of the last true cell above and below, per column.
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

/// `grid` with its thin unknown regions (no square of side `max_thickness_m` fits in them)
/// made occupied. Maps made by SLAM from floor plans draw walls as never-observed grey bands
/// edged by sparse occupied cells: such a band is a wall, not a frontier, while the unknown
/// space beyond a frontier is wide. Returns the number of cells changed.
pub fn fill_thin_unknown(grid: &OccupancyGrid, max_thickness_m: f64) -> (OccupancyGrid, usize) {
    let f = grid.frame;
    let (w, h) = (f.width as usize, f.height as usize);
    let mut out = grid.clone();
    let r = ((max_thickness_m / f.resolution_m - 1.0) / 2.0).ceil();
    if r.is_nan() || r < 1.0 || w == 0 || h == 0 {
        return (out, 0);
    }
    let r = r as usize;
    // Opening of the unknown cells: erode (dilate the complement), then dilate.
    let known: Vec<bool> = grid.data.iter().map(|s| *s != Occupancy::Unknown).collect();
    let eroded: Vec<bool> = dilate(&known, w, h, r).iter().map(|k| !k).collect();
    let opened = dilate(&eroded, w, h, r);
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
    fn dilation_is_square() {
        let mut out = Vec::new();
        dilate_1d(&[false, false, true, false, false, false], 2, &mut out);
        assert_eq!(out, vec![true, true, true, true, true, false]);
    }
}
