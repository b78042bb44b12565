//! Path pruning for a simple follower: keep only the cells where the line of sight breaks.

use crate::geom::Vec2;
use crate::grid::{Bitmap, Cell, GridFrame};
use crate::mapping::ray::line_of_sight;

/// Waypoints (cell centres, world metres) along `path`, start excluded, goal included: from each
/// waypoint the next is the farthest path cell still in line of sight over traversable cells.
pub fn waypoints(path: &[Cell], trav: &Bitmap) -> Vec<Vec2> {
    waypoints_by(path, &trav.frame, |c| trav.get(c) == Some(&true))
}

/// [`waypoints`] with any traversability test.
pub(crate) fn waypoints_by(
    path: &[Cell],
    frame: &GridFrame,
    clear: impl Fn(Cell) -> bool,
) -> Vec<Vec2> {
    let mut out = Vec::new();
    if path.len() < 2 {
        return path
            .iter()
            .skip(1)
            .map(|c| frame.world_from_cell(*c))
            .collect();
    }
    let mut anchor = 0;
    while anchor < path.len() - 1 {
        let mut next = anchor + 1;
        for j in anchor + 2..path.len() {
            if line_of_sight(path[anchor], path[j], &clear) {
                next = j;
            } else {
                break;
            }
        }
        out.push(frame.world_from_cell(path[next]));
        anchor = next;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::OccupancyGrid;
    use crate::plan::dijkstra::dijkstra;
    use crate::plan::inflate::traversable_from_grid;

    #[test]
    fn straight_path_is_one_waypoint_and_a_corner_needs_two() {
        let t = traversable_from_grid(
            &OccupancyGrid::from_ascii(
                "
                .......
                .#####.
                .#####.
                .......",
                1.0,
            ),
            0.0,
        );
        let f = dijkstra(&t, Cell::new(0, 0), None);
        let w = waypoints(&f.path_to(Cell::new(6, 0)).unwrap(), &t);
        assert_eq!(w, vec![Vec2::new(6.5, 0.5)]);
        let w = waypoints(&f.path_to(Cell::new(6, 3)).unwrap(), &t);
        assert_eq!(w.len(), 2, "{w:?}");
        assert_eq!(w.last(), Some(&Vec2::new(6.5, 3.5)));
        assert!(waypoints(&[], &t).is_empty());
        assert!(waypoints(&[Cell::new(0, 0)], &t).is_empty());
    }
}
