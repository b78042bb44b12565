//! Modules depend one way (ARCHITECTURE.md, "Invariants"): within each crate no module uses
//! another that uses it back, directly or round a circle.
//!
//! The graph is read from the sources as text: a module uses another where its code (its tests
//! left out) names a path `crate::a::b` or `super::b`, or imports a group `crate::{a, b}`, and
//! the longest prefix of that path that is a module of the crate is the one used. A module
//! naming its own parent (`super::Config` in `layout/lines.rs`) is not counted: a folder's root
//! holds what its files share, and declares them. Under [`STRICT`] (sim-core's `explore`, the
//! run's state machine) that is counted too, and so is a folder's root naming its children
//! (`self::a`, `a::` in its own code; its `pub use` re-exports and `mod` declarations aside): no
//! two modules there use each other, the root included. No crate's module imports its parent
//! with a glob (`use super::*`) outside its tests.

mod common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Module paths (`layout::directions`) of a crate's files, with their files.
fn modules(src: &Path) -> BTreeMap<Vec<String>, PathBuf> {
    let mut out = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let rel = path.strip_prefix(src).unwrap().with_extension("");
            let mut parts: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            let last = parts.last().cloned().unwrap_or_default();
            if last == "mod" || (parts.len() == 1 && (last == "lib" || last == "main")) {
                parts.pop();
            }
            // A folder's `tests.rs` is test code (`#[cfg(test)] mod tests;`).
            if last == "tests" {
                continue;
            }
            out.insert(parts, path);
        }
    }
    out
}

/// The code of a file without its test modules and comments ([`common::code_lines`]).
fn code_of(text: &str) -> String {
    common::code_lines(text)
        .into_iter()
        .map(|(_, l)| l)
        .collect::<Vec<_>>()
        .join("\n")
}

/// The paths a piece of code names after `prefix` (`crate::` or `super::`): each as its
/// segments, with the first-level names of a group `prefix{a, b::c}` each a path.
fn paths_after(code: &str, prefix: &str) -> Vec<Vec<String>> {
    let ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find(prefix) {
        // Not the tail of a longer name (`mycrate::`).
        let before_ok = rest[..at].chars().next_back().is_none_or(|c| !ident(c));
        rest = &rest[at + prefix.len()..];
        if !before_ok {
            continue;
        }
        if let Some(group) = rest.strip_prefix('{') {
            // The group's first-level items, split at the commas outside nested groups.
            let (mut depth, mut start) = (0i32, 0usize);
            let mut items = Vec::new();
            for (k, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => {
                        items.push(&group[start..k]);
                        break;
                    }
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        items.push(&group[start..k]);
                        start = k + 1;
                    }
                    _ => {}
                }
            }
            for item in items {
                let segs: Vec<String> = item
                    .trim()
                    .split("::")
                    .map(str::trim)
                    .take_while(|s| !s.is_empty() && s.chars().all(ident))
                    .map(str::to_string)
                    .collect();
                if !segs.is_empty() {
                    out.push(segs);
                }
            }
            continue;
        }
        let mut segs = Vec::new();
        let mut tail = rest;
        loop {
            let n = tail.find(|c: char| !ident(c)).unwrap_or(tail.len());
            if n == 0 {
                break;
            }
            segs.push(tail[..n].to_string());
            match tail[n..].strip_prefix("::") {
                Some(t) if t.starts_with(|c: char| ident(c)) => tail = t,
                _ => break,
            }
        }
        if !segs.is_empty() {
            out.push(segs);
        }
    }
    out
}

/// The longest prefix of `path` that is a module of the crate.
fn module_of(path: &[String], modules: &BTreeMap<Vec<String>, PathBuf>) -> Option<Vec<String>> {
    (1..=path.len())
        .rev()
        .map(|n| path[..n].to_vec())
        .find(|p| modules.contains_key(p))
}

/// The folders, by crate source, whose modules follow the strict rule (see the module doc).
const STRICT: &[(&str, &str)] = &[("sim-core/src", "explore")];

/// Whether `module` lies under a strict folder of `src`.
fn strict(src: &Path, module: &[String]) -> bool {
    STRICT
        .iter()
        .any(|(s, folder)| src.ends_with(s) && module.first().is_some_and(|m| m == folder))
}

/// Whether `code` names `prefix` where a path begins (not as the tail of a longer name).
fn names(code: &str, prefix: &str) -> bool {
    let ident = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == ':';
    code.match_indices(prefix)
        .any(|(at, _)| code[..at].chars().next_back().is_none_or(|c| !ident(c)))
}

/// A folder root's own code: its `pub use` re-exports and `mod` declarations taken out.
fn own_code(code: &str) -> String {
    let mut out = String::new();
    for statement in code.split_inclusive(';') {
        let t = statement.trim_start();
        let declaration = [
            "pub use ",
            "pub(crate) use ",
            "mod ",
            "pub mod ",
            "pub(crate) mod ",
        ]
        .iter()
        .any(|k| t.starts_with(k));
        if !declaration {
            out.push_str(statement);
        }
    }
    out
}

