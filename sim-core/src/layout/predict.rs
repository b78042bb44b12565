//! Prediction of partially observed rooms: a partial room grows into neighbouring faces that are
//! mostly unknown and not behind a wall, choosing the set that maximises
//! `Phi = 10 S - 10 C - 5 N` (S: summed weight of the lines bounding the room, C: concavity
//! `(hull area - area) / area`, N: number of bounding lines). All connected subsets are scored
//! when there are few candidates, else the first ring is grown greedily. A set is kept only if it
//! does not lower `Phi`; growing repeats for a few rounds.

use super::arrangement::{Arrangement, NO_FACE};
use super::rooms::{RoomPlan, NO_ROOM};
use super::{LayoutConfig, LayoutDiagnostics};
use crate::geom::Vec2;

/// Area of the convex hull of `pts` (monotone chain). Sorts `pts`.
pub(crate) fn convex_hull_area_m2(pts: &mut [Vec2]) -> f64 {
    if pts.len() < 3 {
        return 0.0;
    }
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: Vec2, a: Vec2, b: Vec2| (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
    let mut hull: Vec<Vec2> = Vec::with_capacity(pts.len() * 2);
    for &p in pts.iter() {
        while hull.len() >= 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0 {
            hull.pop();
        }
        hull.push(p);
    }
    let lower = hull.len() + 1;
    for &p in pts.iter().rev().skip(1) {
        while hull.len() >= lower && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0 {
            hull.pop();
        }
        hull.push(p);
    }
    hull.pop();
    crate::geom::Polygon::new(hull).area_m2()
}

/// Scores face sets that extend one room.
struct Scorer<'a> {
    arr: &'a Arrangement,
    config: &'a LayoutConfig,
    /// Membership of the room plus the subset being scored.
    in_set: Vec<bool>,
    tags: Vec<u32>,
    pts: Vec<Vec2>,
}

impl Scorer<'_> {
    /// `Phi` of `base` plus `extra`; `base_hull` holds the hull-relevant points of `base`.
    fn phi(&mut self, base: &[u32], base_area: f64, base_pts: &[Vec2], extra: &[u32]) -> f64 {
        let arr = self.arr;
        for &f in base.iter().chain(extra) {
            self.in_set[f as usize] = true;
        }
        self.tags.clear();
        let mut area = base_area;
        self.pts.clear();
        self.pts.extend_from_slice(base_pts);
        for &f in base.iter().chain(extra) {
            let face = &arr.faces[f as usize];
            for (i, &e) in face.edges.iter().enumerate() {
                let o = arr.other_face(e, f);
                if o == NO_FACE || !self.in_set[o as usize] {
                    self.tags.push(face.tags[i]);
                }
            }
        }
        for &f in extra {
            let face = &arr.faces[f as usize];
            area += face.area_m2;
            self.pts.extend_from_slice(&face.vertices);
        }
        for &f in base.iter().chain(extra) {
            self.in_set[f as usize] = false;
        }
        self.tags.sort_unstable();
        self.tags.dedup();
        let s: f64 = self
            .tags
            .iter()
            .map(|t| arr.lines[*t as usize].weight)
            .sum();
        let n = self.tags.len() as f64;
        let hull = convex_hull_area_m2(&mut self.pts);
        let c = if area > 0.0 {
            ((hull - area) / area).max(0.0)
        } else {
            0.0
        };
        self.config.phi_support_weight * s
            - self.config.phi_concavity_weight * c
            - self.config.phi_lines_weight * n
    }
}

/// Grows every partial room of `plan` into the faces that best complete it.
pub(crate) fn predict_rooms(
    arr: &Arrangement,
    plan: &mut RoomPlan,
    config: &LayoutConfig,
    diag: &mut LayoutDiagnostics,
) {
    let mut scorer = Scorer {
        arr,
        config,
        in_set: vec![false; arr.faces.len()],
        tags: Vec::new(),
        pts: Vec::new(),
    };
    let open = |e: u32| arr.edges[e as usize].wall_fraction < config.wall_edge_threshold;
    for r in 0..plan.rooms.len() {
        if !plan.rooms[r].partial {
            continue;
        }
        for _round in 0..config.max_prediction_rounds {
            let base: Vec<u32> = plan.rooms[r]
                .faces
                .iter()
                .chain(&plan.rooms[r].predicted)
                .copied()
                .collect();
            let Some((ring, cands)) =
                growth_candidates(arr, plan, &base, &open, config.max_exhaustive_candidates)
            else {
                break;
            };
            let base_area: f64 = base.iter().map(|f| arr.faces[*f as usize].area_m2).sum();
            let mut base_pts: Vec<Vec2> = base
                .iter()
                .flat_map(|f| arr.faces[*f as usize].vertices.iter().copied())
                .collect();
            base_pts = hull_points(&mut base_pts);
            let phi0 = scorer.phi(&base, base_area, &base_pts, &[]);
            diag.phi_evaluations += 1;
            let chosen: Vec<u32> = if cands.len() <= config.max_exhaustive_candidates {
                best_subset(
                    arr,
                    &mut scorer,
                    &base,
                    base_area,
                    &base_pts,
                    &cands,
                    phi0,
                    &open,
                    diag,
                )
            } else {
                // Greedy over the ring.
                let mut chosen = Vec::new();
                let mut phi = phi0;
                for &c in &ring {
                    chosen.push(c);
                    let p = scorer.phi(&base, base_area, &base_pts, &chosen);
                    diag.phi_evaluations += 1;
                    if p >= phi - 1e-9 {
                        phi = p;
                    } else {
                        chosen.pop();
                    }
                }
                chosen
            };
            if chosen.is_empty() {
                break;
            }
            for &f in &chosen {
                plan.face_room[f as usize] = r as u32;
            }
            plan.rooms[r].predicted.extend(chosen);
        }
    }
}

