//! Experiment grids: a TOML file as written (parsed with serde), then a validated [`Plan`]
//! (buildings loaded and hashed, seeds and strategies expanded into jobs with stable ids) before
//! anything runs.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use floorcast_worker::{
    check_start, strategy_names, BuiltIn, GivenSource, GivenStart, Settings, StrategyProgram,
    StrategyRef, JOB_ID_RESULT_FORMAT,
};
use serde::Deserialize;
use sha2::{Digest, Sha256};
use sim_core::generate::{generate, BuildingKind, GenerateConfig};
use sim_core::{Building, Pose};

use floorcast_worker::text::excerpt;

pub const GRID_FORMAT: &str = "floorcast-grid";
pub const GRID_VERSION: u32 = 1;

/// A grid file as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct GridFile {
    format: String,
    version: u32,
    name: String,
    /// Where results go (relative to the current directory); default `results/<name>`.
    results: Option<String>,
    /// Building files or glob patterns, relative to the grid file's directory.
    #[serde(default)]
    buildings: Vec<String>,
    /// Suites (`suites/NAME.toml`): names, found in a `suites/` folder beside the grid file or
    /// above it, or manifests' paths relative to the grid file.
    #[serde(default)]
    suites: Vec<String>,
    /// Buildings generated on the fly.
    #[serde(default)]
    generated: Vec<GeneratedSpec>,
    /// Explicit seeds...
    seeds: Option<Vec<u64>>,
    /// ...or an inclusive range `[first, last]`.
    seed_range: Option<[u64; 2]>,
    strategies: Vec<StrategySpec>,
    /// Settings shared by all jobs (robot, laser, mapping...), as in `--settings` files.
    #[serde(default)]
    settings: toml::Table,
    /// Start poses as a factor of the grid (default: each building's own start).
    starts: Option<StartsSpec>,
    /// Team sizes as a factor of the grid (`robots = [1, 2, 4]`): each strategy runs with each,
    /// labelled `LABEL xN` (docs/teams.md).
    robots: Option<Vec<u64>>,
    /// Seeds added in batches until a sequential test decides each comparison.
    sequential: Option<SequentialSpec>,
    /// The coverage level of the grid's comparisons and sequential test: a run achieves the
    /// outcome with at least this fraction of the explorable area explored (default 0.99).
    coverage: Option<f64>,
}

/// `[sequential]`: the comparisons decided by a sequential test (see `sequential.rs`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SequentialSpec {
    /// The label every other label is compared with.
    reference: String,
    #[serde(default)]
    h0_gain_pct: f64,
    #[serde(default = "default_h1_gain_pct")]
    h1_gain_pct: f64,
    #[serde(default = "default_error_rate")]
    alpha: f64,
    #[serde(default = "default_error_rate")]
    beta: f64,
    /// Seeds added per round, on every building and start, for every label still undecided.
    #[serde(default = "default_batch_seeds")]
    batch_seeds: u64,
    /// The most seeds a comparison takes; undecided then.
    #[serde(default = "default_max_seeds")]
    max_seeds: u64,
    /// How the error rate is shared among several labels tested against the reference:
    /// "bonferroni" (default: each label's test at alpha / labels, so the chance of any false
    /// H1 stays within alpha) or "none" (each at alpha).
    multiplicity: Option<String>,
    /// The time the test measures: "end" (default: until the run ended, having explored the
    /// coverage level) or "coverage" (until it first had the coverage level explored).
    #[serde(default)]
    measure: floorcast_stats::outcome::Measure,
}

fn default_h1_gain_pct() -> f64 {
    5.0
}
fn default_error_rate() -> f64 {
    0.05
}
fn default_batch_seeds() -> u64 {
    2
}
fn default_max_seeds() -> u64 {
    30
}

/// Most seeds a sequential grid may take.
pub const MAX_SEQUENTIAL_SEEDS: u64 = 10_000;

/// `[starts]`: random start poses per building and/or explicit ones.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct StartsSpec {
    /// Random start poses per building.
    #[serde(default)]
    random: u32,
    /// The stream they are drawn from.
    #[serde(default = "default_starts_seed")]
    seed: u64,
    /// `[[starts.poses]]`: a building (named as in the plan) and a pose `[x_m, y_m, heading_deg]`.
    #[serde(default)]
    poses: Vec<PoseSpec>,
}

fn default_starts_seed() -> u64 {
    1
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PoseSpec {
    building: String,
    pose: [f64; 3],
}

/// Most random starts per building a grid may ask for.
pub const MAX_RANDOM_STARTS: u32 = 1000;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct GeneratedSpec {
    seed: u64,
    area_m2: f64,
    #[serde(default = "default_kind")]
    kind: String,
    #[serde(default)]
    clutter: bool,
    #[serde(default)]
    rotation_deg: f64,
    name: Option<String>,
}

fn default_kind() -> String {
    "school".into()
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct StrategySpec {
    /// A built-in strategy (or `command`).
    name: Option<String>,
    /// An external strategy: its command, split into words; words naming files are relative
    /// to the grid file.
    command: Option<Vec<String>>,
    /// Further files the external strategy needs, relative to the grid file.
    #[serde(default)]
    files: Vec<String>,
    /// Seconds the external strategy has for each reply.
    timeout_s: Option<f64>,
    /// The external strategy's own parameters, sent to it in the run message.
    params: Option<toml::Table>,
    /// How the strategy is reported (default: its name; required with `command`). Lets one
    /// grid compare parameter sets.
    label: Option<String>,
    /// Settings overriding the shared ones for this strategy (e.g. `alpha`).
    #[serde(default)]
    settings: toml::Table,
}

/// A building of the plan.
#[derive(Debug, Clone)]
pub struct PlannedBuilding {
    pub name: String,
    /// The file it came from, or `generated(seed=…, area_m2=…, …)`.
    pub source: String,
    pub hash: String,
    pub building: Arc<Building>,
    /// The suite it was planned from (`suites`), which its runs' records carry.
    pub suite: Option<SuiteTag>,
}

/// The suite a building of the plan comes from: its name and hash.
#[derive(Debug, Clone, PartialEq)]
pub struct SuiteTag {
    pub name: String,
    pub hash: String,
}

/// One job of the plan.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedJob {
    /// Hash of everything that determines the result.
    pub id: String,
    /// Index into [`Plan::buildings`].
    pub building: usize,
    pub label: String,
    /// The strategy, resolved when the grid was planned (its name and program are the job's
    /// identity, as the wire and the store name it).
    pub reference: StrategyRef,
    pub seed: u64,
    pub settings: Settings,
    /// The start pose, when the grid sets one (`[starts]`); `None`: the building's own.
    pub start: Option<GivenStart>,
}

/// A validated grid.
#[derive(Debug, Clone)]
pub struct Plan {
    pub name: String,
    pub grid_path: PathBuf,
    pub results_dir: PathBuf,
    pub buildings: Vec<PlannedBuilding>,
    /// The suites the grid names, in its order.
    pub suites: Vec<crate::suite::PlannedSuite>,
    /// Strategy labels in file order (the first `baseline` one is the reference of gains).
    pub labels: Vec<String>,
    pub jobs: Vec<PlannedJob>,
    /// External strategies' files as read when the grid was planned (by their hash), for
    /// remote workers.
    pub program_files: BTreeMap<String, Arc<floorcast_worker::external::ProgramFiles>>,
    /// The sequential test, when the grid has a `[sequential]` table: `jobs` then holds the
    /// first batch of seeds, and [`Plan::jobs_for`] makes the next ones.
    pub sequential: Option<floorcast_stats::sprt::SequentialPlan>,
    /// The coverage level of the grid's comparisons (`coverage`, default 0.99).
    pub coverage: f64,
    /// The strategies and each building's start poses, for [`Plan::jobs_for`].
    strategies: Vec<Resolved>,
    starts: Vec<Vec<Option<GivenStart>>>,
}

impl PlannedJob {
    /// The built-in strategy's name, or the external strategy's label.
    pub fn strategy(&self) -> &str {
        self.reference.name()
    }

    /// An external strategy's program (`None`: a built-in strategy).
    pub fn program(&self) -> Option<&StrategyProgram> {
        self.reference.program()
    }
}

impl Plan {
    /// The jobs of `seeds` for the labels `labels` (all when `None`): building-major, then
    /// start, then seed, then strategy (so partial grids compare fairly).
    pub fn jobs_for(&self, seeds: &[u64], labels: Option<&BTreeSet<String>>) -> Vec<PlannedJob> {
        let mut jobs = Vec::new();
        for (bi, b) in self.buildings.iter().enumerate() {
            for start in &self.starts[bi] {
                for &seed in seeds {
                    for r in &self.strategies {
                        if labels.is_some_and(|l| !l.contains(&r.label)) {
                            continue;
                        }
                        let mut id =
                            job_id_from(&b.hash, &r.name, seed, &r.settings, start.as_ref());
                        if let Some(p) = &r.program {
                            id = program_job_id(&id, p);
                        }
                        jobs.push(PlannedJob {
                            id,
                            building: bi,
                            label: r.label.clone(),
                            reference: r.reference.clone(),
                            seed,
                            settings: r.settings.clone(),
                            start: start.clone(),
                        });
                    }
                }
            }
        }
        jobs
    }
}

#[derive(Debug, thiserror::Error)]
pub enum GridError {
    #[error("cannot read grid file {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Syntax { path: PathBuf, message: String },
    #[error("{path}: {field}: {problem}")]
    Invalid {
        path: PathBuf,
        field: String,
        problem: String,
    },
    #[error("{path}: {field}: {source}")]
    Building {
        path: PathBuf,
        field: String,
        source: Box<floorcast_formats::Error>,
    },
}

/// Bounds on a grid, checked before it is expanded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlanLimits {
    /// Most jobs a grid may hold (buildings x seeds x strategies).
    pub max_jobs: u64,
}

