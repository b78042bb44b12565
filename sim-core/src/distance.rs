//! Exact Euclidean distance transform (Felzenszwalb & Huttenlocher), in cells.

use crate::grid::{Bitmap, Grid};

/// For every cell, the Euclidean distance (in cells) to the nearest cell where `target` is true.
/// Cells of an all-false mask get `f32::INFINITY`.
pub fn distance_to(target: &Bitmap) -> Grid<f32> {
    let w = target.width() as usize;
    let h = target.height() as usize;
    const INF: f64 = 1e20;
    let mut f: Vec<f64> = target
        .data
        .iter()
        .map(|&t| if t { 0.0 } else { INF })
        .collect();
    let n = w.max(h);
    let mut buf_f = vec![0.0; n];
    let mut buf_d = vec![0.0; n];
    let mut v = vec![0usize; n];
    let mut z = vec![0.0; n + 1];
    // Columns.
    for x in 0..w {
        for y in 0..h {
            buf_f[y] = f[y * w + x];
        }
        dt1d(&buf_f[..h], &mut buf_d[..h], &mut v, &mut z);
        for y in 0..h {
            f[y * w + x] = buf_d[y];
        }
    }
    // Rows.
    for y in 0..h {
        buf_f[..w].copy_from_slice(&f[y * w..(y + 1) * w]);
        dt1d(&buf_f[..w], &mut buf_d[..w], &mut v, &mut z);
        f[y * w..(y + 1) * w].copy_from_slice(&buf_d[..w]);
    }
    Grid {
        frame: target.frame,
        data: f
            .into_iter()
            .map(|d| {
                if d >= INF / 2.0 {
                    f32::INFINITY
                } else {
                    d.sqrt() as f32
                }
            })
            .collect(),
    }
}

fn dt1d(f: &[f64], d: &mut [f64], v: &mut [usize], z: &mut [f64]) {
    let n = f.len();
    if n == 0 {
        return;
    }
    let mut k = 0usize;
    v[0] = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in 1..n {
        let parabola = |p: usize| {
            ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * q as f64 - 2.0 * p as f64)
        };
        let mut s = parabola(v[k]);
        // z[0] is -inf, so this stops at k == 0 at the latest.
        while s <= z[k] {
            k -= 1;
            s = parabola(v[k]);
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    k = 0;
    for (q, dq) in d.iter_mut().enumerate().take(n) {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let p = v[k];
        let dx = q as f64 - p as f64;
        *dq = dx * dx + f[p];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec2;
    use crate::grid::{Cell, GridFrame};

    #[test]
    fn matches_brute_force() {
        let frame = GridFrame::new(Vec2::zeros(), 1.0, 23, 17);
        let mut m = Bitmap::filled(frame, false);
        for (x, y) in [(3, 4), (20, 1), (10, 15), (0, 0), (11, 8)] {
            m.set(Cell::new(x, y), true);
        }
        let d = distance_to(&m);
        for (c, &dv) in d.iter() {
            let best = m
                .iter()
                .filter(|(_, t)| **t)
                .map(|(t, _)| (((t.x - c.x).pow(2) + (t.y - c.y).pow(2)) as f32).sqrt())
                .fold(f32::INFINITY, f32::min);
            assert!((dv - best).abs() < 1e-4, "{c:?}: {dv} vs {best}");
        }
    }

    #[test]
    fn empty_target_is_infinite() {
        let frame = GridFrame::new(Vec2::zeros(), 1.0, 4, 3);
        let d = distance_to(&Bitmap::filled(frame, false));
        assert!(d.data.iter().all(|v| v.is_infinite()));
    }
}
