//! Scan-to-map matching: corrects the odometry pose of a scan against the current map.
//!
//! Gauss-Newton on the distance from each hit point to the map's surface: near the surface, to
//! the line through the two nearest mean hit points of occupied cells ([`LogOddsMap::surface`],
//! sub-cell: distances to cell centres are biased by up to half a cell differently on every
//! wall, and the compromise is a rotation), farther away the bilinearly interpolated distance
//! to the nearest occupied cell ([`ObstacleDistance`]), with a Cauchy robust weight (points on walls not yet in
//! the map do not drag the pose) and a Gaussian prior toward the odometry pose, which keeps the
//! estimate put along directions the scan does not constrain (a long featureless corridor).
//! When the result fits poorly, a small correlative search around the prior picks a better
//! starting point and Gauss-Newton runs again. A match that still fits poorly, is based on too
//! few points, or moves the pose too far is rejected: the result is then the prior.
//!
//! Only hit points whose last stretch of ray (at the prior pose) crosses space the map has
//! observed take part. A hit in never-observed space, e.g. the continuation of a wall past the
//! end of the part already mapped (seen while turning), would otherwise be pulled toward the
//! mapped end: a small bias per scan that, while turning in place, rotates the whole map.

use crate::geom::{wrap_angle, Pose, Vec2};
use crate::grid::{Cell, Occupancy};
use crate::mapping::distance_field::ObstacleDistance;
use crate::mapping::log_odds::LogOddsMap;
use crate::scan::Scan;
use nalgebra::{Matrix3, Vector3};

/// Parameters of [`match_scan`]; defaults suit a 0.05 m map and a 6 m laser.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanMatchConfig {
    pub max_iterations: u32,
    /// Stop when a step moves less than this (metres, and radians times 1 m).
    pub convergence_m: f64,
    /// Standard deviation of a point's distance to the map (measurement + discretisation).
    pub point_sigma_m: f64,
    /// Scale of the Cauchy weight: a point this far from the map counts half.
    pub robust_scale_m: f64,
    /// Standard deviations of the odometry prior.
    pub prior_sigma_xy_m: f64,
    pub prior_sigma_theta_rad: f64,
    /// A hit point closer than this to an occupied cell is an inlier (for the score).
    pub inlier_dist_m: f64,
    /// Minimal fraction of hit points that are inliers for the match to be accepted.
    pub min_score: f64,
    /// Minimal number of hit points near the map (closer than the field's cap).
    pub min_points: usize,
    /// Largest accepted correction relative to the prior.
    pub max_correction_m: f64,
    pub max_correction_rad: f64,
    /// Run the correlative search when the first result's score is below this.
    pub search_below_score: f64,
    /// Half-width and step of the correlative search.
    pub search_xy_m: f64,
    pub search_xy_step_m: f64,
    pub search_theta_rad: f64,
    pub search_theta_step_rad: f64,
    /// Use every n-th beam (1 = all).
    pub beam_stride: usize,
    /// A hit point takes part only if the map has observed (free or occupied) some cell on the
    /// last this-many metres of its ray, end included, at the prior pose. 0 keeps every point.
    pub observed_before_hit_m: f64,
}

impl Default for ScanMatchConfig {
    fn default() -> Self {
        Self {
            max_iterations: 20,
            convergence_m: 1e-4,
            point_sigma_m: 0.03,
            robust_scale_m: 0.1,
            prior_sigma_xy_m: 0.05,
            prior_sigma_theta_rad: 0.05,
            inlier_dist_m: 0.075,
            min_score: 0.5,
            min_points: 20,
            max_correction_m: 0.5,
            max_correction_rad: 0.3,
            search_below_score: 0.8,
            search_xy_m: 0.15,
            search_xy_step_m: 0.05,
            search_theta_rad: 4f64.to_radians(),
            search_theta_step_rad: 1f64.to_radians(),
            beam_stride: 1,
            observed_before_hit_m: 0.15,
        }
    }
}

/// The outcome of [`match_scan`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatchResult {
    /// The corrected pose, or the prior when the match was rejected.
    pub pose: Pose,
    /// Fraction of hit points that are inliers at the matched pose (before rejection).
    pub score: f64,
    /// Gauss-Newton iterations run (all passes).
    pub iterations: u32,
    /// Whether the correlative search ran.
    pub searched: bool,
    pub accepted: bool,
}

