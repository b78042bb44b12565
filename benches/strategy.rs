//! The cost of an external strategy: `examples/strategies/baseline.py` (the built-in baseline's
//! rule in Python, over the strategy protocol, without map data) against the built-in
//! `baseline` on the same runs, which make the same decisions.
//!
//! `cargo bench --bench strategy` runs, for each building and seed, the built-in run and the
//! Python run alternately (`--repeat N` times each, default 2), and prints the median wall
//! times, their ratio (goal: at most 1.5) and the protocol's share of the Python run's wall
//! time (the summed time from sending each decide message to reading its reply, which holds
//! the Python interpreter's work too; the program's start-up is in the wall time, not in the
//! share; the start-up, from spawning the program to its hello reply, is printed apart). It
//! checks that the two runs made the same decisions.
//!
//! Buildings: `buildings/small.toml`, and from `maps/` Franch1 and freiburg_building79
//! (skipped when absent).

use std::path::{Path, PathBuf};
use std::time::Instant;

use floorcast_worker::external::ExternalStrategy;
use floorcast_worker::{run_job, Job, Settings, StrategyProgram, StrategyRef};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let repeat: usize = args
        .iter()
        .position(|a| a == "--repeat")
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(2);
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let maps = root.join("maps");
    let buildings: Vec<(PathBuf, u64)> = vec![
        (root.join("buildings/small.toml"), 1),
        (maps.join("schools/Franch1.yaml"), 2),
        (maps.join("radish/freiburg_building79.yaml"), 1),
    ];
    let program = StrategyProgram::new(
        vec![
            "python3".into(),
            root.join("examples/strategies/baseline.py")
                .to_string_lossy()
                .into_owned(),
        ],
        Vec::new(),
        Path::new("."),
        30.0,
    )
    .expect("the example exists");
    println!(
        "{:<24} {:>5} {:>10} {:>10} {:>7} {:>10} {:>9} {:>9}",
        "building", "seed", "built-in", "python", "ratio", "protocol", "start-up", "decisions"
    );
    let mut ratios = Vec::new();
    for (path, seed) in buildings {
        if !path.exists() {
            println!("{}: not found, skipped", path.display());
            continue;
        }
        let building = floorcast_formats::read_building(&path).expect("building reads");
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let job = |program: Option<StrategyProgram>| Job {
            building: &building,
            building_name: name.clone(),
            strategy: StrategyRef::resolve("baseline", program).expect("a built-in strategy"),
            seed,
            settings: Settings::default(),
            start: None,
            snapshot_fractions: Vec::new(),
        };
        let (mut built_in, mut python, mut shares) = (Vec::new(), Vec::new(), Vec::new());
        let mut start_up = Vec::new();
        let mut decisions = (0, 0);
        for _ in 0..repeat {
            let t = Instant::now();
            let a = run_job(&job(None), &mut |_| {}).expect("built-in run");
            built_in.push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            let b = run_job(&job(Some(program.clone())), &mut |_| {}).expect("python run");
            let wall = t.elapsed().as_secs_f64();
            python.push(wall);
            shares.push(b.summary.strategy_compute_s.unwrap_or(0.0) / wall);
            assert_eq!(
                a.result.decisions, b.result.decisions,
                "{name}: the python baseline decided differently"
            );
            decisions = (a.summary.decisions, b.summary.strategy_replies.unwrap_or(0));
            let t = Instant::now();
            let probe = ExternalStrategy::start(&program).expect("the program starts");
            start_up.push(t.elapsed().as_secs_f64());
            let _ = probe.finish();
        }
        let (a, b) = (median(&mut built_in), median(&mut python));
        ratios.push(b / a);
        println!(
            "{:<24} {:>5} {:>9.2}s {:>9.2}s {:>7.2} {:>9.1}% {:>7.0}ms {:>4}/{:<4}",
            name,
            seed,
            a,
            b,
            b / a,
            median(&mut shares) * 100.0,
            median(&mut start_up) * 1000.0,
            decisions.0,
            decisions.1
        );
    }
    println!(
        "median ratio python/built-in: {:.2} (goal: at most 1.5); decisions: goals chosen / decide messages answered",
        median(&mut ratios)
    );
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}
