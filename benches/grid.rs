//! Coordinator overhead and scaling of distributed grids.
//!
//! `cargo bench --bench grid` measures, in one run:
//! 1. trivial jobs (no simulation) through zenoh with 8 worker processes on TCP loopback, in
//!    jobs per second, against the same jobs through the in-process channels of local mode
//!    (the baseline);
//! 2. a real grid (full explorations) with 1 and then 2 worker processes, and the scaling
//!    efficiency `T1 / (2 T2)`.
//!
//! Goals (issue #6): at least 1,000 trivial jobs/s, at least 90 % efficiency. Run it on an idle
//! machine: other processes competing for the cores lower the efficiency.
//!
//! Options (after `--`): `--trivial N` (default 3000), `--seeds N` real jobs (default 6),
//! `--skip-real`.
//! The benchmark runs worker processes by starting itself again with `FLOORCAST_BENCH_WORKER`.

use std::path::Path;
use std::process::{Child, Command};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Instant;

use floorcast_coordinator::grid::{Plan, PlannedJob};
use floorcast_coordinator::inbox::RemoteWorkers;
use floorcast_coordinator::net::{join, NetConfig};
use floorcast_coordinator::run::{run_plan, RunOptions};
use floorcast_coordinator::store::Store;
use floorcast_worker::execute::execute_wire;
use floorcast_worker::process::{run_worker, Executor, WorkerOptions};
use floorcast_worker::wire::{JobReport, WireJob};
use sim_core::Building;

const ROLE: &str = "FLOORCAST_BENCH_WORKER";

fn main() {
    if let Ok(role) = std::env::var(ROLE) {
        return worker_process(&role);
    }
    let args: Vec<String> = std::env::args().collect();
    let opt = |name: &str, default: usize| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .and_then(|v| v.parse().ok())
            .unwrap_or(default)
    };
    let trivial = opt("--trivial", 3000);
    let seeds = opt("--seeds", 6);
    let dir = tempfile::tempdir().expect("temp dir");

    println!("grid benchmark: {trivial} trivial jobs, then a real grid of {seeds} explorations");
    // 1. Trivial jobs: in-process channels (baseline), then zenoh with 8 worker processes.
    let plan = make_plan(dir.path(), "trivial-local", trivial, 1);
    let local = timed_run(&plan, 8, None, 0);
    let plan = make_plan(dir.path(), "trivial-net", trivial, 1);
    let net = timed_run(&plan, 0, Some("trivial"), 8);
    let (local_rate, net_rate) = (trivial as f64 / local, trivial as f64 / net);
    println!(
        "trivial jobs, 8 in-process workers (baseline):   {local_rate:>8.0} jobs/s ({local:.2} s)"
    );
    println!(
        "trivial jobs, 8 worker processes over zenoh/TCP: {net_rate:>8.0} jobs/s ({net:.2} s)  goal >= 1000 jobs/s: {}",
        if net_rate >= 1000.0 { "met" } else { "NOT met" }
    );
    println!(
        "ratio zenoh / in-process: {:.2}",
        net_rate / local_rate.max(1e-9)
    );
    if args.iter().any(|a| a == "--skip-real") {
        return;
    }
    // 2. A real grid with 1 and 2 worker processes.
    let p1 = make_plan(dir.path(), "real-1", seeds, 600);
    let t1 = timed_run(&p1, 0, Some("real"), 1);
    let p2 = make_plan(dir.path(), "real-2", seeds, 600);
    let t2 = timed_run(&p2, 0, Some("real"), 2);
    let eff = t1 / (2.0 * t2);
    println!(
        "real grid ({seeds} explorations of small.toml): 1 worker {t1:.1} s, 2 workers {t2:.1} s"
    );
    println!(
        "scaling efficiency T1/(2 T2): {:.1} %  goal >= 90 %: {}",
        100.0 * eff,
        if eff >= 0.9 { "met" } else { "NOT met" }
    );
}

