//! `floorcast run`, `report` and `layout` end to end.

mod common;

use common::*;

fn grid(dir: &std::path::Path, seeds: &str) -> std::path::PathBuf {
    let small = repo().join("buildings/small.toml");
    let text = format!(
        r#"format = "floorcast-grid"
version = 1
name = "e2e"
buildings = ["{}"]
seeds = {seeds}
[[strategies]]
name = "baseline"
[[strategies]]
name = "baseline"
label = "near"
settings = {{ alpha = 0.8 }}
[settings]
time_limit_s = 60
"#,
        small.display()
    );
    let p = dir.join("grid.toml");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn runs_a_grid_then_resumes_with_nothing_to_do() {
    let dir = tempfile::tempdir().unwrap();
    let g = grid(dir.path(), "[1, 2]");
    let res = dir.path().join("res");
    let args = [
        "run",
        g.to_str().unwrap(),
        "--results",
        res.to_str().unwrap(),
        "--workers",
        "2",
        "-q",
    ];
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("done: 4 jobs run now"), "{out}");
    assert!(
        out.contains("baseline") && out.contains("near") && out.contains("ref"),
        "{out}"
    );
    let o = run(&args);
    assert!(o.status.success());
    assert!(
        stdout(&o).contains("nothing to do: all 4 jobs"),
        "{}",
        stdout(&o)
    );
    // One more seed: only the new jobs run.
    let g = grid(dir.path(), "[1, 2, 3]");
    let o = run_grid(&g, &res);
    assert!(
        stdout(&o).contains("done: 2 jobs run now, 4 stored before"),
        "{}",
        stdout(&o)
    );
    // Report and CSV: one line per job.
    let csv = dir.path().join("r.csv");
    let o = run(&[
        "report",
        res.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // How the runs ended, per strategy.
    let out = stdout(&o);
    assert!(
        out.contains("How runs ended") && out.contains("frontiers unreachable"),
        "{out}"
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 1 + 6);
    assert!(text.starts_with("job_id,building,"));
    // Charts: the times (Fig. 2), the gains, the performance profile and one progress chart per
    // building (Fig. 4), as
    // SVG text naming the strategies; the HTML page holds the printed tables and every chart.
    let plots = dir.path().join("plots");
    let html = dir.path().join("report.html");
    let o = run(&[
        "report",
        res.to_str().unwrap(),
        "--plots",
        plots.to_str().unwrap(),
        "--picture",
        "svg",
        "--html",
        html.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut names: Vec<String> = std::fs::read_dir(&plots)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "gains.svg",
            "profile.svg",
            "progress-small.svg",
            "times.svg"
        ],
        "{names:?}"
    );
    let progress = std::fs::read_to_string(plots.join("progress-small.svg")).unwrap();
    assert!(
        progress.contains(">baseline (3 runs)<") && progress.contains(">near (3 runs)<"),
        "{progress}"
    );
    let gains = std::fs::read_to_string(plots.join("gains.svg")).unwrap();
    assert!(gains.contains(">near<") && !gains.contains(">baseline<"));
    let times = std::fs::read_to_string(plots.join("times.svg")).unwrap();
    assert!(
        times.contains(">baseline<") && times.contains(">exploration time (s)<"),
        "{times}"
    );
    let page = std::fs::read_to_string(&html).unwrap();
    assert_eq!(page.matches("<svg").count(), 4);
    let table = stdout(&o);
    let first_row = table.lines().find(|l| l.contains("baseline")).unwrap();
    assert!(page.contains(first_row), "the page holds the printed table");
}

#[test]
fn grid_errors_name_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let g = grid(dir.path(), "[1, 1]");
    assert_clean_failure(
        &run(&["run", g.to_str().unwrap(), "-q"]),
        &["grid.toml", "seeds", "twice"],
    );
    let o = run(&["report", dir.path().join("nothing").to_str().unwrap()]);
    assert_clean_failure(&o, &["nothing", "floorcast run"]);
}

/// `report --against` pairs the runs of two results directories by building content, seed and
/// start pose: two stores of the same grid pair every run with a gain of exactly zero, and a
/// label compared with another label of the same store gives the table's own paired gain.
#[test]
fn report_against_pairs_runs_across_results_directories() {
    let dir = tempfile::tempdir().unwrap();
    let g = grid(dir.path(), "[1, 2]");
    // Runs that explore the building to the end (a run cut by the time limit is a loss).
    let text = std::fs::read_to_string(&g).unwrap();
    std::fs::write(&g, text.replace("time_limit_s = 60", "time_limit_s = 3600")).unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    for res in [&a, &b] {
        let o = run_grid(&g, res);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let report = |args: &[&str]| {
        let mut all = vec!["report", a.to_str().unwrap(), "--against"];
        all.extend_from_slice(args);
        run(&all)
    };
    let o = report(&[b.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let against = out.split("Against ").nth(1).expect("an --against section");
    for (label, over) in [("baseline", "baseline"), ("near", "near")] {
        let line = against
            .lines()
            .find(|l| l.split_whitespace().next() == Some(label))
            .unwrap_or_else(|| panic!("no line for {label}: {out}"));
        let words: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(words[1], over, "{line}");
        assert_eq!(
            &words[2..],
            ["+0.0", "%", "[+0.0,", "+0.0]", "(n=2)"],
            "{line}"
        );
    }
    // Against baseline of the same store: the table's paired gain of "near".
    let o = report(&[a.to_str().unwrap(), "--against-label", "baseline"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let (table, against) = out.split_once("Against ").unwrap();
    let cell = |text: &str| {
        let line = text
            .lines()
            .find(|l| l.trim_start().starts_with("near "))
            .unwrap_or_else(|| panic!("no near line: {out}"));
        let start = line.find(['+', '-']).unwrap();
        line[start..].split(')').next().unwrap().to_string()
    };
    assert_eq!(cell(against), cell(table), "{out}");
    // The same comparison in the JSON report: the other directory, and per label the label it
    // is compared with and the paired gain, equal to the table's comparison of the same store.
    let json = dir.path().join("r.json");
    let o = report(&[
        a.to_str().unwrap(),
        "--against-label",
        "baseline",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["against"]["results"], a.to_str().unwrap());
    let near = v["against"]["comparisons"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["label"] == "near")
        .unwrap_or_else(|| panic!("{v}"));
    assert_eq!(near["against_label"], "baseline");
    assert_eq!(near["pairs"], 2);
    let overall = v["comparisons"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["label"] == "near" && c["building"].is_null())
        .unwrap_or_else(|| panic!("{v}"));
    let close = |x: &serde_json::Value, y: &serde_json::Value| {
        (x.as_f64().unwrap() - y.as_f64().unwrap()).abs() < 1e-9
    };
    assert!(
        close(&near["mean_gain_pct"], &overall["mean_gain_pct"]),
        "{near} {overall}"
    );
    // A label the other store does not hold: one line naming it and the labels there.
    let o = report(&[b.to_str().unwrap(), "--against-label", "nope"]);
    assert_clean_failure(&o, &["--against-label", "nope", "baseline, near"]);
    assert!(stdout(&o).is_empty(), "nothing printed before the error");
}

#[test]
fn interrupted_grid_resumes_without_duplicates() {
    let dir = tempfile::tempdir().unwrap();
    // 80 jobs on one worker: seconds of work, so that Ctrl-C after the first stored result
    // always lands before the end.
    let seeds: Vec<String> = (1..=40).map(|s| s.to_string()).collect();
    let g = grid(dir.path(), &format!("[{}]", seeds.join(", ")));
    let res = dir.path().join("res");
    let mut child = floorcast()
        .args([
            "run",
            g.to_str().unwrap(),
            "--results",
            res.to_str().unwrap(),
            "--workers",
            "1",
            "-q",
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait for the first stored result, then press Ctrl-C.
    let db = res.join("results.sqlite");
    let t = std::time::Instant::now();
    loop {
        std::thread::sleep(std::time::Duration::from_millis(200));
        let o = run(&["report", res.to_str().unwrap()]);
        if o.status.success() && !stdout(&o).starts_with("0 results") {
            break;
        }
        assert!(t.elapsed().as_secs() < 120, "no result stored in time");
        assert!(child.try_wait().unwrap().is_none() || db.exists());
    }
    let _ = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "Ctrl-C ends a grid with 130");
    let o = run(&["report", res.to_str().unwrap()]);
    assert!(
        !stdout(&o).starts_with("80 results"),
        "interrupted before the end: {}",
        stdout(&o)
    );
    let o = run_grid(&g, &res);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = dir.path().join("r.csv");
    run(&[
        "report",
        res.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut ids: Vec<&str> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert_eq!(ids.len(), 80);
    ids.sort();
    ids.dedup();
    assert_eq!(ids.len(), 80, "every job stored exactly once");
}

#[test]
fn layout_of_a_real_map_and_of_a_generated_building_with_truth() {
    let dir = tempfile::tempdir().unwrap();
    let map = maps_dir().join("schools/Franch1.yaml");
    let o = run(&[
        "layout",
        "--map",
        map.to_str().unwrap(),
        "--out",
        dir.path().join("f").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("f/layout.json")).unwrap())
            .unwrap();
    assert_eq!(j["format"], "floorcast-layout");
    assert!(j["rooms"].as_array().unwrap().len() >= 5);
    assert!(image::open(dir.path().join("f/layout.png")).is_ok());
    let b = repo().join("buildings/paper/paper-01.toml");
    let o = run(&[
        "layout",
        "--map",
        b.to_str().unwrap(),
        "--truth",
        b.to_str().unwrap(),
        "--out",
        dir.path().join("p").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let a: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("p/accuracy.json")).unwrap())
            .unwrap();
    assert!(a["matched_room_iou"].as_f64().unwrap() >= 0.8, "{a}");
}

/// Every grid shipped in `grids/` is valid and plans (its buildings found and read, its
/// strategies known, its settings in range), as a user's first `run` would check it.
#[test]
fn every_shipped_grid_plans() {
    let mut grids: Vec<_> = std::fs::read_dir(repo().join("grids"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    grids.sort();
    assert!(grids.len() >= 10, "{grids:?}");
    for g in grids {
        let res = tempfile::tempdir().unwrap();
        let o = run(&[
            "run",
            g.to_str().unwrap(),
            "--summary",
            "--results",
            res.path().to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}: {}", g.display(), stderr(&o));
        assert!(
            stdout(&o).contains("0 of ") && stdout(&o).contains("jobs stored in"),
            "{}: {}",
            g.display(),
            stdout(&o)
        );
        // A summary of a grid not run yet creates nothing.
        assert!(
            !res.path().join("results.sqlite").exists(),
            "{}: --summary made a store",
            g.display()
        );
    }
}

/// A count of local workers beyond 1024 is refused by the flag's own check, saying what was
/// expected. (More threads than the system allows is an error too, "could not start N worker
/// threads (give fewer --workers)", seen under `ulimit -v 1000000` with `--workers 1024`; not
/// tested here: under a limit of address space, other threads' allocations may fail first.)
#[test]
fn workers_beyond_1024_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let g = grid(dir.path(), "[1]");
    let res = dir.path().join("res");
    let o = run(&[
        "run",
        g.to_str().unwrap(),
        "--results",
        res.to_str().unwrap(),
        "--workers",
        "1025",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(
            "invalid value '1025' for '--workers <N>': expected a whole number from 0 to 1024"
        ),
        "{err}"
    );
    assert!(!res.exists());
}

/// `report` lists labels in their grid's order (not alphabetically), and `--plots` lays the
/// charts out for print: `--plot-width 3.5in --font-pt 8 --no-titles --picture pdf,svg` writes
/// PDFs whose page is 3.5 in (252 pt) wide and SVGs 3.5 in wide whose text is 8 pt at that
/// width, without titles.
#[test]
fn report_keeps_the_grid_order_and_draws_figures_for_print() {
    let dir = tempfile::tempdir().unwrap();
    let small = repo().join("buildings/small.toml");
    let g = dir.path().join("grid.toml");
    std::fs::write(
        &g,
        format!(
            r#"format = "floorcast-grid"
version = 1
name = "order"
buildings = ["{}"]
seeds = [1, 2]
[[strategies]]
name = "baseline"
label = "zz"
settings = {{ alpha = 0.8 }}
[[strategies]]
name = "baseline"
[[strategies]]
name = "baseline"
label = "aa"
settings = {{ alpha = 0.9 }}
"#,
            small.display()
        ),
    )
    .unwrap();
    let res = dir.path().join("res");
    let o = run_grid(&g, &res);
    assert!(o.status.success(), "{}", stderr(&o));
    let plots = dir.path().join("fig");
    let json = dir.path().join("r.json");
    let o = run(&[
        "report",
        res.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
        "--plots",
        plots.to_str().unwrap(),
        "--picture",
        "pdf,svg",
        "--plot-width",
        "3.5in",
        "--font-pt",
        "8",
        "--no-titles",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let labels: Vec<&str> = v["labels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["label"].as_str().unwrap())
        .collect();
    assert_eq!(labels, ["zz", "baseline", "aa"]);
    let text = stdout(&o);
    let at = |l: &str| {
        text.find(&format!("\n  {l} "))
            .unwrap_or_else(|| panic!("{text}"))
    };
    assert!(
        at("zz") < at("baseline") && at("baseline") < at("aa"),
        "{text}"
    );
    for chart in ["times", "gains", "profile", "progress-small"] {
        let pdf = std::fs::read(plots.join(format!("{chart}.pdf"))).unwrap();
        assert!(pdf.starts_with(b"%PDF"), "{chart}");
        let pdf = String::from_utf8_lossy(&pdf);
        assert!(
            pdf.contains("/MediaBox [0 0 252 "),
            "{chart}: no 252 pt page"
        );
        let svg = std::fs::read_to_string(plots.join(format!("{chart}.svg"))).unwrap();
        assert!(svg.contains("width=\"3.5000in\""), "{chart}");
        let view_w: f64 = svg
            .split("viewBox=\"0 0 ")
            .nth(1)
            .unwrap()
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let sizes: Vec<f64> = svg
            .split("font-size=\"")
            .skip(1)
            .map(|s| s.split('"').next().unwrap().parse().unwrap())
            .collect();
        assert!(!sizes.is_empty(), "{chart}");
        for size in sizes {
            let pt = size / view_w * 3.5 * 72.0;
            assert!((pt - 8.0).abs() < 0.05, "{chart}: text of {pt} pt");
        }
        assert!(!svg.contains("over baseline"), "{chart}: a title was drawn");
    }
}

/// `run` makes the known-map tour its runs need once (the one building and start here) and
/// stores it; `report` shows each label's efficiency (tour time / exploration time) and
/// `--json` holds it per label and per run; `--no-tours` makes none, and the report then has
/// no efficiency section.
#[test]
fn a_grid_run_stores_its_tour_and_report_shows_efficiency() {
    let dir = tempfile::tempdir().unwrap();
    let g = grid(dir.path(), "[1]");
    let text = std::fs::read_to_string(&g).unwrap();
    std::fs::write(&g, text.replace("time_limit_s = 60", "time_limit_s = 1200")).unwrap();
    let res = dir.path().join("res");
    let args = [
        "run",
        g.to_str().unwrap(),
        "--results",
        res.to_str().unwrap(),
        "-q",
    ];
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("making 1 known-map tour "),
        "{}",
        stdout(&o)
    );
    let again = run(&args);
    assert!(again.status.success(), "{}", stderr(&again));
    assert!(
        !stdout(&again).contains("known-map tour"),
        "{}",
        stdout(&again)
    );
    let json = dir.path().join("r.json");
    let o = run(&[
        "report",
        res.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("efficiency at 99 %"), "{}", stdout(&o));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let labels = v["efficiency"]["labels"].as_array().unwrap();
    let names: Vec<&str> = labels
        .iter()
        .map(|l| l["label"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["baseline", "near"]);
    for l in labels {
        let median = l["median"].as_f64().unwrap();
        assert!(median > 0.0 && median <= 1.05, "{l}");
        assert_eq!(l["runs"], 1);
    }
    assert_eq!(v["efficiency"]["runs"].as_array().unwrap().len(), 2);
    // The ranking: both labels, ranked 1 and 2, each with its median efficiency.
    let ranking = v["ranking"].as_array().unwrap();
    let ranks: Vec<u64> = ranking
        .iter()
        .map(|p| p["rank"].as_u64().unwrap())
        .collect();
    assert_eq!(ranks, [1, 2]);
    assert!(ranking
        .iter()
        .all(|p| p["median_efficiency"].as_f64().is_some()));

    let bare = dir.path().join("bare");
    let mut args = args.to_vec();
    args[3] = bare.to_str().unwrap();
    args.push("--no-tours");
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stdout(&o).contains("known-map tour"), "{}", stdout(&o));
    let o = run(&[
        "report",
        bare.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(!stdout(&o).contains("efficiency at"), "{}", stdout(&o));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["efficiency"]["labels"].as_array().unwrap().len(), 0);
}

/// Ctrl-C or SIGTERM while `run` makes its known-map tours (up to a minute each on a large
/// building) ends it within seconds with exit code 130, saying how many tours it kept; run
/// again, it makes the tour it lacks.
#[test]
fn an_interrupt_while_tours_are_made_ends_the_run_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("grid.toml");
    // One short run on a large building: its tour takes far longer than the run.
    std::fs::write(
        &g,
        r#"format = "floorcast-grid"
version = 1
name = "tours"
seeds = [1]
[[generated]]
seed = 7
area_m2 = 6000
kind = "office"
[[strategies]]
name = "baseline"
[settings]
time_limit_s = 20
"#,
    )
    .unwrap();
    let res = dir.path().join("res");
    for signal in ["TERM", "INT"] {
        let (mut child, lines) = spawn_lines(floorcast().args([
            "run",
            g.to_str().unwrap(),
            "--results",
            res.to_str().unwrap(),
            "--workers",
            "1",
            // Its estimate (~110 s) is over the default budget: made all the same here.
            "--tour-budget",
            "100000",
        ]));
        let t0 = std::time::Instant::now();
        let mut seen = Vec::new();
        while !seen
            .iter()
            .any(|l: &String| l.contains("making 1 known-map tour"))
        {
            let line = lines.recv_timeout(std::time::Duration::from_secs(120));
            seen.push(line.unwrap_or_else(|_| panic!("no tour began: {seen:?}")));
        }
        std::thread::sleep(std::time::Duration::from_millis(300));
        let sent = std::time::Instant::now();
        send_signal(child.id(), signal);
        let status = child.wait().unwrap();
        let waited = sent.elapsed();
        seen.extend(lines.try_iter());
        assert_eq!(status.code(), Some(130), "{signal}: {seen:?}");
        assert!(
            waited.as_secs_f64() < 5.0,
            "{signal}: {waited:?} after the signal"
        );
        assert!(
            seen.iter()
                .any(|l| l.contains("interrupted while making tours: 0 of 1 made")),
            "{signal}: {seen:?} ({:?} in all)",
            t0.elapsed()
        );
    }
}
