//! Information gain informed by the predicted layout: the paper's "with L".
//!
//! The layout's room walls (the edges of every room polygon) are drawn into a copy of the map as
//! obstacles (`M^L`). [`layout_information_gain`] is the paper's `I(p)`: a candidate `p` expects
//! to see the unknown cells within laser range that are visible from `p` in `M^L` and lie inside
//! the predicted layout. Candidates in a room with an *open* frontier (its prediction reaches the
//! known map's box, so no wall line bounds it) or outside every room keep the baseline gain
//! (unknown counted as free).
//!
//! [`gap_closed_information_gain`] uses only the part of the layout that is reliable on a partial
//! map: wall lines that close a short gap of unknown cells between observed stretches of the same
//! wall (`M^L` restricted to those cells), with unknown counted as free elsewhere. Measured on
//! partial SLAM maps, the paper's `I(p)` ranks candidates worse than the baseline (predicted
//! shapes of rooms seen through a door are often cut short by the wall lines of other rooms), so
//! the explorer orders candidates by this gain and keeps the paper's `I(p)` for early stopping.

use std::borrow::Cow;

use crate::frontier::detect::frontier_row;
use crate::gain::{visible_area_read, CellsRead};
use crate::grid::{Bitmap, Cell, Occupancy, OccupancyGrid};
use crate::layout::morphology::BitRows;
use crate::layout::{Layout, RoomLabel};
use crate::mapping::ray::{grid_from_world, walk_segment};

/// In [`LayoutRaster`]'s room grid: no room (room `k` is stored as `k + 1`, so that a new grid
/// is zeroed memory, which needs no filling).
const NO_ROOM: u32 = 0;

/// The layout rasterised on the map's grid.
#[derive(Debug, Clone, PartialEq)]
pub struct LayoutRaster {
    /// Cells crossed by a layout wall.
    pub walls: Bitmap,
    /// 1 + the index (into `layout.rooms`) of the room whose polygon holds the cell centre, or
    /// [`NO_ROOM`].
    room: RoomGrid,
    /// Per room: its frontier is open.
    open: Vec<bool>,
    /// Unknown cells of a layout wall that close a short gap in an observed wall.
    pub gap_walls: Bitmap,
    /// In [`layout_information_gain`]: a layout wall does not block where the map shows free
    /// space or where it closes a short gap of an observed wall (`gap_walls`: a doorway the
    /// robot has seen, or an unseen piece of wall: for the early stop, the safe reading), and
    /// unknown cells outside every predicted room count, so that a frontier in an opening of a wall line keeps a gain for what lies
    /// beyond (false = the paper's `M^L`, where every layout wall blocks).
    pub through_openings: bool,
}

impl LayoutRaster {
    /// Rasterises `layout` on the frame of `grid` (at a resolution of 2 mm or coarser); walls
    /// close gaps of up to `max_wall_gap_m`.
    pub fn new(layout: &Layout, grid: &OccupancyGrid, max_wall_gap_m: f64) -> Self {
        let (walls, room) = Self::rasterise(layout, grid);
        // The closed edges' cells of the rooms not open by their label, and one table of the
        // frontier cells near all of them (a room's answers do not depend on the box it is
        // read from, as long as the box holds the room's cells).
        let edges: Vec<Option<Vec<Vec<Cell>>>> = layout
            .rooms
            .iter()
            .map(|r| {
                (r.label != RoomLabel::Open).then(|| {
                    let mut edges = Vec::new();
                    for_closed_edge_cells(r, grid.frame, |cells| edges.push(cells.to_vec()));
                    edges
                })
            })
            .collect();
        let reach = (FRONTIER_REACH_M / grid.frame.resolution_m).ceil() as i32;
        let near = FrontierNear::new(grid, edges.iter().flatten().flatten().flatten(), reach);
        let open = edges
            .iter()
            .map(|e| match (e, &near) {
                (None, _) => true,
                (Some(e), Some(near)) => crosses_frontier(e, grid, max_wall_gap_m, near),
                (Some(_), None) => false,
            })
            .collect();
        let gap_walls = gap_walls(layout, grid, max_wall_gap_m);
        Self {
            walls,
            room,
            open,
            gap_walls,
            through_openings: false,
        }
    }

    /// Rasterises a layout known to be complete and exact (the building's true rooms): no room
    /// has an open frontier, so every candidate inside a room uses the room-bounded gain; no
    /// gap walls.
    pub fn exact(layout: &Layout, grid: &OccupancyGrid) -> Self {
        let (walls, room) = Self::rasterise(layout, grid);
        Self {
            walls,
            room,
            open: vec![false; layout.rooms.len()],
            gap_walls: Bitmap::filled(grid.frame, false),
            through_openings: false,
        }
    }

