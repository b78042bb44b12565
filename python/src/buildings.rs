//! The buildings an environment explores: from a path, a glob, a suite's name or manifest, or
//! a generator spec, and the fixed hashed train/test split.

use sim_core::building::Building;
use sim_core::generate::{generate, BuildingKind, GenerateConfig};
use std::path::{Path, PathBuf};

/// One building of an environment, with the name its runs record (as `floorcast explore` names
/// a building: its file's stem; a generated one `gen-KIND-AREA-SEED`).
#[derive(Debug)]
pub(crate) struct Named {
    pub(crate) name: String,
    pub(crate) building: Building,
}

/// Which part of the fixed split to keep.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Split {
    All,
    Train,
    Test,
}

/// The share of buildings in the test part of the split.
pub(crate) const TEST_SHARE: f64 = 0.2;

impl Split {
    pub(crate) fn parse(s: Option<&str>) -> Result<Split, String> {
        match s {
            None => Ok(Split::All),
            Some("train") => Ok(Split::Train),
            Some("test") => Ok(Split::Test),
            Some(other) => Err(format!(
                "split: '{other}' is not a split; expected \"train\", \"test\" or None"
            )),
        }
    }

    /// Whether `b` belongs to this part: the split is the building's content hash (its first
    /// 32 bits as a share of 2^32 below [`TEST_SHARE`]: test), so it does not depend on the
    /// order or company a building is listed in, and a plan listed twice (or copied under
    /// another name) is on one side only.
    pub(crate) fn keeps(self, b: &Building) -> bool {
        let hash = b.content_hash();
        let x = u32::from_str_radix(&hash[..8.min(hash.len())], 16).unwrap_or(0);
        let test = (x as f64) / 4_294_967_296.0 < TEST_SHARE;
        match self {
            Split::All => true,
            Split::Train => !test,
            Split::Test => test,
        }
    }
}

/// Where suites are looked for by name: `$FLOORCAST_SUITES`, `./suites`, and the suites folder
/// of the clone the package was built from.
fn suite_dirs() -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    if let Some(d) = std::env::var_os("FLOORCAST_SUITES") {
        dirs.push(PathBuf::from(d));
    }
    dirs.push(PathBuf::from("suites"));
    dirs.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("../suites"));
    dirs
}

/// The building files and generated buildings one source names, in order.
pub(crate) fn resolve(source: &str) -> Result<Vec<Named>, String> {
    let source = source.trim();
    if source.is_empty() {
        return Err("buildings: an empty name; expected a path, a glob, a suite's name or a generator spec (generate:KIND:AREA_M2:SEEDS)".into());
    }
    if let Some(spec) = source.strip_prefix("generate:") {
        return generated(spec);
    }
    if source.contains(['*', '?', '[']) {
        // Bounded as a grid's patterns are: only below the folder before the first wildcard,
        // at most `MAX_PATTERN_ENTRIES` entries visited, links not followed.
        let files =
            floorcast_worker::pattern::expand_pattern(Path::new(""), source, "the current folder")
                .map_err(|e| format!("buildings: {e}"))?;
        return files.iter().map(|p| read_file(p)).collect();
    }
    let path = Path::new(source);
    if path.is_file() {
        if is_suite_manifest(path) {
            return read_suite(path);
        }
        return Ok(vec![read_file(path)?]);
    }
    if !source.contains(['/', '\\', '.']) {
        for dir in suite_dirs() {
            let manifest = dir.join(format!("{source}.toml"));
            if manifest.is_file() {
                return read_suite(&manifest);
            }
        }
        return Err(format!(
            "buildings: '{source}' is neither a file nor a suite found in {} (give a building file, a glob such as 'maps/plans/*.xml', a suite manifest's path, or generate:KIND:AREA_M2:SEEDS)",
            suite_dirs()
                .iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    Err(format!("buildings: no such file: {source}"))
}

/// Whether a file is a suite manifest (a TOML file saying `format = "floorcast-suite"`).
fn is_suite_manifest(path: &Path) -> bool {
    path.extension().is_some_and(|e| e == "toml")
        && floorcast_formats::limits::read_text(path).is_ok_and(|t| {
            t.lines()
                .any(|l| l.trim() == "format = \"floorcast-suite\"")
        })
}

fn read_suite(path: &Path) -> Result<Vec<Named>, String> {
    let m = floorcast_formats::suite::read_manifest(path).map_err(|e| format!("buildings: {e}"))?;
    m.buildings
        .iter()
        .map(|b| {
            let file = floorcast_formats::suite::Manifest::path_of(path, b);
            read_file(&file)
        })
        .collect()
}

fn read_file(path: &Path) -> Result<Named, String> {
    let building = floorcast_formats::read_building(path).map_err(|e| format!("buildings: {e}"))?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| building.name.clone());
    Ok(Named { name, building })
}

/// `KIND:AREA_M2:SEEDS`, SEEDS one seed or a range `A-B` (at most 10 000 buildings).
fn generated(spec: &str) -> Result<Vec<Named>, String> {
    let usage = "expected generate:KIND:AREA_M2:SEEDS, KIND school or office, AREA_M2 from 100 to 50000, SEEDS a seed or a range A-B (e.g. generate:school:900:1-20)";
    let parts: Vec<&str> = spec.split(':').collect();
    let [kind, area, seeds] = parts[..] else {
        return Err(format!("buildings: 'generate:{spec}': {usage}"));
    };
    let kind = match kind {
        "school" => BuildingKind::School,
        "office" => BuildingKind::Office,
        _ => {
            return Err(format!(
                "buildings: 'generate:{spec}': unknown kind '{kind}'; {usage}"
            ))
        }
    };
    let area_m2: f64 = area
        .parse()
        .ok()
        .filter(|a: &f64| (100.0..=50_000.0).contains(a))
        .ok_or_else(|| format!("buildings: 'generate:{spec}': area '{area}' is not a number from 100 to 50000; {usage}"))?;
    let bad_seeds = || format!("buildings: 'generate:{spec}': seeds '{seeds}'; {usage}");
    let (a, b) = match seeds.split_once('-') {
        Some((a, b)) => (
            a.parse::<u64>().map_err(|_| bad_seeds())?,
            b.parse::<u64>().map_err(|_| bad_seeds())?,
        ),
        None => {
            let s = seeds.parse::<u64>().map_err(|_| bad_seeds())?;
            (s, s)
        }
    };
    if b < a || b - a >= 10_000 {
        return Err(bad_seeds());
    }
    let kind_name = match kind {
        BuildingKind::School => "school",
        BuildingKind::Office => "office",
    };
    Ok((a..=b)
        .map(|seed| {
            let name = format!("gen-{kind_name}-{area}-{seed}");
            let building = generate(&GenerateConfig {
                seed,
                area_m2,
                kind,
                clutter: false,
                rotation_rad: 0.0,
                name: name.clone(),
            });
            Named { name, building }
        })
        .collect())
}
