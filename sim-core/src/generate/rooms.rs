//! Rooms along the skeleton: bands sliced into rooms of a few repeated widths, with doors.

use rand::Rng;

use super::plan::{Band, Entrance, Facing, Params, Skeleton};
use super::{rect, BuildingKind, Layout, Opening, Zone};
use crate::geom::{Aabb, Pose, Vec2};

/// Bands shorter than this hold no room (they are left out of the building).
const MIN_ROOM_M: f64 = 2.2;
const EPS: f64 = 1e-6;

#[derive(Debug, Clone, Copy)]
struct Module {
    kind: &'static str,
    width_m: f64,
    weight: f64,
    max_run: u32,
}

fn modules(p: &Params) -> Vec<Module> {
    let m = |kind, width_m, weight, max_run| Module {
        kind,
        width_m,
        weight,
        max_run,
    };
    match p.kind {
        BuildingKind::School => vec![
            m("classroom", p.module_m, 6.0, 5),
            m("classroom", p.module2_m, 2.5, 3),
            m("toilet", 3.6, 0.6, 1),
            m("storage", 2.6, 0.5, 1),
            m("office", 4.0, 0.6, 2),
            m("hall", 2.0 * p.module_m, 0.8, 1),
        ],
        BuildingKind::Office => vec![
            m("office", p.module_m, 6.0, 6),
            m("office", p.module2_m, 2.5, 3),
            m("meeting", 2.0 * p.module_m, 1.0, 1),
            m("toilet", 3.0, 0.6, 1),
            m("kitchen", 3.6, 0.4, 1),
            m("storage", 2.4, 0.4, 1),
        ],
    }
}

/// Room widths and kinds filling a band of length `len_m`, in order along it.
fn slice(
    p: &Params,
    len_m: f64,
    halls_left: &mut u32,
    force_hall: bool,
    entrance: bool,
    rng: &mut impl Rng,
) -> Vec<(f64, &'static str)> {
    let mods = modules(p);
    let mut out: Vec<(f64, &'static str)> = Vec::new();
    let mut sum = 0.0;
    loop {
        let weights: Vec<f64> = mods
            .iter()
            .map(|m| {
                if m.kind == "hall" && *halls_left == 0 {
                    0.0
                } else {
                    m.weight
                }
            })
            .collect();
        let total: f64 = weights.iter().sum();
        let mut r = rng.random_range(0.0..total);
        let mut k = 0;
        while k + 1 < mods.len() && r >= weights[k] {
            r -= weights[k];
            k += 1;
        }
        let m = mods[k];
        let run = rng.random_range(1..=m.max_run);
        let mut stop = false;
        for _ in 0..run {
            if sum + m.width_m / 2.0 > len_m {
                stop = true;
                break;
            }
            out.push((m.width_m, m.kind));
            sum += m.width_m;
            if m.kind == "hall" {
                *halls_left = halls_left.saturating_sub(1);
            }
        }
        if stop {
            break;
        }
    }
    if out.is_empty() {
        out.push((len_m, mods[0].kind));
        sum = len_m;
    }
    if force_hall && out.len() >= 3 {
        let k = out.len() / 4;
        let w = 2.0 * p.module_m;
        sum += w - out[k].0;
        out[k] = (w, "hall");
        *halls_left = halls_left.saturating_sub(1);
    }
    if entrance {
        let mid = out.len() / 2;
        let w = (1.6 * p.module_m).max(6.0);
        sum += w - out[mid].0;
        out[mid] = (w, "entrance");
    }
    let scale = len_m / sum;
    for r in &mut out {
        r.0 *= scale;
    }
    out
}

/// A band's geometry along its length.
struct BandFrame<'a> {
    band: &'a Band,
}

impl BandFrame<'_> {
    fn span(&self) -> (f64, f64) {
        let r = &self.band.rect;
        match self.band.facing {
            Facing::North | Facing::South => (r.min.x, r.max.x),
            Facing::East | Facing::West => (r.min.y, r.max.y),
        }
    }
    fn depth_m(&self) -> f64 {
        let r = &self.band.rect;
        match self.band.facing {
            Facing::North | Facing::South => r.height_m(),
            Facing::East | Facing::West => r.width_m(),
        }
    }
    /// The point at `t` along the band and `d` from its corridor side.
    fn at(&self, t: f64, d: f64) -> Vec2 {
        let r = &self.band.rect;
        match self.band.facing {
            Facing::North => Vec2::new(t, r.max.y - d),
            Facing::South => Vec2::new(t, r.min.y + d),
            Facing::East => Vec2::new(r.max.x - d, t),
            Facing::West => Vec2::new(r.min.x + d, t),
        }
    }
    fn room(&self, t0: f64, t1: f64) -> Aabb {
        let r = &self.band.rect;
        match self.band.facing {
            Facing::North | Facing::South => rect(t0, r.min.y, t1, r.max.y),
            Facing::East | Facing::West => rect(r.min.x, t0, r.max.x, t1),
        }
    }
}