/// Default [`PlanLimits::max_jobs`].
pub const DEFAULT_MAX_JOBS: u64 = 100_000;

impl Default for PlanLimits {
    fn default() -> Self {
        Self {
            max_jobs: DEFAULT_MAX_JOBS,
        }
    }
}

impl Plan {
    /// Reads, validates and expands a grid file. `results_override` replaces its `results`.
    pub fn load(path: &Path, results_override: Option<&Path>) -> Result<Plan, GridError> {
        Self::load_with(path, results_override, &PlanLimits::default())
    }

    /// [`Plan::load`] with explicit limits.
    pub fn load_with(
        path: &Path,
        results_override: Option<&Path>,
        limits: &PlanLimits,
    ) -> Result<Plan, GridError> {
        let text = floorcast_formats::limits::read_text(path).map_err(|e| match e {
            floorcast_formats::Error::Io { source, .. } => GridError::Read {
                path: path.to_path_buf(),
                source,
            },
            e => GridError::Syntax {
                path: path.to_path_buf(),
                message: e
                    .to_string()
                    .strip_prefix(&format!("{}: ", path.display()))
                    .map(str::to_string)
                    .unwrap_or_else(|| e.to_string()),
            },
        })?;
        Self::parse_with(&text, path, results_override, limits)
    }

    pub fn parse(
        text: &str,
        path: &Path,
        results_override: Option<&Path>,
    ) -> Result<Plan, GridError> {
        Self::parse_with(text, path, results_override, &PlanLimits::default())
    }

    /// [`Plan::parse`] with explicit limits.
    pub fn parse_with(
        text: &str,
        path: &Path,
        results_override: Option<&Path>,
        limits: &PlanLimits,
    ) -> Result<Plan, GridError> {
        let invalid = |field: &str, problem: String| GridError::Invalid {
            path: path.to_path_buf(),
            field: field.to_string(),
            problem,
        };
        let file = read_grid_file(text, path, &invalid)?;
        let base_dir = dir_of(path);
        let (buildings, suites) = plan_buildings(&file, base_dir, path, &invalid)?;

        // Seeds (counted before they are listed). A sequential grid adds them in batches.
        check_job_count(&file, buildings.len(), limits, &invalid)?;
        let mut sequential = match &file.sequential {
            Some(q) => Some(sequential_plan(q, &file, &invalid)?),
            None => None,
        };
        let seeds = plan_seeds(&file, sequential.as_ref(), &invalid)?;

        let strategies = plan_strategies(&file, path, &buildings, &invalid)?;
        let radius_m = strategies
            .resolved
            .iter()
            .map(|r| r.settings.robot_radius_m)
            .fold(0.0, f64::max);
        let starts = plan_starts(file.starts.as_ref(), &buildings, radius_m, &invalid)?;

        let coverage = file
            .coverage
            .unwrap_or(floorcast_stats::outcome::DEFAULT_COVERAGE);
        floorcast_stats::outcome::check_coverage(coverage).map_err(|e| invalid("coverage", e))?;
        if let Some(q) = &mut sequential {
            finish_sequential(q, coverage, &strategies.labels, &starts, &invalid)?;
        }
        check_results(file.results.as_deref()).map_err(|p| invalid("results", p))?;
        let results_dir = match results_override {
            Some(p) => p.to_path_buf(),
            None => PathBuf::from(
                file.results
                    .clone()
                    .unwrap_or_else(|| format!("results/{}", file.name)),
            ),
        };
        Ok(Plan {
            name: file.name,
            grid_path: path.to_path_buf(),
            results_dir,
            buildings,
            suites,
            labels: strategies.labels,
            jobs: Vec::new(),
            program_files: strategies.program_files,
            sequential,
            coverage,
            strategies: strategies.resolved,
            starts,
        }
        .with_jobs_for(&seeds))
    }
}

/// The grid file parsed: its header checked first (so that a newer file says so instead of
/// failing on a key), then its fields, then its name.
fn read_grid_file(
    text: &str,
    path: &Path,
    invalid: &dyn Fn(&str, String) -> GridError,
) -> Result<GridFile, GridError> {
    let syntax = |e: toml::de::Error| GridError::Syntax {
        path: path.to_path_buf(),
        message: one_line(&e.to_string()),
    };
    let value: toml::Table = toml::from_str(text).map_err(syntax)?;
    match (
        value.get("format").and_then(|v| v.as_str()),
        value.get("version").and_then(|v| v.as_integer()),
    ) {
        (Some(GRID_FORMAT), Some(v)) if v == GRID_VERSION as i64 => {}
        (Some(GRID_FORMAT), v) => {
            return Err(invalid(
                "version",
                match v {
                    Some(v) => format!("version {v} is not supported, expected {GRID_VERSION}"),
                    None => {
                        format!("missing or not a whole number; expected version = {GRID_VERSION}")
                    }
                },
            ))
        }
        (f, _) => {
            return Err(invalid(
                "format",
                match f {
                    Some(f) => format!("expected format = \"{GRID_FORMAT}\", found \"{f}\""),
                    None => {
                        format!("missing or not a string; expected format = \"{GRID_FORMAT}\"")
                    }
                },
            ))
        }
    }
    let file: GridFile = toml::from_str(text).map_err(syntax)?;
    let _ = (&file.format, file.version);
    if file.name.trim().is_empty()
        || !file
            .name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
    {
        return Err(invalid(
            "name",
            format!(
                "'{}' must be non-empty and use only letters, digits, '-', '_', '.'",
                excerpt(&file.name)
            ),
        ));
    }
    // The name is a folder of `results/` by default.
    crate::names::file_name_part(&file.name).map_err(|p| invalid("name", p))?;
    Ok(file)
}

/// The folder holding `path`, which the grid's relative paths start from: its parent, and "."
/// for a bare file name (`run g.toml`, whose parent is "", which no folder lookup takes).
pub fn dir_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// The grid's buildings: its files (`buildings`), its suites' and its generated ones, each
/// loaded and hashed, their names checked and distinct.
fn plan_buildings(
    file: &GridFile,
    base_dir: &Path,
    path: &Path,
    invalid: &dyn Fn(&str, String) -> GridError,
) -> Result<(Vec<PlannedBuilding>, Vec<crate::suite::PlannedSuite>), GridError> {
    // Patterns are matched as text: a folder whose name is not UTF-8 would match nothing.
    if !file.buildings.is_empty() && base_dir.to_str().is_none() {
        return Err(invalid(
            "buildings",
            format!(
                "the grid file's folder {} has a name that is not UTF-8, which patterns cannot match; move the grid (or rename the folder) to a UTF-8 path",
                floorcast_worker::text::shown(&base_dir.to_string_lossy(), 300)
            ),
        ));
    }
    let mut buildings: Vec<PlannedBuilding> = Vec::new();
    for (i, pattern) in file.buildings.iter().enumerate() {
        let field = format!("buildings[{i}]");
        let matched = expand_pattern(base_dir, pattern).map_err(|e| invalid(&field, e))?;
        for p in matched {
            buildings.push(building_from_file(&p, path, &field)?);
        }
    }
    let suites = plan_suites(&file.suites, base_dir, path, &mut buildings)?;
    // The names of the buildings from files (their file stems), checked as every name is.
    for b in buildings.iter_mut() {
        b.name = crate::names::building_name(&b.name).map_err(|p| {
            invalid(
                "buildings",
                format!(
                    "{}: its name ({}) {p}",
                    floorcast_worker::text::shown(&b.source, 300),
                    if b.suite.is_some() {
                        "in its suite's manifest"
                    } else {
                        "the file name without extension"
                    }
                ),
            )
        })?;
    }
    for (i, g) in file.generated.iter().enumerate() {
        buildings.push(generated_building(g, &format!("generated[{i}]"), invalid)?);
    }
    if buildings.is_empty() {
        return Err(invalid(
            "buildings",
            "the grid names no building (give `buildings`, `suites` or `[[generated]]`)".into(),
        ));
    }
    let mut names = BTreeMap::new();
    for b in &buildings {
        if let Some(prev) = names.insert(b.name.clone(), b.source.clone()) {
            return Err(invalid(
                "buildings",
                format!(
                    "two buildings are named '{}' ({} and {}; names are compared after trimming and Unicode normalisation); rename one",
                    excerpt(&b.name),
                    floorcast_worker::text::shown(&prev, 300),
                    floorcast_worker::text::shown(&b.source, 300)
                ),
            ));
        }
    }
    Ok((buildings, suites))
}

/// A building file of the grid, loaded and hashed, named by its file stem (checked later).
fn building_from_file(p: &Path, path: &Path, field: &str) -> Result<PlannedBuilding, GridError> {
    let b = floorcast_formats::read_building(p).map_err(|source| GridError::Building {
        path: path.to_path_buf(),
        field: field.to_string(),
        source: Box::new(source),
    })?;
    let name = p
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    Ok(PlannedBuilding {
        name,
        source: p.display().to_string(),
        hash: b.content_hash(),
        building: Arc::new(b),
        suite: None,
    })
}