/// Matches `scan` (taken around `prior`) against `map` and the obstacle distance field of its
/// occupancy (`field`, kept by the caller).
pub fn match_scan(
    field: &ObstacleDistance,
    map: &LogOddsMap,
    prior: &Pose,
    scan: &Scan,
    cfg: &ScanMatchConfig,
) -> MatchResult {
    let stride = cfg.beam_stride.max(1);
    let grid = &map.occupancy;
    let (s, c) = prior.theta_rad.sin_cos();
    let res = grid.frame.resolution_m;
    let front_steps = (cfg.observed_before_hit_m / res.max(1e-9)).ceil().max(0.0) as usize;
    let observed = |p: Vec2| {
        if cfg.observed_before_hit_m <= 0.0 {
            return true;
        }
        let turned = Vec2::new(c * p.x - s * p.y, s * p.x + c * p.y);
        let q = prior.position() + turned;
        let known = |at: Vec2| {
            let cell = grid.frame.cell_from_world(at);
            grid.get(cell).is_some_and(|o| *o != Occupancy::Unknown)
        };
        // The point itself first (`q - back * 0.0`, `back` being finite, is `q` but for the sign
        // of a zero, which changes no cell), as good as always known; the steps back along the
        // beam only when it is not.
        if known(q) {
            return true;
        }
        let back = turned / p.norm().max(1e-9) * res;
        (1..=front_steps).any(|k| known(q - back * k as f64))
    };
    // (Made at the most it can hold: collected from the filters, it grew about seven times.)
    let mut points: Vec<Vec2> = Vec::with_capacity(scan.ranges_m.len().div_ceil(stride));
    BEAM_DIRECTIONS.with_borrow_mut(|dirs| {
        let dirs = dirs.of(scan);
        points.extend(
            (0..scan.ranges_m.len())
                .step_by(stride)
                .filter(|&i| {
                    scan.is_hit(i) && scan.ranges_m[i].is_finite() && scan.ranges_m[i] > 0.0
                })
                .map(|i| dirs[i] * scan.ranges_m[i])
                .filter(|p| observed(*p)),
        )
    });
    let rejected = |score, iterations, searched| MatchResult {
        pose: *prior,
        score,
        iterations,
        searched,
        accepted: false,
    };
    if points.is_empty() || field.frame.is_empty() {
        return rejected(0.0, 0, false);
    }
    let (pose, score, near, iterations, searched) = FITS.with_borrow_mut(|fits| {
        fits.begin(points.len());
        let (mut pose, mut iterations) = gauss_newton(field, map, fits, prior, prior, &points, cfg);
        let (mut score, mut near) = evaluate(field, &pose, &points, cfg);
        let mut searched = false;
        if score < cfg.search_below_score {
            searched = true;
            let start = correlative_search(field, prior, &points, cfg);
            let (p2, it2) = gauss_newton(field, map, fits, prior, &start, &points, cfg);
            iterations += it2;
            let (s2, n2) = evaluate(field, &p2, &points, cfg);
            if s2 > score {
                (pose, score, near) = (p2, s2, n2);
            }
        }
        (pose, score, near, iterations, searched)
    });
    let d = prior.between(&pose);
    let ok = score >= cfg.min_score
        && near >= cfg.min_points
        && d.x_m.hypot(d.y_m) <= cfg.max_correction_m
        && d.theta_rad.abs() <= cfg.max_correction_rad
        && pose.x_m.is_finite()
        && pose.y_m.is_finite()
        && pose.theta_rad.is_finite();
    if !ok {
        return rejected(score, iterations, searched);
    }
    MatchResult {
        pose,
        score,
        iterations,
        searched,
        accepted: true,
    }
}

fn gauss_newton(
    field: &ObstacleDistance,
    map: &LogOddsMap,
    fits: &mut SurfaceFits,
    prior: &Pose,
    start: &Pose,
    points: &[Vec2],
    cfg: &ScanMatchConfig,
) -> (Pose, u32) {
    // Levenberg-Marquardt: a step that raises the cost is undone and the damping raised. A
    // step's cost decides; its normal equations are formed only for a step kept and followed
    // by another (not for a step undone, nor for the last).
    let mut terms = Vec::with_capacity(points.len());
    let mut x = Vector3::new(start.x_m, start.y_m, start.theta_rad);
    let mut cost = residuals(field, map, fits, prior, &x, points, cfg, &mut terms);
    let (mut h, mut g) = normal_equations(&terms, prior, &x, cfg);
    let mut lambda = 1e-4;
    let mut iterations = 0;
    while iterations < cfg.max_iterations {
        iterations += 1;
        let damped = h + Matrix3::from_diagonal(&h.diagonal()) * lambda;
        let Some(step) = damped.cholesky().map(|ch| ch.solve(&(-g))) else {
            break;
        };
        if !step.iter().all(|v| v.is_finite()) {
            break;
        }
        let x_new = x + step;
        let cost_new = residuals(field, map, fits, prior, &x_new, points, cfg, &mut terms);
        if cost_new <= cost {
            (x, cost) = (x_new, cost_new);
            lambda = (lambda * 0.1).max(1e-6);
            if step[0].hypot(step[1]) < cfg.convergence_m && step[2].abs() < cfg.convergence_m
                || iterations == cfg.max_iterations
            {
                break;
            }
            (h, g) = normal_equations(&terms, prior, &x, cfg);
        } else {
            lambda *= 10.0;
            if lambda > 1e4 {
                break;
            }
        }
    }
    (Pose::new(x[0], x[1], wrap_angle(x[2])), iterations)
}

/// A point's term in the normal equations: the point (in the sensor's frame), its distance to
/// the map's surface and that distance's gradient (in the map's frame).
#[derive(Debug, Clone, Copy)]
struct Term {
    p: Vec2,
    r: f64,
    grad: Vec2,
}

/// The prior's information (inverse variances of x, y and theta).
fn prior_information(cfg: &ScanMatchConfig) -> Vector3<f64> {
    Vector3::new(
        1.0 / cfg.prior_sigma_xy_m.powi(2),
        1.0 / cfg.prior_sigma_xy_m.powi(2),
        1.0 / cfg.prior_sigma_theta_rad.powi(2),
    )
}

/// The pose `x`'s difference to the prior (the angle wrapped).
fn prior_error(prior: &Pose, x: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(
        x[0] - prior.x_m,
        x[1] - prior.y_m,
        wrap_angle(x[2] - prior.theta_rad),
    )
}

/// The robust cost at pose `x`, prior included; `terms` gets the terms of the points that
/// inform the normal equations (those closer to the map than the field's cap), in point order.
#[allow(clippy::too_many_arguments)]
fn residuals(
    field: &ObstacleDistance,
    map: &LogOddsMap,
    fits: &mut SurfaceFits,
    prior: &Pose,
    x: &Vector3<f64>,
    points: &[Vec2],
    cfg: &ScanMatchConfig,
    terms: &mut Vec<Term>,
) -> f64 {
    let res = field.frame.resolution_m;
    let cap_m = field.cap_cells as f64 * res;
    let inv_var = 1.0 / (cfg.point_sigma_m * cfg.point_sigma_m);
    let c2 = cfg.robust_scale_m * cfg.robust_scale_m;
    let prior_info = prior_information(cfg);
    let e = prior_error(prior, x);
    let mut cost = 0.5 * e.dot(&prior_info.component_mul(&e));
    let (s, c) = x[2].sin_cos();
    terms.clear();
    for (k, p) in points.iter().enumerate() {
        let q = Vec2::new(x[0] + c * p.x - s * p.y, x[1] + s * p.x + c * p.y);
        let (r, grad) = match fits.residual_of_point(map, k, q) {
            Some(v) => v,
            None => {
                let (d_cells, grad) = field.sample(q);
                (d_cells * res, grad * res)
            }
        };
        // Cauchy cost; points at the cap contribute a constant (no information).
        cost += 0.5 * inv_var * c2 * (r.min(cap_m) * r.min(cap_m) / c2).ln_1p();
        if r.abs() >= cap_m - 0.5 * res {
            continue;
        }
        terms.push(Term { p: *p, r, grad });
    }
    cost
}

