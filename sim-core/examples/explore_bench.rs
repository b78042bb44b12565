//! Speed and quality of a full exploration of a generated 2000 m2 school.
//!
//! `cargo run --release -p sim-core --example explore_bench -- [seed] [area_m2] [office|clutter|rot]...`
//! prints, per run, the simulated time, the wall time, the speed-up (simulated seconds per wall
//! second), exploration quality, the pose error of the SLAM estimate, the run's fingerprint and
//! the process's peak memory (Linux). The baseline in the same
//! run is real time (speed-up 1) and the same exploration with the odometry-only localization
//! (no scan matching), which isolates the cost of the matcher (with `baseline`). Settings to
//! try: `upd=D,R,T` (map update after D m, R rad or T s) and `redecide=S` (the re-decision
//! period).

// Benchmarks, examples and integration tests run at the edge: they read files and clocks,
// which the kernel itself may not (sim-core/clippy.toml).
#![allow(clippy::disallowed_types, clippy::disallowed_methods)]
use std::time::Instant;

use sim_core::building::Building;
use sim_core::explore::{explore, ExploreConfig, Localization, RunResult};
use sim_core::generate::{generate, BuildingKind, GenerateConfig};
use sim_core::Pose;

fn pose_errors(r: &RunResult) -> (f64, f64) {
    let mut max_xy = 0.0f64;
    let mut max_th = 0.0f64;
    for (t, e) in r.trajectory.iter().zip(&r.estimated_trajectory) {
        let d = t.between(e);
        max_xy = max_xy.max((t.position() - e.position()).norm());
        max_th = max_th.max(d.theta_rad.abs());
    }
    (max_xy, max_th.to_degrees())
}

/// The process's peak resident memory (`VmHWM` of `/proc/self/status`), in MB.
fn peak_rss_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let kb: f64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb / 1024.0)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let seed: u64 = args.first().and_then(|s| s.parse().ok()).unwrap_or(1);
    let area_m2: f64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(2000.0);
    let has = |w: &str| args.iter().any(|a| a == w);
    let building = generate(&GenerateConfig {
        seed,
        area_m2,
        kind: if has("office") {
            BuildingKind::Office
        } else {
            BuildingKind::School
        },
        clutter: has("clutter"),
        rotation_rad: if has("rot") { 0.4 } else { 0.0 },
        ..Default::default()
    });
    let start = building
        .default_start(ExploreConfig::default().sim.robot.radius_m)
        .expect("building has room to start")
        .0;
    let mut locs = vec![Localization::Slam];
    if has("baseline") {
        locs.push(Localization::Odometry);
    }
    let mut slam_speedup = 0.0;
    for loc in locs {
        let mut cfg = ExploreConfig {
            localization: loc,
            ..ExploreConfig::default()
        };
        cfg.calibrate_odometry = !has("nocal");
        apply_settings(&mut cfg, &args);
        let t0 = Instant::now();
        let r = explore(&building, start, &cfg, seed, &mut |_| {});
        let wall_s = t0.elapsed().as_secs_f64();
        let speedup = r.total_time_s / wall_s;
        print_run(loc, &r, wall_s, speedup);
        // A fingerprint of the run (every pose, decision, progress sample and map cell), so
        // that a change meant to be only faster can be checked to leave the run bit-identical.
        println!("  fingerprint {}", r.fingerprint());
        println!(
            "  peak memory of the process so far {}",
            peak_rss_mb().map_or("n/a (Linux only)".to_string(), |m| format!("{m:.0} MB"))
        );
        if has("trace") {
            trace(&building, start, &r);
        }
        if loc == Localization::Slam {
            slam_speedup = speedup;
        } else {
            println!(
                "slam/odometry wall-time ratio {:.2}",
                speedup / slam_speedup.max(1e-9)
            );
        }
    }
    println!("speed-up vs real time: {slam_speedup:.0}x (target >= 1000x)");
}

/// Applies the settings among `args`: `redecide=S` and `upd=D,R,T`.
fn apply_settings(cfg: &mut ExploreConfig, args: &[String]) {
    for a in args {
        if let Some(v) = a.strip_prefix("redecide=").and_then(|v| v.parse().ok()) {
            cfg.redecide_period_s = v;
        }
        if let Some(v) = a.strip_prefix("upd=") {
            let v: Vec<f64> = v.split(',').filter_map(|x| x.parse().ok()).collect();
            if let [d, r, t] = v[..] {
                cfg.map_update_distance_m = d;
                cfg.map_update_angle_rad = r;
                cfg.map_update_period_s = t;
            }
        }
    }
}

/// Prints a run's line: times, speed-up, quality, pose errors and counts.
fn print_run(loc: Localization, r: &RunResult, wall_s: f64, speedup: f64) {
    let (exy, eth) = pose_errors(r);
    println!(
        "{:<12} free {:6.0} m2  explored {:.3}  end {:<12}  sim {:6.0} s  wall {:6.2} s  \
         speed-up {:6.0}x real time  decisions {:4}  path {:5.0} m  occ-prec {:.3} (aligned {:.3})  \
         free-prec {:.3}  max pose err {:.2} m {:.1} deg  matches {}/{}  plans {}",
        loc.as_str(),
        r.free_area_m2,
        r.explored_fraction,
        r.end_reason.as_str(),
        r.total_time_s,
        wall_s,
        speedup,
        r.decisions.len(),
        r.path_length_m,
        r.map_quality.occupied_precision,
        r.map_quality.occupied_precision_aligned,
        r.map_quality.free_precision,
        exy,
        eth,
        r.scan_matches_accepted,
        r.scans,
        r.plans,
    );
}

/// Prints the wrong occupied cells of the run's map by their distance to solid space, and the
/// pose error along the trajectory.
fn trace(building: &Building, start: Pose, r: &RunResult) {
    // Wrong occupied cells by their distance to solid space.
    let truth = building.reachable_free(r.map.frame, start.position());
    let solid = sim_core::grid::Grid {
        frame: truth.frame,
        data: truth.data.iter().map(|f| !f).collect(),
    };
    let dist = sim_core::distance::distance_to(&solid);
    let mut hist = [0usize; 6];
    for (i, s) in r.map.data.iter().enumerate() {
        if *s == sim_core::grid::Occupancy::Occupied {
            let d = dist.data[i];
            let k = if d <= 1.5 {
                0
            } else if d <= 2.5 {
                1
            } else if d <= 3.5 {
                2
            } else if d <= 5.5 {
                3
            } else if d <= 10.5 {
                4
            } else {
                5
            };
            hist[k] += 1;
        }
    }
    println!("  occupied cells by distance to solid (<=1.5, 2, 3, 4-5, 6-10, >10 cells): {hist:?}");
    let n = r.trajectory.len();
    for k in (0..n).step_by((n / 60).max(1)) {
        let (t, e) = (r.trajectory[k], r.estimated_trajectory[k]);
        println!(
            "  update {k:5}  true ({:6.2}, {:6.2}, {:6.1} deg)  err {:.3} m {:+.2} deg",
            t.x_m,
            t.y_m,
            t.theta_rad.to_degrees(),
            (t.position() - e.position()).norm(),
            t.between(&e).theta_rad.to_degrees()
        );
    }
}
