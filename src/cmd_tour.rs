//! `floorcast tour`: the known-map yardstick of a building (`sim_core::tour`).

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use floorcast_render::{building_figure, Color, Figure, Style};
use floorcast_worker::tour::{estimate_tour, make_tour_with, TourRecord};
use sim_core::tour::{TourEstimate, TourProgress};
use sim_core::{Pose, Vec2};

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
    /// Also draw the tour over the building to this file (.png, .svg or .pdf): its path in
    /// blue, each viewpoint an orange arrow in the laser's heading, the start red.
    #[arg(long, value_name = "FILE")]
    picture: Option<PathBuf>,
}

pub fn run(a: TourArgs) -> Result<()> {
    if !(0.5..=1.0).contains(&a.coverage) {
        anyhow::bail!(
            "--coverage: {} is out of range, expected a number in [0.5, 1]",
            a.coverage
        );
    }
    crate::output::Paths::new()
        .read("--building", Some(&a.building))
        .read("--settings", a.settings.as_deref())
        .write("--json", a.json.as_deref())
        .write("--picture", a.picture.as_deref())
        .check()?;
    let building = floorcast_formats::read_building(&a.building)?;
    let settings = crate::cmd_explore::settings_file(a.settings.as_deref())?;
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
    let estimate = estimate_tour(&building, &name, start, &settings, a.coverage)?;
    say!("{name}: {}", estimate_text(&estimate));
    let began = std::time::Instant::now();
    let mut shown = Shown::new(began);
    let tour = make_tour_with(&building, &name, start, &settings, a.coverage, &mut |p| {
        shown.progress(&name, p)
    })?;
    if began.elapsed().as_secs_f64() > 2.0 {
        say!(
            "{name}: the tour took {:.1} s to make",
            began.elapsed().as_secs_f64()
        );
    }
    say!(
        "{name}: a tour that knows the building sees {:.1} % of its {:.0} m2 explorable in {:.0} s ({:.1} m, {} viewpoints; replayed with the laser: {:.1} %)",
        100.0 * tour.covered_fraction,
        tour.explorable_m2,
        tour.time_s,
        tour.length_m,
        tour.viewpoints.len(),
        100.0 * tour.replayed_fraction
    );
    if let (Some(b), Some(k)) = (tour.lower_bound_s, tour.bound_regions) {
        say!(
            "{name}: no tour is faster than {b:.0} s (a lower bound: {k} regions every tour must enter, at top speed; the tour is {:.1} times it)",
            tour.time_s / b.max(1e-9)
        );
    }
    if let Some(path) = &a.json {
        let text = serde_json::to_string_pretty(&tour).context("cannot encode the tour")?;
        write_text(path, &text)?;
    }
    if let Some(path) = &a.picture {
        crate::output::save_figure(&tour_figure(&building, &tour), path)
            .with_context(|| format!("--picture: cannot draw the tour to {}", path.display()))?;
        say!("drew {}", path.display());
    }
    Ok(())
}

/// The default of `run --tour-budget` (s): a tour estimated to take longer to make is skipped.
pub const DEFAULT_TOUR_BUDGET_S: f64 = 60.0;

/// What `run` does about tours: on how many threads, and the estimate above which a tour is
/// skipped (s).
#[derive(Debug, Clone, Copy)]
pub struct GridTours {
    pub threads: usize,
    pub budget_s: f64,
}

/// An estimate as said before a tour is made.
fn estimate_text(e: &TourEstimate) -> String {
    format!(
        "making the tour: {} places, about {} viewpoints, estimated {:.0} s on one core (within a factor of about 2)",
        e.places, e.viewpoints, e.seconds
    )
}

/// Shows a tour's progress on stderr, at most every 2 s (nothing for a tour made faster).
struct Shown {
    began: std::time::Instant,
    last: std::time::Instant,
}

impl Shown {
    fn new(began: std::time::Instant) -> Self {
        Self { began, last: began }
    }

    fn progress(&mut self, name: &str, p: TourProgress) {
        let now = std::time::Instant::now();
        if now.duration_since(self.last).as_secs_f64() < 2.0 {
            return;
        }
        self.last = now;
        let what = match p {
            TourProgress::Sweeping { done, total } => {
                format!("what the places see: {done} of {total}")
            }
            TourProgress::Choosing { viewpoints, seen } => format!(
                "choosing viewpoints: {viewpoints}, seeing {:.1} %",
                100.0 * seen
            ),
            TourProgress::Ordering { done, total } => {
                format!("ordering the viewpoints: paths from {done} of {total}")
            }
            TourProgress::Driving { legs, total } => {
                format!("driving the tour: leg {legs} of {total}")
            }
            TourProgress::Replaying { attempt } => {
                format!("replaying the tour with the laser (try {attempt} of at most 3)")
            }
        };
        tell!(
            "{name}: {:.0} s: {what}",
            now.duration_since(self.began).as_secs_f64()
        );
    }
}

