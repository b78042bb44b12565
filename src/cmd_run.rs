//! `floorcast run` (an experiment grid on this machine) and `floorcast report` (tables from a
//! results store).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::{Context, Result};
use clap::Args;
use floorcast_coordinator::grid::Plan;
use floorcast_coordinator::local::{run_local, Outcome};
use floorcast_coordinator::store::{provenance, Store, DB_FILE};
use floorcast_coordinator::table::{render_text, results_csv, table};

use crate::output::{progress_bar, write_text};

#[derive(Debug, Args)]
pub struct RunArgs {
    /// Grid file (TOML): buildings, seeds, strategies, settings; see README.
    grid: PathBuf,
    /// Worker threads on this machine (default: one per core).
    #[arg(long, value_name = "N")]
    workers: Option<usize>,
    /// Where results go (overrides the grid's `results`).
    #[arg(long, value_name = "DIR")]
    results: Option<PathBuf>,
    /// Only print the table of what is stored so far; run nothing.
    #[arg(long)]
    summary: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Debug, Args)]
pub struct ReportArgs {
    /// Results directory (holding results.sqlite), e.g. results/quick.
    results: PathBuf,
    /// Also write one line per job as CSV (for pandas, R, spreadsheets).
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
}

pub fn run(a: RunArgs) -> Result<()> {
    let plan = Plan::load(&a.grid, a.results.as_deref())?;
    let store = Store::open(&plan.results_dir)?;
    if a.summary {
        let results = store.all()?;
        say!(
            "{} of {} jobs stored in {}",
            stored_of_plan(&plan, &store)?,
            plan.jobs.len(),
            store.path().display()
        );
        say_raw!("{}", render_text(&table(&results, &plan.labels)));
        return Ok(());
    }
    let before = stored_of_plan(&plan, &store)?;
    if before == plan.jobs.len() {
        say!(
            "nothing to do: all {} jobs of grid '{}' are already stored in {}",
            plan.jobs.len(),
            plan.name,
            store.path().display()
        );
        say_raw!("{}", render_text(&table(&store.all()?, &plan.labels)));
        return Ok(());
    }
    let workers = a
        .workers
        .unwrap_or_else(|| {
            std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1)
        })
        .max(1);
    store.record_run(&provenance(
        &a.grid.display().to_string(),
        &std::env::args().collect::<Vec<_>>().join(" "),
    ))?;
    say!(
        "grid '{}': {} jobs ({} buildings x seeds x {} strategies), {} already stored, {} workers",
        plan.name,
        plan.jobs.len(),
        plan.buildings.len(),
        plan.labels.len(),
        before,
        workers
    );
    let interrupt = Arc::new(AtomicBool::new(false));
    {
        let flag = Arc::clone(&interrupt);
        // A second Ctrl-C kills at once.
        let _ = ctrlc::set_handler(move || {
            if flag.swap(true, Ordering::SeqCst) {
                std::process::exit(130);
            }
        });
    }
    let pb = progress_bar(
        plan.jobs.len() as u64,
        a.quiet,
        "{spinner} [{elapsed_precise}] [{bar:40}] {pos}/{len} jobs {msg} (eta {eta})",
    );
    let (outcome, counts) = run_local(&plan, &store, workers, &interrupt, &mut |c| {
        pb.set_position(c.done as u64);
        pb.set_message(format!("{} running, {} failed", c.running, c.failed));
    })?;
    pb.finish_and_clear();
    match outcome {
        Outcome::Complete => {
            say!(
                "done: {} jobs run now, {} stored before, {} failed; results in {}",
                counts.done - counts.resumed,
                counts.resumed,
                counts.failed,
                store.path().display()
            );
            say_raw!("{}", render_text(&table(&store.all()?, &plan.labels)));
            Ok(())
        }
        Outcome::Interrupted => {
            eprintln!(
                "interrupted: {} of {} jobs stored in {}; run the same command again to resume",
                counts.done,
                counts.total,
                store.path().display()
            );
            std::process::exit(130);
        }
    }
}

fn stored_of_plan(plan: &Plan, store: &Store) -> Result<usize> {
    let ids = store.stored_ids()?;
    Ok(plan.jobs.iter().filter(|j| ids.contains(&j.id)).count())
}

pub fn report(a: ReportArgs) -> Result<()> {
    let store = Store::open_existing(&a.results)?;
    let results = store.all()?;
    say!(
        "{} results in {}",
        results.len(),
        a.results.join(DB_FILE).display()
    );
    say_raw!("{}", render_text(&table(&results, &[])));
    if let Some(csv) = &a.csv {
        write_text(csv, &results_csv(&results))
            .with_context(|| format!("cannot export to {}", csv.display()))?;
        say!("wrote {}", csv.display());
    }
    Ok(())
}
