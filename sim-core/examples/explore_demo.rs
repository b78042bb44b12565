//! Times one exploration of a synthetic corridor building (development aid).
use std::time::Instant;

use sim_core::explore::{explore, ExploreConfig, Localization};
use sim_core::geom::{Polygon, Pose, Vec2};
use sim_core::{Building, Geometry};

fn main() {
    let n: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(8);
    let len = 5.0 * n as f64;
    let h = 10.0;
    let w = |a: (f64, f64), b: (f64, f64)| Polygon::thick_segment(Vec2::new(a.0, a.1), Vec2::new(b.0, b.1), 0.2);
    let mut solids = vec![w((0.0, 0.0), (len, 0.0)), w((len, 0.0), (len, h)), w((len, h), (0.0, h)), w((0.0, h), (0.0, 0.0))];
    for side in [4.0, 6.0] {
        for i in 0..n {
            let x0 = 5.0 * i as f64;
            solids.push(w((x0, side), (x0 + 1.0, side)));
            solids.push(w((x0 + 2.0, side), (x0 + 5.0, side)));
        }
    }
    for i in 1..n {
        let x = 5.0 * i as f64;
        solids.push(w((x, 0.0), (x, 4.0)));
        solids.push(w((x, 6.0), (x, h)));
    }
    let b = Building {
        name: "demo".into(),
        geometry: Geometry::Vector { outline: Polygon::rect(Vec2::new(-0.1, -0.1), Vec2::new(len + 0.1, h + 0.1)), solids },
        rooms: vec![],
        doors: vec![],
        start: Some(Pose::new(1.0, 5.0, 0.0)),
    };
    for loc in [Localization::GroundTruth, Localization::Slam] {
        let cfg = ExploreConfig { localization: loc, time_limit_s: std::env::args().nth(2).and_then(|s| s.parse().ok()).unwrap_or(1500.0), ..ExploreConfig::default() };
        let t = Instant::now();
        let r = explore(&b, b.start.unwrap(), &cfg, 1, &mut |p| if (p.time_s as u64) % 100 == 0 { eprintln!("  t={:.0} explored={:.3} wall={:.1}", p.time_s, p.explored_fraction, t.elapsed().as_secs_f64()) });
        let wall = t.elapsed().as_secs_f64();
        println!(
            "{loc:?}: {:?} t={:.0}s explored={:.3} of {:.0} m2 decisions={} scans={} matched={} quality={:?} wall={:.2}s speedup={:.0}x",
            r.end_reason, r.exploration_time_s, r.explored_fraction, r.free_area_m2, r.decisions.len(), r.scans,
            r.scan_matches_accepted, r.map_quality, wall, r.exploration_time_s / wall
        );
    }
}
