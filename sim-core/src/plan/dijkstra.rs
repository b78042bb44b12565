//! Dijkstra from the robot over 8-connected traversable cells: one cost field answers the
//! distance to every candidate and gives a path to any of them.
//!
//! Costs are integers: 10 per straight step, 14 per diagonal step (so metres are
//! `cost * resolution / 10`, within 1% of the Euclidean step lengths), plus an optional per-cell
//! extra cost of entering a cell (e.g. near walls, to keep paths centred). Integer costs allow a
//! bucket queue (Dial's algorithm): linear time. Diagonal steps may not cut a corner: both
//! adjacent straight cells must be traversable.
//!
//! Implementation, for speed (results are bit-identical to a plain Dijkstra): [`dijkstra_padded`]
//! searches the planning grid as stored, padded by one blocked cell so that no neighbour needs a
//! bounds check, and stops once every target cell is settled; each cell has one record (cost, entry
//! cost, parent), a blocked cell's with the cost 0 (so that no step improves it: no test of its
//! own), and the eight relaxations of an expansion are tested together as a bit mask before any is
//! applied. [`dijkstra_padded_within`] makes records only for a window of the grid
//! known to hold every passable cell (the part of a building observed so far). [`AStar`] (octile
//! heuristic) finds the path to the one chosen goal on the fine grid, first inside a corridor
//! around the coarse path; its buffers are kept between searches and only the cells a search
//! touched are reset.

use crate::grid::{Bitmap, Cell, Grid, GridFrame};
use crate::mapping::distance_field::ObstacleDistance;

const STRAIGHT: u32 = 10;
const DIAGONAL: u32 = 14;
const UNREACHED: u32 = u32::MAX;
const STEPS: [(i32, i32, u32); 8] = [
    (1, 0, STRAIGHT),
    (-1, 0, STRAIGHT),
    (0, 1, STRAIGHT),
    (0, -1, STRAIGHT),
    (1, 1, DIAGONAL),
    (-1, 1, DIAGONAL),
    (1, -1, DIAGONAL),
    (-1, -1, DIAGONAL),
];

/// Which of the eight steps (in `STEPS` order) may be taken, given each neighbour's entry
/// cost (0 = blocked): a straight step into a passable cell, a diagonal one only when both
/// straight cells beside it are passable too (no cutting corners).
#[inline(always)]
fn allowed_steps(pass: &[u32; 8]) -> [bool; 8] {
    [
        pass[0] != 0,
        pass[1] != 0,
        pass[2] != 0,
        pass[3] != 0,
        (pass[4] != 0) & (pass[0] != 0) & (pass[2] != 0),
        (pass[5] != 0) & (pass[1] != 0) & (pass[2] != 0),
        (pass[6] != 0) & (pass[0] != 0) & (pass[3] != 0),
        (pass[7] != 0) & (pass[1] != 0) & (pass[3] != 0),
    ]
}

/// Costs from the start to every cell, with the step that reached each cell.
#[derive(Debug, Clone, PartialEq)]
pub struct CostField {
    pub frame: GridFrame,
    pub start: Cell,
    /// The part of the frame searched (see [`dijkstra_padded_within`]): its first cell and its
    /// width and height. A cell of the frame outside it is unreachable.
    window: (Cell, usize, usize),
    /// Per cell of the window padded by one cell on every side (row-major, `window.1 + 2`
    /// wide). One array of small records rather than one array per field: a search touches a
    /// cell's cost, entry cost and parent together, and the wavefront visits cells far apart.
    nodes: Vec<Node>,
    /// Whether the search settled every reachable cell (it did not stop at its targets).
    complete: bool,
    /// Costs above this are not final (a search bounded by cost, [`dijkstra_padded_bounded`]):
    /// such a cell reads as not reached. `u32::MAX` = no bound.
    limit: u32,
}

/// The search state of one cell.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Node {
    /// Cost units (see module doc) from the start; `u32::MAX` = not reached. 0 for the start
    /// and for a blocked cell (which no step then improves: no test of its own).
    cost: u32,
    /// 0 = blocked, else 1 + the extra cost of entering the cell.
    enter: u16,
    /// Index into the step table of the step that entered the cell (255 = none).
    parent: u8,
    /// A target of the search not yet settled (in the record's spare byte: no array of its own).
    target: bool,
}

impl CostField {
    /// Whether every reachable cell is settled: `distance_m` is then final for every cell,
    /// not only for the search's targets.
    pub(crate) fn is_complete(&self) -> bool {
        self.complete
    }

    /// Index of `c` in the padded arrays, `None` outside the window.
    fn padded_index(&self, c: Cell) -> Option<usize> {
        let (lo, ww, wh) = self.window;
        let (x, y) = (c.x as i64 - lo.x as i64, c.y as i64 - lo.y as i64);
        (x >= 0 && y >= 0 && (x as usize) < ww && (y as usize) < wh)
            .then(|| (y as usize + 1) * (ww + 2) + x as usize + 1)
    }

    /// Cost units from the start to `c`, `None` if unreachable (a blocked cell's record holds
    /// 0 like the start's).
    fn cost_to(&self, c: Cell) -> Option<u32> {
        let i = self.padded_index(c)?;
        let cost = self.nodes[i].cost;
        (cost != UNREACHED && cost <= self.limit && (cost != 0 || c == self.start)).then_some(cost)
    }

    /// Cost of reaching `c` in metres (extra costs included), `None` if unreachable.
    pub fn distance_m(&self, c: Cell) -> Option<f64> {
        let cost = self.cost_to(c)?;
        Some(cost as f64 * self.frame.resolution_m / STRAIGHT as f64)
    }

    /// Cells from the start to `goal` (both included), `None` if unreachable.
    pub fn path_to(&self, goal: Cell) -> Option<Vec<Cell>> {
        self.cost_to(goal)?;
        let mut i = self.padded_index(goal)?;
        let mut path = vec![goal];
        let mut c = goal;
        while self.nodes[i].parent != 255 {
            let (dx, dy, _) = STEPS[self.nodes[i].parent as usize];
            c = Cell::new(c.x - dx, c.y - dy);
            i = self.padded_index(c)?;
            path.push(c);
        }
        path.reverse();
        Some(path)
    }
}

