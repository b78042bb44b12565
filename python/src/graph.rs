//! The `graph` observation: the known free space as a graph of nodes in ARiADNE's shapes and
//! order (Cao et al., "ARiADNE: A Reinforcement learning approach using Attention-based Deep
//! Networks for Exploration", ICRA 2023): nodes on a lattice over the known free cells, the
//! robot's position first; each node's edges to its K nearest nodes in sight of it; each node's
//! utility the frontier points it sees within sensing range; a guidepost where the robot has
//! been. Built from the robot's map and trail only (never ground truth).

use sim_core::grid::{Cell, Occupancy, OccupancyGrid};
use sim_core::Vec2;

/// The graph's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct GraphConfig {
    /// N: nodes, padded (ARiADNE's NODE_PADDING_SIZE, 360).
    pub(crate) nodes: usize,
    /// K: edges per node, padded (ARiADNE's K_SIZE, 20).
    pub(crate) k: usize,
    /// The lattice's spacing (m).
    pub(crate) spacing_m: f64,
    /// How far a node sees frontier points (m).
    pub(crate) range_m: f64,
}

/// The graph of a decision.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Graph {
    /// Node positions (map frame, m); node 0 is the robot's estimated position.
    pub(crate) nodes: Vec<Vec2>,
    /// Per node, its neighbours by distance (itself first), at most K.
    pub(crate) edges: Vec<Vec<usize>>,
    pub(crate) utility: Vec<u32>,
    pub(crate) guidepost: Vec<bool>,
}

/// Whether `b` is in sight of `a` on the map: every cell of the straight segment from `a`
/// known free, `b` itself too unless `b_may_be_any` (a frontier point seen from `a`).
fn in_sight(map: &OccupancyGrid, a: Cell, b: Cell, b_may_be_any: bool) -> bool {
    let (mut x, mut y) = (a.x, a.y);
    let (dx, dy) = ((b.x - a.x).abs(), -(b.y - a.y).abs());
    let (sx, sy) = (
        if a.x < b.x { 1 } else { -1 },
        if a.y < b.y { 1 } else { -1 },
    );
    let mut err = dx + dy;
    loop {
        let end = x == b.x && y == b.y;
        if end && b_may_be_any {
            return true;
        }
        if map.get(Cell::new(x, y)) != Some(&Occupancy::Free) {
            return false;
        }
        if end {
            return true;
        }
        let e2 = 2 * err;
        if e2 >= dy {
            err += dy;
            x += sx;
        }
        if e2 <= dx {
            err += dx;
            y += sy;
        }
    }
}

/// The frontier points: one frontier cell (free beside unknown) per block of about 0.2 m, in
/// row-major order of the blocks.
fn frontier_points(map: &OccupancyGrid) -> Vec<Cell> {
    let f = map.frame;
    let block = ((0.2 / f.resolution_m).round() as i32).max(1);
    let (w, h) = (f.width as i32, f.height as i32);
    let mut out = Vec::new();
    for by in (0..h).step_by(block as usize) {
        for bx in (0..w).step_by(block as usize) {
            'block: for y in by..(by + block).min(h) {
                for x in bx..(bx + block).min(w) {
                    let c = Cell::new(x, y);
                    if map.get(c) == Some(&Occupancy::Free)
                        && c.neighbours4()
                            .iter()
                            .any(|&n| map.get(n) == Some(&Occupancy::Unknown))
                    {
                        out.push(c);
                        break 'block;
                    }
                }
            }
        }
    }
    out
}

/// The graph of `map` seen from `robot`, the robot having been at `trail`: the robot's node
/// first, then the lattice points (spacing `spacing_m`, cell centres of the map's bounds) on
/// known free cells more than half a spacing from the robot, by x then y, at most N - 1 of
/// them (the nearest to the robot).
pub(crate) fn build(cfg: GraphConfig, map: &OccupancyGrid, robot: Vec2, trail: &[Vec2]) -> Graph {
    let f = map.frame;
    let s = cfg.spacing_m;
    // Lattice points on known free cells, by x then y (ARiADNE's order).
    let mut lattice = Vec::new();
    let b = f.bounds();
    let (nx, ny) = (
        ((b.max.x - b.min.x) / s).floor() as i64,
        ((b.max.y - b.min.y) / s).floor() as i64,
    );
    for i in 0..=nx.min(100_000) {
        for j in 0..=ny.min(100_000) {
            let p = Vec2::new(
                b.min.x + (i as f64 + 0.5) * s,
                b.min.y + (j as f64 + 0.5) * s,
            );
            // (A lattice point within half a spacing of the robot is the robot's own node.)
            if map.get(f.cell_from_world(p)) == Some(&Occupancy::Free)
                && (p - robot).norm() > s / 2.0
            {
                lattice.push(p);
            }
        }
    }
    // At most N - 1 of them: the nearest to the robot, kept in lattice order.
    if lattice.len() > cfg.nodes - 1 {
        let mut order: Vec<usize> = (0..lattice.len()).collect();
        order.sort_by(|&a, &b| {
            (lattice[a] - robot)
                .norm()
                .total_cmp(&(lattice[b] - robot).norm())
                .then(a.cmp(&b))
        });
        order.truncate(cfg.nodes - 1);
        order.sort_unstable();
        lattice = order.into_iter().map(|i| lattice[i]).collect();
    }
    let mut nodes = Vec::with_capacity(lattice.len() + 1);
    nodes.push(robot);
    nodes.extend(lattice);
    let cells: Vec<Cell> = nodes.iter().map(|&p| f.cell_from_world(p)).collect();
    // Edges: the K nearest nodes (itself first) in sight.
    let edges: Vec<Vec<usize>> = (0..nodes.len())
        .map(|i| {
            let mut order: Vec<usize> = (0..nodes.len()).collect();
            order.sort_by(|&a, &b| {
                (nodes[a] - nodes[i])
                    .norm()
                    .total_cmp(&(nodes[b] - nodes[i]).norm())
                    .then(a.cmp(&b))
            });
            order.truncate(cfg.k);
            order
                .into_iter()
                .filter(|&j| j == i || in_sight(map, cells[i], cells[j], false))
                .collect()
        })
        .collect();
    // Utility: the frontier points within range in sight of the node.
    let frontier = frontier_points(map);
    let utility = cells
        .iter()
        .zip(&nodes)
        .map(|(&c, &p)| {
            frontier
                .iter()
                .filter(|&&q| {
                    (f.world_from_cell(q) - p).norm() < cfg.range_m && in_sight(map, c, q, true)
                })
                .count() as u32
        })
        .collect();
    // Guideposts: the robot's node, and the lattice nodes within half a spacing of the trail.
    let guidepost = nodes
        .iter()
        .enumerate()
        .map(|(i, &p)| i == 0 || trail.iter().any(|&t| (t - p).norm() <= s / 2.0))
        .collect();
    Graph {
        nodes,
        edges,
        utility,
        guidepost,
    }
}

