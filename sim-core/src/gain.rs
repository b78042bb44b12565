//! Information gain `I(p)`: the area of unknown cells a laser at `p` could see.
//!
//! Visibility is approximated by casting rays **over 360 degrees** (the robot can turn on the
//! spot) from the centre of `p`'s cell with an exact cell walk, so densely (one ray per cell of
//! arc at full range) that every cell at range is crossed by a ray. A ray stops at the first
//! blocking cell or at the range; a cell counts (once: a byte set over the disc) when its
//! centre is within range.
//! The same core serves the layout variant, which passes other `blocks` / `counts` predicates.
//!
//! Implementation: the 360-degree rays are stored as a prefix tree of cell offsets, built once per
//! range, so the cells that rays share near `p` are tested once, and a blocked cell skips every ray
//! through it. Between decisions, `explore::gain_cache` reuses a candidate's gain while no cell
//! its rays read has changed ([`CellsRead`]: the boxes of the cells read, and where each ray
//! stopped, [`RayStops`], noted only where the walk skips a subtree; a changed cell is looked up
//! among the rays through it).

use crate::grid::{Cell, GridFrame, Occupancy, OccupancyGrid};
use crate::mapping::ray::walk_segment;

/// Area (m2) of the cells within `range_m` of cell `p` that are visible from `p` (no blocking
/// cell on the way, the blocking cell itself excluded) and satisfy `counts`. Cells outside the
/// frame block. Both predicates must be pure: they may be asked about a cell more than once.
pub fn visible_area(
    frame: &GridFrame,
    p: Cell,
    range_m: f64,
    blocks: impl Fn(Cell) -> bool,
    counts: impl Fn(Cell) -> bool,
) -> f64 {
    visible_area_read(frame, p, range_m, |c, _| blocks(c), |c, _| counts(c)).0
}

/// A box of cells, corners included (it may reach outside the frame).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct CellBox {
    pub min: Cell,
    pub max: Cell,
}

/// Where the cells lie whose predicates a visible area read: in the union of four boxes, one
/// per quadrant around the centre cell `p` (each holds `p`), and on the rays up to where they
/// stopped ([`RayStops`]). The area stays the same while no cell read changes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct CellsRead {
    pub boxes: [CellBox; 4],
    pub rays: RayStops,
}

impl CellsRead {
    /// Only the cell `c`.
    pub(crate) fn of(c: Cell) -> Self {
        Self {
            boxes: [CellBox { min: c, max: c }; 4],
            rays: RayStops::default(),
        }
    }

    /// Whether the visible area from `p` that this describes may have read the cell `c`: when
    /// the rays' stops are kept, whether it lies on a ray at or before where it stopped (which
    /// lies in the boxes); otherwise whether it lies in a box.
    #[inline]
    pub(crate) fn may_have_read(&self, p: Cell, c: Cell) -> bool {
        self.rays.read(p, c).unwrap_or_else(|| {
            let holds =
                |b: &CellBox| b.min.x <= c.x && c.x <= b.max.x && b.min.y <= c.y && c.y <= b.max.y;
            self.boxes.iter().any(holds)
        })
    }
}

/// Where each ray of a visible area stopped: ray `k` (at the angle `k 2 pi / n` from the
/// centre of the centre cell, `n` rays) read the first `stops[k] + 1` cells of its walk. Empty
/// when not kept (a walk longer than 255 cells, a range beyond about 180 cells): any cell may
/// then have been read.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct RayStops {
    stops: Vec<u8>,
    cells: Option<std::sync::Arc<RayCells>>,
}

/// The rays of a fan through each cell of the square around its centre: for the cell at
/// offset `(dx, dy)`, `entries[start[j]..start[j + 1]]` with `j = (dy + half) side + dx +
/// half`, each a ray `k` and the index `i` of the cell in its walk, as `k << 8 | i`.
#[derive(Debug, PartialEq, Eq)]
struct RayCells {
    half: i32,
    start: Vec<u32>,
    entries: Vec<u32>,
    /// Per cell of the square (indexed as `start`), whether its centre is within range (the
    /// fan's [`IN_RANGE`]: a visible cell there counts).
    in_range: Vec<bool>,
}

impl RayStops {
    /// Whether a ray from `p` read the cell `c`; `None` when the stops are not kept.
    #[inline]
    pub(crate) fn read(&self, p: Cell, c: Cell) -> Option<bool> {
        let cells = self.cells.as_ref()?;
        Some(
            cells
                .square_index(p, c)
                .is_some_and(|j| self.read_at(cells, j)),
        )
    }

    /// Whether a ray read the cell of index `j` in `cells`' square.
    #[inline]
    fn read_at(&self, cells: &RayCells, j: usize) -> bool {
        let on = &cells.entries[cells.start[j] as usize..cells.start[j + 1] as usize];
        on.iter()
            .any(|&e| self.stops[(e >> 8) as usize] as u32 >= (e & 0xff))
    }

