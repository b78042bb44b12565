//! Runs a plan: the coordinator loop around the [`Scheduler`], fed by embedded worker threads
//! (in-process channels, no network, no port) and by remote workers through a transport its
//! caller hands it ([`RemoteWorkers`]: `net.rs` for zenoh; this module names none). Both kinds
//! of worker send the same [`Inbox`] messages, so local and distributed runs share one code path.
//!
//! Results are stored as they arrive: the loop takes every message waiting, commits the results
//! among them in one SQLite transaction, and only then acknowledges them (a killed coordinator
//! loses nothing it acknowledged; a burst of results costs one disk sync).

use std::collections::{BTreeMap, BTreeSet};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::Arc;
use std::time::{Duration, Instant};

use tokio::sync::oneshot;

use crate::execute::{execute, execute_shared, identity, row};
use crate::grid::{Plan, PlannedJob};
use crate::inbox::{Answer, Inbox, InboxSender, RemoteWorkers, LOCAL};
use crate::schedule::{Grant, Note, Renewal, RequeueReason, Scheduler, Verdict};
use crate::store::{Store, StoreError, StoredResult};
use floorcast_worker::spawn_thread;
use floorcast_worker::wire::{check_report, JobReport, RenewReply, SubmitReply};

/// Counts for a progress display.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Counts {
    pub total: usize,
    pub done: usize,
    pub running: usize,
    pub failed: usize,
    /// Stored before this run started.
    pub resumed: usize,
    /// Remote workers connected now.
    pub remote_workers: usize,
    /// Results of remote workers re-run here and compared ([`crate::verify`]).
    pub verified: usize,
    /// Remote workers whose results were found wrong (discarded and run again elsewhere).
    pub quarantined: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    Complete,
    Interrupted,
}

/// Runs one planned job on an embedded worker or for a check (default: [`execute`]).
pub type LocalExecutor = dyn Fn(&Plan, &PlannedJob) -> JobReport + Send + Sync;

/// How to run a plan.
#[derive(Clone)]
pub struct RunOptions {
    /// Embedded worker threads (0 is allowed only with `remote`).
    pub workers: usize,
    /// Accept remote workers through this transport (the binary gives `net::NetConfig`).
    pub remote: Option<Arc<dyn RemoteWorkers>>,
    /// Lease of a remote job; a worker renews it while it runs the job.
    pub lease_s: f64,
    /// After the last result, keep answering "done" this long so remote workers leave cleanly.
    pub linger_s: f64,
    /// What embedded workers run (benchmarks replace it with a trivial job).
    pub executor: Option<Arc<LocalExecutor>>,
    /// The fraction of remote workers' results (besides each worker's first) re-run on this
    /// machine and compared ([`crate::verify`]); 0 verifies none.
    pub verify_fraction: f64,
    /// Embedded workers run jobs that share their beginning together ([`partners`]): each
    /// result is the one made alone, in less time. Off: every job alone (its wall time all its
    /// own). Ignored with a custom `executor`.
    pub share: bool,
    /// Run the stored failed jobs again (`run --retry-failed`): each new outcome replaces the
    /// failed row; the failures stay in the store's `failures` table.
    pub retry_failed: bool,
    /// Tell this live view what happens (`run --http`).
    pub live: Option<Arc<crate::live::Live>>,
}

impl std::fmt::Debug for RunOptions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RunOptions")
            .field("workers", &self.workers)
            .field("remote", &self.remote.as_ref().map(|_| "remote workers"))
            .field("lease_s", &self.lease_s)
            .field("linger_s", &self.linger_s)
            .field("executor", &self.executor.as_ref().map(|_| "custom"))
            .field("verify_fraction", &self.verify_fraction)
            .field("share", &self.share)
            .field("retry_failed", &self.retry_failed)
            .field("live", &self.live.is_some())
            .finish()
    }
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            workers: 1,
            remote: None,
            lease_s: 60.0,
            linger_s: 2.0,
            executor: None,
            verify_fraction: 0.05,
            share: true,
            retry_failed: false,
            live: None,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Store(#[from] StoreError),
    /// The transport for remote workers could not open.
    #[error(transparent)]
    Remote(Box<dyn std::error::Error + Send + Sync>),
    #[error("no workers: --workers 0 needs --listen or --connect so that remote workers can join")]
    NoWorkers,
    #[error("could not start {workers} worker threads (give fewer --workers): {source}")]
    Spawn {
        workers: usize,
        source: std::io::Error,
    },
    #[error("could not start the thread that checks remote workers' results (the system is out of threads or memory; give fewer --workers, or --verify-fraction 0): {0}")]
    VerifierSpawn(std::io::Error),
}

