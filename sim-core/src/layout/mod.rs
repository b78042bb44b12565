//! Room layout reconstruction and prediction of partially observed rooms from an occupancy grid
//! (after Luperto & Amigoni, IAS-15, and Luperto, Arcerito & Amigoni, ICRA 2019).
//!
//! The pipeline, one file per stage:
//! 1. [`evidence`]: wall evidence: occupied cells that touch free space, with the orientation of
//!    the local free/occupied boundary (moments of the free and occupied cells of a 5x5 window);
//!    thin unknown bands filled as walls. The masks are packed 64 cells to a word
//!    ([`morphology`]): these stages pass over the whole known box at every layout.
//! 2. [`directions`]: dominant wall directions (any angle, not only axis-aligned): a histogram of
//!    boundary orientations, peaks, each refined by maximising the sharpness of the offsets.
//!    [`lines`]: representative wall lines per direction: a 1D histogram of the offsets of the
//!    boundary cells along the direction's normal; peaks are lines, weight = supported length.
//! 3. [`arrangement`]: the lines, clipped to the bounding box of the known map, cut it into convex
//!    faces. A face is an intersection of slabs (one per direction), so labelling a cell is a
//!    lookup of its slab index per direction; face polygons are exact (half-plane clipping, every
//!    vertex keyed by the pair of lines that make it, so that shared edges match exactly).
//! 4. [`rooms`]: faces are classified from the grid; inside faces are merged across edges that
//!    are not covered by wall evidence; frontiers mark the partially observed rooms.
//! 5. [`predict`]: partial rooms grow into neighbouring unknown faces (not across walls) choosing
//!    the set that maximises `Phi = 10 S - 10 C - 5 N`.
//!
//! [`accuracy`] scores a layout against ground-truth rooms.
//!
//! Everything is in world metres; lengths in [`LayoutConfig`] are metres so that results do not
//! depend on the grid resolution. No clock: the caller times it; [`LayoutDiagnostics`] counts
//! the work of each stage instead.

pub mod accuracy;
pub mod arrangement;
pub mod directions;
pub mod evidence;
pub mod lines;
pub mod morphology;
pub mod predict;
pub mod rooms;
#[cfg(any(test, feature = "test-support"))]
pub mod synthetic;

#[cfg(test)]
mod tests;

use crate::geom::{Polygon, Segment, Vec2};
use crate::grid::OccupancyGrid;

pub use accuracy::{evaluate, evaluate_merged, unwalled_pairs, Accuracy};

/// Whether a room was seen completely.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum RoomLabel {
    /// No frontier in the room: completely observed.
    Full,
    /// Holds a frontier; its predicted shape is closed by wall lines.
    Partial,
    /// Holds a frontier and its prediction reaches the bounding box of the known map: no wall line
    /// supports the prediction on that side (an *open frontier*).
    Open,
}

/// One room of the layout.
#[derive(Debug, Clone, PartialEq)]
pub struct LayoutRoom {
    pub id: u32,
    /// The room's shape, prediction included, in world metres (counter-clockwise).
    pub polygon: Polygon,
    /// Per edge of `polygon` (edge `i` runs from vertex `i` to vertex `i + 1`): the edge lies on
    /// the border of the known map's box, so no wall line supports it (an open frontier's side).
    pub open_edges: Vec<bool>,
    /// The shape of the observed part only (the faces it had before prediction).
    pub observed_polygon: Polygon,
    pub label: RoomLabel,
    /// Whether prediction added faces to the room.
    pub predicted: bool,
    pub area_m2: f64,
    pub observed_area_m2: f64,
    /// Unknown cells inside the (predicted) room, in square metres.
    pub unknown_area_m2: f64,
}

/// A representative wall line: the points `p` with `n . p = offset_m`, `n = (-sin d, cos d)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallLine {
    /// Direction of the line, in `[0, pi)`.
    pub direction_rad: f64,
    /// Signed distance of the line from the world origin along its normal.
    pub offset_m: f64,
    /// Supported length relative to the best supported line, in `(0, 1]`.
    pub weight: f64,
    /// Length of wall evidence on the line.
    pub support_m: f64,
    /// From the first to the last supporting cell along the line.
    pub extent: Segment,
    /// Index of the dominant direction the line belongs to.
    pub family: u32,
}

impl WallLine {
    /// Unit normal of the line.
    pub fn normal(&self) -> Vec2 {
        Vec2::new(-self.direction_rad.sin(), self.direction_rad.cos())
    }
}