    /// Whether a ray from `p` read the cell `c`, and whether its centre is within range: a
    /// cell read that does not block is not where a ray stopped (the rays read it on their
    /// way), so it counted exactly when within range and satisfying the predicate `counts`.
    /// `None` when the stops are not kept.
    #[inline]
    pub(crate) fn read_in_range(&self, p: Cell, c: Cell) -> Option<(bool, bool)> {
        let cells = self.cells.as_ref()?;
        Some(cells.square_index(p, c).map_or((false, false), |j| {
            (self.read_at(cells, j), cells.in_range[j])
        }))
    }
}

impl RayCells {
    /// The index in the square around `p` of the cell `c`, if it lies in the square.
    #[inline]
    fn square_index(&self, p: Cell, c: Cell) -> Option<usize> {
        let (dx, dy) = (c.x as i64 - p.x as i64, c.y as i64 - p.y as i64);
        let (h, side) = (self.half as i64, 2 * self.half as i64 + 1);
        (dx.abs() <= h && dy.abs() <= h).then(|| ((dy + h) * side + dx + h) as usize)
    }
}

/// [`visible_area`], with predicates that are also given the cell's row-major index in `frame`
/// (so that they can read a grid without a bounds test on the cell), and where the cells it
/// read lie ([`CellsRead`]).
pub(crate) fn visible_area_read(
    frame: &GridFrame,
    p: Cell,
    range_m: f64,
    blocks: impl Fn(Cell, usize) -> bool,
    counts: impl Fn(Cell, usize) -> bool,
) -> (f64, CellsRead) {
    let (count, read) = visible_count_read(frame, p, range_m, blocks, counts);
    (count as f64 * frame.cell_area_m2(), read)
}

/// [`visible_area_read`] as a number of cells.
pub(crate) fn visible_count_read(
    frame: &GridFrame,
    p: Cell,
    range_m: f64,
    blocks: impl Fn(Cell, usize) -> bool,
    counts: impl Fn(Cell, usize) -> bool,
) -> (usize, CellsRead) {
    let nothing = (0, CellsRead::of(p));
    // (The fan's frame test takes a negative coordinate, cast unsigned, for one beyond the
    // frame: a frame wider or taller than `i32::MAX` cells, some of whose cells no `Cell` can
    // name, shows nothing.)
    let narrow = frame.width <= i32::MAX as u32 && frame.height <= i32::MAX as u32;
    if !narrow || !frame.contains(p) || range_m.is_nan() || range_m <= 0.0 {
        return nothing;
    }
    let pi = p.y as usize * frame.width as usize + p.x as usize;
    if blocks(p, pi) {
        return nothing;
    }
    let r_cells = range_m / frame.resolution_m;
    if !r_cells.is_finite() || r_cells > MAX_FAN_CELLS {
        return nothing;
    }
    let (count, read) = FAN.with(|cache| match cache.try_borrow_mut() {
        Ok(mut cache) => {
            if cache.as_ref().is_none_or(|f| f.r_cells != r_cells) {
                *cache = Some(RayFan::new(r_cells));
            }
            let fan = cache.as_mut().expect("just set");
            fan.count(frame, p, &blocks, &counts)
        }
        // Only reachable if a predicate itself computes a visible area.
        Err(_) => RayFan::new(r_cells).count(frame, p, &blocks, &counts),
    });
    (count, read)
}

/// Ranges beyond this many cells are refused (the fan's offsets are `i16`).
const MAX_FAN_CELLS: f64 = 10_000.0;

thread_local! {
    /// The fan of the last range used (a run uses one laser range), with its set of cells seen.
    static FAN: std::cell::RefCell<Option<RayFan>> = const { std::cell::RefCell::new(None) };
}

/// One cell of the fan: the index just past its subtree, its index in the square of the set of
/// cells seen with whether its centre is within range, its row-major index offset from the
/// centre, and its offset in cells. (16 bytes, all in one record: the walk reads the offset in
/// cells where a ray ends, a predicate needs the cell or the square leaves the map; from an
/// array of its own it cost the loop another pointer to keep, and the fan's bytes are the same.)
#[derive(Debug, Clone, Copy)]
struct FanNode {
    end: u32,
    /// The index in the square of cells seen, and [`IN_RANGE`] when the cell's centre is
    /// within range.
    seen: u32,
    /// Row-major index offset in a frame `RayFan::offsets_width` cells wide.
    offset: i32,
    /// The cell's offset from the centre (`dx`, `dy`).
    cell: (i16, i16),
}

/// [`FanNode::seen`]'s flag: the cell's centre is within range.
const IN_RANGE: u32 = 1 << 31;

