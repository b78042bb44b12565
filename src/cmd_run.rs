//! `floorcast run` (an experiment grid on this machine) and `floorcast report` (tables from a
//! results store).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::{Context, Result};
use clap::Args;
use floorcast_coordinator::grid::Plan;
use floorcast_coordinator::inbox::RemoteWorkers;
use floorcast_coordinator::net::NetConfig;
use floorcast_coordinator::run::{run_plan, Outcome, RunOptions};
use floorcast_coordinator::store::{provenance, Store, DB_FILE};
use floorcast_stats::report::{Report, ReportScope};
use floorcast_stats::table::{
    gains_against, labels_of, render_against, render_text, results_csv, table, SequentialVerdict,
};

use crate::output::{progress_bar, write_text};

/// Network options shared by `run` and `worker`.
#[derive(Debug, Args)]
pub struct NetArgs {
    /// A zenoh configuration file (JSON5 or YAML) for TLS, mutual TLS, user/password or a
    /// router deployment (docs/many-machines.md). Endpoints given with --listen / --connect are
    /// added to it. A worker is always a zenoh client (the file's `mode` is ignored there).
    #[arg(long, value_name = "FILE")]
    pub zenoh_config: Option<PathBuf>,
    /// Name separating grids that share one zenoh router; coordinator and workers must agree.
    #[arg(long, value_name = "NAME", default_value = "default")]
    pub campaign: String,
}