/// A `[[generated]]` building, its parameters checked, generated.
fn generated_building(
    g: &GeneratedSpec,
    field: &str,
    invalid: &dyn Fn(&str, String) -> GridError,
) -> Result<PlannedBuilding, GridError> {
    let max = floorcast_formats::limits::MAX_GENERATED_AREA_M2;
    if !(g.area_m2.is_finite() && (100.0..=max).contains(&g.area_m2)) {
        return Err(invalid(
            &format!("{field}.area_m2"),
            format!("{} is not a free area in [100, {max}] m2", g.area_m2),
        ));
    }
    let kind = match g.kind.as_str() {
        "school" => BuildingKind::School,
        "office" => BuildingKind::Office,
        k => {
            return Err(invalid(
                &format!("{field}.kind"),
                format!("'{}' is not school or office", excerpt(k)),
            ))
        }
    };
    if !g.rotation_deg.is_finite() {
        return Err(invalid(
            &format!("{field}.rotation_deg"),
            format!(
                "expected a finite number of degrees, got {}",
                g.rotation_deg
            ),
        ));
    }
    let name = match &g.name {
        Some(n) => {
            crate::names::building_name(n).map_err(|p| invalid(&format!("{field}.name"), p))?
        }
        None => format!("gen-{}-{}-{}", g.kind, g.area_m2 as u64, g.seed),
    };
    let b = generate(&GenerateConfig {
        seed: g.seed,
        area_m2: g.area_m2,
        kind,
        clutter: g.clutter,
        rotation_rad: g.rotation_deg.to_radians(),
        name: name.clone(),
    });
    Ok(PlannedBuilding {
        name,
        source: format!(
            "generated(seed={}, area_m2={}, kind={}, clutter={}, rotation_deg={})",
            g.seed, g.area_m2, g.kind, g.clutter, g.rotation_deg
        ),
        hash: b.content_hash(),
        building: Arc::new(b),
        suite: None,
    })
}

/// The seeds of the grid (`seeds` or `seed_range`), each once; a sequential grid's first batch.
fn plan_seeds(
    file: &GridFile,
    sequential: Option<&floorcast_stats::sprt::SequentialPlan>,
    invalid: &dyn Fn(&str, String) -> GridError,
) -> Result<Vec<u64>, GridError> {
    let seeds: Vec<u64> = match (&file.seeds, &file.seed_range) {
        _ if sequential.is_some() => {
            let batch = sequential.map_or(1, |q| q.batch_seeds);
            (1..=batch).collect()
        }
        (Some(s), None) if !s.is_empty() => s.clone(),
        (None, Some([a, b])) if a <= b => (*a..=*b).collect(),
        (None, Some(r)) => {
            return Err(invalid(
                "seed_range",
                format!(
                    "[{}, {}] is empty; expected [first, last] with first <= last",
                    r[0], r[1]
                ),
            ))
        }
        (Some(_), Some(_)) => {
            return Err(invalid(
                "seeds",
                "give either `seeds` or `seed_range`, not both".into(),
            ))
        }
        _ => {
            return Err(invalid(
                "seeds",
                "expected `seeds = [1, 2, 3]` or `seed_range = [1, 10]`".into(),
            ))
        }
    };
    let mut seen = std::collections::BTreeSet::new();
    for s in &seeds {
        if !seen.insert(*s) {
            return Err(invalid("seeds", format!("seed {s} is listed twice")));
        }
    }
    Ok(seeds)
}

/// The grid's strategies, resolved: labels in file order, each strategy with its settings and
/// program, and the external strategies' files by hash.
struct PlannedStrategies {
    labels: Vec<String>,
    resolved: Vec<Resolved>,
    program_files: BTreeMap<String, Arc<floorcast_worker::external::ProgramFiles>>,
}

/// Resolves the grid's `[[strategies]]`: each a built-in or an external one, with a distinct
/// label, its settings (the shared ones with its own on top, checked), fitting every building.
fn plan_strategies(
    file: &GridFile,
    path: &Path,
    buildings: &[PlannedBuilding],
    invalid: &dyn Fn(&str, String) -> GridError,
) -> Result<PlannedStrategies, GridError> {
    if file.strategies.is_empty() {
        return Err(invalid("strategies", "the grid names no strategy".into()));
    }
    // Settings from a table, checked; an error names `field`.
    let settings_of = |table: toml::Table, field: &str| -> Result<Settings, GridError> {
        settings_from_table(&table).map_err(|e| match e.field() {
            Some(name) => invalid(&format!("{field}.{name}"), e.problem()),
            None => invalid(field, e.problem()),
        })
    };
    // The shared settings alone first, so that an error in one of them names `settings`
    // rather than the first strategy they were merged into.
    settings_of(file.settings.clone(), "settings")?;
    let mut planned = PlannedStrategies {
        labels: Vec::new(),
        resolved: Vec::new(),
        program_files: BTreeMap::new(),
    };
    let team_sizes = team_sizes(file, invalid)?;
    let grid_dir = dir_of(path);
    for (i, s) in file.strategies.iter().enumerate() {
        let field = format!("strategies[{i}]");
        let reference = match (&s.name, &s.command) {
            (Some(name), None) => StrategyRef::BuiltIn(built_in_strategy(s, name, &field, invalid)?),
            (None, Some(command)) => {
                let (label, program, contents) =
                    external_strategy(s, command, grid_dir, &field, invalid)?;
                planned
                    .program_files
                    .insert(program.files_sha256.clone(), Arc::new(contents));
                StrategyRef::External { label, program }
            }
            (Some(_), Some(_)) => {
                return Err(invalid(
                    &field,
                    "gives both a name (a built-in strategy) and a command (an external one); keep one".into(),
                ))
            }
            (None, None) => {
                return Err(invalid(
                    &field,
                    format!(
                        "names no strategy: give name = one of {}, or command = [\"python3\", \"my_strategy.py\"] with a label",
                        strategy_names().join(", ")
                    ),
                ))
            }
        };
        let (name, program) = (reference.name().to_string(), reference.program().cloned());
        let base_label = s.label.as_deref().unwrap_or(&name);
        for robots in team_sizes.iter().copied() {
            let labelled = match robots {
                Some(n) => format!("{base_label} x{n}"),
                None => base_label.to_string(),
            };
            // Labels are compared as normalised: two that differ only by white space at an end,
            // by NFC against NFD or by an invisible character are one label (the last refused).
            let label = crate::names::label(&labelled)
                .map_err(|p| invalid(&format!("{field}.label"), p))?;
            if let Some(first) = planned.labels.iter().position(|l| *l == label) {
                return Err(invalid(
                &format!("{field}.label"),
                format!(
                    "label '{}' is used twice (strategies[{first}] and {field}; labels are compared after trimming and Unicode normalisation); give each strategy a distinct label",
                    excerpt(&label)
                ),
            ));
            }
            let mut merged = file.settings.clone();
            for (k, v) in &s.settings {
                merged.insert(k.clone(), v.clone());
            }
            with_team_size(&mut merged, robots, &field, invalid)?;
            let settings = settings_of(merged, &format!("{field}.settings"))?;
            check_team_strategy(&settings, program.is_some(), &field, invalid)?;
            if planned.resolved.iter().any(|r: &Resolved| {
                r.settings == settings
                    && match (&r.program, &program) {
                        (None, None) => r.name == name,
                        (Some(a), Some(b)) => program_identity(a) == program_identity(b),
                        _ => false,
                    }
            }) {
                return Err(invalid(
                    &field,
                    format!(
                        "strategy '{}' repeats another with the same name and settings",
                        excerpt(&label)
                    ),
                ));
            }
            check_strategy_fits(reference.base(), &settings, buildings, path)
                .map_err(|(f, p)| invalid(&format!("{field}{f}"), p))?;
            planned.labels.push(label.clone());
            planned.resolved.push(Resolved {
                name: name.clone(),
                settings,
                label,
                program: program.clone(),
                reference: reference.clone(),
            });
        }
    }
    Ok(planned)
}

/// The settings `merged` with the grid's team size `robots` (its `robots` factor) put in;
/// refused when they set `robots` themselves.
fn with_team_size(
    merged: &mut toml::Table,
    robots: Option<u64>,
    field: &str,
    invalid: &dyn Fn(&str, String) -> GridError,
) -> Result<(), GridError> {
    if let Some(n) = robots {
        if merged.contains_key("robots") {
            return Err(invalid(
                "robots",
                format!("is a factor of the grid, and {field}'s settings (or the grid's) set robots too; give the team size in one place"),
            ));
        }
        merged.insert("robots".into(), toml::Value::Integer(n as i64));
    }
    Ok(())
}

/// A team (`robots` > 1) runs built-in strategies only: refused for an external one
/// (`external`) at `field`.
fn check_team_strategy(
    settings: &Settings,
    external: bool,
    field: &str,
    invalid: &dyn Fn(&str, String) -> GridError,
) -> Result<(), GridError> {
    if settings.robots > 1 && external {
        return Err(invalid(
            field,
            format!("an external strategy runs one robot only in this version; team runs ({} robots) take the built-in strategies (team-nearest, team-greedy, team-burgard, team-hungarian, team-minpos, or any other)", settings.robots),
        ));
    }
    Ok(())
}

/// The team sizes of the grid's `robots` factor, checked (`[None]`: no factor, each strategy
/// once).
fn team_sizes(
    file: &GridFile,
    invalid: &dyn Fn(&str, String) -> GridError,
) -> Result<Vec<Option<u64>>, GridError> {
    Ok(match &file.robots {
        None => vec![None],
        Some(sizes) => {
            if sizes.is_empty() {
                return Err(invalid(
                    "robots",
                    "is empty: list team sizes, e.g. robots = [1, 2, 4], or leave it out".into(),
                ));
            }
            for (i, &n) in sizes.iter().enumerate() {
                if !(1..=sim_core::explore::MAX_ROBOTS as u64).contains(&n) {
                    return Err(invalid(
                        &format!("robots[{i}]"),
                        format!(
                            "{n} robots: expected a team size from 1 to {}",
                            sim_core::explore::MAX_ROBOTS
                        ),
                    ));
                }
                if sizes[..i].contains(&n) {
                    return Err(invalid(
                        &format!("robots[{i}]"),
                        format!("{n} is listed twice"),
                    ));
                }
            }
            sizes.iter().map(|&n| Some(n)).collect()
        }
    })
}