/// The rays of [`visible_area`] relative to the centre cell, as a prefix tree flattened in
/// preorder: rays share their first cells, so a shared cell is tested once, and a blocking cell
/// skips its whole subtree (every ray through it stops there). The cells visited are exactly
/// those of walking every ray separately.
#[derive(Debug, Clone)]
struct RayFan {
    r_cells: f64,
    half: i32,
    nodes: Vec<FanNode>,
    /// One byte per cell of the `(2 half + 1)^2` square: 0, or when reached in range in this
    /// call, 1 and (bit 1) whether it counts; all 0 between calls (a call clears what it
    /// marked as it counts the marks). (Bytes, not bits: consecutive nodes are
    /// neighbouring cells, whose bits would share a word, each write waiting on the last.)
    seen: Vec<u8>,
    /// A call left marks in `seen`: it stopped in its walk (a predicate panicked, and the run's
    /// caller caught it), so the next call clears the square first.
    marked: bool,
    /// The frame width the nodes' `offset`s are for (none yet).
    offsets_width: Option<u32>,
    /// Per node, its depth (the index of its cell in a ray's walk, at most 255: see
    /// `ray_cells`) and the leaves before it in preorder (a subtree's leaves follow its root;
    /// one more entry, all the leaves).
    depth: Vec<u8>,
    leaves_before: Vec<u32>,
    /// Per ray (in the order of their angles), the first leaf under its last cell, in preorder.
    ray_leaf: Vec<u32>,
    /// The rays through each cell; none when a walk is longer than [`MAX_DEPTH_KEPT`] cells.
    ray_cells: Option<std::sync::Arc<RayCells>>,
    /// The nodes where rays stopped in this call, other than at leaves (at most one per leaf).
    skips: Vec<u32>,
    /// Per leaf in preorder, the depth of the node where its ray stopped in this call (255: at
    /// its leaf, or beyond its last cell).
    stops: Vec<u8>,
}

/// Visible areas keep where each ray stopped ([`RayStops`]) when no ray's walk is longer than
/// this many cells after the first (a range of 180 cells: a byte per ray, kept with every
/// cached gain).
const MAX_DEPTH_KEPT: usize = 255;

impl RayFan {
    fn new(r_cells: f64) -> Self {
        let half = r_cells.ceil() as i32 + 1;
        // One ray per cell of arc at full range, so every cell at range is crossed by a ray.
        let n_rays = ((std::f64::consts::TAU * r_cells).ceil() as usize).max(8);
        let side = 2 * half + 1;
        let may_keep = r_cells <= 2.0 * MAX_DEPTH_KEPT as f64;
        let trie = RayTrie::build(r_cells, half, n_rays, may_keep);
        // Flatten in preorder (children in the order they were added).
        let (nodes, preorder_of, ids) = trie.preorder(r_cells, half);
        // Leaves before each node in preorder (a subtree's leaves follow its root).
        let mut leaves_before: Vec<u32> = Vec::with_capacity(nodes.len() + 1);
        let mut leaves = 0u32;
        for (i, n) in nodes.iter().enumerate() {
            leaves_before.push(leaves);
            leaves += (n.end as usize == i + 1) as u32;
        }
        leaves_before.push(leaves);
        let depth = trie.depth;
        let deepest = depth.iter().copied().max().unwrap_or(0) as usize;
        let ray_leaf = trie
            .ray_end
            .iter()
            .map(|&id| leaves_before[preorder_of[id as usize] as usize])
            .collect();
        let mut ray_cells = RayCells::of(trie.on, half);
        for n in &nodes {
            if n.seen & IN_RANGE != 0 {
                ray_cells.in_range[(n.seen & !IN_RANGE) as usize] = true;
            }
        }
        let side = side as usize;
        Self {
            r_cells,
            half,
            nodes,
            seen: vec![0; side * side],
            marked: false,
            offsets_width: None,
            depth: ids
                .iter()
                .map(|&id| depth[id as usize].min(255) as u8)
                .collect(),
            leaves_before,
            ray_leaf,
            ray_cells: (may_keep && deepest <= MAX_DEPTH_KEPT)
                .then(|| std::sync::Arc::new(ray_cells)),
            skips: vec![0; leaves as usize],
            stops: vec![0; leaves as usize],
        }
    }

