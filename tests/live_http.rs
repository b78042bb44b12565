//! The live view's server against clients that would harm it (issue 78, items 1 and 2), with no
//! browser: `run --http` on a grid whose one job is held by its strategy until released, while
//! clients send endless headers (`run`'s memory, read from /proc/PID/status, stays bounded),
//! open more connections than it serves (the excess answered 503, its threads bounded), or hold
//! connections open (a finished `run` exits all the same). The bounds: docs/live-view.md.

mod common;

use std::io::{Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::Child;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

use common::*;

/// A strategy that holds every decision while the file `hold` lies beside it.
const HELD: &str = r#"import os, time
from floorcast_strategy import Strategy, run

HERE = os.path.dirname(os.path.abspath(__file__))


class Held(Strategy):
    name = "held.py"

    def decide(self, d):
        while os.path.exists(os.path.join(HERE, "hold")):
            time.sleep(0.05)
        ranked = sorted(d["candidates"], key=lambda c: (c["path_m"], c["id"]))
        return [c["id"] for c in ranked]


run(Held())
"#;

/// `strategies/held.py` (held) and a grid of one job on buildings/small.toml that runs it.
fn project(dir: &Path) -> PathBuf {
    let s = dir.join("strategies");
    std::fs::create_dir_all(&s).unwrap();
    std::fs::write(s.join("held.py"), HELD).unwrap();
    std::fs::write(s.join("hold"), "").unwrap();
    let text = format!(
        "format = \"floorcast-grid\"\nversion = 1\nname = \"live-http\"\nbuildings = [\"{}\"]\nseeds = [1]\n[[strategies]]\nlabel = \"held.py\"\ncommand = [\"python3\", \"strategies/held.py\"]\ntimeout_s = 300\n[settings]\ntime_limit_s = 600\n",
        repo().join("buildings/small.toml").display()
    );
    let g = dir.join("grid.toml");
    std::fs::write(&g, text).unwrap();
    g
}

/// A `run --http 127.0.0.1:0` of [`project`]'s grid, its job held.
struct Run {
    child: Child,
    lines: mpsc::Receiver<String>,
    addr: String,
    dir: PathBuf,
}

impl Run {
    fn start(dir: &Path) -> Run {
        let (child, lines, addr) = spawn_live_run(dir, &project(dir), 1);
        let run = Run {
            child,
            lines,
            addr,
            dir: dir.to_path_buf(),
        };
        run.wait_running();
        run
    }

    /// Waits (at most 60 s) until the held job runs.
    fn wait_running(&self) {
        let t0 = Instant::now();
        loop {
            if let Some((200, body)) = get(&self.addr, "/status.json") {
                if body.contains("\"running\": 1") {
                    return;
                }
            }
            assert!(t0.elapsed() < Duration::from_secs(60), "the job never ran");
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    fn pid(&self) -> u32 {
        self.child.id()
    }

    /// A field of /proc/PID/status, as a number (VmRSS in kB, Threads).
    fn proc_status(&self, field: &str) -> u64 {
        let text = std::fs::read_to_string(format!("/proc/{}/status", self.pid())).unwrap();
        let line = text
            .lines()
            .find(|l| l.starts_with(&format!("{field}:")))
            .unwrap_or_else(|| panic!("no {field} in /proc/PID/status: {text}"));
        line.split_whitespace().nth(1).unwrap().parse().unwrap()
    }

    /// Releases the job; returns the exit code, the output and the seconds from release to exit.
    fn release(mut self) -> (Option<i32>, String, f64) {
        std::fs::remove_file(self.dir.join("strategies/hold")).unwrap();
        let t0 = Instant::now();
        let code = loop {
            if let Some(s) = self.child.try_wait().unwrap() {
                break s.code();
            }
            if t0.elapsed() > Duration::from_secs(60) {
                let _ = self.child.kill();
                let _ = self.child.wait();
                panic!("run did not end within 60 s of its job's release");
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        let took = t0.elapsed().as_secs_f64();
        std::thread::sleep(Duration::from_millis(200));
        let out = self.lines.try_iter().collect::<Vec<_>>().join("\n");
        (code, out, took)
    }
}

impl Drop for Run {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// One HTTP/1.0 GET: status code and body (None when the connection failed or was cut).
fn get(addr: &str, path: &str) -> Option<(u16, String)> {
    let mut s = TcpStream::connect(addr).ok()?;
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    write!(s, "GET {path} HTTP/1.0\r\nHost: {addr}\r\n\r\n").ok()?;
    let mut text = String::new();
    s.read_to_string(&mut text).ok()?;
    let (head, body) = text.split_once("\r\n\r\n")?;
    let code = head.split_whitespace().nth(1)?.parse().ok()?;
    Some((code, body.to_string()))
}

/// Sends header lines without end (up to `cap` bytes); returns the bytes the server took and
/// the status of its answer, if one could be read.
fn endless_header(addr: &str, cap: usize) -> (usize, Option<u16>) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_write_timeout(Some(Duration::from_secs(20))).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let mut sent = 0;
    if s.write_all(b"GET / HTTP/1.1\r\nHost: x\r\n").is_ok() {
        let line = format!("X-Fill: {}\r\n", "a".repeat(4000));
        let chunk = line.repeat(16);
        while sent < cap {
            match s.write(chunk.as_bytes()) {
                Ok(n) => sent += n,
                Err(_) => break,
            }
        }
    }
    let mut answer = [0u8; 64];
    let code = match s.read(&mut answer) {
        Ok(n) if n > 12 => std::str::from_utf8(&answer[9..12])
            .ok()
            .and_then(|c| c.parse().ok()),
        _ => None,
    };
    (sent, code)
}

#[test]
fn endless_headers_are_cut_and_runs_memory_stays_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let run = Run::start(dir.path());
    let rss_before = run.proc_status("VmRSS");
    // Eight clients at once, each offering 400 MB of header (before, four such aborted `run`).
    let peak = Arc::new(AtomicU64::new(rss_before));
    let sending = Arc::new(AtomicBool::new(true));
    let watch = {
        let (peak, sending, pid) = (Arc::clone(&peak), Arc::clone(&sending), run.pid());
        std::thread::spawn(move || {
            while sending.load(Ordering::SeqCst) {
                if let Ok(text) = std::fs::read_to_string(format!("/proc/{pid}/status")) {
                    if let Some(kb) = text
                        .lines()
                        .find(|l| l.starts_with("VmRSS:"))
                        .and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
                    {
                        peak.fetch_max(kb, Ordering::SeqCst);
                    }
                }
                std::thread::sleep(Duration::from_millis(20));
            }
        })
    };
    let t0 = Instant::now();
    let clients: Vec<_> = (0..8)
        .map(|_| {
            let addr = run.addr.clone();
            std::thread::spawn(move || endless_header(&addr, 400 << 20))
        })
        .collect();
    let results: Vec<(usize, Option<u16>)> =
        clients.into_iter().map(|c| c.join().unwrap()).collect();
    let took = t0.elapsed();
    sending.store(false, Ordering::SeqCst);
    watch.join().unwrap();
    for (sent, code) in &results {
        // What the kernel's socket buffers take, at most: the server reads 16 KB of it.
        assert!(
            *sent < 64 << 20,
            "a client got {sent} bytes of header in: {results:?}"
        );
        assert!(code.is_none() || *code == Some(431), "{results:?}");
    }
    assert!(
        took < Duration::from_secs(20),
        "the clients were cut after {took:?}"
    );
    let rss_peak = peak.load(Ordering::SeqCst);
    assert!(
        rss_peak < rss_before + 20 * 1024,
        "run's VmRSS went from {rss_before} kB to {rss_peak} kB under endless headers"
    );
    // The server still serves, and the grid goes on.
    assert_eq!(get(&run.addr, "/status.json").map(|r| r.0), Some(200));
    let (code, out, _) = run.release();
    assert_eq!(code, Some(0), "{out}");
    assert!(out.contains("done: 1 jobs run now"), "{out}");
}

#[test]
fn connections_beyond_the_bound_are_refused_and_threads_stay_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let run = Run::start(dir.path());
    let threads_before = run.proc_status("Threads");
    // 200 connections that send nothing: 32 are served (and cut when idle 5 s), the rest
    // answered 503 at once.
    let mut conns: Vec<TcpStream> = (0..200)
        .map(|_| TcpStream::connect(&run.addr).unwrap())
        .collect();
    let t0 = Instant::now();
    let mut refused = 0;
    for c in &mut conns {
        c.set_read_timeout(Some(Duration::from_millis(50))).unwrap();
        let mut text = String::new();
        if c.read_to_string(&mut text).is_ok() && text.starts_with("HTTP/1.1 503") {
            assert!(text.contains("32 connections at once"), "{text}");
            refused += 1;
        }
    }
    assert!(
        t0.elapsed() < Duration::from_secs(15),
        "{:?} to read the refusals",
        t0.elapsed()
    );
    assert!((160..=168).contains(&refused), "{refused} of 200 refused");
    let threads = run.proc_status("Threads");
    assert!(
        threads <= threads_before + 33,
        "{threads_before} threads before, {threads} with 200 connections"
    );
    // Once the idle ones are cut, a client is served again (still holding all 200 open).
    let t0 = Instant::now();
    loop {
        if let Some((200, _)) = get(&run.addr, "/status.json") {
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(15),
            "not served again 15 s after 200 idle connections"
        );
        std::thread::sleep(Duration::from_millis(200));
    }
    let (code, out, _) = run.release();
    assert_eq!(code, Some(0), "{out}");
    drop(conns);
}

#[test]
fn a_finished_run_exits_whatever_clients_hold_open() {
    let dir = tempfile::tempdir().unwrap();
    let run = Run::start(dir.path());
    // An idle connection, a request begun and never ended, and a keep-alive client asking
    // every 200 ms (never idle) on one connection until it is closed.
    let idle = TcpStream::connect(&run.addr).unwrap();
    let mut half = TcpStream::connect(&run.addr).unwrap();
    half.write_all(b"GET / HTTP/1.1\r\nHost: x\r\n").unwrap();
    let busy = {
        let addr = run.addr.clone();
        std::thread::spawn(move || {
            let mut s = TcpStream::connect(&addr).unwrap();
            s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
            let mut answered = 0u32;
            let mut buf = vec![0u8; 1 << 20];
            loop {
                if s.write_all(b"GET /status.json HTTP/1.1\r\nHost: x\r\n\r\n")
                    .is_err()
                {
                    break;
                }
                // One answer: the head, then Content-Length bytes.
                let mut got = Vec::new();
                let body_len = loop {
                    match s.read(&mut buf) {
                        Ok(0) | Err(_) => return (answered, Instant::now()),
                        Ok(n) => got.extend_from_slice(&buf[..n]),
                    }
                    if let Some(end) = got.windows(4).position(|w| w == b"\r\n\r\n") {
                        let head = String::from_utf8_lossy(&got[..end]).to_lowercase();
                        let len: usize = head
                            .lines()
                            .find_map(|l| l.strip_prefix("content-length:"))
                            .unwrap()
                            .trim()
                            .parse()
                            .unwrap();
                        break end + 4 + len;
                    }
                };
                while got.len() < body_len {
                    match s.read(&mut buf) {
                        Ok(0) | Err(_) => return (answered, Instant::now()),
                        Ok(n) => got.extend_from_slice(&buf[..n]),
                    }
                }
                answered += 1;
                std::thread::sleep(Duration::from_millis(200));
            }
            (answered, Instant::now())
        })
    };
    std::thread::sleep(Duration::from_secs(1));
    let (code, out, took) = run.release();
    let exited = Instant::now();
    assert_eq!(code, Some(0), "{out}");
    // The held job's end takes a moment; a server that waited for its clients would wait for
    // the keep-alive one for ever.
    assert!(
        took < 20.0,
        "run exited {took:.1} s after its job was released"
    );
    let (answered, cut) = busy.join().unwrap();
    assert!(
        answered >= 5,
        "the keep-alive client had {answered} answers"
    );
    assert!(
        cut <= exited + Duration::from_secs(2),
        "the keep-alive connection outlived run by {:?}",
        cut - exited
    );
    drop((idle, half));
}
