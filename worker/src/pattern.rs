//! Building patterns: the files a path with wildcards names, searched within bounds (the
//! patterns of grid files and of the Python package's `buildings`).

use std::path::{Path, PathBuf};

/// At most this many folder entries are visited expanding one building pattern.
pub const MAX_PATTERN_ENTRIES: usize = 100_000;

/// The files `pattern` (relative to `base_dir`, which the error of no match calls `base_is`,
/// e.g. "the grid file's folder") names, sorted. A pattern without wildcards
/// (`*`, `?`, `[...]`) names one file. With wildcards, only the folder before the first
/// wildcard is searched: never the whole file system (`/**`), never above it (`..` after a
/// wildcard), symbolic links to folders not followed, at most [`MAX_PATTERN_ENTRIES`] entries
/// visited; folders that cannot be read are passed over. A matching file whose name is not
/// UTF-8 is an error naming it.
pub fn expand_pattern(
    base_dir: &Path,
    pattern: &str,
    base_is: &str,
) -> Result<Vec<PathBuf>, String> {
    expand_pattern_within(base_dir, pattern, MAX_PATTERN_ENTRIES, base_is)
}

/// [`expand_pattern`] visiting at most `max_entries` entries.
pub fn expand_pattern_within(
    base_dir: &Path,
    pattern: &str,
    max_entries: usize,
    base_is: &str,
) -> Result<Vec<PathBuf>, String> {
    let wild = |s: &str| s.contains(['*', '?', '[']);
    let full = base_dir.join(pattern);
    let none = || {
        format!(
            "'{}' matches no file (paths are relative to {base_is})",
            crate::text::excerpt(pattern)
        )
    };
    if !wild(pattern) {
        return match std::fs::metadata(&full) {
            Ok(_) => Ok(vec![full]),
            Err(_) => Err(none()),
        };
    }
    // The grid's folder is taken as it is (wildcard characters in its name included).
    let mut prefix = base_dir.to_path_buf();
    let mut rest: Vec<String> = Vec::new();
    for c in Path::new(pattern).components() {
        let text = c.as_os_str().to_string_lossy().into_owned();
        if rest.is_empty() && !wild(&text) {
            prefix.push(c);
        } else {
            rest.push(text);
        }
    }
    if rest.iter().any(|c| c == "..") {
        return Err(format!(
            "'{}' has '..' after a wildcard; a pattern searches only below the folder before its first wildcard",
            crate::text::excerpt(pattern)
        ));
    }
    let walk_root = if prefix.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        prefix.clone()
    };
    if prefix.parent().is_none() && prefix.has_root() {
        return Err(format!(
            "'{}' would search the whole file system; start it with the folder to search",
            crate::text::excerpt(pattern)
        ));
    }
    let rest_text = rest.join("/");
    let glob = glob::Pattern::new(&rest_text)
        .map_err(|e| format!("bad glob pattern '{}': {e}", crate::text::excerpt(pattern)))?;
    let options = glob::MatchOptions {
        case_sensitive: true,
        require_literal_separator: true,
        require_literal_leading_dot: false,
    };
    let mut walk = walkdir::WalkDir::new(&walk_root)
        .min_depth(1)
        .follow_links(false);
    if !rest.iter().any(|c| c.contains("**")) {
        walk = walk.max_depth(rest.len());
    }
    let mut matched = Vec::new();
    for (visited, entry) in walk.into_iter().enumerate() {
        if visited >= max_entries {
            return Err(format!(
                "'{}' visits more than {max_entries} entries under {}; give a narrower pattern (a deeper folder, no '**')",
                crate::text::excerpt(pattern),
                crate::text::shown(&prefix.display().to_string(), 200)
            ));
        }
        let Ok(entry) = entry else { continue };
        let Ok(rel) = entry.path().strip_prefix(&walk_root) else {
            continue;
        };
        let rel_text = rel.to_string_lossy();
        if !glob.matches_with(&rel_text, options) {
            continue;
        }
        if !std::fs::metadata(entry.path()).is_ok_and(|m| m.is_file()) {
            continue;
        }
        if rel.to_str().is_none() {
            return Err(format!(
                "{} matches '{}' but its name is not UTF-8; rename it",
                crate::text::shown(&entry.path().display().to_string(), 200),
                crate::text::excerpt(pattern)
            ));
        }
        matched.push(prefix.join(rel));
    }
    matched.sort();
    if matched.is_empty() {
        return Err(none());
    }
    Ok(matched)
}
