//! `floorcast explore`: one exploration run, with its records and picture.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use floorcast_coordinator::grid::normal_heading_deg;
use floorcast_worker::external::ExternalStrategy;
use floorcast_worker::settings::{fmt_num, LocalizationSetting, UtilityDistanceSetting};
use floorcast_worker::{
    check_job, check_start, run_job_from, strategy_names, GivenStart, Job, Settings,
    StrategyProgram, StrategyRef,
};
use sim_core::explore::{EndReason, RunResult};

use crate::output::{parse_pose_deg, progress_bar, write_text, Picture};

#[derive(Debug, Args)]
#[command(
    after_long_help = floorcast_worker::settings::settings_help_text(),
    allow_negative_numbers = true
)]
pub struct ExploreArgs {
    /// Building to explore: floorcast TOML, ROS map_server YAML, Stage .world, or annotated floor
    /// plan .xml.
    #[arg(long, value_name = "FILE")]
    building: PathBuf,
    /// Exploration strategy (built in).
    #[arg(long, default_value = "baseline", value_parser = clap::builder::PossibleValuesParser::new(strategy_names()))]
    strategy: String,
    /// Your own strategy: a program speaking floorcast's strategy protocol
    /// (docs/strategy-protocol.md) on its stdin and stdout, e.g. "python3 my_strategy.py"
    /// (split into words as a shell splits them; files it names are hashed into the run's
    /// record). It chooses among the baseline's candidates; its stderr goes to
    /// strategy-stderr.txt in the output directory, also when it fails (when it fails as it
    /// starts, its name unknown: --out, or results/explore/BUILDING-strategy-command-SEED).
    #[arg(long, value_name = "COMMAND", conflicts_with = "strategy")]
    strategy_command: Option<String>,
    /// Seconds the --strategy-command program has for each reply (the first includes its start),
    /// 0.01 to 3600.
    #[arg(long, value_name = "SECONDS", default_value_t = floorcast_worker::external::DEFAULT_TIMEOUT_S, requires = "strategy_command", value_parser = crate::values::number)]
    strategy_timeout_s: f64,
    /// The --strategy-command program's own parameters, a JSON object (at most 64 KiB), e.g.
    /// '{"stop_below_m2": 5}': sent to it in the run message as `params` and recorded with
    /// the run. Only with --strategy-command (built-in strategies take settings instead).
    #[arg(long, value_name = "JSON")]
    strategy_params: Option<String>,
    /// Seed of the run's randomness (odometry error, laser noise): a whole number, 0 to 2^64 - 1.
    #[arg(long, default_value_t = 0, value_parser = crate::values::whole_number::<u64>(0, u64::MAX))]
    seed: u64,
    /// Output directory (default: results/explore/<building>-<strategy>-<seed>).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Start pose "x,y,theta": x and y in metres, the heading theta in degrees within
    /// [-360, 360]; the robot's body (a disc of robot_radius_m, 0.2 m by default) must fit in
    /// free space there. Or "random": a pose drawn from --seed (draw 0 of that stream), uniform
    /// over the free cells with room for the body plus a 0.05 m margin that connect to the
    /// largest-clearance point, heading uniform. Default: the building file's [start], else the
    /// free point with the largest clearance, facing +x.
    /// With a team (--robots N): once for robot 0, the others placed around it (on rings
    /// 2 radii + 0.3 m apart, reachable from it in a straight line, its heading), or "random"
    /// for every robot drawn (robot k from its own block of draws, at least 2 radii + 0.3 m
    /// from the others), or N times, once per robot (docs/teams.md).
    #[arg(long, value_name = "X,Y,THETA|random", value_parser = parse_start, allow_hyphen_values = true)]
    start: Vec<StartArg>,
    /// Robots in the team, 1 to 8 (default: 1, or the settings file's `robots`; with N
    /// --start poses, N). They explore one shared map, each with its own body, noise,
    /// odometry and goal; use a team strategy (team-nearest, team-greedy, team-burgard,
    /// team-hungarian, team-minpos) to coordinate them. The summary then carries the team's
    /// figures; trajectory.csv and decisions.csv a robot column (docs/teams.md).
    #[arg(long, value_name = "N", value_parser = crate::values::whole_number::<usize>(1, 8))]
    robots: Option<usize>,
    /// Where the map's poses come from (default: slam, or the settings file's).
    #[arg(
        long,
        value_parser = crate::values::word_choice(&LocalizationSetting::ALL, LocalizationSetting::as_str)
    )]
    localization: Option<LocalizationSetting>,
    /// The utility's weight of distance against information gain, in [0, 1] (default: 0.5, or
    /// the settings file's).
    #[arg(long, value_parser = crate::values::number)]
    alpha: Option<f64>,
    /// What the utility's distance D(p) measures: the planned path's length, or the straight
    /// line from the robot to the candidate as the paper defines it (default: path, or the
    /// settings file's).
    #[arg(
        long,
        value_parser = crate::values::word_choice(&UtilityDistanceSetting::ALL, UtilityDistanceSetting::as_str)
    )]
    utility_distance: Option<UtilityDistanceSetting>,
    /// Drive back to the start after exploring.
    #[arg(long)]
    return_home: bool,
    /// When a frontier's middle cell cannot be reached, aim at the reachable part of the
    /// frontier nearest to it instead of passing the frontier over (not the paper's rule).
    #[arg(long)]
    candidate_from_reachable_part: bool,
    /// Stop the run at this simulated time, in seconds, 1 to 100000 (default: 14400, or the
    /// settings file's).
    #[arg(long, value_name = "SECONDS", value_parser = crate::values::number)]
    time_limit_s: Option<f64>,
    /// Layout strategies: rebuild the layout only once the known map grew by this fraction of
    /// itself (as well as by 20 m²), in [0, 1] (default: 0.1, or the settings file's; 0: every
    /// 20 m², the paper's trigger and the default before 0.7).
    #[arg(long, value_name = "F", value_parser = crate::values::number)]
    layout_update_fraction: Option<f64>,
    /// Bound each decision's distance search to paths this long, in metres, 0 to 10000
    /// (default: 0 = off, the paper's exact distances, or the settings file's); farther
    /// candidates take the lengths of the last whole search, and a choice beyond the bound is
    /// made again exactly (built-in strategies; docs/scale.md).
    #[arg(long, value_name = "METRES", value_parser = crate::values::number)]
    distance_bound_m: Option<f64>,
    /// Settings file: a JSON object of run settings such as {"alpha": 0.8} (the settings are
    /// listed below); a flag given on the command line overrides the file's value.
    #[arg(long, value_name = "FILE")]
    settings: Option<PathBuf>,
    /// Picture format of the final map.
    #[arg(long, value_enum, default_value_t = Picture::Png)]
    picture: Picture,
    /// Also draw the layout of the map at 20, 40, 60, 80 and 90 % explored
    /// (layout-20.png ... layout-90.png), like the paper's Fig. 3.
    #[arg(long)]
    layout_snapshots: bool,
    /// Add the measured compute time of every layout to simulated time (the robot waits for
    /// it); the run then depends on the machine.
    #[arg(long)]
    charge_compute: bool,
    /// Refuse a building whose polygons' edges cross, however small the slip (by default a
    /// slip of up to 1.5 m and 2 m², 5 % of the polygon, is repaired with a warning;
    /// docs/limits.md).
    #[arg(long)]
    strict: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