#[derive(Debug, Args)]
#[command(
    after_long_help = floorcast_worker::settings::settings_help_text(),
    allow_negative_numbers = true
)]
pub struct RunArgs {
    /// Grid file (TOML): buildings, seeds, strategies, settings; see README.
    grid: PathBuf,
    /// Worker threads on this machine, 0 to 1024 (default: one per core; 0 with
    /// --listen/--connect lets only remote workers run jobs). Each runs one exploration at a
    /// time, up to about 200 MB of memory each.
    #[arg(long, value_name = "N", value_parser = crate::values::whole_number::<usize>(0, crate::values::MAX_THREADS))]
    workers: Option<usize>,
    /// Also accept remote workers (`floorcast worker --connect ...`) on this zenoh endpoint,
    /// e.g. tcp/0.0.0.0:7447 (repeatable). Without --listen/--connect nothing opens a port.
    #[arg(long, value_name = "ENDPOINT")]
    listen: Vec<String>,
    /// Reach remote workers through this zenoh endpoint instead, e.g. a router at
    /// tcp/router:7447 (repeatable).
    #[arg(long, value_name = "ENDPOINT")]
    connect: Vec<String>,
    #[command(flatten)]
    net: NetArgs,
    /// Lease of a remote job in seconds: a worker renews it while it runs the job; a job whose
    /// lease runs out (a hung worker) goes back to the queue.
    #[arg(long, value_name = "S", default_value_t = 60.0, value_parser = crate::values::number)]
    lease_s: f64,
    /// Fraction of remote workers' results, in [0, 1], that this machine runs again and
    /// compares bit for bit (wall times aside), besides each worker's first result, which is
    /// always checked; 0 checks none. A worker whose result differs gets no more jobs and its
    /// results are discarded and run again. Jobs of external strategies and jobs that charge
    /// compute time are not checked.
    #[arg(long, value_name = "F", default_value_t = 0.05, value_parser = crate::values::number)]
    verify_fraction: f64,
    /// Run every job alone. By default this machine's workers run jobs that share their
    /// beginning together: strategies that differ only in their early stop (`layout`,
    /// `layout-es`, `layout-aes`; `layout-gaps` and `layout-gaps-es`; `layout-truth` and
    /// `layout-truth-es`) on the same building, seed, start and settings make the same choices
    /// until one stops or drops a candidate, so one exploration serves them up to there. Each
    /// result is the one made alone; its wall time is the shared part up to where it went alone
    /// plus its own. Remote workers always run jobs alone.
    #[arg(long)]
    no_share: bool,
    /// Where results go (overrides the grid's `results`).
    #[arg(long, value_name = "DIR")]
    results: Option<PathBuf>,
    /// Most jobs (buildings x seeds x strategies) the grid may hold; a larger grid is refused
    /// before anything runs.
    #[arg(long, value_name = "N", default_value_t = floorcast_coordinator::grid::DEFAULT_MAX_JOBS, value_parser = crate::values::whole_number::<u64>(1, u64::MAX))]
    max_jobs: u64,
    /// Only print the table of what is stored so far; run nothing.
    #[arg(long)]
    summary: bool,
    /// Run the stored failed jobs again (a crashed or timed-out strategy program, fixed since),
    /// besides the jobs not stored yet; the other stored jobs are skipped as always. Each new
    /// outcome replaces the job's failed row in results.sqlite; every failure stays recorded in
    /// its `failures` table (`report RESULTS --failures` lists them). Off by default: a failed
    /// job is stored and not run again.
    #[arg(long, conflicts_with = "summary")]
    retry_failed: bool,
    /// Make no known-map tours. By default, once its jobs are done, `run` makes the tour of
    /// each building, start pose and robot the grid's runs used (docs/known-map-tour.md; about
    /// 1 to 40 s each, on the --workers threads) unless the store has it, so that `report`
    /// shows each run's efficiency.
    #[arg(long)]
    no_tours: bool,
    /// The most a known-map tour may be estimated to take to make (s of one core, at least 1;
    /// default 60): a tour estimated longer (a very short laser range or narrow field of
    /// view) is skipped with a warning, and `report` shows its runs without efficiency.
    #[arg(long, value_name = "SECONDS", default_value_t = crate::cmd_tour::DEFAULT_TOUR_BUDGET_S, value_parser = crate::values::number)]
    tour_budget: f64,
    /// Before running, store the runs and tours of FILE (written by `report DIR --export-runs
    /// FILE`, e.g. results/reference/leaderboard/runs.jsonl.gz) that are jobs of this grid and
    /// not stored yet: only the grid's other jobs are run. A run matches a job only when
    /// everything that determines it matches (building content, strategy, seed, settings,
    /// start, floorcast version); it is stored under this grid's label and building name for
    /// the job, with its worker marked `import`. Its progress curve is the file's thinned one (times to each
    /// whole percent exact).
    #[arg(long, value_name = "FILE", conflicts_with = "summary")]
    import: Option<PathBuf>,
    /// Serve a live view of the run over HTTP at ADDR: a page (`/`, reloading itself every 5 s)
    /// and JSON (`/status.json`, docs/live-view.md) with jobs stored, running, failed and left,
    /// the ETA, the workers (rates, last contact, jobs held), the failures and a sequential
    /// grid's tests. ADDR is a port (8080: on loopback only), HOST:PORT, or 0.0.0.0:PORT to be
    /// reached from other machines (anyone who reaches it can read the grid's state; it
    /// changes nothing); port 0 takes any free one. Off by default.
    #[arg(long, value_name = "ADDR", conflicts_with = "summary", value_parser = floorcast_coordinator::http::parse_addr)]
    http: Option<std::net::SocketAddr>,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct ReportArgs {
    /// Results directory (holding results.sqlite), e.g. results/quick.
    results: PathBuf,
    /// Also write one line per job as CSV (for pandas, R, spreadsheets): identity, times,
    /// explored area, end_reason (complete, early stop, time limit, stuck, frontiers
    /// unreachable), start pose (start_x_m, start_y_m, start_theta_rad) and start_source.
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Also draw charts into this directory: times.png (the paper's Fig. 2: mean exploration
    /// time per building and strategy, ± 1 standard deviation), gains.png (the paired gain over
    /// the reference per building with its 95 % confidence interval) and
    /// progress-<building>.png (the paper's Fig. 4: explored fraction over simulated time per
    /// strategy, mean line, band from the least to the greatest run, rings at early stops);
    /// with labels of a grid's robots factor ("NAME xN"), team-sizes.png (mean exploration time
    /// against team size per strategy).
    #[arg(long, value_name = "DIR")]
    plots: Option<PathBuf>,
    /// Also write one offline HTML page with the report's tables and the charts of --plots
    /// (inline SVG), e.g. report.html.
    #[arg(long, value_name = "FILE")]
    html: Option<PathBuf>,
    /// Picture formats of the charts, one or more (comma-separated or repeated): png, svg, pdf
    /// (vector, fonts embedded, for LaTeX).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "png")]
    picture: Vec<ChartPicture>,
    /// Lay the charts out for print at this width, with its unit: e.g. 3.5in (a journal
    /// column), 7.16in (a page), 8.9cm, 89mm, 252pt; 1 to 20 inches. Text is then --font-pt
    /// points at that size and PNGs are 300 dpi. Default: a screen layout, 1160 px wide.
    #[arg(long, value_name = "LENGTH", value_parser = crate::values::length_in)]
    plot_width: Option<f64>,
    /// With --plot-width: the charts' text size in points, 4 to 36 (default 8).
    #[arg(long, value_name = "PT", requires = "plot_width", value_parser = crate::values::number)]
    font_pt: Option<f64>,
    /// Leave the titles off the charts (a paper's caption says what a figure shows).
    #[arg(long)]
    no_titles: bool,
    /// Also compare with another results directory (or this one): the gain of each strategy
    /// label here over a label there (the same label, or --against-label), paired by building
    /// content, seed and start pose, with its 95 % interval; for a grid that changes one thing
    /// against a reference grid, e.g. results/paper-alpha --against results/paper.
    #[arg(long, value_name = "DIR")]
    against: Option<PathBuf>,
    /// With --against: the label there that every label here is compared with (default: the
    /// same label), e.g. baseline.
    #[arg(long, value_name = "LABEL", requires = "against")]
    against_label: Option<String>,
    /// The label every other label is compared with (default: baseline if present, else the
    /// first label).
    #[arg(long, value_name = "LABEL")]
    reference: Option<String>,
    /// Also write the report as JSON (versioned, documented in docs/report-json.md): per label
    /// its times, ends and failures; per comparison (overall and per building) the paired gain
    /// (mean log ratio) with its t, bootstrap and anytime-valid intervals, the Wilcoxon
    /// p-value, the Holm-adjusted one, the effect size, pairs, runs below the coverage level on
    /// each side, and a sequential grid's decision; the aggregates across buildings (IQM,
    /// probability of improvement, performance profile).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Also list the failed jobs (building, label and strategy, seed, attempts, each attempt's
    /// error) with the first 5 and last 10 lines of the stored stderr of their strategy
    /// program (its last 64 KiB are stored), and the earlier failures of jobs that later
    /// succeeded (`run --retry-failed`), marked as such. Failed jobs do not make report fail
    /// (exit code 0).
    #[arg(long)]
    failures: bool,
    /// The coverage level, a fraction in (0, 1]: a run achieves the outcome when it ended with
    /// at least this fraction of the explorable area explored; a run below it counts as a loss
    /// against a run that reached it (two runs below it are scored by explored fraction, then time). Default: the grids'
    /// `coverage` as recorded in the store (0.99 unless a grid set another).
    #[arg(long, value_name = "F", value_parser = crate::values::number)]
    coverage: Option<f64>,
    /// The time that decides every comparison, aggregate and ranking: end (the time until the
    /// run ended, having explored the coverage level: the paper's measure, the default) or
    /// coverage (the time at which it first had the coverage level explored, from its progress
    /// curve: Explore-Bench's T_90 with --coverage 0.9). The tables show the times to 90 %, 99 %
    /// and the end side by side whichever decides.
    #[arg(long, value_name = "end|coverage", default_value = "end", value_parser = parse_measure)]
    measure: floorcast_stats::outcome::Measure,
    /// Also write the store's successful runs and its tours to FILE (gzip-compressed JSON
    /// lines: a header, then a line per run and per tour), each progress curve thinned to its
    /// times to every whole percent (every tenth from 95 %): small enough to commit, e.g. a
    /// leaderboard's runs, and read by `run GRID --import FILE`, which then runs only the
    /// grid's other jobs.
    #[arg(long, value_name = "FILE")]
    export_runs: Option<PathBuf>,
}

/// The arguments of `run` that clap cannot check alone.
fn check_run_args(a: &RunArgs) -> Result<()> {
    if a.tour_budget.is_nan() || a.tour_budget < 1.0 {
        anyhow::bail!(
            "--tour-budget: {} is out of range, expected seconds at least 1 (default {})",
            a.tour_budget,
            crate::cmd_tour::DEFAULT_TOUR_BUDGET_S
        );
    }
    if let Some(r) = &a.results {
        if r.as_os_str().is_empty() {
            anyhow::bail!("--results: empty; expected a directory such as results/my-grid");
        }
    }
    Ok(())
}

pub fn run(a: RunArgs) -> Result<()> {
    check_run_args(&a)?;
    let plan = Plan::load_with(
        &a.grid,
        a.results.as_deref(),
        &floorcast_coordinator::grid::PlanLimits {
            max_jobs: a.max_jobs,
        },
    )?;
    check_options(&a)?;
    refuse_overwrites_of_run(&a, &plan)?;
    if a.summary && nothing_stored(&a, &plan) {
        return Ok(());
    }
    // Read and checked before the results directory is made.
    let imported = a.import.as_deref().map(read_import).transpose()?;
    let (_lock, store) = open_store(&plan, a.summary)?;
    if !a.summary {
        // Before any job of ours starts: what killed floorcast processes left.
        crate::output::remove_stale_temp_dirs(a.quiet);
    }
    if let Some((path, file)) = imported {
        import_runs(&plan, &store, path, file)?;
    }
    let stored = store.all()?;
    check_stored(&plan, &store, &stored)?;
    say_suites(&plan);
    // A sequential grid's jobs so far: those of every batch whose predecessors are all stored.
    let (progress, jobs) = floorcast_coordinator::sequential::replay(&plan, &stored);
    drop(stored);
    if a.summary {
        let results = store.all()?;
        say!(
            "{} of {} jobs stored in {}",
            stored_of(&jobs, &store)?,
            jobs.len(),
            store.path().display()
        );
        say_raw!(
            "{}",
            render_text(&table(&results, &plan.labels, plan.coverage))
        );
        print_sequential(&plan, &progress);
        return Ok(());
    }
    let before = stored_of(&jobs, &store)?;
    let to_retry = if a.retry_failed {
        failed_of(&jobs, &store)?
    } else {
        0
    };
    // The grid's label order and coverage level, for `report`.
    store.record_grid(&plan.name, &plan.labels, plan.coverage)?;
    if before == jobs.len() && progress.finished && to_retry == 0 {
        return nothing_to_do(&a, &plan, &store, &progress, &jobs);
    }
    let networked = !a.listen.is_empty() || !a.connect.is_empty() || a.net.zenoh_config.is_some();
    let workers = a.workers.unwrap_or_else(crate::values::cores);
    if workers == 0 && !networked {
        anyhow::bail!(
            "--workers 0 runs nothing on this machine; add --listen ENDPOINT so that remote workers can join, or give --workers N"
        );
    }
    let mut opts = run_options(&a, networked, workers);
    let live = start_live(&a, &plan, &mut opts)?;
    store.record_run(&provenance(
        &a.grid.display().to_string(),
        &std::env::args().collect::<Vec<_>>().join(" "),
        &crate::build_info(),
    ))?;
    announce(&plan, jobs.len(), before, workers);
    if to_retry > 0 {
        say!("--retry-failed: {to_retry} failed jobs run again (their failures stay recorded)");
    }
    let interrupt = interrupt_on_ctrl_c();
    let (outcome, counts) = run_with_progress(&plan, &store, &opts, &interrupt, a.quiet)?;
    let tour_threads = (!a.no_tours).then_some(crate::cmd_tour::GridTours {
        threads: workers.max(1),
        budget_s: a.tour_budget,
    });
    if let Some(live) = &opts.live {
        live.set_state(match (outcome, tour_threads) {
            (Outcome::Interrupted, _) => "interrupted",
            (Outcome::Complete, Some(_)) => "making tours",
            (Outcome::Complete, None) => "complete",
        });
    }
    finish(
        &plan,
        &store,
        outcome,
        counts,
        networked,
        tour_threads,
        &interrupt,
    )?;
    if let Some(live) = &opts.live {
        live.set_state("complete");
    }
    drop(live);
    Ok(())
}

/// The store, SQLite's files and the lock `run` writes are none of the files it reads (the
/// grid, `--import`): [`crate::output::Paths`].
fn refuse_overwrites_of_run(a: &RunArgs, plan: &Plan) -> Result<()> {
    let mut paths = crate::output::Paths::new();
    paths
        .read("the grid", Some(&a.grid))
        .read("--import", a.import.as_deref());
    for f in floorcast_coordinator::store::OWNED_FILES {
        paths.write("--results", Some(&plan.results_dir.join(f)));
    }
    paths.check()
}

/// Every job of the grid is stored already: says so, prints the table and the tests, makes the
/// tours still missing, and fails when jobs failed.
fn nothing_to_do(
    a: &RunArgs,
    plan: &Plan,
    store: &Store,
    progress: &floorcast_stats::sequential::Progress,
    jobs: &[floorcast_coordinator::grid::PlannedJob],
) -> Result<()> {
    let failed = match failed_of(jobs, store)? {
        0 => String::new(),
        n => format!(" ({n} of them failed: --retry-failed runs them again)"),
    };
    say!(
        "nothing to do: all {} jobs of grid '{}' are already stored in {}{failed}",
        jobs.len(),
        plan.name,
        store.path().display()
    );
    say_raw!(
        "{}",
        render_text(&table(&store.all()?, &plan.labels, plan.coverage))
    );
    print_sequential(plan, progress);
    if !a.no_tours {
        let how = crate::cmd_tour::GridTours {
            threads: a.workers.unwrap_or_else(crate::values::cores).max(1),
            budget_s: a.tour_budget,
        };
        let interrupt = interrupt_on_ctrl_c();
        crate::cmd_tour::make_grid_tours(plan, jobs, store, how, &interrupt)?;
    }
    failed_jobs(plan, jobs, store)
}

/// `--http`: the live view's server, started before anything runs (a port in use is an error
/// then); the run tells `opts.live` what happens.
fn start_live(
    a: &RunArgs,
    plan: &Plan,
    opts: &mut RunOptions,
) -> Result<Option<floorcast_coordinator::http::LiveServer>> {
    let Some(addr) = a.http else {
        return Ok(None);
    };
    let live = Arc::new(floorcast_coordinator::live::Live::new(&plan.name));
    let server =
        floorcast_coordinator::http::serve(addr, Arc::clone(&live)).map_err(anyhow::Error::msg)?;
    say!("live view: http://{}/ (and /status.json)", server.addr());
    opts.live = Some(live);
    Ok(Some(server))
}

/// `--summary` of a grid whose results directory holds no store yet: says so (nothing is
/// created) and returns true.
fn nothing_stored(a: &RunArgs, plan: &Plan) -> bool {
    let db = plan.results_dir.join(floorcast_coordinator::store::DB_FILE);
    if std::fs::symlink_metadata(&db).is_ok() {
        return false;
    }
    say_suites(plan);
    say!(
        "0 of {} jobs stored in {} (nothing run yet: `floorcast run {}` runs them)",
        plan.jobs.len(),
        db.display(),
        a.grid.display()
    );
    true
}

/// The suites the grid names: name, size, hash and manifest.
fn say_suites(plan: &Plan) {
    for s in &plan.suites {
        say!(
            "suite {}: {} buildings, hash {} ({})",
            s.name,
            s.buildings,
            s.hash,
            s.manifest.display()
        );
    }
}

/// The `--import` file at `path`, read and checked.
fn read_import(
    path: &std::path::Path,
) -> Result<(&std::path::Path, floorcast_coordinator::board::Exported)> {
    floorcast_coordinator::board::read(path)
        .map(|file| (path, file))
        .map_err(|e| anyhow::anyhow!("--import {}: {e}", path.display()))
}

/// Stores the runs of an `--import` file that are jobs of `plan` not stored yet (under the
/// plan's grid name and label, the worker marked), and its tours of the plan's buildings that
/// the store lacks.
fn import_runs(
    plan: &Plan,
    store: &Store,
    path: &std::path::Path,
    file: floorcast_coordinator::board::Exported,
) -> Result<()> {
    let jobs = match &plan.sequential {
        Some(q) => plan.jobs_for(&(1..=q.max_seeds).collect::<Vec<_>>(), None),
        None => plan.jobs.clone(),
    };
    let by_id: std::collections::BTreeMap<&str, &floorcast_coordinator::grid::PlannedJob> =
        jobs.iter().map(|j| (j.id.as_str(), j)).collect();
    let stored = store.stored_ids()?;
    let worker = format!(
        "import:{}",
        path.file_name().unwrap_or_default().to_string_lossy()
    );
    // Every line that claims a job of this grid is checked against that job before any is
    // stored: one refused line stores nothing of the file.
    let mut starts = floorcast_coordinator::board::Starts::new();
    let mut seen = std::collections::BTreeMap::new();
    let mut rows = Vec::new();
    for (mut r, line) in file.runs.into_iter().zip(file.run_lines) {
        let Some(job) = by_id.get(r.job_id.as_str()) else {
            continue;
        };
        if let Some(first) = seen.insert(r.job_id.clone(), line) {
            anyhow::bail!(
                "--import {}: line {line}: job {} again (line {first} holds it already); expected each job once",
                path.display(),
                r.job_id
            );
        }
        floorcast_coordinator::board::check_import(plan, job, &r, &mut starts).map_err(|e| {
            anyhow::anyhow!(
                "--import {}: line {line}: {e}; nothing of the file was stored (export the runs again with `floorcast report DIR --export-runs FILE`)",
                path.display()
            )
        })?;
        if stored.contains(&r.job_id) {
            continue;
        }
        r.label.clone_from(&job.label);
        r.building.clone_from(&plan.buildings[job.building].name);
        r.grid.clone_from(&plan.name);
        r.worker.clone_from(&worker);
        rows.push(r);
    }
    let n = store.insert_many(&rows)?;
    let hashes: std::collections::BTreeSet<&str> =
        plan.buildings.iter().map(|b| b.hash.as_str()).collect();
    let have = store.tours()?;
    let mut tours = 0;
    for t in file
        .tours
        .iter()
        .filter(|t| hashes.contains(t.building_hash.as_str()))
    {
        if !have
            .iter()
            .any(|h| h.building_hash == t.building_hash && h.starts_at(&t.start) && h.key == t.key)
        {
            store.record_tour(t)?;
            tours += 1;
        }
    }
    say!(
        "--import {}: {n} of its {} runs stored as jobs of this grid ({} jobs), {tours} tours",
        path.display(),
        file.header.runs,
        jobs.len()
    );
    Ok(())
}

/// The options checked once the grid is read (before the results directory is made).
fn check_options(a: &RunArgs) -> Result<()> {
    if !(0.0..=1.0).contains(&a.verify_fraction) {
        anyhow::bail!(
            "--verify-fraction: expected a fraction in [0, 1], got {}",
            floorcast_worker::settings::fmt_num(a.verify_fraction)
        );
    }
    if !(1.0..=86_400.0).contains(&a.lease_s) {
        anyhow::bail!(
            "--lease-s: expected seconds in [1, 86400], got {}",
            floorcast_worker::settings::fmt_num(a.lease_s)
        );
    }
    // Checked before the results directory is made.
    if let Some(path) = &a.net.zenoh_config {
        floorcast_coordinator::net::check_config_file(path)?;
    }
    Ok(())
}

/// The results store, locked for this run (`--summary` only reads: nothing written, nothing
/// created beside it).
fn open_store(
    plan: &Plan,
    summary: bool,
) -> Result<(Option<floorcast_coordinator::store::RunLock>, Store)> {
    // One run per results directory (`--summary` only reads).
    let lock = (!summary)
        .then(|| floorcast_coordinator::store::lock_results(&plan.results_dir))
        .transpose()?;
    // `--summary` reads a store as it is (nothing written, nothing created beside it; `run`
    // returned before this when there is none).
    let store = if summary {
        Store::open_existing(&plan.results_dir)?
    } else {
        Store::open(&plan.results_dir)?
    };
    if store.completed_half_made() {
        say!(
            "{}: a store floorcast had created but not finished (it held nothing: its disk was full, or floorcast was killed as it made it) is now complete",
            store.path().display()
        );
    }
    Ok((lock, store))
}

/// What is stored already agrees with the plan: one configuration per label, one version of
/// each suite.
fn check_stored(
    plan: &Plan,
    store: &Store,
    stored: &[floorcast_coordinator::store::StoredResult],
) -> Result<()> {
    // A label stands for one configuration: runs of another under it would be merged in the
    // report (refused before anything runs).
    floorcast_coordinator::grid::check_plan_labels(&plan.jobs, stored).map_err(|e| {
        anyhow::anyhow!(
            "{}: {e} (results in {})",
            plan.grid_path.display(),
            store.path().display()
        )
    })?;
    // One version of a suite per results directory.
    floorcast_coordinator::suite::check_stored_suites(&plan.suites, stored).map_err(|e| {
        anyhow::anyhow!(
            "{}: {e} (results in {})",
            plan.grid_path.display(),
            store.path().display()
        )
    })?;
    Ok(())
}

/// How `run_plan` runs the grid: local workers, remote ones when networked.
fn run_options(a: &RunArgs, networked: bool, workers: usize) -> RunOptions {
    RunOptions {
        workers,
        remote: networked.then(|| {
            Arc::new(NetConfig {
                listen: a.listen.clone(),
                connect: a.connect.clone(),
                zenoh_config: a.net.zenoh_config.clone(),
                campaign: a.net.campaign.clone(),
            }) as Arc<dyn RemoteWorkers>
        }),
        lease_s: a.lease_s,
        // Without remote workers nothing is checked (`run_plan` starts no verifier).
        verify_fraction: a.verify_fraction,
        share: !a.no_share,
        retry_failed: a.retry_failed,
        ..RunOptions::default()
    }
}

/// The grid's first line: what runs, what is stored, on how many workers.
fn announce(plan: &Plan, jobs: usize, before: usize, workers: usize) {
    match &plan.sequential {
        Some(q) => say!(
            "grid '{}': sequential, {} buildings x {} strategies, seeds in batches of {} up to {} ({} jobs so far, {} already stored), {} local workers",
            plan.name,
            plan.buildings.len(),
            plan.labels.len(),
            q.batch_seeds,
            q.max_seeds,
            jobs,
            before,
            workers
        ),
        None => say!(
            "grid '{}': {} jobs ({} buildings x seeds x {} strategies), {} already stored, {} local workers",
            plan.name,
            plan.jobs.len(),
            plan.buildings.len(),
            plan.labels.len(),
            before,
            workers
        ),
    }
}

/// A flag Ctrl-C sets (the run stops cleanly); a second Ctrl-C kills at once.
fn interrupt_on_ctrl_c() -> Arc<AtomicBool> {
    let interrupt = Arc::new(AtomicBool::new(false));
    {
        let flag = Arc::clone(&interrupt);
        // A second Ctrl-C kills at once.
        let _ = ctrlc::set_handler(move || {
            if flag.swap(true, Ordering::SeqCst) {
                floorcast_worker::external::kill_all_programs();
                std::process::exit(130);
            }
        });
    }
    interrupt
}

/// Runs the plan with a progress bar (log lines printed above it).
fn run_with_progress(
    plan: &Plan,
    store: &Store,
    opts: &RunOptions,
    interrupt: &AtomicBool,
    quiet: bool,
) -> Result<(Outcome, floorcast_coordinator::run::Counts)> {
    let pb = progress_bar(
        plan.jobs.len() as u64,
        quiet,
        "{spinner} [{elapsed_precise}] [{bar:40}] {pos}/{len} jobs {msg} (eta {eta})",
    );
    let log_pb = pb.clone();
    let (outcome, counts) = run_plan(
        plan,
        store,
        opts,
        interrupt,
        &mut |c| {
            // A sequential grid's jobs grow batch by batch.
            pb.set_length(c.total as u64);
            pb.set_position(c.done as u64);
            let remote = if opts.remote.is_some() {
                format!(", {} remote workers", c.remote_workers)
            } else {
                String::new()
            };
            pb.set_message(format!(
                "{} running, {} failed{remote}",
                c.running, c.failed
            ));
        },
        &mut |line| {
            if log_pb.is_hidden() {
                tell!("{line}");
            } else {
                log_pb.println(line);
            }
        },
    )?;
    pb.finish_and_clear();
    Ok((outcome, counts))
}

/// What the run did: the table, a sequential grid's tests, the failed jobs (an interrupted run
/// exits 130).
fn finish(
    plan: &Plan,
    store: &Store,
    outcome: Outcome,
    counts: floorcast_coordinator::run::Counts,
    networked: bool,
    tour_threads: Option<crate::cmd_tour::GridTours>,
    interrupt: &AtomicBool,
) -> Result<()> {
    match outcome {
        Outcome::Complete => {
            say!(
                "done: {} jobs run now, {} stored before, {} failed; results in {}",
                counts.done - counts.resumed,
                counts.resumed,
                counts.failed,
                store.path().display()
            );
            if networked {
                say!(
                    "checked: {}",
                    match (counts.verified, counts.quarantined) {
                        (0, _) => "no result of a remote worker was run again here (none came, or --verify-fraction 0)".to_string(),
                        (1, 0) => "1 result of a remote worker run again here, identical".to_string(),
                        (n, 0) => format!("{n} results of remote workers run again here, all identical"),
                        (n, q) => format!(
                            "{n} results of remote workers run again here; {q} worker(s) computed differently, their results were discarded and run again (see the log above)"
                        ),
                    }
                );
            }
            say_raw!(
                "{}",
                render_text(&table(&store.all()?, &plan.labels, plan.coverage))
            );
            let (progress, jobs) = floorcast_coordinator::sequential::replay(plan, &store.all()?);
            print_sequential(plan, &progress);
            if let Some(threads) = tour_threads {
                crate::cmd_tour::make_grid_tours(plan, &jobs, store, threads, interrupt)?;
            }
            failed_jobs(plan, &jobs, store)
        }
        Outcome::Interrupted => {
            tell!(
                "interrupted: {} of {} jobs stored in {}; run the same command again to resume",
                counts.done,
                counts.total,
                store.path().display()
            );
            std::process::exit(130);
        }
    }
}

/// An error naming the plan's failed jobs (building, strategy, seed, error) and the jobs that did
/// not run, if any, and saying how to see and rerun the failed ones.
fn failed_jobs(
    plan: &Plan,
    jobs: &[floorcast_coordinator::grid::PlannedJob],
    store: &Store,
) -> Result<()> {
    let ids: std::collections::BTreeSet<&str> = jobs.iter().map(|j| j.id.as_str()).collect();
    let rows = store.all()?;
    let failed: Vec<_> = rows
        .iter()
        .filter(|r| ids.contains(r.job_id.as_str()) && !r.status.is_ok())
        .collect();
    let missing = jobs.len() - stored_of(jobs, store)?;
    if failed.is_empty() && missing == 0 {
        return Ok(());
    }
    let mut parts: Vec<String> = failed
        .iter()
        .take(3)
        .map(|r| {
            format!(
                "{} {} seed {}: {}",
                r.building,
                r.label,
                r.seed,
                r.error.as_deref().unwrap_or("no error recorded")
            )
        })
        .collect();
    if failed.len() > 3 {
        parts.push(format!("and {} more", failed.len() - 3));
    }
    if missing > 0 {
        parts.push(format!(
            "{missing} jobs did not run; run the same command again"
        ));
    }
    let how = if failed.is_empty() {
        String::new()
    } else {
        format!(
            "; `floorcast report {} --failures` shows their stderr; this `run` with --retry-failed runs them again",
            plan.results_dir.display()
        )
    };
    anyhow::bail!(
        "{} of {} jobs failed ({}); their rows in {} say why{how}",
        failed.len(),
        jobs.len(),
        parts.join("; "),
        store.path().display()
    )
}

/// How many of `jobs` are stored as failed.
fn failed_of(jobs: &[floorcast_coordinator::grid::PlannedJob], store: &Store) -> Result<usize> {
    let ids = store.failed_ids()?;
    Ok(jobs.iter().filter(|j| ids.contains(&j.id)).count())
}

fn stored_of(jobs: &[floorcast_coordinator::grid::PlannedJob], store: &Store) -> Result<usize> {
    let ids = store.stored_ids()?;
    Ok(jobs.iter().filter(|j| ids.contains(&j.id)).count())
}

/// A sequential grid's decisions so far.
fn print_sequential(plan: &Plan, progress: &floorcast_stats::sequential::Progress) {
    if let Some(q) = &plan.sequential {
        say_raw!("{}", floorcast_stats::sequential::render(progress, q));
    }
}

/// A chart's picture format (`report --picture`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ChartPicture {
    Png,
    Svg,
    Pdf,
}

impl ChartPicture {
    fn extension(self) -> &'static str {
        match self {
            ChartPicture::Png => "png",
            ChartPicture::Svg => "svg",
            ChartPicture::Pdf => "pdf",
        }
    }
}

