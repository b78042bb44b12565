//! The private folders strategy programs need (floorcast's Python module, a remote job's
//! program files), and those left behind by a floorcast process that was killed.
//!
//! [`private_temp_dir`] makes each folder under a name no one else chose (mode 0700) and writes
//! its owner into it ([`OWNER_FILE`]: process id, the process's start time and the boot id). A
//! process killed with SIGKILL cannot remove its folders; [`remove_stale_temp_dirs`], called
//! when `floorcast run` and `floorcast worker` start, removes the folders of owners that are no
//! longer alive. A folder is removed only when its owner is known dead: the machine rebooted
//! since (another boot id), no process has its id, or the process with its id started at
//! another time (the id was reused). A folder without an owner file (being made, or made by an
//! earlier floorcast) or whose owner cannot be checked (no `/proc`) is left alone.

use std::path::Path;

/// The prefixes of floorcast's private folders in the temporary directory.
pub const TEMP_PREFIXES: [&str; 2] = ["floorcast-job-", "floorcast-python-"];

/// The file in each private folder that names its owner.
pub(crate) const OWNER_FILE: &str = ".floorcast-owner";

/// The first line of an owner file (its format and version).
const OWNER_HEADER: &str = "floorcast-temp-owner 1";

/// A new folder of this process's own in the temporary directory (`TMPDIR`): a name no one
/// else chose, mode 0700, removed when dropped, its owner written into it ([`OWNER_FILE`]). A
/// folder with a name known in advance could be made first by another user, with modules of
/// theirs that our programs would import.
pub fn private_temp_dir(prefix: &str) -> Result<tempfile::TempDir, String> {
    use std::os::unix::fs::PermissionsExt;
    let tmp = std::env::temp_dir();
    let dir = tempfile::Builder::new()
        .prefix(prefix)
        .permissions(std::fs::Permissions::from_mode(0o700))
        .tempdir_in(&tmp)
        .map_err(|e| {
            format!(
                "cannot create a folder in the temporary directory {} ({e}); set TMPDIR to a directory you can write",
                tmp.display()
            )
        })?;
    let owner = dir.path().join(OWNER_FILE);
    std::fs::write(&owner, owner_text(&Owner::this_process())).map_err(|e| {
        format!(
            "cannot write {} ({e}); set TMPDIR to a directory you can write",
            owner.display()
        )
    })?;
    Ok(dir)
}

/// Who made a folder: a process, when it started (clock ticks since boot, `/proc/PID/stat`'s
/// field 22; none where there is no `/proc`) and the boot it ran in.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Owner {
    pid: u32,
    start_ticks: Option<u64>,
    boot_id: Option<String>,
}

impl Owner {
    fn this_process() -> Owner {
        let pid = std::process::id();
        Owner {
            pid,
            start_ticks: start_ticks(pid),
            boot_id: boot_id(),
        }
    }
}

fn owner_text(o: &Owner) -> String {
    let mut text = format!("{OWNER_HEADER}\npid {}\n", o.pid);
    if let Some(t) = o.start_ticks {
        text.push_str(&format!("start {t}\n"));
    }
    if let Some(b) = &o.boot_id {
        text.push_str(&format!("boot {b}\n"));
    }
    text
}

/// An owner file read back (`None`: not one this version wrote).
fn parse_owner(text: &str) -> Option<Owner> {
    let mut lines = text.lines();
    if lines.next()? != OWNER_HEADER {
        return None;
    }
    let mut owner = Owner {
        pid: 0,
        start_ticks: None,
        boot_id: None,
    };
    for line in lines {
        let (key, value) = line.split_once(' ')?;
        match key {
            "pid" => owner.pid = value.parse().ok()?,
            "start" => owner.start_ticks = Some(value.parse().ok()?),
            "boot" => owner.boot_id = Some(value.to_string()),
            _ => return None,
        }
    }
    (owner.pid > 0).then_some(owner)
}

/// When process `pid` started, in clock ticks since boot (`None`: no such process, or no
/// `/proc`).
fn start_ticks(pid: u32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command name (field 2) is in parentheses and may hold spaces or parentheses: the
    // fields are counted after its last ')', from field 3.
    let rest = &stat[stat.rfind(')')? + 1..];
    rest.split_whitespace().nth(19)?.parse().ok()
}

fn boot_id() -> Option<String> {
    std::fs::read_to_string("/proc/sys/kernel/random/boot_id")
        .ok()
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
}

/// Whether `owner` is known to be dead. Unknown (no `/proc`, nothing to compare) is alive.
fn dead(owner: &Owner) -> bool {
    if start_ticks(std::process::id()).is_none() {
        // No /proc here: nothing can be checked.
        return false;
    }
    if let (Some(then), Some(now)) = (&owner.boot_id, boot_id()) {
        if *then != now {
            return true;
        }
    }
    match (owner.start_ticks, start_ticks(owner.pid)) {
        // No process has its id.
        (_, None) => !Path::new(&format!("/proc/{}", owner.pid)).exists(),
        // Its id is another process's now.
        (Some(then), Some(now)) => then != now,
        (None, Some(_)) => false,
    }
}

