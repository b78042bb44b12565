//! Observations and actions: what a policy is shown at a decision and how its action becomes
//! floorcast's reply. One code path for the environment (from the episode's decision view) and
//! for a policy run as a strategy in grids (from the strategy protocol's decide messages), so
//! that a policy makes the same decisions in both.

use crate::graph::{self, GraphConfig};
use sim_core::explore::{CandidateView, DecisionView, Reply};
use sim_core::grid::{Cell, GridFrame, Occupancy, OccupancyGrid};
use sim_core::{Pose, Vec2};

/// Features of a candidate, in the order of the `candidates` array's last axis.
pub(crate) const FEATURES: [&str; 10] = [
    "path_m",
    "straight_m",
    "gain_m2",
    "layout_gain_m2",
    "has_layout_gain",
    "frontier_cells",
    "forward_m",
    "left_m",
    "bearing_rad",
    "in_robot_room",
];

/// Channels of the `map` observation, in order.
pub(crate) const CHANNELS: [&str; 6] =
    ["free", "occupied", "unknown", "frontier", "trail", "robot"];

/// What a policy is shown and answers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Mode {
    /// The candidates as a padded array; action: an index into it.
    Candidates { max: usize },
    /// The known map as a `(6, size, size)` crop; action: a goal point in the crop.
    Map {
        size: usize,
        cell_m: f64,
        egocentric: bool,
    },
    /// The known free space as a graph in ARiADNE's shapes; action: an index into the robot
    /// node's edges.
    Graph(GraphConfig),
}

impl Mode {
    /// Whether the mode's actions are points (answered with goal points, falling back to the
    /// candidate nearest to a point without a path).
    pub(crate) fn points(self) -> bool {
        !matches!(self, Mode::Candidates { .. })
    }

    /// Whether the mode reads the map.
    pub(crate) fn needs_map(self) -> bool {
        self.points()
    }

    /// The mode with a graph's sensing range taken from the laser's range (m) when it was not
    /// given (seven eighths of it, as ARiADNE's sensor range less its margin).
    pub(crate) fn with_laser_range(self, laser_range_m: f64) -> Mode {
        match self {
            Mode::Graph(mut g) if g.range_m.is_nan() => {
                g.range_m = 0.875 * laser_range_m;
                Mode::Graph(g)
            }
            other => other,
        }
    }
}

/// One candidate as the policy's observation needs it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Cand {
    pub(crate) id: usize,
    pub(crate) goal: Vec2,
    pub(crate) frontier_cells: usize,
    pub(crate) path_m: f64,
    pub(crate) straight_m: f64,
    pub(crate) gain_m2: f64,
    pub(crate) layout_gain_m2: Option<f64>,
    pub(crate) room: Option<usize>,
}

impl Cand {
    pub(crate) fn of(c: &CandidateView) -> Cand {
        Cand {
            id: c.id,
            goal: c.goal,
            frontier_cells: c.frontier_cells,
            path_m: c.path_m,
            straight_m: c.straight_m,
            gain_m2: c.gain_m2,
            layout_gain_m2: c.layout_gain_m2,
            room: c.room,
        }
    }
}

/// A decision as a policy is shown it, owned.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Snapshot {
    pub(crate) decision: usize,
    pub(crate) attempt: usize,
    pub(crate) time_s: f64,
    pub(crate) pose: Pose,
    pub(crate) candidates: Vec<Cand>,
    pub(crate) robot_room: Option<usize>,
    pub(crate) unreachable_goal: Option<Vec2>,
}

impl Snapshot {
    /// The snapshot of an episode's decision view (the robot's room as the protocol computes
    /// it: the predicted room holding the estimated position).
    pub(crate) fn of(view: &DecisionView<'_>) -> Snapshot {
        Snapshot {
            decision: view.decision,
            attempt: view.attempt,
            time_s: view.time_s,
            pose: view.pose,
            candidates: view.candidates.iter().map(Cand::of).collect(),
            robot_room: view
                .layout
                .and_then(|l| l.room_holding(view.pose.position())),
            unreachable_goal: view.unreachable_goal,
        }
    }

