//! External strategies in grids: on this machine and on remote workers, which receive the
//! program's files with the job; a strategy that breaks the protocol fails only its own jobs.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use common::*;

/// A project as a user lays it out: `strategies/` with the programs (copied from the
/// repository, so that they sit nowhere near floorcast's own `python/`), `grids/grid.toml`
/// naming them relative to itself.
fn project(dir: &Path, seeds: &str, strategies: &str) -> PathBuf {
    std::fs::create_dir_all(dir.join("strategies")).unwrap();
    std::fs::create_dir_all(dir.join("grids")).unwrap();
    for f in [
        "examples/strategies/baseline.py",
        "examples/strategies/nearest.py",
        "tests/strategies/crash_mid_run.py",
        "tests/strategies/hang.py",
    ] {
        let name = Path::new(f).file_name().unwrap();
        std::fs::copy(repo().join(f), dir.join("strategies").join(name)).unwrap();
    }
    let text = format!(
        "format = \"floorcast-grid\"\nversion = 1\nname = \"ext\"\nbuildings = [\"{}\"]\nseeds = {seeds}\n{strategies}\n[settings]\ntime_limit_s = 600\n",
        repo().join("buildings/small.toml").display()
    );
    let g = dir.join("grids/grid.toml");
    std::fs::write(&g, text).unwrap();
    g
}

const BASELINES: &str = r#"
[[strategies]]
name = "baseline"
[[strategies]]
label = "baseline.py"
command = ["python3", "../strategies/baseline.py"]
"#;

/// The report's CSV rows by (label, seed): column name -> value.
fn rows(res: &Path) -> BTreeMap<(String, String), BTreeMap<String, String>> {
    report_rows(res)
        .into_iter()
        .map(|row| ((row["label"].clone(), row["seed"].clone()), row))
        .collect()
}

/// The outcome columns of the python baseline's rows equal the built-in's.
fn assert_python_baseline_is_the_built_in(res: &Path, seeds: &[&str]) {
    let rows = rows(res);
    for seed in seeds {
        let a = &rows[&("baseline".to_string(), seed.to_string())];
        let b = &rows[&("baseline.py".to_string(), seed.to_string())];
        assert_eq!(b["status"], "ok");
        for col in [
            "exploration_time_s",
            "explored_area_m2",
            "explored_fraction",
            "path_length_m",
            "decisions",
            "end_reason",
        ] {
            assert_eq!(a[col], b[col], "seed {seed}: {col}");
        }
    }
}

#[test]
fn a_grid_runs_external_strategies_beside_the_built_in_ones() {
    let dir = tempfile::tempdir().unwrap();
    let strategies = format!(
        "{BASELINES}\n[[strategies]]\nlabel = \"nearest\"\ncommand = [\"python3\", \"../strategies/nearest.py\"]\n[[strategies]]\nlabel = \"crashes\"\ncommand = [\"python3\", \"../strategies/crash_mid_run.py\"]\n"
    );
    let g = project(dir.path(), "[1, 2]", &strategies);
    let res = dir.path().join("res");
    let o = run_grid(&g, &res);
    // The crashing strategy fails its own two jobs, with its message; the rest are stored.
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("2 of 8 jobs failed"), "{err}");
    assert!(err.contains("crashes seed 1"), "{err}");
    assert!(err.contains("strategy bug at decision 3"), "{err}");
    assert_python_baseline_is_the_built_in(&res, &["1", "2"]);
    let rows = rows(&res);
    for seed in ["1", "2"] {
        assert_eq!(rows[&("nearest".into(), seed.into())]["status"], "ok");
        assert_eq!(rows[&("crashes".into(), seed.into())]["status"], "failed");
    }
    // The program's identity is in its jobs' ids: the same grid again has nothing to do (the
    // crashing program's failed jobs, which stored no program, count as its own); a changed
    // program is another configuration of its label, refused where the old one's runs are
    // (report would merge them), and makes new jobs in another results directory.
    let again = run_grid(&g, &res);
    assert!(
        stdout(&again).contains("nothing to do"),
        "{}",
        stderr(&again)
    );
    let script = dir.path().join("strategies/nearest.py");
    let text = std::fs::read_to_string(&script).unwrap();
    std::fs::write(&script, format!("{text}\n# changed\n")).unwrap();
    let refused = run_grid(&g, &res);
    assert_clean_failure(
        &refused,
        &[
            "label 'nearest' already has runs of another configuration",
            "external program",
            "its own label",
        ],
    );
    let changed = run_grid(&g, &dir.path().join("res-changed"));
    assert!(
        stdout(&changed).contains("done: 8 jobs run now"),
        "{}",
        stdout(&changed)
    );
}

