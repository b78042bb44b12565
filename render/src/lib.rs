//! Figures of buildings, occupancy maps, trajectories and layouts, drawn in world coordinates
//! (metres, y up) and written as SVG or PNG (image y down: the figure flips).
//!
//! A [`Figure`] is plain data: a list of items in drawing order. [`Figure::to_svg`] writes vector
//! items as SVG elements and rasters (maps) as embedded base64 PNG images, so large maps stay
//! small; [`Figure::to_png`] rasterises everything with tiny-skia and draws labels anti-aliased
//! in DejaVu Sans (embedded; SVGs ask for it by name, falling back to any sans-serif face). This crate does no simulation; files are written only by [`Figure::save`].

mod building;
pub mod chart;
mod png;
mod svg;

use std::path::{Path, PathBuf};

use sim_core::{Aabb, Bitmap, Occupancy, OccupancyGrid, Polygon, Pose, Segment, Vec2};

pub use building::{building_figure, room_color};

/// Largest PNG side in pixels; [`Figure::new`] lowers the scale to stay under it.
pub const MAX_SIDE_PX: u32 = 4000;

/// An sRGB colour with straight (not premultiplied) alpha.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Color {
    pub r: u8,
    pub g: u8,
    pub b: u8,
    pub a: u8,
}

impl Color {
    pub const WHITE: Color = Color::rgb(255, 255, 255);
    pub const BLACK: Color = Color::rgb(0, 0, 0);
    pub const GREY: Color = Color::rgb(160, 160, 160);
    pub const DARK_GREY: Color = Color::rgb(64, 64, 64);
    pub const RED: Color = Color::rgb(220, 30, 30);
    pub const GREEN: Color = Color::rgb(20, 170, 60);
    pub const BLUE: Color = Color::rgb(30, 90, 220);

    pub const fn rgb(r: u8, g: u8, b: u8) -> Self {
        Self { r, g, b, a: 255 }
    }
    pub const fn rgba(r: u8, g: u8, b: u8, a: u8) -> Self {
        Self { r, g, b, a }
    }
    pub const fn with_alpha(self, a: u8) -> Self {
        Self { a, ..self }
    }
}

/// How a shape is drawn. Widths are in pixels; the dash pattern `(on, off)` too.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Style {
    pub stroke: Option<Color>,
    pub stroke_width_px: f64,
    pub fill: Option<Color>,
    pub dash: Option<(f64, f64)>,
}

impl Default for Style {
    fn default() -> Self {
        Self {
            stroke: Some(Color::BLACK),
            stroke_width_px: 1.0,
            fill: None,
            dash: None,
        }
    }
}

impl Style {
    /// An outline of `width_px`.
    pub fn stroke(color: Color, width_px: f64) -> Self {
        Self {
            stroke: Some(color),
            stroke_width_px: width_px,
            fill: None,
            dash: None,
        }
    }
    /// A filled shape without outline.
    pub fn fill(color: Color) -> Self {
        Self {
            stroke: None,
            stroke_width_px: 0.0,
            fill: Some(color),
            dash: None,
        }
    }
    pub fn with_fill(self, color: Color) -> Self {
        Self {
            fill: Some(color),
            ..self
        }
    }
    pub fn dashed(self, on_px: f64, off_px: f64) -> Self {
        Self {
            dash: Some((on_px, off_px)),
            ..self
        }
    }
}

/// A raster placed in the world: `width` x `height` straight-alpha RGBA pixels, top row first,
/// covering `bounds`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Raster {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    pub bounds: Aabb,
}

/// One thing drawn, in world coordinates.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Item {
    Raster(Raster),
    /// A polygon (`closed`) or a polyline.
    Path {
        points: Vec<Vec2>,
        closed: bool,
        style: Style,
    },
    Circle {
        center: Vec2,
        radius_m: f64,
        style: Style,
    },
    /// Text on `pos`: vertically centred, horizontally as `anchor` says.
    Text {
        pos: Vec2,
        size_px: f64,
        color: Color,
        text: String,
        anchor: Anchor,
    },
}

/// Which point of a text its position gives, horizontally.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Anchor {
    /// The left end (text runs right from the position).
    Start,
    #[default]
    Middle,
    /// The right end.
    End,
}

/// A figure: a world-space window, a scale, and items drawn in order.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    bounds: Aabb,
    px_per_m: f64,
    width_px: u32,
    height_px: u32,
    background: Color,
    /// The printed width in inches (SVG and PDF sizes), `None`: its pixels at 96 per inch.
    print_width_in: Option<f64>,
    pub(crate) items: Vec<Item>,
}