/// While a sequential grid's current batch is all stored: tests it (the tests are stored and
/// logged) and adds the next batch's jobs to the scheduler; tells it when no more will come.
fn advance(
    plan: &Plan,
    store: &Store,
    progress: &mut floorcast_stats::sequential::Progress,
    sched: &mut Scheduler,
    jobs: &mut BTreeMap<String, PlannedJob>,
    retried: &BTreeSet<String>,
    on_log: &mut dyn FnMut(&str),
) -> Result<(), RunError> {
    // A batch counts once its results are verified (a verification may send jobs back).
    while !progress.finished && sched.batch_complete() && sched.held() == 0 {
        let results = store.all()?;
        let before = progress.path.len();
        let next = crate::sequential::advance(progress, plan, &results);
        store.record_tests(&plan.name, &progress.path[before..])?;
        for t in &progress.path[before..] {
            if t.state.decision != floorcast_stats::sprt::Decision::Undecided {
                on_log(&format!(
                    "{} against {}: {} after {} pairs (seeds 1-{})",
                    t.label,
                    t.reference,
                    t.state.decision.as_str(),
                    t.state.pairs,
                    t.through_seed
                ));
            }
        }
        let stored = done_ids(store, retried)?;
        sched.add(next.iter().map(|j| j.id.clone()).collect(), &stored);
        jobs.extend(next.into_iter().map(|j| (j.id.clone(), j)));
        if progress.finished {
            sched.expect_more(false);
        }
    }
    Ok(())
}

/// The stored jobs that are not to run: every stored job but those `retried` (failed jobs run
/// again).
fn done_ids(store: &Store, retried: &BTreeSet<String>) -> Result<BTreeSet<String>, RunError> {
    let mut stored = store.stored_ids()?;
    stored.retain(|id| !retried.contains(id));
    Ok(stored)
}

/// Runs every job of `plan` not yet in `store` (and its failed ones with
/// [`RunOptions::retry_failed`]). `interrupt` stops the run (jobs already stored
/// stay stored; running ones are abandoned and run again next time). `on_log` receives lines
/// for the user (workers joining or refused, requeued jobs, dropped messages).
pub fn run_plan(
    plan: &Plan,
    store: &Store,
    opts: &RunOptions,
    interrupt: &AtomicBool,
    on_progress: &mut dyn FnMut(Counts),
    on_log: &mut dyn FnMut(&str),
) -> Result<(Outcome, Counts), RunError> {
    if opts.workers == 0 && opts.remote.is_none() {
        return Err(RunError::NoWorkers);
    }
    // Lines holding remote workers' and programs' text reach a terminal: escaped, bounded.
    let on_log = &mut |line: &str| {
        let line = floorcast_worker::text::shown(line, 4000);
        if let Some(live) = &opts.live {
            live.log(&line);
        }
        on_log(&line)
    };
    let mut state = LoopState::start(plan, store, opts, on_log)?;
    on_progress(state.counts());
    if state.sched.is_finished() {
        return Ok((Outcome::Complete, state.counts()));
    }
    let (inbox_tx, inbox) = mpsc::channel::<Inbox>();
    let listener = match &opts.remote {
        Some(remote) => Some(
            remote
                .open(
                    Arc::clone(&state.plan),
                    opts.lease_s,
                    InboxSender(inbox_tx.clone()),
                )
                .map_err(RunError::Remote)?,
        ),
        None => None,
    };
    if let Some(l) = &listener {
        on_log(&format!("accepting remote workers: {}", l.describe()));
    }
    let local_exec: Arc<LocalExecutor> = opts.executor.clone().unwrap_or_else(|| Arc::new(execute));
    let stop = Arc::new(AtomicBool::new(false));
    let handles = spawn_local_workers(&state.plan, opts, &inbox_tx, &stop, &local_exec)?;
    let verifier = if listener.is_some() && opts.verify_fraction > 0.0 {
        let (tx, rx) = mpsc::channel::<(PlannedJob, StoredResult, String)>();
        let inbox = inbox_tx.clone();
        let plan = Arc::clone(&state.plan);
        let exec = Arc::clone(&local_exec);
        let h = spawn_thread(move || verifier(&plan, &rx, &inbox, &*exec))
            .map_err(RunError::VerifierSpawn)?;
        state.verify_tx = Some(tx);
        Some(h)
    } else {
        None
    };
    drop(inbox_tx);
    let outcome = state.serve(&inbox, interrupt, on_progress, on_log)?;
    stop.store(true, Ordering::SeqCst);
    if let Some(l) = listener {
        l.close();
    }
    state.verify_tx = None;
    if outcome == Outcome::Complete {
        drop(inbox);
        for h in handles.into_iter().chain(verifier) {
            let _ = h.join();
        }
    }
    // On interruption, running simulations are abandoned (the process exits); their jobs are
    // not stored and run again next time.
    Ok((outcome, state.counts()))
}

