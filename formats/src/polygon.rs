//! Whether a polygon's edges cross each other, and the repair of one whose edges cross by an
//! annotator's slip: outlines, solids and rooms are checked on the way in, as an uneven
//! figure-eight has an area and would otherwise load as two shapes.
//!
//! Only proper crossings count: two edges whose ends lie on either side of each other's line,
//! each farther from it than [`TOLERANCE_M`]. Real floor plans repeat points, trace a stretch of
//! wall twice and touch themselves at a vertex; none of that is a crossing.
//!
//! **Repair.** Real plans have slips: one corner of a room placed 0.2-0.6 m across its
//! neighbouring edge, which makes a small twisted loop. A polygon whose edges cross is split at
//! every crossing into the loops it is made of (each crossing point inserted into both edges;
//! each loop is then a simple polygon), and the loop of the largest area is kept: the others
//! (the slip's loops) are dropped. The repair is accepted when the dropped loops reach at most
//! [`MAX_REPAIR_MOVE_M`] beyond the kept polygon (the distance the slipped corner moved), hold
//! at most [`MAX_REPAIR_AREA_FRACTION`] of its area, and the polygon crosses itself at most
//! [`MAX_REPAIR_CROSSINGS`] times; it comes with a warning naming the polygon, the crossing and
//! the size of the change. Beyond that tolerance, or under `--strict`
//! ([`LoadOptions::strict`]), the file is refused, naming both edges and the crossing. A
//! polygon without crossings is never changed.

use std::collections::HashMap;
use std::path::Path;

use sim_core::{Polygon, Vec2};

use crate::error::{metres, point, Error, Warning};

/// An edge end within this distance of the other edge's line is on it (m): far below anything a
/// map shows, far above the rounding of coordinates within [`crate::limits::COORDINATE_LIMIT_M`].
pub const TOLERANCE_M: f64 = 1e-4;

/// Most work (edges entered in cells, pairs of edges tested) the checks of one file may do: a
/// file of huge polygons of long edges over one another is left partly unchecked rather than
/// keep the reader for long.
pub const FILE_BUDGET: u64 = 20_000_000;

/// Farthest the dropped loops of a repaired polygon may reach beyond the polygon kept (m): the
/// slips seen in the KTH plans reach 0.66 and 0.9 m (a corner clicked 0.2-0.6 m off, past its
/// neighbour edge).
pub const MAX_REPAIR_MOVE_M: f64 = 1.5;
/// Largest area the dropped loops of a repaired polygon may have (m²): the slips seen drop
/// 0.04 and 0.08 m².
pub const MAX_REPAIR_AREA_M2: f64 = 2.0;
/// Largest area the dropped loops of a repaired polygon may have, as a fraction of the polygon
/// kept.
pub const MAX_REPAIR_AREA_FRACTION: f64 = 0.05;
/// Most crossings a polygon may have and be repaired.
pub const MAX_REPAIR_CROSSINGS: usize = 16;

/// How strictly a file's polygons are taken.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Refuse every polygon whose edges cross, however small the slip (`--strict`); otherwise
    /// one within the tolerance is repaired with a warning.
    pub strict: bool,
}

/// Two edges of a polygon that cross: edge `i` runs from vertex `i` to the next.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    pub edges: (usize, usize),
    pub at: Vec2,
}

impl Crossing {
    /// The crossing as an error's words, with the edges' ends (`pts`: the polygon checked).
    pub fn describe(&self, pts: &[Vec2]) -> String {
        format!(
            "polygon's edges cross each other: {}; expected a simple polygon, its vertices listed in order around it",
            self.describe_short(pts)
        )
    }

