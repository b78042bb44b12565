//! Embeds what the binary was built from, for the provenance `run` records and `--version`:
//! floorcast's own commit (`git rev-parse HEAD` in this crate's folder, "unknown" when it is not
//! built from a git checkout), whether its code differed from that commit (`git status` of the
//! folders the binary is built from), and the build profile.
//!
//! Cheap: it runs again only when HEAD, the branch's ref, the index or a file of those folders
//! changes (a change that rebuilds the binary anyway), never on every build.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The folders and files the binary is built from (relative to this crate's folder): a change
/// in one of them rebuilds it, and makes the build "dirty" until committed.
const SOURCES: [&str; 10] = [
    "src",
    "sim-core",
    "formats",
    "worker",
    "coordinator",
    "render",
    "python",
    "Cargo.toml",
    "Cargo.lock",
    "build.rs",
];

fn git(dir: &Path, args: &[&str]) -> Option<String> {
    Command::new("git")
        .arg("-C")
        .arg(dir)
        .args(args)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
}

fn main() {
    let dir = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap_or_else(|_| ".".into()));
    println!("cargo:rerun-if-changed=build.rs");
    let profile = std::env::var("PROFILE").unwrap_or_else(|_| "unknown".into());
    println!("cargo:rustc-env=FLOORCAST_BUILD_PROFILE={profile}");
    // The repository must be floorcast's own, rooted here: a source tree unpacked inside
    // another repository is not built from that repository's commit.
    let rooted_here = git(&dir, &["rev-parse", "--show-toplevel"])
        .and_then(|top| std::fs::canonicalize(top).ok())
        .is_some_and(|top| std::fs::canonicalize(&dir).is_ok_and(|d| d == top));
    let commit = git(&dir, &["rev-parse", "HEAD"])
        .filter(|c| rooted_here && c.len() == 40 && c.bytes().all(|b| b.is_ascii_hexdigit()));
    let Some(commit) = commit else {
        println!("cargo:rustc-env=FLOORCAST_GIT_COMMIT=unknown");
        println!("cargo:rustc-env=FLOORCAST_GIT_DIRTY=false");
        return;
    };
    let mut status = vec!["status", "--porcelain", "--untracked-files=no", "--"];
    status.extend(SOURCES);
    let dirty = git(&dir, &status).is_some_and(|s| !s.is_empty());
    println!("cargo:rustc-env=FLOORCAST_GIT_COMMIT={commit}");
    println!("cargo:rustc-env=FLOORCAST_GIT_DIRTY={dirty}");
    // What makes it run again: HEAD (a checkout), the branch's ref (a commit), packed refs, the
    // index (git add), and the sources (a change to a file). Only files that exist are named:
    // cargo would run the script at every build for a missing one.
    let mut watched: Vec<PathBuf> = Vec::new();
    let mut git_path = |name: &str| {
        if let Some(p) = git(&dir, &["rev-parse", "--git-path", name]) {
            let p = dir.join(p);
            watched.push(p);
        }
    };
    git_path("HEAD");
    git_path("index");
    git_path("packed-refs");
    if let Some(head_ref) = git(&dir, &["symbolic-ref", "-q", "HEAD"]) {
        git_path(&head_ref);
    }
    watched.extend(SOURCES.iter().map(|s| dir.join(s)));
    for p in watched.iter().filter(|p| p.exists()) {
        println!("cargo:rerun-if-changed={}", p.display());
    }
}