    /// The cells crossed by room edges, and the room holding each cell centre.
    fn rasterise(layout: &Layout, grid: &OccupancyGrid) -> (Bitmap, RoomGrid) {
        let frame = grid.frame;
        let room = RoomGrid::new(frame, &layout.rooms);
        let mut walls = Bitmap::filled(frame, false);
        for r in &layout.rooms {
            for e in r.polygon.edges() {
                let a = grid_from_world(&frame, e.a);
                let b = grid_from_world(&frame, e.b);
                walk_segment(a, b, |c| {
                    walls.set(c, true);
                    true
                });
            }
        }
        (walls, room)
    }

    /// Whether the cell lies in a predicted room.
    pub fn inside(&self, c: Cell) -> bool {
        self.room.get(c) != NO_ROOM
    }

    /// The index (into the layout's rooms) of the room whose polygon holds the centre of `c`.
    pub(crate) fn room_index(&self, c: Cell) -> Option<usize> {
        let k = self.room.get(c);
        (k != NO_ROOM).then(|| k as usize - 1)
    }

    /// Whether a candidate at `c` must fall back to the baseline gain.
    pub(crate) fn uses_baseline(&self, c: Cell) -> bool {
        match self.room.get(c) {
            NO_ROOM => true,
            k => self.open[k as usize - 1],
        }
    }
}

/// The room holding each cell centre (1 + its index, or [`NO_ROOM`]) over the box of the rooms:
/// two bytes a cell when there are fewer than 65535 rooms (as good as always), else four.
#[derive(Debug, Clone, PartialEq)]
enum RoomGrid {
    Narrow(RoomCells<u16>),
    Wide(RoomCells<u32>),
}

impl RoomGrid {
    fn new(frame: crate::grid::GridFrame, rooms: &[crate::layout::LayoutRoom]) -> Self {
        if rooms.len() < u16::MAX as usize {
            RoomGrid::Narrow(RoomCells::new(frame, rooms))
        } else {
            RoomGrid::Wide(RoomCells::new(frame, rooms))
        }
    }

    #[inline]
    fn get(&self, c: Cell) -> u32 {
        match self {
            RoomGrid::Narrow(r) => r.get(c),
            RoomGrid::Wide(r) => r.get(c),
        }
    }
}

/// [`RoomGrid`]'s cells, row-major over a box of the frame (cells outside it hold no room).
#[derive(Debug, Clone, PartialEq)]
struct RoomCells<T> {
    x0: i64,
    y0: i64,
    width: usize,
    height: usize,
    data: Vec<T>,
}

impl<T: Copy + Default + TryFrom<usize> + Into<u32>> RoomCells<T> {
    /// Room `k` of `rooms` is stored as `k + 1`, which must fit `T`.
    fn new(frame: crate::grid::GridFrame, rooms: &[crate::layout::LayoutRoom]) -> Self {
        // The box of the cells whose centres the rooms' boxes hold, a cell wider on every side
        // (rounding), within the frame.
        let res = frame.resolution_m;
        let (mut x0, mut y0, mut x1, mut y1) = (i64::MAX, i64::MAX, i64::MIN, i64::MIN);
        for r in rooms.iter().filter(|r| r.polygon.vertices.len() >= 3) {
            let bb = r.polygon.aabb();
            let cell = |v: f64, o: f64| ((v - o) / res - 0.5).clamp(-1e15, 1e15);
            x0 = x0.min(cell(bb.min.x, frame.origin_m.x).floor() as i64 - 1);
            y0 = y0.min(cell(bb.min.y, frame.origin_m.y).floor() as i64 - 1);
            x1 = x1.max(cell(bb.max.x, frame.origin_m.x).ceil() as i64 + 1);
            y1 = y1.max(cell(bb.max.y, frame.origin_m.y).ceil() as i64 + 1);
        }
        let (x0, y0) = (x0.max(0), y0.max(0));
        let (x1, y1) = (
            x1.min(frame.width as i64 - 1),
            y1.min(frame.height as i64 - 1),
        );
        // (An empty box at the origin: with no room, `x0` would be `i64::MAX`, and `get`'s
        // subtraction would overflow.)
        let (x0, y0, width, height) = if x0 <= x1 && y0 <= y1 {
            (x0, y0, (x1 - x0 + 1) as usize, (y1 - y0 + 1) as usize)
        } else {
            (0, 0, 0, 0)
        };
        let mut data = vec![T::default(); width * height];
        let fw = frame.width as usize;
        for (k, r) in rooms.iter().enumerate() {
            let Ok(value) = T::try_from(k + 1) else {
                break;
            };
            crate::building::for_runs_in_polygon(frame, &r.polygon, |run| {
                // A run lies in one row of the frame; clipped to the box (it always is inside).
                let y = (run.start / fw) as i64;
                let (xa, xb) = ((run.start % fw) as i64, (run.end - 1) % fw);
                let (xa, xb) = (xa.max(x0), (xb as i64).min(x1));
                if y < y0 || y > y1 || xa > xb {
                    return;
                }
                let row = (y - y0) as usize * width;
                data[row + (xa - x0) as usize..=row + (xb - x0) as usize].fill(value);
            });
        }
        Self {
            x0,
            y0,
            width,
            height,
            data,
        }
    }