    /// Cells visible from `p` (not blocked, in range) that satisfy `counts`, each once; and
    /// where the cells read lie.
    fn count(
        &mut self,
        frame: &GridFrame,
        p: Cell,
        blocks: &impl Fn(Cell, usize) -> bool,
        counts: &impl Fn(Cell, usize) -> bool,
    ) -> (usize, CellsRead) {
        if self.marked {
            self.seen.fill(0);
        }
        self.marked = true;
        let w = frame.width as i32;
        if self.offsets_width != Some(frame.width) {
            for n in self.nodes.iter_mut() {
                let (dx, dy) = n.cell;
                n.offset = dy as i32 * w + dx as i32;
            }
            self.offsets_width = Some(frame.width);
        }
        // A node's index is a fixed offset from `p`'s; when the whole square around `p` lies in
        // the frame, no node needs the frame test.
        let h = self.half;
        let inside = p.x - h >= 0 && p.y - h >= 0 && p.x + h < w && p.y + h < frame.height as i32;
        let base = p.y as isize * w as isize + p.x as isize;
        // (The slices held apart, so that the stores to `seen` cannot make the compiler read
        // the vectors' addresses and lengths again from `self` for every node.)
        let (nodes, seen) = (&self.nodes[..], &mut self.seen[..]);
        let skips = &mut self.skips[..];
        // (Two loops, one per answer to `inside`: the test is not made per node.)
        let (count, boxes, n_skips) = if inside {
            walk::<true>(nodes, seen, skips, frame, p, base, blocks, counts)
        } else {
            walk::<false>(nodes, seen, skips, frame, p, base, blocks, counts)
        };
        // (The walk cleared its marks as it counted them.)
        self.marked = false;
        let rays = match &self.ray_cells {
            Some(cells) => {
                // Each leaf's ray stopped at the skipped node above it, if any.
                self.stops.fill(u8::MAX);
                for &i in &self.skips[..n_skips] {
                    let i = i as usize;
                    let leaves = self.leaves_before[i]..self.leaves_before[nodes[i].end as usize];
                    self.stops[leaves.start as usize..leaves.end as usize].fill(self.depth[i]);
                }
                RayStops {
                    stops: self
                        .ray_leaf
                        .iter()
                        .map(|&l| self.stops[l as usize])
                        .collect(),
                    cells: Some(cells.clone()),
                }
            }
            None => RayStops::default(),
        };
        let at = |(dx, dy): (i16, i16)| Cell::new(p.x + dx as i32, p.y + dy as i32);
        let read = CellsRead {
            boxes: boxes.map(|(lo, hi)| CellBox {
                min: at(lo),
                max: at(hi),
            }),
            rays,
        };
        (count, read)
    }
}

/// No node (in [`RayTrie`]).
const NONE: u32 = u32::MAX;

/// The rays' walks from a cell's centre as a trie, [`RayFan::new`]'s first step.
struct RayTrie {
    // Trie: per node its offset and its children, as a list in the order they were added
    // (first child, next sibling; the last child to append to), in flat arrays.
    offset: Vec<(i16, i16)>,
    first_child: Vec<u32>,
    last_child: Vec<u32>,
    next_sibling: Vec<u32>,
    // Each node's depth, each ray's last node, and per cell of the square the rays through
    // it (the square's index, the ray and the cell's index in its walk), unless the walks
    // are too long to be kept (a walk has up to `r_cells sqrt 2 + 2` cells: listed only up
    // to twice the depth kept, then kept if no walk is deeper).
    depth: Vec<u32>,
    ray_end: Vec<u32>,
    on: Vec<(u32, u32)>,
}

impl RayTrie {
    /// The trie of `n_rays` rays of `r_cells` in a square of `2 half + 1` cells a side, listing
    /// the rays through each cell if `may_keep`.
    fn build(r_cells: f64, half: i32, n_rays: usize, may_keep: bool) -> Self {
        let start = [0.5, 0.5];
        let mut t = RayTrie {
            offset: vec![(0, 0)],
            first_child: vec![NONE],
            last_child: vec![NONE],
            next_sibling: vec![NONE],
            depth: vec![0],
            ray_end: Vec::with_capacity(n_rays),
            on: Vec::new(),
        };
        let side = 2 * half + 1;
        for k in 0..n_rays {
            let a = k as f64 * std::f64::consts::TAU / n_rays as f64;
            let end = [start[0] + a.cos() * r_cells, start[1] + a.sin() * r_cells];
            let mut node = 0usize;
            let mut first = true;
            let mut step = 0u32;
            walk_segment(start, end, |c| {
                let o = (c.x as i16, c.y as i16);
                if may_keep && step as usize <= MAX_DEPTH_KEPT {
                    let j = ((c.y + half) * side + c.x + half) as u32;
                    t.on.push((j, (k as u32) << 8 | step));
                }
                step += 1;
                if first {
                    first = false; // the centre: the root
                    return true;
                }
                node = t.child(node, o);
                true
            });
            t.ray_end.push(node as u32);
        }
        t
    }

    /// The child of `node` at offset `o`, added if there is none.
    #[inline]
    fn child(&mut self, node: usize, o: (i16, i16)) -> usize {
        let mut ch = self.first_child[node];
        while ch != NONE && self.offset[ch as usize] != o {
            ch = self.next_sibling[ch as usize];
        }
        if ch != NONE {
            ch as usize
        } else {
            let id = self.offset.len() as u32;
            self.offset.push(o);
            self.first_child.push(NONE);
            self.last_child.push(NONE);
            self.next_sibling.push(NONE);
            self.depth.push(self.depth[node] + 1);
            match self.last_child[node] {
                NONE => self.first_child[node] = id,
                last => self.next_sibling[last as usize] = id,
            }
            self.last_child[node] = id;
            id as usize
        }
    }

