//! A leaderboard's runs travel with the repository (issue 58): `report DIR --export-runs FILE`
//! writes a store's runs and tours, `run GRID --import FILE` stores those that are jobs of the
//! grid and runs only the others; the report of the merged store shows the imported runs as
//! their own store did. A damaged file is refused with the line and what was expected.

mod common;

use std::io::Write;
use std::path::Path;

use common::*;

/// A grid on the small building, seeds 1-2, with `strategies` (TOML `[[strategies]]` entries).
fn grid(dir: &Path, name: &str, strategies: &str) -> String {
    let text = format!(
        "format = \"floorcast-grid\"\nversion = 1\nname = \"{name}\"\nbuildings = [\"{}\"]\nseeds = [1, 2]\nresults = \"{}\"\n{strategies}",
        repo().join("buildings/small.toml").display(),
        dir.join(name).display()
    );
    let g = dir.join(format!("{name}.toml"));
    std::fs::write(&g, text).unwrap();
    g.to_str().unwrap().to_string()
}

/// The rows of a results directory by (label, seed): exploration time, explored fraction,
/// worker.
fn rows(res: &Path) -> std::collections::BTreeMap<(String, String), (String, String, String)> {
    report_rows(res)
        .into_iter()
        .map(|r| {
            (
                (r["label"].clone(), r["seed"].clone()),
                (
                    r["exploration_time_s"].clone(),
                    r["explored_fraction"].clone(),
                    r["worker"].clone(),
                ),
            )
        })
        .collect()
}

