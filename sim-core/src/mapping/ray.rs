//! Exact cell traversal of a segment (Amanatides & Woo), shared by the mapper, the gain
//! estimate and line-of-sight checks.

use crate::geom::{floor_i32, Vec2};
use crate::grid::{Cell, GridFrame};

/// A point in grid coordinates: cell units, cell `(i, j)` spans `[i, i+1) x [j, j+1)`.
pub fn grid_from_world(frame: &GridFrame, p: Vec2) -> [f64; 2] {
    let q = (p - frame.origin_m) / frame.resolution_m;
    [q.x, q.y]
}

/// Visits, in order, every cell the segment from `a` to `b` (grid coordinates) passes through,
/// both end cells included. `visit` returns `false` to stop early. Cells may lie outside any grid;
/// the caller filters. When the segment passes exactly through a cell corner, the x-neighbour is
/// visited before the y-neighbour (deterministic, 4-connected walk).
// (Always inlined, as profile-guided optimisation chose: BENCHMARKS.md.)
#[inline(always)]
pub fn walk_segment(a: [f64; 2], b: [f64; 2], mut visit: impl FnMut(Cell) -> bool) {
    for c in SegmentCells::new(a, b) {
        if !visit(c) {
            return;
        }
    }
}

/// The cells of [`walk_segment`] as an iterator: a loop over it keeps its body in the caller
/// (a closure per cell is a call per cell when the compiler declines to inline it, as in the
/// map update's hot loop). A segment with a non-finite end has no cells.
#[derive(Debug, Clone)]
pub(crate) struct SegmentCells {
    cx: i32,
    cy: i32,
    ex: i32,
    ey: i32,
    step_x: i32,
    step_y: i32,
    t_delta_x: f64,
    t_delta_y: f64,
    t_max_x: f64,
    t_max_y: f64,
    /// Steps left after the first cell.
    left: u32,
    /// The first cell is still to be returned.
    first: bool,
}

impl SegmentCells {
    // (Always inlined, as profile-guided optimisation chose: BENCHMARKS.md.)
    #[inline(always)]
    pub(crate) fn new(a: [f64; 2], b: [f64; 2]) -> Self {
        let finite = a[0].is_finite() && a[1].is_finite() && b[0].is_finite() && b[1].is_finite();
        let cx = floor_i32(a[0]);
        let cy = floor_i32(a[1]);
        let ex = floor_i32(b[0]);
        let ey = floor_i32(b[1]);
        let (step_x, t_delta_x, t_max_x) = axis(a[0], b[0], cx);
        let (step_y, t_delta_y, t_max_y) = axis(a[1], b[1], cy);
        Self {
            cx,
            cy,
            ex,
            ey,
            step_x,
            step_y,
            t_delta_x,
            t_delta_y,
            t_max_x,
            t_max_y,
            left: if finite {
                ex.abs_diff(cx).saturating_add(ey.abs_diff(cy))
            } else {
                0
            },
            first: finite,
        }
    }
}

/// Along one axis, from `a` (in cell `c`) to `b`: the step (+1 or -1), the segment parameter
/// per cell, and the parameter at the first cell boundary (infinite with no extent).
fn axis(a: f64, b: f64, c: i32) -> (i32, f64, f64) {
    let d = b - a;
    let step = if d > 0.0 { 1 } else { -1 };
    let t_delta = if d != 0.0 {
        1.0 / d.abs()
    } else {
        f64::INFINITY
    };
    let t_max = if d > 0.0 {
        (c as f64 + 1.0 - a) * t_delta
    } else if d < 0.0 {
        (a - c as f64) * t_delta
    } else {
        f64::INFINITY
    };
    (step, t_delta, t_max)
}

impl SegmentCells {
    /// The cells the iterator gives, each with its row-major index in a frame `w` cells wide, for
    /// a segment whose first and last cells lie in that frame (then every cell does: the walk
    /// stays in their box): `visit` gets every cell but the last, which is returned (`None`
    /// when there are no cells), and the steps left from it on each axis (its distance from the
    /// last cell in columns and in rows: the walk moves toward the last cell on both). Steps on
    /// both axes while both have some left (one comparison per step), then on the one left, the
    /// index kept by adding.
    #[inline(always)]
    pub(crate) fn for_each_indexed(
        self,
        w: i32,
        mut visit: impl FnMut(Cell, usize, u32, u32),
    ) -> Option<(Cell, usize)> {
        if !self.first {
            return None;
        }
        let (sx, sy) = (self.step_x, self.step_y);
        let row = sy as isize * w as isize;
        let (mut cx, mut cy) = (self.cx, self.cy);
        let mut idx = cy as isize * w as isize + cx as isize;
        let (mut nx, mut ny) = (self.ex.abs_diff(cx), self.ey.abs_diff(cy));
        let (mut tx, mut ty) = (self.t_max_x, self.t_max_y);
        // Each step visits the cell it leaves.
        while nx > 0 && ny > 0 {
            visit(Cell::new(cx, cy), idx as usize, nx, ny);
            if tx <= ty {
                cx += sx;
                idx += sx as isize;
                tx += self.t_delta_x;
                nx -= 1;
            } else {
                cy += sy;
                idx += row;
                ty += self.t_delta_y;
                ny -= 1;
            }
        }
        while nx > 0 {
            visit(Cell::new(cx, cy), idx as usize, nx, 0);
            cx += sx;
            idx += sx as isize;
            nx -= 1;
        }
        while ny > 0 {
            visit(Cell::new(cx, cy), idx as usize, 0, ny);
            cy += sy;
            idx += row;
            ny -= 1;
        }
        Some((Cell::new(cx, cy), idx as usize))
    }
}

