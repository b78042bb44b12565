//! Synthetic buildings with ground truth, for tests and benchmarks of the layout: a corridor
//! with rooms of repeated widths on both sides, its complete occupancy map, and what a simple
//! 360 degree laser sees of it from a few points.

use crate::building::{fill_polygon, Building, Geometry, Room};
use crate::geom::{Polygon, Vec2};
use crate::grid::{Bitmap, GridFrame, Occupancy, OccupancyGrid};

/// A corridor along x with rooms on both sides.
#[derive(Debug, Clone)]
pub struct BuildingSpec {
    /// Widths of the rooms along the corridor, repeated on both sides.
    pub room_widths_m: Vec<f64>,
    pub room_depth_m: f64,
    pub corridor_width_m: f64,
    pub wall_m: f64,
    pub door_m: f64,
    /// Rotation of the whole building about the origin.
    pub rotation_rad: f64,
}

impl Default for BuildingSpec {
    fn default() -> Self {
        Self {
            room_widths_m: vec![4.0, 4.0, 6.0, 4.0],
            room_depth_m: 5.0,
            corridor_width_m: 2.4,
            wall_m: 0.15,
            door_m: 0.9,
            rotation_rad: 0.0,
        }
    }
}

pub fn corridor_building(spec: &BuildingSpec) -> Building {
    let (s, c) = spec.rotation_rad.sin_cos();
    let rot = |p: Vec2| Vec2::new(c * p.x - s * p.y + 40.0, s * p.x + c * p.y + 40.0);
    let length: f64 = spec.room_widths_m.iter().sum::<f64>().max(8.0);
    let (d, cw, t) = (spec.room_depth_m, spec.corridor_width_m, spec.wall_m);
    let y_c0 = d;
    let y_c1 = d + cw;
    let height = 2.0 * d + cw;
    let mut solids = Vec::new();
    let mut wall = |a: Vec2, b: Vec2| solids.push(Polygon::thick_segment(rot(a), rot(b), t));
    let v = Vec2::new;
    // Envelope.
    wall(v(0.0, 0.0), v(length, 0.0));
    wall(v(length, 0.0), v(length, height));
    wall(v(length, height), v(0.0, height));
    wall(v(0.0, height), v(0.0, 0.0));
    let mut rooms = Vec::new();
    let inset = t / 2.0;
    let mut add_room = |x0: f64, y0: f64, x1: f64, y1: f64, kind: &str| {
        let p = [
            v(x0 + inset, y0 + inset),
            v(x1 - inset, y0 + inset),
            v(x1 - inset, y1 - inset),
            v(x0 + inset, y1 - inset),
        ];
        rooms.push(Room {
            id: rooms.len() as u32,
            kind: kind.into(),
            polygon: Polygon::new(p.iter().map(|q| rot(*q)).collect()),
        });
    };
    add_room(0.0, y_c0, length, y_c1, "corridor");
    if !spec.room_widths_m.is_empty() {
        // Corridor walls with one door per room, partitions.
        for (y, y_far) in [(y_c0, 0.0), (y_c1, height)] {
            let mut x = 0.0;
            for (i, w) in spec.room_widths_m.iter().enumerate() {
                let door0 = x + w / 2.0 - spec.door_m / 2.0;
                let door1 = door0 + spec.door_m;
                wall(v(x, y), v(door0, y));
                wall(v(door1, y), v(x + w, y));
                if i + 1 < spec.room_widths_m.len() {
                    wall(v(x + w, y), v(x + w, y_far));
                }
                let (ya, yb) = if y_far < y { (y_far, y) } else { (y, y_far) };
                add_room(x, ya, x + w, yb, "room");
                x += w;
            }
        }
    }
    let outline = Polygon::new(
        [
            v(-t / 2.0, -t / 2.0),
            v(length + t / 2.0, -t / 2.0),
            v(length + t / 2.0, height + t / 2.0),
            v(-t / 2.0, height + t / 2.0),
        ]
        .iter()
        .map(|q| rot(*q))
        .collect(),
    );
    Building {
        name: "corridor".into(),
        geometry: Geometry::Vector { outline, solids },
        rooms,
        doors: vec![],
        start: None,
    }
}