/// Extra cost of entering each cell: `max_extra` at the inflation radius, falling linearly to 0
/// at `radius_m + band_m` from the nearest obstacle.
pub fn wall_cost(
    obstacles: &ObstacleDistance,
    radius_m: f64,
    band_m: f64,
    max_extra: u8,
) -> Grid<u8> {
    let res = obstacles.frame.resolution_m;
    let data = obstacles
        .data
        .iter()
        .map(|&d| {
            let beyond = (d as f64 * res - radius_m) / band_m.max(1e-9);
            if beyond >= 1.0 {
                0
            } else {
                (max_extra as f64 * (1.0 - beyond.max(0.0))).round() as u8
            }
        })
        .collect();
    Grid {
        frame: obstacles.frame,
        data,
    }
}

/// Dijkstra from `start` over traversable cells. The start cell is always expanded, even if it
/// is not traversable itself (the robot may stand close to a wall). `extra` must share the frame.
pub fn dijkstra(trav: &Bitmap, start: Cell, extra: Option<&Grid<u8>>) -> CostField {
    let extra = extra
        .filter(|e| e.frame == trav.frame)
        .map(|e| e.data.as_slice());
    let max_extra = extra.map_or(0, |e| e.iter().copied().max().unwrap_or(0) as u32);
    dijkstra_by(
        trav.frame,
        start,
        |i| trav.data[i],
        |j| extra.map_or(0, |e| e[j] as u32),
        max_extra,
        &[],
    )
}

/// The general form of [`dijkstra`]: traversability and the extra cost of entering a cell are
/// functions of the cell index (so nothing has to be precomputed over the whole grid), and the
/// search stops as soon as every cell of `targets` is settled (an empty `targets` searches
/// everything reachable). `max_extra` bounds `extra`.
pub(crate) fn dijkstra_by(
    frame: GridFrame,
    start: Cell,
    traversable: impl Fn(usize) -> bool,
    extra: impl Fn(usize) -> u32,
    max_extra: u32,
    targets: &[Cell],
) -> CostField {
    // Everything runs on the frame padded by one blocked cell on every side, so that a cell's
    // neighbours are fixed index offsets with no bounds test.
    let (w, h) = (frame.width as usize, frame.height as usize);
    let pw = w + 2;
    let max_extra = max_extra.min(u16::MAX as u32 - 2);
    // Per padded cell: 0 = blocked, else 1 + the extra cost of entering it.
    let mut enter = vec![0u16; pw * (h + 2)];
    if frame.contains(start) {
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                if traversable(i) {
                    enter[(y + 1) * pw + x + 1] = 1 + extra(i).min(max_extra) as u16;
                }
            }
        }
    }
    dijkstra_padded(frame, start, &enter, max_extra, targets)
}

/// The path lengths (m) between `cells`, row-major (`n * n`; 0 on the diagonal, infinite where
/// no path leads or a cell is `None`): one `search` from each cell to the cells after it (which
/// may stop once it has settled them), its lengths used both ways.
pub(crate) fn lengths_between(
    cells: &[Option<Cell>],
    mut search: impl FnMut(Cell, &[Cell]) -> CostField,
) -> Vec<f64> {
    let n = cells.len();
    let mut out = vec![f64::INFINITY; n * n];
    for i in 0..n {
        out[i * n + i] = 0.0;
        let Some(from) = cells[i] else {
            continue;
        };
        let later: Vec<Cell> = cells[i + 1..].iter().flatten().copied().collect();
        if later.is_empty() {
            continue;
        }
        let field = search(from, &later);
        for j in i + 1..n {
            if let Some(d) = cells[j].and_then(|c| field.distance_m(c)) {
                out[i * n + j] = d;
                out[j * n + i] = d;
            }
        }
    }
    out
}

/// [`dijkstra_by`] on a grid given as it searches it: `enter` covers `frame` padded by one
/// cell on every side (row-major, `frame.width + 2` wide; the padding must be 0), with 0 for a
/// blocked cell and otherwise 1 + the extra cost of entering the cell, at most `max_extra`.
pub(crate) fn dijkstra_padded<T: Copy + Into<u32>>(
    frame: GridFrame,
    start: Cell,
    enter: &[T],
    max_extra: u32,
    targets: &[Cell],
) -> CostField {
    let last = Cell::new(frame.width as i32 - 1, frame.height as i32 - 1);
    dijkstra_padded_within(
        frame,
        start,
        enter,
        max_extra,
        targets,
        (Cell::new(0, 0), last),
    )
}

/// [`dijkstra_padded`] searching only the cells of `window` (its least and greatest corner
/// cells), which must hold every passable cell of the grid: the search is then the same, and
/// costs nothing for the cells outside (a grid of a building's bounding box, of which a search
/// early in a run reaches a small part). A window that does not hold the start and every
/// target in the frame is taken to be the whole frame.
pub(crate) fn dijkstra_padded_within<T: Copy + Into<u32>>(
    frame: GridFrame,
    start: Cell,
    enter: &[T],
    max_extra: u32,
    targets: &[Cell],
    window: (Cell, Cell),
) -> CostField {
    let (mut lo, mut hi) = in_frame(frame, window);
    let inside = |c: &Cell| c.x >= lo.x && c.y >= lo.y && c.x <= hi.x && c.y <= hi.y;
    if !inside(&start) || !targets.iter().filter(|c| frame.contains(**c)).all(inside) {
        (lo, hi) = whole_frame(frame);
    }
    search_window(frame, start, enter, max_extra, targets, (lo, hi), u32::MAX)
}

/// [`dijkstra_padded_within`] without targets, bounded by cost: settles the cells of `window`
/// whose path from `start` costs at most `max_m` metres (extra costs included), and no more. A
/// cell beyond reads as not reached ([`CostField::distance_m`]), whether it is reachable or
/// not; the field is complete only when nothing reachable lies beyond. Only the cells within
/// `max_m` of the start (straight line) can be settled, so the search's window is cut to them.
pub(crate) fn dijkstra_padded_bounded<T: Copy + Into<u32>>(
    frame: GridFrame,
    start: Cell,
    enter: &[T],
    max_extra: u32,
    window: (Cell, Cell),
    max_m: f64,
) -> CostField {
    let max_cost = (max_m / frame.resolution_m * STRAIGHT as f64).floor();
    let max_cost = if max_cost.is_finite() && max_cost >= 0.0 {
        max_cost.min((u32::MAX - 1) as f64) as u32
    } else {
        0
    };
    let (lo, hi) = in_frame(frame, window);
    let inside = start.x >= lo.x && start.y >= lo.y && start.x <= hi.x && start.y <= hi.y;
    let (lo, hi) = if inside { (lo, hi) } else { whole_frame(frame) };
    // A step costs at least `STRAIGHT` per cell of straight-line distance.
    let r = (max_cost / STRAIGHT) as i32 + 1;
    let cut = (
        Cell::new(lo.x.max(start.x - r), lo.y.max(start.y - r)),
        Cell::new(hi.x.min(start.x + r), hi.y.min(start.y + r)),
    );
    search_window(frame, start, enter, max_extra, &[], cut, max_cost)
}

