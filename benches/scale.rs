//! How the cost grows with the building (issue 61): for generated buildings of 1000, 4000,
//! 12000 and 50000 m² of both kinds, each strategy's speed (simulated seconds per wall second,
//! "x real time") over the first `--sim-s` simulated seconds and its process's peak memory, and
//! the ratios to the 1000 m² building of the same kind and strategy (the goals: a 12000 m²
//! building at least 0.67 of the 1000 m² speed, 50000 m² at least 0.5, peak memory at most
//! 1 GB; a layout strategy at least 0.8 of `baseline`'s speed on the same building).
//!
//! `cargo bench --bench scale -- [--sim-s 3000] [--seed 77] [--run-seed 1] [--areas
//! 1000,4000,12000,50000] [--kinds office,school] [--strategies baseline,layout-es]
//! [--max-cells 40000000] [--layout-update-fraction 0.1] [--distance-bound-m 0] [--repeat 1]`
//! (`--layout-update-fraction`, `--distance-bound-m`: the settings of every run, by default the
//! settings' defaults; 0 the paper's layout trigger and exact distances, docs/scale.md;
//! `--repeat N`: N runs of each, the
//! strategies alternating per round, the run of median speed printed: a 1000 m² run lasts a
//! couple of wall seconds, and its speed varies by up to a quarter between invocations)
//!
//! Per run it also prints the area explored per simulated second and the wall time per m²
//! explored, both up to 90 % explored (the last per cent's chase finds little area), with its
//! ratio to the 1000 m² building's (a robot in a large building's long corridors sees
//! more per second, and a run's work follows what it sees: docs/scale.md), the decisions per
//! 1000 simulated seconds, the mean number of candidates per decision, the wall time per
//! decision and the layouts computed: a large building's runs decide more often (more frontiers
//! vanish as corridors are seen), which the speed ratio counts but the work per decision does
//! not.
//!
//! Each run is a process of its own (this program again, with `--case`), so that its peak
//! resident memory (`VmHWM`, Linux) is its own; the building is generated in it, before the
//! clock starts. The strategies run alternately per building, so a change of the machine's
//! speed during the benchmark touches them alike. A run that ends (explored, or stopped early)
//! before `--sim-s` is timed over its whole length.

use std::process::Command;
use std::time::Instant;

use floorcast_worker::{run_job, Job, Settings, StrategyRef};
use sim_core::generate::{generate, BuildingKind, GenerateConfig};

/// The cell budget of the runs (`--max-cells`): a generated 50000 m² office spans about
/// 820 m x 70 m, 28 million cells at 0.05 m, a school 25.6 million (docs/limits.md).
const DEFAULT_BENCH_MAX_CELLS: &str = "40000000";

fn arg<'a>(args: &'a [String], name: &str) -> Option<&'a str> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map(String::as_str)
}

fn list(args: &[String], name: &str, default: &str) -> Vec<String> {
    arg(args, name)
        .unwrap_or(default)
        .split(',')
        .map(str::to_string)
        .collect()
}

