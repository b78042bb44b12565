//! Runs a plan on this machine: embedded worker threads pull jobs from the scheduler through
//! in-process channels (no network, no port). Results are stored as they arrive.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::Arc;
use std::time::{Duration, Instant};

use floorcast_worker::{run_job, Job};

use crate::grid::{Plan, PlannedJob};
use crate::schedule::{Action, Event, Scheduler};
use crate::store::{Store, StoreError, StoredResult};

/// What the embedded workers send to the coordinator loop.
enum FromWorker {
    Request(String),
    Result {
        worker: String,
        job: String,
        result: Box<StoredResult>,
    },
}

/// What the coordinator answers a request with.
enum ToWorker {
    Run(Box<PlannedJob>),
    Wait,
    Done,
}

/// Counts for a progress display.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Counts {
    pub total: usize,
    pub done: usize,
    pub running: usize,
    pub failed: usize,
    /// Stored before this run started.
    pub resumed: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    Complete,
    Interrupted,
}

/// Runs every job of `plan` not yet in `store` with `workers` threads. `interrupt` stops the run
/// (jobs already stored stay stored; running ones are abandoned and rerun next time).
pub fn run_local(
    plan: &Plan,
    store: &Store,
    workers: usize,
    interrupt: &AtomicBool,
    on_progress: &mut dyn FnMut(Counts),
) -> Result<(Outcome, Counts), StoreError> {
    let stored = store.stored_ids()?;
    let ids: Vec<String> = plan.jobs.iter().map(|j| j.id.clone()).collect();
    let mut sched = Scheduler::new(ids, &stored, 7.0 * 24.0 * 3600.0);
    let jobs: BTreeMap<String, PlannedJob> = plan
        .jobs
        .iter()
        .map(|j| (j.id.clone(), j.clone()))
        .collect();
    let resumed = sched.done();
    let mut failed = 0usize;
    let counts = |s: &Scheduler, failed: usize| Counts {
        total: s.total(),
        done: s.done(),
        running: s.running(),
        failed,
        resumed,
    };
    on_progress(counts(&sched, failed));
    if sched.is_finished() {
        return Ok((Outcome::Complete, counts(&sched, failed)));
    }
    let (to_coord, from_workers) = mpsc::channel::<FromWorker>();
    let mut replies: BTreeMap<String, mpsc::Sender<ToWorker>> = BTreeMap::new();
    let plan = Arc::new(plan.clone());
    let stop = Arc::new(AtomicBool::new(false));
    let mut handles = Vec::new();
    for w in 0..workers.max(1) {
        let name = format!("local-{w}");
        let (tx, rx) = mpsc::channel::<ToWorker>();
        replies.insert(name.clone(), tx);
        let to_coord = to_coord.clone();
        let plan = Arc::clone(&plan);
        let stop = Arc::clone(&stop);
        handles.push(std::thread::spawn(move || {
            worker_loop(&name, &plan, &to_coord, &rx, &stop)
        }));
    }
    drop(to_coord);
    let t0 = Instant::now();
    let mut outcome = Outcome::Complete;
    let mut pending_results: BTreeMap<String, StoredResult> = BTreeMap::new();
    loop {
        if interrupt.load(Ordering::SeqCst) {
            outcome = Outcome::Interrupted;
            break;
        }
        let event = match from_workers.recv_timeout(Duration::from_millis(100)) {
            Ok(FromWorker::Request(w)) => Event::JobRequested(w),
            Ok(FromWorker::Result {
                worker,
                job,
                result,
            }) => {
                pending_results.insert(job.clone(), *result);
                Event::ResultSubmitted { worker, job }
            }
            Err(mpsc::RecvTimeoutError::Timeout) => Event::Tick,
            Err(mpsc::RecvTimeoutError::Disconnected) => break,
        };
        let now = t0.elapsed().as_secs_f64();
        let mut finished = false;
        for action in sched.handle(event, now) {
            match action {
                Action::Lease { worker, job, .. } => {
                    if let (Some(tx), Some(j)) = (replies.get(&worker), jobs.get(&job)) {
                        let _ = tx.send(ToWorker::Run(Box::new(j.clone())));
                    }
                }
                Action::Wait { worker } => {
                    if let Some(tx) = replies.get(&worker) {
                        let _ = tx.send(ToWorker::Wait);
                    }
                }
                Action::Done { worker } => {
                    if let Some(tx) = replies.get(&worker) {
                        let _ = tx.send(ToWorker::Done);
                    }
                }
                Action::Store { job, .. } => {
                    if let Some(r) = pending_results.remove(&job) {
                        if r.status != "ok" {
                            failed += 1;
                        }
                        store.insert(&r)?;
                    }
                }
                Action::AckDuplicate { job, .. } | Action::RejectUnknown { job, .. } => {
                    pending_results.remove(&job);
                }
                Action::Requeued { .. } => {}
                Action::Finished => finished = true,
            }
        }
        on_progress(counts(&sched, failed));
        if finished {
            break;
        }
    }
    stop.store(true, Ordering::SeqCst);
    for tx in replies.values() {
        let _ = tx.send(ToWorker::Done);
    }
    if outcome == Outcome::Complete {
        for h in handles {
            let _ = h.join();
        }
    }
    // On interruption, running simulations are abandoned (the process exits); their jobs are
    // not stored and run again next time.
    Ok((outcome, counts(&sched, failed)))
}

