//! What a team costs (issue 81's goal: a team of N robots costs at most N times one robot per
//! simulated second). `cargo bench --bench team` explores `maps/plans/VILLAGE.xml` (a real
//! plan, 3216 m² explorable) with `team-nearest` (and `team-minpos`, which also searches a path
//! from every teammate at each decision) for teams of 1, 2 and 4 robots, whole runs and the
//! first 600 simulated seconds, the team sizes alternating (`--repeat N` rounds, default 1;
//! `--seeds A,B`, default 1,2). It prints, per team size, the median wall milliseconds per
//! simulated second, its ratio to one robot's measured in the same rounds, that ratio over N
//! (the goal: at most 1), and the decisions per robot per simulated second (a robot of a team
//! decides more often than alone: its teammates take its frontiers).

use std::path::PathBuf;
use std::time::Instant;

use floorcast_worker::{run_job, Job, Settings, StrategyRef};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let repeat: usize = arg("--repeat").and_then(|v| v.parse().ok()).unwrap_or(1);
    let seeds: Vec<u64> = arg("--seeds")
        .map(|v| v.split(',').filter_map(|s| s.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![1, 2]);
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("maps/plans/VILLAGE.xml");
    let building = floorcast_formats::read_building(&path).expect("the plan reads");
    println!(
        "{:<14} {:>9} {:>5} {:>10} {:>10} {:>8} {:>8} {:>10}",
        "strategy", "span", "N", "sim s", "ms/sim s", "xN=1", "/N", "dec/rob/s"
    );
    for strategy in ["team-nearest", "team-minpos"] {
        for limit_s in [None, Some(600.0)] {
            // Per team size: (wall ms per simulated second, decisions per robot-second) of
            // each run, and the simulated seconds.
            let sizes = [1usize, 2, 4];
            let mut per: Vec<Vec<(f64, f64, f64)>> = vec![Vec::new(); sizes.len()];
            for _ in 0..repeat {
                for &seed in &seeds {
                    for (k, &n) in sizes.iter().enumerate() {
                        let mut settings = Settings {
                            robots: n,
                            ..Settings::default()
                        };
                        if let Some(l) = limit_s {
                            settings.time_limit_s = l;
                        }
                        let job = Job {
                            building: &building,
                            building_name: "VILLAGE".into(),
                            strategy: StrategyRef::built_in(strategy).unwrap(),
                            seed,
                            settings,
                            start: None,
                            snapshot_fractions: Vec::new(),
                        };
                        let t0 = Instant::now();
                        let out = run_job(&job, &mut |_| {}).expect("the run");
                        let wall_s = t0.elapsed().as_secs_f64();
                        let sim_s = out.result.total_time_s;
                        let decisions = out.result.decisions.len() as f64;
                        per[k].push((1000.0 * wall_s / sim_s, decisions / n as f64 / sim_s, sim_s));
                    }
                }
            }
            let median = |v: &mut Vec<f64>| {
                v.sort_by(f64::total_cmp);
                v[v.len() / 2]
            };
            let base = median(&mut per[0].iter().map(|p| p.0).collect());
            for (k, &n) in sizes.iter().enumerate() {
                let ms = median(&mut per[k].iter().map(|p| p.0).collect());
                let rate = median(&mut per[k].iter().map(|p| p.1).collect());
                let sim = median(&mut per[k].iter().map(|p| p.2).collect());
                println!(
                    "{:<14} {:>9} {:>5} {:>10.0} {:>10.3} {:>8.2} {:>8.2} {:>10.3}",
                    strategy,
                    limit_s.map_or("whole".to_string(), |l| format!("{l:.0} s")),
                    n,
                    sim,
                    ms,
                    ms / base,
                    ms / base / n as f64,
                    rate
                );
            }
        }
    }
}
