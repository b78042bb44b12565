//! `floorcast tour`: the known-map yardstick of a building (`sim_core::tour`).

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use floorcast_worker::Settings;
use serde::Serialize;
use sim_core::tour::{known_map_tour, TourSettings};

use crate::output::write_text;

#[derive(Debug, Args)]
pub struct TourArgs {
    /// Building: floorcast TOML, ROS map_server YAML, Stage .world, or annotated floor plan .xml.
    #[arg(long, value_name = "FILE")]
    building: PathBuf,
    /// Run settings (a JSON object, see `floorcast settings`): the robot's radius, speed and
    /// turn rate, the laser's range and field of view and the map resolution come from them.
    #[arg(long, value_name = "FILE")]
    settings: Option<PathBuf>,
    /// The share of the explorable area the tour must see, 0.5 to 1.
    #[arg(long, default_value_t = 0.99, value_parser = crate::values::number)]
    coverage: f64,
    /// Also write the tour (viewpoints, path, time, length) as JSON to this file.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

pub const TOUR_FORMAT: &str = "floorcast-tour";
pub const TOUR_VERSION: u32 = 1;

/// The `--json` file.
#[derive(Debug, Serialize)]
struct TourFile {
    format: &'static str,
    version: u32,
    floorcast_version: &'static str,
    building: String,
    building_hash: String,
    settings: Settings,
    coverage: f64,
    time_s: f64,
    length_m: f64,
    covered_fraction: f64,
    explorable_m2: f64,
    /// `[x_m, y_m, heading_rad]`, the start first, in the order visited.
    viewpoints: Vec<[f64; 3]>,
    /// `[x_m, y_m]` points of the path driven.
    path: Vec<[f64; 2]>,
}

pub fn run(a: TourArgs) -> Result<()> {
    if !(0.5..=1.0).contains(&a.coverage) {
        anyhow::bail!(
            "--coverage: {} is out of range, expected a number in [0.5, 1]",
            a.coverage
        );
    }
    let building = floorcast_formats::read_building(&a.building)?;
    let settings = crate::cmd_explore::settings_file(a.settings.as_deref())?;
    let config = settings.to_explore_config()?;
    let name = a.building.display().to_string();
    floorcast_formats::limits::check_building(
        &building,
        &a.building,
        "map_resolution_m",
        settings.map_resolution_m,
    )?;
    let (start, _) = building
        .default_start(settings.robot_radius_m)
        .map_err(|e| anyhow::anyhow!("{name}: no start for the tour: {e}"))?;
    let ts = TourSettings {
        coverage: a.coverage,
        ..TourSettings::default()
    };
    let tour = known_map_tour(&building, start, &config, &ts);
    say!(
        "{name}: a tour that knows the building sees {:.1} % of its {:.0} m2 explorable in {:.0} s ({:.1} m, {} viewpoints)",
        100.0 * tour.covered_fraction,
        tour.explorable_m2,
        tour.time_s,
        tour.length_m,
        tour.viewpoints.len()
    );
    if let Some(path) = &a.json {
        let file = TourFile {
            format: TOUR_FORMAT,
            version: TOUR_VERSION,
            floorcast_version: floorcast_worker::FLOORCAST_VERSION,
            building: name.clone(),
            building_hash: building.content_hash(),
            settings,
            coverage: a.coverage,
            time_s: tour.time_s,
            length_m: tour.length_m,
            covered_fraction: tour.covered_fraction,
            explorable_m2: tour.explorable_m2,
            viewpoints: tour
                .viewpoints
                .iter()
                .map(|v| [v.x_m, v.y_m, v.theta_rad])
                .collect(),
            path: tour.path.iter().map(|p| [p.x, p.y]).collect(),
        };
        let text = serde_json::to_string_pretty(&file).context("cannot encode the tour")?;
        write_text(path, &text)?;
    }
    Ok(())
}
