//! Helpers for the end-to-end tests of the `floorcast` binary.
#![allow(dead_code)]

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::mpsc;

pub(crate) fn floorcast() -> Command {
    Command::new(env!("CARGO_BIN_EXE_floorcast"))
}

pub(crate) fn run(args: &[&str]) -> Output {
    floorcast().args(args).output().expect("floorcast runs")
}

pub(crate) fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub(crate) fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The real maps vendored in the repository (`maps/`).
pub(crate) fn maps_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("maps")
}

pub(crate) fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Asserts a failed run: exit code 2, one line on stderr containing every `needles`, no panic.
pub(crate) fn assert_clean_failure(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(2), "exit code; stderr: {err}");
    assert!(!err.contains("panicked"), "panic: {err}");
    assert_eq!(err.trim().lines().count(), 1, "one line expected: {err}");
    for n in needles {
        assert!(err.contains(n), "'{n}' missing from: {err}");
    }
}

/// The rows of `report DIR --csv`: column name -> value, one map per stored job.
pub(crate) fn report_rows(res: &Path) -> Vec<std::collections::BTreeMap<String, String>> {
    let csv = res.join("export.csv");
    let o = run(&[
        "report",
        res.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .map(|l| {
            header
                .iter()
                .cloned()
                .zip(l.split(',').map(str::to_string))
                .collect()
        })
        .collect()
}

/// A `floorcast` child whose stdout and stderr lines are collected.
#[derive(Debug)]
pub(crate) struct Proc(std::process::Child, std::sync::mpsc::Receiver<String>);

impl Proc {
    /// Starts `floorcast ARGS` in `cwd`.
    pub(crate) fn spawn(args: &[&str], cwd: &Path) -> Proc {
        use std::io::BufRead;
        let mut child = floorcast()
            .args(args)
            .current_dir(cwd)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        for stream in [
            Box::new(child.stderr.take().unwrap()) as Box<dyn std::io::Read + Send>,
            Box::new(child.stdout.take().unwrap()),
        ] {
            let tx = tx.clone();
            std::thread::spawn(move || {
                for line in std::io::BufReader::new(stream)
                    .lines()
                    .map_while(Result::ok)
                {
                    let _ = tx.send(line);
                }
            });
        }
        Proc(child, rx)
    }

    /// Waits for the exit (killed after `timeout`, failing the test); returns the exit code and
    /// every line printed.
    pub(crate) fn finish(mut self, timeout: std::time::Duration) -> Exit {
        let t0 = std::time::Instant::now();
        let mut seen = Vec::new();
        loop {
            while let Ok(l) = self.1.try_recv() {
                seen.push(l);
            }
            if let Some(status) = self.0.try_wait().unwrap() {
                std::thread::sleep(std::time::Duration::from_millis(100));
                while let Ok(l) = self.1.try_recv() {
                    seen.push(l);
                }
                return (status.code(), seen.join("\n"));
            }
            if t0.elapsed() > timeout {
                let _ = self.0.kill();
                panic!("did not exit within {timeout:?}: {}", seen.join("\n"));
            }
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
    }
}

/// A process's exit code and everything it printed.
pub(crate) type Exit = (Option<i32>, String);

/// `floorcast run GRID --results RES --workers 0 --listen` on a free loopback port with one
/// `floorcast worker` per name (one job each) started in `workers_cwd`; waits for all. Returns
/// the coordinator's exit code and output, then each worker's.
pub(crate) fn run_with_remote_workers(
    grid: &Path,
    res: &Path,
    names: &[&str],
    workers_cwd: &Path,
) -> (Exit, Vec<Exit>) {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let endpoint = format!("tcp/127.0.0.1:{port}");
    let cwd = grid.parent().unwrap_or(Path::new("."));
    let c = Proc::spawn(
        &[
            "run",
            grid.to_str().unwrap(),
            "--results",
            res.to_str().unwrap(),
            "--workers",
            "0",
            "-q",
            "--listen",
            &endpoint,
        ],
        cwd,
    );
    let workers: Vec<Proc> = names
        .iter()
        .map(|name| {
            Proc::spawn(
                &[
                    "worker",
                    "--connect",
                    &endpoint,
                    "--jobs",
                    "1",
                    "--wait-s",
                    "60",
                    "--name",
                    name,
                ],
                workers_cwd,
            )
        })
        .collect();
    let outs: Vec<Exit> = workers
        .into_iter()
        .map(|w| w.finish(std::time::Duration::from_secs(300)))
        .collect();
    (c.finish(std::time::Duration::from_secs(60)), outs)
}

/// `floorcast run GRID --results RES -q`.
pub(crate) fn run_grid(grid: &Path, res: &Path) -> Output {
    run(&[
        "run",
        grid.to_str().unwrap(),
        "--results",
        res.to_str().unwrap(),
        "-q",
    ])
}

/// Runs one exploration with extra arguments; returns its summary.
pub(crate) fn explore_with(
    building: &std::path::Path,
    seed: u64,
    out: &std::path::Path,
    extra: &[&str],
) -> serde_json::Value {
    let seed = seed.to_string();
    let mut args = vec![
        "explore",
        "--building",
        building.to_str().unwrap(),
        "--seed",
        &seed,
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend_from_slice(extra);
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// The crates' source folders, for the tests that read the code itself.
pub(crate) const CRATE_SOURCES: &[&str] = &[
    "sim-core/src",
    "formats/src",
    "render/src",
    "settings/src",
    "worker/src",
    "stats/src",
    "coordinator/src",
    "src",
];

/// Every `.rs` file under `dir`.
pub(crate) fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// The numbered lines of a file's code: its test modules left out (each `#[cfg(test)]` module,
/// to its closing brace at the indent it opened at) and comment lines skipped.
pub(crate) fn code_lines(text: &str) -> Vec<(usize, &str)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    let mut skip_to: Option<String> = None;
    for (i, l) in lines.iter().enumerate() {
        if let Some(close) = &skip_to {
            if l == close {
                skip_to = None;
            }
            continue;
        }
        let test_module = (l.trim() == "#[cfg(test)]")
            .then(|| lines[i + 1..].iter().find(|n| !n.trim().is_empty()))
            .flatten()
            .filter(|n| {
                let n = n.trim_start();
                n.starts_with("mod ")
                    || n.starts_with("pub(crate) mod ")
                    || n.starts_with("pub mod ")
            });
        if let Some(m) = test_module {
            // The module's lines up to its closing brace (none when it is `mod tests;`).
            if m.trim_end().ends_with('{') {
                skip_to = Some(format!("{}}}", &m[..m.len() - m.trim_start().len()]));
            }
            continue;
        }
        if !l.trim_start().starts_with("//") {
            out.push((i + 1, *l));
        }
    }
    out
}

/// Spawns `cmd` with its stdout and stderr piped: their lines arrive on the channel as they
/// are printed (stderr's and stdout's interleaved as they come).
pub(crate) fn spawn_lines(cmd: &mut Command) -> (Child, mpsc::Receiver<String>) {
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (tx, rx) = mpsc::channel();
    for stream in [
        Box::new(child.stderr.take().unwrap()) as Box<dyn Read + Send>,
        Box::new(child.stdout.take().unwrap()),
    ] {
        let tx = tx.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(stream).lines().map_while(Result::ok) {
                let _ = tx.send(line);
            }
        });
    }
    (child, rx)
}

/// Sends the signal `name` (`TERM`, `INT`, `9`, ...) to the process `pid`, as `kill -NAME PID`;
/// fails the test when it cannot be sent.
pub(crate) fn send_signal(pid: u32, name: &str) {
    let sent = Command::new("kill")
        .args([format!("-{name}"), pid.to_string()])
        .status()
        .unwrap();
    assert!(sent.success(), "kill -{name} {pid}");
}

/// `floorcast run GRID --http 127.0.0.1:0` with `workers` local workers, results in
/// `dir/results`, run in `dir`: the child, its output lines and the address it serves on (read
/// from its `live view:` line within 60 s; else the child is killed and the test fails).
pub(crate) fn spawn_live_run(
    dir: &Path,
    grid: &Path,
    workers: usize,
) -> (Child, mpsc::Receiver<String>, String) {
    let (mut child, rx) = spawn_lines(
        floorcast()
            .args(["run", grid.to_str().unwrap(), "--results"])
            .arg(dir.join("results"))
            .args([
                "--workers",
                &workers.to_string(),
                "--no-share",
                "--no-tours",
                "-q",
            ])
            .args(["--http", "127.0.0.1:0"])
            .current_dir(dir)
            .env("TMPDIR", dir),
    );
    let t0 = std::time::Instant::now();
    let mut seen = Vec::new();
    while t0.elapsed() < std::time::Duration::from_secs(60) {
        if let Ok(l) = rx.recv_timeout(std::time::Duration::from_millis(100)) {
            if let Some(rest) = l.strip_prefix("live view: http://") {
                let addr = rest.split('/').next().unwrap().to_string();
                return (child, rx, addr);
            }
            seen.push(l);
        }
    }
    let _ = child.kill();
    let _ = child.wait();
    panic!("no 'live view:' line within 60 s: {seen:?}");
}
