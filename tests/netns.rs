//! Multi-host tests (issue 60): the coordinator, the workers and a router each in a Linux network
//! namespace of its own, with an address of its own (10.213.T.x/24, T per test), all joined by
//! veth links to a bridge in a "hub" namespace, as machines on a switch. floorcast runs in them
//! with `ip netns exec NS floorcast ...` (which execs: the child's pid is floorcast's, so a kill
//! is a real `kill -9`). Nothing is sent outside the namespaces these tests make.
//!
//! Links are impaired without `tc netem` (the kernels of this project's machines are built
//! without it): a partition drops every packet of a host's link with nftables (as netem's loss
//! 100 % would, silently: no error reaches either side), packet loss drops a random 5 % of them
//! each way with nftables' `numgen random`, and delay is a relay in the worker's namespace that
//! forwards each direction of the TCP stream 150 ms ± 50 ms late (order kept).
//!
//! Rights: these tests need root (CAP_NET_ADMIN) for `ip netns add`, iproute2 (`ip`), nftables
//! (`nft`) and openssl. They are system tests, built only with the `system-tests` feature:
//! `.ci/system-tests` (which CI runs, as root) installs what they need and runs them; without the
//! rights each test fails with a message saying so. The namespaces are
//! named after the test process's id and removed, with the processes started in them, when a
//! test ends (pass or fail); tests take turns (one lock), so that each has the machine's cores.

mod common;

