//! How well a map's walls overlap the truth once the map is allowed one small rigid motion.
//!
//! A map built from estimated poses is anchored at the start; a heading error of 0.2 degrees
//! made while turning there rotates all of it, and 80 m away its walls are 0.3 m off although
//! none is doubled. The overlap after the best small rotation (about the start) and translation
//! separates a consistent map from a doubled or bent one; the raw overlap is kept alongside.

use crate::geom::{Pose, Vec2};
use crate::grid::{Bitmap, Cell, GridFrame, Occupancy, OccupancyGrid};

/// Search range of [`aligned_occupied_precision`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct AlignmentConfig {
    pub max_rotation_rad: f64,
    pub rotation_step_rad: f64,
    pub max_translation_m: f64,
    pub translation_step_m: f64,
}

impl Default for AlignmentConfig {
    fn default() -> Self {
        Self {
            max_rotation_rad: 1f64.to_radians(),
            rotation_step_rad: 0.1f64.to_radians(),
            max_translation_m: 0.3,
            translation_step_m: 0.05,
        }
    }
}

/// Fraction of the map's occupied cells within one cell of solid space (not `truth_free`) after
/// the best rigid motion: the map is first moved by `prior` (a map-to-world motion, e.g.
/// [`fit_rigid`] of the estimated trajectory onto the true one; the identity for none), then by
/// the best small motion in the search range (rotation about `pivot`, in the world frame).
/// Returns that fraction and the small motion (`x_m, y_m` translation, `theta_rad` rotation).
/// The raw overlap (no motion at all) is one of the candidates, so the result is never below it.
/// A map without occupied cells scores 1.
pub(crate) fn aligned_occupied_precision(
    map: &OccupancyGrid,
    truth_free: &Bitmap,
    prior: &Pose,
    pivot: Vec2,
    cfg: &AlignmentConfig,
) -> (f64, Pose) {
    let frame = map.frame;
    // Cells within one cell of solid space (outside the grid counts as solid): solid space on
    // the frame padded by a cell on every side, spread along the rows, then the columns.
    let near_solid = near_solid(frame, truth_free);
    let cells: Vec<Vec2> = map
        .data
        .iter()
        .enumerate()
        .filter(|(_, s)| **s == Occupancy::Occupied)
        .map(|(i, _)| frame.world_from_cell(frame.cell_of_index(i)))
        .collect();
    if cells.is_empty() {
        return (1.0, Pose::new(0.0, 0.0, 0.0));
    }
    let raw = cells
        .iter()
        .filter(|q| {
            frame
                .index(frame.cell_from_world(**q))
                .is_none_or(|i| near_solid[i])
        })
        .count();
    let occupied: Vec<Vec2> = cells
        .iter()
        .map(|p| prior.compose(&Pose::new(p.x, p.y, 0.0)).position() - pivot)
        .collect();
    let aligner = Aligner {
        frame,
        near_solid: &near_solid,
        occupied,
        pivot,
    };
    let steps = |max: f64, step: f64| {
        if step > 0.0 && max > 0.0 {
            (max / step).round() as i32
        } else {
            0
        }
    };
    let nr = steps(cfg.max_rotation_rad, cfg.rotation_step_rad);
    let nt = steps(cfg.max_translation_m, cfg.translation_step_m);
    // Coarse pass on a subsample, then the best few candidates on every cell.
    let stride = (aligner.occupied.len() / 4000).max(1);
    let mut scored = aligner.lattice_scores(cfg, nr, nt, stride);
    // Most hits first; ties to the smallest motion, then lattice order (deterministic).
    scored.sort_by_key(|&(h, ir, iy, ix)| {
        (
            std::cmp::Reverse(h),
            ir.abs() + iy.abs() + ix.abs(),
            ir,
            iy,
            ix,
        )
    });
    let identity = Pose::new(0.0, 0.0, 0.0);
    let mut best = (aligner.hits(&identity), identity);
    if raw > best.0 {
        // Only with a prior: the map as it is overlaps better than the prior moves it.
        best = (raw, identity);
    }
    for &(_, ir, iy, ix) in scored.iter().take(8) {
        let pose = Pose::new(
            ix as f64 * cfg.translation_step_m,
            iy as f64 * cfg.translation_step_m,
            ir as f64 * cfg.rotation_step_rad,
        );
        let h = aligner.hits(&pose);
        if h > best.0 {
            best = (h, pose);
        }
    }
    (best.0 as f64 / aligner.occupied.len() as f64, best.1)
}

