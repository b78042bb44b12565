//! The known-map yardstick: with the whole building known, exploring becomes an inspection tour.
//! [`known_map_tour`] chooses viewpoints (a position and the laser's heading) from which the
//! run's laser sees at least the wanted share of the explorable area (a greedy set cover over
//! a lattice of drivable places), orders them by a short open travelling-salesman path from the
//! start ([`crate::tsp::open_path`], by planned path lengths), and times the tour with the
//! robot's speed and turn rate. The tour is a heuristic's, an upper bound on the best possible:
//! `tour time / exploration time` says how close a strategy comes to a robot that knew the
//! building (slightly above 1 is possible on a lucky run).
//!
//! Approximations (documented in docs/known-map-tour.md): places every `spacing_m` on a lattice;
//! the laser's `fov` at one of `headings` directions per place; what a place sees is found by
//! `rays` rays through the true free space (the explorer's referee uses the same free space);
//! the set cover counts cells of `cover_cell_m` (a cell seen counts all its explorable cells) and
//! goes on until the fine cells its viewpoints see reach the wanted share; the robot scans only
//! at viewpoints (what it sees on the way is not counted) and drives the grid's shortest paths
//! at full speed, turning in place where they turn.

use std::cell::RefCell;

use crate::building::{explorable_free, roomy_cells, Building};
use crate::explore::ExploreConfig;
use crate::geom::{wrap_angle, Pose, Vec2};
use crate::grid::{Bitmap, Cell, GridFrame};
use crate::plan::dijkstra::{dijkstra, dijkstra_by, lengths_between, CostField};

/// The tour's method: raised whenever a change to how tours are made changes a tour, so that
/// stores keep no tour of an older method as the yardstick (it is part of a stored tour's key).
pub const TOUR_METHOD: u32 = 1;

/// How the tour is made.
#[derive(Debug, Clone, PartialEq)]
pub struct TourSettings {
    /// The share of the explorable area the tour must see (0.99).
    pub coverage: f64,
    /// Distance between candidate places (m).
    pub spacing_m: f64,
    /// Size of the cells the set cover counts (m).
    pub cover_cell_m: f64,
    /// Headings tried at each place.
    pub headings: usize,
    /// Rays cast from each place over a full turn.
    pub rays: usize,
}

impl Default for TourSettings {
    fn default() -> Self {
        Self {
            coverage: 0.99,
            spacing_m: 1.0,
            cover_cell_m: 0.2,
            headings: 8,
            rays: 720,
        }
    }
}

/// A tour of the known building.
#[derive(Debug, Clone, PartialEq)]
pub struct KnownMapTour {
    /// Where the robot scans, in the order visited (the start first), each with its heading.
    pub viewpoints: Vec<Pose>,
    /// The path driven, from the start through every viewpoint (m, world frame).
    pub path: Vec<Vec2>,
    pub length_m: f64,
    /// Driving at full speed plus turning in place at the full turn rate (s).
    pub time_s: f64,
    /// Of the explorable area, the share the viewpoints see.
    pub covered_fraction: f64,
    /// The share the run's laser sees when the tour is replayed ([`replay`]).
    pub replayed_fraction: f64,
    pub explorable_m2: f64,
}

/// What the places see: per place, the cover cells it sees with the headings that see them.
struct Sight {
    frame: GridFrame,
    truth: Bitmap,
    /// The free space rays pass through.
    free: Bitmap,
    fov_rad: f64,
    headings: usize,
    rays: Vec<Ray>,
    /// Marks of the fine cells already listed (scratch of `fine_cells` and `see_into`).
    marks: RefCell<Marks>,
}

/// One ray of a sweep: its bearing and the cells it passes through from a cell's centre, as
/// offsets from that cell, in order, out to the laser's range (the same for every cell).
struct Ray {
    bearing: f64,
    cells: Vec<(i32, i32)>,
}

impl Ray {
    /// The `rays` rays of a full turn, sampled every half cell out to `range_cells`.
    fn sweep(rays: usize, range_cells: f64) -> Vec<Ray> {
        (0..rays)
            .map(|r| {
                let bearing = std::f64::consts::TAU * r as f64 / rays as f64;
                let dir = Vec2::new(bearing.cos(), bearing.sin());
                let mut cells: Vec<(i32, i32)> = Vec::new();
                let mut t = 0.0;
                while t <= range_cells {
                    let p = Vec2::new(0.5, 0.5) + dir * t;
                    let c = (p.x.floor() as i32, p.y.floor() as i32);
                    if cells.last() != Some(&c) {
                        cells.push(c);
                    }
                    t += 0.5;
                }
                Ray { bearing, cells }
            })
            .collect()
    }
}

/// Marks over a grid's cells that are all cleared at once (a new generation): the cells a
/// sweep of rays already listed, without sorting the many repeats of rays crossing near their
/// origin.
struct Marks {
    stamp: Vec<u32>,
    generation: u32,
}

impl Marks {
    fn new(len: usize) -> Self {
        Self {
            stamp: vec![0; len],
            generation: 0,
        }
    }

    /// Clears every mark.
    fn clear(&mut self) {
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.stamp.fill(0);
            self.generation = 1;
        }
    }

    /// Marks `i`; whether it was not marked yet.
    fn first(&mut self, i: usize) -> bool {
        let fresh = self.stamp[i] != self.generation;
        self.stamp[i] = self.generation;
        fresh
    }
}

impl Sight {
    /// The fine cells of `truth` a laser at `cell` facing `heading` sees.
    fn fine_cells(&self, cell: Cell, heading: f64) -> Vec<usize> {
        let mut out = Vec::new();
        self.marks.borrow_mut().clear();
        self.see_into(cell, heading, &mut out);
        out
    }

    /// Adds to `out` the fine cells a laser at `cell` facing `heading` sees that are not marked
    /// yet, and marks them.
    fn see_into(&self, cell: Cell, heading: f64, out: &mut Vec<usize>) {
        let mut marks = self.marks.borrow_mut();
        let in_view =
            |bearing: f64| u16::from(wrap_angle(bearing - heading).abs() <= self.fov_rad / 2.0);
        self.cast(cell, in_view, |_, i| {
            if marks.first(i) {
                out.push(i);
            }
        });
    }