pub fn run(a: ExploreArgs) -> Result<()> {
    crate::output::stop_programs_on_ctrl_c();
    // Parameters a built-in strategy would never see are refused, not dropped.
    if a.strategy_params.is_some() && a.strategy_command.is_none() {
        anyhow::bail!(
            "--strategy-params: applies to external strategies (--strategy-command) only; the built-in strategy {} takes settings instead (--settings FILE, see `floorcast settings`)",
            a.strategy
        );
    }
    let (building, _) = crate::cmd_building::read_building_warned(&a.building, a.strict)?;
    let name = a
        .building
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| building.name.clone());
    let mut settings = explore_settings(&a)?;
    if let Some(n) = a.robots {
        settings.robots = n;
    } else if a.start.len() > 1 {
        settings.robots = a.start.len();
    }
    let (start, team_starts) = given_starts(&a, &building, &name, &settings)?;
    let strategy = strategy_of(&a).map_err(|e| failed_start(&a, &name, e))?;
    let label = strategy.name().to_string();
    let job = Job {
        building: &building,
        building_name: name.clone(),
        strategy,
        seed: a.seed,
        settings,
        start,
        snapshot_fractions: if a.layout_snapshots {
            vec![0.2, 0.4, 0.6, 0.8, 0.9]
        } else {
            Vec::new()
        },
    };
    // Everything is checked before any output is created.
    // (A settings file was checked as it was read: what fails here came from a flag.)
    job.settings
        .validate()
        .map_err(|e| anyhow::anyhow!("{e} (given on the command line)"))?;
    let (_, robot0, _) =
        check_job(&job).with_context(|| format!("{}: cannot explore", a.building.display()))?;
    if job.settings.robots > 1 {
        floorcast_worker::team_starts(&job, robot0, team_starts.as_deref())
            .with_context(|| format!("{}: cannot explore", a.building.display()))?;
    }
    let out = out_dir(&a, &name, &label);
    // No file `explore` writes in --out is one it reads.
    let mut paths = crate::output::Paths::new();
    paths
        .read("--building", Some(&a.building))
        .read("--settings", a.settings.as_deref());
    for f in crate::output::EXPLORE_FILES {
        paths.write(&format!("--out's {f}"), Some(&out.join(f)));
    }
    for pct in [20, 40, 60, 80, 90] {
        for ext in ["png", "svg"] {
            let f = format!("layout-{pct}.{ext}");
            paths.write(&format!("--out's {f}"), Some(&out.join(&f)));
        }
    }
    paths.check()?;
    // Written whole or not at all, one explore at a time (`StagedOut`).
    let staged = crate::output::StagedOut::begin(&out)?;
    let dir = staged.dir();

    let pb = progress_bar(1000, a.quiet, "{spinner} {msg} [{bar:40}] {pos}‰ explored");
    let output = match run_job_from(&job, team_starts.as_deref(), &mut |s| {
        pb.set_position((s.explored_fraction * 1000.0) as u64);
        pb.set_message(format!("t = {:.0} s", s.time_s));
    }) {
        Ok(output) => output,
        Err(e) => {
            pb.finish_and_clear();
            return Err(failed_run(staged, &out, e))
                .with_context(|| format!("{}: cannot explore", a.building.display()));
        }
    };
    pb.finish_and_clear();

    write_outputs(&a, dir, &job, &output)?;
    let summary = &output.summary;
    staged.commit()?;
    say!(
        "{name}: {} after {:.0} s simulated ({:.1} % of {:.0} m2 explored, {} decisions, {:.1} m driven) in {:.2} s wall ({:.0}x real time)",
        summary.end_reason,
        summary.exploration_time_s,
        summary.explored_fraction * 100.0,
        summary.free_area_m2,
        summary.decisions,
        summary.path_length_m,
        summary.wall_time_s,
        summary.speedup
    );
    if let Some(w) = short_run_warning(summary) {
        tell!("warning: {w}");
    }
    say!("results in {}", out.display());
    Ok(())
}