/// Starts the embedded worker threads. A thread the system refuses is an error, not a panic;
/// the workers already started leave when the inbox is dropped on the way out.
fn spawn_local_workers(
    plan: &Arc<Plan>,
    opts: &RunOptions,
    inbox_tx: &mpsc::Sender<Inbox>,
    stop: &Arc<AtomicBool>,
    local_exec: &Arc<LocalExecutor>,
) -> Result<Vec<std::thread::JoinHandle<()>>, RunError> {
    let mut handles = Vec::new();
    for w in 0..opts.workers {
        let name = format!("{LOCAL}{w}");
        let tx = inbox_tx.clone();
        let plan = Arc::clone(plan);
        let stop = Arc::clone(stop);
        let exec = Arc::clone(local_exec);
        let h =
            spawn_thread(move || local_worker(&name, &plan, &tx, &stop, &*exec)).map_err(|e| {
                RunError::Spawn {
                    workers: opts.workers,
                    source: e,
                }
            })?;
        handles.push(h);
    }
    Ok(handles)
}

/// What one batch of the inbox's messages produced: the rows to store, the acknowledgements to
/// send once they are stored, and the scheduler's notes.
#[derive(Default)]
struct Batch {
    to_store: Vec<StoredResult>,
    acks: Vec<(oneshot::Sender<SubmitReply>, SubmitReply)>,
    notes: Vec<Note>,
}

/// The coordinator loop's state: the scheduler and the jobs it hands out, a sequential grid's
/// progress, and what the run has seen (failed jobs, remote workers, checks of their results).
struct LoopState<'a> {
    plan: Arc<Plan>,
    store: &'a Store,
    opts: &'a RunOptions,
    sched: Scheduler,
    jobs: BTreeMap<String, PlannedJob>,
    progress: floorcast_stats::sequential::Progress,
    /// Embedded workers run jobs that share their beginning together.
    share: bool,
    share_keys: BTreeMap<String, Option<sim_core::explore::ExploreConfig>>,
    /// Remote workers' results to check go here (`None`: none are checked).
    verify_tx: Option<mpsc::Sender<(PlannedJob, StoredResult, String)>>,
    resumed: usize,
    failed: usize,
    remote: BTreeSet<String>,
    checks: Checks,
    /// Failed jobs run again whose new outcome is not stored yet (it replaces the failed row).
    retried: BTreeSet<String>,
}

