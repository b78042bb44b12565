//! The arrangement of the wall lines inside the bounding box of the known map.
//!
//! Lines of one direction cut the plane into slabs; a face is the intersection of one slab per
//! direction, so it is convex, and a cell's face is found from its slab index in each direction
//! (incrementally along a row: no point location, no polygon clipping per cell). Face polygons
//! come from clipping the box by the face's slabs. Every vertex is the intersection of a pair of
//! lines, computed once from that pair, so neighbouring faces share bit-identical vertices and
//! their common edges are found by key.

use std::hash::{BuildHasherDefault, Hasher};

/// Faces by key, looked up only, never iterated, so its order cannot reach a result (the
/// kernel's clippy configuration forbids hash maps elsewhere).
#[allow(clippy::disallowed_types)]
type FaceIndex = std::collections::HashMap<u64, u32, BuildHasherDefault<KeyHasher>>;

use super::morphology::WindowMask;
use super::{LayoutDiagnostics, WallLine};
use crate::geom::Vec2;
use crate::grid::{Cell, Occupancy, OccupancyGrid};

pub(crate) const NO_FACE: u32 = u32::MAX;
/// The first four lines are the sides of the box: bottom, right, top, left.
pub(crate) const BORDER_LINES: u32 = 4;

/// A line `n . p = c` of the arrangement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArrLine {
    pub n: Vec2,
    pub c: f64,
    /// Normalised support (0 for the box sides).
    pub weight: f64,
}

/// A convex face with its cell statistics.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Face {
    /// Counter-clockwise vertices.
    pub vertices: Vec<Vec2>,
    /// Vertex keys (the pair of lines meeting there), parallel to `vertices`.
    pub keys: Vec<u64>,
    /// `tags[i]`: the line carrying the edge from vertex `i` to vertex `i + 1`.
    pub tags: Vec<u32>,
    /// `edges[i]`: index in [`Arrangement::edges`] of that edge.
    pub edges: Vec<u32>,
    pub area_m2: f64,
    pub cells: u32,
    pub free: u32,
    pub occupied: u32,
    pub unknown: u32,
}

/// An edge of the arrangement between one or two faces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Edge {
    pub a: Vec2,
    pub b: Vec2,
    pub tag: u32,
    /// The faces on both sides; `NO_FACE` when there is none (box side or an empty sliver).
    pub faces: [u32; 2],
    /// Fraction of the edge near wall evidence (1 for edges with a single face).
    pub wall_fraction: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Arrangement {
    pub lines: Vec<ArrLine>,
    pub faces: Vec<Face>,
    pub edges: Vec<Edge>,
    /// The face of every cell of the box, as runs of cells along rows.
    labels: FaceRuns,
}

/// The faces of the cells of a box of the grid, as runs along its rows (a face is convex, so a
/// row crosses it once; a few runs per row label millions of cells).
#[derive(Debug, Clone, PartialEq)]
struct FaceRuns {
    /// Grid width, and the box's first and last cells.
    width: usize,
    c0: Cell,
    c1: Cell,
    /// Per row of the box, where its runs start in `runs` (one more entry than rows).
    row_start: Vec<u32>,
    /// (first cell's x, face), rows in order, each row's runs by x.
    runs: Vec<(i32, u32)>,
}

impl FaceRuns {
    fn face_of(&self, i: usize) -> u32 {
        if self.width == 0 {
            return NO_FACE;
        }
        let (x, y) = ((i % self.width) as i32, (i / self.width) as i32);
        if x < self.c0.x || x > self.c1.x || y < self.c0.y || y > self.c1.y {
            return NO_FACE;
        }
        let r = (y - self.c0.y) as usize;
        let row = &self.runs[self.row_start[r] as usize..self.row_start[r + 1] as usize];
        // The last run starting at or before x (every row's first run starts at the box's edge).
        let k = row.partition_point(|run| run.0 <= x);
        row[k - 1].1
    }
}

impl Arrangement {
    /// The face of the grid cell of index `i` (row-major), `NO_FACE` outside the box.
    pub(crate) fn face_of(&self, i: usize) -> u32 {
        self.labels.face_of(i)
    }