/// The output directory: `--out`, else results/explore/BUILDING-STRATEGY-SEED.
fn out_dir(a: &ExploreArgs, name: &str, label: &str) -> PathBuf {
    a.out.clone().unwrap_or_else(|| {
        let label: String = label
            .chars()
            .map(|c| match c {
                'a'..='z' | 'A'..='Z' | '0'..='9' | '.' | '_' | '-' => c,
                _ => '_',
            })
            .collect();
        PathBuf::from(format!("results/explore/{name}-{label}-{}", a.seed))
    })
}

/// A strategy program that failed as it started (before or at its hello): what it wrote to
/// stderr is kept as for a run that failed ([`failed_run`]), in `--out` or, its name unknown,
/// results/explore/BUILDING-strategy-command-SEED.
fn failed_start(a: &ExploreArgs, name: &str, e: anyhow::Error) -> anyhow::Error {
    let Some(se) = e.downcast_ref::<floorcast_worker::external::StrategyError>() else {
        return e;
    };
    if se.stderr.is_empty() {
        return e;
    }
    let out = out_dir(a, name, "strategy-command");
    match crate::output::StagedOut::begin(&out) {
        Ok(staged) => failed_run(
            staged,
            &out,
            floorcast_worker::JobError::Strategy(se.clone()),
        ),
        Err(w) => anyhow::anyhow!("{e} (its stderr could not be kept: {w:#})"),
    }
}

