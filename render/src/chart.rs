//! Charts of experiment results, drawn on a [`Figure`] (so they save as SVG or PNG like every
//! other figure): a line chart (explored fraction over time, one line per strategy, with a band
//! of its spread and marks where runs stopped early: the paper's Fig. 4) and an interval chart
//! (a mean with an interval per category and series, as points or as grouped bars: the paper's
//! Fig. 2).
//!
//! Data go into a plotting box whose size and margins follow the text size ([`ChartStyle`]: a
//! screen layout, or a printed width and font size for papers); axes carry round tick values.

use sim_core::{Aabb, Vec2};

use crate::{Anchor, Color, Figure, Style};

/// Width of every chart in figure units (the layout inside it is in ems of its text).
const TOTAL_W: f64 = 14.5;
/// Screen layout: figure units to pixels, and the text height in pixels.
const SCREEN_PX_PER_UNIT: f64 = 80.0;
const SCREEN_TEXT_PX: f64 = 12.0;
/// Print layout: pixels per inch of PNGs and of SVG coordinates.
const PRINT_DPI: f64 = 300.0;

/// How a chart is laid out: for a screen (the default: 1160 px wide, 12 px text, titles drawn)
/// or for print at a given width and font size, e.g. a journal column of 3.5 in with 8 pt text.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChartStyle {
    /// The figure's printed width in inches; `None`: the screen layout.
    pub width_in: Option<f64>,
    /// The text size in points (print layout; the screen layout's text is 12 px).
    pub font_pt: f64,
    /// Whether the title is drawn above the plot (papers put it in the caption).
    pub titles: bool,
}

impl Default for ChartStyle {
    fn default() -> Self {
        Self {
            width_in: None,
            font_pt: 9.0,
            titles: true,
        }
    }
}

/// Where everything of a chart goes, in figure units: the plotting box is `[0, box_w] x
/// [0, box_h]`; text and margins are sized in ems (the text's height).
#[derive(Debug, Clone, Copy)]
struct Layout {
    /// One em in figure units, and the text height in pixels.
    em: f64,
    text_px: f64,
    px_per_unit: f64,
    /// Stroke widths are multiplied by this (1 on screen).
    stroke: f64,
    left: f64,
    bottom: f64,
    top: f64,
    legend_w: f64,
    /// The legend goes below the plot (narrow figures), not right of it.
    legend_below: bool,
    legend_rows: usize,
    box_w: f64,
    box_h: f64,
    titles: bool,
    width_in: Option<f64>,
}

impl Layout {
    /// The layout for `style`, with a legend of `legend` labels, `y_ticks` the widest y tick
    /// label, and `x_rows` rows of labels under the x axis.
    fn new(style: &ChartStyle, legend: &[&str], y_ticks: &str, x_rows: usize) -> Layout {
        let (px_per_unit, text_px) = match style.width_in {
            Some(w) => (PRINT_DPI * w / TOTAL_W, style.font_pt * PRINT_DPI / 72.0),
            None => (SCREEN_PX_PER_UNIT, SCREEN_TEXT_PX),
        };
        let em = text_px / px_per_unit;
        let width = |t: &str| crate::png::text_width_px(t, text_px) / px_per_unit;
        let widest = legend.iter().map(|l| width(l)).fold(0.0, f64::max);
        // Room right of the box for the last x tick's text, at least.
        let mut legend_w = if legend.is_empty() {
            1.5 * em
        } else {
            widest + 4.0 * em
        };
        let legend_below = legend_w > 0.35 * TOTAL_W;
        let legend_rows = if legend_below { legend.len() } else { 0 };
        if legend_below {
            legend_w = 1.5 * em;
        }
        let left = width(y_ticks) + 1.6 * em;
        let bottom = (x_rows as f64 * 1.2 + 2.6 + 1.4 * legend_rows as f64) * em;
        let top = if style.titles { 3.0 * em } else { 1.8 * em };
        let box_w = (TOTAL_W - left - legend_w).max(TOTAL_W * 0.3);
        Layout {
            em,
            text_px,
            px_per_unit,
            stroke: text_px / SCREEN_TEXT_PX,
            left,
            bottom,
            top,
            legend_w,
            legend_below,
            legend_rows,
            box_w,
            box_h: box_w * 0.6,
            titles: style.titles,
            width_in: style.width_in,
        }
    }

    fn figure(&self) -> Figure {
        let bounds = Aabb {
            min: Vec2::new(-self.left, -self.bottom),
            max: Vec2::new(self.box_w + self.legend_w, self.box_h + self.top),
        };
        let mut fig = Figure::new(bounds, self.px_per_unit);
        if let Some(w) = self.width_in {
            fig.set_print_width_in(w);
        }
        fig
    }

