//! The laser: a scan's beams cast together against the building's wall segments within range.

use std::sync::Arc;

use parry2d::math::Point as PPoint;
use parry2d::shape::{Polyline, SharedShape};
use rand::Rng;
use rand_distr::{Distribution, Normal};

use crate::geom::{Pose, Segment, Vec2};
use crate::scan::Scan;

/// The laser as in the paper: 180 degree field of view, 6 m range. Defaults: 181 beams (one per
/// degree), 10 scans per second, Gaussian range noise with 0.01 m standard deviation.
#[derive(Debug, Clone, PartialEq)]
pub struct LaserConfig {
    pub fov_rad: f64,
    pub max_range_m: f64,
    pub beams: usize,
    pub rate_hz: f64,
    pub range_noise_sd_m: f64,
}

impl Default for LaserConfig {
    fn default() -> Self {
        Self {
            fov_rad: std::f64::consts::PI,
            max_range_m: 6.0,
            beams: 181,
            rate_hz: 10.0,
            range_noise_sd_m: 0.01,
        }
    }
}

impl LaserConfig {
    /// One scan from `pose`. Beams that hit nothing within range report exactly `max_range_m`.
    pub fn scan(&self, walls: &Walls, pose: &Pose, rng: &mut impl Rng) -> Scan {
        self.scan_among(walls, &[], pose, rng)
    }

    /// One scan from `pose` among the walls and the discs `others` (centre, radius m: the other
    /// robots' bodies), each beam ending at the nearest of them.
    pub fn scan_among(
        &self,
        walls: &Walls,
        others: &[(Vec2, f64)],
        pose: &Pose,
        rng: &mut impl Rng,
    ) -> Scan {
        self.scan_marked(walls, others, pose, rng).0
    }

    /// [`LaserConfig::scan_among`], and per beam whether it ended on one of `others` (as a
    /// laser reads a robot's retro-reflective marker by its return's intensity).
    pub fn scan_marked(
        &self,
        walls: &Walls,
        others: &[(Vec2, f64)],
        pose: &Pose,
        rng: &mut impl Rng,
    ) -> (Scan, Vec<bool>) {
        let n = self.beams.max(1);
        let inc = if n > 1 {
            self.fov_rad / (n - 1) as f64
        } else {
            0.0
        };
        let angle_min = if n > 1 { -self.fov_rad / 2.0 } else { 0.0 };
        let noise = (self.range_noise_sd_m > 0.0)
            .then(|| Normal::new(0.0, self.range_noise_sd_m).ok())
            .flatten();
        let origin = pose.position();
        let first_rad = pose.theta_rad + angle_min;
        let dirs: Vec<Vec2> = (0..n)
            .map(|i| {
                let a = first_rad + i as f64 * inc;
                Vec2::new(a.cos(), a.sin())
            })
            .collect();
        let mut hits = walls.cast_fan(origin, first_rad, inc, &dirs, self.max_range_m);
        let mut on_robot = vec![false; hits.len()];
        for &(centre, radius_m) in others {
            for ((hit, dir), marked) in hits.iter_mut().zip(&dirs).zip(&mut on_robot) {
                if let Some(r) = ray_disc(origin, *dir, centre, radius_m)
                    .filter(|&r| r <= self.max_range_m && hit.is_none_or(|h| r < h))
                {
                    *hit = Some(r);
                    *marked = true;
                }
            }
        }
        let ranges_m = hits
            .into_iter()
            .map(|hit| match hit {
                Some(r) => {
                    let e = noise.map_or(0.0, |d| d.sample(rng));
                    // A noisy hit never reads as "no hit".
                    (r + e).clamp(0.0, self.max_range_m * (1.0 - 1e-9))
                }
                None => self.max_range_m,
            })
            .collect();
        (
            Scan {
                angle_min_rad: angle_min,
                angle_increment_rad: inc,
                max_range_m: self.max_range_m,
                ranges_m,
            },
            on_robot,
        )
    }
}

/// Distance along the unit direction `dir` from `origin` to where it enters the disc of
/// `centre` and `radius_m` (`None`: it misses it, or starts inside it or past it).
fn ray_disc(origin: Vec2, dir: Vec2, centre: Vec2, radius_m: f64) -> Option<f64> {
    let to = centre - origin;
    let along = to.dot(&dir);
    let off2 = to.norm_squared() - along * along;
    let r2 = radius_m * radius_m;
    if along <= 0.0 || off2 > r2 || to.norm_squared() <= r2 {
        return None;
    }
    Some(along - (r2 - off2).sqrt())
}

/// The building's walls: their segments under a uniform grid, for the laser, and as one parry2d
/// polyline, for the robot's collisions.
///
/// The laser casts a scan's beams together ([`Walls::cast_fan`]): every segment within range of
/// the origin is found once through the grid and tested against the beams its angular extent
/// covers (with a margin), in `f64`. A beam's range is the least distance at which it crosses a
/// segment, whatever the order the segments are tested in, so it is the same as testing every
/// segment of the building ([`cast_exhaustive`]).
#[derive(Clone)]
pub struct Walls {
    shape: Option<Arc<Polyline>>,
    index: Arc<WallIndex>,
}

impl std::fmt::Debug for Walls {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Walls")
            .field("segments", &self.index.segments.len())
            .finish()
    }
}

/// The segments and, per grid cell, the segments that touch it.
#[derive(Debug, Default)]
struct WallIndex {
    segments: Vec<Segment>,
    origin: Vec2,
    cell_m: f64,
    width: i32,
    height: i32,
    /// Segment ids of cell `i` (row-major): `ids[starts[i]..starts[i + 1]]`.
    starts: Vec<u32>,
    ids: Vec<u32>,
    /// Per cell: whether every segment in it is axis-aligned (rasters' walls are), so that a
    /// beam crosses them where its computed distance says ([`WallIndex::cell_is_hidden`]).
    aligned: Vec<bool>,
}