    pub(crate) fn is_border(&self, tag: u32) -> bool {
        tag < BORDER_LINES
    }
    /// The face across edge `e` from face `f`.
    pub(crate) fn other_face(&self, e: u32, f: u32) -> u32 {
        let faces = self.edges[e as usize].faces;
        if faces[0] == f {
            faces[1]
        } else {
            faces[0]
        }
    }
}

/// A multiplicative hash for the face keys (looked up once per run of cells; the map is never
/// iterated, so its order does not matter).
#[derive(Default)]
struct KeyHasher(u64);

impl Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.write_u64(*b as u64);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }
}

fn key(a: u32, b: u32) -> u64 {
    let (a, b) = if a < b { (a, b) } else { (b, a) };
    ((a as u64) << 32) | b as u64
}

/// Intersection of the two lines of a vertex key (always computed in the same order).
fn vertex(lines: &[ArrLine], k: u64) -> Vec2 {
    let a = lines[(k >> 32) as usize];
    let b = lines[(k & 0xffff_ffff) as usize];
    let det = a.n.x * b.n.y - a.n.y * b.n.x;
    if det.abs() < 1e-12 {
        // Parallel lines never make a vertex of a face; keep something finite.
        return a.n * a.c;
    }
    Vec2::new(
        (a.c * b.n.y - a.n.y * b.c) / det,
        (a.n.x * b.c - a.c * b.n.x) / det,
    )
}

/// Clips a convex polygon (keys, outgoing tags) to the half-plane `sign * (n . p - c) <= 0`.
fn clip(lines: &[ArrLine], poly: &[(u64, u32)], tag: u32, sign: f64) -> Vec<(u64, u32)> {
    let l = lines[tag as usize];
    let s: Vec<f64> = poly
        .iter()
        .map(|(k, _)| sign * (l.n.dot(&vertex(lines, *k)) - l.c))
        .collect();
    let mut out = Vec::with_capacity(poly.len() + 1);
    let n = poly.len();
    const EPS: f64 = 1e-9;
    for i in 0..n {
        let j = (i + 1) % n;
        let (cur, t) = poly[i];
        let cin = s[i] <= EPS;
        let nin = s[j] <= EPS;
        if cin {
            out.push((cur, t));
        }
        if cin && !nin && s[i] < -EPS {
            out.push((key(t, tag), tag));
        } else if cin && !nin {
            // The current vertex lies on the line: the edge leaving it runs along the line.
            if let Some(last) = out.last_mut() {
                last.1 = tag;
            }
        } else if !cin && nin && s[j] < -EPS {
            out.push((key(t, tag), t));
        }
    }
    out
}

/// Builds the arrangement of `lines` in the inclusive cell box `bbox`, labels the cells of
/// `grid`, and measures the wall evidence (`near_wall`, plus the door gaps of each line in
/// `doors`) along every edge.
#[allow(clippy::too_many_arguments)]
pub fn build(
    grid: &OccupancyGrid,
    bbox: (Cell, Cell),
    wall_lines: &[WallLine],
    doors: &[Vec<(f64, f64)>],
    near_wall: &WindowMask,
    margin_m: f64,
    trim_m: f64,
    diag: &mut LayoutDiagnostics,
) -> Arrangement {
    let gb = grown_box(grid, bbox, margin_m);
    let (lines, mut families, line_doors) = collect_lines(wall_lines, doors, gb.min, gb.max);
    let strides = face_strides(&mut families);
    let (labels, mut faces, face_keys) = label_cells(grid, gb.c0, gb.c1, &families, &strides);
    face_polygons(&mut faces, &face_keys, &families, &strides, &lines);
    let edges = shared_edges(&mut faces, &lines, &line_doors, near_wall, trim_m, diag);
    diag.faces = faces.len();
    diag.edges = edges.len();
    Arrangement {
        lines,
        faces,
        edges,
        labels,
    }
}

