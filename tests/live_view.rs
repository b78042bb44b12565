//! The live view of a running grid (`run --http`, issue 60): its JSON and its page fetched over
//! HTTP while jobs run, fail and wait, the page looked at in headless Chromium (a screenshot
//! whose progress bar shows stored, failed and running jobs), and a sequential grid's tests.
//!
//! A system test, built only with the `system-tests` feature: `.ci/system-tests` (which CI runs)
//! installs Chromium from Debian's package `chromium` and runs it; without Chromium the
//! screenshot test fails and says what to install.

mod common;

use std::io::{Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::Child;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use common::*;
use floorcast_coordinator::live::Status;
use floorcast_coordinator::live_page::{DONE_RGB, FAILED_RGB, RUNNING_RGB};

/// A strategy that holds its decision while the file `hold` lies beside it, for the seed
/// written in `gate_seed` only (having written `held`); else the nearest candidate first.
const GATED: &str = r#"import os, time
from floorcast_strategy import Strategy, run

HERE = os.path.dirname(os.path.abspath(__file__))


class Gated(Strategy):
    name = "gated.py"

    def decide(self, d):
        gate = os.path.join(HERE, "gate_seed")
        if os.path.exists(gate) and self.run["seed"] == int(open(gate).read()):
            open(os.path.join(HERE, "held"), "w").close()
            while os.path.exists(os.path.join(HERE, "hold")):
                time.sleep(0.05)
        ranked = sorted(d["candidates"], key=lambda c: (c["path_m"], c["id"]))
        return [c["id"] for c in ranked]


run(Gated())
"#;

/// A strategy that raises at its first decision.
const BROKEN: &str = r#"from floorcast_strategy import Strategy, run


class Broken(Strategy):
    name = "broken.py"

    def decide(self, d):
        raise ValueError("broken.py always fails")


run(Broken())
"#;

/// `strategies/gated.py` and `strategies/broken.py` in `dir` (the gate set for `gate_seed`,
/// held), and a grid of `body` (its buildings, seeds, strategies and sections).
fn project(dir: &Path, gate_seed: u64, body: &str) -> PathBuf {
    let s = dir.join("strategies");
    std::fs::create_dir_all(&s).unwrap();
    std::fs::write(s.join("gated.py"), GATED).unwrap();
    std::fs::write(s.join("broken.py"), BROKEN).unwrap();
    std::fs::write(s.join("gate_seed"), gate_seed.to_string()).unwrap();
    std::fs::write(s.join("hold"), "").unwrap();
    let text = format!(
        "format = \"floorcast-grid\"\nversion = 1\nname = \"live\"\nbuildings = [\"{}\"]\n{body}\n[settings]\ntime_limit_s = 600\n",
        repo().join("buildings/small.toml").display()
    );
    let g = dir.join("grid.toml");
    std::fs::write(&g, text).unwrap();
    g
}

const GATED_ENTRY: &str =
    "[[strategies]]\nlabel = \"gated.py\"\ncommand = [\"python3\", \"strategies/gated.py\"]\ntimeout_s = 300\n";

/// A plain HTTP/1.0 request: status code and body.
fn http(addr: &str, method: &str, path: &str) -> (u16, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    write!(s, "{method} {path} HTTP/1.0\r\nHost: {addr}\r\n\r\n").unwrap();
    let mut text = String::new();
    s.read_to_string(&mut text).unwrap();
    let (head, body) = text.split_once("\r\n\r\n").unwrap();
    let code = head.split_whitespace().nth(1).unwrap().parse().unwrap();
    (code, body.to_string())
}

fn status(addr: &str) -> Status {
    let (code, body) = http(addr, "GET", "/status.json");
    assert_eq!(code, 200, "{body}");
    serde_json::from_str(&body).unwrap_or_else(|e| panic!("status.json: {e}: {body}"))
}

/// Polls status.json until `ready` holds (at most 120 s).
fn wait_status(addr: &str, what: &str, ready: impl Fn(&Status) -> bool) -> Status {
    let t0 = Instant::now();
    loop {
        let s = status(addr);
        if ready(&s) {
            return s;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(120),
            "no {what} after 120 s: {s:#?}"
        );
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// Releases the gate and waits for the run's exit code and output.
fn release(dir: &Path, mut child: Child, rx: &mpsc::Receiver<String>) -> (Option<i32>, String) {
    std::fs::remove_file(dir.join("strategies/hold")).unwrap();
    let t0 = Instant::now();
    let code = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s.code();
        }
        assert!(t0.elapsed() < Duration::from_secs(120), "run did not end");
        std::thread::sleep(Duration::from_millis(100));
    };
    std::thread::sleep(Duration::from_millis(200));
    (code, rx.try_iter().collect::<Vec<_>>().join("\n"))
}

#[test]
fn the_live_view_serves_progress_workers_and_failures_during_a_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let body = format!(
        "seeds = [1, 2, 3]\n[[strategies]]\nname = \"baseline\"\n[[strategies]]\nlabel = \"broken.py\"\ncommand = [\"python3\", \"strategies/broken.py\"]\n{GATED_ENTRY}"
    );
    let grid = project(d, 2, &body);
    let (child, rx, addr) = spawn_live_run(d, &grid, 2);
    // Every job but gated.py's seed 2 ends (broken.py's three fail); that one is held.
    let s = wait_status(&addr, "8 of 9 jobs stored, 1 running", |s| {
        s.jobs.done == 8 && s.jobs.running == 1
    });
    assert_eq!(
        (
            s.format.as_str(),
            s.version,
            s.grid.as_str(),
            s.state.as_str()
        ),
        ("floorcast-status", 1, "live", "running")
    );
    assert_eq!((s.jobs.total, s.jobs.failed, s.jobs.left), (9, 3, 0));
    assert_eq!(s.jobs.stored_before, 0);
    assert!(s.eta_s.is_some_and(|e| e >= 0.0), "{:?}", s.eta_s);
    let names: Vec<&str> = s.workers.iter().map(|w| w.name.as_str()).collect();
    assert_eq!(names, ["local-0", "local-1"], "{s:#?}");
    assert!(s.workers.iter().all(|w| w.kind == "local" && w.connected));
    assert_eq!(s.workers.iter().map(|w| w.jobs_done).sum::<usize>(), 8);
    assert_eq!(s.workers.iter().map(|w| w.jobs_failed).sum::<usize>(), 3);
    let held: Vec<_> = s.workers.iter().flat_map(|w| &w.running).collect();
    assert_eq!(held.len(), 1, "{s:#?}");
    assert_eq!(
        (
            held[0].building.as_str(),
            held[0].label.as_str(),
            held[0].seed
        ),
        ("small", "gated.py", 2)
    );
    assert!(s.workers.iter().all(|w| w.last_contact_s < 60.0));
    assert_eq!(s.failures_total, 3);
    let mut failed_seeds: Vec<u64> = s.failures.iter().map(|f| f.seed).collect();
    failed_seeds.sort();
    assert_eq!(failed_seeds, [1, 2, 3]);
    assert!(s
        .failures
        .iter()
        .all(|f| f.label == "broken.py" && !f.error.is_empty() && f.building == "small"));
    assert!(s.sequential.is_empty());
    assert!(
        s.log
            .iter()
            .any(|l| l.contains("broken.py") && l.contains("failed")),
        "{:?}",
        s.log
    );

    let (code, page) = http(&addr, "GET", "/");
    assert_eq!(code, 200);
    for needle in [
        "<title>floorcast: live (running)</title>",
        "8 of 9 jobs stored",
        "1 running, 3 failed, 0 left",
        "Workers (2)",
        "local-0",
        "local-1",
        "small gated.py seed 2",
        "Failures (3)",
        "broken.py",
    ] {
        assert!(page.contains(needle), "'{needle}' not on the page:\n{page}");
    }
    assert_eq!(http(&addr, "GET", "/nope").0, 404);
    assert_eq!(http(&addr, "POST", "/status.json").0, 405);

    let shot = screenshot(&addr, d);
    for (rgb, what) in [
        (DONE_RGB, "stored"),
        (FAILED_RGB, "failed"),
        (RUNNING_RGB, "running"),
    ] {
        let n = pixels_of(&shot, rgb);
        assert!(
            n >= 300,
            "the screenshot's bar shows {n} pixels of {what} jobs' colour {rgb:?}"
        );
    }

    let (code, out) = release(d, child, &rx);
    // Failed jobs make `run` exit with 2; the held job is stored once released.
    assert_eq!(code, Some(2), "{out}");
    assert!(out.contains("done: 9 jobs run now"), "{out}");
}

