//! `floorcast building`: generate, check and draw buildings.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use floorcast_render::{building_figure, Color, Figure, Style};
use serde::Serialize;
use sim_core::building::StartSource;
use sim_core::explore::RunResult;
use sim_core::frontier::detect::{detect_frontiers, FrontierConfig};
use sim_core::generate::{generate, BuildingKind, GenerateConfig};
use sim_core::{Building, Vec2};

#[derive(Debug, Subcommand)]
pub enum BuildingCommand {
    /// Generate a school or office building with ground-truth rooms, as floorcast TOML.
    Generate(GenerateArgs),
    /// Print a building's name, size, free area, rooms, start pose and content hash.
    Check(CheckArgs),
    /// Draw a building (walls, rooms, doors, start) as SVG or PNG.
    Render(RenderArgs),
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Kind {
    School,
    Office,
}

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct GenerateArgs {
    /// Seed, 0 to 2^64 - 1: the same seed and options give the same building.
    #[arg(long, default_value_t = 0, value_parser = crate::values::whole_number::<u64>(0, u64::MAX))]
    seed: u64,
    /// Target free area in square metres, 100 to 50000 (the result is within 15 %; above about
    /// 40000 m² exploring it needs a raised global `--max-cells`, e.g. 40000000).
    #[arg(long, value_name = "M2", value_parser = crate::values::number)]
    area_m2: f64,
    /// Kind of building: schools have classrooms and halls, offices smaller rooms.
    #[arg(long, value_enum, default_value = "school")]
    kind: Kind,
    /// Add furniture and pillars inside rooms.
    #[arg(long)]
    clutter: bool,
    /// Rotate the whole building by this many degrees (non-axis-aligned walls).
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        allow_hyphen_values = true,
        value_parser = crate::values::number
    )]
    rotation_deg: f64,
    /// Building name (default: the output file's stem).
    #[arg(long)]
    name: Option<String>,
    /// Output TOML file.
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
}

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct CheckArgs {
    /// Building file (floorcast TOML, map_server YAML, Stage .world, annotated floor plan .xml).
    file: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// Refuse a polygon whose edges cross, however small the slip (by default a slip of up to
    /// 1.5 m and 2 m², 5 % of the polygon, is repaired with a warning; docs/limits.md).
    #[arg(long)]
    strict: bool,
}

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct RenderArgs {
    /// Building file (floorcast TOML, map_server YAML, Stage .world, annotated floor plan .xml).
    file: PathBuf,
    /// Output picture: .svg or .png.
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
}

pub fn run(c: BuildingCommand) -> Result<()> {
    match c {
        BuildingCommand::Generate(a) => generate_cmd(a),
        BuildingCommand::Check(a) => check_cmd(a),
        BuildingCommand::Render(a) => render_cmd(a),
    }
}

fn generate_cmd(a: GenerateArgs) -> Result<()> {
    // (Flags' numbers are finite: `values::number` refused any other.)
    let max = floorcast_formats::limits::MAX_GENERATED_AREA_M2;
    if !(100.0..=max).contains(&a.area_m2) {
        bail!(
            "--area-m2 {}: expected a free area between 100 and {max} m2",
            a.area_m2
        );
    }
    let name = a.name.clone().unwrap_or_else(|| {
        a.out
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "building".into())
    });
    let b = generate(&GenerateConfig {
        seed: a.seed,
        area_m2: a.area_m2,
        kind: match a.kind {
            Kind::School => BuildingKind::School,
            Kind::Office => BuildingKind::Office,
        },
        clutter: a.clutter,
        rotation_rad: a.rotation_deg.to_radians(),
        name,
    });
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        crate::output::create_dir(dir)?;
    }
    let text = floorcast_formats::building_toml::to_toml_string(&b)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.out.display()))?;
    crate::output::write_text(&a.out, &text)?;
    say!(
        "{}: {} rooms, {:.0} m2 free, hash {}",
        a.out.display(),
        b.rooms.len(),
        b.free_area_m2(),
        b.content_hash()
    );
    // A building above the cell budget is written (a run with a raised `--max-cells` explores
    // it), with what exploring it will need.
    if let Err(e) = floorcast_formats::limits::check_building(
        &b,
        &a.out,
        "outline",
        floorcast_formats::limits::EXPLORE_RESOLUTION_M,
    ) {
        tell!("note: {e}");
    }
    Ok(())
}

