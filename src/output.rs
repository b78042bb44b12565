//! Small helpers for writing outputs and showing progress.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};

/// Creates `dir` (and parents), with a message naming it on failure.
/// The picture format of a run's maps (`--picture`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Picture {
    Png,
    Svg,
}

impl Picture {
    /// The file extension, which also chooses the encoder.
    pub fn extension(self) -> &'static str {
        match self {
            Picture::Png => "png",
            Picture::Svg => "svg",
        }
    }
}

pub fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create directory {}", dir.display()))
}

/// Writes a text file, naming it on failure ([`write_bytes`]).
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    write_bytes(path, text.as_bytes())
}

/// Writes a file the one way floorcast writes every output file it names (docs/limits.md,
/// "Output paths"): a symbolic link is written through to its target (the link stays); a
/// device, FIFO or socket (`/dev/stdout`, `/dev/null`, a named pipe) is written directly; a
/// regular file (or none yet) is written whole or not at all, into a new file beside it (beside
/// the link's target) renamed over it at the end, so that a failed write leaves the old file as
/// it was. Which paths a command may write is [`Paths::check`]'s part, before anything is
/// written.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    use std::io::Write;
    let failed = |e: std::io::Error| {
        anyhow::Error::new(e).context(format!("cannot write {}", path.display()))
    };
    if let Ok(m) = std::fs::metadata(path) {
        if !m.is_file() && !m.is_dir() {
            // Written directly: no file beside it, and the link (/dev/stdout) left alone.
            let mut f = std::fs::OpenOptions::new()
                .write(true)
                .open(path)
                .map_err(failed)?;
            return f.write_all(bytes).and_then(|_| f.flush()).map_err(failed);
        }
    }
    let target = floorcast_coordinator::store::resolved(path).ok_or_else(|| {
        anyhow::anyhow!(
            "cannot write {}: its folder does not exist (or the link leads nowhere); create the folder or give another path",
            path.display()
        )
    })?;
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mode = std::fs::metadata(&target)
        .map(|m| std::os::unix::fs::PermissionsExt::mode(&m.permissions()))
        .unwrap_or(0o644);
    let mut tmp = tempfile::Builder::new()
        .prefix(&format!(
            ".{}.part-",
            target
                .file_name()
                .map(|n| n.to_string_lossy())
                .unwrap_or_default()
        ))
        .permissions(std::os::unix::fs::PermissionsExt::from_mode(mode & 0o777))
        .tempfile_in(dir)
        .map_err(failed)?;
    tmp.write_all(bytes)
        .and_then(|_| tmp.as_file().sync_all())
        .map_err(failed)?;
    tmp.persist(&target).map_err(|e| failed(e.error))?;
    Ok(())
}

/// Draws `fig` to `path` (SVG, PNG or PDF by its extension) as [`write_bytes`] writes.
pub fn save_figure(fig: &floorcast_render::Figure, path: &Path) -> Result<()> {
    let bytes = fig.encode_for(path)?;
    write_bytes(path, &bytes)
}

/// What one command reads and writes, checked against the one rule for output paths before
/// anything is written (docs/limits.md, "Output paths"): no output is a file the command reads
/// (a building, grid, settings file, import, a results store or a file of it: SQLite's files and
/// the lock), whatever its spelling (relative, `..`, symbolic or hard links); no two outputs
/// are the same file. An output that is a device (`/dev/stdout`) is compared with the other
/// outputs only: writing one destroys no input.
#[derive(Debug, Default)]
pub struct Paths {
    reads: Vec<(String, PathBuf)>,
    stores: Vec<(String, PathBuf)>,
    writes: Vec<(String, PathBuf)>,
}

impl Paths {
    pub fn new() -> Paths {
        Paths::default()
    }

    /// A file the command reads; `what` names it in a refusal (`--building`, `the grid`).
    pub fn read(&mut self, what: &str, path: Option<&Path>) -> &mut Paths {
        if let Some(p) = path {
            self.reads.push((what.to_string(), p.to_path_buf()));
        }
        self
    }

