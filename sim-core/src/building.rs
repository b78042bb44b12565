//! The building: what the robot explores. Solid geometry, free space, optional ground truth.
//!
//! Two geometries share one interface. A *raster* world comes from an occupancy map (every cell
//! that is not free is solid). A *vector* world has an outline (the building's envelope: outside
//! it is solid) and solid polygons inside it (walls, pillars, clutter). Both give the same derived
//! views: boundary segments for ray casting and collisions, and a free-space mask on any grid.

use sha2::{Digest, Sha256};

use crate::distance::distance_to;
use crate::geom::{Aabb, Polygon, Pose, Segment, Vec2};
use crate::grid::{Bitmap, Cell, GridFrame};

/// Resolution at which vector buildings are rasterised to measure areas.
pub const AREA_RESOLUTION_M: f64 = 0.05;

#[derive(Debug, Clone, PartialEq)]
pub enum Geometry {
    /// Cells that are `true` are solid. Outside the grid is solid too.
    Raster { solid: Bitmap },
    /// Free space is inside `outline` and outside every polygon of `solids`.
    Vector {
        outline: Polygon,
        solids: Vec<Polygon>,
    },
}

/// A ground-truth room.
#[derive(Debug, Clone, PartialEq)]
pub struct Room {
    pub id: u32,
    /// Free text such as "corridor", "classroom"; may be empty.
    pub kind: String,
    pub polygon: Polygon,
}

/// A doorway: an opening in a wall between two rooms (the opening itself is free space).
#[derive(Debug, Clone, PartialEq)]
pub struct Door {
    pub a: Vec2,
    pub b: Vec2,
    /// The rooms it joins; `None` for a door to the outside (the entrance).
    pub rooms: [Option<u32>; 2],
}

#[derive(Debug, Clone, PartialEq)]
pub struct Building {
    pub name: String,
    pub geometry: Geometry,
    pub rooms: Vec<Room>,
    pub doors: Vec<Door>,
    pub start: Option<Pose>,
}

/// Where a start pose comes from, for reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StartSource {
    /// Given by the building file.
    File,
    /// Chosen by [`Building::default_start`]: the free point of largest clearance.
    LargestClearance,
}

impl Building {
    /// The world-space box holding all geometry.
    pub fn bounds(&self) -> Aabb {
        match &self.geometry {
            Geometry::Raster { solid } => solid.frame.bounds(),
            Geometry::Vector { outline, .. } => outline.aabb(),
        }
    }

    /// The boundary between free and solid space as segments (merged where collinear on a raster).
    /// Ray casts and the robot's collisions use these.
    pub fn boundary_segments(&self) -> Vec<Segment> {
        match &self.geometry {
            Geometry::Raster { solid } => raster_boundary(solid),
            Geometry::Vector { outline, solids } => outline
                .edges()
                .chain(solids.iter().flat_map(|p| p.edges()))
                .filter(|s| s.length_m() > 1e-9)
                .collect(),
        }
    }

    /// Whether a world point is in free space.
    pub fn is_free(&self, p: Vec2) -> bool {
        match &self.geometry {
            Geometry::Raster { solid } => {
                let c = solid.frame.cell_from_world(p);
                solid.get(c) == Some(&false)
            }
            Geometry::Vector { outline, solids } => {
                outline.contains(p) && !solids.iter().any(|s| s.contains(p))
            }
        }
    }

    /// Free space on `frame`: a cell is free when its centre is.
    pub fn free_mask(&self, frame: GridFrame) -> Bitmap {
        match &self.geometry {
            Geometry::Raster { solid } if solid.frame == frame => Bitmap {
                frame,
                data: solid.data.iter().map(|s| !s).collect(),
            },
            Geometry::Raster { .. } => {
                let mut m = Bitmap::filled(frame, false);
                for i in 0..frame.len() {
                    m.data[i] = self.is_free(frame.world_from_cell(frame.cell_of_index(i)));
                }
                m
            }
            Geometry::Vector { outline, solids } => {
                let mut m = Bitmap::filled(frame, false);
                fill_polygon(&mut m, outline, true);
                for s in solids {
                    fill_polygon(&mut m, s, false);
                }
                m
            }
        }
    }

