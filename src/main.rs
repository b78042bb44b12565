//! `floorcast`: simulate robot exploration of buildings, fast, and compare strategies.

// A binary has no outside: its modules' `pub` is the crate's (the workspace's
// `unreachable_pub` is for the libraries).
#![allow(unreachable_pub)]

#[macro_use]
mod output;
mod cmd_building;
mod cmd_explore;
mod cmd_layout;
mod cmd_router;
mod cmd_run;
mod cmd_strategy;
mod cmd_suite;
mod cmd_tour;
mod cmd_worker;
mod values;

use std::process::ExitCode;

use clap::error::ErrorKind;
use clap::{Parser, Subcommand};

/// `--version`: the version, and the commit, dirty flag and profile the binary was built from
/// (`build.rs`).
const VERSION: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " (commit ",
    env!("FLOORCAST_GIT_COMMIT"),
    ", dirty ",
    env!("FLOORCAST_GIT_DIRTY"),
    ", ",
    env!("FLOORCAST_BUILD_PROFILE"),
    " build)"
);

/// What this binary was built from, recorded with every grid run's provenance.
pub fn build_info() -> floorcast_coordinator::store::BuildInfo {
    floorcast_coordinator::store::BuildInfo {
        git_commit: env!("FLOORCAST_GIT_COMMIT").to_string(),
        git_dirty: env!("FLOORCAST_GIT_DIRTY") == "true",
        profile: env!("FLOORCAST_BUILD_PROFILE").to_string(),
    }
}

/// Does this exploration strategy map an unknown building faster than that one?
///
/// floorcast simulates a differential-drive robot with a 2D laser exploring a building (laser,
/// odometry noise, SLAM mapping, frontiers, layout prediction, strategy, early stop), far faster
/// than real time, deterministically per seed.
#[derive(Debug, Parser)]
// (Negative numbers are values, so that `--seed -1` is refused by the flag's own check, which
// names the flag, rather than taken for an unknown flag.)
#[command(
    name = "floorcast",
    version = VERSION,
    about,
    long_about = None,
    propagate_version = true,
    allow_negative_numbers = true
)]
struct Cli {
    /// Most grid cells a map or building may need (its 0.05 m exploration grid over its extent
    /// plus a margin of 15 % of its longer side, 1 to 8 m, on each side; an image's pixels, a Stage floor plan's raster); a larger one is
    /// refused before anything is allocated. Raise it for very large buildings (about 22 bytes of
    /// memory per cell while exploring, 27 with a layout strategy).
    #[arg(long, global = true, value_name = "CELLS", default_value_t = floorcast_formats::limits::DEFAULT_MAX_CELLS, value_parser = values::whole_number::<u64>(1, 4_000_000_000))]
    max_cells: u64,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Generate, check and draw buildings (floorcast TOML, ROS map_server YAML, Stage .world, annotated floor plan .xml).
    #[command(subcommand)]
    Building(cmd_building::BuildingCommand),
    /// Run one exploration and write its summary, curve, map and picture.
    Explore(cmd_explore::ExploreArgs),
    /// Reconstruct the room layout of any occupancy map and predict partially seen rooms.
    Layout(cmd_layout::LayoutArgs),
    /// Run an experiment grid (buildings x seeds x strategies) on this machine and, with
    /// --listen, on remote workers; resumable.
    ///
    /// As it starts, it removes the private folders (floorcast-job-*, floorcast-python-*) that
    /// floorcast processes killed on this machine left in the temporary directory (TMPDIR),
    /// never a live process's (docs/failures.md).
    Run(cmd_run::RunArgs),
    /// Join a grid run elsewhere (`floorcast run GRID --listen ...`): take jobs, return results.
    ///
    /// As it starts, it removes the private folders (floorcast-job-*, floorcast-python-*) that
    /// floorcast processes killed on this machine left in the temporary directory (TMPDIR),
    /// never a live process's (docs/failures.md).
    Worker(cmd_worker::WorkerArgs),
    /// Run a zenoh router that a coordinator and its workers all connect to (`--connect`) when
    /// they cannot reach each other directly; no zenohd needed. Runs until stopped.
    Router(cmd_router::RouterArgs),
    /// Print the table of a results directory and export it as CSV; list its failed jobs.
    Report(cmd_run::ReportArgs),
    /// Tools for your own strategies (the strategy protocol): check a program's compliance.
    #[command(subcommand)]
    Strategy(cmd_strategy::StrategyCommand),
    /// Suites: named, versioned sets of buildings (manifests in suites/): list, check, update.
    #[command(subcommand)]
    Suite(cmd_suite::SuiteCommand),
    /// Print the reference of every run setting (type, unit, default, range, meaning).
    Settings(SettingsArgs),
    /// The known-map yardstick: the time of a tour that sees the building's explorable area
    /// with the run's robot and laser, knowing the whole building (docs/known-map-tour.md).
    Tour(cmd_tour::TourArgs),
}

