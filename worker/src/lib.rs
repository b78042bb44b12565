//! The worker: runs floorcast jobs, one exploration of a building with a strategy, a seed and
//! settings, producing a versioned run record ([`record::RunSummary`]) plus the in-memory result,
//! and the worker process that takes jobs from a coordinator.
//!
//! - [`run_job`]: one job, in memory; [`execute`]: one job into its report (the typed outcome a
//!   worker returns); [`run_jobs_shared`]: jobs that share their beginning (the same building,
//!   seed, start and [`share_key`]) run as one exploration where they agree.
//! - [`process`]: the worker process's loop (ask, run, renew, submit), over a link to the
//!   coordinator that the caller supplies (it knows no transport).
//! - [`wire`]: the versioned messages between coordinator and workers.
//! - [`settings`], [`record`], [`external`]: the settings (the `floorcast-settings` crate,
//!   re-exported), the run record, external strategies.
//! - [`tour`]: the known-map yardstick's record (a building's tour for a run's robot and laser).
//! - [`text`]: outside text (a program's output, a remote worker's error) made safe to print
//!   and store.
//!
//! This crate measures wall time and knows the floorcast version; the simulation itself is
//! `sim-core`'s and stays pure. It stores nothing (the binary and the coordinator store what it
//! returns); the only processes and files it touches are an external strategy's
//! ([`external`]: its program, a remote job's copy of its files, the Python module).

pub mod execute;
pub mod external;
pub mod pattern;
pub mod process;
pub mod record;
pub mod text;
pub mod tour;
pub mod wire;

use std::time::Instant;

use sim_core::building::{PoseProblem, StartSource};
use sim_core::explore::strategy::BuiltInPolicy;
use sim_core::explore::{drive_to_end, Episode, ExploreConfig, Policy, ProgressSample, RunResult};
use sim_core::{Building, Pose};

pub use external::{StrategyError, StrategyProgram};
pub use record::{
    RobotSummary, RunSummary, TeamSummary, JOB_ID_RESULT_FORMAT, SUMMARY_FORMAT,
    SUMMARY_OLDEST_VERSION, SUMMARY_VERSION,
};
pub use settings::{Settings, SettingsError};

/// The run settings: the `floorcast-settings` crate, under the name other crates have always
/// used (`floorcast_worker::settings::...`).
pub mod settings {
    pub use floorcast_settings::*;
}
pub use sim_core::explore::BuiltIn;

/// The floorcast version recorded in every result (the build that made it).
pub const FLOORCAST_VERSION: &str = env!("CARGO_PKG_VERSION");

/// The floorcast versions that changed runs, oldest first, each with the built-in strategies
/// whose runs it changed (`None`: every run, external programs' included). A version means one
/// behaviour: a job's identity names the version in which its strategy's runs last changed
/// ([`runs_version`]), so stored results stay valid across the versions that leave them bit for
/// bit as they were, and never mix two behaviours under one name. `tests/fingerprints.rs`
/// records every reference run's fingerprint under its runs version and fails when a run changes
/// without a new entry here (with a new crate version, CHANGELOG.md saying what changed).
pub const RUNS_CHANGED: &[(&str, Option<&[&str]>)] = &[
    ("0.7.0", None),
    ("0.9.0", Some(&["layout-truth", "layout-truth-es"])),
    // New: the team strategies (issue 81).
    (
        "0.10.0",
        Some(&[
            "team-nearest",
            "team-greedy",
            "team-burgard",
            "team-hungarian",
            "team-minpos",
        ]),
    ),
];

/// The version in which the runs of `strategy` (a built-in's name, or anything else for an
/// external program) last changed: the newest [`RUNS_CHANGED`] entry that names it or every run.
pub fn runs_version(strategy: &str) -> &'static str {
    RUNS_CHANGED
        .iter()
        .rev()
        .find(|(_, names)| names.is_none_or(|n| n.contains(&strategy)))
        .map_or(RUNS_CHANGED[0].0, |(v, _)| v)
}

/// Whether a run of `strategy` made by floorcast `version` is a run of this build: made at or
/// after the version in which the strategy's runs last changed ([`runs_version`]) and not by a
/// later floorcast than this one. A version that is not `major.minor.patch` numbers is not.
pub fn runs_as_this_build(strategy: &str, version: &str) -> bool {
    match (
        version_numbers(version),
        version_numbers(runs_version(strategy)),
        version_numbers(FLOORCAST_VERSION),
    ) {
        (Some(v), Some(first), Some(this)) => first <= v && v <= this,
        _ => false,
    }
}