/// The map's occupied points (moved by the prior, relative to the pivot) and the cells near
/// solid space they are scored against.
struct Aligner<'a> {
    frame: GridFrame,
    near_solid: &'a [bool],
    occupied: Vec<Vec2>,
    pivot: Vec2,
}

impl Aligner<'_> {
    /// The points rotated by `theta_rad` (about the pivot), every `stride`-th.
    fn rotated(&self, theta_rad: f64, stride: usize) -> Vec<Vec2> {
        let (s, c) = theta_rad.sin_cos();
        self.occupied
            .iter()
            .step_by(stride)
            .map(|p| Vec2::new(c * p.x - s * p.y, s * p.x + c * p.y))
            .collect()
    }

    /// How many of the rotated points, translated by `(x_m, y_m)` (and back from the pivot),
    /// fall within one cell of solid space.
    fn count(&self, rotated: &[Vec2], x_m: f64, y_m: f64) -> usize {
        let (frame, near_solid) = (self.frame, self.near_solid);
        let t = self.pivot + Vec2::new(x_m, y_m);
        rotated
            .iter()
            .filter(|r| {
                frame
                    .index(frame.cell_from_world(t + **r))
                    .is_none_or(|i| near_solid[i])
            })
            .count()
    }

    /// How many of the points, moved by `pose`, fall within one cell of solid space.
    fn hits(&self, pose: &Pose) -> usize {
        self.count(&self.rotated(pose.theta_rad, 1), pose.x_m, pose.y_m)
    }

    /// The hits of every `stride`-th point for every motion of the search lattice (`nr`
    /// rotation steps, `nt` translation steps either way): (hits, rotation, y, x steps).
    fn lattice_scores(
        &self,
        cfg: &AlignmentConfig,
        nr: i32,
        nt: i32,
        stride: usize,
    ) -> Vec<(usize, i32, i32, i32)> {
        let (frame, pivot) = (self.frame, self.pivot);
        let mut scored: Vec<(usize, i32, i32, i32)> = Vec::new();
        let (w, h) = (frame.width as i64, frame.height as i64);
        let nl = (2 * nt + 1) as usize;
        // Per point, its cell column (row) for every lattice column (row): a point's cell column
        // depends only on the translation along x, so the lattice's points share them; a point's
        // cells for all the lattice are near one another, so the lattice's counts are summed one
        // point at a time (integers: the order does not matter).
        let mut columns: Vec<usize> = Vec::new();
        let mut rows: Vec<usize> = Vec::new();
        let wu = w as usize;
        let padded = padded_near_solid(self.near_solid, w as usize, h as usize);
        let mut lattice_hits = vec![0u32; nl * nl];
        // As in `count`: the cell of `pivot + (x_m, y_m) + r`, one axis at a time, per lattice step.
        let shifts: Vec<(f64, f64)> = (-nt..=nt)
            .map(|it| {
                let m = it as f64 * cfg.translation_step_m;
                (pivot.x + m, pivot.y + m)
            })
            .collect();
        for ir in -nr..=nr {
            // Rotated once per angle, translated per lattice point.
            let r = self.rotated(ir as f64 * cfg.rotation_step_rad, stride);
            columns.clear();
            rows.clear();
            for p in &r {
                for &(tx, ty) in &shifts {
                    // Indices into `padded`: a column or row outside the frame is its padding.
                    let x = frame.cell_from_world(Vec2::new(tx + p.x, 0.0)).x as i64;
                    columns.push((if (0..w).contains(&x) { x } else { w }) as usize);
                    let y = frame.cell_from_world(Vec2::new(0.0, ty + p.y)).y as i64;
                    rows.push((if (0..h).contains(&y) { y } else { h }) as usize * (wu + 1));
                }
            }
            lattice_hits.fill(0);
            sum_lattice_hits(&padded, &columns, &rows, nl, &mut lattice_hits);
            for (ny, iy) in (-nt..=nt).enumerate() {
                for (nx, ix) in (-nt..=nt).enumerate() {
                    scored.push((lattice_hits[ny * nl + nx] as usize, ir, iy, ix));
                }
            }
        }
        scored
    }
}

