//! Times `reconstruct_layout` on every real map in the shared folder and on synthetic complete
//! and partial buildings, prints accuracy on the synthetic ones, and optionally draws the layouts.
//!
//! `cargo run -p sim-core --release --example layout_bench [-- --png /tmp/layouts] [--runs N]`

#[path = "../tests/common/mod.rs"]
mod common;

use std::time::Instant;

use sim_core::building::fill_polygon;
use sim_core::layout::synthetic::{
    corridor_building, corridor_views, observe, rasterise, BuildingSpec,
};
use sim_core::layout::{evaluate, reconstruct_layout, Layout, LayoutConfig, RoomLabel};
use sim_core::{Bitmap, Cell, Occupancy, OccupancyGrid};

fn time_ms(grid: &OccupancyGrid, config: &LayoutConfig, runs: usize) -> (Layout, Vec<f64>) {
    let mut times = Vec::new();
    let mut layout = Layout::default();
    for _ in 0..runs {
        let t = Instant::now();
        layout = reconstruct_layout(grid, config);
        times.push(t.elapsed().as_secs_f64() * 1000.0);
    }
    times.sort_by(f64::total_cmp);
    (layout, times)
}

fn draw(grid: &OccupancyGrid, layout: &Layout, path: &std::path::Path) {
    let f = grid.frame;
    let (w, h) = (f.width, f.height);
    let mut img = image::RgbImage::new(w, h);
    for (c, s) in grid.iter() {
        let v = match s {
            Occupancy::Free => [255, 255, 255],
            Occupancy::Occupied => [0, 0, 0],
            Occupancy::Unknown => [190, 190, 190],
        };
        img.put_pixel(c.x as u32, h - 1 - c.y as u32, image::Rgb(v));
    }
    let palette = [
        [230, 25, 75],
        [60, 180, 75],
        [255, 225, 25],
        [0, 130, 200],
        [245, 130, 48],
        [145, 30, 180],
        [70, 240, 240],
        [240, 50, 230],
        [210, 245, 60],
        [250, 190, 212],
        [0, 128, 128],
        [220, 190, 255],
        [170, 110, 40],
        [128, 0, 0],
        [170, 255, 195],
    ];
    for r in &layout.rooms {
        let mut m = Bitmap::filled(f, false);
        fill_polygon(&mut m, &r.polygon, true);
        let col = palette[r.id as usize % palette.len()];
        for (i, b) in m.data.iter().enumerate() {
            if *b {
                let c = f.cell_of_index(i);
                let p = img.get_pixel_mut(c.x as u32, h - 1 - c.y as u32);
                for (v, c) in p.0.iter_mut().zip(col) {
                    *v = ((*v as u16 + c as u16) / 2) as u8;
                }
            }
        }
    }
    let mut plot = |x: f64, y: f64, col: [u8; 3]| {
        let c = f.cell_from_world(sim_core::Vec2::new(x, y));
        if f.contains(c) {
            img.put_pixel(c.x as u32, h - 1 - c.y as u32, image::Rgb(col));
        }
    };
    for r in &layout.rooms {
        let col = match r.label {
            RoomLabel::Full => [0, 0, 255],
            RoomLabel::Partial => [255, 0, 0],
            RoomLabel::Open => [255, 0, 255],
        };
        for e in r.polygon.edges() {
            let n = (e.length_m() / (f.resolution_m / 2.0)).ceil() as usize + 1;
            for k in 0..=n {
                let p = e.a + (e.b - e.a) * (k as f64 / n as f64);
                plot(p.x, p.y, col);
            }
        }
    }
    let _ = Cell::new(0, 0);
    img.save(path).unwrap();
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        0.0
    } else {
        v[v.len() / 2]
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let png = args
        .iter()
        .position(|a| a == "--png")
        .map(|i| std::path::PathBuf::from(&args[i + 1]));
    let runs: usize = args
        .iter()
        .position(|a| a == "--runs")
        .map(|i| args[i + 1].parse().unwrap())
        .unwrap_or(5);
    let verbose = args.iter().any(|a| a == "--verbose");
    if let Some(d) = &png {
        std::fs::create_dir_all(d).unwrap();
    }
    let config = LayoutConfig::default();
    let mut all_median = Vec::new();
    let mut all_max: f64 = 0.0;
    println!(
        "{:<44} {:>8} {:>8} {:>5} {:>5} {:>5} {:>5} {:>5} {:>8} {:>8}",
        "map", "Mcells", "known_m2", "dirs", "lines", "rooms", "part", "open", "med_ms", "max_ms"
    );
    let mut report = |name: &str, grid: &OccupancyGrid, layout: &Layout, times: &[f64]| {
        let known = (grid.count(Occupancy::Free) + grid.count(Occupancy::Occupied)) as f64
            * grid.frame.cell_area_m2();
        let part = layout
            .rooms
            .iter()
            .filter(|r| r.label == RoomLabel::Partial)
            .count();
        let open = layout
            .rooms
            .iter()
            .filter(|r| r.label == RoomLabel::Open)
            .count();
        let med = times[times.len() / 2];
        let max = times[times.len() - 1];
        all_median.push(med);
        all_max = all_max.max(max);
        println!(
            "{:<44} {:>8.2} {:>8.0} {:>5} {:>5} {:>5} {:>5} {:>5} {:>8.1} {:>8.1}",
            name,
            grid.frame.len() as f64 / 1e6,
            known,
            layout.diagnostics.directions,
            layout.lines.len(),
            layout.rooms.len(),
            part,
            open,
            med,
            max
        );
        if verbose {
            println!("    {:?}", layout.diagnostics);
        }
        if let Some(d) = &png {
            draw(
                grid,
                layout,
                &d.join(format!("{}.png", name.replace('/', "_"))),
            );
        }
    };
    for yaml in common::all_maps() {
        let grid = common::load_map(&yaml);
        let name = format!(
            "{}/{}",
            yaml.parent()
                .unwrap()
                .file_name()
                .unwrap()
                .to_string_lossy(),
            yaml.file_stem().unwrap().to_string_lossy()
        );
        let (layout, times) = time_ms(&grid, &config, runs);
        report(&name, &grid, &layout, &times);
    }
    // Synthetic: a 1100 m2 corridor building, complete and partial, axis-aligned and rotated.
    let mut acc_lines = Vec::new();
    for rotation_rad in [0.0, 0.4, std::f64::consts::FRAC_PI_4] {
        let spec = BuildingSpec {
            room_widths_m: [4.0, 4.0, 6.0, 4.0, 5.0].repeat(3),
            room_depth_m: 6.0,
            rotation_rad,
            ..BuildingSpec::default()
        };
        let b = corridor_building(&spec);
        let full = rasterise(&b, 0.05);
        for fraction in [0.3, 0.5, 0.7, 1.1] {
            let grid = if fraction > 1.0 {
                full.clone()
            } else {
                observe(&full, &corridor_views(&spec, fraction), 6.0)
            };
            let (layout, times) = time_ms(&grid, &config, runs);
            let name = format!("synthetic/rot{rotation_rad:.2}_seen{fraction:.1}");
            report(&name, &grid, &layout, &times);
            let a = evaluate(&layout, &b.rooms, grid.frame);
            acc_lines.push(format!(
                "{name:<34} iou {:.3} pixel {:.3} rooms {}/{} partial {} predicted_iou {} observed_only_iou {}",
                a.matched_room_iou,
                a.pixel_accuracy,
                a.rooms_found,
                a.rooms_true,
                a.partial_rooms,
                a.predicted_iou.map_or("-".into(), |v| format!("{v:.3}")),
                a.observed_only_iou.map_or("-".into(), |v| format!("{v:.3}")),
            ));
        }
    }
    println!();
    for l in acc_lines {
        println!("{l}");
    }
    println!(
        "\nall maps: median of medians {:.1} ms, max {:.1} ms ({} maps, {} runs each)",
        median(&mut all_median.clone()),
        all_max,
        all_median.len(),
        runs
    );
}