    /// Calls `seen(mask, fine index)` for every explorable cell each ray from `cell` passes
    /// through the free space, up to the laser's range, `mask` being `mask_of` the ray's bearing
    /// (computed once per ray; a ray whose mask is 0 is not cast).
    fn cast(&self, cell: Cell, mask_of: impl Fn(f64) -> u16, mut seen: impl FnMut(u16, usize)) {
        for ray in &self.rays {
            let mask = mask_of(ray.bearing);
            if mask == 0 {
                continue;
            }
            for &(dx, dy) in &ray.cells {
                let Some(i) = self.frame.index(Cell::new(cell.x + dx, cell.y + dy)) else {
                    break;
                };
                if !self.free.data[i] {
                    break;
                }
                if self.truth.data[i] {
                    seen(mask, i);
                }
            }
        }
    }

    /// Per heading (a bit each), whether a ray of `bearing` is within the laser's view.
    fn heading_mask(&self, bearing: f64) -> u16 {
        let mut mask = 0u16;
        for k in 0..self.headings {
            if wrap_angle(bearing - self.heading(k)).abs() <= self.fov_rad / 2.0 {
                mask |= 1 << k;
            }
        }
        mask
    }

    fn heading(&self, k: usize) -> f64 {
        std::f64::consts::TAU * k as f64 / self.headings as f64
    }
}

/// Why a tour cannot be made.
#[derive(Debug, Clone, PartialEq)]
pub enum TourError {
    /// No place the robot can drive to from the start has room for its body (its radius and
    /// safety margin, `body_m`): a tour would see only what the start's first scan sees.
    NoRoom { body_m: f64 },
}

impl std::fmt::Display for TourError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TourError::NoRoom { body_m } => write!(
                f,
                "the robot fits nowhere it could drive from the start: no place within reach has {body_m} m clear around it (its radius and safety margin); give a smaller robot_radius_m or another start"
            ),
        }
    }
}

impl std::error::Error for TourError {}

/// What a tour's computation is doing, for a caller that shows its progress (see
/// [`known_map_tour_with`]). Counts only: sim-core reads no clock.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TourProgress {
    /// What `done` of `total` candidate places see (the set cover's input).
    Sweeping { done: usize, total: usize },
    /// `viewpoints` chosen so far, seeing `seen` of the explorable area.
    Choosing { viewpoints: usize, seen: f64 },
    /// Path lengths from `done` of `total` viewpoints to the others (the order's input).
    Ordering { done: usize, total: usize },
    /// `legs` of the tour driven (and pruned), of about `total`.
    Driving { legs: usize, total: usize },
    /// The tour replayed with the run's laser (`attempt` of at most 3).
    Replaying { attempt: usize },
}

/// A progress callback shared by the tour's steps.
struct Report<'a>(RefCell<&'a mut dyn FnMut(TourProgress)>);

impl Report<'_> {
    fn say(&self, p: TourProgress) {
        (self.0.borrow_mut())(p);
    }
}

/// The tour of `building` from `start` for the robot and laser of `cfg` (see the module doc).
///
/// The tour is then replayed with the run's laser ([`replay`]); when that sees less than the
/// wanted share (the tour's sweeps of rays and the laser's beams differ a little), the tour is
/// made again asking for that much more, up to three times. An error when the robot fits
/// nowhere it could drive from the start ([`TourError::NoRoom`]).
pub fn known_map_tour(
    building: &Building,
    start: Pose,
    cfg: &ExploreConfig,
    ts: &TourSettings,
) -> Result<KnownMapTour, TourError> {
    known_map_tour_with(building, start, cfg, ts, &mut |_| {})
}

/// [`known_map_tour`], telling `progress` what it does as it goes.
pub fn known_map_tour_with(
    building: &Building,
    start: Pose,
    cfg: &ExploreConfig,
    ts: &TourSettings,
    progress: &mut dyn FnMut(TourProgress),
) -> Result<KnownMapTour, TourError> {
    let report = Report(RefCell::new(progress));
    let mut asked = ts.coverage;
    let mut tries = 0;
    loop {
        let at = TourSettings {
            coverage: asked,
            ..ts.clone()
        };
        let mut tour = tour_seeing(building, start, cfg, &at, &report)?;
        tries += 1;
        report.say(TourProgress::Replaying { attempt: tries });
        tour.replayed_fraction = replay(building, start, &tour, cfg);
        if tour.replayed_fraction >= ts.coverage || tries == 3 || asked >= 1.0 {
            return Ok(tour);
        }
        asked = (asked + (ts.coverage - tour.replayed_fraction) + 0.001).min(1.0);
    }
}

/// What a tour is made from: the explorable cells, where the body fits, the search from the
/// start, what places see and the places of each round.
struct Setup {
    frame: GridFrame,
    roomy: Bitmap,
    from_start: CostField,
    sight: Sight,
    rounds: Vec<Vec<Cell>>,
}

/// What a tour and its bound both start from: the map frame, the free space reachable from the
/// start, the robot's body and laser range, and the explorable part (the referee's truth).
struct Ground {
    frame: GridFrame,
    reachable: Bitmap,
    body_m: f64,
    range_m: f64,
    truth: Bitmap,
}

impl Ground {
    fn of(building: &Building, start: Pose, cfg: &ExploreConfig) -> Ground {
        let frame = crate::explore::map_frame(&building.bounds(), cfg.map_resolution_m);
        let reachable = building.reachable_free(frame, start.position());
        let body_m = cfg.sim.robot.radius_m + cfg.safety_margin_m;
        let range_m = cfg.sim.laser.max_range_m;
        let truth = explorable_free(&reachable, start.position(), body_m, range_m);
        Ground {
            frame,
            reachable,
            body_m,
            range_m,
            truth,
        }
    }
}

