//! Sequential grids (`[sequential]`): seeds added in batches until each comparison is decided,
//! on this machine and on remote workers, resumed from what is stored.

mod common;

use std::path::{Path, PathBuf};

use common::*;

/// A grid on the small building: `baseline` (the reference), the Python `baseline.py` (the same
/// runs: H0), `nearest` (about 30 % faster: H1).
fn grid(dir: &Path, sequential: &str, seeds: &str) -> PathBuf {
    let text = format!(
        r#"format = "floorcast-grid"
version = 1
name = "seq"
buildings = ["{small}"]
{seeds}
[[strategies]]
name = "baseline"
[[strategies]]
label = "same"
command = ["python3", "{baseline}"]
[[strategies]]
label = "nearest"
command = ["python3", "{nearest}"]
{sequential}
[settings]
time_limit_s = 1200
"#,
        small = repo().join("buildings/small.toml").display(),
        baseline = repo().join("examples/strategies/baseline.py").display(),
        nearest = repo().join("examples/strategies/nearest.py").display(),
    );
    let p = dir.join("grid.toml");
    std::fs::write(&p, text).unwrap();
    p
}

const SEQUENTIAL: &str =
    "[sequential]\nreference = \"baseline\"\nh1_gain_pct = 5\nbatch_seeds = 4\nmax_seeds = 16\n";

/// The decisions printed, as (label, decision, pairs): "rejected H1 (gain below 5 %)" is the
/// GSPRT's H0, "rejected H0 (gain above 0 %)" its H1 (the grid's hypotheses, known to `run`);
/// a test read back by `report` names only what it rejected.
fn decisions(out: &str) -> Vec<(String, String, String)> {
    out.lines()
        .filter(|l| l.contains(" vs baseline "))
        .map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            let decision = if l.contains("rejected H1 (gain below 5 %)")
                || l.contains("rejected H1 (H0 accepted)")
            {
                "H0"
            } else if l.contains("rejected H0 (gain above 0 %)")
                || l.contains("rejected H0 (H1 accepted)")
            {
                "H1"
            } else {
                "?"
            };
            let after = w.iter().position(|x| *x == "after").expect("after N pairs");
            (
                w[0].to_string(),
                decision.to_string(),
                w[after + 1].to_string(),
            )
        })
        .collect()
}

fn assert_decided(out: &str) {
    assert_eq!(
        decisions(out),
        vec![
            ("same".to_string(), "H0".to_string(), "12".to_string()),
            ("nearest".to_string(), "H1".to_string(), "12".to_string()),
        ],
        "{out}"
    );
}

