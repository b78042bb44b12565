//! Timings of the mapping / frontier / planning / gain kernels on a synthetic 60 x 60 m
//! building at 0.05 m (1.44 M cells): `cargo run -p sim-core --release --example mapping_bench`.

// Benchmarks, examples and integration tests run at the edge: they read files and clocks,
// which the kernel itself may not (sim-core/clippy.toml).
#![allow(clippy::disallowed_types, clippy::disallowed_methods)]
use sim_core::frontier::detect::{detect_frontiers, detect_frontiers_in, Frontier, FrontierConfig};
use sim_core::gain::information_gain;
use sim_core::mapping::distance_field::ObstacleDistance;
use sim_core::mapping::log_odds::{LogOddsConfig, LogOddsMap};
use sim_core::mapping::ray::{grid_from_world, walk_segment};
use sim_core::mapping::scan_match::{match_scan, ScanMatchConfig};
use sim_core::plan::dijkstra::{dijkstra, wall_cost};
use sim_core::plan::inflate::{downsample, nearest_traversable, traversable};
use sim_core::plan::waypoints::waypoints;
use sim_core::utility::{best_candidate, CandidateScore};
use sim_core::{Bitmap, Cell, Grid, GridFrame, Pose, Scan, Vec2};
use std::time::Instant;

const SIZE_M: f64 = 60.0;
const RES_M: f64 = 0.05;

/// Outer walls and a 6 m lattice of inner walls with 1 m doors, 0.1 m thick.
fn building(frame: GridFrame) -> Bitmap {
    let mut walls = Grid::filled(frame, false);
    for (c, w) in walls.data.iter_mut().enumerate() {
        let p = frame.world_from_cell(frame.cell_of_index(c));
        let on = |v: f64| (v % 6.0) < 0.1;
        let door = |v: f64| ((v % 6.0) - 3.0).abs() < 0.5;
        let inside = p.x > 0.5 && p.y > 0.5 && p.x < SIZE_M - 0.5 && p.y < SIZE_M - 0.5;
        let outer = !inside && p.x > 0.4 && p.y > 0.4 && p.x < SIZE_M - 0.4 && p.y < SIZE_M - 0.4;
        *w = outer || (inside && ((on(p.x) && !door(p.y)) || (on(p.y) && !door(p.x))));
    }
    walls
}

fn cast(walls: &Bitmap, pose: &Pose) -> Scan {
    let n = 181;
    let angle_min_rad = -std::f64::consts::FRAC_PI_2;
    let inc = std::f64::consts::PI / (n - 1) as f64;
    let max_range_m = 6.0;
    let start = grid_from_world(&walls.frame, pose.position());
    let ranges_m = (0..n)
        .map(|i| {
            let a = pose.theta_rad + angle_min_rad + i as f64 * inc;
            let r = max_range_m / RES_M;
            let end = [start[0] + a.cos() * r, start[1] + a.sin() * r];
            let mut hit = max_range_m;
            walk_segment(start, end, |c| {
                if walls.get(c) == Some(&true) {
                    let q = walls.frame.world_from_cell(c);
                    hit = (q - pose.position()).norm().min(max_range_m - 1e-6);
                    return false;
                }
                true
            });
            hit
        })
        .collect();
    Scan {
        angle_min_rad,
        angle_increment_rad: inc,
        max_range_m,
        ranges_m,
    }
}

fn us(t: Instant, n: usize) -> f64 {
    t.elapsed().as_secs_f64() * 1e6 / n.max(1) as f64
}

fn main() {
    let frame = GridFrame::new(
        Vec2::zeros(),
        RES_M,
        (SIZE_M / RES_M) as u32,
        (SIZE_M / RES_M) as u32,
    );
    let walls = building(frame);
    let poses = lattice_poses(&walls);
    let scans: Vec<Scan> = poses.iter().map(|p| cast(&walls, p)).collect();
    let cfg = LogOddsConfig::default();
    let map = bench_insert(frame, &poses, &scans, &cfg);
    let (m2, field) = bench_distance_field(frame, &map, &poses, &scans, &cfg);
    bench_scan_match(&field, &m2, &poses, &scans);
    let fs = bench_frontiers(&map);
    bench_planning(&map, &field, &poses, &fs);
}

