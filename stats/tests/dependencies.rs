//! The statistics crate's rule (ARCHITECTURE.md, "Code map"): none of zenoh, tokio or rusqlite in
//! its dependency tree, so a program can use the statistics without a network transport, an
//! async runtime or a database. Read from `cargo tree`, as a user's build resolves it.

use std::path::Path;
use std::process::Command;

/// The crates the statistics must never depend on, directly or through another.
const REFUSED: &[&str] = &["zenoh", "tokio", "rusqlite"];

/// The package names of `cargo tree -p floorcast-stats` (normal and build dependencies: what a
/// user's build compiles), one per line of its output.
fn dependency_names() -> Vec<String> {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the crate lies in the workspace");
    let out = Command::new(env!("CARGO"))
        .args([
            "tree",
            "-p",
            "floorcast-stats",
            "-e",
            "normal,build",
            "--prefix",
            "none",
            "--offline",
        ])
        .current_dir(workspace)
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo tree failed ({}): {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .expect("cargo tree writes UTF-8")
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_string)
        .collect()
}

#[test]
fn no_network_runtime_or_database_in_the_dependency_tree() {
    let names = dependency_names();
    // The tree was read: the crate itself and what it is known to use are in it.
    for expected in [
        "floorcast-stats",
        "floorcast-worker",
        "statrs",
        "serde_json",
    ] {
        assert!(
            names.iter().any(|n| n == expected),
            "{expected} not in cargo tree's output: {names:?}"
        );
    }
    let found: Vec<&String> = names
        .iter()
        .filter(|n| {
            REFUSED
                .iter()
                .any(|r| n.as_str() == *r || n.starts_with(&format!("{r}-")))
        })
        .collect();
    assert!(
        found.is_empty(),
        "floorcast-stats depends on {found:?} (none of {REFUSED:?} may be in its tree)"
    );
}
