//! Times `reconstruct_layout` on every real map in `maps/` and on synthetic complete
//! and partial buildings, prints accuracy on the synthetic ones, and optionally draws the layouts.
//!
//! Per map class it prints the median and maximum time of `reconstruct_layout`, and a ratio
//! against a baseline measured in the same run on the same maps: the stage that was the costliest
//! before optimisation (the thin-unknown fill, two dilations of the whole grid) in its reference
//! form (`fill_thin_unknown_reference`: per-cell dilation of the whole grid) against the
//! optimised stage (`fill_thin_unknown`: vectorised dilation of the known window only), and the
//! whole layout with the reference stage swapped in (`layout + reference - optimised`).
//!
//! `cargo run -p sim-core --release --example layout_bench [-- --png /tmp/layouts] [--runs N]`

// Benchmarks, examples and integration tests run at the edge: they read files and clocks,
// which the kernel itself may not (sim-core/clippy.toml).
#![allow(clippy::disallowed_types, clippy::disallowed_methods)]
#[path = "../tests/common/mod.rs"]
mod common;

use std::time::Instant;

use sim_core::building::fill_polygon;
use sim_core::generate::{generate, BuildingKind, GenerateConfig};
use sim_core::layout::evidence::{fill_thin_unknown, fill_thin_unknown_reference};
use sim_core::layout::synthetic::{
    complete_map, corridor_building, corridor_views, explored_map, observe, rasterise, BuildingSpec,
};
use sim_core::layout::{evaluate, reconstruct_layout, Layout, LayoutConfig, RoomLabel};
use sim_core::{Bitmap, Cell, Occupancy, OccupancyGrid};

/// A class name, its layout times, and per map (optimised stage, reference stage, layout
/// median), all in ms.
type ClassTimes = (String, Vec<f64>, Vec<(f64, f64, f64)>);

/// Median times (ms) of the optimised and the reference thin-unknown fill on `grid`.
fn stage_ms(grid: &OccupancyGrid, config: &LayoutConfig, runs: usize) -> (f64, f64) {
    let mut fast = Vec::new();
    let mut reference = Vec::new();
    for _ in 0..runs {
        let t = Instant::now();
        let a = fill_thin_unknown(grid, config.thin_unknown_wall_m);
        fast.push(t.elapsed().as_secs_f64() * 1000.0);
        let t = Instant::now();
        let b = fill_thin_unknown_reference(grid, config.thin_unknown_wall_m);
        reference.push(t.elapsed().as_secs_f64() * 1000.0);
        assert_eq!(a.1, b.1, "the optimised fill differs from the reference");
    }
    (median(&mut fast), median(&mut reference))
}

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

/// A colour per room id: hues spread by the golden ratio, so that neighbours differ.
fn room_colour(id: u32) -> [u8; 3] {
    let h = (id as f64 * 0.618_033_988_75).fract() * 6.0;
    let (s, v) = (0.65, if id.is_multiple_of(2) { 0.95 } else { 0.75 });
    let c = v * s;
    let x = c * (1.0 - ((h % 2.0) - 1.0).abs());
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r, g, b].map(|k| ((k + m) * 255.0) as u8)
}

/// The map in grey (free white, occupied black, unknown grey); each room filled in its colour
/// where observed and hatched where predicted; outlines blue (Full), orange (Partial), red (Open).
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
    for r in &layout.rooms {
        let mut all = Bitmap::filled(f, false);
        fill_polygon(&mut all, &r.polygon, true);
        let mut seen = Bitmap::filled(f, false);
        fill_polygon(&mut seen, &r.observed_polygon, true);
        let col = room_colour(r.id);
        for (i, (a, o)) in all.data.iter().zip(&seen.data).enumerate() {
            let c = f.cell_of_index(i);
            let (px, py) = (c.x as u32, h - 1 - c.y as u32);
            let hatch = (px + py) % 8 < 3;
            if *o || (*a && hatch) {
                let p = img.get_pixel_mut(px, py);
                for (v, c) in p.0.iter_mut().zip(col) {
                    *v = ((*v as u16 + 2 * c as u16) / 3) as u8;
                }
            }
        }
    }
    for r in &layout.rooms {
        let col = match r.label {
            RoomLabel::Full => [0, 0, 160],
            RoomLabel::Partial => [255, 140, 0],
            RoomLabel::Open => [230, 0, 0],
        };
        let thick = if r.label == RoomLabel::Full { 0 } else { 1 };
        for e in r.polygon.edges() {
            let n = (e.length_m() / (f.resolution_m / 2.0)).ceil() as usize + 1;
            for k in 0..=n {
                let p = e.a + (e.b - e.a) * (k as f64 / n as f64);
                let c = f.cell_from_world(p);
                for dy in -thick..=thick {
                    for dx in -thick..=thick {
                        let q = Cell::new(c.x + dx, c.y + dy);
                        if f.contains(q) {
                            img.put_pixel(q.x as u32, h - 1 - q.y as u32, image::Rgb(col));
                        }
                    }
                }
            }
        }
    }
    if let Some([x, y, cw, ch, k]) = crop() {
        let sub = image::imageops::crop_imm(&img, x, y, cw, ch).to_image();
        let big = image::imageops::resize(&sub, cw * k, ch * k, image::imageops::Nearest);
        big.save(path.with_extension("crop.png")).unwrap();
    }
    img.save(path).unwrap();
}

