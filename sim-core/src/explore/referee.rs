//! The referee: what only the simulation knows and the robot does not. It credits the explored
//! area against the building's ground truth (`credit_explored`, through `MapToWorld`, the pose
//! error of the moment), records the progress curve, judges how a run ended (`classify_end`),
//! scores the finished run (`finish`: map quality, rooms entered) and makes the oracle's true
//! layout (`true_layout`). Strategies see none of it.

use crate::mapping::ray::{grid_from_world, walk_segment};

use crate::explore::run::MapQuality;
use crate::geom::{Pose, Vec2};
use crate::grid::{Bitmap, Cell, GridFrame, Occupancy, OccupancyGrid};

/// What only the simulation knows: the building's ground truth on the map grid, and the
/// explored area credited against it.
#[derive(Clone)]
pub(super) struct Referee {
    /// Explorable free space of the building on the map grid (ground truth for the explored
    /// area and the rooms left unexplored).
    pub(super) truth: Bitmap,
    /// Free space connected to the start (ground truth for the map's quality).
    pub(super) free: Bitmap,
    pub(super) truth_cells: usize,
    /// Truth-free cells observed, kept incrementally. Observed means free or occupied in the
    /// map: a cell whose centre is free but which a wall surface crosses is rightly mapped
    /// occupied, and the boundary rows of every room would otherwise cap the fraction near 97 %.
    /// Building cells are credited through the map cells they were observed in: the map is drawn
    /// at the estimated pose, so a heading error made early (e.g. turning where the laser sees no
    /// wall) rotates everything mapped after it, and comparing map and building cell by cell
    /// would count a consistent but rotated map as unexplored far from the start. See
    /// [`Explorer::credit_explored`].
    pub(super) explored_cells: usize,
    /// Building cells credited as observed (world frame).
    pub(super) explored: Bitmap,
    /// Building cells found not creditable in the current update (all false between updates),
    /// and the list of them (see [`Explorer::credit_explored`]).
    pub(super) untestable: Bitmap,
    pub(super) untestable_list: Vec<usize>,
    /// Ground-truth room polygons (for the "rooms never entered" report, and the layout of the
    /// `layout-truth` oracle, its one door to the decision).
    pub(super) rooms: Vec<crate::geom::Polygon>,
    /// Ground-truth doors (world frame): the `layout-truth` oracle's layout is open there.
    pub(super) doors: Vec<(Vec2, Vec2)>,
}

impl Referee {
    /// The explored area credited so far (m2; the truth's grid is the map's).
    pub(super) fn explored_area_m2(&self) -> f64 {
        self.explored_cells as f64 * self.truth.frame.cell_area_m2()
    }

    /// Its share of the explorable area (0 when there is none).
    pub(super) fn explored_fraction(&self) -> f64 {
        if self.truth_cells == 0 {
            0.0
        } else {
            self.explored_cells as f64 / self.truth_cells as f64
        }
    }
}

/// The rigid motion taking a point of the map (drawn at the estimated pose) to where the sensor
/// observed it in the building (the true pose): `true ∘ estimate⁻¹`.
pub(super) struct MapToWorld {
    pub(super) motion: Pose,
    pub(super) inverse: Pose,
    /// `sin_cos` of the two motions' angles, computed once: the arithmetic is then exactly
    /// `Pose::compose`'s.
    pub(super) motion_sc: (f64, f64),
    pub(super) inverse_sc: (f64, f64),
}

impl MapToWorld {
    pub(super) fn new(estimate: &Pose, truth: &Pose) -> Self {
        let origin = Pose::new(0.0, 0.0, 0.0);
        let motion = truth.compose(&estimate.between(&origin));
        let inverse = estimate.compose(&truth.between(&origin));
        Self {
            motion_sc: motion.theta_rad.sin_cos(),
            inverse_sc: inverse.theta_rad.sin_cos(),
            motion,
            inverse,
        }
    }

    /// `pose.compose(p)`'s position, with `(s, c)` = `pose.theta_rad.sin_cos()`.
    pub(super) fn apply(pose: &Pose, (s, c): (f64, f64), p: Vec2) -> Vec2 {
        Vec2::new(pose.x_m + c * p.x - s * p.y, pose.y_m + s * p.x + c * p.y)
    }

    pub(super) fn forward(&self, p: Vec2) -> Vec2 {
        Self::apply(&self.motion, self.motion_sc, p)
    }

    pub(super) fn backward(&self, p: Vec2) -> Vec2 {
        Self::apply(&self.inverse, self.inverse_sc, p)
    }

