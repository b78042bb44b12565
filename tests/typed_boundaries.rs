//! What is a type stays a type (ARCHITECTURE.md, issue 57): a job's status (`JobStatus`), a
//! run's end (`EndReason`), a given start's source (`GivenSource`) and a compared metric
//! (`Metric`) are enums from the moment they are read; only their codecs name their words. A
//! stored row's contents (settings, run summary, progress curve) are decoded once, by the store
//! (`coordinator/src/store.rs`), into `StoredResult`'s typed fields (a `floorcast-stats` type).
//! This test keeps their words and texts out of the rest of the code: no comparison of them with
//! a string, no string-typed field for them, no second reading of a row's text.

mod common;

use std::path::Path;

use common::{code_lines, rust_files};

/// The store, the one reader and writer of a row's text (and the statistics' test fixtures, which
/// make rows as it reads them).
const STORE: &[&str] = &["coordinator/src/store.rs", "stats/src/fixtures.rs"];
/// The metrics' codec.
const METRIC: &[&str] = &["stats/src/metric.rs"];

/// (what is refused, why) as plain substrings of a line of code.
const REFUSED: &[(&str, &str)] = &[
    (".status == \"", "a job's status is a JobStatus"),
    (".status != \"", "a job's status is a JobStatus"),
    ("status: String", "a job's status is a JobStatus"),
    ("end_reason == \"", "a run's end is an EndReason"),
    ("end_reason != \"", "a run's end is an EndReason"),
    (
        "end_reason.as_str() ==",
        "a run's end is an EndReason: match on it",
    ),
    ("end_reason: String", "a run's end is an EndReason"),
    ("GivenStart::RANDOM", "a start's source is a GivenSource"),
    ("GivenStart::GRID", "a start's source is a GivenSource"),
    ("PlannedStart", "a start is one type, GivenStart"),
    (
        "BTreeMap<String, MetricGain>",
        "a metric is a Metric, not its word",
    ),
];

/// (what is refused, why, the files where it belongs) as plain substrings of a line of code.
const REFUSED_BUT_IN: &[(&str, &str, &[&str])] = &[
    (
        "summary_json",
        "a stored summary is decoded once, by the store: use StoredResult::summary",
        STORE,
    ),
    (
        "settings_json",
        "stored settings are decoded once, by the store: use StoredResult::settings",
        STORE,
    ),
    (
        ".progress_csv",
        "a stored progress curve is decoded once, by the store: use StoredResult::progress",
        STORE,
    ),
    (
        "progress_csv:",
        "a stored progress curve is decoded once, by the store: use StoredResult::progress",
        STORE,
    ),
    (
        "RunSummary::from_json",
        "a stored summary is decoded once, by the store: use StoredResult::summary",
        STORE,
    ),
    (
        "progress::decode",
        "a stored progress curve is decoded once, by the store: use StoredResult::progress",
        STORE,
    ),
    (
        "\"time_to_9",
        "a metric is a Metric: its word is Metric::as_str",
        METRIC,
    ),
    (
        "\"unexplored_area_s",
        "a metric is a Metric: its word is Metric::as_str",
        METRIC,
    ),
    (
        "\"explored_fraction_points",
        "a metric is a Metric: its word is Metric::as_str",
        METRIC,
    ),
];

#[test]
fn typed_values_are_not_compared_as_strings() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for c in common::CRATE_SOURCES {
        rust_files(&root.join(c), &mut files);
    }
    assert!(
        files.len() > 50,
        "the sources were not found: {}",
        files.len()
    );
    let mut found = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        let name = f.strip_prefix(root).unwrap().to_string_lossy().into_owned();
        found.extend(refused_in(&name, &text));
    }
    assert!(
        found.is_empty(),
        "strings where types belong:\n{}",
        found.join("\n")
    );
}

/// The refused lines of file `name` (its path from the workspace's root) holding `text`.
fn refused_in(name: &str, text: &str) -> Vec<String> {
    let refused = REFUSED
        .iter()
        .map(|(r, why)| (*r, *why))
        .chain(
            REFUSED_BUT_IN
                .iter()
                .filter(|(_, _, there)| !there.contains(&name))
                .map(|(r, why, _)| (*r, *why)),
        )
        .collect::<Vec<_>>();
    let mut found = Vec::new();
    for (n, line) in code_lines(text) {
        for (refused, why) in &refused {
            if line.contains(refused) {
                found.push(format!("{name}:{n}: `{}`: {why}", line.trim()));
            }
        }
    }
    found
}

/// A row's text read again outside the store, or a metric named by its word outside its codec,
/// is found; in the store and the codec, it is not.
#[test]
fn planted_readings_of_stored_text_are_found() {
    let planted = [
        "let v: Value = serde_json::from_str(r.summary_json.as_deref()?).ok()?;",
        "let limit = time_limit_of(&r.settings_json);",
        "let t = time_to_fraction(r.progress_csv.as_deref()?, 0.9);",
        "let s = RunSummary::from_json(text)?;",
        "for s in crate::progress::decode(text) {}",
        "\"time_to_90_s\" => time_to_fraction(p, 0.90),",
        "pub metrics: BTreeMap<String, MetricGain>,",
    ];
    for line in planted {
        assert_eq!(
            refused_in("stats/src/table.rs", line).len(),
            1,
            "not found: {line}"
        );
    }
    assert!(refused_in("coordinator/src/store.rs", planted[0]).is_empty());
    assert!(refused_in("stats/src/metric.rs", planted[5]).is_empty());
}

/// The reading finds what it should, and leaves tests and comments alone.
#[test]
fn the_reader_sees_code_not_tests_or_comments() {
    let text = "let a = r.status == \"ok\";\n// r.status == \"ok\"\n#[cfg(test)]\nmod tests {\n x.status == \"ok\"\n}\n";
    let lines = code_lines(text);
    assert_eq!(lines, vec![(1, "let a = r.status == \"ok\";")]);
}
