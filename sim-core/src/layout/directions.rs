//! Dominant wall directions: peaks of the histogram of boundary normals (modulo pi), each refined
//! to the angle at which the boundary cells' offsets along the normal are most concentrated
//! (walls are straight, so the right angle stacks a wall's cells into few offset bins).

use std::f64::consts::PI;

use super::evidence::BoundaryCell;
use super::{LayoutConfig, LayoutDiagnostics};

const BINS: usize = 360;

/// Angular distance modulo pi.
pub fn angle_diff_mod_pi(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(PI);
    d.min(PI - d)
}

/// The dominant boundary-normal orientations in `[0, pi)`, strongest first.
pub fn dominant_directions(
    cells: &[BoundaryCell],
    resolution_m: f64,
    config: &LayoutConfig,
    diag: &mut LayoutDiagnostics,
) -> Vec<f64> {
    if cells.is_empty() {
        return Vec::new();
    }
    let mut hist = [0f64; BINS];
    for c in cells {
        let b = ((c.normal_rad / PI * BINS as f64) as usize).min(BINS - 1);
        hist[b] += 1.0;
    }
    // Circular smoothing (triangle of half-width 3 bins = 1.5 degrees).
    let kernel = [1.0, 2.0, 3.0, 4.0, 3.0, 2.0, 1.0];
    let mut smooth = [0f64; BINS];
    for (i, s) in smooth.iter_mut().enumerate() {
        for (k, wk) in kernel.iter().enumerate() {
            *s += wk * hist[(i + BINS + k - 3) % BINS];
        }
    }
    let max = smooth.iter().cloned().fold(0.0, f64::max);
    if max <= 0.0 {
        return Vec::new();
    }
    let mut order: Vec<usize> = (0..BINS).collect();
    order.sort_by(|&a, &b| smooth[b].total_cmp(&smooth[a]).then(a.cmp(&b)));
    let bin_angle = |b: usize| (b as f64 + 0.5) * PI / BINS as f64;
    let mut peaks: Vec<f64> = Vec::new();
    for b in order {
        if peaks.len() >= config.max_directions || smooth[b] < config.min_direction_fraction * max {
            break;
        }
        let is_local_max =
            smooth[b] >= smooth[(b + 1) % BINS] && smooth[b] >= smooth[(b + BINS - 1) % BINS];
        let a = bin_angle(b);
        if is_local_max
            && peaks
                .iter()
                .all(|p| angle_diff_mod_pi(*p, a) >= config.min_direction_separation_rad)
        {
            peaks.push(a);
        }
    }
    diag.directions = peaks.len();
    peaks
        .into_iter()
        .map(|a| refine(cells, a, resolution_m, config, diag))
        .collect()
}

/// The angle within +-1 degree of `a` whose offset histogram is sharpest (sum of squared bins).
fn refine(
    cells: &[BoundaryCell],
    a: f64,
    resolution_m: f64,
    config: &LayoutConfig,
    diag: &mut LayoutDiagnostics,
) -> f64 {
    let pts: Vec<_> = cells
        .iter()
        .filter(|c| angle_diff_mod_pi(c.normal_rad, a) <= config.direction_tolerance_rad)
        .map(|c| c.p)
        .collect();
    if pts.len() < 8 {
        return a;
    }
    let mut hist: Vec<f64> = Vec::new();
    let mut best = (f64::NEG_INFINITY, a);
    let steps = 40;
    let span = 1f64.to_radians();
    for k in 0..=steps {
        let t = a - span + 2.0 * span * k as f64 / steps as f64;
        let (s, c) = t.sin_cos();
        let offsets = pts.iter().map(|p| (p.x * c + p.y * s) / resolution_m);
        let (lo, hi) = offsets
            .clone()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), o| {
                (l.min(o), h.max(o))
            });
        let n = (hi - lo) as usize + 3;
        hist.clear();
        hist.resize(n, 0.0);
        // Linear binning: the score does not jump when a wall crosses a bin boundary.
        for o in offsets {
            let x = o - lo;
            let b = x as usize;
            let fr = x - b as f64;
            hist[b] += 1.0 - fr;
            hist[b + 1] += fr;
        }
        let score: f64 = hist.iter().map(|v| v * v).sum();
        diag.direction_refine_steps += 1;
        if score > best.0 {
            best = (score, t);
        }
    }
    best.1.rem_euclid(PI)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec2;

    fn rotated_box_cells(theta: f64) -> Vec<BoundaryCell> {
        // Points on the sides of a 10 x 6 m rectangle rotated by theta, every 5 cm.
        let (s, c) = theta.sin_cos();
        let rot = |x: f64, y: f64| Vec2::new(c * x - s * y, s * x + c * y);
        let mut out = Vec::new();
        for i in 0..200 {
            let t = i as f64 * 0.05;
            for (p, n) in [
                (rot(t, 0.0), theta + PI / 2.0),
                (rot(t, 6.0), theta + PI / 2.0),
            ] {
                out.push(BoundaryCell {
                    p,
                    normal_rad: n.rem_euclid(PI),
                });
            }
        }
        for i in 0..120 {
            let t = i as f64 * 0.05;
            for p in [rot(0.0, t), rot(10.0, t)] {
                out.push(BoundaryCell {
                    p,
                    normal_rad: theta.rem_euclid(PI),
                });
            }
        }
        out
    }

    #[test]
    fn finds_two_rotated_directions() {
        let theta = 0.7;
        let dirs = dominant_directions(
            &rotated_box_cells(theta),
            0.05,
            &LayoutConfig::default(),
            &mut LayoutDiagnostics::default(),
        );
        assert_eq!(dirs.len(), 2, "{dirs:?}");
        let mut got: Vec<f64> = dirs.iter().map(|d| angle_diff_mod_pi(*d, theta)).collect();
        got.sort_by(f64::total_cmp);
        assert!(got[0] < 0.2f64.to_radians(), "{got:?}");
        assert!((got[1] - PI / 2.0).abs() < 0.2f64.to_radians(), "{got:?}");
    }

    #[test]
    fn no_cells_no_directions() {
        let d = dominant_directions(
            &[],
            0.05,
            &LayoutConfig::default(),
            &mut LayoutDiagnostics::default(),
        );
        assert!(d.is_empty());
    }
}