#[test]
#[allow(clippy::too_many_lines)] // a table of cases
fn a_sequential_grid_stops_when_every_comparison_is_decided() {
    let dir = tempfile::tempdir().unwrap();
    let g = grid(dir.path(), SEQUENTIAL, "");
    let res = dir.path().join("res");
    let o = run_grid(&g, &res);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    // Batches of 4 seeds; the first look needs 10 pairs: seeds 1-12, 3 labels, then decided.
    assert!(out.contains("done: 36 jobs run now"), "{out}");
    assert_decided(&out);
    // Again: nothing to do, the same decisions; `report` reads them from the store.
    let again = run_grid(&g, &res);
    assert!(
        stdout(&again).contains("nothing to do: all 36 jobs"),
        "{}",
        stdout(&again)
    );
    assert_decided(&stdout(&again));
    let r = run(&["report", res.to_str().unwrap()]);
    let report = stdout(&r);
    let stored: String = report
        .lines()
        .filter_map(|l| l.strip_prefix("sequential grid 'seq': "))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_decided(&stored);
    assert!(stored.contains("(seeds 1-12)"), "{report}");
    // `report --json`: every comparison with its statistics and the sequential decision.
    let json = dir.path().join("report.json");
    let r = run(&[
        "report",
        res.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", stderr(&r));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["format"], "floorcast-report");
    assert_eq!(v["version"], 3);
    assert_eq!(v["measure"], "end");
    assert_eq!(v["coverage"], 0.99);
    assert_eq!(v["reference"], "baseline");
    let overall = |label: &str| {
        v["comparisons"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["label"] == label && c["building"].is_null())
            .unwrap_or_else(|| panic!("no comparison of {label}: {v}"))
            .clone()
    };
    let nearest = overall("nearest");
    assert_eq!(nearest["decision"], "H1");
    assert_eq!(nearest["pairs"], 12);
    assert_eq!(nearest["sequential_pairs"], 12);
    let p = nearest["wilcoxon_p"].as_f64().unwrap();
    assert!(p < 0.01, "{nearest}");
    assert!(nearest["holm_p"].as_f64().unwrap() >= p);
    let [lo, hi] = [0, 1].map(|i| nearest["bootstrap_ci95_pct"][i].as_f64().unwrap());
    let mean = nearest["mean_gain_pct"].as_f64().unwrap();
    assert!(lo < mean && mean < hi && lo > 10.0, "{nearest}");
    // After a sequential stop the anytime interval is the one that holds: wider than t's.
    assert_eq!(nearest["fixed_sample_intervals_biased"], true);
    let [alo, ahi] = [0, 1].map(|i| nearest["anytime_ci95_pct"][i].as_f64().unwrap());
    let [tlo, thi] = [0, 1].map(|i| nearest["t_ci95_pct"][i].as_f64().unwrap());
    assert!(
        alo < tlo && thi < ahi && alo < mean && mean < ahi,
        "{nearest}"
    );
    assert_eq!(nearest["family"], "headline");
    // The headline: the Hodges-Lehmann estimate with its Wilcoxon interval; the decision in
    // words (the store does not hold the grid's hypotheses).
    let hl = nearest["hl_gain_pct"].as_f64().unwrap();
    let [hlo, hhi] = [0, 1].map(|i| nearest["hl_ci95_pct"][i].as_f64().unwrap());
    assert!(hlo <= hl && hl <= hhi && hlo > 10.0, "{nearest}");
    assert_eq!(nearest["decision_text"], "rejected H0 (H1 accepted)");
    assert_eq!(nearest["measure"], "end");
    // The aggregates across buildings: the faster label's IQM of normalized times below 1.
    let agg = v["aggregates"]["labels"].as_array().unwrap();
    let iqm = |label: &str| {
        agg.iter().find(|a| a["label"] == label).unwrap()["iqm_normalized_time"]
            .as_f64()
            .unwrap()
    };
    assert!(
        iqm("nearest") < 0.9 && (iqm("same") - 1.0).abs() < 0.05,
        "{agg:?}"
    );
    // The labels' other metrics.
    let labels = v["labels"].as_array().unwrap();
    assert_eq!(labels.len(), 3);
    for l in labels {
        let m = &l["metrics"];
        assert_eq!(m["runs_reaching_99"], 12, "{l}");
        let t90 = m["time_to_90_s_mean"].as_f64().unwrap();
        assert!(
            t90 > 0.0 && t90 <= m["time_to_99_s_mean"].as_f64().unwrap(),
            "{l}"
        );
        assert!(m["unexplored_area_s_mean"].as_f64().unwrap() > 0.0, "{l}");
    }
    // The time to 99 % explored decides instead: named in the table, the comparisons and the
    // JSON; no run's time to 99 % is after its end.
    let cov = dir.path().join("coverage.json");
    let r = run(&[
        "report",
        res.to_str().unwrap(),
        "--measure",
        "coverage",
        "--json",
        cov.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", stderr(&r));
    let text = stdout(&r);
    assert!(
        text.contains("Measure: time to 99 % explored")
            && text.contains("measure: time to 99 % explored"),
        "{text}"
    );
    let c: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&cov).unwrap()).unwrap();
    assert_eq!(c["measure"], "coverage");
    assert_eq!(c["aggregates"]["measure"], "coverage");
    for l in c["labels"].as_array().unwrap() {
        assert!(
            l["time_mean_s"].as_f64().unwrap()
                <= v["labels"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .find(|x| x["label"] == l["label"])
                    .unwrap()["time_mean_s"]
                    .as_f64()
                    .unwrap()
                    + 1e-9,
            "{l}"
        );
    }
    let bad = run(&["report", res.to_str().unwrap(), "--measure", "fastest"]);
    assert_eq!(bad.status.code(), Some(2), "{}", stderr(&bad));
    assert!(
        stderr(&bad).contains("unknown measure 'fastest'"),
        "{}",
        stderr(&bad)
    );
    // Identical runs: no non-zero difference, no Wilcoxon p, decided H0.
    let same = overall("same");
    assert_eq!(same["decision"], "H0");
    assert!(same["wilcoxon_p"].is_null(), "{same}");
    assert_eq!(same["mean_gain_pct"], 0.0);
    // Another reference: the labels are compared with it, and the gain of baseline over
    // nearest is exactly the negative of nearest's over baseline in log space, p the same.
    let swapped = dir.path().join("swapped.json");
    let r = run(&[
        "report",
        res.to_str().unwrap(),
        "--reference",
        "nearest",
        "--json",
        swapped.to_str().unwrap(),
    ]);
    assert!(
        stdout(&r).contains("Paired gains over nearest"),
        "{}",
        stdout(&r)
    );
    let w: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&swapped).unwrap()).unwrap();
    let back = w["comparisons"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["label"] == "baseline" && c["building"].is_null())
        .unwrap()
        .clone();
    assert_eq!(
        back["mean_log_ratio"].as_f64().unwrap(),
        -nearest["mean_log_ratio"].as_f64().unwrap()
    );
    assert_eq!(back["wilcoxon_p"], nearest["wilcoxon_p"]);
    let r = run(&["report", res.to_str().unwrap(), "--reference", "nope"]);
    assert_clean_failure(&r, &["--reference", "no runs labelled 'nope'"]);
}

#[test]
fn a_sequential_grid_goes_on_from_the_runs_already_stored() {
    let dir = tempfile::tempdir().unwrap();
    let res = dir.path().join("res");
    // Seeds 1-6 stored by a plain grid of the same strategies (the jobs are the same).
    let plain = grid(dir.path(), "", "seed_range = [1, 6]");
    let o = run_grid(&plain, &res);
    assert!(o.status.success(), "{}", stderr(&o));
    let g = grid(dir.path(), SEQUENTIAL, "");
    let o = run_grid(&g, &res);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains("done: 18 jobs run now, 18 stored before"),
        "{out}"
    );
    assert_decided(&out);
}