    /// The grid on which areas are measured: the raster's own grid, or a 0.05 m grid over a vector
    /// building.
    pub fn area_frame(&self) -> GridFrame {
        match &self.geometry {
            Geometry::Raster { solid } => solid.frame,
            Geometry::Vector { outline, .. } => {
                GridFrame::covering(&outline.aabb(), AREA_RESOLUTION_M, 0.0)
            }
        }
    }

    /// Total free area in square metres (all free space, connected to the start or not).
    pub fn free_area_m2(&self) -> f64 {
        let f = self.area_frame();
        self.free_mask(f).count_true() as f64 * f.cell_area_m2()
    }

    /// The start pose: the file's, or else the free point with the largest clearance from walls
    /// (centre of the cell farthest from any solid cell, lowest row-major index on ties),
    /// facing +x. `None` only for a building with no free space.
    pub fn default_start(&self) -> Option<(Pose, StartSource)> {
        if let Some(p) = self.start {
            return Some((p, StartSource::File));
        }
        let frame = self.area_frame();
        let free = self.free_mask(frame);
        let solid = Bitmap {
            frame,
            data: free.data.iter().map(|f| !f).collect(),
        };
        let dist = distance_to(&solid);
        let mut best: Option<(usize, f32)> = None;
        for (i, &d) in dist.data.iter().enumerate() {
            if free.data[i] && d.is_finite() && best.is_none_or(|(_, bd)| d > bd) {
                best = Some((i, d));
            }
        }
        best.map(|(i, _)| {
            let p = frame.world_from_cell(frame.cell_of_index(i));
            (Pose::new(p.x, p.y, 0.0), StartSource::LargestClearance)
        })
    }

    /// A content hash (SHA-256, hex, first 16 bytes) of everything that shapes a run: geometry,
    /// rooms, doors and start. The name is not part of it.
    pub fn content_hash(&self) -> String {
        let mut h = Sha256::new();
        h.update(b"floorcast-building-v1\0");
        let f = |h: &mut Sha256, v: f64| h.update(v.to_le_bytes());
        let poly = |h: &mut Sha256, p: &Polygon| {
            h.update((p.vertices.len() as u64).to_le_bytes());
            for v in &p.vertices {
                h.update(v.x.to_le_bytes());
                h.update(v.y.to_le_bytes());
            }
        };
        match &self.geometry {
            Geometry::Raster { solid } => {
                h.update(b"raster");
                f(&mut h, solid.frame.origin_m.x);
                f(&mut h, solid.frame.origin_m.y);
                f(&mut h, solid.frame.resolution_m);
                h.update(solid.frame.width.to_le_bytes());
                h.update(solid.frame.height.to_le_bytes());
                let mut byte = 0u8;
                for (i, &s) in solid.data.iter().enumerate() {
                    byte |= (s as u8) << (i % 8);
                    if i % 8 == 7 {
                        h.update([byte]);
                        byte = 0;
                    }
                }
                h.update([byte]);
            }
            Geometry::Vector { outline, solids } => {
                h.update(b"vector");
                poly(&mut h, outline);
                h.update((solids.len() as u64).to_le_bytes());
                for s in solids {
                    poly(&mut h, s);
                }
            }
        }
        h.update((self.rooms.len() as u64).to_le_bytes());
        for r in &self.rooms {
            h.update(r.id.to_le_bytes());
            h.update(r.kind.as_bytes());
            h.update([0]);
            poly(&mut h, &r.polygon);
        }
        h.update((self.doors.len() as u64).to_le_bytes());
        for d in &self.doors {
            for v in [d.a.x, d.a.y, d.b.x, d.b.y] {
                f(&mut h, v);
            }
            for r in d.rooms {
                h.update(r.map_or(u64::MAX, u64::from).to_le_bytes());
            }
        }
        match self.start {
            Some(p) => {
                for v in [p.x_m, p.y_m, p.theta_rad] {
                    f(&mut h, v);
                }
            }
            None => h.update(b"nostart"),
        }
        let digest = h.finalize();
        digest[..16].iter().map(|b| format!("{b:02x}")).collect()
    }