/// A built-in strategy named, found, with none of an external strategy's fields.
fn built_in_strategy(
    s: &StrategySpec,
    name: &str,
    field: &str,
    invalid: &dyn Fn(&str, String) -> GridError,
) -> Result<&'static BuiltIn, GridError> {
    let Some(found) = BuiltIn::find(name) else {
        return Err(invalid(
            &format!("{field}.name"),
            format!(
                "unknown strategy '{}' (available: {})",
                excerpt(name),
                strategy_names().join(", ")
            ),
        ));
    };
    for (key, given) in [
        ("files", !s.files.is_empty()),
        ("timeout_s", s.timeout_s.is_some()),
        ("params", s.params.is_some()),
    ] {
        if given {
            return Err(invalid(
                &format!("{field}.{key}"),
                "belongs to an external strategy (one with a command), not to a built-in one"
                    .into(),
            ));
        }
    }
    Ok(found)
}

/// An external strategy: its label, its program (timeout, files, command and parameters
/// checked, each error naming its field) and the contents of its files as read now.
fn external_strategy(
    s: &StrategySpec,
    command: &[String],
    grid_dir: &Path,
    field: &str,
    invalid: &dyn Fn(&str, String) -> GridError,
) -> Result<
    (
        String,
        StrategyProgram,
        floorcast_worker::external::ProgramFiles,
    ),
    GridError,
> {
    let Some(label) = &s.label else {
        return Err(invalid(
            &format!("{field}.label"),
            "an external strategy (one with a command) needs a label".into(),
        ));
    };
    let label = crate::names::label(label).map_err(|p| invalid(&format!("{field}.label"), p))?;
    // Each field's errors name that field: the timeout, each of `files`, then the command
    // (reading the files: `files` when there are any).
    let timeout_s = s
        .timeout_s
        .unwrap_or(floorcast_worker::external::DEFAULT_TIMEOUT_S);
    floorcast_worker::external::check_timeout(timeout_s)
        .map_err(|p| invalid(&format!("{field}.timeout_s"), p))?;
    for (j, f) in s.files.iter().enumerate() {
        floorcast_worker::external::check_file(grid_dir, f)
            .map_err(|p| invalid(&format!("{field}.files[{j}]"), p))?;
    }
    let files_field = if s.files.is_empty() || command.first().is_none_or(|w| w.trim().is_empty()) {
        format!("{field}.command")
    } else {
        format!("{field}.files")
    };
    let program = StrategyProgram::new(command.to_vec(), s.files.clone(), grid_dir, timeout_s)
        .map_err(|p| invalid(&files_field, p))?;
    let params = match &s.params {
        Some(t) => params_json(t, &format!("{field}.params")).map_err(|(f, p)| invalid(&f, p))?,
        None => serde_json::Map::new(),
    };
    let program = program
        .with_params(params)
        .map_err(|p| invalid(&format!("{field}.params"), p))?;
    let contents = program.read_files().map_err(|p| invalid(&files_field, p))?;
    Ok((label, program, contents))
}

/// A sequential grid's test completed once the strategies and starts are known: its coverage,
/// the family's size, a `max_seeds` that can give the pairs the test needs, its reference.
fn finish_sequential(
    q: &mut floorcast_stats::sprt::SequentialPlan,
    coverage: f64,
    labels: &[String],
    starts: &[Vec<Option<GivenStart>>],
    invalid: &dyn Fn(&str, String) -> GridError,
) -> Result<(), GridError> {
    q.coverage = coverage;
    q.labels_tested = labels.len().saturating_sub(1).max(1);
    // Pairs a label's test can have at most: one per building, start and seed.
    let per_seed = starts
        .iter()
        .map(|s| s.len().max(1) as u128)
        .sum::<u128>()
        .max(1);
    let most = q.max_seeds as u128 * per_seed;
    if most < floorcast_stats::sprt::MIN_PAIRS as u128 {
        return Err(invalid(
            "sequential.max_seeds",
            format!(
                "{} seeds give at most {most} pairs ({per_seed} per seed: buildings x starts), fewer than the {} the test needs to decide; raise max_seeds to at least {}",
                q.max_seeds,
                floorcast_stats::sprt::MIN_PAIRS,
                (floorcast_stats::sprt::MIN_PAIRS as u128).div_ceil(per_seed)
            ),
        ));
    }
    let reference =
        crate::names::label(&q.reference).map_err(|p| invalid("sequential.reference", p))?;
    if !labels.contains(&reference) {
        return Err(invalid(
            "sequential.reference",
            format!(
                "'{}' is not a label of the grid's strategies ({})",
                excerpt(&q.reference),
                labels.join(", ")
            ),
        ));
    }
    q.reference = reference;
    if labels.len() < 2 {
        return Err(invalid(
            "sequential",
            "a sequential grid compares labels with the reference: give at least two strategies"
                .into(),
        ));
    }
    Ok(())
}

/// The buildings of the grid's `suites` (each found with [`crate::suite::find_suite`] from the
/// grid's folder), added to `buildings` under their manifests' names. Every building must load
/// and have the content hash its manifest states, so that the suite's hash, which the runs'
/// records carry, names the buildings that ran.
fn plan_suites(
    specs: &[String],
    base_dir: &Path,
    path: &Path,
    buildings: &mut Vec<PlannedBuilding>,
) -> Result<Vec<crate::suite::PlannedSuite>, GridError> {
    use floorcast_formats::suite::{read_manifest, Manifest};
    let mut suites: Vec<crate::suite::PlannedSuite> = Vec::new();
    for (i, spec) in specs.iter().enumerate() {
        let field = format!("suites[{i}]");
        let invalid = |problem: String| GridError::Invalid {
            path: path.to_path_buf(),
            field: field.clone(),
            problem,
        };
        let manifest_path = crate::suite::find_suite(spec, base_dir).map_err(&invalid)?;
        let m = read_manifest(&manifest_path).map_err(|source| GridError::Building {
            path: path.to_path_buf(),
            field: field.clone(),
            source: Box::new(source),
        })?;
        if let Some(j) = suites.iter().position(|s| s.name == m.name) {
            return Err(invalid(format!(
                "suite {} is named twice (suites[{j}] and {field})",
                m.name
            )));
        }
        let hash = m.hash();
        for sb in &m.buildings {
            let file = Manifest::path_of(&manifest_path, sb);
            let b =
                floorcast_formats::read_building(&file).map_err(|source| GridError::Building {
                    path: path.to_path_buf(),
                    field: format!("{field} (suite {}, building {})", m.name, sb.name),
                    source: Box::new(source),
                })?;
            let content = b.content_hash();
            if content != sb.hash {
                return Err(invalid(format!(
                    "suite {}: building {} ({}) has content hash {content}, its manifest {} says {}: the file or floorcast's reading of it changed; run `floorcast suite update {}` (then `floorcast suite check {}`)",
                    m.name,
                    sb.name,
                    file.display(),
                    manifest_path.display(),
                    sb.hash,
                    spec,
                    spec
                )));
            }
            buildings.push(PlannedBuilding {
                name: sb.name.clone(),
                source: file.display().to_string(),
                hash: content,
                building: Arc::new(b),
                suite: Some(SuiteTag {
                    name: m.name.clone(),
                    hash: hash.clone(),
                }),
            });
        }
        suites.push(crate::suite::PlannedSuite {
            name: m.name.clone(),
            hash,
            manifest: manifest_path,
            buildings: m.buildings.len(),
        });
    }
    Ok(suites)
}

/// Settings from a grid's settings table, checked setting by setting.
fn settings_from_table(table: &toml::Table) -> Result<Settings, floorcast_worker::SettingsError> {
    match serde_json::to_value(table) {
        Ok(serde_json::Value::Object(map)) => floorcast_worker::settings::settings_from_map(&map),
        _ => Err(floorcast_worker::SettingsError::Shape(
            "expected a table of settings such as { alpha = 0.8 }".into(),
        )),
    }
}

/// The number of jobs (buildings x starts x seeds x strategies) must stay within the limit; counted
/// without listing the seeds.
fn check_job_count(
    file: &GridFile,
    buildings: usize,
    limits: &PlanLimits,
    invalid: &dyn Fn(&str, String) -> GridError,
) -> Result<(), GridError> {
    let (field, seeds): (&str, u128) = match (&file.seeds, &file.seed_range) {
        _ if file.sequential.is_some() => (
            "sequential.max_seeds",
            file.sequential.as_ref().map_or(0, |q| q.max_seeds) as u128,
        ),
        (_, Some([a, b])) if a <= b => ("seed_range", *b as u128 - *a as u128 + 1),
        (Some(s), _) => ("seeds", s.len() as u128),
        _ => return Ok(()),
    };
    // Start poses per building: the random draws plus the listed poses (at most), else one.
    let starts = file
        .starts
        .as_ref()
        .map_or(1, |s| s.random as u128 + s.poses.len() as u128)
        .max(1);
    let jobs = seeds * starts * buildings as u128 * file.strategies.len().max(1) as u128;
    if jobs > limits.max_jobs as u128 {
        return Err(invalid(
            field,
            format!(
                "{seeds} seeds x {buildings} buildings x {starts} starts x {} strategies make {jobs} jobs, more than the limit of {} jobs per grid; use fewer seeds or raise the limit with --max-jobs",
                file.strategies.len(),
                limits.max_jobs
            ),
        ));
    }
    Ok(())
}