    /// The candidates in the order the observation shows them: by path length, then id; at
    /// most `max` (the nearest).
    pub(crate) fn ordered(&self, max: usize) -> Vec<Cand> {
        let mut c = self.candidates.clone();
        c.sort_by(|a, b| a.path_m.total_cmp(&b.path_m).then(a.id.cmp(&b.id)));
        c.truncate(max);
        c
    }
}

/// An observation's arrays, as little-endian bytes (the Python side wraps them in numpy).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Obs {
    /// `(key, dtype, shape, bytes)`.
    pub(crate) arrays: Vec<(&'static str, &'static str, Vec<usize>, Vec<u8>)>,
    /// Candidate ids in the order shown (candidates mode), to map an index back.
    pub(crate) ids: Vec<usize>,
    /// The candidates shown (for the map mode's fallback to the candidate nearest the goal).
    pub(crate) shown: Vec<Cand>,
    /// Graph mode: the point each edge of the robot's node leads to (`None`: padding).
    pub(crate) targets: Vec<Option<Vec2>>,
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// An empty observation (all zeros, no candidate): what an episode shows when it ended before
/// its first decision.
pub(crate) fn empty(mode: Mode) -> Obs {
    let snap = Snapshot {
        decision: 0,
        attempt: 0,
        time_s: 0.0,
        pose: Pose::new(0.0, 0.0, 0.0),
        candidates: Vec::new(),
        robot_room: None,
        unreachable_goal: None,
    };
    observe(mode, &snap, None, &[])
}

/// The observation of a decision: `map` is the robot's map (needed by the map mode), `trail`
/// the estimated positions of the decisions so far.
pub(crate) fn observe(
    mode: Mode,
    snap: &Snapshot,
    map: Option<&OccupancyGrid>,
    trail: &[Vec2],
) -> Obs {
    let pose = [
        snap.pose.x_m as f32,
        snap.pose.y_m as f32,
        snap.pose.theta_rad as f32,
    ];
    let common = |arrays: &mut Vec<(&'static str, &'static str, Vec<usize>, Vec<u8>)>| {
        arrays.push(("pose", "float32", vec![3], f32_bytes(&pose)));
        arrays.push((
            "time_s",
            "float32",
            vec![1],
            f32_bytes(&[snap.time_s as f32]),
        ));
    };
    match mode {
        Mode::Candidates { max } => {
            let shown = snap.ordered(max);
            let f = FEATURES.len();
            let mut feats = vec![0f32; max * f];
            let mut mask = vec![0u8; max];
            let (sin, cos) = snap.pose.theta_rad.sin_cos();
            for (k, c) in shown.iter().enumerate() {
                let d = c.goal - snap.pose.position();
                let forward = d.x * cos + d.y * sin;
                let left = -d.x * sin + d.y * cos;
                let row = [
                    c.path_m,
                    c.straight_m,
                    c.gain_m2,
                    c.layout_gain_m2.unwrap_or(0.0),
                    f64::from(u8::from(c.layout_gain_m2.is_some())),
                    c.frontier_cells as f64,
                    forward,
                    left,
                    left.atan2(forward),
                    f64::from(u8::from(c.room.is_some() && c.room == snap.robot_room)),
                ];
                for (j, v) in row.iter().enumerate() {
                    feats[k * f + j] = *v as f32;
                }
                mask[k] = 1;
            }
            let mut arrays = vec![
                ("candidates", "float32", vec![max, f], f32_bytes(&feats)),
                ("mask", "int8", vec![max], mask),
            ];
            common(&mut arrays);
            Obs {
                arrays,
                ids: shown.iter().map(|c| c.id).collect(),
                shown,
                targets: Vec::new(),
            }
        }
        Mode::Map { size, .. } => {
            let window = Window::of(mode, snap.pose, map.map(|m| m.frame));
            let bytes = match map {
                Some(m) => render(m, &window, trail),
                None => vec![0u8; CHANNELS.len() * size * size],
            };
            let mut arrays = vec![("map", "uint8", vec![CHANNELS.len(), size, size], bytes)];
            common(&mut arrays);
            Obs {
                arrays,
                ids: Vec::new(),
                shown: snap.ordered(usize::MAX),
                targets: Vec::new(),
            }
        }
        Mode::Graph(cfg) => {
            let (mut arrays, targets) = match map {
                Some(m) => {
                    let g = graph::build(cfg, m, snap.pose.position(), trail);
                    let targets = (0..cfg.k)
                        .map(|i| g.edges[0].get(i).filter(|&&j| j != 0).map(|&j| g.nodes[j]))
                        .collect();
                    (graph::arrays(cfg, &g, m), targets)
                }
                None => (graph::empty_arrays(cfg), vec![None; cfg.k]),
            };
            common(&mut arrays);
            Obs {
                arrays,
                ids: Vec::new(),
                shown: snap.ordered(usize::MAX),
                targets,
            }
        }
    }
}