/// Turns a skeleton into zones and openings.
pub(super) fn fill(p: &Params, sk: &Skeleton, rng: &mut impl Rng) -> Layout {
    let (mut zones, mut openings) = corridors(sk);
    let mut halls_left = p.halls;
    let mut start: Option<Pose> = None;
    for (bi, band) in sk.bands.iter().enumerate() {
        let f = BandFrame { band };
        let (lo, hi) = f.span();
        if hi - lo < MIN_ROOM_M || f.depth_m() < MIN_ROOM_M {
            continue;
        }
        let is_entrance = bi == 0 && sk.entrance == Entrance::Hall;
        // A school has at least one hall: the second band gets one if none came up yet.
        let force_hall = p.kind == BuildingKind::School
            && bi == 1
            && halls_left == p.halls
            && hi - lo >= 4.0 * p.module_m;
        let rooms = slice(p, hi - lo, &mut halls_left, force_hall, is_entrance, rng);
        let door_mode = rng.random_range(0..3u32);
        let mut band_rooms = BandRooms {
            p,
            f,
            zones: &mut zones,
            openings: &mut openings,
        };
        if let Some(s) = band_rooms.add(&rooms, lo, hi, door_mode, rng) {
            start = Some(s);
        }
    }
    // Fill in the corridor side of each room door: the corridor sharing that edge.
    let n_corr = sk.corridors.len();
    for o in &mut openings {
        if o.zones[1].is_none() && o.zones[0].is_some_and(|z| z >= n_corr) {
            let mid = (o.a + o.b) / 2.0;
            o.zones[1] = sk.corridors.iter().position(|c| on_boundary(c, mid));
        }
    }
    extra_rooms(p, sk, &mut zones, &mut openings);
    // Order openings: the corridor side of room doors was resolved above; make the entrance
    // (if at a corridor end) explicit.
    let start = match (start, &sk.entrance) {
        (Some(s), _) => s,
        _ => {
            let c = &sk.corridors[0];
            let yc = (c.min.y + c.max.y) / 2.0;
            let half = ((c.height_m() - 0.6) / 2.0).min(0.9);
            openings.push(Opening {
                a: Vec2::new(c.min.x, yc - half),
                b: Vec2::new(c.min.x, yc + half),
                zones: [Some(0), None],
            });
            Pose::new(c.min.x + 1.2, yc, 0.0)
        }
    };
    Layout {
        zones,
        openings,
        start,
    }
}

/// The corridors' zones, and the openings where corridors meet.
fn corridors(sk: &Skeleton) -> (Vec<Zone>, Vec<Opening>) {
    let zones: Vec<Zone> = sk
        .corridors
        .iter()
        .map(|r| Zone {
            rect: *r,
            kind: "corridor",
        })
        .collect();
    let mut openings: Vec<Opening> = Vec::new();
    // Corridor junctions are open along their whole shared edge.
    for i in 0..sk.corridors.len() {
        for j in i + 1..sk.corridors.len() {
            if let Some((a, b)) = shared_edge(&sk.corridors[i], &sk.corridors[j]) {
                openings.push(Opening {
                    a,
                    b,
                    zones: [Some(i), Some(j)],
                });
            }
        }
    }
    (zones, openings)
}

/// The rooms of one band being added to the layout's zones and openings.
struct BandRooms<'a, 'b> {
    p: &'a Params,
    f: BandFrame<'a>,
    zones: &'b mut Vec<Zone>,
    openings: &'b mut Vec<Opening>,
}