impl Setup {
    fn new(
        building: &Building,
        start: Pose,
        cfg: &ExploreConfig,
        ts: &TourSettings,
    ) -> Result<Setup, TourError> {
        let Ground {
            frame,
            reachable,
            body_m,
            range_m,
            truth,
        } = Ground::of(building, start, cfg);
        let res = frame.resolution_m;
        let roomy = roomy_cells(&reachable, body_m);
        let start_cell = frame.cell_from_world(start.position());
        let from_start = dijkstra(&roomy, start_cell, None);
        let sight = Sight {
            frame,
            truth,
            free: reachable,
            fov_rad: cfg.sim.laser.fov_rad,
            headings: ts.headings.clamp(1, 16),
            rays: Ray::sweep(ts.rays.max(8), range_m / res),
            marks: RefCell::new(Marks::new(frame.len())),
        };
        // Places every `spacing_m`; then, if they cannot see the wanted share, the places of
        // lattices twice and four times as fine (cells some corner hides from the first).
        let step = ((ts.spacing_m / res).round() as i32).max(1);
        let lattices: Vec<i32> = [step, step / 2, step / 4]
            .into_iter()
            .filter(|s| *s >= 1)
            .fold(Vec::new(), |mut v, s| {
                if v.last() != Some(&s) {
                    v.push(s);
                }
                v
            });
        let rounds: Vec<Vec<Cell>> = lattices
            .iter()
            .enumerate()
            .map(|(r, &s)| {
                let on = |c: &Cell, s: i32| c.x % s == 0 && c.y % s == 0;
                (0..frame.len())
                    .map(|i| frame.cell_of_index(i))
                    .filter(|c| on(c, s) && !lattices[..r].iter().any(|&p| on(c, p)))
                    .filter(|c| roomy.get(*c) == Some(&true) && from_start.distance_m(*c).is_some())
                    .collect()
            })
            .collect();
        // Not one place to drive to (the body fits nowhere near the start): the tour would be
        // the start's first scan, in 0 s, a yardstick that makes every efficiency 0.
        let drivable = (0..frame.len())
            .filter(|&i| roomy.data[i] && from_start.distance_m(frame.cell_of_index(i)).is_some())
            .take(2)
            .count();
        if drivable < 2 || rounds.iter().all(Vec::is_empty) {
            return Err(TourError::NoRoom { body_m });
        }
        Ok(Setup {
            frame,
            roomy,
            from_start,
            sight,
            rounds,
        })
    }
}

/// The tour that sees `ts.coverage` by its own sweeps.
fn tour_seeing(
    building: &Building,
    start: Pose,
    cfg: &ExploreConfig,
    ts: &TourSettings,
    report: &Report<'_>,
) -> Result<KnownMapTour, TourError> {
    let Setup {
        frame,
        roomy,
        from_start,
        sight,
        rounds,
    } = Setup::new(building, start, cfg, ts)?;
    let cover = Cover::new(&sight, ts.cover_cell_m);
    let explorable = sight.truth.count_true();
    let wanted = (ts.coverage * explorable as f64).ceil() as usize;
    let chosen = cover.choose(&sight, &rounds, start, wanted, report);
    let ordered = order(&roomy, &chosen, &from_start, report);
    let robot = &cfg.sim.robot;
    let driver = Driver {
        roomy: &roomy,
        sight: &sight,
        from_start: &from_start,
        start,
        speed_mps: robot.max_speed_mps,
        turn_radps: robot.max_turn_rate_radps,
        report,
    };
    let mut tour = driver.tour(&ordered);
    tour.prune(&driver, wanted);
    // What is seen on the way made viewpoints needless: order what is left afresh, and again
    // while that makes the tour faster.
    for _ in 0..3 {
        let kept: Vec<Pose> = tour.legs.iter().map(|l| l.to).collect();
        let mut again = driver.tour(&order(&roomy, &kept, &from_start, report));
        again.prune(&driver, wanted);
        if again.total < wanted || again.time_s(&driver) >= tour.time_s(&driver) - 1e-9 {
            break;
        }
        tour = again;
    }
    let mut path = vec![start.position()];
    let (mut length_m, mut time_s) = (0.0, 0.0);
    for leg in &tour.legs {
        path.extend(&leg.points);
        length_m += leg.length_m;
        time_s += driver.time_of(leg);
    }
    Ok(KnownMapTour {
        viewpoints: std::iter::once(start)
            .chain(tour.legs.iter().map(|l| l.to))
            .collect(),
        path,
        length_m,
        time_s,
        covered_fraction: if explorable == 0 {
            1.0
        } else {
            tour.total as f64 / explorable as f64
        },
        replayed_fraction: f64::NAN,
        explorable_m2: explorable as f64 * frame.cell_area_m2(),
    })
}

/// What making a tour will cost, estimated before making it ([`estimate`]).
#[derive(Debug, Clone, PartialEq)]
pub struct TourEstimate {
    /// Candidate places of the first lattice.
    pub places: usize,
    /// Viewpoints the set cover is expected to choose (explorable cells over what a sample of
    /// places sees at its best heading, times [`ESTIMATE_OVERLAP`]).
    pub viewpoints: usize,
    /// Cells where the body fits (each path search between viewpoints may visit them all).
    pub roomy_cells: usize,
    /// Cells the sweeps of rays from every place pass through.
    pub sweep_cells: f64,
    /// Seconds on one core of the reference machine: the constants `ESTIMATE_S_PER_*` fitted
    /// to tours of 0.5 to 180 s (docs/known-map-tour.md), within a factor of about 2 on them.
    pub seconds: f64,
}

/// How many more viewpoints the greedy cover chooses than explorable area over what one sees.
pub(crate) const ESTIMATE_OVERLAP: f64 = 2.0;
/// Seconds per cell a place's sweep of rays passes through (measured, see docs/known-map-tour.md).
pub(crate) const ESTIMATE_S_PER_SWEEP_CELL: f64 = 1.5e-8;
/// Seconds per cell a path search between viewpoints settles (measured likewise).
pub(crate) const ESTIMATE_S_PER_SEARCH_CELL: f64 = 1.43e-8;
/// Seconds per pair of viewpoints (the order's improving moves and the legs' pruning).
pub(crate) const ESTIMATE_S_PER_PAIR: f64 = 5.5e-5;
/// Seconds per cell where the body fits, for what every tour does once (the explorable area,
/// the replay with the laser).
pub(crate) const ESTIMATE_S_PER_CELL: f64 = 1.0e-5;
/// Path searches per viewpoint: the order's (from each to the later ones, four orders at most)
/// and the legs' (driving and pruning).
const SEARCHES_PER_VIEWPOINT: f64 = 4.0;