/// A version's three numbers, for ordering ("0.10.0" after "0.9.1").
fn version_numbers(v: &str) -> Option<[u64; 3]> {
    let mut parts = v.split('.').map(|p| p.parse::<u64>().ok());
    let numbers = [parts.next()??, parts.next()??, parts.next()??];
    parts.next().is_none().then_some(numbers)
}

#[cfg(test)]
mod version_tests {
    use super::*;

    #[test]
    fn a_run_is_this_builds_from_its_strategys_runs_version_to_this_version() {
        let first = runs_version("baseline");
        assert!(runs_as_this_build("baseline", first));
        assert!(runs_as_this_build("baseline", FLOORCAST_VERSION));
        for v in [
            "0.1.0",
            "0.6.9",
            "99.0.0",
            "0.7",
            "0.7.0.1",
            "x",
            "",
            "0.7.0-rc1",
        ] {
            assert!(!runs_as_this_build("baseline", v), "{v}");
        }
        assert_eq!(version_numbers("0.10.2"), Some([0, 10, 2]));
        assert!(version_numbers("0.10.0") > version_numbers("0.9.1"));
    }
}

/// One exploration to run.
#[derive(Debug, Clone)]
pub struct Job<'a> {
    pub building: &'a Building,
    /// Name to record (usually the file stem or the building's name).
    pub building_name: String,
    /// Its strategy, resolved (records name it by [`StrategyRef::name`]).
    pub strategy: StrategyRef,
    pub seed: u64,
    pub settings: Settings,
    /// Overrides the building's start pose.
    pub start: Option<GivenStart>,
    /// Explored fractions at which to keep a copy of the map (see `ExploreConfig`).
    pub snapshot_fractions: Vec<f64>,
}

/// A job's strategy, resolved once: when a grid is planned, a command's arguments are read or
/// a job comes over the wire. A built-in strategy of sim-core's registry
/// ([`sim_core::explore::BUILT_IN`]), or an external program with the label its results carry.
/// Records and wire messages name it as they always have ([`StrategyRef::name`]).
#[derive(Debug, Clone, PartialEq)]
pub enum StrategyRef {
    BuiltIn(&'static BuiltIn),
    External {
        label: String,
        program: StrategyProgram,
    },
}

impl StrategyRef {
    /// The built-in strategy `name`.
    pub fn built_in(name: &str) -> Result<Self, JobError> {
        BuiltIn::find(name)
            .map(Self::BuiltIn)
            .ok_or_else(|| JobError::UnknownStrategy(name.to_string()))
    }

    /// The strategy a job's name and program give: the external `program` labelled `name`, or
    /// without one the built-in strategy `name`.
    pub fn resolve(name: &str, program: Option<StrategyProgram>) -> Result<Self, JobError> {
        match program {
            Some(program) => Ok(Self::External {
                label: name.to_string(),
                program,
            }),
            None => Self::built_in(name),
        }
    }

    /// Its name in records and on the wire: the built-in strategy's name, or the external
    /// strategy's label.
    pub fn name(&self) -> &str {
        match self {
            Self::BuiltIn(b) => b.name,
            Self::External { label, .. } => label,
        }
    }

    /// The external strategy's program (`None`: a built-in strategy).
    pub fn program(&self) -> Option<&StrategyProgram> {
        match self {
            Self::BuiltIn(_) => None,
            Self::External { program, .. } => Some(program),
        }
    }

    /// The built-in strategy whose candidates and gains it chooses among: itself, or for an
    /// external strategy the baseline (and the layout's, when the program asks for them).
    pub fn base(&self) -> &'static BuiltIn {
        match self {
            Self::BuiltIn(b) => b,
            Self::External { .. } => sim_core::explore::strategies::BASELINE,
        }
    }
}

/// A start pose chosen outside the building file (on the command line, or by a grid): the one
/// start type of a job, planned or run here (its wire form is [`wire::WireStart`]).
#[derive(Debug, Clone, PartialEq)]
pub struct GivenStart {
    pub pose: Pose,
    pub source: GivenSource,
}

