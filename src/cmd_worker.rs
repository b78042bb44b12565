//! `floorcast worker`: joins a grid run by `floorcast run GRID --listen ...` on another machine
//! (or through a zenoh router), runs jobs, returns results, leaves when the grid is done.

use anyhow::Result;
use clap::Args;
use floorcast_coordinator::net::{join, NetConfig};
use floorcast_worker::execute::execute_wire;
use floorcast_worker::process::{run_worker, WorkerEvent, WorkerOptions};

use crate::cmd_run::NetArgs;

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct WorkerArgs {
    /// The coordinator's (or a zenoh router's) endpoint, e.g. tcp/192.168.1.10:7447
    /// (repeatable). May be omitted when --zenoh-config lists the endpoints.
    #[arg(long, value_name = "ENDPOINT")]
    connect: Vec<String>,
    /// Jobs to run at once, 1 to 1024 (default: one per core), each up to about 200 MB of
    /// memory.
    #[arg(long, value_name = "N", value_parser = crate::values::whole_number::<usize>(1, crate::values::MAX_THREADS))]
    jobs: Option<usize>,
    /// Give up when no coordinator has answered for this many seconds, 0 to 86400 (a day);
    /// 0: wait forever. The worker also waits this long for a coordinator that restarts.
    #[arg(long, value_name = "S", default_value_t = 300.0, value_parser = crate::values::number)]
    wait_s: f64,
    /// This worker's name in the coordinator's log and the results (default: host, process id
    /// and zenoh id).
    #[arg(long, value_name = "NAME")]
    name: Option<String>,
    #[command(flatten)]
    net: NetArgs,
    /// Print only errors and the final line.
    #[arg(long, short)]
    quiet: bool,
}

/// The longest `--wait-s` (a day): longer is "forever", which is 0.
const MAX_WAIT_S: f64 = 86_400.0;

pub fn run(a: WorkerArgs) -> Result<()> {
    crate::output::stop_programs_on_ctrl_c();
    if a.connect.is_empty() && a.net.zenoh_config.is_none() {
        anyhow::bail!(
            "no coordinator to join: give --connect tcp/HOST:7447 (the endpoint of `floorcast run GRID --listen ...`) or a --zenoh-config that lists it"
        );
    }
    if !(0.0..=MAX_WAIT_S).contains(&a.wait_s) {
        anyhow::bail!(
            "--wait-s: expected seconds in [0, {MAX_WAIT_S}] (0: wait forever), got {}",
            floorcast_worker::settings::fmt_num(a.wait_s)
        );
    }
    let jobs = a.jobs.unwrap_or_else(crate::values::cores);
    crate::output::remove_stale_temp_dirs(a.quiet);
    let net = NetConfig {
        listen: Vec::new(),
        connect: a.connect.clone(),
        zenoh_config: a.net.zenoh_config.clone(),
        campaign: a.net.campaign.clone(),
    };
    let quiet = a.quiet;
    // A job's status and the coordinator's reply may quote a program's output.
    use floorcast_worker::text::shown;
    let events = move |e: WorkerEvent| {
        if quiet {
            return;
        }
        match e {
            WorkerEvent::Joined { worker } => {
                tell!("worker {worker}: connected, taking jobs ({jobs} at once)")
            }
            WorkerEvent::Started { job, what } => tell!("job {job}: {what}"),
            WorkerEvent::Finished {
                job,
                status,
                wall_time_s,
                reply,
            } => tell!(
                "job {job}: {} in {wall_time_s:.1} s, {}",
                status.as_str(),
                shown(&reply, 4000)
            ),
            WorkerEvent::Note(n) => tell!("note: {}", shown(&n, 4000)),
        }
    };
    let t0 = std::time::Instant::now();
    let link = join(&net, a.name.as_deref(), a.wait_s)?;
    // The time spent reaching the coordinator (or router) counts towards --wait-s.
    let wait_s = if a.wait_s > 0.0 {
        (a.wait_s - t0.elapsed().as_secs_f64()).max(1.0)
    } else {
        0.0
    };
    let report = run_worker(
        &link,
        &floorcast_coordinator::store::host_name(),
        WorkerOptions { jobs, wait_s },
        &execute_wire,
        &events,
    );
    link.leave();
    let report = report?;
    say!(
        "grid complete: this worker ran {} jobs ({} stored, {} duplicates, {} rejected)",
        report.jobs_run,
        report.stored,
        report.duplicates,
        report.rejected
    );
    Ok(())
}
