//! Walls and outline of a plan, on the grid of its zones' edge coordinates.
//!
//! Every boundary between two different zones (or a zone and the outside) is a wall, except
//! between two corridors; walls are merged along each grid line, so two neighbouring rooms share
//! one wall, and door openings are cut out of them.

use super::{Layout, Opening, WALL_THICKNESS_M};
use crate::geom::{Polygon, Vec2};

const EPS: f64 = 1e-6;

/// The sorted distinct coordinates of `values`.
fn axis(mut values: Vec<f64>) -> Vec<f64> {
    values.sort_by(|a, b| a.total_cmp(b));
    values.dedup_by(|a, b| (*a - *b).abs() < EPS);
    values
}

fn index_of(axis: &[f64], v: f64) -> usize {
    axis.partition_point(|&a| a < v - EPS)
}

/// Zone ids per cell of the compressed grid.
struct ZoneGrid {
    xs: Vec<f64>,
    ys: Vec<f64>,
    cells: Vec<Option<usize>>,
}

impl ZoneGrid {
    fn new(layout: &Layout) -> Self {
        let xs = axis(
            layout
                .zones
                .iter()
                .flat_map(|z| [z.rect.min.x, z.rect.max.x])
                .collect(),
        );
        let ys = axis(
            layout
                .zones
                .iter()
                .flat_map(|z| [z.rect.min.y, z.rect.max.y])
                .collect(),
        );
        let nx = xs.len().saturating_sub(1);
        let ny = ys.len().saturating_sub(1);
        let mut cells = vec![None; nx * ny];
        for (i, z) in layout.zones.iter().enumerate() {
            let (x0, x1) = (index_of(&xs, z.rect.min.x), index_of(&xs, z.rect.max.x));
            let (y0, y1) = (index_of(&ys, z.rect.min.y), index_of(&ys, z.rect.max.y));
            for cy in y0..y1 {
                for cx in x0..x1 {
                    cells[cy * nx + cx] = Some(i);
                }
            }
        }
        Self { xs, ys, cells }
    }
    fn nx(&self) -> usize {
        self.xs.len().saturating_sub(1)
    }
    fn ny(&self) -> usize {
        self.ys.len().saturating_sub(1)
    }
    fn at(&self, cx: isize, cy: isize) -> Option<usize> {
        if cx < 0 || cy < 0 || cx as usize >= self.nx() || cy as usize >= self.ny() {
            return None;
        }
        self.cells[cy as usize * self.nx() + cx as usize]
    }
}

/// The building outline (counter-clockwise) and its walls.
pub(super) fn build_walls(layout: &Layout) -> (Polygon, Vec<Polygon>) {
    let g = ZoneGrid::new(layout);
    let is_wall = |a: Option<usize>, b: Option<usize>| match (a, b) {
        (None, None) => false,
        (Some(a), Some(b)) => {
            a != b && !(layout.zones[a].is_corridor() && layout.zones[b].is_corridor())
        }
        _ => true,
    };
    let mut walls = Vec::new();
    // Horizontal lines.
    for j in 0..=g.ny() {
        let y = g.ys[j];
        let gaps = gaps_on(&layout.openings, true, y);
        let mut run: Option<usize> = None;
        for i in 0..=g.nx() {
            let wall = i < g.nx()
                && is_wall(
                    g.at(i as isize, j as isize - 1),
                    g.at(i as isize, j as isize),
                );
            match (run, wall) {
                (None, true) => run = Some(i),
                (Some(i0), false) => {
                    for (a, b) in cut(g.xs[i0], g.xs[i], &gaps) {
                        walls.push(Polygon::thick_segment(
                            Vec2::new(a, y),
                            Vec2::new(b, y),
                            WALL_THICKNESS_M,
                        ));
                    }
                    run = None;
                }
                _ => {}
            }
        }
    }
    // Vertical lines.
    for i in 0..=g.nx() {
        let x = g.xs[i];
        let gaps = gaps_on(&layout.openings, false, x);
        let mut run: Option<usize> = None;
        for j in 0..=g.ny() {
            let wall = j < g.ny()
                && is_wall(
                    g.at(i as isize - 1, j as isize),
                    g.at(i as isize, j as isize),
                );
            match (run, wall) {
                (None, true) => run = Some(j),
                (Some(j0), false) => {
                    for (a, b) in cut(g.ys[j0], g.ys[j], &gaps) {
                        walls.push(Polygon::thick_segment(
                            Vec2::new(x, a),
                            Vec2::new(x, b),
                            WALL_THICKNESS_M,
                        ));
                    }
                    run = None;
                }
                _ => {}
            }
        }
    }
    (outline(&g), walls)
}

