//! Representative wall lines: for each dominant direction, the boundary cells oriented like it are
//! projected on its normal; peaks of that 1D histogram (at least `min_line_separation_m` apart,
//! with at least `min_line_support_m` of evidence) are the lines.

use std::f64::consts::PI;

use super::evidence::BoundaryCell;
use super::{LayoutConfig, WallLine};
use crate::geom::angle_diff_mod_pi;
use crate::geom::{Segment, Vec2};
use crate::grid::{Occupancy, OccupancyGrid};

/// Lines of every direction in `normals_rad` (boundary-normal orientations), weights normalised
/// to the best supported line. Ordered by family, then offset.
pub fn wall_lines(
    cells: &[BoundaryCell],
    normals_rad: &[f64],
    resolution_m: f64,
    config: &LayoutConfig,
) -> Vec<WallLine> {
    wall_lines_and_doors(cells, normals_rad, resolution_m, config).0
}

/// [`wall_lines`], and per line its door gaps: intervals of the line's coordinate along its
/// direction (`u . p`, `u = (cos d, sin d)`) where the wall evidence lying on the line stops for
/// at most [`LayoutConfig::max_door_width_m`] between two runs of at least
/// [`LayoutConfig::min_door_jamb_m`]. Only evidence parallel to the line counts, so a line
/// extended across a corridor (whose walls are perpendicular to it) gets no gap there, while a
/// door in a wall does: the wall continues on both sides of it.
pub(crate) fn wall_lines_and_doors(
    cells: &[BoundaryCell],
    normals_rad: &[f64],
    resolution_m: f64,
    config: &LayoutConfig,
) -> (Vec<WallLine>, Vec<Vec<(f64, f64)>>) {
    let mut out = Vec::new();
    let mut doors = Vec::new();
    for (family, &phi) in normals_rad.iter().enumerate() {
        let direction_rad = (phi - PI / 2.0).rem_euclid(PI);
        let n = Vec2::new(-direction_rad.sin(), direction_rad.cos());
        let pts = family_points(cells, normals_rad, phi, config);
        if pts.is_empty() {
            continue;
        }
        let offs: Vec<f64> = pts.iter().map(|p| n.dot(p)).collect();
        let Some(hist) = Histogram::of(&offs, resolution_m) else {
            continue;
        };
        let peaks = hist.peaks(config);
        let family = Family {
            direction_rad,
            family: family as u32,
            pts: &pts,
            offs: &offs,
        };
        family.lines(&peaks, resolution_m, config, &mut out, &mut doors);
    }
    let max = out.iter().map(|l| l.support_m).fold(0.0, f64::max);
    if max > 0.0 {
        for l in &mut out {
            l.weight = l.support_m / max;
        }
    }
    (out, doors)
}

/// The points of the boundary cells of the family of normal `phi`: those whose local normal is
/// nearest it among `normals_rad`, within the tolerance.
fn family_points(
    cells: &[BoundaryCell],
    normals_rad: &[f64],
    phi: f64,
    config: &LayoutConfig,
) -> Vec<Vec2> {
    // Cells whose local normal is nearest this direction, within the tolerance.
    cells
        .iter()
        .filter(|c| {
            let d = angle_diff_mod_pi(c.normal_rad, phi);
            d <= config.direction_tolerance_rad
                && normals_rad
                    .iter()
                    .all(|o| angle_diff_mod_pi(c.normal_rad, *o) >= d)
        })
        .map(|c| c.p)
        .collect()
}

/// The histogram of a family's offsets, in bins of one cell from `lo`.
struct Histogram {
    lo: f64,
    bin_m: f64,
    hist: Vec<f64>,
}

impl Histogram {
    /// The histogram of `offs` (each weighing one cell), `None` when it would be too long.
    fn of(offs: &[f64], resolution_m: f64) -> Option<Histogram> {
        let bin_m = resolution_m;
        let lo = offs.iter().cloned().fold(f64::INFINITY, f64::min) - bin_m;
        let hi = offs.iter().cloned().fold(f64::NEG_INFINITY, f64::max) + bin_m;
        let nbins = ((hi - lo) / bin_m) as usize + 2;
        if nbins > 10_000_000 {
            return None;
        }
        let mut hist = vec![0f64; nbins];
        let bin_of = |o: f64| (((o - lo) / bin_m) as usize).min(nbins - 1);
        for &o in offs {
            hist[bin_of(o)] += resolution_m;
        }
        Some(Histogram { lo, bin_m, hist })
    }