/// `--crop x,y,w,h,zoom`: also save an enlarged crop of each picture (pixels of the picture).
fn crop() -> Option<[u32; 5]> {
    let args: Vec<String> = std::env::args().collect();
    let i = args.iter().position(|a| a == "--crop")?;
    let v: Vec<u32> = args[i + 1]
        .split(',')
        .filter_map(|t| t.parse().ok())
        .collect();
    v.try_into().ok()
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
    let mut bench = Bench {
        config: LayoutConfig::default(),
        runs,
        verbose,
        png,
        classes: Vec::new(),
        all_median: Vec::new(),
        all_max: 0.0,
        acc_lines: Vec::new(),
        iou_complete: Vec::new(),
        iou_pred: Vec::new(),
        iou_obs: Vec::new(),
    };
    println!(
        "{:<44} {:>8} {:>8} {:>5} {:>5} {:>5} {:>5} {:>5} {:>8} {:>8}",
        "map", "Mcells", "known_m2", "dirs", "lines", "rooms", "part", "open", "med_ms", "max_ms"
    );
    let only = args
        .iter()
        .position(|a| a == "--only")
        .map(|i| args[i + 1].clone());
    let wanted = |name: &str| only.as_ref().is_none_or(|o| name.contains(o.as_str()));
    bench.real_maps(&wanted);
    bench.synthetic();
    bench.generated(&wanted);
    bench.summary();
}

/// The benchmark's settings and what it has measured so far.
struct Bench {
    config: LayoutConfig,
    runs: usize,
    verbose: bool,
    png: Option<std::path::PathBuf>,
    /// Per class: layout times, and per map (optimised stage, reference stage, layout median).
    classes: Vec<ClassTimes>,
    all_median: Vec<f64>,
    all_max: f64,
    /// The accuracy lines of the synthetic and generated maps.
    acc_lines: Vec<String>,
    /// Matched IoU of the complete generated maps; predicted and observed-only IoU of the
    /// partial ones.
    iou_complete: Vec<f64>,
    iou_pred: Vec<f64>,
    iou_obs: Vec<f64>,
}

impl Bench {
    /// Prints a map's line (and draws it with `--png`), and records its times in `class`.
    fn report(
        &mut self,
        class: &str,
        name: &str,
        grid: &OccupancyGrid,
        layout: &Layout,
        times: &[f64],
    ) {
        let known = (grid.count(Occupancy::Free) + grid.count(Occupancy::Occupied)) as f64
            * grid.frame.cell_area_m2();
        let part = layout.rooms_labelled(RoomLabel::Partial);
        let open = layout.rooms_labelled(RoomLabel::Open);
        let med = times[times.len() / 2];
        let max = times[times.len() - 1];
        let stage = stage_ms(grid, &self.config, self.runs);
        let classes = &mut self.classes;
        let i = match classes.iter().position(|c| c.0 == class) {
            Some(i) => i,
            None => {
                classes.push((class.to_string(), Vec::new(), Vec::new()));
                classes.len() - 1
            }
        };
        classes[i].1.extend_from_slice(times);
        classes[i].2.push((stage.0, stage.1, med));
        self.all_median.push(med);
        self.all_max = self.all_max.max(max);
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
        if self.verbose {
            println!("    {:?}", layout.diagnostics);
        }
        if let Some(d) = &self.png {
            draw(
                grid,
                layout,
                &d.join(format!("{}.png", name.replace('/', "_"))),
            );
        }
    }

    /// Every real map in `maps/` (those `wanted`).
    fn real_maps(&mut self, wanted: &impl Fn(&str) -> bool) {
        for yaml in common::all_maps() {
            if !wanted(&yaml.to_string_lossy()) {
                continue;
            }
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
            let (layout, times) = time_ms(&grid, &self.config, self.runs);
            let class = if name.starts_with("partial") {
                "real rotated 0.10 m (partial/)"
            } else {
                "real other"
            };
            self.report(class, &name, &grid, &layout, &times);
        }
    }