/// The complete map of a building: free cells free, other cells in the outline's box occupied,
/// a 1 m unknown margin around.
pub fn rasterise(b: &Building, resolution_m: f64) -> OccupancyGrid {
    let frame = GridFrame::covering(&b.bounds(), resolution_m, 1.0);
    let free = b.free_mask(frame);
    let mut inside = Bitmap::filled(frame, false);
    if let Geometry::Vector { outline, .. } = &b.geometry {
        fill_polygon(&mut inside, outline, true);
    }
    OccupancyGrid {
        frame,
        data: free
            .data
            .iter()
            .zip(&inside.data)
            .map(|(f, i)| match (f, i) {
                (true, _) => Occupancy::Free,
                (false, true) => Occupancy::Occupied,
                _ => Occupancy::Unknown,
            })
            .collect(),
    }
}

/// What a 360 degree laser of `range_m` sees from `views` in the complete map `full`.
pub fn observe(full: &OccupancyGrid, views: &[Vec2], range_m: f64) -> OccupancyGrid {
    let f = full.frame;
    let mut out = OccupancyGrid::filled(f, Occupancy::Unknown);
    let step = f.resolution_m / 2.0;
    for p in views {
        for k in 0..1440 {
            let a = k as f64 * std::f64::consts::TAU / 1440.0;
            let d = Vec2::new(a.cos(), a.sin());
            let mut r = 0.0;
            while r <= range_m {
                let c = f.cell_from_world(p + d * r);
                match full.get(c) {
                    Some(Occupancy::Free) => out.set(c, Occupancy::Free),
                    Some(Occupancy::Occupied) => {
                        out.set(c, Occupancy::Occupied);
                        break;
                    }
                    _ => break,
                }
                r += step;
            }
        }
    }
    out
}

/// View points every metre along the corridor's centre line, up to `fraction` of its length.
pub fn corridor_views(spec: &BuildingSpec, fraction: f64) -> Vec<Vec2> {
    let length: f64 = spec.room_widths_m.iter().sum::<f64>().max(8.0);
    let (s, c) = spec.rotation_rad.sin_cos();
    let y = spec.room_depth_m + spec.corridor_width_m / 2.0;
    let mut out = Vec::new();
    let mut x = 0.8;
    while x <= fraction * length {
        out.push(Vec2::new(c * x - s * y + 40.0, s * x + c * y + 40.0));
        x += 1.0;
    }
    out
}

/// The complete map of a generated building at `resolution_m`: free where
/// [`Building::free_mask`] is, occupied elsewhere in the building's bounding box, unknown in a
/// 1 m margin around it.
pub fn complete_map(b: &Building, resolution_m: f64) -> OccupancyGrid {
    let bounds = b.bounds();
    let frame = GridFrame::covering(&bounds, resolution_m, 1.0);
    let free = b.free_mask(frame);
    OccupancyGrid {
        frame,
        data: free
            .data
            .iter()
            .enumerate()
            .map(|(i, f)| {
                if *f {
                    Occupancy::Free
                } else if bounds.contains(frame.world_from_cell(frame.cell_of_index(i))) {
                    Occupancy::Occupied
                } else {
                    Occupancy::Unknown
                }
            })
            .collect(),
    }
}

/// Marks what a laser at `p` looking along `heading_rad` with field of view `fov_rad` and range
/// `range_m` sees of the complete map `full` (rays stop at the first occupied cell).
pub(crate) fn scan_into(
    full: &OccupancyGrid,
    out: &mut OccupancyGrid,
    p: Vec2,
    heading_rad: f64,
    fov_rad: f64,
    range_m: f64,
) {
    let f = full.frame;
    let step = f.resolution_m / 2.0;
    let rays = ((fov_rad / (0.25f64).to_radians()).ceil() as usize).max(1);
    for k in 0..=rays {
        let a = heading_rad - fov_rad / 2.0 + fov_rad * k as f64 / rays as f64;
        let d = Vec2::new(a.cos(), a.sin());
        let mut r = 0.0;
        while r <= range_m {
            let c = f.cell_from_world(p + d * r);
            match full.get(c) {
                Some(Occupancy::Free) => out.set(c, Occupancy::Free),
                Some(Occupancy::Occupied) => {
                    out.set(c, Occupancy::Occupied);
                    break;
                }
                _ => break,
            }
            r += step;
        }
    }
}

