//! Nothing lost, round two (issue 78): every write to stdout and stderr checked, one rule for
//! every path floorcast writes, `run --import` lines verified against their jobs, a store
//! floorcast created but could not finish completed.

mod common;

use std::path::{Path, PathBuf};

use common::*;

/// The crates' non-test sources: every `.rs` file under their `src/`, cut at its test module
/// (`#[cfg(test)]` then `mod`), test-module files (`tests.rs`) left out.
fn non_test_sources() -> Vec<(PathBuf, String)> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs")
                && p.file_name().is_some_and(|n| n != "tests.rs")
            {
                out.push(p);
            }
        }
    }
    let mut files = Vec::new();
    for c in [
        "src",
        "stats/src",
        "coordinator/src",
        "worker/src",
        "settings/src",
        "formats/src",
        "render/src",
        "sim-core/src",
    ] {
        walk(&repo().join(c), &mut files);
    }
    assert!(files.len() > 50, "too few sources found: {}", files.len());
    files.sort();
    files
        .into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(&p).unwrap();
            let lines: Vec<&str> = text.lines().collect();
            let end = (0..lines.len())
                .find(|&i| {
                    lines[i].trim() == "#[cfg(test)]"
                        && lines.get(i + 1).is_some_and(|l| {
                            l.trim_start().starts_with("mod ")
                                || l.trim_start().starts_with("pub(crate) mod ")
                        })
                })
                .unwrap_or(lines.len());
            (p, lines[..end].join("\n"))
        })
        .collect()
}

/// The unchecked print macros used in `text` (comments left out): `(line, macro)`.
fn unchecked_prints(text: &str) -> Vec<(usize, String)> {
    const MACROS: [&str; 5] = ["println!", "eprintln!", "print!", "eprint!", "dbg!"];
    let mut found = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let code = line.split("//").next().unwrap_or("");
        for m in MACROS {
            let mut from = 0;
            while let Some(i) = code[from..].find(m) {
                let at = from + i;
                let before = code[..at].chars().next_back();
                if !before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                    found.push((n + 1, m.to_string()));
                }
                from = at + m.len();
            }
        }
    }
    found
}

#[test]
fn the_grep_finds_what_it_looks_for() {
    let cases: [(&str, &[&str]); 7] = [
        ("    eprintln!(\"x\");", &["eprintln!"]),
        ("println!(\"{x}\")", &["println!"]),
        ("let _ = dbg!(x); print!(\"a\");", &["dbg!", "print!"]),
        ("    eprint!(\"no newline\")", &["eprint!"]),
        ("say!(\"x\"); tell!(\"y\"); say_raw!(\"z\")", &[]),
        ("// eprintln!(\"in a comment\")", &[]),
        ("/// `println!` that survives a closed pipe", &[]),
    ];
    for (text, want) in cases {
        let mut got: Vec<String> = unchecked_prints(text).into_iter().map(|(_, m)| m).collect();
        got.sort();
        let mut want = want.to_vec();
        want.sort_unstable();
        assert_eq!(got, want, "{text}");
    }
}

/// No `println!`, `eprintln!`, `print!`, `eprint!` or `dbg!` outside tests: every write to
/// stdout goes through `say!`/`say_raw!` (a closed pipe ends quietly, a full disk is an error)
/// and every write to stderr through `tell!` (a failed write never panics).
#[test]
fn every_print_goes_through_the_checked_writer() {
    let mut bad = Vec::new();
    for (path, text) in non_test_sources() {
        for (line, m) in unchecked_prints(&text) {
            bad.push(format!(
                "{}:{line}: {m}",
                path.strip_prefix(repo()).unwrap().display()
            ));
        }
    }
    assert!(
        bad.is_empty(),
        "use say!/say_raw!/tell! (src/output.rs) instead:\n{}",
        bad.join("\n")
    );
}