impl<'a> LoopState<'a> {
    /// The scheduler over the jobs not yet stored (a sequential grid's batches replayed).
    fn start(
        plan: &Plan,
        store: &'a Store,
        opts: &'a RunOptions,
        on_log: &mut dyn FnMut(&str),
    ) -> Result<LoopState<'a>, RunError> {
        let retried = if opts.retry_failed {
            store.failed_ids()?
        } else {
            BTreeSet::new()
        };
        let stored = done_ids(store, &retried)?;
        let ids: Vec<String> = plan.jobs.iter().map(|j| j.id.clone()).collect();
        let mut sched = Scheduler::new(ids, &stored, opts.lease_s);
        let mut jobs: BTreeMap<String, PlannedJob> = plan
            .jobs
            .iter()
            .map(|j| (j.id.clone(), j.clone()))
            .collect();
        // A sequential grid: batches of seeds added as the tests go (replaying those already run).
        let mut progress = crate::sequential::start(plan);
        sched.expect_more(!progress.finished);
        advance(
            plan,
            store,
            &mut progress,
            &mut sched,
            &mut jobs,
            &retried,
            on_log,
        )?;
        Ok(LoopState {
            plan: Arc::new(plan.clone()),
            store,
            opts,
            resumed: sched.done(),
            sched,
            jobs,
            progress,
            share: opts.share && opts.executor.is_none(),
            share_keys: BTreeMap::new(),
            verify_tx: None,
            failed: 0,
            remote: BTreeSet::new(),
            checks: Checks::default(),
            retried,
        })
    }

    fn counts(&self) -> Counts {
        Counts {
            total: self.sched.total(),
            done: self.sched.done(),
            running: self.sched.running(),
            failed: self.failed,
            resumed: self.resumed,
            remote_workers: self.remote.len(),
            verified: self.checks.verified,
            quarantined: self.checks.refused.len(),
        }
    }

    /// Answers the inbox until the grid is finished (and remote workers left, or the linger
    /// passed), every sender is gone, or `interrupt` is set.
    fn serve(
        &mut self,
        inbox: &mpsc::Receiver<Inbox>,
        interrupt: &AtomicBool,
        on_progress: &mut dyn FnMut(Counts),
        on_log: &mut dyn FnMut(&str),
    ) -> Result<Outcome, RunError> {
        let t0 = Instant::now();
        let mut finished_at: Option<Instant> = None;
        let mut last_renewal = 0.0f64;
        loop {
            if interrupt.load(Ordering::SeqCst) {
                return Ok(Outcome::Interrupted);
            }
            if let Some(t) = finished_at {
                // Remote workers get "done" when they ask; stop once they left or after the
                // linger.
                if self.remote.is_empty() || t.elapsed().as_secs_f64() >= self.opts.linger_s {
                    return Ok(Outcome::Complete);
                }
            }
            let mut messages = Vec::new();
            match inbox.recv_timeout(Duration::from_millis(100)) {
                Ok(m) => messages.push(m),
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => return Ok(Outcome::Complete),
            }
            while messages.len() < 512 {
                match inbox.try_recv() {
                    Ok(m) => messages.push(m),
                    Err(_) => break,
                }
            }
            let now = t0.elapsed().as_secs_f64();
            let mut batch = Batch::default();
            // Embedded workers cannot die alone (they are threads of this process): keep their
            // leases alive.
            if now - last_renewal >= self.opts.lease_s / 4.0 {
                last_renewal = now;
                self.renew_local(now, &mut batch);
            }
            batch.notes.extend(self.sched.tick(now));
            for msg in messages {
                self.handle(msg, now, &mut batch, on_log)?;
            }
            if self.flush(batch, on_log)? {
                finished_at = Some(Instant::now());
            }
            let (plan, store) = (Arc::clone(&self.plan), self.store);
            advance(
                &plan,
                store,
                &mut self.progress,
                &mut self.sched,
                &mut self.jobs,
                &self.retried,
                on_log,
            )?;
            if self.sched.is_finished() && finished_at.is_none() {
                finished_at = Some(Instant::now());
            }
            if let Some(live) = &self.opts.live {
                let c = self.counts();
                let jobs = crate::live::JobCounts {
                    total: c.total,
                    done: c.done,
                    running: c.running,
                    failed: c.failed,
                    left: c.total.saturating_sub(c.done + c.running),
                    stored_before: c.resumed,
                };
                live.counts(jobs, self.running_jobs());
                live.tests(&self.progress.path);
            }
            on_progress(self.counts());
        }
    }

    /// The jobs leased now, as (worker, job), for the live view.
    fn running_jobs(&self) -> Vec<(String, crate::live::RunningJob)> {
        self.sched
            .leases()
            .map(|(id, worker)| {
                let job = self.jobs.get(id);
                let building = job.and_then(|j| self.plan.buildings.get(j.building));
                let running = crate::live::RunningJob {
                    job_id: id.clone(),
                    building: building.map_or(String::new(), |b| b.name.clone()),
                    label: job.map_or(String::new(), |j| j.label.clone()),
                    seed: job.map_or(0, |j| j.seed),
                };
                (worker.clone(), running)
            })
            .collect()
    }

    /// Renews the leases of the embedded workers' jobs.
    fn renew_local(&mut self, now: f64, batch: &mut Batch) {
        let local: Vec<(String, String)> = self
            .sched
            .leases()
            .filter(|(_, w)| w.starts_with(LOCAL))
            .map(|(j, w)| (j.clone(), w.clone()))
            .collect();
        for (job, worker) in local {
            batch
                .notes
                .extend(self.sched.renew(&worker, &job, now).notes);
        }
    }

    /// One message: a refused worker is told so; the others go to their handlers.
    fn handle(
        &mut self,
        msg: Inbox,
        now: f64,
        batch: &mut Batch,
        on_log: &mut dyn FnMut(&str),
    ) -> Result<(), RunError> {
        if let Some(live) = &self.opts.live {
            match &msg {
                Inbox::Request { worker, .. }
                | Inbox::Submit { worker, .. }
                | Inbox::Renew { worker, .. }
                | Inbox::Joined(worker) => live.contact(worker, worker.starts_with(LOCAL)),
                Inbox::Left(worker) => live.left(worker),
                Inbox::Verified { .. } | Inbox::Log(_) => {}
            }
        }
        let refused = &self.checks.refused;
        match msg {
            Inbox::Request { worker, reply } if refused.contains_key(&worker) => {
                let _ = reply.send(Answer::Refused(refused[&worker].clone()));
            }
            Inbox::Submit { worker, reply, .. } if refused.contains_key(&worker) => {
                let reason = refused[&worker].clone();
                let _ = reply.send(SubmitReply::Rejected { reason });
            }
            Inbox::Renew { worker, reply, .. } if refused.contains_key(&worker) => {
                let _ = reply.send(RenewReply::NotLeased);
            }
            Inbox::Request { worker, reply } => {
                let answer = self.request(worker, now, batch);
                let _ = reply.send(answer);
            }
            Inbox::Submit {
                worker,
                job_id,
                report,
                reply,
            } => self.submit(worker, job_id, &report, reply, batch, on_log),
            Inbox::Renew { worker, job, reply } => {
                let r = self.sched.renew(&worker, &job, now);
                batch.notes.extend(r.notes);
                let _ = reply.send(match r.answer {
                    Renewal::Renewed { .. } => RenewReply::Renewed,
                    Renewal::NotLeased => RenewReply::NotLeased,
                });
            }
            Inbox::Verified {
                job,
                worker,
                ours,
                outcome,
            } => self.verified(&job, worker, &ours, outcome, batch, on_log)?,
            Inbox::Joined(w) => {
                if self.remote.insert(w.clone()) {
                    on_log(&format!("worker {w} joined"));
                }
                self.sched.joined(w);
            }
            Inbox::Left(w) => {
                if self.remote.remove(&w) {
                    on_log(&format!("worker {w} left"));
                }
                batch.notes.extend(self.sched.left(&w));
            }
            Inbox::Log(line) => on_log(&line),
        }
        Ok(())
    }

    /// A worker asks for work: a job (with the jobs that share its beginning, for an embedded
    /// worker), or wait, or done.
    fn request(&mut self, worker: String, now: f64, batch: &mut Batch) -> Answer {
        let local = worker.starts_with(LOCAL);
        let r = self.sched.request(worker.clone(), now);
        batch.notes.extend(r.notes);
        match r.answer {
            Grant::Lease { job, .. } => match self.jobs.get(&job) {
                Some(j) if local && self.share => {
                    let mut group = vec![j.clone()];
                    for p in partners(&self.plan, j, &self.jobs, &mut self.share_keys) {
                        if self.sched.claim(&worker, &p, now) {
                            group.push(self.jobs[&p].clone());
                        }
                    }
                    if group.len() > 1 {
                        Answer::RunShared(group)
                    } else {
                        Answer::Run(Box::new(group.remove(0)))
                    }
                }
                Some(j) => Answer::Run(Box::new(j.clone())),
                None => Answer::Wait,
            },
            Grant::Wait => Answer::Wait,
            Grant::Done => Answer::Done,
        }
    }

    /// A worker's result: checked against its job, stored (acknowledged once durable), and for
    /// a remote worker perhaps sent to be checked by a re-run here.
    fn submit(
        &mut self,
        worker: String,
        job_id: String,
        report: &JobReport,
        reply: oneshot::Sender<SubmitReply>,
        batch: &mut Batch,
        on_log: &mut dyn FnMut(&str),
    ) {
        // The row's identity comes from the plan; the report is checked against the job first.
        let result = match self.jobs.get(&job_id) {
            Some(j) => match check_report(report, &identity(&self.plan, j)) {
                Ok(()) => Some(row(&self.plan, j, &worker, report)),
                Err(reason) => {
                    on_log(&format!(
                        "rejected result of job {job_id} from {worker}: {reason}"
                    ));
                    let _ = reply.send(SubmitReply::Rejected { reason });
                    return;
                }
            },
            None => None, // the scheduler rejects unknown jobs
        };
        // Chosen for a check: held (the grid does not finish) until it is done.
        let check = match (&self.verify_tx, self.jobs.get(&job_id), &result) {
            (Some(tx), Some(j), Some(result))
                if !worker.starts_with(LOCAL)
                    && crate::verify::verifiable(j, result)
                    && (self.checks.first_checked.insert(worker.clone())
                        || rand::random::<f64>() < self.opts.verify_fraction) =>
            {
                self.sched.hold(&job_id);
                Some((tx.clone(), j.clone(), result.clone()))
            }
            _ => None,
        };
        let r = self.sched.submit(&job_id);
        batch.notes.extend(r.notes);
        if let Some((tx, j, theirs)) = check {
            if r.answer == Verdict::Store {
                let _ = tx.send((j, theirs, worker.clone()));
            } else {
                self.sched.release(&job_id);
            }
        }
        match (r.answer, result) {
            (Verdict::Store, Some(result)) => {
                if let Some(live) = &self.opts.live {
                    live.stored(&worker, crate::live::failure_of(&result));
                }
                if !result.status.is_ok() {
                    self.failed += 1;
                    on_log(&format!(
                        "job {} ({} {} seed {}) failed on {worker}: {}",
                        job_id,
                        result.building,
                        result.label,
                        result.seed,
                        result.error.as_deref().unwrap_or("")
                    ));
                }
                batch.to_store.push(result);
                batch.acks.push((reply, SubmitReply::Stored));
            }
            (Verdict::Duplicate, _) => batch.acks.push((reply, SubmitReply::Duplicate)),
            _ => {
                let reason = format!("job {job_id} is not part of grid '{}'", self.plan.name);
                on_log(&format!("rejected result from {worker}: {reason}"));
                let _ = reply.send(SubmitReply::Rejected { reason });
            }
        }
    }

    /// The answer of a check of a remote worker's result: counted, or (when the worker computes
    /// differently) all its results discarded and run again, and the worker refused.
    fn verified(
        &mut self,
        job: &str,
        worker: String,
        ours: &StoredResult,
        outcome: Result<(), String>,
        batch: &mut Batch,
        on_log: &mut dyn FnMut(&str),
    ) -> Result<(), RunError> {
        self.sched.release(job);
        if self.checks.refused.contains_key(&worker) {
            return Ok(()); // its results are discarded already
        }
        match outcome {
            Ok(()) => self.checks.verified += 1,
            Err(why) if !ours.status.is_ok() => on_log(&format!(
                "job {job}: its re-run on this machine failed ({}), so {worker}'s result is kept unverified ({why})",
                ours.error.as_deref().unwrap_or("")
            )),
            Err(why) => {
                // The worker computes differently or forged its results: all of them (stored,
                // or of this batch) are discarded and run again, but the job checked, whose
                // row this machine's replaces.
                self.checks.verified += 1;
                let mut again = self.store.discard_worker(&worker)?;
                again.extend(
                    batch
                        .to_store
                        .iter()
                        .filter(|r| r.worker == worker)
                        .map(|r| r.job_id.clone()),
                );
                batch.to_store.retain(|r| r.worker != worker);
                again.retain(|j| *j != job);
                self.store.replace(ours)?;
                self.sched.reopen(&again);
                batch.notes.extend(self.sched.left(&worker));
                on_log(&format!(
                    "worker {worker} computes differently or forged its results: in job {job} {why} (this machine's re-run); its other {} results are discarded and run again, and it gets no more jobs",
                    again.len()
                ));
                self.checks.refused.insert(
                    worker,
                    format!("its result of job {job} differed from the coordinator's re-run ({why}); its results were discarded. Check that it runs the same floorcast build on a sound machine"),
                );
            }
        }
        Ok(())
    }

    /// Stores the batch's results (durable first, acknowledged second) and logs its notes;
    /// true when the scheduler said the grid is finished.
    fn flush(&mut self, batch: Batch, on_log: &mut dyn FnMut(&str)) -> Result<bool, RunError> {
        self.store
            .insert_many_replacing(&batch.to_store, &self.retried)?;
        for r in &batch.to_store {
            self.retried.remove(&r.job_id);
        }
        for (r, a) in batch.acks {
            let _ = r.send(a);
        }
        let mut finished = false;
        for n in batch.notes {
            match n {
                Note::Requeued {
                    job,
                    worker,
                    reason,
                } => on_log(&format!(
                    "job {job} back in the queue: {}",
                    match reason {
                        RequeueReason::WorkerLeft => format!("worker {worker} left"),
                        RequeueReason::LeaseExpired => format!("lease of {worker} expired"),
                    }
                )),
                Note::Finished => finished = true,
            }
        }
        Ok(finished)
    }
}