    /// A results directory the command reads or writes: its store, SQLite's files beside it and
    /// its lock ([`floorcast_coordinator::store::OWNED_FILES`]).
    pub fn store(&mut self, what: &str, dir: Option<&Path>) -> &mut Paths {
        if let Some(d) = dir {
            self.stores.push((what.to_string(), d.to_path_buf()));
        }
        self
    }

    /// A file the command writes, given by `flag` (`--json`).
    pub fn write(&mut self, flag: &str, path: Option<&Path>) -> &mut Paths {
        if let Some(p) = path {
            self.writes.push((flag.to_string(), p.to_path_buf()));
        }
        self
    }

    /// Refuses, naming the flag, the path and the file it would overwrite, any output the rule
    /// forbids. Nothing is written.
    pub fn check(&self) -> Result<()> {
        use floorcast_coordinator::store::{refuse_owned, same_file};
        for (i, (flag, out)) in self.writes.iter().enumerate() {
            for (what, dir) in &self.stores {
                refuse_owned(flag, Some(out), dir).map_err(|e| anyhow::anyhow!("{e} ({what})"))?;
            }
            let device = std::fs::metadata(out).is_ok_and(|m| !m.is_file() && !m.is_dir());
            if !device {
                if let Some((what, input)) = self.reads.iter().find(|(_, r)| same_file(out, r)) {
                    anyhow::bail!(
                        "{flag}: {} is {} ({what}), which this command reads; writing there would destroy it: give another path",
                        out.display(),
                        input.display()
                    );
                }
            }
            if let Some((other, _)) = self.writes[..i].iter().find(|(_, o)| same_file(out, o)) {
                anyhow::bail!(
                    "{other} and {flag} are the same file ({}): one would overwrite the other; give each its own path",
                    out.display()
                );
            }
        }
        Ok(())
    }
}

/// A progress bar on stderr, hidden when `quiet` or when stderr is not a terminal.
pub fn progress_bar(len: u64, quiet: bool, template: &str) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(len);
    if let Ok(style) = ProgressStyle::with_template(template) {
        pb.set_style(style.progress_chars("=> "));
    }
    pb
}

/// Parses "x,y,theta" into its three finite numbers as written (metres, metres, degrees).
pub fn parse_pose_deg(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!(
            "expected x,y,theta (metres, metres, degrees), got '{s}'"
        ));
    }
    let mut v = [0.0; 3];
    for (i, p) in parts.iter().enumerate() {
        v[i] = p
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("'{p}' in '{s}' is not a finite number (expected x,y,theta)"))?;
    }
    Ok(v)
}

/// Ctrl-C ends floorcast at once (exit code 130) and every strategy program with everything it
/// started: each runs in a process group of its own, which the terminal's signal does not reach.
/// An `explore` stopped so leaves no output either: its staging folder and the `--out` it made
/// go ([`StagedOut`]).
pub fn stop_programs_on_ctrl_c() {
    let _ = ctrlc::set_handler(|| {
        floorcast_worker::external::kill_all_programs();
        for (staging, made) in staged(std::mem::take) {
            let _ = std::fs::remove_dir_all(staging);
            if let Some(out) = made {
                let _ = std::fs::remove_dir(out);
            }
        }
        std::process::exit(130);
    });
}

/// Removes the private folders (`floorcast-job-*`, `floorcast-python-*`) that floorcast
/// processes killed on this machine left in the temporary directory, saying so unless `quiet`
/// (`floorcast_worker::external::remove_stale_temp_dirs`: never a live process's).
pub fn remove_stale_temp_dirs(quiet: bool) {
    let n = floorcast_worker::external::remove_stale_temp_dirs();
    if n > 0 && !quiet {
        tell_fmt(format_args!(
            "removed {n} temporary folder(s) left in {} by floorcast processes that were killed",
            std::env::temp_dir().display()
        ));
    }
}

