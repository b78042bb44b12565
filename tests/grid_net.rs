//! Distributed grids with real processes on loopback: a coordinator (`floorcast run --listen`)
//! and `floorcast worker` processes; workers and the coordinator killed with SIGKILL; wrong
//! credentials.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use common::*;

const JOBS: usize = 6;

fn grid(dir: &Path) -> PathBuf {
    let small = repo().join("buildings/small.toml");
    let text = format!(
        "format = \"floorcast-grid\"\nversion = 1\nname = \"net-e2e\"\nbuildings = [\"{}\"]\nseed_range = [1, {JOBS}]\n[[strategies]]\nname = \"baseline\"\n[settings]\ntime_limit_s = 150\n",
        small.display()
    );
    let p = dir.join("grid.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// A free TCP port on loopback (the OS picks it).
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// A child whose stderr lines arrive on a channel (and are kept for messages).
struct Proc {
    child: Child,
    lines: mpsc::Receiver<String>,
    seen: Vec<String>,
}

impl Proc {
    fn spawn(cmd: &mut Command) -> Proc {
        let (child, rx) = spawn_lines(cmd);
        Proc {
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

    /// Waits for a line containing `needle`.
    fn wait_for(&mut self, needle: &str, timeout: Duration) -> String {
        let t0 = Instant::now();
        loop {
            if let Some(l) = self.seen.iter().find(|l| l.contains(needle)) {
                return l.clone();
            }
            match self.lines.recv_timeout(Duration::from_millis(50)) {
                Ok(l) => self.seen.push(l),
                Err(_) if t0.elapsed() < timeout => {}
                Err(_) => panic!("no line with '{needle}' after {timeout:?}: {:?}", self.seen),
            }
        }
    }

    /// Waits for the exit; returns success and everything printed.
    fn finish(mut self, timeout: Duration) -> (bool, String) {
        let t0 = Instant::now();
        loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                std::thread::sleep(Duration::from_millis(100));
                self.drain();
                return (status.success(), self.seen.join("\n"));
            }
            if t0.elapsed() > timeout {
                let _ = self.child.kill();
                self.drain();
                panic!("did not exit within {timeout:?}: {}", self.seen.join("\n"));
            }
            self.drain();
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    fn kill9(&mut self) {
        self.child.kill().unwrap(); // SIGKILL on Unix
        let _ = self.child.wait();
    }
}

fn coordinator(g: &Path, res: &Path, port: u16, extra: &[&str]) -> Proc {
    Proc::spawn(
        floorcast()
            .args([
                "run",
                g.to_str().unwrap(),
                "--results",
                res.to_str().unwrap(),
            ])
            .args(["--workers", "0", "-q", "--lease-s", "20"])
            .args(["--listen", &format!("tcp/127.0.0.1:{port}")])
            .args(extra),
    )
}

fn worker(port: u16, name: &str, extra: &[&str]) -> Proc {
    Proc::spawn(
        floorcast()
            .args(["worker", "--connect", &format!("tcp/127.0.0.1:{port}")])
            .args(["--jobs", "1", "--wait-s", "60", "--name", name])
            .args(extra),
    )
}

/// Rows of the results store, as (job_id, worker).
fn stored(res: &Path) -> Vec<(String, String)> {
    report_rows(res)
        .into_iter()
        .map(|r| (r["job_id"].clone(), r["worker"].clone()))
        .collect()
}

fn assert_each_job_once(res: &Path) -> Vec<(String, String)> {
    let rows = stored(res);
    let mut ids: Vec<&String> = rows.iter().map(|(j, _)| j).collect();
    ids.sort();
    ids.dedup();
    assert_eq!(rows.len(), JOBS, "{rows:?}");
    assert_eq!(ids.len(), JOBS, "{rows:?}");
    rows
}

#[test]
fn two_worker_processes_complete_a_grid() {
    let dir = tempfile::tempdir().unwrap();
    let g = grid(dir.path());
    let res = dir.path().join("res");
    let port = free_port();
    let c = coordinator(&g, &res, port, &[]);
    let w1 = worker(port, "w1", &[]);
    let w2 = worker(port, "w2", &[]);
    let (ok1, out1) = w1.finish(Duration::from_secs(240));
    let (ok2, out2) = w2.finish(Duration::from_secs(60));
    let (okc, outc) = c.finish(Duration::from_secs(60));
    assert!(ok1 && ok2, "{out1}\n---\n{out2}");
    assert!(okc, "{outc}");
    assert!(out1.contains("grid complete") && out2.contains("grid complete"));
    assert!(outc.contains("done: 6 jobs run now"), "{outc}");
    // Each worker's first result was run again on the coordinator, and matched.
    assert!(
        outc.contains("checked: ") && outc.contains("run again here, all identical"),
        "{outc}"
    );
    let rows = assert_each_job_once(&res);
    // Both took part.
    assert!(rows.iter().any(|(_, w)| w == "w1") && rows.iter().any(|(_, w)| w == "w2"));
    // A second run has nothing to do.
    let o = run(&[
        "run",
        g.to_str().unwrap(),
        "--results",
        res.to_str().unwrap(),
    ]);
    assert!(stdout(&o).contains("nothing to do"), "{}", stdout(&o));
}

#[test]
fn a_worker_killed_mid_job_loses_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let g = grid(dir.path());
    let res = dir.path().join("res");
    let port = free_port();
    let c = coordinator(&g, &res, port, &[]);
    let mut w1 = worker(port, "w1", &[]);
    w1.wait_for("job ", Duration::from_secs(60)); // w1 runs a job now
    let w2 = worker(port, "w2", &[]);
    w1.kill9();
    let (ok2, out2) = w2.finish(Duration::from_secs(240));
    let (okc, outc) = c.finish(Duration::from_secs(60));
    assert!(ok2, "{out2}");
    assert!(okc, "{outc}");
    assert!(
        outc.contains("back in the queue: worker w1 left"),
        "the killed worker's job is requeued: {outc}"
    );
    let rows = assert_each_job_once(&res);
    assert!(rows.iter().all(|(_, w)| w == "w2"), "{rows:?}");
}

#[test]
fn a_coordinator_killed_mid_grid_resumes_without_rerunning() {
    let dir = tempfile::tempdir().unwrap();
    let g = grid(dir.path());
    let res = dir.path().join("res");
    let port = free_port();
    let mut c = coordinator(&g, &res, port, &[]);
    let mut w = worker(port, "w1", &[]);
    // Kill the coordinator once two results are stored.
    w.wait_for("job ", Duration::from_secs(60));
    let t0 = Instant::now();
    while w.seen.iter().filter(|l| l.contains(", stored")).count() < 2 {
        w.drain();
        assert!(t0.elapsed() < Duration::from_secs(120), "{:?}", w.seen);
        std::thread::sleep(Duration::from_millis(20));
    }
    c.kill9();
    let before = stored(&res);
    assert!(before.len() >= 2 && before.len() < JOBS, "{before:?}");
    // The worker keeps its result and waits; a new coordinator finishes the grid.
    let c2 = coordinator(&g, &res, port, &[]);
    let (okw, outw) = w.finish(Duration::from_secs(240));
    let (okc, outc) = c2.finish(Duration::from_secs(60));
    assert!(okw, "{outw}");
    assert!(okc, "{outc}");
    assert_each_job_once(&res);
    // Every job started once: nothing stored before the kill ran again.
    let mut started: Vec<&str> = outw
        .lines()
        .filter(|l| l.starts_with("job ") && !l.contains(" in "))
        .collect();
    let n = started.len();
    started.sort();
    started.dedup();
    assert_eq!(started.len(), n, "a job ran twice: {outw}");
    for (id, _) in &before {
        assert_eq!(
            outw.matches(&format!("job {id}: small")).count(),
            1,
            "{outw}"
        );
    }
}

#[test]
fn a_worker_with_wrong_credentials_gets_no_jobs() {
    let dir = tempfile::tempdir().unwrap();
    let g = grid(dir.path());
    let res = dir.path().join("res");
    let port = free_port();
    let creds = dir.path().join("credentials.txt");
    std::fs::write(
        &creds,
        "worker:right-password\ncoordinator:coord-password\n",
    )
    .unwrap();
    let conf = |name: &str, user: &str, password: &str, dictionary: Option<&Path>| {
        let dict = dictionary
            .map(|d| format!(", dictionary_file: \"{}\"", d.display()))
            .unwrap_or_default();
        let text = format!(
            "{{ mode: \"peer\", scouting: {{ multicast: {{ enabled: false }}, gossip: {{ enabled: false }} }}, transport: {{ auth: {{ usrpwd: {{ user: \"{user}\", password: \"{password}\"{dict} }} }} }} }}"
        );
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let coord_conf = conf("coord.json5", "coordinator", "coord-password", Some(&creds));
    let bad = conf("bad.json5", "worker", "wrong-password", None);
    let good = conf("good.json5", "worker", "right-password", None);
    let c = coordinator(
        &g,
        &res,
        port,
        &["--zenoh-config", coord_conf.to_str().unwrap()],
    );
    std::thread::sleep(Duration::from_millis(500));
    let intruder = Proc::spawn(
        floorcast()
            .args(["worker", "--connect", &format!("tcp/127.0.0.1:{port}")])
            .args(["--wait-s", "4", "--name", "intruder"])
            .args(["--zenoh-config", bad.to_str().unwrap()]),
    );
    let (ok, out) = intruder.finish(Duration::from_secs(60));
    assert!(!ok, "{out}");
    assert!(out.contains("no coordinator answered"), "{out}");
    assert!(!out.contains("panicked"), "{out}");
    assert!(!res.join("results.sqlite").exists() || stored(&res).is_empty());
    let w = worker(port, "member", &["--zenoh-config", good.to_str().unwrap()]);
    let (okw, outw) = w.finish(Duration::from_secs(240));
    let (okc, outc) = c.finish(Duration::from_secs(60));
    assert!(okw, "{outw}");
    assert!(okc, "{outc}");
    let rows = assert_each_job_once(&res);
    assert!(rows.iter().all(|(_, w)| w == "member"));
}

#[test]
fn garbage_on_the_job_keys_changes_nothing() {
    use floorcast_coordinator::net::raw_exchange;
    let dir = tempfile::tempdir().unwrap();
    let g = grid(dir.path());
    let res = dir.path().join("res");
    let port = free_port();
    let c = coordinator(&g, &res, port, &[]);
    let ep = format!("tcp/127.0.0.1:{port}");
    // Wait for the coordinator: it answers garbage with an error reply.
    let t0 = Instant::now();
    loop {
        let r = raw_exchange(&ep, "default", "ctl/next", b"garbage").unwrap_or_default();
        if !r.is_empty() {
            assert!(r.iter().all(|x| x.is_err()), "{r:?}");
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(30),
            "coordinator never answered"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    let fake_job = "0123456789abcdef0123456789abcdef";
    for (key, body) in [
        ("ctl/next", &b"\x00\x01\x02"[..]),
        (
            "ctl/next",
            br#"{"format":"floorcast-wire","version":1,"kind":"hello","body":{}}"#,
        ),
        (
            "ctl/next",
            br#"{"format":"floorcast-wire","version":99,"kind":"hello"}"#,
        ),
        (
            &format!("ctl/submit/{fake_job}"),
            br#"{"format":"floorcast-wire"}"#,
        ),
        (&format!("ctl/renew/{fake_job}"), b"[1,2,3]"),
        ("ctl/building/nothing", b"{}"),
    ] {
        let r = raw_exchange(&ep, "default", key, body).unwrap();
        assert!(
            !r.is_empty() && r.iter().all(|x| x.is_err()),
            "{key}: {r:?}"
        );
    }
    let w = worker(port, "w1", &[]);
    let (okw, outw) = w.finish(Duration::from_secs(240));
    let (okc, outc) = c.finish(Duration::from_secs(60));
    assert!(okw, "{outw}");
    assert!(okc, "{outc}");
    assert!(outc.contains("dropped a message"), "{outc}");
    let rows = assert_each_job_once(&res);
    assert!(rows.iter().all(|(_, w)| w == "w1"));
}