    /// The crossing in words: `the edge from (..) to (..) crosses the edge from (..) to (..) at
    /// (..)`.
    pub fn describe_short(&self, pts: &[Vec2]) -> String {
        let end = |e: usize| {
            let (a, b) = (pts[e], pts[(e + 1) % pts.len()]);
            format!("from {} to {}", point(a.x, a.y), point(b.x, b.y))
        };
        format!(
            "the edge {} crosses the edge {} at {}",
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
    let mut first: Option<Crossing> = None;
    let done = visit_crossings(pts, budget, |c| {
        if first.is_none_or(|f| c.edges < f.edges) {
            first = Some(c);
        }
    });
    if done {
        first
    } else {
        None
    }
}

/// The crossings of the ring `pts`, each pair of edges once, by edges: all of them, or `limit`
/// + 1 when there are more; `None` when the work `budget` ran out first.
pub fn all_crossings(pts: &[Vec2], budget: &mut u64, limit: usize) -> Option<Vec<Crossing>> {
    let mut all: Vec<Crossing> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    let done = visit_crossings(pts, budget, |c| {
        if all.len() <= limit && seen.insert(c.edges) {
            all.push(c);
        }
    });
    all.sort_by_key(|a| a.edges);
    done.then_some(all)
}

/// Calls `found` with every crossing of the ring `pts` (a pair of edges may come more than once,
/// from each cell both cover); false when the work `budget` ran out first.
fn visit_crossings(pts: &[Vec2], budget: &mut u64, mut found: impl FnMut(Crossing)) -> bool {
    let n = pts.len();
    if n < 4 {
        return true;
    }
    if n as u64 > *budget || n > u32::MAX as usize {
        return false;
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
            return false;
        }
        *budget -= cost;
        for y in y0..=y1 {
            entries.extend((x0..=x1).map(|x| ((y * side + x) as u32, e as u32)));
        }
    }
    entries.sort_unstable();
    for cell in entries.chunk_by(|a, b| a.0 == b.0) {
        for (k, &(_, i)) in cell.iter().enumerate() {
            for &(_, j) in &cell[k + 1..] {
                if *budget == 0 {
                    return false;
                }
                *budget -= 1;
                let (i, j) = (i as usize, j as usize);
                if j == i + 1 || (i == 0 && j == n - 1) {
                    continue;
                }
                if let Some(at) =
                    proper_crossing((pts[i], pts[(i + 1) % n]), (pts[j], pts[(j + 1) % n]))
                {
                    found(Crossing { edges: (i, j), at });
                }
            }
        }
    }
    true
}

/// A polygon whose edges crossed, made simple: the loop of the largest area of those it splits
/// into at its crossings.
#[derive(Debug, Clone, PartialEq)]
pub struct Repair {
    /// The polygon kept (its vertices, with the crossing points it passes through).
    pub polygon: Vec<Vec2>,
    /// The crossings, by edges of the polygon as given.
    pub crossings: Vec<Crossing>,
    /// Area of the loops dropped (m²): the valid polygon of the same area (every loop) less
    /// the polygon kept.
    pub dropped_area_m2: f64,
    /// Area of the polygon kept (m²).
    pub kept_area_m2: f64,
    /// Farthest a point of the dropped loops lies from the polygon kept (m): how far the
    /// slipped corner moved.
    pub moved_m: f64,
}

impl Repair {
    /// Whether the repair is within the tolerance ([`MAX_REPAIR_MOVE_M`], [`MAX_REPAIR_AREA_M2`],
    /// [`MAX_REPAIR_AREA_FRACTION`], [`MAX_REPAIR_CROSSINGS`]).
    pub fn within_tolerance(&self) -> bool {
        self.moved_m <= MAX_REPAIR_MOVE_M
            && self.dropped_area_m2 <= MAX_REPAIR_AREA_M2
            && self.dropped_area_m2 <= MAX_REPAIR_AREA_FRACTION * self.kept_area_m2
            && self.crossings.len() <= MAX_REPAIR_CROSSINGS
    }

