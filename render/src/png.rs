//! PNG output: rasterisation with tiny-skia, encoding with `image`.

use tiny_skia::{
    FillRule, FilterQuality, IntSize, Paint, PathBuilder, Pixmap, PixmapPaint, Stroke, StrokeDash,
    Transform,
};

use crate::{font, Color, Figure, Item, Style};

fn paint(c: Color) -> Paint<'static> {
    let mut p = Paint::default();
    p.set_color_rgba8(c.r, c.g, c.b, c.a);
    p.anti_alias = true;
    p
}

fn draw_path(pixmap: &mut Pixmap, path: &tiny_skia::Path, style: &Style) {
    if let Some(fill) = style.fill {
        pixmap.fill_path(
            path,
            &paint(fill),
            FillRule::EvenOdd,
            Transform::identity(),
            None,
        );
    }
    if let Some(stroke) = style.stroke {
        let mut s = Stroke {
            width: style.stroke_width_px.max(0.0) as f32,
            ..Stroke::default()
        };
        if let Some((on, off)) = style.dash {
            s.dash = StrokeDash::new(vec![on as f32, off as f32], 0.0);
        }
        pixmap.stroke_path(path, &paint(stroke), &s, Transform::identity(), None);
    }
}

/// Draws the figure on a pixmap of its size.
pub(crate) fn rasterise(fig: &Figure) -> Pixmap {
    let (w, h) = fig.size_px();
    let mut pixmap = Pixmap::new(w, h).expect("figure sides are 1..=MAX_SIDE_PX");
    let bg = fig.background_color();
    pixmap.fill(tiny_skia::Color::from_rgba8(bg.r, bg.g, bg.b, bg.a));
    let px = |p: sim_core::Vec2| {
        let (x, y) = fig.px_from_world(p);
        (x as f32, y as f32)
    };
    for item in &fig.items {
        match item {
            Item::Raster(r) => {
                // tiny-skia wants premultiplied alpha.
                let data = r
                    .rgba
                    .chunks_exact(4)
                    .flat_map(|c| {
                        let a = c[3] as u16;
                        let m = |v: u8| ((v as u16 * a + 127) / 255) as u8;
                        [m(c[0]), m(c[1]), m(c[2]), c[3]]
                    })
                    .collect();
                let Some(size) = IntSize::from_wh(r.width, r.height) else {
                    continue;
                };
                let Some(src) = Pixmap::from_vec(data, size) else {
                    continue;
                };
                let (x0, y0) = px(sim_core::Vec2::new(r.bounds.min.x, r.bounds.max.y));
                let sx = (r.bounds.width_m() * fig.px_per_m()) as f32 / r.width as f32;
                let sy = (r.bounds.height_m() * fig.px_per_m()) as f32 / r.height as f32;
                let paint = PixmapPaint {
                    quality: FilterQuality::Nearest,
                    ..PixmapPaint::default()
                };
                pixmap.draw_pixmap(
                    0,
                    0,
                    src.as_ref(),
                    &paint,
                    Transform::from_row(sx, 0.0, 0.0, sy, x0, y0),
                    None,
                );
            }
            Item::Path {
                points,
                closed,
                style,
            } => {
                let mut pb = PathBuilder::new();
                let (x, y) = px(points[0]);
                pb.move_to(x, y);
                for p in &points[1..] {
                    let (x, y) = px(*p);
                    pb.line_to(x, y);
                }
                if *closed {
                    pb.close();
                }
                if let Some(path) = pb.finish() {
                    let style = if *closed {
                        *style
                    } else {
                        Style {
                            fill: None,
                            ..*style
                        }
                    };
                    draw_path(&mut pixmap, &path, &style);
                }
            }
            Item::Circle {
                center,
                radius_m,
                style,
            } => {
                let (x, y) = px(*center);
                let r = (*radius_m * fig.px_per_m()).max(0.5) as f32;
                if let Some(path) = PathBuilder::from_circle(x, y, r) {
                    draw_path(&mut pixmap, &path, style);
                }
            }
            Item::Text {
                pos,
                size_px,
                color,
                text,
            } => draw_text(&mut pixmap, px(*pos), *size_px, *color, text),
        }
    }
    pixmap
}

/// Text in the 5x7 font, centred on `(cx, cy)`, one font pixel per `size_px / 8` pixels.
fn draw_text(pixmap: &mut Pixmap, (cx, cy): (f32, f32), size_px: f64, color: Color, text: &str) {
    let scale = (size_px / 8.0).round().max(1.0) as f32;
    let n = text.chars().count() as f32;
    let width = (n * 6.0 - 1.0) * scale;
    let x0 = (cx - width / 2.0).round();
    let y0 = (cy - 3.5 * scale).round();
    let mut pb = PathBuilder::new();
    for (k, c) in text.chars().enumerate() {
        let Some(g) = font::glyph(c) else { continue };
        for (row, bits) in g.iter().enumerate() {
            for col in 0..5 {
                if bits & (0x10 >> col) != 0 {
                    let x = x0 + (k as f32 * 6.0 + col as f32) * scale;
                    let y = y0 + row as f32 * scale;
                    if let Some(r) = tiny_skia::Rect::from_xywh(x, y, scale, scale) {
                        pb.push_rect(r);
                    }
                }
            }
        }
    }
    if let Some(path) = pb.finish() {
        let mut p = paint(color);
        p.anti_alias = false;
        pixmap.fill_path(&path, &p, FillRule::Winding, Transform::identity(), None);
    }
}

/// PNG bytes of a pixmap (straight alpha).
pub(crate) fn encode(pixmap: &Pixmap) -> Vec<u8> {
    let rgba: Vec<u8> = pixmap
        .pixels()
        .iter()
        .flat_map(|p| {
            let c = p.demultiply();
            [c.red(), c.green(), c.blue(), c.alpha()]
        })
        .collect();
    encode_rgba(pixmap.width(), pixmap.height(), rgba)
}

/// PNG bytes of straight-alpha RGBA pixels, top row first.
pub(crate) fn encode_rgba(width: u32, height: u32, rgba: Vec<u8>) -> Vec<u8> {
    let mut out = Vec::new();
    let img = image::RgbaImage::from_raw(width, height, rgba).expect("buffer matches its size");
    img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .expect("PNG encoding into memory does not fail");
    out
}