/// `window` cut to the cells of `frame`.
fn in_frame(frame: GridFrame, window: (Cell, Cell)) -> (Cell, Cell) {
    let (w, h) = (frame.width as i32, frame.height as i32);
    (
        Cell::new(window.0.x.max(0), window.0.y.max(0)),
        Cell::new(window.1.x.min(w - 1), window.1.y.min(h - 1)),
    )
}

fn whole_frame(frame: GridFrame) -> (Cell, Cell) {
    let (w, h) = (frame.width as i32, frame.height as i32);
    (Cell::new(0, 0), Cell::new(w - 1, h - 1))
}

/// The search of [`dijkstra_padded_within`] and [`dijkstra_padded_bounded`] on the cells from
/// `lo` to `hi` (in the frame, holding `start` when the frame does): settles cells in order of
/// cost until every target is settled, the next cost is above `max_cost`, or everything
/// reachable is (the field is then complete).
fn search_window<T: Copy + Into<u32>>(
    frame: GridFrame,
    start: Cell,
    enter: &[T],
    max_extra: u32,
    targets: &[Cell],
    (lo, hi): (Cell, Cell),
    max_cost: u32,
) -> CostField {
    let (w, h) = (frame.width as usize, frame.height as usize);
    let pw = w + 2;
    let np = pw * (h + 2);
    assert_eq!(enter.len(), np, "the cost grid must cover the padded frame");
    let max_extra = max_extra.min(u16::MAX as u32 - 2);
    if !frame.contains(start) {
        return CostField {
            frame,
            start,
            window: (Cell::new(0, 0), 0, 0),
            nodes: Vec::new(),
            complete: true,
            limit: max_cost,
        };
    }
    let (ww, wh) = ((hi.x - lo.x + 1) as usize, (hi.y - lo.y + 1) as usize);
    let nodes = window_nodes(enter, pw, lo, (ww, wh), max_extra);
    let mut field = CostField {
        frame,
        start,
        window: (lo, ww, wh),
        nodes,
        complete: true,
        limit: max_cost,
    };
    // From here on, the window padded is the grid searched.
    let pw = ww + 2;
    let pad = |c: Cell| ((c.y - lo.y) as usize + 1) * pw + (c.x - lo.x) as usize + 1;
    let si = pad(start);
    // Targets still to settle, marked in their cells (unmarked as they settle).
    let mut targets_left = 0usize;
    for c in targets.iter().filter(|c| frame.contains(**c)) {
        let n = &mut field.nodes[pad(*c)];
        if !n.target {
            n.target = true;
            targets_left += 1;
        }
    }
    let Some(targets_left) = settle(&mut field.nodes, si, pw, max_extra, targets_left, max_cost)
    else {
        field.complete = false;
        return field;
    };
    // (Targets never reached are left unmarked too: the field says nothing of its targets.)
    if targets_left > 0 {
        for c in targets.iter().filter(|c| frame.contains(**c)) {
            field.nodes[pad(*c)].target = false;
        }
    }
    field
}

/// The records of the search window from `lo`, `ww` x `wh` cells, of the padded grid `enter`
/// (`pw` wide), padded by one blocked cell on every side.
fn window_nodes<T: Copy + Into<u32>>(
    enter: &[T],
    pw: usize,
    lo: Cell,
    (ww, wh): (usize, usize),
    max_extra: u32,
) -> Vec<Node> {
    // (Also the record of a blocked cell: its cost 0, see `Node::cost`.)
    let unreached = Node {
        cost: 0,
        enter: 0,
        parent: 255,
        target: false,
    };
    // The window's records, padded by one blocked cell on every side (the cells there, if in
    // the frame, are not passable: the window holds every passable cell). (Clamped, so that a
    // grid breaking the `max_extra` promise cannot overrun the bucket ring. Made from the grid
    // in one pass, not filled and then given their entry costs: a search that stops at a near
    // target costs little more than this.)
    let qw = ww + 2;
    let mut nodes = Vec::with_capacity(qw * (wh + 2));
    nodes.resize(qw, unreached);
    for y in 0..wh {
        let from = (lo.y as usize + y + 1) * pw + lo.x as usize + 1;
        nodes.push(unreached);
        nodes.extend(enter[from..from + ww].iter().map(|&e| {
            let e = Into::<u32>::into(e).min(max_extra + 1);
            Node {
                // (`UNREACHED` for a passable cell, 0 for a blocked one.)
                cost: 0u32.wrapping_sub((e != 0) as u32),
                enter: e as u16,
                ..unreached
            }
        }));
        nodes.push(unreached);
    }
    nodes.resize(qw * (wh + 2), unreached);
    nodes
}