#[test]
fn grid_errors_name_the_external_strategy_field() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "[[strategies]]\ncommand = [\"python3\", \"x.py\"]\n",
            "strategies[0].label: an external strategy (one with a command) needs a label",
        ),
        (
            "[[strategies]]\nname = \"baseline\"\ncommand = [\"python3\", \"x.py\"]\n",
            "strategies[0]: gives both a name",
        ),
        (
            "[[strategies]]\nlabel = \"x\"\ncommand = []\n",
            "strategies[0].command: the strategy command is empty",
        ),
        (
            "[[strategies]]\nlabel = \"x\"\ncommand = [\"python3\", \"x.py\"]\nfiles = [\"missing.py\"]\n",
            "strategies[0].files[0]: file 'missing.py' is not a file",
        ),
        (
            "[[strategies]]\nlabel = \"x\"\ncommand = [\"python3\", \"x.py\"]\ntimeout_s = 0\n",
            "strategies[0].timeout_s: the strategy timeout 0 s is outside",
        ),
        (
            "[[strategies]]\nname = \"baseline\"\ntimeout_s = 5\n",
            "strategies[0].timeout_s: belongs to an external strategy",
        ),
        (
            "[[strategies]]\nname = \"baseline\"\nparams = { a = 1 }\n",
            "strategies[0].params: belongs to an external strategy",
        ),
        (
            "[[strategies]]\nlabel = \"x\"\ncommand = [\"python3\", \"x.py\"]\nparams = { when = 2026-11-25 }\n",
            "strategies[0].params.when: 2026-11-25 is a TOML date or time",
        ),
        (
            "[[strategies]]\nlabel = \"x\"\ncommand = [\"python3\", \"x.py\"]\nparams = { a = { b = [1.0, nan] } }\n",
            "strategies[0].params.a.b[1]: NaN has no JSON form",
        ),
        (
            "[[strategies]]\nlabel = \"x\"\ncommand = [\"python3\", \"x.py\"]\nparams = 5\n",
            "params = 5 | ^ invalid type: integer `5`, expected a map",
        ),
    ];
    for (strategies, needle) in cases {
        let g = project(dir.path(), "[1]", strategies);
        let o = run(&["run", g.to_str().unwrap(), "--summary"]);
        assert_clean_failure(&o, &["grid.toml", needle]);
    }
}

#[test]
fn remote_workers_receive_the_program_and_a_hanging_one_fails_only_its_jobs() {
    let dir = tempfile::tempdir().unwrap();
    // `stops` is nearest.py with a parameter that makes it stop at once: the parameters travel
    // with the job.
    let strategies = format!(
        "{BASELINES}\n[[strategies]]\nlabel = \"hangs\"\ncommand = [\"python3\", \"../strategies/hang.py\"]\ntimeout_s = 1\n[[strategies]]\nlabel = \"stops\"\ncommand = [\"python3\", \"../strategies/nearest.py\"]\nparams = {{ stop_below_m2 = 1e9 }}\n"
    );
    let g = project(dir.path(), "[1, 2]", &strategies);
    let res = dir.path().join("res");
    // The workers run elsewhere, where none of the programs' files are.
    let elsewhere = tempfile::tempdir().unwrap();
    let ((cc, outc), workers) = run_with_remote_workers(&g, &res, &["w1", "w2"], elsewhere.path());
    let [(c1, out1), (c2, out2)] = [workers[0].clone(), workers[1].clone()];
    assert_eq!((c1, c2), (Some(0), Some(0)), "{out1}\n---\n{out2}");
    // The hanging strategy's two jobs failed, named; the grid went on.
    assert_eq!(cc, Some(2), "{outc}");
    assert!(outc.contains("2 of 8 jobs failed"), "{outc}");
    assert!(
        outc.contains("did not answer decision 0 within 1 s"),
        "{outc}"
    );
    assert_python_baseline_is_the_built_in(&res, &["1", "2"]);
    let rows = rows(&res);
    let remote = |label: &str| {
        ["1", "2"]
            .iter()
            .all(|s| rows[&(label.to_string(), s.to_string())]["worker"].starts_with('w'))
    };
    assert!(
        remote("baseline.py") && remote("hangs") && remote("stops"),
        "{rows:?}"
    );
    for seed in ["1", "2"] {
        let row = &rows[&("stops".to_string(), seed.to_string())];
        assert_eq!(
            (row["status"].as_str(), row["end_reason"].as_str()),
            ("ok", "early stop"),
            "{row:?}"
        );
    }
}