/// Which suites the runs come from, so that two results directories say whether they ran the
/// same one.
fn say_report_suites(
    results: &[floorcast_coordinator::store::StoredResult],
    against: Option<&(&PathBuf, Vec<floorcast_coordinator::store::StoredResult>)>,
) {
    for line in &floorcast_coordinator::suite::describe_suites(results) {
        say!("{line}");
    }
    if let Some((dir, other)) = against {
        say_same_suites(dir, results, other);
    }
}

pub fn report(a: ReportArgs) -> Result<()> {
    let style = report_style(&a)?;
    let store = Store::open_existing(&a.results)?;
    refuse_overwrites(&a)?;
    let results = store.all()?;
    let failed = floorcast_coordinator::failures::failed_jobs(&results, &store.failures()?);
    // A label stands for one configuration: runs of two are never merged into one row.
    floorcast_stats::table::check_label_configurations(&results)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.results.join(DB_FILE).display()))?;
    let grids = store.grids()?;
    let against = open_against(&a)?;
    say!(
        "{} results in {}",
        results.len(),
        a.results.join(DB_FILE).display()
    );
    say_report_suites(&results, against.as_ref());
    let order = report_order(&grids, &results);
    let reference = report_reference(&a, &order)?;
    let coverage = report_coverage(&a, &grids)?;
    let verdicts = last_verdicts(&store, &order)?;
    let tours = store.tours()?;
    let scope = ReportScope {
        order,
        reference,
        coverage,
        measure: a.measure,
    };
    let report = Report::new(&results, &tours, scope, verdicts);
    // What is printed, kept for --html.
    let mut text = report.text();
    say_raw!("{}", text);
    text.push_str(&say_verdicts(&report.verdicts));
    let cross = against.as_ref().map(|(dir, other)| {
        let gains = gains_against(&results, other, a.against_label.as_deref(), coverage);
        (dir.display().to_string(), gains)
    });
    if let Some((dir, gains)) = &cross {
        let against = render_against(gains, dir);
        say_raw!("{}", against);
        text.push_str(&against);
    }
    if let Some(path) = &a.json {
        let mut v = report.json(&results);
        if let Some((dir, gains)) = &cross {
            v["against"] = floorcast_stats::table::against_json(gains, dir);
        }
        v["failures"] = floorcast_coordinator::failures::to_json(&failed);
        write_text(path, &(serde_json::to_string_pretty(&v)? + "\n"))
            .with_context(|| format!("cannot write {}", path.display()))?;
        say!("wrote {}", path.display());
    }
    if let Some(csv) = &a.csv {
        write_text(csv, &results_csv(&results))
            .with_context(|| format!("cannot export to {}", csv.display()))?;
        say!("wrote {}", csv.display());
    }
    if a.plots.is_some() || a.html.is_some() {
        let charts = charts(&results, &report.table, &report.aggregates, &style);
        write_pictures(&a, results.len(), &text, &charts)?;
    }
    if a.failures {
        say_raw!("{}", floorcast_coordinator::failures::render(&failed));
    }
    if let Some(path) = &a.export_runs {
        export_runs(path, &results, &tours)?;
    }
    Ok(())
}

