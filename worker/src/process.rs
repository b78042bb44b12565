//! The worker process: joins a grid through a link to its coordinator, asks for jobs, runs them
//! (`jobs` at once, each on a thread of its own), renews their leases while they run and submits
//! their rows until the coordinator says the grid is done.
//!
//! It knows no transport: the link is a [`Coordinator`], which the binary makes with
//! `floorcast_coordinator::net::join` (zenoh, the only module that knows it). Delivery is
//! at-least-once: a submission is retried until the coordinator acknowledges it (it may be
//! restarting), and the coordinator deduplicates by job id. A worker gives up when no coordinator
//! has answered for `wait_s`, and leaves when it is told the grid is done or it is refused.

use std::collections::BTreeMap;
use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

use sim_core::Building;

use crate::wire::{
    BuildingRequest, Hello, JobReport, NextReply, RenewReply, Renewal, Submission, SubmitReply,
    WireBuilding, WireJob,
};

/// A worker's link to its coordinator: one typed request and its reply each. `Ok(None)`: no
/// coordinator answered (none is running now, or it is restarting); `Err`: an answer that was an
/// error or could not be decoded.
pub trait Coordinator: Send + Sync {
    /// This worker's id, as the coordinator knows it (the link announced it when it joined).
    fn worker(&self) -> &str;
    /// Where the coordinator is looked for, for messages (e.g. "tcp/10.0.0.2:7447 (campaign
    /// 'default')").
    fn whereabouts(&self) -> String;
    /// Asks for a job.
    fn next(&self, hello: &Hello) -> Result<Option<NextReply>, String>;
    /// Fetches the building with content hash `hash`.
    fn building(
        &self,
        hash: &str,
        request: &BuildingRequest,
    ) -> Result<Option<WireBuilding>, String>;
    /// Extends the lease of job `job_id`.
    fn renew(&self, job_id: &str, renewal: &Renewal) -> Result<Option<RenewReply>, String>;
    /// Returns the row of job `job_id`.
    fn submit(&self, job_id: &str, submission: &Submission) -> Result<Option<SubmitReply>, String>;
}

/// How a worker runs.
#[derive(Debug, Clone, Copy)]
pub struct WorkerOptions {
    /// Jobs run at once (one per core is a good choice).
    pub jobs: usize,
    /// Give up when no coordinator answered for this long, in seconds (0: wait forever).
    pub wait_s: f64,
}

/// What a worker did, for its log.
#[derive(Debug, Clone)]
pub enum WorkerEvent {
    Joined {
        worker: String,
    },
    Started {
        job: String,
        what: String,
    },
    Finished {
        job: String,
        status: crate::wire::JobStatus,
        wall_time_s: f64,
        reply: String,
    },
    Note(String),
}

/// What a worker did in all.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WorkerReport {
    pub jobs_run: usize,
    pub stored: usize,
    pub duplicates: usize,
    pub rejected: usize,
}

#[derive(Debug, thiserror::Error)]
pub enum WorkerError {
    #[error("the coordinator refused this worker: {0}")]
    Refused(String),
    #[error("no coordinator answered on {whereabouts} for {waited_s:.0} s: check that `floorcast run GRID --listen ...` runs there, the address, and the credentials/TLS settings of --zenoh-config")]
    NoCoordinator { whereabouts: String, waited_s: f64 },
    #[error("could not start {jobs} job threads (give fewer --jobs): {source}")]
    Spawn { jobs: usize, source: std::io::Error },
}

/// Runs `job` in `building` and reports what it gave ([`crate::execute::execute_wire`] is the
/// real one).
pub type Executor<'a> = dyn Fn(&WireJob, &Building) -> JobReport + Send + Sync + 'a;
/// Receives the worker's events (from its threads).
pub type EventSink<'a> = dyn Fn(WorkerEvent) + Send + Sync + 'a;

