//! What a team's run produces ([`TeamResult`]): each robot's [`RunResult`], the team's run as
//! one (for everything that reads a run: summaries, reports, grids), and the team's own
//! figures (the area each robot saw and the overlap, idle time, the map updates exchanged, the
//! closest two robots came).

use crate::explore::run::{Decision, EndReason, ProgressSample, RunResult};

/// One robot's figures in a team.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotFigures {
    /// Map area its own scans observed (m2; alone, its explored area).
    pub seen_m2: f64,
    /// Its path length (m).
    pub path_length_m: f64,
    /// When its exploration ended (s) and why.
    pub exploration_time_s: f64,
    pub end_reason: EndReason,
    /// Time it did not explore while the team did (s): after its own exploration ended until the
    /// team's did, and standing still for charged compute time.
    pub idle_s: f64,
    /// Decisions it made.
    pub decisions: usize,
}

/// Everything a team's run produced.
#[derive(Debug, Clone, PartialEq)]
pub struct TeamResult {
    /// The team's run as one: robot 0's record with the team's end (the reason of the robot
    /// whose exploration ended last, the time limit if any robot reached it), its exploration
    /// and total times (the last robot's), the explored area of the team's map, the summed path
    /// lengths, scans, plans and layouts, every robot's decisions in time order, and the team's
    /// progress curve (the explored area of the team's map over time). Rooms never entered are
    /// those no robot entered.
    pub team: RunResult,
    /// Each robot's own record, by robot number (its explored figures are the team map's at
    /// the end of its exploration when the map is shared).
    pub robots: Vec<RunResult>,
    /// Each robot's figures.
    pub figures: Vec<RobotFigures>,
    /// Map area observed by more than one robot (m2; 0 alone or with separate maps), and by any.
    pub overlap_m2: f64,
    pub seen_m2: f64,
    /// Map updates passed on to teammates (one per update and teammate).
    pub exchanges: u64,
    /// The closest two robots' centres came (m; infinite alone).
    pub min_separation_m: f64,
}

impl TeamResult {
    /// The team's time to reach `fraction` of the explorable area (s), from its progress curve.
    pub fn time_to_fraction_s(&self, fraction: f64) -> Option<f64> {
        self.team
            .progress
            .iter()
            .find(|s| s.explored_fraction >= fraction)
            .map(|s| s.time_s)
    }

    /// The share of the area seen that more than one robot saw (0 when nothing was seen).
    pub fn overlap_fraction(&self) -> f64 {
        if self.seen_m2 > 0.0 {
            self.overlap_m2 / self.seen_m2
        } else {
            0.0
        }
    }

    /// A fingerprint of the whole team run (SHA-256 of every robot's fingerprint; first 8 bytes,
    /// hex). A team of one has its one run's fingerprint.
    pub fn fingerprint(&self) -> String {
        if self.robots.len() == 1 {
            return self.robots[0].fingerprint();
        }
        use sha2::{Digest, Sha256};
        let mut h = Sha256::new();
        for r in &self.robots {
            h.update(r.fingerprint().as_bytes());
        }
        h.finalize()[..8]
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect()
    }
}

/// The team's progress curve from its robots' curves (each a sampling of the team's explored
/// area when the map is shared): every sample in time order, one per time, the explored area
/// never falling.
pub(super) fn team_curve(robots: &[RunResult]) -> Vec<ProgressSample> {
    let mut all: Vec<ProgressSample> = robots.iter().flat_map(|r| r.progress.clone()).collect();
    all.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    let mut out: Vec<ProgressSample> = Vec::with_capacity(all.len());
    for s in all {
        let best = out.last().map_or(s, |l| {
            if s.explored_area_m2 >= l.explored_area_m2 {
                s
            } else {
                ProgressSample {
                    time_s: s.time_s,
                    ..*l
                }
            }
        });
        match out.last_mut() {
            Some(l) if l.time_s == s.time_s => *l = best,
            _ => out.push(best),
        }
    }
    out
}

/// The area a robot's laser swept (the free space its beams crossed, from its estimated poses),
/// on a grid of [`COVERAGE_CELL_M`]: the map records a cell once, whoever sees it first, so a
/// team's overlap is counted here from the scans themselves.
#[derive(Debug, Clone)]
pub(crate) struct Coverage {
    pub(crate) seen: crate::grid::Bitmap,
}

/// The coverage grid's cell (m).
pub(crate) const COVERAGE_CELL_M: f64 = 0.2;

impl Coverage {
    /// Nothing seen yet, on a grid of [`COVERAGE_CELL_M`] over the map's `frame`.
    pub(crate) fn new(frame: crate::grid::GridFrame) -> Coverage {
        let f = (COVERAGE_CELL_M / frame.resolution_m).round().max(1.0);
        let coarse = crate::grid::GridFrame::new(
            frame.origin_m,
            frame.resolution_m * f,
            (frame.width as f64 / f).ceil() as u32,
            (frame.height as f64 / f).ceil() as u32,
        );
        Coverage {
            seen: crate::grid::Bitmap::filled(coarse, false),
        }
    }