    /// The size of the change in words: `1 crossing; the loop beyond it dropped: the area
    /// changed by 0.081 m² (0.2 % of the 41.958 m² kept) and a corner moved by up to 0.9 m`.
    pub fn describe_change(&self) -> String {
        format!(
            "{} crossing{}; the loop{s} beyond {} dropped: the area changed by {} m² ({} % of the {} m² kept) and a corner moved by up to {} m",
            self.crossings.len(),
            if self.crossings.len() == 1 { "" } else { "s" },
            if self.crossings.len() == 1 { "it" } else { "them" },
            metres(self.dropped_area_m2),
            percent(self.dropped_area_m2 / self.kept_area_m2.max(f64::MIN_POSITIVE)),
            metres(self.kept_area_m2),
            metres(self.moved_m),
            s = if self.crossings.len() == 1 { "" } else { "s" },
        )
    }
}

/// Splits the ring `pts`, whose edges cross at `crossings` (all of them, as [`all_crossings`]
/// finds them), into loops at the crossings and keeps the loop of the largest area; `None` when
/// nothing is left with an area, or the work of measuring the change would exceed `budget`.
///
/// The ring is walked with every crossing point inserted into both its edges (in order along
/// each); when the walk comes back to a crossing point it passed, the stretch since is a loop,
/// cut off. Each loop passes each crossing point at most once, so that none crosses itself.
pub fn repair(pts: &[Vec2], crossings: &[Crossing], budget: &mut u64) -> Option<Repair> {
    let n = pts.len();
    // The crossings on each edge, with their position along it.
    let mut on_edge: Vec<Vec<(f64, usize)>> = vec![Vec::new(); n];
    for (c, x) in crossings.iter().enumerate() {
        for e in [x.edges.0, x.edges.1] {
            let (a, b) = (pts[e], pts[(e + 1) % n]);
            let d = b - a;
            on_edge[e].push(((x.at - a).dot(&d) / d.norm_squared(), c));
        }
    }
    // The walk: (point, the crossing it is, if one).
    let mut walk: Vec<(Vec2, Option<usize>)> = Vec::with_capacity(n + 2 * crossings.len());
    for (e, on) in on_edge.iter_mut().enumerate() {
        walk.push((pts[e], None));
        on.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        walk.extend(on.iter().map(|&(_, c)| (crossings[c].at, Some(c))));
    }
    let mut loops: Vec<Vec<Vec2>> = Vec::new();
    let mut stack: Vec<(Vec2, Option<usize>)> = Vec::with_capacity(walk.len());
    // Where each crossing passed once lies on the stack.
    let mut passed: HashMap<usize, usize> = HashMap::new();
    for node in walk {
        if let Some(c) = node.1 {
            if let Some(k) = passed.remove(&c) {
                let cut: Vec<(Vec2, Option<usize>)> = stack.drain(k + 1..).collect();
                for (_, d) in &cut {
                    if let Some(d) = d {
                        passed.remove(d);
                    }
                }
                let mut lp = vec![stack[k].0];
                lp.extend(cut.iter().map(|x| x.0));
                loops.push(lp);
                continue;
            }
            passed.insert(c, stack.len());
        }
        stack.push(node);
    }
    loops.push(stack.iter().map(|x| x.0).collect());
    let area = |l: &Vec<Vec2>| Polygon::new(l.clone()).area_m2();
    let areas: Vec<f64> = loops.iter().map(area).collect();
    let keep = (0..loops.len()).max_by(|&a, &b| areas[a].total_cmp(&areas[b]))?;
    if areas[keep] <= 0.0 {
        return None;
    }
    let kept = &loops[keep];
    let dropped: Vec<Vec2> = loops
        .iter()
        .enumerate()
        .filter(|&(k, _)| k != keep)
        .flat_map(|(_, l)| l.iter().copied())
        .collect();
    let work = (dropped.len() as u64).saturating_mul(kept.len() as u64);
    if work > *budget {
        *budget = 0;
        return None;
    }
    *budget -= work;
    let m = kept.len();
    let moved_m = dropped
        .iter()
        .map(|&p| {
            (0..m)
                .map(|e| segment_distance(p, kept[e], kept[(e + 1) % m]))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max);
    Some(Repair {
        polygon: kept.clone(),
        crossings: crossings.to_vec(),
        dropped_area_m2: areas.iter().sum::<f64>() - areas[keep],
        kept_area_m2: areas[keep],
        moved_m,
    })
}

/// A fraction as a percentage with one decimal, or two below 0.1 %: `0.2`, `0.04`.
fn percent(f: f64) -> String {
    let p = 100.0 * f;
    if p < 0.1 {
        format!("{p:.2}")
    } else {
        format!("{p:.1}")
    }
}

/// Distance from `p` to the segment `a`-`b`.
fn segment_distance(p: Vec2, a: Vec2, b: Vec2) -> f64 {
    let d = b - a;
    let len2 = d.norm_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(&d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + d * t - p).norm()
}

/// The polygons of one file, checked for crossings within the file's work budget and repaired
/// (or refused) by the file's [`LoadOptions`]; the repairs' warnings kept for the reader.
pub(crate) struct Rings {
    budget: u64,
    options: LoadOptions,
    pub warnings: Vec<Warning>,
}

impl Rings {
    pub(crate) fn new(options: LoadOptions) -> Self {
        Rings {
            budget: FILE_BUDGET,
            options,
            warnings: Vec::new(),
        }
    }

    /// The ring `pts` (the polygon at `field` of the file at `path`, called `name` in warnings)
    /// as it is when its edges do not cross; repaired, with a warning, when they cross within
    /// the tolerance; else an error naming the first crossing.
    pub(crate) fn check(
        &mut self,
        path: &Path,
        field: &str,
        name: &str,
        pts: Vec<Vec2>,
    ) -> Result<Vec<Vec2>, Error> {
        let Some(first) = first_crossing(&pts, &mut self.budget) else {
            return Ok(pts);
        };
        let refuse =
            |why: String| Error::invalid(path, field, format!("{}{why}", first.describe(&pts)));
        if self.options.strict {
            return Err(refuse(
                " (refused under --strict; without it, a slip within the tolerance of docs/limits.md is repaired with a warning)".into(),
            ));
        }
        let Some(all) = all_crossings(&pts, &mut self.budget, MAX_REPAIR_CROSSINGS) else {
            return Err(refuse(
                " (too large a polygon to repair within the file's work budget)".into(),
            ));
        };
        if all.len() > MAX_REPAIR_CROSSINGS {
            return Err(refuse(format!(
                "; not repaired: more than {MAX_REPAIR_CROSSINGS} crossings, the most a repair may have (docs/limits.md)"
            )));
        }
        let repaired = repair(&pts, &all, &mut self.budget);
        let Some(r) = repaired else {
            return Err(refuse(
                " (too large a polygon to repair within the file's work budget)".into(),
            ));
        };
        if !r.within_tolerance() {
            return Err(refuse(format!(
                "; not repaired: the repair would be too large a change ({}), beyond the tolerance of a corner moved by {} m and an area changed by {} m² or {} % (docs/limits.md)",
                r.describe_change(),
                metres(MAX_REPAIR_MOVE_M),
                metres(MAX_REPAIR_AREA_M2),
                MAX_REPAIR_AREA_FRACTION * 100.0
            )));
        }
        // The loop kept is simple; checked all the same.
        if let Some(c) = first_crossing(&r.polygon, &mut self.budget) {
            return Err(refuse(format!(
                "; the repair still crosses at {}",
                point(c.at.x, c.at.y)
            )));
        }
        self.warnings.push(Warning {
            path: path.to_path_buf(),
            field: field.to_string(),
            message: format!(
                "{name}: {}; repaired as the largest simple polygon: {} (use --strict to refuse such a polygon)",
                first.describe_short(&pts),
                r.describe_change()
            ),
        });
        Ok(r.polygon)
    }
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

    /// What a file's reader makes of a polygon.
    #[derive(Debug)]
    enum Want {
        /// Read as it is, without a warning.
        Unchanged,
        /// Repaired with a warning: (crossings, dropped m², moved m, kept m²), each to 1 %.
        Repaired(usize, f64, f64, f64),
        /// Refused, the error saying this.
        Refused(&'static str),
    }

    /// (polygon, strict, what comes of it)
    #[test]
    fn slips_are_repaired_and_large_crossings_refused() {
        // virginia_cross_updated (KTH data set): a room whose last point overshoots the first
        // edge by 5 px at 0.18 m/px.
        let virginia: Vec<[f64; 2]> = [
            [454.0, 406.0],
            [454.0, 444.0],
            [489.0, 444.0],
            [489.0, 407.0],
            [481.0, 407.0],
            [449.0, 407.0],
        ]
        .iter()
        .map(|p| [p[0] * 0.18, p[1] * 0.18])
        .collect();
        // A corner's two clicks swapped: (0, 4.6) and (0.4, 5) in the wrong order.
        let swapped: &[[f64; 2]] = &[[0.0, 0.0], [6.0, 0.0], [6.0, 5.0], [0.0, 4.6], [0.4, 5.0]];
        // The same at two corners.
        let two: &[[f64; 2]] = &[
            [0.4, 0.0],
            [0.0, 0.4],
            [6.0, 0.0],
            [6.0, 5.0],
            [0.0, 4.6],
            [0.4, 5.0],
        ];
        let zigzag: Vec<[f64; 2]> = (0..40)
            .map(|k| [k as f64, if k % 2 == 0 { 0.0 } else { 1.0 }])
            .chain(
                (0..40)
                    .rev()
                    .map(|k| [k as f64 + 0.5, if k % 2 == 0 { 1.2 } else { -0.2 }]),
            )
            .collect();
        type Case<'a> = (&'a str, &'a [[f64; 2]], bool, Want);
        let cases: &[Case] = &[
            (
                "a room",
                &[[0.0, 0.0], [6.0, 0.0], [6.0, 5.0], [0.0, 5.0]],
                false,
                Want::Unchanged,
            ),
            (
                "a room, strict",
                &[[0.0, 0.0], [6.0, 0.0], [6.0, 5.0], [0.0, 5.0]],
                true,
                Want::Unchanged,
            ),
            (
                "virginia's slip",
                &virginia,
                false,
                Want::Repaired(1, 2.5 * 0.0324, 0.9, 35.0 * 37.0 * 0.0324),
            ),
            (
                "virginia's slip, strict",
                &virginia,
                true,
                Want::Refused("under --strict"),
            ),
            (
                "a corner's clicks swapped",
                swapped,
                false,
                Want::Repaired(1, 0.0, 0.0, 0.0),
            ),
            (
                "two corners' clicks swapped",
                two,
                false,
                Want::Repaired(2, 0.0, 0.0, 0.0),
            ),
            (
                "a large uneven figure-eight",
                &[[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 4.0]],
                false,
                Want::Refused("not repaired: the repair would be too large a change"),
            ),
            (
                "a corner 3 m past its neighbour edge",
                &[[0.0, 0.0], [6.0, 0.0], [6.0, 5.0], [0.0, 4.0], [3.0, 8.0]],
                false,
                Want::Refused("beyond the tolerance"),
            ),
            (
                "a zigzag crossing itself many times",
                &zigzag,
                false,
                Want::Refused("more than 16 crossings"),
            ),
        ];
        for (name, pts, strict, want) in cases {
            let ring: Vec<Vec2> = pts.iter().map(|p| Vec2::new(p[0], p[1])).collect();
            assert_outcome(name, ring, *strict, want);
        }
    }

    /// What a file's reader makes of the polygon `ring` is `want`.
    fn assert_outcome(name: &str, ring: Vec<Vec2>, strict: bool, want: &Want) {
        let mut rings = Rings::new(LoadOptions { strict });
        let got = rings.check(
            Path::new("f.xml"),
            "space[3] (a)",
            "the 'room' (type R)",
            ring.clone(),
        );
        match want {
            Want::Unchanged => {
                assert_eq!(got.unwrap(), ring, "{name}");
                assert!(rings.warnings.is_empty(), "{name}");
            }
            Want::Refused(words) => {
                let e = got.unwrap_err().to_string();
                assert!(
                    e.starts_with(
                        "f.xml: space[3] (a): polygon's edges cross each other: the edge from ("
                    ),
                    "{name}: {e}"
                );
                assert!(e.contains(words), "{name}: {e}");
                assert!(!e.contains('\n'), "{name}: {e}");
                assert!(rings.warnings.is_empty(), "{name}");
            }
            Want::Repaired(n, dropped, moved, kept) => {
                let poly = got.unwrap_or_else(|e| panic!("{name}: {e}"));
                let r = repair(
                    &ring,
                    &all_crossings(&ring, &mut { FILE_BUDGET }, 99).unwrap(),
                    &mut { FILE_BUDGET },
                )
                .unwrap();
                assert_eq!(poly, r.polygon, "{name}");
                assert_eq!(r.crossings.len(), *n, "{name}");
                // The polygon kept is simple, has the crossing points, and lost only the
                // dropped loops: every loop's area is the original's parts.
                assert_eq!(first_crossing(&poly, &mut { FILE_BUDGET }), None, "{name}");
                for c in &r.crossings {
                    assert!(poly.contains(&c.at), "{name}");
                }
                let area = Polygon::new(poly.clone()).area_m2();
                assert!((area - r.kept_area_m2).abs() < 1e-9, "{name}");
                assert!(r.within_tolerance(), "{name}");
                assert!(r.dropped_area_m2 > 0.0 && r.moved_m > 0.0, "{name}");
                let near = |a: f64, b: f64| (a - b).abs() <= 0.01 * b;
                if *dropped > 0.0 {
                    assert!(near(r.dropped_area_m2, *dropped), "{name}: {r:?}");
                    assert!(near(r.moved_m, *moved), "{name}: {r:?}");
                    assert!(near(r.kept_area_m2, *kept), "{name}: {r:?}");
                }
                assert_eq!(rings.warnings.len(), 1, "{name}");
                let w = rings.warnings[0].to_string();
                assert!(
                    w.starts_with("f.xml: space[3] (a): the 'room' (type R): the edge from ("),
                    "{name}: {w}"
                );
                assert!(
                    w.contains("; repaired as the largest simple polygon: "),
                    "{name}: {w}"
                );
                assert!(
                    w.contains(&format!(
                        "the area changed by {} m²",
                        metres(r.dropped_area_m2)
                    )),
                    "{name}: {w}"
                );
                assert!(
                    w.contains(&format!("a corner moved by up to {} m", metres(r.moved_m))),
                    "{name}: {w}"
                );
            }
        }
    }

    /// Splitting at the crossings keeps all of the area: the loops' areas add up to the area of
    /// the points inside the polygon by the even-odd rule, sampled.
    #[test]
    fn the_loops_hold_the_whole_area() {
        let ring: Vec<Vec2> = [[0.0, 0.0], [6.0, 0.0], [6.0, 5.0], [0.0, 4.6], [0.4, 5.0]]
            .iter()
            .map(|p| Vec2::new(p[0], p[1]))
            .collect();
        let all = all_crossings(&ring, &mut { FILE_BUDGET }, 99).unwrap();
        let r = repair(&ring, &all, &mut { FILE_BUDGET }).unwrap();
        let (n, step) = (1200, 0.005);
        let odd = Polygon::new(ring.clone());
        let inside = (0..n * n)
            .filter(|k| {
                odd.contains(Vec2::new(
                    (k % n) as f64 * step + 0.0025,
                    (k / n) as f64 * step + 0.0025,
                ))
            })
            .count() as f64
            * step
            * step;
        let total = r.kept_area_m2 + r.dropped_area_m2;
        assert!((inside - total).abs() < 0.02, "{inside} vs {total}");
    }
}