/// Joins a grid through `link`: asks for jobs until the coordinator says the grid is done.
/// `host` goes into the worker's greeting (with this build's version and bench signature).
pub fn run_worker(
    link: &dyn Coordinator,
    host: &str,
    opts: WorkerOptions,
    exec: &Executor<'_>,
    events: &EventSink<'_>,
) -> Result<WorkerReport, WorkerError> {
    let state = State {
        link,
        hello: Hello::this_build(link.worker(), host),
        exec,
        events,
        wait_s: opts.wait_s,
        last_contact: Mutex::new(Instant::now()),
        buildings: Mutex::new(BTreeMap::new()),
        joined: AtomicBool::new(false),
        run: AtomicUsize::new(0),
        stored: AtomicUsize::new(0),
        duplicates: AtomicUsize::new(0),
        rejected: AtomicUsize::new(0),
    };
    let jobs = opts.jobs.max(1);
    // Every slot's thread is started before any asks for a job: a thread the system refuses
    // (too many for its limits) is an error, and the slots already started leave without
    // working, rather than a worker left with what it got and no room for anything else.
    let gate = std::sync::RwLock::new(false);
    let outcomes: Vec<Result<(), WorkerError>> = std::thread::scope(|s| {
        let mut all_started = gate.write().unwrap_or_else(|p| p.into_inner());
        let mut slots = Vec::with_capacity(jobs);
        let mut refused = None;
        for _ in 0..jobs {
            let started = crate::spawn_scoped_thread(s, || {
                if *gate.read().unwrap_or_else(|p| p.into_inner()) {
                    slot(&state)
                } else {
                    Ok(())
                }
            });
            match started {
                Ok(h) => slots.push(h),
                Err(e) => {
                    refused = Some(e);
                    break;
                }
            }
        }
        *all_started = refused.is_none();
        drop(all_started);
        let mut outcomes: Vec<Result<(), WorkerError>> = slots
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect();
        if let Some(source) = refused {
            outcomes.push(Err(WorkerError::Spawn { jobs, source }));
        }
        outcomes
    });
    outcomes.into_iter().collect::<Result<(), _>>()?;
    Ok(WorkerReport {
        jobs_run: state.run.load(Ordering::SeqCst),
        stored: state.stored.load(Ordering::SeqCst),
        duplicates: state.duplicates.load(Ordering::SeqCst),
        rejected: state.rejected.load(Ordering::SeqCst),
    })
}

struct State<'a> {
    link: &'a dyn Coordinator,
    hello: Hello,
    exec: &'a Executor<'a>,
    events: &'a EventSink<'a>,
    wait_s: f64,
    last_contact: Mutex<Instant>,
    /// Buildings fetched so far, by content hash (checked).
    buildings: Mutex<BTreeMap<String, Arc<Building>>>,
    joined: AtomicBool,
    run: AtomicUsize,
    stored: AtomicUsize,
    duplicates: AtomicUsize,
    rejected: AtomicUsize,
}

impl State<'_> {
    fn worker(&self) -> &str {
        &self.hello.worker
    }

    fn contact(&self) {
        *self.last_contact.lock().expect("not poisoned") = Instant::now();
        if !self.joined.swap(true, Ordering::SeqCst) {
            (self.events)(WorkerEvent::Joined {
                worker: self.worker().to_string(),
            });
        }
    }

    /// Fails when no coordinator answered for `wait_s`.
    fn check_silence(&self) -> Result<(), WorkerError> {
        let waited_s = self
            .last_contact
            .lock()
            .expect("not poisoned")
            .elapsed()
            .as_secs_f64();
        if self.wait_s > 0.0 && waited_s > self.wait_s {
            return Err(WorkerError::NoCoordinator {
                whereabouts: self.link.whereabouts(),
                waited_s,
            });
        }
        Ok(())
    }
}

/// Doubles a retry delay up to 2 s.
fn back_off(ms: &mut u64) {
    std::thread::sleep(Duration::from_millis(*ms));
    *ms = (*ms * 2).min(2000);
}

/// One of the worker's `jobs` threads: asks for a job, runs it, and again.
fn slot(x: &State<'_>) -> Result<(), WorkerError> {
    let mut backoff_ms = 100u64;
    loop {
        match x.link.next(&x.hello) {
            Ok(Some(NextReply::Job { job, lease_s })) => {
                x.contact();
                backoff_ms = 100;
                run_one(x, *job, lease_s)?;
            }
            Ok(Some(NextReply::Wait { retry_ms })) => {
                x.contact();
                std::thread::sleep(Duration::from_millis(retry_ms.clamp(10, 10_000)));
            }
            Ok(Some(NextReply::Done)) => return Ok(()),
            Ok(Some(NextReply::Refused { reason })) => return Err(WorkerError::Refused(reason)),
            Ok(None) => {
                x.check_silence()?;
                back_off(&mut backoff_ms);
            }
            Err(e) => {
                (x.events)(WorkerEvent::Note(e));
                x.check_silence()?;
                std::thread::sleep(Duration::from_millis(1000));
            }
        }
    }
}