/// The page as headless Chromium draws it (1000 x 900 pixels).
fn screenshot(addr: &str, dir: &Path) -> image::RgbImage {
    let chromium = ["/usr/bin/chromium", "/usr/bin/chromium-browser"]
        .into_iter()
        .find(|p| Path::new(p).exists())
        .unwrap_or_else(|| {
            panic!("headless Chromium is needed to look at the live view: install Debian's package `chromium` (apt-get install chromium; .ci/system-tests does)")
        });
    let png = dir.join("live.png");
    let profile = dir.join("chromium-profile");
    let o = std::process::Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--hide-scrollbars",
            "--window-size=1000,900",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("--screenshot={}", png.display()))
        .arg(format!("http://{addr}/"))
        .output()
        .unwrap();
    assert!(
        png.exists(),
        "chromium made no screenshot: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    image::open(&png).unwrap().to_rgb8()
}

fn pixels_of(img: &image::RgbImage, rgb: [u8; 3]) -> usize {
    img.pixels().filter(|p| p.0 == rgb).count()
}

#[test]
fn the_live_view_follows_a_sequential_grids_tests() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Batches of 5 seeds: after the first, each label has a test of 5 pairs (too few for an
    // LLR or a decision, so a second batch comes); gated.py holds seed 6, in the second.
    let body = format!(
        "[[strategies]]\nname = \"baseline\"\n[[strategies]]\nname = \"nearest\"\n{GATED_ENTRY}[sequential]\nreference = \"baseline\"\nh1_gain_pct = 5\nbatch_seeds = 5\nmax_seeds = 20\n"
    );
    let grid = project(d, 6, &body);
    let (child, rx, addr) = spawn_live_run(d, &grid, 2);
    let s = wait_status(&addr, "tests of the first batch", |s| {
        s.sequential.len() == 2 && s.jobs.running == 1 && s.jobs.done + 1 == s.jobs.total
    });
    let labels: Vec<&str> = s.sequential.iter().map(|t| t.label.as_str()).collect();
    assert!(
        labels.contains(&"nearest") && labels.contains(&"gated.py"),
        "{s:#?}"
    );
    for t in &s.sequential {
        assert_eq!(t.reference, "baseline");
        assert!(t.lower < 0.0 && t.upper > 0.0, "{t:?}");
        assert_eq!(t.points.len(), 1, "{t:?}");
        assert_eq!((t.points[0].through_seed, t.points[0].pairs), (5, 5));
        assert_eq!(t.points[0].llr, None, "{t:?}");
        assert_eq!(t.decision, "undecided");
    }
    let (code, page) = http(&addr, "GET", "/");
    assert_eq!(code, 200);
    assert!(page.contains("Sequential tests"), "{page}");
    assert!(page.contains("nearest against baseline"), "{page}");
    assert_eq!(page.matches("<svg class=\"llr\"").count(), 2, "{page}");
    let (code, out) = release(d, child, &rx);
    assert_eq!(code, Some(0), "{out}");
}

#[test]
fn a_bad_http_address_is_refused_before_anything_runs() {
    let dir = tempfile::tempdir().unwrap();
    let grid = project(
        dir.path(),
        0,
        "seeds = [1]\n[[strategies]]\nname = \"baseline\"\n",
    );
    let res = dir.path().join("results");
    for (addr, needle) in [
        ("nowhere:port", "is not an address to serve on"),
        ("70000", "is not an address to serve on"),
    ] {
        let o = floorcast()
            .args(["run", grid.to_str().unwrap(), "--results"])
            .arg(&res)
            .args(["--http", addr])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{addr}: {}", stderr(&o));
        assert!(stderr(&o).contains(needle), "{addr}: {}", stderr(&o));
        assert!(!res.exists(), "{addr}: a results directory was made");
    }
    // A port in use: refused before any job runs, nothing stored.
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = taken.local_addr().unwrap().port().to_string();
    let o = floorcast()
        .args(["run", grid.to_str().unwrap(), "--results"])
        .arg(&res)
        .args(["--http", &port, "-q"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("cannot serve the live view"),
        "{}",
        stderr(&o)
    );
    assert!(report_rows(&res).is_empty());
}
