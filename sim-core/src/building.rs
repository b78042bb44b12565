//! The building: what the robot explores. Solid geometry, free space, optional ground truth.
//!
//! Two geometries share one interface. A *raster* world comes from an occupancy map (every cell
//! that is not free is solid). A *vector* world has an outline (the building's envelope: outside
//! it is solid) and solid polygons inside it (walls, pillars, clutter). Both give the same derived
//! views: boundary segments for ray casting and collisions, and a free-space mask on any grid.

use sha2::{Digest, Sha256};

use crate::distance::distance_to;
use crate::geom::{Aabb, Polygon, Pose, Segment, Vec2};
use crate::grid::{Bitmap, Cell, Grid, GridFrame};

/// Resolution at which vector buildings are rasterised to measure areas.
pub(crate) const AREA_RESOLUTION_M: f64 = 0.05;

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

/// Headings of start poses are refused beyond this (360°).
pub(crate) const MAX_HEADING_RAD: f64 = std::f64::consts::TAU * (1.0 + 1e-12);

/// Room kept free around the robot's body at a random start (the explorer's safety margin).
pub(crate) const RANDOM_START_MARGIN_M: f64 = 0.05;

/// Why no start pose could be chosen.
#[derive(Debug, Clone, PartialEq)]
pub enum StartError {
    /// The building has no free space at all.
    NoFreeSpace,
    /// No free point is far enough from solid space for the robot's body.
    NoRoom { needed_m: f64, max_clearance_m: f64 },
    /// Only `placed` of a team's `robots` found room by the team's start rule
    /// ([`Building::team_starts`]).
    NoRoomForTeam { robots: usize, placed: usize },
}

impl std::fmt::Display for StartError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StartError::NoFreeSpace => write!(f, "the building has no free space to start in"),
            StartError::NoRoom {
                needed_m,
                max_clearance_m,
            } => write!(
                f,
                "no free point has room for the robot's body: the largest clearance from solid \
                 space is {max_clearance_m:.3} m, the robot needs {needed_m:.3} m; use a smaller \
                 robot_radius_m, or check that the map's free space is not walled in by unknown \
                 (grey) cells"
            ),
            StartError::NoRoomForTeam { robots, placed } => write!(
                f,
                "room for only {placed} of the team's {robots} robots by the team's start rule \
                 (each robot's body clear of walls, {TEAM_SPACING_EXTRA_M} m between bodies, \
                 reachable from robot 0's start); use fewer robots or another start"
            ),
        }
    }
}

impl std::error::Error for StartError {}

/// Why a given start pose is refused.
#[derive(Debug, Clone, PartialEq)]
pub enum PoseProblem {
    NotFinite,
    /// The heading is beyond ±360°.
    Heading,
    /// The position is not in free space (in a wall or outside the building).
    NotFree,
    /// The robot's body would overlap solid space.
    TooClose {
        clearance_m: f64,
    },
}

impl std::fmt::Display for PoseProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PoseProblem::NotFinite => write!(f, "is not a finite pose"),
            PoseProblem::Heading => write!(f, "has a heading beyond [-360, 360] degrees"),
            PoseProblem::NotFree => write!(f, "is not in free space"),
            PoseProblem::TooClose { clearance_m } => write!(
                f,
                "is {clearance_m:.3} m from solid space, too close for the robot's body"
            ),
        }
    }
}

/// The clearance of the cells of a grid covering a building ([`Building::clearance_field`]).
#[derive(Debug, Clone)]
pub(crate) struct ClearanceField {
    /// The building's [`Building::area_frame`].
    pub base: GridFrame,
    /// `base` padded by one (solid) cell on every side.
    pub frame: GridFrame,
    pub free: Bitmap,
    /// Per cell, a lower bound of the distance (m) from its centre to solid space; 0 on solid
    /// cells.
    pub clearance_m: Grid<f32>,
}

impl ClearanceField {
    /// The world position of the centre of cell `index` of `frame`, computed on `base` (so
    /// that a point is bit for bit the same as on the building's own grid).
    pub(crate) fn position(&self, index: usize) -> Vec2 {
        let c = self.frame.cell_of_index(index);
        self.base.world_from_cell(Cell::new(c.x - 1, c.y - 1))
    }

    /// The free cell of largest clearance (lowest row-major index on ties) and its clearance.
    pub(crate) fn largest(&self) -> Option<(usize, f32)> {
        let mut best: Option<(usize, f32)> = None;
        for (i, &c) in self.clearance_m.data.iter().enumerate() {
            if self.free.data[i] && best.is_none_or(|(_, bc)| c > bc) {
                best = Some((i, c));
            }
        }
        best
    }
}

/// Draws random start poses: cell centres of free space with room for the robot's body plus
/// [`RANDOM_START_MARGIN_M`], uniformly over such cells connected (through such cells) to the
/// largest-clearance point, heading uniform in [-π, π). Each draw is a pure function of the
/// building's content ([`Building::content_digest`]), the radius, the seed and the draw's
/// index: the same seed draws unrelated poses and headings in different buildings.
#[derive(Debug, Clone)]
pub struct StartSampler<'a> {
    building: &'a Building,
    robot_radius_m: f64,
    /// The centres of the cells a start may be drawn from, in row-major order.
    cells: Vec<Vec2>,
    /// The building's content digest, mixed into every draw's seed.
    key: [u8; 32],
}

impl<'a> StartSampler<'a> {
    pub fn new(building: &'a Building, robot_radius_m: f64) -> Result<Self, StartError> {
        let field = building.clearance_field();
        let (best, best_clearance) = field.largest().ok_or(StartError::NoFreeSpace)?;
        let need_m = robot_radius_m + RANDOM_START_MARGIN_M;
        if (best_clearance as f64) < need_m {
            return Err(StartError::NoRoom {
                needed_m: need_m,
                max_clearance_m: best_clearance as f64,
            });
        }
        let roomy = Bitmap {
            frame: field.frame,
            data: field
                .clearance_m
                .data
                .iter()
                .map(|&c| c as f64 >= need_m)
                .collect(),
        };
        let reach = flood_fill(&roomy, field.frame.cell_of_index(best));
        let cells = (0..reach.data.len())
            .filter(|&i| reach.data[i])
            .map(|i| field.position(i))
            .collect();
        Ok(Self {
            building,
            robot_radius_m,
            cells,
            key: building.content_digest(),
        })
    }

    /// How many cells a start may be drawn from.
    pub fn cells(&self) -> usize {
        self.cells.len()
    }

    /// The `index`-th start of the stream `seed`. A drawn cell whose centre the exact check
    /// ([`Building::check_start`]) refuses is drawn again from the same stream.
    pub fn draw(&self, seed: u64, index: u64) -> Pose {
        use rand::RngCore;
        use rand::SeedableRng;
        let mut h = Sha256::new();
        h.update(b"floorcast-random-start-v2\0");
        h.update(self.key);
        h.update(seed.to_le_bytes());
        let mut rng = rand_chacha::ChaCha8Rng::from_seed(h.finalize().into());
        rng.set_stream(RANDOM_START_STREAM);
        // 2 words per draw, up to 64 tries per start.
        rng.set_word_pos(index as u128 * 128 * 2);
        let n = self.cells.len() as u128;
        let mut first = None;
        for _ in 0..64 {
            let k = ((rng.next_u64() as u128 * n) >> 64) as usize;
            let u = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
            let p = self.cells[k];
            let pose = Pose::new(p.x, p.y, -std::f64::consts::PI + u * std::f64::consts::TAU);
            if self.building.check_start(pose, self.robot_radius_m).is_ok() {
                return pose;
            }
            first.get_or_insert(pose);
        }
        first.expect("at least one draw")
    }
}

/// The ChaCha stream of random start poses (the simulator's streams are 1 and 2).
const RANDOM_START_STREAM: u64 = 0x0053_5441_5254;

/// The gap kept between two team robots' bodies at their starts (m).
pub const TEAM_SPACING_EXTRA_M: f64 = 0.3;