    /// The building cells (index, cell; same frame) within `reach` cells of where map cell `c`
    /// lies in the building. [`Self::map_index_of`] gives the map cell each corresponds to.
    /// (`credit_explored` walks the same box row by row.)
    #[cfg(test)]
    pub(super) fn cells_near<'a>(
        &'a self,
        frame: &'a GridFrame,
        c: Cell,
        reach: i32,
    ) -> impl Iterator<Item = (usize, Cell)> + 'a {
        let w = self.building_cell_of(frame, c);
        (-reach..=reach)
            .flat_map(move |dy| (-reach..=reach).map(move |dx| Cell::new(w.x + dx, w.y + dy)))
            .filter_map(move |n| Some((frame.index(n)?, n)))
    }

    /// The building cell where map cell `c` lies.
    pub(super) fn building_cell_of(&self, frame: &GridFrame, c: Cell) -> Cell {
        frame.cell_from_world(self.forward(frame.world_from_cell(c)))
    }

    /// The map cell (index) the centre of building cell `n` falls in, `None` off the frame.
    pub(super) fn map_index_of(&self, frame: &GridFrame, n: Cell) -> Option<usize> {
        frame.index(frame.cell_from_world(self.backward(frame.world_from_cell(n))))
    }
}

/// The building's rooms as a complete layout in the map's frame (world positions brought back
/// through `to_map`, the current pose error): every room closed and fully known.
pub(super) fn true_layout(
    rooms: &[crate::geom::Polygon],
    to_map: &MapToWorld,
) -> crate::layout::Layout {
    let rooms = rooms
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let polygon =
                crate::geom::Polygon::new(p.vertices.iter().map(|v| to_map.backward(*v)).collect());
            let area_m2 = polygon.area_m2();
            crate::layout::LayoutRoom {
                id: k as u32,
                open_edges: vec![false; polygon.vertices.len()],
                observed_polygon: polygon.clone(),
                polygon,
                label: crate::layout::RoomLabel::Partial,
                predicted: false,
                area_m2,
                observed_area_m2: area_m2,
                unknown_area_m2: 0.0,
            }
        })
        .collect();
    crate::layout::Layout {
        rooms,
        lines: Vec::new(),
        diagnostics: Default::default(),
    }
}

/// How far either side of a door's line the oracle's layout walls are opened: through the wall
/// (the rooms' outlines run along its faces, or its centre line).
const DOOR_REACH_M: f64 = 0.3;

/// Opens the true layout's walls (`walls`, on `frame`) at the building's doors (world frame,
/// brought into the map's through `to_map`): the layout cells within the door's width and
/// [`DOOR_REACH_M`] of its line. A perfect layout knows its doorways, as a predicted one learns
/// them from the gaps it sees in walls; without this, the oracle's gain stops at a door the
/// robot has not yet seen open, and its early stop can leave a room behind it unexplored.
pub(super) fn open_true_doors(walls: &mut Bitmap, doors: &[(Vec2, Vec2)], to_map: &MapToWorld) {
    let frame = walls.frame;
    for &(a, b) in doors {
        let (a, b) = (to_map.backward(a), to_map.backward(b));
        let len = (b - a).norm();
        if len.is_nan() || len <= 1e-9 {
            continue;
        }
        let u = (b - a) / len;
        let mid = (a + b) * 0.5;
        let r = len / 2.0 + DOOR_REACH_M;
        let lo = frame.cell_from_world(mid - Vec2::new(r, r));
        let hi = frame.cell_from_world(mid + Vec2::new(r, r));
        for y in lo.y.max(0)..=hi.y.min(frame.height as i32 - 1) {
            for x in lo.x.max(0)..=hi.x.min(frame.width as i32 - 1) {
                let c = Cell::new(x, y);
                let d = frame.world_from_cell(c) - mid;
                if d.dot(&u).abs() <= len / 2.0 && (d.x * u.y - d.y * u.x).abs() <= DOOR_REACH_M {
                    walls.set(c, false);
                }
            }
        }
    }
}

/// Opens the true layout's walls (`walls`, on `frame`) wherever the building has no wall: the
/// cells of a room's outline (`layout`, in the map frame) from which the building's free space
/// (`free`, world frame, read through `to_map`) runs on across the outline for [`DOOR_REACH_M`]
/// on both sides. A plan's rooms often meet with no wall between them and no door listed there
/// (a corridor split into pieces, a hall open to a corridor: 100-136 m of such outline on some
/// vendored plans), and a door's outlines can lie farther from its line than the door's reach;
/// closed there, the true layout hides the room beyond, and the oracle's early stop, which sums
/// what the candidates would see through the layout's walls, can end the run with that room
/// unexplored while `baseline` drives in. An outline along a wall's face or centre line keeps
/// its wall: within the reach on one side the building is solid.
pub(super) fn open_where_free(
    walls: &mut Bitmap,
    layout: &crate::layout::Layout,
    free: &Bitmap,
    to_map: &MapToWorld,
) {
    let frame = walls.frame;
    let (steps, step_m) = reach_steps(&frame);
    let free_at = |p: Vec2| free.get(free.frame.cell_from_world(to_map.forward(p))) == Some(&true);
    for_outline_edges(layout, &frame, |cells, n| {
        for &c in cells {
            if walls.get(c) == Some(&true) {
                let p = frame.world_from_cell(c);
                if (-steps..=steps).all(|k| free_at(p + n * (f64::from(k) * step_m))) {
                    walls.set(c, false);
                }
            }
        }
    });
}