/// Removes, from the temporary directory (`TMPDIR`), floorcast's private folders whose owner
/// is dead; returns how many were removed. Folders of live processes, of other users, without
/// an owner file, and anything else are left alone; a folder that cannot be removed is skipped.
pub fn remove_stale_temp_dirs() -> usize {
    remove_stale_temp_dirs_in(&std::env::temp_dir())
}

/// [`remove_stale_temp_dirs`] in `tmp`.
pub fn remove_stale_temp_dirs_in(tmp: &Path) -> usize {
    use std::os::unix::fs::MetadataExt;
    let Ok(entries) = std::fs::read_dir(tmp) else {
        return 0;
    };
    // This process's user (the owner of its /proc entry): only our own folders are looked at.
    let Ok(me) = std::fs::metadata("/proc/self").map(|m| m.uid()) else {
        return 0;
    };
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if !TEMP_PREFIXES.iter().any(|p| name.starts_with(p)) {
            continue;
        }
        let path = entry.path();
        // Not followed: a link is not a folder of ours.
        match std::fs::symlink_metadata(&path) {
            Ok(m) if m.is_dir() && m.uid() == me => {}
            _ => continue,
        }
        let owner = std::fs::read_to_string(path.join(OWNER_FILE))
            .ok()
            .and_then(|t| parse_owner(&t));
        if owner.is_some_and(|o| dead(&o)) && std::fs::remove_dir_all(&path).is_ok() {
            removed += 1;
        }
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Folders of dead owners go (the process gone, its id reused, another boot); those of a
    /// live owner, without an owner file, with one floorcast did not write, of another name,
    /// and files stay.
    #[test]
    fn only_folders_of_dead_owners_are_removed() {
        let tmp = tempfile::tempdir().unwrap();
        let me = Owner::this_process();
        assert!(me.start_ticks.is_some(), "this test needs Linux's /proc");
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let gone = child.id();
        child.wait().unwrap();
        let dead_child = Owner {
            pid: gone,
            ..me.clone()
        };
        let reused = Owner {
            start_ticks: me.start_ticks.map(|t| t + 1),
            ..me.clone()
        };
        let rebooted = Owner {
            boot_id: Some("another-boot".into()),
            ..me.clone()
        };
        // (name, owner file's text, a file rather than a folder, removed)
        let cases: Vec<(&str, Option<String>, bool, bool)> = vec![
            ("floorcast-job-live", Some(owner_text(&me)), false, false),
            ("floorcast-python-live", Some(owner_text(&me)), false, false),
            (
                "floorcast-job-dead",
                Some(owner_text(&dead_child)),
                false,
                true,
            ),
            (
                "floorcast-python-dead",
                Some(owner_text(&dead_child)),
                false,
                true,
            ),
            (
                "floorcast-job-reused",
                Some(owner_text(&reused)),
                false,
                true,
            ),
            (
                "floorcast-job-rebooted",
                Some(owner_text(&rebooted)),
                false,
                true,
            ),
            ("floorcast-job-unmarked", None, false, false),
            (
                "floorcast-job-foreign",
                Some("pid 1\n".into()),
                false,
                false,
            ),
            ("other-dead", Some(owner_text(&dead_child)), false, false),
            ("floorcast-job-file", None, true, false),
        ];
        for (name, owner, file, _) in &cases {
            let path = tmp.path().join(name);
            if *file {
                std::fs::write(&path, "x").unwrap();
                continue;
            }
            std::fs::create_dir(&path).unwrap();
            std::fs::write(path.join("floorcast_strategy.py"), "x").unwrap();
            if let Some(text) = owner {
                std::fs::write(path.join(OWNER_FILE), text).unwrap();
            }
        }
        let removed = remove_stale_temp_dirs_in(tmp.path());
        for (name, _, _, gone) in &cases {
            assert_eq!(
                !tmp.path().join(name).exists(),
                *gone,
                "{name}: removed should be {gone}"
            );
        }
        assert_eq!(removed, cases.iter().filter(|c| c.3).count());
    }

    /// A private folder names its owner, this process, which is alive.
    #[test]
    fn a_private_folder_names_its_live_owner() {
        let dir = private_temp_dir("floorcast-job-").unwrap();
        let text = std::fs::read_to_string(dir.path().join(OWNER_FILE)).unwrap();
        let owner = parse_owner(&text).unwrap();
        assert_eq!(owner, Owner::this_process());
        assert!(!dead(&owner));
        assert_eq!(parse_owner(&owner_text(&owner)), Some(owner));
    }
}