/// How a team's robots 1 to N - 1 are placed; robot 0 starts at the run's start pose
/// ([`Building::team_starts`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TeamStarts {
    /// Around robot 0, as a team set down together: on rings about its start, 2 radii + 0.3 m
    /// apart, the nearest free places first (behind it first on each ring), each reached from
    /// robot 0's start by a straight line the body fits along; robot 0's heading.
    Together,
    /// Drawn at random ([`StartSampler`], the stream `seed`): robot `k` takes the first of the
    /// draws `k * 1_000_000 + index * 64 + j` (`j` = 0 to 63) at least 2 radii + 0.3 m from every
    /// robot placed before it. `index` is the run's random start index (robot 0's draw).
    Random { seed: u64, index: u64 },
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
            Geometry::Raster { solid } => {
                // `is_free` of every centre: the raster column of a centre depends on its
                // column only, and its row on its row, so each is found once.
                let sf = solid.frame;
                let column: Vec<Option<usize>> = (0..frame.width as i32)
                    .map(|x| {
                        let c = sf.cell_from_world(frame.world_from_cell(Cell::new(x, 0)));
                        (c.x >= 0 && (c.x as u32) < sf.width).then_some(c.x as usize)
                    })
                    .collect();
                let mut m = Bitmap::filled(frame, false);
                let w = frame.width as usize;
                for y in 0..frame.height as i32 {
                    let r = sf.cell_from_world(frame.world_from_cell(Cell::new(0, y))).y;
                    if r < 0 || r as u32 >= sf.height {
                        continue;
                    }
                    let raster_row =
                        &solid.data[r as usize * sf.width as usize..][..sf.width as usize];
                    for (f, c) in m.data[y as usize * w..][..w].iter_mut().zip(&column) {
                        *f = c.is_some_and(|c| !raster_row[c]);
                    }
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

    /// The start pose: the file's, or else [`Building::largest_clearance_start`] for a robot of
    /// `robot_radius_m`. The file's pose is returned as written: check it with
    /// [`Building::check_start`].
    pub fn default_start(&self, robot_radius_m: f64) -> Result<(Pose, StartSource), StartError> {
        if let Some(p) = self.start {
            return Ok((p, StartSource::File));
        }
        self.largest_clearance_start(robot_radius_m)
            .map(|p| (p, StartSource::LargestClearance))
    }

    /// The free point of largest clearance inside the building, facing +x: the centre of the
    /// free cell farthest from solid space (outside the outline or the raster is solid; lowest
    /// row-major index on ties). Refused when even there a disc of `robot_radius_m` would
    /// overlap solid space.
    pub(crate) fn largest_clearance_start(&self, robot_radius_m: f64) -> Result<Pose, StartError> {
        let field = self.clearance_field();
        let (i, _) = field.largest().ok_or(StartError::NoFreeSpace)?;
        let p = field.position(i);
        let clearance_m = self.clearance_at(p);
        if clearance_m < robot_radius_m {
            return Err(StartError::NoRoom {
                needed_m: robot_radius_m,
                max_clearance_m: clearance_m,
            });
        }
        Ok(Pose::new(p.x, p.y, 0.0))
    }

    /// The distance (m) from `p` to the nearest solid space, 0 where `p` is not free. Exact:
    /// measured to the boundary segments the simulated robot collides with.
    pub(crate) fn clearance_at(&self, p: Vec2) -> f64 {
        if !self.is_free(p) {
            return 0.0;
        }
        self.boundary_segments()
            .iter()
            .map(|s| s.distance_to(p))
            .fold(f64::INFINITY, f64::min)
    }

    /// Checks a start pose for a robot of `robot_radius_m`: finite, heading within ±2π (±360°),
    /// in free space, and the robot's body (a disc) clear of solid space.
    pub fn check_start(&self, pose: Pose, robot_radius_m: f64) -> Result<(), PoseProblem> {
        if !(pose.x_m.is_finite() && pose.y_m.is_finite() && pose.theta_rad.is_finite()) {
            return Err(PoseProblem::NotFinite);
        }
        if pose.theta_rad.abs() > MAX_HEADING_RAD {
            return Err(PoseProblem::Heading);
        }
        let p = pose.position();
        if !self.is_free(p) {
            return Err(PoseProblem::NotFree);
        }
        let clearance_m = self.clearance_at(p);
        if clearance_m < robot_radius_m {
            return Err(PoseProblem::TooClose { clearance_m });
        }
        Ok(())
    }

    /// The free point nearest to `p` (cell centre on the clearance grid) where a disc of
    /// `robot_radius_m` fits with 1 cm to spare (for rounding when printed), if any: what to
    /// suggest instead of a refused start.
    pub fn nearest_start_position(&self, p: Vec2, robot_radius_m: f64) -> Option<Vec2> {
        let field = self.clearance_field();
        let mut best: Option<(f64, usize)> = None;
        for (i, &c) in field.clearance_m.data.iter().enumerate() {
            if (c as f64) < robot_radius_m + 0.01 {
                continue;
            }
            let q = field.position(i);
            let d = (q - p).norm();
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, i));
            }
        }
        best.map(|(_, i)| field.position(i))
    }

    /// A random start pose for a robot of `robot_radius_m`: the `index`-th draw of the stream
    /// `seed` (see [`StartSampler`]). A pure function of the building and its arguments.
    pub fn random_start(
        &self,
        robot_radius_m: f64,
        seed: u64,
        index: u64,
    ) -> Result<Pose, StartError> {
        Ok(StartSampler::new(self, robot_radius_m)?.draw(seed, index))
    }

    /// The start poses of a team of `robots` robots of `robot_radius_m` whose robot 0 starts at
    /// `first`, by the rule `rule` (see [`TeamStarts`]). `first` comes first; an error when the
    /// rule finds room for fewer robots.
    pub fn team_starts(
        &self,
        first: Pose,
        robots: usize,
        robot_radius_m: f64,
        rule: TeamStarts,
    ) -> Result<Vec<Pose>, StartError> {
        let spacing = 2.0 * robot_radius_m + TEAM_SPACING_EXTRA_M;
        let mut placed = vec![first];
        let apart = |p: Vec2, placed: &[Pose]| {
            placed
                .iter()
                .all(|q| (q.position() - p).norm() >= spacing - 1e-9)
        };
        // (The exact check of `check_start`, the boundary computed once.)
        let segments = self.boundary_segments();
        let clear = |p: Vec2, r: f64| {
            p.x.is_finite()
                && p.y.is_finite()
                && self.is_free(p)
                && segments.iter().all(|s| s.distance_to(p) >= r)
        };
        let fits = |pose: Pose| clear(pose.position(), robot_radius_m + RANDOM_START_MARGIN_M);
        match rule {
            TeamStarts::Together => {
                // Rings out to 20 spacings; on each, places about `spacing` apart.
                'rings: for ring in 1..=20 {
                    let r = ring as f64 * spacing;
                    let m = ((std::f64::consts::TAU * r / spacing).floor() as usize).max(6);
                    for a in 0..m {
                        if placed.len() == robots {
                            break 'rings;
                        }
                        // Behind robot 0 first, then alternately either side of behind.
                        let step = std::f64::consts::TAU / m as f64;
                        let k = a.div_ceil(2) as f64 * if a % 2 == 1 { 1.0 } else { -1.0 };
                        let angle = first.theta_rad + std::f64::consts::PI + k * step;
                        let p = first.position() + Vec2::new(angle.cos(), angle.sin()) * r;
                        let pose = Pose::new(p.x, p.y, first.theta_rad);
                        if !apart(p, &placed) || !fits(pose) {
                            continue;
                        }
                        // Reached from robot 0's start along a straight line the body fits
                        // along (every 0.05 m).
                        let steps = (r / 0.05).ceil() as usize;
                        let reached = (1..steps).all(|i| {
                            let q = first.position()
                                + (p - first.position()) * (i as f64 / steps as f64);
                            clear(q, robot_radius_m)
                        });
                        if reached {
                            placed.push(pose);
                        }
                    }
                }
            }
            TeamStarts::Random { seed, index } => {
                let sampler = StartSampler::new(self, robot_radius_m)?;
                for k in 1..robots as u64 {
                    let found = (0..64)
                        .map(|j| sampler.draw(seed, k * 1_000_000 + index * 64 + j))
                        .find(|p| apart(p.position(), &placed));
                    match found {
                        Some(p) => placed.push(p),
                        None => break,
                    }
                }
            }
        }
        if placed.len() < robots {
            return Err(StartError::NoRoomForTeam {
                robots,
                placed: placed.len(),
            });
        }
        Ok(placed)
    }

    /// The clearance of every cell of [`Building::area_frame`] (the raster's own grid or a
    /// 0.05 m grid over the outline's box), padded by one solid cell all around: outside the
    /// outline or the raster is solid.
    pub(crate) fn clearance_field(&self) -> ClearanceField {
        let base = self.area_frame();
        let base_free = self.free_mask(base);
        let frame = GridFrame::new(
            base.origin_m - Vec2::new(base.resolution_m, base.resolution_m),
            base.resolution_m,
            base.width + 2,
            base.height + 2,
        );
        let mut free = Bitmap::filled(frame, false);
        for (i, &f) in base_free.data.iter().enumerate() {
            let c = base.cell_of_index(i);
            free.set(Cell::new(c.x + 1, c.y + 1), f);
        }
        let solid = Bitmap {
            frame,
            data: free.data.iter().map(|f| !f).collect(),
        };
        let dist = distance_to(&solid);
        // From a free cell's centre to the nearest point of a solid cell whose centre is `d`
        // cells away: at least `d - sqrt(2) / 2` cells.
        let res = frame.resolution_m;
        let clearance_m = Grid {
            frame,
            data: dist
                .data
                .iter()
                .zip(&free.data)
                .map(|(&d, &f)| {
                    if f && d.is_finite() {
                        ((d as f64 - std::f64::consts::FRAC_1_SQRT_2).max(0.0) * res) as f32
                    } else {
                        0.0
                    }
                })
                .collect(),
        };
        ClearanceField {
            base,
            frame,
            free,
            clearance_m,
        }
    }

    /// A content hash (SHA-256, hex, first 16 bytes) of everything that shapes a run: geometry,
    /// rooms, doors and start. The name is not part of it.
    pub fn content_hash(&self) -> String {
        let digest = self.content_digest();
        digest[..16].iter().map(|b| format!("{b:02x}")).collect()
    }

    /// The full SHA-256 digest behind [`Building::content_hash`].
    pub(crate) fn content_digest(&self) -> [u8; 32] {
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
        h.finalize().into()
    }

    /// Free cells 4-connected to `start` on `frame` (the space a robot could map).
    pub fn reachable_free(&self, frame: GridFrame, start: Vec2) -> Bitmap {
        let free = self.free_mask(frame);
        flood_fill(&free, frame.cell_from_world(start))
    }
}