/// `report --measure`: "end" or "coverage".
fn parse_measure(word: &str) -> std::result::Result<floorcast_stats::outcome::Measure, String> {
    word.parse()
}

/// `report --export-runs`: the store's successful runs and tours, written to `path`.
fn export_runs(
    path: &std::path::Path,
    results: &[floorcast_coordinator::store::StoredResult],
    tours: &[floorcast_worker::tour::TourRecord],
) -> Result<()> {
    let (bytes, runs, tours) = floorcast_coordinator::board::export(results, tours)
        .map_err(|e| anyhow::anyhow!("--export-runs: {e}"))?;
    crate::output::write_bytes(path, &bytes).context("--export-runs")?;
    say!("wrote {} ({runs} runs, {tours} tours)", path.display());
    Ok(())
}

/// The charts' style, with the report's options checked.
fn report_style(a: &ReportArgs) -> Result<floorcast_render::chart::ChartStyle> {
    if let Some(f) = a.font_pt {
        if !(4.0..=36.0).contains(&f) {
            anyhow::bail!("--font-pt: expected a text size in points from 4 to 36, got {f}");
        }
    }
    if let Some(c) = a.coverage {
        floorcast_stats::outcome::check_coverage(c)
            .map_err(|e| anyhow::anyhow!("--coverage: {e}"))?;
    }
    Ok(floorcast_render::chart::ChartStyle {
        width_in: a.plot_width,
        font_pt: a.font_pt.unwrap_or(8.0),
        titles: !a.no_titles,
    })
}

