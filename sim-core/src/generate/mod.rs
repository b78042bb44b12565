//! Procedural buildings: schools and offices with the regularities the layout method exploits.
//!
//! A building is planned on axis-aligned rectangles (*zones*): corridors forming a skeleton
//! (straight, L, T or a ring with cross corridors) and rooms lined up on both sides of them in
//! *bands*, sliced into rooms of a few repeated widths. Walls (0.2 m) lie on every boundary
//! between two zones, so neighbouring rooms share them; doors are gaps in those walls. The plan
//! is sized to the requested free area, optionally cluttered, then rotated.
//!
//! Pure: the same [`GenerateConfig`] gives the same [`Building`], bit for bit.

mod clutter;
mod plan;
mod rooms;
mod walls;

#[cfg(test)]
mod tests;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::building::{Building, Door, Geometry, Room};
use crate::geom::{Aabb, Polygon, Pose, Vec2};

/// Wall thickness in metres.
pub const WALL_THICKNESS_M: f64 = 0.2;

/// What kind of building to generate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BuildingKind {
    /// Big classrooms (6-9 m deep, 7-10 m wide), wide corridors, a few large halls.
    School,
    /// Small offices (3-5 m wide), narrower corridors, meeting rooms.
    Office,
}

/// Everything that determines a generated building.
#[derive(Debug, Clone, PartialEq)]
pub struct GenerateConfig {
    pub seed: u64,
    /// Target free area; the result is within 15 % of it for 300-5000 m2.
    pub area_m2: f64,
    pub kind: BuildingKind,
    /// Furniture and pillars inside rooms (never blocking doors or disconnecting free space).
    pub clutter: bool,
    /// Rotation of the whole building about the centre of its bounding box.
    pub rotation_rad: f64,
    pub name: String,
}

impl Default for GenerateConfig {
    fn default() -> Self {
        Self {
            seed: 0,
            area_m2: 2000.0,
            kind: BuildingKind::School,
            clutter: false,
            rotation_rad: 0.0,
            name: "generated".into(),
        }
    }
}

/// An axis-aligned piece of the plan: a corridor or a room, measured between wall centre lines.
#[derive(Debug, Clone, PartialEq)]
struct Zone {
    rect: Aabb,
    kind: &'static str,
}

impl Zone {
    fn is_corridor(&self) -> bool {
        self.kind == "corridor"
    }
}

/// A gap in a wall, on the wall's centre line, between two zones (`None`: outside).
#[derive(Debug, Clone, PartialEq)]
struct Opening {
    a: Vec2,
    b: Vec2,
    zones: [Option<usize>; 2],
}

/// The finished axis-aligned plan, before walls and rotation.
#[derive(Debug, Clone, PartialEq)]
struct Layout {
    zones: Vec<Zone>,
    openings: Vec<Opening>,
    start: Pose,
}

/// Generates a building. Deterministic in `config`; takes a few milliseconds.
pub fn generate(config: &GenerateConfig) -> Building {
    let salt = match config.kind {
        BuildingKind::School => 0x5c4_001,
        BuildingKind::Office => 0x0ff_1ce,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed ^ salt);
    let area_m2 = if config.area_m2.is_finite() {
        config.area_m2.clamp(100.0, 50_000.0)
    } else {
        2000.0
    };
    let params = plan::Params::sample(config.kind, &mut rng);
    let shape = plan::choose_shape(&params, area_m2, &mut rng);
    let layout = size_layout(&params, shape, area_m2, &rng);
    let mut rng = ChaCha8Rng::seed_from_u64(rng.random::<u64>());
    let (outline, mut solids) = walls::build_walls(&layout);
    if config.clutter {
        solids.extend(clutter::place_clutter(&layout, &mut rng));
    }
    assemble(config, &layout, outline, solids)
}

/// Finds the skeleton length whose layout has about `area_m2` of free area.
fn size_layout(
    params: &plan::Params,
    shape: plan::Shape,
    area_m2: f64,
    rng: &ChaCha8Rng,
) -> Layout {
    let mut length_m = plan::initial_length_m(params, shape, area_m2);
    let mut best: Option<(f64, Layout)> = None;
    for _ in 0..6 {
        // Same random stream for every trial: only the length changes.
        let mut trial_rng = rng.clone();
        let skeleton = plan::skeleton(params, shape, length_m);
        let layout = rooms::fill(params, &skeleton, &mut trial_rng);
        let est = estimated_free_area_m2(&layout);
        let err = (est / area_m2 - 1.0).abs();
        if best.as_ref().is_none_or(|(e, _)| err < *e) {
            best = Some((err, layout));
        }
        if err < 0.02 || est <= 0.0 {
            break;
        }
        length_m = (length_m * (area_m2 / est).powf(shape.area_exponent()))
            .max(plan::min_length_m(params, shape));
    }
    best.map(|(_, l)| l).expect("at least one trial")
}

/// Free area of a plan: every zone loses half a wall on each side; doors add a little back.
fn estimated_free_area_m2(layout: &Layout) -> f64 {
    let t = WALL_THICKNESS_M;
    layout
        .zones
        .iter()
        .map(|z| (z.rect.width_m() - t).max(0.0) * (z.rect.height_m() - t).max(0.0))
        .sum()
}

/// A zone's free interior: its rectangle shrunk by half a wall.
fn interior(rect: &Aabb) -> Aabb {
    let h = WALL_THICKNESS_M / 2.0;
    Aabb {
        min: rect.min + Vec2::new(h, h),
        max: rect.max - Vec2::new(h, h),
    }
}

fn assemble(
    config: &GenerateConfig,
    layout: &Layout,
    outline: Polygon,
    solids: Vec<Polygon>,
) -> Building {
    let bb = outline.aabb();
    let centre = (bb.min + bb.max) / 2.0;
    let (s, c) = config.rotation_rad.sin_cos();
    let rot = |p: Vec2| {
        let d = p - centre;
        centre + Vec2::new(c * d.x - s * d.y, s * d.x + c * d.y)
    };
    let rot_poly = |p: &Polygon| Polygon::new(p.vertices.iter().map(|v| rot(*v)).collect());
    let rooms = layout
        .zones
        .iter()
        .enumerate()
        .map(|(i, z)| {
            let r = interior(&z.rect);
            Room {
                id: i as u32 + 1,
                kind: z.kind.to_string(),
                polygon: rot_poly(&Polygon::rect(r.min, r.max)),
            }
        })
        .collect();
    let doors = layout
        .openings
        .iter()
        .map(|o| Door {
            a: rot(o.a),
            b: rot(o.b),
            rooms: o.zones.map(|z| z.map(|i| i as u32 + 1)),
        })
        .collect();
    let p = rot(layout.start.position());
    let start = Pose::new(
        p.x,
        p.y,
        crate::geom::wrap_angle(layout.start.theta_rad + config.rotation_rad),
    );
    Building {
        name: config.name.clone(),
        geometry: Geometry::Vector {
            outline: rot_poly(&outline),
            solids: solids.iter().map(rot_poly).collect(),
        },
        rooms,
        doors,
        start: Some(start),
    }
}

/// Shorthand for an axis-aligned box.
fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Aabb {
    Aabb {
        min: Vec2::new(x0.min(x1), y0.min(y1)),
        max: Vec2::new(x0.max(x1), y0.max(y1)),
    }
}