/// `near_solid` (of a `wu` x `hu` frame) with one more column and row, solid (outside the
/// frame), as bytes.
fn padded_near_solid(near_solid: &[bool], wu: usize, hu: usize) -> Vec<u8> {
    // `near_solid` with one more column and row, solid (outside the frame), as bytes.
    let mut padded = vec![1u8; (wu + 1) * (hu + 1)];
    for (y, row) in near_solid.chunks_exact(wu.max(1)).enumerate().take(hu) {
        for (p, n) in padded[y * (wu + 1)..y * (wu + 1) + wu].iter_mut().zip(row) {
            *p = *n as u8;
        }
    }
    padded
}

/// Adds to `lattice_hits` (`nl` x `nl`, rows by y) the cells of `padded` at each point's
/// `columns` and `rows` (`nl` of each per point) that are near solid space.
fn sum_lattice_hits(
    padded: &[u8],
    columns: &[usize],
    rows: &[usize],
    nl: usize,
    lattice_hits: &mut [u32],
) {
    for (cols, rws) in columns.chunks_exact(nl).zip(rows.chunks_exact(nl)) {
        // Usually the lattice's columns are consecutive cells of the frame (a translation
        // step of one cell): each row's counts then add a slice (vectorised).
        let first = cols[0];
        let consecutive = cols.iter().enumerate().all(|(k, x)| *x == first + k);
        for (&row, hits) in rws.iter().zip(lattice_hits.chunks_exact_mut(nl)) {
            if consecutive {
                let cells = &padded[row + first..row + first + nl];
                for (n, c) in hits.iter_mut().zip(cells) {
                    *n += *c as u32;
                }
            } else {
                for (&x, n) in cols.iter().zip(hits.iter_mut()) {
                    *n += padded[row + x] as u32;
                }
            }
        }
    }
}

/// For every cell of `frame`, whether it or one of its 8 neighbours is not `true` in
/// `truth_free` (looked up by cell; outside `truth_free`'s grid counts as solid).
fn near_solid(frame: GridFrame, truth_free: &Bitmap) -> Vec<bool> {
    let (w, h) = (frame.width as i32, frame.height as i32);
    let solid = |x: i32, y: i32| truth_free.get(Cell::new(x, y)) != Some(&true);
    // Rows -1..=h: solid at a cell or either of its neighbours along the row.
    let row_near: Vec<bool> = (-1..=h)
        .flat_map(|y| (0..w).map(move |x| solid(x - 1, y) || solid(x, y) || solid(x + 1, y)))
        .collect();
    let wu = w as usize;
    (0..frame.len())
        .map(|i| {
            // Row y of the frame is row y + 1 of `row_near`.
            let (x, y1) = (i % wu, i / wu + 1);
            row_near[(y1 - 1) * wu + x] || row_near[y1 * wu + x] || row_near[(y1 + 1) * wu + x]
        })
        .collect()
}