/// No export may overwrite a store the report reads (the reported one and `--against`'s) or a
/// file of one, nor another export (checked before anything is written: [`crate::output::Paths`]).
fn refuse_overwrites(a: &ReportArgs) -> Result<()> {
    use floorcast_coordinator::store::refuse_owned_in;
    crate::output::Paths::new()
        .store("the reported store", Some(&a.results))
        .store("--against's store", a.against.as_deref())
        .write("--csv", a.csv.as_deref())
        .write("--json", a.json.as_deref())
        .write("--html", a.html.as_deref())
        .write("--export-runs", a.export_runs.as_deref())
        .check()?;
    for picture in &a.picture {
        for dir in std::iter::once(&a.results).chain(&a.against) {
            refuse_owned_in("--plots", a.plots.as_deref(), picture.extension(), dir)?;
        }
    }
    Ok(())
}

/// The other store of `--against` and its runs, its `--against-label` checked (before
/// anything is printed).
fn open_against(
    a: &ReportArgs,
) -> Result<Option<(&PathBuf, Vec<floorcast_coordinator::store::StoredResult>)>> {
    Ok(match &a.against {
        Some(dir) => {
            let other = Store::open_existing(dir)?.all()?;
            if let Some(l) = &a.against_label {
                if !other.iter().any(|r| &r.label == l) {
                    anyhow::bail!(
                        "--against-label: {} holds no runs labelled '{l}'; its labels: {}",
                        dir.display(),
                        labels_of(&other).join(", ")
                    );
                }
            }
            Some((dir, other))
        }
        None => None,
    })
}

