//! `floorcast suite`: list, check and write suites, the named, versioned sets of buildings whose
//! manifests are in `suites/` (`floorcast_formats::suite`, suites/README.md).

use std::path::{Component, Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use floorcast_coordinator::suite::{find_suite, is_path, manifests_in, suites_dir, SUITES_DIR};
use floorcast_formats::suite::{
    area_text, parse_manifest, read_manifest, rounded_area_m2, suite_name, Manifest, SuiteBuilding,
    SuiteKind,
};
use serde::Serialize;
use sim_core::Building;

/// The least share of a building's free area that must be explorable from its start (what
/// `formats/tests/floorplans.rs` asks of every vendored plan).
pub const MIN_EXPLORABLE: f64 = 0.97;

#[derive(Debug, Subcommand)]
pub enum SuiteCommand {
    /// List the suites (the manifests of the first `suites/` folder in the current folder or
    /// one above it): name, buildings, their kinds, total free area (m2) and the suite's hash.
    List(ListArgs),
    /// Check a suite: every building loads, has the content hash, free area (to 0.1 m2) and
    /// rooms its manifest states, and at least 97 % of its free area is explorable from its
    /// start (reachable by the robot's 0.2 m body and in sight of its 6 m laser). Prints each
    /// building's result as it goes; exits with code 2 naming every failing building.
    Check(CheckArgs),
    /// Write or refresh a suite's manifest from its building files: each one's free area,
    /// rooms and content hash (as `floorcast building check` prints them). Without FILES, the
    /// buildings of the existing manifest are refreshed (after a change to how floorcast reads
    /// a format, e.g.); with FILES, the suite becomes those files, each new one described by
    /// --kind, --source and --licence.
    Update(UpdateArgs),
}

#[derive(Debug, Args)]
pub struct ListArgs {
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
pub struct CheckArgs {
    /// The suite: its name (found as suites/NAME.toml in the current folder or one above it)
    /// or its manifest's path, e.g. real-schools or suites/real-schools.toml.
    suite: String,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum KindArg {
    School,
    Office,
    Generated,
    Map,
}

impl From<KindArg> for SuiteKind {
    fn from(k: KindArg) -> SuiteKind {
        match k {
            KindArg::School => SuiteKind::School,
            KindArg::Office => SuiteKind::Office,
            KindArg::Generated => SuiteKind::Generated,
            KindArg::Map => SuiteKind::Map,
        }
    }
}

#[derive(Debug, Args)]
pub struct UpdateArgs {
    /// The suite: its name (suites/NAME.toml in the current folder or one above it, made in
    /// ./suites/ if there is none) or its manifest's path.
    suite: String,
    /// Building files (floorcast TOML, map_server YAML, Stage .world, floor-plan XML): the
    /// suite's buildings, each named by its file name without extension. Default: the
    /// manifest's own.
    files: Vec<PathBuf>,
    /// Kind of the buildings (new ones need it; given, it applies to all).
    #[arg(long, value_enum)]
    kind: Option<KindArg>,
    /// Where the files come from, e.g. "goldleaf3i/generativeCMLgraphs at 143b780" (new
    /// buildings need it; given, it applies to all).
    #[arg(long, value_name = "TEXT")]
    source: Option<String>,
    /// The files' licence, e.g. "MIT, (c) 2017 goldleaf3i" (new buildings need it; given, it
    /// applies to all).
    #[arg(long, value_name = "TEXT")]
    licence: Option<String>,
    /// One line saying what the suite is (a new suite needs it).
    #[arg(long, value_name = "TEXT")]
    description: Option<String>,
}

pub fn run(c: SuiteCommand) -> Result<()> {
    match c {
        SuiteCommand::List(a) => list_cmd(a),
        SuiteCommand::Check(a) => check_cmd(a),
        SuiteCommand::Update(a) => update_cmd(a),
    }
}

/// What `suite list --json` prints for each suite.
#[derive(Debug, Serialize)]
struct ListEntry {
    name: String,
    description: String,
    manifest: String,
    buildings: usize,
    /// Buildings per kind.
    kinds: std::collections::BTreeMap<String, usize>,
    free_area_m2: f64,
    hash: String,
}

fn list_cmd(a: ListArgs) -> Result<()> {
    let Some(dir) = suites_dir(Path::new(".")) else {
        bail!(
            "no {SUITES_DIR}/ folder in the current folder or one above it; run floorcast in a floorcast checkout"
        );
    };
    let mut entries = Vec::new();
    for path in manifests_in(&dir).map_err(anyhow::Error::msg)? {
        let m = read_manifest(&path)?;
        let mut kinds = std::collections::BTreeMap::new();
        for b in &m.buildings {
            *kinds.entry(b.kind.as_str().to_string()).or_insert(0) += 1;
        }
        entries.push(ListEntry {
            name: m.name.clone(),
            description: m.description.clone(),
            manifest: path.display().to_string(),
            buildings: m.buildings.len(),
            kinds,
            free_area_m2: rounded_area_m2(m.free_area_m2()),
            hash: m.hash(),
        });
    }
    if a.json {
        say!("{}", serde_json::to_string_pretty(&entries)?);
        return Ok(());
    }
    say!(
        "{:<16} {:>9}  {:<22} {:>12}  hash",
        "suite",
        "buildings",
        "kinds",
        "free m2"
    );
    for e in &entries {
        let kinds: Vec<String> = e.kinds.iter().map(|(k, n)| format!("{k} {n}")).collect();
        say!(
            "{:<16} {:>9}  {:<22} {:>12}  {}",
            e.name,
            e.buildings,
            kinds.join(", "),
            area_text(e.free_area_m2),
            e.hash
        );
    }
    say!("{} suites in {}", entries.len(), dir.display());
    Ok(())
}

/// The share of a building's free area that is explorable from its start: reachable by the
/// robot's body and in sight of its laser (`sim_core::building::explorable_free`), with the
/// default robot and laser.
fn explorable_share(b: &Building) -> Result<f64, String> {
    let s = floorcast_worker::Settings::default();
    let (start, _) = b
        .default_start(s.robot_radius_m)
        .map_err(|e| format!("no start pose: {e}"))?;
    let frame = b.area_frame();
    let reachable = b.reachable_free(frame, start.position());
    let explorable = sim_core::building::explorable_free(
        &reachable,
        start.position(),
        s.robot_radius_m,
        s.laser_range_m,
    );
    let free_m2 = b.free_area_m2();
    if free_m2 <= 0.0 {
        return Err("no free area".into());
    }
    Ok(explorable.count_true() as f64 * frame.cell_area_m2() / free_m2)
}

/// Checks one building of a suite against its manifest entry: `Ok` with what it is, or every
/// problem found.
fn check_building(manifest: &Path, spec: &str, sb: &SuiteBuilding) -> Result<String, String> {
    let file = Manifest::path_of(manifest, sb);
    let b = floorcast_formats::read_building(&file).map_err(|e| e.to_string())?;
    let mut problems = Vec::new();
    let hash = b.content_hash();
    if hash != sb.hash {
        problems.push(format!(
            "hash differs ({hash}, the manifest says {}): run `floorcast suite update {spec}`",
            sb.hash
        ));
    }
    let area = rounded_area_m2(b.free_area_m2());
    if (area - sb.free_area_m2).abs() > 0.05 + 1e-9 {
        problems.push(format!(
            "free area {} m2, the manifest says {} m2",
            area_text(area),
            area_text(sb.free_area_m2)
        ));
    }
    let rooms = (!b.rooms.is_empty()).then_some(b.rooms.len() as u64);
    if rooms != sb.rooms {
        let said = |r: Option<u64>| r.map_or("no rooms".to_string(), |n| format!("{n} rooms"));
        problems.push(format!(
            "{}, the manifest says {}",
            said(rooms),
            said(sb.rooms)
        ));
    }
    let share = match explorable_share(&b) {
        Ok(share) => {
            if share < MIN_EXPLORABLE {
                problems.push(format!(
                    "only {:.1} % of its free area is explorable from its start, less than {:.0} %",
                    share * 100.0,
                    MIN_EXPLORABLE * 100.0
                ));
            }
            share
        }
        Err(e) => {
            problems.push(e);
            0.0
        }
    };
    if problems.is_empty() {
        Ok(format!(
            "{} m2, {}, {:.1} % explorable from the start",
            area_text(area),
            rooms.map_or("no rooms".to_string(), |n| format!("{n} rooms")),
            share * 100.0
        ))
    } else {
        Err(problems.join("; "))
    }
}

fn check_cmd(a: CheckArgs) -> Result<()> {
    let path =
        find_suite(&a.suite, Path::new(".")).map_err(|e| anyhow::anyhow!("{}: {e}", a.suite))?;
    let m = read_manifest(&path)?;
    let n = m.buildings.len();
    say!(
        "suite {} ({}): {n} buildings, hash {}",
        m.name,
        path.display(),
        m.hash()
    );
    let width = n.to_string().len();
    let mut failing = Vec::new();
    for (i, sb) in m.buildings.iter().enumerate() {
        match check_building(&path, &a.suite, sb) {
            Ok(what) => say!("[{:>width$}/{n}] {}: ok: {what}", i + 1, sb.name),
            Err(why) => {
                say!("[{:>width$}/{n}] {}: FAILS: {why}", i + 1, sb.name);
                failing.push(format!("{} ({why})", sb.name));
            }
        }
    }
    if !failing.is_empty() {
        bail!(
            "suite {} ({}): {} of {n} buildings fail: {}",
            m.name,
            path.display(),
            failing.len(),
            failing.join("; ")
        );
    }
    say!("suite {}: all {n} buildings pass", m.name);
    Ok(())
}

/// `path` made absolute and lexically normal (no `.`, `..` taken off), links not followed (a
/// linked folder stays where it is linked).
fn normal(path: &Path) -> Result<PathBuf> {
    let abs = std::path::absolute(path).with_context(|| format!("{}", path.display()))?;
    let mut out = PathBuf::new();
    for c in abs.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            c => out.push(c),
        }
    }
    Ok(out)
}

/// `file` relative to the folder `dir` (both made [`normal`]), with `/` separators.
fn relative_to(file: &Path, dir: &Path) -> Result<String> {
    let (file, dir) = (normal(file)?, normal(dir)?);
    let f: Vec<Component> = file.components().collect();
    let d: Vec<Component> = dir.components().collect();
    let common = f.iter().zip(&d).take_while(|(a, b)| a == b).count();
    let mut parts: Vec<String> = vec!["..".to_string(); d.len() - common];
    for c in &f[common..] {
        parts.push(c.as_os_str().to_string_lossy().into_owned());
    }
    Ok(parts.join("/"))
}

fn update_cmd(a: UpdateArgs) -> Result<()> {
    // The manifest's path.
    let path = if is_path(&a.suite) {
        PathBuf::from(&a.suite)
    } else {
        let name = suite_name(&a.suite).map_err(|e| anyhow::anyhow!("{}: {e}", a.suite))?;
        suites_dir(Path::new("."))
            .unwrap_or_else(|| PathBuf::from(SUITES_DIR))
            .join(format!("{name}.toml"))
    };
    let old = if std::fs::symlink_metadata(&path).is_ok() {
        Some(read_manifest(&path)?)
    } else {
        None
    };
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
        .to_path_buf();
    let name = match (&old, is_path(&a.suite)) {
        (Some(m), true) => m.name.clone(),
        (_, false) => a.suite.clone(),
        (None, true) => path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
    };
    let name = suite_name(&name).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let description = match (&a.description, &old) {
        (Some(d), _) => d.clone(),
        (None, Some(m)) => m.description.clone(),
        (None, None) => bail!(
            "--description: {} does not exist yet; a new suite needs a description",
            path.display()
        ),
    };
    let (mut entries, files) = suite_entries(&a, &path, &dir, old.as_ref(), &name)?;
    for e in entries.iter_mut() {
        if let Some(k) = a.kind {
            e.kind = k.into();
        }
        if let Some(s) = &a.source {
            e.source = s.clone();
        }
        if let Some(l) = &a.licence {
            e.licence = l.clone();
        }
    }
    let changed = read_entries(&mut entries, &files)?;
    entries.sort_by(|x, y| x.name.cmp(&y.name));
    let m = Manifest {
        name,
        description,
        buildings: entries,
    };
    write_manifest(&m, &dir, &path)?;
    let hash = m.hash();
    let was = old.as_ref().map(|o| o.hash());
    say!(
        "{}: suite {}, {} buildings, {} m2, hash {hash}{}",
        path.display(),
        m.name,
        m.buildings.len(),
        area_text(rounded_area_m2(m.free_area_m2())),
        match was {
            Some(w) if w == hash => " (unchanged)".to_string(),
            Some(w) => format!(" (was {w})"),
            None => " (new)".to_string(),
        }
    );
    if !changed.is_empty() {
        say!(
            "content hash changed: {} ({} buildings)",
            changed.join(", "),
            changed.len()
        );
    }
    Ok(())
}

/// The suite's entries and the files they are read from: the files given (each keeping what
/// the manifest said of it), or the manifest's own.
fn suite_entries(
    a: &UpdateArgs,
    path: &Path,
    dir: &Path,
    old: Option<&Manifest>,
    name: &str,
) -> Result<(Vec<SuiteBuilding>, Vec<PathBuf>)> {
    let mut entries: Vec<SuiteBuilding> = Vec::new();
    // Where each is read from: the file as given, or as the manifest names it.
    let mut files: Vec<PathBuf> = Vec::new();
    if a.files.is_empty() {
        let Some(m) = old else {
            bail!(
                "{}: no such manifest; give the suite's FILES with --kind, --source, --licence and --description to make it",
                path.display()
            );
        };
        entries = m.buildings.clone();
        files = entries.iter().map(|e| Manifest::path_of(path, e)).collect();
    } else {
        for file in &a.files {
            let rel = relative_to(file, dir)?;
            let known = old.and_then(|m| m.buildings.iter().find(|b| b.path == rel));
            let entry = match known {
                Some(b) => b.clone(),
                None => new_entry(a, file, rel, name)?,
            };
            entries.push(entry);
            files.push(file.clone());
        }
    }
    Ok((entries, files))
}

/// A file new to the suite: its entry, named by its file stem, with the flags that say what
/// the manifest says of every building (required).
fn new_entry(a: &UpdateArgs, file: &Path, rel: String, name: &str) -> Result<SuiteBuilding> {
    let missing: Vec<&str> = [
        ("--kind", a.kind.is_none()),
        ("--source", a.source.is_none()),
        ("--licence", a.licence.is_none()),
    ]
    .into_iter()
    .filter_map(|(f, m)| m.then_some(f))
    .collect();
    if !missing.is_empty() {
        bail!(
            "{}: {} is new to suite {name}: give {}",
            missing.join(", "),
            file.display(),
            missing.join(", ")
        );
    }
    Ok(SuiteBuilding {
        name: file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        path: rel,
        kind: SuiteKind::School,
        source: String::new(),
        licence: String::new(),
        free_area_m2: 0.0,
        rooms: None,
        hash: String::new(),
    })
}

/// Each building read: its hash, free area and rooms; the names of those whose hash changed.
fn read_entries(entries: &mut [SuiteBuilding], files: &[PathBuf]) -> Result<Vec<String>> {
    let mut changed = Vec::new();
    for (e, file) in entries.iter_mut().zip(files) {
        let b = floorcast_formats::read_building(file)?;
        let hash = b.content_hash();
        if !e.hash.is_empty() && e.hash != hash {
            changed.push(e.name.clone());
        }
        e.hash = hash;
        e.free_area_m2 = rounded_area_m2(b.free_area_m2());
        e.rooms = (!b.rooms.is_empty()).then_some(b.rooms.len() as u64);
    }
    Ok(changed)
}

/// Writes the manifest beside `path` and moves it into place (never half written), after
/// checking that it reads back as itself (every value checked as on reading).
fn write_manifest(m: &Manifest, dir: &Path, path: &Path) -> Result<()> {
    let text = m.to_toml();
    let back = parse_manifest(&text, path)?;
    debug_assert_eq!(&back, m);
    crate::output::create_dir(dir)?;
    // Written beside it (beside a link's target) and moved into place: a manifest is never half
    // written, and a link to it stays a link.
    crate::output::write_text(path, &text)
}

#[cfg(test)]
mod tests {
    use super::relative_to;
    use std::path::Path;

    #[test]
    fn paths_are_made_relative_to_the_manifest_folder() {
        let cases = [
            ("maps/plans/a.xml", "suites", "../maps/plans/a.xml"),
            ("suites/../maps/a.yaml", "./suites", "../maps/a.yaml"),
            ("suites/x.toml", "suites", "x.toml"),
            ("/r/a/b.toml", "/r/c/d", "../../a/b.toml"),
        ];
        for (file, dir, want) in cases {
            assert_eq!(
                relative_to(Path::new(file), Path::new(dir)).unwrap(),
                want,
                "{file} from {dir}"
            );
        }
    }
}