    /// The peaks (offset, support), at least the minimum separation apart and with at least the
    /// minimum support, by offset.
    fn peaks(&self, config: &LayoutConfig) -> Vec<(f64, f64)> {
        let (lo, bin_m, hist) = (self.lo, self.bin_m, &self.hist);
        let nbins = hist.len();
        // Support of a peak: evidence within half the separation.
        let half = ((config.min_line_separation_m / 2.0) / bin_m)
            .round()
            .max(0.0) as usize;
        let mut prefix = vec![0f64; nbins + 1];
        for i in 0..nbins {
            prefix[i + 1] = prefix[i] + hist[i];
        }
        let window = |i: usize| {
            let a = i.saturating_sub(half);
            let b = (i + half + 1).min(nbins);
            prefix[b] - prefix[a]
        };
        let support: Vec<f64> = (0..nbins).map(window).collect();
        let mut order: Vec<usize> = (0..nbins).filter(|&i| hist[i] > 0.0).collect();
        order.sort_by(|&a, &b| support[b].total_cmp(&support[a]).then(a.cmp(&b)));
        let mut taken = vec![false; nbins];
        let sep_bins = (config.min_line_separation_m / bin_m).round().max(1.0) as usize;
        let mut peaks: Vec<(f64, f64)> = Vec::new();
        for i in order {
            if support[i] < config.min_line_support_m {
                break;
            }
            let a = i.saturating_sub(sep_bins - 1);
            let b = (i + sep_bins).min(nbins);
            if taken[a..b].iter().any(|t| *t) {
                continue;
            }
            let (centre, mass) = self.mean_shift(i, config);
            if peaks
                .iter()
                .any(|(c, _)| (c - centre).abs() < config.min_line_separation_m)
            {
                continue;
            }
            let cb = (((centre - lo) / bin_m) as usize).min(nbins - 1);
            taken[cb] = true;
            taken[i] = true;
            peaks.push((centre, mass.max(support[i])));
        }
        peaks.sort_by(|a, b| a.0.total_cmp(&b.0));
        peaks
    }

    /// The centre of the peak at bin `i` and the evidence around it (0 when none).
    fn mean_shift(&self, i: usize, config: &LayoutConfig) -> (f64, f64) {
        let (lo, bin_m, hist) = (self.lo, self.bin_m, &self.hist);
        let nbins = hist.len();
        // Mean shift: the evidence-weighted mean within one separation, so that both sides
        // of a wall give its centre.
        let mut centre = lo + (i as f64 + 0.5) * bin_m;
        let mut mass = 0.0;
        for _ in 0..3 {
            let a = (((centre - config.min_line_separation_m - lo) / bin_m)
                .floor()
                .max(0.0)) as usize;
            let b = ((((centre + config.min_line_separation_m - lo) / bin_m).ceil()) as usize)
                .min(nbins);
            let mut s = 0.0;
            let mut m = 0.0;
            for (j, hj) in hist.iter().enumerate().take(b).skip(a) {
                let o = lo + (j as f64 + 0.5) * bin_m;
                if (o - centre).abs() <= config.min_line_separation_m {
                    s += hj;
                    m += hj * o;
                }
            }
            if s <= 0.0 {
                break;
            }
            centre = m / s;
            mass = s;
        }
        (centre, mass)
    }
}

/// A family's points and their offsets along its normal.
struct Family<'a> {
    direction_rad: f64,
    family: u32,
    pts: &'a [Vec2],
    offs: &'a [f64],
}