    fn line(&self, color: Color, width: f64) -> Style {
        Style::stroke(color, width * self.stroke)
    }
}

/// Colours of successive series.
pub fn series_color(k: usize) -> Color {
    const PALETTE: [Color; 8] = [
        Color::rgb(40, 40, 40),
        Color::rgb(30, 90, 220),
        Color::rgb(220, 30, 30),
        Color::rgb(20, 150, 60),
        Color::rgb(230, 130, 0),
        Color::rgb(140, 60, 180),
        Color::rgb(0, 160, 170),
        Color::rgb(160, 110, 60),
    ];
    PALETTE[k % PALETTE.len()]
}

/// One line of a [`LineChart`].
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub label: String,
    pub color: Color,
    /// `(x, y)` in data units, in order of `x`.
    pub points: Vec<(f64, f64)>,
    /// `(x, low, high)`: a band drawn under the line (e.g. the range over seeds); may be empty.
    pub band: Vec<(f64, f64, f64)>,
    /// `(x, y)` points marked on the line (e.g. where runs stopped early); may be empty.
    pub marks: Vec<(f64, f64)>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct LineChart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// Fixed x range; `None`: from 0 to the data's end.
    pub x_range: Option<(f64, f64)>,
    /// Fixed y range; `None` fits the data.
    pub y_range: Option<(f64, f64)>,
    pub series: Vec<Series>,
    /// The legend's name for the marks (e.g. "early stop"), shown when any series has marks.
    pub marks_label: String,
}

/// One category's value of an [`IntervalChart`] series: a mean and its interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    pub mean: f64,
    pub lo: f64,
    pub hi: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct IntervalChart {
    pub title: String,
    pub y_label: String,
    pub categories: Vec<String>,
    /// Per series: its label, its colour and one optional interval per category.
    pub series: Vec<(String, Color, Vec<Option<Interval>>)>,
    /// Bars from zero to the mean, grouped by category (else a point at the mean).
    pub bars: bool,
}

/// A step between ticks of 1, 2 or 5 times a power of ten giving about `n` ticks over `span`.
fn tick_step(span: f64, n: f64) -> f64 {
    if !(span.is_finite() && span > 0.0) {
        return 1.0;
    }
    let raw = span / n;
    let p = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * p)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * p)
}