/// Line families: (normal, sorted (offset, tag)).
type Families = Vec<(Vec2, Vec<(f64, u32)>)>;

/// The door gaps of each arrangement line.
type LineDoors<'a> = Vec<&'a [(f64, f64)]>;

/// The box of the known cells grown by the margin, in metres (`min`, `max`) and in cells
/// (`c0`, `c1`, clamped to the grid).
struct GrownBox {
    min: Vec2,
    max: Vec2,
    c0: Cell,
    c1: Cell,
}

/// The box `bbox` grown by `margin_m`, in metres and clamped to the grid in cells.
fn grown_box(grid: &OccupancyGrid, bbox: (Cell, Cell), margin_m: f64) -> GrownBox {
    let f = grid.frame;
    let res = f.resolution_m;
    // The box of the known cells grown by `margin_m`, so that lines on the outermost walls cut
    // it; cells are labelled where the grown box meets the grid.
    let (k0, k1) = bbox;
    let min =
        f.origin_m + Vec2::new(k0.x as f64, k0.y as f64) * res - Vec2::new(margin_m, margin_m);
    let max = f.origin_m
        + Vec2::new(k1.x as f64 + 1.0, k1.y as f64 + 1.0) * res
        + Vec2::new(margin_m, margin_m);
    let m = (margin_m / res).floor() as i32;
    let c0 = Cell::new((k0.x - m).max(0), (k0.y - m).max(0));
    let c1 = Cell::new(
        (k1.x + m).min(f.width as i32 - 1),
        (k1.y + m).min(f.height as i32 - 1),
    );
    GrownBox { min, max, c0, c1 }
}

/// The arrangement's lines (the four box sides, then the wall lines that cut the box), their
/// families (sorted by offset) and the door gaps of each line.
fn collect_lines<'a>(
    wall_lines: &[WallLine],
    doors: &'a [Vec<(f64, f64)>],
    min: Vec2,
    max: Vec2,
) -> (Vec<ArrLine>, Families, LineDoors<'a>) {
    let mut lines = vec![
        ArrLine {
            n: Vec2::new(0.0, 1.0),
            c: min.y,
            weight: 0.0,
        },
        ArrLine {
            n: Vec2::new(1.0, 0.0),
            c: max.x,
            weight: 0.0,
        },
        ArrLine {
            n: Vec2::new(0.0, 1.0),
            c: max.y,
            weight: 0.0,
        },
        ArrLine {
            n: Vec2::new(1.0, 0.0),
            c: min.x,
            weight: 0.0,
        },
    ];
    // Families: (normal, sorted (offset, tag)).
    let mut families: Families = Vec::new();
    let corners = [min, Vec2::new(max.x, min.y), max, Vec2::new(min.x, max.y)];
    // Door gaps per arrangement line.
    let mut line_doors: Vec<&[(f64, f64)]> = vec![&[]; 4];
    for (li, wl) in wall_lines.iter().enumerate() {
        let n = wl.normal();
        let (lo, hi) = corners
            .iter()
            .map(|p| n.dot(p))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                (l.min(v), h.max(v))
            });
        if wl.offset_m <= lo + 1e-9 || wl.offset_m >= hi - 1e-9 {
            continue;
        }
        let tag = lines.len() as u32;
        line_doors.push(doors.get(li).map_or(&[], |d| d.as_slice()));
        lines.push(ArrLine {
            n,
            c: wl.offset_m,
            weight: wl.weight,
        });
        let fam = wl.family as usize;
        while families.len() <= fam {
            families.push((n, Vec::new()));
        }
        families[fam].0 = n;
        families[fam].1.push((wl.offset_m, tag));
    }
    families.retain(|(_, v)| !v.is_empty());
    for (_, v) in &mut families {
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    (lines, families, line_doors)
}

