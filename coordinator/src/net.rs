//! The zenoh transport: the only module of floorcast that knows zenoh.
//!
//! Pull-based work queue (zenoh itself has no work queue; see `ARCHITECTURE.md`). Keys, under
//! `floorcast/v1/<campaign>/`:
//!
//! | key | who declares | what |
//! |---|---|---|
//! | `ctl/next` | coordinator (queryable) | a worker `get`s one job: [`Hello`] -> [`NextReply`] |
//! | `ctl/submit/<job_id>` | coordinator (queryable) | a worker returns a result: [`Submission`] -> [`SubmitReply`] |
//! | `ctl/renew/<job_id>` | coordinator (queryable) | a worker extends its lease: [`Renewal`] -> [`RenewReply`] |
//! | `ctl/building/<hash>` | coordinator (queryable) | a worker fetches a building once: [`BuildingRequest`] -> [`WireBuilding`] |
//! | `workers/<worker_id>` | each worker (liveliness token) | the coordinator requeues the jobs of a worker whose token disappears |
//! | `coordinator` | coordinator (liveliness token) | for observers |
//!
//! Delivery is at-least-once (a worker retries a submission until it is acknowledged; a job of a
//! vanished worker is handed out again), so the coordinator deduplicates by job id. Every message
//! is decoded and validated ([`crate::wire`]); a malformed or foreign one is logged and answered
//! with an error, never trusted. Queries use `ConsolidationMode::None` (the default keeps one
//! reply per key). zenoh needs tokio's multi-thread runtime; simulations run on blocking
//! threads, never on the runtime's workers.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

use sim_core::Building;
use tokio::sync::oneshot;
use zenoh::query::{ConsolidationMode, Query, QueryTarget};
use zenoh::sample::SampleKind;
use zenoh::Session;

use crate::execute::{failed_wire_row, wire_job};
use crate::grid::Plan;
use crate::inbox::{Answer, Inbox, InboxSender, RemoteSession, RemoteWorkers, LOCAL};
use crate::store::StoredResult;
use crate::wire::{
    decode, encode, BuildingRequest, Hello, Message, NextReply, RenewReply, Renewal, Submission,
    SubmitReply, WireBuilding, WireJob,
};

/// Where and how to reach the other side.
#[derive(Debug, Clone, Default)]
pub struct NetConfig {
    /// Endpoints to listen on, e.g. `tcp/0.0.0.0:7447`.
    pub listen: Vec<String>,
    /// Endpoints to connect to (a coordinator or a `zenohd` router), e.g. `tcp/host:7447`.
    pub connect: Vec<String>,
    /// A zenoh configuration file (JSON5/YAML): TLS, mutual TLS, user/password, router mode...
    /// Endpoints given on the command line are added to it.
    pub zenoh_config: Option<PathBuf>,
    /// Separates grids sharing one router (default `default`).
    pub campaign: String,
}

#[derive(Debug, thiserror::Error)]
pub enum NetError {
    #[error("zenoh configuration {path}: {message}")]
    ConfigFile { path: PathBuf, message: String },
    #[error("bad network option {what}: {message}")]
    Option { what: String, message: String },
    #[error("cannot open the zenoh session ({0}); check the endpoints (is the port free? is the address reachable?) and --zenoh-config")]
    Open(String),
    #[error("zenoh: {0}")]
    Zenoh(String),
    #[error("the coordinator refused this worker: {0}")]
    Refused(String),
    #[error("no coordinator answered on {endpoints} (campaign '{campaign}') for {waited_s:.0} s: check that `floorcast run GRID --listen ...` runs there, the address, and the credentials/TLS settings of --zenoh-config")]
    NoCoordinator {
        endpoints: String,
        campaign: String,
        waited_s: f64,
    },
}

fn zerr(e: impl std::fmt::Display) -> NetError {
    NetError::Zenoh(e.to_string())
}

/// `floorcast/v1/<campaign>/<rest>`.
fn key(campaign: &str, rest: &str) -> String {
    format!("floorcast/v1/{campaign}/{rest}")
}

/// Names that may be one key chunk: worker ids, job ids, campaigns.
pub fn valid_chunk(s: &str) -> bool {
    !s.is_empty()
        && s.len() <= 96
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_' || c == '.')
}