/// The search itself on the padded window `nodes` (`pw` wide) from the cell of index `si`,
/// with `targets_left` targets marked: settles cells in order of cost until every target is
/// settled (`None`) or every reachable cell is (`Some`: the targets left).
fn settle(
    nodes: &mut [Node],
    si: usize,
    pw: usize,
    max_extra: u32,
    mut targets_left: usize,
    max_cost: u32,
) -> Option<usize> {
    // A ring of buckets, one per cost modulo its length (a power of two at least the spread
    // of costs pending at once, `DIAGONAL + max_extra + 1`: the bucket of a cost by a mask).
    let nb = ((DIAGONAL + max_extra + 1) as usize).next_power_of_two();
    let ring = nb - 1;
    let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); nb];
    let offsets: [isize; 8] = STEPS.map(|(dx, dy, _)| dy as isize * pw as isize + dx as isize);
    nodes[si].cost = 0;
    buckets[0].push(si as u32);
    let mut pending = 1usize;
    let mut current = 0u32;
    while pending > 0 {
        if current > max_cost {
            // Every cell of cost up to `max_cost` is settled; the rest is not searched.
            return None;
        }
        let b = current as usize & ring;
        // The bucket being emptied is taken out of the ring (the steps it pushes go to other
        // buckets: each costs from `current + 10` to `current + nb - 1`).
        let mut bucket = std::mem::take(&mut buckets[b]);
        pending -= bucket.len();
        while let Some(i) = bucket.pop() {
            let i = i as usize;
            if nodes[i].cost != current {
                continue; // stale entry
            }
            if nodes[i].target {
                nodes[i].target = false;
                targets_left -= 1;
                if targets_left == 0 {
                    return None;
                }
            }
            // The cell's neighbours, in `STEPS` order, read from the three rows around it (every
            // expanded cell is inside the frame, so its neighbours are in the padding).
            let below: &[Node; 3] = nodes[i - pw - 1..i - pw + 2].try_into().expect("3");
            let row: &[Node; 3] = nodes[i - 1..i + 2].try_into().expect("3");
            let above: &[Node; 3] = nodes[i + pw - 1..i + pw + 2].try_into().expect("3");
            let near = [
                row[2], row[0], above[1], below[1], above[2], above[0], below[2], below[0],
            ];
            // Which steps are allowed and improve their cell, found for all eight before any is
            // applied (they are distinct cells), as a bit mask: fewer unpredictable branches than
            // testing and applying one step at a time. A step improves its cell when its cost is
            // below the cell's (never a blocked cell's: its cost is 0); a diagonal step is
            // allowed only when both straight cells beside it are passable (no cutting corners).
            let open = |k: usize| near[k].enter != 0;
            let corners = [
                open(0) & open(2),
                open(1) & open(2),
                open(0) & open(3),
                open(1) & open(3),
            ];
            let mut improved = 0u32;
            for (k, &(_, _, step)) in STEPS.iter().enumerate() {
                // (With `enter == 0` this is one below the step, and no improvement.)
                let c = (current + step + near[k].enter as u32).wrapping_sub(1);
                let allowed = k < 4 || corners[k - 4];
                improved |= ((allowed & (c < near[k].cost)) as u32) << k;
            }
            while improved != 0 {
                let k = improved.trailing_zeros() as usize;
                improved &= improved - 1;
                let j = (i as isize + offsets[k]) as usize;
                let n = &mut nodes[j];
                let c = current + STEPS[k].2 + n.enter as u32 - 1;
                n.cost = c;
                n.parent = k as u8;
                buckets[c as usize & ring].push(j as u32);
                pending += 1;
            }
        }
        buckets[b] = bucket;
        current += 1;
    }
    Some(targets_left)
}

/// The cheapest path from `start` to `goal` on a grid given as [`dijkstra_padded`] takes it,
/// found by A* (octile distance as the heuristic, consistent with the step costs, so the cost
/// is the one Dijkstra finds; among paths of equal cost it may pick another). Its buffers are
/// kept between searches and only the cells a search touched are reset, so a short path costs
/// little however large the grid. An unreachable goal costs a search of everything reachable
/// (in [`AStar::path_or_reached`], of the smaller of the parts of the start and of the goal).
#[derive(Debug, Clone, Default)]
pub struct AStar {
    /// Per padded cell: cost units from the start (`u32::MAX` = not reached) and the step that
    /// entered the cell.
    cost: Vec<u32>,
    parent: Vec<u8>,
    touched: Vec<u32>,
    buckets: Vec<Vec<u32>>,
    /// Per padded cell, for [`AStar::connected`]: 0, or which flood reached it (1 from the
    /// start, 2 from the goal); and each flood's cells in the order reached.
    flooded: Vec<u8>,
    floods: [Vec<u32>; 2],
}

/// The index of `c` (in `frame`) in a grid of `frame` padded by one cell on every side, as
/// [`dijkstra_padded`] and [`AStar`] take them.
pub(crate) fn padded_index(frame: &GridFrame, c: Cell) -> usize {
    (c.y as usize + 1) * (frame.width as usize + 2) + c.x as usize + 1
}

impl AStar {
    /// The path (start and goal included) and its cost in metres (extra costs included), or
    /// `None` when `goal` cannot be reached.
    pub fn path<T: Copy + Into<u32>>(
        &mut self,
        frame: GridFrame,
        start: Cell,
        enter: &[T],
        max_extra: u32,
        goal: Cell,
    ) -> Option<(Vec<Cell>, f64)> {
        self.path_within(frame, start, enter, max_extra, goal, |_| true)
    }

    /// [`AStar::path`], the search run only once floods from both ends have met
    /// ([`AStar::connected`]: an unreachable goal in a small part of the grid, beyond a gap too
    /// narrow, costs that part rather than everything reachable). When `goal` cannot be
    /// reached, `reached` (cleared first) holds every cell that can, by index in the padded
    /// frame ([`padded_index`]), when the start's flood went everywhere it could (another goal
    /// not among them cannot be reached either); otherwise it is empty (the goal's part was
    /// the smaller, or a start or goal lies outside the frame).
    pub(crate) fn path_or_reached<T: Copy + Into<u32>>(
        &mut self,
        frame: GridFrame,
        start: Cell,
        enter: &[T],
        max_extra: u32,
        goal: Cell,
        reached: &mut Vec<u32>,
    ) -> Option<(Vec<Cell>, f64)> {
        reached.clear();
        if frame.contains(start)
            && frame.contains(goal)
            && !self.connected(frame, enter, start, goal, reached)
        {
            return None;
        }
        self.search_within(
            frame,
            start,
            enter,
            max_extra,
            goal,
            |_| true,
            Some(reached),
        )
    }