/// The strides of the mixed-radix face keys (one digit per family: its slab index); families
/// that would overflow are dropped.
fn face_strides(families: &mut Families) -> Vec<u64> {
    // Mixed-radix face keys; families that would overflow are dropped.
    let mut strides = Vec::new();
    let mut total: u64 = 1;
    let mut kept = 0;
    for (_, v) in families.iter() {
        match total.checked_mul(v.len() as u64 + 1) {
            Some(t) if t < (1u64 << 62) => {
                strides.push(total);
                total = t;
                kept += 1;
            }
            _ => break,
        }
    }
    families.truncate(kept);
    strides
}

/// Labels the cells of the box `c0`..=`c1` with their faces (as runs along rows), creating the
/// faces (with their cell counts) and their keys in the order the cells meet them.
fn label_cells(
    grid: &OccupancyGrid,
    c0: Cell,
    c1: Cell,
    families: &Families,
    strides: &[u64],
) -> (FaceRuns, Vec<Face>, Vec<u64>) {
    let f = grid.frame;
    let res = f.resolution_m;
    // Label cells.
    let w = f.width as usize;
    let mut labels = FaceRuns {
        width: w,
        c0,
        c1,
        row_start: Vec::with_capacity((c1.y - c0.y + 2).max(0) as usize),
        runs: Vec::new(),
    };
    let mut faces: Vec<Face> = Vec::new();
    let mut face_keys: Vec<u64> = Vec::new();
    let mut index: FaceIndex = FaceIndex::default();
    let offsets: Vec<Vec<f64>> = families
        .iter()
        .map(|(_, v)| v.iter().map(|(o, _)| *o).collect())
        .collect();
    let mut idx = vec![0usize; families.len()];
    // Per row, the cells where a slab index changes; between them the face is constant.
    let mut events: Vec<(i32, usize, i32)> = Vec::new();
    let x_of = |i: f64| (i - f.origin_m.x) / res - 0.5;
    for y in c0.y..=c1.y {
        labels.row_start.push(labels.runs.len() as u32);
        let yc = f.origin_m.y + (y as f64 + 0.5) * res;
        let xc0 = f.origin_m.x + (c0.x as f64 + 0.5) * res;
        events.clear();
        for (k, (n, _)) in families.iter().enumerate() {
            let v0 = n.x * xc0 + n.y * yc;
            idx[k] = offsets[k].partition_point(|o| *o < v0);
            if n.x.abs() < 1e-12 {
                continue;
            }
            for &o in &offsets[k] {
                // Cell centres with n . p > o are past the line.
                let xl = x_of((o - n.y * yc) / n.x);
                let (cell, delta) = if n.x > 0.0 {
                    (xl.floor() as i64 + 1, 1)
                } else {
                    (xl.ceil() as i64, -1)
                };
                if cell > c0.x as i64 && cell <= c1.x as i64 {
                    events.push((cell as i32, k, delta));
                }
            }
        }
        events.sort_unstable();
        let mut ev = 0;
        let mut x = c0.x;
        while x <= c1.x {
            while ev < events.len() && events[ev].0 <= x {
                let (_, k, d) = events[ev];
                idx[k] = (idx[k] as i64 + d as i64).clamp(0, offsets[k].len() as i64) as usize;
                ev += 1;
            }
            let end = if ev < events.len() {
                events[ev].0
            } else {
                c1.x + 1
            };
            let fk: u64 = idx.iter().zip(strides).map(|(i, s)| *i as u64 * s).sum();
            let id = *index.entry(fk).or_insert_with(|| {
                faces.push(Face::default());
                face_keys.push(fk);
                (faces.len() - 1) as u32
            });
            let row = y as usize * w;
            let (a, b) = (row + x as usize, row + end as usize);
            labels.runs.push((x, id));
            let (free, occ) = count_free_occupied(&grid.data[a..b]);
            let unk = (b - a) as u32 - free - occ;
            let face = &mut faces[id as usize];
            face.cells += (b - a) as u32;
            face.free += free;
            face.occupied += occ;
            face.unknown += unk;
            x = end;
        }
    }

    labels.row_start.push(labels.runs.len() as u32);
    (labels, faces, face_keys)
}