/// The checks of remote workers' results during a run.
#[derive(Debug, Default)]
struct Checks {
    /// Workers whose first result went to a check.
    first_checked: BTreeSet<String>,
    /// Results checked.
    verified: usize,
    /// Workers whose results were found wrong, and what they are told.
    refused: BTreeMap<String, String>,
}

/// Re-runs the jobs whose results it receives, one at a time, and tells the loop whether each
/// is identical ([`crate::verify::compare`]).
fn verifier(
    plan: &Plan,
    jobs: &mpsc::Receiver<(PlannedJob, StoredResult, String)>,
    inbox: &mpsc::Sender<Inbox>,
    exec: &LocalExecutor,
) {
    for (job, theirs, worker) in jobs {
        let ours = row(
            plan,
            &job,
            &format!("{LOCAL}verifier"),
            &run_guarded(plan, &job, exec),
        );
        let outcome = crate::verify::compare(&theirs, &ours);
        let sent = inbox.send(Inbox::Verified {
            job: job.id.clone(),
            worker,
            ours: Box::new(ours),
            outcome,
        });
        if sent.is_err() {
            return;
        }
    }
}

/// Runs a job here; a panicking job is a failed job, never a lost one (nor a dead worker).
fn run_guarded(plan: &Plan, job: &PlannedJob, exec: &LocalExecutor) -> JobReport {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| exec(plan, job))).unwrap_or_else(|p| {
        JobReport::failed(format!(
            "the job panicked (a bug in floorcast, please report it): {}",
            floorcast_worker::panic_message(&*p)
        ))
    })
}

