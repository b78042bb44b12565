//! `floorcast layout`: reconstruct and predict the room layout of any occupancy map.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Args;
use floorcast_render::{room_color, Color, Figure, Style};
use serde::Serialize;
use sim_core::layout::{
    evaluate_merged, reconstruct_layout, unwalled_pairs, Layout, LayoutConfig, RoomLabel,
};
use sim_core::{OccupancyGrid, Polygon};

use crate::output::{create_dir, write_text};

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct LayoutArgs {
    /// Map to analyse: a map_server YAML (e.g. a `map.yaml` written by `floorcast explore`), a
    /// building TOML, a Stage .world or an annotated floor plan .xml (drawn at 0.05 m).
    #[arg(long, value_name = "FILE")]
    map: PathBuf,
    /// A building with ground-truth rooms to score the layout against (writes accuracy.json):
    /// a building TOML or an annotated floor plan .xml, in the map's frame. True rooms that no
    /// wall parts (joined by a doorway at least 1.5 m wide, or corridor, hall and lobby pieces
    /// joined by any) are scored as one.
    #[arg(long, value_name = "FILE")]
    truth: Option<PathBuf>,
    /// Output directory (default: results/layout/<map>).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Picture format.
    #[arg(long, default_value = "png", value_parser = ["png", "svg"])]
    picture: String,
}

pub const LAYOUT_FORMAT: &str = "floorcast-layout";
pub const LAYOUT_VERSION: u32 = 1;

/// `layout.json`.
#[derive(Debug, Serialize)]
struct LayoutFile {
    format: &'static str,
    version: u32,
    floorcast_version: &'static str,
    map: String,
    resolution_m: f64,
    /// Wall-clock time of `reconstruct_layout` (the kernel has no clock; per-stage work counts
    /// are in `diagnostics`).
    layout_time_ms: f64,
    rooms: Vec<RoomOut>,
    lines: Vec<LineOut>,
    /// Work counts per stage (Debug form of `LayoutDiagnostics`).
    diagnostics: String,
}

#[derive(Debug, Serialize)]
struct RoomOut {
    id: u32,
    /// "full", "partial" or "open" (partially observed, prediction reaches the map's box).
    label: &'static str,
    predicted: bool,
    area_m2: f64,
    observed_area_m2: f64,
    unknown_area_m2: f64,
    polygon: Vec<[f64; 2]>,
    observed_polygon: Vec<[f64; 2]>,
}

#[derive(Debug, Serialize)]
struct LineOut {
    direction_deg: f64,
    offset_m: f64,
    weight: f64,
    from: [f64; 2],
    to: [f64; 2],
}

#[derive(Debug, Serialize)]
struct AccuracyFile {
    format: &'static str,
    version: u32,
    map: String,
    truth: String,
    matched_room_iou: f64,
    pixel_accuracy: f64,
    rooms_found: usize,
    rooms_true: usize,
    partial_rooms: usize,
    predicted_iou: Option<f64>,
    observed_only_iou: Option<f64>,
    /// `predicted_iou - observed_only_iou`: what the prediction gained on partial rooms.
    prediction_gain: Option<f64>,
}

fn label_str(l: RoomLabel) -> &'static str {
    match l {
        RoomLabel::Full => "full",
        RoomLabel::Partial => "partial",
        RoomLabel::Open => "open",
    }
}

fn pts(p: &Polygon) -> Vec<[f64; 2]> {
    p.vertices.iter().map(|v| [v.x, v.y]).collect()
}

pub fn run(a: LayoutArgs) -> Result<()> {
    let grid = floorcast_formats::read_occupancy(&a.map)?;
    if grid.frame.is_empty() {
        bail!("{}: the map is empty", a.map.display());
    }
    // The ground truth is checked before anything is written.
    let truth = match &a.truth {
        Some(truth_path) => {
            let truth = floorcast_formats::read_building(truth_path)?;
            if truth.rooms.is_empty() {
                bail!(
                    "{}: the building has no ground-truth rooms to compare with",
                    truth_path.display()
                );
            }
            Some((truth_path, truth))
        }
        None => None,
    };
    let stem = a
        .map
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "map".into());
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("results/layout/{stem}")));
    let picture = out.join(format!("layout.{}", a.picture));
    crate::output::Paths::new()
        .read("the map", Some(&a.map))
        .read("--truth", a.truth.as_deref())
        .write("layout.json", Some(&out.join("layout.json")))
        .write("the layout picture", Some(&picture))
        .write(
            "accuracy.json",
            a.truth
                .as_ref()
                .map(|_| out.join("accuracy.json"))
                .as_deref(),
        )
        .check()?;
    create_dir(&out)?;
    let t = Instant::now();
    let layout = reconstruct_layout(&grid, &LayoutConfig::default());
    let ms = t.elapsed().as_secs_f64() * 1000.0;
    let file = layout_file(&a.map, &grid, &layout, ms);
    write_text(
        &out.join("layout.json"),
        &(serde_json::to_string_pretty(&file)? + "\n"),
    )?;
    crate::output::save_figure(&layout_figure(&grid, &layout), &picture)
        .with_context(|| format!("cannot write {}", picture.display()))?;
    let full = layout.rooms_labelled(RoomLabel::Full);
    let open = layout.rooms_labelled(RoomLabel::Open);
    say!(
        "{}: {} rooms ({} full, {} partial, {} open), {} wall lines, in {:.0} ms",
        a.map.display(),
        layout.rooms.len(),
        full,
        layout.rooms.len() - full - open,
        open,
        layout.lines.len(),
        ms
    );
    if let Some((truth_path, truth)) = truth {
        write_accuracy(&a.map, truth_path, &truth, &grid, &layout, &out)?;
    }
    say!("results in {}", out.display());
    Ok(())
}

