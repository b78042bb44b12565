//! The cluster recipes of `examples/clusters/` (docs/clusters.md) are what floorcast accepts:
//! every floorcast command line in them is run as written, with `--help` appended (its
//! subcommand and options parse; nothing connects), the Slurm script through bash with a
//! `floorcast` on `PATH` that does so, the systemd unit's `ExecStart`, and the Kubernetes
//! workers' arguments under the Dockerfile's entry point.

mod common;

use std::path::Path;

use common::*;

fn recipe(name: &str) -> String {
    std::fs::read_to_string(repo().join("examples/clusters").join(name))
        .unwrap_or_else(|e| panic!("examples/clusters/{name}: {e}"))
}

/// Runs floorcast with `args` and `--help`: it must succeed and print the subcommand's help.
fn parses(what: &str, args: &[String]) {
    let mut all: Vec<&str> = args.iter().map(String::as_str).collect();
    all.push("--help");
    let o = run(&all);
    assert!(o.status.success(), "{what}: {args:?}: {}", stderr(&o));
    assert!(
        stdout(&o).contains("Usage: floorcast"),
        "{what}: {}",
        stdout(&o)
    );
}

/// The Slurm array script, run by bash as a node would run it, with Slurm's variables set and
/// a `floorcast` that appends `--help`; its #SBATCH lines ask for what a worker needs.
#[test]
fn the_slurm_script_starts_a_worker() {
    let text = recipe("slurm-workers.sbatch");
    for line in [
        "#SBATCH --array=",
        "#SBATCH --cpus-per-task=",
        "#SBATCH --mem-per-cpu=",
    ] {
        assert!(text.contains(line), "{line}");
    }
    let dir = tempfile::tempdir().unwrap();
    let shim = dir.path().join("floorcast");
    std::fs::write(
        &shim,
        format!(
            "#!/bin/sh\nexec '{}' \"$@\" --help\n",
            env!("CARGO_BIN_EXE_floorcast")
        ),
    )
    .unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&shim, std::fs::Permissions::from_mode(0o755)).unwrap();
    let path = format!(
        "{}:{}",
        dir.path().display(),
        std::env::var("PATH").unwrap()
    );
    let script = repo().join("examples/clusters/slurm-workers.sbatch");
    let o = std::process::Command::new("bash")
        .arg(&script)
        .env("PATH", &path)
        .env("FLOORCAST_AT", "tcp/login1:7447")
        .env("SLURM_CPUS_PER_TASK", "8")
        .env("SLURM_ARRAY_JOB_ID", "42")
        .env("SLURM_ARRAY_TASK_ID", "3")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("Join a grid run elsewhere"),
        "{}",
        stdout(&o)
    );
    // Without the endpoint it says what to set, and starts nothing.
    let o = std::process::Command::new("bash")
        .arg(&script)
        .env("PATH", &path)
        .env_remove("FLOORCAST_AT")
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(stderr(&o).contains("set FLOORCAST_AT"), "{}", stderr(&o));
}

/// The systemd unit's ExecStart (its `%H` as systemd expands it) names floorcast's worker.
#[test]
fn the_systemd_unit_starts_a_worker() {
    let text = recipe("floorcast-worker.service");
    for section in ["[Unit]", "[Service]", "[Install]"] {
        assert!(text.contains(section), "{section}");
    }
    let exec = text
        .lines()
        .find_map(|l| l.strip_prefix("ExecStart="))
        .expect("an ExecStart line");
    let words: Vec<String> = exec
        .replace("%H", "node7")
        .split_whitespace()
        .map(String::from)
        .collect();
    assert!(Path::new(&words[0]).ends_with("floorcast"), "{exec}");
    assert_eq!(words[1], "worker", "{exec}");
    parses("ExecStart", &words[1..]);
}

/// Every document of the Kubernetes file is an object with its kind; the workers' container
/// arguments, under the Dockerfile's `ENTRYPOINT ["floorcast"]`, are a floorcast worker
/// connecting to the router's Service.
#[test]
fn the_kubernetes_workers_connect_to_the_router() {
    let docker = recipe("Dockerfile");
    assert!(docker.contains("ENTRYPOINT [\"floorcast\"]"), "{docker}");
    let text = recipe("kubernetes.yaml");
    let mut kinds = Vec::new();
    let mut workers = 0;
    for doc in serde_yaml_ng::Deserializer::from_str(&text) {
        let v: serde_json::Value = serde::Deserialize::deserialize(doc).expect("a YAML document");
        let kind = v["kind"].as_str().expect("a kind").to_string();
        let name = v["metadata"]["name"].as_str().expect("a name").to_string();
        kinds.push(format!("{kind}/{name}"));
        for c in v["spec"]["template"]["spec"]["containers"]
            .as_array()
            .into_iter()
            .flatten()
        {
            let image = c["image"].as_str().unwrap();
            if image.starts_with("eclipse/zenoh") {
                continue;
            }
            let args: Vec<String> = c["args"]
                .as_array()
                .expect("args")
                .iter()
                .map(|a| a.as_str().unwrap().to_string())
                .collect();
            assert_eq!(args[0], "worker");
            assert!(
                args.contains(&"tcp/floorcast-router:7447".to_string()),
                "{args:?}"
            );
            parses(&name, &args);
            workers += 1;
        }
    }
    assert_eq!(
        kinds,
        [
            "Deployment/floorcast-router",
            "Service/floorcast-router",
            "Deployment/floorcast-workers"
        ]
    );
    assert_eq!(workers, 1);
}