/// The lines of the report's efficiency section of `label`.
fn efficiency_line(res: &Path, label: &str) -> String {
    let o = run(&["report", res.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    let from = text.find("fficiency").expect("an efficiency section");
    text[from..]
        .lines()
        .find(|l| l.trim_start().starts_with(label))
        .unwrap_or_else(|| panic!("no efficiency line of {label} in {text}"))
        .to_string()
}

/// A board in `d`: `nearest` and `frontier-tsp` on the small building, seeds 1-2, run into
/// `d/board` and exported to `d/runs.jsonl.gz` (returned).
fn board(d: &Path) -> std::path::PathBuf {
    let board = grid(
        d,
        "board",
        "[[strategies]]\nname = \"nearest\"\n[[strategies]]\nname = \"frontier-tsp\"\n",
    );
    let o = run(&["run", &board, "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let file = d.join("runs.jsonl.gz");
    let o = run(&[
        "report",
        d.join("board").to_str().unwrap(),
        "--export-runs",
        file.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("(4 runs, 1 tours)"), "{}", stdout(&o));
    file
}

/// The new strategy's grid: the board's two strategies (one under another label) and its own.
fn mine(d: &Path) -> String {
    grid(
        d,
        "mine",
        "[[strategies]]\nname = \"nearest\"\nlabel = \"closest\"\n[[strategies]]\nname = \"frontier-tsp\"\n[[strategies]]\nname = \"room-first\"\n",
    )
}

#[test]
fn a_new_strategy_runs_beside_imported_runs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = board(d);
    let mine = mine(d);
    let o = run(&["run", &mine, "--quiet", "--import", file.to_str().unwrap()]);
    let out = stdout(&o) + &stderr(&o);
    assert!(o.status.success(), "{out}");
    assert!(
        out.contains("4 of its 4 runs stored as jobs of this grid (6 jobs), 1 tours"),
        "{out}"
    );
    assert!(out.contains("6 jobs"), "{out}");
    assert!(out.contains("4 already stored"), "{out}");
    let (before, after) = (rows(&d.join("board")), rows(&d.join("mine")));
    assert_eq!(after.len(), 6);
    for seed in ["1", "2"] {
        for (there, here) in [("nearest", "closest"), ("frontier-tsp", "frontier-tsp")] {
            let a = &before[&(there.to_string(), seed.to_string())];
            let b = &after[&(here.to_string(), seed.to_string())];
            assert_eq!((&a.0, &a.1), (&b.0, &b.1), "{here} seed {seed}");
            assert_eq!(b.2, "import:runs.jsonl.gz", "{here} seed {seed}");
        }
        let own = &after[&("room-first".to_string(), seed.to_string())];
        assert!(!own.2.starts_with("import"), "{own:?}");
    }
    // The tour came with the runs: the efficiencies are the board's.
    assert_eq!(
        efficiency_line(&d.join("board"), "nearest").replacen("nearest", "", 1),
        efficiency_line(&d.join("mine"), "closest").replacen("closest", "", 1)
    );
    // Importing again stores nothing more.
    let o = run(&["run", &mine, "--quiet", "--import", file.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("0 of its 4 runs stored"),
        "{}",
        stdout(&o)
    );

    // The export never replaces the store.
    let store = d.join("mine/results.sqlite");
    let o = run(&[
        "report",
        d.join("mine").to_str().unwrap(),
        "--export-runs",
        store.to_str().unwrap(),
    ]);
    assert_clean_failure(&o, &["--export-runs"]);
    assert_eq!(rows(&d.join("mine")).len(), 6);
}

/// A damaged or foreign file is refused before anything is stored or made: one line naming
/// the file, the line and what was expected, exit code 2.
#[test]
fn a_damaged_import_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = board(d);
    let mine = mine(d);
    // Damaged files: (what is wrong, the file's bytes, what the error says).
    let gz = |text: &str| -> Vec<u8> {
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        e.write_all(text.as_bytes()).unwrap();
        e.finish().unwrap()
    };
    let good = {
        let mut text = String::new();
        std::io::Read::read_to_string(
            &mut flate2::read::GzDecoder::new(std::fs::File::open(&file).unwrap()),
            &mut text,
        )
        .unwrap();
        text
    };
    let lines: Vec<&str> = good.lines().collect();
    let header =
        r#"{"format":"floorcast-runs","version":1,"floorcast_version":"0","runs":0,"tours":0}"#;
    let cases: Vec<(&str, Vec<u8>, Vec<&str>)> = vec![
        ("not gzip", b"hello\n".to_vec(), vec!["line 1"]),
        ("empty", gz(""), vec!["empty"]),
        (
            "another format",
            gz(&header.replace("floorcast-runs", "x")),
            vec!["line 1", "format"],
        ),
        (
            "another version",
            gz(&header.replace("\"version\":1", "\"version\":9")),
            vec!["line 1", "version"],
        ),
        ("cut short", gz(&lines[..3].join("\n")), vec!["cut short"]),
        (
            "a run of another seed",
            gz(&[
                lines[0],
                &lines[1].replacen("\"seed\":1,", "\"seed\":7,", 1).replacen(
                    "\"seed\":2,",
                    "\"seed\":7,",
                    1,
                ),
            ]
            .join("\n")),
            vec!["line 2", "seed"],
        ),
        (
            "not a line",
            gz(&format!("{}\n[1, 2]\n", lines[0])),
            vec!["line 2", "expected a run or a tour"],
        ),
    ];
    for (what, bytes, needles) in cases {
        let bad = d.join("bad.jsonl.gz");
        std::fs::write(&bad, bytes).unwrap();
        let res = d.join(format!("bad-{}", what.replace(' ', "-")));
        let o = run(&[
            "run",
            &mine,
            "--quiet",
            "--import",
            bad.to_str().unwrap(),
            "--results",
            res.to_str().unwrap(),
        ]);
        let mut all = needles.clone();
        all.push("--import");
        all.push("bad.jsonl.gz");
        assert_clean_failure(&o, &all);
        assert!(!res.exists(), "{what}: nothing is made");
    }
    let o = run(&[
        "run",
        &mine,
        "--quiet",
        "--import",
        d.join("none.gz").to_str().unwrap(),
    ]);
    assert_clean_failure(&o, &["--import", "none.gz", "cannot open"]);
    assert!(!d.join("mine").exists(), "nothing is made");
}

/// The leaderboard's committed runs are every job of `grids/leaderboard.toml`, and the report
/// of a store made from them alone is `table.txt` (its first line, the store's path, aside):
/// the reference table is reproduced from the repository, and a new strategy's author runs
/// only their own jobs.
#[test]
fn the_committed_leaderboard_runs_reproduce_its_table() {
    let dir = tempfile::tempdir().unwrap();
    let res = dir.path().join("leaderboard");
    let board = repo().join("results/reference/leaderboard");
    let o = floorcast()
        .args(["run", "grids/leaderboard.toml", "--quiet", "--import"])
        .arg(board.join("runs.jsonl.gz"))
        .arg("--results")
        .arg(&res)
        .current_dir(repo())
        .output()
        .unwrap();
    let out = stdout(&o);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        out.contains("1296 of its 1296 runs stored as jobs of this grid (1296 jobs), 27 tours"),
        "{out}"
    );
    assert!(out.contains("nothing to do: all 1296 jobs"), "{out}");
    let o = run(&["report", res.to_str().unwrap(), "--reference", "nearest"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = std::fs::read_to_string(board.join("table.txt")).unwrap();
    let skip_first = |t: &str| t.lines().skip(1).collect::<Vec<_>>().join("\n");
    let (got, want) = (skip_first(&stdout(&o)), skip_first(&table));
    assert!(want.lines().count() > 1000, "table.txt is the whole report");
    assert!(
        got == want,
        "the report of the imported runs differs from table.txt"
    );
}