    #[inline]
    fn get(&self, c: Cell) -> u32 {
        // (A cell left of or above the box wraps to a column or row far past it.)
        let x = (c.x as i64 - self.x0) as usize;
        let y = (c.y as i64 - self.y0) as usize;
        if x < self.width && y < self.height {
            self.data[y * self.width + x].into()
        } else {
            NO_ROOM
        }
    }
}

/// Whether one of the room's edges (off the box) runs through the map for more than `max_gap_m`
/// with no observed wall near it and a frontier within `FRONTIER_REACH_M` all along that
/// stretch: the wall line there was extended from elsewhere across space the robot is still
/// seeing into (e.g. a corridor cut near the end of the laser's reach by another room's wall
/// line), so the room's frontier is open, as if the edge were on the box. An unseen stretch of
/// wall next to the corner of a frontier (a room seen through its side) keeps the room closed.
/// `edges` are the cells of the room's edges off the box ([`for_closed_edge_cells`]), and
/// `frontier_near` was made for a box holding them, with a reach of [`FRONTIER_REACH_M`].
fn crosses_frontier(
    edges: &[Vec<Cell>],
    grid: &OccupancyGrid,
    max_gap_m: f64,
    frontier_near: &FrontierNear,
) -> bool {
    let max_gap = if max_gap_m.is_finite() && max_gap_m > 0.0 {
        (max_gap_m / grid.frame.resolution_m).ceil() as usize
    } else {
        0
    };
    for cells in edges {
        // Length of the current stretch of cells with no wall near and a frontier near.
        let mut run = 0usize;
        for c in cells {
            if near_occupied(grid, *c) || !frontier_near.at(*c) {
                run = 0;
                continue;
            }
            run += 1;
            if run > max_gap {
                return true;
            }
        }
    }
    false
}

/// How far a frontier may be from a room's edge for the edge to cross it (see
/// [`crosses_frontier`]).
const FRONTIER_REACH_M: f64 = 0.5;

/// Whether a frontier cell lies within `reach` cells (`dx² + dy² <= reach²`) of a cell, for the
/// cells of a box: the frontier cells of the box (the cells' bounding box grown by `reach`) as
/// bits, so that a query tests `2 reach + 1` row spans of the disk a word or two at a time
/// instead of every cell of it. Exactly the disk test, in a fraction of the time.
struct FrontierNear {
    x0: i32,
    y0: i32,
    reach: i32,
    /// Per `dy` in `-reach..=reach`: the disk's half-width in that row.
    half_width: Vec<i64>,
    frontier: BitRows,
}

