//! Dominant wall directions: the angles at which the boundary cells' offsets along the normal are
//! most concentrated (walls are straight, so the right angle stacks a wall's cells into few offset
//! bins).

use std::f64::consts::PI;

use super::evidence::BoundaryCell;
use super::{LayoutConfig, LayoutDiagnostics};
use crate::geom::{angle_diff_mod_pi, Vec2};

const BINS: usize = 180;
/// A direction this close to perpendicular to a kept one is its partner.
const PERPENDICULAR_TOLERANCE_RAD: f64 = 0.06;
/// Directions that are not the partner of a kept one need this many times
/// [`LayoutConfig::min_direction_fraction`].
const OBLIQUE_FACTOR: f64 = 3.0;
/// Boundary cells whose local normal is this close to a direction support it locally.
const LOCAL_TOLERANCE_RAD: f64 = 0.14;
/// A direction needs at least this fraction of the locally supporting cells of the best one.
const MIN_LOCAL_FRACTION: f64 = 0.12;

/// [`sharpness_of`] at one angle.
#[cfg(test)]
fn sharpness(pts: &[Vec2], t: f64, bin_m: f64, buf: &mut SharpnessBuffers) -> f64 {
    sharpness_of::<1>(pts, [t], bin_m, std::slice::from_mut(buf))[0]
}

/// [`sharpness_of`] at each angle of `ts`, in order, with `bufs` reused: the angles four at a
/// time.
fn sharpness_at(
    pts: &[Vec2],
    ts: &[f64],
    bin_m: f64,
    bufs: &mut [SharpnessBuffers; 4],
) -> Vec<f64> {
    let mut out = Vec::with_capacity(ts.len());
    let quads = ts.chunks_exact(4);
    let rest = quads.remainder();
    for q in quads {
        out.extend(sharpness_of::<4>(
            pts,
            [q[0], q[1], q[2], q[3]],
            bin_m,
            bufs,
        ));
    }
    match *rest {
        [] => {}
        [a] => out.extend(sharpness_of::<1>(pts, [a], bin_m, bufs)),
        [a, b] => out.extend(sharpness_of::<2>(pts, [a, b], bin_m, bufs)),
        [a, b, c] => out.extend(sharpness_of::<3>(pts, [a, b, c], bin_m, bufs)),
        _ => unreachable!("a remainder of chunks of four"),
    }
    out
}

/// Sharpness of the offsets of `pts` along the normal at each angle of `ts`: the sum of squared
/// counts of a linearly binned histogram (a straight wall at that angle stacks its cells into
/// one bin). Bins start at the lowest offset, so that the outermost wall's cells fall on a bin
/// boundary.
///
/// The `K` histograms (one per angle, in `bufs[..K]`) are filled in one pass over the points,
/// each in point order as one alone would be, so each score is bit for bit the one angle's.
/// Along a wall consecutive points fall into the same or neighbouring bins at nearly every
/// angle, so one histogram's additions wait on each other through memory (a store, then the
/// load of the next addition); `K` histograms give the processor `K` such chains side by side
/// (with four, 14 % less time for the directions of a real map; the pass is then mostly bound
/// by its instructions).
fn sharpness_of<const K: usize>(
    pts: &[Vec2],
    ts: [f64; K],
    bin_m: f64,
    bufs: &mut [SharpnessBuffers],
) -> [f64; K] {
    debug_assert!(bufs.len() >= K, "a buffer per angle");
    let mut ready = [false; K];
    for ((buf, &t), ready) in bufs.iter_mut().zip(&ts).zip(&mut ready) {
        *ready = buf.offsets_from_lowest(pts, t, bin_m);
    }
    if ready.contains(&false) {
        // (No point, or no finite offset: such an angle scores 0, the others alone.)
        return std::array::from_fn(|k| {
            if ready[k] {
                sharpness_of::<1>(pts, [ts[k]], bin_m, &mut bufs[k..=k])[0]
            } else {
                0.0
            }
        });
    }
    let mut parts: [(&[f64], &mut [f64]); K] = {
        let mut it = bufs.iter_mut().map(|b| (&b.offsets[..], &mut b.hist[..]));
        std::array::from_fn(|_| it.next().expect("a buffer per angle"))
    };
    // Linear binning: the score does not jump when a wall crosses a bin boundary.
    for i in 0..pts.len() {
        for (offs, hist) in parts.iter_mut() {
            let x = offs[i];
            // (Converted through i64: `x` is at least 0 and below the histogram's length, where
            // the signed conversions give what the unsigned ones do, each in one instruction
            // rather than a sequence of six or so.)
            let b = x as i64;
            let fr = x - b as f64;
            let b = b as usize;
            // (The two bins as one slice: one bounds test, and the two additions in one
            // vector instruction.)
            let [h0, h1]: &mut [f64; 2] = (&mut hist[b..b + 2]).try_into().expect("two bins");
            *h0 += 1.0 - fr;
            *h1 += fr;
        }
    }
    std::array::from_fn(|k| parts[k].1.iter().map(|v| v * v).sum())
}