/// Gauss-Newton normal equations `(H, g)` at pose `x`, prior included, of the points' `terms`
/// there ([`residuals`]).
fn normal_equations(
    terms: &[Term],
    prior: &Pose,
    x: &Vector3<f64>,
    cfg: &ScanMatchConfig,
) -> (Matrix3<f64>, Vector3<f64>) {
    let inv_var = 1.0 / (cfg.point_sigma_m * cfg.point_sigma_m);
    let c2 = cfg.robust_scale_m * cfg.robust_scale_m;
    let prior_info = prior_information(cfg);
    // H's upper triangle (row by row; H is symmetric: `j[a] * j[b]` is `j[b] * j[a]`, bit for
    // bit), each entry summed in point order as `h += j * j^T * w` would.
    let mut hu = [prior_info[0], 0.0, 0.0, prior_info[1], 0.0, prior_info[2]];
    let mut g = prior_info.component_mul(&prior_error(prior, x));
    let (s, c) = x[2].sin_cos();
    for &Term { p, r, grad } in terms {
        let dq_dtheta = Vec2::new(-s * p.x - c * p.y, c * p.x - s * p.y);
        let j = Vector3::new(grad.x, grad.y, grad.dot(&dq_dtheta));
        let w = inv_var / (1.0 + r * r / c2);
        for (k, (a, b)) in [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]
            .into_iter()
            .enumerate()
        {
            hu[k] += j[a] * j[b] * w;
        }
        g += j * (w * r);
    }
    let h = Matrix3::new(
        hu[0], hu[1], hu[2], //
        hu[1], hu[3], hu[4], //
        hu[2], hu[4], hu[5],
    );
    (h, g)
}

/// The unit vectors of a scan's beams in the sensor's frame, `(cos a, sin a)` of each beam's
/// angle, kept for the scans of the same angles (a run's laser): the same values as computed
/// afresh, without a sine and a cosine per beam and scan.
#[derive(Default)]
struct BeamDirections {
    /// The first beam's angle and the increment (their bits) and the number of beams.
    key: (u64, u64, usize),
    dirs: Vec<Vec2>,
}

impl BeamDirections {
    fn of(&mut self, scan: &Scan) -> &[Vec2] {
        let key = (
            scan.angle_min_rad.to_bits(),
            scan.angle_increment_rad.to_bits(),
            scan.ranges_m.len(),
        );
        if self.key != key || self.dirs.len() != key.2 {
            self.dirs.clear();
            self.dirs.extend((0..key.2).map(|i| {
                let a = scan.beam_angle_rad(i);
                Vec2::new(a.cos(), a.sin())
            }));
            self.key = key;
        }
        &self.dirs
    }
}

thread_local! {
    /// The beams' unit vectors of the thread's last scan matched.
    static BEAM_DIRECTIONS: std::cell::RefCell<BeamDirections> =
        std::cell::RefCell::new(BeamDirections::default());
}

/// Around a cell: the signed distance of a point `q` in it to the surface near it and its
/// gradient (unit). The mean hit points of the occupied cells around the cell (3 x 3) are fitted
/// with a line (principal axis); when they lie on one, the distance is to that line, otherwise
/// (a corner, a single point) to the nearest of them. The fit depends on the cell only.
#[derive(Debug, Clone, Copy, PartialEq)]
enum SurfaceFit {
    /// No occupied cell with hits around.
    Nothing,
    /// The mean hit points lie on the line through `mean` of normal `nrm`.
    Line { mean: Vec2, nrm: Vec2 },
    /// A corner or a single point: the nearest of the mean hit points (kept beside the fit)
    /// is found for each point.
    Points,
}

impl SurfaceFit {
    /// The fit of the mean hit points `pts` around a cell (in row order).
    fn of_points(pts: &[Vec2], res: f64) -> Self {
        let n = pts.len();
        if n == 0 {
            return SurfaceFit::Nothing;
        }
        if n >= 2 {
            let mean = pts.iter().fold(Vec2::zeros(), |s, p| s + p) / n as f64;
            let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
            for p in pts {
                let d = p - mean;
                sxx += d.x * d.x;
                sxy += d.x * d.y;
                syy += d.y * d.y;
            }
            let (sxx, sxy, syy) = (sxx / n as f64, sxy / n as f64, syy / n as f64);
            let half_tr = 0.5 * (sxx + syy);
            let disc = (0.25 * (sxx - syy).powi(2) + sxy * sxy).sqrt();
            let (l_max, l_min) = (half_tr + disc, half_tr - disc);
            // A line: spread along it (at least ~a third of a cell), almost none across.
            if l_max >= (0.15 * res).powi(2) && l_min <= (0.3 * res).powi(2) {
                // Eigenvector of the larger eigenvalue is the line's direction.
                let t = if sxy.abs() > 1e-15 {
                    Vec2::new(l_max - syy, sxy)
                } else if sxx >= syy {
                    Vec2::new(1.0, 0.0)
                } else {
                    Vec2::new(0.0, 1.0)
                };
                let nrm = Vec2::new(-t.y, t.x) / t.norm();
                return SurfaceFit::Line { mean, nrm };
            }
        }
        SurfaceFit::Points
    }

    /// The residual of `q`, with `pts` the mean hit points the fit was made of.
    fn residual(&self, pts: &[Vec2], q: Vec2) -> Option<(f64, Vec2)> {
        match *self {
            SurfaceFit::Nothing => None,
            SurfaceFit::Line { mean, nrm } => {
                let r = nrm.dot(&(q - mean));
                Some(if r < 0.0 { (-r, -nrm) } else { (r, nrm) })
            }
            SurfaceFit::Points => {
                let a = nearest_point(pts, q)?;
                let d = q - a;
                let r = d.norm();
                Some(if r > 1e-9 {
                    (r, d / r)
                } else {
                    (0.0, Vec2::zeros())
                })
            }
        }
    }
}