/// `floorcast ARGS` with stderr on /dev/full (a device that refuses every write).
fn with_full_stderr(args: &[&str], cwd: &Path) -> std::process::Output {
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .expect("/dev/full (Linux) is there");
    floorcast()
        .args(args)
        .current_dir(cwd)
        .stderr(full)
        .output()
        .unwrap()
}

/// A failed write to stderr never panics: an error still exits 2, a warning after the results
/// were written leaves them and exit code 0.
#[test]
fn stderr_on_a_full_device_never_panics() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    // An error: exit code 2, not a panic's 101.
    for args in [
        &["building", "check", "missing.toml"][..],
        &["report", "no-such-results"],
        &["run", "--no-such-flag"],
    ] {
        let o = with_full_stderr(args, tmp);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
    }
    // explore's "ended short" warning, after its results were written.
    let small = repo().join("buildings/small.toml");
    let out = tmp.join("short");
    let o = with_full_stderr(
        &[
            "explore",
            "--building",
            small.to_str().unwrap(),
            "--time-limit-s",
            "5",
            "--out",
            out.to_str().unwrap(),
        ],
        tmp,
    );
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(summary.contains("time_limit"), "{summary}");
    // The same run with stderr readable does warn (the case above did reach the warning).
    let out2 = tmp.join("short2");
    let o = run(&[
        "explore",
        "--building",
        small.to_str().unwrap(),
        "--time-limit-s",
        "5",
        "--out",
        out2.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("ended short"), "{}", stderr(&o));
}

/// A one-job grid (baseline on small.toml, seed `seed`, 30 s simulated) in `dir`, its results
/// in `dir/res-NAME` unless `--results` is given.
fn one_job_grid(dir: &Path, name: &str, seed: u64) -> PathBuf {
    let grid = dir.join(format!("{name}.toml"));
    std::fs::write(
        &grid,
        format!(
            "format = \"floorcast-grid\"\nversion = 1\nname = \"{name}\"\nbuildings = [\"{}\"]\nseeds = [{seed}]\nresults = \"{}\"\n[[strategies]]\nname = \"baseline\"\n[settings]\ntime_limit_s = 30\n",
            repo().join("buildings/small.toml").display(),
            dir.join(format!("res-{name}")).display()
        ),
    )
    .unwrap();
    grid
}

