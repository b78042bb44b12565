//! SVG output: vector items as elements, rasters as embedded base64 PNG images.

use std::fmt::Write;

use base64::Engine;

use crate::{Anchor, Color, Figure, Item, Style};

fn color_attr(name: &str, c: Option<Color>) -> String {
    match c {
        None => format!(" {name}=\"none\""),
        Some(c) if c.a == 255 => format!(" {name}=\"rgb({},{},{})\"", c.r, c.g, c.b),
        Some(c) => format!(
            " {name}=\"rgb({},{},{})\" {name}-opacity=\"{:.3}\"",
            c.r,
            c.g,
            c.b,
            c.a as f64 / 255.0
        ),
    }
}

fn style_attrs(style: &Style, closed: bool) -> String {
    let mut s = color_attr("fill", if closed { style.fill } else { None });
    s += &color_attr("stroke", style.stroke);
    if style.stroke.is_some() {
        let _ = write!(
            s,
            " stroke-width=\"{:.2}\" stroke-linejoin=\"round\"",
            style.stroke_width_px
        );
        if let Some((on, off)) = style.dash {
            let _ = write!(s, " stroke-dasharray=\"{on:.2} {off:.2}\"");
        }
    }
    s
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

pub(crate) fn render(fig: &Figure) -> String {
    let (w, h) = fig.size_px();
    let mut out = String::new();
    // A figure sized for print says its size in inches; its coordinates stay pixels.
    let (width, height) = match fig.print_size_in() {
        Some((wi, hi)) => (format!("{wi:.4}in"), format!("{hi:.4}in")),
        None => (w.to_string(), h.to_string()),
    };
    let _ = writeln!(
        out,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" viewBox=\"0 0 {w} {h}\">"
    );
    let bg = fig.background_color();
    let _ = writeln!(
        out,
        "<rect x=\"0\" y=\"0\" width=\"{w}\" height=\"{h}\"{}/>",
        color_attr("fill", Some(bg))
    );
    let px = |p: sim_core::Vec2| fig.px_from_world(p);
    for item in &fig.items {
        match item {
            Item::Raster(r) => {
                let png = crate::png::encode_rgba(r.width, r.height, r.rgba.clone());
                let b64 = base64::engine::general_purpose::STANDARD.encode(png);
                let (x, y) = px(sim_core::Vec2::new(r.bounds.min.x, r.bounds.max.y));
                let _ = writeln!(
                    out,
                    "<image x=\"{x:.2}\" y=\"{y:.2}\" width=\"{:.2}\" height=\"{:.2}\" preserveAspectRatio=\"none\" style=\"image-rendering:pixelated\" href=\"data:image/png;base64,{b64}\"/>",
                    r.bounds.width_m() * fig.px_per_m(),
                    r.bounds.height_m() * fig.px_per_m()
                );
            }
            Item::Path {
                points,
                closed,
                style,
            } => {
                let pts: Vec<String> = points
                    .iter()
                    .map(|p| {
                        let (x, y) = px(*p);
                        format!("{x:.2},{y:.2}")
                    })
                    .collect();
                let tag = if *closed { "polygon" } else { "polyline" };
                let rule = if *closed {
                    " fill-rule=\"evenodd\""
                } else {
                    ""
                };
                let _ = writeln!(
                    out,
                    "<{tag} points=\"{}\"{}{rule}/>",
                    pts.join(" "),
                    style_attrs(style, *closed)
                );
            }
            Item::Circle {
                center,
                radius_m,
                style,
            } => {
                let (x, y) = px(*center);
                let _ = writeln!(
                    out,
                    "<circle cx=\"{x:.2}\" cy=\"{y:.2}\" r=\"{:.2}\"{}/>",
                    radius_m * fig.px_per_m(),
                    style_attrs(style, true)
                );
            }
            Item::Text {
                pos,
                size_px,
                color,
                text,
                anchor,
            } => {
                let (x, y) = px(*pos);
                let anchor = match anchor {
                    Anchor::Start => "start",
                    Anchor::Middle => "middle",
                    Anchor::End => "end",
                };
                let _ = writeln!(
                    out,
                    "<text x=\"{x:.2}\" y=\"{y:.2}\" font-size=\"{size_px:.1}\" font-family=\"DejaVu Sans, sans-serif\" text-anchor=\"{anchor}\" dominant-baseline=\"central\"{}>{}</text>",
                    color_attr("fill", Some(*color)),
                    escape(text)
                );
            }
        }
    }
    out.push_str("</svg>\n");
    out
}
