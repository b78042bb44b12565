//! The standard figure of a building with its ground truth.

use sim_core::{Building, Geometry, Polygon, Vec2};

use crate::{Color, Figure, Style};

/// Default scale of building figures.
const PX_PER_M: f64 = 12.0;

/// A light colour for room `id`: hues spread by the golden ratio, deterministic.
pub fn room_color(id: u32) -> Color {
    let hue = (id as f64 * 0.618_033_988_75).fract() * 6.0;
    let (s, l) = (0.55, 0.84);
    let c = (1.0 - (2.0 * l - 1.0f64).abs()) * s;
    let x = c * (1.0 - (hue % 2.0 - 1.0).abs());
    let (r, g, b) = match hue as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = l - c / 2.0;
    let u = |v: f64| ((v + m) * 255.0).round().clamp(0.0, 255.0) as u8;
    Color::rgb(u(r), u(g), u(b))
}

/// The area-weighted centroid of a polygon (its vertex mean if degenerate).
fn centroid(p: &Polygon) -> Vec2 {
    let n = p.vertices.len();
    let a = p.signed_area_m2();
    if n == 0 {
        return Vec2::zeros();
    }
    if a.abs() < 1e-9 {
        return p.vertices.iter().sum::<Vec2>() / n as f64;
    }
    let mut c = Vec2::zeros();
    for i in 0..n {
        let (v, w) = (p.vertices[i], p.vertices[(i + 1) % n]);
        c += (v + w) * (v.x * w.y - w.x * v.y);
    }
    c / (6.0 * a)
}

/// Free space white, solids dark grey, ground-truth rooms in light colours labelled with their
/// ids, doors green, the start a red arrow. One metre of margin around the building.
pub fn building_figure(b: &Building) -> Figure {
    let mut bounds = b.bounds();
    if !bounds.is_empty() {
        bounds.min -= Vec2::new(1.0, 1.0);
        bounds.max += Vec2::new(1.0, 1.0);
    }
    let mut fig = Figure::new(bounds, PX_PER_M);
    let solid = Style::fill(Color::DARK_GREY);
    match &b.geometry {
        Geometry::Vector { outline, .. } => {
            fig.background(Color::DARK_GREY);
            fig.polygon(outline, &Style::fill(Color::WHITE));
        }
        Geometry::Raster { solid } => {
            fig.background(Color::WHITE);
            fig.bitmap(solid, Color::DARK_GREY);
        }
    }
    for r in &b.rooms {
        fig.polygon(&r.polygon, &Style::fill(room_color(r.id)));
    }
    if let Geometry::Vector { solids, .. } = &b.geometry {
        for s in solids {
            fig.polygon(s, &solid);
        }
    }
    let scale = fig.px_per_m();
    for d in &b.doors {
        fig.polyline(
            &[d.a, d.b],
            &Style::stroke(Color::GREEN, (0.25 * scale).max(2.0)),
        );
    }
    for r in &b.rooms {
        let bb = r.polygon.aabb();
        let side_px = bb.width_m().min(bb.height_m()) * scale;
        let size_px = (side_px / 2.5).clamp(8.0, 16.0);
        fig.text(
            centroid(&r.polygon),
            size_px,
            Color::BLACK,
            &r.id.to_string(),
        );
    }
    if let Some(start) = b.start {
        fig.arrow(
            &start,
            1.5,
            &Style::stroke(Color::RED, (0.2 * scale).max(2.0)),
        );
        fig.circle(start.position(), 0.25, &Style::fill(Color::RED));
    }
    fig
}