impl Family<'_> {
    /// Pushes the line of each peak (offset, support) with evidence to `out`, and its door gaps
    /// to `doors`.
    fn lines(
        &self,
        peaks: &[(f64, f64)],
        resolution_m: f64,
        config: &LayoutConfig,
        out: &mut Vec<WallLine>,
        doors: &mut Vec<Vec<(f64, f64)>>,
    ) {
        let (direction_rad, pts, offs) = (self.direction_rad, self.pts, self.offs);
        let n = Vec2::new(-direction_rad.sin(), direction_rad.cos());
        let u = Vec2::new(direction_rad.cos(), direction_rad.sin());
        let bin_m = resolution_m;
        // The cells by offset: those near a line's offset are a run of them (`o - c` never
        // decreases as `o` grows), found from where the offset would be sorted in.
        let mut by_offset: Vec<u32> = (0..offs.len() as u32).collect();
        by_offset.sort_by(|&a, &b| offs[a as usize].total_cmp(&offs[b as usize]));
        for &(offset_m, support_m) in peaks {
            // Extent along the line of the cells that support it.
            let tol = config.min_line_separation_m / 2.0 + bin_m;
            let near = |o: f64| (o - offset_m).abs() <= tol;
            // Below the run: lower than the offset and not near; up to its end: lower or near.
            let a = by_offset.partition_point(|&k| {
                let o = offs[k as usize];
                o < offset_m && !near(o)
            });
            let b = by_offset.partition_point(|&k| {
                let o = offs[k as usize];
                o < offset_m || near(o)
            });
            // (Sorted below: the order they are gathered in does not matter.)
            let mut ts: Vec<f64> = by_offset[a..b]
                .iter()
                .map(|&k| u.dot(&pts[k as usize]))
                .collect();
            if ts.is_empty() {
                continue;
            }
            ts.sort_by(f64::total_cmp);
            let (t0, t1) = (ts[0], ts[ts.len() - 1]);
            doors.push(door_gaps(&ts, resolution_m, config));
            let foot = n * offset_m;
            out.push(WallLine {
                direction_rad,
                offset_m,
                weight: support_m,
                support_m,
                extent: Segment::new(foot + u * t0, foot + u * t1),
                family: self.family,
            });
        }
    }
}

/// Door gaps along a line from the sorted coordinates `ts` of its evidence cells: runs of
/// evidence (holes up to a quarter metre are noise) and the short holes between two long runs.
pub(crate) fn door_gaps(ts: &[f64], resolution_m: f64, config: &LayoutConfig) -> Vec<(f64, f64)> {
    let join_m = (2.5 * resolution_m).max(0.25);
    let mut runs: Vec<(f64, f64)> = Vec::new();
    for &t in ts {
        match runs.last_mut() {
            Some(r) if t - r.1 <= join_m => r.1 = t,
            _ => runs.push((t, t)),
        }
    }
    let long = |r: &(f64, f64)| r.1 - r.0 + resolution_m >= config.min_door_jamb_m;
    runs.windows(2)
        .filter(|w| {
            let gap = w[1].0 - w[0].1;
            gap <= config.max_door_width_m + resolution_m && long(&w[0]) && long(&w[1])
        })
        .map(|w| (w[0].1, w[1].0))
        .collect()
}

