//! Laser throughput: scans per second (181 beams, 6 m) on a 3000 m2 building, one core.
//!
//! Run: `cargo bench --bench laser`. Prints scans/s for the simulator's laser (a scan's beams cast
//! together against the segments within range, `Walls::cast_fan`), for the same scans plus a
//! log-odds map update, and, as baselines measured in the same run, for parry2d's BVH over the
//! same segments (the simulator's laser up to 0.6.0, in `f32`) and for a brute-force caster that
//! tests every wall segment. Goal: >= 5000 scans/s.

use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sim_core::generate::{generate, BuildingKind, GenerateConfig};
use sim_core::grid::GridFrame;
use sim_core::mapping::log_odds::{LogOddsConfig, LogOddsMap};
use sim_core::sim::{LaserConfig, Walls};
use sim_core::{Building, Pose, Segment, Vec2};

fn poses(b: &Building, n: usize) -> Vec<Pose> {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let bb = b.bounds();
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let p = Vec2::new(
            rng.random_range(bb.min.x..bb.max.x),
            rng.random_range(bb.min.y..bb.max.y),
        );
        if b.is_free(p) {
            out.push(Pose::new(
                p.x,
                p.y,
                rng.random_range(-std::f64::consts::PI..std::f64::consts::PI),
            ));
        }
    }
    out
}

fn brute_force_cast(segs: &[Segment], o: Vec2, d: Vec2, max: f64) -> Option<f64> {
    let mut best = max;
    let mut hit = false;
    for s in segs {
        let e = s.b - s.a;
        let den = d.x * e.y - d.y * e.x;
        if den.abs() < 1e-12 {
            continue;
        }
        let w = s.a - o;
        let t = (w.x * e.y - w.y * e.x) / den;
        let u = (w.x * d.y - w.y * d.x) / den;
        if t >= 0.0 && t < best && (0.0..=1.0).contains(&u) {
            best = t;
            hit = true;
        }
    }
    hit.then_some(best)
}

fn bench(name: &str, b: &Building) {
    let segs = b.boundary_segments();
    let walls = Walls::new(&segs);
    let laser = LaserConfig::default();
    let ps = poses(b, 2000);
    let mut rng = ChaCha8Rng::seed_from_u64(1);

    // Warm up, then time the simulator's caster.
    for p in ps.iter().take(100) {
        std::hint::black_box(laser.scan(&walls, p, &mut rng));
    }
    let t = Instant::now();
    let mut beams = 0usize;
    for p in &ps {
        beams += std::hint::black_box(laser.scan(&walls, p, &mut rng))
            .ranges_m
            .len();
    }
    let fan_rate = ps.len() as f64 / t.elapsed().as_secs_f64();

    // parry2d's BVH over the same segments and beams (the casts only: the laser's figure also
    // draws the noise and builds the scans).
    let polyline = parry2d::shape::Polyline::new(
        segs.iter()
            .flat_map(|s| [s.a, s.b])
            .map(|p| parry2d::math::Point::new(p.x as f32, p.y as f32))
            .collect(),
        Some((0..segs.len() as u32).map(|i| [2 * i, 2 * i + 1]).collect()),
    );
    let t = Instant::now();
    for p in &ps {
        for i in 0..laser.beams {
            let a = p.theta_rad - laser.fov_rad / 2.0
                + i as f64 * laser.fov_rad / (laser.beams - 1) as f64;
            let ray = parry2d::query::Ray::new(
                parry2d::math::Point::new(p.x_m as f32, p.y_m as f32),
                parry2d::math::Vector::new(a.cos() as f32, a.sin() as f32),
            );
            std::hint::black_box(parry2d::query::RayCast::cast_ray(
                &polyline,
                &parry2d::math::Isometry::identity(),
                &ray,
                laser.max_range_m as f32,
                false,
            ));
        }
    }
    let bvh_rate = ps.len() as f64 / t.elapsed().as_secs_f64();

    // The same scans with a map update each.
    let frame = GridFrame::covering(&b.bounds(), 0.05, 1.0);
    let mut map = LogOddsMap::new(frame);
    let cfg = LogOddsConfig::default();
    let t = Instant::now();
    for p in &ps {
        let scan = laser.scan(&walls, p, &mut rng);
        map.insert_scan(p, &scan, &cfg);
    }
    let mapped_rate = ps.len() as f64 / t.elapsed().as_secs_f64();

    // Baseline: brute force over every segment (fewer scans: it is slow).
    let n_base = 100.min(ps.len());
    let t = Instant::now();
    for p in ps.iter().take(n_base) {
        for i in 0..laser.beams {
            let a = p.theta_rad - laser.fov_rad / 2.0
                + i as f64 * laser.fov_rad / (laser.beams - 1) as f64;
            std::hint::black_box(brute_force_cast(
                &segs,
                p.position(),
                Vec2::new(a.cos(), a.sin()),
                laser.max_range_m,
            ));
        }
    }
    let base_rate = n_base as f64 / t.elapsed().as_secs_f64();

    println!(
        "{name}: {:.0} m2 free, {} wall segments, {} beams/scan",
        b.free_area_m2(),
        segs.len(),
        beams / ps.len()
    );
    println!(
        "  the laser (fan caster):   {fan_rate:>9.0} scans/s  ({:.2}x the 5000 scans/s goal)",
        fan_rate / 5000.0
    );
    println!("  caster + log-odds update: {mapped_rate:>9.0} scans/s");
    println!(
        "  parry2d BVH (to 0.6.0):   {bvh_rate:>9.0} scans/s  (the fan is {:.2}x as fast)",
        fan_rate / bvh_rate
    );
    println!(
        "  brute-force baseline:     {base_rate:>9.0} scans/s  (the fan is {:.0}x faster)",
        fan_rate / base_rate
    );
}

fn main() {
    let school = generate(&GenerateConfig {
        seed: 3000,
        area_m2: 3000.0,
        kind: BuildingKind::School,
        name: "school-3000".into(),
        ..GenerateConfig::default()
    });
    bench("generated school (vector)", &school);
    let willow =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("maps/stage/willow-full.yaml");
    match floorcast_formats::read_building(&willow) {
        Ok(b) => bench("willow-full (raster, 0.10 m)", &b),
        Err(e) => println!("skipping willow-full: {e}"),
    }
}