/// Where a given start pose came from, as the summary's `start_source` records it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GivenSource {
    /// `explore --start X,Y,THETA`.
    CommandLine,
    /// Drawn by [`Building::random_start`] (`--start random`, a grid's random starts).
    Random,
    /// Listed in a grid file (`[[starts.poses]]`).
    Grid,
}

impl GivenSource {
    /// The words of `start_source` (and of the wire's `WireStart::source`).
    pub fn as_str(self) -> &'static str {
        match self {
            GivenSource::CommandLine => "command line",
            GivenSource::Random => "random",
            GivenSource::Grid => "grid",
        }
    }

    /// The source of its words (`None`: not a given start's source).
    pub fn from_name(name: &str) -> Option<GivenSource> {
        [
            GivenSource::CommandLine,
            GivenSource::Random,
            GivenSource::Grid,
        ]
        .into_iter()
        .find(|s| s.as_str() == name)
    }
}

#[derive(Debug, thiserror::Error)]
pub enum JobError {
    #[error("building {name}: {source}")]
    NoStart {
        name: String,
        source: sim_core::building::StartError,
    },
    #[error("{}", bad_start_message(name, origin, pose, problem, *hint))]
    BadStart {
        name: String,
        /// Where the pose came from, e.g. "the building file's \[start\]".
        origin: String,
        pose: Pose,
        problem: PoseProblem,
        /// The nearest position with room for the robot's body.
        hint: Option<sim_core::Vec2>,
    },
    #[error("unknown strategy '{0}' (available: {list})", list = strategy_names().join(", "))]
    UnknownStrategy(String),
    #[error("strategy {strategy} takes its layout from the building's ground-truth rooms, and building {name} has none (a map without rooms); use it with a floorcast building file that lists rooms, or choose another strategy")]
    NoRooms { strategy: String, name: String },
    #[error(transparent)]
    Settings(#[from] SettingsError),
    #[error("building {name}: {problem}")]
    TooLarge { name: String, problem: String },
    #[error(transparent)]
    Strategy(#[from] StrategyError),
    #[error("the simulation failed (a bug in floorcast, please report it): {0}")]
    Panicked(String),
    #[error("strategy {0} is an external program: a team (settings.robots > 1) runs the built-in strategies only in this version (team-nearest, team-greedy, team-burgard, team-hungarian, team-minpos, or any other); run the program with robots = 1")]
    TeamStrategy(String),
    #[error("team starts: {0}")]
    TeamStarts(String),
}

/// What a job produced.
#[derive(Debug, Clone)]
pub struct JobOutput {
    pub summary: RunSummary,
    pub result: RunResult,
    /// What an external strategy wrote to stderr.
    pub strategy_stderr: Option<String>,
    /// A team's whole result (`result` is then the team's run as one).
    pub team: Option<sim_core::explore::TeamResult>,
}

/// The strategies this version implements.
pub fn strategy_names() -> Vec<&'static str> {
    sim_core::explore::Strategy::names()
}

/// This build's bench signature (fishtest's "bench"): the fingerprint of one short, fixed
/// exploration (a generated 300 m2 school, `layout-es`, seed 1, 300 s simulated: mapping, scan
/// matching, planning and the layout all take part). Machines that compute differently
/// (another build, compiler flags or platform) give another signature, and their runs would
/// not match: a coordinator refuses a worker whose signature differs from its own. Computed
/// once per process (about 0.3 s).
pub fn bench_signature() -> &'static str {
    static SIGNATURE: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    SIGNATURE.get_or_init(|| bench_run().fingerprint())
}

/// The bench exploration (see [`bench_signature`]).
fn bench_run() -> sim_core::explore::RunResult {
    let building = sim_core::generate::generate(&sim_core::generate::GenerateConfig {
        seed: 20261125,
        area_m2: 300.0,
        kind: sim_core::generate::BuildingKind::School,
        clutter: false,
        rotation_rad: 0.0,
        name: "bench".into(),
    });
    let settings = Settings {
        time_limit_s: 300.0,
        ..Settings::default()
    };
    let config = settings
        .to_explore_config_for("layout-es")
        .expect("the bench settings are valid");
    let start = building
        .default_start(settings.robot_radius_m)
        .expect("the bench building has a start")
        .0;
    sim_core::explore::explore(&building, start, &config, 1, &mut |_| {})
}

