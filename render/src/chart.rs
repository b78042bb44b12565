//! Charts of experiment results, drawn on a [`Figure`] (so they save as SVG or PNG like every
//! other figure): a line chart (explored fraction over time, one line per strategy, with a band
//! of its spread and marks where runs stopped early: the paper's Fig. 4) and an interval chart
//! (a mean with an interval per category and series, as points or as grouped bars: the paper's
//! Fig. 2).
//!
//! Data go into a plotting box of fixed size in figure units; axes carry round tick values.

use sim_core::{Aabb, Vec2};

use crate::{Anchor, Color, Figure, Style};

/// Size of the plotting box in figure units, and the margins around it.
const BOX_W: f64 = 10.0;
const BOX_H: f64 = 6.0;
const LEFT: f64 = 1.3;
const BOTTOM: f64 = 1.0;
const TOP: f64 = 0.8;
const LEGEND_W: f64 = 3.2;
const PX_PER_UNIT: f64 = 80.0;

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

/// A figure with the plotting box, its axes, ticks and labels for data ranges `x` and `y`.
/// Returns the figure and the map from data to figure units.
fn frame(
    title: &str,
    x_label: &str,
    y_label: &str,
    x: (f64, f64),
    y: (f64, f64),
    x_ticks: bool,
) -> (Figure, impl Fn(f64, f64) -> Vec2) {
    let bounds = Aabb {
        min: Vec2::new(-LEFT, -BOTTOM),
        max: Vec2::new(BOX_W + LEGEND_W, BOX_H + TOP),
    };
    let mut fig = Figure::new(bounds, PX_PER_UNIT);
    let (x0, x1) = x;
    let (y0, y1) = y;
    let sx = BOX_W / (x1 - x0).max(1e-12);
    let sy = BOX_H / (y1 - y0).max(1e-12);
    let map = move |a: f64, b: f64| Vec2::new((a - x0) * sx, (b - y0) * sy);
    let axis = Style::stroke(Color::BLACK, 1.5);
    let grid = Style::stroke(Color::rgb(225, 225, 225), 1.0);
    let ys = tick_step(y1 - y0, 5.0);
    let mut v = (y0 / ys).ceil() * ys;
    while v <= y1 + 1e-9 * ys {
        let p = map(x0, v);
        fig.polyline(&[p, Vec2::new(BOX_W, p.y)], &grid);
        fig.text_anchored(
            Vec2::new(-0.12, p.y),
            12.0,
            Color::BLACK,
            &tick_text(v, ys),
            Anchor::End,
        );
        v += ys;
    }
    if x_ticks {
        let xs = tick_step(x1 - x0, 6.0);
        let mut v = (x0 / xs).ceil() * xs;
        while v <= x1 + 1e-9 * xs {
            let p = map(v, y0);
            fig.polyline(&[p, Vec2::new(p.x, BOX_H)], &grid);
            fig.text(Vec2::new(p.x, -0.3), 12.0, Color::BLACK, &tick_text(v, xs));
            v += xs;
        }
    }
    fig.polyline(
        &[Vec2::new(0.0, BOX_H), Vec2::zeros(), Vec2::new(BOX_W, 0.0)],
        &axis,
    );
    fig.text(
        Vec2::new(BOX_W / 2.0, BOX_H + 0.45),
        16.0,
        Color::BLACK,
        title,
    );
    fig.text(Vec2::new(BOX_W / 2.0, -0.75), 13.0, Color::BLACK, x_label);
    fig.text_anchored(
        Vec2::new(-LEFT + 0.1, BOX_H + 0.3),
        13.0,
        Color::BLACK,
        y_label,
        Anchor::Start,
    );
    (fig, map)
}