/// What making the tour of `building` from `start` for `cfg` would cost (see [`TourEstimate`]),
/// from the grids the tour is made on and the sweeps of a sample of at most 24 places: a
/// fraction of the tour's own cost. The same error as [`known_map_tour`] when the robot fits
/// nowhere.
pub fn estimate(
    building: &Building,
    start: Pose,
    cfg: &ExploreConfig,
    ts: &TourSettings,
) -> Result<TourEstimate, TourError> {
    let setup = Setup::new(building, start, cfg, ts)?;
    let sight = &setup.sight;
    let places = &setup.rounds[0];
    let sample: Vec<Cell> = if places.is_empty() {
        setup.rounds.iter().flatten().take(24).copied().collect()
    } else {
        let every = places.len().div_ceil(24).max(1);
        places.iter().step_by(every).copied().collect()
    };
    let (mut swept, mut seen) = (0usize, 0usize);
    for &p in &sample {
        sight.cast(p, |_| 1, |_, _| swept += 1);
        seen += (0..sight.headings)
            .map(|k| sight.fine_cells(p, sight.heading(k)).len())
            .max()
            .unwrap_or(0);
    }
    let n = sample.len().max(1) as f64;
    let per_place = swept as f64 / n;
    let per_view = (seen as f64 / n).max(1.0);
    let explorable = sight.truth.count_true() as f64;
    let viewpoints = (ESTIMATE_OVERLAP * explorable / per_view).ceil().max(1.0);
    let roomy_cells = setup.roomy.count_true();
    let sweep_cells = per_place * places.len().max(sample.len()) as f64;
    let search_cells = SEARCHES_PER_VIEWPOINT * viewpoints * roomy_cells as f64;
    Ok(TourEstimate {
        places: places.len(),
        viewpoints: viewpoints as usize,
        roomy_cells,
        sweep_cells,
        seconds: sweep_cells * ESTIMATE_S_PER_SWEEP_CELL
            + search_cells * ESTIMATE_S_PER_SEARCH_CELL
            + viewpoints * viewpoints * ESTIMATE_S_PER_PAIR
            + roomy_cells as f64 * ESTIMATE_S_PER_CELL,
    })
}

/// An independent check of a tour: the share of the explorable area the run's laser (its
/// beams, field of view and range, without noise, against the building's walls) sees when the
/// robot drives `tour` from `start`, scanning at the laser's rate while it drives at full speed
/// and turns in place at the full turn rate (to face each leg, and each viewpoint's heading).
/// A cell counts as seen when a beam passes through it or ends in it, as the explorer's map
/// knows it.
pub fn replay(building: &Building, start: Pose, tour: &KnownMapTour, cfg: &ExploreConfig) -> f64 {
    let frame = crate::explore::map_frame(&building.bounds(), cfg.map_resolution_m);
    let reachable = building.reachable_free(frame, start.position());
    let body_m = cfg.sim.robot.radius_m + cfg.safety_margin_m;
    let truth = explorable_free(
        &reachable,
        start.position(),
        body_m,
        cfg.sim.laser.max_range_m,
    );
    let total = truth.count_true();
    if total == 0 {
        return 1.0;
    }
    let walls = crate::sim::Walls::new(&building.boundary_segments());
    let laser = crate::sim::LaserConfig {
        range_noise_sd_m: 0.0,
        ..cfg.sim.laser.clone()
    };
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(0);
    let mut seen = vec![false; frame.len()];
    let mut count = 0usize;
    let mut scan_at = |pose: Pose| {
        let scan = laser.scan(&walls, &pose, &mut rng);
        for (i, &r) in scan.ranges_m.iter().enumerate() {
            let a = pose.theta_rad + scan.angle_min_rad + i as f64 * scan.angle_increment_rad;
            let dir = Vec2::new(a.cos(), a.sin());
            let steps = (r / (0.5 * frame.resolution_m)).ceil() as usize;
            for k in 0..=steps {
                let q = pose.position() + dir * (r * k as f64 / steps.max(1) as f64);
                if let Some(j) = frame.index(frame.cell_from_world(q)) {
                    if truth.data[j] && !seen[j] {
                        seen[j] = true;
                        count += 1;
                    }
                }
            }
        }
    };
    let dt = 1.0 / cfg.sim.laser.rate_hz;
    let (step_m, step_rad) = (
        cfg.sim.robot.max_speed_mps * dt,
        cfg.sim.robot.max_turn_rate_radps * dt,
    );
    let mut pose = start;
    scan_at(pose);
    let turn_to = |pose: &mut Pose, heading: f64, scan_at: &mut dyn FnMut(Pose)| {
        let turn = wrap_angle(heading - pose.theta_rad);
        let n = (turn.abs() / step_rad).ceil() as usize;
        for k in 1..=n {
            scan_at(Pose::new(
                pose.x_m,
                pose.y_m,
                pose.theta_rad + turn * k as f64 / n as f64,
            ));
        }
        pose.theta_rad = heading;
    };
    let mut next_view = 1;
    for &p in tour.path.iter().skip(1) {
        let d = p - pose.position();
        if d.norm() > 1e-9 {
            turn_to(&mut pose, d.y.atan2(d.x), &mut scan_at);
            let n = (d.norm() / step_m).ceil() as usize;
            let from = pose.position();
            for k in 1..=n {
                let q = from + d * (k as f64 / n as f64);
                scan_at(Pose::new(q.x, q.y, pose.theta_rad));
            }
            pose = Pose::new(p.x, p.y, pose.theta_rad);
        }
        while let Some(v) = tour.viewpoints.get(next_view) {
            if (v.position() - p).norm() > 1e-9 {
                break;
            }
            turn_to(&mut pose, v.theta_rad, &mut scan_at);
            next_view += 1;
        }
    }
    count as f64 / total as f64
}

/// The greedy set cover's cells: the fine cells grouped `k` by `k`, each weighing its
/// explorable cells.
struct Cover {
    k: i32,
    width: usize,
    weight: Vec<u32>,
    /// Scratch of `seen_from`: the cover cells listed, and where.
    listed: RefCell<(Marks, Vec<u32>)>,
}

impl Cover {
    fn new(sight: &Sight, cover_cell_m: f64) -> Self {
        let f = sight.frame;
        let k = ((cover_cell_m / f.resolution_m).round() as i32).max(1);
        let width = (f.width as usize).div_ceil(k as usize);
        let height = (f.height as usize).div_ceil(k as usize);
        let mut weight = vec![0u32; width * height];
        for (i, &t) in sight.truth.data.iter().enumerate() {
            if t {
                weight[Self::of(k, width, f.cell_of_index(i))] += 1;
            }
        }
        let listed = RefCell::new((Marks::new(weight.len()), vec![0; weight.len()]));
        Self {
            k,
            width,
            weight,
            listed,
        }
    }

    fn of(k: i32, width: usize, c: Cell) -> usize {
        (c.y / k) as usize * width + (c.x / k) as usize
    }

    /// What a place sees: each cover cell with the headings that see it.
    fn seen_from(&self, sight: &Sight, place: Cell) -> Vec<(u32, u16)> {
        let mut merged: Vec<(u32, u16)> = Vec::new();
        let f = sight.frame;
        let mask_of = |bearing| sight.heading_mask(bearing);
        let mut listed = self.listed.borrow_mut();
        let (marks, at) = &mut *listed;
        marks.clear();
        sight.cast(place, mask_of, |mask, i| {
            let c = Self::of(self.k, self.width, f.cell_of_index(i));
            if marks.first(c) {
                at[c] = merged.len() as u32;
                merged.push((c as u32, mask));
            } else {
                merged[at[c] as usize].1 |= mask;
            }
        });
        merged
    }

