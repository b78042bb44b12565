//! Accuracy of a layout against ground-truth rooms, rasterised on a grid frame.

use std::collections::BTreeMap;

use super::{Layout, RoomLabel};
use crate::building::{fill_polygon, Room};
use crate::geom::{Polygon, Vec2};
use crate::grid::{Bitmap, GridFrame};

/// How well a layout matches the true rooms.
#[derive(Debug, Clone, PartialEq)]
pub struct Accuracy {
    /// Mean over true rooms of the IoU with the best-matching layout room (0 when unmatched).
    pub matched_room_iou: f64,
    /// Fraction of the cells of true rooms that lie in the layout room matched to their room.
    pub pixel_accuracy: f64,
    pub rooms_found: usize,
    pub rooms_true: usize,
    /// True rooms whose best match is a layout room with a frontier (Partial or Open).
    pub partial_rooms: usize,
    /// Mean IoU of those rooms with their matched layout room's predicted polygon.
    pub predicted_iou: Option<f64>,
    /// The same rooms' mean IoU with the observed polygon only (no prediction).
    pub observed_only_iou: Option<f64>,
}

const NONE: u32 = u32::MAX;

/// One label per cell: the last polygon covering the cell's centre.
fn rasterise<'a>(frame: GridFrame, polys: impl Iterator<Item = &'a Polygon>) -> Vec<u32> {
    let mut labels = vec![NONE; frame.len()];
    let res = frame.resolution_m;
    for (i, p) in polys.enumerate() {
        let bb = p.aabb();
        if bb.is_empty() || frame.is_empty() {
            continue;
        }
        let x0 =
            (((bb.min.x - frame.origin_m.x) / res).floor() as i64).clamp(0, frame.width as i64);
        let y0 =
            (((bb.min.y - frame.origin_m.y) / res).floor() as i64).clamp(0, frame.height as i64);
        let x1 = (((bb.max.x - frame.origin_m.x) / res).ceil() as i64).clamp(0, frame.width as i64);
        let y1 =
            (((bb.max.y - frame.origin_m.y) / res).ceil() as i64).clamp(0, frame.height as i64);
        if x1 <= x0 || y1 <= y0 {
            continue;
        }
        let sub = GridFrame::new(
            frame.origin_m + Vec2::new(x0 as f64, y0 as f64) * res,
            res,
            (x1 - x0) as u32,
            (y1 - y0) as u32,
        );
        let mut m = Bitmap::filled(sub, false);
        fill_polygon(&mut m, p, true);
        for (j, &b) in m.data.iter().enumerate() {
            if b {
                let (sx, sy) = (j % sub.width as usize, j / sub.width as usize);
                let k = (sy + y0 as usize) * frame.width as usize + sx + x0 as usize;
                labels[k] = i as u32;
            }
        }
    }
    labels
}

fn counts(labels: &[u32], n: usize) -> Vec<usize> {
    let mut c = vec![0; n];
    for &l in labels {
        if l != NONE {
            c[l as usize] += 1;
        }
    }
    c
}

fn iou(inter: usize, a: usize, b: usize) -> f64 {
    let union = a + b - inter;
    if union == 0 {
        0.0
    } else {
        inter as f64 / union as f64
    }
}

/// A doorway at least this wide (m) joins two true rooms into one region of the map.
pub(crate) const OPENING_M: f64 = 1.5;

/// The pairs of `b`'s rooms (indices into `b.rooms`) that no wall parts, to be scored as one
/// ([`evaluate_merged`]): joined by a doorway at least [`OPENING_M`] wide, or both connective
/// (kind `corridor`, `hall` or `lobby`) and joined by any doorway: the pieces a generator or an
/// annotator splits a corridor into, which no map shows apart.
pub fn unwalled_pairs(b: &crate::building::Building) -> Vec<(usize, usize)> {
    let index = |id: Option<u32>| b.rooms.iter().position(|r| Some(r.id) == id);
    let connective = |i: usize| matches!(b.rooms[i].kind.as_str(), "corridor" | "hall" | "lobby");
    b.doors
        .iter()
        .filter_map(|d| {
            let (i, j) = (index(d.rooms[0])?, index(d.rooms[1])?);
            let wide = (d.b - d.a).norm() >= OPENING_M;
            (i != j && (wide || (connective(i) && connective(j)))).then_some((i, j))
        })
        .collect()
}