impl FrontierNear {
    /// `None` without cells.
    fn new<'a>(
        grid: &OccupancyGrid,
        cells: impl Iterator<Item = &'a Cell>,
        reach: i32,
    ) -> Option<Self> {
        let (mut x0, mut y0, mut x1, mut y1) = (i32::MAX, i32::MAX, i32::MIN, i32::MIN);
        for c in cells {
            x0 = x0.min(c.x);
            y0 = y0.min(c.y);
            x1 = x1.max(c.x);
            y1 = y1.max(c.y);
        }
        if x0 > x1 {
            return None;
        }
        let (x0, y0, x1, y1) = (x0 - reach, y0 - reach, x1 + reach, y1 + reach);
        let width = (x1 - x0 + 1) as usize;
        let height = (y1 - y0 + 1) as usize;
        let mut frontier = BitRows::new(width, height);
        let (w, h) = (grid.frame.width as i64, grid.frame.height as i64);
        // (The columns outside the frame stay false; `frontier_row` writes all the others.)
        let mut flags = vec![false; width];
        for r in 0..height {
            let y = (y0 + r as i32) as i64;
            // The row's frontier cells (only the box's columns in the frame can have any).
            let (xa, xb) = ((x0 as i64).max(0), (x1 as i64).min(w - 1));
            if !(0..h).contains(&y) || xa > xb {
                continue;
            }
            let out = &mut flags[(xa - x0 as i64) as usize..];
            frontier_row(grid, y as usize, xa as usize, xb as usize, out);
            // (Most rows of the box have no frontier cell: the row is already clear.)
            if flags.iter().fold(false, |a, f| a | f) {
                frontier.set_row(r, &flags);
            }
        }
        let r2 = reach as i64 * reach as i64;
        let half_width = (-reach..=reach)
            .map(|dy| (r2 - dy as i64 * dy as i64).isqrt())
            .collect();
        Some(Self {
            x0,
            y0,
            reach,
            half_width,
            frontier,
        })
    }

    /// For a cell of the box (the cells it was made from).
    fn at(&self, c: Cell) -> bool {
        let col = (c.x - self.x0) as i64;
        (-self.reach..=self.reach)
            .zip(&self.half_width)
            .any(|(dy, &hw)| {
                let row = (c.y + dy - self.y0) as usize;
                self.frontier.any_in(row, col - hw, col + hw)
            })
    }
}

/// Whether `c` or one of its 8-neighbours is occupied (an observed wall at `c`).
fn near_occupied(grid: &OccupancyGrid, c: Cell) -> bool {
    grid.is(c, Occupancy::Occupied)
        || c.neighbours8()
            .iter()
            .any(|n| grid.is(*n, Occupancy::Occupied))
}

/// Calls `f` with the cells of each edge of `room` that is not on the known map's box.
fn for_closed_edge_cells(
    room: &crate::layout::LayoutRoom,
    frame: crate::grid::GridFrame,
    mut f: impl FnMut(&[Cell]),
) {
    let mut cells = Vec::new();
    for (k, e) in room.polygon.edges().enumerate() {
        if room.open_edges.get(k) == Some(&true) {
            continue;
        }
        cells.clear();
        walk_segment(
            grid_from_world(&frame, e.a),
            grid_from_world(&frame, e.b),
            |c| {
                cells.push(c);
                true
            },
        );
        f(&cells);
    }
}

/// A bitmap of the raster as cells of `grid`'s frame, row-major: its own cells when it covers
/// that frame (as when rasterised from this map), so that a predicate reads a cell by its
/// index with no frame test; else copied cell by cell onto the frame.
fn cells_on<'a>(bits: &'a Bitmap, grid: &OccupancyGrid) -> Cow<'a, [bool]> {
    if bits.frame == grid.frame && bits.data.len() == grid.data.len() {
        return Cow::Borrowed(&bits.data[..]);
    }
    let w = (grid.frame.width as usize).max(1);
    Cow::Owned(
        (0..grid.data.len())
            .map(|i| bits.get(Cell::new((i % w) as i32, (i / w) as i32)) == Some(&true))
            .collect(),
    )
}

/// `I(p)` with the layout, in square metres (see the module doc).
pub fn layout_information_gain(
    grid: &OccupancyGrid,
    raster: &LayoutRaster,
    p: Cell,
    range_m: f64,
) -> f64 {
    layout_information_gain_read(grid, raster, p, range_m).0
}

/// [`layout_information_gain`] and where the map cells it read lie ([`CellsRead`]).
pub(crate) fn layout_information_gain_read(
    grid: &OccupancyGrid,
    raster: &LayoutRaster,
    p: Cell,
    range_m: f64,
) -> (f64, CellsRead) {
    if raster.uses_baseline(p) {
        return crate::gain::information_gain_read(grid, p, range_m);
    }
    // (The cells as a slice: the predicates then read them without going through `grid`.)
    let data = &grid.data[..];
    let (walls, gap_walls) = (
        cells_on(&raster.walls, grid),
        cells_on(&raster.gap_walls, grid),
    );
    visible_area_read(
        &grid.frame,
        p,
        range_m,
        // A candidate lies on the frontier, often right on the edge of its room's polygon: the
        // layout walls touching its own cell must not hide everything from it.
        |c, i| {
            data[i] == Occupancy::Occupied
                || (walls[i]
                    && !(raster.through_openings && (data[i] == Occupancy::Free || gap_walls[i]))
                    && (c.x - p.x).abs().max((c.y - p.y).abs()) > 1)
        },
        |c, i| data[i] == Occupancy::Unknown && (raster.through_openings || raster.inside(c)),
    )
}