    /// The synthetic corridor buildings.
    fn synthetic(&mut self) {
        // Synthetic: a 1100 m2 corridor building, complete and partial, axis-aligned and rotated.
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
                let (layout, times) = time_ms(&grid, &self.config, self.runs);
                let name = format!("synthetic/rot{rotation_rad:.2}_seen{fraction:.1}");
                self.report("synthetic corridor", &name, &grid, &layout, &times);
                let a = evaluate(&layout, &b.rooms, grid.frame);
                self.acc_lines.push(format!(
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
    }

    /// The generated schools and offices (those `wanted`).
    fn generated(&mut self, wanted: &impl Fn(&str) -> bool) {
        // Generated schools and offices, 1000-3500 m2, complete and explored 30-90 %.
        for seed in 0..4u64 {
            for kind in [BuildingKind::School, BuildingKind::Office] {
                let area_m2 = [1000.0, 2000.0, 3500.0, 1500.0][seed as usize];
                let rotation_rad = [0.0, 0.35, std::f64::consts::FRAC_PI_4, 0.0][seed as usize];
                let b = generate(&GenerateConfig {
                    seed,
                    area_m2,
                    kind,
                    rotation_rad,
                    ..GenerateConfig::default()
                });
                let full = complete_map(&b, 0.05);
                for fraction in [0.3, 0.6, 0.9, 1.1] {
                    let grid = if fraction > 1.0 {
                        full.clone()
                    } else {
                        explored_map(&b, &full, fraction, 0.4, seed)
                    };
                    if !wanted(&format!("generated {kind:?}")) {
                        continue;
                    }
                    let name = format!(
                        "gen/{kind:?}{seed}_{area_m2}_rot{rotation_rad:.2}_seen{fraction:.1}"
                    );
                    self.generated_map(&name, &grid, &b.rooms, fraction > 1.0);
                }
            }
        }
    }

    /// Times and evaluates one generated map (`complete` or partly explored) against its
    /// building's `rooms`.
    fn generated_map(
        &mut self,
        name: &str,
        grid: &OccupancyGrid,
        rooms: &[sim_core::building::Room],
        complete: bool,
    ) {
        let (layout, times) = time_ms(grid, &self.config, self.runs);
        let class = if complete {
            "generated complete 0.05 m"
        } else {
            "generated partial 0.05 m"
        };
        self.report(class, name, grid, &layout, &times);
        let a = evaluate(&layout, rooms, grid.frame);
        if complete {
            self.iou_complete.push(a.matched_room_iou);
        } else if let (Some(p), Some(o)) = (a.predicted_iou, a.observed_only_iou) {
            self.iou_pred.push(p);
            self.iou_obs.push(o);
        }
        self.acc_lines.push(format!(
            "{name:<44} iou {:.3} rooms {}/{} partial {} predicted_iou {} observed_only_iou {}",
            a.matched_room_iou,
            a.rooms_found,
            a.rooms_true,
            a.partial_rooms,
            a.predicted_iou.map_or("-".into(), |v| format!("{v:.3}")),
            a.observed_only_iou
                .map_or("-".into(), |v| format!("{v:.3}")),
        ));
    }

    /// Prints the per-class table, the generated maps' IoU, the accuracy lines and the totals.
    fn summary(self) {
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
        println!();
        println!(
            "baseline: thin-unknown fill (the costliest stage before optimisation), reference = \
             per-cell dilation of the whole grid, optimised = vectorised dilation of the known window"
        );
        println!(
            "{:<32} {:>8} {:>8} {:>6} | {:>9} {:>9} {:>7} | {:>12} {:>7}",
            "class",
            "med_ms",
            "max_ms",
            "runs",
            "stage_ref",
            "stage_opt",
            "ratio",
            "layout_w_ref",
            "ratio"
        );
        for (class, mut t, stages) in self.classes {
            let max = t.iter().cloned().fold(0.0, f64::max);
            let mut opt: Vec<f64> = stages.iter().map(|s| s.0).collect();
            let mut reference: Vec<f64> = stages.iter().map(|s| s.1).collect();
            let mut with_ref: Vec<f64> = stages.iter().map(|s| s.2 + s.1 - s.0).collect();
            let mut layout: Vec<f64> = stages.iter().map(|s| s.2).collect();
            let (o, r, wr, l) = (
                median(&mut opt),
                median(&mut reference),
                median(&mut with_ref),
                median(&mut layout),
            );
            println!(
                "{class:<32} {:>8.1} {:>8.1} {:>6} | {:>9.1} {:>9.1} {:>6.1}x | {:>12.1} {:>6.2}x",
                median(&mut t),
                max,
                t.len(),
                r,
                o,
                r / o.max(1e-9),
                wr,
                wr / l.max(1e-9)
            );
        }
        println!(
            "generated: complete matched IoU {:.3}; partial rooms IoU predicted {:.3} vs observed only {:.3}",
            mean(&self.iou_complete),
            mean(&self.iou_pred),
            mean(&self.iou_obs)
        );
        println!();
        for l in self.acc_lines {
            println!("{l}");
        }
        println!(
            "\nall maps: median of medians {:.1} ms, max {:.1} ms ({} maps, {} runs each)",
            median(&mut self.all_median.clone()),
            self.all_max,
            self.all_median.len(),
            self.runs
        );
    }
}
