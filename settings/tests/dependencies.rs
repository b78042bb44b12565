//! The settings crate's rule (ARCHITECTURE.md, "Code map"): no clap in its dependency tree (nor
//! zenoh, tokio or rusqlite), so a program can read and check settings without the command
//! line's parser, a network transport, an async runtime or a database. Read from `cargo tree`,
//! as a user's build resolves it.

use std::path::Path;
use std::process::Command;

/// The crates the settings must never depend on, directly or through another.
const REFUSED: &[&str] = &["clap", "zenoh", "tokio", "rusqlite"];

/// The package names of `cargo tree -p floorcast-settings` (normal and build dependencies: what
/// a user's build compiles), one per line of its output.
fn dependency_names() -> Vec<String> {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the crate lies in the workspace");
    let out = Command::new(env!("CARGO"))
        .args([
            "tree",
            "-p",
            "floorcast-settings",
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
fn no_command_line_parser_network_runtime_or_database_in_the_dependency_tree() {
    let names = dependency_names();
    // The tree was read: the crate itself and what it is known to use are in it.
    for expected in ["floorcast-settings", "sim-core", "serde_json"] {
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
        "floorcast-settings depends on {found:?} (none of {REFUSED:?} may be in its tree)"
    );
}
