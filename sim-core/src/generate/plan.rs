//! The corridor skeleton: corridor rectangles and the bands of rooms along them, per shape.

use rand::Rng;

use super::{rect, BuildingKind};
use crate::geom::Aabb;

/// Dimensions drawn once per building; repeated across its rooms.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Params {
    pub kind: BuildingKind,
    pub corridor_m: f64,
    /// Depth of the rooms on the south (and west) side of the main corridor.
    pub depth_south_m: f64,
    /// Depth of the rooms on the north (and east) side.
    pub depth_north_m: f64,
    /// Depth of each of the back-to-back rooms between two corridors of a ring.
    pub depth_inner_m: f64,
    /// The main room width, and a second, less frequent one.
    pub module_m: f64,
    pub module2_m: f64,
    pub door_m: f64,
    /// How many large halls a school may have.
    pub halls: u32,
    /// Probability that two neighbouring rooms get a door between them.
    pub connect_prob: f64,
}

impl Params {
    pub(crate) fn sample(kind: BuildingKind, rng: &mut impl Rng) -> Self {
        match kind {
            BuildingKind::School => {
                let module_m = rng.random_range(7.0..10.0);
                Self {
                    kind,
                    corridor_m: rng.random_range(2.6..3.6),
                    depth_south_m: rng.random_range(6.0..9.0),
                    depth_north_m: rng.random_range(6.0..9.0),
                    depth_inner_m: rng.random_range(6.0..8.0),
                    module_m,
                    module2_m: module_m * rng.random_range(0.7..0.85),
                    door_m: rng.random_range(1.0..1.3),
                    halls: rng.random_range(1..=3),
                    connect_prob: 0.15,
                }
            }
            BuildingKind::Office => {
                let module_m = rng.random_range(3.0..4.2);
                Self {
                    kind,
                    corridor_m: rng.random_range(1.8..2.5),
                    depth_south_m: rng.random_range(4.0..5.5),
                    depth_north_m: rng.random_range(4.0..5.5),
                    depth_inner_m: rng.random_range(3.5..5.0),
                    module_m,
                    module2_m: rng.random_range(4.4..5.2),
                    door_m: rng.random_range(0.9..1.1),
                    halls: 0,
                    connect_prob: 0.3,
                }
            }
        }
    }

    /// Width of a double-loaded wing: rooms, corridor, rooms.
    fn wing_m(&self) -> f64 {
        self.depth_south_m + self.corridor_m + self.depth_north_m
    }

    /// Free area per footprint area, roughly (walls take the rest).
    fn efficiency(&self) -> f64 {
        match self.kind {
            BuildingKind::School => 0.93,
            BuildingKind::Office => 0.88,
        }
    }
}

/// The skeleton's shape and its shape-specific proportions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Shape {
    Straight {
        entrance_hall: bool,
    },
    L {
        ratio: f64,
        entrance_hall: bool,
    },
    T {
        ratio: f64,
        stem_at: f64,
        entrance_hall: bool,
    },
    /// `corridors` parallel corridors joined at both ends (a loop for 2), back-to-back rooms
    /// between them; long rings get cross corridors.
    Ring {
        corridors: usize,
    },
}

impl Shape {
    /// How the free area grows with the skeleton length (used to size it).
    pub(crate) fn area_exponent(&self) -> f64 {
        1.0
    }
}

/// Which side of a band faces its corridor.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Facing {
    North,
    South,
    East,
    West,
}

/// A strip of rooms; its whole `facing` side borders corridors.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Band {
    pub rect: Aabb,
    pub facing: Facing,
}

#[derive(Debug, Clone, PartialEq)]
pub(super) enum Entrance {
    /// A door in the outline at the west end of corridor 0.
    CorridorEnd,
    /// An entrance hall in the middle of band 0 (whose south side is on the outline).
    Hall,
}

#[derive(Debug, Clone, PartialEq)]
pub(super) struct Skeleton {
    pub corridors: Vec<Aabb>,
    pub bands: Vec<Band>,
    /// Rooms reached through a neighbouring room (corners of a ring).
    pub extra_rooms: Vec<Aabb>,
    pub entrance: Entrance,
}

const MAX_ARM_M: f64 = 120.0;

fn ring_height_m(p: &Params, corridors: usize) -> f64 {
    let n = corridors as f64;
    p.depth_south_m + p.depth_north_m + n * p.corridor_m + (n - 1.0) * 2.0 * p.depth_inner_m
}