/// The layout as `layout.json` holds it.
fn layout_file(
    map: &std::path::Path,
    grid: &OccupancyGrid,
    layout: &Layout,
    ms: f64,
) -> LayoutFile {
    LayoutFile {
        format: LAYOUT_FORMAT,
        version: LAYOUT_VERSION,
        floorcast_version: floorcast_worker::FLOORCAST_VERSION,
        map: map.display().to_string(),
        resolution_m: grid.frame.resolution_m,
        layout_time_ms: ms,
        rooms: layout
            .rooms
            .iter()
            .map(|r| RoomOut {
                id: r.id,
                label: label_str(r.label),
                predicted: r.predicted,
                area_m2: r.area_m2,
                observed_area_m2: r.observed_area_m2,
                unknown_area_m2: r.unknown_area_m2,
                polygon: pts(&r.polygon),
                observed_polygon: pts(&r.observed_polygon),
            })
            .collect(),
        lines: layout
            .lines
            .iter()
            .map(|l| LineOut {
                direction_deg: l.direction_rad.to_degrees(),
                offset_m: l.offset_m,
                weight: l.weight,
                from: [l.extent.a.x, l.extent.a.y],
                to: [l.extent.b.x, l.extent.b.y],
            })
            .collect(),
        diagnostics: format!("{:?}", layout.diagnostics),
    }
}

/// The layout's accuracy against the building's true rooms: `accuracy.json` and one line.
fn write_accuracy(
    map: &std::path::Path,
    truth_path: &std::path::Path,
    truth: &sim_core::building::Building,
    grid: &OccupancyGrid,
    layout: &Layout,
    out: &std::path::Path,
) -> Result<()> {
    let acc = evaluate_merged(layout, &truth.rooms, &unwalled_pairs(truth), grid.frame);
    let f = AccuracyFile {
        format: "floorcast-layout-accuracy",
        version: 1,
        map: map.display().to_string(),
        truth: truth_path.display().to_string(),
        matched_room_iou: acc.matched_room_iou,
        pixel_accuracy: acc.pixel_accuracy,
        rooms_found: acc.rooms_found,
        rooms_true: acc.rooms_true,
        partial_rooms: acc.partial_rooms,
        predicted_iou: acc.predicted_iou,
        observed_only_iou: acc.observed_only_iou,
        prediction_gain: acc
            .predicted_iou
            .zip(acc.observed_only_iou)
            .map(|(p, o)| p - o),
    };
    write_text(
        &out.join("accuracy.json"),
        &(serde_json::to_string_pretty(&f)? + "\n"),
    )?;
    say!(
        "accuracy: matched room IoU {:.3}, pixel accuracy {:.3}, {} rooms found for {} true",
        f.matched_room_iou,
        f.pixel_accuracy,
        f.rooms_found,
        f.rooms_true
    );
    Ok(())
}

/// Drawn like the paper's Fig. 1: the grid in grey, full rooms solid, predicted parts dashed,
/// open frontiers in red.
pub fn layout_figure(grid: &OccupancyGrid, layout: &Layout) -> Figure {
    let mut fig = Figure::new(grid.frame.bounds(), 20.0);
    fig.grid(grid);
    for r in &layout.rooms {
        let c = room_color(r.id);
        fig.polygon(
            &r.observed_polygon,
            &Style::stroke(Color::rgb(40, 40, 40), 1.5).with_fill(c.with_alpha(150)),
        );
        if r.predicted {
            fig.polygon(
                &r.polygon,
                &Style::stroke(Color::rgb(30, 60, 200), 2.0).dashed(6.0, 4.0),
            );
        }
        if r.label == RoomLabel::Open {
            fig.polygon(&r.polygon, &Style::stroke(Color::rgb(220, 30, 30), 2.5));
        }
    }
    fig
}