fn zenoh_config(cfg: &NetConfig) -> Result<zenoh::Config, NetError> {
    if !valid_chunk(&cfg.campaign) {
        return Err(NetError::Option {
            what: "--campaign".into(),
            message: format!(
                "'{}' is not a name of letters, digits, '-', '_' or '.'",
                cfg.campaign
            ),
        });
    }
    let mut c = match &cfg.zenoh_config {
        Some(path) => {
            if !path.exists() {
                return Err(NetError::ConfigFile {
                    path: path.clone(),
                    message: "no such file".into(),
                });
            }
            zenoh::Config::from_file(path).map_err(|e| NetError::ConfigFile {
                path: path.clone(),
                message: e.to_string(),
            })?
        }
        None => {
            // Explicit endpoints only: no multicast discovery, no gossip, no port unless asked.
            let mut c = zenoh::Config::default();
            for (k, v) in [
                ("mode", "\"peer\""),
                ("scouting/multicast/enabled", "false"),
                ("scouting/gossip/enabled", "false"),
                ("listen/endpoints", "[]"),
            ] {
                c.insert_json5(k, v).map_err(zerr)?;
            }
            c
        }
    };
    for (what, list, k) in [
        ("--listen", &cfg.listen, "listen/endpoints"),
        ("--connect", &cfg.connect, "connect/endpoints"),
    ] {
        if list.is_empty() {
            continue;
        }
        for e in list {
            if !e.contains('/') {
                return Err(NetError::Option {
                    what: what.into(),
                    message: format!(
                        "'{e}' is not a zenoh endpoint; write e.g. tcp/0.0.0.0:7447, tls/host:7447 or unixsock-stream//tmp/floorcast.sock"
                    ),
                });
            }
        }
        let json = serde_json::to_string(list).expect("strings serialise");
        c.insert_json5(k, &json).map_err(|e| NetError::Option {
            what: what.into(),
            message: e.to_string(),
        })?;
    }
    Ok(c)
}

fn runtime() -> Result<tokio::runtime::Runtime, NetError> {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .thread_name("floorcast-net")
        .build()
        .map_err(zerr)
}

fn payload(q: &Query) -> Vec<u8> {
    q.payload()
        .map(|p| p.to_bytes().into_owned())
        .unwrap_or_default()
}

fn last_chunk(k: &str) -> &str {
    k.rsplit('/').next().unwrap_or("")
}

// ------------------------------------------------------------------------------------------
// Coordinator side

/// The coordinator's zenoh session and its tasks; dropped with [`Listener::close`].
#[derive(Debug)]
struct Listener {
    rt: tokio::runtime::Runtime,
    session: Session,
    describe: String,
}

impl RemoteSession for Listener {
    fn describe(&self) -> String {
        self.describe.clone()
    }

    fn close(self: Box<Self>) {
        let Listener { rt, session, .. } = *self;
        rt.block_on(async {
            let _ = tokio::time::timeout(Duration::from_secs(3), session.close()).await;
        });
        rt.shutdown_timeout(Duration::from_secs(1));
    }
}

/// Context shared by the coordinator's query handlers.
struct Ctx {
    plan: Arc<Plan>,
    /// Encoded [`WireBuilding`] messages by content hash.
    buildings: std::collections::BTreeMap<String, Vec<u8>>,
    lease_s: f64,
    inbox: mpsc::Sender<Inbox>,
}

impl Ctx {
    fn log(&self, line: String) {
        let _ = self.inbox.send(Inbox::Log(line));
    }
}

/// The coordinator's side of the network: `run_plan` opens it when its caller passes the
/// `NetConfig` as the run's [`RemoteWorkers`].
impl RemoteWorkers for NetConfig {
    fn open(
        &self,
        plan: Arc<Plan>,
        lease_s: f64,
        inbox: InboxSender,
    ) -> Result<Box<dyn RemoteSession>, Box<dyn std::error::Error + Send + Sync>> {
        Ok(Box::new(serve(self, plan, lease_s, inbox.0)?))
    }
}