/// The results directory, when given, is a non-empty path on one line.
fn check_results(results: Option<&str>) -> Result<(), String> {
    match results {
        Some(r) if r.trim().is_empty() => Err(
            "empty; expected a directory such as \"results/my-grid\" (or leave `results` out)"
                .into(),
        ),
        Some(r) if r.chars().any(char::is_control) => Err(format!(
            "'{}' holds a line break or control character; expected a directory path",
            excerpt(r)
        )),
        _ => Ok(()),
    }
}

/// A strategy must be able to run on every building of the grid: the oracle strategies need
/// ground-truth rooms, and every building's exploration grid at the strategy's map resolution
/// must fit the cell budget. Returns the field suffix and the problem.
fn check_strategy_fits(
    strategy: &BuiltIn,
    settings: &Settings,
    buildings: &[PlannedBuilding],
    path: &Path,
) -> Result<(), (String, String)> {
    let name = strategy.name;
    let truth = (strategy.make)(&settings.strategy_params()).layout_from_truth();
    for b in buildings {
        if truth && b.building.rooms.is_empty() {
            return Err((
                ".name".into(),
                format!(
                    "strategy {name} takes its layout from the building's ground-truth rooms, and building {} ({}) has none; use buildings that list rooms or another strategy",
                    b.name, b.source
                ),
            ));
        }
        floorcast_formats::limits::check_building(
            &b.building,
            path,
            "map_resolution_m",
            settings.map_resolution_m,
        )
        .map_err(|e| {
            let e = e.to_string();
            let prefix = format!("{}: map_resolution_m: ", path.display());
            (
                ".settings.map_resolution_m".into(),
                format!(
                    "building {}: {}",
                    b.name,
                    e.strip_prefix(&prefix).unwrap_or(&e)
                ),
            )
        })?;
    }
    Ok(())
}

/// The start poses of each building's jobs: `[None]` (the building's own start, checked for
/// a robot of `radius_m`) without `[starts]`; else the random draws then the listed poses
/// (a building with neither keeps its own start). Every pose is checked for the largest
/// robot of the grid, `radius_m`.
fn plan_starts(
    spec: Option<&StartsSpec>,
    buildings: &[PlannedBuilding],
    radius_m: f64,
    invalid: &dyn Fn(&str, String) -> GridError,
) -> Result<Vec<Vec<Option<GivenStart>>>, GridError> {
    let mut out: Vec<Vec<Option<GivenStart>>> = vec![Vec::new(); buildings.len()];
    if let Some(spec) = spec {
        if spec.random > MAX_RANDOM_STARTS {
            return Err(invalid(
                "starts.random",
                format!(
                    "{} random starts per building; at most {MAX_RANDOM_STARTS}",
                    spec.random
                ),
            ));
        }
        if spec.random == 0 && spec.poses.is_empty() {
            return Err(invalid(
                "starts",
                "sets no start: give `random = N` (random starts per building) or \
                 [[starts.poses]] entries, or remove [starts]"
                    .into(),
            ));
        }
        if spec.random > 0 {
            for (bi, b) in buildings.iter().enumerate() {
                let sampler = sim_core::building::StartSampler::new(&b.building, radius_m)
                    .map_err(|e| invalid("starts.random", format!("building {}: {e}", b.name)))?;
                for k in 0..spec.random {
                    out[bi].push(Some(GivenStart {
                        pose: sampler.draw(spec.seed, k as u64),
                        source: GivenSource::Random,
                    }));
                }
            }
        }
        for (i, p) in spec.poses.iter().enumerate() {
            let field = format!("starts.poses[{i}]");
            let name = crate::names::normalized(&p.building, "a building's name")
                .map_err(|e| invalid(&format!("{field}.building"), e))?;
            let Some(bi) = buildings.iter().position(|b| b.name == name) else {
                let names: Vec<&str> = buildings.iter().map(|b| b.name.as_str()).collect();
                return Err(invalid(
                    &format!("{field}.building"),
                    format!(
                        "no building of the grid is named '{}' (the names: {})",
                        excerpt(&p.building),
                        excerpt(&names.join(", "))
                    ),
                ));
            };
            let [x, y, deg] = p.pose;
            if !(-360.0..=360.0).contains(&deg) {
                return Err(invalid(
                    &format!("{field}.pose"),
                    format!(
                        "heading {} is not in [-360, 360] degrees (expected [x_m, y_m, heading_deg])",
                        floorcast_worker::settings::fmt_num(deg)
                    ),
                ));
            }
            let pose = Pose::new(x, y, normal_heading_deg(deg).to_radians());
            let b = &buildings[bi];
            check_start(
                &b.building,
                &b.name,
                pose,
                radius_m,
                &format!("{field}.pose"),
            )
            .map_err(|e| invalid(&format!("{field}.pose"), e.to_string()))?;
            let start = Some(GivenStart {
                pose,
                source: GivenSource::Grid,
            });
            if out[bi].contains(&start) {
                return Err(invalid(
                    &format!("{field}.pose"),
                    format!("building {} already starts at this pose", b.name),
                ));
            }
            out[bi].push(start);
        }
    }
    for (bi, b) in buildings.iter().enumerate() {
        if out[bi].is_empty() {
            // The building's own start: the file's (checked) or the largest clearance.
            let (pose, source) = b
                .building
                .default_start(radius_m)
                .map_err(|e| invalid("buildings", format!("{} ({}): {e}", b.name, b.source)))?;
            if source == sim_core::building::StartSource::File {
                check_start(
                    &b.building,
                    &b.name,
                    pose,
                    radius_m,
                    "the building file's [start]",
                )
                .map_err(|e| invalid("buildings", format!("{}: {e}", b.source)))?;
            }
            out[bi].push(None);
        }
    }
    Ok(out)
}

/// A heading in degrees as one angle of (-180, 180]: 0 and 360, or -180 and 180, are one start
/// pose (one job identity). A heading already in (-180, 180] is returned bit for bit, so that the
/// ids of the jobs it starts keep their value.
pub fn normal_heading_deg(deg: f64) -> f64 {
    if deg > -180.0 && deg <= 180.0 {
        return deg;
    }
    let r = deg.rem_euclid(360.0);
    if r > 180.0 {
        r - 360.0
    } else {
        r
    }
}

/// The labels of a planned grid's jobs have, among the stored `results`, only runs of the same
/// configuration as the grid gives them ([`floorcast_stats::table::Configuration`]); else the
/// first label that has others, in one line.
pub fn check_plan_labels(
    jobs: &[PlannedJob],
    results: &[floorcast_stats::StoredResult],
) -> Result<(), String> {
    use floorcast_stats::table::{check_planned_labels, Configuration};
    let planned = jobs.iter().map(|j| {
        (
            j.label.as_str(),
            Configuration::new(j.strategy(), &j.settings, j.program()),
        )
    });
    check_planned_labels(planned, results)
}

/// The identity of a job: a hash of everything that determines its result.
pub fn job_id(building_hash: &str, strategy: &str, seed: u64, settings: &Settings) -> String {
    job_id_from(building_hash, strategy, seed, settings, None)
}

/// [`job_id`] of a job whose start pose the grid sets (bit-exact); without one, the same id
/// as [`job_id`].
pub fn job_id_from(
    building_hash: &str,
    strategy: &str,
    seed: u64,
    settings: &Settings,
    start: Option<&GivenStart>,
) -> String {
    // The version of this strategy's behaviour, not of the build (the key keeps its name, so
    // that identities made before runs versions existed are unchanged).
    let mut canonical = serde_json::json!({
        "floorcast_version": floorcast_worker::runs_version(strategy),
        "result_format": JOB_ID_RESULT_FORMAT,
        "building_hash": building_hash,
        "strategy": strategy,
        "seed": seed,
        "settings": settings,
    });
    if let Some(s) = start {
        let bits =
            [s.pose.x_m, s.pose.y_m, s.pose.theta_rad].map(|v| format!("{:016x}", v.to_bits()));
        canonical["start"] = serde_json::json!({ "pose_bits": bits, "source": s.source.as_str() });
    }
    let digest = Sha256::digest(canonical.to_string().as_bytes());
    digest[..16].iter().map(|b| format!("{b:02x}")).collect()
}

impl Plan {
    fn with_jobs_for(mut self, seeds: &[u64]) -> Self {
        self.jobs = self.jobs_for(seeds, None);
        self
    }
}