/// Errors of saving a figure; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("{path}: cannot write figure: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: unknown figure format (use .svg, .png or .pdf)")]
    UnknownFormat { path: PathBuf },
    #[error("cannot convert the figure to PDF: {0}")]
    Pdf(String),
}

impl Figure {
    /// A figure showing `bounds` at `px_per_m`, lowered if needed so that no side exceeds
    /// [`MAX_SIDE_PX`]. An empty or degenerate `bounds` gives a 1 m square at the origin.
    pub fn new(bounds: Aabb, px_per_m: f64) -> Self {
        let bounds = if bounds.is_empty() || !bounds.min.x.is_finite() || !bounds.max.x.is_finite()
        {
            Aabb {
                min: Vec2::zeros(),
                max: Vec2::new(1.0, 1.0),
            }
        } else {
            bounds
        };
        let side_m = bounds.width_m().max(bounds.height_m()).max(1e-3);
        let mut px_per_m = if px_per_m.is_finite() && px_per_m > 0.0 {
            px_per_m
        } else {
            10.0
        };
        px_per_m = px_per_m.min(MAX_SIDE_PX as f64 / side_m);
        let side = |m: f64| ((m * px_per_m).ceil() as u32).clamp(1, MAX_SIDE_PX);
        Self {
            bounds,
            px_per_m,
            width_px: side(bounds.width_m()),
            height_px: side(bounds.height_m()),
            background: Color::WHITE,
            print_width_in: None,
            items: Vec::new(),
        }
    }

    pub fn bounds(&self) -> Aabb {
        self.bounds
    }
    /// The scale actually used (after clamping).
    pub fn px_per_m(&self) -> f64 {
        self.px_per_m
    }
    pub fn size_px(&self) -> (u32, u32) {
        (self.width_px, self.height_px)
    }
    pub fn background(&mut self, color: Color) -> &mut Self {
        self.background = color;
        self
    }

    /// Image pixel coordinates (y down) of a world point.
    pub fn px_from_world(&self, p: Vec2) -> (f64, f64) {
        (
            (p.x - self.bounds.min.x) * self.px_per_m,
            (self.bounds.max.y - p.y) * self.px_per_m,
        )
    }

    /// An occupancy map: free white, occupied black, unknown grey.
    pub fn grid(&mut self, grid: &OccupancyGrid) -> &mut Self {
        self.raster_of(grid.frame, |i| match grid.data[i] {
            Occupancy::Free => Color::WHITE,
            Occupancy::Occupied => Color::BLACK,
            Occupancy::Unknown => Color::GREY,
        })
    }

    /// A mask: `true` cells in `color`, `false` cells transparent.
    pub fn bitmap(&mut self, mask: &Bitmap, color: Color) -> &mut Self {
        self.raster_of(mask.frame, |i| {
            if mask.data[i] {
                color
            } else {
                Color::rgba(0, 0, 0, 0)
            }
        })
    }

    fn raster_of(
        &mut self,
        frame: sim_core::GridFrame,
        color: impl Fn(usize) -> Color,
    ) -> &mut Self {
        let (w, h) = (frame.width, frame.height);
        if w == 0 || h == 0 {
            return self;
        }
        let mut rgba = Vec::with_capacity(w as usize * h as usize * 4);
        // Grid row 0 is at the bottom; image row 0 at the top.
        for y in (0..h as usize).rev() {
            for x in 0..w as usize {
                let c = color(y * w as usize + x);
                rgba.extend_from_slice(&[c.r, c.g, c.b, c.a]);
            }
        }
        self.items.push(Item::Raster(Raster {
            width: w,
            height: h,
            rgba,
            bounds: frame.bounds(),
        }));
        self
    }

    pub fn polygon(&mut self, polygon: &Polygon, style: &Style) -> &mut Self {
        if polygon.vertices.len() >= 2 {
            self.items.push(Item::Path {
                points: polygon.vertices.clone(),
                closed: true,
                style: *style,
            });
        }
        self
    }

    pub fn polyline(&mut self, points: &[Vec2], style: &Style) -> &mut Self {
        if points.len() >= 2 {
            self.items.push(Item::Path {
                points: points.to_vec(),
                closed: false,
                style: *style,
            });
        }
        self
    }

    pub fn segment(&mut self, segment: &Segment, style: &Style) -> &mut Self {
        self.polyline(&[segment.a, segment.b], style)
    }