/// Most cells of the wall grid (cells grow beyond 1 m to stay under it).
const MAX_GRID_CELLS: f64 = 1_000_000.0;

/// Most (segment, cell) entries of the wall grid (4 bytes each): with more (many long walls
/// crossing a large building), the cells are made larger until the entries fit. Counted before
/// anything is allocated.
const MAX_ENTRIES: u64 = 16_000_000;

/// Angle (rad) added on both sides of a segment's angular extent when choosing the beams to test
/// against it: far more than the error of [`atan2_approx`] and the rounding of the angles, far
/// less than a beam's spacing.
const BEAM_MARGIN_RAD: f64 = 1e-3;
// (Well above three times the approximation's bound, 3e-4 rad.)
const _: () = assert!(3.0 * 3e-4 < BEAM_MARGIN_RAD);

/// Angle (rad) added on both sides of a grid cell's angular extent when asking whether a beam
/// points into it ([`WallIndex::cell_arc`]): more than a segment's margin and the
/// approximate angles' errors of both, so that every segment tested against a beam is still
/// found in some cell.
const CELL_MARGIN_RAD: f64 = 0.01;
const _: () = assert!(BEAM_MARGIN_RAD + 4.0 * 3e-4 < CELL_MARGIN_RAD);

/// Cells holding fewer segments are searched without asking whether a beam points into them.
const CULL_MIN_SEGMENTS: usize = 4;

/// How much nearer (m) than a cell every beam pointing into it must have found a wall for the
/// cell to be skipped ([`WallIndex::cell_is_hidden`]): far more than the rounding of the
/// distances.
const HIDDEN_MARGIN_M: f64 = 1e-6;

/// `y.atan2(x)` within 3e-4 rad (a polynomial on the octant; tested against `atan2`), for
/// choosing beams only: the beams a segment is tested against may be a few more than it spans.
#[inline]
fn atan2_approx(y: f64, x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, PI};
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = if ax < ay { (ax, ay) } else { (ay, ax) };
    if hi == 0.0 {
        return 0.0;
    }
    let a = lo / hi;
    let s = a * a;
    let mut r = ((-0.046_496_474_9 * s + 0.159_314_22) * s - 0.327_622_764) * s * a + a;
    if ay > ax {
        r = FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = PI - r;
    }
    if y < 0.0 {
        -r
    } else {
        r
    }
}

impl WallIndex {
    fn new(segments: &[Segment]) -> Self {
        Self::with_limit(segments, MAX_ENTRIES)
    }

    /// The index with at most `max_entries` entries, or the coarsest grid (one cell) if even
    /// that has more.
    fn with_limit(segments: &[Segment], max_entries: u64) -> Self {
        let finite = |s: &Segment| {
            s.a.x.is_finite() && s.a.y.is_finite() && s.b.x.is_finite() && s.b.y.is_finite()
        };
        let segments: Vec<Segment> = segments.iter().copied().filter(finite).collect();
        if segments.is_empty() {
            return Self::default();
        }
        let (mut lo, mut hi) = (segments[0].a, segments[0].a);
        for s in &segments {
            for p in [s.a, s.b] {
                lo = Vec2::new(lo.x.min(p.x), lo.y.min(p.y));
                hi = Vec2::new(hi.x.max(p.x), hi.y.max(p.y));
            }
        }
        let (ex, ey) = ((hi.x - lo.x).max(1.0), (hi.y - lo.y).max(1.0));
        let mut cell_m = (ex * ey / MAX_GRID_CELLS).sqrt().max(1.0);
        let mut index = loop {
            let width = (ex / cell_m).floor() as i32 + 1;
            let height = (ey / cell_m).floor() as i32 + 1;
            let index = Self {
                segments: Vec::new(),
                origin: lo,
                cell_m,
                width,
                height,
                starts: Vec::new(),
                ids: Vec::new(),
                aligned: Vec::new(),
            };
            let mut entries = 0u64;
            for s in &segments {
                index.cells_of(s, |x0, x1, _| entries += (x1 - x0 + 1) as u64);
                if entries > max_entries {
                    break;
                }
            }
            if entries <= max_entries || (width == 1 && height == 1) {
                break index;
            }
            cell_m *= 2.0;
        };
        let cells = (index.width * index.height) as usize;
        let mut counts = vec![0u32; cells + 1];
        for s in &segments {
            index.cells_of(s, |x0, x1, y| {
                for x in x0..=x1 {
                    counts[(y * index.width + x) as usize + 1] += 1;
                }
            });
        }
        for i in 0..cells {
            counts[i + 1] += counts[i];
        }
        let mut next = counts.clone();
        let mut ids = vec![0u32; counts[cells] as usize];
        let mut aligned = vec![true; cells];
        for (k, s) in segments.iter().enumerate() {
            let along_axis = s.a.x == s.b.x || s.a.y == s.b.y;
            index.cells_of(s, |x0, x1, y| {
                for x in x0..=x1 {
                    let c = (y * index.width + x) as usize;
                    ids[next[c] as usize] = k as u32;
                    next[c] += 1;
                    aligned[c] &= along_axis;
                }
            });
        }
        index.segments = segments;
        index.starts = counts;
        index.ids = ids;
        index.aligned = aligned;
        index
    }

