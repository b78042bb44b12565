//! Names, labels and messages (issue 62, items 10 and 11) where the malformed-input corpus
//! cannot express the case: a results directory written by two runs, a FIFO, a folder whose name
//! is not UTF-8, a store whose building name would climb out of `--plots`.

mod common;

use std::path::Path;
use std::process::Output;

use common::{assert_clean_failure, floorcast, repo, stderr};

/// A one-job grid `file` in `dir` whose only strategy is labelled `near`, with `alpha`.
fn grid(dir: &Path, file: &str, alpha: f64) {
    std::fs::write(
        dir.join(file),
        format!(
            "format = \"floorcast-grid\"\nversion = 1\nname = \"g\"\nbuildings = [\"small.toml\"]\nseeds = [1]\n\
             [[strategies]]\nname = \"baseline\"\nlabel = \"near\"\nsettings = {{ alpha = {alpha:?} }}\n\
             [settings]\ntime_limit_s = 5\n"
        ),
    )
    .unwrap();
}

fn floorcast_in(dir: &Path, args: &[&str]) -> Output {
    floorcast()
        .args(args)
        .current_dir(dir)
        .output()
        .expect("floorcast runs")
}

fn sqlite(dir: &Path, script: &str) {
    let o = std::process::Command::new("python3")
        .arg("-c")
        .arg(format!("import sqlite3\nc = sqlite3.connect('r1/results.sqlite')\n{script}\nc.commit()\nc.close()"))
        .current_dir(dir)
        .output()
        .expect("python3 runs");
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn a_label_reused_with_other_settings_is_refused_by_run_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    std::fs::copy(repo().join("buildings/small.toml"), tmp.join("small.toml")).unwrap();
    grid(tmp, "a.toml", 0.5);
    grid(tmp, "b.toml", 0.8);
    let o = floorcast_in(tmp, &["run", "a.toml", "--results", "r1", "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let before = std::fs::read(tmp.join("r1/results.sqlite")).unwrap();
    // The same label with another alpha in the same results directory: refused before it runs.
    let o = floorcast_in(tmp, &["run", "b.toml", "--results", "r1", "--quiet"]);
    assert_clean_failure(
        &o,
        &[
            "b.toml",
            "label 'near' already has runs of another configuration",
            "setting alpha 0.5 and 0.8",
            "reused after its settings changed",
            "its own label",
            "another results directory",
        ],
    );
    assert_eq!(
        std::fs::read(tmp.join("r1/results.sqlite")).unwrap(),
        before
    );
    // The same grid again is no change.
    let o = floorcast_in(tmp, &["run", "a.toml", "--results", "r1", "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Elsewhere it runs; a store holding both (merged by hand) is refused by report.
    let o = floorcast_in(tmp, &["run", "b.toml", "--results", "r2", "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = floorcast_in(tmp, &["report", "r2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    sqlite(
        tmp,
        "c.execute(\"ATTACH 'r2/results.sqlite' AS b\")\nc.execute('INSERT INTO results SELECT * FROM b.results')",
    );
    let o = floorcast_in(tmp, &["report", "r1"]);
    assert_clean_failure(
        &o,
        &[
            "r1/results.sqlite",
            "label 'near' holds runs of two configurations",
            "setting alpha",
            "reused after its settings changed",
            "its own label",
        ],
    );
    assert!(common::stdout(&o).is_empty(), "{}", common::stdout(&o));
}

#[test]
fn a_stored_building_name_never_leaves_the_chart_folder() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    std::fs::copy(repo().join("buildings/small.toml"), tmp.join("small.toml")).unwrap();
    grid(tmp, "a.toml", 0.5);
    let o = floorcast_in(tmp, &["run", "a.toml", "--results", "r1", "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    sqlite(
        tmp,
        "c.execute(\"UPDATE results SET building = '../../evil'\")",
    );
    std::fs::create_dir(tmp.join("deep")).unwrap();
    let o = floorcast_in(
        &tmp.join("deep"),
        &["report", "../r1", "--plots", "charts", "--picture", "svg"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(tmp.join("deep/charts/progress-____evil.svg").is_file());
    assert!(!tmp.join("evil.svg").exists() && !tmp.join("progress-evil.svg").exists());
    let outside: Vec<_> = std::fs::read_dir(tmp)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("evil"))
        .collect();
    assert!(outside.is_empty(), "{outside:?}");
}

#[test]
fn an_image_that_is_a_fifo_is_not_a_regular_file() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    let made = std::process::Command::new("mkfifo")
        .arg(tmp.join("map.pgm"))
        .status()
        .expect("mkfifo runs");
    assert!(made.success());
    std::fs::write(
        tmp.join("map.yaml"),
        "image: map.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
    )
    .unwrap();
    let o = floorcast_in(tmp, &["building", "check", "map.yaml"]);
    assert_clean_failure(
        &o,
        &["map.yaml", "image", "map.pgm", "is not a regular file"],
    );
    assert!(!stderr(&o).contains("does not exist"), "{}", stderr(&o));
}

#[test]
fn a_grid_in_a_folder_whose_name_is_not_utf8_says_so() {
    use std::os::unix::ffi::OsStrExt;
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join(std::ffi::OsStr::from_bytes(b"grids-\xff"));
    std::fs::create_dir(&folder).unwrap();
    std::fs::copy(
        repo().join("buildings/small.toml"),
        folder.join("small.toml"),
    )
    .unwrap();
    grid(&folder, "a.toml", 0.5);
    let o = floorcast()
        .arg("run")
        .arg(folder.join("a.toml"))
        .args(["--results", "r", "--quiet"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert_clean_failure(&o, &["buildings", "not UTF-8", "grids-"]);
    assert!(!stderr(&o).contains("matches no file"), "{}", stderr(&o));
    assert!(!dir.path().join("r").exists());
}