/// Sets every face's polygon: the box clipped by the face's slab in each family.
fn face_polygons(
    faces: &mut [Face],
    face_keys: &[u64],
    families: &Families,
    strides: &[u64],
    lines: &[ArrLine],
) {
    // Face polygons.
    for (face, fk) in faces.iter_mut().zip(face_keys) {
        let mut poly: Vec<(u64, u32)> = vec![
            (key(3, 0), 0),
            (key(0, 1), 1),
            (key(1, 2), 2),
            (key(2, 3), 3),
        ];
        for (k, (_, fam)) in families.iter().enumerate() {
            let i = ((fk / strides[k]) % (fam.len() as u64 + 1)) as usize;
            if i > 0 {
                poly = clip(lines, &poly, fam[i - 1].1, -1.0);
            }
            if i < fam.len() {
                poly = clip(lines, &poly, fam[i].1, 1.0);
            }
        }
        // Drop repeated vertices (lines meeting at one point).
        poly.dedup_by(|b, a| a.0 == b.0);
        while poly.len() > 1 && poly[0].0 == poly[poly.len() - 1].0 {
            poly.pop();
        }
        if poly.len() < 3 {
            continue;
        }
        face.vertices = poly.iter().map(|(k, _)| vertex(lines, *k)).collect();
        face.keys = poly.iter().map(|(k, _)| *k).collect();
        face.tags = poly.iter().map(|(_, t)| *t).collect();
        face.area_m2 = crate::geom::Polygon::new(face.vertices.clone()).area_m2();
    }
}

/// The edges, shared by key between the faces on both sides (each face's `edges` set), with
/// the wall evidence along each.
fn shared_edges(
    faces: &mut [Face],
    lines: &[ArrLine],
    line_doors: &[&[(f64, f64)]],
    near_wall: &WindowMask,
    trim_m: f64,
    diag: &mut LayoutDiagnostics,
) -> Vec<Edge> {
    // Edges shared by key.
    let mut all: Vec<(u64, u64, u32, u32, u32)> = Vec::new();
    for (fi, face) in faces.iter().enumerate() {
        let n = face.keys.len();
        for i in 0..n {
            let (a, b) = (face.keys[i], face.keys[(i + 1) % n]);
            let (a, b) = if a < b { (a, b) } else { (b, a) };
            all.push((a, b, face.tags[i], fi as u32, i as u32));
        }
    }
    all.sort_unstable();
    let mut edges: Vec<Edge> = Vec::new();
    let mut i = 0;
    while i < all.len() {
        let mut j = i + 1;
        while j < all.len() && (all[j].0, all[j].1, all[j].2) == (all[i].0, all[i].1, all[i].2) {
            j += 1;
        }
        let (_, _, tag, f0, l0) = all[i];
        let face0 = &faces[f0 as usize];
        let n0 = face0.vertices.len();
        let a = face0.vertices[l0 as usize];
        let b = face0.vertices[(l0 as usize + 1) % n0];
        let f1 = if j > i + 1 { all[i + 1].3 } else { NO_FACE };
        let id = edges.len() as u32;
        for item in &all[i..j] {
            let face = &mut faces[item.3 as usize];
            let n = face.keys.len();
            face.edges.resize(n, 0);
            face.edges[item.4 as usize] = id;
        }
        let wall_fraction = if f1 == NO_FACE {
            1.0
        } else {
            wall_coverage(
                near_wall,
                a,
                b,
                lines[tag as usize].n,
                line_doors[tag as usize],
                trim_m,
                diag,
            )
        };
        edges.push(Edge {
            a,
            b,
            tag,
            faces: [f0, f1],
            wall_fraction,
        });
        i = j;
    }
    edges
}

/// The free and the occupied cells of `cells`: two branch-free counts per block of cells short
/// enough for byte counters, which the compiler vectorises 16 cells at a time.
fn count_free_occupied(cells: &[Occupancy]) -> (u32, u32) {
    let count = |block: &[Occupancy], state: Occupancy| {
        block.iter().fold(0u8, |n, s| n + (*s == state) as u8) as u32
    };
    cells.chunks(255).fold((0, 0), |(free, occ), block| {
        (
            free + count(block, Occupancy::Free),
            occ + count(block, Occupancy::Occupied),
        )
    })
}