/// What `building check` reports.
#[derive(Debug, Serialize)]
struct CheckReport {
    file: String,
    name: String,
    width_m: f64,
    height_m: f64,
    free_area_m2: f64,
    reachable_free_area_m2: f64,
    /// What a robot with the default settings can see from the start: the explored fraction's
    /// denominator.
    explorable_area_m2: f64,
    rooms: Option<usize>,
    doors: Option<usize>,
    /// The ground-truth rooms: id, label, area, and the share of it the robot can see.
    room_list: Vec<RoomReport>,
    /// Rooms of which the robot can see less than half from the start (through no doorway it
    /// fits).
    unreachable_rooms: Vec<u32>,
    start: [f64; 3],
    start_source: &'static str,
    geometry: &'static str,
    wall_segments: usize,
    hash: String,
    /// What the reader repaired in the file (polygons whose edges crossed by a slip), one line
    /// each; left out when nothing was.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    warnings: Vec<String>,
}

/// One ground-truth room in `building check`'s report.
#[derive(Debug, Serialize)]
struct RoomReport {
    id: u32,
    label: String,
    area_m2: f64,
    /// Share of the room's free cells the robot can see from the start, 0 to 1.
    explorable: f64,
}

/// A room of which the robot can see less than this share is reported unreachable.
const UNREACHABLE_BELOW: f64 = 0.5;

fn check_report(file: &std::path::Path, b: &Building) -> Result<CheckReport> {
    let bounds = b.bounds();
    let settings = floorcast_worker::Settings::default();
    let config = settings
        .to_explore_config()
        .context("the default settings are invalid")?;
    let (start, source) = b
        .default_start(settings.robot_radius_m)
        .with_context(|| format!("{}: no start pose", file.display()))?;
    let frame = b.area_frame();
    let reachable_cells = b.reachable_free(frame, start.position());
    let reachable = reachable_cells.count_true() as f64 * frame.cell_area_m2();
    let explorable = sim_core::building::explorable_free(
        &reachable_cells,
        start.position(),
        config.sim.robot.radius_m + config.safety_margin_m,
        config.sim.laser.max_range_m,
    );
    let free = b.free_mask(frame);
    let room_list: Vec<RoomReport> = b
        .rooms
        .iter()
        .map(|r| {
            let (mut cells, mut seen) = (0usize, 0usize);
            let aabb = r.polygon.aabb();
            let (lo, hi) = (
                frame.cell_from_world(aabb.min),
                frame.cell_from_world(aabb.max),
            );
            for y in lo.y.max(0)..=hi.y.min(frame.height as i32 - 1) {
                for x in lo.x.max(0)..=hi.x.min(frame.width as i32 - 1) {
                    let c = sim_core::Cell::new(x, y);
                    if free.get(c) == Some(&true) && r.polygon.contains(frame.world_from_cell(c)) {
                        cells += 1;
                        seen += usize::from(explorable.get(c) == Some(&true));
                    }
                }
            }
            RoomReport {
                id: r.id,
                label: r.kind.clone(),
                area_m2: r.polygon.area_m2(),
                explorable: if cells == 0 {
                    0.0
                } else {
                    seen as f64 / cells as f64
                },
            }
        })
        .collect();
    let unreachable_rooms = room_list
        .iter()
        .filter(|r| r.explorable < UNREACHABLE_BELOW)
        .map(|r| r.id)
        .collect();
    Ok(CheckReport {
        file: file.display().to_string(),
        name: b.name.clone(),
        width_m: bounds.width_m(),
        height_m: bounds.height_m(),
        free_area_m2: b.free_area_m2(),
        reachable_free_area_m2: reachable,
        explorable_area_m2: explorable.count_true() as f64 * frame.cell_area_m2(),
        room_list,
        unreachable_rooms,
        rooms: (!b.rooms.is_empty()).then_some(b.rooms.len()),
        doors: (!b.doors.is_empty()).then_some(b.doors.len()),
        start: [start.x_m, start.y_m, start.theta_rad.to_degrees()],
        start_source: match source {
            StartSource::File => "file",
            StartSource::LargestClearance => "largest clearance (no start in the file)",
        },
        geometry: match b.geometry {
            sim_core::Geometry::Raster { .. } => "raster",
            sim_core::Geometry::Vector { .. } => "vector",
        },
        wall_segments: b.boundary_segments().len(),
        hash: b.content_hash(),
        warnings: Vec::new(),
    })
}

