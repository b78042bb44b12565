//! Whether a polygon's edges cross each other: outlines, solids and rooms are checked on the
//! way in, as an uneven figure-eight has an area and would otherwise load as two shapes.
//!
//! Only proper crossings count: two edges whose ends lie on either side of each other's line,
//! each farther from it than [`TOLERANCE_M`]. Real floor plans repeat points, trace a stretch of
//! wall twice and touch themselves at a vertex; none of that is a crossing.

use sim_core::Vec2;

use crate::error::point;

/// An edge end within this distance of the other edge's line is on it (m): far below anything a
/// map shows, far above the rounding of coordinates within [`crate::limits::COORDINATE_LIMIT_M`].
pub const TOLERANCE_M: f64 = 1e-4;

/// Most work (edges entered in cells, pairs of edges tested) the checks of one file may do: a
/// file of huge polygons of long edges over one another is left partly unchecked rather than
/// keep the reader for long.
pub const FILE_BUDGET: u64 = 20_000_000;

/// Two edges of a polygon that cross: edge `i` runs from vertex `i` to the next.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    pub edges: (usize, usize),
    pub at: Vec2,
}

impl Crossing {
    /// The crossing as an error's words, with the edges' ends (`pts`: the polygon checked).
    pub fn describe(&self, pts: &[Vec2]) -> String {
        let end = |e: usize| {
            let (a, b) = (pts[e], pts[(e + 1) % pts.len()]);
            format!("from {} to {}", point(a.x, a.y), point(b.x, b.y))
        };
        format!(
            "polygon's edges cross each other: the edge {} crosses the edge {} at {}; expected a simple polygon, its vertices listed in order around it",
            end(self.edges.0),
            end(self.edges.1),
            point(self.at.x, self.at.y)
        )
    }
}