    /// Viewpoints (place, heading) chosen greedily, each the one that sees the most cover
    /// cells' weight not yet seen, after what the start sees, until the fine cells seen reach
    /// `wanted` or nothing more is seen; from the places of each round in turn while short of
    /// `wanted` (in the later rounds a cover cell counts as seen only once all its cells are).
    fn choose(
        &self,
        sight: &Sight,
        rounds: &[Vec<Cell>],
        start: Pose,
        wanted: usize,
        report: &Report<'_>,
    ) -> Vec<Pose> {
        let f = sight.frame;
        let mut seen = Seen {
            fine: vec![false; f.len()],
            fine_seen: 0,
            covered: vec![false; self.weight.len()],
            seen_in: vec![0; self.weight.len()],
        };
        seen.see(
            self,
            sight,
            f.cell_from_world(start.position()),
            start.theta_rad,
        );
        let mut chosen = Vec::new();
        for (r, places) in rounds.iter().enumerate() {
            if seen.fine_seen >= wanted {
                break;
            }
            if r > 0 {
                for (c, covered) in seen.covered.iter_mut().enumerate() {
                    *covered = seen.seen_in[c] == self.weight[c];
                }
            }
            self.choose_among(sight, places, &mut seen, wanted, &mut chosen, report);
        }
        chosen
    }

    /// The lazy greedy over `places` (see [`Cover::choose`]).
    fn choose_among(
        &self,
        sight: &Sight,
        places: &[Cell],
        seen: &mut Seen,
        wanted: usize,
        chosen: &mut Vec<Pose>,
        report: &Report<'_>,
    ) {
        let f = sight.frame;
        let total = places.len();
        let lists: Vec<Vec<(u32, u16)>> = places
            .iter()
            .enumerate()
            .map(|(done, p)| {
                if done % 256 == 0 {
                    report.say(TourProgress::Sweeping { done, total });
                }
                self.seen_from(sight, *p)
            })
            .collect();
        let explorable = sight.truth.count_true().max(1) as f64;
        let gain = |item: usize, covered: &[bool]| -> u64 {
            let (p, k) = (item / sight.headings, item % sight.headings);
            lists[p]
                .iter()
                .filter(|(c, m)| m & (1 << k) != 0 && !covered[*c as usize])
                .map(|(c, _)| u64::from(self.weight[*c as usize]))
                .sum()
        };
        // Lazy greedy: gains only fall as cells are covered, so a stale gain bounds the true.
        let mut heap: std::collections::BinaryHeap<(u64, std::cmp::Reverse<usize>)> =
            (0..places.len() * sight.headings)
                .map(|i| (gain(i, &seen.covered), std::cmp::Reverse(i)))
                .collect();
        while seen.fine_seen < wanted {
            let Some((stale, std::cmp::Reverse(item))) = heap.pop() else {
                break;
            };
            let now = gain(item, &seen.covered);
            if now == 0 {
                continue;
            }
            if now < stale && heap.peek().is_some_and(|top| top.0 > now) {
                heap.push((now, std::cmp::Reverse(item)));
                continue;
            }
            let (p, k) = (item / sight.headings, item % sight.headings);
            let heading = sight.heading(k);
            seen.see(self, sight, places[p], heading);
            let at = f.world_from_cell(places[p]);
            chosen.push(Pose::new(at.x, at.y, wrap_angle(heading)));
            report.say(TourProgress::Choosing {
                viewpoints: chosen.len(),
                seen: seen.fine_seen as f64 / explorable,
            });
        }
    }
}

/// What the chosen viewpoints see: fine cells (and their number) and cover cells.
struct Seen {
    fine: Vec<bool>,
    fine_seen: usize,
    covered: Vec<bool>,
    /// Per cover cell, its fine cells seen.
    seen_in: Vec<u32>,
}

impl Seen {
    fn see(&mut self, cover: &Cover, sight: &Sight, cell: Cell, heading: f64) {
        for i in sight.fine_cells(cell, heading) {
            let c = Cover::of(cover.k, cover.width, sight.frame.cell_of_index(i));
            self.covered[c] = true;
            if !self.fine[i] {
                self.fine[i] = true;
                self.fine_seen += 1;
                self.seen_in[c] += 1;
            }
        }
    }
}

/// `chosen` in the order of a short open path from the start (over the planned path lengths
/// between them on the `roomy` cells; `from_start` is the search from the start's cell).
fn order(
    roomy: &Bitmap,
    chosen: &[Pose],
    from_start: &CostField,
    report: &Report<'_>,
) -> Vec<Pose> {
    let frame = roomy.frame;
    let cells: Vec<Cell> = chosen
        .iter()
        .map(|p| frame.cell_from_world(p.position()))
        .collect();
    let first: Vec<f64> = cells
        .iter()
        .map(|c| from_start.distance_m(*c).unwrap_or(f64::INFINITY))
        .collect();
    let some: Vec<Option<Cell>> = cells.iter().copied().map(Some).collect();
    let total = some.len();
    let mut done = 0;
    let between = lengths_between(&some, |from, to| {
        report.say(TourProgress::Ordering { done, total });
        done += 1;
        dijkstra_by(frame, from, |k| roomy.data[k], |_| 0, 0, to)
    });
    crate::tsp::open_path(&first, &between, 50)
        .into_iter()
        .map(|i| chosen[i])
        .collect()
}

/// The robot scans this often on its way (m): about the explorer's map updates (0.25 m).
const SENSE_EVERY_M: f64 = 0.25;

/// One leg of a tour: driven from the previous viewpoint to `to`, and what it sees on the way
/// (facing where it drives, every [`SENSE_EVERY_M`]) and at `to`.
struct Leg {
    to: Pose,
    points: Vec<Vec2>,
    length_m: f64,
    turn_rad: f64,
    seen: Vec<usize>,
}

/// Drives legs: along the shortest paths of the `roomy` cells, pulled straight, at full speed,
/// turning in place at the full turn rate.
struct Driver<'a, 'r> {
    roomy: &'a Bitmap,
    sight: &'a Sight,
    from_start: &'a CostField,
    start: Pose,
    speed_mps: f64,
    turn_radps: f64,
    report: &'a Report<'r>,
}

impl Driver<'_, '_> {
    fn time_of(&self, leg: &Leg) -> f64 {
        leg.length_m / self.speed_mps + leg.turn_rad / self.turn_radps
    }