/// A run that failed: an external strategy's stderr is kept in `out` (`strategy-stderr.txt`, the
/// run's only file: the directory holds what this run left, as after a successful run), and the
/// error says where; otherwise nothing is written.
fn failed_run(
    staged: crate::output::StagedOut,
    out: &std::path::Path,
    e: floorcast_worker::JobError,
) -> anyhow::Error {
    let floorcast_worker::JobError::Strategy(se) = &e else {
        return e.into();
    };
    if se.stderr.is_empty() {
        return e.into();
    }
    let file = staged.dir().join("strategy-stderr.txt");
    let kept = write_text(&file, &se.stderr).and_then(|()| staged.commit());
    match kept {
        Ok(()) => anyhow::anyhow!(
            "{e} (its stderr: {})",
            out.join("strategy-stderr.txt").display()
        ),
        Err(w) => anyhow::anyhow!("{e} (its stderr could not be kept: {w:#})"),
    }
}

/// The run's settings: the file's (or the defaults), with the flags on top.
/// The settings of a `--settings` file (the defaults without one).
pub fn settings_file(path: Option<&std::path::Path>) -> Result<Settings> {
    Ok(match path {
        Some(p) => {
            let text = floorcast_formats::limits::read_text(p)?;
            floorcast_worker::settings::settings_from_json_text(&text)
                .map_err(|e| anyhow::anyhow!("{}: {e} (see `floorcast settings`)", p.display()))?
        }
        None => Settings::default(),
    })
}

fn explore_settings(a: &ExploreArgs) -> Result<Settings> {
    let mut settings = settings_file(a.settings.as_deref())?;
    if let Some(l) = a.localization {
        settings.localization = l;
    }
    if let Some(alpha) = a.alpha {
        settings.alpha = alpha;
    }
    if let Some(t) = a.time_limit_s {
        settings.time_limit_s = t;
    }
    if let Some(d) = a.utility_distance {
        settings.utility_distance = d;
    }
    if let Some(f) = a.layout_update_fraction {
        settings.layout_update_fraction = f;
    }
    if let Some(b) = a.distance_bound_m {
        settings.distance_bound_m = b;
    }
    settings.return_home |= a.return_home;
    settings.candidate_from_reachable_part |= a.candidate_from_reachable_part;
    settings.charge_compute |= a.charge_compute;
    Ok(settings)
}

/// Robot 0's start pose of `--start`, checked (`None`: the building's own), and every robot's
/// when `--start` gives one per robot of a team.
fn given_starts(
    a: &ExploreArgs,
    building: &sim_core::building::Building,
    name: &str,
    settings: &Settings,
) -> Result<(Option<GivenStart>, Option<Vec<sim_core::Pose>>)> {
    match a.start.len() {
        0 | 1 => Ok((given_start(a, building, name, settings)?, None)),
        n if n != settings.robots => anyhow::bail!(
            "--start: given {n} times for a team of {} robots (--robots or the settings' robots); give it once (the others start around robot 0) or once per robot",
            settings.robots
        ),
        _ => {
            let mut poses = Vec::new();
            for (k, s) in a.start.iter().enumerate() {
                let StartArg::Pose(pose) = s else {
                    anyhow::bail!(
                        "--start random: given among {} starts; give 'random' once for every robot drawn, or a pose per robot",
                        a.start.len()
                    );
                };
                check_start(
                    building,
                    name,
                    *pose,
                    settings.robot_radius_m,
                    &format!("--start (robot {k})"),
                )
                .with_context(|| format!("{}: cannot explore", a.building.display()))?;
                poses.push(*pose);
            }
            let first = GivenStart {
                pose: poses[0],
                source: floorcast_worker::GivenSource::CommandLine,
            };
            Ok((Some(first), Some(poses)))
        }
    }
}