/// The square of the world a map observation shows: `size` cells of `cell_m` from its
/// lower-left corner `origin` (row 0 of the image is its top).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Window {
    pub(crate) origin: Vec2,
    pub(crate) cell_m: f64,
    pub(crate) size: usize,
}

impl Window {
    /// Egocentric: centred on the estimated position (axis-aligned, not rotated). Global: the
    /// whole map, centred, scaled so its longer side fills the crop.
    pub(crate) fn of(mode: Mode, pose: Pose, frame: Option<GridFrame>) -> Window {
        let Mode::Map {
            size,
            cell_m,
            egocentric,
        } = mode
        else {
            return Window {
                origin: Vec2::new(0.0, 0.0),
                cell_m: 1.0,
                size: 0,
            };
        };
        let side = size as f64;
        match (egocentric, frame) {
            (false, Some(f)) => {
                let b = f.bounds();
                let (w, h) = (b.max.x - b.min.x, b.max.y - b.min.y);
                let cell = w.max(h) / side;
                let centre = Vec2::new((b.min.x + b.max.x) / 2.0, (b.min.y + b.max.y) / 2.0);
                Window {
                    origin: centre - Vec2::new(side * cell / 2.0, side * cell / 2.0),
                    cell_m: cell,
                    size,
                }
            }
            _ => Window {
                origin: pose.position() - Vec2::new(side * cell_m / 2.0, side * cell_m / 2.0),
                cell_m,
                size,
            },
        }
    }

    /// The world point of an action `(column, row)` in [0, 1]² (row 0 at the top).
    pub(crate) fn point(&self, a: [f64; 2]) -> Vec2 {
        let side = self.size as f64 * self.cell_m;
        Vec2::new(
            self.origin.x + a[0] * side,
            self.origin.y + (1.0 - a[1]) * side,
        )
    }
}

/// The `(6, size, size)` channels of `map` in `window` (255 where any of the map's cells in a
/// crop cell is of the channel's kind, 0 elsewhere; outside the map: unknown; the trail's
/// segments; the robot's estimated position, the trail's last point).
fn render(map: &OccupancyGrid, w: &Window, trail: &[Vec2]) -> Vec<u8> {
    let n = w.size;
    let plane = n * n;
    let mut out = vec![0u8; CHANNELS.len() * plane];
    let frame = map.frame;
    let r = frame.resolution_m;
    let state = |c: Cell| map.get(c).copied().unwrap_or(Occupancy::Unknown);
    for row in 0..n {
        let y0 = w.origin.y + (n - 1 - row) as f64 * w.cell_m;
        for col in 0..n {
            let x0 = w.origin.x + col as f64 * w.cell_m;
            let lo = frame.cell_from_world(Vec2::new(x0 + r * 0.5, y0 + r * 0.5));
            let hi =
                frame.cell_from_world(Vec2::new(x0 + w.cell_m - r * 0.5, y0 + w.cell_m - r * 0.5));
            let (mut free, mut occ, mut unknown, mut frontier) = (false, false, false, false);
            for cy in lo.y..=hi.y.max(lo.y) {
                for cx in lo.x..=hi.x.max(lo.x) {
                    let c = Cell::new(cx, cy);
                    match state(c) {
                        Occupancy::Free => {
                            free = true;
                            if !frontier
                                && c.neighbours4()
                                    .iter()
                                    .any(|&m| frame.contains(m) && state(m) == Occupancy::Unknown)
                            {
                                frontier = true;
                            }
                        }
                        Occupancy::Occupied => occ = true,
                        Occupancy::Unknown => unknown = true,
                    }
                }
            }
            let i = row * n + col;
            for (ch, on) in [free, occ, unknown, frontier].into_iter().enumerate() {
                if on {
                    out[ch * plane + i] = 255;
                }
            }
        }
    }
    draw_trail(&mut out[4 * plane..5 * plane], w, trail);
    draw_trail(
        &mut out[5 * plane..],
        w,
        &trail[trail.len().saturating_sub(1)..],
    );
    out
}