/// What [`sharpness_of`] reuses from one set of angles to the next (one per angle).
#[derive(Default)]
struct SharpnessBuffers {
    offsets: Vec<f64>,
    hist: Vec<f64>,
}

impl SharpnessBuffers {
    /// The offsets of `pts` along the normal at angle `t` in bins of `bin_m`, less the lowest,
    /// and a histogram of zeros long enough for them; false when there is no finite lowest
    /// offset (no point).
    fn offsets_from_lowest(&mut self, pts: &[Vec2], t: f64, bin_m: f64) -> bool {
        let (s, c) = t.sin_cos();
        let (cb, sb) = (c / bin_m, s / bin_m);
        let offs = &mut self.offsets;
        offs.clear();
        offs.extend(pts.iter().map(|p| p.x * cb + p.y * sb));
        // The lowest and highest offsets, in four lanes (the least and the greatest of the
        // values do not depend on the order they are compared in). By comparisons, which
        // compile to the processor's min and max, rather than `f64::min` and `max`, whose NaN
        // rule costs a few more instructions. A lane never holds a NaN (it takes a value only
        // when the value compares below or above it), so a NaN offset is passed over as `min`
        // passes it over; a lane may differ from `min`'s only in the sign of a zero, which
        // changes no bin and no sum below (an offset from the lowest is then 0 or -0, its
        // fraction 0 or -0, added to sums that are never -0).
        let (mut lo4, mut hi4) = ([f64::INFINITY; 4], [f64::NEG_INFINITY; 4]);
        let quads = offs.chunks_exact(4);
        let rest = quads.remainder();
        for q in quads {
            for k in 0..4 {
                lo4[k] = if q[k] < lo4[k] { q[k] } else { lo4[k] };
                hi4[k] = if q[k] > hi4[k] { q[k] } else { hi4[k] };
            }
        }
        let (lo, hi) = rest.iter().fold(
            (
                lo4[0].min(lo4[1]).min(lo4[2]).min(lo4[3]),
                hi4[0].max(hi4[1]).max(hi4[2]).max(hi4[3]),
            ),
            |(l, h), o| (l.min(*o), h.max(*o)),
        );
        if !lo.is_finite() {
            return false;
        }
        let n = (hi - lo) as usize + 3;
        self.hist.clear();
        self.hist.resize(n, 0.0);
        // (Offsets from the lowest in a pass of their own, which the compiler vectorises.)
        offs.iter_mut().for_each(|o| *o -= lo);
        true
    }
}