/// The start pose of `--start` given once, checked (`None`: the building's own).
fn given_start(
    a: &ExploreArgs,
    building: &sim_core::building::Building,
    name: &str,
    settings: &Settings,
) -> Result<Option<GivenStart>> {
    Ok(match a.start.first().cloned() {
        None => None,
        Some(StartArg::Pose(pose)) => {
            check_start(building, name, pose, settings.robot_radius_m, "--start")
                .with_context(|| format!("{}: cannot explore", a.building.display()))?;
            Some(GivenStart {
                pose,
                source: floorcast_worker::GivenSource::CommandLine,
            })
        }
        Some(StartArg::Random) => Some(GivenStart {
            pose: building
                .random_start(settings.robot_radius_m, a.seed, 0)
                .with_context(|| {
                    format!(
                        "{}: --start random: cannot draw a start",
                        a.building.display()
                    )
                })?,
            source: floorcast_worker::GivenSource::Random,
        }),
    })
}

/// The strategy, resolved: the built-in `--strategy`, or the program of `--strategy-command`
/// labelled by its name. An external strategy is started once to learn its name (and refused
/// here if it cannot start or shake hands), before any output is created.
fn strategy_of(a: &ExploreArgs) -> Result<StrategyRef> {
    Ok(match &a.strategy_command {
        Some(line) => {
            let program = StrategyProgram::from_command_line(
                line,
                std::path::Path::new("."),
                a.strategy_timeout_s,
            )
            .map_err(|e| anyhow::anyhow!("--strategy-command: {e}"))?;
            let program = match &a.strategy_params {
                Some(text) => program.with_params(strategy_params(text)?),
                None => Ok(program),
            }
            .map_err(|e| anyhow::anyhow!("--strategy-params: {e}"))?;
            let probe = ExternalStrategy::start(&program)?;
            let name = probe.hello().name.clone();
            probe.finish()?;
            StrategyRef::External {
                label: name,
                program,
            }
        }
        None => StrategyRef::built_in(&a.strategy)?,
    })
}

/// The run's files: summary, progress, decisions, trajectory, the strategy's stderr, the map,
/// the final picture and the layout snapshots.
fn write_outputs(
    a: &ExploreArgs,
    dir: &std::path::Path,
    job: &Job,
    output: &floorcast_worker::JobOutput,
) -> Result<()> {
    let summary = &output.summary;
    write_text(
        &dir.join("summary.json"),
        &(serde_json::to_string_pretty(summary)? + "\n"),
    )?;
    write_text(&dir.join("progress.csv"), &progress_csv(&output.result))?;
    let robots = match &output.team {
        Some(t) => t.robots.iter().collect(),
        None => vec![&output.result],
    };
    write_text(&dir.join("decisions.csv"), &decisions_csv(&robots))?;
    write_text(&dir.join("trajectory.csv"), &trajectory_csv(&robots))?;
    if let Some(text) = output.strategy_stderr.as_ref().filter(|t| !t.is_empty()) {
        write_text(&dir.join("strategy-stderr.txt"), text)?;
    }
    floorcast_formats::map_server::write_map(&output.result.map, &dir.join("map.yaml"))?;
    let picture = dir.join(format!("final.{}", a.picture.extension()));
    match &output.team {
        Some(t) => crate::cmd_building::team_figure(t, job.settings.min_frontier_m),
        None => {
            crate::cmd_building::exploration_figure(&output.result, job.settings.min_frontier_m)
        }
    }
    .save(&picture)
    .with_context(|| format!("cannot write {}", picture.display()))?;

    for snap in &output.result.snapshots {
        let layout = sim_core::layout::reconstruct_layout(
            &snap.map,
            &sim_core::layout::LayoutConfig::default(),
        );
        let p = dir.join(format!(
            "layout-{:.0}.{}",
            snap.fraction * 100.0,
            a.picture.extension()
        ));
        crate::cmd_layout::layout_figure(&snap.map, &layout)
            .save(&p)
            .with_context(|| format!("cannot write {}", p.display()))?;
    }
    Ok(())
}

/// What a user should know about a run that reached the time limit or explored less than 97 %
/// of the reachable free area: a silent short run misleads.
fn short_run_warning(s: &floorcast_worker::RunSummary) -> Option<String> {
    let explored = s.explored_fraction * 100.0;
    let why = match s.end_reason {
        EndReason::TimeLimit => "it reached the time limit (raise time_limit_s)".to_string(),
        _ if s.explored_fraction >= 0.97 => return None,
        EndReason::Stuck => format!(
            "it gave up every goal toward the {} frontier cells left (magenta in final.png)",
            s.frontier_cells_left
        ),
        EndReason::Unreachable => format!(
            "no path leads to the {} frontier cells left (magenta in final.png; a passage narrower than the robot?)",
            s.frontier_cells_left
        ),
        other => format!("it ended with '{other}'"),
    };
    Some(format!(
        "the run ended short, {explored:.1} % explored: {why}"
    ))
}