/// Counts of what each stage did (no timing: the core has no clock).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct LayoutDiagnostics {
    /// Unknown cells in thin bands, taken as wall.
    pub thin_unknown_cells: usize,
    pub known_cells: usize,
    pub boundary_cells: usize,
    pub directions: usize,
    /// Angles tried to find the directions: the coarse scan's (one per degree), then each
    /// refinement's (its second scan's centre counted, though its score is the first scan's best).
    pub direction_refine_steps: usize,
    pub lines: usize,
    pub faces: usize,
    pub inside_faces: usize,
    pub edges: usize,
    pub wall_edges: usize,
    /// Cells visited while sampling edges for wall evidence.
    pub edge_samples: usize,
    pub frontier_clusters: usize,
    pub frontier_cells: usize,
    pub partial_rooms: usize,
    pub predicted_rooms: usize,
    pub open_rooms: usize,
    /// Candidate face sets scored with `Phi`.
    pub phi_evaluations: usize,
    /// Rooms dropped as smaller than [`LayoutConfig::min_room_area_m2`].
    pub dropped_small_rooms: usize,
    /// Rooms whose outline was not a single loop (the largest loop was kept).
    pub split_outlines: usize,
}

/// A reconstructed (and partly predicted) layout.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Layout {
    pub rooms: Vec<LayoutRoom>,
    pub lines: Vec<WallLine>,
    pub diagnostics: LayoutDiagnostics,
}

impl Layout {
    /// How many of its rooms carry `label`.
    pub fn rooms_labelled(&self, label: RoomLabel) -> usize {
        self.rooms.iter().filter(|r| r.label == label).count()
    }
}

/// Parameters. Lengths in metres, angles in radians.
#[derive(Debug, Clone, PartialEq)]
pub struct LayoutConfig {
    /// A direction is kept when the square root of its sharpness peak (above the lowest; the
    /// sharpness grows with the square of wall length) is at least this fraction of the highest
    /// one's. Default 0.15.
    pub min_direction_fraction: f64,
    /// Minimum angle between two dominant directions. Default 10 degrees.
    pub min_direction_separation_rad: f64,
    /// At most this many dominant directions. Default 4.
    pub max_directions: usize,
    /// Boundary cells whose local orientation is within this angle of a direction (and nearer to
    /// it than to any other) support its lines. Local orientations of rotated walls are biased
    /// by their staircases, hence a wide default: 25 degrees.
    pub direction_tolerance_rad: f64,
    /// Parallel wall evidence closer than this is one line (both sides of a wall). Default 0.35 m
    /// (the authors' 7 px at 0.05 m).
    pub min_line_separation_m: f64,
    /// A line needs at least this much wall evidence. Default 0.8 m.
    pub min_line_support_m: f64,
    /// Wall evidence within this distance of an edge covers it. Default 0.15 m.
    pub wall_tolerance_m: f64,
    /// An edge between faces is a wall when at least this fraction of it is covered. Default 0.2.
    pub wall_edge_threshold: f64,
    /// A face is inside the building when at least this fraction of its cells is free.
    /// Default 0.3.
    pub min_free_fraction: f64,
    /// Frontier clusters shorter than this are ignored. Default 0.5 m.
    pub min_frontier_length_m: f64,
    /// A room is partial when it holds at least this fraction of a frontier cluster. Default 0.3.
    pub partial_room_frontier_fraction: f64,
    /// A face not in a room can be predicted into when at least this fraction of it is unknown.
    /// Default 0.5.
    pub min_unknown_fraction_candidate: f64,
    /// All subsets of the candidate faces are scored when there are at most this many.
    /// Default 9.
    pub max_exhaustive_candidates: usize,
    /// Prediction grows a room at most this many times (one ring of faces or better each).
    /// Default 3.
    pub max_prediction_rounds: usize,
    /// Weights of `Phi = support * S - concavity * C - lines * N`. Defaults 10, 10, 5.
    pub phi_support_weight: f64,
    pub phi_concavity_weight: f64,
    pub phi_lines_weight: f64,
    /// Rooms smaller than this are dropped. Default 1.0 m2.
    pub min_room_area_m2: f64,
    /// A hole in the evidence along a wall line at most this long, between two runs of wall on
    /// the line, is a door: the edge across it separates rooms (unless walls at its ends run far
    /// across the line: a corridor crossing or junction, see [`lines::drop_crossings`]).
    /// Default 4.0 m: wide enough for the double doors and open fronts of classrooms seen in
    /// real school maps.
    pub max_door_width_m: f64,
    /// The wall on each side of a door must run at least this far along the line. Default 0.4 m.
    pub min_door_jamb_m: f64,
    /// Unknown regions thinner than this are walls (see [`evidence::fill_thin_unknown`]); 0
    /// turns it off. Default 0.6 m.
    pub thin_unknown_wall_m: f64,
}