    /// The nodes in preorder (children in the order they were added), each node's index in
    /// it, and the nodes' ids in it.
    fn preorder(&self, r_cells: f64, half: i32) -> (Vec<FanNode>, Vec<u32>, Vec<u32>) {
        let (offset, first_child, next_sibling) =
            (&self.offset, &self.first_child, &self.next_sibling);
        let side = 2 * half + 1;
        let r2 = r_cells * r_cells;
        let mut nodes = Vec::with_capacity(offset.len());
        let mut stack: Vec<(u32, bool)> = vec![(0, false)];
        let mut open: Vec<usize> = Vec::new();
        let mut children: Vec<u32> = Vec::new();
        let mut preorder_of: Vec<u32> = vec![0; offset.len()];
        let mut ids: Vec<u32> = Vec::with_capacity(offset.len());
        while let Some((id, done)) = stack.pop() {
            if done {
                let at = open.pop().expect("opened before closed");
                let len = nodes.len() as u32;
                let n: &mut FanNode = &mut nodes[at];
                n.end = len;
                continue;
            }
            let (dx, dy) = offset[id as usize];
            let d2 = (dx as i32 * dx as i32 + dy as i32 * dy as i32) as f64;
            open.push(nodes.len());
            preorder_of[id as usize] = nodes.len() as u32;
            ids.push(id);
            let seen_at = ((dy as i32 + half) * side + dx as i32 + half) as u32;
            nodes.push(FanNode {
                end: 0,
                seen: seen_at | if d2 <= r2 { IN_RANGE } else { 0 },
                offset: 0,
                cell: (dx, dy),
            });
            stack.push((id, true));
            children.clear();
            let mut ch = first_child[id as usize];
            while ch != NONE {
                children.push(ch);
                ch = next_sibling[ch as usize];
            }
            for &ch in children.iter().rev() {
                stack.push((ch, false));
            }
        }
        (nodes, preorder_of, ids)
    }
}

impl RayCells {
    /// The rays through each cell of the square of `2 half + 1` cells a side, from the list
    /// `on` of (cell, entry).
    fn of(mut on: Vec<(u32, u32)>, half: i32) -> Self {
        let side = 2 * half + 1;
        on.sort_unstable();
        let mut starts = vec![0u32; (side * side) as usize + 1];
        for &(j, _) in &on {
            starts[j as usize + 1] += 1;
        }
        for j in 1..starts.len() {
            starts[j] += starts[j - 1];
        }
        RayCells {
            half,
            start: starts,
            entries: on.into_iter().map(|(_, e)| e).collect(),
            in_range: vec![false; (side * side) as usize],
        }
    }
}

/// Per quadrant of a ray's end (see [`walk`]): the least and the greatest offsets from the
/// centre of the ends in it.
type QuadrantBoxes = [((i16, i16), (i16, i16)); 4];

/// [`RayFan::count`]'s walk of the fan from `p`, with `INSIDE` whether the whole square around
/// `p` lies in the frame (no cell then needs the frame test; a node's index is `base` plus its
/// offset either way). The cells read lie on the rays walked, each from the centre to where it
/// stopped: a blocking cell (or one outside the frame), or a leaf. A ray's cells lie in the box
/// of its first and last (the walk is monotonic on both axes), so the boxes of the centre and
/// these ends, one per quadrant of the end, hold them all; they are kept at the ends only, not
/// at every node. Returns the count and the boxes (offsets from `p`).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn walk<const INSIDE: bool>(
    nodes: &[FanNode],
    seen: &mut [u8],
    skips: &mut [u32],
    frame: &GridFrame,
    p: Cell,
    base: isize,
    blocks: &impl Fn(Cell, usize) -> bool,
    counts: &impl Fn(Cell, usize) -> bool,
) -> (usize, QuadrantBoxes, usize) {
    let mut boxes: QuadrantBoxes = [((0i16, 0i16), (0i16, 0i16)); 4];
    let mut end_at = |(dx, dy): (i16, i16)| {
        let (lo, hi) = &mut boxes[(dx < 0) as usize | ((dy < 0) as usize) << 1];
        *lo = (lo.0.min(dx), lo.1.min(dy));
        *hi = (hi.0.max(dx), hi.1.max(dy));
    };
    let mut n_skips = 0usize;
    let mut i = 0usize;
    while i < nodes.len() {
        let n = nodes[i];
        let (dx, dy) = n.cell;
        let c = Cell::new(p.x + dx as i32, p.y + dy as i32);
        // (When the square leaves the frame, a cell in the frame still has its index at its
        // node's offset from `base`. The frame test: two unsigned comparisons, without branches,
        // a negative coordinate wrapping to above any width or height the fan takes.)
        let in_frame = || ((c.x as u32) < frame.width) & ((c.y as u32) < frame.height);
        let idx = if INSIDE || in_frame() {
            (base + n.offset as isize) as usize
        } else {
            end_at((dx, dy));
            skips[n_skips] = i as u32;
            n_skips += 1;
            i = n.end as usize;
            continue;
        };
        if blocks(c, idx) {
            end_at((dx, dy));
            skips[n_skips] = i as u32;
            n_skips += 1;
            i = n.end as usize;
            continue;
        }
        if n.end as usize == i + 1 {
            end_at((dx, dy));
        }
        if n.seen & IN_RANGE != 0 {
            // Marked, and counted after the walk: whether a cell was seen by an earlier ray,
            // and whether it counts, are both close to coin flips (cells are crossed by about
            // two rays; unknown and known cells meet along frontiers), so branches on them are
            // mispredicted often, and a count kept here is one more value live in the loop.
            // `counts` is a pure predicate: a cell marked again is marked the same.
            seen[(n.seen & !IN_RANGE) as usize] = 1 | (counts(c, idx) as u8) << 1;
        }
        i += 1;
    }
    // The cells that count: those marked 3, the marks cleared as they are read (the next
    // walk starts from a clear square). (In runs of at most 255 bytes, each adding at most 1,
    // summed in bytes: the compiler adds 16 at a time.)
    let count = seen
        .chunks_mut(255)
        .map(|run| {
            run.iter_mut().fold(0u8, |a, b| {
                let counted = *b >> 1;
                *b = 0;
                a + counted
            }) as usize
        })
        .sum();
    (count, boxes, n_skips)
}