/// The first of `pts` nearest `q` (by squared distance, as `min_by` with `total_cmp` orders
/// them), `None` if there are none. The points are finite (mean hit points), so the squared
/// distances are all numbers `>= 0`, where `total_cmp` is `<`, or (`q` not finite) all the same
/// infinity or NaN, where both keep the first: a plain loop, without the total order's bit
/// manipulations.
#[inline]
fn nearest_point(pts: &[Vec2], q: Vec2) -> Option<Vec2> {
    let (&first, rest) = pts.split_first()?;
    let (mut best, mut best_d2) = (first, (first - q).norm_squared());
    for &a in rest {
        let d2 = (a - q).norm_squared();
        if d2 < best_d2 {
            (best, best_d2) = (a, d2);
        }
    }
    Some(best)
}

/// A slot of [`SurfaceFits`]: the cell, the match it was fitted in, its fit, and how many mean
/// hit points around the cell it was made of (kept beside the slots: a line's residual, most
/// residuals, reads only the slot).
#[derive(Debug, Clone, Copy)]
struct FitSlot {
    cell: Cell,
    generation: u64,
    fit: SurfaceFit,
    n: u8,
}

/// The surface fits of the cells a scan's points fall in, kept while the scan is matched (the
/// map does not change meanwhile; a scan's points fall in the same cells from one step of the
/// optimisation to the next). Direct-mapped: a cell whose slot another holds is fitted again.
/// The slots are kept from one match to the next (the thread's [`FITS`]) but serve only the
/// match they were filled in (its `generation`): nothing needs clearing.
struct SurfaceFits {
    generation: u64,
    slots: Vec<FitSlot>,
    /// The mean hit points of each slot's fit (the first `n`).
    points: Vec<[Vec2; 9]>,
    /// Per point of the match's scan, the cell it last fell in and that cell's fit, unless a
    /// corner's (which needs its points): read in point order, where the slots are scattered.
    last: Vec<(Cell, SurfaceFit)>,
}

/// A cell no point falls in: [`SurfaceFits`]'s points before their first.
const NO_CELL: Cell = Cell::new(i32::MIN, i32::MIN);

/// Slots of [`SurfaceFits`] (a power of two).
const SURFACE_FIT_SLOTS: usize = 1024;

thread_local! {
    /// The slots of the thread's matches.
    static FITS: std::cell::RefCell<SurfaceFits> =
        std::cell::RefCell::new(SurfaceFits::new());
}

impl SurfaceFits {
    fn new() -> Self {
        Self::with_slots(SURFACE_FIT_SLOTS)
    }

    /// With `n` slots (a power of two).
    fn with_slots(n: usize) -> Self {
        let empty = FitSlot {
            cell: NO_CELL,
            generation: 0,
            fit: SurfaceFit::Nothing,
            n: 0,
        };
        Self {
            // (No slot serves generation 0's match: `begin` is called before any.)
            generation: 0,
            slots: vec![empty; n],
            points: vec![[Vec2::zeros(); 9]; n],
            last: Vec::new(),
        }
    }

    /// Starts a match of `points` points (the map may have changed since the last): every
    /// slot is stale, no point has a cell yet.
    fn begin(&mut self, points: usize) {
        self.generation += 1;
        self.last.clear();
        self.last.resize(points, (NO_CELL, SurfaceFit::Nothing));
    }

    /// The residual of the match's point `k` at `q` and its gradient; `None` when no occupied
    /// cell with hits is next to `q`'s cell. The point's last cell's fit when `q` is still in
    /// that cell, else the fit of `q`'s cell's slot.
    #[inline]
    fn residual_of_point(&mut self, map: &LogOddsMap, k: usize, q: Vec2) -> Option<(f64, Vec2)> {
        let c0 = map.frame.cell_from_world(q);
        let (cell, fit) = self.last[k];
        if cell == c0 && fit != SurfaceFit::Points {
            return fit.residual(&[], q);
        }
        let i = self.slot_of(map, c0);
        let (fit, n) = (self.slots[i].fit, self.slots[i].n as usize);
        self.last[k] = (c0, fit);
        fit.residual(&self.points[i][..n], q)
    }

    /// The slot of cell `c0`, fitted for this match.
    #[inline]
    fn slot_of(&mut self, map: &LogOddsMap, c0: Cell) -> usize {
        let k = (c0.x as u32).wrapping_mul(0x9e37_79b9) ^ (c0.y as u32).wrapping_mul(0x85eb_ca6b);
        let mask = self.slots.len() - 1;
        let i = (k >> 16) as usize & mask;
        let slot = &mut self.slots[i];
        if slot.cell != c0 || slot.generation != self.generation {
            let pts = &mut self.points[i];
            let n = map.surface_points_around(c0, pts);
            slot.cell = c0;
            slot.generation = self.generation;
            slot.n = n as u8;
            slot.fit = SurfaceFit::of_points(&pts[..n], map.frame.resolution_m);
        }
        i
    }
}

/// (inlier fraction, number of points near the map).
fn evaluate(
    field: &ObstacleDistance,
    pose: &Pose,
    points: &[Vec2],
    cfg: &ScanMatchConfig,
) -> (f64, usize) {
    let res = field.frame.resolution_m;
    let cap_m = field.cap_cells as f64 * res;
    let (s, c) = pose.theta_rad.sin_cos();
    let mut inliers = 0;
    let mut near = 0;
    for p in points {
        let q = Vec2::new(pose.x_m + c * p.x - s * p.y, pose.y_m + s * p.x + c * p.y);
        let r = field.sample(q).0 * res;
        if r < cfg.inlier_dist_m {
            inliers += 1;
        }
        if r < cap_m - 0.5 * res {
            near += 1;
        }
    }
    (inliers as f64 / points.len().max(1) as f64, near)
}