/// A sequential grid's test, checked; the error names the field.
fn sequential_plan(
    q: &SequentialSpec,
    file: &GridFile,
    invalid: &dyn Fn(&str, String) -> GridError,
) -> Result<floorcast_stats::sprt::SequentialPlan, GridError> {
    if file.seeds.is_some() || file.seed_range.is_some() {
        return Err(invalid(
            if file.seeds.is_some() { "seeds" } else { "seed_range" },
            "a grid with [sequential] adds seeds 1, 2, ... in batches itself; leave out seeds and seed_range (max_seeds bounds them)".into(),
        ));
    }
    let config = floorcast_stats::sprt::SprtConfig {
        h0_gain_pct: q.h0_gain_pct,
        h1_gain_pct: q.h1_gain_pct,
        alpha: q.alpha,
        beta: q.beta,
    };
    config.validate().map_err(|e| match e.split_once(": ") {
        Some((field, problem)) => invalid(&format!("sequential.{field}"), problem.to_string()),
        None => invalid("sequential", e),
    })?;
    if !(1..=MAX_SEQUENTIAL_SEEDS).contains(&q.max_seeds) {
        return Err(invalid(
            "sequential.max_seeds",
            format!("{} is not in [1, {MAX_SEQUENTIAL_SEEDS}]", q.max_seeds),
        ));
    }
    if !(1..=q.max_seeds).contains(&q.batch_seeds) {
        return Err(invalid(
            "sequential.batch_seeds",
            format!(
                "{} is not in [1, max_seeds = {}]",
                q.batch_seeds, q.max_seeds
            ),
        ));
    }
    let multiplicity = match q.multiplicity.as_deref() {
        None | Some("bonferroni") => floorcast_stats::sprt::Multiplicity::Bonferroni,
        Some("none") => floorcast_stats::sprt::Multiplicity::None,
        Some(other) => {
            return Err(invalid(
                "sequential.multiplicity",
                format!(
                    "'{}' is not a multiplicity rule (expected \"bonferroni\" or \"none\")",
                    excerpt(other)
                ),
            ))
        }
    };
    Ok(floorcast_stats::sprt::SequentialPlan {
        config,
        reference: q.reference.clone(),
        batch_seeds: q.batch_seeds,
        max_seeds: q.max_seeds,
        coverage: floorcast_stats::outcome::DEFAULT_COVERAGE,
        multiplicity,
        labels_tested: 1,
        measure: q.measure,
    })
}

/// A strategy of the grid, resolved.
#[derive(Debug, Clone)]
struct Resolved {
    /// The built-in strategy's name, or the external strategy's label.
    name: String,
    settings: Settings,
    label: String,
    program: Option<StrategyProgram>,
    /// The strategy resolved.
    reference: StrategyRef,
}

/// What identifies an external strategy's program: its command as written, its files and
/// their hash, its params when it has any (not where it is, nor its timeout).
fn program_identity(p: &StrategyProgram) -> serde_json::Value {
    let mut id = serde_json::json!({
        "command": p.command,
        "files": p.files,
        "files_sha256": p.files_sha256,
    });
    if !p.params.is_empty() {
        id["params"] = serde_json::Value::Object(p.params.clone());
    }
    id
}

/// A strategy's `params` table as JSON; TOML's dates and times, infinities and NaNs have no
/// JSON form and are refused (the failing field and why).
fn params_json(
    t: &toml::Table,
    field: &str,
) -> Result<serde_json::Map<String, serde_json::Value>, (String, String)> {
    fn value(v: &toml::Value, field: &str) -> Result<serde_json::Value, (String, String)> {
        use serde_json::Value as J;
        Ok(match v {
            toml::Value::String(s) => J::String(s.clone()),
            toml::Value::Integer(i) => J::from(*i),
            toml::Value::Boolean(b) => J::Bool(*b),
            toml::Value::Float(x) => match serde_json::Number::from_f64(*x) {
                Some(n) => J::Number(n),
                None => {
                    return Err((
                        field.to_string(),
                        format!("{x} has no JSON form (expected a finite number)"),
                    ))
                }
            },
            toml::Value::Datetime(d) => {
                return Err((
                    field.to_string(),
                    format!(
                        "{d} is a TOML date or time, which JSON has not (write it as a string)"
                    ),
                ))
            }
            toml::Value::Array(a) => J::Array(
                a.iter()
                    .enumerate()
                    .map(|(i, x)| value(x, &format!("{field}[{i}]")))
                    .collect::<Result<_, _>>()?,
            ),
            toml::Value::Table(t) => J::Object(params_json(t, field)?),
        })
    }
    t.iter()
        .map(|(k, v)| Ok((k.clone(), value(v, &format!("{field}.{k}"))?)))
        .collect()
}

/// The id of an external strategy's job: the built-in id's hash with the program's identity.
fn program_job_id(id: &str, p: &StrategyProgram) -> String {
    let canonical = serde_json::json!({ "job": id, "program": program_identity(p) });
    let digest = Sha256::digest(canonical.to_string().as_bytes());
    digest[..16].iter().map(|b| format!("{b:02x}")).collect()
}