/// The building ([`building_figure`]) with the tour's path and viewpoints.
fn tour_figure(building: &sim_core::Building, tour: &TourRecord) -> Figure {
    let mut fig = building_figure(building);
    let px = fig.px_per_m();
    let path: Vec<Vec2> = tour.path.iter().map(|p| Vec2::new(p[0], p[1])).collect();
    fig.polyline(&path, &Style::stroke(Color::BLUE, (0.08 * px).max(1.5)));
    let orange = Style::stroke(Color::rgb(240, 140, 20), (0.08 * px).max(1.5));
    for v in tour.viewpoints.iter().skip(1) {
        fig.arrow(&Pose::new(v[0], v[1], v[2]), 0.6, &orange);
    }
    fig
}

/// Makes and stores the known-map tours `jobs` need that `store` lacks
/// (`floorcast_coordinator::tours`), on `how.threads` threads, saying what it does; a tour
/// whose estimate exceeds `how.budget_s` is skipped with a warning (its runs get no
/// efficiency). When `interrupt` is set (Ctrl-C, SIGTERM) it ends the process with exit code
/// 130, the tours made so far stored.
pub fn make_grid_tours(
    plan: &floorcast_coordinator::grid::Plan,
    jobs: &[floorcast_coordinator::grid::PlannedJob],
    store: &floorcast_coordinator::store::Store,
    how: GridTours,
    interrupt: &std::sync::atomic::AtomicBool,
) -> Result<()> {
    let workers = how.threads;
    use floorcast_coordinator::tours::{missing, planned_tours};
    // Only the runs that succeeded are measured (a failed job's start may be no start at all).
    let ok: std::collections::BTreeSet<String> = store
        .all()?
        .into_iter()
        .filter(|r| r.status.is_ok())
        .map(|r| r.job_id)
        .collect();
    let jobs: Vec<_> = jobs
        .iter()
        .filter(|j| ok.contains(&j.id))
        .cloned()
        .collect();
    let planned = planned_tours(plan, &jobs);
    let stored = store.tours()?;
    let todo = missing(plan, &planned, &stored);
    if todo.is_empty() {
        return Ok(());
    }
    let threads = workers.clamp(1, todo.len());
    say!(
        "making {} known-map tour{} (the yardstick of efficiency, docs/known-map-tour.md) on {threads} thread{}",
        todo.len(),
        if todo.len() == 1 { "" } else { "s" },
        if threads == 1 { "" } else { "s" },
    );
    let next = std::sync::atomic::AtomicUsize::new(0);
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::scope(|scope| -> Result<()> {
        for _ in 0..threads {
            let tx = tx.clone();
            let (next, todo) = (&next, &todo);
            scope.spawn(move || loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(t) = todo.get(i) else { break };
                let b = &plan.buildings[t.building];
                let began = std::time::Instant::now();
                // A tour is a yardstick, not a result: one that cannot be made (a setting
                // refused, a robot that fits nowhere, a building the method cannot handle) or
                // that would take longer than the budget is reported and skipped.
                let made = std::panic::catch_unwind(|| {
                    let e = estimate_tour(&b.building, &b.name, t.start, &t.settings, t.key.coverage)?;
                    if e.seconds > how.budget_s {
                        return Err(anyhow::anyhow!(
                            "skipped: its estimate is {:.0} s ({} places, about {} viewpoints), over the budget of {:.0} s (`run --tour-budget`)",
                            e.seconds, e.places, e.viewpoints, how.budget_s
                        ));
                    }
                    Ok(make_tour_with(&b.building, &b.name, t.start, &t.settings, t.key.coverage, &mut |_| {})?)
                })
                .map_err(|_| "the tour's computation failed".to_string())
                .and_then(|r| r.map_err(|e| e.to_string()))
                .map_err(|e| format!("{}: {e}; its runs get no efficiency", b.name));
                if tx.send((made, began.elapsed().as_secs_f64())).is_err() {
                    break;
                }
            });
        }
        drop(tx);
        let mut k = 0;
        loop {
            // A tour takes up to a minute on a large building: an interrupt (Ctrl-C, SIGTERM)
            // is answered within a fifth of a second, the tours made so far kept in the store.
            let (made, wall_s) = match rx.recv_timeout(std::time::Duration::from_millis(200)) {
                Ok(got) => got,
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                    if interrupt.load(std::sync::atomic::Ordering::SeqCst) {
                        tell!(
                            "interrupted while making tours: {k} of {} made and stored in {}; run the same command again to make the rest",
                            todo.len(),
                            store.path().display()
                        );
                        floorcast_worker::external::kill_all_programs();
                        std::process::exit(130);
                    }
                    continue;
                }
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => break,
            };
            k += 1;
            let tour = match made {
                Ok(tour) => tour,
                Err(e) => {
                    tell!("tour {k}/{}: {e}", todo.len());
                    continue;
                }
            };
            store.record_tour(&tour)?;
            say!(
                "tour {k}/{}: {}: {:.0} s, {:.1} % of {:.0} m2 seen ({:.1} s to make)",
                todo.len(),
                tour.building,
                tour.time_s,
                100.0 * tour.covered_fraction,
                tour.explorable_m2,
                wall_s
            );
        }
        Ok(())
    })
}