    /// The grid cells segment `s` touches, as runs `x0..=x1` of row `y`, row by row: per row, the
    /// cells of the part of the segment within the row's band, both widened by a millionth of a
    /// cell so that rounding loses none (a cell or two more do no harm: the laser's answer does
    /// not depend on the segments tested beyond those in range). Every point of `s` lies in one
    /// of them ([`Self::cell_of`]).
    fn cells_of(&self, s: &Segment, mut run: impl FnMut(i32, i32, i32)) {
        let eps = self.cell_m * 1e-6;
        let y0 = self.row_of(s.a.y.min(s.b.y) - eps);
        let y1 = self.row_of(s.a.y.max(s.b.y) + eps);
        let dy = s.b.y - s.a.y;
        for y in y0..=y1 {
            let (band_lo, band_hi) = (
                self.origin.y + y as f64 * self.cell_m - eps,
                self.origin.y + (y + 1) as f64 * self.cell_m + eps,
            );
            let (xa, xb) = if dy == 0.0 {
                (s.a.x, s.b.x)
            } else {
                let ta = ((band_lo - s.a.y) / dy).clamp(0.0, 1.0);
                let tb = ((band_hi - s.a.y) / dy).clamp(0.0, 1.0);
                let x = |t: f64| s.a.x + t * (s.b.x - s.a.x);
                (x(ta), x(tb))
            };
            run(
                self.column_of(xa.min(xb) - eps),
                self.column_of(xa.max(xb) + eps),
                y,
            );
        }
    }

    /// The arc of directions (radians from the first beam of a fan, `lo <= hi`, as for
    /// [`beams_in_arc`]) that a grid cell, whose lower corner is at `(x0, y0)` from the origin,
    /// spans; `None` for a cell the origin is in or near (every beam may point into it).
    /// A cell no beam points into (within [`CELL_MARGIN_RAD`] of its arc) holds no part of a
    /// segment that a beam could cross (the parts it crosses lie in cells a beam points into,
    /// which hold the segment too): the fan skips it, and casts the same segments against the
    /// same beams.
    #[inline]
    fn cell_arc(&self, (x0, y0): (f64, f64), first_wrapped: f64) -> Option<(f64, f64)> {
        let (x1, y1) = (x0 + self.cell_m, y0 + self.cell_m);
        // Within a twentieth of a cell of it (or in it), the corners' angles could span nearly
        // half a turn or more; farther, less than 169 degrees.
        let near = 0.05 * self.cell_m;
        if x0 - near <= 0.0 && x1 + near >= 0.0 && y0 - near <= 0.0 && y1 + near >= 0.0 {
            return None;
        }
        // The corners' angles from the first beam; the cell spans less than half a turn, so
        // the smallest arc holding them is the one between the least and greatest turn from the
        // first corner.
        let a0 = wrap_once(atan2_approx(y0, x0) - first_wrapped);
        let (mut lo, mut hi) = (0.0f64, 0.0f64);
        for (x, y) in [(x1, y0), (x0, y1), (x1, y1)] {
            let d = wrap_once(wrap_once(atan2_approx(y, x) - first_wrapped) - a0);
            lo = lo.min(d);
            hi = hi.max(d);
        }
        Some((a0 + lo, a0 + hi))
    }

    /// Whether every beam of `beams` (ranges of indices) has already found a wall nearer than
    /// grid cell `c` (whose lower corner is at `(x0, y0)` from the origin) by a micrometre, and
    /// the cell's segments are all axis-aligned: then no segment in the cell can bring a beam
    /// nearer, and the cell is skipped without changing the scan.
    ///
    /// Why: with an axis-aligned segment (one of the direction's components exactly 0), each
    /// cross product of [`crossing`] is one rounded product, so the computed distance `t` is
    /// within a few ulps of the distance to where the beam meets the segment's line, and the
    /// test of where along the segment rounds by a few ulps of the distances involved (at most
    /// 1e-9 m for coordinates within 1000 km), whatever the beam's angle to the segment: the
    /// point at `t` lies in one of the segment's cells (grown by a millionth of a cell), at least
    /// as far as that cell. A segment that would set a beam's distance is thus in a cell nearer
    /// than that distance, which is not skipped. (A slanted segment's crossing rounds by the
    /// distance over the beam's sine to it, unbounded for a beam nearly along it: cells holding
    /// one are searched.)
    fn cell_is_hidden(
        &self,
        c: usize,
        (x0, y0): (f64, f64),
        mut beams: impl Iterator<Item = (usize, usize)>,
        best: &[f64],
    ) -> bool {
        if !self.aligned[c] {
            return false;
        }
        let (x1, y1) = (x0 + self.cell_m, y0 + self.cell_m);
        let (dx, dy) = (x0.max(-x1).max(0.0), y0.max(-y1).max(0.0));
        let distance = (dx * dx + dy * dy).sqrt();
        beams.all(|(i0, i1)| {
            best[i0..=i1]
                .iter()
                .all(|&b| b + HIDDEN_MARGIN_M < distance)
        })
    }

    /// The grid cell of `p`, clamped to the grid.
    fn cell_of(&self, p: Vec2) -> [i32; 2] {
        [self.column_of(p.x), self.row_of(p.y)]
    }

    /// The grid column of abscissa `x`, clamped to the grid.
    fn column_of(&self, x: f64) -> i32 {
        (((x - self.origin.x) / self.cell_m).floor().max(0.0) as i32).min(self.width - 1)
    }

    /// The grid row of ordinate `y`, clamped to the grid.
    fn row_of(&self, y: f64) -> i32 {
        (((y - self.origin.y) / self.cell_m).floor().max(0.0) as i32).min(self.height - 1)
    }
}

thread_local! {
    /// Per segment: the cast that last tested it (a segment is tested once per cast, however
    /// many cells of the query square hold it), and the last cast's number. Kept per thread
    /// between casts; the numbers of different indexes' casts never coincide.
    static TESTED: std::cell::RefCell<(Vec<u32>, u32)> =
        const { std::cell::RefCell::new((Vec::new(), 0)) };
}