impl Iterator for SegmentCells {
    type Item = Cell;

    #[inline]
    fn next(&mut self) -> Option<Cell> {
        if self.first {
            self.first = false;
            return Some(Cell::new(self.cx, self.cy));
        }
        if self.left == 0 {
            return None;
        }
        self.left -= 1;
        // Step along the axis whose boundary comes first, but never past the end cell on it.
        let go_x = if self.cx == self.ex {
            false
        } else if self.cy == self.ey {
            true
        } else {
            self.t_max_x <= self.t_max_y
        };
        if go_x {
            self.cx += self.step_x;
            self.t_max_x += self.t_delta_x;
        } else {
            self.cy += self.step_y;
            self.t_max_y += self.t_delta_y;
        }
        Some(Cell::new(self.cx, self.cy))
    }
}

/// Whether every cell on the segment between the centres of `a` and `b` satisfies `clear`.
// (Always inlined, as profile-guided optimisation chose: BENCHMARKS.md.)
#[inline(always)]
pub(crate) fn line_of_sight(a: Cell, b: Cell, mut clear: impl FnMut(Cell) -> bool) -> bool {
    let mut ok = true;
    walk_segment(
        [a.x as f64 + 0.5, a.y as f64 + 0.5],
        [b.x as f64 + 0.5, b.y as f64 + 0.5],
        |c| {
            ok = clear(c);
            ok
        },
    );
    ok
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cells(a: [f64; 2], b: [f64; 2]) -> Vec<(i32, i32)> {
        let mut v = Vec::new();
        walk_segment(a, b, |c| {
            v.push((c.x, c.y));
            true
        });
        v
    }

    #[test]
    fn horizontal_and_diagonal_walks() {
        assert_eq!(
            cells([0.5, 0.5], [3.2, 0.7]),
            vec![(0, 0), (1, 0), (2, 0), (3, 0)]
        );
        assert_eq!(cells([2.5, 0.5], [0.1, 0.5]), vec![(2, 0), (1, 0), (0, 0)]);
        let d = cells([0.2, 0.1], [2.9, 1.8]);
        assert_eq!(d.first(), Some(&(0, 0)));
        assert_eq!(d.last(), Some(&(2, 1)));
        // 4-connected: consecutive cells differ in exactly one coordinate by one.
        for w in d.windows(2) {
            assert_eq!((w[0].0 - w[1].0).abs() + (w[0].1 - w[1].1).abs(), 1);
        }
        assert_eq!(cells([1.5, 1.5], [1.7, 1.2]), vec![(1, 1)]);
        assert!(cells([f64::NAN, 0.0], [1.0, 1.0]).is_empty());
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(2000))]
        /// The indexed walk visits the iterator's cells, with their indices and their distances
        /// from the last cell on each axis, and returns the last.
        #[test]
        fn the_indexed_walk_is_the_walk(
            a in (0.0f64..40.0, 0.0f64..30.0), b in (0.0f64..40.0, 0.0f64..30.0),
            snap in 0u8..4,
        ) {
            // Ends on cell corners and edges too (ties between the axes).
            let q = |v: f64| match snap { 0 => v, 1 => v.round(), 2 => (v * 2.0).round() / 2.0, _ => v.floor() + 0.5 };
            let (a, b) = ([q(a.0), q(a.1)], [q(b.0), q(b.1)]);
            let w = 41;
            let e = Cell::new(b[0].floor() as i32, b[1].floor() as i32);
            let want: Vec<(Cell, usize, u32, u32)> = SegmentCells::new(a, b)
                .map(|c| (c, (c.y * w + c.x) as usize, c.x.abs_diff(e.x), c.y.abs_diff(e.y)))
                .collect();
            let mut got = Vec::new();
            let last = SegmentCells::new(a, b)
                .for_each_indexed(w, |c, i, nx, ny| got.push((c, i, nx, ny)));
            got.extend(last.map(|(c, i)| (c, i, 0, 0)));
            proptest::prop_assert_eq!(&got, &want);
        }
    }

    #[test]
    fn line_of_sight_stops_at_blocker() {
        let blocked = Cell::new(2, 0);
        assert!(!line_of_sight(Cell::new(0, 0), Cell::new(4, 0), |c| c != blocked));
        assert!(line_of_sight(Cell::new(0, 1), Cell::new(4, 1), |c| c != blocked));
    }
}