    /// Marks the cells the beams of `scan` taken from `pose` (map frame) crossed.
    pub(crate) fn add_scan(&mut self, pose: &crate::geom::Pose, scan: &crate::scan::Scan) {
        use crate::mapping::ray::{grid_from_world, walk_segment};
        let frame = self.seen.frame;
        let from = grid_from_world(&frame, pose.position());
        for (i, &r) in scan.ranges_m.iter().enumerate() {
            if !r.is_finite() {
                continue;
            }
            let a = pose.theta_rad + scan.beam_angle_rad(i);
            let end = pose.position()
                + crate::geom::Vec2::new(a.cos(), a.sin()) * r.min(scan.max_range_m);
            walk_segment(from, grid_from_world(&frame, end), |c| {
                if let Some(k) = frame.index(c) {
                    self.seen.data[k] = true;
                }
                true
            });
        }
    }

    /// The grid's cell area (m2).
    pub(crate) fn cell_area_m2(&self) -> f64 {
        self.seen.frame.cell_area_m2()
    }
}

/// The team's run as one (see [`TeamResult::team`]) from its robots' results: `last` is the
/// robot whose exploration ended last, `rooms` the building's true rooms, `union` the team's
/// explored area and fraction when the robots' maps were separate (`None`: shared, every
/// robot's figures the team map's).
pub(super) fn team_run(
    robots: &[RunResult],
    last: usize,
    rooms: &[crate::geom::Polygon],
    union: Option<(f64, f64)>,
) -> RunResult {
    let mut team = robots[0].clone();
    let n = robots.len();
    if n > 1 {
        let at_end = &robots[(0..n)
            .max_by(|&a, &b| {
                robots[a]
                    .total_time_s
                    .total_cmp(&robots[b].total_time_s)
                    .then(b.cmp(&a))
            })
            .expect("a team has robots")];
        team.end_reason = if robots.iter().any(|r| r.end_reason == EndReason::TimeLimit) {
            EndReason::TimeLimit
        } else {
            robots[last].end_reason
        };
        team.stopped_early = team.end_reason == EndReason::EarlyStop;
        team.exploration_time_s = robots[last].exploration_time_s;
        team.total_time_s = at_end.total_time_s;
        team.explored_area_m2 = at_end.explored_area_m2;
        team.explored_fraction = at_end.explored_fraction;
        if let Some((area_m2, fraction)) = union {
            team.explored_area_m2 = area_m2;
            team.explored_fraction = fraction;
        }
        team.map = at_end.map.clone();
        team.map_quality = at_end.map_quality;
        team.frontier_cells_left = robots[last].frontier_cells_left;
        team.rooms_unexplored = at_end.rooms_unexplored;
        team.rooms_never_entered = (!rooms.is_empty()).then(|| {
            rooms
                .iter()
                .filter(|room| {
                    !robots
                        .iter()
                        .any(|r| r.trajectory.iter().any(|p| room.contains(p.position())))
                })
                .count()
        });
        team.path_length_m = robots.iter().map(|r| r.path_length_m).sum();
        team.layouts_computed = robots.iter().map(|r| r.layouts_computed).sum();
        team.layout_compute_s = robots.iter().map(|r| r.layout_compute_s).sum();
        team.strategy_compute_s = robots.iter().map(|r| r.strategy_compute_s).sum();
        team.blacklisted_goals = robots.iter().map(|r| r.blacklisted_goals).sum();
        team.scans = robots.iter().map(|r| r.scans).sum();
        team.scan_matches_accepted = robots.iter().map(|r| r.scan_matches_accepted).sum();
        team.plans = robots.iter().map(|r| r.plans).sum();
        let mut decisions: Vec<Decision> =
            robots.iter().flat_map(|r| r.decisions.clone()).collect();
        decisions.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
        team.decisions = decisions;
        team.progress = team_curve(robots);
        team.snapshots = Vec::new();
    }
    team
}

/// The area each of `coverages` swept (m2), the area more than one swept and the area any swept.
pub(super) fn overlap(coverages: &[&Coverage]) -> (Vec<f64>, f64, f64) {
    let cell = coverages.first().map_or(0.0, |c| c.cell_area_m2());
    let cells = coverages.first().map_or(0, |c| c.seen.data.len());
    let (mut overlap, mut any) = (0usize, 0usize);
    for i in 0..cells {
        let k = coverages.iter().filter(|c| c.seen.data[i]).count();
        any += (k > 0) as usize;
        overlap += (k > 1) as usize;
    }
    let seen = coverages
        .iter()
        .map(|c| c.seen.count_true() as f64 * cell)
        .collect();
    (seen, overlap as f64 * cell, any as f64 * cell)
}