fn tick_text(v: f64, step: f64) -> String {
    // A tick at zero reached by adding steps is a rounding error away from it ("-0").
    let v = if v.abs() < 1e-9 * step { 0.0 } else { v };
    if step >= 1.0 {
        format!("{v:.0}")
    } else if step >= 0.1 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

/// The y ticks of `y`: their values and texts.
fn y_ticks(y: (f64, f64)) -> Vec<(f64, String)> {
    let (y0, y1) = y;
    let ys = tick_step(y1 - y0, 5.0);
    let mut out = Vec::new();
    let mut v = (y0 / ys).ceil() * ys;
    while v <= y1 + 1e-9 * ys && out.len() < 100 {
        out.push((v, tick_text(v, ys)));
        v += ys;
    }
    out
}

/// A chart's figure with the plotting box, its axes, ticks and labels for data ranges `x` and
/// `y`, and the legend's space. Returns the figure, its layout and the map from data to figure
/// units.
#[allow(clippy::too_many_arguments)]
fn frame(
    style: &ChartStyle,
    title: &str,
    x_label: &str,
    y_label: &str,
    x: (f64, f64),
    y: (f64, f64),
    x_ticks: bool,
    x_rows: usize,
    legend: &[&str],
) -> (Figure, Layout, impl Fn(f64, f64) -> Vec2) {
    let ticks = y_ticks(y);
    let widest = ticks
        .iter()
        .map(|(_, t)| t.as_str())
        .max_by_key(|t| t.len())
        .unwrap_or("0");
    let lay = Layout::new(style, legend, widest, x_rows);
    let mut fig = lay.figure();
    let (x0, x1) = x;
    let (y0, y1) = y;
    let (bw, bh, em, size) = (lay.box_w, lay.box_h, lay.em, lay.text_px);
    let sx = bw / (x1 - x0).max(1e-12);
    let sy = bh / (y1 - y0).max(1e-12);
    let map = move |a: f64, b: f64| Vec2::new((a - x0) * sx, (b - y0) * sy);
    let axis = lay.line(Color::BLACK, 1.5);
    let grid = lay.line(Color::rgb(225, 225, 225), 1.0);
    for (v, text) in &ticks {
        let p = map(x0, *v);
        fig.polyline(&[p, Vec2::new(bw, p.y)], &grid);
        fig.text_anchored(
            Vec2::new(-0.6 * em, p.y),
            size,
            Color::BLACK,
            text,
            Anchor::End,
        );
    }
    if x_ticks {
        let xs = tick_step(x1 - x0, 6.0);
        let mut v = (x0 / xs).ceil() * xs;
        while v <= x1 + 1e-9 * xs {
            let p = map(v, y0);
            fig.polyline(&[p, Vec2::new(p.x, bh)], &grid);
            fig.text(
                Vec2::new(p.x, -1.2 * em),
                size,
                Color::BLACK,
                &tick_text(v, xs),
            );
            v += xs;
        }
    }
    fig.polyline(
        &[Vec2::new(0.0, bh), Vec2::zeros(), Vec2::new(bw, 0.0)],
        &axis,
    );
    if lay.titles {
        fig.text(
            Vec2::new(bw / 2.0, bh + 2.0 * em),
            size * 1.2,
            Color::BLACK,
            title,
        );
    }
    let x_label_y = -(x_rows as f64 * 1.2 + 1.4) * em;
    fig.text(Vec2::new(bw / 2.0, x_label_y), size, Color::BLACK, x_label);
    fig.text_anchored(
        Vec2::new(-lay.left + 0.2 * em, bh + 0.9 * em),
        size,
        Color::BLACK,
        y_label,
        Anchor::Start,
    );
    (fig, lay, map)
}

/// The legend: right of the box, or below the x label on a narrow figure; a line of each
/// colour and its label, then, with `marks`, a mark and its name.
fn legend(fig: &mut Figure, lay: &Layout, labels: &[(&str, Color)], marks: Option<&str>) {
    let em = lay.em;
    let (x, y_of): (f64, Box<dyn Fn(usize) -> f64>) = if lay.legend_below {
        let first = -(lay.bottom - 1.4 * lay.legend_rows as f64 * em) - 0.7 * em;
        (0.0, Box::new(move |k| first - 1.4 * em * k as f64))
    } else {
        let top = lay.box_h - 0.8 * em;
        (
            lay.box_w + 0.6 * em,
            Box::new(move |k| top - 1.5 * em * k as f64),
        )
    };
    for (k, &(l, c)) in labels.iter().enumerate() {
        let y = y_of(k);
        fig.polyline(
            &[Vec2::new(x, y), Vec2::new(x + 2.2 * em, y)],
            &lay.line(c, 3.0),
        );
        fig.text_anchored(
            Vec2::new(x + 2.8 * em, y),
            lay.text_px,
            Color::BLACK,
            l,
            Anchor::Start,
        );
    }
    if let Some(name) = marks {
        let k = labels.len();
        // Below the plot, the mark's entry goes right of the last line's.
        let (mx, y) = if lay.legend_below {
            (lay.box_w * 0.6, y_of(k.saturating_sub(1)))
        } else {
            (x, y_of(k))
        };
        mark(fig, lay, Vec2::new(mx + 1.1 * em, y), Color::DARK_GREY);
        fig.text_anchored(
            Vec2::new(mx + 2.8 * em, y),
            lay.text_px,
            Color::BLACK,
            name,
            Anchor::Start,
        );
    }
}

/// A mark: a small ring.
fn mark(fig: &mut Figure, lay: &Layout, at: Vec2, color: Color) {
    fig.circle(
        at,
        0.5 * lay.em,
        &Style {
            fill: Some(Color::WHITE),
            ..lay.line(color, 2.0)
        },
    );
}

impl LineChart {
    /// The chart in the screen layout.
    pub fn figure(&self) -> Figure {
        self.figure_styled(&ChartStyle::default())
    }

    pub fn figure_styled(&self, style: &ChartStyle) -> Figure {
        let pts = self.series.iter().flat_map(|s| s.points.iter());
        let (mut x1, mut y0, mut y1) = (0.0f64, f64::INFINITY, f64::NEG_INFINITY);
        for &(x, y) in pts {
            if x.is_finite() && y.is_finite() {
                x1 = x1.max(x);
                y0 = y0.min(y);
                y1 = y1.max(y);
            }
        }
        let (y0, y1) = self.y_range.unwrap_or(if y0 <= y1 {
            (y0.min(0.0), y1.max(y0 + 1e-9))
        } else {
            (0.0, 1.0)
        });
        let (x0, x1) = self
            .x_range
            .unwrap_or((0.0, if x1 > 0.0 { x1 } else { 1.0 }));
        let marked = self.series.iter().any(|s| !s.marks.is_empty());
        let mut names: Vec<&str> = self.series.iter().map(|s| s.label.as_str()).collect();
        if marked {
            names.push(self.marks_label.as_str());
        }
        let (mut fig, lay, map) = frame(
            style,
            &self.title,
            &self.x_label,
            &self.y_label,
            (x0, x1),
            (y0, y1),
            true,
            1,
            &names,
        );
        let clamp = |y: f64| y.clamp(y0, y1);
        let inside = |x: f64| x >= x0 && x <= x1;
        // Bands first, under every line.
        for s in &self.series {
            let band: Vec<&(f64, f64, f64)> = s
                .band
                .iter()
                .filter(|(x, lo, hi)| {
                    x.is_finite() && lo.is_finite() && hi.is_finite() && inside(*x)
                })
                .collect();
            if band.len() >= 2 {
                let outline: Vec<Vec2> = band
                    .iter()
                    .map(|&&(x, lo, _)| map(x, clamp(lo)))
                    .chain(band.iter().rev().map(|&&(x, _, hi)| map(x, clamp(hi))))
                    .collect();
                let c = s.color;
                fig.polygon(
                    &sim_core::Polygon::new(outline),
                    &Style::fill(Color { a: 45, ..c }),
                );
            }
        }
        for s in &self.series {
            let line: Vec<Vec2> = s
                .points
                .iter()
                .filter(|(x, y)| x.is_finite() && y.is_finite() && inside(*x))
                .map(|&(x, y)| map(x, clamp(y)))
                .collect();
            fig.polyline(&line, &lay.line(s.color, 2.0));
        }
        for s in &self.series {
            for &(x, y) in s
                .marks
                .iter()
                .filter(|(x, y)| x.is_finite() && y.is_finite() && inside(*x))
            {
                mark(&mut fig, &lay, map(x, clamp(y)), s.color);
            }
        }
        let labels: Vec<(&str, Color)> = self
            .series
            .iter()
            .map(|s| (s.label.as_str(), s.color))
            .collect();
        legend(
            &mut fig,
            &lay,
            &labels,
            marked.then_some(self.marks_label.as_str()),
        );
        fig
    }
}

impl IntervalChart {
    /// The chart in the screen layout.
    pub fn figure(&self) -> Figure {
        self.figure_styled(&ChartStyle::default())
    }

    pub fn figure_styled(&self, style: &ChartStyle) -> Figure {
        let all = self
            .series
            .iter()
            .flat_map(|(_, _, v)| v.iter().flatten())
            .flat_map(|i| [i.lo, i.hi, i.mean])
            .filter(|v| v.is_finite());
        let (mut y0, mut y1) = (0.0f64, 0.0f64);
        for v in all {
            y0 = y0.min(v);
            y1 = y1.max(v);
        }
        let pad = 0.05 * (y1 - y0).max(1e-9);
        // Bars stand on zero: no room below it unless a value is negative.
        let below = if self.bars && y0 >= 0.0 { 0.0 } else { pad };
        let (y0, y1) = (y0 - below, y1 + pad);
        let n = self.categories.len().max(1) as f64;
        // Many categories: every other label one line lower, so that they do not overlap.
        let staggered = self.categories.len() > 6;
        let names: Vec<&str> = self.series.iter().map(|(l, _, _)| l.as_str()).collect();
        let (mut fig, lay, map) = frame(
            style,
            &self.title,
            "",
            &self.y_label,
            (0.0, n),
            (y0, y1),
            false,
            if staggered { 2 } else { 1 },
            &names,
        );
        let em = lay.em;
        // The zero line.
        fig.polyline(
            &[map(0.0, 0.0), map(n, 0.0)],
            &lay.line(Color::DARK_GREY, 1.0)
                .dashed(4.0 * lay.stroke, 3.0 * lay.stroke),
        );
        let m = self.series.len().max(1) as f64;
        for (c, name) in self.categories.iter().enumerate() {
            let p = map(c as f64 + 0.5, y0);
            let y = if staggered && c % 2 == 1 {
                -2.4 * em
            } else {
                -1.2 * em
            };
            fig.text(Vec2::new(p.x, y), lay.text_px, Color::BLACK, name);
            for (k, (_, color, values)) in self.series.iter().enumerate() {
                let Some(Some(i)) = values.get(c) else {
                    continue;
                };
                let x = c as f64 + (k as f64 + 1.0) / (m + 1.0);
                let color = *color;
                if self.bars && i.mean.is_finite() {
                    let w = 0.8 / (m + 1.0);
                    let (a, b) = (map(x - w / 2.0, 0.0), map(x + w / 2.0, i.mean));
                    fig.polygon(
                        &sim_core::Polygon::rect(
                            Vec2::new(a.x, a.y.min(b.y)),
                            Vec2::new(b.x, a.y.max(b.y)),
                        ),
                        &Style::fill(Color { a: 170, ..color }),
                    );
                }
                let stroke = lay.line(
                    if self.bars { Color::BLACK } else { color },
                    if self.bars { 1.2 } else { 2.0 },
                );
                if i.lo.is_finite() && i.hi.is_finite() {
                    fig.polyline(&[map(x, i.lo), map(x, i.hi)], &stroke);
                    for v in [i.lo, i.hi] {
                        let e = map(x, v);
                        fig.polyline(
                            &[
                                Vec2::new(e.x - 0.4 * em, e.y),
                                Vec2::new(e.x + 0.4 * em, e.y),
                            ],
                            &stroke,
                        );
                    }
                }
                if i.mean.is_finite() && !self.bars {
                    fig.circle(map(x, i.mean), 0.47 * em, &Style::fill(color));
                }
            }
        }
        let labels: Vec<(&str, Color)> = self
            .series
            .iter()
            .map(|(l, c, _)| (l.as_str(), *c))
            .collect();
        legend(&mut fig, &lay, &labels, None);
        fig
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round() {
        assert_eq!(tick_step(1.0, 5.0), 0.2);
        assert_eq!(tick_step(3000.0, 6.0), 500.0);
        assert_eq!(tick_step(40.0, 5.0), 10.0);
        assert_eq!(tick_step(0.0, 5.0), 1.0);
        assert_eq!(tick_text(-1e-13, 0.2), "0.0");
        assert_eq!(tick_text(-5.0, 5.0), "-5");
    }

    #[test]
    fn charts_draw_every_series_and_survive_empty_data() {
        let chart = LineChart {
            title: "t".into(),
            x_label: "time (s)".into(),
            x_range: None,
            y_label: "explored".into(),
            y_range: Some((0.0, 1.0)),
            series: vec![
                Series {
                    label: "baseline".into(),
                    color: series_color(0),
                    points: vec![(0.0, 0.0), (100.0, 0.5), (200.0, 1.0)],
                    band: vec![(0.0, 0.0, 0.0), (100.0, 0.4, 0.6), (200.0, 1.0, 1.0)],
                    marks: vec![],
                },
                Series {
                    label: "layout".into(),
                    color: series_color(1),
                    points: vec![(0.0, 0.0), (150.0, 1.0)],
                    band: vec![],
                    marks: vec![(150.0, 1.0)],
                },
            ],
            marks_label: "early stop".into(),
        };
        let svg = chart.figure().to_svg();
        assert!(svg.contains("baseline") && svg.contains("layout"));
        assert!(
            svg.contains(">early stop<"),
            "the marks are named in the legend"
        );
        let empty = LineChart {
            series: vec![],
            y_range: None,
            ..chart
        };
        assert!(!empty.figure().to_png().is_empty());
        let bars = IntervalChart {
            title: "gain".into(),
            y_label: "%".into(),
            categories: vec!["a".into(), "b".into()],
            series: vec![(
                "layout".into(),
                series_color(1),
                vec![
                    Some(Interval {
                        mean: -5.0,
                        lo: -9.0,
                        hi: -1.0,
                    }),
                    None,
                ],
            )],
            bars: false,
        };
        let svg = bars.figure().to_svg();
        assert!(svg.contains(">a<") && svg.contains(">b<"), "{svg}");
        assert!(!bars.figure().to_png().is_empty());
        // As bars: the point at the mean becomes a filled bar (a closed path) from zero.
        let grouped = IntervalChart {
            bars: true,
            ..bars.clone()
        };
        let circles = |f: &Figure| {
            f.items
                .iter()
                .filter(|i| matches!(i, crate::Item::Circle { .. }))
                .count()
        };
        let closed = |f: &Figure| {
            f.items
                .iter()
                .filter(|i| matches!(i, crate::Item::Path { closed: true, .. }))
                .count()
        };
        let (as_points, as_bars) = (bars.figure(), grouped.figure());
        assert_eq!((circles(&as_points), circles(&as_bars)), (1, 0));
        assert_eq!(closed(&as_bars), closed(&as_points) + 1);
        assert!(!as_bars.to_png().is_empty());
    }
}