/// The free cells of `reachable` (a building's free space connected to the start, see
/// [`Building::reachable_free`]) that a robot whose body is a disc of `robot_radius_m` could
/// see with a laser of `range_m` from somewhere it can drive to: the denominator of the
/// explored fraction. Free space behind a gap narrower than the robot, or a pocket of a raster
/// map joined to the rest by a one-cell gap, is free but cannot be explored; counting it would
/// make complete runs look short.
///
/// The body can stand where the clearance of a cell's centre (a lower bound, as in
/// [`Building::clearance_field`]) is at least `robot_radius_m`; the places it can drive to are
/// those 4-connected to the start's cell (or, when the start's cell is just short of the
/// clearance by the bound's rounding, to the nearest such cell). Every free cell within the
/// body's radius of such a place is seen (the disc around it is free). Other cells are seen
/// when a ray from a place on the boundary of the drivable region, in one of 720 directions
/// (every 0.5 degree), reaches them through free cells within `range_m`: a line of sight from
/// anywhere in the region leaves it through its boundary, so its boundary sees all the region
/// does. A ray that enters the region again stops, since the region's boundary farther along
/// casts its own.
///
/// Without any drivable place (no room for the body), `reachable` is returned unchanged.
pub fn explorable_free(
    reachable: &Bitmap,
    start: Vec2,
    robot_radius_m: f64,
    range_m: f64,
) -> Bitmap {
    let frame = reachable.frame;
    let res = frame.resolution_m;
    let roomy = roomy_cells(reachable, robot_radius_m);
    let Some(seed) = drive_seed(&roomy, start) else {
        return reachable.clone();
    };
    let drivable = flood_fill(&roomy, seed);
    let mut seen = seen_by_body(reachable, &drivable, robot_radius_m);
    // Rays from the drivable region's boundary.
    // A ray sees a gap of one or two cells (the speckle of a scanned map) but not through it:
    // it shows a glimpse, not a room.
    let narrow = narrow_gaps(reachable);
    let dirs = ray_directions(range_m / res);
    let class = ray_classes(reachable, &drivable, &narrow);
    let marked = mark_rays(&class, &drivable, &dirs);
    let (w, h) = (frame.width as usize, frame.height as usize);
    let pw = w + 2;
    for y in 0..h {
        for x in 0..w {
            if marked[(y + 1) * pw + x + 1] {
                seen.data[y * w + x] = true;
            }
        }
    }
    seen
}

/// The cells of [`explorable_free`] where the robot's body (a disc of `robot_radius_m`) fits:
/// those far enough from the cells outside `reachable`.
pub(crate) fn roomy_cells(reachable: &Bitmap, robot_radius_m: f64) -> Bitmap {
    let frame = reachable.frame;
    let res = frame.resolution_m;
    let solid = Bitmap {
        frame,
        data: reachable.data.iter().map(|f| !f).collect(),
    };
    let need_cells = robot_radius_m / res + std::f64::consts::FRAC_1_SQRT_2;
    // A cell is roomy when its distance to solid space, as `distance_to` gives it, is at least
    // `need_cells`. Distances grow with squared distances (whole numbers of cells²), so that is
    // when no solid cell lies nearer than the smallest squared distance whose distance is that
    // much; the distance transform decides when that is beyond `MAX_WINDOW_SQ`.
    let roomy_sq = (0..=MAX_WINDOW_SQ).find(|&d2| distance_of_sq(d2) >= need_cells);
    Bitmap {
        frame,
        data: match roomy_sq {
            Some(t) => within_sq(&solid, t.checked_sub(1))
                .into_iter()
                .map(|near| !near)
                .collect(),
            None => distance_to(&solid)
                .data
                .iter()
                .map(|&d| d as f64 >= need_cells)
                .collect(),
        },
    }
}

/// The cells of `reachable` within the body's radius of a `drivable` cell: seen from inside
/// the disc.
fn seen_by_body(reachable: &Bitmap, drivable: &Bitmap, robot_radius_m: f64) -> Bitmap {
    let frame = reachable.frame;
    let res = frame.resolution_m;
    // Seen from inside the disc: within the body's radius of a drivable cell.
    let body_cells = robot_radius_m / res;
    // As for `roomy`: the squared distances whose distances are at most `body_cells` are those
    // up to the largest such (none when even 0 is not).
    let within: Vec<bool> = if distance_of_sq(MAX_WINDOW_SQ) <= body_cells {
        distance_to(drivable)
            .data
            .iter()
            .map(|&d| (d as f64) <= body_cells)
            .collect()
    } else {
        let body_sq = (0..=MAX_WINDOW_SQ)
            .take_while(|&d2| distance_of_sq(d2) <= body_cells)
            .last();
        within_sq(drivable, body_sq)
    };
    Bitmap {
        frame,
        data: within
            .iter()
            .zip(&reachable.data)
            .map(|(&near, &f)| f && near)
            .collect(),
    }
}

/// What a ray does on entering each cell, on the frame padded by a cell on every side.
fn ray_classes(reachable: &Bitmap, drivable: &Bitmap, narrow: &Bitmap) -> Vec<u8> {
    let frame = reachable.frame;
    // What a ray does on entering a cell, on the frame padded by a cell on every side (a ray
    // stops at the frame's edge): pass on, stop before it, or mark it and stop (narrow).
    let (w, h) = (frame.width as usize, frame.height as usize);
    let pw = w + 2;
    let mut class = vec![RAY_STOP; pw * (h + 2)];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            class[(y + 1) * pw + x + 1] = if !reachable.data[i] || drivable.data[i] {
                RAY_STOP
            } else if narrow.data[i] {
                RAY_LAST
            } else {
                RAY_PASS
            };
        }
    }
    class
}

/// The cells (on the padded frame of `class`) that the rays in directions `dirs` from the
/// cells of `drivable` see.
fn mark_rays(class: &[u8], drivable: &Bitmap, dirs: &[[f64; 2]]) -> Vec<bool> {
    let frame = drivable.frame;
    let (w, h) = (frame.width as usize, frame.height as usize);
    let pw = w + 2;
    let mut marked = vec![false; class.len()];
    let (by_step, keyed) = uniform_walks(dirs, frame, pw);
    let mut others = KeyedWalks {
        dirs,
        keyed,
        pw,
        walks: vec![Vec::new(); RAYS],
        steps: Vec::new(),
    };
    // (Row by row: no division per cell. A neighbour is open when a ray may enter it: in the
    // frame, reachable and not drivable, as `class` says.)
    for (x, y) in (0..h).flat_map(|y| (0..w).map(move |x| (x, y))) {
        if !drivable.data[y * w + x] {
            continue;
        }
        let c = Cell::new(x as i32, y as i32);
        let start = (y + 1) * pw + x + 1;
        // In `Cell::neighbours4`'s order: +x, -x, +y, -y.
        let open = [start + 1, start - 1, start + pw, start - pw].map(|j| class[j] != RAY_STOP);
        if !open.contains(&true) {
            // Every ray stops at its first step (the region, solid space or the frame's edge).
            continue;
        }
        for (group, _) in by_step.iter().zip(open).filter(|(_, o)| *o) {
            // The walks' cells in preorder, each with the index past its subtree: a cell is
            // entered when every cell before it on its walk was passed.
            let mut n = 0;
            while n < group.len() {
                let (offset, past) = group[n];
                let j = start.wrapping_add_signed(offset);
                n = match class[j] {
                    RAY_PASS => {
                        marked[j] = true;
                        n + 1
                    }
                    RAY_LAST => {
                        marked[j] = true;
                        past
                    }
                    _ => past,
                };
            }
        }
        others.mark(class, &mut marked, c, start);
    }
    marked
}

/// Index offset on the padded frame of width `pw` of a step `(dx, dy)`.
#[inline]
fn padded_offset((dx, dy): (i32, i32), pw: usize) -> isize {
    dx as isize + dy as isize * pw as isize
}