/// The dominant boundary-normal orientations in `[0, pi)`, strongest first: peaks of the
/// sharpness of all boundary cells' offsets over angles (a Radon-like scan, robust to the
/// staircases of rotated walls, unlike local gradients), each refined to 0.05 degree.
pub(crate) fn dominant_directions(
    cells: &[BoundaryCell],
    resolution_m: f64,
    config: &LayoutConfig,
    diag: &mut LayoutDiagnostics,
) -> Vec<f64> {
    if cells.len() < 8 {
        return Vec::new();
    }
    // Coarse scan on at most ~COARSE_POINTS cells, bins of two cells, 1 degree steps.
    let stride = cells.len().div_ceil(COARSE_POINTS).max(1);
    let pts: Vec<Vec2> = cells.iter().step_by(stride).map(|c| c.p).collect();
    let mut bufs = Default::default();
    let angles: Vec<f64> = (0..BINS).map(|b| b as f64 * PI / BINS as f64).collect();
    let score = sharpness_at(&pts, &angles, 2.0 * resolution_m, &mut bufs);
    diag.direction_refine_steps += BINS;
    let mut sorted = score.clone();
    sorted.sort_by(f64::total_cmp);
    let base = sorted[0];
    let max = sorted[BINS - 1];
    if max <= base {
        return Vec::new();
    }
    let mut order: Vec<usize> = (0..BINS).collect();
    order.sort_by(|&a, &b| score[b].total_cmp(&score[a]).then(a.cmp(&b)));
    let mut peaks: Vec<f64> = Vec::new();
    for b in order {
        let strength = ((score[b] - base) / (max - base)).sqrt();
        if peaks.len() >= config.max_directions || strength < config.min_direction_fraction {
            break;
        }
        // The perpendicular of a kept direction is expected; any other direction must be
        // clearly stronger than the lattice aliases of the kept ones.
        let a = b as f64 * PI / BINS as f64;
        let perpendicular = peaks
            .iter()
            .any(|p| (angle_diff_mod_pi(*p, a) - PI / 2.0).abs() <= PERPENDICULAR_TOLERANCE_RAD);
        if !peaks.is_empty()
            && !perpendicular
            && strength < OBLIQUE_FACTOR * config.min_direction_fraction
        {
            continue;
        }
        let is_local_max =
            score[b] >= score[(b + 1) % BINS] && score[b] >= score[(b + BINS - 1) % BINS];
        if is_local_max
            && peaks
                .iter()
                .all(|p| angle_diff_mod_pi(*p, a) >= config.min_direction_separation_rad)
        {
            peaks.push(a);
        }
    }
    // Lattice aliasing: the cells of axis-aligned walls also stack at rational angles (atan 1/5,
    // atan 1/4...), where no wall runs. A real direction is also the local orientation of many
    // boundary cells; keep the peaks holding a good fraction of the best one's cells.
    let local = |a: f64| {
        cells
            .iter()
            .filter(|c| angle_diff_mod_pi(c.normal_rad, a) <= LOCAL_TOLERANCE_RAD)
            .count()
    };
    let counts: Vec<usize> = peaks.iter().map(|a| local(*a)).collect();
    let best = counts.iter().copied().max().unwrap_or(0);
    let peaks: Vec<f64> = peaks
        .iter()
        .zip(&counts)
        .filter(|(_, n)| **n > 0 && **n as f64 >= MIN_LOCAL_FRACTION * best as f64)
        .map(|(a, _)| *a)
        .collect();
    diag.directions = peaks.len();
    // Refinement on at most ~REFINE_POINTS cells spread over the whole map (a stride keeps every
    // wall represented).
    let stride = cells.len().div_ceil(REFINE_POINTS).max(1);
    let all: Vec<Vec2> = cells.iter().step_by(stride).map(|c| c.p).collect();
    peaks
        .into_iter()
        .map(|a| refine(&all, a, resolution_m, diag))
        .collect()
}

/// Cells used to refine a direction.
const REFINE_POINTS: usize = 20_000;
/// Cells used to find the directions.
const COARSE_POINTS: usize = 5_000;

