//! `floorcast`: simulate robot exploration of buildings, fast, and compare strategies.

#[macro_use]
mod output;
mod cmd_building;
mod cmd_explore;
mod cmd_layout;
mod cmd_run;
mod cmd_worker;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Does this exploration strategy map an unknown building faster than that one?
///
/// floorcast simulates a differential-drive robot with a 2D laser exploring a building (laser,
/// odometry noise, SLAM mapping, frontiers, layout prediction, strategy, early stop), far faster
/// than real time, deterministically per seed.
#[derive(Debug, Parser)]
#[command(name = "floorcast", version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Generate, check and draw buildings (floorcast TOML, ROS map_server YAML, Stage .world).
    #[command(subcommand)]
    Building(cmd_building::BuildingCommand),
    /// Run one exploration and write its summary, curve, map and picture.
    Explore(cmd_explore::ExploreArgs),
    /// Reconstruct the room layout of any occupancy map and predict partially seen rooms.
    Layout(cmd_layout::LayoutArgs),
    /// Run an experiment grid (buildings x seeds x strategies) on this machine and, with
    /// --listen, on remote workers; resumable.
    Run(cmd_run::RunArgs),
    /// Join a grid run elsewhere (`floorcast run GRID --listen ...`): take jobs, return results.
    Worker(cmd_worker::WorkerArgs),
    /// Print the table of a results directory and export it as CSV.
    Report(cmd_run::ReportArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Building(c) => cmd_building::run(c),
        Command::Explore(a) => cmd_explore::run(a),
        Command::Layout(a) => cmd_layout::run(a),
        Command::Run(a) => cmd_run::run(a),
        Command::Worker(a) => cmd_worker::run(a),
        Command::Report(a) => cmd_run::report(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