impl BandRooms<'_, '_> {
    /// Adds the band's `rooms` (width, kind) from `lo` to `hi` with their doors; returns the
    /// start pose if one of them is the entrance.
    fn add(
        &mut self,
        rooms: &[(f64, &'static str)],
        lo: f64,
        hi: f64,
        door_mode: u32,
        rng: &mut impl Rng,
    ) -> Option<Pose> {
        let (p, f) = (self.p, &self.f);
        let mut start = None;
        let mut t = lo;
        let mut prev: Option<(usize, &'static str)> = None;
        for (k, &(w, kind)) in rooms.iter().enumerate() {
            let t1 = if k + 1 == rooms.len() { hi } else { t + w };
            let zi = self.zones.len();
            self.zones.push(Zone {
                rect: f.room(t, t1),
                kind,
            });
            for (s0, s1) in corridor_doors(p, kind, t, t1, door_mode) {
                self.openings.push(Opening {
                    a: f.at(s0, 0.0),
                    b: f.at(s1, 0.0),
                    zones: [Some(zi), None],
                });
            }
            // Some neighbours are connected, away from the corridor.
            if let Some((pi, pkind)) = prev {
                let private = |k: &str| k == "toilet" || k == "storage" || k == "entrance";
                let depth = f.depth_m();
                if !private(kind)
                    && !private(pkind)
                    && depth >= 3.0
                    && rng.random_bool(p.connect_prob)
                {
                    let d0 = depth - 0.6 - 0.9;
                    self.openings.push(Opening {
                        a: f.at(t, d0),
                        b: f.at(t, d0 + 0.9),
                        zones: [Some(pi), Some(zi)],
                    });
                }
            }
            if kind == "entrance" {
                // Band 0 faces north with its south side on the outline.
                let c = (t + t1) / 2.0;
                let y0 = f.band.rect.min.y;
                self.openings.push(Opening {
                    a: Vec2::new(c - 0.9, y0),
                    b: Vec2::new(c + 0.9, y0),
                    zones: [Some(zi), None],
                });
                start = Some(Pose::new(c, y0 + 1.2, std::f64::consts::FRAC_PI_2));
            }
            prev = Some((zi, kind));
            t = t1;
        }
        start
    }
}

/// The spans (along the band) of the doors to the corridor of a room of `kind` from `t` to
/// `t1`.
fn corridor_doors(p: &Params, kind: &str, t: f64, t1: f64, door_mode: u32) -> Vec<(f64, f64)> {
    let width = t1 - t;
    // Doors to the corridor: halls and long rooms get two.
    let dw = match kind {
        "hall" | "entrance" => 1.5,
        _ => p.door_m,
    }
    .min(width - 0.8)
    .max(0.8);
    let margin = 0.5_f64.min((width - dw) / 2.0);
    if kind == "entrance" {
        let c = (t + t1) / 2.0;
        vec![(c - 0.75, c + 0.75)]
    } else if width >= 12.0 {
        vec![(t + 1.0, t + 1.0 + dw), (t1 - 1.0 - dw, t1 - 1.0)]
    } else {
        match door_mode {
            0 => vec![(t + margin, t + margin + dw)],
            1 => vec![(t1 - margin - dw, t1 - margin)],
            _ => {
                let c = (t + t1) / 2.0;
                vec![(c - dw / 2.0, c + dw / 2.0)]
            }
        }
    }
}

/// Adds the skeleton's extra rooms, each opening into a neighbouring room (those too small or
/// without one are left out).
fn extra_rooms(p: &Params, sk: &Skeleton, zones: &mut Vec<Zone>, openings: &mut Vec<Opening>) {
    // Extra rooms open into a neighbouring room.
    for r in &sk.extra_rooms {
        if r.width_m() < MIN_ROOM_M || r.height_m() < MIN_ROOM_M {
            continue;
        }
        let zi = zones.len();
        let neighbour = zones.iter().enumerate().find_map(|(j, z)| {
            let (a, b) = shared_edge(r, &z.rect)?;
            ((b - a).norm() >= 2.0).then_some((j, a, b))
        });
        let Some((j, a, b)) = neighbour else { continue };
        zones.push(Zone {
            rect: *r,
            kind: if p.kind == BuildingKind::School {
                "storage"
            } else {
                "office"
            },
        });
        let u = (b - a).normalize();
        let len = (b - a).norm();
        openings.push(Opening {
            a: a + u * (len / 2.0 - 0.45),
            b: a + u * (len / 2.0 + 0.45),
            zones: [Some(zi), Some(j)],
        });
    }
}

/// Whether `p` lies on the boundary of `r`.
fn on_boundary(r: &Aabb, p: Vec2) -> bool {
    let inside_x = p.x >= r.min.x - EPS && p.x <= r.max.x + EPS;
    let inside_y = p.y >= r.min.y - EPS && p.y <= r.max.y + EPS;
    ((p.x - r.min.x).abs() < EPS || (p.x - r.max.x).abs() < EPS) && inside_y
        || ((p.y - r.min.y).abs() < EPS || (p.y - r.max.y).abs() < EPS) && inside_x
}

/// The edge two touching rectangles share, if it has positive length.
pub(super) fn shared_edge(a: &Aabb, b: &Aabb) -> Option<(Vec2, Vec2)> {
    for (x, ok) in [
        (a.max.x, (a.max.x - b.min.x).abs() < EPS),
        (a.min.x, (a.min.x - b.max.x).abs() < EPS),
    ] {
        if ok {
            let y0 = a.min.y.max(b.min.y);
            let y1 = a.max.y.min(b.max.y);
            if y1 - y0 > EPS {
                return Some((Vec2::new(x, y0), Vec2::new(x, y1)));
            }
        }
    }
    for (y, ok) in [
        (a.max.y, (a.max.y - b.min.y).abs() < EPS),
        (a.min.y, (a.min.y - b.max.y).abs() < EPS),
    ] {
        if ok {
            let x0 = a.min.x.max(b.min.x);
            let x1 = a.max.x.min(b.max.x);
            if x1 - x0 > EPS {
                return Some((Vec2::new(x0, y), Vec2::new(x1, y)));
            }
        }
    }
    None
}
