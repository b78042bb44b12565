//! Suite manifests: a named, versioned set of buildings (`suites/NAME.toml`, see
//! `suites/README.md`), each building with its file, name, kind, source, licence, free area,
//! rooms and content hash ([`sim_core::Building::content_hash`], what `floorcast building
//! check` prints).
//!
//! ```toml
//! format = "floorcast-suite"
//! version = 1
//! name = "real-schools"
//! description = "The annotated school plans of maps/plans"
//! [[buildings]]
//! name = "Lamuniere1_updated"
//! path = "../maps/plans/Lamuniere1_updated.xml"   # relative to this manifest's folder
//! kind = "school"                                 # school, office, generated or map
//! source = "goldleaf3i/generativeCMLgraphs at 143b780"
//! licence = "MIT, (c) 2017 goldleaf3i"
//! free_area_m2 = 1234.5                           # as `building check` prints it, 0.1 m2
//! rooms = 25                                      # absent: no ground-truth rooms
//! hash = "0123456789abcdef0123456789abcdef"
//! ```
//!
//! As every file of floorcast, a manifest is validated on the way in: the header first (a newer
//! version says so), unknown fields refused, every value checked and bounded, each error one
//! line naming the file and the field. The suite's own hash ([`suite_hash`]) is made from its
//! buildings' sorted (name, content hash) pairs: it is never written, so it cannot disagree
//! with them. Only this module reads and writes the format.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use sha2::{Digest, Sha256};

use crate::error::{num, Error};

/// The value of the `format` key.
pub const SUITE_FORMAT: &str = "floorcast-suite";
/// The only version this crate reads and writes.
pub const SUITE_VERSION: i64 = 1;
/// Largest manifest read (bytes): 4 MiB, about 10 000 buildings.
pub const MAX_MANIFEST_BYTES: u64 = 4 << 20;
/// Most buildings a suite may hold.
pub const MAX_SUITE_BUILDINGS: usize = 10_000;
/// Longest suite name (characters): it names a file, `suites/NAME.toml`.
pub const MAX_SUITE_NAME_CHARS: usize = 64;
/// Longest building name (characters), as a grid's.
pub const MAX_BUILDING_NAME_CHARS: usize = 100;
/// Longest description, source or licence (characters).
pub const MAX_TEXT_CHARS: usize = 2000;
/// Longest path (bytes).
pub const MAX_PATH_BYTES: usize = 4096;
/// Largest free area (m2) and most rooms a manifest may state.
pub const MAX_FREE_AREA_M2: f64 = 1e6;
pub const MAX_ROOMS: u64 = 1_000_000;

/// What a building of a suite is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum SuiteKind {
    /// A real school (an annotated plan).
    School,
    /// A real office.
    Office,
    /// Made by floorcast's generator.
    Generated,
    /// An occupancy-grid map (an image: no rooms).
    Map,
}

impl SuiteKind {
    pub const ALL: [SuiteKind; 4] = [
        SuiteKind::School,
        SuiteKind::Office,
        SuiteKind::Generated,
        SuiteKind::Map,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            SuiteKind::School => "school",
            SuiteKind::Office => "office",
            SuiteKind::Generated => "generated",
            SuiteKind::Map => "map",
        }
    }

    pub fn parse(s: &str) -> Option<SuiteKind> {
        SuiteKind::ALL.into_iter().find(|k| k.as_str() == s)
    }
}

/// One building of a suite, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct SuiteBuilding {
    pub name: String,
    /// The file, as written: relative to the manifest's folder ([`Manifest::path_of`]).
    pub path: String,
    pub kind: SuiteKind,
    pub source: String,
    pub licence: String,
    /// Free area (m2), to 0.1 m2.
    pub free_area_m2: f64,
    /// Ground-truth rooms (`None`: the building has none).
    pub rooms: Option<u64>,
    /// The building's content hash (32 hex digits).
    pub hash: String,
}

/// A suite manifest, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct Manifest {
    pub name: String,
    pub description: String,
    pub buildings: Vec<SuiteBuilding>,
}

/// The file as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FileV1 {
    format: String,
    version: i64,
    name: String,
    description: String,
    buildings: Vec<BuildingV1>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BuildingV1 {
    name: String,
    path: String,
    kind: String,
    source: String,
    licence: String,
    free_area_m2: f64,
    rooms: Option<i64>,
    hash: String,
}