/// The steps across a room's outline within [`DOOR_REACH_M`] on `frame`: how many on each side,
/// and their length (m).
fn reach_steps(frame: &GridFrame) -> (i32, f64) {
    let steps = (DOOR_REACH_M / frame.resolution_m).ceil().max(1.0) as i32;
    (steps, DOOR_REACH_M / f64::from(steps))
}

/// Calls `f` with the cells on `frame` of each edge of each room's outline in `layout` (map
/// frame), in order along the edge, and the edge's unit normal; edges of no length are skipped.
fn for_outline_edges(
    layout: &crate::layout::Layout,
    frame: &GridFrame,
    mut f: impl FnMut(&[Cell], Vec2),
) {
    let mut cells = Vec::new();
    for room in &layout.rooms {
        for e in room.polygon.edges() {
            let d = e.b - e.a;
            let len = d.norm();
            if len.is_nan() || len <= 1e-9 {
                continue;
            }
            cells.clear();
            walk_segment(
                grid_from_world(frame, e.a),
                grid_from_world(frame, e.b),
                |c| {
                    cells.push(c);
                    true
                },
            );
            f(&cells, Vec2::new(-d.y, d.x) / len);
        }
    }
}

/// How long a stretch of a room's outline must run unseen along a frontier for the oracle's
/// layout to leave it open (see [`open_unseen_walls`]): longer than a doorway.
const UNSEEN_WALL_M: f64 = 1.0;

/// Opens the true layout's walls (`walls`, on the map's frame) where the robot has not seen
/// them and its view ends at them: the stretches, longer than [`UNSEEN_WALL_M`], of a room's
/// outline (`layout`, map frame) within [`DOOR_REACH_M`] of which, across the outline, the map
/// (`grid`) shows free space and unknown cells and no occupied cell. There a frontier runs
/// along a wall the laser only grazed, and a candidate stands on that wall: through the true
/// walls it sees along their face and nothing behind them, not even through a door beside it
/// (PineCondos, seed 2: 0.19 m² through the true walls from a candidate 0.2 m beside the door
/// of a room never seen, and the early stop left the room unexplored while `baseline` drove
/// there, saw the wall and went in). Left open, what lies behind such a stretch counts as the
/// baseline counts it until the robot has looked at the wall; walls the map shows keep
/// blocking, as the map's own occupied cells.
pub(super) fn open_unseen_walls(
    walls: &mut Bitmap,
    layout: &crate::layout::Layout,
    grid: &OccupancyGrid,
) {
    let frame = walls.frame;
    let (steps, step_m) = reach_steps(&frame);
    let longer = (UNSEEN_WALL_M / frame.resolution_m).ceil() as usize;
    let mut unseen = Vec::new();
    for_outline_edges(layout, &frame, |cells, n| {
        unseen.clear();
        unseen.extend(cells.iter().map(|&c| {
            let p = frame.world_from_cell(c);
            let (mut free, mut unknown) = (false, false);
            for k in -steps..=steps {
                match grid
                    .get(frame.cell_from_world(p + n * (f64::from(k) * step_m)))
                    .copied()
                {
                    Some(Occupancy::Occupied) => return false,
                    Some(Occupancy::Free) => free = true,
                    Some(Occupancy::Unknown) => unknown = true,
                    None => {}
                }
            }
            free && unknown
        }));
        let mut i = 0;
        while i < cells.len() {
            let j = (i..cells.len())
                .find(|&j| !unseen[j])
                .unwrap_or(cells.len());
            if j - i > longer {
                for c in &cells[i..j] {
                    walls.set(*c, false);
                }
            }
            i = j + 1;
        }
    });
}

pub(super) fn map_quality(map: &OccupancyGrid, truth_free: &Bitmap) -> MapQuality {
    let mut free = 0usize;
    let mut free_ok = 0usize;
    let mut occ = 0usize;
    let mut occ_ok = 0usize;
    for (i, s) in map.data.iter().enumerate() {
        match s {
            Occupancy::Free => {
                free += 1;
                free_ok += truth_free.data[i] as usize;
            }
            Occupancy::Occupied => {
                occ += 1;
                let c = map.frame.cell_of_index(i);
                let near_solid = std::iter::once(c)
                    .chain(c.neighbours8())
                    .any(|n| truth_free.get(n) != Some(&true));
                occ_ok += near_solid as usize;
            }
            Occupancy::Unknown => {}
        }
    }
    let ratio = |a: usize, b: usize| if b == 0 { 1.0 } else { a as f64 / b as f64 };
    MapQuality {
        free_precision: ratio(free_ok, free),
        occupied_precision: ratio(occ_ok, occ),
        occupied_precision_aligned: ratio(occ_ok, occ),
    }
}
