//! Nothing lost, nothing run that should not be (issue 62), end to end: exports never overwrite
//! the results store, a failed write to stdout is an error, one `run` per results directory.

mod common;

use std::path::Path;

use common::*;

/// A results directory `res` in `dir` holding two runs of a one-seed grid on small.toml.
fn results(dir: &Path) -> std::path::PathBuf {
    let small = repo().join("buildings/small.toml");
    let grid = dir.join("grid.toml");
    std::fs::write(
        &grid,
        format!(
            "format = \"floorcast-grid\"\nversion = 1\nname = \"safe\"\nbuildings = [\"{}\"]\nseeds = [1]\n[[strategies]]\nname = \"baseline\"\n[[strategies]]\nname = \"baseline\"\nlabel = \"near\"\nsettings = {{ alpha = 0.8 }}\n[settings]\ntime_limit_s = 30\n",
            small.display()
        ),
    )
    .unwrap();
    let res = dir.join("res");
    let o = run_grid(&grid, &res);
    assert!(o.status.success(), "{}", stderr(&o));
    res
}

/// The CSV of every stored row (written outside the results directory).
fn rows_csv(dir: &Path, res: &Path) -> String {
    let csv = dir.join("check.csv");
    let o = run(&[
        "report",
        res.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::read_to_string(csv).unwrap()
}

/// Every spelling of a file the store owns is refused, before anything is written, for every
/// export flag: one line naming the flag and the path, exit code 2, the store's rows intact.
#[test]
fn exports_never_overwrite_the_store() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    let res = results(tmp);
    let before = rows_csv(tmp, &res);
    assert_eq!(before.lines().count(), 3, "{before}");
    // The lock the run left (it says who held it last).
    let lock = std::fs::read(res.join("floorcast.lock")).unwrap();
    std::fs::create_dir(res.join("sub")).unwrap();
    std::os::unix::fs::symlink("res", tmp.join("link")).unwrap();
    std::os::unix::fs::symlink("res/results.sqlite", tmp.join("store-link")).unwrap();
    std::os::unix::fs::symlink("res/results.sqlite-journal", tmp.join("dangling")).unwrap();
    std::fs::hard_link(res.join("results.sqlite"), tmp.join("hard")).unwrap();
    // Chart directories whose chart files would be the store.
    std::fs::create_dir(tmp.join("plots-sym")).unwrap();
    std::os::unix::fs::symlink("../res/results.sqlite", tmp.join("plots-sym/times.png")).unwrap();
    std::fs::create_dir(tmp.join("plots-hard")).unwrap();
    std::fs::hard_link(res.join("results.sqlite"), tmp.join("plots-hard/gains.svg")).unwrap();
    let abs = res.join("results.sqlite").display().to_string();
    // (flag, path, extra arguments)
    let cases: &[(&str, &str, &[&str])] = &[
        ("--csv", "res/results.sqlite", &[]),
        ("--csv", "./res/results.sqlite", &[]),
        ("--csv", "res/../res/results.sqlite", &[]),
        ("--csv", "res/sub/../results.sqlite", &[]),
        ("--csv", "res//results.sqlite", &[]),
        ("--csv", &abs, &[]),
        ("--csv", "link/results.sqlite", &[]),
        ("--csv", "store-link", &[]),
        ("--csv", "hard", &[]),
        ("--csv", "dangling", &[]),
        ("--csv", "res/results.sqlite-wal", &[]),
        ("--csv", "res/results.sqlite-shm", &[]),
        ("--csv", "res/results.sqlite-journal", &[]),
        ("--csv", "res/floorcast.lock", &[]),
        ("--json", "res/results.sqlite", &[]),
        ("--json", "link/../res/results.sqlite", &[]),
        ("--json", "hard", &[]),
        ("--html", "./link/./results.sqlite", &[]),
        ("--html", "store-link", &[]),
        ("--plots", "plots-sym", &[]),
        ("--plots", "plots-hard", &["--picture", "svg"]),
    ];
    let mut failures = Vec::new();
    for (flag, path, extra) in cases {
        let o = floorcast()
            .args(["report", "res", flag, path])
            .args(*extra)
            .current_dir(tmp)
            .output()
            .unwrap();
        let err = stderr(&o);
        let clean = o.status.code() == Some(2)
            && err.trim().lines().count() == 1
            && err.contains(flag)
            && err.contains(path)
            && err.contains("floorcast owns")
            && o.stdout.is_empty();
        if !clean {
            failures.push(format!("{flag} {path}: {:?} {err}", o.status.code()));
        }
        let now = rows_csv(tmp, &res);
        if now != before {
            failures.push(format!("{flag} {path}: the store changed"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(!tmp.join("res/results.sqlite-journal").exists());
    assert_eq!(std::fs::read(res.join("floorcast.lock")).unwrap(), lock);
}

/// Exports beside the store, and charts in the results directory itself, are still written.
#[test]
fn exports_beside_the_store_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    let res = results(tmp);
    let o = floorcast()
        .args([
            "report",
            "res",
            "--csv",
            "res/results.csv",
            "--json",
            "./res/results.sqlite.json",
            "--plots",
            "res",
            "--html",
            "res/report.html",
        ])
        .current_dir(tmp)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    for f in [
        "results.csv",
        "results.sqlite.json",
        "times.png",
        "report.html",
    ] {
        assert!(res.join(f).is_file(), "{f} missing");
    }
    assert_eq!(rows_csv(tmp, &res).lines().count(), 3);
}

/// A strategy program using floorcast's Python module (`import floorcast_strategy` from its
/// `PYTHONPATH`), which stops at once; written into `dir` as `stops.py`.
fn python_module_strategy(dir: &Path) -> String {
    std::fs::write(
        dir.join("stops.py"),
        "from floorcast_strategy import Strategy, run\n\n\nclass Stops(Strategy):\n    name = \"stops\"\n\n    def decide(self, d):\n        return None\n\n\nrun(Stops())\n",
    )
    .unwrap();
    "python3 stops.py".to_string()
}

/// `explore` of small.toml with the program `command`, in `cwd`, with `TMPDIR` set to `tmpdir`.
fn explore_with_tmpdir(cwd: &Path, command: &str, tmpdir: &Path) -> std::process::Output {
    floorcast()
        .args(["explore", "--building"])
        .arg(repo().join("buildings/small.toml"))
        .args([
            "--seed",
            "1",
            "--out",
            "out",
            "--quiet",
            "--strategy-command",
            command,
        ])
        .env("TMPDIR", tmpdir)
        .current_dir(cwd)
        .output()
        .unwrap()
}

/// The folder floorcast's Python module used to be put in (and reused): a name anyone could
/// make first, here holding a `json.py` and a `floorcast_strategy.py` that leave a marker when
/// imported. floorcast never puts it on a program's `PYTHONPATH`, and leaves no folder of its own
/// behind in `TMPDIR`.
#[test]
fn a_planted_python_folder_is_never_used() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    let tmpdir = tmp.join("tmp");
    let o = std::process::Command::new("sha256sum")
        .arg(repo().join("python/floorcast_strategy.py"))
        .output()
        .unwrap();
    let hash = String::from_utf8(o.stdout).unwrap()[..12].to_string();
    let planted = tmpdir.join(format!("floorcast-python-{hash}"));
    std::fs::create_dir_all(&planted).unwrap();
    let marker = tmp.join("marker");
    let plant = format!(
        "open({:?}, 'w').write('planted')\n",
        marker.display().to_string()
    );
    for module in ["json.py", "floorcast_strategy.py", "sys.py"] {
        std::fs::write(planted.join(module), &plant).unwrap();
    }
    let command = python_module_strategy(tmp);
    let o = explore_with_tmpdir(tmp, &command, &tmpdir);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(tmp.join("out/summary.json").is_file());
    assert!(!marker.exists(), "a planted module ran");
    let left: Vec<_> = std::fs::read_dir(&tmpdir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, vec![planted.file_name().unwrap().to_owned()]);
}

/// A `TMPDIR` floorcast cannot write in is a floorcast error naming it and what to do, not
/// Python's `ModuleNotFoundError`.
#[test]
fn an_unwritable_tmpdir_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    let command = python_module_strategy(tmp);
    let o = explore_with_tmpdir(tmp, &command, &tmp.join("no-such-dir"));
    assert_clean_failure(
        &o,
        &["no-such-dir", "set TMPDIR to a directory you can write"],
    );
    assert!(
        !stderr(&o).contains("ModuleNotFoundError"),
        "{}",
        stderr(&o)
    );
}

/// Whether process `pid` has ended (gone, or a zombie waiting to be reaped).
fn ended(pid: u32) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Err(_) => true,
        Ok(stat) => stat
            .rsplit_once(')')
            .unwrap()
            .1
            .trim_start()
            .starts_with('Z'),
    }
}

