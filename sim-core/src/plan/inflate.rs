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
    let mut best: Option<(i32, Cell)> = None;
    for dy in -radius_cells..=radius_cells {
        for dx in -radius_cells..=radius_cells {
            let n = Cell::new(c.x + dx, c.y + dy);
            let d2 = dx * dx + dy * dy;
            if d2 > radius_cells * radius_cells || trav.get(n) != Some(&true) {
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
}