    /// The leg from `from` (`None`: the start) to `to`, if a path leads there.
    fn leg(&self, from: Option<Pose>, to: Pose) -> Option<Leg> {
        let frame = self.roomy.frame;
        let goal = frame.cell_from_world(to.position());
        let searched;
        let (field, origin) = match from {
            None => (self.from_start, self.start),
            Some(f) => {
                let cell = frame.cell_from_world(f.position());
                searched = dijkstra_by(frame, cell, |k| self.roomy.data[k], |_| 0, 0, &[goal]);
                (&searched, f)
            }
        };
        let points = smooth(self.roomy, &field.path_to(goal)?);
        let mut leg = Leg {
            to,
            points: Vec::new(),
            length_m: 0.0,
            turn_rad: 0.0,
            seen: Vec::new(),
        };
        let (mut at, mut heading) = (origin.position(), origin.theta_rad);
        self.sight.marks.borrow_mut().clear();
        for p in points {
            let d = p - at;
            if d.norm() > 1e-9 {
                let dir = d.y.atan2(d.x);
                leg.turn_rad += wrap_angle(dir - heading).abs();
                leg.length_m += d.norm();
                let n = (d.norm() / SENSE_EVERY_M).ceil() as usize;
                for s in 1..=n {
                    let q = at + d * (s as f64 / n as f64);
                    let cell = frame.cell_from_world(q);
                    self.sight.see_into(cell, dir, &mut leg.seen);
                }
                leg.points.push(p);
                (at, heading) = (p, dir);
            }
        }
        leg.turn_rad += wrap_angle(to.theta_rad - heading).abs();
        self.sight.see_into(goal, to.theta_rad, &mut leg.seen);
        Some(leg)
    }

    /// The tour through `ordered` (viewpoints no path leads to are left out).
    fn tour(&self, ordered: &[Pose]) -> Tour {
        let f = self.sight.frame;
        let mut tour = Tour {
            legs: Vec::new(),
            counts: vec![0u32; f.len()],
            total: 0,
        };
        let start_cell = f.cell_from_world(self.start.position());
        tour.add(&self.sight.fine_cells(start_cell, self.start.theta_rad), 1);
        for (k, &v) in ordered.iter().enumerate() {
            if k % 16 == 0 {
                self.report.say(TourProgress::Driving {
                    legs: k,
                    total: ordered.len(),
                });
            }
            if let Some(leg) = self.leg(tour.legs.last().map(|l| l.to), v) {
                tour.add(&leg.seen, 1);
                tour.legs.push(leg);
            }
        }
        tour
    }
}

/// A tour as legs, with how many of its scans see each explorable cell.
struct Tour {
    legs: Vec<Leg>,
    counts: Vec<u32>,
    /// Explorable cells seen.
    total: usize,
}

impl Tour {
    fn time_s(&self, driver: &Driver<'_, '_>) -> f64 {
        self.legs.iter().map(|l| driver.time_of(l)).sum()
    }

    /// Counts the scans of `cells` once more (`by` 1) or once less (-1).
    fn add(&mut self, cells: &[usize], by: i32) {
        for &i in cells {
            let before = self.counts[i];
            self.counts[i] = before.wrapping_add_signed(by);
            match (before, self.counts[i]) {
                (0, _) => self.total += 1,
                (_, 0) => self.total -= 1,
                _ => {}
            }
        }
    }

    /// Drops viewpoints the rest of the tour makes needless (what the robot sees on its way
    /// covers them), one at a time in the order visited, each drop joining its neighbours by a
    /// new leg, while the tour still sees `wanted` cells and takes less time.
    fn prune(&mut self, driver: &Driver<'_, '_>, wanted: usize) {
        let mut k = 0;
        while k < self.legs.len() {
            if k % 16 == 0 {
                driver.report.say(TourProgress::Driving {
                    legs: k,
                    total: self.legs.len(),
                });
            }
            let end = (k + 2).min(self.legs.len());
            let from = k.checked_sub(1).map(|p| self.legs[p].to);
            let joined = match self.legs.get(k + 1) {
                None => None,
                Some(next) => match driver.leg(from, next.to) {
                    Some(leg) => Some(leg),
                    None => {
                        k += 1;
                        continue;
                    }
                },
            };
            let removed_s: f64 = self.legs[k..end].iter().map(|l| driver.time_of(l)).sum();
            let added_s = joined.as_ref().map_or(0.0, |l| driver.time_of(l));
            let old: Vec<usize> = self.legs[k..end]
                .iter()
                .flat_map(|l| l.seen.iter().copied())
                .collect();
            self.add(&old, -1);
            if let Some(j) = &joined {
                self.add(&j.seen, 1);
            }
            if self.total >= wanted && added_s < removed_s {
                self.legs.splice(k..end, joined);
            } else {
                if let Some(j) = &joined {
                    self.add(&j.seen, -1);
                }
                self.add(&old, 1);
                k += 1;
            }
        }
    }
}

/// The grid path `cells` pulled straight: from each corner, the farthest cell of the path in
/// a straight line through `roomy` cells (the grid's zigzag is neither driven nor turned).
fn smooth(roomy: &Bitmap, cells: &[Cell]) -> Vec<Vec2> {
    let frame = roomy.frame;
    let Some(&last) = cells.last() else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let mut i = 0;
    while i + 1 < cells.len() {
        let mut j = i + 1;
        while j + 1 < cells.len() && clear(roomy, cells[i], cells[j + 1]) {
            j += 1;
        }
        out.push(frame.world_from_cell(cells[j]));
        i = j;
    }
    if out.is_empty() {
        out.push(frame.world_from_cell(last));
    }
    out
}

/// Whether the straight line between the centres of `a` and `b` stays in `roomy` cells.
fn clear(roomy: &Bitmap, a: Cell, b: Cell) -> bool {
    let (dx, dy) = ((b.x - a.x) as f64, (b.y - a.y) as f64);
    let steps = (dx.abs().max(dy.abs()) * 2.0).ceil() as i32;
    (0..=steps).all(|s| {
        let t = if steps == 0 {
            0.0
        } else {
            s as f64 / steps as f64
        };
        let c = Cell::new(
            (a.x as f64 + 0.5 + dx * t).floor() as i32,
            (a.y as f64 + 0.5 + dy * t).floor() as i32,
        );
        roomy.get(c) == Some(&true)
    })
}

/// A lower bound on the time of any tour ([`lower_bound`]).
#[derive(Debug, Clone, PartialEq)]
pub struct LowerBound {
    /// No path from the start that sees the wanted share is shorter (m).
    pub length_m: f64,
    /// `length_m` at the robot's top speed (s).
    pub time_s: f64,
    /// Regions every such path must enter (beside the start).
    pub regions: usize,
}