fn make_plan(dir: &Path, name: &str, seeds: usize, time_limit_s: u64) -> Plan {
    let small = Path::new(env!("CARGO_MANIFEST_DIR")).join("buildings/small.toml");
    let text = format!(
        "format = \"floorcast-grid\"\nversion = 1\nname = \"{name}\"\nbuildings = [\"{}\"]\nseed_range = [1, {seeds}]\n[[strategies]]\nname = \"baseline\"\n[settings]\ntime_limit_s = {time_limit_s}\n",
        small.display()
    );
    Plan::parse(&text, &dir.join("grid.toml"), Some(&dir.join(name))).expect("bench grid")
}

fn trivial_row(_: &Plan, _: &PlannedJob) -> JobReport {
    JobReport::failed("trivial benchmark job")
}

/// Runs `plan` with `local` embedded trivial workers and `procs` worker processes of `role`;
/// returns the wall time in seconds from the first handed-out job to the last stored one.
fn timed_run(plan: &Plan, local: usize, role: Option<&str>, procs: usize) -> f64 {
    let store = Store::open(&plan.results_dir).expect("store");
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("free port");
    let endpoint = format!("tcp/127.0.0.1:{port}");
    let opts = RunOptions {
        workers: local,
        remote: role.map(|_| {
            Arc::new(NetConfig {
                listen: vec![endpoint.clone()],
                connect: vec![],
                zenoh_config: None,
                campaign: "bench".into(),
            }) as Arc<dyn RemoteWorkers>
        }),
        lease_s: 600.0,
        linger_s: 3.0,
        executor: Some(Arc::new(trivial_row)),
        // The coordinator's own re-runs would add to what is measured.
        verify_fraction: 0.0,
        // Every job alone: what is measured is the coordinator and the scaling.
        share: false,
        retry_failed: false,
        live: None,
    };
    let mut children: Vec<Child> = Vec::new();
    if let Some(role) = role {
        for i in 0..procs {
            children.push(
                Command::new(std::env::current_exe().expect("own path"))
                    .env(ROLE, format!("{role} {endpoint} w{i}"))
                    .spawn()
                    .expect("worker process"),
            );
        }
    }
    let mut first: Option<Instant> = None;
    let mut last = Instant::now();
    let mut prev_done = 0;
    let t0 = Instant::now();
    run_plan(
        plan,
        &store,
        &opts,
        &AtomicBool::new(false),
        &mut |c| {
            if c.running > 0 && first.is_none() {
                first = Some(Instant::now());
            }
            if c.done > prev_done {
                prev_done = c.done;
                last = Instant::now();
            }
        },
        &mut |_| {},
    )
    .expect("grid runs");
    for mut c in children {
        let _ = c.wait();
    }
    let start = first.unwrap_or(t0);
    last.duration_since(start).as_secs_f64().max(1e-6)
}

/// A worker process: `trivial|real ENDPOINT NAME`.
fn worker_process(role: &str) {
    let parts: Vec<&str> = role.split_whitespace().collect();
    let [kind, endpoint, name] = parts[..] else {
        panic!("bad {ROLE}: {role}");
    };
    let trivial = |_: &WireJob, _: &Building| JobReport::failed("trivial benchmark job");
    let exec: &Executor<'_> = if kind == "trivial" {
        &trivial
    } else {
        &execute_wire
    };
    let net = NetConfig {
        listen: vec![],
        connect: vec![endpoint.to_string()],
        zenoh_config: None,
        campaign: "bench".into(),
    };
    let outcome = join(&net, Some(name), 60.0)
        .map_err(|e| e.to_string())
        .and_then(|link| {
            let report = run_worker(
                &link,
                "bench",
                WorkerOptions {
                    jobs: 1,
                    wait_s: 60.0,
                },
                exec,
                &|_| {},
            );
            link.leave();
            report.map_err(|e| e.to_string())
        });
    if let Err(e) = outcome {
        eprintln!("bench worker {name}: {e}");
        std::process::exit(1);
    }
}