/// A parser's message on one line, each of its lines (which may quote a long line of the
/// grid) shortened ([`floorcast_worker::text::shortened`]).
fn one_line(s: &str) -> String {
    s.lines()
        .map(floorcast_worker::text::shortened)
        .collect::<Vec<_>>()
        .join("\n")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

/// At most this many folder entries are visited expanding one building pattern.
pub use floorcast_worker::pattern::MAX_PATTERN_ENTRIES;

/// The files `pattern` (relative to the grid file's folder `base_dir`) names
/// ([`floorcast_worker::pattern::expand_pattern`]).
fn expand_pattern(base_dir: &Path, pattern: &str) -> Result<Vec<PathBuf>, String> {
    expand_pattern_within(base_dir, pattern, MAX_PATTERN_ENTRIES)
}

/// [`expand_pattern`] visiting at most `max_entries` entries.
fn expand_pattern_within(
    base_dir: &Path,
    pattern: &str,
    max_entries: usize,
) -> Result<Vec<PathBuf>, String> {
    floorcast_worker::pattern::expand_pattern_within(
        base_dir,
        pattern,
        max_entries,
        "the grid file's folder",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Plan, GridError> {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../grids/x.toml");
        Plan::parse(text, &dir, None)
    }

    const GOOD: &str = r#"
format = "floorcast-grid"
version = 1
name = "t"
buildings = ["../buildings/small.toml"]
seed_range = [1, 3]
[[generated]]
seed = 4
area_m2 = 500
[[strategies]]
name = "baseline"
[[strategies]]
name = "baseline"
label = "near"
settings = { alpha = 0.8 }
[settings]
time_limit_s = 600
"#;

    #[test]
    fn every_shipped_grid_is_a_valid_plan() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../grids");
        let mut grids: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .collect();
        grids.sort();
        assert!(grids.len() >= 10, "{grids:?}");
        for g in &grids {
            let text = std::fs::read_to_string(g).unwrap();
            let plan =
                Plan::parse(&text, g, None).unwrap_or_else(|e| panic!("{}: {e}", g.display()));
            assert!(!plan.jobs.is_empty(), "{}", g.display());
        }
    }

    #[test]
    fn building_patterns_stay_below_their_folder_and_are_bounded() {
        use std::os::unix::ffi::OsStrExt;
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        let grids = root.join("grids");
        for d in ["grids", "b/sub/deeper", "many", "odd"] {
            std::fs::create_dir_all(root.join(d)).unwrap();
        }
        for f in [
            "b/a.toml",
            "b/z.toml",
            "b/sub/c.toml",
            "b/sub/deeper/d.toml",
            "b/notes.txt",
        ] {
            std::fs::write(root.join(f), "").unwrap();
        }
        for i in 0..20 {
            std::fs::write(root.join(format!("many/{i}.toml")), "").unwrap();
        }
        std::fs::write(
            root.join("odd")
                .join(std::ffi::OsStr::from_bytes(b"caf\xe9.toml")),
            "",
        )
        .unwrap();
        // A link back up: followed, it would never end.
        std::os::unix::fs::symlink(root.join("b"), root.join("b/sub/loop")).unwrap();
        let names = |r: Result<Vec<PathBuf>, String>| -> Result<Vec<String>, String> {
            r.map(|v| {
                v.iter()
                    .map(|p| p.strip_prefix(&grids).unwrap().display().to_string())
                    .collect()
            })
        };
        // (pattern, entries visited at most, the files, or words of the error)
        type Case<'a> = (&'a str, usize, Result<&'a [&'a str], &'a [&'a str]>);
        let cases: &[Case] = &[
            ("../b/a.toml", 10, Ok(&["../b/a.toml"])),
            ("../b/*.toml", 10, Ok(&["../b/a.toml", "../b/z.toml"])),
            ("../b/?.toml", 10, Ok(&["../b/a.toml", "../b/z.toml"])),
            (
                "../b/**/*.toml",
                100,
                Ok(&[
                    "../b/a.toml",
                    "../b/sub/c.toml",
                    "../b/sub/deeper/d.toml",
                    "../b/z.toml",
                ]),
            ),
            ("../b/*/c.toml", 100, Ok(&["../b/sub/c.toml"])),
            ("../b/*.yaml", 10, Err(&["'../b/*.yaml' matches no file"])),
            ("../b/nothing.toml", 10, Err(&["matches no file"])),
            ("../b/*/../a.toml", 100, Err(&["'..' after a wildcard"])),
            ("/**/small.toml", 100, Err(&["whole file system"])),
            ("/*.toml", 100, Err(&["whole file system"])),
            ("../b/[a.toml", 100, Err(&["bad glob pattern"])),
            (
                "../many/*.toml",
                10,
                Err(&["visits more than 10 entries", "narrower"]),
            ),
            ("../odd/*.toml", 10, Err(&["is not UTF-8", "rename it"])),
        ];
        for (pattern, max, want) in cases {
            let got = names(expand_pattern_within(&grids, pattern, *max));
            match (want, &got) {
                (Ok(files), Ok(v)) => assert_eq!(v, files, "{pattern}"),
                (Err(words), Err(e)) => {
                    for w in *words {
                        assert!(e.contains(w), "{pattern}: {w:?} missing in {e}");
                    }
                }
                _ => panic!("{pattern}: got {got:?}, expected {want:?}"),
            }
        }
        assert_eq!(
            names(expand_pattern(&grids, "../many/*.toml"))
                .unwrap()
                .len(),
            20
        );
    }

    /// A suite's buildings are planned under their manifests' names, tagged with the suite's
    /// name and hash; their jobs are those of the same files named in `buildings` (a suite is a
    /// label on a result, not part of its identity).
    #[test]
    fn a_suite_plans_its_buildings_with_the_same_job_ids_as_their_files() {
        let grid = |buildings: &str| {
            format!(
                "format = \"floorcast-grid\"\nversion = 1\nname = \"s\"\n{buildings}\nseeds = [1]\n[[strategies]]\nname = \"baseline\"\n"
            )
        };
        let suite = parse(&grid("suites = [\"paper-set\"]")).unwrap();
        let files = parse(&grid("buildings = [\"../buildings/paper/paper-*.toml\"]")).unwrap();
        let manifest = floorcast_formats::suite::read_manifest(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("../suites/paper-set.toml"),
        )
        .unwrap();
        assert_eq!(suite.suites.len(), 1);
        assert_eq!(suite.suites[0].name, "paper-set");
        assert_eq!(suite.suites[0].hash, manifest.hash());
        assert_eq!(suite.buildings.len(), 10);
        for b in &suite.buildings {
            let tag = b.suite.as_ref().unwrap();
            assert_eq!(
                (tag.name.as_str(), tag.hash.as_str()),
                ("paper-set", manifest.hash().as_str())
            );
        }
        assert!(files.buildings.iter().all(|b| b.suite.is_none()));
        let ids = |p: &Plan| {
            let mut v: Vec<(String, String)> = p
                .jobs
                .iter()
                .map(|j| (p.buildings[j.building].name.clone(), j.id.clone()))
                .collect();
            v.sort();
            v
        };
        assert_eq!(ids(&suite), ids(&files));
        // Both at once: the same buildings twice, refused by name.
        let e = parse(&grid(
            "buildings = [\"../buildings/paper/paper-01.toml\"]\nsuites = [\"paper-set\"]",
        ))
        .unwrap_err()
        .to_string();
        assert!(e.contains("two buildings are named 'paper-01'"), "{e}");
    }

    #[test]
    fn expands_buildings_seeds_and_strategies() {
        let p = parse(GOOD).unwrap();
        assert_eq!(p.buildings.len(), 2);
        assert_eq!(p.jobs.len(), 2 * 3 * 2);
        assert_eq!(p.labels, vec!["baseline", "near"]);
        assert_eq!(p.results_dir, PathBuf::from("results/t"));
        let near = p.jobs.iter().find(|j| j.label == "near").unwrap();
        assert_eq!(near.settings.alpha, 0.8);
        assert_eq!(near.settings.time_limit_s, 600.0);
        // Ids are unique and stable.
        let ids: std::collections::BTreeSet<_> = p.jobs.iter().map(|j| j.id.clone()).collect();
        assert_eq!(ids.len(), p.jobs.len());
        assert_eq!(parse(GOOD).unwrap().jobs, p.jobs);
    }

    #[test]
    fn errors_name_the_field() {
        let cases = [
            (
                GOOD.replace(
                    "name = \"baseline\"\n[[strategies]]",
                    "name = \"nope\"\n[[strategies]]",
                ),
                "strategies[0].name",
            ),
            (
                GOOD.replace("seed_range = [1, 3]", "seed_range = [3, 1]"),
                "seed_range",
            ),
            (
                GOOD.replace("alpha = 0.8", "alpha = 2.0"),
                "strategies[1].settings",
            ),
            (GOOD.replace("alpha = 0.8", "alpah = 0.8"), "alpah"),
            (
                GOOD.replace("../buildings/small.toml", "../buildings/nothing*.toml"),
                "buildings[0]",
            ),
            (GOOD.replace("version = 1", "version = 9"), "version"),
            (
                GOOD.replace("area_m2 = 500", "area_m2 = -5"),
                "generated[0].area_m2",
            ),
            (
                GOOD.replace("label = \"near\"", "label = \"baseline\""),
                "strategies[1].label",
            ),
            (
                GOOD.replace("seed_range = [1, 3]", "seeds = [1, 1]"),
                "seeds",
            ),
            (
                GOOD.replace("name = \"t\"", "name = \"t\"\nbogus = 1"),
                "bogus",
            ),
        ];
        for (text, needle) in cases {
            let e = parse(&text).unwrap_err().to_string();
            assert!(e.contains(needle) && e.contains("x.toml"), "{needle}: {e}");
            assert_eq!(e.lines().count(), 1, "{e}");
        }
        // A bad shared setting is named as such, not as the first strategy's.
        for bad in ["time_limit_s = -5", "time_limt_s = 600"] {
            let e = parse(&GOOD.replace("time_limit_s = 600", bad))
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("settings") && !e.contains("strategies["),
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn the_starts_grid_plans_ten_random_starts_on_every_shared_map_and_paper_building() {
        let g = Path::new(env!("CARGO_MANIFEST_DIR")).join("../grids/starts.toml");
        let p = Plan::parse(&std::fs::read_to_string(&g).unwrap(), &g, None).unwrap();
        let maps = Path::new(env!("CARGO_MANIFEST_DIR")).join("../maps");
        let mut expected = 10; // the paper set
        for folder in ["schools", "partial", "radish", "stage"] {
            expected += std::fs::read_dir(maps.join(folder))
                .unwrap()
                .filter(|e| {
                    let p = e.as_ref().unwrap().path();
                    p.extension().is_some_and(|x| x == "yaml" || x == "world")
                })
                .count();
        }
        assert_eq!(p.buildings.len(), expected);
        assert_eq!(p.jobs.len(), expected * 10 * 2);
        let radius = Settings::default().robot_radius_m;
        for (bi, b) in p.buildings.iter().enumerate() {
            let starts: std::collections::BTreeSet<[u64; 3]> = p
                .jobs
                .iter()
                .filter(|j| j.building == bi)
                .map(|j| {
                    let s = j.start.as_ref().expect("a start pose");
                    assert_eq!(s.source, GivenSource::Random);
                    assert!(b.building.check_start(s.pose, radius).is_ok(), "{}", b.name);
                    [s.pose.x_m, s.pose.y_m, s.pose.theta_rad].map(f64::to_bits)
                })
                .collect();
            assert_eq!(starts.len(), 10, "{}", b.name);
        }
        let ids: std::collections::BTreeSet<_> = p.jobs.iter().map(|j| j.id.clone()).collect();
        assert_eq!(ids.len(), p.jobs.len());
    }

    #[test]
    fn starts_multiply_the_jobs_and_change_only_their_ids() {
        let plain = parse(GOOD).unwrap();
        let with = |starts: &str| parse(&format!("{GOOD}{starts}"));
        let p = with("[starts]\nrandom = 2\n").unwrap();
        assert_eq!(p.jobs.len(), 2 * plain.jobs.len());
        // Without [starts] every job keeps the id it has always had.
        for j in &plain.jobs {
            assert_eq!(j.start, None);
            assert_eq!(
                j.id,
                job_id(
                    &plain.buildings[j.building].hash,
                    j.strategy(),
                    j.seed,
                    &j.settings
                )
            );
        }
        let ids: std::collections::BTreeSet<_> = p.jobs.iter().map(|j| j.id.clone()).collect();
        assert_eq!(ids.len(), p.jobs.len());
        assert!(p
            .jobs
            .iter()
            .all(|j| !plain.jobs.iter().any(|q| q.id == j.id)));
        // The same draws every time; another seed draws others.
        assert_eq!(with("[starts]\nrandom = 2\n").unwrap().jobs, p.jobs);
        let other = with("[starts]\nrandom = 2\nseed = 9\n").unwrap();
        assert_ne!(other.jobs[0].start, p.jobs[0].start);
        // Every strategy and seed of a building starts from the same poses.
        let small: Vec<_> = p.jobs.iter().filter(|j| j.building == 0).collect();
        assert_eq!(small[0].start, small[5].start);
        assert_ne!(small[0].start, small[6].start);
        // Listed poses, per building; a building without any keeps its own start.
        let listed = with(
            "[starts]\n[[starts.poses]]\nbuilding = \"small\"\npose = [3.0, 3.0, 90.0]\n\
             [[starts.poses]]\nbuilding = \"small\"\npose = [5.0, 3.0, -45.0]\n",
        )
        .unwrap();
        let starts: Vec<Option<GivenStart>> = listed.jobs.iter().map(|j| j.start.clone()).collect();
        assert_eq!(listed.jobs.len(), 2 * 6 + 6);
        assert_eq!(
            starts[0],
            Some(GivenStart {
                pose: Pose::new(3.0, 3.0, 90f64.to_radians()),
                source: GivenSource::Grid
            })
        );
        assert!(starts[12..].iter().all(|s| s.is_none()));
        let gen = &listed.jobs[12];
        assert_eq!(
            gen.id,
            plain.jobs.iter().find(|j| j.building == 1).unwrap().id
        );
    }

    #[test]
    fn bad_starts_name_the_field() {
        let cases = [
            ("[starts]\nrandom = 1001\n", "starts.random", "at most 1000"),
            ("[starts]\nseed = 2\n", "starts", "sets no start"),
            ("[starts]\nrandmo = 2\n", "randmo", ""),
            (
                "[[starts.poses]]\nbuilding = \"nope\"\npose = [3.0, 3.0, 0.0]\n",
                "starts.poses[0].building",
                "small, gen-school-500-4",
            ),
            (
                "[[starts.poses]]\nbuilding = \"small\"\npose = [3.0, 3.0, 1e300]\n",
                "starts.poses[0].pose",
                "[-360, 360]",
            ),
            (
                "[[starts.poses]]\nbuilding = \"small\"\npose = [-50.0, 3.0, 0.0]\n",
                "starts.poses[0].pose",
                "not in free space in building small; the nearest free position",
            ),
            (
                "[[starts.poses]]\nbuilding = \"small\"\npose = [0.0, 9.81, 0.0]\n",
                "starts.poses[0].pose",
                "too close for the robot's body",
            ),
            (
                "[[starts.poses]]\nbuilding = \"small\"\npose = [3.0, 3.0, 0.0]\n\
                 [[starts.poses]]\nbuilding = \"small\"\npose = [3.0, 3.0, 0.0]\n",
                "starts.poses[1].pose",
                "already starts at this pose",
            ),
        ];
        for (starts, field, needle) in cases {
            let e = parse(&format!("{GOOD}{starts}")).unwrap_err().to_string();
            assert!(
                e.contains(field) && e.contains(needle) && e.contains("x.toml"),
                "{starts}: {e}"
            );
            assert_eq!(e.lines().count(), 1, "{e}");
        }
        // A robot too large for any start of the building.
        let e = parse(&GOOD.replace(
            "time_limit_s = 600",
            "time_limit_s = 600\nrobot_radius_m = 2.0",
        ))
        .unwrap_err()
        .to_string();
        assert!(e.contains("for the robot's body"), "{e}");
    }

    #[test]
    fn labels_are_unique_after_normalisation_naming_both() {
        for second in ["near ", " near", "near\u{200b}"] {
            let text = GOOD.replace("label = \"near\"", &format!("label = \"{second}\""))
                + "[[strategies]]\nname = \"baseline\"\nlabel = \"near\"\nsettings = { alpha = 0.7 }\n";
            let e = parse(&text).unwrap_err().to_string();
            if second.contains('\u{200b}') {
                assert!(
                    e.contains("strategies[1].label") && e.contains("U+200B"),
                    "{e}"
                );
            } else {
                assert!(
                    e.contains("strategies[2].label")
                        && e.contains("used twice")
                        && e.contains("strategies[1]"),
                    "{second:?}: {e}"
                );
            }
            assert_eq!(e.lines().count(), 1, "{e}");
        }
        // NFD and NFC spellings of one label are one label.
        let text = GOOD.replace("label = \"near\"", "label = \"cafe\\u0301\"")
            + "[[strategies]]\nname = \"baseline\"\nlabel = \"caf\\u00e9\"\nsettings = { alpha = 0.7 }\n";
        let e = parse(&text).unwrap_err().to_string();
        assert!(
            e.contains("strategies[2].label") && e.contains("used twice"),
            "{e}"
        );
        // A kept label is the normalised one.
        let p = parse(&GOOD.replace("label = \"near\"", "label = \" cafe\\u0301 \"")).unwrap();
        assert_eq!(p.labels, vec!["baseline", "caf\u{e9}"]);
        for bad in ["\\u202eevil", "a\\u2066b", "\\u0007bell"] {
            let e = parse(&GOOD.replace("label = \"near\"", &format!("label = \"{bad}\"")))
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("strategies[1].label") && e.contains("printable"),
                "{e}"
            );
            assert!(!e
                .chars()
                .any(|c| floorcast_worker::text::unprintable(c).is_some()));
        }
    }

    #[test]
    fn building_names_are_printable_short_and_no_paths() {
        for (name, needle) in [
            ("../evil", "path separator"),
            ("a/b", "path separator"),
            ("bell\\u0007", "U+0007"),
            ("line\\nbreak", "U+000A"),
            ("\\u202egnp", "U+202E"),
        ] {
            let text = GOOD.replace(
                "area_m2 = 500",
                &format!("area_m2 = 500\nname = \"{name}\""),
            );
            let e = parse(&text).unwrap_err().to_string();
            assert!(
                e.contains("generated[0].name") && e.contains(needle),
                "{name}: {e}"
            );
            assert_eq!(e.lines().count(), 1, "{e}");
        }
        let long = "n".repeat(245);
        let e = parse(&GOOD.replace(
            "area_m2 = 500",
            &format!("area_m2 = 500\nname = \"{long}\""),
        ))
        .unwrap_err()
        .to_string();
        assert!(e.contains("245 characters") && e.len() < 400, "{e}");
        // A generated name equal to a file's stem after trimming is a duplicate.
        let e = parse(&GOOD.replace("area_m2 = 500", "area_m2 = 500\nname = \" small \""))
            .unwrap_err()
            .to_string();
        assert!(e.contains("two buildings are named 'small'"), "{e}");
        // Start poses name buildings as normalised.
        let p = parse(&format!(
            "{GOOD}[[starts.poses]]\nbuilding = \" small \"\npose = [3.0, 3.0, 0.0]\n"
        ))
        .unwrap();
        assert!(p.jobs.iter().any(|j| j.start.is_some()));
    }

    #[test]
    fn headings_are_one_angle_and_in_range_ids_keep_their_value() {
        for (deg, want) in [
            (0.0, 0.0),
            (360.0, 0.0),
            (-360.0, 0.0),
            (180.0, 180.0),
            (-180.0, 180.0),
            (270.0, -90.0),
            (-270.0, 90.0),
            (-90.0, -90.0),
            (45.5, 45.5),
        ] {
            assert_eq!(normal_heading_deg(deg), want, "{deg}");
        }
        // In (-180, 180]: bit for bit.
        for deg in [0.1f64, -179.999, 180.0, 1e-300, -0.0, 33.333333333333336] {
            assert_eq!(normal_heading_deg(deg).to_bits(), deg.to_bits(), "{deg}");
        }
        let pose = |deg: &str| {
            format!("{GOOD}[[starts.poses]]\nbuilding = \"small\"\npose = [3.0, 3.0, {deg}]\n")
        };
        let id = |deg: &str| parse(&pose(deg)).unwrap().jobs[0].id.clone();
        assert_eq!(id("360.0"), id("0.0"));
        assert_eq!(id("-180.0"), id("180.0"));
        assert_eq!(id("-270.0"), id("90.0"));
        assert_ne!(id("90.0"), id("0.0"));
        // The id of an in-range heading is the one it always had.
        let p = parse(&pose("90.0")).unwrap();
        let j = &p.jobs[0];
        assert_eq!(
            j.id,
            job_id_from(
                &p.buildings[0].hash,
                "baseline",
                j.seed,
                &j.settings,
                Some(&GivenStart {
                    pose: Pose::new(3.0, 3.0, 90f64.to_radians()),
                    source: GivenSource::Grid
                })
            )
        );
        // 0 and 360 degrees are one start pose: listed twice, refused.
        let e = parse(&format!(
            "{}[[starts.poses]]\nbuilding = \"small\"\npose = [3.0, 3.0, 360.0]\n",
            pose("0.0")
        ))
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("starts.poses[1].pose") && e.contains("already starts"),
            "{e}"
        );
    }

    #[test]
    fn a_programs_files_are_named_as_files_and_its_timeout_as_timeout() {
        let ext = |extra: &str| {
            GOOD.replace(
                "[[strategies]]\nname = \"baseline\"\nlabel",
                &format!("[[strategies]]\ncommand = [\"python3\", \"../examples/strategies/nearest.py\"]\n{extra}label"),
            )
        };
        let e = parse(&ext("files = [\"nothing.py\"]\n"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("strategies[1].files[0]") && e.contains("nothing.py"),
            "{e}"
        );
        let e = parse(&ext("files = [\"/etc/hostname\"]\n"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("strategies[1].files[0]"), "{e}");
        let e = parse(&ext("timeout_s = 1e300\n")).unwrap_err().to_string();
        assert!(
            e.contains("strategies[1].timeout_s") && e.contains("[0.01, 3600]"),
            "{e}"
        );
    }

    #[test]
    fn long_values_are_quoted_as_short_excerpts() {
        let big = "x".repeat(200_000);
        // The parser's own messages quote the line (and the value): shortened.
        for text in [
            GOOD.replace("seed_range = [1, 3]", &format!("seed_range = \"{big}\"")),
            GOOD.replace("label = \"near\"", &format!("label = \"{big}")),
        ] {
            let e = parse(&text).unwrap_err().to_string();
            assert!(e.len() < 800, "{} bytes: {}", e.len(), &e[..800]);
            assert!(e.contains("characters in all)"), "{e}");
        }
        // A setting's name.
        let e = parse(&GOOD.replace("time_limit_s = 600", &format!("{big} = 1")))
            .unwrap_err()
            .to_string();
        assert!(
            e.len() < 1200 && e.contains("(200000 characters in all): unknown setting"),
            "{}",
            &e[..800.min(e.len())]
        );
        for text in [
            GOOD.replace(
                "name = \"baseline\"\n[[strategies]]",
                &format!("name = \"{big}\"\n[[strategies]]"),
            ),
            GOOD.replace("area_m2 = 500", &format!("area_m2 = 500\nkind = \"{big}\"")),
            GOOD.replace("label = \"near\"", &format!("label = \"{big}\"")),
        ] {
            let e = parse(&text).unwrap_err().to_string();
            assert!(e.len() < 600, "{} bytes: {}", e.len(), &e[..600]);
            assert!(e.contains("200000 characters in all"), "{e}");
        }
    }

    #[test]
    fn job_id_depends_on_every_input() {
        let s = Settings::default();
        let a = job_id("h", "baseline", 1, &s);
        assert_eq!(a, job_id("h", "baseline", 1, &s));
        assert_ne!(a, job_id("g", "baseline", 1, &s));
        assert_ne!(a, job_id("h", "baseline", 2, &s));
        assert_ne!(
            a,
            job_id(
                "h",
                "baseline",
                1,
                &Settings {
                    alpha: 0.4,
                    ..Settings::default()
                }
            )
        );
    }
}