/// The walks of the directions that walk the same way from every start, as preorder trees of
/// steps on the padded frame of width `pw`, grouped by the first step; and the other
/// directions (by index).
fn uniform_walks(
    dirs: &[[f64; 2]],
    frame: GridFrame,
    pw: usize,
) -> ([Vec<(isize, usize)>; 4], Vec<usize>) {
    let padded = |d: (i32, i32)| padded_offset(d, pw);
    // Most directions walk the same way from every start (`uniform_walk`): their walks, as
    // steps on the padded frame, grouped by the first step (in the order of
    // `Cell::neighbours4`). A ray marks nothing unless its first step lands on a cell it may
    // pass, so a start walks only the groups whose first cell is in the frame, reachable and
    // not drivable.
    let limit = frame.width.max(frame.height) as f64 + 1.0;
    let mut by_step: [WalkTree; 4] = Default::default();
    let mut keyed: Vec<usize> = Vec::new();
    for (k, d) in dirs.iter().enumerate() {
        match uniform_walk(*d, limit) {
            Some(walk) => {
                if let Some(&first) = walk.first() {
                    let n = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                        .iter()
                        .position(|&s| s == first)
                        .expect("a walk steps to a 4-neighbour");
                    by_step[n].insert(walk.into_iter().map(padded));
                }
            }
            None => keyed.push(k),
        }
    }
    (by_step.map(|t| t.preorder()), keyed)
}

/// A key of a walk of [`KeyedWalks`].
type WalkKey = (i32, i32, u64, u64);

/// The directions whose walk depends on the start, with the walks each has met.
struct KeyedWalks<'a> {
    dirs: &'a [[f64; 2]],
    /// The directions (by index).
    keyed: Vec<usize>,
    /// The padded frame's width.
    pw: usize,
    /// Per direction, its walks met so far with their keys.
    walks: Vec<Vec<(WalkKey, Vec<isize>)>>,
    /// Scratch for a new walk.
    steps: Vec<isize>,
}

impl KeyedWalks<'_> {
    /// Marks the cells the rays of these directions from cell `c` (index `start` on the padded
    /// frame) see.
    fn mark(&mut self, class: &[u8], marked: &mut [bool], c: Cell, start: usize) {
        // The walk of the others from the centre of a cell depends only on the end point's
        // offset from the start in cells and on the extent `b - a` `SegmentCells` computes (the
        // start's fraction is always one half): each direction keeps the walks it has met under
        // that key.
        const WALKS_PER_DIRECTION: usize = 64;
        let (dirs, pw) = (self.dirs, self.pw);
        let padded = |d: (i32, i32)| padded_offset(d, pw);
        for &k in &self.keyed {
            let a = [c.x as f64 + 0.5, c.y as f64 + 0.5];
            let b = [a[0] + dirs[k][0], a[1] + dirs[k][1]];
            if !(b[0].is_finite() && b[1].is_finite()) {
                // No cells at all.
                continue;
            }
            let key = (
                crate::geom::floor_i32(b[0]).wrapping_sub(c.x),
                crate::geom::floor_i32(b[1]).wrapping_sub(c.y),
                (b[0] - a[0]).to_bits(),
                (b[1] - a[1]).to_bits(),
            );
            match self.walks[k].iter().find(|(kk, _)| *kk == key) {
                Some((_, walk)) => mark_along(class, marked, start, walk),
                None => {
                    self.steps.clear();
                    let mut prev = c;
                    for cell in crate::mapping::ray::SegmentCells::new(a, b).skip(1) {
                        self.steps.push(padded((cell.x - prev.x, cell.y - prev.y)));
                        prev = cell;
                    }
                    mark_along(class, marked, start, &self.steps);
                    if self.walks[k].len() < WALKS_PER_DIRECTION {
                        self.walks[k].push((key, self.steps.clone()));
                    }
                }
            }
        }
    }
}

/// How many rays [`explorable_free`] casts from each cell of the drivable region's boundary.
const RAYS: usize = 720;

/// The [`RAYS`] rays' extents (cells) for a range of `range_cells`, evenly spaced from angle 0.
fn ray_directions(range_cells: f64) -> Vec<[f64; 2]> {
    (0..RAYS)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / RAYS as f64;
            [a.cos() * range_cells, a.sin() * range_cells]
        })
        .collect()
}

/// Where [`explorable_free`]'s drivable region grows from: the start's cell when the robot fits
/// there, else the cell nearest to it where it fits (lowest index on ties); none when it fits
/// nowhere.
fn drive_seed(roomy: &Bitmap, start: Vec2) -> Option<Cell> {
    let frame = roomy.frame;
    let start_cell = frame.cell_from_world(start);
    if roomy.get(start_cell) == Some(&true) {
        return Some(start_cell);
    }
    let mut best: Option<(i64, usize)> = None;
    for (i, &r) in roomy.data.iter().enumerate() {
        if r {
            let c = frame.cell_of_index(i);
            let (dx, dy) = ((c.x - start_cell.x) as i64, (c.y - start_cell.y) as i64);
            let d = dx * dx + dy * dy;
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, i));
            }
        }
    }
    best.map(|(_, i)| frame.cell_of_index(i))
}

/// The largest squared distance (in cells²) [`within_sq`] is used for; beyond it
/// [`explorable_free`] takes the distance transform.
const MAX_WINDOW_SQ: u64 = 64 * 64;

/// The distance (in cells) of a squared distance, rounded as [`distance_to`] rounds it.
fn distance_of_sq(d2: u64) -> f64 {
    (d2 as f64).sqrt() as f32 as f64
}

/// For every cell of `mask`'s frame (row-major), whether a true cell of `mask` lies at a
/// squared distance (in cells², between centres) of at most `t` (none for `None`): the
/// distance along its column to the nearest true cell, capped beyond `sqrt(t)`, then the
/// nearest over the columns within `sqrt(t)`.
fn within_sq(mask: &Bitmap, t: Option<u64>) -> Vec<bool> {
    let (w, h) = (mask.frame.width as usize, mask.frame.height as usize);
    let Some(t) = t.filter(|_| w * h > 0) else {
        return vec![false; w * h];
    };
    // The largest r with r * r <= t.
    let r = (0..=t).take_while(|&r| r * r <= t).last().unwrap_or(0) as usize;
    // (In 16-bit lanes when the squared distances fit, twice as many per vector instruction as
    // 32-bit ones: the same comparisons of the same whole numbers.)
    if (r as u64 + 1).pow(2) <= u16::MAX as u64 && t <= u16::MAX as u64 {
        within_sq_in::<u16>(mask, w, h, t, r)
    } else {
        within_sq_in::<u32>(mask, w, h, t, r)
    }
}

/// The whole numbers [`within_sq`] computes in.
trait Lane:
    Copy + Ord + std::ops::Add<Output = Self> + std::ops::Mul<Output = Self> + TryFrom<u64>
{
    fn of(v: u64) -> Self {
        Self::try_from(v).ok().expect("checked to fit")
    }
}
impl Lane for u16 {}
impl Lane for u32 {}

fn within_sq_in<T: Lane>(mask: &Bitmap, w: usize, h: usize, t: u64, r: usize) -> Vec<bool> {
    let cap = T::of(r as u64 + 1);
    let (zero, one) = (T::of(0), T::of(1));
    // Down the columns, then up: the distance to the nearest true cell along the column.
    let mut g: Vec<T> = mask
        .data
        .iter()
        .map(|&m| if m { zero } else { cap })
        .collect();
    for y in 1..h {
        let (above, row) = g.split_at_mut(y * w);
        for (v, &a) in row[..w].iter_mut().zip(&above[(y - 1) * w..]) {
            *v = (*v).min(a + one);
        }
    }
    for y in (0..h - 1).rev() {
        let (row, below) = g.split_at_mut((y + 1) * w);
        for (v, &b) in row[y * w..].iter_mut().zip(&below[..w]) {
            *v = (*v).min(b + one);
        }
    }
    // Squared, then along the rows: a true cell within `t` lies in a column `dx <= r` away.
    for v in &mut g {
        *v = *v * *v;
    }
    let mut out = vec![false; w * h];
    for (row, near) in g.chunks_exact(w).zip(out.chunks_exact_mut(w)) {
        for dx in 0..=r.min(w - 1) {
            let limit = T::of(t - (dx * dx) as u64);
            for (n, &v) in near[..w - dx].iter_mut().zip(&row[dx..]) {
                *n |= v <= limit;
            }
            for (n, &v) in near[dx..].iter_mut().zip(&row[..w - dx]) {
                *n |= v <= limit;
            }
        }
    }
    out
}

/// What a ray of [`explorable_free`] does on entering a cell: pass on, stop before it, or mark
/// it and stop.
const RAY_PASS: u8 = 0;
const RAY_STOP: u8 = 1;
const RAY_LAST: u8 = 2;