/// Opens the coordinator's session, declares its queryables and liveliness subscriber, and
/// forwards what workers say into `inbox`.
fn serve(
    cfg: &NetConfig,
    plan: Arc<Plan>,
    lease_s: f64,
    inbox: mpsc::Sender<Inbox>,
) -> Result<Listener, NetError> {
    let config = zenoh_config(cfg)?;
    // The bench signature workers are checked against, made before any of them asks.
    floorcast_worker::bench_signature();
    let rt = runtime()?;
    let c = cfg.campaign.clone();
    let buildings = plan
        .buildings
        .iter()
        .map(|b| {
            (
                b.hash.clone(),
                encode(&WireBuilding::from_building(&b.building)),
            )
        })
        .collect();
    let ctx = Arc::new(Ctx {
        plan,
        buildings,
        lease_s,
        inbox,
    });
    let session = rt.block_on(async {
        let session = zenoh::open(config)
            .await
            .map_err(|e| NetError::Open(e.to_string()))?;
        let next = session
            .declare_queryable(key(&c, "ctl/next"))
            .await
            .map_err(zerr)?;
        let submit = session
            .declare_queryable(key(&c, "ctl/submit/*"))
            .await
            .map_err(zerr)?;
        let renew = session
            .declare_queryable(key(&c, "ctl/renew/*"))
            .await
            .map_err(zerr)?;
        let building = session
            .declare_queryable(key(&c, "ctl/building/*"))
            .await
            .map_err(zerr)?;
        let live = session
            .liveliness()
            .declare_subscriber(key(&c, "workers/*"))
            .history(true)
            .await
            .map_err(zerr)?;
        let token = session
            .liveliness()
            .declare_token(key(&c, "coordinator"))
            .await
            .map_err(zerr)?;
        let x = Arc::clone(&ctx);
        tokio::spawn(async move {
            while let Ok(q) = next.recv_async().await {
                tokio::spawn(on_next(Arc::clone(&x), q));
            }
        });
        let x = Arc::clone(&ctx);
        tokio::spawn(async move {
            while let Ok(q) = submit.recv_async().await {
                tokio::spawn(on_submit(Arc::clone(&x), q));
            }
        });
        let x = Arc::clone(&ctx);
        tokio::spawn(async move {
            while let Ok(q) = renew.recv_async().await {
                tokio::spawn(on_renew(Arc::clone(&x), q));
            }
        });
        let x = Arc::clone(&ctx);
        tokio::spawn(async move {
            while let Ok(q) = building.recv_async().await {
                tokio::spawn(on_building(Arc::clone(&x), q));
            }
        });
        let x = Arc::clone(&ctx);
        tokio::spawn(async move {
            let _token = token; // alive as long as this task
            while let Ok(s) = live.recv_async().await {
                let id = last_chunk(s.key_expr().as_str()).to_string();
                let msg = match s.kind() {
                    SampleKind::Put => Inbox::Joined(id),
                    SampleKind::Delete => Inbox::Left(id),
                };
                if x.inbox.send(msg).is_err() {
                    break;
                }
            }
        });
        Ok::<_, NetError>(session)
    })?;
    let mut describe = if cfg.listen.is_empty() {
        String::new()
    } else {
        format!("listening on {}", cfg.listen.join(", "))
    };
    if !cfg.connect.is_empty() {
        if !describe.is_empty() {
            describe.push_str("; ");
        }
        describe.push_str(&format!("connected to {}", cfg.connect.join(", ")));
    }
    if let Some(p) = &cfg.zenoh_config {
        describe.push_str(&format!(" (zenoh config {})", p.display()));
    }
    describe.push_str(&format!(
        "; workers join with `floorcast worker --connect ENDPOINT{}`",
        if cfg.campaign == "default" {
            String::new()
        } else {
            format!(" --campaign {}", cfg.campaign)
        }
    ));
    Ok(Listener {
        rt,
        session,
        describe,
    })
}

async fn reply<T: Message>(q: &Query, msg: &T) {
    let _ = q.reply(q.key_expr().clone(), encode(msg)).await;
}

async fn refuse(ctx: &Ctx, q: &Query, what: &str, why: String) {
    ctx.log(format!(
        "dropped a message on {}: {what}: {why}",
        q.key_expr().as_str()
    ));
    let _ = q.reply_err(why).await;
}

async fn on_next(ctx: Arc<Ctx>, q: Query) {
    let hello = match decode::<Hello>(&payload(&q)) {
        Ok(h) => h,
        Err(e) => return refuse(&ctx, &q, "not a job request", e.to_string()).await,
    };
    if !valid_chunk(&hello.worker) || hello.worker.starts_with(LOCAL) {
        let why = format!(
            "'{}' is not a valid remote worker id (letters, digits, '-', '_', '.'; not starting with '{}')",
            hello.worker,
            LOCAL
        );
        return refuse(&ctx, &q, "bad worker id", why).await;
    }
    if let Err(reason) = hello.compatible() {
        ctx.log(format!("refused worker {}: {reason}", hello.worker));
        return reply(&q, &NextReply::Refused { reason }).await;
    }
    let (tx, rx) = oneshot::channel();
    let sent = ctx.inbox.send(Inbox::Request {
        worker: hello.worker.clone(),
        reply: tx,
    });
    let answer = match (sent, rx.await) {
        (Ok(()), Ok(a)) => a,
        _ => return, // the coordinator is shutting down
    };
    let msg = match answer {
        Answer::Run(job) => NextReply::Job {
            job: Box::new(wire_job(&ctx.plan, &job)),
            lease_s: ctx.lease_s,
        },
        Answer::Wait => NextReply::Wait { retry_ms: 200 },
        Answer::Done => NextReply::Done,
    };
    reply(&q, &msg).await;
}