/// Checks everything about a job that can be checked before it runs (strategy, settings, rooms
/// for the oracle strategies, the map's size against the cell budget, the start pose), so that
/// callers can refuse a bad job before they create any output. Returns the config and the start.
pub fn check_job(
    job: &Job<'_>,
) -> Result<(sim_core::explore::ExploreConfig, Pose, String), JobError> {
    let mut config = job.settings.to_explore_config_with(job.strategy.base())?;
    if config.strategy.layout_from_truth() && job.building.rooms.is_empty() {
        return Err(JobError::NoRooms {
            strategy: job.strategy.name().to_string(),
            name: job.building_name.clone(),
        });
    }
    config.snapshot_fractions = job.snapshot_fractions.clone();
    check_size(job.building, &job.building_name, config.map_resolution_m)?;
    let radius_m = job.settings.robot_radius_m;
    let (start, source, origin) = match &job.start {
        Some(g) => (
            g.pose,
            g.source.as_str().to_string(),
            format!("the {} start", g.source.as_str()),
        ),
        None => match job.building.default_start(radius_m) {
            Ok((p, StartSource::File)) => (
                p,
                "building file".to_string(),
                "the building file's [start]".to_string(),
            ),
            Ok((p, StartSource::LargestClearance)) => (
                p,
                "largest clearance".to_string(),
                "the largest clearance".to_string(),
            ),
            Err(source) => {
                return Err(JobError::NoStart {
                    name: job.building_name.clone(),
                    source,
                })
            }
        },
    };
    check_start(job.building, &job.building_name, start, radius_m, &origin)?;
    Ok((config, start, source))
}

/// The exploration grid of `building` at `resolution_m` must fit the cell budget
/// ([`floorcast_formats::limits`]).
fn check_size(building: &Building, name: &str, resolution_m: f64) -> Result<(), JobError> {
    floorcast_formats::limits::check_building(
        building,
        std::path::Path::new(name),
        "map_resolution_m",
        resolution_m,
    )
    .map_err(|e| JobError::TooLarge {
        name: name.to_string(),
        problem: e
            .to_string()
            .strip_prefix(&format!("{name}: "))
            .map(str::to_string)
            .unwrap_or_else(|| e.to_string()),
    })
}

/// Runs one job to completion. `on_progress` sees the exploration curve as it grows. A panic of
/// the simulation is caught and returned as [`JobError::Panicked`]. The run is an [`Episode`]
/// driven to its end, its decisions answered by the job's external program or by the
/// strategy's built-in rule.
pub fn run_job(
    job: &Job<'_>,
    on_progress: &mut dyn FnMut(&ProgressSample),
) -> Result<JobOutput, JobError> {
    run_job_from(job, None, on_progress)
}

/// [`run_job`] of a team (`settings.robots` > 1) whose robots start at `starts` when given
/// (robot 0 at the job's start; each checked), else placed by the team's rule
/// ([`team_starts`]). `on_progress` sees the team's explored area (robot 0's samples).
pub fn run_job_from(
    job: &Job<'_>,
    starts: Option<&[Pose]>,
    on_progress: &mut dyn FnMut(&ProgressSample),
) -> Result<JobOutput, JobError> {
    let (config, start, source) = check_job(job)?;
    if job.settings.robots > 1 || starts.is_some_and(|s| s.len() > 1) {
        return run_team_job(job, config, start, source, starts, on_progress);
    }
    let t0 = Instant::now();
    let mut external = start_external(job, &config, start)?;
    let (building, seed) = (job.building, job.seed);
    let result =
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match external.as_mut() {
            Some(program) => {
                let needs = program.needs();
                let episode = Episode::with_policy(building, start, config.clone(), seed, needs);
                drive_to_end(charged(episode, job), program, on_progress)
            }
            None => {
                let mut rule = BuiltInPolicy::new(&config.strategy, seed);
                let episode = Episode::new(building, start, config.clone(), seed);
                drive_to_end(charged(episode, job), &mut rule, on_progress)
            }
        }))
        .map_err(|p| JobError::Panicked(panic_message(&*p)))?;
    let wall_time_s = t0.elapsed().as_secs_f64();
    let mut summary = RunSummary::new(job, &result, &source, wall_time_s);
    let strategy_stderr = match external {
        Some(s) => {
            let name = s.hello().name.clone();
            let stats = s.finish()?;
            summary.strategy_name = Some(name);
            summary.strategy_compute_s = Some(stats.compute_s);
            summary.strategy_replies = Some(stats.replies);
            Some(stats.stderr)
        }
        None => None,
    };
    Ok(JobOutput {
        summary,
        result,
        strategy_stderr,
        team: None,
    })
}

