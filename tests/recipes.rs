//! ARCHITECTURE.md's "Where to add" recipes, checked by counting what each asks for: every map
//! format `read_building` accepts comes with its reader module, its malformed inputs (the
//! corpus of `tests/malformed/`) and a valid example in the repository.

use std::collections::BTreeSet;
use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn read(path: &str) -> String {
    std::fs::read_to_string(root().join(path)).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The extensions `formats::read_building` dispatches on (its `kind_of` match arms), each with
/// the `Kind` it chooses.
fn format_extensions() -> Vec<(String, String)> {
    let lib = read("formats/src/lib.rs");
    let start = lib
        .find("fn kind_of(")
        .expect("formats/src/lib.rs: fn kind_of");
    let body = &lib[start..start + lib[start..].find("\n}\n").unwrap()];
    let mut out = Vec::new();
    for line in body.lines().filter(|l| l.contains("=> Ok(Kind::")) {
        let kind = line
            .split("Kind::")
            .nth(1)
            .unwrap()
            .trim_end_matches([')', ',']);
        for ext in line.split('"').skip(1).step_by(2) {
            out.push((ext.to_string(), kind.to_string()));
        }
    }
    out
}

/// Files under `dir` (recursively) with extension `ext`.
fn files_with(dir: &Path, ext: &str, out: &mut Vec<std::path::PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            files_with(&p, ext, out);
        } else if p.extension().is_some_and(|x| x.eq_ignore_ascii_case(ext)) {
            out.push(p);
        }
    }
}

/// A map format: `read_building` chooses it by extension, a reader function of a module of
/// `formats/src/` reads it, the malformed corpus has cases of it that the CLI runs, and the
/// repository holds an example (under `maps/` or `buildings/`).
#[test]
fn every_map_format_has_its_reader_malformed_cases_and_an_example() {
    let exts = format_extensions();
    let kinds: BTreeSet<&str> = exts.iter().map(|(_, k)| k.as_str()).collect();
    assert!(kinds.len() >= 4, "formats read: {exts:?}");
    let lib = read("formats/src/lib.rs");
    let cases = read("tests/malformed/cases.toml");
    for kind in kinds {
        // The reader: `Kind::X => ... read_x(path) ...` in `read_building`, `read_x` defined in
        // a module of its own.
        let arm = lib
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("Kind::{kind} =>")))
            .unwrap_or_else(|| panic!("read_building has no arm for Kind::{kind}"));
        let reader: String = arm
            .split("read_")
            .nth(1)
            .map(|r| r.chars().take_while(|c| c.is_alphanumeric() || *c == '_'))
            .unwrap_or_else(|| panic!("Kind::{kind}: no read_ function in {arm}"))
            .collect();
        let defined = std::fs::read_dir(root().join("formats/src"))
            .unwrap()
            .flatten()
            .map(|e| e.path())
            .filter(|p| !p.ends_with("lib.rs"))
            .any(|p| {
                let text = std::fs::read_to_string(&p).unwrap_or_default();
                text.contains(&format!("pub fn read_{reader}("))
            });
        assert!(
            defined,
            "Kind::{kind}: read_{reader} not defined in a module of formats/src"
        );
        let ext_of_kind: Vec<&str> = exts
            .iter()
            .filter(|(_, k)| k == kind)
            .map(|(e, _)| e.as_str())
            .collect();
        let mut malformed = Vec::new();
        let mut examples = Vec::new();
        for ext in &ext_of_kind {
            files_with(&root().join("tests/malformed/files"), ext, &mut malformed);
            files_with(&root().join("maps"), ext, &mut examples);
            files_with(&root().join("buildings"), ext, &mut examples);
        }
        let run: Vec<_> = malformed
            .iter()
            .filter(|p| cases.contains(p.file_name().unwrap().to_str().unwrap()))
            .collect();
        assert!(
            !run.is_empty(),
            "Kind::{kind} ({ext_of_kind:?}): no malformed case"
        );
        assert!(
            !examples.is_empty(),
            "Kind::{kind} ({ext_of_kind:?}): no example"
        );
    }
}

/// The reader of the recipe's count sees what a fifth format would add.
#[test]
fn the_format_count_reads_the_dispatch() {
    let exts = format_extensions();
    for (e, k) in [
        ("yaml", "MapServer"),
        ("yml", "MapServer"),
        ("xml", "FloorPlan"),
    ] {
        assert!(exts.contains(&(e.to_string(), k.to_string())), "{exts:?}");
    }
}