/// The pid a wrapper script wrote, and whether it has ended (waiting up to 5 s).
fn ended_soon(pid_file: &Path) -> (u32, bool) {
    let pid: u32 = std::fs::read_to_string(pid_file)
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    let t0 = std::time::Instant::now();
    while !ended(pid) && t0.elapsed() < std::time::Duration::from_secs(5) {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    (pid, ended(pid))
}

/// A wrapper script (`sh wrap-<name>.sh`) that starts `background` (a command such as `sleep
/// 1000`) in the background (its pid in `<name>.pid`) and then becomes the Python program
/// `program`.
fn wrapper_starting(dir: &Path, name: &str, background: &str, program: &str) -> String {
    std::fs::write(
        dir.join(format!("wrap-{name}.sh")),
        format!("{background} &\necho $! > {name}.pid\nexec {program}\n"),
    )
    .unwrap();
    format!("sh wrap-{name}.sh")
}

/// Everything a strategy program starts is ended with it: at the run's end, on a timeout, and
/// when `strategy check` finds it left processes behind, which fails the check.
#[test]
fn a_programs_children_end_with_it() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    let stops = python_module_strategy(tmp);
    let hang = format!(
        "python3 {}",
        repo().join("tests/strategies/hang.py").display()
    );
    // (name, what it starts in the background, program, extra arguments, whether explore
    // succeeds): `setsid` leaves the program's process group and session.
    let cases: &[(&str, &str, &str, &[&str], bool)] = &[
        ("end", "sleep 1000", &stops, &[], true),
        (
            "timeout",
            "sleep 1000",
            &hang,
            &["--strategy-timeout-s", "1"],
            false,
        ),
        ("setsid-end", "setsid sleep 1000", &stops, &[], true),
        (
            "setsid-timeout",
            "setsid sleep 1000",
            &hang,
            &["--strategy-timeout-s", "1"],
            false,
        ),
    ];
    for (name, background, program, extra, ok) in cases {
        let command = wrapper_starting(tmp, name, background, program);
        let o = floorcast()
            .args(["explore", "--building"])
            .arg(repo().join("buildings/small.toml"))
            .args(["--seed", "1", "--quiet", "--out", name])
            .args(["--strategy-command", &command])
            .args(*extra)
            .current_dir(tmp)
            .output()
            .unwrap();
        assert_eq!(o.status.success(), *ok, "{name}: {}", stderr(&o));
        let (pid, gone) = ended_soon(&tmp.join(format!("{name}.pid")));
        assert!(gone, "{name}: the program's child {pid} still runs");
    }
    for (name, background) in [
        ("check", "sleep 1000"),
        ("check-setsid", "setsid sleep 1000"),
    ] {
        let command = wrapper_starting(tmp, name, background, &stops);
        let o = floorcast()
            .args(["strategy", "check", &command])
            .current_dir(tmp)
            .output()
            .unwrap();
        assert_clean_failure(
            &o,
            &[
                &format!("wrap-{name}.sh"),
                "left processes it started running",
            ],
        );
        let (pid, gone) = ended_soon(&tmp.join(format!("{name}.pid")));
        assert!(gone, "{name}: the program's child {pid} still runs");
    }
}