/// The rigid motion `m` minimising the summed squared distances `|m(from[k]) - to[k]|`
/// (least squares in closed form, Kabsch/Umeyama in 2-D); the identity without points.
pub(crate) fn fit_rigid(from: &[Vec2], to: &[Vec2]) -> Pose {
    let n = from.len().min(to.len());
    if n == 0 {
        return Pose::new(0.0, 0.0, 0.0);
    }
    let mean = |v: &[Vec2]| v[..n].iter().fold(Vec2::zeros(), |a, p| a + p) / n as f64;
    let (cf, ct) = (mean(from), mean(to));
    // The rotation maximising sum(to' . R from'): angle atan2(sum cross, sum dot).
    let (mut dot, mut cross) = (0.0, 0.0);
    for (a, b) in from[..n].iter().zip(&to[..n]) {
        let (a, b) = (a - cf, b - ct);
        dot += a.x * b.x + a.y * b.y;
        cross += a.x * b.y - a.y * b.x;
    }
    let theta = if dot == 0.0 && cross == 0.0 {
        0.0
    } else {
        cross.atan2(dot)
    };
    let (s, c) = theta.sin_cos();
    let t = ct - Vec2::new(c * cf.x - s * cf.y, s * cf.x + c * cf.y);
    Pose::new(t.x, t.y, theta)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{Grid, GridFrame};

    const ID: Pose = Pose::new(0.0, 0.0, 0.0);

    /// [`aligned_occupied_precision`] as it was before `near_solid` was spread along rows and
    /// columns and the coarse search shared the points' cells across the lattice.
    fn aligned_occupied_precision_oracle(
        map: &OccupancyGrid,
        truth_free: &Bitmap,
        prior: &Pose,
        pivot: Vec2,
        cfg: &AlignmentConfig,
    ) -> (f64, Pose) {
        let frame = map.frame;
        // Cells within one cell of solid space (outside the grid counts as solid).
        let near_solid: Vec<bool> = (0..frame.len())
            .map(|i| {
                let c = frame.cell_of_index(i);
                std::iter::once(c)
                    .chain(c.neighbours8())
                    .any(|n| truth_free.get(n) != Some(&true))
            })
            .collect();
        let cells: Vec<Vec2> = map
            .data
            .iter()
            .enumerate()
            .filter(|(_, s)| **s == Occupancy::Occupied)
            .map(|(i, _)| frame.world_from_cell(frame.cell_of_index(i)))
            .collect();
        if cells.is_empty() {
            return (1.0, Pose::new(0.0, 0.0, 0.0));
        }
        let raw = cells
            .iter()
            .filter(|q| {
                frame
                    .index(frame.cell_from_world(**q))
                    .is_none_or(|i| near_solid[i])
            })
            .count();
        let occupied: Vec<Vec2> = cells
            .iter()
            .map(|p| prior.compose(&Pose::new(p.x, p.y, 0.0)).position() - pivot)
            .collect();
        // The points rotated by `theta_rad` (about the pivot), every `stride`-th.
        let rotated = |theta_rad: f64, stride: usize| -> Vec<Vec2> {
            let (s, c) = theta_rad.sin_cos();
            occupied
                .iter()
                .step_by(stride)
                .map(|p| Vec2::new(c * p.x - s * p.y, s * p.x + c * p.y))
                .collect()
        };
        // How many of the rotated points, translated by `(x_m, y_m)` (and back from the pivot),
        // fall within one cell of solid space.
        let count = |rotated: &[Vec2], x_m: f64, y_m: f64| -> usize {
            let t = pivot + Vec2::new(x_m, y_m);
            rotated
                .iter()
                .filter(|r| {
                    frame
                        .index(frame.cell_from_world(t + **r))
                        .is_none_or(|i| near_solid[i])
                })
                .count()
        };
        let hits = |pose: &Pose| count(&rotated(pose.theta_rad, 1), pose.x_m, pose.y_m);
        let steps = |max: f64, step: f64| {
            if step > 0.0 && max > 0.0 {
                (max / step).round() as i32
            } else {
                0
            }
        };
        let nr = steps(cfg.max_rotation_rad, cfg.rotation_step_rad);
        let nt = steps(cfg.max_translation_m, cfg.translation_step_m);
        // Coarse pass on a subsample, then the best few candidates on every cell.
        let stride = (occupied.len() / 4000).max(1);
        let mut scored: Vec<(usize, i32, i32, i32)> = Vec::new();
        for ir in -nr..=nr {
            // Rotated once per angle, translated per lattice point.
            let r = rotated(ir as f64 * cfg.rotation_step_rad, stride);
            for iy in -nt..=nt {
                for ix in -nt..=nt {
                    let (x_m, y_m) = (
                        ix as f64 * cfg.translation_step_m,
                        iy as f64 * cfg.translation_step_m,
                    );
                    scored.push((count(&r, x_m, y_m), ir, iy, ix));
                }
            }
        }
        // Most hits first; ties to the smallest motion, then lattice order (deterministic).
        scored.sort_by_key(|&(h, ir, iy, ix)| {
            (
                std::cmp::Reverse(h),
                ir.abs() + iy.abs() + ix.abs(),
                ir,
                iy,
                ix,
            )
        });
        let identity = Pose::new(0.0, 0.0, 0.0);
        let mut best = (hits(&identity), identity);
        if raw > best.0 {
            // Only with a prior: the map as it is overlaps better than the prior moves it.
            best = (raw, identity);
        }
        for &(_, ir, iy, ix) in scored.iter().take(8) {
            let pose = Pose::new(
                ix as f64 * cfg.translation_step_m,
                iy as f64 * cfg.translation_step_m,
                ir as f64 * cfg.rotation_step_rad,
            );
            let h = hits(&pose);
            if h > best.0 {
                best = (h, pose);
            }
        }
        (best.0 as f64 / occupied.len() as f64, best.1)
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// Random truths and maps (on frames of their own sizes), priors, pivots and searches.
        #[test]
        fn aligned_occupied_precision_equals_its_oracle(
            truth in proptest::collection::vec(proptest::bool::weighted(0.8), 40 * 36),
            occupied in proptest::collection::vec(proptest::bool::weighted(0.15), 40 * 36),
            (tw, th, mw, mh) in (4u32..40, 4u32..36, 4u32..40, 4u32..36),
            res in 0.02f64..0.2,
            prior in (-0.5f64..0.5, -0.5f64..0.5, -0.2f64..0.2),
            pivot in (-1.0f64..3.0, -1.0f64..3.0),
            (rot, rot_step) in (0.0f64..0.05, proptest::prop_oneof![proptest::strategy::Just(0.0), 0.002f64..0.01]),
            (tr, tr_step) in (0.0f64..0.4, proptest::prop_oneof![proptest::strategy::Just(0.0), 0.03f64..0.1]),
        ) {
            let truth_frame = GridFrame::new(Vec2::new(-0.3, 0.2), res, tw, th);
            let truth = Bitmap { frame: truth_frame, data: truth[..truth_frame.len()].to_vec() };
            let frame = GridFrame::new(Vec2::new(-0.3, 0.2), res, mw, mh);
            let mut map = Grid::filled(frame, Occupancy::Unknown);
            for (i, &o) in occupied[..frame.len()].iter().enumerate() {
                if o {
                    map.data[i] = Occupancy::Occupied;
                }
            }
            let prior = Pose::new(prior.0, prior.1, prior.2);
            let pivot = Vec2::new(pivot.0, pivot.1);
            let cfg = AlignmentConfig {
                max_rotation_rad: rot,
                rotation_step_rad: rot_step,
                max_translation_m: tr,
                translation_step_m: tr_step,
            };
            let got = aligned_occupied_precision(&map, &truth, &prior, pivot, &cfg);
            let want = aligned_occupied_precision_oracle(&map, &truth, &prior, pivot, &cfg);
            proptest::prop_assert_eq!(got.0.to_bits(), want.0.to_bits());
            proptest::prop_assert_eq!(got.1, want.1);
            for (c, s) in [(cfg, "given"), (AlignmentConfig::default(), "default")] {
                let got = aligned_occupied_precision(&map, &truth, &ID, pivot, &c);
                let want = aligned_occupied_precision_oracle(&map, &truth, &ID, pivot, &c);
                proptest::prop_assert_eq!(got.0.to_bits(), want.0.to_bits(), "{}", s);
                proptest::prop_assert_eq!(got.1, want.1, "{}", s);
            }
        }
    }

    /// The room maps of the tests above, rotated and shifted within and beyond the search.
    #[test]
    fn aligned_occupied_precision_equals_its_oracle_on_rooms() {
        let pivot = Vec2::new(1.0, 1.0);
        let mut moved = 0;
        for (k, motion) in [
            Pose::new(0.0, 0.0, 0.0),
            Pose::new(0.1, -0.05, 0.8f64.to_radians()),
            Pose::new(-0.17, 0.22, -0.6f64.to_radians()),
            Pose::new(0.3, 0.0, 3f64.to_radians()),
        ]
        .into_iter()
        .enumerate()
        {
            let (map, truth) = room_map(motion, pivot);
            let got = aligned_occupied_precision(&map, &truth, &ID, pivot, &Default::default());
            let want =
                aligned_occupied_precision_oracle(&map, &truth, &ID, pivot, &Default::default());
            assert_eq!(got.0.to_bits(), want.0.to_bits(), "{k}");
            assert_eq!(got.1, want.1, "{k}");
            moved += usize::from(got.1 != ID);
        }
        // The search moved the maps that were moved.
        assert_eq!(moved, 3);
    }

    #[test]
    fn fit_rigid_recovers_a_motion() {
        let m = Pose::new(1.5, -0.7, 0.3);
        let from: Vec<Vec2> = (0..20)
            .map(|k| Vec2::new((k as f64 * 0.7).sin() * 5.0, k as f64 * 0.4))
            .collect();
        let to: Vec<Vec2> = from
            .iter()
            .map(|p| m.compose(&Pose::new(p.x, p.y, 0.0)).position())
            .collect();
        let f = fit_rigid(&from, &to);
        assert!((f.x_m - m.x_m).abs() < 1e-9 && (f.y_m - m.y_m).abs() < 1e-9);
        assert!((f.theta_rad - m.theta_rad).abs() < 1e-9, "{f:?}");
        assert_eq!(fit_rigid(&[], &[]), ID);
        let one = fit_rigid(&[Vec2::new(1.0, 1.0)], &[Vec2::new(2.0, 3.0)]);
        assert_eq!(one, Pose::new(1.0, 2.0, 0.0));
    }

    #[test]
    fn a_prior_aligns_a_map_rotated_beyond_the_search() {
        let pivot = Vec2::new(1.0, 1.0);
        let (_, truth) = room_map(ID, pivot);
        // 5 degrees about the pivot: far outside the default search.
        let motion = Pose::new(0.0, 0.0, 5f64.to_radians());
        let (rotated, _) = room_map(motion, pivot);
        let (raw, _) =
            aligned_occupied_precision(&rotated, &truth, &ID, pivot, &Default::default());
        assert!(raw < 0.8, "{raw}");
        // The map-to-world motion that undoes it: rotate by -5 degrees about the pivot.
        let back = Pose::new(pivot.x, pivot.y, -motion.theta_rad)
            .compose(&Pose::new(-pivot.x, -pivot.y, 0.0));
        let (p, _) =
            aligned_occupied_precision(&rotated, &truth, &back, pivot, &Default::default());
        assert!(p > 0.97, "{p}");
    }

    /// A 6 m x 4 m room (free inside), its walls drawn into a map after a rigid motion.
    fn room_map(motion: Pose, pivot: Vec2) -> (OccupancyGrid, Bitmap) {
        let frame = GridFrame::new(Vec2::new(-1.0, -1.0), 0.05, 160, 120);
        let inside = |p: Vec2| p.x > 0.0 && p.x < 6.0 && p.y > 0.0 && p.y < 4.0;
        let mut truth = Bitmap::filled(frame, false);
        for i in 0..frame.len() {
            truth.data[i] = inside(frame.world_from_cell(frame.cell_of_index(i)));
        }
        let mut map = Grid::filled(frame, Occupancy::Unknown);
        let (s, c) = motion.theta_rad.sin_cos();
        let mut k = 0.0;
        while k <= 20.0 {
            for p in [
                Vec2::new(k * 0.3, 0.0),
                Vec2::new(k * 0.3, 4.0),
                Vec2::new(0.0, k * 0.2),
                Vec2::new(6.0, k * 0.2),
            ] {
                let d = p - pivot;
                let q = pivot
                    + Vec2::new(motion.x_m, motion.y_m)
                    + Vec2::new(c * d.x - s * d.y, s * d.x + c * d.y);
                map.set(frame.cell_from_world(q), Occupancy::Occupied);
            }
            k += 0.02;
        }
        (map, truth)
    }

    #[test]
    fn a_rotated_map_aligns_and_a_right_one_stays() {
        let pivot = Vec2::new(1.0, 1.0);
        let (right, truth) = room_map(Pose::new(0.0, 0.0, 0.0), pivot);
        let (p, motion) =
            aligned_occupied_precision(&right, &truth, &ID, pivot, &Default::default());
        assert!(p > 0.99, "{p}");
        assert_eq!(motion, Pose::new(0.0, 0.0, 0.0));
        let (rotated, _) = room_map(Pose::new(0.1, -0.05, 0.8f64.to_radians()), pivot);
        let none = AlignmentConfig {
            max_rotation_rad: 0.0,
            max_translation_m: 0.0,
            ..Default::default()
        };
        let (raw, _) = aligned_occupied_precision(&rotated, &truth, &ID, pivot, &none);
        let (p, motion) =
            aligned_occupied_precision(&rotated, &truth, &ID, pivot, &Default::default());
        assert!(raw < 0.8, "{raw}");
        assert!(p > 0.97, "{p} {motion:?}");
        assert!(motion.theta_rad < 0.0 && motion.x_m < 0.0, "{motion:?}");
        // Doubled walls cannot be aligned away.
        let mut doubled = right.clone();
        let shifted = room_map(Pose::new(0.4, 0.4, 0.0), pivot).0;
        for (i, s) in shifted.data.iter().enumerate() {
            if *s == Occupancy::Occupied {
                doubled.data[i] = Occupancy::Occupied;
            }
        }
        let (p, _) = aligned_occupied_precision(&doubled, &truth, &ID, pivot, &Default::default());
        assert!(p < 0.85, "{p}");
        // Nothing mapped.
        let empty = Grid::filled(right.frame, Occupancy::Unknown);
        assert_eq!(
            aligned_occupied_precision(&empty, &truth, &ID, pivot, &Default::default()).0,
            1.0
        );
    }
}
