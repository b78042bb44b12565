//! What is a type stays a type (ARCHITECTURE.md, issue 57): a job's status (`JobStatus`), a
//! run's end (`EndReason`) and a given start's source (`GivenSource`) are enums from the moment
//! they are read; only their codecs name their words. This test keeps their words out of the
//! rest of the code: no comparison of them with a string, no string-typed field for them.

mod common;

use std::path::Path;

use common::{code_lines, rust_files};

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
        for (n, line) in code_lines(&text) {
            for (refused, why) in REFUSED {
                if line.contains(refused) {
                    found.push(format!(
                        "{}:{n}: `{}`: {why}",
                        f.strip_prefix(root).unwrap().display(),
                        line.trim()
                    ));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "strings where types belong:\n{}",
        found.join("\n")
    );
}

/// The reading finds what it should, and leaves tests and comments alone.
#[test]
fn the_reader_sees_code_not_tests_or_comments() {
    let text = "let a = r.status == \"ok\";\n// r.status == \"ok\"\n#[cfg(test)]\nmod tests {\n x.status == \"ok\"\n}\n";
    let lines = code_lines(text);
    assert_eq!(lines, vec![(1, "let a = r.status == \"ok\";")]);
}