    pub fn circle(&mut self, center: Vec2, radius_m: f64, style: &Style) -> &mut Self {
        self.items.push(Item::Circle {
            center,
            radius_m,
            style: *style,
        });
        self
    }

    /// An arrow from the pose's position along its heading, `len_m` long; the head is filled
    /// with the stroke colour.
    pub fn arrow(&mut self, pose: &Pose, len_m: f64, style: &Style) -> &mut Self {
        let p = pose.position();
        let u = Vec2::new(pose.theta_rad.cos(), pose.theta_rad.sin());
        let n = Vec2::new(-u.y, u.x);
        let tip = p + u * len_m;
        let head = len_m * 0.35;
        let base = tip - u * head;
        self.polyline(&[p, base], style);
        let color = style.stroke.or(style.fill).unwrap_or(Color::BLACK);
        self.items.push(Item::Path {
            points: vec![tip, base + n * head * 0.6, base - n * head * 0.6],
            closed: true,
            style: Style::fill(color),
        });
        self
    }

    /// Text centred on `pos`, `size_px` high (em).
    pub fn text(&mut self, pos: Vec2, size_px: f64, color: Color, text: &str) -> &mut Self {
        self.text_anchored(pos, size_px, color, text, Anchor::Middle)
    }

    /// Text vertically centred on `pos`, its start, middle or end there.
    pub fn text_anchored(
        &mut self,
        pos: Vec2,
        size_px: f64,
        color: Color,
        text: &str,
        anchor: Anchor,
    ) -> &mut Self {
        self.items.push(Item::Text {
            pos,
            size_px,
            color,
            text: text.to_string(),
            anchor,
        });
        self
    }

    pub fn to_svg(&self) -> String {
        svg::render(self)
    }

    /// Sets the width the figure is printed at (inches): its SVG and PDF say so, its height in
    /// proportion; pixels and PNGs are unchanged.
    pub fn set_print_width_in(&mut self, width_in: f64) -> &mut Self {
        self.print_width_in = (width_in.is_finite() && width_in > 0.0).then_some(width_in);
        self
    }

    /// The printed size in inches, if set.
    pub fn print_size_in(&self) -> Option<(f64, f64)> {
        let w = self.print_width_in?;
        Some((w, w * self.height_px as f64 / self.width_px as f64))
    }

    /// The figure as a PDF document of one page its size (vector shapes, text in the embedded
    /// DejaVu Sans), converted from its SVG by `svg2pdf`.
    pub fn to_pdf(&self) -> Result<Vec<u8>, RenderError> {
        let mut options = svg2pdf::usvg::Options::default();
        options
            .fontdb_mut()
            .load_font_data(dejavu::sans::regular().to_vec());
        options.font_family = "DejaVu Sans".into();
        let tree = svg2pdf::usvg::Tree::from_str(&self.to_svg(), &options)
            .map_err(|e| RenderError::Pdf(e.to_string()))?;
        svg2pdf::to_pdf(
            &tree,
            svg2pdf::ConversionOptions::default(),
            // usvg reads the SVG's inches as 96 pixels each: so many per inch of the page.
            svg2pdf::PageOptions { dpi: 96.0 },
        )
        .map_err(|e| RenderError::Pdf(e.to_string()))
    }

    /// The figure as PNG bytes.
    pub fn to_png(&self) -> Vec<u8> {
        png::encode(&png::rasterise(self))
    }

    /// Writes the figure as SVG, PNG or PDF, chosen by the extension of `path`.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), RenderError> {
        let path = path.as_ref();
        let bytes = self.encode_for(path)?;
        std::fs::write(path, bytes).map_err(|source| RenderError::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    /// The figure's bytes as SVG, PNG or PDF, chosen by the extension of `path` (what
    /// [`Figure::save`] writes there).
    pub fn encode_for(&self, path: impl AsRef<Path>) -> Result<Vec<u8>, RenderError> {
        let path = path.as_ref();
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        let bytes = match ext.as_deref() {
            Some("svg") => self.to_svg().into_bytes(),
            Some("png") => self.to_png(),
            Some("pdf") => self.to_pdf()?,
            _ => {
                return Err(RenderError::UnknownFormat {
                    path: path.to_path_buf(),
                })
            }
        };
        Ok(bytes)
    }

    pub(crate) fn background_color(&self) -> Color {
        self.background
    }
}

#[cfg(test)]
mod tests;