/// A lower bound on the time of any tour of `building` from `start` that sees `coverage` of the
/// explorable area with the robot and laser of `cfg`: the known-map tour's, an explorer's, the
/// best possible.
///
/// **Why it is sound.** Let `N` be the explorable cells and `m = N - ceil(coverage * N)` the
/// cells a tour may leave unseen. A cell is seen when a beam, a straight segment from the
/// robot's centre of length at most the laser's range `R`, passes through it, so the centre
/// was within `R + δ` of the cell's centre (`δ` half the cell's diagonal). Take an explorable
/// cell `c` and the explorable cells whose centres lie within `r` of it: more than `m` of them
/// (`r` is the smallest radius, in steps of a cell, that holds more than `m` explorable cells
/// around the least crowded of the candidates). Any of them is seen only from within
/// `ρ = R + δ + r` of `c`, so a tour that never comes within `ρ` of `c` leaves more than `m`
/// cells unseen: every tour enters the disc `D(c, ρ)`, whatever it does elsewhere. For a set
/// of such discs, the path's pieces from the start to its first entry into the first disc it
/// enters, and from there to its first entry into each next one, are disjoint and each at
/// least as long as the straight distance between what they join: from the start to a disc
/// `max(0, |s - c| - ρ)`, between two discs `max(0, |c_i - c_j| - 2ρ)`. These pieces form a
/// spanning path of {start, discs}, so the tour is at least as long as the minimum spanning
/// tree of {start, discs} under those distances. Nothing drives faster than the top speed.
/// Turning, and what walls make longer than a straight line, are left out: the bound is
/// sound, not tight (docs/known-map-tour.md).
///
/// The discs' centres are chosen farthest first (from the start and the centres chosen, among
/// explorable cells every `spacing` on a lattice whose disc of radius `r` holds more than `m`),
/// at most 48; the bound is the largest spanning tree's of the first `k` centres, `k` from 0.
pub fn lower_bound(
    building: &Building,
    start: Pose,
    cfg: &ExploreConfig,
    coverage: f64,
) -> LowerBound {
    let Ground {
        frame,
        range_m,
        truth,
        ..
    } = Ground::of(building, start, cfg);
    let res = frame.resolution_m;
    let n = truth.count_true();
    let zero = LowerBound {
        length_m: 0.0,
        time_s: 0.0,
        regions: 0,
    };
    let m = n - ((coverage.clamp(0.0, 1.0) * n as f64).ceil() as usize).min(n);
    if n == 0 || m + 1 > n {
        return zero;
    }
    let cells: Vec<Cell> = (0..frame.len())
        .filter(|&i| truth.data[i])
        .map(|i| frame.cell_of_index(i))
        .collect();
    // Candidates on a lattice of about 0.5 m (at most about 4000 of them).
    let area_m2 = n as f64 * frame.cell_area_m2();
    let spacing_m = (area_m2 / 4000.0).sqrt().max(0.5);
    let step = ((spacing_m / res).round() as i32).max(1);
    let candidates: Vec<Cell> = cells
        .iter()
        .copied()
        .filter(|c| c.x % step == 0 && c.y % step == 0)
        .collect();
    // Explorable cells within `r_cells` of `c` (centre to centre).
    let count = |c: Cell, r_cells: i32| -> usize {
        let mut k = 0;
        for dy in -r_cells..=r_cells {
            for dx in -r_cells..=r_cells {
                if dx * dx + dy * dy <= r_cells * r_cells
                    && truth.get(Cell::new(c.x + dx, c.y + dy)) == Some(&true)
                {
                    k += 1;
                }
            }
        }
        k
    };
    // The smallest radius whose full disc would hold more than `m` cells, then grown until
    // at least a tenth of the candidates' discs do (those whose discs do are the centres).
    let mut r_cells = ((m as f64 + 1.0) / std::f64::consts::PI).sqrt().ceil() as i32;
    let max_r = (range_m / res).ceil() as i32 * 4 + 8;
    let mut valid: Vec<Cell> = Vec::new();
    while r_cells <= max_r {
        valid = candidates
            .iter()
            .copied()
            .filter(|c| count(*c, r_cells) > m)
            .collect();
        if valid.len() * 10 >= candidates.len() && !valid.is_empty() {
            break;
        }
        r_cells = r_cells + (r_cells / 4).max(1);
    }
    if valid.is_empty() {
        return zero;
    }
    let rho = range_m + res * std::f64::consts::SQRT_2 / 2.0 + r_cells as f64 * res;
    let valid: Vec<Vec2> = valid.iter().map(|c| frame.world_from_cell(*c)).collect();
    let (best, best_k) = farthest_first_tree(start.position(), &valid, rho);
    LowerBound {
        length_m: best,
        time_s: best / cfg.sim.robot.max_speed_mps,
        regions: best_k,
    }
}

/// The longest of the minimum spanning trees (see [`spanning_tree`]) of the start `s` and discs
/// of radius `rho` round the first k centres, for k up to 48, the centres taken from `valid`
/// farthest first from the start and the centres already taken; with that k.
fn farthest_first_tree(s: Vec2, valid: &[Vec2], rho: f64) -> (f64, usize) {
    let mut nearest: Vec<f64> = valid.iter().map(|c| (*c - s).norm()).collect();
    let mut centres: Vec<Vec2> = Vec::new();
    let mut best = 0.0f64;
    let mut best_k = 0;
    while centres.len() < 48 {
        let Some((i, &d)) = nearest
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(&a.0)))
        else {
            break;
        };
        if d <= 0.0 {
            break;
        }
        let c = valid[i];
        centres.push(c);
        for (j, v) in valid.iter().enumerate() {
            nearest[j] = nearest[j].min((*v - c).norm());
        }
        let mst = spanning_tree(s, &centres, rho);
        if mst > best {
            (best, best_k) = (mst, centres.len());
        }
    }
    (best, best_k)
}