/// The staging folders of the [`StagedOut`]s not yet committed, each with its `--out` if it was
/// made for it (what a stop removes).
type Staged = Vec<(PathBuf, Option<PathBuf>)>;

fn staged<T>(f: impl FnOnce(&mut Staged) -> T) -> T {
    static STAGED: std::sync::Mutex<Staged> = std::sync::Mutex::new(Vec::new());
    f(&mut STAGED.lock().unwrap_or_else(|e| e.into_inner()))
}

/// Writes one line to stdout. A closed pipe (`floorcast ... | head`) ends the program quietly
/// with exit code 0, as `head`'s reader wanted no more; any other failed write (a full disk) is
/// an error: one line on stderr and exit code 2, never a silently cut output.
pub fn say_fmt(args: std::fmt::Arguments<'_>, newline: bool) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let r = if newline {
        writeln!(out, "{args}")
    } else {
        write!(out, "{args}")
    };
    if let Err(e) = r.and_then(|_| out.flush()) {
        stdout_failed(&e);
    }
}

/// Ends the program after a failed write to stdout: quietly (exit code 0) on a closed pipe, else
/// with one line naming the problem and exit code 2.
pub fn stdout_failed(e: &std::io::Error) -> ! {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        std::process::exit(0);
    }
    tell_fmt(format_args!("error: cannot write to stdout ({e}); free space on its device or send the output elsewhere"));
    std::process::exit(2);
}

/// `println!` that survives a closed pipe and fails on a full disk.
macro_rules! say {
    ($($t:tt)*) => { crate::output::say_fmt(format_args!($($t)*), true) };
}

/// `print!` that survives a closed pipe and fails on a full disk.
macro_rules! say_raw {
    ($($t:tt)*) => { crate::output::say_fmt(format_args!($($t)*), false) };
}

/// Writes one line to stderr (messages, warnings, errors). A failed write (stderr closed, or on a
/// full device: `2>/dev/full`) is let go: there is nowhere left to say it, the outputs already
/// written stay, and the exit code still tells an error (never a panic, as `eprintln!` would).
pub fn tell_fmt(args: std::fmt::Arguments<'_>) {
    use std::io::Write;
    let mut err = std::io::stderr().lock();
    let _ = writeln!(err, "{args}").and_then(|_| err.flush());
}

/// `eprintln!` that never panics ([`tell_fmt`]). Every write to stdout or stderr outside tests
/// goes through [`say!`], [`say_raw!`] or this (`tests/checked_writes.rs` greps the sources).
macro_rules! tell {
    ($($t:tt)*) => { crate::output::tell_fmt(format_args!($($t)*)) };
}

/// The files `explore` writes in its `--out` directory (besides its layout snapshots,
/// `layout-NN.png`/`.svg`).
pub const EXPLORE_FILES: [&str; 9] = [
    "summary.json",
    "progress.csv",
    "decisions.csv",
    "trajectory.csv",
    "strategy-stderr.txt",
    "map.yaml",
    "map.pgm",
    "final.png",
    "final.svg",
];

/// Whether `name` is a file `explore` writes in its `--out` directory.
fn is_explore_output(name: &str) -> bool {
    EXPLORE_FILES.contains(&name)
        || (name.starts_with("layout-") && (name.ends_with(".png") || name.ends_with(".svg")))
}

/// `explore`'s output directory, written whole or not at all: the files go into a new hidden
/// folder beside it (`.<name>.partial-XXXXXX`) and move into place only at the end
/// ([`StagedOut::commit`]), so that a failed or killed `explore` leaves no half-written output.
/// A new (or empty) directory is replaced by the folder in one rename; into one that holds files
/// already, the new files move one by one, after `explore`'s files of an earlier run that this
/// run did not make (a layout snapshot) are removed; other files are left alone. The directory
/// is locked while `explore` runs: a second `explore` into it is refused.
#[derive(Debug)]
pub struct StagedOut {
    out: PathBuf,
    staging: Option<tempfile::TempDir>,
    /// Created here (removed again if nothing is committed).
    created: bool,
    _lock: std::fs::File,
}