/// A team's job (see [`run_job_from`]).
fn run_team_job(
    job: &Job<'_>,
    config: ExploreConfig,
    start: Pose,
    source: String,
    given: Option<&[Pose]>,
    on_progress: &mut dyn FnMut(&ProgressSample),
) -> Result<JobOutput, JobError> {
    if job.strategy.program().is_some() {
        return Err(JobError::TeamStrategy(job.strategy.name().to_string()));
    }
    let starts = team_starts(job, start, given)?;
    let t0 = Instant::now();
    let (building, seed) = (job.building, job.seed);
    let team = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut rules: Vec<BuiltInPolicy> = starts
            .iter()
            .map(|_| BuiltInPolicy::new(&config.strategy, seed))
            .collect();
        let mut policies: Vec<&mut dyn sim_core::explore::Policy> = rules
            .iter_mut()
            .map(|r| r as &mut dyn sim_core::explore::Policy)
            .collect();
        let episode = Episode::team(
            building,
            &starts,
            config.clone(),
            seed,
            None,
            sim_core::explore::TeamMap::Shared,
        );
        sim_core::explore::drive_team_to_end(
            charged(episode, job),
            &mut policies,
            &mut |robot, sample| {
                if robot.0 == 0 {
                    on_progress(sample)
                }
            },
        )
    }))
    .map_err(|p| JobError::Panicked(panic_message(&*p)))?
    .ok_or_else(|| JobError::Panicked("a team without robots".into()))?;
    let wall_time_s = t0.elapsed().as_secs_f64();
    let mut summary = RunSummary::new(job, &team.team, &source, wall_time_s);
    summary.team = Some(TeamSummary::new(&team));
    Ok(JobOutput {
        summary,
        result: team.team.clone(),
        strategy_stderr: None,
        team: Some(team),
    })
}

/// The start poses of a job's team of `settings.robots`: `given` (robot 0's must be the job's
/// `start`; each checked as a start), else robot 0 at `start` and the others by
/// [`Building::team_starts`]: drawn at random (the job's seed, and an index from robot 0's
/// start) when the job's start was drawn, else around robot 0.
pub fn team_starts(
    job: &Job<'_>,
    start: Pose,
    given: Option<&[Pose]>,
) -> Result<Vec<Pose>, JobError> {
    let (robots, radius_m) = (job.settings.robots, job.settings.robot_radius_m);
    if let Some(poses) = given {
        if poses.len() != robots {
            return Err(JobError::TeamStarts(format!(
                "{} start poses for a team of {robots} robots (settings.robots); give one per robot, or one and let the others start around it",
                poses.len()
            )));
        }
        for (k, &p) in poses.iter().enumerate().skip(1) {
            check_start(
                job.building,
                &job.building_name,
                p,
                radius_m,
                &format!("robot {k}'s start"),
            )?;
            for (j, q) in poses[..k].iter().enumerate() {
                let gap = (p.position() - q.position()).norm();
                if gap < 2.0 * radius_m {
                    return Err(JobError::TeamStarts(format!(
                        "robots {j} and {k} start {gap:.2} m apart: their bodies ({radius_m} m radius) overlap; start them at least {:.2} m apart",
                        2.0 * radius_m
                    )));
                }
            }
        }
        return Ok(poses.to_vec());
    }
    // (Drawn teammates depend on robot 0's drawn start too: a grid's random starts of one seed
    // put the others elsewhere for each.)
    let rule = match &job.start {
        Some(g) if g.source == GivenSource::Random => sim_core::building::TeamStarts::Random {
            seed: job.seed,
            index: (g.pose.x_m.to_bits() ^ g.pose.y_m.to_bits().rotate_left(21)) % 15_000,
        },
        _ => sim_core::building::TeamStarts::Together,
    };
    job.building
        .team_starts(start, robots, radius_m, rule)
        .map_err(|source| JobError::NoStart {
            name: job.building_name.clone(),
            source,
        })
}