async fn on_submit(ctx: Arc<Ctx>, q: Query) {
    let job = last_chunk(q.key_expr().as_str()).to_string();
    let sub = match decode::<Submission>(&payload(&q)) {
        Ok(s) => s,
        Err(e) => return refuse(&ctx, &q, "not a result", e.to_string()).await,
    };
    if sub.result.job_id != job {
        let why = format!(
            "result of job {} submitted on the key of job {job}",
            sub.result.job_id
        );
        return refuse(&ctx, &q, "mismatched result", why).await;
    }
    let (tx, rx) = oneshot::channel();
    let sent = ctx.inbox.send(Inbox::Submit {
        worker: sub.worker,
        result: Box::new(sub.result),
        reply: tx,
    });
    if let (Ok(()), Ok(a)) = (sent, rx.await) {
        reply(&q, &a).await;
    }
}

async fn on_building(ctx: Arc<Ctx>, q: Query) {
    let hash = last_chunk(q.key_expr().as_str()).to_string();
    if let Err(e) = decode::<BuildingRequest>(&payload(&q)) {
        return refuse(&ctx, &q, "not a building request", e.to_string()).await;
    }
    match ctx.buildings.get(&hash) {
        Some(bytes) => {
            let _ = q.reply(q.key_expr().clone(), bytes.clone()).await;
        }
        None => {
            let why = format!("no building with hash {hash} in grid '{}'", ctx.plan.name);
            refuse(&ctx, &q, "unknown building", why).await
        }
    }
}

async fn on_renew(ctx: Arc<Ctx>, q: Query) {
    let job = last_chunk(q.key_expr().as_str()).to_string();
    let r = match decode::<Renewal>(&payload(&q)) {
        Ok(r) => r,
        Err(e) => return refuse(&ctx, &q, "not a lease renewal", e.to_string()).await,
    };
    let (tx, rx) = oneshot::channel();
    let sent = ctx.inbox.send(Inbox::Renew {
        worker: r.worker,
        job,
        reply: tx,
    });
    if let (Ok(()), Ok(a)) = (sent, rx.await) {
        reply(&q, &a).await;
    }
}

// ------------------------------------------------------------------------------------------
// Worker side

