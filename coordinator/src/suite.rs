//! Suites in grids and stores: finding a suite's manifest by name (`suites/NAME.toml` in a
//! folder or one above it) or by path, and the suites a results store's runs were planned from.
//! The manifest format is `floorcast_formats::suite`'s.
//!
//! A run's record carries the suite its building was planned from (`RunSummary::suite` and
//! `suite_hash`, set by the coordinator from the plan: a job's id does not hash them, so a
//! building planned from a suite and from a grid's `buildings` is one job, stored once, with
//! the record of the grid that ran it first). One results directory holds one version of a
//! suite: `run` refuses a grid whose suite has another hash than the runs of that suite already
//! stored ([`check_stored_suites`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use floorcast_formats::suite::suite_name;
use floorcast_worker::text::excerpt;

use crate::store::StoredResult;

/// The folder suites are looked for in, under `base` or a folder above it.
pub const SUITES_DIR: &str = "suites";

/// A suite of a plan: its name, hash, manifest and number of buildings.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedSuite {
    pub name: String,
    pub hash: String,
    pub manifest: PathBuf,
    pub buildings: usize,
}

/// The first `suites/` folder in `base` or a folder above it (as a path relative to the
/// current directory when it is under it).
pub fn suites_dir(base: &Path) -> Option<PathBuf> {
    // "" (the parent of a bare file name) is the current folder.
    let base = if base.as_os_str().is_empty() {
        Path::new(".")
    } else {
        base
    };
    let abs = std::path::absolute(base).ok()?;
    let cwd = std::env::current_dir().ok();
    for dir in abs.ancestors() {
        let candidate = dir.join(SUITES_DIR);
        if candidate.is_dir() {
            return Some(
                match cwd.as_deref().and_then(|c| candidate.strip_prefix(c).ok()) {
                    Some(rel) if !rel.as_os_str().is_empty() => rel.to_path_buf(),
                    _ => candidate,
                },
            );
        }
    }
    None
}

/// The manifests of a `suites/` folder, sorted by file name.
pub fn manifests_in(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let entries =
        std::fs::read_dir(dir).map_err(|e| format!("cannot read {}: {e}", dir.display()))?;
    let mut out: Vec<PathBuf> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml") && p.is_file())
        .collect();
    out.sort();
    Ok(out)
}

/// Whether `spec` names a suite by its manifest's path (it ends in `.toml` or holds a path
/// separator) rather than by name.
pub fn is_path(spec: &str) -> bool {
    spec.ends_with(".toml") || spec.contains('/') || spec.contains('\\')
}

/// The manifest `spec` names: a path (relative to `base`), or a suite's name, found as
/// `suites/NAME.toml` in `base` or the nearest folder above it that has a `suites/` folder.
pub fn find_suite(spec: &str, base: &Path) -> Result<PathBuf, String> {
    if spec.trim().is_empty() {
        return Err(
            "is empty; expected a suite's name such as \"real-schools\" or its manifest's path"
                .into(),
        );
    }
    if is_path(spec) {
        return Ok(base.join(spec));
    }
    let name = suite_name(spec)?;
    let Some(dir) = suites_dir(base) else {
        return Err(format!(
            "no suite named '{name}': there is no {SUITES_DIR}/ folder in {} or a folder above it; give the manifest's path (e.g. ../suites/{name}.toml)",
            shown_dir(base)
        ));
    };
    let path = dir.join(format!("{name}.toml"));
    if path.is_file() {
        return Ok(path);
    }
    let known: Vec<String> = manifests_in(&dir)
        .unwrap_or_default()
        .iter()
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    Err(format!(
        "no suite named '{name}' in {} (its suites: {}); `floorcast suite list` lists them, or give a manifest's path",
        dir.display(),
        if known.is_empty() {
            "none".to_string()
        } else {
            excerpt(&known.join(", "))
        }
    ))
}

fn shown_dir(base: &Path) -> String {
    if base.as_os_str().is_empty() {
        ".".into()
    } else {
        base.display().to_string()
    }
}

/// The suites of a store's runs: (name, hash) with their number of runs, sorted.
pub fn stored_suites(results: &[StoredResult]) -> Vec<(String, String, usize)> {
    let mut count: BTreeMap<(String, String), usize> = BTreeMap::new();
    for r in results {
        let Some(s) = &r.summary else {
            continue;
        };
        if let (Some(name), Some(hash)) = (&s.suite, &s.suite_hash) {
            *count.entry((name.clone(), hash.clone())).or_default() += 1;
        }
    }
    count.into_iter().map(|((n, h), c)| (n, h, c)).collect()
}

/// A store holds one version of each suite: refused when `suites` (a plan's) has a suite whose
/// name the store's runs carry with another hash.
pub fn check_stored_suites(suites: &[PlannedSuite], stored: &[StoredResult]) -> Result<(), String> {
    for (name, hash, runs) in stored_suites(stored) {
        if let Some(s) = suites.iter().find(|s| s.name == name && s.hash != hash) {
            return Err(format!(
                "suite {name} has hash {} here ({}), and the {runs} runs of suite {name} stored there have hash {hash}: its buildings changed since (`floorcast suite check {name}` says which); one results directory holds one version of a suite: give another --results directory",
                s.hash,
                s.manifest.display()
            ));
        }
    }
    Ok(())
}