/// Marks the cells a ray from `start` enters by the steps of `walk` (index offsets on the
/// frame of `class`), up to where `class` stops it.
fn mark_along(class: &[u8], marked: &mut [bool], start: usize, walk: &[isize]) {
    let mut j = start;
    for &s in walk {
        j = j.wrapping_add_signed(s);
        match class[j] {
            RAY_PASS => marked[j] = true,
            RAY_LAST => {
                marked[j] = true;
                break;
            }
            _ => break,
        }
    }
}

/// Walks from one start merged where they share their first steps: a tree whose nodes are
/// cells (index offsets from the start) and whose root is the start.
#[derive(Debug, Default)]
struct WalkTree {
    /// Per node: its offset from the start and its children.
    nodes: Vec<(isize, Vec<usize>)>,
}

impl WalkTree {
    /// Adds the walk taking the steps `steps` (index offsets from cell to cell).
    fn insert(&mut self, steps: impl IntoIterator<Item = isize>) {
        if self.nodes.is_empty() {
            self.nodes.push((0, Vec::new()));
        }
        let mut node = 0;
        for step in steps {
            let offset = self.nodes[node].0 + step;
            node = match self.nodes[node]
                .1
                .iter()
                .copied()
                .find(|&c| self.nodes[c].0 == offset)
            {
                Some(c) => c,
                None => {
                    self.nodes.push((offset, Vec::new()));
                    let c = self.nodes.len() - 1;
                    self.nodes[node].1.push(c);
                    c
                }
            };
        }
    }

    /// The nodes below the root in preorder, each as its offset and the position past its
    /// subtree in that order.
    fn preorder(&self) -> Vec<(isize, usize)> {
        let mut out: Vec<(isize, usize)> = Vec::new();
        // (node, position of its entry in `out` once its subtree is done)
        let mut stack: Vec<(usize, Option<usize>)> = self
            .nodes
            .first()
            .map(|root| root.1.iter().rev().map(|&c| (c, None)).collect())
            .unwrap_or_default();
        while let Some((node, done)) = stack.pop() {
            match done {
                Some(at) => out[at].1 = out.len(),
                None => {
                    out.push((self.nodes[node].0, 0));
                    stack.push((node, Some(out.len() - 1)));
                    stack.extend(self.nodes[node].1.iter().rev().map(|&c| (c, None)));
                }
            }
        }
        out
    }
}

/// The walk of [`crate::mapping::ray::SegmentCells`] from the centre of a cell to that centre
/// plus `d`, as the steps from cell to cell, when it is the same from the centre of every cell
/// with coordinates from 0 to below `limit`; `None` when it may depend on the cell.
///
/// From the centre `a` of a cell, the walk ends at the cell of `a + d` and steps along the axis
/// whose next cell boundary comes first: after `n` steps along an axis, the next boundary is
/// `(n + 1/2) / |extent|` of the way along. With coordinates below 2^24 and extents below
/// 10^6 cells, the rounding of `b = a + d`, of the extent `b - a` that `SegmentCells` computes
/// and of its running sums changes the end point by less than 2^-28 cells and these fractions
/// by less than 10^-8 of their size. So where every end coordinate `1/2 + d` is at least 10^-6
/// from a whole number and every comparison differs by more than 10^-7 of the larger, the walk
/// is the same from every cell. Ties (45 degrees) go to x in `SegmentCells` and are left to it.
fn uniform_walk(d: [f64; 2], limit: f64) -> Option<Vec<(i32, i32)>> {
    const MARGIN: f64 = 1e-6;
    const RELATIVE: f64 = 1e-7;
    const MAX_STEPS: f64 = 1e6;
    let [dx, dy] = d;
    if !(dx.is_finite()
        && dy.is_finite()
        && limit + dx.abs() + dy.abs() < (1u32 << 24) as f64
        && dx.abs() + dy.abs() < MAX_STEPS)
    {
        return None;
    }
    // The end cell's offset from the start along an axis.
    let end = |e: f64| {
        let v = 0.5 + e;
        let f = v.floor();
        (v - f >= MARGIN && f + 1.0 - v >= MARGIN).then_some(f as i32)
    };
    let (ex, ey) = (end(dx)?, end(dy)?);
    let (sx, sy) = (ex.signum(), ey.signum());
    let (mut x, mut y) = (0, 0);
    let mut walk = Vec::with_capacity((ex.unsigned_abs() + ey.unsigned_abs()) as usize);
    while (x, y) != (ex, ey) {
        let go_x = if x == ex {
            false
        } else if y == ey {
            true
        } else {
            let tx = (x.unsigned_abs() as f64 + 0.5) / dx.abs();
            let ty = (y.unsigned_abs() as f64 + 0.5) / dy.abs();
            if (tx - ty).abs() <= RELATIVE * tx.max(ty) {
                return None;
            }
            tx < ty
        };
        let step = if go_x { (sx, 0) } else { (0, sy) };
        x += step.0;
        y += step.1;
        walk.push(step);
    }
    Some(walk)
}

/// The true cells of `free` in a gap of one or two cells: along the row or the column through
/// the cell, at most two true cells lie between false ones (outside counts as false). Rays
/// walk 4-connected, so they never pass between cells that touch only at a corner.
fn narrow_gaps(free: &Bitmap) -> Bitmap {
    let frame = free.frame;
    let (w, h) = (frame.width as usize, frame.height as usize);
    // The mask with two false cells around it, so that every cell's neighbours up to two cells
    // away along its row and column are plain offsets. A cell is in a gap along a line when
    // the free cells next to it on that line, on both sides and up to two away, number at most
    // one: neither neighbour free, or one free with the cell beyond it not.
    let pw = w + 4;
    let mut padded = vec![false; pw * (h + 4)];
    for y in 0..h {
        padded[(y + 2) * pw + 2..][..w].copy_from_slice(&free.data[y * w..][..w]);
    }
    let at = |k: usize| &padded[k..];
    let mut out = Bitmap::filled(frame, false);
    for y in 0..h {
        let c = (y + 2) * pw + 2;
        let (l2, l1, r1, r2) = (at(c - 2), at(c - 1), at(c + 1), at(c + 2));
        let (d2, d1, u1, u2) = (at(c - 2 * pw), at(c - pw), at(c + pw), at(c + 2 * pw));
        let gap = |a2: bool, a1: bool, b1: bool, b2: bool| (!a1 | !a2) & (!b1 | !b2) & !(a1 & b1);
        for (x, o) in out.data[y * w..][..w].iter_mut().enumerate() {
            *o =
                padded[c + x] & (gap(l2[x], l1[x], r1[x], r2[x]) | gap(d2[x], d1[x], u1[x], u2[x]));
        }
    }
    out
}

/// Cells of `mask` 4-connected to `seed` (empty when `seed` is not in `mask`).
pub fn flood_fill(mask: &Bitmap, seed: Cell) -> Bitmap {
    let frame = mask.frame;
    let mut out = Bitmap::filled(frame, false);
    if mask.get(seed) != Some(&true) {
        return out;
    }
    // On the frame padded by a cell that is never filled, so that a cell's four neighbours are
    // plain offsets. (Which cells are filled does not depend on the order they are reached.)
    let (w, h) = (frame.width as usize, frame.height as usize);
    let pw = w + 2;
    let mut open = vec![false; pw * (h + 2)];
    for y in 0..h {
        open[(y + 1) * pw + 1..][..w].copy_from_slice(&mask.data[y * w..][..w]);
    }
    let first = (seed.y as usize + 1) * pw + seed.x as usize + 1;
    open[first] = false;
    let mut stack = vec![first];
    while let Some(i) = stack.pop() {
        for j in [i + 1, i - 1, i + pw, i - pw] {
            if open[j] {
                open[j] = false;
                stack.push(j);
            }
        }
    }
    // Filled: the cells of the mask no longer open.
    for y in 0..h {
        let row = &open[(y + 1) * pw + 1..][..w];
        for ((o, &m), &still) in out.data[y * w..][..w]
            .iter_mut()
            .zip(&mask.data[y * w..])
            .zip(row)
        {
            *o = m & !still;
        }
    }
    out
}