/// Reads and validates a manifest (at most [`MAX_MANIFEST_BYTES`]).
pub fn read_manifest(path: &Path) -> Result<Manifest, Error> {
    let bytes = crate::limits::read_bytes(path, MAX_MANIFEST_BYTES)?;
    let text = String::from_utf8(bytes).map_err(|e| {
        Error::syntax(
            path,
            format!(
                "not UTF-8 text (invalid byte at offset {}); expected a suite manifest (TOML)",
                e.utf8_error().valid_up_to()
            ),
        )
    })?;
    parse_manifest(&text, path)
}

/// Parses and validates a manifest's text; `path` is named in errors.
pub fn parse_manifest(text: &str, path: &Path) -> Result<Manifest, Error> {
    // The header first, so that a newer file says so instead of failing on a key.
    let table: toml::Table =
        toml::from_str(text).map_err(|e| Error::syntax(path, e.to_string()))?;
    check_header(&table, path)?;
    // Counted before the entries are read one by one.
    if let Some(n) = table
        .get("buildings")
        .and_then(|b| b.as_array())
        .map(Vec::len)
    {
        if n > MAX_SUITE_BUILDINGS {
            return Err(Error::invalid(
                path,
                "buildings",
                format!("{n} buildings, more than the {MAX_SUITE_BUILDINGS} a suite may hold"),
            ));
        }
    }
    let file: FileV1 = toml::from_str(text).map_err(|e| Error::syntax(path, e.to_string()))?;
    let _ = (&file.format, file.version);
    let bad = |field: &str, problem: String| Error::invalid(path, field, problem);
    let name = suite_name(&file.name).map_err(|p| bad("name", p))?;
    let description = text_field(&file.description, "a one-line description")
        .map_err(|p| bad("description", p))?;
    if file.buildings.is_empty() {
        return Err(bad(
            "buildings",
            "the suite lists no building; expected [[buildings]] entries".into(),
        ));
    }
    let mut buildings = Vec::with_capacity(file.buildings.len());
    let mut names = BTreeSet::new();
    let mut paths = BTreeSet::new();
    for (i, b) in file.buildings.into_iter().enumerate() {
        buildings.push(suite_building(i, b, &mut names, &mut paths, path)?);
    }
    Ok(Manifest {
        name,
        description,
        buildings,
    })
}

/// The manifest's `format` and `version`, checked before anything else.
fn check_header(table: &toml::Table, path: &Path) -> Result<(), Error> {
    match table.get("format").and_then(|v| v.as_str()) {
        Some(SUITE_FORMAT) => {}
        Some(f) => {
            return Err(Error::invalid(
                path,
                "format",
                format!("expected \"{SUITE_FORMAT}\", found \"{}\"", excerpt(f)),
            ))
        }
        None => {
            return Err(Error::invalid(
                path,
                "format",
                format!("missing or not a string; expected format = \"{SUITE_FORMAT}\""),
            ))
        }
    }
    match table.get("version").and_then(|v| v.as_integer()) {
        Some(SUITE_VERSION) => {}
        Some(v) => {
            return Err(Error::invalid(
                path,
                "version",
                format!("version {v} is not supported, expected {SUITE_VERSION}"),
            ))
        }
        None => {
            return Err(Error::invalid(
                path,
                "version",
                format!("missing or not a whole number; expected version = {SUITE_VERSION}"),
            ))
        }
    }
    Ok(())
}