#[cfg(test)]
thread_local! {
    /// Cells skipped as hidden ([`WallIndex::cell_is_hidden`]), counted for the tests.
    static HIDDEN_CELLS: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// Where the ray from the origin along `d` crosses the segment from `a` to `a + e` (`a` relative
/// to the origin), if at a distance in `[0, max_range_m]`: `t` with `t d = a + s e`, `s` in
/// `[0, 1]` (parallel segments are never crossed).
#[inline]
fn crossing(a: Vec2, e: Vec2, cross_ae: f64, d: Vec2, max_range_m: f64) -> Option<f64> {
    let den = d.x * e.y - d.y * e.x;
    let sn = a.x * d.y - a.y * d.x;
    let (s_ok, t_ok) = if den > 0.0 {
        (sn >= 0.0 && sn <= den, cross_ae >= 0.0)
    } else if den < 0.0 {
        (sn <= 0.0 && sn >= den, cross_ae <= 0.0)
    } else {
        (false, false)
    };
    if !(s_ok && t_ok) {
        return None;
    }
    let t = cross_ae / den;
    (t <= max_range_m).then_some(t)
}

/// The definition [`Walls::cast_fan`] implements: every segment tested against every beam.
pub fn cast_exhaustive(
    segments: &[Segment],
    origin: Vec2,
    dirs: &[Vec2],
    max_range_m: f64,
) -> Vec<Option<f64>> {
    dirs.iter()
        .map(|&d| {
            segments
                .iter()
                .filter_map(|s| {
                    let (a, e) = (s.a - origin, s.b - s.a);
                    crossing(a, e, a.x * e.y - a.y * e.x, d, max_range_m)
                })
                .reduce(f64::min)
        })
        .collect()
}

/// `v` in `(-2 pi, 2 pi]` (a difference of two angles in `[-pi, pi]`) brought to about
/// `(-pi, pi]` by one turn at most, without the library's rounding (only the beams a segment is
/// tested against depend on it, with a margin, and beams are tried a turn either way).
#[inline]
fn wrap_once(v: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    if v > PI {
        v - TAU
    } else if v <= -PI {
        v + TAU
    } else {
        v
    }
}

/// The beams `ceil(x0)..=floor(x1)` of `0..n` (`n > 0`), if any, by conversions to integers
/// rather than the library's `ceil` and `floor` (function calls on the baseline x86-64). (The
/// conversions through i64: the values converted lie in `0..n`, where the signed conversions
/// give what the unsigned ones do, each in one instruction rather than a sequence.)
#[inline]
fn beam_range(x0: f64, x1: f64, n: usize) -> Option<(usize, usize)> {
    let last = (n - 1) as i64 as f64;
    if !(x1 >= 0.0 && x0 <= last) {
        return None;
    }
    let i0 = if x0 <= 0.0 {
        0
    } else {
        let t = x0 as i64;
        (t + i64::from((t as f64) < x0)) as usize
    };
    let i1 = if x1 >= last {
        n - 1
    } else {
        x1 as i64 as usize
    };
    (i0 <= i1).then_some((i0, i1))
}

/// The beams (`n` of them, `beams_per_rad` a radian from the first: the increment's reciprocal)
/// pointing within `margin` of the arc from `lo` to `hi` (radians from the first beam,
/// `lo <= hi`, `lo` in about `(-pi, pi]`), as ranges of beam indices: the arc taken as it is and
/// a turn either way. (A product rather than a quotient by the increment: the two differ by an
/// ulp or so, far inside the margin.)
#[inline]
fn beams_in_arc(
    lo: f64,
    hi: f64,
    margin: f64,
    beams_per_rad: f64,
    n: usize,
) -> impl Iterator<Item = (usize, usize)> {
    [-1.0, 0.0, 1.0].into_iter().filter_map(move |turn| {
        let shift = turn * std::f64::consts::TAU;
        beam_range(
            (lo + shift - margin) * beams_per_rad,
            (hi + shift + margin) * beams_per_rad,
            n,
        )
    })
}

/// The `t`-th of `o`, `o - 1`, `o + 1`, `o - 2`, `o + 2`, ...
#[inline]
fn outwards(o: i32, t: i32) -> i32 {
    if t % 2 == 1 {
        o - (t + 1) / 2
    } else {
        o + t / 2
    }
}

/// `v` in `(-pi, pi]`.
fn wrap_pi(v: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let w = v - TAU * (v / TAU).round();
    if w <= -PI {
        w + TAU
    } else if w > PI {
        w - TAU
    } else {
        w
    }
}

impl Walls {
    pub fn new(segments: &[Segment]) -> Self {
        let index = Arc::new(WallIndex::new(segments));
        if index.segments.is_empty() {
            return Self { shape: None, index };
        }
        let mut vertices = Vec::with_capacity(index.segments.len() * 2);
        let mut indices = Vec::with_capacity(index.segments.len());
        for (i, s) in index.segments.iter().enumerate() {
            vertices.push(PPoint::new(s.a.x as f32, s.a.y as f32));
            vertices.push(PPoint::new(s.b.x as f32, s.b.y as f32));
            indices.push([2 * i as u32, 2 * i as u32 + 1]);
        }
        Self {
            shape: Some(Arc::new(Polyline::new(vertices, Some(indices)))),
            index,
        }
    }

    pub fn segment_count(&self) -> usize {
        self.index.segments.len()
    }

    pub(super) fn shared_shape(&self) -> Option<SharedShape> {
        self.shape.as_ref().map(|s| SharedShape::new((**s).clone()))
    }

    /// Distance along the unit direction `dir` from `origin` to the first wall, if within
    /// `max_range_m`.
    pub fn cast(&self, origin: Vec2, dir: Vec2, max_range_m: f64) -> Option<f64> {
        self.cast_fan(origin, dir.y.atan2(dir.x), 0.0, &[dir], max_range_m)[0]
    }

    /// The distances from `origin` to the first wall along each of `dirs` (unit vectors), if
    /// within `max_range_m`. Beam `i` must point at about `first_rad + i * increment_rad`
    /// (within a microradian; the angles only choose which segments to test against a beam).
    pub fn cast_fan(
        &self,
        origin: Vec2,
        first_rad: f64,
        increment_rad: f64,
        dirs: &[Vec2],
        max_range_m: f64,
    ) -> Vec<Option<f64>> {
        let mut best = vec![f64::INFINITY; dirs.len()];
        let ix = &*self.index;
        let ok = |v: f64| v.is_finite();
        if ix.segments.is_empty()
            || dirs.is_empty()
            || !(ok(origin.x) && ok(origin.y) && ok(first_rad) && ok(increment_rad))
            || !(max_range_m >= 0.0 && max_range_m.is_finite())
        {
            return vec![None; dirs.len()];
        }
        let n = dirs.len();
        let first_wrapped = wrap_pi(first_rad);
        let r = max_range_m;
        let [qx0, qy0] = ix.cell_of(origin - Vec2::new(r, r));
        let [qx1, qy1] = ix.cell_of(origin + Vec2::new(r, r));
        // (A segment within range touches the square around the origin; one clamped to the
        // grid's edge cells is tested, and rejected by its distance, if it does not.)
        let reach2 = {
            let reach = r * (1.0 + 1e-9) + 1e-9;
            reach * reach
        };
        let fan = Fan {
            ix,
            origin,
            first_wrapped,
            increment_rad,
            beams_per_rad: 1.0 / increment_rad,
            dirs,
            max_range_m,
            reach2,
            n,
        };
        TESTED.with(|t| {
            let mut t = t.borrow_mut();
            let (tested, last) = &mut *t;
            if tested.len() < ix.segments.len() {
                tested.resize(ix.segments.len(), 0);
            }
            if *last == u32::MAX {
                tested.fill(0);
                *last = 0;
            }
            *last += 1;
            let cast = *last;
            let cull = n > 1 && increment_rad > 0.0;
            // The square's rows outwards from the origin's (its row, the one below, above, two
            // below, ...), and each row's cells outwards from the origin's column: the cells
            // between a cell and the origin come before it, so that the walls nearby are found
            // before the cells they hide are reached.
            let [ox, oy] = ix.cell_of(origin);
            let (rx, ry) = ((ox - qx0).max(qx1 - ox), (oy - qy0).max(qy1 - oy));
            for t in 0..=2 * ry {
                let cy = outwards(oy, t);
                if cy < qy0 || cy > qy1 {
                    continue;
                }
                for u in 0..=2 * rx {
                    let cx = outwards(ox, u);
                    if cx < qx0 || cx > qx1 {
                        continue;
                    }
                    let c = (cy * ix.width + cx) as usize;
                    let held = (ix.starts[c + 1] - ix.starts[c]) as usize;
                    if held == 0 {
                        continue;
                    }
                    // (Asked only of a cell of several segments: the question costs about as
                    // much as two segments; a raster's cells hold tens of short ones.)
                    if cull && held >= CULL_MIN_SEGMENTS && fan.cell_is_culled(c, cx, cy, &best) {
                        continue;
                    }
                    let ids = &ix.ids[ix.starts[c] as usize..ix.starts[c + 1] as usize];
                    fan.test_segments(ids, tested, cast, &mut best);
                }
            }
        });
        best.into_iter()
            .map(|t| t.is_finite().then_some(t))
            .collect()
    }
}

/// A fan of beams being cast by [`Walls::cast_fan`]: its origin, beams and range.
struct Fan<'a> {
    ix: &'a WallIndex,
    origin: Vec2,
    /// The first beam's angle, wrapped to (-pi, pi].
    first_wrapped: f64,
    increment_rad: f64,
    beams_per_rad: f64,
    dirs: &'a [Vec2],
    max_range_m: f64,
    /// The range squared, with a margin far above any rounding.
    reach2: f64,
    /// The number of beams.
    n: usize,
}