/// The building with content hash `hash`, fetched from the coordinator on first use (retried
/// while the coordinator is away; one fetch at a time, so each building crosses once).
/// `Ok(Err(_))`: the coordinator has no such building or sent a damaged one.
fn building(x: &State<'_>, hash: &str) -> Result<Result<Arc<Building>, String>, WorkerError> {
    let mut cache = x.buildings.lock().expect("not poisoned");
    if let Some(b) = cache.get(hash) {
        return Ok(Ok(Arc::clone(b)));
    }
    let request = BuildingRequest {
        worker: x.worker().to_string(),
    };
    let mut backoff_ms = 100u64;
    loop {
        match x.link.building(hash, &request) {
            Ok(Some(w)) => {
                x.contact();
                return Ok(w.to_building(hash).map(|b| {
                    let b = Arc::new(b);
                    cache.insert(hash.to_string(), Arc::clone(&b));
                    b
                }));
            }
            Ok(None) => {}
            Err(e) => return Ok(Err(e)),
        }
        x.check_silence()?;
        back_off(&mut backoff_ms);
    }
}

/// Runs one job while a second thread renews its lease, then submits its row until the
/// coordinator acknowledges it.
fn run_one(x: &State<'_>, job: WireJob, lease_s: f64) -> Result<(), WorkerError> {
    let id = job.job_id.clone();
    (x.events)(WorkerEvent::Started {
        job: id.clone(),
        what: format!("{} {} seed {}", job.building_name, job.label, job.seed),
    });
    let every = Duration::from_secs_f64((lease_s / 3.0).clamp(0.05, 600.0));
    let (stop, stopped) = mpsc::channel::<()>();
    let result = std::thread::scope(|s| {
        let id = id.as_str();
        // (Without the thread, the job runs unrenewed: should its lease run out, the
        // coordinator hands it to another worker too, and keeps the first result.)
        let renewing = crate::spawn_scoped_thread(s, move || {
            let renewal = Renewal {
                worker: x.worker().to_string(),
            };
            // Until the job ends (the sender is dropped).
            while let Err(mpsc::RecvTimeoutError::Timeout) = stopped.recv_timeout(every) {
                if let Ok(Some(RenewReply::NotLeased)) = x.link.renew(id, &renewal) {
                    (x.events)(WorkerEvent::Note(format!(
                        "job {id} was handed to another worker meanwhile; finishing it anyway"
                    )));
                    return;
                }
            }
        });
        if let Err(e) = renewing {
            (x.events)(WorkerEvent::Note(format!(
                "job {id}: its lease is not renewed: the system refused a thread ({e})"
            )));
        }
        let result = match building(x, &job.building_hash) {
            Ok(Ok(b)) => Ok(run_guarded(x, &job, &b)),
            Ok(Err(e)) => Ok(JobReport::failed(format!("its building: {e}"))),
            Err(e) => Err(e),
        };
        drop(stop);
        result
    })?;
    x.run.fetch_add(1, Ordering::SeqCst);
    let status = result.status();
    let wall_time_s = result.wall_time_s;
    let submission = Submission {
        worker: x.worker().to_string(),
        job_id: id.clone(),
        report: result,
    };
    let mut backoff_ms = 100u64;
    let reply = loop {
        match x.link.submit(&id, &submission) {
            Ok(Some(r)) => {
                x.contact();
                break r;
            }
            Ok(None) => {}
            Err(e) => (x.events)(WorkerEvent::Note(format!("submitting job {id}: {e}"))),
        }
        x.check_silence()?;
        back_off(&mut backoff_ms);
    };
    let what = match &reply {
        SubmitReply::Stored => {
            x.stored.fetch_add(1, Ordering::SeqCst);
            "stored".to_string()
        }
        SubmitReply::Duplicate => {
            x.duplicates.fetch_add(1, Ordering::SeqCst);
            "already stored (duplicate)".to_string()
        }
        SubmitReply::Rejected { reason } => {
            x.rejected.fetch_add(1, Ordering::SeqCst);
            format!("rejected: {reason}")
        }
    };
    (x.events)(WorkerEvent::Finished {
        job: id,
        status,
        wall_time_s,
        reply: what,
    });
    Ok(())
}

