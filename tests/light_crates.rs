//! The library crates' dependency rules (ARCHITECTURE.md, "Code map"), read from `cargo tree`
//! as a user's build resolves them: the kernel, the settings and the statistics can be used
//! without a network transport, an async runtime or a database (and the kernel and the
//! settings without the command line's parser).

use std::process::Command;

/// (package, packages its tree must show (so that it was read), packages it must never depend
/// on, directly or through another).
const RULES: &[(&str, &[&str], &[&str])] = &[
    (
        "sim-core",
        &["sim-core", "rapier2d", "rand_chacha"],
        &["clap", "zenoh", "tokio", "rusqlite"],
    ),
    (
        "floorcast-settings",
        &["floorcast-settings", "sim-core", "serde_json"],
        &["clap", "zenoh", "tokio", "rusqlite"],
    ),
    (
        "floorcast-stats",
        &[
            "floorcast-stats",
            "floorcast-worker",
            "statrs",
            "serde_json",
        ],
        &["zenoh", "tokio", "rusqlite"],
    ),
];

/// The package names of `cargo tree -p package` (normal and build dependencies: what a user's
/// build compiles), one per line of its output.
fn dependency_names(package: &str) -> Vec<String> {
    let args = [
        "tree",
        "-p",
        package,
        "-e",
        "normal,build",
        "--prefix",
        "none",
        "--offline",
    ];
    let out = Command::new(env!("CARGO"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo tree -p {package} failed ({}): {}",
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
fn the_light_crates_keep_their_dependency_rules() {
    for &(package, expected, refused) in RULES {
        let names = dependency_names(package);
        for e in expected {
            assert!(
                names.iter().any(|n| n == e),
                "{package}: {e} not in cargo tree's output: {names:?}"
            );
        }
        let found: Vec<&String> = names
            .iter()
            .filter(|n| {
                refused
                    .iter()
                    .any(|r| n.as_str() == *r || n.starts_with(&format!("{r}-")))
            })
            .collect();
        assert!(
            found.is_empty(),
            "{package} depends on {found:?} (none of {refused:?} may be in its tree)"
        );
    }
}

/// The rule's reader sees a refused crate where there is one: the coordinator's tree holds
/// zenoh, tokio and rusqlite.
#[test]
fn the_reader_finds_a_refused_crate() {
    let names = dependency_names("floorcast-coordinator");
    for r in ["zenoh", "tokio", "rusqlite"] {
        assert!(names.iter().any(|n| n == r), "{r} not found: {names:?}");
    }
}
