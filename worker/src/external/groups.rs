//! Process groups of the programs running now, and the strays they leave: every process a
//! program starts is ended with it ([`kill_group`], [`end_strays`]), and a floorcast that must
//! stop at once kills them all ([`kill_all_programs`]).

use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Makes floorcast the reaper of its orphaned descendants (Linux's child subreaper): a process a
/// strategy program started in a session or process group of its own (`setsid`, a daemon) is
/// no longer ended with the program's group, but when its parent ends it becomes floorcast's
/// child instead of init's, and `end_strays` finds it. Called once at start.
pub fn adopt_orphans() {
    let _ = nix::sys::prctl::set_child_subreaper(true);
}

/// Ends (SIGKILL) and reaps every stray: a process that became floorcast's child by its parent
/// ending ([`adopt_orphans`]), in a process group of neither floorcast nor a program running
/// now, with the group it leads. Done after every program's end; returns how many it ended
/// (ended strays not yet reaped are reaped, not counted).
pub fn end_strays() -> usize {
    let me = std::process::id();
    let my_group = nix::unistd::getpgrp().as_raw() as u32;
    let mut ended = 0;
    // A stray's children become strays when it ends: a few rounds find them.
    for _ in 0..10 {
        let found = live_groups(|live| {
            let mut found = 0;
            for (pid, state, group) in children_of(me) {
                if group == my_group || live.contains(&group) || live.contains(&pid) {
                    continue;
                }
                let target = nix::unistd::Pid::from_raw(pid as i32);
                if state != 'Z' {
                    kill_group(group);
                    let _ = nix::sys::signal::kill(target, nix::sys::signal::Signal::SIGKILL);
                    found += 1;
                }
                let _ = nix::sys::wait::waitpid(target, None);
            }
            found
        });
        ended += found;
        if found == 0 {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    ended
}

/// The children of process `parent` (pid, state, process group), from `/proc` (none without it).
fn children_of(parent: u32) -> Vec<(u32, char, u32)> {
    processes()
        .unwrap_or_default()
        .into_iter()
        .filter(|p| p.parent == parent)
        .map(|p| (p.pid, p.state, p.group))
        .collect()
}

/// A process as `/proc/<pid>/stat` describes it.
struct ProcessStat {
    pid: u32,
    state: char,
    parent: u32,
    group: u32,
}

/// Every process of the system, from `/proc` (`None` without it).
fn processes() -> Option<Vec<ProcessStat>> {
    let mut out = Vec::new();
    for e in std::fs::read_dir("/proc").ok()?.flatten() {
        let Ok(pid) = e.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        let Ok(stat) = std::fs::read_to_string(e.path().join("stat")) else {
            continue;
        };
        // "pid (comm) state ppid pgrp ...": the name may hold spaces and parentheses.
        let Some((_, rest)) = stat.rsplit_once(')') else {
            continue;
        };
        let fields: Vec<&str> = rest.split_whitespace().take(3).collect();
        if let [state, parent, group] = fields[..] {
            if let (Some(state), Ok(parent), Ok(group)) =
                (state.chars().next(), parent.parse(), group.parse())
            {
                out.push(ProcessStat {
                    pid,
                    state,
                    parent,
                    group,
                });
            }
        }
    }
    Some(out)
}

/// The process groups of the programs running now (each program's group is its process id).
pub(super) fn live_groups<T>(f: impl FnOnce(&mut std::collections::BTreeSet<u32>) -> T) -> T {
    static GROUPS: Mutex<std::collections::BTreeSet<u32>> =
        Mutex::new(std::collections::BTreeSet::new());
    f(&mut GROUPS.lock().unwrap_or_else(|e| e.into_inner()))
}

/// Set when floorcast is being stopped ([`kill_all_programs`]).
static STOPPING: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether floorcast is being stopped by a signal (its programs killed): an error that follows
/// (a program's pipe closed) is the stop's doing, and the stop's handler sets the exit code.
pub fn stopping() -> bool {
    STOPPING.load(std::sync::atomic::Ordering::SeqCst)
}

/// Kills every process of every program running now, for a floorcast that must stop at once
/// (a second Ctrl-C): the programs' process groups do not get the terminal's signals.
pub fn kill_all_programs() {
    STOPPING.store(true, std::sync::atomic::Ordering::SeqCst);
    for g in live_groups(std::mem::take) {
        kill_group(g);
    }
    end_strays();
}

/// Kills (SIGKILL) every process of the process group `pgid`, a program's.
pub(super) fn kill_group(pgid: u32) {
    if let Ok(pgid) = i32::try_from(pgid) {
        let _ = nix::sys::signal::killpg(
            nix::unistd::Pid::from_raw(pgid),
            nix::sys::signal::Signal::SIGKILL,
        );
    }
}

/// Whether a process of the group `pgid` is still running after its leader (the program)
/// ended, waiting up to 200 ms for processes on their way out. Ended processes not yet reaped
/// (zombies) do not count; without `/proc`, whether the group has any process.
pub(super) fn group_alive(pgid: u32) -> bool {
    let deadline = Instant::now() + Duration::from_millis(200);
    loop {
        let alive = match running_in_group(pgid) {
            Some(n) => n > 0,
            None => i32::try_from(pgid).is_ok_and(|p| {
                nix::sys::signal::killpg(nix::unistd::Pid::from_raw(p), None).is_ok()
            }),
        };
        if !alive || Instant::now() >= deadline {
            return alive;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// How many processes of the group `pgid` run (zombies aside), from `/proc` (`None` without it).
fn running_in_group(pgid: u32) -> Option<usize> {
    Some(
        processes()?
            .iter()
            .filter(|p| p.state != 'Z' && p.group == pgid)
            .count(),
    )
}
