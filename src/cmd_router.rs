//! `floorcast router`: a zenoh router (`floorcast_coordinator::net::open_router`) that a
//! coordinator and its workers all connect to when they cannot reach each other directly, for
//! deployments without `zenohd`. It runs until it is stopped.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use floorcast_coordinator::net::{open_router, NetConfig};

#[derive(Debug, Args)]
#[command(after_long_help = "\
The coordinator and the workers connect to it:
  floorcast router --listen tcp/0.0.0.0:7447                       # router host R
  floorcast run GRID --connect tcp/R:7447 --workers 0              # coordinator
  floorcast worker --connect tcp/R:7447                            # each worker
It routes every campaign (--campaign of run and worker) and stores nothing. It prints one line \
saying where it listens, then runs until Ctrl-C, SIGTERM or SIGHUP (exit code 0) or kill.")]
pub struct RouterArgs {
    /// Endpoint to listen on, e.g. tcp/0.0.0.0:7447 (all addresses, port 7447; zenoh's default
    /// port) or tls/0.0.0.0:7447 with a --zenoh-config that sets the certificates
    /// (repeatable). No default: give at least one, here or in --zenoh-config.
    #[arg(long, value_name = "ENDPOINT")]
    listen: Vec<String>,
    /// Endpoint of another router to join, e.g. tcp/R2:7447 (repeatable; default: none).
    #[arg(long, value_name = "ENDPOINT")]
    connect: Vec<String>,
    /// A zenoh configuration file (JSON5 or YAML, at most 1 MiB) for TLS, mutual TLS,
    /// user/password or access control (docs/many-machines.md); its mode is overridden (this
    /// is a router). Endpoints given with --listen / --connect are added to it. Default: none
    /// (plain TCP, no multicast discovery, no gossip).
    #[arg(long, value_name = "FILE")]
    zenoh_config: Option<PathBuf>,
}

pub fn run(a: RouterArgs) -> Result<()> {
    if a.listen.is_empty() && a.zenoh_config.is_none() {
        anyhow::bail!(
            "no endpoint to listen on: give --listen tcp/0.0.0.0:7447 (or a --zenoh-config that lists one)"
        );
    }
    let cfg = NetConfig {
        listen: a.listen,
        connect: a.connect,
        zenoh_config: a.zenoh_config,
        campaign: "default".into(),
    };
    let (stop, stopped) = std::sync::mpsc::channel::<()>();
    // Ctrl-C, SIGTERM and SIGHUP (ctrlc's `termination` feature) close the router cleanly.
    ctrlc::set_handler(move || {
        let _ = stop.send(());
    })?;
    let router = open_router(&cfg)?;
    let mut line = format!(
        "router {} listening on {}",
        router.id(),
        router.listening().join(", ")
    );
    if !cfg.connect.is_empty() {
        line.push_str(&format!(", joined to {}", cfg.connect.join(", ")));
    }
    if let Some(p) = &cfg.zenoh_config {
        line.push_str(&format!(" (zenoh config {})", p.display()));
    }
    say!("{line}; connect the coordinator (`floorcast run GRID --connect ENDPOINT --workers 0`) and the workers (`floorcast worker --connect ENDPOINT`) to it");
    let _ = stopped.recv();
    router.close();
    tell!("router stopped");
    Ok(())
}
