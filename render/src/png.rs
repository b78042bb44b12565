//! PNG output: rasterisation with tiny-skia, encoding with `image`.

use std::sync::OnceLock;

use ab_glyph::{point, Font, FontRef, PxScale, ScaleFont};
use tiny_skia::{
    FillRule, FilterQuality, IntSize, Paint, PathBuilder, Pixmap, PixmapPaint,
    PremultipliedColorU8, Stroke, StrokeDash, Transform,
};

use crate::{Anchor, Color, Figure, Item, Style};

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
                anchor,
            } => {
                let (x, y) = px(*pos);
                let w = text_width_px(text, *size_px) as f32;
                let left = match anchor {
                    Anchor::Start => x,
                    Anchor::Middle => x - w / 2.0,
                    Anchor::End => x - w,
                };
                draw_text(&mut pixmap, (left, y), *size_px, *color, text)
            }
        }
    }
    pixmap
}

/// The face of every label: DejaVu Sans, parsed once.
fn face() -> &'static FontRef<'static> {
    static FACE: OnceLock<FontRef<'static>> = OnceLock::new();
    FACE.get_or_init(|| {
        FontRef::try_from_slice(dejavu::sans::regular()).expect("the embedded DejaVu Sans parses")
    })
}

/// The glyphs of `text` at `size_px` and the pen position of each (advances and kerning),
/// then the width of the whole text, in pixels.
fn set_text(text: &str, size_px: f64) -> (Vec<(ab_glyph::GlyphId, f32)>, f32) {
    let font = face().as_scaled(PxScale::from(size_px as f32));
    let mut x = 0.0f32;
    let mut prev = None;
    let mut glyphs = Vec::with_capacity(text.len());
    for c in text.chars() {
        let id = font.glyph_id(c);
        if let Some(p) = prev {
            x += font.kern(p, id);
        }
        glyphs.push((id, x));
        x += font.h_advance(id);
        prev = Some(id);
    }
    (glyphs, x)
}

/// Width in pixels of `text` at `size_px`.
pub(crate) fn text_width_px(text: &str, size_px: f64) -> f64 {
    set_text(text, size_px).1 as f64
}

/// Anti-aliased text in DejaVu Sans, `size_px` high (em), from `x0`, vertically centred on `cy`.
fn draw_text(pixmap: &mut Pixmap, (x0, cy): (f32, f32), size_px: f64, color: Color, text: &str) {
    let scale = PxScale::from(size_px as f32);
    let font = face().as_scaled(scale);
    // The middle of the capitals and the descenders' span on `cy`.
    let baseline = cy + (font.ascent() + font.descent()) / 2.0;
    let (w, h) = (pixmap.width() as i64, pixmap.height() as i64);
    let stride = pixmap.width() as usize;
    let pixels = pixmap.pixels_mut();
    for (id, x) in set_text(text, size_px).0 {
        let glyph = id.with_scale_and_position(scale, point(x0 + x, baseline));
        let Some(outline) = face().outline_glyph(glyph) else {
            continue; // a space
        };
        let bounds = outline.px_bounds();
        outline.draw(|gx, gy, coverage| {
            let px = bounds.min.x as i64 + gx as i64;
            let py = bounds.min.y as i64 + gy as i64;
            if px < 0 || py < 0 || px >= w || py >= h {
                return;
            }
            let a = coverage.clamp(0.0, 1.0) * color.a as f32 / 255.0;
            let dst = &mut pixels[py as usize * stride + px as usize];
            // Source over, premultiplied.
            let over = |s: u8, d: u8| (s as f32 * a + d as f32 * (1.0 - a)).round() as u8;
            let blended = PremultipliedColorU8::from_rgba(
                over(color.r, dst.red()),
                over(color.g, dst.green()),
                over(color.b, dst.blue()),
                (255.0 * a + dst.alpha() as f32 * (1.0 - a)).round() as u8,
            );
            if let Some(c) = blended {
                *dst = c;
            }
        });
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