/// Brute-force search of the pose minimising the summed robust cost on a small lattice.
fn correlative_search(
    field: &ObstacleDistance,
    prior: &Pose,
    points: &[Vec2],
    cfg: &ScanMatchConfig,
) -> Pose {
    let res = field.frame.resolution_m;
    let c2 = cfg.robust_scale_m * cfg.robust_scale_m;
    let nxy = if cfg.search_xy_step_m > 0.0 {
        (cfg.search_xy_m / cfg.search_xy_step_m).round() as i32
    } else {
        0
    };
    let nth = if cfg.search_theta_step_rad > 0.0 {
        (cfg.search_theta_rad / cfg.search_theta_step_rad).round() as i32
    } else {
        0
    };
    // Subsample to about 60 points: the search only needs a starting point.
    let stride = (points.len() / 60).max(1);
    let mut best = (f64::INFINITY, *prior);
    for it in -nth..=nth {
        let th = prior.theta_rad + it as f64 * cfg.search_theta_step_rad;
        let (s, c) = th.sin_cos();
        let rotated: Vec<Vec2> = points
            .iter()
            .step_by(stride)
            .map(|p| Vec2::new(c * p.x - s * p.y, s * p.x + c * p.y))
            .collect();
        for iy in -nxy..=nxy {
            for ix in -nxy..=nxy {
                let t = Vec2::new(
                    prior.x_m + ix as f64 * cfg.search_xy_step_m,
                    prior.y_m + iy as f64 * cfg.search_xy_step_m,
                );
                let cost: f64 = rotated
                    .iter()
                    .map(|p| {
                        let r = field.get(field.frame.cell_from_world(t + p)) as f64 * res;
                        (r * r / c2).ln_1p()
                    })
                    .sum();
                // Strictly better only: ties keep the earlier (lattice order) pose.
                if cost < best.0 {
                    best = (cost, Pose::new(t.x, t.y, wrap_angle(th)));
                }
            }
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GridFrame;
    use crate::mapping::log_odds::{LogOddsConfig, LogOddsMap};

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(512))]

        /// The nearest of a corner's points is the one `min_by` with `total_cmp` picks: the first
        /// of those equally near (points on a coarse lattice, `q` often halfway between two), and
        /// for a `q` not finite.
        #[test]
        fn nearest_point_is_min_by_total_cmp(
            pts in proptest::collection::vec((-4i32..4, -4i32..4), 0..10),
            q in (-40i32..40, -40i32..40),
            odd in 0usize..4,
        ) {
            let pts: Vec<Vec2> =
                pts.iter().map(|&(x, y)| Vec2::new(x as f64 * 0.25, y as f64 * 0.25)).collect();
            let q = match odd {
                0 => Vec2::new(f64::NAN, q.1 as f64),
                1 => Vec2::new(-f64::NAN, f64::INFINITY),
                _ => Vec2::new(q.0 as f64 * 0.125, q.1 as f64 * 0.125),
            };
            let reference = pts
                .iter()
                .copied()
                .min_by(|a, b| (a - q).norm_squared().total_cmp(&(b - q).norm_squared()));
            let bits = |v: Option<Vec2>| v.map(|p| (p.x.to_bits(), p.y.to_bits()));
            proptest::prop_assert_eq!(bits(nearest_point(&pts, q)), bits(reference));
        }
    }

    /// A world of axis-aligned boxes, ray cast exactly.
    struct BoxWorld(Vec<[f64; 4]>);

    impl BoxWorld {
        fn cast(&self, o: Vec2, dir: Vec2, max_range_m: f64) -> f64 {
            let mut best = max_range_m;
            for b in &self.0 {
                let (mut t0, mut t1) = (0.0f64, best);
                for (lo, hi, oo, d) in [(b[0], b[2], o.x, dir.x), (b[1], b[3], o.y, dir.y)] {
                    if d.abs() < 1e-12 {
                        if oo < lo || oo > hi {
                            t0 = f64::INFINITY;
                        }
                        continue;
                    }
                    let (a, c) = ((lo - oo) / d, (hi - oo) / d);
                    t0 = t0.max(a.min(c));
                    t1 = t1.min(a.max(c));
                }
                if t0 <= t1 && t0 < best {
                    best = t0;
                }
            }
            best
        }

        fn scan(&self, pose: &Pose) -> Scan {
            let n = 181;
            let angle_min_rad = -std::f64::consts::FRAC_PI_2;
            let inc = std::f64::consts::PI / (n - 1) as f64;
            let ranges_m = (0..n)
                .map(|i| {
                    let a = pose.theta_rad + angle_min_rad + i as f64 * inc;
                    self.cast(pose.position(), Vec2::new(a.cos(), a.sin()), 6.0)
                })
                .collect();
            Scan {
                angle_min_rad,
                angle_increment_rad: inc,
                max_range_m: 6.0,
                ranges_m,
            }
        }
    }

    fn wall(x0: f64, y0: f64, x1: f64, y1: f64) -> [f64; 4] {
        [x0, y0, x1, y1]
    }

    fn room() -> BoxWorld {
        BoxWorld(vec![
            wall(0.0, 0.0, 8.0, 0.1),
            wall(0.0, 5.9, 8.0, 6.0),
            wall(0.0, 0.0, 0.1, 6.0),
            wall(7.9, 0.0, 8.0, 6.0),
            wall(3.0, 2.0, 3.6, 2.4), // a box
            wall(5.5, 3.0, 5.6, 5.9), // a partial wall
        ])
    }

    fn build_map(
        world: &BoxWorld,
        frame: GridFrame,
        poses: &[Pose],
    ) -> (ObstacleDistance, LogOddsMap) {
        let mut map = LogOddsMap::new(frame);
        for p in poses {
            map.insert_scan(p, &world.scan(p), &LogOddsConfig::default());
        }
        (ObstacleDistance::from_grid(&map.occupancy, 8), map)
    }

    /// A scan's hit points in the sensor's frame, every beam that hit.
    fn hit_points(scan: &Scan) -> Vec<Vec2> {
        (0..scan.ranges_m.len())
            .filter(|&i| scan.is_hit(i))
            .map(|i| {
                let a = scan.beam_angle_rad(i);
                Vec2::new(a.cos(), a.sin()) * scan.ranges_m[i]
            })
            .collect()
    }

    /// The frame the room is mapped in.
    fn room_frame() -> GridFrame {
        GridFrame::new(Vec2::new(-1.013, -0.987), 0.05, 200, 160)
    }

    /// Eight poses the room is mapped from, across it, turning.
    fn room_mapping_poses() -> Vec<Pose> {
        (0..8)
            .map(|k| {
                Pose::new(
                    1.5 + 0.6 * k as f64,
                    1.2 + 0.3 * (k % 3) as f64,
                    0.8 * k as f64,
                )
            })
            .collect()
    }

    /// The residual as first written, cell by cell for every point.
    fn surface_residual_reference(map: &LogOddsMap, q: Vec2) -> Option<(f64, Vec2)> {
        let c0 = map.frame.cell_from_world(q);
        let mut pts = [Vec2::zeros(); 9];
        let mut n = 0;
        for dy in -1..=1 {
            for dx in -1..=1 {
                if let Some(a) = map.surface_point(Cell::new(c0.x + dx, c0.y + dy)) {
                    pts[n] = a;
                    n += 1;
                }
            }
        }
        if n == 0 {
            return None;
        }
        let pts = &pts[..n];
        let res = map.frame.resolution_m;
        if n >= 2 {
            let mean = pts.iter().fold(Vec2::zeros(), |s, p| s + p) / n as f64;
            let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
            for p in pts {
                let d = p - mean;
                sxx += d.x * d.x;
                sxy += d.x * d.y;
                syy += d.y * d.y;
            }
            let (sxx, sxy, syy) = (sxx / n as f64, sxy / n as f64, syy / n as f64);
            let half_tr = 0.5 * (sxx + syy);
            let disc = (0.25 * (sxx - syy).powi(2) + sxy * sxy).sqrt();
            let (l_max, l_min) = (half_tr + disc, half_tr - disc);
            if l_max >= (0.15 * res).powi(2) && l_min <= (0.3 * res).powi(2) {
                let t = if sxy.abs() > 1e-15 {
                    Vec2::new(l_max - syy, sxy)
                } else if sxx >= syy {
                    Vec2::new(1.0, 0.0)
                } else {
                    Vec2::new(0.0, 1.0)
                };
                let nrm = Vec2::new(-t.y, t.x) / t.norm();
                let r = nrm.dot(&(q - mean));
                return Some(if r < 0.0 { (-r, -nrm) } else { (r, nrm) });
            }
        }
        let a = pts
            .iter()
            .copied()
            .min_by(|a, b| (a - q).norm_squared().total_cmp(&(b - q).norm_squared()))?;
        let d = q - a;
        let r = d.norm();
        Some(if r > 1e-9 {
            (r, d / r)
        } else {
            (0.0, Vec2::zeros())
        })
    }

    #[test]
    fn kept_surface_fits_give_the_residuals_computed_afresh() {
        // A mapped room (walls, a box's corners, a partial wall's end); points near its walls and
        // all over it and off the frame, each cell asked many times (more cells than slots: slots
        // are shared). Then more scans change the map: a new match's fits are made afresh.
        let world = room();
        let frame = room_frame();
        let poses: Vec<Pose> = (0..9)
            .map(|k| {
                Pose::new(
                    1.5 + 0.6 * k as f64,
                    1.0 + 0.7 * (k % 4) as f64,
                    0.9 * k as f64,
                )
            })
            .collect();
        // Many slots (as in a match) and few (cells evicting one another all the time).
        let mut many = SurfaceFits::new();
        let mut few = SurfaceFits::with_slots(4);
        let (mut near_line, mut near_points) = (0, 0);
        for (m, mapped) in [3, 6, 9].into_iter().enumerate() {
            let (_, map) = build_map(&world, frame, &poses[..mapped]);
            // (One point, asked at a new place each time: its last cell is mostly another.)
            many.begin(1);
            few.begin(1);
            for round in 0..3 {
                for k in 0..10_000 {
                    let u = ((k * 7919 + round * 104_729 + m) % 20_011) as f64 / 20_011.0;
                    let v = ((k * 6271 + round * 3 + m) % 19_997) as f64 / 19_997.0;
                    let b = world.0[k % world.0.len()];
                    let q = if k % 4 == 0 {
                        Vec2::new(-1.5 + 11.0 * u, -1.5 + 9.0 * v)
                    } else {
                        Vec2::new(
                            b[0] - 0.15 + u * (b[2] - b[0] + 0.3),
                            b[1] - 0.15 + v * (b[3] - b[1] + 0.3),
                        )
                    };
                    let bits = |v: Option<(f64, Vec2)>| {
                        v.map(|(r, g)| (r.to_bits(), g.x.to_bits(), g.y.to_bits()))
                    };
                    let want = bits(surface_residual_reference(&map, q));
                    let got = |fits: &mut SurfaceFits| bits(fits.residual_of_point(&map, 0, q));
                    assert_eq!(got(&mut many), want, "{mapped} scans, {q:?}");
                    assert_eq!(got(&mut few), want, "{mapped} scans, {q:?}");
                    let mut pts = [Vec2::zeros(); 9];
                    let c0 = map.frame.cell_from_world(q);
                    let n = map.surface_points_around(c0, &mut pts);
                    match SurfaceFit::of_points(&pts[..n], map.frame.resolution_m) {
                        SurfaceFit::Line { .. } => near_line += 1,
                        SurfaceFit::Points => near_points += 1,
                        SurfaceFit::Nothing => {}
                    }
                }
            }
        }
        assert!(
            near_line > 1000 && near_points > 100,
            "{near_line} {near_points}"
        );
    }

    #[test]
    fn residuals_by_point_are_those_of_their_cells() {
        // A scan's points at poses a step apart, as in a match (most stay in their cell, some
        // cross into the next), against the residuals computed afresh; the room mapped from
        // more poses for each next match. Both ways through are taken: a point's last cell and
        // fit, and the slots (a new cell, or a corner's fit).
        let world = room();
        let poses = room_mapping_poses();
        let mut fits = SurfaceFits::new();
        let (mut kept, mut looked_up) = (0, 0);
        for mapped in [2, 5, 8] {
            let (_, map) = build_map(&world, room_frame(), &poses[..mapped]);
            for at in &poses {
                let scan = world.scan(at);
                let points = hit_points(&scan);
                fits.begin(points.len());
                for step in 0..6 {
                    let d = 0.004 * step as f64;
                    let (s, c) = (at.theta_rad + 0.3 * d).sin_cos();
                    for (k, p) in points.iter().enumerate() {
                        let q = Vec2::new(
                            at.x_m + d + c * p.x - s * p.y,
                            at.y_m - d + s * p.x + c * p.y,
                        );
                        let (cell, fit) = fits.last[k];
                        if cell == map.frame.cell_from_world(q) && fit != SurfaceFit::Points {
                            kept += 1;
                        } else {
                            looked_up += 1;
                        }
                        let bits = |v: Option<(f64, Vec2)>| {
                            v.map(|(r, g)| (r.to_bits(), g.x.to_bits(), g.y.to_bits()))
                        };
                        assert_eq!(
                            bits(fits.residual_of_point(&map, k, q)),
                            bits(surface_residual_reference(&map, q)),
                            "{mapped} poses mapped, point {k} at {q:?}"
                        );
                    }
                }
            }
        }
        assert!(
            kept > 10 * 1000 && looked_up > 2 * 1000,
            "{kept} {looked_up}"
        );
    }

    /// [`residuals`] and [`normal_equations`] as first written, in one pass over the points:
    /// the cost, and `H` summed as whole matrices, `j * j^T * w`.
    fn normal_equations_reference(
        field: &ObstacleDistance,
        map: &LogOddsMap,
        prior: &Pose,
        x: &Vector3<f64>,
        points: &[Vec2],
        cfg: &ScanMatchConfig,
    ) -> (Matrix3<f64>, Vector3<f64>, f64) {
        let res = field.frame.resolution_m;
        let cap_m = field.cap_cells as f64 * res;
        let inv_var = 1.0 / (cfg.point_sigma_m * cfg.point_sigma_m);
        let c2 = cfg.robust_scale_m * cfg.robust_scale_m;
        let prior_info = Vector3::new(
            1.0 / cfg.prior_sigma_xy_m.powi(2),
            1.0 / cfg.prior_sigma_xy_m.powi(2),
            1.0 / cfg.prior_sigma_theta_rad.powi(2),
        );
        let mut h = Matrix3::from_diagonal(&prior_info);
        let e = Vector3::new(
            x[0] - prior.x_m,
            x[1] - prior.y_m,
            wrap_angle(x[2] - prior.theta_rad),
        );
        let mut g = prior_info.component_mul(&e);
        let mut cost = 0.5 * e.dot(&prior_info.component_mul(&e));
        let (s, c) = x[2].sin_cos();
        for p in points {
            let q = Vec2::new(x[0] + c * p.x - s * p.y, x[1] + s * p.x + c * p.y);
            let (r, grad) = match surface_residual_reference(map, q) {
                Some(v) => v,
                None => {
                    let (d_cells, grad) = field.sample(q);
                    (d_cells * res, grad * res)
                }
            };
            cost += 0.5 * inv_var * c2 * (r.min(cap_m) * r.min(cap_m) / c2).ln_1p();
            if r.abs() >= cap_m - 0.5 * res {
                continue;
            }
            let dq_dtheta = Vec2::new(-s * p.x - c * p.y, c * p.x - s * p.y);
            let j = Vector3::new(grad.x, grad.y, grad.dot(&dq_dtheta));
            let w = inv_var / (1.0 + r * r / c2);
            h += j * j.transpose() * w;
            g += j * (w * r);
        }
        (h, g, cost)
    }

    #[test]
    fn normal_equations_are_the_whole_matrices_summed() {
        // The room mapped from a few poses; a scan from others, its points at poses around
        // where it was taken (near the walls, off them, some off the map).
        let world = room();
        let (field, map) = build_map(&world, room_frame(), &room_mapping_poses());
        let cfg = ScanMatchConfig::default();
        let mut fits = SurfaceFits::new();
        let mut informed = 0;
        for k in 0..40 {
            let at = Pose::new(
                1.2 + 0.15 * k as f64,
                0.8 + 0.11 * (k % 9) as f64,
                0.4 * k as f64,
            );
            let scan = world.scan(&at);
            let points = hit_points(&scan);
            fits.begin(points.len());
            for d in [0.0, 0.02, -0.07, 0.3] {
                let x = Vector3::new(at.x_m + d, at.y_m - 0.5 * d, at.theta_rad + d);
                let mut terms = Vec::new();
                let cost = residuals(&field, &map, &mut fits, &at, &x, &points, &cfg, &mut terms);
                let (h, g) = normal_equations(&terms, &at, &x, &cfg);
                let got = (h, g, cost);
                let want = normal_equations_reference(&field, &map, &at, &x, &points, &cfg);
                let bits = |(h, g, c): (Matrix3<f64>, Vector3<f64>, f64)| {
                    (h.map(f64::to_bits), g.map(f64::to_bits), c.to_bits())
                };
                assert_eq!(bits(got), bits(want), "pose {k}, offset {d}");
                informed += (got.0 != Matrix3::from_diagonal(&got.0.diagonal())) as usize;
            }
        }
        assert!(informed > 100, "{informed}");
    }

    #[test]
    fn beam_directions_kept_are_those_computed_afresh() {
        // Scans of other angles and other numbers of beams in turn, and back: each time the
        // bits of (cos a, sin a) of every beam.
        let scan = |first: f64, step: f64, n: usize| Scan {
            angle_min_rad: first,
            angle_increment_rad: step,
            max_range_m: 6.0,
            ranges_m: vec![1.0; n],
        };
        let mut kept = BeamDirections::default();
        for s in [
            scan(-1.5, 0.017, 181),
            scan(-1.5, 0.017, 181),
            scan(-1.5, 0.017, 90),
            scan(-1.5, 0.0171, 90),
            scan(0.25, 0.0171, 90),
            scan(-1.5, 0.017, 181),
            scan(0.0, 0.0, 3),
            scan(0.0, 0.0, 0),
        ] {
            let want: Vec<(u64, u64)> = (0..s.ranges_m.len())
                .map(|i| {
                    let a = s.beam_angle_rad(i);
                    (a.cos().to_bits(), a.sin().to_bits())
                })
                .collect();
            let got: Vec<(u64, u64)> = kept
                .of(&s)
                .iter()
                .map(|d| (d.x.to_bits(), d.y.to_bits()))
                .collect();
            assert_eq!(
                got,
                want,
                "{} beams from {}",
                s.ranges_m.len(),
                s.angle_min_rad
            );
        }
    }

    #[test]
    fn recovers_perturbed_pose_in_a_room() {
        let world = room();
        let frame = room_frame();
        let (field, grid) = build_map(&world, frame, &room_mapping_poses());
        let truths = [
            Pose::new(2.0, 1.0, 0.3),
            Pose::new(4.5, 3.5, 2.0),
            Pose::new(6.5, 1.5, -2.5),
            Pose::new(1.2, 4.5, -0.7),
        ];
        let offsets = [
            (0.15, 0.0, 4.0),
            (-0.1, 0.11, -4.0),
            (0.0, -0.15, 2.5),
            (0.1, 0.1, -3.0),
        ];
        for truth in &truths {
            let scan = world.scan(truth);
            for &(dx, dy, dth) in &offsets {
                let prior = Pose::new(
                    truth.x_m + dx,
                    truth.y_m + dy,
                    truth.theta_rad + f64::to_radians(dth),
                );
                let r = match_scan(&field, &grid, &prior, &scan, &ScanMatchConfig::default());
                let err = truth.between(&r.pose);
                assert!(r.accepted, "{truth:?} {prior:?} {r:?}");
                assert!(err.x_m.hypot(err.y_m) < 0.025, "{truth:?} {prior:?} {r:?}");
                assert!(err.theta_rad.abs() < 0.5f64.to_radians(), "{truth:?} {r:?}");
            }
        }
    }

    #[test]
    fn corridor_does_not_drift_along_its_axis() {
        // 40 m long, 2 m wide corridor; the ends are beyond the laser's range.
        let world = BoxWorld(vec![wall(0.0, 0.0, 40.0, 0.1), wall(0.0, 2.1, 40.0, 2.2)]);
        let frame = GridFrame::new(Vec2::new(-1.013, -0.987), 0.05, 840, 80);
        let poses: Vec<Pose> = (0..12)
            .map(|k| Pose::new(14.0 + k as f64, 1.1, 0.0))
            .collect();
        let (field, grid) = build_map(&world, frame, &poses);
        let truth = Pose::new(20.0, 1.1, 0.0);
        let scan = world.scan(&truth);
        for along in [-0.15, 0.1, 0.15] {
            let prior = Pose::new(truth.x_m + along, truth.y_m + 0.08, 0.03);
            let r = match_scan(&field, &grid, &prior, &scan, &ScanMatchConfig::default());
            let err_along = r.pose.x_m - truth.x_m;
            // Discretisation of the walls can pull by about a quarter of a cell.
            assert!(err_along.abs() <= along.abs() + 0.015, "{along}: {r:?}");
            if r.accepted {
                assert!((r.pose.y_m - truth.y_m).abs() < 0.025, "{r:?}");
                assert!(r.pose.theta_rad.abs() < 0.5f64.to_radians(), "{r:?}");
            }
        }
    }

    #[test]
    fn rejects_without_map_or_when_the_scan_does_not_fit() {
        let world = room();
        let frame = room_frame();
        let empty = ObstacleDistance::new(frame, 8);
        let prior = Pose::new(2.0, 1.0, 0.3);
        let r = match_scan(
            &empty,
            &LogOddsMap::new(frame),
            &prior,
            &world.scan(&prior),
            &ScanMatchConfig::default(),
        );
        assert!(!r.accepted);
        assert_eq!(r.pose, prior);
        // A map of a different world.
        let other = BoxWorld(vec![wall(0.0, 0.0, 0.1, 6.0), wall(1.0, 3.0, 7.0, 3.1)]);
        let (field, grid) = build_map(
            &other,
            frame,
            &[Pose::new(4.0, 1.5, 1.57), Pose::new(3.0, 1.0, 3.0)],
        );
        let r = match_scan(
            &field,
            &grid,
            &prior,
            &world.scan(&prior),
            &ScanMatchConfig::default(),
        );
        assert!(!r.accepted, "{r:?}");
        assert_eq!(r.pose, prior);
    }

    /// Turning in place against a map of one scan, with an exact prior: the match must stay put
    /// whatever the wall surfaces' offset inside their cells (cell-centre distances pulled by
    /// 0.2-0.6 degrees per scan, which rotated whole maps).
    #[test]
    fn turning_in_place_has_no_rotation_bias() {
        let world = room();
        for offset_m in [0.0, 0.013, 0.025, 0.037] {
            let origin = Vec2::new(-1.0 + offset_m, -1.0 + offset_m);
            let frame = GridFrame::new(origin, 0.05, 200, 160);
            let p0 = Pose::new(4.0, 1.2, std::f64::consts::FRAC_PI_2);
            let (field, map) = build_map(&world, frame, &[p0]);
            for k in 1..4 {
                let truth = Pose::new(4.0, 1.2, std::f64::consts::FRAC_PI_2 - 0.1 * k as f64);
                let cfg = ScanMatchConfig {
                    prior_sigma_xy_m: 0.001,
                    prior_sigma_theta_rad: 0.0045,
                    ..Default::default()
                };
                let r = match_scan(&field, &map, &truth, &world.scan(&truth), &cfg);
                let err = wrap_angle(r.pose.theta_rad - truth.theta_rad);
                assert!(r.accepted, "{offset_m} {k}: {r:?}");
                assert!(err.abs() < 0.1f64.to_radians(), "{offset_m} {k}: {r:?}");
            }
        }
    }
}