/// The manifest's `i`-th building, checked: a name and a path no other entry has, a kind, its
/// source and licence, a free area, a number of rooms, a content hash.
fn suite_building(
    i: usize,
    b: BuildingV1,
    names: &mut BTreeSet<String>,
    paths: &mut BTreeSet<String>,
    path: &Path,
) -> Result<SuiteBuilding, Error> {
    let bad = |field: &str, problem: String| Error::invalid(path, field, problem);
    let field = |f: &str| format!("buildings[{i}].{f}");
    let name = building_name(&b.name).map_err(|p| bad(&field("name"), p))?;
    if !names.insert(name.clone()) {
        return Err(bad(
            &field("name"),
            format!(
                "'{}' names two buildings of the suite; names must differ",
                excerpt(&name)
            ),
        ));
    }
    let file_path = relative_path(&b.path).map_err(|p| bad(&field("path"), p))?;
    if !paths.insert(file_path.clone()) {
        return Err(bad(
            &field("path"),
            format!("'{}' is listed twice", excerpt(&file_path)),
        ));
    }
    let kind = SuiteKind::parse(&b.kind).ok_or_else(|| {
        bad(
            &field("kind"),
            format!(
                "'{}' is not a kind; expected one of {}",
                excerpt(&b.kind),
                kinds_list()
            ),
        )
    })?;
    let source =
        text_field(&b.source, "where the file comes from").map_err(|p| bad(&field("source"), p))?;
    let licence =
        text_field(&b.licence, "the file's licence").map_err(|p| bad(&field("licence"), p))?;
    if !(b.free_area_m2.is_finite() && b.free_area_m2 > 0.0 && b.free_area_m2 <= MAX_FREE_AREA_M2) {
        return Err(bad(
            &field("free_area_m2"),
            format!(
                "{} is not a free area in (0, {}] m2",
                num(b.free_area_m2),
                num(MAX_FREE_AREA_M2)
            ),
        ));
    }
    let rooms = match b.rooms {
        None => None,
        Some(r) if (1..=MAX_ROOMS as i64).contains(&r) => Some(r as u64),
        Some(r) => {
            return Err(bad(
                &field("rooms"),
                format!(
                    "{r} is not a number of rooms in [1, {MAX_ROOMS}] (leave `rooms` out for a building without ground-truth rooms)"
                ),
            ))
        }
    };
    let hash = content_hash(&b.hash).map_err(|p| bad(&field("hash"), p))?;
    Ok(SuiteBuilding {
        name,
        path: file_path,
        kind,
        source,
        licence,
        free_area_m2: b.free_area_m2,
        rooms,
        hash,
    })
}

/// The hash of a suite: SHA-256 over its buildings' (name, content hash) pairs sorted by name,
/// 32 hex digits as a building's content hash. Two suites of one name and hash hold the same
/// buildings under the same names.
pub fn suite_hash<'a>(pairs: impl IntoIterator<Item = (&'a str, &'a str)>) -> String {
    let mut pairs: Vec<(&str, &str)> = pairs.into_iter().collect();
    pairs.sort();
    let mut h = Sha256::new();
    h.update(b"floorcast-suite-v1\0");
    for (name, hash) in pairs {
        h.update((name.len() as u64).to_le_bytes());
        h.update(name.as_bytes());
        h.update((hash.len() as u64).to_le_bytes());
        h.update(hash.as_bytes());
    }
    h.finalize()[..16]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

impl Manifest {
    /// The suite's hash ([`suite_hash`] of its buildings).
    pub fn hash(&self) -> String {
        suite_hash(
            self.buildings
                .iter()
                .map(|b| (b.name.as_str(), b.hash.as_str())),
        )
    }

    /// The file of a building of the manifest at `manifest_path`: its `path` taken relative to
    /// the manifest's folder.
    pub fn path_of(manifest_path: &Path, building: &SuiteBuilding) -> PathBuf {
        manifest_path
            .parent()
            .unwrap_or(Path::new("."))
            .join(&building.path)
    }

    /// Total free area (m2) the manifest states.
    pub fn free_area_m2(&self) -> f64 {
        self.buildings.iter().map(|b| b.free_area_m2).sum()
    }

    /// The manifest as TOML, as `floorcast suite update` writes it (reads back equal).
    pub fn to_toml(&self) -> String {
        use std::fmt::Write as _;
        let s = |v: &str| toml::Value::String(v.to_string()).to_string();
        let mut out = String::new();
        let _ = writeln!(
            out,
            "# A floorcast suite (suites/README.md). Written by `floorcast suite update {}`, which\n# refreshes every building's free area, rooms and content hash from its file.",
            self.name
        );
        let _ = writeln!(out, "format = {}", s(SUITE_FORMAT));
        let _ = writeln!(out, "version = {SUITE_VERSION}");
        let _ = writeln!(out, "name = {}", s(&self.name));
        let _ = writeln!(out, "description = {}", s(&self.description));
        for b in &self.buildings {
            let _ = writeln!(out, "\n[[buildings]]");
            let _ = writeln!(out, "name = {}", s(&b.name));
            let _ = writeln!(out, "path = {}", s(&b.path));
            let _ = writeln!(out, "kind = {}", s(b.kind.as_str()));
            let _ = writeln!(out, "source = {}", s(&b.source));
            let _ = writeln!(out, "licence = {}", s(&b.licence));
            let _ = writeln!(out, "free_area_m2 = {}", area_text(b.free_area_m2));
            if let Some(r) = b.rooms {
                let _ = writeln!(out, "rooms = {r}");
            }
            let _ = writeln!(out, "hash = {}", s(&b.hash));
        }
        out
    }
}