/// Whether `dir` ran the same suites (names and hashes) as the report's results.
fn say_same_suites(
    dir: &std::path::Path,
    results: &[floorcast_coordinator::store::StoredResult],
    other: &[floorcast_coordinator::store::StoredResult],
) {
    use floorcast_coordinator::suite::stored_suites;
    let versions = |r: &[floorcast_coordinator::store::StoredResult]| {
        stored_suites(r)
            .into_iter()
            .map(|(n, h, _)| format!("{n} {h}"))
            .collect::<Vec<_>>()
    };
    let (mine, theirs) = (versions(results), versions(other));
    if !mine.is_empty() || !theirs.is_empty() {
        say!(
            "{} ran {}: {}",
            dir.display(),
            if theirs.is_empty() {
                "no suite".to_string()
            } else {
                format!("suites {}", theirs.join(", "))
            },
            if mine == theirs {
                "the same suites (names and hashes) as here"
            } else {
                "NOT the same suites as here (names or hashes differ)"
            }
        );
    }
}

/// Labels in the order of the grids that made them, then as stored.
fn report_order(
    grids: &[(String, Vec<String>, f64)],
    results: &[floorcast_coordinator::store::StoredResult],
) -> Vec<String> {
    let mut order: Vec<String> = Vec::new();
    for (_, labels, _) in grids {
        for l in labels {
            if !order.contains(l) && results.iter().any(|r| &r.label == l) {
                order.push(l.clone());
            }
        }
    }
    floorcast_stats::outcome::label_order(results, &order)
}