/// Footprint area of a shape at skeleton length `length_m`.
fn footprint_m2(p: &Params, shape: Shape, length_m: f64) -> f64 {
    let w = p.wing_m();
    match shape {
        Shape::Straight { .. } => w * length_m,
        Shape::L { ratio, .. } => w * length_m + (ratio * length_m).max(p.module_m) * w,
        Shape::T { ratio, .. } => w * length_m + (ratio * length_m).max(p.module_m) * w,
        Shape::Ring { corridors } => ring_height_m(p, corridors) * length_m,
    }
}

/// A first guess at the length giving `area_m2` of free area.
pub(super) fn initial_length_m(p: &Params, shape: Shape, area_m2: f64) -> f64 {
    let per_m = footprint_m2(p, shape, 100.0) / 100.0 * p.efficiency();
    (area_m2 / per_m).max(min_length_m(p, shape))
}

/// The shortest skeleton for which every band still holds a room.
pub(super) fn min_length_m(p: &Params, shape: Shape) -> f64 {
    let w = p.wing_m();
    match shape {
        Shape::Straight { .. } => p.module2_m.min(p.module_m),
        Shape::L { .. } => w + p.module_m,
        Shape::T { .. } => w + 2.0 * p.module_m,
        Shape::Ring { .. } => 2.0 * p.depth_south_m + 2.0 * p.corridor_m + 2.0 * p.module_m,
    }
}

/// Picks a skeleton among those that fit `area_m2` with arms of sensible length.
pub(super) fn choose_shape(p: &Params, area_m2: f64, rng: &mut impl Rng) -> Shape {
    let entrance_hall = rng.random_bool(0.5);
    let ratio = rng.random_range(0.45..0.9);
    let stem_at = rng.random_range(0.3..0.7);
    let aspect = rng.random_range(1.2..2.6);
    let pick = rng.random_range(0..4usize);
    let fits = |s: Shape| {
        let l = initial_length_m(p, s, area_m2);
        let min = min_length_m(p, s);
        let arm_ok = match s {
            Shape::Straight { .. } => l <= MAX_ARM_M,
            Shape::Ring { corridors } => {
                let a = l / ring_height_m(p, corridors);
                (0.8..=3.5).contains(&a) && l <= MAX_ARM_M * 1.3
            }
            _ => l <= MAX_ARM_M,
        };
        l >= min * 1.05 && arm_ok
    };
    // Ring: the number of corridors whose aspect is nearest the drawn one.
    let ring = (2..=6)
        .map(|n| Shape::Ring { corridors: n })
        .filter(|s| fits(*s))
        .min_by(|a, b| {
            let d = |s: &Shape| {
                let Shape::Ring { corridors } = s else {
                    return f64::INFINITY;
                };
                (initial_length_m(p, *s, area_m2) / ring_height_m(p, *corridors) - aspect).abs()
            };
            d(a).total_cmp(&d(b))
        });
    let candidates = [
        Some(Shape::Straight { entrance_hall }).filter(|s| fits(*s)),
        Some(Shape::L {
            ratio,
            entrance_hall,
        })
        .filter(|s| fits(*s)),
        Some(Shape::T {
            ratio: ratio * 0.7,
            stem_at,
            entrance_hall,
        })
        .filter(|s| fits(*s)),
        ring,
    ];
    let feasible: Vec<Shape> = candidates.iter().flatten().copied().collect();
    if let Some(s) = candidates[pick] {
        return s;
    }
    if let Some(s) = feasible.get(pick % feasible.len().max(1)) {
        return *s;
    }
    // Nothing fits the arm limits: tiny areas get a straight wing, huge ones a tall ring.
    if area_m2 < 1000.0 {
        Shape::Straight { entrance_hall }
    } else {
        Shape::Ring { corridors: 6 }
    }
}