/// The unknown cells of every non-open room edge that lie in a run of at most `max_gap_m` of
/// edge cells with no occupied cell around them, between two such runs that have one: the gaps
/// of an observed wall that the wall line closes.
fn gap_walls(layout: &Layout, grid: &OccupancyGrid, max_gap_m: f64) -> Bitmap {
    let frame = grid.frame;
    let mut out = Bitmap::filled(frame, false);
    if !(max_gap_m.is_finite() && max_gap_m > 0.0) || frame.is_empty() {
        return out;
    }
    let max_gap = (max_gap_m / frame.resolution_m).ceil() as usize;
    for r in &layout.rooms {
        for_closed_edge_cells(r, frame, |cells| {
            let occupied: Vec<bool> = cells.iter().map(|c| near_occupied(grid, *c)).collect();
            let mut i = 0;
            while i < cells.len() {
                if occupied[i] {
                    i += 1;
                    continue;
                }
                let mut j = i;
                while j < cells.len() && !occupied[j] {
                    j += 1;
                }
                if i > 0 && j < cells.len() && j - i <= max_gap {
                    for c in &cells[i..j] {
                        if grid.is(*c, Occupancy::Unknown) {
                            out.set(*c, true);
                        }
                    }
                }
                i = j;
            }
        });
    }
    out
}

/// The baseline `I(p)` through the map with the layout's gap-closing walls drawn in (m2).
pub fn gap_closed_information_gain(
    grid: &OccupancyGrid,
    raster: &LayoutRaster,
    p: Cell,
    range_m: f64,
) -> f64 {
    gap_closed_information_gain_read(grid, raster, p, range_m).0
}

