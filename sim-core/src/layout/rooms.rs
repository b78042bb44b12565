//! Rooms of the observed part: faces are classified from the grid, inside faces are merged across
//! edges without wall evidence, and frontiers (free cells next to unknown ones) mark the rooms
//! that are only partly observed. Room polygons are unions of faces.

use std::collections::BTreeMap;

use super::arrangement::{Arrangement, NO_FACE};
use super::{LayoutConfig, LayoutDiagnostics, LayoutRoom, RoomLabel};
use crate::geom::{Polygon, Vec2};
use crate::grid::{Cell, OccupancyGrid};

pub(crate) const NO_ROOM: u32 = u32::MAX;

/// A room as a set of faces.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct PlanRoom {
    /// Faces seen as inside.
    pub faces: Vec<u32>,
    /// Faces added by prediction.
    pub predicted: Vec<u32>,
    /// Whether the room holds a good part of a frontier.
    pub partial: bool,
}

/// Rooms as sets of faces, with the owner of every face.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct RoomPlan {
    pub rooms: Vec<PlanRoom>,
    pub face_room: Vec<u32>,
    /// Face can be predicted into: not in a room, mostly unknown.
    pub candidate: Vec<bool>,
}

fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let p = parent[parent[x as usize] as usize];
        parent[x as usize] = p;
        x = p;
    }
    x
}

/// Frontier cells of `grid` grouped in 8-connected clusters of at least `min_cells` cells (grid
/// indices, sorted per cluster). Only the box of the known cells is scanned.
pub fn frontier_clusters(grid: &OccupancyGrid, min_cells: usize) -> Vec<Vec<usize>> {
    frontier_clusters_in(grid, super::evidence::known_box(grid).0, min_cells)
}

/// [`frontier_clusters`] with the box of the known cells of `grid` given (from
/// [`known_box`](super::evidence::known_box)).
pub(crate) fn frontier_clusters_in(
    grid: &OccupancyGrid,
    known_box: Option<(Cell, Cell)>,
    min_cells: usize,
) -> Vec<Vec<usize>> {
    let f = grid.frame;
    let w = f.width as usize;
    let Some((b0, b1)) = known_box else {
        return Vec::new();
    };
    let (x0, y0) = (b0.x as usize, b0.y as usize);
    let (bw, bh) = ((b1.x - b0.x + 1) as usize, (b1.y - b0.y + 1) as usize);
    // Frontier flags in box coordinates.
    let mut is_frontier = vec![false; bw * bh];
    for (by, row) in is_frontier.chunks_exact_mut(bw).enumerate() {
        crate::frontier::detect::frontier_row(grid, y0 + by, x0, x0 + bw - 1, row);
    }
    let mut clusters = Vec::new();
    let mut stack = Vec::new();
    // The frontier cells in order (blocks without one, most of the box, are passed over whole).
    const BLOCK: usize = 64;
    let flagged: Vec<usize> = is_frontier
        .chunks(BLOCK)
        .enumerate()
        .filter(|(_, block)| block.iter().fold(false, |a, f| a | f))
        .flat_map(|(b, block)| {
            (0..block.len())
                .filter(|k| block[*k])
                .map(move |k| b * BLOCK + k)
        })
        .collect();
    for start in flagged {
        if !is_frontier[start] {
            continue;
        }
        is_frontier[start] = false;
        stack.push(start);
        let mut cluster = Vec::new();
        while let Some(i) = stack.pop() {
            let (bx, by) = ((i % bw) as isize, (i / bw) as isize);
            cluster.push((y0 + by as usize) * w + x0 + bx as usize);
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (nx, ny) = (bx + dx, by + dy);
                    if nx < 0 || ny < 0 || nx >= bw as isize || ny >= bh as isize {
                        continue;
                    }
                    let j = ny as usize * bw + nx as usize;
                    if is_frontier[j] {
                        is_frontier[j] = false;
                        stack.push(j);
                    }
                }
            }
        }
        if cluster.len() >= min_cells {
            cluster.sort_unstable();
            clusters.push(cluster);
        }
    }
    clusters
}