/// Lays out corridors and bands of a shape at skeleton length `length_m`. The building's lower
/// left corner is at the origin.
pub(super) fn skeleton(p: &Params, shape: Shape, length_m: f64) -> Skeleton {
    let c = p.corridor_m;
    let ds = p.depth_south_m;
    let dn = p.depth_north_m;
    let wing = p.wing_m();
    let lx = length_m.max(min_length_m(p, shape));
    let band = |x0, y0, x1, y1, facing| Band {
        rect: rect(x0, y0, x1, y1),
        facing,
    };
    let entrance = |hall: bool| {
        if hall {
            Entrance::Hall
        } else {
            Entrance::CorridorEnd
        }
    };
    match shape {
        Shape::Straight { entrance_hall } => Skeleton {
            corridors: vec![rect(0.0, ds, lx, ds + c)],
            bands: vec![
                band(0.0, 0.0, lx, ds, Facing::North),
                band(0.0, ds + c, lx, wing, Facing::South),
            ],
            extra_rooms: vec![],
            entrance: entrance(entrance_hall),
        },
        Shape::L {
            ratio,
            entrance_hall,
        } => {
            // Vertical wing on the west end going north: west rooms (depth ds), corridor,
            // east rooms (depth dn).
            let ly = wing + (ratio * lx).max(p.module_m);
            let xc = ds;
            Skeleton {
                corridors: vec![rect(0.0, ds, lx, ds + c), rect(xc, ds + c, xc + c, ly)],
                bands: vec![
                    band(0.0, 0.0, lx, ds, Facing::North),
                    band(xc + c, ds + c, lx, wing, Facing::South),
                    band(0.0, ds + c, xc, ly, Facing::East),
                    band(xc + c, wing, xc + c + dn, ly, Facing::West),
                ],
                extra_rooms: vec![],
                entrance: entrance(entrance_hall),
            }
        }
        Shape::T {
            ratio,
            stem_at,
            entrance_hall,
        } => {
            let ly = wing + (ratio * lx).max(p.module_m);
            let lo = dn + p.module_m;
            let hi = lx - c - dn - p.module_m;
            let xv = (stem_at * lx).clamp(lo, hi.max(lo));
            Skeleton {
                corridors: vec![rect(0.0, ds, lx, ds + c), rect(xv, ds + c, xv + c, ly)],
                bands: vec![
                    band(0.0, 0.0, lx, ds, Facing::North),
                    band(0.0, ds + c, xv - dn, wing, Facing::South),
                    band(xv + c + dn, ds + c, lx, wing, Facing::South),
                    band(xv - dn, ds + c, xv, ly, Facing::East),
                    band(xv + c, ds + c, xv + c + dn, ly, Facing::West),
                ],
                extra_rooms: vec![],
                entrance: entrance(entrance_hall),
            }
        }
        Shape::Ring { corridors } => ring(p, corridors.max(2), lx),
    }
}

fn ring(p: &Params, n: usize, x: f64) -> Skeleton {
    let c = p.corridor_m;
    let ds = p.depth_south_m;
    let dn = p.depth_north_m;
    let di = p.depth_inner_m;
    let dw = ds;
    let de = ds;
    let ys: Vec<f64> = (0..n).map(|k| ds + k as f64 * (c + 2.0 * di)).collect();
    let ytop = ys[n - 1] + c;
    let y = ytop + dn;
    // Cross corridors split long inner blocks (x positions of their west sides).
    let inner = (dw + c, x - de - c);
    let crosses = ((inner.1 - inner.0) / 55.0).floor().max(0.0) as usize;
    let mut xs_cross: Vec<f64> = vec![dw];
    for k in 1..=crosses {
        xs_cross.push(inner.0 + (inner.1 - inner.0) * k as f64 / (crosses + 1) as f64 - c / 2.0);
    }
    xs_cross.push(x - de - c);
    let mut corridors: Vec<Aabb> = ys.iter().map(|&yk| rect(dw, yk, x - de, yk + c)).collect();
    let mut bands = vec![
        Band {
            rect: rect(dw, 0.0, x - de, ds),
            facing: Facing::North,
        },
        Band {
            rect: rect(dw, ytop, x - de, y),
            facing: Facing::South,
        },
        Band {
            rect: rect(0.0, ds, dw, ytop),
            facing: Facing::East,
        },
        Band {
            rect: rect(x - de, ds, x, ytop),
            facing: Facing::West,
        },
    ];
    for k in 0..n - 1 {
        let (y0, y1) = (ys[k] + c, ys[k + 1]);
        for &xc in &xs_cross {
            corridors.push(rect(xc, y0, xc + c, y1));
        }
        for w in xs_cross.windows(2) {
            let (x0, x1) = (w[0] + c, w[1]);
            bands.push(Band {
                rect: rect(x0, y0, x1, y0 + di),
                facing: Facing::South,
            });
            bands.push(Band {
                rect: rect(x0, y0 + di, x1, y1),
                facing: Facing::North,
            });
        }
    }
    Skeleton {
        corridors,
        bands,
        extra_rooms: vec![
            rect(0.0, 0.0, dw, ds),
            rect(x - de, 0.0, x, ds),
            rect(0.0, ytop, dw, y),
            rect(x - de, ytop, x, y),
        ],
        entrance: Entrance::Hall,
    }
}