/// Intervals of the openings lying on the line `y = c` (horizontal) or `x = c`, sorted.
fn gaps_on(openings: &[Opening], horizontal: bool, c: f64) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = openings
        .iter()
        .filter_map(|o| {
            let (pa, pb, qa, qb) = if horizontal {
                (o.a.y, o.b.y, o.a.x, o.b.x)
            } else {
                (o.a.x, o.b.x, o.a.y, o.b.y)
            };
            ((pa - c).abs() < EPS && (pb - c).abs() < EPS).then(|| (qa.min(qb), qa.max(qb)))
        })
        .collect();
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

/// The wall run `[a, b]` minus the gaps, as centre-line segments for `thick_segment`: ends at a
/// gap are pulled back by half a thickness so that the wall stops at the gap's edge.
fn cut(a: f64, b: f64, gaps: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let h = WALL_THICKNESS_M / 2.0;
    let mut out = Vec::new();
    let mut cur = a;
    let mut cur_gap = false;
    let mut push = |s: f64, s_gap: bool, e: f64, e_gap: bool| {
        let s2 = if s_gap { s + h } else { s };
        let e2 = if e_gap { e - h } else { e };
        if e2 - s2 > EPS {
            out.push((s2, e2));
        }
    };
    for &(g0, g1) in gaps {
        if g1 <= cur + EPS || g0 >= b - EPS {
            continue;
        }
        if g0 > cur + EPS {
            push(cur, cur_gap, g0, true);
        }
        cur = g1.max(cur);
        cur_gap = true;
    }
    if b > cur + EPS {
        push(cur, cur_gap, b, false);
    }
    out
}

/// Traces the boundary of the union of zones (assumed one region without holes).
fn outline(g: &ZoneGrid) -> Polygon {
    let (nx, ny) = (g.nx() as isize, g.ny() as isize);
    let inside = |x: isize, y: isize| g.at(x, y).is_some();
    // Directed boundary edges with the inside on the left, keyed by their start vertex.
    let mut next: std::collections::BTreeMap<(isize, isize), (isize, isize)> = Default::default();
    for j in 0..=ny {
        for i in 0..nx {
            let (below, above) = (inside(i, j - 1), inside(i, j));
            if above && !below {
                next.insert((i, j), (i + 1, j));
            } else if below && !above {
                next.insert((i + 1, j), (i, j));
            }
        }
    }
    for i in 0..=nx {
        for j in 0..ny {
            let (left, right) = (inside(i - 1, j), inside(i, j));
            if left && !right {
                next.insert((i, j), (i, j + 1));
            } else if right && !left {
                next.insert((i, j + 1), (i, j));
            }
        }
    }
    let Some((&first, _)) = next.iter().next() else {
        return Polygon::new(vec![]);
    };
    let mut chain = vec![first];
    let mut cur = first;
    while let Some(&n) = next.get(&cur) {
        if n == first || chain.len() > next.len() {
            break;
        }
        chain.push(n);
        cur = n;
    }
    // Keep corners only, moved out by half a wall so that the outer walls (and the entrance
    // door in them) lie inside the outline.
    let m = chain.len();
    let h = WALL_THICKNESS_M / 2.0;
    let at = |k: usize| Vec2::new(g.xs[chain[k].0 as usize], g.ys[chain[k].1 as usize]);
    let vertices = (0..m)
        .filter_map(|k| {
            let p = at((k + m - 1) % m);
            let c = at(k);
            let n = at((k + 1) % m);
            let (d1, d2) = (c - p, n - c);
            if (d1.x * d2.y - d1.y * d2.x).abs() < EPS {
                return None;
            }
            // Outward normals of a counter-clockwise boundary: the direction turned clockwise.
            let out = |d: Vec2| Vec2::new(d.y, -d.x) / d.norm();
            Some(c + (out(d1) + out(d2)) * h)
        })
        .collect();
    Polygon::new(vertices)
}