/// Groups the inside faces into rooms and marks the partial ones.
pub(crate) fn group_rooms(
    grid: &OccupancyGrid,
    known_box: Option<(Cell, Cell)>,
    arr: &Arrangement,
    config: &LayoutConfig,
    diag: &mut LayoutDiagnostics,
) -> RoomPlan {
    let res = grid.frame.resolution_m;
    let nf = arr.faces.len();
    let min_cells = ((config.min_frontier_length_m / res).round() as usize).max(1);
    let clusters = frontier_clusters_in(grid, known_box, min_cells);
    diag.frontier_clusters = clusters.len();
    diag.frontier_cells = clusters.iter().map(|c| c.len()).sum();
    let mut face_frontier = vec![0u32; nf];
    for c in &clusters {
        for &i in c {
            let fi = arr.face_of(i);
            if fi != NO_FACE {
                face_frontier[fi as usize] += 1;
            }
        }
    }
    let cell_m2 = res * res;
    let inside: Vec<bool> = arr
        .faces
        .iter()
        .zip(&face_frontier)
        .map(|(f, &fr)| {
            !f.vertices.is_empty()
                && f.cells > 0
                && (f.unknown as f64) < config.min_unknown_fraction_candidate * f.cells as f64
                && (f.free as f64 >= config.min_free_fraction * f.cells as f64
                    || (fr as usize >= min_cells && f.free as f64 * cell_m2 >= 0.25))
        })
        .collect();
    diag.inside_faces = inside.iter().filter(|b| **b).count();
    let (mut rooms, face_room) = join_inside_faces(arr, &inside, config, diag);
    // Partial rooms: holding at least a fraction of a frontier cluster.
    let mut counts: BTreeMap<u32, usize> = BTreeMap::new();
    for c in &clusters {
        counts.clear();
        for &i in c {
            let fi = arr.face_of(i);
            if fi != NO_FACE && face_room[fi as usize] != NO_ROOM {
                *counts.entry(face_room[fi as usize]).or_default() += 1;
            }
        }
        for (&r, &n) in &counts {
            if n as f64 >= config.partial_room_frontier_fraction * c.len() as f64 {
                rooms[r as usize].partial = true;
            }
        }
    }
    // ... or holding a frontier's worth of frontier cells in all, however they are split among
    // clusters (a long cluster running along several faces may leave under the fraction in each).
    let mut room_frontier = vec![0usize; rooms.len()];
    for (fi, &n) in face_frontier.iter().enumerate() {
        if face_room[fi] != NO_ROOM {
            room_frontier[face_room[fi] as usize] += n as usize;
        }
    }
    for (room, &n) in rooms.iter_mut().zip(&room_frontier) {
        room.partial |= n >= min_cells;
    }
    diag.partial_rooms = rooms.iter().filter(|r| r.partial).count();
    let candidate = arr
        .faces
        .iter()
        .enumerate()
        .map(|(i, f)| {
            face_room[i] == NO_ROOM
                && !f.vertices.is_empty()
                && f.unknown as f64 >= config.min_unknown_fraction_candidate * f.cells as f64
        })
        .collect();
    RoomPlan {
        rooms,
        face_room,
        candidate,
    }
}

/// The rooms made of the faces `inside` that share an edge with less wall than
/// `wall_edge_threshold` (union-find, the smaller index the root), each face's room
/// (`NO_ROOM` outside), and the wall edges counted into `diag`.
fn join_inside_faces(
    arr: &Arrangement,
    inside: &[bool],
    config: &LayoutConfig,
    diag: &mut LayoutDiagnostics,
) -> (Vec<PlanRoom>, Vec<u32>) {
    let nf = arr.faces.len();
    let mut parent: Vec<u32> = (0..nf as u32).collect();
    for e in &arr.edges {
        let [a, b] = e.faces;
        if e.wall_fraction >= config.wall_edge_threshold {
            diag.wall_edges += (b != NO_FACE) as usize;
            continue;
        }
        if b == NO_FACE || !inside[a as usize] || !inside[b as usize] {
            continue;
        }
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        if ra != rb {
            // Union by smaller index keeps the result independent of edge order.
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            parent[hi as usize] = lo;
        }
    }
    let mut face_room = vec![NO_ROOM; nf];
    let mut root_room: BTreeMap<u32, u32> = BTreeMap::new();
    let mut rooms: Vec<PlanRoom> = Vec::new();
    for fi in 0..nf as u32 {
        if !inside[fi as usize] {
            continue;
        }
        let r = find(&mut parent, fi);
        let id = *root_room.entry(r).or_insert_with(|| {
            rooms.push(PlanRoom::default());
            (rooms.len() - 1) as u32
        });
        rooms[id as usize].faces.push(fi);
        face_room[fi as usize] = id;
    }
    (rooms, face_room)
}

/// The outline of a union of faces: edges between two faces of the set cancel, the rest are
/// chained into loops; the largest loop is returned with the lines carrying its edges and the
/// number of loops found.
pub(crate) fn union_outline(
    arr: &Arrangement,
    faces: &[u32],
    in_set: &mut [bool],
) -> Option<(Polygon, Vec<u32>, usize)> {
    for &f in faces {
        in_set[f as usize] = true;
    }
    // Directed boundary edges: (from key, to key, tag, from point).
    let mut out: Vec<(u64, u64, u32, Vec2)> = Vec::new();
    for &f in faces {
        let face = &arr.faces[f as usize];
        let n = face.keys.len();
        for i in 0..n {
            let other = arr.other_face(face.edges[i], f);
            if other != NO_FACE && in_set[other as usize] {
                continue;
            }
            out.push((
                face.keys[i],
                face.keys[(i + 1) % n],
                face.tags[i],
                face.vertices[i],
            ));
        }
    }
    for &f in faces {
        in_set[f as usize] = false;
    }
    if out.len() < 3 {
        return None;
    }
    out.sort_by_key(|e| (e.0, e.1));
    let mut used = vec![false; out.len()];
    let mut best: Option<(f64, Vec<Vec2>, Vec<u32>)> = None;
    let mut loops = 0;
    for start in 0..out.len() {
        if used[start] {
            continue;
        }
        let mut pts = Vec::new();
        let mut tags = Vec::new();
        let mut cur = start;
        loop {
            used[cur] = true;
            pts.push(out[cur].3);
            tags.push(out[cur].2);
            let to = out[cur].1;
            if to == out[start].0 {
                break;
            }
            let lo = out.partition_point(|e| e.0 < to);
            match (lo..out.len())
                .take_while(|&j| out[j].0 == to)
                .find(|&j| !used[j])
            {
                Some(j) => cur = j,
                None => break,
            }
        }
        loops += 1;
        let area = Polygon::new(pts.clone()).signed_area_m2();
        if best.as_ref().is_none_or(|b| area > b.0) {
            best = Some((area, pts, tags));
        }
    }
    let (area, pts, tags) = best?;
    if area <= 0.0 {
        return None;
    }
    // Merge consecutive edges on the same line.
    let n = pts.len();
    let mut v = Vec::with_capacity(n);
    let mut t = Vec::with_capacity(n);
    for i in 0..n {
        let prev = tags[(i + n - 1) % n];
        if tags[i] != prev {
            v.push(pts[i]);
            t.push(tags[i]);
        }
    }
    if v.len() < 3 {
        v = pts;
        t = tags;
    }
    Some((Polygon::new(v), t, loops))
}