/// Poses on a lattice over the left 60% of the building (room centres and doorways), those in
/// free space.
fn lattice_poses(walls: &Bitmap) -> Vec<Pose> {
    let frame = walls.frame;
    let mut poses = Vec::new();
    for iy in 0..40 {
        for ix in 0..24 {
            let p = Pose::new(
                1.5 + 1.5 * ix as f64,
                1.2 + 1.45 * iy as f64,
                0.7 * (ix + iy) as f64,
            );
            if walls.get(frame.cell_from_world(p.position())) == Some(&false) {
                poses.push(p);
            }
        }
    }
    poses
}

/// Times `insert_scan` of every scan; returns the map.
fn bench_insert(
    frame: GridFrame,
    poses: &[Pose],
    scans: &[Scan],
    cfg: &LogOddsConfig,
) -> LogOddsMap {
    let mut map = LogOddsMap::new(frame);
    let t = Instant::now();
    for (p, s) in poses.iter().zip(scans) {
        map.insert_scan(p, s, cfg);
    }
    println!(
        "insert_scan (181 beams, 6 m): {:8.1} us/scan over {} scans",
        us(t, scans.len()),
        scans.len()
    );
    map
}

/// Times the distance field built from scratch against updated per scan (checked equal);
/// returns the map built again and its field.
fn bench_distance_field(
    frame: GridFrame,
    map: &LogOddsMap,
    poses: &[Pose],
    scans: &[Scan],
    cfg: &LogOddsConfig,
) -> (LogOddsMap, ObstacleDistance) {
    // Incremental distance field: rebuild from scratch vs update per scan.
    let t = Instant::now();
    let full = ObstacleDistance::from_grid(&map.occupancy, 8);
    println!(
        "ObstacleDistance::from_grid:  {:8.1} us (full map, cap 8 cells)",
        us(t, 1)
    );
    let mut m2 = LogOddsMap::new(frame);
    let mut field = ObstacleDistance::new(frame, 8);
    let mut t_ins = 0.0;
    let mut t_upd = 0.0;
    for (p, s) in poses.iter().zip(scans) {
        let t = Instant::now();
        m2.insert_scan(p, s, cfg);
        t_ins += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let flips = m2.take_occupied_flips();
        field.update(&m2.occupancy, &flips);
        t_upd += t.elapsed().as_secs_f64();
    }
    assert_eq!(field, full);
    println!(
        "  incremental: insert {:6.1} us + field update {:6.1} us per scan",
        t_ins * 1e6 / scans.len() as f64,
        t_upd * 1e6 / scans.len() as f64
    );
    (m2, field)
}

/// Times scan matching from perturbed priors and from the exact one.
fn bench_scan_match(field: &ObstacleDistance, m2: &LogOddsMap, poses: &[Pose], scans: &[Scan]) {
    // Scan matching from perturbed priors.
    let mcfg = ScanMatchConfig::default();
    let (mut err_sum, mut accepted, mut searched) = (0.0, 0, 0);
    let t = Instant::now();
    for (k, (p, s)) in poses.iter().zip(scans).enumerate() {
        let d = [(0.05, -0.03, 1.0), (-0.04, 0.05, -1.5), (0.1, 0.0, 3.0)][k % 3];
        let prior = Pose::new(p.x_m + d.0, p.y_m + d.1, p.theta_rad + f64::to_radians(d.2));
        let r = match_scan(field, m2, &prior, s, &mcfg);
        accepted += r.accepted as usize;
        searched += r.searched as usize;
        let e = p.between(&r.pose);
        err_sum += e.x_m.hypot(e.y_m);
    }
    println!(
        "match_scan:                    {:8.1} us/scan (accepted {}/{}, searched {}, mean error {:.3} m)",
        us(t, scans.len()),
        accepted,
        scans.len(),
        searched,
        err_sum / scans.len() as f64
    );
    let prior = poses[10];
    let t = Instant::now();
    for _ in 0..100 {
        std::hint::black_box(match_scan(field, m2, &prior, &scans[10], &mcfg));
    }
    println!("  match_scan, exact prior:     {:8.1} us", us(t, 100));
}