/// A partial map of `b` as an exploring robot would make it: it walks from the start room
/// through the doors (depth first, corridors before rooms, entering a room with probability
/// `enter_probability`), and scans every metre with a 6 m laser of 180 to 360 degrees (drawn
/// per scan) until `fraction` of the free cells of `full` are known. Deterministic in `seed`.
pub fn explored_map(
    b: &Building,
    full: &OccupancyGrid,
    fraction: f64,
    enter_probability: f64,
    seed: u64,
) -> OccupancyGrid {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut out = OccupancyGrid::filled(full.frame, Occupancy::Unknown);
    let total_free = full.count(Occupancy::Free).max(1);
    let centroid = |p: &Polygon| {
        let n = p.vertices.len().max(1) as f64;
        p.vertices.iter().fold(Vec2::zeros(), |a, v| a + v) / n
    };
    let is_corridor = |id: u32| b.rooms.iter().any(|r| r.id == id && r.kind == "corridor");
    // Start: the room holding the start pose, else the first corridor, else the first room.
    let start_room = b
        .start
        .as_ref()
        .and_then(|s| {
            b.rooms
                .iter()
                .find(|r| r.polygon.contains(s.position()))
                .map(|r| r.id)
        })
        .or_else(|| b.rooms.iter().find(|r| r.kind == "corridor").map(|r| r.id))
        .or_else(|| b.rooms.first().map(|r| r.id));
    let Some(start_room) = start_room else {
        return out;
    };
    let mut pos = centroid(&b.rooms.iter().find(|r| r.id == start_room).unwrap().polygon);
    let mut visited = vec![start_room];
    let mut stack = vec![start_room];
    let walk =
        |pos: &mut Vec2, to: Vec2, out: &mut OccupancyGrid, rng: &mut rand_chacha::ChaCha8Rng| {
            let d = to - *pos;
            let len = d.norm();
            let heading = d.y.atan2(d.x);
            let steps = len.ceil().max(1.0) as usize;
            for k in 1..=steps {
                let p = *pos + d * (k as f64 / steps as f64);
                let fov = rng.random_range(std::f64::consts::PI..=std::f64::consts::TAU);
                scan_into(full, out, p, heading, fov, 6.0);
            }
            *pos = to;
        };
    walk(&mut pos.clone(), pos, &mut out, &mut rng);
    while let Some(&here) = stack.last() {
        if out.count(Occupancy::Free) as f64 >= fraction * total_free as f64 {
            break;
        }
        // Doors of this room to unvisited rooms, corridors first.
        let mut next: Vec<(bool, u32, Vec2)> = b
            .doors
            .iter()
            .filter_map(|d| {
                let [r0, r1] = d.rooms;
                let other = match (r0, r1) {
                    (Some(a), Some(o)) if a == here => o,
                    (Some(o), Some(a)) if a == here => o,
                    _ => return None,
                };
                (!visited.contains(&other)).then(|| (!is_corridor(other), other, (d.a + d.b) / 2.0))
            })
            .collect();
        next.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.cmp(&b.1)));
        let Some(&(is_room, to, door)) = next.first() else {
            stack.pop();
            if let Some(&back) = stack.last() {
                let c = centroid(&b.rooms.iter().find(|r| r.id == back).unwrap().polygon);
                walk(&mut pos, c, &mut out, &mut rng);
            }
            continue;
        };
        visited.push(to);
        if is_room && !rng.random_bool(enter_probability.clamp(0.0, 1.0)) {
            // Look through the door from the corridor side only.
            walk(&mut pos, door, &mut out, &mut rng);
            continue;
        }
        walk(&mut pos, door, &mut out, &mut rng);
        let c = centroid(&b.rooms.iter().find(|r| r.id == to).unwrap().polygon);
        walk(&mut pos, c, &mut out, &mut rng);
        stack.push(to);
    }
    out
}

/// Pairs of indices of corridor rooms of `b` joined by a door: the pieces of one corridor.
pub fn corridor_pieces(b: &Building) -> Vec<(usize, usize)> {
    let index = |id: Option<u32>| {
        let id = id?;
        b.rooms
            .iter()
            .position(|r| r.id == id && r.kind == "corridor")
    };
    b.doors
        .iter()
        .filter_map(|d| Some((index(d.rooms[0])?, index(d.rooms[1])?)))
        .collect()
}