/// The legend right of the box: a line of each colour and its label; then, with `marks`, a
/// mark and its name.
fn legend(fig: &mut Figure, labels: &[(&str, Color)], marks: Option<&str>) {
    let y_of = |k: usize| BOX_H - 0.4 - 0.45 * k as f64;
    for (k, &(l, c)) in labels.iter().enumerate() {
        let y = y_of(k);
        fig.polyline(
            &[Vec2::new(BOX_W + 0.3, y), Vec2::new(BOX_W + 0.8, y)],
            &Style::stroke(c, 3.0),
        );
        fig.text_anchored(
            Vec2::new(BOX_W + 1.0, y),
            12.0,
            Color::BLACK,
            l,
            Anchor::Start,
        );
    }
    if let Some(name) = marks {
        let y = y_of(labels.len());
        mark(fig, Vec2::new(BOX_W + 0.55, y), Color::DARK_GREY);
        fig.text_anchored(
            Vec2::new(BOX_W + 1.0, y),
            12.0,
            Color::BLACK,
            name,
            Anchor::Start,
        );
    }
}

/// A mark: a small ring.
fn mark(fig: &mut Figure, at: Vec2, color: Color) {
    fig.circle(
        at,
        0.075,
        &Style {
            fill: Some(Color::WHITE),
            ..Style::stroke(color, 2.0)
        },
    );
}

impl LineChart {
    pub fn figure(&self) -> Figure {
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
        let x1 = if x1 > 0.0 { x1 } else { 1.0 };
        let (mut fig, map) = frame(
            &self.title,
            &self.x_label,
            &self.y_label,
            (0.0, x1),
            (y0, y1),
            true,
        );
        let clamp = |y: f64| y.clamp(y0, y1);
        // Bands first, under every line.
        for s in &self.series {
            let band: Vec<&(f64, f64, f64)> = s
                .band
                .iter()
                .filter(|(x, lo, hi)| x.is_finite() && lo.is_finite() && hi.is_finite())
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
                .filter(|(x, y)| x.is_finite() && y.is_finite())
                .map(|&(x, y)| map(x, clamp(y)))
                .collect();
            fig.polyline(&line, &Style::stroke(s.color, 2.0));
        }
        for s in &self.series {
            for &(x, y) in s
                .marks
                .iter()
                .filter(|(x, y)| x.is_finite() && y.is_finite())
            {
                mark(&mut fig, map(x, clamp(y)), s.color);
            }
        }
        let labels: Vec<(&str, Color)> = self
            .series
            .iter()
            .map(|s| (s.label.as_str(), s.color))
            .collect();
        let marked = self.series.iter().any(|s| !s.marks.is_empty());
        legend(
            &mut fig,
            &labels,
            marked.then_some(self.marks_label.as_str()),
        );
        fig
    }
}

impl IntervalChart {
    pub fn figure(&self) -> Figure {
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
        let (mut fig, map) = frame(&self.title, "", &self.y_label, (0.0, n), (y0, y1), false);
        // The zero line.
        fig.polyline(
            &[map(0.0, 0.0), map(n, 0.0)],
            &Style::stroke(Color::DARK_GREY, 1.0).dashed(4.0, 3.0),
        );
        let m = self.series.len().max(1) as f64;
        for (c, name) in self.categories.iter().enumerate() {
            let p = map(c as f64 + 0.5, y0);
            // Many categories: every other label one line lower, so that they do not overlap.
            let y = if self.categories.len() > 6 && c % 2 == 1 {
                -0.6
            } else {
                -0.3
            };
            fig.text(Vec2::new(p.x, y), 12.0, Color::BLACK, name);
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
                let stroke = Style::stroke(
                    if self.bars { Color::BLACK } else { color },
                    if self.bars { 1.2 } else { 2.0 },
                );
                if i.lo.is_finite() && i.hi.is_finite() {
                    fig.polyline(&[map(x, i.lo), map(x, i.hi)], &stroke);
                    for v in [i.lo, i.hi] {
                        let e = map(x, v);
                        fig.polyline(
                            &[Vec2::new(e.x - 0.06, e.y), Vec2::new(e.x + 0.06, e.y)],
                            &stroke,
                        );
                    }
                }
                if i.mean.is_finite() && !self.bars {
                    fig.circle(map(x, i.mean), 0.07, &Style::fill(color));
                }
            }
        }
        let labels: Vec<(&str, Color)> = self
            .series
            .iter()
            .map(|(l, c, _)| (l.as_str(), *c))
            .collect();
        legend(&mut fig, &labels, None);
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