/// The faces a partial room with faces `base` may grow into: the first ring of candidate faces
/// (in no room yet) across open edges, and the candidates to choose from: the ring and the faces
/// beyond it breadth-first while they are at most `max` (for all subsets), else the ring alone.
/// `None` when the ring is empty.
fn growth_candidates(
    arr: &Arrangement,
    plan: &RoomPlan,
    base: &[u32],
    open: &impl Fn(u32) -> bool,
    max: usize,
) -> Option<(Vec<u32>, Vec<u32>)> {
    let is_cand = |f: u32, plan: &RoomPlan| {
        f != NO_FACE && plan.candidate[f as usize] && plan.face_room[f as usize] == NO_ROOM
    };
    // First ring.
    let mut ring: Vec<u32> = Vec::new();
    for &f in base {
        for &e in &arr.faces[f as usize].edges {
            let o = arr.other_face(e, f);
            if open(e) && is_cand(o, plan) {
                ring.push(o);
            }
        }
    }
    ring.sort_unstable();
    ring.dedup();
    if ring.is_empty() {
        return None;
    }
    // Breadth-first beyond the ring, while few enough for all subsets.
    let mut all = ring.clone();
    let mut head = 0;
    while head < all.len() && all.len() <= max {
        let f = all[head];
        head += 1;
        for &e in &arr.faces[f as usize].edges {
            let o = arr.other_face(e, f);
            if open(e) && is_cand(o, plan) && !all.contains(&o) {
                all.push(o);
            }
        }
    }
    let cands = if all.len() <= max { all } else { ring.clone() };
    Some((ring, cands))
}

/// The points of `pts` on their convex hull (enough to compute hulls of supersets).
fn hull_points(pts: &mut [Vec2]) -> Vec<Vec2> {
    if pts.len() < 3 {
        return pts.to_vec();
    }
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: Vec2, a: Vec2, b: Vec2| (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
    let mut hull: Vec<Vec2> = Vec::new();
    for &p in pts.iter() {
        while hull.len() >= 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0 {
            hull.pop();
        }
        hull.push(p);
    }
    let lower = hull.len() + 1;
    for &p in pts.iter().rev().skip(1) {
        while hull.len() >= lower && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0 {
            hull.pop();
        }
        hull.push(p);
    }
    hull.pop();
    hull
}

/// The non-empty subset of `cands`, connected to the room through open edges, with the highest
/// `Phi` if that is not lower than `phi0`; empty otherwise.
#[allow(clippy::too_many_arguments)]
fn best_subset(
    arr: &Arrangement,
    scorer: &mut Scorer<'_>,
    base: &[u32],
    base_area: f64,
    base_pts: &[Vec2],
    cands: &[u32],
    phi0: f64,
    open: &impl Fn(u32) -> bool,
    diag: &mut LayoutDiagnostics,
) -> Vec<u32> {
    let k = cands.len();
    // Local adjacency: to the room, and between candidates.
    let mut touches_room = vec![false; k];
    let mut adj = vec![0u32; k];
    for (i, &c) in cands.iter().enumerate() {
        for &e in &arr.faces[c as usize].edges {
            if !open(e) {
                continue;
            }
            let o = arr.other_face(e, c);
            if base.contains(&o) {
                touches_room[i] = true;
            }
            if let Some(j) = cands.iter().position(|&x| x == o) {
                adj[i] |= 1 << j;
            }
        }
    }
    let mut best: Option<(f64, u32)> = None;
    let mut extra = Vec::with_capacity(k);
    for mask in 1u32..(1u32 << k) {
        // Connected to the room?
        let mut reached: u32 = 0;
        for (i, t) in touches_room.iter().enumerate() {
            if *t && mask & (1 << i) != 0 {
                reached |= 1 << i;
            }
        }
        loop {
            let mut next = reached;
            for (i, a) in adj.iter().enumerate() {
                if reached & (1 << i) != 0 {
                    next |= a & mask;
                }
            }
            if next == reached {
                break;
            }
            reached = next;
        }
        if reached != mask {
            continue;
        }
        extra.clear();
        extra.extend((0..k).filter(|i| mask & (1 << i) != 0).map(|i| cands[i]));
        let p = scorer.phi(base, base_area, base_pts, &extra);
        diag.phi_evaluations += 1;
        if best.is_none_or(|(bp, _)| p > bp + 1e-9) {
            best = Some((p, mask));
        }
    }
    match best {
        Some((p, mask)) if p >= phi0 - 1e-9 => (0..k)
            .filter(|i| mask & (1 << i) != 0)
            .map(|i| cands[i])
            .collect(),
        _ => Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_area_of_an_l() {
        let mut pts = vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(2.0, 0.0),
            Vec2::new(2.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 2.0),
            Vec2::new(0.0, 2.0),
        ];
        assert!((convex_hull_area_m2(&mut pts) - 3.5).abs() < 1e-12);
        assert_eq!(hull_points(&mut pts).len(), 5);
    }
}