/// Runs `grid` (into `results` if given), asserting success; returns stdout.
fn run_ok(grid: &Path, results: Option<&Path>, more: &[&str]) -> String {
    let mut args = vec!["run", grid.to_str().unwrap(), "--quiet"];
    if let Some(r) = results {
        args.extend(["--results", r.to_str().unwrap()]);
    }
    args.extend(more);
    let o = run(&args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    stdout(&o)
}

/// The bytes of every file in `dir` (by name), to show nothing there changed.
fn snapshot(dir: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect()
}

/// No command writes a file it reads (a store, `--against`'s store and their files, a building,
/// a settings file, a grid) nor one of its own outputs twice; each refusal is one line naming
/// the flag and what the path is, exit code 2, and every input is left as it was.
#[test]
#[allow(clippy::too_many_lines)] // a table of cases
fn no_output_is_an_input_or_another_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let grid = one_job_grid(d, "g", 1);
    let (a, b) = (d.join("res-a"), d.join("res-b"));
    run_ok(&grid, Some(&a), &[]);
    run_ok(&grid, Some(&b), &[]);
    let building = d.join("b.toml");
    std::fs::copy(repo().join("buildings/small.toml"), &building).unwrap();
    let settings = d.join("s.json");
    std::fs::write(&settings, "{\"time_limit_s\": 30}\n").unwrap();
    std::os::unix::fs::symlink("res-b/results.sqlite", d.join("b-link")).unwrap();
    std::os::unix::fs::symlink("b.toml", d.join("building-link.json")).unwrap();
    let p = |x: &str| d.join(x).to_str().unwrap().to_string();
    let (a_s, b_s) = (p("res-a"), p("res-b"));
    // (arguments, words of the refusal)
    let cases: Vec<(Vec<String>, Vec<&str>)> = [
        (
            vec![
                "report",
                &a_s,
                "--against",
                &b_s,
                "--csv",
                &p("res-b/results.sqlite"),
            ],
            vec![
                "--csv",
                "results.sqlite",
                "a file floorcast owns",
                "--against",
            ],
        ),
        (
            vec!["report", &a_s, "--against", &b_s, "--json", &p("b-link")],
            vec!["--json", "b-link", "a file floorcast owns"],
        ),
        (
            vec![
                "report",
                &a_s,
                "--against",
                &b_s,
                "--html",
                &p("res-b/floorcast.lock"),
            ],
            vec!["--html", "floorcast.lock"],
        ),
        (
            vec![
                "report",
                &a_s,
                "--against",
                &b_s,
                "--export-runs",
                &p("res-b/results.sqlite-wal"),
            ],
            vec!["--export-runs", "results.sqlite-wal"],
        ),
        (
            vec![
                "report",
                &a_s,
                "--against",
                &format!("{b_s}/../res-b"),
                "--csv",
                &p("res-b/./results.sqlite"),
            ],
            vec!["--csv", "a file floorcast owns"],
        ),
        (
            vec!["report", &a_s, "--csv", &p("x.out"), "--json", &p("x.out")],
            vec!["--csv and --json are the same file"],
        ),
        (
            vec![
                "report",
                &a_s,
                "--json",
                &p("y.out"),
                "--export-runs",
                &format!(
                    "{}/../{}/y.out",
                    d.display(),
                    d.file_name().unwrap().to_string_lossy()
                ),
            ],
            vec!["--json and --export-runs are the same file"],
        ),
        (
            vec!["tour", "--building", &p("b.toml"), "--json", &p("b.toml")],
            vec!["--json", "b.toml", "which this command reads", "--building"],
        ),
        (
            vec![
                "tour",
                "--building",
                &p("b.toml"),
                "--json",
                &p("building-link.json"),
            ],
            vec!["--json", "which this command reads"],
        ),
        (
            vec![
                "tour",
                "--building",
                &p("b.toml"),
                "--settings",
                &p("s.json"),
                "--picture",
                &p("s.json"),
            ],
            vec!["--picture", "--settings"],
        ),
        (
            vec![
                "tour",
                "--building",
                &p("b.toml"),
                "--json",
                &p("t.svg"),
                "--picture",
                &p("t.svg"),
            ],
            vec!["--json and --picture are the same file"],
        ),
        (
            vec!["building", "render", &p("b.toml"), "--out", &p("b.toml")],
            vec!["--out", "which this command reads"],
        ),
    ]
    .into_iter()
    .map(|(args, needles)| (args.into_iter().map(str::to_string).collect(), needles))
    .collect();
    let before = (snapshot(&a), snapshot(&b), snapshot(d));
    for (args, needles) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = run(&args);
        assert_clean_failure(&o, needles);
        assert_eq!(
            before,
            (snapshot(&a), snapshot(&b), snapshot(d)),
            "{args:?} changed a file"
        );
    }
    // An explore whose --out holds its building under an output's name is refused.
    let out = d.join("ex");
    std::fs::create_dir(&out).unwrap();
    std::fs::copy(
        repo().join("maps/radish/intel_map.yaml"),
        out.join("map.yaml"),
    )
    .unwrap();
    std::fs::copy(
        repo().join("maps/radish/intel_map.pgm"),
        out.join("intel_map.pgm"),
    )
    .unwrap();
    let yaml = std::fs::read(out.join("map.yaml")).unwrap();
    let o = run(&[
        "explore",
        "--building",
        out.join("map.yaml").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_clean_failure(&o, &["--out's map.yaml", "which this command reads"]);
    assert_eq!(std::fs::read(out.join("map.yaml")).unwrap(), yaml);
    // An import that is the results directory's lock (which `run` writes).
    let res = d.join("res-lockimport");
    std::fs::create_dir(&res).unwrap();
    std::fs::write(res.join("floorcast.lock"), "not yet\n").unwrap();
    let o = run(&[
        "run",
        grid.to_str().unwrap(),
        "--import",
        res.join("floorcast.lock").to_str().unwrap(),
        "--results",
        res.to_str().unwrap(),
    ]);
    assert_clean_failure(
        &o,
        &[
            "--results",
            "floorcast.lock",
            "--import",
            "which this command reads",
        ],
    );
    assert_eq!(
        std::fs::read_to_string(res.join("floorcast.lock")).unwrap(),
        "not yet\n"
    );
}

/// Outputs that are symbolic links are written through to their targets (the links stay);
/// devices are written directly (`/dev/stdout`, `/dev/null`), never replaced.
#[test]
fn symlinked_outputs_are_written_through() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let grid = one_job_grid(d, "g", 1);
    let a = d.join("res-a");
    run_ok(&grid, Some(&a), &[]);
    std::fs::create_dir(d.join("real")).unwrap();
    for (flag, name) in [
        ("--csv", "x.csv"),
        ("--json", "x.json"),
        ("--export-runs", "x.gz"),
        ("--html", "x.html"),
    ] {
        let link = d.join(format!("link-{name}"));
        std::os::unix::fs::symlink(format!("real/{name}"), &link).unwrap();
        let o = run(&["report", a.to_str().unwrap(), flag, link.to_str().unwrap()]);
        assert!(o.status.success(), "{flag}: {}", stderr(&o));
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink(),
            "{flag}: the link was replaced"
        );
        let written = std::fs::read(d.join("real").join(name)).unwrap();
        assert!(
            !written.is_empty(),
            "{flag}: nothing written through the link"
        );
        // Nothing left beside the link or the target.
        let left: Vec<_> = std::fs::read_dir(d)
            .unwrap()
            .chain(std::fs::read_dir(d.join("real")).unwrap())
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains(".part-"))
            .collect();
        assert!(left.is_empty(), "{flag}: {left:?}");
    }
    // The export to /dev/stdout: its bytes on stdout, /dev/stdout still a link.
    let o = run(&[
        "report",
        a.to_str().unwrap(),
        "--export-runs",
        "/dev/stdout",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        o.stdout.windows(2).any(|w| w == [0x1f, 0x8b]),
        "no gzip data on stdout"
    );
    assert!(std::fs::symlink_metadata("/dev/stdout")
        .unwrap()
        .file_type()
        .is_symlink());
    let o = run(&[
        "report",
        a.to_str().unwrap(),
        "--csv",
        "/dev/null",
        "--json",
        d.join("r.json").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::metadata("/dev/null")
        .unwrap()
        .file_type()
        .is_char_device());
}

/// A results directory's lock that is a symbolic link (or not a regular file) is refused, its
/// target never written.
#[test]
fn a_symlinked_lock_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let grid = one_job_grid(d, "g", 1);
    let victim = d.join("victim.txt");
    std::fs::write(&victim, "precious\n").unwrap();
    type Make = fn(&Path, &Path);
    let cases: [(&str, Make, &str); 3] = [
        (
            "link",
            |res, v| std::os::unix::fs::symlink(v, res.join("floorcast.lock")).unwrap(),
            "a symbolic link",
        ),
        (
            "dangling",
            |res, _| {
                std::os::unix::fs::symlink("nowhere/lock", res.join("floorcast.lock")).unwrap()
            },
            "a symbolic link",
        ),
        (
            "dir",
            |res, _| std::fs::create_dir(res.join("floorcast.lock")).unwrap(),
            "not a regular file",
        ),
    ];
    for (what, make, said) in cases {
        let res = d.join(format!("res-{what}"));
        std::fs::create_dir(&res).unwrap();
        make(&res, &victim);
        let o = run(&[
            "run",
            grid.to_str().unwrap(),
            "--quiet",
            "--results",
            res.to_str().unwrap(),
        ]);
        assert_clean_failure(&o, &["floorcast.lock", said, "remove it"]);
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious\n");
        assert!(
            !res.join("results.sqlite").exists(),
            "{what}: a store was made"
        );
    }
    assert!(!d.join("nowhere").exists());
}