    /// Free cells 4-connected to `start` on `frame` (the space a robot could map).
    pub fn reachable_free(&self, frame: GridFrame, start: Vec2) -> Bitmap {
        let free = self.free_mask(frame);
        flood_fill(&free, frame.cell_from_world(start))
    }
}

/// Cells of `mask` 4-connected to `seed` (empty when `seed` is not in `mask`).
pub fn flood_fill(mask: &Bitmap, seed: Cell) -> Bitmap {
    let frame = mask.frame;
    let mut out = Bitmap::filled(frame, false);
    if mask.get(seed) != Some(&true) {
        return out;
    }
    let mut stack = vec![seed];
    out.set(seed, true);
    while let Some(c) = stack.pop() {
        for n in c.neighbours4() {
            if let Some(i) = frame.index(n) {
                if mask.data[i] && !out.data[i] {
                    out.data[i] = true;
                    stack.push(n);
                }
            }
        }
    }
    out
}

/// Boundary of a solid raster as merged segments. Outside the grid counts as solid.
fn raster_boundary(solid: &Bitmap) -> Vec<Segment> {
    let f = solid.frame;
    let (w, h) = (f.width as i32, f.height as i32);
    let is_solid = |x: i32, y: i32| solid.get(Cell::new(x, y)).copied().unwrap_or(true);
    let corner = |x: i32, y: i32| f.origin_m + Vec2::new(x as f64, y as f64) * f.resolution_m;
    let mut out = Vec::new();
    // Horizontal edges on the line y (between rows y-1 and y). Orientation matters for merging:
    // a run continues only while the same side is solid.
    for y in 0..=h {
        let mut run: Option<(i32, bool)> = None;
        for x in 0..=w {
            let edge = if x < w {
                let below = is_solid(x, y - 1);
                let above = is_solid(x, y);
                (below != above).then_some(below)
            } else {
                None
            };
            match (run, edge) {
                (Some((_, o)), Some(e)) if o == e => {}
                (Some((x0, _)), e) => {
                    out.push(Segment::new(corner(x0, y), corner(x, y)));
                    run = e.map(|e| (x, e));
                }
                (None, Some(e)) => run = Some((x, e)),
                (None, None) => {}
            }
        }
    }
    for x in 0..=w {
        let mut run: Option<(i32, bool)> = None;
        for y in 0..=h {
            let edge = if y < h {
                let left = is_solid(x - 1, y);
                let right = is_solid(x, y);
                (left != right).then_some(left)
            } else {
                None
            };
            match (run, edge) {
                (Some((_, o)), Some(e)) if o == e => {}
                (Some((y0, _)), e) => {
                    out.push(Segment::new(corner(x, y0), corner(x, y)));
                    run = e.map(|e| (y, e));
                }
                (None, Some(e)) => run = Some((y, e)),
                (None, None) => {}
            }
        }
    }
    out
}

/// Sets every cell whose centre lies inside `poly` (even-odd rule) to `value`.
pub fn fill_polygon(mask: &mut Bitmap, poly: &Polygon, value: bool) {
    let frame = mask.frame;
    for_cells_in_polygon(frame, poly, |i| mask.data[i] = value);
}