/// The first crossing (the least pair of edges) of the ring `pts` (its last vertex joins its
/// first; not repeated), or `None`: no crossing, or the work `budget` (of the file: it is spent)
/// ran out first. Edges are entered in the cells of a grid of about one cell per edge over the
/// polygon's box that their boxes cover, and the edges sharing a cell are tested in pairs.
pub fn first_crossing(pts: &[Vec2], budget: &mut u64) -> Option<Crossing> {
    let n = pts.len();
    if n < 4 || n as u64 > *budget || n > u32::MAX as usize {
        return None;
    }
    let (mut lo, mut hi) = (pts[0], pts[0]);
    for p in pts {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let side = (n as f64).sqrt().ceil().clamp(1.0, 1024.0) as usize;
    let size = hi - lo;
    let cell_of = |v: f64, lo: f64, extent: f64| -> usize {
        if extent > 0.0 {
            (((v - lo) / extent * side as f64) as usize).min(side - 1)
        } else {
            0
        }
    };
    // (cell, edge), sorted by cell: the edges of each cell together.
    let mut entries: Vec<(u32, u32)> = Vec::with_capacity(n);
    for e in 0..n {
        let (a, b) = (pts[e], pts[(e + 1) % n]);
        let (x0, x1) = (
            cell_of(a.x.min(b.x), lo.x, size.x),
            cell_of(a.x.max(b.x), lo.x, size.x),
        );
        let (y0, y1) = (
            cell_of(a.y.min(b.y), lo.y, size.y),
            cell_of(a.y.max(b.y), lo.y, size.y),
        );
        let cost = ((x1 - x0 + 1) * (y1 - y0 + 1)) as u64;
        if cost > *budget {
            *budget = 0;
            return None;
        }
        *budget -= cost;
        for y in y0..=y1 {
            entries.extend((x0..=x1).map(|x| ((y * side + x) as u32, e as u32)));
        }
    }
    entries.sort_unstable();
    let mut first: Option<Crossing> = None;
    for cell in entries.chunk_by(|a, b| a.0 == b.0) {
        for (k, &(_, i)) in cell.iter().enumerate() {
            for &(_, j) in &cell[k + 1..] {
                if *budget == 0 {
                    return None;
                }
                *budget -= 1;
                let (i, j) = (i as usize, j as usize);
                if j == i + 1 || (i == 0 && j == n - 1) {
                    continue;
                }
                if first.is_some_and(|c| c.edges <= (i, j)) {
                    continue;
                }
                if let Some(at) =
                    proper_crossing((pts[i], pts[(i + 1) % n]), (pts[j], pts[(j + 1) % n]))
                {
                    first = Some(Crossing { edges: (i, j), at });
                }
            }
        }
    }
    first
}

/// Where the segments `p` and `q` cross, when each one's ends lie on either side of the other's
/// line, farther from it than [`TOLERANCE_M`].
fn proper_crossing(p: (Vec2, Vec2), q: (Vec2, Vec2)) -> Option<Vec2> {
    let off = |s: (Vec2, Vec2), v: Vec2| -> Option<f64> {
        let d = s.1 - s.0;
        let len = d.norm();
        (len > 0.0).then(|| d.perp(&(v - s.0)) / len)
    };
    let (s1, s2) = (off(p, q.0)?, off(p, q.1)?);
    let (s3, s4) = (off(q, p.0)?, off(q, p.1)?);
    let apart = |a: f64, b: f64| a * b < 0.0 && a.abs() > TOLERANCE_M && b.abs() > TOLERANCE_M;
    if !(apart(s1, s2) && apart(s3, s4)) {
        return None;
    }
    let t = s3 / (s3 - s4);
    Some(p.0 + (p.1 - p.0) * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring(pts: &[[f64; 2]]) -> Vec<Vec2> {
        pts.iter().map(|p| Vec2::new(p[0], p[1])).collect()
    }

    /// (polygon, its first crossing's edges, or none)
    #[test]
    fn crossings_are_found_and_touches_are_not() {
        type Case<'a> = (&'a str, &'a [[f64; 2]], Option<(usize, usize)>);
        let cases: &[Case] = &[
            (
                "square",
                &[[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]],
                None,
            ),
            (
                "uneven figure-eight",
                &[[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 4.0]],
                Some((0, 2)),
            ),
            (
                "even figure-eight",
                &[[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 10.0]],
                Some((0, 2)),
            ),
            // A real plan's room: its last edge runs back over its first.
            (
                "a wall traced twice",
                &[
                    [394.0, 237.0],
                    [394.0, 246.0],
                    [394.0, 279.0],
                    [453.0, 279.0],
                    [453.0, 239.0],
                    [394.0, 239.0],
                ],
                None,
            ),
            (
                "touching itself at a vertex",
                &[
                    [0.0, 0.0],
                    [4.0, 0.0],
                    [2.0, 2.0],
                    [4.0, 4.0],
                    [0.0, 4.0],
                    [2.0, 2.0],
                ],
                None,
            ),
            (
                "a vertex on another edge",
                &[[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [2.0, 0.0], [0.0, 4.0]],
                None,
            ),
            (
                "crossing by less than the tolerance",
                &[
                    [0.0, 0.0],
                    [4.0, 0.0],
                    [4.0, 4.0],
                    [2.0, -0.00005],
                    [0.0, 4.0],
                ],
                None,
            ),
            (
                "crossing by a millimetre",
                &[
                    [0.0, 0.0],
                    [4.0, 0.0],
                    [4.0, 4.0],
                    [2.0, -0.001],
                    [0.0, 4.0],
                ],
                Some((0, 2)),
            ),
            (
                "an L",
                &[
                    [0.0, 0.0],
                    [6.0, 0.0],
                    [6.0, 2.0],
                    [2.0, 2.0],
                    [2.0, 6.0],
                    [0.0, 6.0],
                ],
                None,
            ),
            ("a triangle", &[[0.0, 0.0], [6.0, 0.0], [0.0, 6.0]], None),
        ];
        for (name, pts, want) in cases {
            let mut budget = FILE_BUDGET;
            let got = first_crossing(&ring(pts), &mut budget).map(|c| c.edges);
            assert_eq!(got, *want, "{name}");
        }
        let bowtie = ring(&[[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 10.0]]);
        let c = first_crossing(&bowtie, &mut { FILE_BUDGET });
        assert!((c.unwrap().at - Vec2::new(5.0, 5.0)).norm() < 1e-12);
    }

    /// A many-sided polygon, simple or with one spike through its far side, checked on the grid
    /// as by testing every pair.
    #[test]
    fn the_grid_finds_what_every_pair_finds() {
        let n = 2000;
        let circle: Vec<Vec2> = (0..n)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                Vec2::new(50.0 * a.cos(), 50.0 * a.sin())
            })
            .collect();
        let mut budget = FILE_BUDGET;
        assert_eq!(first_crossing(&circle, &mut budget), None);
        assert!(budget < FILE_BUDGET);
        let mut spiked = circle.clone();
        spiked[10] = Vec2::new(-60.0, 1.0);
        let every_pair = (0..n)
            .flat_map(|i| (i + 2..n).map(move |j| (i, j)))
            .filter(|&(i, j)| !(i == 0 && j == n - 1))
            .find(|&(i, j)| {
                proper_crossing(
                    (spiked[i], spiked[(i + 1) % n]),
                    (spiked[j], spiked[(j + 1) % n]),
                )
                .is_some()
            });
        assert!(every_pair.is_some());
        assert_eq!(
            first_crossing(&spiked, &mut budget).map(|c| c.edges),
            every_pair
        );
        // Without the budget for it, a polygon is left unchecked.
        assert_eq!(first_crossing(&spiked, &mut 100), None);
    }
}