impl Fan<'_> {
    /// Whether the grid cell `c` (at column `cx`, row `cy`) can be skipped: no beam passes
    /// through its arc, or it is hidden behind walls found nearer (`best` so far).
    #[inline]
    fn cell_is_culled(&self, c: usize, cx: i32, cy: i32, best: &[f64]) -> bool {
        let (ix, origin, n) = (self.ix, self.origin, self.n);
        let beams_per_rad = self.beams_per_rad;
        let corner = (
            ix.origin.x + cx as f64 * ix.cell_m - origin.x,
            ix.origin.y + cy as f64 * ix.cell_m - origin.y,
        );
        if let Some((lo, hi)) = ix.cell_arc(corner, self.first_wrapped) {
            let beams = || beams_in_arc(lo, hi, CELL_MARGIN_RAD, beams_per_rad, n);
            if beams().next().is_none() {
                return true;
            }
            if ix.cell_is_hidden(c, corner, beams(), best) {
                #[cfg(test)]
                HIDDEN_CELLS.with(|h| h.set(h.get() + 1));
                return true;
            }
        }
        false
    }

    /// Tests the segments `ids` of a grid cell not tested yet in this cast (`tested[k] ==
    /// cast` once tested) against the beams that may cross them, lowering `best`.
    #[inline]
    fn test_segments(&self, ids: &[u32], tested: &mut [u32], cast: u32, best: &mut [f64]) {
        let (ix, origin, n, dirs) = (self.ix, self.origin, self.n, self.dirs);
        let (reach2, max_range_m, increment_rad) =
            (self.reach2, self.max_range_m, self.increment_rad);
        let (first_wrapped, beams_per_rad) = (self.first_wrapped, self.beams_per_rad);
        for &k in ids {
            // Each segment once, in the first of its cells in the square.
            if tested[k as usize] == cast {
                continue;
            }
            tested[k as usize] = cast;
            let s = ix.segments[k as usize];
            let (a, e) = (s.a - origin, s.b - s.a);
            // Out of reach: the segment's nearest point to the origin (an end, or
            // the foot of the perpendicular, `|a x e|^2 / |e|^2` away squared) is
            // farther than the range (and the margin of `reach2`, far above any
            // rounding). Without a quotient: a segment kept needlessly is crossed
            // beyond the range, if at all.
            let l2 = e.dot(&e);
            let along = -a.dot(&e);
            let cross_ae = a.x * e.y - a.y * e.x;
            let out_of_reach = if along <= 0.0 || l2 <= 0.0 {
                a.norm_squared() > reach2
            } else if along >= l2 {
                (a + e).norm_squared() > reach2
            } else {
                cross_ae * cross_ae > reach2 * l2
            };
            if out_of_reach {
                continue;
            }
            let mut test = |i: usize| {
                if let Some(t) = crossing(a, e, cross_ae, dirs[i], max_range_m) {
                    best[i] = best[i].min(t);
                }
            };
            let b_rel = a + e;
            if n == 1
                || increment_rad <= 0.0
                || a.norm_squared() < 1e-24
                || b_rel.norm_squared() < 1e-24
            {
                (0..n).for_each(&mut test);
                continue;
            }
            // The beams within the angle the segment spans seen from the origin (less
            // than half a turn), measured from the first beam.
            let pa = wrap_once(atan2_approx(a.y, a.x) - first_wrapped);
            let pb = wrap_once(atan2_approx(b_rel.y, b_rel.x) - first_wrapped);
            let span = wrap_once(pb - pa);
            // Nearly half a turn (a long wall passing close by): should the approximate
            // angles' errors not cancel (they do for opposite directions), they could
            // pick the other side; every beam is tested instead.
            if span.abs() > std::f64::consts::PI - 0.01 {
                (0..n).for_each(&mut test);
                continue;
            }
            let lo = if span >= 0.0 { pa } else { pb };
            let arc = beams_in_arc(lo, lo + span.abs(), BEAM_MARGIN_RAD, beams_per_rad, n);
            for (i0, i1) in arc {
                (i0..=i1).for_each(&mut test);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry2d::math::{Isometry, Vector as PVector};
    use parry2d::query::{Ray, RayCast};
    use proptest::prelude::*;

    /// An axis-aligned wall from lattice point `(x, y)` (0.05 m apart), `l` lattice steps long.
    fn lattice_segment((x, y, l, vertical): (i32, i32, i32, bool)) -> Segment {
        let a = Vec2::new(x as f64 * 0.05, y as f64 * 0.05);
        let d = l as f64 * 0.05;
        let b = if vertical {
            a + Vec2::new(0.0, d)
        } else {
            a + Vec2::new(d, 0.0)
        };
        Segment::new(a, b)
    }

    fn segment() -> impl Strategy<Value = Segment> {
        // Axis-aligned walls on a 0.05 m lattice (as rasters and generated buildings have them),
        // and slanted ones anywhere.
        prop_oneof![
            (0i32..400, 0i32..400, -80i32..80, any::<bool>()).prop_map(lattice_segment),
            (0.0..20.0f64, 0.0..20.0f64, -5.0..5.0f64, -5.0..5.0f64).prop_map(|(x, y, dx, dy)| {
                Segment::new(Vec2::new(x, y), Vec2::new(x + dx, y + dy))
            }),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// The fan finds, for every beam, what testing every segment finds, to the bit; and
        /// what parry2d's BVH finds, to its `f32` precision, wherever no two walls are as close
        /// along the beam as that precision (the one the simulator used up to 0.6.0).
        #[test]
        fn fan_is_every_segment_tested(
            segments in proptest::collection::vec(segment(), 1..60),
            ox in -2.0..22.0f64,
            oy in -2.0..22.0f64,
            first in -10.0..10.0f64,
            fov_deg in 1.0..=360.0f64,
            beams in 2usize..400,
            range in 0.5..30.0f64,
            limit in 0u64..300,
        ) {
            let walls = Walls::new(&segments);
            let origin = Vec2::new(ox, oy);
            let (inc, dirs) = fan_dirs(first, fov_deg, beams);
            let fan = walls.cast_fan(origin, first, inc, &dirs, range);
            let all = cast_exhaustive(&segments, origin, &dirs, range);
            prop_assert_eq!(&fan, &all);
            // The same through a grid coarsened to fit a budget of entries.
            let coarse = Walls {
                shape: None,
                index: Arc::new(WallIndex::with_limit(&segments, limit)),
            };
            prop_assert_eq!(&coarse.cast_fan(origin, first, inc, &dirs, range), &all);
            let shape = walls.shape.as_ref().expect("walls");
            for (i, d) in dirs.iter().enumerate() {
                let ray = Ray::new(
                    PPoint::new(origin.x as f32, origin.y as f32),
                    PVector::new(d.x as f32, d.y as f32),
                );
                let parry = shape
                    .cast_ray(&Isometry::identity(), &ray, range as f32, false)
                    .map(|t| t as f64);
                // Beams that graze a wall, pass near a wall's end or end near the range may
                // differ (f32 rounding); the rest must agree.
                // (Near a wall's end: the beam crosses the wall grown by a thousandth of its
                // length at both ends, but not the wall shrunk by as much.)
                let doubtful = segments.iter().any(|s| {
                    let e = s.b - s.a;
                    let grown = Segment::new(s.a - e * 1e-3, s.b + e * 1e-3);
                    let shrunk = Segment::new(s.a + e * 1e-3, s.b - e * 1e-3);
                    let cross = |s: &Segment, r: f64| {
                        let (a, e) = (s.a - origin, s.b - s.a);
                        crossing(a, e, a.x * e.y - a.y * e.x, *d, r)
                    };
                    let grazing = (d.x * e.y - d.y * e.x).abs() < 0.05 * e.norm();
                    cross(&grown, range + 1e-2).is_some()
                        && (grazing || cross(&shrunk, range - 1e-2).is_none())
                });
                let agree = match (fan[i], parry) {
                    (Some(a), Some(b)) => (a - b).abs() < 1e-3,
                    (a, b) => a.is_some() == b.is_some(),
                };
                prop_assert!(doubtful || agree, "beam {}: {:?} vs {:?}", i, fan[i], parry);
            }
        }
    }

    /// A fan of `beams` unit directions over `fov_deg` from `first` (rad), and its increment.
    fn fan_dirs(first: f64, fov_deg: f64, beams: usize) -> (f64, Vec<Vec2>) {
        let inc = fov_deg.to_radians() / (beams - 1) as f64;
        let dirs = (0..beams)
            .map(|i| {
                let a = first + i as f64 * inc;
                Vec2::new(a.cos(), a.sin())
            })
            .collect();
        (inc, dirs)
    }

    /// A raster's staircase: short axis-aligned segments on a 0.05 m lattice in an 8 m square.
    fn short_segment() -> impl Strategy<Value = Segment> {
        (0i32..160, 0i32..160, -6i32..6, any::<bool>()).prop_map(lattice_segment)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// On dense short segments (cells of many, which the fan may skip when no beam points
        /// into them), the fan still finds what testing every segment finds, to the bit.
        #[test]
        fn fan_on_dense_segments_is_every_segment_tested(
            segments in proptest::collection::vec(short_segment(), 50..400),
            ox in -1.0..9.0f64,
            oy in -1.0..9.0f64,
            first in -10.0..10.0f64,
            fov_deg in 1.0..=360.0f64,
            beams in 2usize..400,
            range in 0.5..12.0f64,
        ) {
            let walls = Walls::new(&segments);
            let origin = Vec2::new(ox, oy);
            let (inc, dirs) = fan_dirs(first, fov_deg, beams);
            let fan = walls.cast_fan(origin, first, inc, &dirs, range);
            prop_assert_eq!(fan, cast_exhaustive(&segments, origin, &dirs, range));
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// Where beams run along the lattice's lines or within a hair of them (the robot on a
        /// wall's line, facing along an axis), and the cells hidden behind the walls nearby are
        /// skipped, the fan still finds what testing every segment finds.
        #[test]
        fn fan_along_the_lattice_is_every_segment_tested(
            segments in proptest::collection::vec(short_segment(), 50..400),
            (ix, iy) in (0i32..160, 0i32..160),
            (fx, fy) in (0.0..1.0f64, 0.0..1.0f64),
            on_line in 0usize..3,
            quarter in -4i32..4,
            nudge in prop_oneof![Just(0.0), Just(1e-12), Just(-1e-9), -1e-3..1e-3f64],
            range in 0.5..12.0f64,
        ) {
            // On a lattice point, on a lattice line, or anywhere in a lattice cell.
            let (dx, dy) = match on_line {
                0 => (0.0, 0.0),
                1 => (fx * 0.05, 0.0),
                _ => (fx * 0.05, fy * 0.05),
            };
            let origin = Vec2::new(ix as f64 * 0.05 + dx, iy as f64 * 0.05 + dy);
            // The default laser (181 beams over half a turn) with its first beam along an axis.
            let first = quarter as f64 * std::f64::consts::FRAC_PI_2 + nudge;
            let (inc, dirs) = fan_dirs(first, 180.0, 181);
            let walls = Walls::new(&segments);
            let fan = walls.cast_fan(origin, first, inc, &dirs, range);
            prop_assert_eq!(fan, cast_exhaustive(&segments, origin, &dirs, range));
        }
    }

    fn long_segment() -> impl Strategy<Value = Segment> {
        (
            -50.0..450.0f64,
            -50.0..450.0f64,
            -400.0..400.0f64,
            -400.0..400.0f64,
        )
            .prop_map(|(x, y, dx, dy)| Segment::new(Vec2::new(x, y), Vec2::new(x + dx, y + dy)))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// Every point of a segment lies in a grid cell that holds the segment, and a segment is
        /// held by about the cells it crosses (not every cell of its bounding box: a building of
        /// long diagonal walls keeps a small index), within the budget of entries when one is
        /// set that the grid can meet.
        #[test]
        fn segments_are_in_the_cells_they_cross(
            segments in proptest::collection::vec(prop_oneof![segment(), long_segment()], 1..40),
            limit in prop_oneof![Just(MAX_ENTRIES), 0u64..2000],
        ) {
            let ix = WallIndex::with_limit(&segments, limit);
            for (k, s) in ix.segments.iter().enumerate() {
                for i in 0..=64 {
                    let p = s.a + (s.b - s.a) * (i as f64 / 64.0);
                    let [x, y] = ix.cell_of(p);
                    let c = (y * ix.width + x) as usize;
                    let held = &ix.ids[ix.starts[c] as usize..ix.starts[c + 1] as usize];
                    prop_assert!(held.contains(&(k as u32)), "segment {} point {} cell {:?}", k, i, (x, y));
                }
            }
            let crossed: f64 = ix
                .segments
                .iter()
                .map(|s| ((s.b.x - s.a.x).abs() + (s.b.y - s.a.y).abs()) / ix.cell_m + 4.0)
                .sum();
            prop_assert!(ix.ids.len() as f64 <= 3.0 * crossed, "{} entries for {}", ix.ids.len(), crossed);
            prop_assert!(ix.ids.len() as u64 <= limit || ix.width * ix.height == 1);
        }
    }

    #[test]
    fn beam_range_is_ceil_to_floor_clipped() {
        let definition = |x0: f64, x1: f64, n: usize| {
            let i0 = x0.ceil().max(0.0);
            let i1 = x1.floor().min((n - 1) as f64);
            (i0 <= i1).then_some((i0 as usize, i1 as usize))
        };
        let xs = [
            f64::NEG_INFINITY,
            -1e300,
            -3.5,
            -1.0,
            -1e-300,
            -0.0,
            0.0,
            1e-300,
            0.5,
            1.0,
            1.0 + f64::EPSILON,
            2.999_999_999,
            3.0,
            7.25,
            179.0,
            179.5,
            180.0,
            180.000_001,
            1e300,
            f64::INFINITY,
        ];
        for n in [1, 2, 4, 181, 1000] {
            for &x0 in &xs {
                for &x1 in &xs {
                    assert_eq!(
                        beam_range(x0, x1, n),
                        definition(x0, x1, n),
                        "{x0} {x1} {n}"
                    );
                }
            }
        }
    }

    #[test]
    fn atan2_approx_is_within_its_bound() {
        let mut worst = 0.0f64;
        for i in 0..200_000 {
            let t = i as f64 / 200_000.0 * std::f64::consts::TAU - std::f64::consts::PI;
            for r in [1e-9, 0.3, 7.0, 1e6] {
                let (y, x) = (r * t.sin(), r * t.cos());
                worst = worst.max((atan2_approx(y, x) - y.atan2(x)).abs());
            }
        }
        for (y, x) in [
            (0.0, 1.0),
            (1.0, 0.0),
            (0.0, -1.0),
            (-1.0, 0.0),
            (1.0, 1.0),
            (-2.0, -2.0),
        ] {
            worst = worst.max((atan2_approx(y, x) - f64::atan2(y, x)).abs());
        }
        assert!(worst < 3e-4, "{worst}");
    }

    /// Walls that span nearly half a turn seen from the origin (long, passing close by), at
    /// every heading: the approximate angles must not pick the wrong side of them.
    #[test]
    fn long_walls_close_by_are_found() {
        for k in 0..360 {
            let th = (k as f64).to_radians();
            let (c, s) = (th.cos(), th.sin());
            let rot = |x: f64, y: f64| Vec2::new(c * x - s * y, s * x + c * y);
            let segments = [
                Segment::new(rot(-20000.0, 0.2), rot(20000.0, 0.2)),
                Segment::new(rot(0.21, -30000.0), rot(0.21, 1.0)),
                Segment::new(rot(-5000.0, -0.25), rot(4000.0, -0.25)),
            ];
            let walls = Walls::new(&segments);
            for (first, beams) in [(th - 0.3, 181usize), (th + 1.0, 7), (th - 3.0, 361)] {
                let inc = std::f64::consts::TAU / (beams - 1) as f64;
                let dirs: Vec<Vec2> = (0..beams)
                    .map(|i| {
                        let a = first + i as f64 * inc;
                        Vec2::new(a.cos(), a.sin())
                    })
                    .collect();
                let fan = walls.cast_fan(Vec2::zeros(), first, inc, &dirs, 6.0);
                assert_eq!(fan, cast_exhaustive(&segments, Vec2::zeros(), &dirs, 6.0));
                assert!(fan.iter().any(|t| t.is_some()));
            }
        }
    }

    /// Beams along the lattice's lines and within a hair of them, from a point on a wall's
    /// line, with walls on that line behind a wall that hides their cell from every beam
    /// pointing into it: the fan finds what testing every segment finds.
    #[test]
    fn walls_on_a_beams_line_behind_a_wall_are_as_tested() {
        let at = |i: i32| i as f64 * 0.05;
        let origin = Vec2::new(at(20), at(20));
        // A long wall across the beams ahead at x = 1.5 m, then, in one cell behind it, short
        // walls on the origin's line y = 1 m and beside it.
        let mut segments = vec![Segment::new(Vec2::new(1.5, 0.0), Vec2::new(1.5, 2.0))];
        for k in 0..6 {
            for y in [19, 20, 22] {
                segments.push(Segment::new(
                    Vec2::new(at(60 + k), at(y)),
                    Vec2::new(at(61 + k), at(y)),
                ));
            }
        }
        let walls = Walls::new(&segments);
        let hidden_before = HIDDEN_CELLS.with(|h| h.get());
        for quarter in -4..4 {
            for nudge in [0.0, 1e-15, -1e-15, 1e-9, -1e-9] {
                let first = quarter as f64 * std::f64::consts::FRAC_PI_2 + nudge;
                let (inc, dirs) = fan_dirs(first, 180.0, 181);
                let fan = walls.cast_fan(origin, first, inc, &dirs, 6.0);
                let all = cast_exhaustive(&segments, origin, &dirs, 6.0);
                assert_eq!(fan, all, "first beam {quarter} quarters + {nudge} rad");
            }
        }
        // (The cell of short walls behind the long one was skipped, facing it.)
        assert!(HIDDEN_CELLS.with(|h| h.get()) > hidden_before);
        // (Facing +x, the middle beam meets the long wall.)
        let (inc, dirs) = fan_dirs(-std::f64::consts::FRAC_PI_2, 180.0, 181);
        let fan = walls.cast_fan(origin, -std::f64::consts::FRAC_PI_2, inc, &dirs, 6.0);
        assert_eq!(fan[90], Some(0.5));
    }

    #[test]
    fn odd_inputs_give_no_hits_rather_than_panics() {
        let walls = Walls::new(&[Segment::new(Vec2::new(1.0, -1.0), Vec2::new(1.0, 1.0))]);
        let d = [Vec2::new(1.0, 0.0)];
        assert_eq!(
            walls.cast_fan(Vec2::zeros(), 0.0, 0.0, &d, 5.0),
            vec![Some(1.0)]
        );
        assert_eq!(walls.cast_fan(Vec2::zeros(), 0.0, 0.0, &d, 0.5), vec![None]);
        assert_eq!(
            walls.cast_fan(Vec2::new(f64::NAN, 0.0), 0.0, 0.0, &d, 5.0),
            vec![None]
        );
        assert_eq!(
            walls.cast_fan(Vec2::zeros(), 0.0, 0.0, &d, f64::INFINITY),
            vec![None]
        );
        assert_eq!(
            walls.cast(Vec2::new(0.0, 0.5), Vec2::new(1.0, 0.0), 5.0),
            Some(1.0)
        );
        let none = Walls::new(&[]);
        assert_eq!(none.cast(Vec2::zeros(), Vec2::new(1.0, 0.0), 5.0), None);
    }
}