/// Reads a building file, refusing a polygon whose edges cross when `strict`, else repairing
/// it: the warnings printed on stderr (`warning: ...`) and returned.
pub(crate) fn read_building_warned(
    file: &std::path::Path,
    strict: bool,
) -> Result<(Building, Vec<String>)> {
    let l = floorcast_formats::read_building_with(file, floorcast_formats::LoadOptions { strict })?;
    let warnings: Vec<String> = l.warnings.iter().map(|w| w.to_string()).collect();
    for w in &warnings {
        tell!("warning: {w}");
    }
    Ok((l.building, warnings))
}

fn check_cmd(a: CheckArgs) -> Result<()> {
    let (b, warnings) = read_building_warned(&a.file, a.strict)?;
    let mut r = check_report(&a.file, &b)?;
    r.warnings = warnings;
    if a.json {
        say!("{}", serde_json::to_string_pretty(&r)?);
        return Ok(());
    }
    say!("file:            {}", r.file);
    say!("name:            {}", r.name);
    say!(
        "size:            {:.1} x {:.1} m ({})",
        r.width_m,
        r.height_m,
        r.geometry
    );
    say!(
        "free area:       {:.1} m2 ({:.1} m2 reachable from the start)",
        r.free_area_m2,
        r.reachable_free_area_m2
    );
    say!(
        "explorable:      {:.1} m2 ({:.1} % of the free area: what the robot can see from the start)",
        r.explorable_area_m2,
        100.0 * r.explorable_area_m2 / r.free_area_m2.max(f64::MIN_POSITIVE)
    );
    match r.rooms {
        Some(n) => say!("rooms:           {n} ({} doors)", r.doors.unwrap_or(0)),
        None => say!("rooms:           unknown (no ground truth)"),
    }
    if !r.unreachable_rooms.is_empty() {
        let names: Vec<String> = r
            .room_list
            .iter()
            .filter(|x| r.unreachable_rooms.contains(&x.id))
            .map(|x| format!("{} ({}, {:.0} m2)", x.id, x.label, x.area_m2))
            .collect();
        say!(
            "unreachable:     {} of the rooms, the robot sees less than half of each from the \
             start (no doorway it fits leads there): {}",
            names.len(),
            text_list(&names, 12)
        );
    }
    say!(
        "start:           x {:.2} m, y {:.2} m, theta {:.1} deg ({})",
        r.start[0],
        r.start[1],
        r.start[2],
        r.start_source
    );
    say!("wall segments:   {}", r.wall_segments);
    say!("hash:            {}", r.hash);
    Ok(())
}

/// At most `max` items joined by ", ", then how many more.
fn text_list(items: &[String], max: usize) -> String {
    let mut s = items[..items.len().min(max)].join(", ");
    if items.len() > max {
        s.push_str(&format!(" and {} more", items.len() - max));
    }
    s
}