/// The job's external strategy program, started and told of the run (`None`: a built-in
/// strategy).
fn start_external(
    job: &Job<'_>,
    config: &ExploreConfig,
    start: Pose,
) -> Result<Option<external::ExternalStrategy>, JobError> {
    let Some(program) = job.strategy.program() else {
        return Ok(None);
    };
    program.check_files().map_err(|what| StrategyError {
        command: program.display(),
        what,
        stderr: String::new(),
    })?;
    let mut s = external::ExternalStrategy::start(program)?;
    let frame = sim_core::explore::map_frame(&job.building.bounds(), config.map_resolution_m);
    s.begin(
        external::run_message(
            &job.building_name,
            &job.building.content_hash(),
            job.seed,
            start,
            &job.settings,
            &program.params,
            &frame,
        ),
        job.settings.charge_compute,
    )?;
    Ok(Some(s))
}

/// `episode`, each layout computation charged the wall time it took when the job's settings
/// ask for it (`charge_compute`: the robot waits for it).
fn charged(mut episode: Episode, job: &Job<'_>) -> Episode {
    if job.settings.charge_compute {
        episode.charge_layouts(Box::new(|work: &mut dyn FnMut()| {
            let t = Instant::now();
            work();
            t.elapsed().as_secs_f64()
        }));
    }
    episode
}

/// Whether a job's run may share its beginning with runs of other strategies (see
/// [`run_jobs_shared`]): a built-in strategy, compute not charged (charged runs depend on the
/// machine).
fn may_run_together(job: &Job<'_>) -> bool {
    job.strategy.program().is_none() && !job.settings.charge_compute && job.settings.robots == 1
}

/// What the runs sharing a job's beginning must have in common (`None`: it runs alone): its
/// explore configuration without the strategy's early stop
/// ([`sim_core::explore::shared_part`]). Jobs with equal keys and the same building, seed and
/// start can run together.
pub fn share_key(job: &Job<'_>) -> Option<sim_core::explore::ExploreConfig> {
    if !may_run_together(job) {
        return None;
    }
    let mut config = job
        .settings
        .to_explore_config_with(job.strategy.base())
        .ok()?;
    config.snapshot_fractions = job.snapshot_fractions.clone();
    Some(sim_core::explore::shared_part(&config))
}

/// [`run_job`] for each of `jobs`, with the wall time each took. Jobs of the same building,
/// seed, start and [`share_key`] (strategies that differ in their early stop only: `layout`,
/// `layout-es`, `layout-aes`) run as one exploration for as long as their choices agree
/// ([`sim_core::explore::explore_shared`]): each result is the one the job makes alone, and
/// its wall time is the shared part up to where it went alone plus its own. Any other jobs, or
/// any that fails its checks, run one by one.
pub fn run_jobs_shared(jobs: &[Job<'_>]) -> Vec<(Result<JobOutput, JobError>, f64)> {
    let alone = |job: &Job<'_>| {
        let t = Instant::now();
        let r = run_job(job, &mut |_| {});
        (r, t.elapsed().as_secs_f64())
    };
    let same_run = jobs.len() >= 2
        && jobs.iter().all(|j| {
            may_run_together(j)
                && std::ptr::eq(j.building, jobs[0].building)
                && j.seed == jobs[0].seed
                && j.start == jobs[0].start
        });
    if !same_run {
        return jobs.iter().map(alone).collect();
    }
    let checked: Vec<_> = jobs.iter().map(check_job).collect();
    if checked.iter().any(|c| c.is_err()) {
        return jobs.iter().map(alone).collect();
    }
    let checked: Vec<_> = checked.into_iter().map(|c| c.expect("checked")).collect();
    let start = checked[0].1;
    // The one without an early stop leads (it runs longest); the others follow in their order.
    let mut order: Vec<usize> = (0..jobs.len()).collect();
    let no_early_stop = sim_core::explore::EarlyStop::Never;
    order.sort_by_key(|&i| checked[i].0.strategy.early_stop != no_early_stop);
    let configs: Vec<_> = order.iter().map(|&i| checked[i].0.clone()).collect();
    if !sim_core::explore::can_share(&configs) || checked.iter().any(|c| c.1 != start) {
        return jobs.iter().map(alone).collect();
    }
    let t0 = Instant::now();
    let mut clock = || t0.elapsed().as_secs_f64();
    let made = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        sim_core::explore::explore_shared(
            jobs[0].building,
            start,
            &configs,
            jobs[0].seed,
            &mut |_| {},
            &mut clock,
        )
    }));
    let made = match made {
        Ok(m) => m,
        Err(p) => {
            let e = panic_message(&*p);
            return jobs
                .iter()
                .map(|_| (Err(JobError::Panicked(e.clone())), 0.0))
                .collect();
        }
    };
    let mut out: Vec<Option<(Result<JobOutput, JobError>, f64)>> =
        (0..jobs.len()).map(|_| None).collect();
    for (&i, (result, wall_s)) in order.iter().zip(made) {
        let summary = RunSummary::new(&jobs[i], &result, &checked[i].2, wall_s);
        let output = JobOutput {
            summary,
            result,
            strategy_stderr: None,
            team: None,
        };
        out[i] = Some((Ok(output), wall_s));
    }
    out.into_iter().map(|o| o.expect("every job run")).collect()
}