/// Builds the output rooms: outlines, labels, areas.
pub(crate) fn room_polygons(
    grid: &OccupancyGrid,
    arr: &Arrangement,
    plan: &RoomPlan,
    config: &LayoutConfig,
    diag: &mut LayoutDiagnostics,
) -> Vec<LayoutRoom> {
    let cell_m2 = grid.frame.cell_area_m2();
    let mut in_set = vec![false; arr.faces.len()];
    let mut out = Vec::new();
    for room in &plan.rooms {
        let all: Vec<u32> = room.faces.iter().chain(&room.predicted).copied().collect();
        let Some((polygon, tags, loops)) = union_outline(arr, &all, &mut in_set) else {
            diag.dropped_small_rooms += 1;
            continue;
        };
        let area_m2 = polygon.area_m2();
        if area_m2 < config.min_room_area_m2 {
            diag.dropped_small_rooms += 1;
            continue;
        }
        if loops > 1 {
            diag.split_outlines += 1;
        }
        let observed = if room.predicted.is_empty() {
            Some((polygon.clone(), tags.clone(), 1))
        } else {
            union_outline(arr, &room.faces, &mut in_set)
        };
        let observed_polygon = observed.map(|o| o.0).unwrap_or_else(|| polygon.clone());
        let label = if !room.partial {
            RoomLabel::Full
        } else if tags.iter().any(|t| arr.is_border(*t)) {
            RoomLabel::Open
        } else {
            RoomLabel::Partial
        };
        diag.open_rooms += (label == RoomLabel::Open) as usize;
        diag.predicted_rooms += (!room.predicted.is_empty()) as usize;
        let unknown: u32 = all.iter().map(|f| arr.faces[*f as usize].unknown).sum();
        out.push(LayoutRoom {
            id: out.len() as u32,
            observed_area_m2: observed_polygon.area_m2(),
            open_edges: tags.iter().map(|t| arr.is_border(*t)).collect(),
            polygon,
            observed_polygon,
            label,
            predicted: !room.predicted.is_empty(),
            area_m2,
            unknown_area_m2: unknown as f64 * cell_m2,
        });
    }
    out
}

/// Faces left out of every room after prediction that still hold observed free space (mostly
/// unknown faces seen through a door, say) become rooms of their own, joined across open edges;
/// they are partial.
pub(crate) fn adopt_leftovers(
    grid: &OccupancyGrid,
    arr: &Arrangement,
    plan: &mut RoomPlan,
    config: &LayoutConfig,
) {
    let cell_m2 = grid.frame.cell_area_m2();
    let nf = arr.faces.len();
    let left: Vec<bool> = (0..nf)
        .map(|i| {
            let f = &arr.faces[i];
            plan.face_room[i] == NO_ROOM
                && !f.vertices.is_empty()
                && f.free as f64 * cell_m2 >= 0.5
                && f.free as f64 >= 0.1 * f.cells as f64
        })
        .collect();
    let mut parent: Vec<u32> = (0..nf as u32).collect();
    for e in &arr.edges {
        let [a, b] = e.faces;
        if b == NO_FACE || e.wall_fraction >= config.wall_edge_threshold {
            continue;
        }
        if !left[a as usize] || !left[b as usize] {
            continue;
        }
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        if ra != rb {
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            parent[hi as usize] = lo;
        }
    }
    let mut root_room: BTreeMap<u32, u32> = BTreeMap::new();
    for fi in 0..nf as u32 {
        if !left[fi as usize] {
            continue;
        }
        let r = find(&mut parent, fi);
        let id = *root_room.entry(r).or_insert_with(|| {
            plan.rooms.push(PlanRoom {
                partial: true,
                ..PlanRoom::default()
            });
            (plan.rooms.len() - 1) as u32
        });
        plan.rooms[id as usize].faces.push(fi);
        plan.face_room[fi as usize] = id;
    }
}