#[test]
fn remote_workers_serve_a_sequential_grid_across_its_batches() {
    let dir = tempfile::tempdir().unwrap();
    let g = grid(dir.path(), SEQUENTIAL, "");
    let res = dir.path().join("res");
    let ((code, out), workers) = run_with_remote_workers(&g, &res, &["w1", "w2"], dir.path());
    for (code, out) in workers {
        assert_eq!(code, Some(0), "{out}");
        // Between batches the workers waited instead of leaving.
        assert!(out.contains("grid complete"), "{out}");
    }
    assert_eq!(code, Some(0), "{out}");
    assert_decided(&out);
}

#[test]
fn sequential_grid_errors_name_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            SEQUENTIAL,
            "seed_range = [1, 4]",
            "seed_range: a grid with [sequential] adds seeds",
        ),
        (
            "[sequential]\nreference = \"nope\"\n",
            "",
            "sequential.reference: 'nope' is not a label",
        ),
        (
            "[sequential]\nreference = \"baseline\"\nh0_gain_pct = 5\nh1_gain_pct = 5\n",
            "",
            "sequential.h1_gain_pct",
        ),
        (
            "[sequential]\nreference = \"baseline\"\nalpha = 0.7\n",
            "",
            "sequential.alpha",
        ),
        (
            "[sequential]\nreference = \"baseline\"\nbatch_seeds = 5\nmax_seeds = 4\n",
            "",
            "sequential.batch_seeds: 5 is not in [1, max_seeds = 4]",
        ),
        (
            "[sequential]\nreference = \"baseline\"\nmax_seeds = 0\n",
            "",
            "sequential.max_seeds",
        ),
        // One building and start: 4 seeds give 4 pairs, never the 10 the test needs.
        (
            "[sequential]\nreference = \"baseline\"\nbatch_seeds = 2\nmax_seeds = 4\n",
            "",
            "sequential.max_seeds: 4 seeds give at most 4 pairs",
        ),
        (
            "[sequential]\nreference = \"baseline\"\nmultiplicity = \"holm\"\n",
            "",
            "sequential.multiplicity: 'holm' is not a multiplicity rule",
        ),
        (
            SEQUENTIAL,
            "coverage = 1.5",
            "coverage: 1.5 is not a coverage level",
        ),
    ];
    for (sequential, seeds, needle) in cases {
        let g = grid(dir.path(), sequential, seeds);
        let o = run(&["run", g.to_str().unwrap(), "--summary"]);
        assert_clean_failure(&o, &["grid.toml", needle]);
    }
}