/// The baseline `I(p)`: unknown area visible from `p` through the map, unknown treated as free,
/// occupied cells blocking.
pub fn information_gain(grid: &OccupancyGrid, p: Cell, range_m: f64) -> f64 {
    information_gain_read(grid, p, range_m).0
}

/// [`information_gain`] and where the cells it read lie ([`CellsRead`]).
pub(crate) fn information_gain_read(
    grid: &OccupancyGrid,
    p: Cell,
    range_m: f64,
) -> (f64, CellsRead) {
    let (count, read) = information_count_read(grid, p, range_m);
    (count as f64 * grid.frame.cell_area_m2(), read)
}

/// [`information_gain_read`] as a number of cells: the unknown cells visible from `p`. (Only
/// an occupied cell blocks and only an unknown one counts, so while no cell read changes
/// whether it is occupied, the count falls by one for each cell read within range that stops
/// being unknown: [`RayStops::read_in_range`].)
pub(crate) fn information_count_read(
    grid: &OccupancyGrid,
    p: Cell,
    range_m: f64,
) -> (usize, CellsRead) {
    // (The cells as a slice: the predicates then read them without going through `grid`.)
    let data = &grid.data[..];
    visible_count_read(
        &grid.frame,
        p,
        range_m,
        |_, i| data[i] == Occupancy::Occupied,
        |_, i| data[i] == Occupancy::Unknown,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The definition the fan implements: every ray walked on its own from the centre of `p`.
    fn visible_area_by_rays(
        frame: &GridFrame,
        p: Cell,
        range_m: f64,
        blocks: impl Fn(Cell) -> bool,
        counts: impl Fn(Cell) -> bool,
    ) -> f64 {
        if !frame.contains(p) || blocks(p) {
            return 0.0;
        }
        let r_cells = range_m / frame.resolution_m;
        let n_rays = ((std::f64::consts::TAU * r_cells).ceil() as usize).max(8);
        let mut seen = std::collections::BTreeSet::new();
        let mut count = 0usize;
        for k in 0..n_rays {
            let a = k as f64 * std::f64::consts::TAU / n_rays as f64;
            let end = [0.5 + a.cos() * r_cells, 0.5 + a.sin() * r_cells];
            walk_segment([0.5, 0.5], end, |o| {
                let c = Cell::new(p.x + o.x, p.y + o.y);
                if !frame.contains(c) || blocks(c) {
                    return false;
                }
                if seen.insert(c)
                    && ((o.x * o.x + o.y * o.y) as f64) <= r_cells * r_cells
                    && counts(c)
                {
                    count += 1;
                }
                true
            });
        }
        count as f64 * frame.cell_area_m2()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn fan_equals_walking_every_ray(
            cells in proptest::collection::vec(0u8..10, 40 * 30),
            px in 0i32..40, py in 0i32..30, range in 0.5f64..3.0,
        ) {
            // 0-1 occupied, 2-5 unknown, rest free, at 0.1 m.
            let text: String = cells
                .chunks(40)
                .map(|row| {
                    row.iter()
                        .map(|&v| match v { 0..=1 => '#', 2..=5 => '?', _ => '.' })
                        .chain(std::iter::once('\n'))
                        .collect::<String>()
                })
                .collect();
            let g = OccupancyGrid::from_ascii(&text, 0.1);
            let p = Cell::new(px, py);
            let fast = information_gain(&g, p, range);
            let slow = visible_area_by_rays(
                &g.frame,
                p,
                range,
                |c| g.is(c, Occupancy::Occupied),
                |c| g.is(c, Occupancy::Unknown),
            );
            prop_assert_eq!(fast, slow);
            // Every cell whose predicates were asked lies in a box of the cells read, and each
            // box holds `p`.
            let asked = std::cell::RefCell::new(std::collections::BTreeSet::new());
            let (area, read) = visible_area_read(
                &g.frame,
                p,
                range,
                |c, _| {
                    asked.borrow_mut().insert(c);
                    g.is(c, Occupancy::Occupied)
                },
                |c, _| {
                    asked.borrow_mut().insert(c);
                    g.is(c, Occupancy::Unknown)
                },
            );
            prop_assert_eq!(area, fast);
            let holds = |b: &CellBox, c: Cell| {
                (b.min.x..=b.max.x).contains(&c.x) && (b.min.y..=b.max.y).contains(&c.y)
            };
            let asked = asked.into_inner();
            for c in &asked {
                prop_assert!(read.boxes.iter().any(|b| holds(b, *c)), "{:?} not in {:?}", c, read);
            }
            prop_assert!(read.boxes.iter().all(|b| holds(b, p)));
            // The rays' stops are kept whenever the fan was walked (a range of at most 30
            // cells), and name exactly the cells asked about (or the boxes do, `p` alone).
            prop_assert_eq!(read.rays.cells.is_some(), !g.is(p, Occupancy::Occupied));
            for y in -2..32 {
                for x in -2..42 {
                    let c = Cell::new(x, y);
                    let inside = g.frame.contains(c);
                    prop_assert_eq!(
                        read.may_have_read(p, c) && inside,
                        asked.contains(&c),
                        "{:?}",
                        c
                    );
                }
            }
        }
    }

    #[test]
    fn the_cells_read_from_inside_a_room_are_the_room() {
        // A closed room 8 x 5 cells inside (x 2..=9, y 2..=6) in a 30 x 20 unknown map; from
        // any cell of it, the cells read are the room and its walls, whatever the range.
        let frame = GridFrame::new(crate::geom::Vec2::zeros(), 0.1, 30, 20);
        let mut g = OccupancyGrid::filled(frame, Occupancy::Unknown);
        for y in 1..=7 {
            for x in 1..=10 {
                let wall = x == 1 || x == 10 || y == 1 || y == 7;
                g.set(
                    Cell::new(x, y),
                    if wall {
                        Occupancy::Occupied
                    } else {
                        Occupancy::Free
                    },
                );
            }
        }
        let walls = CellBox {
            min: Cell::new(1, 1),
            max: Cell::new(10, 7),
        };
        for p in [Cell::new(2, 2), Cell::new(5, 4), Cell::new(9, 6)] {
            for range in [0.3, 1.0, 3.0] {
                let (area, read) = information_gain_read(&g, p, range);
                assert_eq!(area, 0.0);
                for b in read.boxes {
                    assert!(
                        b.min.x >= walls.min.x
                            && b.min.y >= walls.min.y
                            && b.max.x <= walls.max.x
                            && b.max.y <= walls.max.y,
                        "{p:?} {range}: {b:?}"
                    );
                }
            }
        }
    }

    /// The fan as first built: a vector of children per node, found by a linear search.
    fn fan_nodes_reference(r_cells: f64) -> Vec<(i16, i16, bool, u32, u32)> {
        let half = r_cells.ceil() as i32 + 1;
        let n_rays = ((std::f64::consts::TAU * r_cells).ceil() as usize).max(8);
        let start = [0.5, 0.5];
        let mut offset: Vec<(i16, i16)> = vec![(0, 0)];
        let mut children: Vec<Vec<u32>> = vec![Vec::new()];
        for k in 0..n_rays {
            let a = k as f64 * std::f64::consts::TAU / n_rays as f64;
            let end = [start[0] + a.cos() * r_cells, start[1] + a.sin() * r_cells];
            let mut node = 0usize;
            let mut first = true;
            walk_segment(start, end, |c| {
                if first {
                    first = false;
                    return true;
                }
                let o = (c.x as i16, c.y as i16);
                node = match children[node].iter().find(|&&ch| offset[ch as usize] == o) {
                    Some(&ch) => ch as usize,
                    None => {
                        let id = offset.len();
                        offset.push(o);
                        children.push(Vec::new());
                        children[node].push(id as u32);
                        id
                    }
                };
                true
            });
        }
        let r2 = r_cells * r_cells;
        let mut nodes: Vec<(i16, i16, bool, u32, u32)> = Vec::new();
        let mut stack: Vec<(u32, bool)> = vec![(0, false)];
        let mut open: Vec<usize> = Vec::new();
        while let Some((id, done)) = stack.pop() {
            if done {
                let at = open.pop().unwrap();
                nodes[at].3 = nodes.len() as u32;
                continue;
            }
            let (dx, dy) = offset[id as usize];
            let d2 = (dx as i32 * dx as i32 + dy as i32 * dy as i32) as f64;
            open.push(nodes.len());
            let side = 2 * half + 1;
            let seen_at = ((dy as i32 + half) * side + dx as i32 + half) as u32;
            nodes.push((dx, dy, d2 <= r2, 0, seen_at));
            stack.push((id, true));
            for &ch in children[id as usize].iter().rev() {
                stack.push((ch, false));
            }
        }
        nodes
    }

    #[test]
    fn the_rays_stops_are_kept_up_to_walks_of_255_cells() {
        // A walk of a ray of `r` cells has about `r (|cos| + |sin|)` cells, up to `r sqrt 2`:
        // 255 at 180 cells.
        let frame = GridFrame::new(crate::geom::Vec2::zeros(), 1.0, 500, 500);
        let p = Cell::new(250, 250);
        for (range_m, kept) in [(3.0, true), (120.0, true), (179.0, true), (182.0, false)] {
            let (area, read) = visible_area_read(&frame, p, range_m, |_, _| false, |_, _| true);
            assert!(area > 0.0);
            assert_eq!(read.rays.cells.is_some(), kept, "{range_m}");
            // Either way, a cell far out on a ray was read and one beyond the range was not.
            let r = range_m as i32;
            assert!(
                read.may_have_read(p, Cell::new(250 + r - 1, 250)),
                "{range_m}"
            );
            assert!(
                !read.may_have_read(p, Cell::new(250 + r + 3, 250)),
                "{range_m}"
            );
        }
    }

    #[test]
    fn the_fan_is_the_tree_first_built() {
        for r_cells in [0.3, 1.0, 2.5, 7.77, 40.0, 120.0, 121.3] {
            let fan = RayFan::new(r_cells);
            let nodes: Vec<_> = fan
                .nodes
                .iter()
                .map(|n| {
                    let (dx, dy) = n.cell;
                    (dx, dy, n.seen & IN_RANGE != 0, n.end, n.seen & !IN_RANGE)
                })
                .collect();
            assert_eq!(nodes, fan_nodes_reference(r_cells), "r_cells {r_cells}");
        }
    }

    #[test]
    fn unknown_behind_a_frontier_counts_and_a_wall_blocks() {
        let open = OccupancyGrid::from_ascii(
            "
            ??????????
            ??????????
            ..........
            ..........",
            1.0,
        );
        let near = information_gain(&open, Cell::new(4, 0), 2.5);
        assert!(near > 0.0);
        let far = information_gain(&open, Cell::new(4, 0), 20.0);
        assert_eq!(far, 20.0);
        let walled = OccupancyGrid::from_ascii(
            "
            ??????????
            ??????????
            ##########
            ..........",
            1.0,
        );
        assert_eq!(information_gain(&walled, Cell::new(4, 0), 20.0), 0.0);
        let half_walled = OccupancyGrid::from_ascii(
            "
            ??????????
            ??????????
            #####.....
            ..........",
            1.0,
        );
        let g = information_gain(&half_walled, Cell::new(8, 0), 20.0);
        assert!(g > 0.0 && g < 20.0, "{g}");
        // The range limits: from the row below, a 1.2 m range sees only the cells right above.
        let g = information_gain(&open, Cell::new(4, 1), 1.2);
        assert_eq!(g, 1.0);
    }

    #[test]
    fn counts_each_cell_once_and_handles_odd_input() {
        let all_unknown = OccupancyGrid::from_ascii("?????\n?????\n?????\n?????\n?????", 1.0);
        let g = visible_area(
            &all_unknown.frame,
            Cell::new(2, 2),
            10.0,
            |_| false,
            |_| true,
        );
        assert_eq!(g, 25.0);
        assert_eq!(information_gain(&all_unknown, Cell::new(9, 9), 3.0), 0.0);
        assert_eq!(information_gain(&all_unknown, Cell::new(2, 2), 0.0), 0.0);
        let wall = OccupancyGrid::from_ascii("#", 1.0);
        assert_eq!(information_gain(&wall, Cell::new(0, 0), 3.0), 0.0);
    }

    /// A walk stopped by a panicking predicate (a job's panic, caught by its worker, which
    /// goes on with other jobs on the same thread) leaves no mark that a later count on that
    /// thread would add: here the later count sees less than the stopped walk had marked.
    #[test]
    fn a_walk_stopped_by_a_panic_leaves_no_marks() {
        let frame = GridFrame::new(crate::geom::Vec2::zeros(), 1.0, 41, 41);
        let p = Cell::new(20, 20);
        // Walls on a ring of radius 5 around `p`: the far cells are hidden.
        let ring = |c: Cell, _: usize| {
            let d2 = (c.x - p.x).pow(2) + (c.y - p.y).pow(2);
            (25..=36).contains(&d2)
        };
        let walled = || visible_area_read(&frame, p, 15.0, ring, |_, _| true).0;
        let before = walled();
        let calls = std::cell::Cell::new(0);
        let stopped = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            visible_area_read(
                &frame,
                p,
                15.0,
                |_, _| false,
                |_, _| {
                    calls.set(calls.get() + 1);
                    assert!(calls.get() < 600, "a predicate's panic");
                    true
                },
            )
        }));
        assert!(stopped.is_err());
        assert!(
            calls.get() >= 600,
            "the walk marked cells beyond the ring first"
        );
        assert_eq!(walled(), before);
    }
}