/// The value of `--start`.
#[derive(Debug, Clone, PartialEq)]
pub enum StartArg {
    Pose(sim_core::Pose),
    Random,
}

fn parse_start(s: &str) -> Result<StartArg, String> {
    if s.trim() == "random" {
        return Ok(StartArg::Random);
    }
    let [x, y, heading] = parse_pose_deg(s)?;
    if !(-360.0..=360.0).contains(&heading) {
        return Err(format!(
            "heading {} in '{s}' is outside [-360, 360] degrees (expected x,y,theta with theta in degrees, or random)",
            fmt_num(heading)
        ));
    }
    // One heading, one start pose, as a grid's `[starts]` reads it: 360 starts the run 0 does,
    // -180 the run 180 does, and `explore` reproduces a grid's job bit for bit.
    Ok(StartArg::Pose(sim_core::Pose::new(
        x,
        y,
        normal_heading_deg(heading).to_radians(),
    )))
}

/// `progress.csv`: as the results store keeps a run's curve.
fn progress_csv(r: &RunResult) -> String {
    use floorcast_stats::progress::Sample;
    let samples: Vec<Sample> = r
        .progress
        .iter()
        .map(|p| Sample {
            time_s: p.time_s,
            explored_area_m2: p.explored_area_m2,
            explored_fraction: p.explored_fraction,
        })
        .collect();
    floorcast_stats::progress::encode(&samples)
}

/// `decisions.csv`: one robot's decisions, or a team's (then with a first column `robot`, robot
/// by robot).
fn decisions_csv(robots: &[&RunResult]) -> String {
    let team = robots.len() > 1;
    let mut s = String::from(if team { "robot," } else { "" });
    s.push_str("time_s,x_m,y_m,theta_rad,goal_x_m,goal_y_m,candidates,gain_m2,distance_m\n");
    for (k, r) in robots.iter().enumerate() {
        for d in &r.decisions {
            if team {
                let _ = write!(s, "{k},");
            }
            let _ = writeln!(
                s,
                "{:.1},{:.3},{:.3},{:.4},{:.3},{:.3},{},{:.3},{:.3}",
                d.time_s,
                d.pose.x_m,
                d.pose.y_m,
                d.pose.theta_rad,
                d.goal.x,
                d.goal.y,
                d.candidates,
                d.gain_m2,
                d.distance_m
            );
        }
    }
    s
}

/// `trajectory.csv`: true and estimated poses at each map update, one robot's or a team's (then
/// with a first column `robot`, robot by robot).
fn trajectory_csv(robots: &[&RunResult]) -> String {
    let team = robots.len() > 1;
    let mut s = String::from(if team { "robot," } else { "" });
    s.push_str("x_m,y_m,theta_rad,est_x_m,est_y_m,est_theta_rad\n");
    for (k, r) in robots.iter().enumerate() {
        for (t, e) in r.trajectory.iter().zip(&r.estimated_trajectory) {
            if team {
                let _ = write!(s, "{k},");
            }
            let _ = writeln!(
                s,
                "{:.3},{:.3},{:.4},{:.3},{:.3},{:.4}",
                t.x_m, t.y_m, t.theta_rad, e.x_m, e.y_m, e.theta_rad
            );
        }
    }
    s
}

/// `--strategy-params`: a JSON object.
pub(crate) fn strategy_params(
    text: &str,
) -> anyhow::Result<serde_json::Map<String, serde_json::Value>> {
    match serde_json::from_str::<serde_json::Value>(text) {
        Ok(serde_json::Value::Object(map)) => Ok(map),
        Ok(_) => Err(anyhow::anyhow!(
            "--strategy-params: expected a JSON object such as '{{\"stop_below_m2\": 5}}'"
        )),
        Err(e) => Err(anyhow::anyhow!(
            "--strategy-params: not JSON ({e}); expected an object such as '{{\"stop_below_m2\": 5}}'"
        )),
    }
}