/// Boundary of a solid raster as merged segments. Outside the grid counts as solid.
fn raster_boundary(solid: &Bitmap) -> Vec<Segment> {
    let f = solid.frame;
    let (w, h) = (f.width as i32, f.height as i32);
    let wu = w as usize;
    // Rows -1..=h, outside the grid solid: row y of the grid is `rows[y + 1]`.
    let all_solid = vec![true; wu];
    let row = |y: i32| -> &[bool] {
        if y < 0 || y >= h {
            &all_solid
        } else {
            &solid.data[y as usize * wu..][..wu]
        }
    };
    let corner = |x: i32, y: i32| f.origin_m + Vec2::new(x as f64, y as f64) * f.resolution_m;
    let mut out = Vec::new();
    // Horizontal edges on the line y (between rows y-1 and y). Orientation matters for merging:
    // a run continues only while the same side is solid.
    for y in 0..=h {
        let (below_row, above_row) = (row(y - 1), row(y));
        let mut run: Option<(i32, bool)> = None;
        for x in 0..=w {
            let edge = if x < w {
                let (below, above) = (below_row[x as usize], above_row[x as usize]);
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
    // Vertical edges on the line x (between columns x-1 and x), column after column, each from
    // the bottom up: found row by row (the rows are contiguous), each column's runs kept apart.
    let mut runs: Vec<Option<(i32, bool)>> = vec![None; wu + 1];
    let mut columns: Vec<Vec<Segment>> = vec![Vec::new(); wu + 1];
    for y in 0..=h {
        let r = row(y);
        for x in 0..=w {
            let edge = if y < h {
                let left = x > 0 && r[x as usize - 1] || x == 0;
                let right = x == w || r[x as usize];
                (left != right).then_some(left)
            } else {
                None
            };
            let run = &mut runs[x as usize];
            match (*run, edge) {
                (Some((_, o)), Some(e)) if o == e => {}
                (Some((y0, _)), e) => {
                    columns[x as usize].push(Segment::new(corner(x, y0), corner(x, y)));
                    *run = e.map(|e| (y, e));
                }
                (None, Some(e)) => *run = Some((y, e)),
                (None, None) => {}
            }
        }
    }
    out.extend(columns.into_iter().flatten());
    out
}

/// Sets every cell whose centre lies inside `poly` (even-odd rule) to `value`.
pub fn fill_polygon(mask: &mut Bitmap, poly: &Polygon, value: bool) {
    let frame = mask.frame;
    for_runs_in_polygon(frame, poly, |run| mask.data[run].fill(value));
}

/// Calls `visit` with the row-major index of every cell of `f` whose centre lies inside `poly`
/// (even-odd rule), touching only the polygon's rows.
pub(crate) fn for_cells_in_polygon(f: GridFrame, poly: &Polygon, mut visit: impl FnMut(usize)) {
    for_runs_in_polygon(f, poly, |run| run.for_each(&mut visit));
}

/// [`for_cells_in_polygon`] by runs: `visit` gets the row-major indices of each run of cells
/// along a row, in the same order.
pub(crate) fn for_runs_in_polygon(
    f: GridFrame,
    poly: &Polygon,
    mut visit: impl FnMut(std::ops::Range<usize>),
) {
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
            if cx0 <= cx1 {
                visit(row + cx0 as usize..row + cx1 as usize + 1);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::OccupancyGrid;

    /// Two rooms of 12 x 12 cells (0.05 m) side by side, the wall between them open over
    /// `opening` cells in its middle; `.` free, `#` solid. Row 0 is the top.
    fn rooms_with_opening(opening: usize) -> Bitmap {
        let (w, h) = (27usize, 14usize);
        let frame = GridFrame::new(Vec2::zeros(), 0.05, w as u32, h as u32);
        let mut b = Bitmap::filled(frame, false);
        let top = (h - opening) / 2;
        for y in 1..h - 1 {
            for x in 1..w - 1 {
                let in_wall = x == 13 && !(top..top + opening).contains(&y);
                b.set(Cell::new(x as i32, y as i32), !in_wall);
            }
        }
        b
    }

    fn cells_in(b: &Bitmap, xs: std::ops::Range<i32>) -> usize {
        b.iter().filter(|(c, &v)| v && xs.contains(&c.x)).count()
    }

    /// What a robot of radius 0.1 m (4 cells across) with a 1 m laser, started in the left
    /// room, can explore of the right one: all of it through an opening it fits through,
    /// part of it (what is in sight through the gap) through one it does not fit through, and
    /// nothing beyond a one- or two-cell gap (the speckle of a scanned map).
    #[test]
    fn explorable_space_is_what_the_laser_sees_from_where_the_body_fits() {
        let start = Vec2::new(0.3, 0.35);
        let right = 14..26;
        // (opening in cells, right room cells explorable: min, max)
        let cases = [(6, 144, 144), (4, 20, 143), (2, 0, 0), (1, 0, 0), (0, 0, 0)];
        for (opening, min, max) in cases {
            let free = rooms_with_opening(opening);
            let reachable = flood_fill(&free, free.frame.cell_from_world(start));
            let e = explorable_free(&reachable, start, 0.1, 1.0);
            let got = cells_in(&e, right.clone());
            assert!(
                (min..=max).contains(&got),
                "opening {opening}: {got} cells of the right room, expected {min}..={max}"
            );
            // The left room is explorable whole; nothing outside the reachable free space is.
            assert_eq!(cells_in(&e, 1..13), 144, "opening {opening}");
            assert!(e.data.iter().zip(&reachable.data).all(|(&e, &r)| !e || r));
        }
        // No room for the body anywhere: the reachable free space as it is.
        let free = rooms_with_opening(4);
        let reachable = flood_fill(&free, free.frame.cell_from_world(start));
        assert_eq!(explorable_free(&reachable, start, 0.5, 1.0), reachable);
    }

    /// [`raster_boundary`] as first written: every edge looked up by cell, columns scanned one
    /// by one.
    fn raster_boundary_reference(solid: &Bitmap) -> Vec<Segment> {
        let f = solid.frame;
        let (w, h) = (f.width as i32, f.height as i32);
        let is_solid = |x: i32, y: i32| solid.get(Cell::new(x, y)).copied().unwrap_or(true);
        let corner = |x: i32, y: i32| f.origin_m + Vec2::new(x as f64, y as f64) * f.resolution_m;
        let mut out = Vec::new();
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

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]
        /// The same segments in the same order (the laser's BVH is built from them in order).
        #[test]
        fn raster_boundary_equals_its_first_form(
            cells in proptest::collection::vec(proptest::bool::weighted(0.4), 24 * 20),
            w in 0u32..24, h in 0u32..20, res in 0.01f64..1.0, ox in -5.0f64..5.0,
        ) {
            let frame = GridFrame::new(Vec2::new(ox, -ox / 3.0), res, w, h);
            let solid = Bitmap { frame, data: cells[..frame.len()].to_vec() };
            proptest::prop_assert_eq!(raster_boundary(&solid), raster_boundary_reference(&solid));
        }
    }

    /// [`flood_fill`] as first written: cells on a stack, each neighbour looked up by cell.
    fn flood_fill_reference(mask: &Bitmap, seed: Cell) -> Bitmap {
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

    /// [`narrow_gaps`] as first written: the runs counted cell by cell.
    fn narrow_gaps_reference(free: &Bitmap) -> Bitmap {
        let frame = free.frame;
        let is_free = |c: Cell| free.get(c).copied().unwrap_or(false);
        let mut out = Bitmap::filled(frame, false);
        for i in 0..free.data.len() {
            if !free.data[i] {
                continue;
            }
            let c = frame.cell_of_index(i);
            out.data[i] = [(1, 0), (0, 1)].iter().any(|&(dx, dy)| {
                let run = |sign: i32| {
                    (1..=2)
                        .take_while(|&k| {
                            is_free(Cell::new(c.x + sign * k * dx, c.y + sign * k * dy))
                        })
                        .count()
                };
                1 + run(1) + run(-1) <= 2
            });
        }
        out
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]
        /// Flood fill and narrow gaps on masks of every density and shape (one row or column
        /// included), from any seed, in or out of the mask.
        #[test]
        fn flood_fill_and_narrow_gaps_equal_their_first_forms(
            cells in proptest::collection::vec(proptest::bool::weighted(0.6), 24 * 20),
            w in 1u32..24, h in 1u32..20, sx in -1i32..25, sy in -1i32..21,
        ) {
            let frame = GridFrame::new(Vec2::zeros(), 0.1, w, h);
            let mask = Bitmap { frame, data: cells[..frame.len()].to_vec() };
            let seed = Cell::new(sx, sy);
            proptest::prop_assert_eq!(flood_fill(&mask, seed), flood_fill_reference(&mask, seed));
            proptest::prop_assert_eq!(narrow_gaps(&mask), narrow_gaps_reference(&mask));
        }
    }

    /// [`explorable_free`] as it was before its rays were grouped by first step and their walks
    /// shared: every ray from every boundary cell walked with `SegmentCells`.
    fn explorable_free_oracle(
        reachable: &Bitmap,
        start: Vec2,
        robot_radius_m: f64,
        range_m: f64,
    ) -> Bitmap {
        let frame = reachable.frame;
        let res = frame.resolution_m;
        let solid = Bitmap {
            frame,
            data: reachable.data.iter().map(|f| !f).collect(),
        };
        let dist = distance_to(&solid);
        let need_cells = robot_radius_m / res + std::f64::consts::FRAC_1_SQRT_2;
        let roomy = Bitmap {
            frame,
            data: dist.data.iter().map(|&d| d as f64 >= need_cells).collect(),
        };
        // (Where the drivable region starts did not change: shared with the code under test.)
        let Some(seed) = drive_seed(&roomy, start) else {
            return reachable.clone();
        };
        let drivable = flood_fill_reference(&roomy, seed);
        // Seen from inside the disc: within the body's radius of a drivable cell.
        let to_drivable = distance_to(&drivable);
        let body_cells = robot_radius_m / res;
        let mut seen = Bitmap {
            frame,
            data: to_drivable
                .data
                .iter()
                .zip(&reachable.data)
                .map(|(&d, &f)| f && (d as f64) <= body_cells)
                .collect(),
        };
        // Rays from the drivable region's boundary.
        let narrow = narrow_gaps_reference(reachable);
        let dirs = ray_directions(range_m / res);
        for i in 0..drivable.data.len() {
            if !drivable.data[i] {
                continue;
            }
            let c = frame.cell_of_index(i);
            if c.neighbours4()
                .iter()
                .all(|&n| drivable.get(n) == Some(&true))
            {
                continue;
            }
            let a = [c.x as f64 + 0.5, c.y as f64 + 0.5];
            for d in &dirs {
                let b = [a[0] + d[0], a[1] + d[1]];
                for cell in crate::mapping::ray::SegmentCells::new(a, b).skip(1) {
                    let Some(j) = frame.index(cell) else { break };
                    if !reachable.data[j] || drivable.data[j] {
                        break;
                    }
                    seen.data[j] = true;
                    if narrow.data[j] {
                        break;
                    }
                }
            }
        }
        seen
    }

    /// A `w` x `h` raster at `res` m per cell, free where `free` says, and a start at the
    /// centre of the free cell `pick` (modulo the free cells), with the free cells 4-connected
    /// to it.
    fn reachable_from(w: u32, h: u32, res: f64, free: &[bool], pick: usize) -> (Bitmap, Vec2) {
        let frame = GridFrame::new(Vec2::new(-1.3, 2.1), res, w, h);
        let mask = Bitmap {
            frame,
            data: free.iter().copied().take(frame.len()).collect(),
        };
        let free_cells: Vec<usize> = (0..frame.len()).filter(|&i| mask.data[i]).collect();
        let i = free_cells[pick % free_cells.len()];
        let start = frame.world_from_cell(frame.cell_of_index(i));
        (flood_fill(&mask, frame.cell_of_index(i)), start)
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(128))]
        /// Random rasters (mostly free, speckled with solid cells), any start, body and range
        /// (down to less than a cell, where a ray's first step depends on rounding).
        #[test]
        fn explorable_free_equals_its_oracle_on_random_rasters(
            free in proptest::collection::vec(proptest::bool::weighted(0.85), 48 * 40),
            w in 8u32..48, h in 8u32..40, pick in 0usize..10_000,
            res in proptest::prop_oneof![proptest::strategy::Just(0.05), 0.02f64..0.3],
            radius in 0.0f64..0.3, range in proptest::prop_oneof![0.0f64..0.2, 0.0f64..4.0],
        ) {
            let mut free = free;
            // At least one free cell to start from.
            free[0] = true;
            let (reachable, start) = reachable_from(w, h, res, &free, pick);
            proptest::prop_assert_eq!(
                explorable_free(&reachable, start, radius, range),
                explorable_free_oracle(&reachable, start, radius, range)
            );
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(32))]
        /// Generated buildings at 0.05 m and 0.1 m, the explorer's body and a short laser.
        #[test]
        fn explorable_free_equals_its_oracle_on_generated_buildings(
            seed in 0u64..1000, area in 60.0f64..250.0, office: bool,
            res in proptest::prop_oneof![proptest::strategy::Just(0.05), proptest::strategy::Just(0.1)],
            radius in 0.1f64..0.35, range in 0.5f64..6.0,
        ) {
            let b = crate::generate::generate(&crate::generate::GenerateConfig {
                seed,
                area_m2: area,
                kind: if office {
                    crate::generate::BuildingKind::Office
                } else {
                    crate::generate::BuildingKind::School
                },
                ..Default::default()
            });
            let start = b.default_start(0.2).unwrap().0.position();
            let frame = GridFrame::covering(&b.bounds(), res, 1.0);
            let reachable = b.reachable_free(frame, start);
            let got = explorable_free(&reachable, start, radius, range);
            proptest::prop_assert_eq!(&got, &explorable_free_oracle(&reachable, start, radius, range));
            // More than the body's disc around the start: rays were cast.
            proptest::prop_assert!(got.count_true() > 100);
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(128))]
        /// A raster's free mask on another frame (offset, finer, coarser, larger or smaller than
        /// the raster) is `is_free` of every cell centre.
        #[test]
        fn raster_free_mask_on_another_frame_is_is_free_of_every_centre(
            solid in proptest::collection::vec(proptest::bool::weighted(0.3), 30 * 20),
            w in 1u32..30, h in 1u32..20,
            res in proptest::prop_oneof![proptest::strategy::Just(0.05), 0.01f64..0.5],
            fres in proptest::prop_oneof![proptest::strategy::Just(0.05), 0.01f64..0.5],
            ox in -2.0f64..2.0, oy in -2.0f64..2.0, fw in 0u32..60, fh in 0u32..40,
        ) {
            let frame = GridFrame::new(Vec2::new(0.3, -0.7), res, w, h);
            let b = Building {
                name: "r".into(),
                geometry: Geometry::Raster {
                    solid: Bitmap { frame, data: solid[..frame.len()].to_vec() },
                },
                rooms: vec![],
                doors: vec![],
                start: None,
            };
            let other = GridFrame::new(Vec2::new(0.3 + ox, -0.7 + oy), fres, fw, fh);
            let expected: Vec<bool> = (0..other.len())
                .map(|i| b.is_free(other.world_from_cell(other.cell_of_index(i))))
                .collect();
            proptest::prop_assert_eq!(b.free_mask(other).data, expected);
        }
    }

    /// The walks `uniform_walk` gives for every direction at ranges around half a cell, a cell
    /// and the explorer's, from cells near the origin and far out, are `SegmentCells`'s.
    #[test]
    fn a_uniform_walk_is_the_walk_from_every_cell() {
        let limit = 70_001.0;
        let (mut sure, mut unsure) = (0, 0);
        let ranges = [
            0.3,
            0.5,
            0.5 + 1e-7,
            std::f64::consts::FRAC_1_SQRT_2 - 1e-7,
            1.0,
            1.5,
            7.3,
            120.0,
            2000.0,
        ];
        for range in ranges {
            for k in 0..720 {
                let a = k as f64 * std::f64::consts::TAU / 720.0;
                let d = [a.cos() * range, a.sin() * range];
                let Some(walk) = uniform_walk(d, limit) else {
                    unsure += 1;
                    continue;
                };
                sure += 1;
                for (x, y) in [
                    (0, 0),
                    (1, 7),
                    (13, 2),
                    (1023, 1024),
                    (4095, 3),
                    (70_000, 69_999),
                ] {
                    let a = [x as f64 + 0.5, y as f64 + 0.5];
                    let cells: Vec<Cell> =
                        crate::mapping::ray::SegmentCells::new(a, [a[0] + d[0], a[1] + d[1]])
                            .collect();
                    let steps: Vec<(i32, i32)> = cells
                        .windows(2)
                        .map(|p| (p[1].x - p[0].x, p[1].y - p[0].y))
                        .collect();
                    assert_eq!(steps, walk, "range {range} k {k} from ({x}, {y})");
                }
            }
        }
        // About 45 degrees, or an end about a cell boundary: a few directions per range.
        assert!((8..9 * 40).contains(&unsure), "{unsure}");
        assert!(sure > 9 * 600, "{sure}");
        assert_eq!(uniform_walk([1e30, 0.0], limit), None);
        assert_eq!(uniform_walk([f64::NAN, 0.0], limit), None);
        assert_eq!(uniform_walk([0.2, -0.3], limit), Some(vec![]));
    }

    /// `WalkTree` in preorder: shared first steps once, each node's skip past its subtree.
    #[test]
    fn a_walk_tree_merges_shared_first_steps() {
        let mut t = WalkTree::default();
        t.insert([1, 1, 10]);
        t.insert([1, 1, -10]);
        t.insert([1, 10]);
        // Offsets 1, 2, 12, -8 (below 2), 11 (below 1).
        assert_eq!(
            t.preorder(),
            vec![(1, 5), (2, 4), (12, 3), (-8, 4), (11, 5)]
        );
        assert!(WalkTree::default().preorder().is_empty());
    }

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
        let (p, src) = b.default_start(0.2).unwrap();
        assert_eq!(src, StartSource::LargestClearance);
        assert!(b.check_start(p, 0.2).is_ok());
        assert_eq!(b.default_start(0.2).unwrap().0, p);
    }

    fn vector(outline: Polygon, solids: Vec<Polygon>) -> Building {
        Building {
            name: "v".into(),
            geometry: Geometry::Vector { outline, solids },
            rooms: vec![],
            doors: vec![],
            start: None,
        }
    }

    fn raster(ascii: &str, resolution_m: f64) -> Building {
        let g = OccupancyGrid::from_ascii(ascii, resolution_m);
        let solid = Bitmap {
            frame: g.frame,
            data: g
                .data
                .iter()
                .map(|s| *s != crate::grid::Occupancy::Free)
                .collect(),
        };
        Building {
            name: "r".into(),
            geometry: Geometry::Raster { solid },
            rooms: vec![],
            doors: vec![],
            start: None,
        }
    }

    #[test]
    fn the_default_start_is_the_point_farthest_from_solid_space_and_the_outside() {
        let rect = |x0, y0, x1, y1| Polygon::rect(Vec2::new(x0, y0), Vec2::new(x1, y1));
        let area = |x0, y0, x1, y1| [x0, y0, x1, y1];
        // (building, where the start must be [x0, y0, x1, y1], clearance at least m)
        let cases = [
            // An outline alone (60 m2): on its middle line (3 m from the outline).
            (
                vector(rect(0.0, 0.0, 10.0, 6.0), vec![]),
                area(2.95, 2.95, 7.05, 3.05),
                2.95,
            ),
            // BUILDING_FORMAT.md's example without its [start]: a wall along the bottom, half a
            // wall at x = 5 and a small solid. Measured on the bounding box alone, the point
            // farthest from every solid was a top corner; the outside is solid too.
            (
                vector(
                    rect(0.0, 0.0, 10.0, 6.0),
                    vec![
                        Polygon::thick_segment(Vec2::new(0.0, 0.0), Vec2::new(10.0, 0.0), 0.2),
                        Polygon::thick_segment(Vec2::new(5.0, 0.0), Vec2::new(5.0, 2.5), 0.2),
                        Polygon::new(vec![
                            Vec2::new(2.0, 2.0),
                            Vec2::new(2.5, 2.0),
                            Vec2::new(2.5, 2.5),
                        ]),
                    ],
                ),
                // Farthest from the right outline, the top and the inner wall's top corner.
                area(7.3, 3.3, 7.65, 3.65),
                2.45,
            ),
            // A raster whose free space reaches the raster's edge: the outside is solid, so the
            // start is inside the free 6 x 4 cells, not on their open edge.
            (
                raster(
                    "
                    ......
                    ......
                    ......
                    ......
                    ",
                    1.0,
                ),
                area(0.9, 0.9, 5.1, 3.1),
                1.49,
            ),
        ];
        for (i, (b, [x0, y0, x1, y1], min_clearance)) in cases.iter().enumerate() {
            let (p, src) = b
                .default_start(0.2)
                .unwrap_or_else(|e| panic!("case {i}: {e}"));
            assert_eq!(src, StartSource::LargestClearance);
            assert!(
                (*x0..=*x1).contains(&p.x_m) && (*y0..=*y1).contains(&p.y_m),
                "case {i}: {p:?}"
            );
            let c = b.clearance_at(p.position());
            assert!(c >= *min_clearance, "case {i}: clearance {c}");
            assert!(b.check_start(p, 0.2).is_ok(), "case {i}");
        }
    }

    #[test]
    fn a_building_without_room_for_the_robot_is_refused() {
        // A 0.3 m wide corridor: a 0.2 m robot (0.4 m across) does not fit anywhere.
        let narrow = vector(
            Polygon::rect(Vec2::new(0.0, 0.0), Vec2::new(5.0, 0.3)),
            vec![],
        );
        match narrow.default_start(0.2) {
            Err(StartError::NoRoom {
                needed_m,
                max_clearance_m,
            }) => {
                assert_eq!(needed_m, 0.2);
                assert!((max_clearance_m - 0.15).abs() < 0.03, "{max_clearance_m}");
            }
            other => panic!("{other:?}"),
        }
        assert!(narrow.default_start(0.1).is_ok());
        assert!(narrow.random_start(0.2, 1, 0).is_err());
        let all_solid = raster("\n###\n###\n", 1.0);
        assert_eq!(all_solid.default_start(0.2), Err(StartError::NoFreeSpace));
        // A file's start is returned as written: check_start judges it.
        let mut with_start = narrow.clone();
        with_start.start = Some(Pose::new(1.0, 0.15, 0.0));
        assert_eq!(with_start.default_start(0.2).unwrap().1, StartSource::File);
    }

    #[test]
    fn a_start_pose_is_checked_for_the_robots_body() {
        let b = two_rooms_vector();
        let r = 0.2;
        let cases = [
            (Pose::new(2.5, 3.0, 0.0), None),
            (Pose::new(2.5, 3.0, -std::f64::consts::TAU), None),
            (Pose::new(f64::NAN, 3.0, 0.0), Some("is not a finite pose")),
            (
                Pose::new(2.5, f64::INFINITY, 0.0),
                Some("is not a finite pose"),
            ),
            (Pose::new(2.5, 3.0, 1e300), Some("heading")),
            (Pose::new(2.5, 3.0, 7.0), Some("heading")),
            (Pose::new(-1.0, 3.0, 0.0), Some("not in free space")),
            (Pose::new(5.0, 1.0, 0.0), Some("not in free space")),
            // Free, but 0.15 m from the inner wall's face (x = 4.9).
            (Pose::new(4.75, 1.0, 0.0), Some("too close")),
            // 0.25 m from it: room for the body.
            (Pose::new(4.65, 1.0, 0.0), None),
        ];
        for (pose, want) in cases {
            let got = b.check_start(pose, r);
            match want {
                None => assert!(got.is_ok(), "{pose:?}: {got:?}"),
                Some(needle) => {
                    let e = got.expect_err("refused").to_string();
                    assert!(e.contains(needle), "{pose:?}: {e}");
                }
            }
        }
        // The suggestion has room for the body and is near the refused point.
        let near = b.nearest_start_position(Vec2::new(4.75, 1.0), r).unwrap();
        assert!(b.check_start(Pose::new(near.x, near.y, 0.0), r).is_ok());
        assert!((near - Vec2::new(4.75, 1.0)).norm() < 0.2, "{near:?}");
    }

    #[test]
    fn random_starts_are_free_connected_distinct_and_reproducible() {
        // Two rooms joined by a door, and a closed third room the robot cannot reach.
        let mut b = two_rooms_vector();
        if let Geometry::Vector { outline, solids } = &mut b.geometry {
            *outline = Polygon::rect(Vec2::new(0.0, 0.0), Vec2::new(14.0, 6.0));
            for [x0, y0, x1, y1] in [
                [10.0, 0.0, 10.0, 6.0],
                [10.0, 0.0, 14.0, 0.0],
                [14.0, 0.0, 14.0, 6.0],
                [10.0, 6.0, 14.0, 6.0],
            ] {
                solids.push(Polygon::thick_segment(
                    Vec2::new(x0, y0),
                    Vec2::new(x1, y1),
                    0.2,
                ));
            }
        }
        let r = 0.2;
        let sampler = StartSampler::new(&b, r).unwrap();
        let poses: Vec<Pose> = (0..200).map(|k| sampler.draw(7, k)).collect();
        let (mut left, mut right) = (0, 0);
        for p in &poses {
            assert!(b.check_start(*p, r).is_ok(), "{p:?}");
            assert!(b.clearance_at(p.position()) >= r + RANDOM_START_MARGIN_M - 0.01);
            assert!(p.x_m < 10.0, "in the closed room: {p:?}");
            assert!((-std::f64::consts::PI..std::f64::consts::PI).contains(&p.theta_rad));
            if p.x_m < 5.0 {
                left += 1;
            } else {
                right += 1;
            }
        }
        // Both rooms (about equal areas) are drawn from.
        assert!(left > 60 && right > 60, "{left} {right}");
        let distinct: std::collections::BTreeSet<(u64, u64)> = poses
            .iter()
            .map(|p| (p.x_m.to_bits(), p.y_m.to_bits()))
            .collect();
        assert!(distinct.len() > 150, "{}", distinct.len());
        // A pure function of building, radius, seed and index.
        assert_eq!(b.random_start(r, 7, 3).unwrap(), poses[3]);
        assert_ne!(b.random_start(r, 8, 3).unwrap(), poses[3]);
        // Headings cover the circle.
        assert!(
            poses.iter().any(|p| p.theta_rad < -2.0) && poses.iter().any(|p| p.theta_rad > 2.0)
        );
        // Another building draws other headings with the same seed and index (the building's
        // content is part of the draw), though its free space is the same.
        let mut other = b.clone();
        other.start = Some(Pose::new(2.5, 3.0, 0.0));
        assert_ne!(other.content_hash(), b.content_hash());
        let sampler = StartSampler::new(&other, r).unwrap();
        let same = (0..200)
            .filter(|&k| sampler.draw(7, k).theta_rad == poses[k as usize].theta_rad)
            .count();
        assert_eq!(same, 0);
    }

    #[test]
    fn raster_boundary_merges_runs() {
        let b = raster(
            "
            ######
            #....#
            #....#
            ######
            ",
            1.0,
        );
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