/// A free area as a manifest states it: to 0.1 m2, always with its decimal.
pub fn area_text(m2: f64) -> String {
    format!("{m2:.1}")
}

/// A free area rounded as a manifest states it.
pub fn rounded_area_m2(m2: f64) -> f64 {
    (m2 * 10.0).round() / 10.0
}

fn kinds_list() -> String {
    SuiteKind::ALL
        .iter()
        .map(|k| k.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

/// A suite's name: 1 to [`MAX_SUITE_NAME_CHARS`] ASCII letters, digits, '-', '_' or '.', not
/// starting with '.' (it names the file `suites/NAME.toml`).
pub fn suite_name(name: &str) -> Result<String, String> {
    let n = name.chars().count();
    if n == 0
        || n > MAX_SUITE_NAME_CHARS
        || name.starts_with('.')
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
    {
        return Err(format!(
            "'{}' is not a suite name; expected 1 to {MAX_SUITE_NAME_CHARS} letters, digits, '-', '_' or '.' (not first), such as \"real-schools\"",
            excerpt(name)
        ));
    }
    Ok(name.to_string())
}

fn building_name(name: &str) -> Result<String, String> {
    let t = name.trim();
    if t.is_empty() || t != name {
        return Err(format!(
            "'{}' is empty or has blanks at an end; expected a name such as \"school-a\"",
            excerpt(name)
        ));
    }
    if let Some(c) = name.chars().find(|c| c.is_control()) {
        return Err(format!(
            "'{}' holds a control character (U+{:04X}); expected one line of printable characters",
            excerpt(name),
            c as u32
        ));
    }
    if name.contains(['/', '\\']) || name == "." || name == ".." {
        return Err(format!(
            "'{}' is a path; expected a name (it becomes part of file names)",
            excerpt(name)
        ));
    }
    let n = name.chars().count();
    if n > MAX_BUILDING_NAME_CHARS {
        return Err(format!(
            "'{}' is {n} characters long, more than {MAX_BUILDING_NAME_CHARS}",
            excerpt(name)
        ));
    }
    Ok(name.to_string())
}

fn text_field(text: &str, what: &str) -> Result<String, String> {
    if text.trim().is_empty() {
        return Err(format!("is empty; expected {what}"));
    }
    if let Some(c) = text.chars().find(|c| c.is_control()) {
        return Err(format!(
            "'{}' holds a control character (U+{:04X}); expected {what} on one line",
            excerpt(text),
            c as u32
        ));
    }
    let n = text.chars().count();
    if n > MAX_TEXT_CHARS {
        return Err(format!(
            "'{}' is {n} characters long, more than {MAX_TEXT_CHARS}",
            excerpt(text)
        ));
    }
    Ok(text.to_string())
}

fn relative_path(p: &str) -> Result<String, String> {
    if p.trim().is_empty() {
        return Err("is empty; expected a building file relative to the manifest's folder, such as \"../maps/plans/x.xml\"".into());
    }
    if p.len() > MAX_PATH_BYTES {
        return Err(format!(
            "'{}' is {} bytes long, more than {MAX_PATH_BYTES}",
            excerpt(p),
            p.len()
        ));
    }
    if p.chars().any(char::is_control) {
        return Err(format!(
            "'{}' holds a control character; expected a path on one line",
            excerpt(p)
        ));
    }
    if Path::new(p).is_absolute() || p.starts_with('\\') || p.starts_with('~') {
        return Err(format!(
            "'{}' is absolute; expected a path relative to the manifest's folder (the suite moves with the repository)",
            excerpt(p)
        ));
    }
    Ok(p.to_string())
}

fn content_hash(h: &str) -> Result<String, String> {
    if h.len() == 32
        && h.chars()
            .all(|c| c.is_ascii_digit() || ('a'..='f').contains(&c))
    {
        Ok(h.to_string())
    } else {
        Err(format!(
            "'{}' is not a content hash; expected 32 lowercase hex digits, as `floorcast building check` prints (`floorcast suite update` writes them)",
            excerpt(h)
        ))
    }
}

/// At most 80 characters of outside text, control characters shown escaped.
fn excerpt(s: &str) -> String {
    const MAX: usize = 80;
    let n = s.chars().count();
    let mut out: String = s
        .chars()
        .take(MAX)
        .flat_map(|c| {
            if c.is_control() {
                c.escape_default().collect::<Vec<_>>()
            } else {
                vec![c]
            }
        })
        .collect();
    if n > MAX {
        out.push_str(&format!("... ({n} characters in all)"));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"format = "floorcast-suite"
version = 1
name = "two"
description = "Two buildings"

[[buildings]]
name = "a"
path = "../buildings/a.toml"
kind = "school"
source = "made here"
licence = "MIT"
free_area_m2 = 400.5
rooms = 12
hash = "0123456789abcdef0123456789abcdef"

[[buildings]]
name = "b"
path = "../maps/b.yaml"
kind = "map"
source = "made here"
licence = "MIT"
free_area_m2 = 1000.0
hash = "fedcba9876543210fedcba9876543210"
"#;

    fn parse(text: &str) -> Result<Manifest, Error> {
        parse_manifest(text, Path::new("suites/two.toml"))
    }

    #[test]
    fn a_good_manifest_reads_and_writes_back_equal() {
        let m = parse(GOOD).unwrap();
        assert_eq!(m.name, "two");
        assert_eq!(m.buildings.len(), 2);
        assert_eq!(m.buildings[0].rooms, Some(12));
        assert_eq!(m.buildings[1].rooms, None);
        assert_eq!(m.buildings[1].kind, SuiteKind::Map);
        assert_eq!(parse(&m.to_toml()).unwrap(), m);
        assert_eq!(m.free_area_m2(), 1400.5);
        assert_eq!(
            Manifest::path_of(Path::new("suites/two.toml"), &m.buildings[0]),
            Path::new("suites/../buildings/a.toml")
        );
    }

    #[test]
    fn the_suite_hash_is_of_the_sorted_names_and_hashes() {
        let m = parse(GOOD).unwrap();
        let h = m.hash();
        assert_eq!(h.len(), 32);
        // Order does not matter; a name or a hash does.
        let mut swapped = m.clone();
        swapped.buildings.reverse();
        assert_eq!(swapped.hash(), h);
        let mut renamed = m.clone();
        renamed.buildings[0].name = "c".into();
        assert_ne!(renamed.hash(), h);
        let mut changed = m.clone();
        changed.buildings[1].hash = "0".repeat(32);
        assert_ne!(changed.hash(), h);
        // Metadata does not.
        let mut meta = m.clone();
        meta.buildings[0].licence = "BSD".into();
        meta.description = "other".into();
        assert_eq!(meta.hash(), h);
        // Pairs are delimited: ("ab", "c...") is not ("a", "bc...").
        assert_ne!(suite_hash([("ab", "c")]), suite_hash([("a", "bc")]));
    }

    /// Each malformed manifest is refused with one line naming the file, the field and the
    /// words of the problem.
    #[test]
    #[allow(clippy::too_many_lines)] // a table of cases
    fn malformed_manifests_are_refused_naming_the_field() {
        let first = GOOD.find("[[buildings]]").unwrap();
        let one = |from: &str, to: &str| {
            assert!(GOOD.contains(from), "{from}");
            GOOD.replacen(from, to, 1)
        };
        let long = "x".repeat(3000);
        let many = {
            let mut t = GOOD[..first].to_string();
            for i in 0..=MAX_SUITE_BUILDINGS {
                t.push_str(&format!("[[buildings]]\nname = \"b{i}\"\n"));
            }
            t
        };
        // (what, text, words of the error)
        let cases: Vec<(&str, String, Vec<&str>)> = vec![
            ("empty", String::new(), vec!["format", "missing"]),
            ("not toml", "x = = 1".into(), vec!["TOML parse error"]),
            (
                "a grid",
                one("floorcast-suite", "floorcast-grid"),
                vec!["format", "floorcast-grid"],
            ),
            (
                "version 2",
                one("version = 1", "version = 2"),
                vec!["version 2 is not supported"],
            ),
            (
                "version text",
                one("version = 1", "version = \"1\""),
                vec!["version", "whole number"],
            ),
            (
                "unknown top field",
                one("description", "colour = 1\ndescription"),
                vec!["unknown field", "colour"],
            ),
            (
                "unknown building field",
                one("rooms = 12", "rooms = 12\ndoors = 3"),
                vec!["unknown field", "doors"],
            ),
            (
                "missing hash",
                one("hash = \"0123456789abcdef0123456789abcdef\"\n", ""),
                vec!["missing field", "hash"],
            ),
            (
                "no buildings",
                GOOD[..first].to_string() + "buildings = []\n",
                vec!["buildings", "lists no building"],
            ),
            (
                "too many buildings",
                many,
                vec!["buildings", "more than the 10000"],
            ),
            (
                "name with slash",
                one("name = \"two\"", "name = \"a/b\""),
                vec!["name", "not a suite name"],
            ),
            (
                "name empty",
                one("name = \"two\"", "name = \"\""),
                vec!["name", "not a suite name"],
            ),
            (
                "description empty",
                one("\"Two buildings\"", "\" \""),
                vec!["description", "empty"],
            ),
            (
                "description too long",
                one("Two buildings", &long),
                vec!["description", "more than 2000"],
            ),
            (
                "building name a path",
                one("name = \"a\"", "name = \"../a\""),
                vec!["buildings[0].name", "is a path"],
            ),
            (
                "building name control",
                one("name = \"a\"", "name = \"a\\u0007\""),
                vec!["buildings[0].name", "control character"],
            ),
            (
                "duplicate name",
                one("name = \"b\"", "name = \"a\""),
                vec!["buildings[1].name", "names two buildings"],
            ),
            (
                "duplicate path",
                one("../maps/b.yaml", "../buildings/a.toml"),
                vec!["buildings[1].path", "listed twice"],
            ),
            (
                "absolute path",
                one("../maps/b.yaml", "/etc/b.yaml"),
                vec!["buildings[1].path", "absolute"],
            ),
            (
                "empty path",
                one("../maps/b.yaml", ""),
                vec!["buildings[1].path", "empty"],
            ),
            (
                "unknown kind",
                one("kind = \"map\"", "kind = \"castle\""),
                vec![
                    "buildings[1].kind",
                    "castle",
                    "school, office, generated, map",
                ],
            ),
            (
                "empty source",
                one("source = \"made here\"", "source = \"\""),
                vec!["buildings[0].source", "empty"],
            ),
            (
                "empty licence",
                one("licence = \"MIT\"", "licence = \"\""),
                vec!["buildings[0].licence", "empty"],
            ),
            (
                "negative area",
                one("400.5", "-1.0"),
                vec!["buildings[0].free_area_m2", "not a free area"],
            ),
            (
                "infinite area",
                one("400.5", "inf"),
                vec!["buildings[0].free_area_m2", "not a free area"],
            ),
            (
                "huge area",
                one("400.5", "1e300"),
                vec!["buildings[0].free_area_m2", "not a free area"],
            ),
            (
                "area as text",
                one("400.5", "\"400\""),
                vec!["free_area_m2", "invalid type"],
            ),
            (
                "zero rooms",
                one("rooms = 12", "rooms = 0"),
                vec!["buildings[0].rooms", "not a number of rooms"],
            ),
            (
                "negative rooms",
                one("rooms = 12", "rooms = -3"),
                vec!["buildings[0].rooms", "not a number of rooms"],
            ),
            (
                "short hash",
                one("0123456789abcdef0123456789abcdef", "0123"),
                vec!["buildings[0].hash", "32 lowercase hex"],
            ),
            (
                "upper-case hash",
                one(
                    "0123456789abcdef0123456789abcdef",
                    "0123456789ABCDEF0123456789ABCDEF",
                ),
                vec!["buildings[0].hash", "32 lowercase hex"],
            ),
        ];
        let mut failed = Vec::new();
        for (what, text, words) in &cases {
            match parse(text) {
                Ok(_) => failed.push(format!("{what}: accepted")),
                Err(e) => {
                    let msg = e.to_string();
                    if msg.contains('\n')
                        || !msg.starts_with("suites/two.toml: ")
                        || !words.iter().all(|w| msg.contains(w))
                    {
                        failed.push(format!("{what}: {msg}"));
                    }
                }
            }
        }
        assert!(failed.is_empty(), "{}", failed.join("\n"));
    }
}