fn kind_of(k: &str) -> BuildingKind {
    match k {
        "office" => BuildingKind::Office,
        "school" => BuildingKind::School,
        _ => panic!("--kinds: '{k}' is not office or school"),
    }
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

/// One run in this process: prints `case SIM_S WALL_S FREE_M2 EXPLORED PEAK_MB END`.
fn case(args: &[String]) {
    let kind = kind_of(arg(args, "--kind").expect("--kind"));
    let area: f64 = arg(args, "--area").expect("--area").parse().expect("area");
    let seed: u64 = arg(args, "--seed").unwrap_or("77").parse().expect("seed");
    let run_seed: u64 = arg(args, "--run-seed")
        .unwrap_or("1")
        .parse()
        .expect("run seed");
    let sim_s: f64 = arg(args, "--sim-s")
        .unwrap_or("3000")
        .parse()
        .expect("sim s");
    let strategy = arg(args, "--strategy").expect("--strategy").to_string();
    // (A 50000 m² building's 0.05 m grid is above the default budget of 25 million cells: the
    // documented raised budget, as `--max-cells` raises it for the binary.)
    let max_cells: u64 = arg(args, "--max-cells")
        .unwrap_or(DEFAULT_BENCH_MAX_CELLS)
        .parse()
        .expect("--max-cells: a number of cells");
    floorcast_formats::limits::set_max_cells(max_cells);
    let building = generate(&GenerateConfig {
        seed,
        area_m2: area,
        kind,
        ..Default::default()
    });
    let layout_update_fraction: f64 = arg(args, "--layout-update-fraction")
        .map_or(Ok(Settings::default().layout_update_fraction), str::parse)
        .expect("--layout-update-fraction: a number");
    let distance_bound_m: f64 = arg(args, "--distance-bound-m")
        .map_or(Ok(Settings::default().distance_bound_m), str::parse)
        .expect("--distance-bound-m: a number");
    let settings = Settings {
        time_limit_s: sim_s,
        layout_update_fraction,
        distance_bound_m,
        ..Settings::default()
    };
    let job = Job {
        building: &building,
        building_name: format!("gen-{area}"),
        strategy: StrategyRef::built_in(&strategy).expect("--strategy: a built-in strategy"),
        seed: run_seed,
        settings,
        start: None,
        snapshot_fractions: Vec::new(),
    };
    let t = Instant::now();
    // The wall time, simulated time and area explored when the run first reached
    // `EXPLORING_UNTIL` explored: what follows is the last per cent's chase, which costs wall
    // time and finds little area.
    let mut exploring: Option<(f64, f64, f64)> = None;
    let out = run_job(&job, &mut |s| {
        if exploring.is_none() && s.explored_fraction >= EXPLORING_UNTIL {
            exploring = Some((t.elapsed().as_secs_f64(), s.time_s, s.explored_area_m2));
        }
    })
    .expect("the run");
    let wall = t.elapsed().as_secs_f64();
    let (wall_x, sim_x, area_x) = exploring.unwrap_or((
        wall,
        out.summary.total_time_s,
        out.result.free_area_m2 * out.summary.explored_fraction,
    ));
    let decisions = &out.result.decisions;
    let candidates = decisions.iter().map(|d| d.candidates).sum::<usize>() as f64
        / decisions.len().max(1) as f64;
    println!(
        "case {} {} {} {} {} {:?} {} {} {} {} {} {}",
        out.summary.total_time_s,
        wall,
        out.result.free_area_m2,
        out.summary.explored_fraction,
        peak_rss_mb().unwrap_or(f64::NAN),
        out.summary.end_reason,
        decisions.len(),
        candidates,
        out.result.layouts_computed,
        wall_x,
        sim_x,
        area_x,
    );
}

/// The explored fraction up to which the area explored per simulated second and the wall time
/// per m² explored are measured (the whole run if it stops before).
const EXPLORING_UNTIL: f64 = 0.9;

#[derive(Debug, Clone)]
struct Row {
    kind: String,
    area: f64,
    strategy: String,
    free_m2: f64,
    sim_s: f64,
    speed: f64,
    peak_mb: f64,
    explored: f64,
    end: String,
    /// Decisions made, their mean number of candidates, layouts computed, wall seconds.
    decisions: f64,
    candidates: f64,
    layouts: f64,
    wall_s: f64,
    /// Up to `EXPLORING_UNTIL` explored (or the end): wall s, simulated s, m² explored.
    exploring: (f64, f64, f64),
}

impl Row {
    /// Area explored per simulated second, up to `EXPLORING_UNTIL` explored.
    fn m2_per_s(&self) -> f64 {
        self.exploring.2 / self.exploring.1
    }

    /// Wall milliseconds per m² explored, up to `EXPLORING_UNTIL` explored.
    fn ms_per_m2(&self) -> f64 {
        self.exploring.0 * 1000.0 / self.exploring.2
    }
}

fn measure(args: &[String], kind: &str, area: &str, strategy: &str) -> Row {
    let exe = std::env::current_exe().expect("this program");
    let mut cmd = Command::new(exe);
    cmd.args([
        "--case",
        "--kind",
        kind,
        "--area",
        area,
        "--strategy",
        strategy,
    ]);
    for k in [
        "--sim-s",
        "--seed",
        "--run-seed",
        "--max-cells",
        "--layout-update-fraction",
        "--distance-bound-m",
    ] {
        if let Some(v) = arg(args, k) {
            cmd.args([k, v]);
        }
    }
    let o = cmd.output().expect("the case runs");
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text
        .lines()
        .find_map(|l| l.strip_prefix("case "))
        .unwrap_or_else(|| {
            panic!(
                "{kind} {area} {strategy}: no result: {}",
                String::from_utf8_lossy(&o.stderr)
            )
        });
    let f: Vec<&str> = line.split_whitespace().collect();
    let num = |i: usize| f[i].parse::<f64>().unwrap_or(f64::NAN);
    Row {
        kind: kind.into(),
        area: area.parse().unwrap_or(f64::NAN),
        strategy: strategy.into(),
        sim_s: num(0),
        speed: num(0) / num(1),
        free_m2: num(2),
        explored: num(3),
        peak_mb: num(4),
        end: f.get(5).unwrap_or(&"?").to_string(),
        decisions: num(6),
        candidates: num(7),
        layouts: num(8),
        wall_s: num(1),
        exploring: (num(9), num(10), num(11)),
    }
}

/// The run of median speed among `runs` (the lower middle one of an even number), with the
/// greatest peak memory of them.
fn median_run(runs: &mut [Row]) -> Row {
    runs.sort_by(|a, b| a.speed.total_cmp(&b.speed));
    let peak = runs.iter().map(|r| r.peak_mb).fold(f64::NAN, f64::max);
    Row {
        peak_mb: peak,
        ..runs[(runs.len() - 1) / 2].clone()
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--case") {
        return case(&args);
    }
    let areas = list(&args, "--areas", "1000,4000,12000,50000");
    let kinds = list(&args, "--kinds", "office,school");
    let strategies = list(&args, "--strategies", "baseline,layout-es");
    println!(
        "generated buildings (seed {}), run seed {}, first {} simulated s of each run, layout_update_fraction {}, distance_bound_m {}, the median of {} runs",
        arg(&args, "--seed").unwrap_or("77"),
        arg(&args, "--run-seed").unwrap_or("1"),
        arg(&args, "--sim-s").unwrap_or("3000"),
        arg(&args, "--layout-update-fraction")
            .map_or(Settings::default().layout_update_fraction.to_string(), str::to_string),
        arg(&args, "--distance-bound-m")
            .map_or(Settings::default().distance_bound_m.to_string(), str::to_string),
        arg(&args, "--repeat").unwrap_or("1"),
    );
    println!(
        "{:<7} {:>7} {:>8} {:<10} {:>7} {:>9} {:>8} {:>9} {:>8} {:>9} {:>10} {:>7} {:>6} {:>7} {:>8} {:>6} {:>6} {:>10}",
        "kind",
        "area",
        "free m2",
        "strategy",
        "sim s",
        "x real",
        "peak MB",
        "explored",
        "vs 1000",
        "vs base",
        "end",
        "dec/ks",
        "cand",
        "ms/dec",
        "layouts",
        "m2/s",
        "ms/m2",
        "m2 vs 1000"
    );
    let repeat: usize = arg(&args, "--repeat")
        .unwrap_or("1")
        .parse()
        .ok()
        .filter(|&n| n > 0)
        .expect("--repeat: a number of runs, at least 1");
    let mut rows: Vec<Row> = Vec::new();
    for kind in &kinds {
        for area in &areas {
            // Each strategy's runs on this building, the strategies alternating per round.
            let mut runs: Vec<Vec<Row>> = vec![Vec::new(); strategies.len()];
            for _ in 0..repeat {
                for (k, strategy) in strategies.iter().enumerate() {
                    runs[k].push(measure(&args, kind, area, strategy));
                }
            }
            for mut of_strategy in runs {
                let r = median_run(&mut of_strategy);
                let first = rows
                    .iter()
                    .find(|s| s.kind == r.kind && s.strategy == r.strategy);
                let small = first.map_or(r.speed, |s| s.speed);
                let small_ms_m2 = first.map_or(r.ms_per_m2(), Row::ms_per_m2);
                let base = rows
                    .iter()
                    .find(|s| s.kind == r.kind && s.area == r.area && s.strategy == strategies[0])
                    .map_or(r.speed, |s| s.speed);
                println!(
                    "{:<7} {:>7} {:>8.0} {:<10} {:>7.0} {:>8.0}x {:>8.0} {:>9.4} {:>8.2} {:>9.2} {:>10} {:>7.0} {:>6.0} {:>7.1} {:>8.0} {:>6.2} {:>6.2} {:>10.2}",
                    r.kind,
                    r.area,
                    r.free_m2,
                    r.strategy,
                    r.sim_s,
                    r.speed,
                    r.peak_mb,
                    r.explored,
                    r.speed / small,
                    r.speed / base,
                    r.end,
                    r.decisions * 1000.0 / r.sim_s,
                    r.candidates,
                    r.wall_s * 1000.0 / r.decisions.max(1.0),
                    r.layouts,
                    r.m2_per_s(),
                    r.ms_per_m2(),
                    small_ms_m2 / r.ms_per_m2()
                );
                rows.push(r);
            }
        }
    }
    println!("vs 1000: speed / the same kind's and strategy's first area's; vs base: speed / the first strategy's on the same building");
    println!("m2/s: area explored per simulated s, ms/m2: wall ms per m2 explored, both up to {} % explored (or the run's end); m2 vs 1000: the first area's ms/m2 / this one's (the speed per area explored, not per simulated s: docs/scale.md)", EXPLORING_UNTIL * 100.0);
    println!("dec/ks: decisions per 1000 simulated s; cand: candidates per decision (mean); ms/dec: wall ms per decision (the whole run's wall time / decisions); layouts: layouts computed");
}