impl Default for LayoutConfig {
    fn default() -> Self {
        Self {
            min_direction_fraction: 0.15,
            min_direction_separation_rad: 10f64.to_radians(),
            max_directions: 4,
            direction_tolerance_rad: 25f64.to_radians(),
            min_line_separation_m: 0.35,
            min_line_support_m: 0.8,
            wall_tolerance_m: 0.15,
            wall_edge_threshold: 0.2,
            min_free_fraction: 0.3,
            min_frontier_length_m: 0.5,
            partial_room_frontier_fraction: 0.3,
            min_unknown_fraction_candidate: 0.5,
            max_exhaustive_candidates: 9,
            max_prediction_rounds: 3,
            phi_support_weight: 10.0,
            phi_concavity_weight: 10.0,
            phi_lines_weight: 5.0,
            min_room_area_m2: 1.0,
            max_door_width_m: 4.0,
            min_door_jamb_m: 0.4,
            thin_unknown_wall_m: 0.6,
        }
    }
}

/// A direction is kept when its best line has at least this weight (relative to the best line of
/// all directions).
const MIN_FAMILY_BEST_LINE_WEIGHT: f64 = 0.3;

/// Reconstructs the layout of `grid` and predicts the shape of its partially observed rooms.
/// Never panics: an empty, unknown or wall-less grid gives a layout without rooms.
pub fn reconstruct_layout(grid: &OccupancyGrid, config: &LayoutConfig) -> Layout {
    let mut diag = LayoutDiagnostics::default();
    let res = grid.frame.resolution_m;
    if grid.frame.is_empty() || !(res.is_finite() && res > 0.0) {
        return Layout::default();
    }
    let (known_box, known_cells) = evidence::known_box(grid);
    let (filled, thin_cells, known_box) =
        evidence::fill_thin_unknown_in(grid, config.thin_unknown_wall_m, known_box);
    diag.thin_unknown_cells = thin_cells;
    let grid = &filled;
    let evidence = evidence::wall_evidence_in(grid, config, (known_box, known_cells + thin_cells));
    diag.known_cells = evidence.known_cells;
    diag.boundary_cells = evidence.cells.len();
    let Some(bbox) = evidence.known_box else {
        return Layout {
            diagnostics: diag,
            ..Layout::default()
        };
    };
    let dirs = directions::dominant_directions(&evidence.cells, res, config, &mut diag);
    let (mut lines, mut doors) = lines::wall_lines_and_doors(&evidence.cells, &dirs, res, config);
    // A direction whose best line is weak is an alias of the grid lattice (the boundary cells of
    // real walls, oriented like another direction, are not its own) unless it is perpendicular to
    // another direction: drop it and give its cells back to the others.
    let kept: Vec<f64> = dirs
        .iter()
        .enumerate()
        .filter(|(k, d)| {
            let partner = dirs.iter().any(|o| {
                (crate::geom::angle_diff_mod_pi(*o, **d) - std::f64::consts::FRAC_PI_2).abs()
                    <= 0.06
            });
            partner
                || lines
                    .iter()
                    .filter(|l| l.family == *k as u32)
                    .any(|l| l.weight >= MIN_FAMILY_BEST_LINE_WEIGHT)
        })
        .map(|(_, d)| *d)
        .collect();
    if kept.len() < dirs.len() {
        diag.directions = kept.len();
        (lines, doors) = lines::wall_lines_and_doors(&evidence.cells, &kept, res, config);
    }
    lines::drop_crossings(grid, &lines, &mut doors);
    diag.lines = lines.len();
    let trim_m = config.wall_tolerance_m + res;
    let margin_m = config.min_line_separation_m;
    let arr = arrangement::build(
        grid,
        bbox,
        &lines,
        &doors,
        &evidence.near_wall,
        margin_m,
        trim_m,
        &mut diag,
    );
    let mut plan = rooms::group_rooms(grid, Some(bbox), &arr, config, &mut diag);
    predict::predict_rooms(&arr, &mut plan, config, &mut diag);
    rooms::adopt_leftovers(grid, &arr, &mut plan, config);
    let rooms = rooms::room_polygons(grid, &arr, &plan, config, &mut diag);
    Layout {
        rooms,
        lines,
        diagnostics: diag,
    }
}

/// The edges of every room polygon: the walls of the layout, to draw into a map as obstacles.
pub fn layout_walls(layout: &Layout) -> Vec<Segment> {
    layout
        .rooms
        .iter()
        .flat_map(|r| r.polygon.edges())
        .filter(|s| s.length_m() > 1e-9)
        .collect()
}

/// The room whose (predicted) polygon contains `point`, if any (the first one by id).
pub fn room_at(layout: &Layout, point: Vec2) -> Option<&LayoutRoom> {
    layout
        .rooms
        .iter()
        .find(|r| r.polygon.aabb().contains(point) && r.polygon.contains(point))
}
