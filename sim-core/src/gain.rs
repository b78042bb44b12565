//! Information gain `I(p)`: the area of unknown cells a laser at `p` could see.
//!
//! Visibility is approximated by casting rays **over 360 degrees** (the robot can turn on the
//! spot) from the centre of `p`'s cell with an exact cell walk, so densely (one ray per cell of
//! arc at full range) that every cell at range is crossed by a ray. A ray stops at the first
//! blocking cell or at the range; a cell counts (once: a stamp buffer over the disc) when its
//! centre is within range.
//! The same core serves the layout variant, which passes other `blocks` / `counts` predicates.

use crate::grid::{Cell, GridFrame, Occupancy, OccupancyGrid};
use crate::mapping::ray::walk_segment;

/// Area (m2) of the cells within `range_m` of cell `p` that are visible from `p` (no blocking
/// cell on the way, the blocking cell itself excluded) and satisfy `counts`. Cells outside the
/// frame block.
pub fn visible_area(
    frame: &GridFrame,
    p: Cell,
    range_m: f64,
    blocks: impl Fn(Cell) -> bool,
    counts: impl Fn(Cell) -> bool,
) -> f64 {
    if !frame.contains(p) || range_m.is_nan() || range_m <= 0.0 || blocks(p) {
        return 0.0;
    }
    let r_cells = range_m / frame.resolution_m;
    let half = r_cells.ceil() as i32 + 1;
    let side = (2 * half + 1) as usize;
    let mut seen = vec![false; side * side];
    let n_rays = ((std::f64::consts::TAU * r_cells).ceil() as usize).max(8);
    let start = [p.x as f64 + 0.5, p.y as f64 + 0.5];
    let r2 = r_cells * r_cells;
    let mut count = 0usize;
    for k in 0..n_rays {
        let a = k as f64 * std::f64::consts::TAU / n_rays as f64;
        let end = [start[0] + a.cos() * r_cells, start[1] + a.sin() * r_cells];
        walk_segment(start, end, |c| {
            if !frame.contains(c) || blocks(c) {
                return false;
            }
            let (dx, dy) = (c.x - p.x, c.y - p.y);
            let s = &mut seen[(dy + half) as usize * side + (dx + half) as usize];
            if !*s {
                *s = true;
                if ((dx * dx + dy * dy) as f64) <= r2 && counts(c) {
                    count += 1;
                }
            }
            true
        });
    }
    count as f64 * frame.cell_area_m2()
}

/// The baseline `I(p)`: unknown area visible from `p` through the map, unknown treated as free,
/// occupied cells blocking.
pub fn information_gain(grid: &OccupancyGrid, p: Cell, range_m: f64) -> f64 {
    visible_area(
        &grid.frame,
        p,
        range_m,
        |c| grid.is(c, Occupancy::Occupied),
        |c| grid.is(c, Occupancy::Unknown),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_behind_a_frontier_counts_and_a_wall_blocks() {
        let open = OccupancyGrid::from_ascii(
            "
            ??????????
            ??????????
            ..........
            ..........",
            1.0,
        );
        let near = information_gain(&open, Cell::new(4, 0), 2.5);
        assert!(near > 0.0);
        let far = information_gain(&open, Cell::new(4, 0), 20.0);
        assert_eq!(far, 20.0);
        let walled = OccupancyGrid::from_ascii(
            "
            ??????????
            ??????????
            ##########
            ..........",
            1.0,
        );
        assert_eq!(information_gain(&walled, Cell::new(4, 0), 20.0), 0.0);
        let half_walled = OccupancyGrid::from_ascii(
            "
            ??????????
            ??????????
            #####.....
            ..........",
            1.0,
        );
        let g = information_gain(&half_walled, Cell::new(8, 0), 20.0);
        assert!(g > 0.0 && g < 20.0, "{g}");
        // The range limits: from the row below, a 1.2 m range sees only the cells right above.
        let g = information_gain(&open, Cell::new(4, 1), 1.2);
        assert_eq!(g, 1.0);
    }

    #[test]
    fn counts_each_cell_once_and_handles_odd_input() {
        let all_unknown = OccupancyGrid::from_ascii("?????\n?????\n?????\n?????\n?????", 1.0);
        let g = visible_area(
            &all_unknown.frame,
            Cell::new(2, 2),
            10.0,
            |_| false,
            |_| true,
        );
        assert_eq!(g, 25.0);
        assert_eq!(information_gain(&all_unknown, Cell::new(9, 9), 3.0), 0.0);
        assert_eq!(information_gain(&all_unknown, Cell::new(2, 2), 0.0), 0.0);
        let wall = OccupancyGrid::from_ascii("#", 1.0);
        assert_eq!(information_gain(&wall, Cell::new(0, 0), 3.0), 0.0);
    }
}