/// Scores `layout` against `truth` on `frame`.
pub fn evaluate(layout: &Layout, truth: &[Room], frame: GridFrame) -> Accuracy {
    evaluate_merged(layout, truth, &[], frame)
}

/// [`evaluate`] with some true rooms scored as one: every pair `(i, j)` of indices into `truth`
/// in `merge` joins two rooms (for example the straight pieces of one corridor, which a
/// generator splits where corridors meet without a wall).
pub fn evaluate_merged(
    layout: &Layout,
    truth: &[Room],
    merge: &[(usize, usize)],
    frame: GridFrame,
) -> Accuracy {
    let mut group: Vec<usize> = (0..truth.len()).collect();
    fn root(g: &mut [usize], mut x: usize) -> usize {
        while g[x] != x {
            g[x] = g[g[x]];
            x = g[x];
        }
        x
    }
    for &(a, b) in merge {
        if a < truth.len() && b < truth.len() {
            let (ra, rb) = (root(&mut group, a), root(&mut group, b));
            group[ra.max(rb)] = ra.min(rb);
        }
    }
    // Dense group ids in index order.
    let mut id = vec![usize::MAX; truth.len()];
    let mut next = 0u32;
    let mut dense = vec![0u32; truth.len()];
    for (i, d) in dense.iter_mut().enumerate() {
        let r = root(&mut group, i);
        if id[r] == usize::MAX {
            id[r] = next as usize;
            next += 1;
        }
        *d = id[r] as u32;
    }
    let mut t_lab = rasterise(frame, truth.iter().map(|r| &r.polygon));
    for l in &mut t_lab {
        if *l != NONE {
            *l = dense[*l as usize];
        }
    }
    let truth_groups = next as usize;
    let l_lab = rasterise(frame, layout.rooms.iter().map(|r| &r.polygon));
    let o_lab = rasterise(frame, layout.rooms.iter().map(|r| &r.observed_polygon));
    let nt = truth_groups;
    let nl = layout.rooms.len();
    let t_n = counts(&t_lab, nt);
    let l_n = counts(&l_lab, nl);
    let o_n = counts(&o_lab, nl);
    let mut inter: BTreeMap<(u32, u32), usize> = BTreeMap::new();
    let mut inter_obs: BTreeMap<(u32, u32), usize> = BTreeMap::new();
    for i in 0..t_lab.len() {
        if t_lab[i] == NONE {
            continue;
        }
        if l_lab[i] != NONE {
            *inter.entry((t_lab[i], l_lab[i])).or_default() += 1;
        }
        if o_lab[i] != NONE {
            *inter_obs.entry((t_lab[i], o_lab[i])).or_default() += 1;
        }
    }
    let mut best: Vec<Option<(f64, u32, usize)>> = vec![None; nt];
    for (&(t, l), &n) in &inter {
        let v = iou(n, t_n[t as usize], l_n[l as usize]);
        if best[t as usize].is_none_or(|(b, _, _)| v > b) {
            best[t as usize] = Some((v, l, n));
        }
    }
    let total_true: usize = t_n.iter().sum();
    let matched_room_iou = if nt == 0 {
        0.0
    } else {
        best.iter().map(|b| b.map_or(0.0, |x| x.0)).sum::<f64>() / nt as f64
    };
    let pixel_accuracy = if total_true == 0 {
        0.0
    } else {
        best.iter().map(|b| b.map_or(0, |x| x.2)).sum::<usize>() as f64 / total_true as f64
    };
    let mut pred = Vec::new();
    let mut obs = Vec::new();
    for (t, b) in best.iter().enumerate() {
        let Some((v, l, _)) = b else { continue };
        if layout.rooms[*l as usize].label == RoomLabel::Full {
            continue;
        }
        pred.push(*v);
        let io = inter_obs.get(&(t as u32, *l)).copied().unwrap_or(0);
        obs.push(iou(io, t_n[t], o_n[*l as usize]));
    }
    let mean = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
    Accuracy {
        matched_room_iou,
        pixel_accuracy,
        rooms_found: nl,
        rooms_true: nt,
        partial_rooms: pred.len(),
        predicted_iou: mean(&pred),
        observed_only_iou: mean(&obs),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::{LayoutRoom, RoomLabel};

    /// Which true rooms are scored as one: (kinds of rooms 1 and 2, door width, merged).
    #[test]
    fn rooms_no_wall_parts_are_scored_as_one() {
        use crate::building::{Building, Door, Geometry};
        use crate::geom::Polygon;
        let cases = [
            (("corridor", "corridor"), 0.9, true),
            (("hall", "lobby"), 0.9, true),
            (("corridor", "classroom"), 0.9, false),
            (("corridor", "classroom"), 1.5, true),
            (("office", "office"), 1.2, false),
            (("washroom", "corridor"), 0.9, false),
        ];
        for ((k1, k2), width, merged) in cases {
            let mut a = room(7, (0.0, 0.0), (4.0, 2.0));
            a.kind = k1.into();
            let mut b = room(9, (0.0, 2.0), (4.0, 6.0));
            b.kind = k2.into();
            let building = Building {
                name: "t".into(),
                geometry: Geometry::Vector {
                    outline: Polygon::rect(Vec2::new(0.0, 0.0), Vec2::new(4.0, 6.0)),
                    solids: vec![],
                },
                rooms: vec![a, b],
                doors: vec![
                    Door {
                        a: Vec2::new(1.0, 2.0),
                        b: Vec2::new(1.0 + width, 2.0),
                        rooms: [Some(9), Some(7)],
                    },
                    // A door to the outside joins nothing.
                    Door {
                        a: Vec2::new(0.0, 0.5),
                        b: Vec2::new(0.0, 2.5),
                        rooms: [Some(7), None],
                    },
                ],
                start: None,
            };
            let want: Vec<(usize, usize)> = if merged { vec![(1, 0)] } else { vec![] };
            assert_eq!(unwalled_pairs(&building), want, "{k1} {k2} {width}");
        }
    }

    fn room(id: u32, min: (f64, f64), max: (f64, f64)) -> Room {
        Room {
            id,
            kind: String::new(),
            polygon: Polygon::rect(Vec2::new(min.0, min.1), Vec2::new(max.0, max.1)),
        }
    }

    #[test]
    fn perfect_and_half_layouts() {
        let frame = GridFrame::new(Vec2::zeros(), 0.1, 100, 50);
        let truth = vec![
            room(0, (0.0, 0.0), (5.0, 5.0)),
            room(1, (5.0, 0.0), (10.0, 5.0)),
        ];
        let lr = |id: u32, r: &Room, observed: Polygon, label| LayoutRoom {
            id,
            polygon: r.polygon.clone(),
            open_edges: vec![false; r.polygon.vertices.len()],
            observed_polygon: observed,
            label,
            predicted: true,
            area_m2: 25.0,
            observed_area_m2: 12.5,
            unknown_area_m2: 0.0,
        };
        let half = Polygon::rect(Vec2::new(5.0, 0.0), Vec2::new(7.5, 5.0));
        let layout = Layout {
            rooms: vec![
                lr(0, &truth[0], truth[0].polygon.clone(), RoomLabel::Full),
                lr(1, &truth[1], half, RoomLabel::Partial),
            ],
            ..Layout::default()
        };
        let a = evaluate(&layout, &truth, frame);
        assert!((a.matched_room_iou - 1.0).abs() < 1e-9, "{a:?}");
        assert!((a.pixel_accuracy - 1.0).abs() < 1e-9);
        assert_eq!(a.partial_rooms, 1);
        assert!((a.predicted_iou.unwrap() - 1.0).abs() < 1e-9);
        assert!((a.observed_only_iou.unwrap() - 0.5).abs() < 1e-9);
        let empty = evaluate(&Layout::default(), &truth, frame);
        assert_eq!(empty.matched_room_iou, 0.0);
        assert_eq!(empty.rooms_found, 0);
    }
}