/// Calls `visit` with the row-major index of every cell of `f` whose centre lies inside `poly`
/// (even-odd rule), touching only the polygon's rows.
pub fn for_cells_in_polygon(f: GridFrame, poly: &Polygon, mut visit: impl FnMut(usize)) {
    let n = poly.vertices.len();
    if n < 3 || f.is_empty() {
        return;
    }
    let bb = poly.aabb();
    let y0 = (((bb.min.y - f.origin_m.y) / f.resolution_m - 0.5).floor() as i64).max(0);
    let y1 =
        (((bb.max.y - f.origin_m.y) / f.resolution_m - 0.5).ceil() as i64).min(f.height as i64 - 1);
    let mut xs: Vec<f64> = Vec::new();
    for cy in y0..=y1 {
        let wy = f.origin_m.y + (cy as f64 + 0.5) * f.resolution_m;
        xs.clear();
        for i in 0..n {
            let a = poly.vertices[i];
            let b = poly.vertices[(i + 1) % n];
            if (a.y > wy) != (b.y > wy) {
                xs.push(a.x + (wy - a.y) * (b.x - a.x) / (b.y - a.y));
            }
        }
        xs.sort_by(|a, b| a.total_cmp(b));
        for pair in xs.chunks_exact(2) {
            // Cells whose centre x is in [pair[0], pair[1]).
            let cx0 = (((pair[0] - f.origin_m.x) / f.resolution_m) - 0.5).ceil() as i64;
            let cx1 = (((pair[1] - f.origin_m.x) / f.resolution_m) - 0.5).ceil() as i64 - 1;
            let cx0 = cx0.max(0);
            let cx1 = cx1.min(f.width as i64 - 1);
            let row = cy as usize * f.width as usize;
            for cx in cx0..=cx1 {
                visit(row + cx as usize);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::OccupancyGrid;

    fn two_rooms_vector() -> Building {
        // 10 x 6 m box, an inner wall at x = 5 with a 1 m door.
        let outline = Polygon::rect(Vec2::new(0.0, 0.0), Vec2::new(10.0, 6.0));
        let solids = vec![
            Polygon::thick_segment(Vec2::new(0.0, 0.0), Vec2::new(10.0, 0.0), 0.2),
            Polygon::thick_segment(Vec2::new(10.0, 0.0), Vec2::new(10.0, 6.0), 0.2),
            Polygon::thick_segment(Vec2::new(10.0, 6.0), Vec2::new(0.0, 6.0), 0.2),
            Polygon::thick_segment(Vec2::new(0.0, 6.0), Vec2::new(0.0, 0.0), 0.2),
            Polygon::thick_segment(Vec2::new(5.0, 0.0), Vec2::new(5.0, 2.5), 0.2),
            Polygon::thick_segment(Vec2::new(5.0, 3.5), Vec2::new(5.0, 6.0), 0.2),
        ];
        Building {
            name: "two-rooms".into(),
            geometry: Geometry::Vector { outline, solids },
            rooms: vec![],
            doors: vec![],
            start: None,
        }
    }

    #[test]
    fn vector_free_area_is_interior_minus_walls() {
        let b = two_rooms_vector();
        // Interior 9.8 x 5.8 minus the inner wall (0.2 x 5.0 incl. its end caps inside).
        let expected = 9.8 * 5.8 - 0.2 * (2.6 + 2.6);
        let got = b.free_area_m2();
        assert!((got - expected).abs() < 0.5, "{got} vs {expected}");
    }

    #[test]
    fn default_start_is_free_and_deterministic() {
        let b = two_rooms_vector();
        let (p, src) = b.default_start().unwrap();
        assert_eq!(src, StartSource::LargestClearance);
        assert!(b.is_free(p.position()));
        assert_eq!(b.default_start().unwrap().0, p);
    }

    #[test]
    fn raster_boundary_merges_runs() {
        let g = OccupancyGrid::from_ascii(
            "
            ######
            #....#
            #....#
            ######
            ",
            1.0,
        );
        let solid = Bitmap {
            frame: g.frame,
            data: g
                .data
                .iter()
                .map(|s| *s != crate::grid::Occupancy::Free)
                .collect(),
        };
        let b = Building {
            name: "box".into(),
            geometry: Geometry::Raster { solid },
            rooms: vec![],
            doors: vec![],
            start: None,
        };
        let segs = b.boundary_segments();
        assert_eq!(segs.len(), 4, "{segs:?}");
        let total: f64 = segs.iter().map(|s| s.length_m()).sum();
        assert_eq!(total, 12.0);
        assert_eq!(b.free_area_m2(), 8.0);
    }

    #[test]
    fn hash_ignores_name_but_not_geometry() {
        let a = two_rooms_vector();
        let mut b = a.clone();
        b.name = "other".into();
        assert_eq!(a.content_hash(), b.content_hash());
        b.start = Some(Pose::new(1.0, 1.0, 0.0));
        assert_ne!(a.content_hash(), b.content_hash());
    }
}