/// The graph's arrays in ARiADNE's shapes (without its batch axis): `node_inputs` (N, 4)
/// float32 `[x, y, utility / 50, guidepost]` with x, y from the map's lower-left corner over its
/// longer side; `edge_inputs` (1, K) int64, the robot node's neighbours (0 pads); `current_index`
/// (1, 1) int64 (0: the robot's node); `node_padding_mask` (1, N) int8, 1 for a padded node;
/// `edge_padding_mask` (1, K) int8, 1 where `edge_inputs` is 0 (ARiADNE's rule: node 0, the
/// robot's own, is not a move); `edge_mask` (N, N) int8, 0 where an edge joins the nodes.
pub(crate) fn arrays(
    cfg: GraphConfig,
    g: &Graph,
    map: &OccupancyGrid,
) -> Vec<(&'static str, &'static str, Vec<usize>, Vec<u8>)> {
    let (n, k) = (cfg.nodes, cfg.k);
    let b = map.frame.bounds();
    let extent = (b.max.x - b.min.x).max(b.max.y - b.min.y).max(1e-9);
    let mut inputs = vec![0f32; n * 4];
    for (i, p) in g.nodes.iter().enumerate().take(n) {
        inputs[i * 4] = ((p.x - b.min.x) / extent) as f32;
        inputs[i * 4 + 1] = ((p.y - b.min.y) / extent) as f32;
        inputs[i * 4 + 2] = g.utility[i] as f32 / 50.0;
        inputs[i * 4 + 3] = f32::from(u8::from(g.guidepost[i]));
    }
    let mut edge_inputs = vec![0i64; k];
    for (slot, &j) in edge_inputs.iter_mut().zip(&g.edges[0]) {
        *slot = j as i64;
    }
    let node_pad: Vec<u8> = (0..n).map(|i| u8::from(i >= g.nodes.len())).collect();
    let edge_pad: Vec<u8> = edge_inputs.iter().map(|&j| u8::from(j == 0)).collect();
    let mut mask = vec![1u8; n * n];
    for (i, es) in g.edges.iter().enumerate().take(n) {
        for &j in es {
            mask[i * n + j] = 0;
        }
    }
    let f32s = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let i64s = |v: &[i64]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    vec![
        ("node_inputs", "float32", vec![n, 4], f32s(&inputs)),
        ("edge_inputs", "int64", vec![1, k], i64s(&edge_inputs)),
        ("current_index", "int64", vec![1, 1], i64s(&[0])),
        ("node_padding_mask", "int8", vec![1, n], node_pad),
        ("edge_padding_mask", "int8", vec![1, k], edge_pad),
        ("edge_mask", "int8", vec![n, n], mask),
    ]
}

/// The arrays of an episode that ended before its first decision: every node padding.
pub(crate) fn empty_arrays(
    cfg: GraphConfig,
) -> Vec<(&'static str, &'static str, Vec<usize>, Vec<u8>)> {
    let (n, k) = (cfg.nodes, cfg.k);
    vec![
        ("node_inputs", "float32", vec![n, 4], vec![0u8; n * 16]),
        ("edge_inputs", "int64", vec![1, k], vec![0u8; k * 8]),
        ("current_index", "int64", vec![1, 1], vec![0u8; 8]),
        ("node_padding_mask", "int8", vec![1, n], vec![1u8; n]),
        ("edge_padding_mask", "int8", vec![1, k], vec![1u8; k]),
        ("edge_mask", "int8", vec![n, n], vec![1u8; n * n]),
    ]
}