/// A thread, or the system's refusal (out of threads or memory) as an error rather than a
/// panic: the threads of a strategy program's pipes and of `run` (its embedded workers, the
/// checker of remote workers' results).
pub fn spawn_thread<T: Send + 'static>(
    f: impl FnOnce() -> T + Send + 'static,
) -> std::io::Result<std::thread::JoinHandle<T>> {
    refused_for_a_test()?;
    std::thread::Builder::new().spawn(f)
}

/// [`spawn_thread`] in a scope: the threads of `worker` (its job slots, a job's lease renewal).
pub fn spawn_scoped_thread<'scope, T: Send + 'scope>(
    scope: &'scope std::thread::Scope<'scope, '_>,
    f: impl FnOnce() -> T + Send + 'scope,
) -> std::io::Result<std::thread::ScopedJoinHandle<'scope, T>> {
    refused_for_a_test()?;
    std::thread::Builder::new().spawn_scoped(scope, f)
}

/// Without test support no thread is refused here.
#[cfg(not(any(test, feature = "test-support")))]
fn refused_for_a_test() -> std::io::Result<()> {
    Ok(())
}

/// The refusal [`refuse_threads_after`] asked for, if this is the thread to refuse.
#[cfg(any(test, feature = "test-support"))]
fn refused_for_a_test() -> std::io::Result<()> {
    let refuse = REFUSED_AFTER.with(|n| {
        let left = n.get();
        n.set(left.map(|k| k.saturating_sub(1)));
        left == Some(0)
    });
    if refuse {
        return Err(std::io::Error::other("refused for a test"));
    }
    Ok(())
}

#[cfg(any(test, feature = "test-support"))]
thread_local! {
    /// How many more threads [`spawn_thread`] and [`spawn_scoped_thread`] start on this thread
    /// before they refuse them (`None`, always but in tests: all).
    static REFUSED_AFTER: std::cell::Cell<Option<usize>> = const { std::cell::Cell::new(None) };
}

/// For tests of what a refused thread does: [`spawn_thread`] and [`spawn_scoped_thread`],
/// called on this thread, start the next `n` threads and refuse every one after, as a system
/// out of threads would (`None`: refuse none).
#[cfg(any(test, feature = "test-support"))]
pub fn refuse_threads_after(n: Option<usize>) {
    REFUSED_AFTER.with(|r| r.set(n));
}

/// The message of a caught panic.
pub fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".to_string()
    }
}

/// Checks a start pose for a robot of `robot_radius_m` in `building`; the error names
/// `origin` (where the pose came from, e.g. "--start") and suggests the nearest free position
/// with room for the robot's body.
pub fn check_start(
    building: &Building,
    building_name: &str,
    pose: Pose,
    robot_radius_m: f64,
    origin: &str,
) -> Result<(), JobError> {
    building
        .check_start(pose, robot_radius_m)
        .map_err(|problem| {
            let hint = match problem {
                PoseProblem::NotFinite | PoseProblem::Heading => None,
                _ => building.nearest_start_position(pose.position(), robot_radius_m),
            };
            JobError::BadStart {
                name: building_name.to_string(),
                origin: origin.to_string(),
                pose,
                problem,
                hint,
            }
        })
}

/// A coordinate for a message: centimetres, or scientific notation when that would take more
/// than a few digits (a start of 1e300 m is refused in one short line).
fn metres(v: f64) -> String {
    if v.abs() < 1e6 {
        format!("{v:.2}")
    } else {
        format!("{v:.3e}")
    }
}