fn worker_loop(
    name: &str,
    plan: &Plan,
    to_coord: &mpsc::Sender<FromWorker>,
    rx: &mpsc::Receiver<ToWorker>,
    stop: &AtomicBool,
) {
    while !stop.load(Ordering::SeqCst) {
        if to_coord
            .send(FromWorker::Request(name.to_string()))
            .is_err()
        {
            return;
        }
        match rx.recv() {
            Ok(ToWorker::Run(job)) => {
                let result = execute(plan, &job, name);
                let msg = FromWorker::Result {
                    worker: name.to_string(),
                    job: job.id.clone(),
                    result: Box::new(result),
                };
                if to_coord.send(msg).is_err() {
                    return;
                }
            }
            Ok(ToWorker::Wait) => std::thread::sleep(Duration::from_millis(50)),
            Ok(ToWorker::Done) | Err(_) => return,
        }
    }
}

/// Runs one planned job and turns its outcome (success or a job error) into a store row.
pub fn execute(plan: &Plan, job: &PlannedJob, worker: &str) -> StoredResult {
    let b = &plan.buildings[job.building];
    let spec = Job {
        building: &b.building,
        building_name: b.name.clone(),
        strategy: job.strategy.clone(),
        seed: job.seed,
        settings: job.settings.clone(),
        start: None,
        snapshot_fractions: Vec::new(),
    };
    let t = Instant::now();
    let outcome = run_job(&spec, &mut |_| {});
    let mut row = StoredResult {
        job_id: job.id.clone(),
        grid: plan.name.clone(),
        building: b.name.clone(),
        building_hash: b.hash.clone(),
        strategy: job.strategy.clone(),
        label: job.label.clone(),
        seed: job.seed,
        settings_json: serde_json::to_string(&job.settings).unwrap_or_default(),
        status: "ok".into(),
        error: None,
        summary_json: None,
        progress_csv: None,
        worker: worker.to_string(),
        wall_time_s: t.elapsed().as_secs_f64(),
        floorcast_version: floorcast_worker::FLOORCAST_VERSION.to_string(),
    };
    match outcome {
        Ok(out) => {
            row.summary_json = serde_json::to_string(&out.summary).ok();
            let mut csv = String::from("time_s,explored_area_m2,explored_fraction\n");
            for p in &out.result.progress {
                let _ = writeln!(
                    csv,
                    "{:.1},{:.3},{:.5}",
                    p.time_s, p.explored_area_m2, p.explored_fraction
                );
            }
            row.progress_csv = Some(csv);
        }
        Err(e) => {
            row.status = "failed".into();
            row.error = Some(e.to_string());
        }
    }
    row
}