/// A floorcast ended by SIGTERM or SIGHUP (a shell closing, `kill`, a batch system's timeout)
/// ends every strategy program it runs with everything they started, and leaves no output.
#[test]
fn a_terminated_floorcast_ends_its_programs() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    let hang = format!(
        "python3 {}",
        repo().join("tests/strategies/hang.py").display()
    );
    for (name, signal) in [("term", "TERM"), ("hup", "HUP")] {
        let command = wrapper_starting(tmp, name, "setsid sleep 1000", &hang);
        let mut child = floorcast()
            .args(["explore", "--building"])
            .arg(repo().join("buildings/small.toml"))
            .args(["--seed", "1", "--quiet", "--out", name])
            .args(["--strategy-command", &command, "--strategy-timeout-s", "60"])
            .current_dir(tmp)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let pid_file = tmp.join(format!("{name}.pid"));
        let t0 = std::time::Instant::now();
        while !pid_file.is_file() && t0.elapsed() < std::time::Duration::from_secs(20) {
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
        // The program is waiting for its first decision by now, or soon.
        std::thread::sleep(std::time::Duration::from_millis(500));
        send_signal(child.id(), signal);
        let status = child.wait().unwrap();
        assert!(!status.success(), "{name}: {status:?}");
        let (pid, gone) = ended_soon(&pid_file);
        assert!(gone, "{name}: the program's child {pid} still runs");
        assert!(!tmp.join(name).exists(), "{name}: output left");
    }
}