/// The angle within one degree of `a` whose offset histogram is sharpest: 0.2 degree steps,
/// then 0.05 degree steps around the best.
fn refine(pts: &[Vec2], a: f64, resolution_m: f64, diag: &mut LayoutDiagnostics) -> f64 {
    let mut bufs = Default::default();
    let mut best = (f64::NEG_INFINITY, a);
    // The angles of a scan, scored together, then taken in order as one at a time would be.
    let mut scan = |centre: f64, step_deg: f64, ks: &[i32], best: &mut (f64, f64)| {
        diag.direction_refine_steps += ks.len();
        let ts: Vec<f64> = ks
            .iter()
            .map(|&k| centre + (k as f64 * step_deg).to_radians())
            .collect();
        for (score, t) in sharpness_at(pts, &ts, resolution_m, &mut bufs)
            .into_iter()
            .zip(ts)
        {
            if score > best.0 {
                *best = (score, t);
            }
        }
    };
    scan(a, 0.2, &[-5, -4, -3, -2, -1, 0, 1, 2, 3, 4, 5], &mut best);
    let coarse = best.1;
    // (Its centre, `coarse + 0.0`, is `coarse`, already scored and the best: its score would
    // not be above the best, so it is not computed again; still counted as an angle tried.)
    scan(coarse, 0.05, &[-3, -2, -1, 1, 2, 3], &mut best);
    diag.direction_refine_steps += 1;
    best.1.rem_euclid(PI)
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// [`sharpness`] as first written: one fold for the extremes, the offsets computed again.
    fn sharpness_reference(pts: &[Vec2], t: f64, bin_m: f64) -> f64 {
        let (s, c) = t.sin_cos();
        let (cb, sb) = (c / bin_m, s / bin_m);
        let (lo, hi) = pts
            .iter()
            .map(|p| p.x * cb + p.y * sb)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), o| {
                (l.min(o), h.max(o))
            });
        if !lo.is_finite() {
            return 0.0;
        }
        let mut hist = vec![0.0; (hi - lo) as usize + 3];
        for p in pts {
            let x = p.x * cb + p.y * sb - lo;
            let b = x as usize;
            let fr = x - b as f64;
            hist[b] += 1.0 - fr;
            hist[b + 1] += fr;
        }
        hist.iter().map(|v| v * v).sum()
    }

    /// The points of `cells` (column, row) on a lattice of spacing `res`, the origin at 0.
    fn centres(cells: &[(i32, i32)], res: f64) -> Vec<Vec2> {
        cells
            .iter()
            .map(|&(x, y)| Vec2::new(x as f64 * res, y as f64 * res))
            .collect()
    }

    proptest::proptest! {
        /// Bit for bit the reference, on cell centres of any grid (the origin's cell included:
        /// zero offsets of either sign), any number of points and any angle.
        #[test]
        fn sharpness_is_the_reference(
            cells in proptest::collection::vec((-300i32..300, -300i32..300), 0..300),
            t in 0.0f64..PI,
            res in proptest::prop_oneof![proptest::strategy::Just(0.05), 0.01f64..0.2],
        ) {
            let pts = centres(&cells, res);
            let mut buf = SharpnessBuffers::default();
            for angle in [t, 0.0, PI / 2.0] {
                let got = sharpness(&pts, angle, 2.0 * res, &mut buf);
                let want = sharpness_reference(&pts, angle, 2.0 * res);
                proptest::prop_assert_eq!(got.to_bits(), want.to_bits());
            }
        }

        /// Angles scored four at a time (and the rest one, two or three at a time) score bit
        /// for bit as each alone, on any points (none included) and any list of angles (a NaN
        /// among them, which has no finite offset, included).
        #[test]
        fn angles_together_score_as_each_alone(
            cells in proptest::collection::vec((-300i32..300, -300i32..300), 0..200),
            ts in proptest::collection::vec(
                proptest::prop_oneof![8 => 0.0f64..PI, 1 => proptest::strategy::Just(f64::NAN)],
                0..11,
            ),
            res in proptest::prop_oneof![proptest::strategy::Just(0.05), 0.01f64..0.2],
        ) {
            let pts = centres(&cells, res);
            let mut bufs = Default::default();
            let got = sharpness_at(&pts, &ts, 2.0 * res, &mut bufs);
            let want: Vec<u64> =
                ts.iter().map(|&t| sharpness_reference(&pts, t, 2.0 * res).to_bits()).collect();
            proptest::prop_assert_eq!(got.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), want);
        }
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
    fn grid_aliases_of_manhattan_walls_are_not_directions() {
        // The cells of axis-aligned walls also stack at atan(1/5), atan(1/4)...: only the two
        // real directions may come out, at 0.05 and at 0.10 m.
        use super::super::evidence::wall_evidence;
        use super::super::synthetic::{corridor_building, rasterise, BuildingSpec};
        let b = corridor_building(&BuildingSpec::default());
        for res in [0.05, 0.1] {
            let g = rasterise(&b, res);
            let config = LayoutConfig::default();
            let e = wall_evidence(&g, &config);
            let dirs =
                dominant_directions(&e.cells, res, &config, &mut LayoutDiagnostics::default());
            assert_eq!(dirs.len(), 2, "{res}: {dirs:?}");
            for d in dirs {
                let off = angle_diff_mod_pi(d, 0.0).min(angle_diff_mod_pi(d, PI / 2.0));
                assert!(off < 0.5f64.to_radians(), "{res}: {d}");
            }
        }
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