/// How a remote worker runs.
#[derive(Debug, Clone)]
pub struct WorkerOptions {
    pub net: NetConfig,
    /// Jobs run at once (one per core is a good choice).
    pub jobs: usize,
    /// Give up when no coordinator answered for this long (0: wait forever).
    pub wait_s: f64,
    /// The worker's id (default: host, process id and zenoh id).
    pub name: Option<String>,
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
        status: String,
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

/// Runs `job` in `building` as worker `worker` (on a blocking thread) and returns its store row.
pub type Executor = dyn Fn(&WireJob, &Building, &str) -> StoredResult + Send + Sync;
/// Receives the worker's events (from the network threads).
pub type EventSink = dyn Fn(WorkerEvent) + Send + Sync;

/// Joins a grid: asks for jobs until the coordinator says the grid is done.
pub fn run_worker(
    opts: &WorkerOptions,
    exec: Arc<Executor>,
    events: Arc<EventSink>,
) -> Result<WorkerReport, NetError> {
    if let Some(n) = &opts.name {
        if !valid_chunk(n) || n.starts_with(LOCAL) {
            return Err(NetError::Option {
                what: "--name".into(),
                message: format!(
                    "'{n}' is not a name of letters, digits, '-', '_' or '.' (not starting with '{}')",
                    LOCAL
                ),
            });
        }
    }
    let config = zenoh_config(&opts.net)?;
    let rt = runtime()?;
    let result = rt.block_on(async {
        let session = zenoh::open(config)
            .await
            .map_err(|e| NetError::Open(e.to_string()))?;
        let host = crate::store::host_name();
        let worker = opts.name.clone().unwrap_or_else(|| {
            let zid = session.zid().to_string();
            let host: String = host
                .chars()
                .filter(|c| c.is_ascii_alphanumeric() || *c == '-')
                .take(32)
                .collect();
            format!("{host}-{}-{}", std::process::id(), &zid[..zid.len().min(8)])
        });
        let token = session
            .liveliness()
            .declare_token(key(&opts.net.campaign, &format!("workers/{worker}")))
            .await
            .map_err(zerr)?;
        let shared = Arc::new(Slots {
            session: session.clone(),
            campaign: opts.net.campaign.clone(),
            hello: Hello::this_build(&worker, &host),
            exec,
            events,
            wait_s: opts.wait_s,
            endpoints: opts.net.connect.join(", "),
            last_contact: std::sync::Mutex::new(Instant::now()),
            buildings: tokio::sync::Mutex::new(std::collections::BTreeMap::new()),
            joined: AtomicBool::new(false),
            run: AtomicUsize::new(0),
            stored: AtomicUsize::new(0),
            duplicates: AtomicUsize::new(0),
            rejected: AtomicUsize::new(0),
        });
        let mut tasks = Vec::new();
        for _ in 0..opts.jobs.max(1) {
            tasks.push(tokio::spawn(slot(Arc::clone(&shared))));
        }
        let mut outcome = Ok(());
        for t in tasks {
            match t.await {
                Ok(Ok(())) => {}
                Ok(Err(e)) => {
                    if outcome.is_ok() {
                        outcome = Err(e);
                    }
                }
                Err(e) => outcome = Err(zerr(e)),
            }
        }
        drop(token);
        let _ = tokio::time::timeout(Duration::from_secs(3), session.close()).await;
        outcome.map(|()| WorkerReport {
            jobs_run: shared.run.load(Ordering::SeqCst),
            stored: shared.stored.load(Ordering::SeqCst),
            duplicates: shared.duplicates.load(Ordering::SeqCst),
            rejected: shared.rejected.load(Ordering::SeqCst),
        })
    });
    rt.shutdown_timeout(Duration::from_secs(1));
    result
}

struct Slots {
    session: Session,
    campaign: String,
    hello: Hello,
    exec: Arc<Executor>,
    events: Arc<EventSink>,
    wait_s: f64,
    endpoints: String,
    last_contact: std::sync::Mutex<Instant>,
    /// Buildings fetched so far, by content hash (checked).
    buildings: tokio::sync::Mutex<std::collections::BTreeMap<String, Arc<Building>>>,
    joined: AtomicBool,
    run: AtomicUsize,
    stored: AtomicUsize,
    duplicates: AtomicUsize,
    rejected: AtomicUsize,
}

impl Slots {
    fn contact(&self) {
        *self.last_contact.lock().expect("not poisoned") = Instant::now();
        if !self.joined.swap(true, Ordering::SeqCst) {
            (self.events)(WorkerEvent::Joined {
                worker: self.hello.worker.clone(),
            });
        }
    }