/// Output to a full disk (`/dev/full` as stdout) is an error for every command that prints: one
/// line, exit code 2; a closed pipe (`| head -1`) ends the program quietly with exit code 0.
#[test]
fn failed_writes_to_stdout_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    let res = results(tmp);
    let grid = tmp.join("grid.toml");
    let small = repo().join("buildings/small.toml");
    let (res, grid, small) = (
        res.to_str().unwrap(),
        grid.to_str().unwrap(),
        small.to_str().unwrap(),
    );
    let cases: &[&[&str]] = &[
        &["report", res],
        &["settings"],
        &["settings", "--markdown"],
        &["run", grid, "--results", res, "--summary"],
        &["run", grid, "--results", res],
        &[
            "explore",
            "--building",
            small,
            "--out",
            "out",
            "--time-limit-s",
            "20",
        ],
        &["building", "check", small],
        &["--help"],
        &["report", "--help"],
        &["--version"],
    ];
    let mut failures = Vec::new();
    for args in cases {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let o = floorcast()
            .args(*args)
            .current_dir(tmp)
            .stdout(full)
            .output()
            .unwrap();
        let err = stderr(&o);
        if o.status.code() != Some(2)
            || err.trim().lines().count() != 1
            || !err.starts_with("error: cannot write to stdout")
            || !err.contains("No space left on device")
        {
            failures.push(format!(
                "{args:?} to /dev/full: {:?} {err}",
                o.status.code()
            ));
        }
        let mut child = floorcast()
            .args(*args)
            .current_dir(tmp)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        let o = child.wait_with_output().unwrap();
        let err = stderr(&o);
        if o.status.code() != Some(0) || !err.is_empty() {
            failures.push(format!(
                "{args:?} to a closed pipe: {:?} {err}",
                o.status.code()
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// One `run` per results directory: while another process holds the lock, `run` is refused at
/// once, naming the holder, and runs no job; `report` needs no lock.
#[test]
fn a_second_run_is_refused() {
    use std::io::Write;
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    let res = results(tmp);
    let before = rows_csv(tmp, &res);
    let grid = tmp.join("grid.toml");
    let two_seeds = std::fs::read_to_string(&grid)
        .unwrap()
        .replace("seeds = [1]", "seeds = [1, 2]");
    std::fs::write(&grid, two_seeds).unwrap();
    let mut lock = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .open(res.join("floorcast.lock"))
        .unwrap();
    lock.try_lock().unwrap();
    writeln!(lock, "pid 4242 on host elsewhere\x1b[31m").unwrap();
    let t0 = std::time::Instant::now();
    let o = run_grid(&grid, &res);
    assert_clean_failure(
        &o,
        &[
            res.to_str().unwrap(),
            "in use by another floorcast run (pid 4242 on host elsewhere",
            "wait for it to end or stop it",
        ],
    );
    assert!(!stderr(&o).contains('\x1b'), "{}", stderr(&o));
    assert!(t0.elapsed() < std::time::Duration::from_secs(10));
    // No job ran; report reads the store while the lock is held.
    assert_eq!(rows_csv(tmp, &res), before);
    drop(lock);
    let o = run_grid(&grid, &res);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(rows_csv(tmp, &res).lines().count(), 5);
    // The lock says who held it last.
    let text = std::fs::read_to_string(res.join("floorcast.lock")).unwrap();
    assert!(
        text.starts_with("pid ") && text.contains(" on host "),
        "{text}"
    );
}

/// Whether `text` holds a control character other than the line feeds that end lines.
fn has_controls(text: &str) -> bool {
    text.chars().any(|c| c.is_control() && c != '\n')
}

/// A program's ESC, BEL and NUL bytes (and a 200 KB line) on its stderr or stdout, before it
/// crashes, reach neither floorcast's stderr nor the store's `error` raw: escaped, and echoed
/// only in part.
#[test]
fn a_programs_control_bytes_are_escaped() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    let noise = r#""red \x1b[31m bell \x07 nul \x00 c1 \xc2\x9b " + "x" * 200000 + "\n""#;
    // (name, what the program does, words of the error)
    let cases = [
        (
            "stderr",
            format!("sys.stderr.write({noise})\nsys.stderr.flush()\nsys.exit(3)\n"),
            "its last stderr line: 'red \\x1b[31m bell \\x07 nul \\x00",
        ),
        (
            "stdout",
            format!("sys.stdout.write({noise})\nsys.stdout.flush()\nsys.exit(3)\n"),
            "not a protocol message: 'red \\x1b[31m bell \\x07 nul \\x00",
        ),
    ];
    for (name, body, words) in &cases {
        std::fs::write(
            tmp.join(format!("{name}.py")),
            format!("import sys\n{body}"),
        )
        .unwrap();
        let command = format!("python3 {name}.py");
        let o = floorcast()
            .args(["explore", "--building"])
            .arg(repo().join("buildings/small.toml"))
            .args(["--quiet", "--out", name, "--strategy-command", &command])
            .current_dir(tmp)
            .output()
            .unwrap();
        assert_clean_failure(&o, &[words]);
        assert!(!has_controls(&stderr(&o)), "{name}: {:?}", stderr(&o));
        assert!(o.stderr.len() < 1000, "{name}: {} bytes", o.stderr.len());
        // The same program in a grid: the stored error, and what run prints.
        std::fs::write(
            tmp.join(format!("{name}.toml")),
            format!(
                "format = \"floorcast-grid\"\nversion = 1\nname = \"{name}\"\nbuildings = [\"{}\"]\nseeds = [1]\n[[strategies]]\nlabel = \"noisy\"\ncommand = [\"python3\", \"{name}.py\"]\n",
                repo().join("buildings/small.toml").display()
            ),
        )
        .unwrap();
        let res = tmp.join(format!("res-{name}"));
        let o = run_grid(&tmp.join(format!("{name}.toml")), &res);
        assert_eq!(o.status.code(), Some(2), "{name}: {}", stderr(&o));
        assert!(stderr(&o).contains(words), "{name}: {}", stderr(&o));
        assert!(!has_controls(&stderr(&o)), "{name}: {:?}", stderr(&o));
        let stored = std::process::Command::new("python3")
            .arg("-c")
            .arg("import sqlite3, sys; sys.stdout.write(sqlite3.connect(sys.argv[1]).execute('SELECT error FROM results').fetchone()[0])")
            .arg(res.join("results.sqlite"))
            .output()
            .unwrap();
        let error = String::from_utf8(stored.stdout).unwrap();
        assert!(error.contains(words), "{name}: {error}");
        assert!(!has_controls(&error), "{name}: {error:?}");
        assert!(error.len() < 1000, "{name}: {} bytes", error.len());
    }
}

/// The names in `dir`, sorted.
fn names_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|r| {
            r.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// `explore` of small.toml into `out` (in `cwd`) with `extra` arguments.
fn explore_into(cwd: &Path, out: &str, extra: &[&str]) -> std::process::Output {
    floorcast()
        .args(["explore", "--building"])
        .arg(repo().join("buildings/small.toml"))
        .args(["--quiet", "--out", out])
        .args(extra)
        .current_dir(cwd)
        .output()
        .unwrap()
}

/// A reused `--out` keeps no output of an earlier run that this one did not make (layout
/// snapshots), keeps files that are not explore's, and no staging folder is left beside it.
#[test]
fn a_reused_out_holds_one_runs_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    let o = explore_into(tmp, "out", &["--layout-snapshots"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(tmp.join("out/layout-90.png").is_file());
    std::fs::write(tmp.join("out/notes.txt"), "mine").unwrap();
    let o = explore_into(tmp, "out", &["--seed", "2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let names = names_in(&tmp.join("out"));
    assert!(!names.iter().any(|n| n.starts_with("layout-")), "{names:?}");
    assert!(names.contains(&"notes.txt".to_string()), "{names:?}");
    let summary = std::fs::read_to_string(tmp.join("out/summary.json")).unwrap();
    assert!(summary.contains("\"seed\": 2"), "{summary}");
    assert_eq!(names_in(tmp), vec!["out".to_string()]);
}

/// A second `explore` into a `--out` another is writing is refused at once and writes nothing.
#[test]
fn a_second_explore_into_one_out_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    std::fs::create_dir(tmp.join("out")).unwrap();
    let lock = std::fs::File::open(tmp.join("out")).unwrap();
    lock.try_lock().unwrap();
    let o = explore_into(tmp, "out", &[]);
    assert_clean_failure(&o, &["--out", "out", "another floorcast explore"]);
    assert!(names_in(&tmp.join("out")).is_empty());
    assert_eq!(names_in(tmp), vec!["out".to_string()]);
}

/// An `explore` stopped mid-run (Ctrl-C) or failing leaves no output: no `--out` directory and
/// no staging folder.
#[test]
fn a_stopped_or_failed_explore_leaves_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    let hang = format!(
        "python3 {}",
        repo().join("tests/strategies/hang.py").display()
    );
    let mut child = floorcast()
        .args(["explore", "--building"])
        .arg(repo().join("buildings/small.toml"))
        .args(["--quiet", "--out", "stopped", "--strategy-command", &hang])
        .args(["--strategy-timeout-s", "60"])
        .current_dir(tmp)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    while !names_in(tmp).iter().any(|n| n.contains(".partial-")) {
        assert!(
            t0.elapsed() < std::time::Duration::from_secs(30),
            "no staging folder"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(300));
    send_signal(child.id(), "INT");
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130));
    assert!(names_in(tmp).is_empty(), "{:?}", names_in(tmp));
    let o = explore_into(
        tmp,
        "failed",
        &["--strategy-command", &hang, "--strategy-timeout-s", "1"],
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(!tmp.join("failed").exists());
    assert!(
        !names_in(tmp).iter().any(|n| n.contains("failed")),
        "{:?}",
        names_in(tmp)
    );
}