/// The trail after a decision: its estimated position added, unless the robot has not moved.
pub(crate) fn extend_trail(trail: &mut Vec<Vec2>, snap: &Snapshot) {
    let pos = snap.pose.position();
    if trail.last() != Some(&pos) {
        trail.push(pos);
    }
}

/// The segments between consecutive trail points, drawn into one channel.
fn draw_trail(plane: &mut [u8], w: &Window, trail: &[Vec2]) {
    let n = w.size as i64;
    let mut mark = |p: Vec2| {
        let col = ((p.x - w.origin.x) / w.cell_m).floor();
        let row = n as f64 - 1.0 - ((p.y - w.origin.y) / w.cell_m).floor();
        if col >= 0.0 && row >= 0.0 && (col as i64) < n && (row as i64) < n {
            plane[row as usize * w.size + col as usize] = 255;
        }
    };
    if let [only] = trail {
        mark(*only);
    }
    for pair in trail.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let steps = ((b - a).norm() / (w.cell_m * 0.5))
            .ceil()
            .clamp(1.0, 100_000.0) as usize;
        for k in 0..=steps {
            mark(a + (b - a) * (k as f64 / steps as f64));
        }
    }
}

/// An action as the policy gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Action {
    Index(i64),
    Point([f64; 2]),
}

/// The reply an action makes at a decision shown as `obs`, or what is wrong with it (naming
/// `action`).
pub(crate) fn reply(
    mode: Mode,
    obs: &Obs,
    window: Option<Window>,
    action: Action,
) -> Result<Reply, String> {
    match (mode, action) {
        (Mode::Candidates { .. }, Action::Index(i)) => {
            let n = obs.ids.len();
            if i < 0 || i as usize >= n {
                return Err(if n == 0 {
                    format!("action: {i}, but no candidate is shown (the episode is over: call reset())")
                } else {
                    format!(
                        "action: {i} is not a candidate shown; expected an index from 0 to {} where mask is 1",
                        n - 1
                    )
                });
            }
            Ok(Reply::Choose(obs.ids[i as usize]))
        }
        (Mode::Map { .. }, Action::Point(a)) => {
            if !a.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)) {
                return Err(format!(
                    "action: [{}, {}] is not a point of the crop; expected two finite numbers from 0 to 1 (column, row; row 0 at the top)",
                    a[0], a[1]
                ));
            }
            let w = window.ok_or("action: no decision is pending (call reset())")?;
            Ok(Reply::Goal(w.point(a)))
        }
        (Mode::Graph(cfg), Action::Index(i)) => {
            let target = usize::try_from(i)
                .ok()
                .and_then(|i| obs.targets.get(i).copied().flatten());
            target.map(Reply::Goal).ok_or_else(|| {
                format!(
                    "action: {i} is not an edge of the robot's node; expected an index from 0 to {} where edge_padding_mask is 0",
                    cfg.k - 1
                )
            })
        }
        (Mode::Graph(_), Action::Point(_)) => {
            Err("action: expected one edge index (an integer) in the graph observation".into())
        }
        (Mode::Candidates { .. }, Action::Point(_)) => Err(
            "action: expected one candidate index (an integer) in the candidates observation"
                .into(),
        ),
        (Mode::Map { .. }, Action::Index(_)) => {
            Err("action: expected a point [column, row] in [0, 1]² in the map observation".into())
        }
    }
}

/// The fallback after a goal point with no drivable path: the candidate whose goal is nearest
/// to it (then the lowest id).
pub(crate) fn nearest_candidate(snap: &Snapshot, p: Vec2) -> Option<usize> {
    snap.candidates
        .iter()
        .min_by(|a, b| {
            (a.goal - p)
                .norm()
                .total_cmp(&(b.goal - p).norm())
                .then(a.id.cmp(&b.id))
        })
        .map(|c| c.id)
}
