//! Furniture and pillars: small solid rectangles inside rooms.
//!
//! An item either stands against a wall (flush, so no pocket opens behind it) or keeps 0.7 m from
//! walls and other items; none comes near a door or the start, and items cover at most 4 % of a
//! room, so free space stays connected and every room stays reachable.

use rand::Rng;

use super::{interior, Layout, Opening};
use crate::geom::{Aabb, Polygon, Vec2};

const GAP_M: f64 = 0.7;
const DOOR_KEEP_OUT_M: f64 = 1.8;
const MAX_COVER: f64 = 0.04;

fn overlaps(a: &Aabb, b: &Aabb, margin: f64) -> bool {
    a.min.x < b.max.x + margin
        && b.min.x < a.max.x + margin
        && a.min.y < b.max.y + margin
        && b.min.y < a.max.y + margin
}

/// Keep-out box in front of (both sides of) a door.
fn door_keep_out(o: &Opening) -> Aabb {
    let mut b = Aabb::empty();
    b.grow(o.a);
    b.grow(o.b);
    let horizontal = (o.a.y - o.b.y).abs() < 1e-9;
    let (ex, ey) = if horizontal {
        (0.4, DOOR_KEEP_OUT_M)
    } else {
        (DOOR_KEEP_OUT_M, 0.4)
    };
    Aabb {
        min: b.min - Vec2::new(ex, ey),
        max: b.max + Vec2::new(ex, ey),
    }
}

pub(super) fn place_clutter(layout: &Layout, rng: &mut impl Rng) -> Vec<Polygon> {
    let mut keep_out: Vec<Aabb> = layout.openings.iter().map(door_keep_out).collect();
    let s = layout.start.position();
    keep_out.push(Aabb {
        min: s - Vec2::new(1.0, 1.0),
        max: s + Vec2::new(1.0, 1.0),
    });
    let mut out = Vec::new();
    for z in &layout.zones {
        let room = interior(&z.rect);
        let area = room.width_m() * room.height_m();
        if room.width_m() < 2.0 || room.height_m() < 2.0 {
            continue;
        }
        let pillars = z.kind == "hall" || z.kind == "corridor";
        let (attempts, max_side) = match z.kind {
            "corridor" => ((area / 60.0) as usize, 0.4),
            "toilet" | "storage" => (2, 0.8),
            _ => ((area / 8.0) as usize + 2, 1.6),
        };
        let mut placed: Vec<Aabb> = Vec::new();
        let mut covered = 0.0;
        for _ in 0..attempts {
            let (w, h) = if pillars {
                (0.4, 0.4)
            } else {
                (
                    rng.random_range(0.4..max_side),
                    rng.random_range(0.4..max_side),
                )
            };
            if covered + w * h > MAX_COVER * area
                || w + 2.0 * GAP_M > room.width_m()
                || h + 2.0 * GAP_M > room.height_m()
            {
                continue;
            }
            let against_wall = !pillars && rng.random_bool(0.6);
            let mut x = rng.random_range(room.min.x + GAP_M..room.max.x - GAP_M - w);
            let mut y = rng.random_range(room.min.y + GAP_M..room.max.y - GAP_M - h);
            if against_wall {
                match rng.random_range(0..4u32) {
                    0 => x = room.min.x,
                    1 => x = room.max.x - w,
                    2 => y = room.min.y,
                    _ => y = room.max.y - h,
                }
                // Close to a perpendicular wall: into the corner, no pocket.
                if x - room.min.x < GAP_M {
                    x = room.min.x;
                }
                if room.max.x - (x + w) < GAP_M {
                    x = room.max.x - w;
                }
                if y - room.min.y < GAP_M {
                    y = room.min.y;
                }
                if room.max.y - (y + h) < GAP_M {
                    y = room.max.y - h;
                }
            }
            let item = Aabb {
                min: Vec2::new(x, y),
                max: Vec2::new(x + w, y + h),
            };
            if keep_out.iter().any(|k| overlaps(k, &item, 0.0))
                || placed.iter().any(|p| overlaps(p, &item, GAP_M))
            {
                continue;
            }
            covered += w * h;
            placed.push(item);
            out.push(Polygon::rect(item.min, item.max));
        }
    }
    out
}