    /// Fails when no coordinator answered for `wait_s`.
    fn check_silence(&self) -> Result<(), NetError> {
        let waited_s = self
            .last_contact
            .lock()
            .expect("not poisoned")
            .elapsed()
            .as_secs_f64();
        if self.wait_s > 0.0 && waited_s > self.wait_s {
            return Err(NetError::NoCoordinator {
                endpoints: if self.endpoints.is_empty() {
                    "the configured endpoints".into()
                } else {
                    self.endpoints.clone()
                },
                campaign: self.campaign.clone(),
                waited_s,
            });
        }
        Ok(())
    }
}

/// One `get` with a typed reply. `Ok(None)`: nobody answered (no coordinator now).
async fn ask<T: Message>(
    s: &Session,
    key: &str,
    body: Vec<u8>,
    timeout: Duration,
) -> Result<Option<T>, String> {
    let replies = s
        .get(key)
        .payload(body)
        .target(QueryTarget::BestMatching)
        .consolidation(ConsolidationMode::None)
        .timeout(timeout)
        .await
        .map_err(|e| e.to_string())?;
    let mut out: Option<Result<T, String>> = None;
    while let Ok(reply) = replies.recv_async().await {
        if out.is_some() {
            continue; // drain; the first answer counts
        }
        out = Some(match reply.result() {
            Ok(sample) => decode::<T>(&sample.payload().to_bytes()).map_err(|e| e.to_string()),
            Err(e) => Err(format!(
                "the coordinator answered with an error: {}",
                String::from_utf8_lossy(&e.payload().to_bytes())
            )),
        });
    }
    out.transpose()
}

async fn slot(x: Arc<Slots>) -> Result<(), NetError> {
    let next_key = key(&x.campaign, "ctl/next");
    let mut backoff_ms = 100u64;
    loop {
        let reply = ask::<NextReply>(
            &x.session,
            &next_key,
            encode(&x.hello),
            Duration::from_secs(10),
        )
        .await;
        match reply {
            Ok(Some(NextReply::Job { job, lease_s })) => {
                x.contact();
                backoff_ms = 100;
                run_one(&x, *job, lease_s).await?;
            }
            Ok(Some(NextReply::Wait { retry_ms })) => {
                x.contact();
                tokio::time::sleep(Duration::from_millis(retry_ms.clamp(10, 10_000))).await;
            }
            Ok(Some(NextReply::Done)) => return Ok(()),
            Ok(Some(NextReply::Refused { reason })) => return Err(NetError::Refused(reason)),
            Ok(None) => {
                x.check_silence()?;
                tokio::time::sleep(Duration::from_millis(backoff_ms)).await;
                backoff_ms = (backoff_ms * 2).min(2000);
            }
            Err(e) => {
                (x.events)(WorkerEvent::Note(e));
                x.check_silence()?;
                tokio::time::sleep(Duration::from_millis(1000)).await;
            }
        }
    }
}

/// The building with content hash `hash`, fetched from the coordinator on first use (retried
/// while the coordinator is away). `Ok(Err(_))`: the coordinator has no such building or sent a
/// damaged one.
async fn building(x: &Arc<Slots>, hash: &str) -> Result<Result<Arc<Building>, String>, NetError> {
    let mut cache = x.buildings.lock().await;
    if let Some(b) = cache.get(hash) {
        return Ok(Ok(Arc::clone(b)));
    }
    let k = key(&x.campaign, &format!("ctl/building/{hash}"));
    let body = encode(&BuildingRequest {
        worker: x.hello.worker.clone(),
    });
    let mut backoff_ms = 100u64;
    loop {
        match ask::<WireBuilding>(&x.session, &k, body.clone(), Duration::from_secs(30)).await {
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
        tokio::time::sleep(Duration::from_millis(backoff_ms)).await;
        backoff_ms = (backoff_ms * 2).min(2000);
    }
}

async fn run_one(x: &Arc<Slots>, job: WireJob, lease_s: f64) -> Result<(), NetError> {
    let id = job.job_id.clone();
    (x.events)(WorkerEvent::Started {
        job: id.clone(),
        what: format!("{} {} seed {}", job.building_name, job.label, job.seed),
    });
    // Renew the lease while the job runs.
    let renewer = {
        let x = Arc::clone(x);
        let id = id.clone();
        let every = Duration::from_secs_f64((lease_s / 3.0).clamp(0.05, 600.0));
        tokio::spawn(async move {
            let k = key(&x.campaign, &format!("ctl/renew/{id}"));
            let body = encode(&Renewal {
                worker: x.hello.worker.clone(),
            });
            loop {
                tokio::time::sleep(every).await;
                if let Ok(Some(RenewReply::NotLeased)) =
                    ask::<RenewReply>(&x.session, &k, body.clone(), Duration::from_secs(5)).await
                {
                    (x.events)(WorkerEvent::Note(format!(
                        "job {id} was handed to another worker meanwhile; finishing it anyway"
                    )));
                    return;
                }
            }
        })
    };
    let exec = Arc::clone(&x.exec);
    let worker = x.hello.worker.clone();
    let result = match building(x, &job.building_hash).await? {
        Ok(b) => tokio::task::spawn_blocking(move || exec(&job, &b, &worker))
            .await
            .map_err(zerr)?,
        Err(e) => failed_wire_row(&job, &worker, e),
    };
    renewer.abort();
    x.run.fetch_add(1, Ordering::SeqCst);
    let status = result.status.clone();
    let wall_time_s = result.wall_time_s;
    let body = encode(&Submission {
        worker: x.hello.worker.clone(),
        result,
    });
    let k = key(&x.campaign, &format!("ctl/submit/{id}"));
    let mut backoff_ms = 100u64;
    // Retry until acknowledged: the coordinator may be restarting.
    let reply = loop {
        match ask::<SubmitReply>(&x.session, &k, body.clone(), Duration::from_secs(30)).await {
            Ok(Some(r)) => {
                x.contact();
                break r;
            }
            Ok(None) => {}
            Err(e) => (x.events)(WorkerEvent::Note(format!("submitting job {id}: {e}"))),
        }
        x.check_silence()?;
        tokio::time::sleep(Duration::from_millis(backoff_ms)).await;
        backoff_ms = (backoff_ms * 2).min(2000);
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

/// Sends raw bytes as a query on `floorcast/v1/<campaign>/<key_rest>` through `connect` and
/// returns the replies (`Err` for error replies), and puts raw bytes on the same key. For tests
/// and diagnostics: what a foreign or broken program could send.
pub fn raw_exchange(
    connect: &str,
    campaign: &str,
    key_rest: &str,
    body: &[u8],
) -> Result<Vec<Result<Vec<u8>, String>>, NetError> {
    let cfg = NetConfig {
        connect: vec![connect.to_string()],
        campaign: campaign.to_string(),
        ..NetConfig::default()
    };
    let config = zenoh_config(&cfg)?;
    let rt = runtime()?;
    let k = key(campaign, key_rest);
    let out = rt.block_on(async {
        let s = zenoh::open(config)
            .await
            .map_err(|e| NetError::Open(e.to_string()))?;
        s.put(&k, body.to_vec()).await.map_err(zerr)?;
        let replies = s
            .get(&k)
            .payload(body.to_vec())
            .consolidation(ConsolidationMode::None)
            .timeout(Duration::from_secs(5))
            .await
            .map_err(zerr)?;
        let mut out = Vec::new();
        while let Ok(r) = replies.recv_async().await {
            out.push(match r.result() {
                Ok(sample) => Ok(sample.payload().to_bytes().into_owned()),
                Err(e) => Err(String::from_utf8_lossy(&e.payload().to_bytes()).into_owned()),
            });
        }
        let _ = tokio::time::timeout(Duration::from_secs(3), s.close()).await;
        Ok::<_, NetError>(out)
    });
    rt.shutdown_timeout(Duration::from_secs(1));
    out
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::execute::{execute_wire, expected_row};
    use crate::run::{run_plan, RunOptions};
    use crate::store::Store;

    fn plan(dir: &Path, seeds: &str) -> Plan {
        let small = Path::new(env!("CARGO_MANIFEST_DIR")).join("../buildings/small.toml");
        let text = format!(
            "format = \"floorcast-grid\"\nversion = 1\nname = \"net\"\nbuildings = [\"{}\"]\nseeds = {seeds}\n[[strategies]]\nname = \"baseline\"\n[settings]\ntime_limit_s = 30\n",
            small.display()
        );
        Plan::parse(&text, &dir.join("grid.toml"), Some(&dir.join("res"))).unwrap()
    }

    fn endpoint(dir: &Path) -> String {
        format!("unixsock-stream/{}", dir.join("c.sock").display())
    }

    fn net(listen: Vec<String>, connect: Vec<String>) -> NetConfig {
        NetConfig {
            listen,
            connect,
            zenoh_config: None,
            campaign: "test".into(),
        }
    }

    /// Runs the coordinator of `plan` on a thread; returns its log when it finishes.
    fn coordinator(plan: Plan, ep: String) -> std::thread::JoinHandle<(Vec<String>, usize)> {
        std::thread::spawn(move || {
            let store = Store::open(&plan.results_dir).unwrap();
            let opts = RunOptions {
                workers: 0,
                remote: Some(Arc::new(net(vec![ep], vec![]))),
                lease_s: 30.0,
                linger_s: 1.0,
                executor: None,
            };
            let mut log = Vec::new();
            let (_, counts) = run_plan(
                &plan,
                &store,
                &opts,
                &AtomicBool::new(false),
                &mut |_| {},
                &mut |l| log.push(l.to_string()),
            )
            .unwrap();
            (log, counts.done)
        })
    }

    fn worker(ep: &str, name: &str) -> Result<WorkerReport, NetError> {
        run_worker(
            &WorkerOptions {
                net: net(vec![], vec![ep.to_string()]),
                jobs: 1,
                wait_s: 20.0,
                name: Some(name.into()),
            },
            Arc::new(execute_wire),
            Arc::new(|_| {}),
        )
    }

    #[test]
    fn garbage_and_foreign_messages_change_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = plan(dir.path(), "[1, 2]");
        let job0 = p.jobs[0].id.clone();
        let results = p.results_dir.clone();
        let ep = endpoint(dir.path());
        let coord = coordinator(p.clone(), ep.clone());
        // A raw zenoh session throws garbage at every key.
        let rt = runtime().unwrap();
        rt.block_on(async {
            let s = zenoh::open(zenoh_config(&net(vec![], vec![ep.clone()])).unwrap())
                .await
                .unwrap();
            let k = |r: &str| key("test", r);
            // Wait until the coordinator answers at all.
            let mut up = false;
            for _ in 0..100 {
                let r =
                    ask::<NextReply>(&s, &k("ctl/next"), b"junk".to_vec(), Duration::from_secs(2))
                        .await;
                if let Err(e) = r {
                    assert!(e.contains("not a floorcast message"), "{e}");
                    up = true;
                    break;
                }
                tokio::time::sleep(Duration::from_millis(50)).await;
            }
            assert!(up, "coordinator never answered");
            for (key_rest, body) in [
                (
                    "ctl/next".to_string(),
                    br#"{"format":"floorcast-wire","version":7,"kind":"hello"}"#.to_vec(),
                ),
                (format!("ctl/submit/{job0}"), b"\x00\xff\xfe".to_vec()),
                (
                    format!("ctl/submit/{job0}"),
                    encode(&Renewal { worker: "x".into() }),
                ),
                ("ctl/renew/nope".to_string(), b"{}".to_vec()),
                (
                    "ctl/building/nope".to_string(),
                    encode(&BuildingRequest { worker: "x".into() }),
                ),
            ] {
                let r = ask::<SubmitReply>(&s, &k(&key_rest), body, Duration::from_secs(5)).await;
                assert!(r.is_err(), "{key_rest}: {r:?}");
            }
            // A forged result: right key, wrong building hash -> rejected, not stored.
            let mut forged = expected_row(&p, &p.jobs[0], "forger");
            forged.building_hash = "0".repeat(32);
            forged.summary_json = Some("{}".into());
            let r = ask::<SubmitReply>(
                &s,
                &k(&format!("ctl/submit/{job0}")),
                encode(&Submission {
                    worker: "forger".into(),
                    result: forged,
                }),
                Duration::from_secs(5),
            )
            .await;
            assert!(matches!(r, Ok(Some(SubmitReply::Rejected { .. }))), "{r:?}");
            // A worker of another version is refused with a reason.
            let mut hello = Hello::this_build("old", "h");
            hello.floorcast_version = "0.0.1".into();
            let r =
                ask::<NextReply>(&s, &k("ctl/next"), encode(&hello), Duration::from_secs(5)).await;
            assert!(
                matches!(&r, Ok(Some(NextReply::Refused { reason })) if reason.contains("0.0.1")),
                "{r:?}"
            );
            // So is one of this version that computes differently (its bench signature).
            let mut hello = Hello::this_build("odd", "h");
            hello.bench = "0123456789abcdef0123".into();
            let r =
                ask::<NextReply>(&s, &k("ctl/next"), encode(&hello), Duration::from_secs(5)).await;
            assert!(
                matches!(&r, Ok(Some(NextReply::Refused { reason }))
                    if reason.contains("computes differently")
                        && reason.contains("0123456789abcdef…")),
                "{r:?}"
            );
            // Puts on the job keys are not queries: ignored.
            s.put(k("ctl/next"), "garbage").await.unwrap();
            s.put(k(&format!("ctl/submit/{job0}")), "garbage")
                .await
                .unwrap();
            s.close().await.unwrap();
        });
        let report = worker(&ep, "w1").unwrap();
        assert_eq!(report.stored, 2);
        let (log, done) = coord.join().unwrap();
        assert_eq!(done, 2);
        assert!(
            log.iter().any(|l| l.contains("refused worker old")),
            "{log:?}"
        );
        assert!(
            log.iter().any(|l| l.contains("refused worker odd")),
            "{log:?}"
        );
        assert!(log.iter().any(|l| l.contains("rejected result")), "{log:?}");
        let rows = Store::open(&results).unwrap().all().unwrap();
        assert_eq!(rows.len(), 2);
        assert!(rows.iter().all(|r| r.worker == "w1" && r.status == "ok"));
    }

    #[test]
    fn a_worker_without_coordinator_gives_up_with_a_clear_message() {
        let dir = tempfile::tempdir().unwrap();
        let e = run_worker(
            &WorkerOptions {
                net: net(vec![], vec![endpoint(dir.path())]),
                jobs: 1,
                wait_s: 0.5,
                name: None,
            },
            Arc::new(execute_wire),
            Arc::new(|_| {}),
        )
        .unwrap_err();
        assert!(matches!(e, NetError::NoCoordinator { .. }), "{e}");
        assert!(e.to_string().contains("floorcast run GRID --listen"));
    }

    #[test]
    fn bad_options_are_named() {
        let mut n = net(vec!["7447".into()], vec![]);
        assert!(zenoh_config(&n)
            .unwrap_err()
            .to_string()
            .contains("--listen"));
        n.listen.clear();
        n.campaign = "a/b".into();
        assert!(zenoh_config(&n)
            .unwrap_err()
            .to_string()
            .contains("--campaign"));
        n.campaign = "ok".into();
        n.zenoh_config = Some("/nonexistent/z.json5".into());
        assert!(zenoh_config(&n)
            .unwrap_err()
            .to_string()
            .contains("/nonexistent/z.json5"));
    }
}