/// Drops the door gaps that are corridor crossings rather than doors: a line extended across a
/// corridor (or along a corridor past a side corridor, a T junction) meets walls at the ends of
/// the gap that run away from the line, along its normal, on one side or both, far beyond the
/// line's own wall; a door's jambs are only as deep as that wall, however thick it is drawn.
pub(crate) fn drop_crossings(
    grid: &OccupancyGrid,
    lines: &[WallLine],
    doors: &mut [Vec<(f64, f64)>],
) {
    let res = grid.frame.resolution_m;
    let reach = (1.5 / res).round().max(1.0) as i32;
    let slack = (0.2 / res).round().max(1.0) as i32;
    for (line, gaps) in lines.iter().zip(doors.iter_mut()) {
        let n = line.normal();
        let u = Vec2::new(n.y, -n.x);
        let foot = n * line.offset_m;
        let occupied = |t: f64, k: i32| {
            let p = foot + u * t + n * (k as f64 * res);
            grid.get(grid.frame.cell_from_world(p)) == Some(&Occupancy::Occupied)
        };
        // Depth in metres of the occupied cells at `t` running from the line towards `side`
        // (the run must start within `slack` cells of the line).
        let depth = |t: f64, side: i32| {
            let Some(k0) = (-slack..=slack).find(|&k| occupied(t, k * side)) else {
                return 0.0;
            };
            let mut k = k0;
            while k < reach && occupied(t, (k + 1) * side) {
                k += 1;
            }
            (k.max(0) + 1) as f64 * res
        };
        let probe = (0.3f64).max(2.0 * res);
        gaps.retain(|&(t0, t1)| {
            let inside = (0.4f64).min((t1 - t0) / 2.0);
            let steps = ((inside / res).ceil() as usize).max(1);
            ![1, -1].iter().any(|&side| {
                // The line's own wall beside the gap, on this side.
                let own = depth(t0 - probe, side).max(depth(t1 + probe, side));
                (0..=steps).any(|i| {
                    let d = i as f64 * res;
                    let run = depth(t0 + d, side).max(depth(t1 - d, side));
                    run >= 0.8 && run >= own + 0.6
                })
            })
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_sides_of_a_wall_are_one_line() {
        // A 0.2 m thick horizontal wall, 5 m long: boundary cells at y = 1.0 and y = 1.2.
        let mut cells = Vec::new();
        for i in 0..100 {
            for y in [1.0, 1.2] {
                cells.push(BoundaryCell {
                    p: Vec2::new(i as f64 * 0.05, y),
                    normal_rad: PI / 2.0,
                });
            }
        }
        // Another wall 3 m away, half as long.
        for i in 0..50 {
            cells.push(BoundaryCell {
                p: Vec2::new(i as f64 * 0.05, 4.1),
                normal_rad: PI / 2.0,
            });
        }
        let lines = wall_lines(&cells, &[PI / 2.0], 0.05, &LayoutConfig::default());
        assert_eq!(lines.len(), 2, "{lines:?}");
        // Direction pi/2 - pi/2 = 0: the normal is +y, offsets are y.
        assert!((lines[0].offset_m - 1.1).abs() < 0.03, "{lines:?}");
        assert!((lines[1].offset_m - 4.1).abs() < 0.03, "{lines:?}");
        assert_eq!(lines[0].weight, 1.0);
        assert!((lines[1].weight - 0.25).abs() < 0.05);
        assert!((lines[0].extent.length_m() - 4.95).abs() < 1e-6);
    }

    /// The gaps of the horizontal line on the top face of the bottom wall (y index 2 from the
    /// bottom, cell centres 0.25 m), after `drop_crossings`.
    fn gaps_after_crossings(text: &str) -> Vec<(f64, f64)> {
        let g = OccupancyGrid::from_ascii(text, 0.1);
        let line = WallLine {
            direction_rad: 0.0,
            offset_m: 0.25,
            weight: 1.0,
            support_m: 1.0,
            extent: Segment::new(Vec2::new(0.0, 0.25), Vec2::new(3.0, 0.25)),
            family: 0,
        };
        // A gap between x = 1.05 and x = 1.95 m (columns 10..19).
        let mut doors = vec![vec![(1.05, 1.95)]];
        drop_crossings(&g, &[line], &mut doors);
        doors.pop().unwrap()
    }

    #[test]
    fn thick_wall_door_is_kept_and_junction_is_dropped() {
        // A door in a 0.3 m thick wall: its jambs are as deep as the wall.
        let door = format!(
            "{}{}",
            "..............................\n".repeat(12),
            "##########.........###########\n".repeat(3)
        );
        assert_eq!(gaps_after_crossings(&door).len(), 1);
        // A side corridor leaving the wall: its walls run 1.2 m up from the gap's ends.
        let junction = format!(
            "{}{}{}",
            "..............................\n".repeat(3),
            ".........#.........#..........\n".repeat(9),
            "##########.........###########\n".repeat(3)
        );
        assert!(gaps_after_crossings(&junction).is_empty());
    }
}