/// Each module's uses of the crate's other modules (not of its ancestors; under [`STRICT`], of
/// its parent and, for a folder's root, of its children too).
fn graph(src: &Path) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let modules = modules(src);
    let mut edges: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (module, file) in &modules {
        let code = code_of(&std::fs::read_to_string(file).unwrap());
        let is_root = file.file_name().is_some_and(|n| n == "mod.rs");
        if strict(src, module) && is_root {
            let own = own_code(&code);
            let children = modules
                .keys()
                .filter(|m| m.len() == module.len() + 1 && m[..module.len()] == module[..]);
            let uses = edges.entry(module.clone()).or_default();
            for child in children {
                let name = child.last().unwrap();
                let named =
                    names(&own, &format!("self::{name}::")) || names(&own, &format!("{name}::"));
                if named {
                    uses.insert(child.clone());
                }
            }
        }
        // `super::` of `a/b.rs` (module `a::b`) is `a`; of `a/mod.rs` (module `a`), `a`'s parent.
        let parent: Vec<String> = module[..module.len().saturating_sub(1)].to_vec();
        let mut named: Vec<Vec<String>> = paths_after(&code, "crate::");
        for p in paths_after(&code, "super::") {
            named.push(parent.iter().cloned().chain(p).collect());
        }
        let uses = edges.entry(module.clone()).or_default();
        for p in named {
            if let Some(m) = module_of(&p, &modules) {
                let ancestor = m.len() < module.len() && module[..m.len()] == m[..];
                let parent_counted = strict(src, module) && m.len() + 1 == module.len();
                if m != *module && (!ancestor || parent_counted) && !m.is_empty() {
                    uses.insert(m);
                }
            }
        }
    }
    edges
}

/// A circle of the graph, if any (depth-first search).
fn circle(edges: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>) -> Option<Vec<Vec<String>>> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        Open,
        Done,
    }
    fn visit(
        m: &Vec<String>,
        edges: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
        marks: &mut BTreeMap<Vec<String>, Mark>,
        stack: &mut Vec<Vec<String>>,
    ) -> Option<Vec<Vec<String>>> {
        marks.insert(m.clone(), Mark::Open);
        stack.push(m.clone());
        for next in edges.get(m).into_iter().flatten() {
            match marks.get(next) {
                Some(Mark::Open) => {
                    let from = stack.iter().position(|s| s == next).unwrap();
                    let mut c = stack[from..].to_vec();
                    c.push(next.clone());
                    return Some(c);
                }
                Some(Mark::Done) => {}
                None => {
                    if let Some(c) = visit(next, edges, marks, stack) {
                        return Some(c);
                    }
                }
            }
        }
        stack.pop();
        marks.insert(m.clone(), Mark::Done);
        None
    }
    let mut marks = BTreeMap::new();
    for m in edges.keys() {
        if !marks.contains_key(m) {
            if let Some(c) = visit(m, edges, &mut marks, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

#[test]
fn no_crate_has_a_module_cycle() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for src in common::CRATE_SOURCES {
        let edges = graph(&root.join(src));
        // The reading finds the graph it should: a crate of more than one module has arrows.
        assert!(
            edges.len() < 3 || edges.values().any(|u| !u.is_empty()),
            "{src}: no module uses another: the sources were not read"
        );
        if let Some(c) = circle(&edges) {
            let names: Vec<String> = c.iter().map(|m| m.join("::")).collect();
            panic!(
                "{src}: modules use each other round a circle: {}",
                names.join(" -> ")
            );
        }
    }
}

/// No module imports its parent with a glob outside its tests: what it uses is named.
#[test]
fn no_module_imports_its_parent_with_a_glob() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut globs = Vec::new();
    for src in common::CRATE_SOURCES {
        for (module, file) in modules(&root.join(src)) {
            let code = code_of(&std::fs::read_to_string(&file).unwrap());
            if code.contains("use super::*") {
                globs.push(format!("{src}: {}", module.join("::")));
            }
        }
    }
    assert!(
        globs.is_empty(),
        "modules importing their parent with a glob: {globs:?}"
    );
}

/// The functions of `text` (its tests left out, comments counted) longer than `max` lines, from
/// `fn` to its closing brace: each as its name and length.
fn long_functions(text: &str, max: usize) -> Vec<(String, usize)> {
    let lines: Vec<(usize, &str)> = text.lines().enumerate().collect();
    let code: BTreeSet<usize> = common::code_lines(text)
        .iter()
        .map(|(n, _)| n - 1)
        .collect();
    let mut out = Vec::new();
    for &(i, l) in &lines {
        let t = l.trim_start();
        let head = t
            .trim_start_matches("pub(crate) ")
            .trim_start_matches("pub(super) ")
            .trim_start_matches("pub ")
            .trim_start_matches("const ")
            .trim_start_matches("async ");
        let Some(rest) = head.strip_prefix("fn ") else {
            continue;
        };
        if !code.contains(&i) || l.trim_end().ends_with(';') {
            continue;
        }
        let indent = &l[..l.len() - t.len()];
        let close = format!("{indent}}}");
        if let Some(end) = lines[i + 1..].iter().position(|(_, m)| *m == close) {
            let n = end + 2;
            if n > max {
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                out.push((name, n));
            }
        }
    }
    out
}

/// No function of sim-core (the kernel every run goes through) is over 100 lines, its tests
/// aside.
#[test]
fn no_function_of_sim_core_is_over_100_lines() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut long = Vec::new();
    for (module, file) in modules(&root.join("sim-core/src")) {
        for (name, n) in long_functions(&std::fs::read_to_string(&file).unwrap(), 100) {
            long.push(format!("{}::{name} ({n} lines)", module.join("::")));
        }
    }
    assert!(long.is_empty(), "functions over 100 lines: {long:?}");
    let body = (0..101).map(|_| "    x();\n").collect::<String>();
    let text = format!("pub fn long() {{\n{body}}}\n\nfn short() {{\n}}\n");
    assert_eq!(long_functions(&text, 100), vec![("long".to_string(), 103)]);
}

