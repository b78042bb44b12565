//! A grid's relative paths start from the folder holding it, however the grid is named: a bare
//! file name (`run g.toml`, whose parent is "") finds `./suites/`, its buildings and its
//! strategy programs as `./g.toml` and `/abs/g.toml` do (issue 78, item 10).

mod common;

use common::*;

#[test]
fn a_grid_named_by_its_bare_file_name_finds_its_suites_buildings_and_programs() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    std::fs::create_dir_all(root.join("buildings")).unwrap();
    std::fs::create_dir_all(root.join("strategies")).unwrap();
    std::fs::copy(
        repo().join("buildings/small.toml"),
        root.join("buildings/small.toml"),
    )
    .unwrap();
    // Two halves that no door joins, the suite's building.
    std::fs::write(
        root.join("buildings/halves.toml"),
        "format = \"floorcast-building\"\nversion = 1\noutline = [[0.0, 0.0], [12.0, 0.0], [12.0, 6.0], [0.0, 6.0], [0.0, 0.0]]\n[[walls]]\nfrom = [6.0, 0.0]\nto = [6.0, 6.0]\nthickness = 0.2\n[start]\nx = 3.0\ny = 3.0\n",
    )
    .unwrap();
    std::fs::copy(
        repo().join("tests/strategies/plain_v1.py"),
        root.join("strategies/plain.py"),
    )
    .unwrap();
    let o = floorcast()
        .args([
            "suite",
            "update",
            "one",
            "--kind",
            "generated",
            "--source",
            "made here",
            "--licence",
            "MIT",
            "--description",
            "One building",
            "buildings/halves.toml",
        ])
        .current_dir(root)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::write(
        root.join("g.toml"),
        "format = \"floorcast-grid\"\nversion = 1\nname = \"g\"\nresults = \"results/g\"\nsuites = [\"one\"]\nbuildings = [\"buildings/small.toml\"]\nseeds = [1]\n[[strategies]]\nlabel = \"plain\"\ncommand = [\"python3\", \"strategies/plain.py\"]\n[settings]\ntime_limit_s = 20\n",
    )
    .unwrap();
    let abs = root.join("g.toml");
    for name in ["g.toml", "./g.toml", abs.to_str().unwrap()] {
        let o = floorcast()
            .args(["run", name, "--summary"])
            .current_dir(root)
            .output()
            .unwrap();
        let out = stdout(&o);
        assert!(o.status.success(), "{name}: {out}{}", stderr(&o));
        assert!(out.contains("suite one: 1 buildings"), "{name}: {out}");
        assert!(out.contains("0 of 2 jobs stored"), "{name}: {out}");
    }
    // And it runs from there: the suite's building and the file, with the program beside it.
    let o = floorcast()
        .args(["run", "g.toml", "--quiet", "--no-tours"])
        .current_dir(root)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}{}", stdout(&o), stderr(&o));
    assert_eq!(report_rows(&root.join("results/g")).len(), 2);
}