/// Times frontier detection on the full grid and in the known box (checked equal); returns
/// the frontiers.
fn bench_frontiers(map: &LogOddsMap) -> Vec<Frontier> {
    // Frontiers.
    let fcfg = FrontierConfig::with_min_length_m(0.3, RES_M);
    let t = Instant::now();
    let fs = detect_frontiers(&map.occupancy, &fcfg);
    println!(
        "detect_frontiers (full grid):  {:8.1} us, {} frontiers",
        us(t, 1),
        fs.len()
    );
    let (lo, hi) = map.known_bounds.unwrap();
    let t = Instant::now();
    let fs2 = detect_frontiers_in(&map.occupancy, lo, hi, &fcfg);
    println!("detect_frontiers_in (known bb):{:8.1} us", us(t, 1));
    assert_eq!(fs, fs2);
    fs
}

/// Times traversability, wall costs, Dijkstra (fine, with wall costs, coarse), the gains of the
/// frontiers `fs`, the paths and waypoints to them, and the choice of the best.
fn bench_planning(map: &LogOddsMap, field: &ObstacleDistance, poses: &[Pose], fs: &[Frontier]) {
    let frame = map.frame;
    // Planning.
    let radius_m = 0.2;
    let t = Instant::now();
    let trav = traversable(&map.occupancy, field, radius_m);
    println!(
        "traversable (from field):      {:8.1} us, {} cells",
        us(t, 1),
        trav.count_true()
    );
    let start = frame.cell_from_world(poses[0].position());
    let start = nearest_traversable(&trav, start, 6).unwrap();
    let t = Instant::now();
    let extra = wall_cost(field, radius_m, 0.2, 5);
    println!("wall_cost:                     {:8.1} us", us(t, 1));
    let t = Instant::now();
    let costs = dijkstra(&trav, start, None);
    println!("dijkstra 0.05 m:               {:8.1} us", us(t, 1));
    let t = Instant::now();
    let costs_pen = dijkstra(&trav, start, Some(&extra));
    println!("dijkstra 0.05 m + wall cost:   {:8.1} us", us(t, 1));
    let t = Instant::now();
    let coarse = downsample(&trav, 2);
    let cstart = nearest_traversable(
        &coarse,
        coarse.frame.cell_from_world(frame.world_from_cell(start)),
        3,
    )
    .unwrap();
    let costs_coarse = dijkstra(&coarse, cstart, None);
    println!("downsample + dijkstra 0.1 m:   {:8.1} us", us(t, 1));
    let mut reachable = 0;
    let mut wp_time = 0.0;
    let mut n_wp = 0;
    let mut cands = Vec::new();
    let t_gain = Instant::now();
    let gains: Vec<f64> = fs
        .iter()
        .map(|f| information_gain(&map.occupancy, f.candidate, 6.0))
        .collect();
    let gain_us = us(t_gain, fs.len());
    for (f, g) in fs.iter().zip(&gains) {
        let goal = nearest_traversable(&trav, f.candidate, 8);
        let d = goal.and_then(|c| costs.distance_m(c));
        if let Some(goal) = goal.filter(|_| d.is_some()) {
            reachable += 1;
            let t = Instant::now();
            let path = costs_pen.path_to(goal).unwrap_or_default();
            n_wp += waypoints(&path, &trav).len();
            wp_time += t.elapsed().as_secs_f64();
        }
        cands.push(CandidateScore {
            distance_m: d,
            gain_m2: *g,
        });
    }
    let _ = costs_coarse;
    println!(
        "information_gain (6 m, 360):   {:8.1} us/candidate over {} candidates",
        gain_us,
        fs.len()
    );
    println!(
        "path_to + waypoints:           {:8.1} us/goal ({} reachable, {} waypoints total)",
        wp_time * 1e6 / reachable.max(1) as f64,
        reachable,
        n_wp
    );
    let t = Instant::now();
    let best = best_candidate(&cands, 0.5);
    println!(
        "best_candidate:                {:8.1} us -> {:?}",
        us(t, 1),
        best
    );
    let _ = Cell::new(0, 0);
}
