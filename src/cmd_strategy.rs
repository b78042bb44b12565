//! `floorcast strategy`: tools for external strategies (the strategy protocol).

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use floorcast_worker::external::{check_program, DEFAULT_TIMEOUT_S};
use floorcast_worker::{run_job, Job, Settings, StrategyProgram, StrategyRef};

#[derive(Debug, Subcommand)]
pub enum StrategyCommand {
    /// Check that a program keeps to the strategy protocol (docs/strategy-protocol.md): a
    /// scripted session through every message and rule, then a real exploration with it.
    /// Prints each check; exits 2 at the first the program fails.
    Check(CheckArgs),
    /// List the built-in strategies: how each estimates the information gain I(p) and when it
    /// stops (the README's table).
    List(ListArgs),
}

#[derive(Debug, Args)]
pub struct ListArgs {
    /// Print the list as the markdown table of the README.
    #[arg(long, conflicts_with_all = ["json", "settings_markdown"])]
    markdown: bool,
    /// Print the settings each strategy reads, with their defaults, as the markdown table of
    /// docs/settings.md.
    #[arg(long, conflicts_with = "json")]
    settings_markdown: bool,
    /// Print the list as JSON: per strategy its name, gain, stop, citation and the settings it
    /// reads with their defaults (those of the layout's use without a value: the run's).
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct CheckArgs {
    /// The program, e.g. "python3 my_strategy.py" (split into words as a shell splits them).
    #[arg(value_name = "COMMAND")]
    command: String,
    /// Seconds the program has for each reply, 0.01 to 3600.
    #[arg(long, value_name = "SECONDS", default_value_t = DEFAULT_TIMEOUT_S, value_parser = crate::values::number)]
    strategy_timeout_s: f64,
    /// The program's own parameters, a JSON object (at most 64 KiB), e.g. '{"stop_below_m2":
    /// 5}': sent in the run messages of the check and of its exploration (in protocol 2 the
    /// needs of the program's ready reply may depend on them).
    #[arg(long, value_name = "JSON")]
    strategy_params: Option<String>,
    /// Building of the exploration (default: a generated school of about 400 m2, seed 1).
    #[arg(long, value_name = "FILE")]
    building: Option<PathBuf>,
    /// Simulated seconds the exploration may take, 1 to 100000.
    #[arg(long, value_name = "SECONDS", default_value_t = 1800.0, value_parser = crate::values::number)]
    time_limit_s: f64,
}

pub fn run(c: StrategyCommand) -> Result<()> {
    match c {
        StrategyCommand::Check(a) => check(a),
        StrategyCommand::List(a) => {
            list(&a);
            Ok(())
        }
    }
}

fn list(a: &ListArgs) {
    use sim_core::explore::strategies::{strategies_markdown, BUILT_IN};
    if a.markdown {
        say_raw!("{}", strategies_markdown());
        return;
    }
    if a.settings_markdown {
        say_raw!(
            "{}",
            floorcast_worker::settings::strategy_settings_markdown()
        );
        return;
    }
    if a.json {
        say_raw!("{}\n", strategies_json());
        return;
    }
    let width = BUILT_IN.iter().map(|b| b.name.len()).max().unwrap_or(0);
    for b in BUILT_IN {
        let gain = b.gain_cited().replace('`', "");
        let stops = b.stops.replace('`', "");
        say_raw!("{:width$}  I(p): {gain}; stops: {stops}\n", b.name);
    }
}

/// `strategy list --json`: the built-in strategies with the default settings' parameters.
fn strategies_json() -> String {
    use sim_core::explore::strategies::BUILT_IN;
    let params = Settings::default().strategy_params();
    let list: Vec<serde_json::Value> = BUILT_IN
        .iter()
        .map(|b| {
            let strategy = (b.make)(&params);
            let parameters: Vec<serde_json::Value> = strategy
                .parameters()
                .into_iter()
                .map(|(name, default)| serde_json::json!({"setting": name, "default": default}))
                .collect();
            serde_json::json!({
                "name": b.name,
                "gain": b.gain.replace('`', ""),
                "stops": b.stops.replace('`', ""),
                "citation": b.citation,
                "parameters": parameters,
            })
        })
        .collect();
    serde_json::to_string_pretty(&serde_json::json!({
        "format": "floorcast-strategies",
        "version": 1,
        "strategies": list,
    }))
    .expect("the list encodes")
}

fn check(a: CheckArgs) -> Result<()> {
    crate::output::stop_programs_on_ctrl_c();
    let program = StrategyProgram::from_command_line(
        &a.command,
        std::path::Path::new("."),
        a.strategy_timeout_s,
    )
    .map_err(|e| anyhow::anyhow!("{e}"))?;
    let program = match &a.strategy_params {
        Some(text) => program
            .with_params(crate::cmd_explore::strategy_params(text)?)
            .map_err(|e| anyhow::anyhow!("--strategy-params: {e}"))?,
        None => program,
    };
    let shown = program.display();
    let mut failed = None;
    let (checks, protocol) = check_program(&program);
    for c in checks {
        match &c.outcome {
            Ok(what) => say!("ok    {}: {what}", c.what),
            Err(what) => {
                say!("FAIL  {}: {what}", c.what);
                failed = Some(format!(
                    "strategy '{shown}' fails the check '{}': {what}",
                    c.what
                ));
            }
        }
    }
    if let Some(f) = failed {
        anyhow::bail!(f);
    }
    let (building, name) = match &a.building {
        Some(p) => (
            floorcast_formats::read_building(p)?,
            p.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
        ),
        None => (
            sim_core::generate::generate(&sim_core::generate::GenerateConfig {
                seed: 1,
                area_m2: 400.0,
                name: "check".into(),
                ..Default::default()
            }),
            "a generated school of 400 m2".to_string(),
        ),
    };
    let job = Job {
        building: &building,
        building_name: name.clone(),
        strategy: StrategyRef::External {
            label: "check".into(),
            program,
        },
        seed: 1,
        settings: Settings {
            time_limit_s: a.time_limit_s,
            ..Settings::default()
        },
        start: None,
        snapshot_fractions: Vec::new(),
    };
    job.settings
        .validate()
        .map_err(|e| anyhow::anyhow!("--time-limit-s: {e}"))?;
    let out = run_job(&job, &mut |_| {}).with_context(|| {
        say!("FAIL  explore {name}");
        format!("strategy '{shown}' fails the check 'explore'")
    })?;
    let s = &out.summary;
    let replies = s.strategy_replies.unwrap_or(0);
    say!(
        "ok    explore {name}: {} after {:.0} s simulated, {:.1} % explored, {} decisions, {} replies, {:.2} ms per reply",
        s.end_reason,
        s.exploration_time_s,
        s.explored_fraction * 100.0,
        s.decisions,
        replies,
        s.strategy_compute_s.unwrap_or(0.0) * 1000.0 / replies.max(1) as f64
    );
    say!(
        "strategy '{shown}' keeps to the strategy protocol version {}",
        protocol.unwrap_or_default()
    );
    Ok(())
}