/// Runs the job; a panic in it (a bug) becomes a failure that says so, and the worker goes on.
fn run_guarded(x: &State<'_>, job: &WireJob, building: &Building) -> JobReport {
    std::panic::catch_unwind(AssertUnwindSafe(|| (x.exec)(job, building))).unwrap_or_else(|p| {
        JobReport::failed(format!(
            "the job panicked on worker {} (a bug in floorcast, please report it): {}",
            x.worker(),
            crate::panic_message(&*p)
        ))
    })
}

#[cfg(test)]
mod tests {
    use std::collections::VecDeque;

    use super::*;
    use crate::wire::JobOutcome;
    use crate::Settings;

    /// A coordinator in memory: hands out `jobs`, ignores the first `silent_submits`
    /// submissions (as a restarting coordinator would), refuses or stays silent on request.
    struct Fake {
        jobs: Mutex<VecDeque<WireJob>>,
        building: WireBuilding,
        silent_submits: AtomicUsize,
        submitted: Mutex<Vec<(String, Submission)>>,
        renewed: AtomicUsize,
        refuse: bool,
        silent: bool,
        /// Every thread the worker's job slot starts after asking for a job is refused.
        refuse_threads: bool,
    }

    impl Coordinator for Fake {
        fn worker(&self) -> &str {
            "w"
        }
        fn whereabouts(&self) -> String {
            "memory (campaign 'test')".into()
        }
        fn next(&self, _: &Hello) -> Result<Option<NextReply>, String> {
            if self.silent {
                return Ok(None);
            }
            if self.refuse_threads {
                // (Asked on the slot's thread, which starts the job's threads.)
                crate::refuse_threads_after(Some(0));
            }
            if self.refuse {
                return Ok(Some(NextReply::Refused {
                    reason: "not you".into(),
                }));
            }
            Ok(Some(match self.jobs.lock().unwrap().pop_front() {
                Some(job) => NextReply::Job {
                    job: Box::new(job),
                    lease_s: 0.3,
                },
                None => NextReply::Done,
            }))
        }
        fn building(&self, _: &str, _: &BuildingRequest) -> Result<Option<WireBuilding>, String> {
            Ok(Some(self.building.clone()))
        }
        fn renew(&self, _: &str, _: &Renewal) -> Result<Option<RenewReply>, String> {
            self.renewed.fetch_add(1, Ordering::SeqCst);
            Ok(Some(RenewReply::Renewed))
        }
        fn submit(&self, id: &str, s: &Submission) -> Result<Option<SubmitReply>, String> {
            if self
                .silent_submits
                .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| n.checked_sub(1))
                .is_ok()
            {
                return Ok(None);
            }
            self.submitted
                .lock()
                .unwrap()
                .push((id.to_string(), s.clone()));
            Ok(Some(SubmitReply::Stored))
        }
    }

    fn fake(n_jobs: usize) -> Fake {
        let b = crate::small_building();
        let jobs = (0..n_jobs)
            .map(|i| WireJob {
                job_id: format!("job{i}"),
                grid: "g".into(),
                building_name: "small".into(),
                building_hash: b.content_hash(),
                strategy: "baseline".into(),
                label: "baseline".into(),
                seed: i as u64,
                settings: Settings::default(),
                start: None,
                program: None,
            })
            .collect();
        Fake {
            jobs: Mutex::new(jobs),
            building: WireBuilding::from_building(&b),
            silent_submits: AtomicUsize::new(0),
            submitted: Mutex::new(Vec::new()),
            renewed: AtomicUsize::new(0),
            refuse: false,
            silent: false,
            refuse_threads: false,
        }
    }

    /// An executor that runs nothing: a failure "not run" after 250 ms (the lease is 300 ms
    /// and renewed every 100 ms, so each job's lease is renewed at least once even on a busy
    /// machine), or a panic for seed 1.
    fn exec(job: &WireJob, _: &Building) -> JobReport {
        std::thread::sleep(Duration::from_millis(250));
        assert_ne!(job.seed, 1, "a bug in the job");
        JobReport::failed("not run")
    }

    fn options(wait_s: f64) -> WorkerOptions {
        WorkerOptions { jobs: 2, wait_s }
    }

    #[test]
    fn every_job_is_run_once_and_submitted_until_acknowledged_and_a_panic_fails_only_its_job() {
        let f = fake(5);
        f.silent_submits.store(3, Ordering::SeqCst);
        let events = Mutex::new(Vec::new());
        let report = run_worker(&f, "host", options(5.0), &exec, &|e| {
            events.lock().unwrap().push(e)
        })
        .unwrap();
        assert_eq!(
            report,
            WorkerReport {
                jobs_run: 5,
                stored: 5,
                duplicates: 0,
                rejected: 0
            }
        );
        assert!(
            f.renewed.load(Ordering::SeqCst) >= 5,
            "a lease renewed per job at least"
        );
        let mut submitted = f.submitted.into_inner().unwrap();
        submitted.sort_by(|a, b| a.0.cmp(&b.0));
        let ids: Vec<&str> = submitted.iter().map(|(id, _)| id.as_str()).collect();
        assert_eq!(ids, ["job0", "job1", "job2", "job3", "job4"]);
        for (id, s) in &submitted {
            assert_eq!(&s.job_id, id);
            assert_eq!(s.worker, "w");
            let JobOutcome::Failed { error } = &s.report.outcome else {
                panic!("{id}: {:?}", s.report);
            };
            let panicked = error.contains("panicked") && error.contains("a bug in the job");
            assert_eq!(panicked, id == "job1", "{id}: {error}");
            assert_eq!(error == "not run", id != "job1", "{id}: {error}");
        }
        let events = events.into_inner().unwrap();
        let joined = events
            .iter()
            .filter(|e| matches!(e, WorkerEvent::Joined { .. }))
            .count();
        assert_eq!(joined, 1);
    }

    #[test]
    fn a_silent_coordinator_is_given_up_naming_where_it_was_looked_for() {
        let mut f = fake(1);
        f.silent = true;
        let t = Instant::now();
        let e = run_worker(&f, "host", options(0.3), &exec, &|_| {}).unwrap_err();
        assert!(matches!(e, WorkerError::NoCoordinator { .. }), "{e}");
        assert!(e.to_string().contains("memory (campaign 'test')"), "{e}");
        assert!(t.elapsed() < Duration::from_secs(10));
    }

    /// A job slot's thread the system refuses (the first, second or third of three): the worker
    /// is an error saying what to do, and no job is taken (the slots already started leave
    /// without asking for one).
    #[test]
    fn a_refused_slot_thread_is_an_error_and_no_job_is_taken() {
        for started in 0..3 {
            let f = fake(4);
            crate::refuse_threads_after(Some(started));
            let e = run_worker(
                &f,
                "host",
                WorkerOptions {
                    jobs: 3,
                    wait_s: 5.0,
                },
                &exec,
                &|_| {},
            );
            crate::refuse_threads_after(None);
            let e = e.unwrap_err();
            assert!(
                matches!(e, WorkerError::Spawn { jobs: 3, .. })
                    && e.to_string().contains("give fewer --jobs"),
                "after {started} threads: {e}"
            );
            assert_eq!(f.jobs.lock().unwrap().len(), 4, "after {started} threads");
            assert!(f.submitted.lock().unwrap().is_empty());
        }
    }

    /// A job's lease renewal thread refused: the job still runs and is submitted (unrenewed),
    /// and the worker says so.
    #[test]
    fn a_refused_renewal_thread_leaves_the_job_run_but_unrenewed() {
        let mut f = fake(1);
        f.refuse_threads = true;
        let events = Mutex::new(Vec::new());
        let opts = WorkerOptions {
            jobs: 1,
            wait_s: 5.0,
        };
        let report = run_worker(&f, "host", opts, &exec, &|e| events.lock().unwrap().push(e));
        let report = report.unwrap();
        assert_eq!((report.jobs_run, report.stored), (1, 1));
        assert_eq!(f.renewed.load(Ordering::SeqCst), 0);
        let notes = format!("{:?}", events.lock().unwrap());
        assert!(
            notes.contains("job job0: its lease is not renewed: the system refused a thread"),
            "{notes}"
        );
    }

    #[test]
    fn a_refused_worker_leaves_with_the_reason() {
        let mut f = fake(1);
        f.refuse = true;
        let e = run_worker(&f, "host", options(5.0), &exec, &|_| {}).unwrap_err();
        assert_eq!(
            e.to_string(),
            "the coordinator refused this worker: not you"
        );
    }
}
