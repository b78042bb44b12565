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
//! is decoded and validated ([`floorcast_worker::wire`]); a malformed or foreign one is logged and answered
//! with an error, never trusted. Queries use `ConsolidationMode::None` (the default keeps one
//! reply per key). zenoh needs tokio's multi-thread runtime; simulations run on blocking
//! threads, never on the runtime's workers.
//!
//! [`open_router`] runs a zenoh router (`floorcast router`) for deployments where the
//! coordinator and the workers cannot reach each other directly and no `zenohd` is installed.

use std::path::{Path, PathBuf};
use std::sync::{mpsc, Arc};
use std::time::Duration;

use tokio::sync::oneshot;
use zenoh::query::{ConsolidationMode, Query, QueryTarget};
use zenoh::sample::SampleKind;
use zenoh::Session;

use crate::execute::wire_job;
use crate::grid::Plan;
use crate::inbox::{Answer, Inbox, InboxSender, RemoteSession, RemoteWorkers, LOCAL};
use floorcast_worker::process::Coordinator;
use floorcast_worker::wire::{
    decode, encode, BuildingRequest, Hello, Message, NextReply, RenewReply, Renewal, Submission,
    SubmitReply, WireBuilding,
};

/// Where and how to reach the other side.
#[derive(Debug, Clone, Default)]
pub struct NetConfig {
    /// Endpoints to listen on, e.g. `tcp/0.0.0.0:7447`.
    pub listen: Vec<String>,
    /// Endpoints to connect to (a coordinator, or a router: `floorcast router` or `zenohd`), e.g.
    /// `tcp/host:7447`.
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
    #[error("no coordinator answered on {whereabouts} for {waited_s:.0} s: check that `floorcast run GRID --listen ...` runs there (or the router it connects to), the address, and the credentials/TLS settings of --zenoh-config")]
    NoAnswer { whereabouts: String, waited_s: f64 },
    #[error("zenoh: {0}")]
    Zenoh(String),
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

/// Largest zenoh configuration file read: 1 MiB.
pub const MAX_ZENOH_CONFIG_BYTES: u64 = 1 << 20;

/// Checks a `--zenoh-config` before zenoh reads it: a regular file (not a FIFO, which would
/// block, nor `/dev/zero`, which never ends) of at most [`MAX_ZENOH_CONFIG_BYTES`], named as
/// zenoh's parsers expect (`*.json5`, `*.json`, `*.yaml`, `*.yml`).
pub fn check_config_file(path: &Path) -> Result<(), NetError> {
    let refuse = |message: String| NetError::ConfigFile {
        path: path.to_path_buf(),
        message,
    };
    floorcast_formats::limits::read_bytes(path, MAX_ZENOH_CONFIG_BYTES).map_err(|e| {
        let text = e.to_string();
        let prefix = format!("{}: ", path.display());
        refuse(text.strip_prefix(&prefix).unwrap_or(&text).to_string())
    })?;
    match path.extension().and_then(|x| x.to_str()) {
        Some("json" | "json5" | "yaml" | "yml") => Ok(()),
        _ => Err(refuse(
            "expected a zenoh configuration file named *.json5, *.json, *.yaml or *.yml".into(),
        )),
    }
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
            check_config_file(path)?;
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
        // (Only embedded workers are given jobs to run together; should a remote one be, it
        // runs the first and the others' leases run out and they are handed out again.)
        Answer::RunShared(jobs) => match jobs.first() {
            Some(job) => NextReply::Job {
                job: Box::new(wire_job(&ctx.plan, job)),
                lease_s: ctx.lease_s,
            },
            None => NextReply::Wait { retry_ms: 200 },
        },
        Answer::Wait => NextReply::Wait { retry_ms: 200 },
        Answer::Done => NextReply::Done,
        Answer::Refused(reason) => NextReply::Refused { reason },
    };
    reply(&q, &msg).await;
}