#[derive(Debug, clap::Args)]
struct SettingsArgs {
    /// Print the reference as the markdown table of the README.
    #[arg(long)]
    markdown: bool,
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage_error(e),
    };
    floorcast_formats::limits::set_max_cells(cli.max_cells);
    // What a strategy program starts in a session of its own is still found and ended.
    floorcast_worker::external::adopt_orphans();
    let result = match cli.command {
        Command::Building(c) => cmd_building::run(c),
        Command::Explore(a) => cmd_explore::run(a),
        Command::Layout(a) => cmd_layout::run(a),
        Command::Run(a) => cmd_run::run(a),
        Command::Worker(a) => cmd_worker::run(a),
        Command::Router(a) => cmd_router::run(a),
        Command::Report(a) => cmd_run::report(a),
        Command::Strategy(c) => cmd_strategy::run(c),
        Command::Suite(c) => cmd_suite::run(c),
        Command::Tour(a) => cmd_tour::run(a),
        Command::Settings(a) => {
            if a.markdown {
                say_raw!(
                    "{}",
                    floorcast_worker::settings::settings_reference_markdown()
                );
            } else {
                say_raw!("{}", floorcast_worker::settings::settings_help_text());
            }
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            if floorcast_worker::external::stopping() {
                // A signal is stopping floorcast (its handler ends the process with exit code
                // 130 once the programs and partial output are gone): this error is its doing.
                std::thread::sleep(std::time::Duration::from_secs(10));
                return ExitCode::from(130);
            }
            // Errors quote outside text (a program's output): escaped, bounded.
            tell!(
                "error: {}",
                floorcast_worker::text::shown(&one_line_error(&e), 4000)
            );
            ExitCode::from(2)
        }
    }
}

/// A command line clap refuses (an unknown flag or subcommand, a value out of its range, a
/// missing argument): one `error: ...` line and exit code 2, as for any other bad input. Help and
/// the version (and the help shown when no subcommand is given) print as clap prints them, a
/// failed write of them as any other ([`output::stdout_failed`]).
fn usage_error(e: clap::Error) -> ExitCode {
    if matches!(
        e.kind(),
        ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        use std::io::Write;
        if let Err(err) = e.print().and_then(|_| std::io::stdout().flush()) {
            output::stdout_failed(&err);
        }
        return ExitCode::from(e.exit_code() as u8);
    }
    tell!("{}", usage_line(&e.render().to_string()));
    ExitCode::from(2)
}

/// Clap's message on one line: its usage lines left out (`--help` prints them), the rest joined
/// (a list of possible values, or the list a line ending in a colon announces, after a space;
/// other lines after a semicolon).
fn usage_line(text: &str) -> String {
    let mut line = String::new();
    for part in text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with("Usage:"))
    {
        if !line.is_empty() {
            let list = part.starts_with('[') || line.ends_with(':');
            line.push_str(if list { " " } else { "; " });
        }
        line.push_str(part);
    }
    line
}

/// An error and its causes on one line, each cause said once: a cause whose text the message so
/// far already holds (a library error that quotes its source) is left out.
fn one_line_error(e: &anyhow::Error) -> String {
    let mut msg = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        let text = text.trim();
        if text.is_empty() || msg.contains(text) {
            continue;
        }
        if !msg.is_empty() {
            msg.push_str(": ");
        }
        msg.push_str(text);
    }
    msg.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use super::{one_line_error, usage_line};

    #[test]
    fn clap_errors_are_one_line_without_the_usage() {
        let text = "error: invalid value 'x' for '--strategy <STRATEGY>'\n  [possible values: a, b]\n\nFor more information, try '--help'.\n";
        assert_eq!(
            usage_line(text),
            "error: invalid value 'x' for '--strategy <STRATEGY>' [possible values: a, b]; For more information, try '--help'."
        );
        let text = "error: unrecognized subcommand 'x'\n\nUsage: floorcast [OPTIONS] <COMMAND>\n\nFor more information, try '--help'.\n";
        assert_eq!(
            usage_line(text),
            "error: unrecognized subcommand 'x'; For more information, try '--help'."
        );
        let text = "error: the following required arguments were not provided:\n  <RESULTS>\n\nUsage: floorcast report <RESULTS>\n";
        assert_eq!(
            usage_line(text),
            "error: the following required arguments were not provided: <RESULTS>"
        );
    }

    #[test]
    fn causes_are_said_once_on_one_line() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "No such file");
        let e = anyhow::Error::new(io).context("cannot read x.json: No such file");
        assert_eq!(one_line_error(&e), "cannot read x.json: No such file");
        let e = anyhow::anyhow!("inner\nsecond line").context("outer");
        assert_eq!(one_line_error(&e), "outer: inner second line");
    }
}