impl StagedOut {
    /// Creates `out` if need be, locks it and makes the folder the files are written into.
    pub fn begin(out: &Path) -> Result<StagedOut> {
        use std::os::unix::fs::PermissionsExt;
        let created = !out.exists();
        create_dir(out)?;
        let undo = |created: bool| {
            if created {
                let _ = std::fs::remove_dir(out);
            }
        };
        let lock = std::fs::File::open(out)
            .with_context(|| format!("cannot open directory {}", out.display()))?;
        match lock.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => anyhow::bail!(
                "--out: {} is being written by another floorcast explore; wait for it to end, or give another --out",
                out.display()
            ),
            Err(std::fs::TryLockError::Error(e)) => {
                undo(created);
                return Err(e).with_context(|| format!("cannot lock {}", out.display()));
            }
        }
        // A link to a directory is written through: the files move into its target (the
        // staging folder is made beside the target), the link stays.
        let real = out.canonicalize().unwrap_or_else(|_| out.to_path_buf());
        let parent = match real.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let name = real
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "explore".into());
        let staging = tempfile::Builder::new()
            .prefix(&format!(".{name}.partial-"))
            .permissions(std::fs::Permissions::from_mode(0o755))
            .tempdir_in(parent)
            .with_context(|| {
                undo(created);
                format!("cannot create a folder in {}", parent.display())
            })?;
        let made = created.then(|| out.to_path_buf());
        staged(|s| s.push((staging.path().to_path_buf(), made)));
        Ok(StagedOut {
            out: real,
            staging: Some(staging),
            created,
            _lock: lock,
        })
    }

    /// Where the files are written until [`StagedOut::commit`].
    pub fn dir(&self) -> &Path {
        self.staging
            .as_ref()
            .map_or(self.out.as_path(), |s| s.path())
    }

    /// Moves the files written into place.
    pub fn commit(mut self) -> Result<()> {
        let Some(staging) = self.staging.take() else {
            return Ok(());
        };
        staged(|s| s.retain(|(p, _)| p != staging.path()));
        let failed = |e: std::io::Error| {
            anyhow::Error::new(e).context(format!(
                "cannot move the outputs into {}",
                self.out.display()
            ))
        };
        let empty = std::fs::read_dir(&self.out)
            .map_err(failed)?
            .next()
            .is_none();
        if empty {
            // An empty directory is replaced in one step.
            let path = staging.keep();
            return std::fs::rename(&path, &self.out).map_err(|e| {
                let _ = std::fs::remove_dir_all(&path);
                failed(e)
            });
        }
        let new: std::collections::BTreeSet<std::ffi::OsString> = std::fs::read_dir(staging.path())
            .map_err(failed)?
            .map(|e| e.map(|e| e.file_name()))
            .collect::<std::io::Result<_>>()
            .map_err(failed)?;
        for e in std::fs::read_dir(&self.out).map_err(failed)? {
            let name = e.map_err(failed)?.file_name();
            if !new.contains(&name) && is_explore_output(&name.to_string_lossy()) {
                std::fs::remove_file(self.out.join(&name)).map_err(failed)?;
            }
        }
        for name in &new {
            std::fs::rename(staging.path().join(name), self.out.join(name)).map_err(failed)?;
        }
        Ok(())
    }
}

impl Drop for StagedOut {
    fn drop(&mut self) {
        // Not committed: the folder goes (TempDir), and the directory if it was made here.
        if let Some(staging) = self.staging.take() {
            staged(|s| s.retain(|(p, _)| p != staging.path()));
            drop(staging);
            if self.created {
                let _ = std::fs::remove_dir(&self.out);
            }
        }
    }
}