/// The minimum spanning tree's length over the start (node 0) and discs of radius `rho`
/// around `centres`, the distances those of [`lower_bound`] (Prim's, quadratic).
fn spanning_tree(start: Vec2, centres: &[Vec2], rho: f64) -> f64 {
    let k = centres.len();
    let dist = |a: usize, b: usize| -> f64 {
        match (a, b) {
            (0, 0) => 0.0,
            (0, j) | (j, 0) => ((centres[j - 1] - start).norm() - rho).max(0.0),
            (i, j) => ((centres[i - 1] - centres[j - 1]).norm() - 2.0 * rho).max(0.0),
        }
    };
    let mut in_tree = vec![false; k + 1];
    let mut best: Vec<f64> = (0..=k).map(|j| dist(0, j)).collect();
    in_tree[0] = true;
    let mut total = 0.0;
    for _ in 0..k {
        let Some(j) = (0..=k)
            .filter(|j| !in_tree[*j])
            .min_by(|a, b| best[*a].total_cmp(&best[*b]))
        else {
            break;
        };
        in_tree[j] = true;
        total += best[j];
        for l in 0..=k {
            if !in_tree[l] {
                best[l] = best[l].min(dist(j, l));
            }
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::{generate, BuildingKind, GenerateConfig};

    fn building(seed: u64, kind: BuildingKind, area_m2: f64) -> Building {
        generate(&GenerateConfig {
            seed,
            area_m2,
            kind,
            ..GenerateConfig::default()
        })
    }

    /// On generated buildings of both kinds: the tour sees the wanted share (by its own sweeps
    /// and replayed with the laser), starts at the start, is timed no faster than its length at full speed, and beats the nearest frontier
    /// (which must discover what the tour knows).
    #[test]
    fn the_tour_covers_the_building_and_beats_exploring_it() {
        for (seed, kind) in [(3, BuildingKind::Office), (5, BuildingKind::School)] {
            let b = building(seed, kind, 300.0);
            let start = b.start.unwrap();
            let cfg = ExploreConfig::default();
            let tour = known_map_tour(&b, start, &cfg, &TourSettings::default()).unwrap();
            assert!(
                tour.covered_fraction >= 0.99,
                "{kind:?}: {}",
                tour.covered_fraction
            );
            // The run's laser, replayed along the tour, sees what the tour's sweeps promised.
            assert!(
                tour.replayed_fraction >= 0.99,
                "{kind:?}: {}",
                tour.replayed_fraction
            );
            assert_eq!(tour.viewpoints[0], start);
            assert!(tour.viewpoints.len() >= 2);
            assert!(tour.time_s >= tour.length_m / cfg.sim.robot.max_speed_mps);
            assert!(tour.explorable_m2 > 100.0);
            let nearest = ExploreConfig {
                strategy: crate::explore::Strategy::by_name(
                    "nearest",
                    &crate::explore::StrategyParams::default(),
                )
                .unwrap(),
                ..ExploreConfig::default()
            };
            let run = crate::explore::explore(&b, start, &nearest, 1, &mut |_| {});
            assert!(
                tour.time_s < run.exploration_time_s,
                "{kind:?}: the tour {} s ({} viewpoints, {} m), nearest {} s",
                tour.time_s,
                tour.viewpoints.len(),
                tour.length_m,
                run.exploration_time_s
            );
        }
    }

    /// A wider laser needs no more viewpoints, and asking for less coverage no more either.
    #[test]
    fn fewer_viewpoints_with_a_wider_view_or_less_coverage() {
        let b = building(7, BuildingKind::Office, 300.0);
        let start = b.start.unwrap();
        let narrow = ExploreConfig::default();
        let mut wide = ExploreConfig::default();
        wide.sim.laser.fov_rad = std::f64::consts::TAU;
        let ts = TourSettings::default();
        let n = |cfg: &ExploreConfig, coverage: f64| {
            let ts = TourSettings {
                coverage,
                ..ts.clone()
            };
            known_map_tour(&b, start, cfg, &ts)
                .unwrap()
                .viewpoints
                .len()
        };
        assert!(n(&wide, 0.99) <= n(&narrow, 0.99));
        assert!(n(&narrow, 0.8) <= n(&narrow, 0.99));
    }

    /// The lower bound is at most the tour's time on generated buildings of both kinds, sizes
    /// and laser ranges (every tour that reached the coverage), and positive where the building
    /// is wider than the laser sees.
    #[test]
    fn the_lower_bound_is_at_most_the_tour() {
        let cases = [
            (1, BuildingKind::Office, 200.0, 6.0),
            (2, BuildingKind::School, 250.0, 6.0),
            (4, BuildingKind::Office, 300.0, 2.0),
            (6, BuildingKind::School, 200.0, 3.0),
            (8, BuildingKind::Office, 150.0, 1.0),
        ];
        let mut positive = 0;
        for (seed, kind, area, range) in cases {
            let b = building(seed, kind, area);
            let start = b.start.unwrap();
            let mut cfg = ExploreConfig::default();
            cfg.sim.laser.max_range_m = range;
            let tour = known_map_tour(&b, start, &cfg, &TourSettings::default()).unwrap();
            let bound = lower_bound(&b, start, &cfg, 0.99);
            let case = format!("{kind:?} seed {seed} {area} m2 range {range}");
            assert!(tour.covered_fraction >= 0.99, "{case}");
            assert!(
                bound.time_s <= tour.time_s,
                "{case}: bound {} s > tour {} s",
                bound.time_s,
                tour.time_s
            );
            assert!(bound.length_m <= tour.length_m, "{case}");
            positive += usize::from(bound.time_s > 0.0);
        }
        assert!(positive >= 3, "{positive} positive bounds");
    }

    /// A robot that fits nowhere it could drive to is an error, for the tour and its estimate;
    /// the estimate grows as the laser's range shrinks (more viewpoints, more pairs of them).
    #[test]
    fn no_room_is_an_error_and_estimates_grow_as_the_range_shrinks() {
        let b = building(3, BuildingKind::Office, 200.0);
        let start = b.start.unwrap();
        let mut huge = ExploreConfig::default();
        huge.sim.robot.radius_m = 3.0;
        let ts = TourSettings::default();
        assert!(matches!(
            known_map_tour(&b, start, &huge, &ts),
            Err(TourError::NoRoom { .. })
        ));
        assert!(matches!(
            estimate(&b, start, &huge, &ts),
            Err(TourError::NoRoom { .. })
        ));
        let mut last: Option<TourEstimate> = None;
        for range in [6.0, 2.0, 0.5] {
            let mut cfg = ExploreConfig::default();
            cfg.sim.laser.max_range_m = range;
            let e = estimate(&b, start, &cfg, &ts).unwrap();
            assert!(e.places > 0 && e.seconds > 0.0, "{range}: {e:?}");
            if let Some(l) = &last {
                assert!(
                    e.viewpoints > l.viewpoints && e.seconds > l.seconds,
                    "{range}: {e:?} after {l:?}"
                );
            }
            last = Some(e);
        }
    }
}