/// The decompressed lines of a `--export-runs` file.
fn export_lines(file: &Path) -> Vec<String> {
    let mut text = String::new();
    std::io::Read::read_to_string(
        &mut flate2::read::GzDecoder::new(std::fs::File::open(file).unwrap()),
        &mut text,
    )
    .unwrap();
    text.lines().map(str::to_string).collect()
}

fn gzip(text: &str) -> Vec<u8> {
    use std::io::Write;
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(text.as_bytes()).unwrap();
    e.finish().unwrap()
}

/// `run --import` checks every line that claims a job of the grid against that job: each forged
/// field is refused naming the file, the line and the field, nothing of the file is stored, and
/// the same `run` then runs its own grid. Data after the gzip stream is refused, and a FIFO at
/// once (it would block).
#[test]
#[allow(clippy::too_many_lines)] // a table of cases
fn forged_import_lines_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let grid = one_job_grid(d, "g", 1);
    let a = d.join("res-a");
    run_ok(&grid, Some(&a), &[]);
    let file = d.join("runs.gz");
    let o = run(&[
        "report",
        a.to_str().unwrap(),
        "--export-runs",
        file.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let lines = export_lines(&file);
    assert_eq!(lines.len(), 3, "header, the run, its tour: {lines:?}");
    let run_line: serde_json::Value = serde_json::from_str(&lines[1]).unwrap();
    assert!(run_line.get("run").is_some(), "{}", lines[1]);
    // The untouched file is taken whole.
    let res = d.join("res-good");
    let out = run_ok(&grid, Some(&res), &["--import", file.to_str().unwrap()]);
    assert!(out.contains("1 of its 1 runs stored"), "{out}");
    type Forge = fn(&mut serde_json::Value);
    // (what is forged, how, words of the refusal)
    let cases: Vec<(&str, Forge, &[&str])> = vec![
        (
            "building_hash",
            |r| r["building_hash"] = "0123456789abcdef0123456789abcdef".into(),
            &["building_hash"],
        ),
        (
            "strategy",
            |r| {
                r["strategy"] = "nearest".into();
                r["summary"]["strategy"] = "nearest".into();
            },
            &["strategy", "nearest"],
        ),
        (
            "seed",
            |r| {
                r["seed"] = 2.into();
                r["summary"]["seed"] = 2.into();
            },
            &["seed"],
        ),
        (
            "seed 2^64-1",
            |r| {
                r["seed"] = u64::MAX.into();
                r["summary"]["seed"] = u64::MAX.into();
            },
            &["seed", "18446744073709551615"],
        ),
        (
            "settings",
            |r| {
                r["settings"]["alpha"] = 0.3.into();
                r["summary"]["settings"]["alpha"] = 0.3.into();
            },
            &["settings"],
        ),
        (
            "summary settings",
            |r| r["summary"]["settings"]["max_speed_mps"] = 0.9.into(),
            &["settings"],
        ),
        (
            "start",
            |r| r["summary"]["start"][0] = 1.25.into(),
            &["start"],
        ),
        (
            "version",
            |r| {
                r["floorcast_version"] = "0.6.0".into();
                r["summary"]["floorcast_version"] = "0.6.0".into();
            },
            &["floorcast_version", "0.6.0"],
        ),
        (
            "a 1 s exploration at 100 %",
            |r| {
                let s = &mut r["summary"];
                s["exploration_time_s"] = 1.0.into();
                s["total_time_s"] = 1.0.into();
                s["explored_fraction"] = 1.0.into();
                s["explored_area_m2"] = s["free_area_m2"].clone();
                s["unexplored_free_m2"] = 0.0.into();
                s["end_reason"] = "complete".into();
            },
            &["summary", "explored_fraction"],
        ),
        (
            "a shorter time",
            |r| {
                r["summary"]["exploration_time_s"] = 3.0.into();
                r["summary"]["total_time_s"] = 3.0.into();
            },
            &["summary.exploration_time_s", "progress curve ends"],
        ),
        (
            "a curve going back in time",
            |r| {
                let p = r["progress"].as_str().unwrap().to_string();
                let mut rows: Vec<&str> = p.lines().collect();
                rows.swap(2, 3);
                r["progress"] = (rows.join("\n") + "\n").into();
            },
            &["progress", "before the one before it"],
        ),
        (
            "wall time",
            |r| r["wall_time_s"] = (-1.0).into(),
            &["wall_time_s"],
        ),
    ];
    let forged = d.join("forged.gz");
    for (what, forge, needles) in &cases {
        let mut v = run_line.clone();
        forge(&mut v["run"]);
        let text = format!("{}\n{}\n{}\n", lines[0], v, lines[2]);
        std::fs::write(&forged, gzip(&text)).unwrap();
        let res = d.join(format!("res-{}", what.replace([' ', '^', '%'], "-")));
        let o = run(&[
            "run",
            grid.to_str().unwrap(),
            "--quiet",
            "--import",
            forged.to_str().unwrap(),
            "--results",
            res.to_str().unwrap(),
        ]);
        let mut all = needles.to_vec();
        all.extend(["forged.gz", "line 2"]);
        assert_clean_failure(&o, &all);
        // Nothing of it was stored (a store without rows, or none at all).
        if res.join("results.sqlite").exists() {
            let o = run(&["report", res.to_str().unwrap()]);
            assert!(
                stdout(&o).starts_with("0 results"),
                "{what}: {}",
                stdout(&o)
            );
        }
    }
    // The same run then accepts its own grid.
    let res = d.join("res-seed");
    let out = run_ok(&grid, Some(&res), &[]);
    assert!(!out.contains("import"), "{out}");
    assert_eq!(report_rows(&res).len(), 1);
    // A job given twice.
    let text = format!(
        "{}\n{}\n{}\n{}\n",
        lines[0].replace("\"runs\":1", "\"runs\":2"),
        lines[1],
        lines[1],
        lines[2]
    );
    std::fs::write(&forged, gzip(&text)).unwrap();
    let o = run(&[
        "run",
        grid.to_str().unwrap(),
        "--quiet",
        "--import",
        forged.to_str().unwrap(),
        "--results",
        d.join("res-twice").to_str().unwrap(),
    ]);
    assert_clean_failure(&o, &["forged.gz", "line 3", "again", "line 2"]);
    // Data after the gzip stream: another member, or bytes appended.
    let good = std::fs::read(&file).unwrap();
    for (what, tail) in [
        ("a second member", gzip(&lines[1])),
        ("bytes", b"junk\n".to_vec()),
        ("one zero byte", vec![0]),
    ] {
        let mut bytes = good.clone();
        bytes.extend(&tail);
        std::fs::write(&forged, bytes).unwrap();
        let o = run(&[
            "run",
            grid.to_str().unwrap(),
            "--quiet",
            "--import",
            forged.to_str().unwrap(),
            "--results",
            d.join("res-tail").to_str().unwrap(),
        ]);
        assert_clean_failure(
            &o,
            &[
                "--import",
                "forged.gz",
                "bytes follow the end of its gzip stream",
            ],
        );
        assert!(!d.join("res-tail").exists(), "{what}: nothing is made");
    }
    // A FIFO is refused at once (opening it would wait for a writer).
    let fifo = d.join("fifo.gz");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo (coreutils) runs");
    assert!(made.success());
    let mut child = floorcast()
        .args([
            "run",
            grid.to_str().unwrap(),
            "--quiet",
            "--import",
            fifo.to_str().unwrap(),
            "--results",
            d.join("res-fifo").to_str().unwrap(),
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let t = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t.elapsed() > std::time::Duration::from_secs(20) {
            child.kill().unwrap();
            panic!("run --import FIFO did not end within 20 s");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let o = child.wait_with_output().unwrap();
    assert_clean_failure(&o, &["--import", "fifo.gz", "not a regular file"]);
}

/// A store floorcast created but could not finish (its disk was full: the SQLite header, no
/// table; or not even that, an empty file) in a folder a run used is recognised: `report` says
/// what it is and what completes it, `run` completes it and says so.
#[test]
fn a_half_made_store_is_completed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let grid = one_job_grid(d, "g", 1);
    type Make = fn(&Path);
    let cases: [(&str, Make); 2] = [
        ("header only", |p| {
            let c = rusqlite::Connection::open(p).unwrap();
            let mode: String = c
                .query_row("PRAGMA journal_mode = WAL", [], |r| r.get(0))
                .unwrap();
            assert_eq!(mode, "wal");
            drop(c);
            let len = std::fs::metadata(p).unwrap().len();
            assert!(len > 0 && len <= 4096, "{len} bytes");
        }),
        ("empty file", |p| std::fs::write(p, b"").unwrap()),
    ];
    for (what, make) in cases {
        let res = d.join(format!("res-{}", what.replace(' ', "-")));
        std::fs::create_dir(&res).unwrap();
        std::fs::write(res.join("floorcast.lock"), "pid 1 on host x\n").unwrap();
        make(&res.join("results.sqlite"));
        let o = run(&["report", res.to_str().unwrap()]);
        assert_clean_failure(
            &o,
            &["created by floorcast but never finished", "completes it"],
        );
        let out = run_ok(&grid, Some(&res), &[]);
        assert!(out.contains("is now complete"), "{what}: {out}");
        assert_eq!(report_rows(&res).len(), 1, "{what}");
    }
    // Without a run's lock beside it, a database without tables is not taken for one.
    let res = d.join("res-foreign");
    std::fs::create_dir(&res).unwrap();
    rusqlite::Connection::open(res.join("results.sqlite"))
        .unwrap()
        .execute_batch("PRAGMA user_version = 7;")
        .unwrap();
    let o = run(&[
        "run",
        grid.to_str().unwrap(),
        "--quiet",
        "--results",
        res.to_str().unwrap(),
    ]);
    assert_clean_failure(&o, &["not a floorcast results store"]);
}

/// `explore --out LINK`, a link to a directory, writes into the directory; the link stays.
#[test]
fn explore_writes_through_a_linked_out() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (what, existing) in [("new", false), ("holding files", true)] {
        let real = d.join(format!("real-{}", what.replace(' ', "-")));
        std::fs::create_dir(&real).unwrap();
        if existing {
            std::fs::write(real.join("notes.txt"), "mine\n").unwrap();
        }
        let link = d.join(format!("link-{}", what.replace(' ', "-")));
        std::os::unix::fs::symlink(&real, &link).unwrap();
        let o = run(&[
            "explore",
            "--building",
            repo().join("buildings/small.toml").to_str().unwrap(),
            "--time-limit-s",
            "5",
            "--quiet",
            "--out",
            link.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{what}: {}", stderr(&o));
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink(),
            "{what}: the link was replaced"
        );
        assert!(
            real.join("summary.json").is_file(),
            "{what}: no summary in the link's target"
        );
        assert_eq!(existing, real.join("notes.txt").exists(), "{what}");
    }
}