async fn on_submit(ctx: Arc<Ctx>, q: Query) {
    let job = last_chunk(q.key_expr().as_str()).to_string();
    let sub = match decode::<Submission>(&payload(&q)) {
        Ok(s) => s,
        Err(e) => return refuse(&ctx, &q, "not a result", e.to_string()).await,
    };
    if sub.job_id != job {
        let why = format!(
            "result of job {} submitted on the key of job {job}",
            sub.job_id
        );
        return refuse(&ctx, &q, "mismatched result", why).await;
    }
    let (tx, rx) = oneshot::channel();
    let sent = ctx.inbox.send(Inbox::Submit {
        worker: sub.worker,
        job_id: sub.job_id,
        report: Box::new(sub.report),
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
// Worker side: the link the worker process (`floorcast_worker::process`) asks through.

/// A worker's link to its coordinator over zenoh: joined with [`join`], left with
/// [`ZenohLink::leave`]. Its liveliness token announces the worker (the coordinator requeues the
/// jobs of a worker whose token disappears).
pub struct ZenohLink {
    rt: tokio::runtime::Runtime,
    session: Session,
    token: zenoh::liveliness::LivelinessToken,
    campaign: String,
    worker: String,
    endpoints: String,
}

impl std::fmt::Debug for ZenohLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ZenohLink")
            .field("campaign", &self.campaign)
            .field("worker", &self.worker)
            .field("endpoints", &self.endpoints)
            .finish_non_exhaustive()
    }
}

/// Opens a zenoh session as worker `name` (default: host, process id and zenoh id) and
/// announces it. The worker is a zenoh client, whatever mode its configuration file names: a
/// router routes between clients, but expects the peers that reach it to reach each other too
/// (zenoh 1.10's regions), which workers behind NAT or in other subnets cannot. A client's
/// session opens only once it reaches its coordinator or router, so `join` tries again every
/// second, for up to `wait_s` seconds (0: forever), while nothing answers.
pub fn join(cfg: &NetConfig, name: Option<&str>, wait_s: f64) -> Result<ZenohLink, NetError> {
    if let Some(n) = name {
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
    let mut config = zenoh_config(cfg)?;
    config.insert_json5("mode", "\"client\"").map_err(zerr)?;
    let rt = runtime()?;
    let joined = rt.block_on(async {
        let session = open_client(config, cfg, wait_s).await?;
        let worker = name.map(str::to_string).unwrap_or_else(|| {
            let zid = session.zid().to_string();
            let host: String = crate::store::host_name()
                .chars()
                .filter(|c| c.is_ascii_alphanumeric() || *c == '-')
                .take(32)
                .collect();
            format!("{host}-{}-{}", std::process::id(), &zid[..zid.len().min(8)])
        });
        let token = session
            .liveliness()
            .declare_token(key(&cfg.campaign, &format!("workers/{worker}")))
            .await
            .map_err(zerr)?;
        Ok::<_, NetError>((session, token, worker))
    });
    let (session, token, worker) = match joined {
        Ok(j) => j,
        Err(e) => {
            rt.shutdown_timeout(Duration::from_secs(1));
            return Err(e);
        }
    };
    Ok(ZenohLink {
        rt,
        session,
        token,
        campaign: cfg.campaign.clone(),
        worker,
        endpoints: cfg.connect.join(", "),
    })
}

/// Opens a client session, trying again every second while its endpoints do not answer (for up
/// to `wait_s` seconds; 0: forever).
async fn open_client(
    config: zenoh::Config,
    cfg: &NetConfig,
    wait_s: f64,
) -> Result<Session, NetError> {
    let t0 = std::time::Instant::now();
    loop {
        match zenoh::open(config.clone()).await {
            Ok(session) => return Ok(session),
            // (What zenoh says when none of a client's endpoints could be reached.)
            Err(e) if e.to_string().contains("Unable to connect") => {
                let waited_s = t0.elapsed().as_secs_f64();
                if wait_s > 0.0 && waited_s > wait_s {
                    return Err(NetError::NoAnswer {
                        whereabouts: whereabouts(&cfg.connect.join(", "), &cfg.campaign),
                        waited_s,
                    });
                }
                tokio::time::sleep(Duration::from_secs(1)).await;
            }
            Err(e) => return Err(NetError::Open(e.to_string())),
        }
    }
}

/// Where a worker looks for its coordinator, for messages.
fn whereabouts(endpoints: &str, campaign: &str) -> String {
    let endpoints = if endpoints.is_empty() {
        "the configured endpoints"
    } else {
        endpoints
    };
    format!("{endpoints} (campaign '{campaign}')")
}

impl ZenohLink {
    /// Withdraws the worker's token and closes the session.
    pub fn leave(self) {
        let ZenohLink {
            rt, session, token, ..
        } = self;
        rt.block_on(async {
            drop(token);
            let _ = tokio::time::timeout(Duration::from_secs(3), session.close()).await;
        });
        rt.shutdown_timeout(Duration::from_secs(1));
    }

    fn request<T: Message>(
        &self,
        key_rest: &str,
        body: Vec<u8>,
        timeout: Duration,
    ) -> Result<Option<T>, String> {
        let k = key(&self.campaign, key_rest);
        self.rt.block_on(ask::<T>(&self.session, &k, body, timeout))
    }
}

impl Coordinator for ZenohLink {
    fn worker(&self) -> &str {
        &self.worker
    }

    fn whereabouts(&self) -> String {
        whereabouts(&self.endpoints, &self.campaign)
    }

    fn next(&self, hello: &Hello) -> Result<Option<NextReply>, String> {
        self.request("ctl/next", encode(hello), Duration::from_secs(10))
    }

    fn building(
        &self,
        hash: &str,
        request: &BuildingRequest,
    ) -> Result<Option<WireBuilding>, String> {
        self.request(
            &format!("ctl/building/{hash}"),
            encode(request),
            Duration::from_secs(30),
        )
    }

    fn renew(&self, job_id: &str, renewal: &Renewal) -> Result<Option<RenewReply>, String> {
        self.request(
            &format!("ctl/renew/{job_id}"),
            encode(renewal),
            Duration::from_secs(5),
        )
    }

    fn submit(&self, job_id: &str, submission: &Submission) -> Result<Option<SubmitReply>, String> {
        self.request(
            &format!("ctl/submit/{job_id}"),
            encode(submission),
            Duration::from_secs(30),
        )
    }
}

// ------------------------------------------------------------------------------------------
// Router: `floorcast router`, for deployments without `zenohd`.

/// A zenoh session in router mode (what `zenohd` runs, without its plugins): a coordinator and
/// workers that cannot reach each other directly all connect to it, and it routes their queries
/// and liveliness tokens. It serves every campaign. Closed with [`Router::close`].
pub struct Router {
    rt: tokio::runtime::Runtime,
    session: Session,
    listening: Vec<String>,
}

impl std::fmt::Debug for Router {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Router")
            .field("listening", &self.listening)
            .finish_non_exhaustive()
    }
}

/// Opens a router listening on `cfg.listen` and on the endpoints of `cfg.zenoh_config` (whose
/// TLS, authentication and access control apply; its `mode` is overridden: this is a router).
/// Its `connect` endpoints (other routers) are joined too. `cfg.campaign` plays no part.
pub fn open_router(cfg: &NetConfig) -> Result<Router, NetError> {
    let mut config = zenoh_config(cfg)?;
    config.insert_json5("mode", "\"router\"").map_err(zerr)?;
    let listening = router_endpoints(&config)?;
    if listening.is_empty() {
        return Err(NetError::Option {
            what: "--listen".into(),
            message: "a router needs an endpoint to listen on: give e.g. --listen tcp/0.0.0.0:7447, or a --zenoh-config that lists one".into(),
        });
    }
    let rt = runtime()?;
    match rt.block_on(async { zenoh::open(config).await }) {
        Ok(session) => Ok(Router {
            rt,
            session,
            listening,
        }),
        Err(e) => {
            rt.shutdown_timeout(Duration::from_secs(1));
            Err(NetError::Open(e.to_string()))
        }
    }
}

/// The endpoints a router listens on: `listen/endpoints` of its configuration, a list or, mode
/// by mode, the router's.
fn router_endpoints(config: &zenoh::Config) -> Result<Vec<String>, NetError> {
    let json = config.get_json("listen/endpoints").map_err(zerr)?;
    let value: serde_json::Value = serde_json::from_str(&json).map_err(zerr)?;
    let list = match value {
        serde_json::Value::Object(mut by_mode) => by_mode.remove("router").unwrap_or_default(),
        v => v,
    };
    Ok(list
        .as_array()
        .map(|l| {
            l.iter()
                .filter_map(|e| e.as_str().map(str::to_string))
                .collect()
        })
        .unwrap_or_default())
}

impl Router {
    /// The endpoints it listens on.
    pub fn listening(&self) -> &[String] {
        &self.listening
    }

    /// Its zenoh id (as other nodes' logs name it).
    pub fn id(&self) -> String {
        self.session.zid().to_string()
    }

    /// Closes the session: connected nodes see it leave.
    pub fn close(self) {
        let Router { rt, session, .. } = self;
        rt.block_on(async {
            let _ = tokio::time::timeout(Duration::from_secs(3), session.close()).await;
        });
        rt.shutdown_timeout(Duration::from_secs(1));
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

/// Sends raw bytes as a query on `floorcast/v1/<campaign>/<key_rest>` through `connect` and
/// returns the replies (`Err` for error replies), and puts raw bytes on the same key. For tests
/// (test support): what a foreign or broken program could send.
#[cfg(any(test, feature = "test-support"))]
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

    use std::sync::atomic::AtomicBool;

    use super::*;
    use crate::execute::{execute, row};
    use crate::run::{run_plan, Counts, RunError, RunOptions};
    use crate::store::Store;
    use floorcast_worker::execute::execute_wire;
    use floorcast_worker::process::{run_worker, WorkerError, WorkerOptions, WorkerReport};
    use floorcast_worker::wire::{JobOutcome, WireJob};

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

    /// Runs the coordinator of `plan` on a thread (checking each remote worker's first result
    /// and `verify_fraction` of the others); returns its log and counts when it finishes.
    fn coordinator(
        plan: Plan,
        ep: String,
        verify_fraction: f64,
    ) -> std::thread::JoinHandle<(Vec<String>, Counts)> {
        std::thread::spawn(move || {
            let store = Store::open(&plan.results_dir).unwrap();
            let opts = RunOptions {
                workers: 0,
                remote: Some(Arc::new(net(vec![ep], vec![]))),
                lease_s: 30.0,
                linger_s: 1.0,
                executor: None,
                verify_fraction,
                share: true,
                retry_failed: false,
                live: None,
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
            (log, counts)
        })
    }

    fn worker(ep: &str, name: Option<&str>, wait_s: f64) -> Result<WorkerReport, WorkerError> {
        let link = join(&net(vec![], vec![ep.to_string()]), name, wait_s).unwrap();
        let report = run_worker(
            &link,
            "host",
            WorkerOptions { jobs: 1, wait_s },
            &execute_wire,
            &|_| {},
        );
        link.leave();
        report
    }

    #[test]
    #[allow(clippy::too_many_lines)] // a table of cases
    fn garbage_and_foreign_messages_change_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = plan(dir.path(), "[1, 2]");
        let job0 = p.jobs[0].id.clone();
        let results = p.results_dir.clone();
        let ep = endpoint(dir.path());
        let coord = coordinator(p.clone(), ep.clone(), 0.0);
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
            let mut forged = execute(&p, &p.jobs[0]);
            if let JobOutcome::Ok { summary, .. } = &mut forged.outcome {
                summary.building_hash = "0".repeat(32);
            }
            let r = ask::<SubmitReply>(
                &s,
                &k(&format!("ctl/submit/{job0}")),
                encode(&Submission {
                    worker: "forger".into(),
                    job_id: job0.clone(),
                    report: forged,
                }),
                Duration::from_secs(5),
            )
            .await;
            assert!(
                matches!(&r, Ok(Some(SubmitReply::Rejected { reason })) if reason.contains("building_hash")),
                "{r:?}"
            );
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
        let report = worker(&ep, Some("w1"), 20.0).unwrap();
        assert_eq!(report.stored, 2);
        let (log, counts) = coord.join().unwrap();
        assert_eq!(counts.done, 2);
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
        assert!(rows.iter().all(|r| r.worker == "w1" && r.status.is_ok()));
    }

    /// A worker whose results differ from the coordinator's re-run (here: one that adds a
    /// thousandth to the explored fraction) is caught by the check of its first result: it is
    /// refused, every result it returned is discarded, and an honest worker (whose first result
    /// is checked too) runs those jobs again to the rows a local run gives.
    #[test]
    fn a_worker_that_alters_its_results_is_caught_and_its_jobs_run_again() {
        let dir = tempfile::tempdir().unwrap();
        let p = plan(dir.path(), "[1, 2, 3]");
        let ep = endpoint(dir.path());
        // Each worker's first result checked, hardly any other.
        let coord = coordinator(p.clone(), ep.clone(), 1e-9);
        let tampered = |job: &WireJob, b: &sim_core::Building| {
            let mut r = execute_wire(job, b);
            if let JobOutcome::Ok { summary, .. } = &mut r.outcome {
                summary.explored_fraction += 1e-3;
            }
            r
        };
        let link = join(&net(vec![], vec![ep.clone()]), Some("forger"), 20.0).unwrap();
        let e = run_worker(
            &link,
            "host",
            WorkerOptions {
                jobs: 1,
                wait_s: 20.0,
            },
            &tampered,
            &|_| {},
        )
        .unwrap_err();
        link.leave();
        assert!(
            matches!(&e, WorkerError::Refused(r) if r.contains("differed from the coordinator's re-run")),
            "{e}"
        );
        worker(&ep, Some("honest"), 20.0).unwrap();
        let (log, counts) = coord.join().unwrap();
        assert_eq!((counts.done, counts.quarantined), (3, 1), "{log:?}");
        assert!(counts.verified >= 2, "{counts:?}");
        assert!(
            log.iter()
                .any(|l| l.contains("worker forger computes differently")
                    && l.contains("summary field explored_fraction")),
            "{log:?}"
        );
        let rows = Store::open(&p.results_dir).unwrap().all().unwrap();
        assert_eq!(rows.len(), 3);
        for r in &rows {
            assert_ne!(r.worker, "forger");
            let job = p.jobs.iter().find(|j| j.id == r.job_id).unwrap();
            let local = row(&p, job, "here", &execute(&p, job));
            assert_eq!(crate::verify::compare(r, &local), Ok(()), "{}", r.job_id);
        }
    }

    #[test]
    fn a_worker_without_coordinator_gives_up_with_a_clear_message() {
        let dir = tempfile::tempdir().unwrap();
        let ep = endpoint(dir.path());
        let e = join(&net(vec![], vec![ep.clone()]), None, 1.5).unwrap_err();
        assert!(matches!(e, NetError::NoAnswer { .. }), "{e}");
        assert!(e.to_string().contains("floorcast run GRID --listen"));
        assert!(
            e.to_string().contains(&format!("{ep} (campaign 'test')")),
            "{e}"
        );
    }

    /// A worker started before its coordinator waits for it (its client session opens once
    /// the coordinator's endpoint answers).
    #[test]
    fn a_worker_started_first_waits_for_its_coordinator() {
        let dir = tempfile::tempdir().unwrap();
        let p = plan(dir.path(), "[1]");
        let ep = endpoint(dir.path());
        let early = std::thread::spawn({
            let ep = ep.clone();
            move || worker(&ep, Some("early"), 30.0)
        });
        std::thread::sleep(Duration::from_secs(2));
        let (_, counts) = coordinator(p, ep, 0.0).join().unwrap();
        assert_eq!(counts.done, 1);
        assert_eq!(early.join().unwrap().unwrap().stored, 1);
    }

    /// The thread that checks remote workers' results refused by the system: `run` is an error
    /// saying what to do (fewer workers, or no checks), not a panic.
    #[test]
    fn a_refused_checker_thread_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = plan(dir.path(), "[1]");
        let store = Store::open(&p.results_dir).unwrap();
        let opts = RunOptions {
            workers: 0,
            remote: Some(Arc::new(net(vec![endpoint(dir.path())], vec![]))),
            lease_s: 30.0,
            linger_s: 0.0,
            executor: None,
            verify_fraction: 0.5,
            share: true,
            retry_failed: false,
            live: None,
        };
        floorcast_worker::refuse_threads_after(Some(0));
        let r = crate::run::tests::run_quietly(&p, &store, &opts);
        floorcast_worker::refuse_threads_after(None);
        let e = r.expect_err("an error");
        assert!(
            matches!(e, RunError::VerifierSpawn(_))
                && e.to_string().contains("--verify-fraction 0"),
            "{e}"
        );
    }

    /// A coordinator and a worker that both connect to a router (neither listens) complete a
    /// grid through it.
    #[test]
    fn a_grid_runs_through_a_router() {
        let dir = tempfile::tempdir().unwrap();
        let p = plan(dir.path(), "[1, 2]");
        let ep = endpoint(dir.path());
        let router = open_router(&net(vec![ep.clone()], vec![])).unwrap();
        assert_eq!(router.listening(), std::slice::from_ref(&ep));
        let coord = std::thread::spawn({
            let p = p.clone();
            let ep = ep.clone();
            move || {
                let store = Store::open(&p.results_dir).unwrap();
                let opts = RunOptions {
                    workers: 0,
                    remote: Some(Arc::new(net(vec![], vec![ep]))),
                    lease_s: 30.0,
                    linger_s: 1.0,
                    executor: None,
                    verify_fraction: 0.0,
                    share: true,
                    retry_failed: false,
                    live: None,
                };
                crate::run::tests::run_quietly(&p, &store, &opts).unwrap()
            }
        });
        let report = worker(&ep, Some("w1"), 20.0).unwrap();
        assert_eq!(report.stored, 2);
        coord.join().unwrap();
        router.close();
        let rows = Store::open(&p.results_dir).unwrap().all().unwrap();
        assert_eq!(rows.len(), 2);
        assert!(rows.iter().all(|r| r.worker == "w1" && r.status.is_ok()));
    }

    #[test]
    fn a_router_needs_an_endpoint() {
        let e = open_router(&net(vec![], vec![])).unwrap_err();
        assert!(e.to_string().contains("--listen tcp/0.0.0.0:7447"), "{e}");
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