/// Lines saying which suites a store's runs come from (one per suite and hash; a suite name
/// with two hashes is said to be two versions).
pub fn describe_suites(results: &[StoredResult]) -> Vec<String> {
    let suites = stored_suites(results);
    let mut lines = Vec::new();
    for (name, hash, runs) in &suites {
        let versions = suites.iter().filter(|(n, _, _)| n == name).count();
        lines.push(format!(
            "suite {name}, hash {hash}: {runs} runs{}",
            if versions > 1 {
                format!(" (suite {name} has {versions} versions here: their buildings differ)")
            } else {
                String::new()
            }
        ));
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Records of version 1 (no suite) and 2 read; a store holds one hash of a suite name.
    #[test]
    fn a_store_holds_one_version_of_a_suite_and_old_records_read() {
        use floorcast_worker::RunSummary;
        // A record as written (text), edited.
        let edit = |r: &StoredResult, f: &dyn Fn(&mut serde_json::Value)| {
            let mut v = serde_json::to_value(r.summary.as_ref().unwrap()).unwrap();
            f(&mut v);
            v.to_string()
        };
        // The row holding a record read from its text.
        let with = |r: &StoredResult, text: &str| StoredResult {
            summary: Some(RunSummary::from_json(text).unwrap()),
            ..r.clone()
        };
        let (ha, hb) = ("a".repeat(32), "b".repeat(32));
        let old = floorcast_stats::fixtures::stored("small", "baseline", 1, 100.0);
        let second = floorcast_stats::fixtures::stored("small", "baseline", 2, 100.0);
        let tagged_text = edit(&second, &|v| {
            v["version"] = 2.into();
            v["suite"] = "s".into();
            v["suite_hash"] = ha.as_str().into();
        });
        let tagged = with(&second, &tagged_text);
        let read = |text: &str| RunSummary::from_json(text);
        read(&edit(&old, &|_| {})).unwrap();
        let both = [old.clone(), tagged.clone()];
        assert_eq!(stored_suites(&both), vec![("s".to_string(), ha.clone(), 1)]);
        assert_eq!(
            describe_suites(&both),
            vec![format!("suite s, hash {ha}: 1 runs")]
        );
        let planned = |hash: &str| {
            vec![PlannedSuite {
                name: "s".into(),
                hash: hash.into(),
                manifest: PathBuf::from("suites/s.toml"),
                buildings: 1,
            }]
        };
        assert_eq!(check_stored_suites(&planned(&ha), &both), Ok(()));
        let e = check_stored_suites(&planned(&hb), &both).unwrap_err();
        assert!(e.contains("one version of a suite"), "{e}");
        // Two versions in one store (written by hand): said.
        let other = with(
            &tagged,
            &edit(&tagged, &|v| v["suite_hash"] = hb.as_str().into()),
        );
        let lines = describe_suites(&[tagged.clone(), other]);
        assert!(lines[0].contains("has 2 versions here"), "{lines:?}");
        // A version 1 record with a suite, a suite without its hash: refused (a tampered row).
        let cases = [
            (edit(&old, &|v| v["suite"] = "s".into()), "new in version 2"),
            (
                edit(&tagged, &|v| {
                    v.as_object_mut().unwrap().remove("suite_hash");
                }),
                "go together",
            ),
            (edit(&tagged, &|v| v["suite_hash"] = "xyz".into()), "32 hex"),
            (
                edit(&tagged, &|v| v["version"] = 3.into()),
                "version 1 to 2",
            ),
        ];
        for (text, words) in &cases {
            let e = read(text).unwrap_err();
            assert!(e.contains(words), "{words}: {e}");
        }
    }

    #[test]
    fn suites_are_found_by_name_in_a_folder_above_or_by_path() {
        let tmp = tempfile::tempdir().unwrap();
        let root = tmp.path();
        std::fs::create_dir_all(root.join("suites")).unwrap();
        std::fs::create_dir_all(root.join("grids/deep")).unwrap();
        std::fs::write(root.join("suites/a.toml"), "").unwrap();
        let found = find_suite("a", &root.join("grids/deep")).unwrap();
        assert_eq!(
            std::fs::canonicalize(found).unwrap(),
            std::fs::canonicalize(root.join("suites/a.toml")).unwrap()
        );
        assert_eq!(
            find_suite("../x.toml", &root.join("grids")).unwrap(),
            root.join("grids/../x.toml")
        );
        let e = find_suite("b", &root.join("grids")).unwrap_err();
        assert!(
            e.contains("no suite named 'b'") && e.contains("its suites: a"),
            "{e}"
        );
        let e = find_suite("a b", root).unwrap_err();
        assert!(e.contains("not a suite name"), "{e}");
        let e = find_suite("", root).unwrap_err();
        assert!(e.contains("empty"), "{e}");
    }
}