/// Hands a local worker's report to the loop; false when the loop is gone.
fn submit(name: &str, inbox: &mpsc::Sender<Inbox>, job_id: &str, report: JobReport) -> bool {
    let (tx, rx) = oneshot::channel();
    let submit = Inbox::Submit {
        worker: name.to_string(),
        job_id: job_id.to_string(),
        report: Box::new(report),
        reply: tx,
    };
    inbox.send(submit).is_ok() && rx.blocking_recv().is_ok()
}

/// The jobs that can run together with `job` (`floorcast_worker::run_jobs_shared`): built-in
/// strategies that differ from its own in the early stop only (`layout`, `layout-es`,
/// `layout-aes`...), on the same building, seed, start and settings, in job-id order. `keys`
/// caches each job's `share_key`.
fn partners(
    plan: &Plan,
    job: &PlannedJob,
    jobs: &BTreeMap<String, PlannedJob>,
    keys: &mut BTreeMap<String, Option<sim_core::explore::ExploreConfig>>,
) -> Vec<String> {
    let mut key = |j: &PlannedJob| {
        keys.entry(j.id.clone())
            .or_insert_with(|| floorcast_worker::share_key(&crate::execute::spec(plan, j)))
            .clone()
    };
    let Some(mine) = key(job) else {
        return Vec::new();
    };
    let same_run = |j: &PlannedJob| {
        j.id != job.id && j.building == job.building && j.seed == job.seed && j.start == job.start
    };
    jobs.values()
        .filter(|j| same_run(j) && key(j).as_ref() == Some(&mine))
        .map(|j| j.id.clone())
        .collect()
}