/// Fraction of samples (one per cell length) along `a`-`b` (on the line of normal `n`) that fall
/// on `near_wall` cells or in one of the line's door gaps.
fn wall_coverage(
    near_wall: &WindowMask,
    a: Vec2,
    b: Vec2,
    n: Vec2,
    doors: &[(f64, f64)],
    trim_m: f64,
    diag: &mut LayoutDiagnostics,
) -> f64 {
    let f = near_wall.frame;
    let len = (b - a).norm();
    // The ends of an edge touch the walls it runs between: they are not evidence of a wall
    // along it.
    let trim = (trim_m / len).min(0.5);
    let (a, b) = (a + (b - a) * trim, b - (b - a) * trim);
    let len = (b - a).norm();
    let u = Vec2::new(n.y, -n.x);
    let n = ((len / f.resolution_m).ceil() as usize).max(1);
    let mut hits = 0;
    for k in 0..n {
        let p = a + (b - a) * ((k as f64 + 0.5) / n as f64);
        let t = u.dot(&p);
        if near_wall.get(f.cell_from_world(p)) || doors.iter().any(|d| d.0 <= t && t <= d.1) {
            hits += 1;
        }
    }
    diag.edge_samples += n;
    hits as f64 / n as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Segment;

    fn line(direction_rad: f64, offset_m: f64, family: u32) -> WallLine {
        WallLine {
            direction_rad,
            offset_m,
            weight: 1.0,
            support_m: 1.0,
            extent: Segment::new(Vec2::zeros(), Vec2::zeros()),
            family,
        }
    }

    #[test]
    fn grid_of_lines_gives_rectangles_sharing_edges() {
        // 10 x 10 cells of 1 m; a vertical line at x = 4 (direction pi/2: normal (-1, 0), offset
        // -4) and a horizontal one at y = 6.
        let g = OccupancyGrid::from_ascii(&"..........\n".repeat(10), 1.0);
        let lines = [
            line(std::f64::consts::FRAC_PI_2, -4.0, 0),
            line(0.0, 6.0, 1),
        ];
        let near = WindowMask::empty(g.frame);
        let arr = build(
            &g,
            (Cell::new(0, 0), Cell::new(9, 9)),
            &lines,
            &[],
            &near,
            0.0,
            0.0,
            &mut LayoutDiagnostics::default(),
        );
        assert_eq!(arr.faces.len(), 4);
        let mut areas: Vec<f64> = arr.faces.iter().map(|f| f.area_m2).collect();
        areas.sort_by(f64::total_cmp);
        assert_eq!(areas, vec![16.0, 24.0, 24.0, 36.0]);
        for face in &arr.faces {
            assert_eq!(face.cells as f64, face.area_m2);
        }
        // 4 inner half-edges shared, 8 box edges.
        let shared = arr.edges.iter().filter(|e| e.faces[1] != NO_FACE).count();
        assert_eq!(shared, 4);
        assert_eq!(arr.edges.len(), 12);
        assert!(arr
            .edges
            .iter()
            .all(|e| e.faces[1] == NO_FACE || e.wall_fraction == 0.0));
    }

    #[test]
    fn diagonal_line_cuts_the_box_in_two() {
        let g = OccupancyGrid::from_ascii(&"..........\n".repeat(10), 1.0);
        // The diagonal y = x: direction pi/4, normal (-s, s), offset 0.
        let lines = [line(std::f64::consts::FRAC_PI_4, 0.0, 0)];
        let near = WindowMask::empty(g.frame);
        let arr = build(
            &g,
            (Cell::new(0, 0), Cell::new(9, 9)),
            &lines,
            &[],
            &near,
            0.0,
            0.0,
            &mut LayoutDiagnostics::default(),
        );
        assert_eq!(arr.faces.len(), 2);
        for face in &arr.faces {
            assert!((face.area_m2 - 50.0).abs() < 1e-9);
            assert_eq!(face.vertices.len(), 3);
        }
    }
}