    /// Whether a path (of the search's steps) leads from `start` to `goal` (both in `frame`), by
    /// two breadth-first floods taking turns, one from each: they meet, or one of them runs
    /// out of cells having gone through its part of the grid, at about twice the cost of the
    /// smaller part. When the start's runs out, `reached` gets its cells: every cell reachable
    /// from the start (as the search's). Steps are symmetric (a diagonal one needs the same
    /// two cells beside it both ways); the start is left even when blocked (as by the search),
    /// and the goal's flood meets the start's in the cells the start's first steps reach.
    fn connected<T: Copy + Into<u32>>(
        &mut self,
        frame: GridFrame,
        enter: &[T],
        start: Cell,
        goal: Cell,
        reached: &mut Vec<u32>,
    ) -> bool {
        let pw = frame.width as usize + 2;
        let np = pw * (frame.height as usize + 2);
        assert_eq!(enter.len(), np, "the cost grid must cover the padded frame");
        if self.flooded.len() != np {
            self.flooded = vec![0; np];
        }
        let (si, gi) = (padded_index(&frame, start), padded_index(&frame, goal));
        if si == gi {
            return true;
        }
        let offsets: [isize; 8] = STEPS.map(|(dx, dy, _)| dy as isize * pw as isize + dx as isize);
        let open = |j: usize| Into::<u32>::into(enter[j]);
        let [mut from_start, mut from_goal] = std::mem::take(&mut self.floods);
        from_start.clear();
        from_goal.clear();
        self.flooded[si] = 1;
        from_start.push(si as u32);
        self.flooded[gi] = 2;
        from_goal.push(gi as u32);
        let mut heads = [0usize; 2];
        let met = 'flood: loop {
            for (side, head) in heads.iter_mut().enumerate() {
                let (flood, mark) = if side == 0 {
                    (&mut from_start, 1u8)
                } else {
                    (&mut from_goal, 2u8)
                };
                let Some(&i) = flood.get(*head) else {
                    if side == 0 {
                        reached.extend_from_slice(flood);
                    }
                    break 'flood false;
                };
                *head += 1;
                let i = i as usize;
                // (Every cell flooded is inside the frame: its neighbours are in the padding at
                // worst.)
                let at = |k: usize| open((i as isize + offsets[k]) as usize);
                let pass: [u32; 8] = [at(0), at(1), at(2), at(3), at(4), at(5), at(6), at(7)];
                let ok = allowed_steps(&pass);
                for k in 0..8 {
                    if !ok[k] {
                        continue;
                    }
                    let j = (i as isize + offsets[k]) as usize;
                    match self.flooded[j] {
                        0 => {
                            self.flooded[j] = mark;
                            flood.push(j as u32);
                        }
                        m if m != mark => break 'flood true,
                        _ => {}
                    }
                }
            }
        };
        for &i in from_start.iter().chain(&from_goal) {
            self.flooded[i as usize] = 0;
        }
        self.floods = [from_start, from_goal];
        met
    }

    /// [`AStar::path`] through the cells for which `allowed` holds only (the start excepted),
    /// e.g. a corridor around a path found on a coarser grid.
    pub(crate) fn path_within<T: Copy + Into<u32>>(
        &mut self,
        frame: GridFrame,
        start: Cell,
        enter: &[T],
        max_extra: u32,
        goal: Cell,
        allowed: impl Fn(Cell) -> bool,
    ) -> Option<(Vec<Cell>, f64)> {
        self.search_within(frame, start, enter, max_extra, goal, allowed, None)
    }

    #[allow(clippy::too_many_arguments)]
    fn search_within<T: Copy + Into<u32>>(
        &mut self,
        frame: GridFrame,
        start: Cell,
        enter: &[T],
        max_extra: u32,
        goal: Cell,
        allowed: impl Fn(Cell) -> bool,
        reached: Option<&mut Vec<u32>>,
    ) -> Option<(Vec<Cell>, f64)> {
        let (w, h) = (frame.width as usize, frame.height as usize);
        let pw = w + 2;
        let np = pw * (h + 2);
        assert_eq!(enter.len(), np, "the cost grid must cover the padded frame");
        if !frame.contains(start) || !frame.contains(goal) {
            return None;
        }
        let max_extra = max_extra.min(u16::MAX as u32 - 2);
        if self.cost.len() != np {
            self.cost = vec![UNREACHED; np];
            self.parent = vec![255; np];
            self.touched.clear();
        }
        // Keys are `cost + heuristic`; a step raises the key by at most two diagonal steps and
        // the extra cost. (A ring of a power of two buckets: a key's bucket by a mask.)
        let nb = ((2 * DIAGONAL + max_extra + 1) as usize).next_power_of_two();
        self.buckets.resize_with(nb, Vec::new);
        let found = self.search(pw, enter, max_extra, nb, start, goal, allowed);
        let result = found.map(|cost| {
            let mut path = vec![goal];
            let mut c = goal;
            let mut i = (c.y as usize + 1) * pw + c.x as usize + 1;
            while self.parent[i] != 255 {
                let (dx, dy, _) = STEPS[self.parent[i] as usize];
                c = Cell::new(c.x - dx, c.y - dy);
                i = (c.y as usize + 1) * pw + c.x as usize + 1;
                path.push(c);
            }
            path.reverse();
            (path, cost as f64 * frame.resolution_m / STRAIGHT as f64)
        });
        if let (None, Some(reached)) = (&result, reached) {
            // Every cell the search gave a cost to, and no other, can be reached.
            reached.extend_from_slice(&self.touched);
        }
        for &i in &self.touched {
            self.cost[i as usize] = UNREACHED;
            self.parent[i as usize] = 255;
        }
        self.touched.clear();
        for b in &mut self.buckets {
            b.clear();
        }
        result
    }

    /// The search itself: the goal's cost, `None` if unreachable.
    #[allow(clippy::too_many_arguments)]
    fn search<T: Copy + Into<u32>>(
        &mut self,
        pw: usize,
        enter: &[T],
        max_extra: u32,
        nb: usize,
        start: Cell,
        goal: Cell,
        allowed: impl Fn(Cell) -> bool,
    ) -> Option<u32> {
        let pad = |c: Cell| (c.y as usize + 1) * pw + c.x as usize + 1;
        let (si, gi) = (pad(start), pad(goal));
        // Octile distance to the goal in cost units: a lower bound of every path's cost, and
        // consistent (it falls by at most a step's cost per step).
        let heuristic = |c: Cell| -> u32 {
            let (dx, dy) = (c.x.abs_diff(goal.x), c.y.abs_diff(goal.y));
            STRAIGHT * dx.max(dy) + (DIAGONAL - STRAIGHT) * dx.min(dy)
        };
        // (A padded index's cell by one division; its neighbours' cells by a step from it.)
        let cell_of = |i: usize| Cell::new((i % pw) as i32 - 1, (i / pw) as i32 - 1);
        let offsets: [isize; 8] = STEPS.map(|(dx, dy, _)| dy as isize * pw as isize + dx as isize);
        let pass_of = |j: usize, cell: Cell| {
            if allowed(cell) {
                Into::<u32>::into(enter[j]).min(max_extra + 1)
            } else {
                0
            }
        };
        self.cost[si] = 0;
        self.touched.push(si as u32);
        let mut current = heuristic(start);
        let ring = nb - 1;
        self.buckets[current as usize & ring].push(si as u32);
        let mut pending = 1usize;
        while pending > 0 {
            let b = current as usize & ring;
            while let Some(i) = self.buckets[b].pop() {
                pending -= 1;
                let i = i as usize;
                let g = self.cost[i];
                let here = cell_of(i);
                if g.wrapping_add(heuristic(here)) != current {
                    continue; // stale entry
                }
                if i == gi {
                    return Some(g);
                }
                // Every expanded cell is inside the frame (the start, or entered through a
                // passable cell), so its neighbours are in the padding at worst.
                let near = |k: usize| Cell::new(here.x + STEPS[k].0, here.y + STEPS[k].1);
                let at = |k: usize| pass_of((i as isize + offsets[k]) as usize, near(k));
                let pass: [u32; 8] = [at(0), at(1), at(2), at(3), at(4), at(5), at(6), at(7)];
                // The steps allowed that improve their cell, found for all eight before any is
                // applied (as in `dijkstra_padded_within`: fewer unpredictable branches).
                let ok = allowed_steps(&pass);
                let mut improved = 0u32;
                for (k, &(_, _, step)) in STEPS.iter().enumerate() {
                    let j = (i as isize + offsets[k]) as usize;
                    // (With `pass[k] == 0` this is one below the step, and unused.)
                    let c = (g + step + pass[k]).wrapping_sub(1);
                    improved |= ((ok[k] & (c < self.cost[j])) as u32) << k;
                }
                while improved != 0 {
                    let k = improved.trailing_zeros() as usize;
                    improved &= improved - 1;
                    let j = (i as isize + offsets[k]) as usize;
                    let c = g + STEPS[k].2 + pass[k] - 1;
                    if self.cost[j] == UNREACHED {
                        self.touched.push(j as u32);
                    }
                    self.cost[j] = c;
                    self.parent[j] = k as u8;
                    self.buckets[(c + heuristic(near(k))) as usize & ring].push(j as u32);
                    pending += 1;
                }
            }
            current += 1;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::OccupancyGrid;
    use crate::plan::inflate::traversable_from_grid;

    fn trav(s: &str) -> Bitmap {
        traversable_from_grid(&OccupancyGrid::from_ascii(s, 0.1), 0.0)
    }

    /// Costs by a textbook Dijkstra (binary heap, explicit bounds tests).
    fn reference_costs(trav: &[bool], extra: &[u8], w: i32, h: i32, s: (i32, i32)) -> Vec<u32> {
        use std::cmp::Reverse;
        let mut cost = vec![UNREACHED; (w * h) as usize];
        let mut heap = std::collections::BinaryHeap::new();
        cost[(s.1 * w + s.0) as usize] = 0;
        heap.push(Reverse((0u32, s.0, s.1)));
        let ok = |x: i32, y: i32| x >= 0 && y >= 0 && x < w && y < h && trav[(y * w + x) as usize];
        while let Some(Reverse((c, x, y))) = heap.pop() {
            if c != cost[(y * w + x) as usize] {
                continue;
            }
            for &(dx, dy, step) in &STEPS {
                if !ok(x + dx, y + dy) || (dx != 0 && dy != 0 && !(ok(x + dx, y) && ok(x, y + dy)))
                {
                    continue;
                }
                let j = ((y + dy) * w + x + dx) as usize;
                let n = c + step + extra[j] as u32;
                if n < cost[j] {
                    cost[j] = n;
                    heap.push(Reverse((n, x + dx, y + dy)));
                }
            }
        }
        cost
    }

    proptest::proptest! {
        #[test]
        fn costs_equal_a_textbook_dijkstra(
            cells in proptest::collection::vec((proptest::bool::weighted(0.75), 0u8..6), 23 * 17),
            sx in 0i32..23, sy in 0i32..17,
        ) {
            let (w, h) = (23, 17);
            let trav: Vec<bool> = cells.iter().map(|c| c.0).collect();
            let extra: Vec<u8> = cells.iter().map(|c| c.1).collect();
            let frame = GridFrame::new(crate::geom::Vec2::zeros(), 0.1, w as u32, h as u32);
            let f = dijkstra_by(frame, Cell::new(sx, sy), |i| trav[i], |j| extra[j] as u32, 5, &[]);
            let reference = reference_costs(&trav, &extra, w, h, (sx, sy));
            for y in 0..h {
                for x in 0..w {
                    let c = Cell::new(x, y);
                    let want = reference[(y * w + x) as usize];
                    let got = f.distance_m(c);
                    proptest::prop_assert_eq!(
                        got,
                        (want != UNREACHED).then(|| want as f64 * 0.1 / STRAIGHT as f64)
                    );
                    // Every path runs from the start through traversable steps to the cell.
                    if let Some(path) = f.path_to(c) {
                        proptest::prop_assert_eq!(path[0], Cell::new(sx, sy));
                        proptest::prop_assert_eq!(*path.last().unwrap(), c);
                    }
                }
            }
        }
    }

    /// A `w` x `h` grid at 0.1 m, padded: a cell passable (entry cost `1 + extra`) or not.
    fn padded_grid(cells: &[(bool, u8)], w: usize, h: usize) -> (GridFrame, Vec<u8>) {
        let frame = GridFrame::new(crate::geom::Vec2::zeros(), 0.1, w as u32, h as u32);
        let mut padded = vec![0u8; (w + 2) * (h + 2)];
        for (i, &(passable, extra)) in cells.iter().enumerate() {
            if passable {
                padded[(i / w + 1) * (w + 2) + i % w + 1] = 1 + extra;
            }
        }
        (frame, padded)
    }

    /// A 23 x 17 grid's cells (each passable with probability `open`, an extra cost of 0-5),
    /// a start and a goal in it.
    fn search_case(
        open: f64,
    ) -> impl proptest::strategy::Strategy<Value = (Vec<(bool, u8)>, Cell, Cell)> {
        use proptest::strategy::Strategy;
        let cell = || (0i32..23, 0i32..17).prop_map(|(x, y)| Cell::new(x, y));
        (
            proptest::collection::vec((proptest::bool::weighted(open), 0u8..6), 23 * 17),
            cell(),
            cell(),
        )
    }

    proptest::proptest! {
        #[test]
        fn a_star_finds_the_cost_dijkstra_finds((cells, start, goal) in search_case(0.7)) {
            let (w, h) = (23usize, 17usize);
            let (frame, padded) = padded_grid(&cells, w, h);
            let d = dijkstra_padded(frame, start, &padded, 5, &[]);
            // One search object for two searches: the second must not see the first's state.
            let mut astar = AStar::default();
            let _ = astar.path(frame, goal, &padded, 5, start);
            let a = astar.path(frame, start, &padded, 5, goal);
            proptest::prop_assert_eq!(a.as_ref().map(|a| a.1), d.distance_m(goal));
            if let Some((path, distance_m)) = a {
                proptest::prop_assert_eq!(path[0], start);
                proptest::prop_assert_eq!(*path.last().unwrap(), goal);
                // The path's own cost is the one reported: steps and entry costs add up.
                let mut cost = 0u32;
                for s in path.windows(2) {
                    let (dx, dy) = (s[1].x - s[0].x, s[1].y - s[0].y);
                    proptest::prop_assert!(dx.abs() <= 1 && dy.abs() <= 1);
                    let entry = padded[(s[1].y as usize + 1) * (w + 2) + s[1].x as usize + 1] as u32;
                    proptest::prop_assert!(entry > 0, "the path enters a blocked cell");
                    cost += if dx != 0 && dy != 0 { DIAGONAL } else { STRAIGHT } + entry - 1;
                }
                proptest::prop_assert_eq!(cost as f64 * 0.1 / STRAIGHT as f64, distance_m);
            }
        }
    }

    proptest::proptest! {
        /// A search with targets stops once it has settled them all, with their costs those of
        /// the search without; one that settles everything reachable (a target it cannot reach)
        /// is the search without targets, record for record (its targets' marks cleared).
        #[test]
        fn a_search_with_targets_is_the_search_without_at_its_targets(
            (cells, start, goal) in search_case(0.6),
            more in proptest::collection::vec((0i32..23, 0i32..17), 0..4),
        ) {
            let (w, h) = (23usize, 17usize);
            let (frame, padded) = padded_grid(&cells, w, h);
            let all = dijkstra_padded(frame, start, &padded, 5, &[]);
            let mut targets: Vec<Cell> = more.into_iter().map(|(x, y)| Cell::new(x, y)).collect();
            targets.push(goal);
            let some = dijkstra_padded(frame, start, &padded, 5, &targets);
            let reachable = targets.iter().all(|c| all.distance_m(*c).is_some());
            proptest::prop_assert_eq!(some.is_complete(), !reachable);
            for c in &targets {
                proptest::prop_assert_eq!(some.distance_m(*c), all.distance_m(*c));
            }
            proptest::prop_assert!(reachable || some == all, "an unreachable target: {:?}", targets);
        }
    }

    proptest::proptest! {
        /// A search within a window holding every passable cell is the search of the whole
        /// grid: every cell's cost and path are the same (a cell outside is unreachable); a
        /// window without the start or a target is the whole grid.
        #[test]
        fn a_search_within_a_window_of_the_passable_cells_is_the_whole_search(
            (cells, start, goal) in search_case(0.7),
            (x0, y0, x1, y1) in (0i32..12, 0i32..9, 11i32..23, 8i32..17),
            grow in 0i32..3,
        ) {
            let (w, h) = (23usize, 17usize);
            // Passable cells only within the box (x0, y0)-(x1, y1).
            let boxed: Vec<(bool, u8)> = cells
                .iter()
                .enumerate()
                .map(|(i, &(open, extra))| {
                    let (x, y) = ((i % w) as i32, (i / w) as i32);
                    (open && x >= x0 && x <= x1 && y >= y0 && y <= y1, extra)
                })
                .collect();
            let (frame, padded) = padded_grid(&boxed, w, h);
            let window = (Cell::new(x0 - grow, y0 - grow), Cell::new(x1 + grow, y1 + grow));
            for targets in [vec![], vec![goal]] {
                let all = dijkstra_padded(frame, start, &padded, 5, &targets);
                let within = dijkstra_padded_within(frame, start, &padded, 5, &targets, window);
                proptest::prop_assert_eq!(within.is_complete(), all.is_complete());
                for y in -1..=h as i32 {
                    for x in -1..=w as i32 {
                        let c = Cell::new(x, y);
                        proptest::prop_assert_eq!(within.distance_m(c), all.distance_m(c));
                        proptest::prop_assert_eq!(within.path_to(c), all.path_to(c));
                    }
                }
            }
        }
    }

    proptest::proptest! {
        /// A search bounded by cost gives every cell whose cost is within the bound the cost
        /// and the path of the whole search, and no other cell a cost; it is complete exactly
        /// when everything reachable is within the bound.
        #[test]
        fn a_bounded_search_is_the_whole_search_within_its_bound(
            (cells, start, _goal) in search_case(0.7),
            bound_m in 0.0f64..4.0,
        ) {
            let (w, h) = (23usize, 17usize);
            let (frame, padded) = padded_grid(&cells, w, h);
            let all = dijkstra_padded(frame, start, &padded, 5, &[]);
            let last = Cell::new(w as i32 - 1, h as i32 - 1);
            let bounded =
                dijkstra_padded_bounded(frame, start, &padded, 5, (Cell::new(0, 0), last), bound_m);
            // (A cost at the bound itself counts as within: the bound's cost units rounded down.)
            let within = |d: f64| d <= (bound_m / 0.1 * STRAIGHT as f64).floor() * 0.1 / STRAIGHT as f64;
            let mut beyond = false;
            for y in -1..=h as i32 {
                for x in -1..=w as i32 {
                    let c = Cell::new(x, y);
                    match all.distance_m(c) {
                        Some(d) if within(d) => {
                            proptest::prop_assert_eq!(bounded.distance_m(c), Some(d));
                            proptest::prop_assert_eq!(bounded.path_to(c), all.path_to(c));
                        }
                        Some(_) => {
                            beyond = true;
                            proptest::prop_assert_eq!(bounded.distance_m(c), None);
                        }
                        None => proptest::prop_assert_eq!(bounded.distance_m(c), None),
                    }
                }
            }
            proptest::prop_assert_eq!(bounded.is_complete(), !beyond);
        }
    }

    proptest::proptest! {
        /// A search gives the path `path` gives (none exactly when the goal cannot be reached);
        /// a failed one reports every cell that can be reached from the start and no other (the
        /// cells Dijkstra gives a cost to), or nothing when the goal's part of the grid was the
        /// smaller (and its flood ran out first); one that finds its goal reports none.
        #[test]
        fn a_failed_search_reports_every_reachable_cell((cells, start, goal) in search_case(0.6)) {
            let (w, h) = (23usize, 17usize);
            let (frame, padded) = padded_grid(&cells, w, h);
            let d = dijkstra_padded(frame, start, &padded, 5, &[]);
            let mut astar = AStar::default();
            let mut reached = vec![7];
            let got = astar.path_or_reached(frame, start, &padded, 5, goal, &mut reached);
            proptest::prop_assert_eq!(&got, &AStar::default().path(frame, start, &padded, 5, goal));
            proptest::prop_assert_eq!(got.is_some(), d.distance_m(goal).is_some() && cells[goal.y as usize * w + goal.x as usize].0 || start == goal);
            reached.sort_unstable();
            let part = |d: &CostField| -> Vec<u32> {
                (0..h as i32)
                    .flat_map(|y| (0..w as i32).map(move |x| Cell::new(x, y)))
                    .filter(|c| d.distance_m(*c).is_some())
                    .map(|c| padded_index(&frame, c) as u32)
                    .collect()
            };
            let want = part(&d);
            // Apart, the floods take turns from the start's: the goal's runs out first only when
            // its part has fewer cells, and then nothing is reported; when the parts touch (a
            // blocked goal beside the start's part), either flood may end it.
            let goal_part = part(&dijkstra_padded(frame, goal, &padded, 5, &[]));
            let touch = goal_part.iter().any(|i| want.binary_search(i).is_ok());
            let allowed: Vec<Vec<u32>> = match (got.is_some(), goal_part.len() < want.len(), touch) {
                (true, ..) => vec![Vec::new()],
                (false, false, _) => vec![want],
                (false, true, false) => vec![Vec::new()],
                (false, true, true) => vec![want, Vec::new()],
            };
            proptest::prop_assert!(allowed.contains(&reached), "{:?} not in {:?}", reached, allowed);
        }
    }

    #[test]
    fn path_goes_around_a_wall() {
        let t = trav(
            "
            .......
            ...#...
            ...#...
            ...#...",
        );
        let f = dijkstra(&t, Cell::new(1, 0), None);
        let goal = Cell::new(5, 0);
        let path = f.path_to(goal).unwrap();
        assert_eq!(path.first(), Some(&Cell::new(1, 0)));
        assert_eq!(path.last(), Some(&goal));
        assert!(path.iter().all(|c| t.get(*c) == Some(&true)));
        assert!(
            path.iter().any(|c| c.y == 3),
            "must pass above the wall: {path:?}"
        );
        let d = f.distance_m(goal).unwrap();
        assert!(d > 0.6 && d < 1.0, "{d}");
        for w in path.windows(2) {
            assert!((w[0].x - w[1].x).abs() <= 1 && (w[0].y - w[1].y).abs() <= 1);
        }
    }

    /// A goal beyond a wall: whichever side is the smaller part, no path; the cells reachable
    /// from the start are reported when the start's part is the smaller.
    #[test]
    fn an_unreachable_goal_costs_the_smaller_part() {
        let t = trav(
            "
            .#.........
            .#.........
            ##.........",
        );
        let cells: Vec<(bool, u8)> = t.data.iter().map(|&open| (open, 0)).collect();
        let (frame, padded) = padded_grid(&cells, t.frame.width as usize, t.frame.height as usize);
        // (The first row drawn is the top one, y = 2.)
        let (pocket, open) = (Cell::new(0, 2), Cell::new(8, 1));
        let mut astar = AStar::default();
        let mut reached = Vec::new();
        // From the pocket (two cells): its flood runs out first and reports them.
        assert_eq!(
            astar.path_or_reached(frame, pocket, &padded, 5, open, &mut reached),
            None
        );
        reached.sort_unstable();
        let want: Vec<u32> = [Cell::new(0, 1), Cell::new(0, 2)]
            .map(|c| padded_index(&frame, c) as u32)
            .into();
        assert_eq!(reached, want);
        // From the open side: the pocket's flood runs out first, nothing reported.
        assert_eq!(
            astar.path_or_reached(frame, open, &padded, 5, pocket, &mut reached),
            None
        );
        assert!(reached.is_empty());
        // Within the open side: the path.
        let path = astar.path_or_reached(frame, open, &padded, 5, Cell::new(2, 0), &mut reached);
        assert_eq!(path.map(|(p, _)| *p.last().unwrap()), Some(Cell::new(2, 0)));
    }

    #[test]
    fn unreachable_goal_gives_none() {
        let t = trav(
            "
            ...#...
            ...#...",
        );
        let f = dijkstra(&t, Cell::new(0, 0), None);
        assert_eq!(f.path_to(Cell::new(5, 0)), None);
        assert_eq!(f.distance_m(Cell::new(5, 0)), None);
        // One diagonal (14) and one straight (10) step at 0.1 m.
        assert!((f.distance_m(Cell::new(2, 1)).unwrap() - 0.24).abs() < 1e-9);
        assert_eq!(f.path_to(Cell::new(0, 0)), Some(vec![Cell::new(0, 0)]));
        // Outside start: nothing reachable, no panic.
        let f = dijkstra(&t, Cell::new(-3, 0), None);
        assert_eq!(f.distance_m(Cell::new(0, 0)), None);
    }

    #[test]
    fn wall_cost_pushes_paths_to_the_middle() {
        let g = OccupancyGrid::from_ascii(
            "
            ###########
            ...........
            ...........
            ...........
            ...........
            ...........
            ###########",
            0.1,
        );
        let t = traversable_from_grid(&g, 0.0);
        let obstacles = ObstacleDistance::from_grid(&g, 6);
        let extra = wall_cost(&obstacles, 0.0, 0.3, 20);
        let f = dijkstra(&t, Cell::new(0, 1), Some(&extra));
        let path = f.path_to(Cell::new(10, 1)).unwrap();
        assert!(path.iter().any(|c| c.y >= 3), "{path:?}");
        let plain = dijkstra(&t, Cell::new(0, 1), None)
            .path_to(Cell::new(10, 1))
            .unwrap();
        assert!(plain.iter().all(|c| c.y == 1));
    }
}