use std::io::{Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use common::repo;

/// The port everything listens on (each namespace has its own ports).
const PORT: u16 = 7447;
/// Summary fields that are measured, not computed: they differ between runs of one job.
const MEASURED: [&str; 3] = ["wall_time_s", "speedup", "strategy_compute_s"];

// ------------------------------------------------------------------------------------------
// Namespaces

/// The namespaces of one test: a hub with a bridge and one namespace per host, each with an
/// `eth0` on the bridge. Dropping it removes them all.
struct Lab {
    /// Prefix of every namespace's name: `fc<pid><test letter>`.
    tag: String,
    /// Third byte of the test's addresses (10.213.T.x).
    subnet: u8,
    hosts: Vec<String>,
    _turn: MutexGuard<'static, ()>,
}

/// Tests take turns: each has the machine's cores, so its timing is what it plans.
static TURN: Mutex<()> = Mutex::new(());

fn ip(args: &[&str]) -> Result<(), String> {
    match Command::new("ip").args(args).output() {
        Ok(o) if o.status.success() => Ok(()),
        Ok(o) => Err(format!(
            "`ip {}`: {}",
            args.join(" "),
            String::from_utf8_lossy(&o.stderr).trim()
        )),
        Err(e) => Err(format!("`ip {}`: {e}", args.join(" "))),
    }
}

fn must(r: Result<(), String>) {
    if let Err(e) = r {
        panic!("{e}");
    }
}

impl Lab {
    /// Makes the hub and `hosts` (each gets 10.213.`subnet`.(i+1)). Without the rights to make a
    /// namespace it panics with what to do.
    fn new(test: char, subnet: u8, hosts: &[&str]) -> Lab {
        let turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
        remove_stale_namespaces();
        let tag = format!("fc{}{test}", std::process::id());
        let hub = format!("{tag}-hub");
        if let Err(e) = ip(&["netns", "add", &hub]) {
            panic!(
                "these multi-host tests make Linux network namespaces and could not ({e}). They \
                 need root (or CAP_NET_ADMIN) and iproute2 (`ip`; Debian/Ubuntu: apt-get install \
                 iproute2), plus nftables (`nft`) and openssl: run them as root with \
                 `sudo -E bash .ci/system-tests`, which installs what they need."
            );
        }
        let mut lab = Lab {
            tag,
            subnet,
            hosts: Vec::new(),
            _turn: turn,
        };
        must(ip(&["-n", &hub, "link", "add", "br0", "type", "bridge"]));
        must(ip(&["-n", &hub, "link", "set", "br0", "up"]));
        for h in hosts {
            lab.add_host(h);
        }
        lab
    }

    fn ns(&self, host: &str) -> String {
        format!("{}-{host}", self.tag)
    }

    fn add_host(&mut self, host: &str) {
        let (ns, hub) = (self.ns(host), self.ns("hub"));
        must(ip(&["netns", "add", &ns]));
        self.hosts.push(host.to_string());
        let addr = format!("{}/24", self.addr(host));
        let port = format!("v-{host}");
        for args in [
            &[
                "link", "add", "eth0", "netns", &ns, "type", "veth", "peer", "name", &port,
                "netns", &hub,
            ][..],
            &["-n", &hub, "link", "set", &port, "master", "br0", "up"],
            &["-n", &ns, "addr", "add", &addr, "dev", "eth0"],
            &["-n", &ns, "link", "set", "eth0", "up"],
            &["-n", &ns, "link", "set", "lo", "up"],
        ] {
            must(ip(args));
        }
    }

    /// The host's address.
    fn addr(&self, host: &str) -> String {
        let i = self.hosts.iter().position(|h| h == host).expect("a host") + 1;
        format!("10.213.{}.{i}", self.subnet)
    }

    fn endpoint(&self, proto: &str, host: &str) -> String {
        format!("{proto}/{}:{PORT}", self.addr(host))
    }

    /// Loads an nftables ruleset into the host's namespace.
    fn nft(&self, host: &str, ruleset: &str) {
        let mut child = Command::new("ip")
            .args(["netns", "exec", &self.ns(host), "nft", "-f", "-"])
            .stdin(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        child
            .stdin
            .take()
            .unwrap()
            .write_all(ruleset.as_bytes())
            .unwrap();
        let o = child.wait_with_output().unwrap();
        assert!(
            o.status.success(),
            "nft in {host} (nftables installed? Debian/Ubuntu: apt-get install nftables): {}\n{ruleset}",
            String::from_utf8_lossy(&o.stderr)
        );
    }

    /// Drops every packet of the host's link, both ways (a partition), until [`Lab::heal`].
    fn partition(&self, host: &str) {
        self.nft(host, &drop_rules("partition", ""));
    }

    fn heal(&self, host: &str) {
        self.nft(host, "delete table inet partition\n");
    }

    /// Drops `percent` % of the packets of the host's link each way, at random.
    fn lose(&self, host: &str, percent: u32) {
        self.nft(
            host,
            &drop_rules("loss", &format!("numgen random mod 100 < {percent}")),
        );
    }
}

/// An nftables table that drops the packets of `eth0` (both ways) that match `condition`.
fn drop_rules(table: &str, condition: &str) -> String {
    format!(
        "table inet {table} {{\n\
         chain in {{ type filter hook input priority 0; iifname \"eth0\" {condition} drop; }}\n\
         chain out {{ type filter hook output priority 0; oifname \"eth0\" {condition} drop; }}\n\
         }}\n"
    )
}

impl Drop for Lab {
    fn drop(&mut self) {
        for h in self
            .hosts
            .iter()
            .map(|h| self.ns(h))
            .chain([self.ns("hub")])
        {
            let _ = ip(&["netns", "del", &h]);
        }
    }
}

/// Removes the namespaces of earlier runs of these tests whose process is gone (killed before
/// it could remove them).
fn remove_stale_namespaces() {
    let Ok(o) = Command::new("ip").args(["netns", "list"]).output() else {
        return;
    };
    for line in String::from_utf8_lossy(&o.stdout).lines() {
        let name = line.split_whitespace().next().unwrap_or("");
        let Some(rest) = name.strip_prefix("fc") else {
            continue;
        };
        let pid: String = rest.chars().take_while(char::is_ascii_digit).collect();
        let after = &rest[pid.len()..];
        let ours = after.len() > 2 && after.as_bytes()[1] == b'-';
        if !pid.is_empty() && ours && !Path::new(&format!("/proc/{pid}")).exists() {
            let _ = ip(&["netns", "del", name]);
        }
    }
}

// ------------------------------------------------------------------------------------------
// Processes

/// A floorcast process in a namespace, its stdout and stderr lines collected; killed when
/// dropped.
struct Node {
    name: String,
    child: Child,
    lines: mpsc::Receiver<String>,
    seen: Vec<String>,
}

impl Node {
    fn start(lab: &Lab, host: &str, name: &str, args: &[&str]) -> Node {
        let (child, rx) = common::spawn_lines(
            Command::new("ip")
                .args([
                    "netns",
                    "exec",
                    &lab.ns(host),
                    env!("CARGO_BIN_EXE_floorcast"),
                ])
                .args(args),
        );
        Node {
            name: name.to_string(),
            child,
            lines: rx,
            seen: Vec::new(),
        }
    }

    fn drain(&mut self) {
        while let Ok(l) = self.lines.try_recv() {
            self.seen.push(l);
        }
    }

    /// Lines printed so far that contain `needle`.
    fn count(&mut self, needle: &str) -> usize {
        self.drain();
        self.seen.iter().filter(|l| l.contains(needle)).count()
    }

    fn log(&mut self) -> String {
        self.drain();
        format!("--- {}:\n{}", self.name, self.seen.join("\n"))
    }

    /// Waits for the exit; returns success and everything printed.
    fn finish(&mut self, timeout: Duration) -> (bool, String) {
        let t0 = Instant::now();
        loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                std::thread::sleep(Duration::from_millis(200));
                return (status.success(), self.log());
            }
            if t0.elapsed() > timeout {
                panic!("did not exit within {timeout:?}: {}", self.log());
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    fn kill9(&mut self) {
        self.child.kill().unwrap(); // SIGKILL
        let _ = self.child.wait();
    }
}

impl Drop for Node {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Waits until `done` holds (polled every 50 ms), failing the test with `what` and the nodes'
/// logs after `timeout`.
fn wait(
    timeout: Duration,
    what: &str,
    nodes: &mut [&mut Node],
    done: impl Fn(&mut [&mut Node]) -> bool,
) {
    let t0 = Instant::now();
    while !done(nodes) {
        if t0.elapsed() > timeout {
            let logs: Vec<String> = nodes.iter_mut().map(|n| n.log()).collect();
            panic!("{what}: not after {timeout:?}\n{}", logs.join("\n"));
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Results the workers had acknowledged as stored (their "..., stored" lines).
fn acknowledged(workers: &mut [&mut Node]) -> usize {
    workers.iter_mut().map(|w| w.count(", stored")).sum()
}

// ------------------------------------------------------------------------------------------
// A relay that delays

/// Enters the network namespace `ns` (this thread only; threads it starts inherit it).
fn enter_namespace(ns: &str) {
    let f = std::fs::File::open(format!("/run/netns/{ns}")).unwrap();
    nix::sched::setns(&f, nix::sched::CloneFlags::CLONE_NEWNET).unwrap();
}

/// A TCP relay in a namespace: forwards each connection to `upstream`, each direction
/// `delay_ms` ± `jitter_ms` late (uniform; order kept). Stopped when dropped.
struct DelayRelay {
    stop: Arc<AtomicBool>,
    streams: Arc<Mutex<Vec<TcpStream>>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl DelayRelay {
    fn start(
        ns: String,
        listen: SocketAddr,
        upstream: SocketAddr,
        delay_ms: f64,
        jitter_ms: f64,
    ) -> DelayRelay {
        let stop = Arc::new(AtomicBool::new(false));
        let streams = Arc::new(Mutex::new(Vec::<TcpStream>::new()));
        let (ready, started) = mpsc::channel();
        let (s, all) = (Arc::clone(&stop), Arc::clone(&streams));
        let thread = std::thread::spawn(move || {
            enter_namespace(&ns);
            let listener = TcpListener::bind(listen).unwrap();
            listener.set_nonblocking(true).unwrap();
            ready.send(()).unwrap();
            while !s.load(Ordering::SeqCst) {
                let down = match listener.accept() {
                    Ok((down, _)) => down,
                    Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                        std::thread::sleep(Duration::from_millis(20));
                        continue;
                    }
                    Err(e) => panic!("relay in {ns}: {e}"),
                };
                // (Nobody upstream, as while the coordinator restarts: the connection closes.)
                let Ok(up) = TcpStream::connect_timeout(&upstream, Duration::from_secs(5)) else {
                    continue;
                };
                down.set_nonblocking(false).unwrap();
                let mut list = all.lock().unwrap();
                list.extend([down.try_clone().unwrap(), up.try_clone().unwrap()]);
                for (from, to) in [
                    (down.try_clone().unwrap(), up.try_clone().unwrap()),
                    (up, down),
                ] {
                    std::thread::spawn(move || late_copy(from, to, delay_ms, jitter_ms));
                }
            }
        });
        started
            .recv_timeout(Duration::from_secs(10))
            .expect("the relay listens");
        DelayRelay {
            stop,
            streams,
            thread: Some(thread),
        }
    }
}

/// Copies `from` to `to`, each chunk `delay_ms` ± `jitter_ms` after it was read, never before
/// the one read before it; then closes both.
fn late_copy(mut from: TcpStream, to: TcpStream, delay_ms: f64, jitter_ms: f64) {
    use rand::Rng;
    let (tx, rx) = mpsc::channel::<(Instant, Vec<u8>)>();
    let mut out = to.try_clone().unwrap();
    let writer = std::thread::spawn(move || {
        for (due, bytes) in rx {
            std::thread::sleep(due.saturating_duration_since(Instant::now()));
            if out.write_all(&bytes).is_err() {
                break;
            }
        }
        let _ = out.shutdown(Shutdown::Both);
    });
    let mut rng = rand::rng();
    let mut last = Instant::now();
    let mut buf = vec![0u8; 1 << 16];
    while let Ok(n @ 1..) = from.read(&mut buf) {
        let ms = delay_ms + rng.random_range(-jitter_ms..=jitter_ms);
        last = last.max(Instant::now() + Duration::from_secs_f64(ms / 1000.0));
        if tx.send((last, buf[..n].to_vec())).is_err() {
            break;
        }
    }
    drop(tx);
    let _ = writer.join();
    let _ = from.shutdown(Shutdown::Both);
    let _ = to.shutdown(Shutdown::Both);
}

impl Drop for DelayRelay {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        for s in self.streams.lock().unwrap().iter() {
            let _ = s.shutdown(Shutdown::Both);
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

// ------------------------------------------------------------------------------------------
// Grids and their stores

/// A grid of `jobs` seeds of `building` (under buildings/) with the baseline strategy, each
/// run for at most `time_limit_s` simulated seconds.
fn grid(dir: &Path, name: &str, building: &str, jobs: usize, time_limit_s: u32) -> PathBuf {
    let b = repo().join("buildings").join(building);
    let text = format!(
        "format = \"floorcast-grid\"\nversion = 1\nname = \"{name}\"\nbuildings = [\"{}\"]\nseed_range = [1, {jobs}]\n[[strategies]]\nname = \"baseline\"\n[settings]\ntime_limit_s = {time_limit_s}\n",
        b.display()
    );
    let p = dir.join("grid.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// One stored row: its job, who ran it, and what must be identical wherever it ran (the
/// job's identity, status, error, progress curve and summary, measured times aside).
#[derive(Debug)]
struct Row {
    job_id: String,
    worker: String,
    computed: Vec<String>,
}

/// Every row of the results store in `res` (none without a store).
fn rows(res: &Path) -> Vec<Row> {
    let db = res.join("results.sqlite");
    if !db.exists() {
        return Vec::new();
    }
    let conn = rusqlite::Connection::open(db).unwrap();
    let mut q = conn
        .prepare(
            "SELECT job_id, worker, grid, building, building_hash, strategy, label, seed, \
             settings_json, status, coalesce(error, ''), coalesce(summary_json, ''), \
             coalesce(progress_csv, ''), floorcast_version FROM results ORDER BY job_id",
        )
        .unwrap();
    q.query_map([], |r| {
        let mut computed = Vec::new();
        for i in 2..14 {
            computed.push(match r.get_ref(i)? {
                rusqlite::types::ValueRef::Integer(n) => n.to_string(),
                _ => r.get::<_, String>(i)?,
            });
        }
        // The summary without its measured fields (a failed job has none).
        if !computed[9].is_empty() {
            let mut summary: serde_json::Value = serde_json::from_str(&computed[9]).unwrap();
            for k in MEASURED {
                summary.as_object_mut().unwrap().remove(k);
            }
            computed[9] = summary.to_string();
        }
        Ok(Row {
            job_id: r.get(0)?,
            worker: r.get(1)?,
            computed,
        })
    })
    .unwrap()
    .map(Result::unwrap)
    .collect()
}

/// Asserts one row per job of the grid (`jobs` of them) in `res`, each identical to the row of
/// the same grid run here without a network (into `local`); returns the rows.
fn assert_same_as_local(g: &Path, res: &Path, local: &Path, jobs: usize) -> Vec<Row> {
    let got = rows(res);
    let mut ids: Vec<&str> = got.iter().map(|r| r.job_id.as_str()).collect();
    ids.dedup();
    assert_eq!(got.len(), jobs, "{got:?}");
    assert_eq!(ids.len(), jobs, "a job stored twice: {ids:?}");
    let o = common::run(&[
        "run",
        g.to_str().unwrap(),
        "--results",
        local.to_str().unwrap(),
        "-q",
        "--no-tours",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let want = rows(local);
    assert_eq!(want.len(), jobs);
    for (a, b) in got.iter().zip(&want) {
        assert_eq!(a.job_id, b.job_id);
        assert_eq!(
            a.computed, b.computed,
            "job {} run by {} differs from the local run",
            a.job_id, a.worker
        );
    }
    got
}

fn worker_args<'a>(connect: &'a str, name: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut a = vec![
        "worker",
        "--connect",
        connect,
        "--jobs",
        "1",
        "--name",
        name,
    ];
    a.extend_from_slice(extra);
    a
}

fn say_wall_time(test: &str, t0: Instant) {
    eprintln!("{test}: {:.0} s", t0.elapsed().as_secs_f64());
}

// ------------------------------------------------------------------------------------------
// 1. A partition and a coordinator restart, on a lossy, slow network

/// Jobs of the partition test (1.5 to 4 s each on one core): enough that the grid is still
/// running when the partition heals (w2 alone stores about 15 in the 30 s) and the coordinator
/// is killed.
const PARTITION_JOBS: usize = 32;
/// How long the partition lasts.
const PARTITION: Duration = Duration::from_secs(30);

/// Three hosts: coordinator `c`, worker `w1` on a clean link, worker `w2` on a link that loses
/// 5 % of its packets each way and delays each direction 150 ± 50 ms. Mid-grid, `w1` is cut off
/// for 30 s (every packet dropped) and comes back; then the coordinator is killed with SIGKILL
/// and started again with the same command. The store ends with one row per job, each
/// identical to the row of the same grid run locally.
#[test]
fn a_partition_and_a_coordinator_restart_on_a_lossy_network_change_no_result() {
    let lab = Lab::new('p', 1, &["c", "w1", "w2"]);
    let t0 = Instant::now();
    let dir = tempfile::tempdir().unwrap();
    let g = grid(
        dir.path(),
        "netns-partition",
        "paper/paper-05.toml",
        PARTITION_JOBS,
        900,
    );
    let res = dir.path().join("res");
    let (gs, rs) = (g.to_str().unwrap(), res.to_str().unwrap());
    let listen = lab.endpoint("tcp", "c");
    let coordinator = [
        "run",
        gs,
        "--results",
        rs,
        "--workers",
        "0",
        "-q",
        "--no-tours",
        "--lease-s",
        "20",
        "--listen",
        &listen,
    ];
    lab.lose("w2", 5);
    let upstream: SocketAddr = format!("{}:{PORT}", lab.addr("c")).parse().unwrap();
    let local: SocketAddr = format!("127.0.0.1:{PORT}").parse().unwrap();
    let _relay = DelayRelay::start(lab.ns("w2"), local, upstream, 150.0, 50.0);
    let mut c = Node::start(&lab, "c", "coordinator", &coordinator);
    // (Waiting long enough for a partition and a restart.)
    let wait_s = ["--wait-s", "120"];
    let mut w1 = Node::start(&lab, "w1", "w1", &worker_args(&listen, "w1", &wait_s));
    let relayed = format!("tcp/{local}");
    let mut w2 = Node::start(&lab, "w2", "w2", &worker_args(&relayed, "w2", &wait_s));
    partition_mid_grid(&lab, &mut c, &mut w1, &mut w2);
    eprintln!(
        "{:.0} s: partition healed, w1 delivered",
        t0.elapsed().as_secs_f64()
    );
    let first_log = c.log();
    // Once w1 is back and one more result is stored, kill -9 the coordinator and start it again.
    let acked = acknowledged(&mut [&mut w1, &mut w2]);
    wait(
        Duration::from_secs(120),
        "a result stored after the heal",
        &mut [&mut w1, &mut w2],
        |n| acknowledged(n) > acked,
    );
    c.kill9();
    std::thread::sleep(Duration::from_millis(300));
    let acked = acknowledged(&mut [&mut w1, &mut w2]);
    let kept = rows(&res).len();
    assert!(
        kept >= acked,
        "{acked} results were acknowledged but {kept} are stored"
    );
    assert!(
        kept < PARTITION_JOBS,
        "the grid ended before the restart: make it longer"
    );
    let mut c = Node::start(&lab, "c", "coordinator (again)", &coordinator);
    eprintln!(
        "{:.0} s: coordinator restarted ({kept} stored)",
        t0.elapsed().as_secs_f64()
    );
    let (ok1, out1) = w1.finish(Duration::from_secs(300));
    let (ok2, out2) = w2.finish(Duration::from_secs(60));
    let (okc, outc) = c.finish(Duration::from_secs(60));
    eprintln!("{:.0} s: grid complete", t0.elapsed().as_secs_f64());
    assert!(ok1 && ok2 && okc, "{out1}\n{out2}\n{first_log}\n{outc}");
    assert!(
        out1.contains("grid complete") && out2.contains("grid complete"),
        "{out1}\n{out2}"
    );
    let got = assert_same_as_local(&g, &res, &dir.path().join("local"), PARTITION_JOBS);
    assert!(
        got.iter().any(|r| r.worker == "w1") && got.iter().any(|r| r.worker == "w2"),
        "{got:?}"
    );
    say_wall_time("partition and restart", t0);
}

/// Waits until `w1` has a result stored and runs another job, then drops every packet of its
/// link for [`PARTITION`] and heals it; checks that the coordinator saw `w1` leave and gave its
/// job back, that `w2` went on meanwhile, and that `w1` delivers its result once back.
fn partition_mid_grid(lab: &Lab, c: &mut Node, w1: &mut Node, w2: &mut Node) {
    wait(
        Duration::from_secs(120),
        "w1 runs its second job",
        &mut [&mut *w1],
        |n| n[0].count(", stored") >= 1 && n[0].count(" seed ") >= 2,
    );
    let before = (w1.count(", stored"), w2.count(", stored"));
    lab.partition("w1");
    eprintln!("partition: w1 cut off with {before:?} results stored by w1, w2");
    let cut = Instant::now();
    // (Its zenoh session times out after 10 s; its job's lease, 20 s, may run out first.)
    wait(
        Duration::from_secs(25),
        "the coordinator sees w1 leave and requeues its job",
        &mut [&mut *c],
        |n| n[0].count("worker w1 left") >= 1 && n[0].count(" back in the queue: ") >= 1,
    );
    std::thread::sleep(PARTITION.saturating_sub(cut.elapsed()));
    let during = (w1.count(", stored"), w2.count(", stored"));
    eprintln!("partition: healed with {during:?} results stored by w1, w2");
    assert_eq!(
        during.0,
        before.0,
        "w1 stored a result while cut off:\n{}",
        w1.log()
    );
    assert!(
        during.1 > before.1,
        "w2 stored nothing meanwhile:\n{}",
        w2.log()
    );
    assert!(
        during.0 + during.1 < PARTITION_JOBS,
        "the grid ended during the partition: make it longer"
    );
    let replies = |w: &mut Node| w.count(", stored") + w.count("(duplicate)");
    let held = replies(w1);
    lab.heal("w1");
    // Its result (stored, or a duplicate if w2 ran that job meanwhile) once it reconnects.
    wait(
        Duration::from_secs(60),
        "w1 delivers its result after the heal",
        &mut [&mut *w1],
        |n| replies(n[0]) > held,
    );
}

// ------------------------------------------------------------------------------------------
// 2. A router

const ROUTER_JOBS: usize = 6;

/// Four hosts: a router (`floorcast router`), a coordinator and two workers that all connect to
/// it (none listens): the grid completes through it, with one row per job; the router stops
/// cleanly on SIGTERM.
#[test]
fn a_grid_runs_through_a_router() {
    let lab = Lab::new('r', 2, &["r", "c", "w1", "w2"]);
    let t0 = Instant::now();
    let dir = tempfile::tempdir().unwrap();
    let g = grid(dir.path(), "netns-router", "small.toml", ROUTER_JOBS, 150);
    let res = dir.path().join("res");
    let via = lab.endpoint("tcp", "r");
    let mut r = Node::start(&lab, "r", "router", &["router", "--listen", &via]);
    wait(
        Duration::from_secs(30),
        "the router listens",
        &mut [&mut r],
        |n| n[0].count(&format!("listening on {via}")) == 1,
    );
    let (gs, rs) = (g.to_str().unwrap(), res.to_str().unwrap());
    let mut c = Node::start(
        &lab,
        "c",
        "coordinator",
        &[
            "run",
            gs,
            "--results",
            rs,
            "--workers",
            "0",
            "-q",
            "--no-tours",
            "--connect",
            &via,
        ],
    );
    let mut w1 = Node::start(
        &lab,
        "w1",
        "w1",
        &worker_args(&via, "w1", &["--wait-s", "60"]),
    );
    let mut w2 = Node::start(
        &lab,
        "w2",
        "w2",
        &worker_args(&via, "w2", &["--wait-s", "60"]),
    );
    let (ok1, out1) = w1.finish(Duration::from_secs(240));
    let (ok2, out2) = w2.finish(Duration::from_secs(60));
    let (okc, outc) = c.finish(Duration::from_secs(60));
    assert!(ok1 && ok2 && okc, "{out1}\n{out2}\n{outc}");
    assert!(
        out1.contains("grid complete") && out2.contains("grid complete"),
        "{out1}\n{out2}"
    );
    let got = rows(&res);
    let mut ids: Vec<&str> = got.iter().map(|r| r.job_id.as_str()).collect();
    ids.dedup();
    assert_eq!(
        (got.len(), ids.len()),
        (ROUTER_JOBS, ROUTER_JOBS),
        "{got:?}"
    );
    assert!(
        got.iter().any(|r| r.worker == "w1") && got.iter().any(|r| r.worker == "w2"),
        "{got:?}"
    );
    let pid = nix::unistd::Pid::from_raw(r.child.id() as i32);
    nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM).unwrap();
    let (okr, outr) = r.finish(Duration::from_secs(15));
    assert!(okr && outr.contains("router stopped"), "{outr}");
    say_wall_time("router", t0);
}

// ------------------------------------------------------------------------------------------
// 3. Mutual TLS

const TLS_JOBS: usize = 4;

/// Runs the openssl command in `dir`.
fn openssl(dir: &Path, args: &[&str]) {
    let o = Command::new("openssl")
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap_or_else(|e| {
            panic!("openssl: {e}: this test makes its certificates with the openssl command (Debian/Ubuntu: apt-get install openssl)")
        });
    assert!(
        o.status.success(),
        "openssl {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A certificate authority: `NAME.pem`, `NAME.key`.
fn make_ca(dir: &Path, name: &str) {
    openssl(
        dir,
        &[
            "req",
            "-x509",
            "-newkey",
            "ec",
            "-pkeyopt",
            "ec_paramgen_curve:prime256v1",
            "-nodes",
            "-keyout",
            &format!("{name}.key"),
            "-out",
            &format!("{name}.pem"),
            "-days",
            "2",
            "-subj",
            &format!("/CN=floorcast test {name}"),
            "-addext",
            "basicConstraints=critical,CA:TRUE",
            "-addext",
            "keyUsage=critical,keyCertSign,cRLSign",
        ],
    );
}

/// A certificate for `san` (e.g. `IP:10.213.3.1`) signed by `ca`: `NAME.pem`, `NAME.key`.
fn make_cert(dir: &Path, name: &str, ca: &str, san: &str, serial: u32) {
    openssl(
        dir,
        &[
            "req",
            "-new",
            "-newkey",
            "ec",
            "-pkeyopt",
            "ec_paramgen_curve:prime256v1",
            "-nodes",
            "-keyout",
            &format!("{name}.key"),
            "-out",
            &format!("{name}.csr"),
            "-subj",
            &format!("/CN={name}"),
        ],
    );
    let ext = format!(
        "subjectAltName={san}\nbasicConstraints=critical,CA:FALSE\nkeyUsage=critical,digitalSignature\nextendedKeyUsage=serverAuth,clientAuth\n"
    );
    std::fs::write(dir.join(format!("{name}.ext")), ext).unwrap();
    openssl(
        dir,
        &[
            "x509",
            "-req",
            "-in",
            &format!("{name}.csr"),
            "-CA",
            &format!("{ca}.pem"),
            "-CAkey",
            &format!("{ca}.key"),
            "-set_serial",
            &serial.to_string(),
            "-days",
            "2",
            "-out",
            &format!("{name}.pem"),
            "-extfile",
            &format!("{name}.ext"),
        ],
    );
}

/// A zenoh configuration (docs/many-machines.md's shape) trusting `ca`, with `cert` as its
/// certificate (to listen too when `listens`).
fn tls_config(dir: &Path, file: &str, ca: &str, cert: &str, listens: bool) -> PathBuf {
    let p = |f: String| dir.join(f).display().to_string();
    let (pem, key) = (p(format!("{cert}.pem")), p(format!("{cert}.key")));
    let listen = if listens {
        format!("listen_certificate: \"{pem}\", listen_private_key: \"{key}\", ")
    } else {
        String::new()
    };
    let text = format!(
        "{{ mode: \"peer\", scouting: {{ multicast: {{ enabled: false }}, gossip: {{ enabled: false }} }},\n\
         transport: {{ link: {{ protocols: [\"tls\"], tls: {{ root_ca_certificate: \"{}\", enable_mtls: true, {listen}\
         connect_certificate: \"{pem}\", connect_private_key: \"{key}\" }} }} }} }}\n",
        p(format!("{ca}.pem"))
    );
    let path = dir.join(file);
    std::fs::write(&path, text).unwrap();
    path
}

/// A coordinator listening with mutual TLS (its CA, its certificate): a worker whose
/// certificate another CA signed, and one that trusts another CA (so not the coordinator),
/// get no job and give up; the grid does not move. A worker with a certificate of the right
/// CA then completes it.
#[test]
fn workers_without_the_right_certificate_get_no_jobs() {
    let lab = Lab::new('t', 3, &["c", "x", "w"]);
    let t0 = Instant::now();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    make_ca(d, "ca");
    make_ca(d, "other-ca");
    make_cert(d, "coordinator", "ca", &format!("IP:{}", lab.addr("c")), 1);
    make_cert(d, "worker", "ca", "DNS:worker", 2);
    make_cert(d, "forged", "other-ca", "DNS:worker", 3);
    let configs = [
        tls_config(d, "coordinator.json5", "ca", "coordinator", true),
        tls_config(d, "intruder.json5", "ca", "forged", false),
        tls_config(d, "misled.json5", "other-ca", "worker", false),
        tls_config(d, "member.json5", "ca", "worker", false),
    ];
    let [coord, intruder, misled, member] = configs.each_ref().map(|p| p.to_str().unwrap());
    let g = grid(d, "netns-tls", "small.toml", TLS_JOBS, 150);
    let res = d.join("res");
    let (gs, rs) = (g.to_str().unwrap(), res.to_str().unwrap());
    let at = lab.endpoint("tls", "c");
    let mut c = Node::start(
        &lab,
        "c",
        "coordinator",
        &[
            "run",
            gs,
            "--results",
            rs,
            "--workers",
            "0",
            "-q",
            "--no-tours",
            "--listen",
            &at,
            "--zenoh-config",
            coord,
        ],
    );
    std::thread::sleep(Duration::from_millis(500));
    let wrong = |name: &str, config: &str| {
        Node::start(
            &lab,
            "x",
            name,
            &worker_args(&at, name, &["--wait-s", "8", "--zenoh-config", config]),
        )
    };
    let (mut a, mut b) = (wrong("intruder", intruder), wrong("misled", misled));
    for w in [&mut a, &mut b] {
        let (ok, out) = w.finish(Duration::from_secs(60));
        assert!(!ok && out.contains("no coordinator answered"), "{out}");
        assert!(
            !out.contains("panicked") && !out.contains("connected, taking jobs"),
            "{out}"
        );
    }
    assert!(rows(&res).is_empty(), "the grid moved: {:?}", rows(&res));
    let mut w = Node::start(
        &lab,
        "w",
        "member",
        &worker_args(&at, "member", &["--wait-s", "60", "--zenoh-config", member]),
    );
    let (okw, outw) = w.finish(Duration::from_secs(240));
    let (okc, outc) = c.finish(Duration::from_secs(60));
    assert!(okw && okc, "{outw}\n{outc}");
    assert!(
        !outc.contains("intruder") && !outc.contains("misled"),
        "{outc}"
    );
    let got = rows(&res);
    assert_eq!(got.len(), TLS_JOBS, "{got:?}");
    assert!(got.iter().all(|r| r.worker == "member"), "{got:?}");
    say_wall_time("mutual TLS", t0);
}