fn bad_start_message(
    name: &str,
    origin: &str,
    pose: &Pose,
    problem: &PoseProblem,
    hint: Option<sim_core::Vec2>,
) -> String {
    let what = match problem {
        PoseProblem::NotFinite | PoseProblem::Heading => format!(
            "start pose {}, {}, {} deg",
            pose.x_m,
            pose.y_m,
            pose.theta_rad.to_degrees()
        ),
        _ => format!("start position {}, {}", metres(pose.x_m), metres(pose.y_m)),
    };
    let next = match (problem, hint) {
        (PoseProblem::NotFinite, _) => {
            "give finite x,y in metres and a heading in degrees".to_string()
        }
        (PoseProblem::Heading, _) => "give a heading in degrees within [-360, 360]".to_string(),
        (_, Some(h)) => format!(
            "the nearest free position with room for the robot is {:.2},{:.2}",
            h.x, h.y
        ),
        (_, None) => "no position in the building has room for the robot".to_string(),
    };
    format!("{what} from {origin} {problem} in building {name}; {next}")
}

/// The repository's `buildings/small.toml`, for tests.
#[cfg(test)]
pub(crate) fn small_building() -> Building {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../buildings/small.toml"
    ))
    .unwrap();
    floorcast_formats::building_toml::parse_building_toml(&text, std::path::Path::new("small.toml"))
        .unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim_core::{Geometry, Polygon, Vec2};

    #[test]
    fn the_bench_signature_is_a_repeatable_run_that_exercises_the_layout() {
        let r = bench_run();
        assert!(r.layouts_computed > 0, "{}", r.layouts_computed);
        assert!(r.decisions.len() >= 5, "{}", r.decisions.len());
        assert!(r.explored_fraction > 0.3, "{}", r.explored_fraction);
        assert_eq!(bench_signature(), r.fingerprint());
        assert_eq!(bench_run().fingerprint(), r.fingerprint());
    }

    fn box_building(start: Option<Pose>) -> Building {
        Building {
            name: "box".into(),
            geometry: Geometry::Vector {
                outline: Polygon::rect(Vec2::new(0.0, 0.0), Vec2::new(4.0, 3.0)),
                solids: vec![],
            },
            rooms: vec![],
            doors: vec![],
            start,
        }
    }

    fn job<'a>(b: &'a Building, start: Option<GivenStart>) -> Job<'a> {
        Job {
            building: b,
            building_name: "box".into(),
            strategy: StrategyRef::built_in("baseline").unwrap(),
            seed: 1,
            settings: Settings {
                time_limit_s: 2.0,
                ..Settings::default()
            },
            start,
            snapshot_fractions: vec![],
        }
    }

    #[test]
    fn every_start_is_checked_and_named_by_where_it_came_from() {
        let given = |x, y, source| {
            Some(GivenStart {
                pose: Pose::new(x, y, 0.0),
                source,
            })
        };
        // (building's start, given start, error wanted (None = runs), start_source)
        let cases = [
            (None, None, None, "largest clearance"),
            (Some(Pose::new(2.0, 1.5, 0.0)), None, None, "building file"),
            (
                Some(Pose::new(0.1, 1.5, 0.0)),
                None,
                Some("from the building file's [start] is 0.100 m from solid space"),
                "",
            ),
            (
                Some(Pose::new(5.0, 1.5, 0.0)),
                None,
                Some("the building file's [start] is not in free space in building box; the nearest free position with room for the robot is 3.7"),
                "",
            ),
            (None, given(1.0, 1.0, GivenSource::Grid), None, "grid"),
            (
                None,
                given(1.0, 0.15, GivenSource::Random),
                Some("from the random start is 0.150 m"),
                "",
            ),
        ];
        for (file_start, given_start, want_error, source) in cases {
            let b = box_building(file_start);
            match (run_job(&job(&b, given_start), &mut |_| {}), want_error) {
                (Ok(out), None) => assert_eq!(out.summary.start_source, source),
                (Err(e), Some(needle)) => assert!(e.to_string().contains(needle), "{e}"),
                (Ok(out), Some(n)) => panic!("{n}: ran from {:?}", out.summary.start),
                (Err(e), None) => panic!("{e}"),
            }
        }
    }
}