fn render_cmd(a: RenderArgs) -> Result<()> {
    crate::output::Paths::new()
        .read("the building", Some(&a.file))
        .write("--out", Some(&a.out))
        .check()?;
    let b = floorcast_formats::read_building(&a.file)?;
    crate::output::save_figure(&building_figure(&b), &a.out)
        .with_context(|| format!("cannot write {}", a.out.display()))?;
    say!("{}", a.out.display());
    Ok(())
}

/// The paper-style picture of a run: the final map, the true trajectory, the decisions, and the
/// frontiers (at least `min_frontier_m` long) still on the map at the end: what was left after an
/// early stop or the time limit, and none after "no frontiers" unless `frontier_clearance_m` had
/// the explorer ignore some.
pub fn exploration_figure(r: &RunResult, min_frontier_m: f64) -> Figure {
    exploration_figure_of(r, std::slice::from_ref(r), min_frontier_m)
}

/// The robots' colours in a team's picture (robot k the k-th, robot 0 the blue of one robot's).
pub const TEAM_COLOURS: [(u8, u8, u8); 8] = [
    (30, 90, 220),
    (0, 150, 70),
    (200, 40, 160),
    (230, 130, 0),
    (0, 160, 190),
    (140, 70, 20),
    (110, 60, 200),
    (90, 90, 90),
];

/// A team's picture: the team's map and frontiers, each robot's true path in its own colour
/// ([`TEAM_COLOURS`]), its estimated path dashed, its goals and its start.
pub fn team_figure(t: &sim_core::explore::TeamResult, min_frontier_m: f64) -> Figure {
    exploration_figure_of(&t.team, &t.robots, min_frontier_m)
}

/// The final map of `whole` with the paths, goals and starts of `robots`.
fn exploration_figure_of(whole: &RunResult, robots: &[RunResult], min_frontier_m: f64) -> Figure {
    let r = whole;
    let bounds = r.map.frame.bounds();
    let mut fig = Figure::new(bounds, 20.0);
    fig.grid(&r.map);
    let team = robots.len() > 1;
    for (k, robot) in robots.iter().enumerate() {
        let (cr, cg, cb) = TEAM_COLOURS[k % TEAM_COLOURS.len()];
        let traj: Vec<Vec2> = robot.trajectory.iter().map(|p| p.position()).collect();
        fig.polyline(&traj, &Style::stroke(Color::rgb(cr, cg, cb), 1.5));
        let est: Vec<Vec2> = robot
            .estimated_trajectory
            .iter()
            .map(|p| p.position())
            .collect();
        let dashed = if team {
            Color::rgba(cr, cg, cb, 140)
        } else {
            Color::rgba(220, 120, 30, 160)
        };
        fig.polyline(&est, &Style::stroke(dashed, 1.0).dashed(4.0, 3.0));
        for d in &robot.decisions {
            let goal = if team {
                Color::rgb(cr, cg, cb)
            } else {
                Color::rgb(220, 30, 30)
            };
            fig.circle(d.goal, 0.25, &Style::fill(goal));
        }
    }
    let frontier = Color::rgb(200, 0, 200);
    let cfg = FrontierConfig::with_min_length_m(min_frontier_m, r.map.frame.resolution_m);
    for f in detect_frontiers(&r.map, &cfg) {
        for c in &f.cells {
            fig.circle(
                r.map.frame.world_from_cell(*c),
                0.05,
                &Style::fill(frontier),
            );
        }
        let candidate = r.map.frame.world_from_cell(f.candidate);
        fig.circle(candidate, 0.35, &Style::stroke(frontier, 2.0));
    }
    for (k, robot) in robots.iter().enumerate() {
        let colour = if team {
            let (cr, cg, cb) = TEAM_COLOURS[k % TEAM_COLOURS.len()];
            Color::rgb(cr, cg, cb)
        } else {
            Color::rgb(0, 150, 0)
        };
        fig.arrow(&robot.start, 1.0, &Style::stroke(colour, 3.0));
    }
    fig
}