fn local_worker(
    name: &str,
    plan: &Plan,
    inbox: &mpsc::Sender<Inbox>,
    stop: &AtomicBool,
    exec: &LocalExecutor,
) {
    while !stop.load(Ordering::SeqCst) {
        let (tx, rx) = oneshot::channel();
        let request = Inbox::Request {
            worker: name.to_string(),
            reply: tx,
        };
        if inbox.send(request).is_err() {
            return;
        }
        match rx.blocking_recv() {
            Ok(Answer::Run(job)) => {
                let report = run_guarded(plan, &job, exec);
                if !submit(name, inbox, &job.id, report) {
                    return;
                }
            }
            Ok(Answer::RunShared(jobs)) => {
                let reports = std::panic::catch_unwind(|| execute_shared(plan, &jobs))
                    .unwrap_or_else(|p| {
                        let why = format!(
                            "the job panicked (a bug in floorcast, please report it): {}",
                            floorcast_worker::panic_message(&*p)
                        );
                        jobs.iter()
                            .map(|_| JobReport::failed(why.clone()))
                            .collect()
                    });
                for (job, report) in jobs.iter().zip(reports) {
                    if !submit(name, inbox, &job.id, report) {
                        return;
                    }
                }
            }
            Ok(Answer::Wait) => std::thread::sleep(Duration::from_millis(50)),
            Ok(Answer::Done | Answer::Refused(_)) | Err(_) => return,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::execute::tests::small_plan;

    /// [`run_plan`] not interrupted, its progress and log dropped.
    pub(crate) fn run_quietly(
        plan: &Plan,
        store: &Store,
        opts: &RunOptions,
    ) -> Result<(Outcome, Counts), RunError> {
        run_plan(
            plan,
            store,
            opts,
            &AtomicBool::new(false),
            &mut |_| {},
            &mut |_| {},
        )
    }

    /// A job that panics is stored as a failed job (with the panic's message), never lost, and
    /// the other workers' jobs still run.
    #[test]
    fn a_panicking_job_is_a_failed_job() {
        let dir = tempfile::tempdir().unwrap();
        let plan = small_plan(dir.path(), "[1, 2, 3, 4]", 10, "");
        let store = Store::open(&plan.results_dir).unwrap();
        let exec: Arc<LocalExecutor> = Arc::new(|plan: &Plan, job: &PlannedJob| {
            if job.seed.is_multiple_of(2) {
                panic!("boom at seed {}", job.seed);
            }
            execute(plan, job)
        });
        let opts = RunOptions {
            workers: 2,
            executor: Some(exec),
            ..RunOptions::default()
        };
        let (outcome, counts) = run_quietly(&plan, &store, &opts).unwrap();
        assert_eq!(outcome, Outcome::Complete);
        assert_eq!((counts.done, counts.failed), (4, 2));
        let rows = store.all().unwrap();
        assert_eq!(rows.len(), 4);
        for r in rows {
            let failed = r.seed % 2 == 0;
            assert_eq!(r.status == crate::store::JobStatus::Failed, failed, "{r:?}");
            let boom = format!("boom at seed {}", r.seed);
            assert_eq!(
                r.error.as_deref().is_some_and(|e| e.contains(&boom)),
                failed,
                "{r:?}"
            );
        }
    }

    /// A worker thread the system refuses (the first, second or third of three): `run` is an
    /// error naming the workers asked for, runs no job, and the workers already started leave
    /// (none is left waiting for a job: each holds the executor until it leaves).
    #[test]
    fn a_refused_worker_thread_is_an_error_and_the_started_ones_leave() {
        let dir = tempfile::tempdir().unwrap();
        let plan = small_plan(dir.path(), "[1, 2, 3, 4]", 10, "");
        let store = Store::open(&plan.results_dir).unwrap();
        let exec: Arc<LocalExecutor> =
            Arc::new(|_: &Plan, job: &PlannedJob| panic!("job {} was run", job.id));
        for started in 0..3 {
            let opts = RunOptions {
                workers: 3,
                executor: Some(Arc::clone(&exec)),
                ..RunOptions::default()
            };
            floorcast_worker::refuse_threads_after(Some(started));
            let r = run_quietly(&plan, &store, &opts);
            floorcast_worker::refuse_threads_after(None);
            match r {
                Err(e @ RunError::Spawn { workers: 3, .. }) => {
                    assert!(e.to_string().contains("give fewer --workers"), "{e}")
                }
                other => panic!("after {started} threads: {other:?}"),
            }
            drop(opts);
            let t0 = Instant::now();
            while Arc::strong_count(&exec) > 1 && t0.elapsed() < Duration::from_secs(10) {
                std::thread::sleep(Duration::from_millis(10));
            }
            assert_eq!(
                Arc::strong_count(&exec),
                1,
                "after {started} threads: a started worker did not leave"
            );
        }
        assert!(store.all().unwrap().is_empty());
    }

    /// Jobs that share their beginning (`layout`, `layout-es`, `layout-aes` on one building,
    /// seed and start) run together by one embedded worker store what they store when each runs
    /// alone (`--no-share`), field by field but the measured times; `baseline` runs alone.
    #[test]
    fn jobs_run_together_store_what_they_store_alone() {
        let dir = tempfile::tempdir().unwrap();
        let small =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../buildings/small.toml");
        let text = format!(
            "format = \"floorcast-grid\"\nversion = 1\nname = \"s\"\nbuildings = [\"{}\"]\nseeds = [1, 2, 3]\n[[strategies]]\nname = \"baseline\"\n[[strategies]]\nname = \"layout-es\"\n[[strategies]]\nname = \"layout\"\n[[strategies]]\nname = \"layout-aes\"\n",
            small.display()
        );
        let mut rows = Vec::new();
        for share in [true, false] {
            let results = dir.path().join(format!("r-{share}"));
            let plan = Plan::parse(&text, &dir.path().join("grid.toml"), Some(&results)).unwrap();
            let store = Store::open(&plan.results_dir).unwrap();
            let opts = RunOptions {
                workers: 2,
                share,
                retry_failed: false,
                ..RunOptions::default()
            };
            let (outcome, counts) = run_quietly(&plan, &store, &opts).unwrap();
            assert_eq!(outcome, Outcome::Complete);
            assert_eq!((counts.done, counts.failed), (12, 0));
            let mut all = store.all().unwrap();
            all.sort_by(|a, b| a.job_id.cmp(&b.job_id));
            rows.push(all);
        }
        assert_eq!(rows[0].len(), rows[1].len());
        for (together, alone) in rows[0].iter().zip(&rows[1]) {
            assert_eq!(together.job_id, alone.job_id);
            assert_eq!(together.status, crate::store::JobStatus::Ok, "{together:?}");
            crate::verify::compare(together, alone)
                .unwrap_or_else(|e| panic!("{} {}: {e}", together.strategy, together.seed));
        }
        // Together: one worker ran each seed's three layout jobs.
        for seed in 1..=3 {
            let workers: BTreeSet<&str> = rows[0]
                .iter()
                .filter(|r| r.seed == seed && r.strategy.starts_with("layout"))
                .map(|r| r.worker.as_str())
                .collect();
            assert_eq!(workers.len(), 1, "seed {seed}: {workers:?}");
        }
    }
}