/// The strict rule finds a root and its child using each other, and ignores re-exports.
#[test]
fn the_strict_rule_sees_a_root_and_its_children() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("sim-core/src");
    std::fs::create_dir_all(src.join("explore")).unwrap();
    std::fs::write(src.join("lib.rs"), "pub mod explore;\n").unwrap();
    let write = |root: &str, child: &str| {
        std::fs::write(src.join("explore/mod.rs"), root).unwrap();
        std::fs::write(src.join("explore/a.rs"), child).unwrap();
    };
    // Re-exports and declarations only: no circle.
    write(
        "mod a;\npub use a::{A, B};\n",
        "use super::super::geom::X;\npub struct A;\n",
    );
    assert_eq!(circle(&graph(&src)), None);
    // The root's code uses its child, which names the root: a circle.
    write(
        "mod a;\npub struct Shared;\nfn f() -> a::A { a::A }\n",
        "use super::Shared;\npub struct A;\n",
    );
    assert!(circle(&graph(&src)).is_some());
    // A glob of the child in the root's code counts.
    write(
        "mod a;\nuse self::a::*;\npub struct Shared;\n",
        "use super::Shared;\npub struct A;\n",
    );
    assert!(circle(&graph(&src)).is_some());
    assert!(own_code("pub use a::{\n B,\n};\nfn g() {}")
        .find("a::")
        .is_none());
}

/// The reading itself, on cases with a known answer.
#[test]
fn the_reader_finds_paths_groups_and_circles() {
    let cases: &[(&str, &str, Vec<&str>)] = &[
        (
            "use crate::store::StoredResult;",
            "crate::",
            vec!["store::StoredResult"],
        ),
        (
            "use crate::{outcome::{self, Pair}, store};",
            "crate::",
            vec!["outcome", "store"],
        ),
        (
            "x = crate::sprt::MIN_PAIRS as u128;",
            "crate::",
            vec!["sprt::MIN_PAIRS"],
        ),
        ("use floorcast_crate::a;", "crate::", vec![]),
        (
            "let a = super::directions::rem_pi(a);",
            "super::",
            vec!["directions::rem_pi"],
        ),
    ];
    for (code, prefix, want) in cases {
        let got: Vec<String> = paths_after(code, prefix)
            .into_iter()
            .map(|p| p.join("::"))
            .collect();
        assert_eq!(got, *want, "{code}");
    }
    let m = |s: &str| s.split("::").map(str::to_string).collect::<Vec<_>>();
    let mut edges: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    edges.entry(m("a")).or_default().insert(m("b"));
    edges.entry(m("b")).or_default().insert(m("c"));
    edges.entry(m("c")).or_default();
    assert_eq!(circle(&edges), None);
    edges.entry(m("c")).or_default().insert(m("a"));
    assert_eq!(circle(&edges), Some(vec![m("a"), m("b"), m("c"), m("a")]));
    assert!(
        code_of("fn f() {}\n#[cfg(test)]\nmod tests {\n use crate::x;\n}")
            .find("crate::x")
            .is_none()
    );
}

/// The drivers of a run, floorcast's own loop (`explore_with`) and the grid's worker path
/// (`run_job`), are short functions over an `Episode` (issue 79): each under 60 lines, and each
/// makes an episode and hands it to the driver loop.
#[test]
fn the_drivers_of_a_run_are_short_and_over_an_episode() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (file, name) in [
        ("sim-core/src/explore/drive.rs", "explore_with"),
        ("worker/src/lib.rs", "run_job_from"),
    ] {
        let text = std::fs::read_to_string(root.join(file)).unwrap();
        let all = long_functions(&text, 0);
        let Some(&(_, n)) = all.iter().find(|(f, _)| f == name) else {
            panic!("{file}: no function {name}");
        };
        assert!(n < 60, "{file}: {name} is {n} lines");
        let start = text.find(&format!("fn {name}(")).unwrap();
        let body: String = text[start..].lines().take(n).collect::<Vec<_>>().join("\n");
        assert!(
            body.contains("Episode::") && body.contains("drive_to_end("),
            "{file}: {name} does not make an Episode and drive it"
        );
    }
}
