//! The built-in strategies are registered values (sim-core's `explore/strategies/`): every
//! registered strategy is listed by `floorcast strategy list`, in the README's table and in
//! docs/settings.md, and a strategy is one file of that folder plus its line in the registry
//! (its name written in no other file of sim-core's code).

mod common;

use std::path::Path;

use common::*;
use sim_core::explore::BUILT_IN;

#[test]
fn every_registered_strategy_is_listed_and_documented() {
    let o = run(&["strategy", "list"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let listed: Vec<String> = stdout(&o)
        .lines()
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .collect();
    let readme = std::fs::read_to_string(repo().join("README.md")).unwrap();
    let table = between(
        &readme,
        "<!-- strategies:begin -->",
        "<!-- strategies:end -->",
    );
    let settings = std::fs::read_to_string(repo().join("docs/settings.md")).unwrap();
    let read = between(
        &settings,
        "<!-- strategy-settings:begin -->",
        "<!-- strategy-settings:end -->",
    );
    assert_eq!(listed.len(), BUILT_IN.len(), "{listed:?}");
    for b in BUILT_IN {
        let row = format!("| `{}` |", b.name);
        assert!(
            listed.iter().any(|l| l == b.name),
            "`floorcast strategy list` does not list {}",
            b.name
        );
        assert!(table.contains(&row), "README.md's table lacks {}", b.name);
        assert!(read.contains(&row), "docs/settings.md lacks {}", b.name);
    }
}

/// The text of `text` between the lines `begin` and `end`.
fn between<'a>(text: &'a str, begin: &str, end: &str) -> &'a str {
    let a = text.find(begin).unwrap_or_else(|| panic!("no {begin}")) + begin.len();
    let b = text[a..].find(end).unwrap_or_else(|| panic!("no {end}")) + a;
    &text[a..b]
}

/// A strategy is one file: each registered name is written (as a string) in exactly one file of
/// `sim-core/src/explore/strategies/` and in no other file of sim-core's code (tests aside), and
/// the registry holds one line per strategy.
#[test]
fn a_strategy_is_one_file_and_one_registry_line() {
    let src = repo().join("sim-core/src");
    let folder = src.join("explore/strategies");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let code: Vec<(&Path, String)> = files
        .iter()
        .filter(|f| f.file_name().is_some_and(|n| n != "tests.rs"))
        .map(|f| {
            let text = std::fs::read_to_string(f).unwrap();
            let lines: Vec<&str> = code_lines(&text).into_iter().map(|(_, l)| l).collect();
            (f.as_path(), lines.join("\n"))
        })
        .collect();
    let registry = std::fs::read_to_string(folder.join("mod.rs")).unwrap();
    for b in BUILT_IN {
        let quoted = format!("\"{}\"", b.name);
        let holding: Vec<&Path> = code
            .iter()
            .filter(|(_, c)| c.contains(&quoted))
            .map(|(f, _)| *f)
            .collect();
        assert_eq!(
            holding.len(),
            1,
            "{} is written in {holding:?}: a strategy's name belongs to its one file",
            b.name
        );
        let file = holding[0];
        assert_eq!(file.parent(), Some(folder.as_path()), "{}", b.name);
        let module = file.file_stem().unwrap().to_string_lossy().into_owned();
        assert_eq!(module, b.name.replace('-', "_"), "{}'s file", b.name);
        let line = format!("    {module}::STRATEGY,\n");
        assert_eq!(
            registry.matches(&line).count(),
            1,
            "the registry (strategies/mod.rs) has no line `{}`",
            line.trim()
        );
    }
    // Every file of the folder but the registry and the shared part is a registered strategy.
    let mut strategy_files = 0;
    for f in std::fs::read_dir(&folder).unwrap() {
        let name = f.unwrap().file_name().to_string_lossy().into_owned();
        if name != "mod.rs" && name != "shared.rs" {
            strategy_files += 1;
        }
    }
    assert_eq!(strategy_files, BUILT_IN.len());
}