/// [`gap_closed_information_gain`] and where the map cells it read lie ([`CellsRead`]).
pub(crate) fn gap_closed_information_gain_read(
    grid: &OccupancyGrid,
    raster: &LayoutRaster,
    p: Cell,
    range_m: f64,
) -> (f64, CellsRead) {
    // (The cells as a slice: the predicates then read them without going through `grid`.)
    let data = &grid.data[..];
    let gap_walls = cells_on(&raster.gap_walls, grid);
    visible_area_read(
        &grid.frame,
        p,
        range_m,
        |c, i| {
            data[i] == Occupancy::Occupied
                || (gap_walls[i] && (c.x - p.x).abs().max((c.y - p.y).abs()) > 1)
        },
        |_, i| data[i] == Occupancy::Unknown,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frontier::detect::is_frontier_cell;
    use crate::gain::information_gain;
    use proptest::prelude::*;

    proptest! {
        /// The room grid (over the rooms' box, two or four bytes a cell) answers as the room
        /// polygons filled into the whole frame, later rooms over earlier ones, for every cell of
        /// the frame and around it, with rooms partly or wholly off the frame.
        #[test]
        fn room_grid_is_the_rooms_filled_into_the_frame(
            (w, h) in (1u32..60, 1u32..40),
            rects in proptest::collection::vec(
                (-1.0f64..4.0, -1.0f64..3.0, 0.0f64..2.5, 0.0f64..2.0, any::<bool>()),
                0..8,
            ),
        ) {
            let frame = crate::grid::GridFrame::new(Vec2::new(0.02, -0.03), 0.05, w, h);
            let rooms: Vec<LayoutRoom> = rects
                .iter()
                .enumerate()
                .map(|(k, &(x, y, dx, dy, triangle))| {
                    let mut r = room(k as u32, (x, y), (x + dx, y + dy), RoomLabel::Full);
                    if triangle {
                        r.polygon = Polygon::new(vec![
                            Vec2::new(x, y),
                            Vec2::new(x + dx, y),
                            Vec2::new(x, y + dy),
                        ]);
                    }
                    r
                })
                .collect();
            let mut want = vec![NO_ROOM; frame.len()];
            for (k, r) in rooms.iter().enumerate() {
                crate::building::for_cells_in_polygon(frame, &r.polygon, |i| {
                    want[i] = k as u32 + 1
                });
            }
            let narrow = RoomCells::<u16>::new(frame, &rooms);
            let wide = RoomCells::<u32>::new(frame, &rooms);
            for y in -2..h as i32 + 2 {
                for x in -2..w as i32 + 2 {
                    let c = Cell::new(x, y);
                    let expected = frame.index(c).map_or(NO_ROOM, |i| want[i]);
                    prop_assert_eq!(narrow.get(c), expected, "{:?}", c);
                    prop_assert_eq!(wide.get(c), expected, "{:?}", c);
                }
            }
            prop_assert_eq!(RoomGrid::new(frame, &rooms), RoomGrid::Narrow(narrow));
        }
    }

    proptest! {
        /// The test of a frontier within reach on the frontier bits is the disk test, cell for
        /// cell, on random maps (cells in and out of the grid, any reach; rows of a few cells to
        /// several words, with few frontier cells far apart).
        #[test]
        fn frontier_near_is_the_disk_test(
            width in 1i32..700,
            height in 1i32..8,
            seed in any::<u64>(),
            sparse in any::<bool>(),
            reach in 0i32..7,
            queries in proptest::collection::vec((0i32..10_000, -4i32..12), 1..40),
        ) {
            use rand::{Rng, SeedableRng};
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let mut grid = OccupancyGrid::filled(
                crate::grid::GridFrame::new(Vec2::zeros(), 0.05, width as u32, height as u32),
                Occupancy::Unknown,
            );
            let known = if sparse { 0.01 } else { 0.6 };
            for d in grid.data.iter_mut() {
                if rng.random_bool(known) {
                    *d = if rng.random_bool(0.8) { Occupancy::Free } else { Occupancy::Occupied };
                }
            }
            let qs: Vec<Cell> = queries
                .iter()
                .map(|&(x, y)| Cell::new(x % (width + 8) - 4, y))
                .collect();
            let near = FrontierNear::new(&grid, qs.iter(), reach).unwrap();
            for c in &qs {
                let disk = (-reach..=reach).any(|dy| {
                    (-reach..=reach).any(|dx| {
                        dx * dx + dy * dy <= reach * reach
                            && is_frontier_cell(&grid, Cell::new(c.x + dx, c.y + dy))
                    })
                });
                prop_assert_eq!(near.at(*c), disk, "{:?}", c);
            }
        }
    }
    use crate::geom::{Polygon, Vec2};
    use crate::layout::{LayoutRoom, RoomLabel};

    fn room(id: u32, min: (f64, f64), max: (f64, f64), label: RoomLabel) -> LayoutRoom {
        let polygon = Polygon::rect(Vec2::new(min.0, min.1), Vec2::new(max.0, max.1));
        LayoutRoom {
            id,
            open_edges: vec![false; polygon.vertices.len()],
            observed_polygon: polygon.clone(),
            area_m2: polygon.area_m2(),
            observed_area_m2: polygon.area_m2(),
            polygon,
            label,
            predicted: true,
            unknown_area_m2: 0.0,
        }
    }

    /// A 2 x 1 m room seen on its left half, its walls observed there; unknown to the right and
    /// beyond.
    fn map() -> OccupancyGrid {
        let mut rows = Vec::new();
        for y in 0..30 {
            let mut row = String::new();
            for x in 0..60 {
                row.push(if (5..15).contains(&y) && (5..15).contains(&x) {
                    '.'
                } else if (4..=15).contains(&y)
                    && (4..=15).contains(&x)
                    && (y == 4 || y == 15 || x == 4)
                {
                    '#'
                } else {
                    '?'
                });
            }
            rows.push(row);
        }
        OccupancyGrid::from_ascii(&rows.join("\n"), 0.1)
    }

    /// A corridor 2 m wide (walls observed) seen for 3 m from its left end, unknown beyond.
    fn corridor() -> OccupancyGrid {
        let mut rows = vec!["?".repeat(60); 5];
        rows.push(format!("{}{}", "#".repeat(31), "?".repeat(29)));
        rows.extend(vec![format!("#{}{}", ".".repeat(30), "?".repeat(29)); 20]);
        rows.push(format!("{}{}", "#".repeat(31), "?".repeat(29)));
        rows.extend(vec!["?".repeat(60); 5]);
        OccupancyGrid::from_ascii(&rows.join("\n"), 0.1)
    }

    /// A 1 x 1 m room, fully seen, whose right wall (one cell, x = 15) has a 0.5 m doorway (seen
    /// free) with unknown beyond; the predicted room's right edge runs one cell outside the
    /// wall, through the unknown beyond the doorway (a wall line fitted a little off).
    fn room_with_doorway() -> (OccupancyGrid, Layout) {
        let mut rows = Vec::new();
        for y in 0..30 {
            let mut row = String::new();
            for x in 0..60 {
                let inside = (5..15).contains(&y) && (5..15).contains(&x);
                let wall = (4..=15).contains(&y) && (4..=15).contains(&x) && !inside;
                let door = x == 15 && (8..13).contains(&y);
                row.push(if inside || door {
                    '.'
                } else if wall {
                    '#'
                } else {
                    '?'
                });
            }
            rows.push(row);
        }
        // The first line of the text is the top row of the grid.
        rows.reverse();
        let layout = Layout {
            rooms: vec![room(1, (0.5, 0.5), (1.66, 1.5), RoomLabel::Partial)],
            ..Layout::default()
        };
        (OccupancyGrid::from_ascii(&rows.join("\n"), 0.1), layout)
    }

    #[test]
    fn a_doorway_in_a_wall_line_keeps_the_gain_of_what_lies_beyond() {
        let (g, layout) = room_with_doorway();
        let mut r = LayoutRaster::new(&layout, &g, 1.0);
        // Inside the room, in line with the doorway, three cells from the wall line.
        let p = Cell::new(13, 10);
        assert!(!r.uses_baseline(p));
        // The paper's M^L: the wall line closes the doorway, next to nothing left to see.
        let closed = layout_information_gain(&g, &r, p, 6.0);
        assert!(closed < 0.1, "{closed}");
        // Through the opening: the unknown beyond the doorway counts.
        r.through_openings = true;
        let through = layout_information_gain(&g, &r, p, 6.0);
        assert!(through > 1.0, "{through}");
        assert!(through <= information_gain(&g, p, 6.0) + 1e-9);
        // Seen from a corner of the room, the doorway is hidden by the wall: nothing either way.
        let q = Cell::new(14, 14);
        assert!(layout_information_gain(&g, &r, q, 6.0) < 0.1);
    }

    #[test]
    fn a_raster_on_another_frame_is_read_by_cell() {
        // The gains read a raster made on the map's frame by cell index; a raster on another
        // frame (here moved by 1 m, the same cells) is read cell by cell: the same gains.
        let (g, layout) = room_with_doorway();
        let mut r = LayoutRaster::new(&layout, &g, 1.0);
        let mut moved = r.clone();
        moved.walls.frame.origin_m.x += 1.0;
        moved.gap_walls.frame.origin_m.x += 1.0;
        assert!(r.gap_walls.count_true() > 0);
        let mut walls_hid_something = false;
        for through in [false, true] {
            r.through_openings = through;
            moved.through_openings = through;
            for (x, y) in [(13, 10), (14, 14), (6, 6), (10, 12), (14, 9)] {
                let p = Cell::new(x, y);
                let by_index = layout_information_gain_read(&g, &r, p, 6.0);
                assert_eq!(by_index, layout_information_gain_read(&g, &moved, p, 6.0));
                walls_hid_something |= by_index.0 < information_gain(&g, p, 6.0);
                assert_eq!(
                    gap_closed_information_gain_read(&g, &r, p, 6.0),
                    gap_closed_information_gain_read(&g, &moved, p, 6.0)
                );
            }
        }
        assert!(walls_hid_something);
    }

    #[test]
    fn a_room_cut_across_a_frontier_is_open() {
        let g = corridor();
        // The corridor's room ends 0.1 m past the end of what was seen, at a wall line extended
        // from elsewhere: the edge crosses the frontier (2 m with no wall) and the room is open.
        let cut = Layout {
            rooms: vec![room(1, (0.05, 0.5), (3.2, 2.6), RoomLabel::Partial)],
            ..Layout::default()
        };
        let p = Cell::new(30, 15);
        let r = LayoutRaster::new(&cut, &g, 1.0);
        assert!(r.uses_baseline(p));
        assert_eq!(
            layout_information_gain(&g, &r, p, 6.0),
            information_gain(&g, p, 6.0)
        );
        // Predicted 3 m further on, the edge is far from the frontier: a closed prediction.
        let long = Layout {
            rooms: vec![room(1, (0.05, 0.5), (6.2, 2.6), RoomLabel::Partial)],
            ..Layout::default()
        };
        let r = LayoutRaster::new(&long, &g, 1.0);
        assert!(!r.uses_baseline(p));
        let with_l = layout_information_gain(&g, &r, p, 6.0);
        assert!(with_l > 4.0 && with_l < 6.5, "with L: {with_l}");
        // A crossing no longer than the gaps walls may close (here 2.5 m) keeps it closed.
        let r = LayoutRaster::new(&cut, &g, 2.5);
        assert!(!r.uses_baseline(p));
    }

    #[test]
    fn an_exact_layout_never_falls_back_to_the_baseline() {
        let g = corridor();
        let p = Cell::new(30, 15);
        // The cut corridor that `new` judges open, and a room labelled open: as the true rooms
        // both are complete, so the candidate counts only the unknown cells inside them.
        for label in [RoomLabel::Partial, RoomLabel::Open] {
            let cut = Layout {
                rooms: vec![room(1, (0.05, 0.5), (3.2, 2.6), label)],
                ..Layout::default()
            };
            assert!(LayoutRaster::new(&cut, &g, 1.0).uses_baseline(p));
            let r = LayoutRaster::exact(&cut, &g);
            assert!(!r.uses_baseline(p));
            assert_eq!(r.gap_walls.count_true(), 0);
            let with_l = layout_information_gain(&g, &r, p, 6.0);
            // The room holds 0.1 m x 2.1 m of unknown cells past the corridor's end.
            let base = information_gain(&g, p, 6.0);
            assert!(
                with_l < 0.5 && base > 10.0 * with_l,
                "{label:?}: {with_l} vs {base}"
            );
        }
        // Outside every room: the baseline.
        let none = Layout::default();
        assert!(LayoutRaster::exact(&none, &g).uses_baseline(p));
    }

    /// 4 x 1 m of free space (rows 0-9) under an observed wall (row 10) with a gap of unknown
    /// cells `gap` long in its middle, unknown beyond: the top text line is the top row.
    fn gapped_wall(gap: usize) -> OccupancyGrid {
        let mut rows = vec!["?".repeat(40); 19];
        let x0 = 20 - gap / 2;
        let wall: String = (0..40)
            .map(|x| {
                if (x0..x0 + gap).contains(&x) {
                    '?'
                } else {
                    '#'
                }
            })
            .collect();
        rows.push(wall);
        rows.extend(vec![".".repeat(40); 10]);
        OccupancyGrid::from_ascii(&rows.join("\n"), 0.1)
    }

    #[test]
    fn wall_lines_close_short_gaps_in_observed_walls_only() {
        // The layout's room: the free space, its top edge on the wall's row.
        let layout = Layout {
            rooms: vec![room(1, (0.0, 0.0), (4.0, 1.05), RoomLabel::Partial)],
            ..Layout::default()
        };
        let p = Cell::new(20, 7);
        // A 0.4 m gap: the wall line closes it, nothing unknown is left to see from below.
        let g = gapped_wall(4);
        let r = LayoutRaster::new(&layout, &g, 1.0);
        let base = information_gain(&g, p, 6.0);
        assert!(base > 1.0, "baseline sees through the gap: {base}");
        // The cells touching the wall's ends count as observed wall already (8-neighbourhood):
        // the two in the middle are drawn, which leaves only diagonal slivers to see through.
        assert_eq!(r.gap_walls.count_true(), 2);
        let closed = gap_closed_information_gain(&g, &r, p, 6.0);
        assert!(closed < 0.5 * base, "closed: {closed} vs {base}");
        // The same wall with a 1.4 m opening (a door, not a gap): left open.
        let g = gapped_wall(14);
        let r = LayoutRaster::new(&layout, &g, 1.0);
        assert_eq!(r.gap_walls.count_true(), 0);
        assert_eq!(
            gap_closed_information_gain(&g, &r, p, 6.0),
            information_gain(&g, p, 6.0)
        );
        // No gap closing at all when the maximum gap is zero.
        let g = gapped_wall(4);
        let r = LayoutRaster::new(&layout, &g, 0.0);
        assert_eq!(gap_closed_information_gain(&g, &r, p, 6.0), base);
    }

    #[test]
    fn the_layout_bounds_the_gain_and_open_rooms_fall_back() {
        let g = map();
        let p = Cell::new(14, 20);
        let base = information_gain(&g, p, 6.0);
        // The predicted room ends at x = 2.5 m: only 1 m x 1 m of it is unknown.
        let layout = Layout {
            rooms: vec![room(1, (0.5, 1.5), (2.5, 2.5), RoomLabel::Partial)],
            ..Layout::default()
        };
        let r = LayoutRaster::new(&layout, &g, 1.0);
        let with_l = layout_information_gain(&g, &r, p, 6.0);
        assert!(with_l > 0.5 && with_l < 1.2, "with L: {with_l}");
        assert!(base > 10.0 * with_l, "baseline {base} vs {with_l}");
        // A candidate on the room's own wall line still sees into the room.
        let on_edge = layout_information_gain(&g, &r, Cell::new(5, 20), 6.0);
        assert!(on_edge > 0.5 && on_edge < 1.2, "on the edge: {on_edge}");
        // The same room with an open frontier keeps the baseline.
        let layout = Layout {
            rooms: vec![room(1, (0.5, 1.5), (2.5, 2.5), RoomLabel::Open)],
            ..Layout::default()
        };
        let r = LayoutRaster::new(&layout, &g, 1.0);
        assert_eq!(layout_information_gain(&g, &r, p, 6.0), base);
    }
}