/// The reference label: `--reference`, else `baseline`, else the first.
fn report_reference(a: &ReportArgs, order: &[String]) -> Result<String> {
    Ok(match &a.reference {
        Some(r) if !order.contains(r) => anyhow::bail!(
            "--reference: {} holds no runs labelled '{r}'; its labels: {}",
            a.results.display(),
            order.join(", ")
        ),
        Some(r) => r.clone(),
        None => order
            .iter()
            .find(|l| l.as_str() == "baseline")
            .or(order.first())
            .cloned()
            .unwrap_or_default(),
    })
}

/// The coverage level: as given, else the grids' own when they agree.
fn report_coverage(a: &ReportArgs, grids: &[(String, Vec<String>, f64)]) -> Result<f64> {
    Ok(match a.coverage {
        Some(c) => c,
        None => {
            let levels: Vec<f64> = grids.iter().map(|g| g.2).collect();
            match levels.first() {
                Some(&c) if levels.iter().all(|l| *l == c) => c,
                Some(_) => anyhow::bail!(
                    "the grids of {} were compared at different coverage levels ({}); choose one with --coverage",
                    a.results.display(),
                    levels
                        .iter()
                        .map(|l| l.to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
                None => floorcast_stats::outcome::DEFAULT_COVERAGE,
            }
        }
    })
}

/// Sequential grids' decisions: each label's last test, by grid and label order.
/// Prints each sequential grid's last verdict; returns what was printed.
fn say_verdicts(verdicts: &[SequentialVerdict]) -> String {
    let mut text = String::new();
    for v in verdicts {
        let line = format!(
            "sequential grid '{}': {}",
            v.grid,
            floorcast_stats::sequential::render_test(&v.test, None)
        );
        say!("{line}");
        text.push_str(&line);
        text.push('\n');
    }
    text
}

fn last_verdicts(store: &Store, order: &[String]) -> Result<Vec<SequentialVerdict>> {
    let mut last: std::collections::BTreeMap<(String, String), SequentialVerdict> =
        Default::default();
    for (grid, t) in store.tests()? {
        last.insert(
            (grid.clone(), t.label.clone()),
            SequentialVerdict { grid, test: t },
        );
    }
    let mut verdicts: Vec<SequentialVerdict> = last.into_values().collect();
    verdicts.sort_by_key(|v| {
        (
            v.grid.clone(),
            order.iter().position(|l| *l == v.test.label),
        )
    });
    Ok(verdicts)
}

/// `--plots` and `--html`: the charts in each picture format, and the report as a page.
fn write_pictures(
    a: &ReportArgs,
    runs: usize,
    text: &str,
    charts: &[(String, floorcast_render::Figure)],
) -> Result<()> {
    if let Some(dir) = &a.plots {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the chart directory {}", dir.display()))?;
        let mut formats = a.picture.clone();
        formats.dedup();
        for (name, fig) in charts {
            for f in &formats {
                crate::output::save_figure(fig, &dir.join(format!("{name}.{}", f.extension())))?;
            }
        }
        let names: Vec<&str> = formats.iter().map(|f| f.extension()).collect();
        say!(
            "wrote {} charts ({}) to {}",
            charts.len(),
            names.join(", "),
            dir.display()
        );
    }
    if let Some(path) = &a.html {
        write_text(path, &report_html(&a.results, runs, text, charts))
            .with_context(|| format!("cannot write {}", path.display()))?;
        say!("wrote {}", path.display());
    }
    Ok(())
}

/// The charts of a report, by file stem: `times` (the paper's Fig. 2: the mean exploration
/// time per building and strategy, with one standard deviation over the runs that achieved the
/// outcome), `gains` (the paired gain over the reference per building with its 95 % t
/// interval), `profile` (the performance profile across buildings: the fraction of runs whose
/// normalized time is at most tau, with its bootstrap band) and `progress-<building>` (the
/// paper's Fig. 4: the explored fraction over time per strategy, its mean, a band from the
/// least to the greatest run, and rings where runs stopped early).
fn charts(
    results: &[floorcast_coordinator::store::StoredResult],
    t: &floorcast_stats::table::Table,
    aggregates: &floorcast_stats::aggregate::Aggregates,
    style: &floorcast_render::chart::ChartStyle,
) -> Vec<(String, floorcast_render::Figure)> {
    use floorcast_render::chart::{series_color, Interval, IntervalChart, LineChart, Series};
    let reference = t.reference.clone().unwrap_or_default();
    // One colour per strategy label in every chart.
    let order: Vec<String> = t.overall.iter().map(|r| r.label.clone()).collect();
    let color = |l: &str| series_color(order.iter().position(|o| o == l).unwrap_or(0));
    let labels: Vec<String> = order.iter().filter(|l| **l != reference).cloned().collect();
    let gain = |rows: &[floorcast_stats::table::LabelRow], label: &str| {
        let p = rows.iter().find(|r| r.label == label)?.paired.as_ref()?;
        let (lo, hi) = p.ci_pct().unwrap_or((p.gain_pct(), p.gain_pct()));
        Some(Interval {
            mean: p.gain_pct(),
            lo,
            hi,
        })
    };
    let time = |rows: &[floorcast_stats::table::LabelRow], label: &str| {
        let s = rows.iter().find(|r| r.label == label)?.time;
        (s.n > 0).then(|| {
            let sd = if s.sd.is_finite() { s.sd } else { 0.0 };
            Interval {
                mean: s.mean,
                lo: s.mean - sd,
                hi: s.mean + sd,
            }
        })
    };
    let buildings: Vec<String> = t.per_building.keys().cloned().collect();
    let times = IntervalChart {
        title: "Exploration time per building (mean ± 1 sd over seeds)".into(),
        y_label: "exploration time (s)".into(),
        categories: buildings.clone(),
        series: order
            .iter()
            .map(|l| {
                let v = t.per_building.values().map(|rows| time(rows, l)).collect();
                (l.clone(), color(l), v)
            })
            .collect(),
        bars: true,
    };
    let mut categories = buildings;
    categories.push("all".into());
    let gains = IntervalChart {
        title: format!(
            "Exploration time gain over {reference} (paired, {} coverage, 95 % CI)",
            floorcast_stats::outcome::coverage_text(t.coverage)
        ),
        y_label: "gain (%)".into(),
        series: labels
            .iter()
            .map(|l| {
                let mut v: Vec<Option<Interval>> =
                    t.per_building.values().map(|rows| gain(rows, l)).collect();
                v.push(gain(&t.overall, l));
                (l.clone(), color(l), v)
            })
            .collect(),
        categories,
        bars: false,
    };
    let profile = LineChart {
        title: format!(
            "Performance profile across {} buildings (time / {reference}'s median)",
            aggregates.reference_median_s.len()
        ),
        x_label: "normalized exploration time tau".into(),
        x_range: Some((0.5, 2.0)),
        y_label: "fraction of runs at most tau".into(),
        y_range: Some((0.0, 1.0)),
        series: aggregates
            .labels
            .iter()
            .map(|l| Series {
                color: color(&l.label),
                label: format!("{} ({} runs)", l.label, l.runs),
                points: l.profile.iter().map(|p| (p.tau, p.fraction)).collect(),
                band: l.profile.iter().map(|p| (p.tau, p.lo, p.hi)).collect(),
                marks: Vec::new(),
            })
            .collect(),
        marks_label: String::new(),
    };
    let mut out = vec![
        ("times".to_string(), times.figure_styled(style)),
        ("gains".to_string(), gains.figure_styled(style)),
    ];
    if !aggregates.labels.is_empty() {
        out.push(("profile".to_string(), profile.figure_styled(style)));
    }
    out.extend(team_sizes_chart(t, style));
    for building in t.per_building.keys() {
        out.extend(progress_chart(results, building, &order, style));
    }
    out
}

/// `team-sizes`: the mean exploration time (over every building and seed, of the runs that
/// achieved the outcome, ± 1 sd) against team size per strategy, for the labels a grid's
/// `robots` factor made (`NAME xN`); `None` unless some strategy has two sizes.
fn team_sizes_chart(
    t: &floorcast_stats::table::Table,
    style: &floorcast_render::chart::ChartStyle,
) -> Option<(String, floorcast_render::Figure)> {
    use floorcast_render::chart::{series_color, LineChart, Series};
    // (name, robots, mean, sd) of each label `NAME xN`.
    let sized: Vec<(String, usize, f64, f64)> = t
        .overall
        .iter()
        .filter_map(|r| {
            let (name, n) = r.label.rsplit_once(" x")?;
            let n: usize = n.parse().ok()?;
            (r.time.n > 0).then(|| {
                let sd = if r.time.sd.is_finite() {
                    r.time.sd
                } else {
                    0.0
                };
                (name.to_string(), n, r.time.mean, sd)
            })
        })
        .collect();
    let mut names: Vec<String> = Vec::new();
    for (name, ..) in &sized {
        if !names.contains(name) {
            names.push(name.clone());
        }
    }
    names.retain(|n| sized.iter().filter(|s| &s.0 == n).count() > 1);
    if names.is_empty() {
        return None;
    }
    let most = sized.iter().map(|s| s.1).max().unwrap_or(1) as f64;
    let chart = LineChart {
        title: "Exploration time against team size (mean ± 1 sd over buildings and seeds)".into(),
        x_label: "robots".into(),
        x_range: Some((0.5, most + 0.5)),
        y_label: "exploration time (s)".into(),
        y_range: None,
        series: names
            .iter()
            .enumerate()
            .map(|(k, name)| {
                let mut pts: Vec<&(String, usize, f64, f64)> =
                    sized.iter().filter(|s| &s.0 == name).collect();
                pts.sort_by_key(|s| s.1);
                Series {
                    label: name.clone(),
                    color: series_color(k),
                    points: pts.iter().map(|s| (s.1 as f64, s.2)).collect(),
                    band: pts
                        .iter()
                        .map(|s| (s.1 as f64, s.2 - s.3, s.2 + s.3))
                        .collect(),
                    marks: Vec::new(),
                }
            })
            .collect(),
        marks_label: String::new(),
    };
    Some(("team-sizes".to_string(), chart.figure_styled(style)))
}

/// The paper's Fig. 4 for one building: the explored fraction over time per strategy (`None`
/// when no run has a progress curve).
fn progress_chart(
    results: &[floorcast_coordinator::store::StoredResult],
    building: &str,
    order: &[String],
    style: &floorcast_render::chart::ChartStyle,
) -> Option<(String, floorcast_render::Figure)> {
    use floorcast_render::chart::{series_color, LineChart, Series};
    let color = |l: &str| series_color(order.iter().position(|o| o == l).unwrap_or(0));
    let curves = floorcast_stats::table::progress_curves(results, building, order, 400);
    if curves.is_empty() {
        return None;
    }
    let chart = LineChart {
        title: format!("{building}: explored fraction (mean, range over seeds)"),
        x_label: "simulated time (s)".into(),
        x_range: None,
        y_label: "explored fraction".into(),
        y_range: Some((0.0, 1.0)),
        series: curves
            .into_iter()
            .map(|c| Series {
                color: color(&c.label),
                label: format!("{} ({} runs)", c.label, c.runs),
                points: c.points.iter().map(|p| (p.0, p.1)).collect(),
                band: c.points.iter().map(|p| (p.0, p.2, p.3)).collect(),
                marks: c.early_stops,
            })
            .collect(),
        marks_label: "early stop".into(),
    };
    Some((
        format!("progress-{}", file_name_part(building)),
        chart.figure_styled(style),
    ))
}

/// A stored building's name as part of a chart's file name: a name the grid checks
/// ([`floorcast_coordinator::names::file_name_part`]) as it is; another (from an older or a
/// tampered store) with its separators, dots and unprintable characters replaced by '_' and cut
/// to 100 characters, so that no chart is written outside `--plots`.
fn file_name_part(name: &str) -> String {
    if floorcast_coordinator::names::file_name_part(name).is_ok()
        && !name
            .chars()
            .any(|c| floorcast_worker::text::unprintable(c).is_some())
    {
        return name.to_string();
    }
    name.replace("..", "_")
        .chars()
        .map(|c| {
            if c == '/' || c == '\\' || floorcast_worker::text::unprintable(c).is_some() {
                '_'
            } else {
                c
            }
        })
        .take(floorcast_coordinator::names::MAX_NAME_CHARS)
        .collect()
}

/// `report --html`: one offline page with the report's text and its charts (inline SVG).
fn report_html(
    dir: &std::path::Path,
    runs: usize,
    text: &str,
    charts: &[(String, floorcast_render::Figure)],
) -> String {
    let esc = |s: &str| {
        s.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    let mut html = format!(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>floorcast report: {}</title>\n<style>body{{font-family:'DejaVu Sans',sans-serif;max-width:1250px;margin:2em auto;padding:0 1em}}pre{{font-size:12px;overflow-x:auto;background:#f6f6f6;padding:1em}}figure{{margin:2em 0}}svg{{max-width:100%;height:auto}}</style></head><body>\n<h1>floorcast report: {}</h1>\n<p>{runs} runs, floorcast {}. Made by <code>floorcast report {} --html</code>; the tables are those the command prints.</p>\n<h2>Tables</h2>\n<pre>{}</pre>\n<h2>Figures</h2>\n",
        esc(&dir.display().to_string()),
        esc(&dir.display().to_string()),
        floorcast_worker::FLOORCAST_VERSION,
        esc(&dir.display().to_string()),
        esc(text)
    );
    for (name, fig) in charts {
        html.push_str(&format!(
            "<figure id=\"{}\">\n{}<figcaption>{}</figcaption></figure>\n",
            esc(name),
            fig.to_svg(),
            esc(name)
        ));
    }
    html.push_str("</body></html>\n");
    html
}
